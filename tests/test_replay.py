"""An estimator beside the loop (the controller does not read it) is replayed over the compiled plant's run:
the same run, samples, estimates and encoder record as the Python loop that interleaves them, bit for bit."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import switchobs.plants._simulate as simulate_module
from switchobs.loop import INITIAL_STATE, EncoderLoopEstimator, EstimatorSpec, ObserverXbsEstimator, xbs_estimator
from switchobs.observers import xbs4_observer
from switchobs.plants import BrakingScenario, FivePhaseABS, RoadChange, RoadSchedule, TwoPhaseABS, \
    replay_updates, simulate
from switchobs.sensors import Encoder
from switchobs.sweep import BrakingCase, run_case

from _compare import assert_same

pytestmark = pytest.mark.skipif(__import__("shutil").which("gcc") is None and __import__("shutil").which("cc") is None,
                                reason="no C compiler")

#: A braking with a road change in the middle of the ABS cycles and a 60-ppr encoder feeding the observer.
SC = BrakingScenario(RoadSchedule("dry-asphalt", [RoadChange("snow", at_time_s=0.6)]), speed_m_s=60 / 3.6,
                     duration_s=1.5, stop_speed_m_s=10 / 3.6)


def encoder_estimator(impl: str, method: str = "radau3", beta: float | None = None) -> EncoderLoopEstimator:
    spec = EstimatorSpec("xbs4", impl=impl, method=method, beta=beta)
    est = xbs_estimator(spec, SC.vehicle, SC.roads.initial)
    return EncoderLoopEstimator([(str(spec), est.observer, dict(INITIAL_STATE["xbs4"]))],
                                encoder=Encoder(ppr=60, seed=5), radius_m=SC.vehicle.radius_m)


@pytest.mark.parametrize("impl", ["python", "c"])
def test_an_encoder_fed_observer_beside_the_loop_is_replayed_bit_for_bit(impl):
    ref_est, fast_est = encoder_estimator(impl), encoder_estimator(impl)
    ref = simulate(SC, estimator=ref_est, compiled=False)
    fast = simulate(SC, estimator=fast_est)
    assert_same(ref, fast)
    assert np.isfinite(fast.series["xbs_hat"][-1]) and fast.metrics.xbs_rms_error is not None
    assert ref_est.record().to_json() == fast_est.record().to_json()


def test_a_sweep_case_gives_the_same_row_replayed_as_interleaved(monkeypatch):
    case = BrakingCase(road="wet-asphalt", changes=(("dry-cobblestones", 0.5),), speed_kmh=70.0, observer="xbs4",
                       method="radau3", encoder_ppr=60, encoder_seed=11, stop_kmh=10.0, duration_s=1.2)
    fast = run_case(case, series=True)
    monkeypatch.setattr(simulate_module, "compiler_available", lambda: False)  # the interleaved Python loop
    ref = run_case(case, series=True)
    assert fast.to_json() == ref.to_json() and fast.metrics["recovery_s"]


def test_a_step_the_observer_refuses_ends_the_replay_where_it_ends_the_interleaved_run():
    vehicle = SC.vehicle

    def estimator():
        return ObserverXbsEstimator(xbs4_observer(1e6, 1e6, params={"a": vehicle.a, "b": -vehicle.b}, method="rk4"),
                                    initial_state={"z2": 0.5})
    sc = replace(SC, duration_s=1.0)
    ref, fast = simulate(sc, estimator=estimator(), compiled=False), simulate(sc, estimator=estimator())
    assert ref.status == "observer-failed" and "NONFINITE" in ref.message
    assert_same(ref, fast)


@pytest.mark.parametrize("impl", ["python", "c"])
def test_an_encoder_fed_observer_refusing_a_step_ends_the_replay_as_the_interleaved_run(impl):
    # beta 3e4 in rk4 over a measurement interval of about 1 ms overflows: refused at a sample in mid-run
    ref_est, fast_est = (encoder_estimator(impl, method="rk4", beta=3e4) for _ in range(2))
    sc = replace(SC, duration_s=1.0)
    ref = simulate(sc, estimator=ref_est, compiled=False)
    fast = simulate(sc, estimator=fast_est)
    assert ref.status == "observer-failed" and "NONFINITE_RESULT" in ref.message
    assert_same(ref, fast)
    assert ref_est.record().to_json() == fast_est.record().to_json()


def test_the_controller_reading_the_estimate_keeps_the_interleaved_loop_and_the_replay_needs_no_compiler():
    est = ObserverXbsEstimator(xbs4_observer(100.0, 100.0, params={"a": SC.vehicle.a, "b": -SC.vehicle.b}),
                               initial_state={"z2": 0.5})
    assert not simulate(replace(SC, controller=TwoPhaseABS()), estimator=est).compiled
    assert simulate(replace(SC, controller=TwoPhaseABS()), estimator=est, observer_in_loop=False).compiled
    assert simulate(replace(SC, controller=FivePhaseABS(tracking=True)), estimator=est,
                    observer_in_loop=False).compiled


def test_replay_updates_feeds_reset_then_update_per_sample_and_stops_at_a_refusal():
    calls = []

    class Recorder:
        def reset(self, t0, y0, vx0):
            calls.append(("reset", t0, y0, vx0))

        def update(self, t, y, vx, u, dt):
            calls.append(("update", t, y, vx, u, dt))
            if t >= 3.0:
                raise simulate_module.SimulationError("refused at 3")
            return 10.0 * t

    hat, refused, message = replay_updates(Recorder(), *(np.arange(5.0) + k for k in range(5)))
    assert calls[0] == ("reset", 0.0, 1.0, 2.0) and calls[1] == ("update", 1.0, 2.0, 3.0, 4.0, 5.0)
    assert refused == 3 and message == "refused at 3"
    assert np.array_equal(hat, [np.nan, 10.0, 20.0, 20.0], equal_nan=True)
