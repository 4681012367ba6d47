"""encoder_measurements: the encoder chain over a whole recorded run equals the per-step EncoderLoopEstimator.

The specification is the per-step chain with the Python TSA and three-stage estimator (``compiled=False``):
the chain as it was before the C kernels and the batch path.  The batch path gives its numbers bit for bit
with the same implementation, and within rounding (1e-12 of the signal's range) with the C kernels.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from switchobs.exceptions import SimulationError
from switchobs.loop import (INITIAL_STATE, EncoderLoopEstimator, EncoderMeasurements, EstimatorSpec,
                            encoder_measurements, xbs_estimator)
from switchobs.loop._adapter import initial_xbs_state
from switchobs.plants import BrakingScenario, FivePhaseABS, QuarterCar, RoadChange, RoadSchedule, simulate
from switchobs.sensors import Encoder

from test_sensors_kernels import needs_compiler

RECORD = ("t", "t_measured", "x2_tsa", "x2_notch", "x2_measured", "omega_tsa", "omega_measured", "vx")
#: What the C kernels' rounding may change: the TSA fit's outputs and the three-stage and notch outputs on
#: them (tests/test_sensors_kernels.py); the sample times, the window means and the speed are bit for bit.
COMPENSATED = ("x2_tsa", "x2_notch", "x2_measured", "omega_tsa", "omega_measured")
ENCODER = Encoder(ppr=60, dnl_cycles=0.01, eccentricity=0.003, clock_hz=1e6, seed=7)


class Recorder:
    """Hands the plant's calls to an estimator and keeps them (the arrays encoder_measurements takes)."""

    def __init__(self, inner: EncoderLoopEstimator) -> None:
        self.inner, self.calls = inner, []

    def reset(self, t0, y0, vx0):
        self.start = (t0, y0, vx0)
        self.inner.reset(t0, y0, vx0)

    def update(self, t, y, vx, u, dt):
        self.calls.append((t, y, vx, u, dt))
        return self.inner.update(t, y, vx, u, dt)

    def arrays(self):
        c = np.array(self.calls)
        return ([np.concatenate([[s], c[:, i]]) for i, s in enumerate(self.start)], c[:, 3], c[:, 4])


def chain(observers=(), compiled=None, encoder=ENCODER, **kw) -> EncoderLoopEstimator:
    return EncoderLoopEstimator(observers, encoder=encoder, radius_m=QuarterCar().radius_m, compiled=compiled, **kw)


def drive(loop: EncoderLoopEstimator, arrays) -> EncoderLoopEstimator:
    (t, x2, vx), u, dt = arrays
    loop.reset(t[0], x2[0], vx[0])
    for i in range(1, t.size):
        loop.update(t[i], x2[i], vx[i], u[i - 1], dt[i - 1])
    return loop


def batch(arrays, compiled=None, encoder=ENCODER, **kw) -> EncoderMeasurements:
    (t, x2, vx), u, dt = arrays
    return encoder_measurements(t, x2, vx, u, dt, encoder=encoder, radius_m=QuarterCar().radius_m,
                                compiled=compiled, **kw)


def estimates(meas: EncoderMeasurements, observer, initial) -> np.ndarray:
    """The observer's estimate at every sample from observer_steps, as the per-step chain steps it."""
    first, at, span, signals = meas.observer_steps()
    out = np.full(meas.t.size, np.nan)
    x = initial_xbs_state(observer, meas.x2_measured[first], initial)
    ends = [*at.tolist(), meas.t.size]
    out[first:ends[0]] = observer.readout(x)
    for i in range(at.size):
        x = observer.step(x, tuple(signals[i]), span[i])
        out[at[i]:ends[i + 1]] = observer.readout(x)
    return out


@pytest.fixture(scope="module")
def braking():
    """1.6 s of ABS braking from 90 km/h, dry asphalt then snow from 0.7 s: the xbs4 observer beside the
    five-phase ABS, on the encoder chain with the Python three-stage estimator (the specification)."""
    vehicle = QuarterCar()
    roads = RoadSchedule("dry-asphalt", [RoadChange("snow", at_time_s=0.7)])
    sc = BrakingScenario(roads, speed_m_s=25.0, controller=FivePhaseABS(), vehicle=vehicle, duration_s=1.6)
    observer = xbs_estimator(EstimatorSpec("xbs4", method="radau3"), vehicle, roads.initial).observer
    initial = dict(INITIAL_STATE["xbs4"])
    rec = Recorder(chain([("xbs4", observer, initial)], compiled=False))
    res = simulate(sc, estimator=rec, observer_in_loop=False)
    assert res.status == "duration" and res.metrics.abs_cycles >= 2
    return rec.arrays(), rec.inner.record(), observer, initial, res.series["xbs_hat"]


