"""The Examples sections of switchobs.sensors run and hold."""

from __future__ import annotations

import doctest
import importlib

import pytest

MODULES = ["_chain", "_encoder", "_super_twisting", "_three_stage", "_tsa", "_vehicle_speed"]


@pytest.mark.parametrize("name", MODULES)
def test_sensor_docstring_examples(name):
    module = importlib.import_module(f"switchobs.sensors.{name}")
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0
