"""The docstring examples of switchobs.plants run and hold."""

import doctest
import importlib

import pytest

MODULES = ["_tyre", "_road", "_estimator", "_poincare", "_simulate", "_scenarios", "_plot", "_metrics", "_fmu"]


@pytest.mark.parametrize("module", MODULES)
def test_plants_docstring_examples(module):
    result = doctest.testmod(importlib.import_module(f"switchobs.plants.{module}"), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0
