"""The six-phase (Bosch) ABS of seed 001 Sec. 2.2.3 and the two-axle braking of Sec. 3.6 it drives."""

import json
import re

import numpy as np
import pytest

from switchobs.exceptions import SimulationError
from switchobs.plants import BrakingScenario, SixPhaseABS, TwoAxleScenario, aguado_sec36, simulate, simulate_two_axle
from switchobs.experiments import (SEC36_OBSERVER, bosch_sequence, sec36_estimators, sec36_late_excursions,
                                              sec36_settled, sec36_stays)
from switchobs.experiments import Runs


def _bosch(res):
    """The phases visited, as Bosch numbers, from the events (a phase left at its entry instant has no sample)."""
    seq = [1]
    for _, event in res.events:
        m = re.match(r"phase (\d) -> (\d)", event)
        if m and m.group(1) != m.group(2):
            seq.append(SixPhaseABS.BOSCH[int(m.group(2))])
    return seq


def longest_stay(res):
    t, ph = res.series["t"], res.series["phase"]
    starts = np.concatenate([[0], np.flatnonzero(np.diff(ph) != 0) + 1, [t.size - 1]])
    return float(np.max(np.diff(t[starts])))


def test_aguado2020_sec223_six_phase_visits_the_bosch_phases_in_order():
    res = simulate(BrakingScenario("dry-asphalt", speed_m_s=120 / 3.6, controller=SixPhaseABS(), duration_s=2.0))
    seq = "".join(map(str, _bosch(res)))
    # first cycle: apply, hold until lambda1, release, hold, apply above +A, hold, slow apply; then from the
    # second cycle on the release starts at -a directly (phase 8 = second phase 3)
    assert seq.startswith("1234567")
    assert seq[7:].startswith("34567") and seq[7:].count("34567") >= 3
    # each phase has its modulator setting: apply > 0, hold = 0, release < 0
    s = res.series
    for ours, sign in ((1, -1), (2, 0), (3, 1), (4, 0), (5, 1), (6, 0)):
        u = np.round(s["u"][s["phase"] == ours], 9)
        assert u.size == 0 or np.all(np.sign(u) == sign) or (sign == -1 and np.all(u <= 0)), ours
    # the slow apply (Bosch 7) raises the pressure more slowly than the apply above +A (Bosch 5)
    assert np.median(s["u"][s["phase"] == 5]) < np.median(s["u"][s["phase"] == 3])


@pytest.mark.parametrize("name", ["dry-asphalt", "wet-asphalt", "dry-concrete", "dry-cobblestones",
                                  "wet-cobblestones", "snow", "ice"])
def test_six_phase_never_stalls_on_the_table21_roads(name):
    for kmh in (30.0, 200.0):
        res = simulate(BrakingScenario(name, speed_m_s=kmh / 3.6, controller=SixPhaseABS(), duration_s=3.0))
        assert res.metrics.abs_cycles >= 3, (name, kmh)
        assert longest_stay(res) < 1.5, (name, kmh)
        # the wheel keeps turning while the vehicle is fast (no lock-up)
        fast = res.series["vx"] > 5.0
        assert np.mean(res.series["lambda"][fast] > -0.7) > 0.97, (name, kmh)


def test_six_phase_settings_are_checked_and_round_trip_through_json():
    for bad, text in ((dict(a_plus=30.0, a_big=20.0), "+A"), (dict(lock_slip=0.05), "lock_slip"),
                      (dict(u_step=4000.0), "u_step"), (dict(a_minus=-1.0), "a_minus")):
        with pytest.raises(SimulationError, match=re.escape(text)):
            SixPhaseABS(**bad)
    sc = BrakingScenario("snow", speed_m_s=20.0, controller=SixPhaseABS(a_big=25.0))
    assert BrakingScenario.from_json(json.loads(json.dumps(sc.to_json()))) == sc
    with pytest.raises(SimulationError, match="six-phase"):
        aguado_sec36("seven-phase")


@pytest.fixture(scope="module")
def sec36():
    # the observers' a from the loads (3.36) with the measured acceleration, as in seed 001 Sec. 3.6
    sc = aguado_sec36()
    return simulate_two_axle(sc, estimators=sec36_estimators(sc, SEC36_OBSERVER))


@pytest.fixture(scope="module")
def sec36_static():
    # the same with the observers' static-load a
    sc = aguado_sec36()
    return simulate_two_axle(sc, estimators=sec36_estimators(sc, SEC36_OBSERVER, load_signal=False))


def _first_half_second(res, k):
    """RMS of wheel k's XBS error over its first 0.5 s of ABS."""
    s, t = res.series, res.series["t"]
    a = t[np.argmax(s[f"phase_{k}"] > 0)]
    keep = (t >= a) & (t < a + 0.5)
    return float(np.sqrt(np.mean((s[f"xbs_hat_{k}"] - s[f"xbs_{k}"])[keep] ** 2)))