def test_batch_equals_the_per_step_chain_bit_for_bit_with_the_python_estimator(braking):
    arrays, record, observer, initial, xbs_hat = braking
    meas = batch(arrays, compiled=False)
    for name in RECORD:
        assert np.array_equal(getattr(meas, name), getattr(record, name), equal_nan=True), name
    assert meas.events == record.events > 500
    assert np.array_equal(meas.steps_t, record.steps_t) and np.array_equal(meas.omega_steps, record.omega_steps)
    # the observer stepped as observer_steps says gives the per-step chain's estimates
    ours = estimates(meas, observer, initial)
    assert np.array_equal(ours, record.estimates["xbs4"], equal_nan=True)
    # and sample_step puts them on the plant's steps: what the per-step chain handed simulate at each
    last = np.searchsorted(meas.sample_step, np.arange(xbs_hat.size), side="right") - 1
    on_steps = np.where(last >= 0, ours[np.maximum(last, 0)], np.nan)
    on_steps = np.where(np.isnan(on_steps), 0.5, on_steps)       # initial_xbs before the first measurement
    assert np.array_equal(on_steps[1:], xbs_hat[1:])      # the series' first row is before any update()
    # measured from the sample at which the TSA window first holds its 15 edges on
    first = int(np.argmax(np.isfinite(meas.x2_measured)))
    assert 0 < first and np.all(np.isfinite(meas.x2_measured[first:]))


@needs_compiler
def test_batch_with_the_c_kernel_equals_the_python_specification_to_rounding(braking):
    arrays, record, _, _, _ = braking
    meas = batch(arrays, compiled=True)
    for name in RECORD:
        ours, spec = getattr(meas, name), getattr(record, name)
        assert np.array_equal(np.isnan(ours), np.isnan(spec)), name
        if name in COMPENSATED:
            scale = np.nanmax(np.abs(spec))
            assert np.nanmax(np.abs(ours - spec)) <= 1e-12 * scale, name
        else:
            assert np.array_equal(ours, spec, equal_nan=True), name
    # the compensation did something: the rounding bound is not met by leaving the TSA alone
    assert np.nanmax(np.abs(meas.omega_measured - meas.omega_tsa)) > 1e-3


@needs_compiler
def test_batch_equals_the_per_step_chain_bit_for_bit_with_the_c_kernel(braking):
    arrays = braking[0]
    record = drive(chain(compiled=True), arrays).record()
    meas = batch(arrays, compiled=True)
    for name in RECORD:
        assert np.array_equal(getattr(meas, name), getattr(record, name), equal_nan=True), name


def synthetic(steps: int = 1500, seed: int = 3):
    """A wheel that brakes hard, locks (the reconstruction clamps at 0) and spins up again, with uneven steps
    and a step of zero length (which update() skips)."""
    rng = np.random.default_rng(seed)
    dt = rng.uniform(2e-4, 1.2e-3, steps)
    dt[100] = 0.0
    t = np.concatenate([[0.2], 0.2 + np.cumsum(dt)])
    vx = np.linspace(20.0, 15.0, steps + 1)
    x2 = np.where((t > 0.5) & (t < 0.8), -400.0, 0.0) + np.where((t > 1.0) & (t < 1.2), 420.0, 0.0)
    x2 += rng.normal(0.0, 5.0, t.size)
    return (t, x2, vx), rng.normal(0.0, 100.0, steps), dt


