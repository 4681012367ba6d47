"""The quarter car with its ABS as an FMU, and the loop closed between it and the observer FMU in FMPy.

``examples/fmu_closed_loop.py`` steps both FMUs with FMPy's ``FMU3Slave`` and checks every sample against
``simulate`` (the compiled loop with the same C observer) bit for bit; here it runs on the page's commands.
``fmpy.validation`` checks the plant FMU, and ``fmpy.simulate_fmu`` runs it alone on a fixed 1 ms grid.
"""

from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from _docs_blocks import matches_with_elisions, shown_output

fmpy = pytest.importorskip("fmpy", reason="fmpy is not installed: the plant FMU is NOT checked (pip install fmpy)")
from fmpy import extract, read_model_description, simulate_fmu  # noqa: E402
from fmpy.fmi3 import FMU3Slave  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

from switchobs.exceptions import SimulationError  # noqa: E402
from switchobs.plants import (PLANT_OUTPUTS, BrakeActuator, generate_plant_fmu, scenario,  # noqa: E402
                              simulate)

ROOT = Path(__file__).resolve().parents[1]
SHORT = 2.0   # s of hoang-fig3


@pytest.fixture(scope="module")
def fig3(tmp_path_factory):
    sc = replace(scenario("hoang-fig3"), duration_s=SHORT)
    fmu = generate_plant_fmu(sc)
    return sc, fmu, fmu.write(tmp_path_factory.mktemp("plant") / fmu.file_name)


def test_plant_fmu_passes_fmpy_validation_and_names_its_variables(fig3):
    sc, fmu, path = fig3
    assert validate_fmu(str(path)) == []
    md = read_model_description(str(path))
    assert md.fmiVersion == "3.0" and md.coSimulation.modelIdentifier == "switchobs_quarter_car"
    causality = {v.name: v.causality for v in md.modelVariables}
    assert [n for n, c in causality.items() if c == "input"] == ["xbs_hat"]
    assert [n for n, c in causality.items() if c == "output"] == [n for n, _ in PLANT_OUTPUTS] + ["phase"]
    starts = {v.name: float(v.start) for v in md.modelVariables if v.causality == "parameter"}
    assert starts["V0"] == sc.speed_m_s and starts["DT"] == sc.dt_s and starts["T_END"] == SHORT


def test_simulate_fmu_runs_the_plant_on_a_fixed_grid_as_simulate(fig3):
    """Without early return every doStep ends on the 1 ms grid (an event inside a step splits it there): the
    speed and pressure are the simulation's within the interpolation of its samples onto that grid."""
    sc, _, path = fig3
    ref = simulate(sc)
    res = simulate_fmu(str(path), start_time=0.0, stop_time=SHORT, step_size=sc.dt_s, output_interval=sc.dt_s,
                       output=["vx", "P_b", "phase"])
    assert res["time"].size == round(SHORT / sc.dt_s) + 1
    assert np.abs(res["vx"] - np.interp(res["time"], ref.series["t"], ref.series["vx"])).max() < 1e-12
    assert np.abs(res["P_b"] - np.interp(res["time"], ref.series["t"], ref.series["P_b"])).max() < 1e-3
    assert set(np.unique(res["phase"])) == set(np.unique(ref.series["phase"]))


def test_parameters_are_fixed_after_initialization_and_the_start_time_is_zero(fig3, tmp_path):
    _, fmu, path = fig3
    messages = []
    s = FMU3Slave(guid=read_model_description(str(path)).instantiationToken,
                  unzipDirectory=extract(str(path), unzipdir=str(tmp_path / "u")),
                  modelIdentifier=fmu.prefix, instanceName="p")
    s.instantiate(logMessage=lambda env, status, category, message: messages.append(message.decode()))
    s.enterInitializationMode()
    s.setFloat64([fmu.value_references["V0"]], [20.0])      # before the initialization ends: allowed
    s.exitInitializationMode()
    assert s.getFloat64([fmu.value_references["vx"]]) == [20.0]
    with pytest.raises(Exception):
        s.setFloat64([fmu.value_references["V0"]], [10.0])
    assert messages[-1] == "fmi3SetFloat64: the parameters can only be set before initialization ends"
    s.terminate()
    s.freeInstance()


def test_a_scenario_outside_the_compiled_loop_is_refused_in_one_line():
    sc = replace(scenario("hoang-fig3"), actuator=BrakeActuator(delay_s=0.01))
    with pytest.raises(SimulationError, match=r"^scenario 'hoang-fig3' has no plant FMU: an actuator delay runs "
                                              r"in the Python loop only$"):
        generate_plant_fmu(sc)


@pytest.mark.parametrize("command", ["python examples/fmu_closed_loop.py gen two-phase",
                                     pytest.param("python examples/fmu_closed_loop.py gen",
                                                  marks=pytest.mark.slow)])
def test_the_closed_loop_of_two_fmus_equals_simulate_bit_for_bit(command, tmp_path):
    """The page's commands: the example asserts every sample equal to simulate's and prints it."""
    args = command.split()[1:]
    proc = subprocess.run([sys.executable, str(ROOT / args[0]), *args[1:]], capture_output=True, text=True,
                          cwd=tmp_path, timeout=600, env={**os.environ, "SWITCHOBS_FAST": "0"})
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-3000:]
    printed = proc.stdout
    assert matches_with_elisions(shown_output("codegen.md", command), printed), printed
