"""The braking loop compiled to C gives the Python loop's runs bit for bit; run_braking, the sweep's entry."""

from __future__ import annotations

import pickle
from dataclasses import replace

import numpy as np
import pytest

from switchobs.exceptions import SimulationError
from switchobs.loop import BrakingRun, EstimatorSpec, ObserverXbsEstimator, run_braking, xbs_estimator
from switchobs.loop._adapter import c_readout
from switchobs.observers import xbs4_observer
from switchobs.plants import (BrakeActuator, BrakingScenario, ContinuousXbsControl, FivePhaseABS, RoadChange,
                              RoadSchedule, TwoPhaseABS, scenario, simulate)

from _compare import assert_same

pytestmark = pytest.mark.skipif(__import__("shutil").which("gcc") is None and __import__("shutil").which("cc") is None,
                                reason="no C compiler")


def both(sc: BrakingScenario, spec: EstimatorSpec | str | None = None, in_loop: bool = True):
    """The same run in the Python loop and in the compiled loop, each with its own fresh estimator."""
    out = []
    for compiled in (False, True):
        if isinstance(spec, EstimatorSpec):
            est = xbs_estimator(spec, sc.vehicle, sc.roads.initial)
        else:
            est = spec
        out.append((simulate(sc, estimator=est, observer_in_loop=in_loop, compiled=compiled), est))
    return out


CASES = {
    # time-triggered changes with 25 ms blends, drum speed profile, stall timeouts
    "aguado-sec34, five-phase, no observer": (replace(scenario("aguado-sec34"), duration_s=4.0), None, True),
    # the estimate in the loop: the controller's guards read it, checked at step ends only
    "two-phase, adaptive (C) in the loop": (replace(scenario("aguado-sec34"), controller=TwoPhaseABS(),
                                                    duration_s=4.0), EstimatorSpec("adaptive", impl="c"), True),
    # wheel-acceleration tracking (21)-(22): reference breakpoints, the estimate in the rate
    "hoang-fig4, tracking, xbs4 (C)": (replace(scenario("hoang-fig4"), duration_s=4.3),
                                       EstimatorSpec("xbs4", impl="c"), True),
    # a free vehicle to standstill: a located stop, the low-speed steps, a position-triggered jump of road
    "free vehicle, road jump at 20 m, fig66": (
        BrakingScenario(RoadSchedule("dry-asphalt", [RoadChange("snow", at_position_m=20.0, duration_s=0.0)]),
                        speed_m_s=60 / 3.6, controller=FivePhaseABS.fig66()), EstimatorSpec("xbs3", impl="c"), False),
    "two-phase on the true XBS": (BrakingScenario("wet-asphalt", speed_m_s=50 / 3.6, controller=TwoPhaseABS(
        start_decel_m_s2=None)), "true", True),
}


@pytest.mark.parametrize("name", list(CASES))
def test_the_compiled_loop_gives_the_python_loops_run_bit_for_bit(name):
    sc, spec, in_loop = CASES[name]
    (ref, est_ref), (fast, est_fast) = both(sc, spec, in_loop)
    assert_same(ref, fast)
    if isinstance(est_ref, ObserverXbsEstimator):
        # the estimator is left where the Python loop leaves it
        assert np.array_equal(est_ref.state, est_fast.state) and est_ref.estimate == est_fast.estimate


def test_a_refused_observer_step_ends_both_loops_alike():
    sc = replace(scenario("aguado-sec34"), duration_s=1.0)
    (ref, _), (fast, _) = both(sc, EstimatorSpec("xbs4", beta=1e6, impl="c", method="rk4"))   # radau3 stays bounded
    assert ref.status == "observer-failed" and "NONFINITE_RESULT" in ref.message
    assert_same(ref, fast)