@pytest.mark.parametrize("compiled", [False, pytest.param(True, marks=needs_compiler)])
def test_a_locked_wheel_and_skipped_steps_give_the_per_step_numbers(compiled):
    arrays = synthetic()
    record = drive(chain(compiled=compiled, rate_hz=800.0, window=9, harmonics=3), arrays).record()
    meas = batch(arrays, compiled=compiled, rate_hz=800.0, window=9, harmonics=3)
    assert np.any(meas.omega_steps == 0.0) and meas.steps_t.size == arrays[0][0].size - 1
    for name in RECORD:
        assert np.array_equal(getattr(meas, name), getattr(record, name), equal_nan=True), name
    assert np.array_equal(meas.omega_steps, record.omega_steps) and meas.events == record.events
    assert np.all(np.diff(meas.sample_step) >= 0) and 101 not in meas.sample_step    # the skipped step


def test_two_edges_on_one_timer_tick_raise_the_per_step_chains_error():
    coarse = Encoder(ppr=60, clock_hz=2000.0)
    arrays = synthetic()
    with pytest.raises(SimulationError, match="strictly increasing") as per_step:
        drive(chain(encoder=coarse, compiled=False), arrays)
    with pytest.raises(SimulationError, match="strictly increasing") as batched:
        batch(arrays, encoder=coarse, compiled=False)
    assert str(batched.value) == str(per_step.value)


@pytest.mark.parametrize("change, match", [
    (lambda a: ((a[0][0], a[0][1][:-1], a[0][2]), a[1], a[2]), "x2 has shape"),
    (lambda a: (a[0], a[1][:-1], a[2]), "u has shape"),
    (lambda a: (a[0], a[1], a[2][:-2]), "dt has shape"),
    (lambda a: ((a[0][0], np.where(a[0][0] == a[0][0][-1], np.nan, a[0][1]), a[0][2]), a[1], a[2]), "x2 holds nan"),
    (lambda a: ((a[0][0][:, None], a[0][1], a[0][2]), a[1], a[2]), "1-D array"),
])
def test_bad_arrays_are_refused_naming_the_array(change, match):
    with pytest.raises(SimulationError, match=match):
        batch(change(synthetic(200)), compiled=False)


def test_bad_chain_settings_are_refused():
    arrays = synthetic(200)
    with pytest.raises(SimulationError, match="window n = 2 must exceed"):
        batch(arrays, window=2)
    with pytest.raises(SimulationError, match="rate_hz must be finite"):
        batch(arrays, rate_hz=0.0)
    # the loop's edges are fixed: a per-event jitter (open-loop chain only) is refused, not ignored
    jittered = Encoder(ppr=60, jitter_cycles=0.004, seed=7)
    with pytest.raises(SimulationError, match="jitter_cycles = 0.004: the ABS loop's encoder chain has fixed edges"):
        batch(arrays, encoder=jittered)
    with pytest.raises(SimulationError, match="jitter_cycles = 0.004"):
        EncoderLoopEstimator([], encoder=jittered, radius_m=0.3)


def test_dt_defaults_to_the_differences_of_t_and_the_result_reads_and_serialises():
    (t, x2, vx), u, _ = synthetic(600)
    meas = encoder_measurements(t, x2, vx, u, encoder=ENCODER, radius_m=0.3, compiled=False)
    same = encoder_measurements(t, x2, vx, u, np.diff(t), encoder=ENCODER, radius_m=0.3, compiled=False)
    assert np.array_equal(meas.x2_measured, same.x2_measured, equal_nan=True)
    data = json.loads(json.dumps(meas.to_json()))
    assert data["events"] == meas.events and len(data["t"]) == meas.t.size and data["t_measured"][0] is None
    assert f"{meas.t.size} samples" in str(meas) and f"{meas.events} edges" in str(meas)
    first, at, span, signals = meas.observer_steps()
    assert first >= 0 and np.all(span > 0.0) and signals.shape == (at.size, 3)


def test_the_three_measurement_records_are_one_record_with_additions():
    """EncoderLoopRecord, EncoderMeasurements and ReplayResult are EncoderSamples: its fields first, in its order."""
    import dataclasses

    from switchobs.loop import EncoderLoopRecord, EncoderSamples, ReplayResult

    base = [f.name for f in dataclasses.fields(EncoderSamples)]
    assert tuple(base) == EncoderSamples.SIGNALS
    for cls in (EncoderLoopRecord, EncoderMeasurements, ReplayResult):
        assert issubclass(cls, EncoderSamples)
        names = [f.name for f in dataclasses.fields(cls)]
        assert names[:len(base)] == base and not set(names[len(base):]) & set(base), cls
