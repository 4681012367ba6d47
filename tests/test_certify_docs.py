"""The runnable examples of the certify docstrings hold."""

import doctest
import importlib

import pytest

MODULES = ["_certify", "_dwell", "_lyapunov", "_planar", "_trajectory", "_verify"]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    mod = importlib.import_module(f"switchobs.certify.{name}")
    res = doctest.testmod(mod, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert res.attempted > 0 and res.failed == 0