def test_aguado2020_sec36_online_load_helps_the_front_but_the_unmodelled_load_rate_hurts_the_rear(sec36,
                                                                                                   sec36_static):
    from switchobs.plants import road
    m, m0 = sec36.metrics, sec36_static.metrics
    assert m["front"]["xbs_rms_error"] < 0.9 * m0["front"]["xbs_rms_error"]
    assert _first_half_second(sec36, "r") > 1.5 * _first_half_second(sec36_static, "r")
    # the term (R^2/J) dFz/dt mu of dx2/dt, not in (3.2), outweighs the modelled a mu' x2/vx on the rear wheel only
    s, t = sec36.series, sec36.series["t"]
    for k, low, high in (("f", 0.0, 0.5), ("r", 1.0, np.inf)):
        a = t[np.argmax(s[f"phase_{k}"] > 0)]
        keep = (t >= a) & (t < a + 0.5)
        unmodelled = np.gradient(s[f"Fz_{k}"], t) * road("dry-asphalt").mu_array(s[f"lambda_{k}"])
        modelled = s[f"Fz_{k}"] * s[f"xbs_{k}"] * s[f"x2_{k}"] / s["vx"]
        assert low < np.sqrt(np.mean(unmodelled[keep] ** 2) / np.mean(modelled[keep] ** 2)) < high


def test_aguado2020_fig319_reapproach_within_half_a_second_with_the_online_load(sec36, sec36_static):
    # Fig. 3.19: "re-approach their true values within 0.5 s" after both road changes, on both wheels, read as
    # the error's 100 ms RMS back within 10 % of the XBS range; with the static-load a the rear wheel misses it
    # after the change to wet asphalt (its load there is about 2/3 of the static one)
    end = float(sec36.series["t"][-1])
    for k in "fr":
        for a, b in ((2.5, 5.0), (5.0, end)):
            assert sec36_settled(sec36, k, a, b) <= 0.5
    static, sc = sec36_static, sec36_static.scenario
    assert sec36_settled(static, "r", 5.0, float(static.series["t"][-1])) > 0.5
    wet = static.series["t"] >= 5.0
    assert np.mean(static.series["Fz_r"][wet]) < 0.7 * sc.vehicle.static_loads[1]


def test_aguado2020_fig319_strict_reading_fails_on_snow_at_the_recoveries(sec36):
    # the error stays within the band from 0.5 s after the change to wet asphalt on, but not after the change to
    # snow: it leaves the band again only at recoveries after a release (the true XBS on the stable side)
    s, t = sec36.series, sec36.series["t"]
    end = float(t[-1])
    for k in "fr":
        assert sec36_stays(sec36, k, 5.0, end) <= 0.5
        assert sec36_stays(sec36, k, 2.5, 5.0) > 0.5
        stretches = sec36_late_excursions(sec36, k, 2.5, 5.0)
        assert 1 <= len(stretches) <= 3
        for t0, t1 in stretches:
            during = (t >= t0) & (t <= t1)
            assert t1 - t0 < 0.2 and np.all(s[f"xbs_{k}"][during] > 0.0)


def test_aguado2020_sec36_c_hat_on_snow_moves_only_at_the_recoveries(sec36):
    # what limits the strict reading: c_hat has not converged to the snow's c = 94.1 half a second after the
    # change (front above it, rear below) and changes (almost) only while the wheel is on the stable side
    rows = Runs().sec36_c_hat          # the fixture's run again (deterministic), recording c_hat
    t, s = sec36.series["t"], sec36.series
    for k, bounds in (("f", (1.2, 2.0)), ("r", (0.2, 0.7))):
        tt, ch = rows[k][:, 0], rows[k][:, 1]
        np.testing.assert_array_equal(tt, t[1:])
        assert bounds[0] * 94.129 < ch[np.searchsorted(tt, 3.0)] < bounds[1] * 94.129
        keep = ((tt >= 3.0) & (tt < 5.0))[1:]
        stable = (np.interp(tt, t, s[f"xbs_{k}"]) > 0.0)[1:][keep]
        moved = np.abs(np.diff(ch))[keep]
        assert moved[stable].sum() > 0.9 * moved.sum() and stable.mean() < 0.4