def test_runs_the_compiled_loop_does_not_port_stay_in_python_or_are_refused_when_required():
    sc = BrakingScenario("dry-asphalt", speed_m_s=20.0, duration_s=0.3)
    python_observer = ObserverXbsEstimator(xbs4_observer(100.0, 100.0, params={"a": sc.vehicle.a, "b": -sc.vehicle.b}),
                                           initial_state={"z2": 0.5})
    # a Python observer the controller reads (beside the loop, it is replayed over the compiled run: test_replay)
    for changed, est in ((replace(sc, controller=ContinuousXbsControl()), None),
                         (replace(sc, actuator=BrakeActuator(delay_s=0.005)), None),
                         (replace(sc, controller=TwoPhaseABS()), python_observer)):
        assert not simulate(changed, estimator=est).compiled
        with pytest.raises(SimulationError, match="cannot run in the compiled loop"):
            simulate(changed, estimator=est, compiled=True)
    assert simulate(sc).compiled


def test_run_braking_returns_metrics_without_series_unless_asked_and_pickles():
    spec = EstimatorSpec("xbs4", impl="c")
    fast = run_braking("wet-asphalt", 50, controller="two-phase", observer=spec, duration_s=1.5)
    ref = run_braking("wet-asphalt", 50, controller="two-phase", observer=spec, duration_s=1.5, compiled=False,
                      series=True)
    assert fast.compiled and not ref.compiled
    assert fast.series is None and ref.series is not None and len(ref.series["t"]) == ref.steps + 1
    assert fast.metrics == ref.metrics and fast.events == ref.events
    assert fast.metrics.xbs_rms_error is not None
    back = pickle.loads(pickle.dumps(fast))
    assert isinstance(back, BrakingRun) and back.metrics == fast.metrics
    assert "compiled loop" in str(fast) and fast.to_json()["cost"]["compiled"] is True


def test_run_braking_refuses_an_unknown_controller_and_a_bad_speed():
    with pytest.raises(SimulationError, match="unknown controller 'six-phase'"):
        run_braking("dry-asphalt", 60, controller="six-phase")
    with pytest.raises(SimulationError, match="speed_kmh must be a positive number, got -5"):
        run_braking("dry-asphalt", -5)


@pytest.mark.parametrize("code, expected", [("x1", "x[1]"), ("-0.004678362573099415*x2*x0 + x1", "-0.004678362573099415*x[2]*x[0]+x[1]"),
                                            ("3*x0/2", "3.0*x[0]/2.0"), ("1e-3*x0", "1e-3*x[0]"),
                                            ("numpy.sqrt(x0)", None), ("x0**2", None), ("x0//2", None)])
def test_readouts_are_translated_to_c_only_when_c_evaluates_them_as_python(code, expected):
    assert c_readout(code) == expected


def test_a_run_longer_than_its_first_buffers_is_rerun_with_more_room(monkeypatch):
    import switchobs.plants._compiled as compiled_loop

    sc = replace(scenario("aguado-sec34"), duration_s=1.5)
    (ref, _), _ = both(sc)
    monkeypatch.setattr(compiled_loop, "_FIRST_ROWS", 7)
    monkeypatch.setattr(compiled_loop, "_FIRST_EVENTS", 1)
    fast = simulate(sc, compiled=True)
    assert len(ref.events) > 8 and ref.steps > 4 * 4 * 4 * 7
    assert_same(ref, fast)


def test_without_a_c_compiler_the_default_runs_the_python_loop_and_compiled_true_says_so(monkeypatch):
    from switchobs.exceptions import CodegenError

    monkeypatch.delenv("CC", raising=False)
    monkeypatch.setenv("PATH", "")
    sc = BrakingScenario("dry-asphalt", speed_m_s=20.0, duration_s=0.2)
    assert not simulate(sc).compiled
    with pytest.raises(CodegenError, match="no C compiler found"):
        simulate(sc, compiled=True)


def test_contradictory_thresholds_raise_the_same_cascade_error_in_both_loops():
    ctrl = FivePhaseABS()
    # every guard of every phase positive: the validation refuses such thresholds, set them past it
    object.__setattr__(ctrl, "eps", (-1e9, -1e9, -1e9, 1e9, -1e9, -1e9))
    sc = BrakingScenario("dry-asphalt", speed_m_s=20.0, controller=ctrl, duration_s=0.2)
    messages = []
    for compiled in (False, True):
        with pytest.raises(SimulationError, match="changed phase 8 times at t = ") as info:
            simulate(sc, compiled=compiled)
        messages.append(str(info.value))
    assert messages[0] == messages[1]
