"""Encoder model: exact edge crossings, transition noise (5.6), eccentricity (5.7)/(5.8), clock (seed 001 Sec. 5.3)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from switchobs.exceptions import SimulationError
from switchobs.sensors import AngleTrajectory, Encoder, constant_speed, rpm_to_rad_s, trapezoid_speed, varying_speed


def _quadratic(theta0: float, w0: float, a0: float, duration: float) -> AngleTrajectory:
    return AngleTrajectory(theta=lambda t: theta0 + w0 * t + 0.5 * a0 * t**2, omega=lambda t: w0 + a0 * t,
                           alpha=lambda t: np.full(np.shape(t), a0), t_start=0.0, t_end=duration,
                           grid=np.linspace(0.0, duration, 11), name="quadratic")


def test_ideal_encoder_edges_at_exact_crossing_times_of_constant_speed():
    traj = constant_speed(1020.0, 0.5)
    ev = Encoder(ppr=60).events(traj)
    w0 = rpm_to_rad_s(1020.0)
    k = np.arange(1, len(ev) + 1)
    np.testing.assert_allclose(ev.times, k * (2 * math.pi / 60) / w0, rtol=4e-15)
    assert len(ev) == math.floor(0.5 * w0 / (2 * math.pi / 60))
    np.testing.assert_allclose(ev.angles, ev.true_angles, atol=1e-12)


def test_crossing_times_solve_the_quadratic_not_a_sampled_grid():
    traj = _quadratic(0.3, 50.0, -40.0, 1.0)
    ev = Encoder(ppr=48).events(traj)
    # closed-form root of theta0 + w0 t + a0 t^2 / 2 = level
    lv = ev.true_angles - 0.3
    exact = (-50.0 + np.sqrt(50.0**2 + 2 * -40.0 * lv)) / -40.0
    np.testing.assert_allclose(ev.exact_times, exact, rtol=1e-13)


def test_from_samples_speed_only_integrates_the_spline_exactly():
    t = np.linspace(0.0, 2.0, 201)
    w = 80.0 + 10.0 * np.sin(3.0 * t)
    traj = AngleTrajectory.from_samples(t, omega=w, theta0=1.0)
    assert traj.theta(np.array([0.0]))[0] == pytest.approx(1.0, abs=1e-12)
    # integral of 80 + 10 sin 3t
    expected = 1.0 + 80.0 * 2.0 + 10.0 / 3.0 * (1.0 - math.cos(6.0))
    assert float(traj.theta(np.array([2.0]))[0]) == pytest.approx(expected, rel=1e-7)
    ev = Encoder(ppr=60).events(traj)
    np.testing.assert_allclose(traj.theta(ev.exact_times), ev.true_angles, atol=1e-11)


@pytest.mark.parametrize("ramp_s", [None, 0.25])
def test_trapezoid_plateaus_and_ramps_are_continuous_and_integrate(ramp_s):
    traj = trapezoid_speed(300.0, 600.0, 5.0, segment_s=1.0, ramp_s=ramp_s)
    ramp = 1.0 if ramp_s is None else ramp_s
    lo, hi = rpm_to_rad_s(300.0), rpm_to_rad_s(600.0)
    period = 2.0 * (1.0 + ramp)
    t = np.array([0.5, 1.0 + 0.5 * ramp, 1.5 + ramp, period + 0.5])
    np.testing.assert_allclose(traj.omega(t), [lo, 0.5 * (lo + hi), hi, lo], rtol=1e-12)
    np.testing.assert_allclose(traj.alpha(t[:3]), [0.0, (hi - lo) / ramp, 0.0], atol=1e-9)
    # theta is the exact integral of omega across the corners
    fine = np.linspace(0.0, 5.0, 200001)
    w = traj.omega(fine)
    integral = np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * np.diff(fine))])
    np.testing.assert_allclose(traj.theta(fine), integral, atol=1e-6)


def test_aguado_eq56_dnl_is_fixed_per_tooth_and_bounded():
    enc = Encoder(ppr=60, dnl_cycles=0.02, seed=7)
    delta = enc.transition_angles() - enc.nominal_angles()
    eps = 0.02 * 2 * math.pi / 60
    assert np.all(np.abs(delta) <= eps) and np.ptp(delta) > eps  # spread over [-eps, eps]
    np.testing.assert_array_equal(delta, Encoder(ppr=60, dnl_cycles=0.02, seed=7).transition_angles()
                                  - enc.nominal_angles())
    assert not np.allclose(delta, Encoder(ppr=60, dnl_cycles=0.02, seed=8).transition_angles()
                           - enc.nominal_angles())
    ev = enc.events(constant_speed(1020.0, 1.0))
    # the same tooth shows the same position error at every revolution
    err = ev.angle_error()
    for tooth in range(60):
        e = err[ev.edge_index == tooth]
        assert e.size >= 15 and np.ptp(e) < 1e-11
        assert e[0] == pytest.approx(-delta[tooth], abs=1e-11)


def test_aguado_eq56_jitter_is_drawn_per_event_bounded_and_reproducible():
    # the stochastic part of (5.6): a fresh error at every event (seed 001 Fig. 5.3's scatter), on top of the
    # fixed per-tooth error and seen through the eccentricity law (5.7)
    enc = Encoder(ppr=60, dnl_cycles=0.01, jitter_cycles=0.02, eccentricity=0.003, seed=4)
    traj = constant_speed(1020.0, 1.0)
    ev = enc.events(traj)
    again = Encoder(ppr=60, dnl_cycles=0.01, jitter_cycles=0.02, eccentricity=0.003, seed=4).events(traj)
    np.testing.assert_array_equal(ev.times, again.times)
    np.testing.assert_allclose(traj.theta(ev.exact_times), ev.true_angles, atol=1e-11)
    # the code-track angle at each crossing is the tooth's fixed location plus at most the jitter bound
    code = enc.measured_angle(ev.true_angles)
    tooth = enc.transition_angles()[ev.edge_index]
    jitter = np.mod(code - tooth + 1.0, 2 * math.pi) - 1.0
    eps = 0.02 * 2 * math.pi / 60
    assert np.all(np.abs(jitter) <= eps * (1 + 1e-9)) and np.ptp(jitter) > 1.8 * eps
    # ... and differs from revolution to revolution for the same tooth
    first = jitter[ev.edge_index == 0]
    assert first.size >= 15 and np.std(first) > 0.4 * eps
    assert len(ev) == len(Encoder(ppr=60).events(traj))


@pytest.mark.parametrize("exact", [True, False])
def test_aguado_eq57_eq58_eccentricity_error_is_the_arcsin_law(exact):
    rho, phi = 0.05, 0.7
    enc = Encoder(ppr=60, eccentricity=rho, eccentricity_phase_rad=phi, exact_arcsin=exact)
    ev = enc.events(constant_speed(600.0, 0.3))
    s = rho * np.sin(ev.true_angles + phi)
    law = np.arcsin(s) if exact else s
    # the unit counts edges: its angle is theta_m, the true angle theta_r, theta_m - theta_r = (5.7) / (5.8)
    np.testing.assert_allclose(ev.angle_error(), law, atol=1e-12)


def test_aguado_eq58_is_the_small_angle_limit_of_eq57():
    angles = np.linspace(0.0, 2 * math.pi, 50)
    for rho in (1e-2, 1e-3):
        exact = Encoder(eccentricity=rho).measured_angle(angles)
        small = Encoder(eccentricity=rho, exact_arcsin=False).measured_angle(angles)
        assert np.max(np.abs(exact - small)) <= rho**3 / 6 * 1.01


def test_both_edges_doubles_the_event_rate_and_alternates():
    traj = constant_speed(1020.0, 0.5)
    rising = Encoder(ppr=48).events(traj)
    both = Encoder(ppr=48, both_edges=True).events(traj)
    assert len(both) in (2 * len(rising), 2 * len(rising) + 1)
    assert np.all(np.diff(both.edge_index) % 96 == 1)


def test_clock_floors_time_stamps_to_ticks():
    ev = Encoder(ppr=60, clock_hz=1e5).events(varying_speed(1020.0, 1.0))
    ticks = ev.times * 1e5
    np.testing.assert_allclose(ticks, np.round(ticks), atol=1e-6)
    lag = ev.exact_times - ev.times
    assert np.all(lag >= -1e-15) and np.all(lag < 1e-5 + 1e-15) and np.ptp(lag) > 5e-6


@settings(max_examples=20, deadline=None)
@given(ppr=st.integers(2, 120), dnl=st.floats(0.0, 0.2), ecc=st.floats(0.0, 0.05),
       phase=st.floats(-3.0, 3.0), both=st.booleans(), seed=st.integers(0, 1000))
def test_events_cross_the_transition_locations_exactly(ppr, dnl, ecc, phase, both, seed):
    enc = Encoder(ppr=ppr, dnl_cycles=dnl, eccentricity=ecc, eccentricity_phase_rad=phase, both_edges=both,
                  seed=seed)
    traj = varying_speed(300.0, 0.4, amplitude_rad_s=10.0, frequency_hz=3.0)
    ev = enc.events(traj)
    assert np.all(np.diff(ev.times) > 0)
    np.testing.assert_allclose(traj.theta(ev.exact_times), ev.true_angles, atol=1e-11)
    code = enc.measured_angle(ev.true_angles)
    tooth = enc.transition_angles()[ev.edge_index]
    np.testing.assert_allclose(np.mod(code - tooth + 1.0, 2 * math.pi) - 1.0, 0.0, atol=1e-11)


@pytest.mark.parametrize("kwargs, match", [
    ({"ppr": 1}, r"ppr .* at least 2, got 1"),
    ({"ppr": 60.5}, r"ppr .* integer"),
    ({"dnl_cycles": -0.1}, "dnl_cycles"),
    ({"dnl_cycles": 0.3, "both_edges": True}, r"below 0.25"),
    ({"dnl_cycles": 0.3, "jitter_cycles": 0.2}, r"dnl_cycles \+ jitter_cycles = 0.5 must stay below 0.5"),
    ({"jitter_cycles": -0.01}, "jitter_cycles"),
    ({"eccentricity": 0.5}, r"eccentricity"),
    ({"clock_hz": 0.0}, "clock_hz"),
    ({"eccentricity_phase_rad": float("nan")}, "eccentricity_phase_rad"),
])
def test_bad_encoder_settings_raise(kwargs, match):
    with pytest.raises(SimulationError, match=match):
        Encoder(**kwargs)


def test_reversing_wheel_and_coarse_clock_raise():
    back = AngleTrajectory(theta=lambda t: np.sin(5 * t), omega=lambda t: 5 * np.cos(5 * t),
                           alpha=lambda t: -25 * np.sin(5 * t), t_start=0.0, t_end=1.0,
                           grid=np.linspace(0, 1, 50), name="swing")
    with pytest.raises(SimulationError, match=r"decreases .* omega >= 0"):
        Encoder().events(back)
    with pytest.raises(SimulationError, match=r"clock_hz = 500 is too coarse"):
        Encoder(ppr=60, clock_hz=500.0).events(constant_speed(1020.0, 0.1))


def test_from_samples_rejects_nan_and_unsorted_times():
    t = np.linspace(0, 1, 11)
    w = np.full(11, 50.0)
    w[4] = np.nan
    with pytest.raises(SimulationError, match=r"omega\[4\] = nan is not finite"):
        AngleTrajectory.from_samples(t, omega=w)
    with pytest.raises(SimulationError, match=r"strictly increasing.*t\[3\]"):
        AngleTrajectory.from_samples(t[[0, 1, 3, 2, 4]], omega=np.ones(5))
    with pytest.raises(SimulationError, match="needs theta or omega"):
        AngleTrajectory.from_samples(t)


def test_events_json_and_str():
    ev = Encoder(ppr=60, dnl_cycles=0.01, seed=3).events(constant_speed(1020.0, 0.2))
    data = ev.to_json(arrays=True)
    assert data["count"] == len(ev) == len(data["times"])
    assert data["encoder"]["ppr"] == 60 and "_transitions" not in data["encoder"]
    assert "60-ppr" in str(ev)