def test_aguado2020_sec36_six_phase_with_the_adaptive_observer(sec36):
    m, s, t = sec36.metrics, sec36.series, sec36.series["t"]
    assert isinstance(sec36.scenario.front, SixPhaseABS) and sec36.status == "stopped" and sec36.failure is None
    # the Bosch cycle on each wheel, releases throughout
    for k, axle in (("f", "front"), ("r", "rear")):
        seq = "".join(map(str, bosch_sequence(sec36, k)))
        assert seq.count("34567") >= 5 and m[axle]["abs_cycles"] >= 10
    # speed underestimated on average: ours -14.9 % (docs/reproductions.md, Sec. 3.6), the seed's -18 %. The run
    # is deterministic (fixed seeds, fixed steps); one point covers floating-point differences between machines and
    # still leaves the seed's value out: the filter is ours (the seed's [19] is not described), so the page gives
    # the 3.1 points of deviation rather than claim the seed's number
    assert m["speed_error_mean_pct"] == pytest.approx(-14.9, abs=1.0)
    assert abs(m["speed_error_mean_pct"] - (-18.0)) > 2.0
    # the pressure is drastically reduced on snow (Fig. 3.16)
    dry, snow = (t > 0.75) & (t < 2.5), (t > 3.0) & (t < 5.0)
    assert s["P_f"][snow].mean() < 0.3 * s["P_f"][dry].mean()
    # the estimates stay bounded and follow the XBS (front: right sign most of the time, Fig. 3.18)
    assert m["front"]["xbs_rms_error"] < 5.0 and m["rear"]["xbs_rms_error"] < 5.0
    on = t > 0.5
    assert np.mean(np.sign(s["xbs_hat_f"][on]) == np.sign(s["xbs_f"][on])) > 0.8
    # the ABS takes over at about the seed's times: 0.75 s front, 0.50 s rear
    start = {k: t[np.argmax(s[f"phase_{k}"] > 0)] for k in "fr"}
    assert start["f"] == pytest.approx(0.75, abs=0.05) and start["r"] == pytest.approx(0.50, abs=0.05)


def test_aguado2020_sec36_true_signals_run_reads_the_true_speed():
    sc = TwoAxleScenario("dry-asphalt", speed_m_s=30.0, front=SixPhaseABS(), rear=SixPhaseABS(), duration_s=1.0,
                         speed_from_filter=False)
    s = simulate_two_axle(sc).series
    np.testing.assert_array_equal(s["vx_hat"][1:], s["vx"][1:])
    assert TwoAxleScenario.from_json(json.loads(json.dumps(sc.to_json()))) == sc


def test_aguado2020_sec36_signs_disagree_only_near_zero_xbs(sec36):
    # Fig. 3.18 "the zero-crossing of the estimate coincides with that of the real XBS": the share of the time
    # with equal signs (rear about 65 %) is not that claim; away from XBS = 0 the signs agree on both wheels
    s, t = sec36.series, sec36.series["t"]
    for k in "fr":
        on = t >= t[np.argmax(s[f"phase_{k}"] > 0)]
        xbs, hat = s[f"xbs_{k}"][on], s[f"xbs_hat_{k}"][on]
        away = np.abs(xbs) > 0.1 * np.ptp(xbs)
        assert np.mean(np.sign(hat[away]) == np.sign(xbs[away])) > 0.99
    rear = t >= t[np.argmax(s["phase_r"] > 0)]
    assert np.mean(np.sign(s["xbs_hat_r"][rear]) == np.sign(s["xbs_r"][rear])) < 0.8


@pytest.mark.parametrize("dt, h_max, bounded", [(1e-3, None, False), (5e-4, None, True), (1e-3, 1e-4, True)])
def test_aguado2020_sec36_default_gamma_diverges_by_the_explicit_step_not_by_the_observer(dt, h_max, bounded):
    # Gamma = 1e4 I (the seed gives none) with the RK4 step: unstable at 1 ms on the front wheel (the largest
    # a = R^2 Fz / J), stable at 0.5 ms or with the observer sub-stepped in rescaled time: the discretisation fails
    from dataclasses import replace

    from switchobs.loop import DEFAULT_GAMMA, INITIAL_STATE, ObserverXbsEstimator
    from switchobs.observers import adaptive_xbs_observer
    sc = replace(aguado_sec36(), duration_s=1.0, dt_s=dt)

    def estimator(axle):
        q = sc.vehicle.corner(axle)
        obs = adaptive_xbs_observer(100.0, [DEFAULT_GAMMA] * 2, params={"a": q.a, "b": q.b}, h_max=h_max,
                                    max_substeps=None if h_max is None else 1000)
        return ObserverXbsEstimator(obs, initial_state=INITIAL_STATE["adaptive"])
    with np.errstate(over="ignore", invalid="ignore"):
        res = simulate_two_axle(sc, estimators=(estimator("front"), estimator("rear")))
    front = res.metrics["front"]["xbs_rms_error"]
    assert (front is not None and np.isfinite(front) and front < 20.0) == bounded
    assert res.metrics["rear"]["xbs_rms_error"] < 20.0
