"""Sliding-mode observer of the vehicle speed, equivalent output injections and theta_1, theta_2 (seed 003
Secs. III-B, IV, V), on the torque-driven quarter car of switchobs.plants with a linear tyre of known stiffness."""

from __future__ import annotations

import math

import numpy as np
import pytest

from switchobs.exceptions import SimulationError
from switchobs.experiments import (MSIRDI_INITIAL_ERROR_M_S, MSIRDI_STIFFNESS_N, equivalent_injection, identify_theta,
                                   msirdi_wheel, theorem3_reaching)
from switchobs.sensors import (VehicleSpeedGain, VehicleSpeedObserver, identify_speed_parameters, vehicle_speed_gain,
                               vehicle_speed_observer)


@pytest.fixture(scope="module")
def wheel():
    run = msirdi_wheel()
    return run, run.trajectory()


def test_msirdi2008_eq15_is_the_euler_step_of_the_observer():
    g = vehicle_speed_gain(5.0)
    obs = VehicleSpeedObserver(g, x3_0=30.0)
    assert obs.derivative(29.0) == -10.0 and obs.derivative(31.0) == 10.0 and obs.derivative(30.0) == 0.0
    assert obs.step(29.0, 0.01) == -10.0 and obs.x3_hat == pytest.approx(29.9)
    assert g.reaching_time_bound(-3.0) == pytest.approx(0.6)
    assert VehicleSpeedGain(beta=5.0, eta=5.0).reaching_time_bound(1.0) == math.inf


def test_msirdi2008_theorem3_reaching_time_within_its_bound_and_shorter_for_a_larger_margin(wheel):
    # x3_hat(0) = x3(0) + 2 m/s: the braking force pushes x3 away from x3_hat, so d|x3_tilde|/dt =
    # -(beta - |xi2|) and t1 lies in [|e0| / (beta + eta), |e0| / (beta - eta)] (the bound of (17))
    rows = [r for r in theorem3_reaching(wheel[0]) if r.margin > 0.0]
    assert len(rows) == 5
    for r in rows:
        assert r.lower_s < r.reached_s <= r.bound_s, r
        # finite time: after t1 the discrete error stays in its band (beta + eta) delta for good
        assert r.after_max_m_s <= r.band_m_s, r
    times = [r.reached_s for r in sorted(rows, key=lambda r: r.margin)]
    assert all(a > b for a, b in zip(times, times[1:])), times


def test_msirdi2008_theorem3_condition_beta_above_eta_matters(wheel):
    below = {r.margin: r for r in theorem3_reaching(wheel[0], (-0.1, -0.5))}
    # beta = eta / 2 is below the mean deceleration: the error grows on average and x3 is never reached
    never = below[-0.5]
    assert never.beta < never.mean_xi2
    assert math.isnan(never.reached_s) and abs(never.final_error_m_s) > 2.0 * MSIRDI_INITIAL_ERROR_M_S
    # beta = 0.9 eta reaches x3 (the mean deceleration is below beta) but loses the sliding motion whenever
    # |xi2| > beta: the error leaves the band (beta + eta) delta by more than ten times
    lost = below[-0.1]
    assert lost.beta > lost.mean_xi2
    assert math.isfinite(lost.reached_s) and lost.after_max_m_s > 10.0 * lost.band_m_s


def test_msirdi2008_eq20_eq21_filtered_injections_tend_to_xi1_xi2(wheel):
    # tau halves and delta / tau halves with it (Sec. IV: tau -> 0, delta / tau -> 0): both errors halve
    rows = equivalent_injection(wheel[0], trajectory=wheel[1])
    for a, b in zip(rows, rows[1:]):
        assert b.xi1_rms < 0.6 * a.xi1_rms and b.xi2_rms < 0.6 * a.xi2_rms, (a, b)
    last = rows[-1]
    assert (last.delta_s, last.tau_s) == (2.5e-5, 0.005)
    # measured 1.9 % and 1.6 % of the largest |xi|: the filter lag tau |d xi / dt| dominates
    assert last.xi1_rel < 0.025 and last.xi2_rel < 0.02


def test_msirdi2008_sec5_theta1_theta2_identified_on_the_quarter_car(wheel):
    run, traj = wheel
    fine = identify_theta(run, trajectory=traj)           # delta = 1e-5
    coarse = identify_theta(run, delta_s=2e-5, trajectory=traj)
    truth = fine.truth
    assert truth == pytest.approx({"theta_11": 0.3 * MSIRDI_STIFFNESS_N, "theta_12": 0.09 * MSIRDI_STIFFNESS_N,
                                   "theta_21": MSIRDI_STIFFNESS_N, "theta_22": 0.3 * MSIRDI_STIFFNESS_N})
    for name, values in fine.identified.items():
        for v in values:
            # measured within 0.4 %; 1 % leaves room for the rounding of a different BLAS
            assert v == pytest.approx(truth[name], rel=0.01), name
    # the bias comes from x2_hat, O(delta) by Theorem 2: it shrinks with the step
    worst = [max(abs(v / truth[k] - 1.0) for k, vs in e.identified.items() for v in vs) for e in (coarse, fine)]
    assert worst[1] < 0.7 * worst[0]
    assert fine.theta2_remark5.radius_m == pytest.approx(0.3, rel=0.005)
    assert fine.theta2_remark4.given_stiffness_radius_nm == fine.theta1.stiffness_radius


def test_vehicle_speed_observer_refuses_bad_input():
    with pytest.raises(SimulationError, match=r"beta = 3 must exceed eta = 5 \(M'Sirdi et al. 2008, Theorem 3\)"):
        vehicle_speed_gain(5.0, beta=3.0)
    with pytest.raises(SimulationError, match="eta must be finite and > 0"):
        vehicle_speed_gain(0.0)
    g = vehicle_speed_gain(5.0)
    with pytest.raises(SimulationError, match=r"x3 \(speed measurements\)\[1\] = nan"):
        vehicle_speed_observer([0.0, 1.0], [1.0, np.nan], gain=g)
    with pytest.raises(SimulationError, match="t must be strictly increasing"):
        vehicle_speed_observer([0.0, 0.0], [1.0, 1.0], gain=g)
    t = np.linspace(0.0, 1.0, 101)
    ones = np.ones(101)
    with pytest.raises(SimulationError, match="speed_m_s must stay positive"):
        identify_speed_parameters(t, ones, ones, -ones, mass_kg=290.0)
    with pytest.raises(SimulationError, match="mass_kg must be finite and > 0"):
        identify_speed_parameters(t, ones, ones, ones, mass_kg=0.0)
    with pytest.raises(SimulationError, match="initial has 2 samples; expected 1"):
        identify_speed_parameters(t, ones, ones, ones, mass_kg=290.0, stiffness_radius_nm=1.0, initial=[1.0, 2.0])
    with pytest.raises(SimulationError, match="identify_speed_parameters needs uniformly spaced samples"):
        identify_speed_parameters(t ** 2, ones, ones, ones, mass_kg=290.0)
