"""Time-stamping algorithm (seed 001 (5.1)-(5.5), Remark 2, Appendix C)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from switchobs.exceptions import SimulationError
from switchobs.sensors import (AngleTrajectory, Encoder, TimeStamper, controller_times, time_stamping,
                               tsa_condition_number, varying_speed)


def _quadratic(theta0: float, w0: float, a0: float, t0: float, duration: float) -> AngleTrajectory:
    return AngleTrajectory(theta=lambda t: theta0 + w0 * (t - t0) + 0.5 * a0 * (t - t0) ** 2,
                           omega=lambda t: w0 + a0 * (t - t0), alpha=lambda t: np.full(np.shape(t), a0),
                           t_start=t0, t_end=t0 + duration, grid=np.linspace(t0, t0 + duration, 21),
                           name="quadratic")


@pytest.mark.parametrize("t0, w0, a0", [(0.0, 100.0, -150.0), (50.0, 20.0, 150.0), (1000.0, 107.0, 0.0)])
def test_aguado_eq54_eq55_ideal_encoder_quadratic_angle_is_exact_at_m2(t0, w0, a0):
    traj = _quadratic(2.0, w0, a0, t0, 0.5)
    ev = Encoder(ppr=60).events(traj)
    ts = controller_times(t0, t0 + 0.5, 1000.0)
    est = time_stamping(ev.times, ev.angles, ts, order=2, window=15)
    ok = est.valid
    assert np.count_nonzero(ok) > 300
    np.testing.assert_allclose(est.omega[ok], traj.omega(ts[ok]), rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(est.alpha[ok], a0, rtol=1e-7, atol=2e-6)
    np.testing.assert_allclose(est.theta[ok], traj.theta(ts[ok]), atol=1e-9)
    assert np.all(np.isnan(est.omega[~ok]))


def test_aguado_appendixC_condition_numbers_m2_n5():
    t_reg = np.array([22.0, 23.0, 24.0, 25.0, 26.0]) * 1e-5
    # the seed prints 5.97e9 (5.976e9 truncated) and 16.66
    assert tsa_condition_number(t_reg, order=2, scaled=False) == pytest.approx(5.97e9, rel=2e-3)
    assert tsa_condition_number(t_reg, order=2, scaled=True) == pytest.approx(16.66, abs=0.01)


@settings(max_examples=25, deadline=None)
@given(shift=st.floats(-1e3, 1e3), scale=st.floats(1e-6, 1e2), order=st.integers(2, 4))
def test_aguado_appendixC_scaled_conditioning_is_shift_and_scale_invariant(shift, scale, order):
    base = np.array([0.0, 0.1, 0.35, 0.5, 0.8, 1.0])
    reference = tsa_condition_number(base, order=order, scaled=True)
    assert tsa_condition_number(shift + scale * base, order=order, scaled=True) == pytest.approx(reference,
                                                                                                  rel=1e-6)


def test_aguado_eq55_cubic_angle_needs_m3():
    traj = AngleTrajectory(theta=lambda t: 80 * t + 40 * t**2 + 30 * t**3, omega=lambda t: 80 + 80 * t + 90 * t**2,
                           alpha=lambda t: 80 + 180 * t, t_start=0.0, t_end=0.5,
                           grid=np.linspace(0, 0.5, 11))
    ev = Encoder(ppr=60).events(traj)
    ts = controller_times(0.0, 0.5, 1000.0)
    m2 = time_stamping(ev.times, ev.angles, ts, order=2, window=15)
    m3 = time_stamping(ev.times, ev.angles, ts, order=3, window=15)
    ok = m3.valid
    np.testing.assert_allclose(m3.alpha[ok], traj.alpha(ts[ok]), rtol=1e-6)
    assert np.max(np.abs(m2.alpha[ok] - traj.alpha(ts[ok]))) > 1.0


def test_streaming_time_stamper_matches_batch():
    ev = Encoder(ppr=60, dnl_cycles=0.02, eccentricity=0.004, clock_hz=1e6, seed=2).events(
        varying_speed(1020.0, 0.6))
    ts = controller_times(0.0, 0.6, 1000.0)
    batch = time_stamping(ev.times, ev.angles, ts, order=2, window=12)
    stream = TimeStamper(order=2, window=12)
    k = 0
    for i, t in enumerate(ts):
        while k < len(ev) and ev.times[k] <= t:
            stream.push(float(ev.times[k]), float(ev.angles[k]))
            k += 1
        th, om, al = stream.estimate(float(t))
        if batch.valid[i]:
            assert (th, om, al) == pytest.approx((batch.theta[i], batch.omega[i], batch.alpha[i]), rel=1e-12)
        else:
            assert math.isnan(om)


@pytest.mark.parametrize("order, window, match", [
    (2, 2, r"window n = 2 must exceed the polynomial order m = 2"),
    (3, 3, r"window n = 3 must exceed"),
    (1, 5, r"order .* at least 2, got 1"),
    (2.5, 5, r"order .* integer"),
])
def test_bad_order_window_raise(order, window, match):
    with pytest.raises(SimulationError, match=match):
        time_stamping([0.0, 1.0, 2.0, 3.0, 4.0, 5.0], np.arange(6.0), [5.0], order=order, window=window)


def test_non_monotone_and_nan_time_stamps_raise():
    t = np.array([0.0, 0.001, 0.003, 0.002, 0.004])
    with pytest.raises(SimulationError, match=r"event times must be strictly increasing.*event times\[3\]"):
        time_stamping(t, np.arange(5.0), [0.004], window=3)
    with pytest.raises(SimulationError, match=r"event angles\[2\] = nan is not finite"):
        time_stamping(np.arange(5.0), [0.0, 1.0, np.nan, 3.0, 4.0], [4.0], window=3)
    with pytest.raises(SimulationError, match=r"event angles has 4 samples; expected 5"):
        time_stamping(np.arange(5.0), np.arange(4.0), [4.0], window=3)
    stamper = TimeStamper(window=3)
    stamper.push(1.0, 0.0)
    with pytest.raises(SimulationError, match="strictly increasing"):
        stamper.push(1.0, 0.1)
    with pytest.raises(SimulationError, match="not finite"):
        stamper.push(2.0, math.nan)


def test_tsa_estimate_json():
    est = time_stamping(np.arange(10.0), 3.0 * np.arange(10.0), [1.0, 5.5, 9.0], window=4)
    data = est.to_json(arrays=True)
    assert data["valid_samples"] == 2 and data["omega"][0] is None
    assert data["omega"][1] == pytest.approx(3.0)
    assert "2 valid" in str(est)
