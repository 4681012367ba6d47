"""The brake controller closed on a measured x2 (seed 001 Sec. 6.4, Figs. 6.7-6.9): the hook, the encoder source."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from switchobs.exceptions import SimulationError
from switchobs.loop import EncoderX2
from switchobs.plants import BrakingScenario, FivePhaseABS, X2Measurement, simulate
from switchobs.sensors import Encoder


class Offset:
    """The exact x2 plus a constant, as the controller's measurement."""

    def __init__(self, offset: float):
        self.offset = offset
        self.calls = 0

    def reset(self, t0, y0, vx0):
        self.calls = 0

    def update(self, t, y, vx, u, dt):
        self.calls += 1
        return y + self.offset


SC = BrakingScenario("dry-asphalt", speed_m_s=20.0, duration_s=1.0)


def test_the_exact_x2_as_a_measurement_gives_the_exact_run_within_a_step_per_switch():
    exact, measured = simulate(SC, compiled=False), simulate(SC, x2_source=Offset(0.0))
    assert isinstance(Offset(0.0), X2Measurement)
    assert not measured.compiled
    # the guards are checked at the step ends instead of located: each switch comes at most one step late
    assert measured.metrics.abs_cycles == exact.metrics.abs_cycles
    assert abs(measured.metrics.stopping_distance_m / exact.metrics.stopping_distance_m - 1) < 0.01
    first = [t for t, e in exact.events if "phase 0 -> 1" in e][0]
    late = [t for t, e in measured.events if "phase 0 -> 1" in e][0]
    assert 0.0 <= late - first <= SC.dt_s + 1e-12


def test_the_controller_switches_on_the_measurement_not_on_the_exact_x2():
    blind = simulate(SC, x2_source=Offset(+1000.0))        # never sees a deceleration: the build-up never ends
    assert set(blind.series["phase"]) == {0.0}
    src = Offset(-1000.0)                                  # sees one at once: phase 0 -> 1 at the first step end
    eager = simulate(replace(SC, duration_s=0.01), x2_source=src)
    assert eager.events[0][1] == "phase 0 -> 1" and eager.events[0][0] == pytest.approx(SC.dt_s)
    assert src.calls == len(eager.series["t"]) - 1


def test_the_compiled_loop_refuses_a_measured_x2_and_the_default_falls_back_to_python():
    assert not simulate(SC, x2_source=Offset(0.0)).compiled
    with pytest.raises(SimulationError, match="measured x2"):
        simulate(SC, x2_source=Offset(0.0), compiled=True)


def test_bad_sources_and_settings_are_refused():
    with pytest.raises(SimulationError, match="lacks reset"):
        simulate(SC, x2_source=object())
    enc = Encoder(ppr=60)
    with pytest.raises(SimulationError, match="unknown x2 measurement 'kalman'"):
        EncoderX2("kalman", encoder=enc, radius_m=0.3)
    with pytest.raises(SimulationError, match="cruise_s"):
        EncoderX2("tsa", encoder=enc, radius_m=0.3, cruise_s=-1.0)


def test_the_encoder_source_measures_the_cruise_and_feeds_the_controller():
    sc = BrakingScenario("dry-concrete", speed_m_s=130 / 3.6, duration_s=0.3,
                         controller=replace(FivePhaseABS.fig66(), stall_timeout_s=None, initial_rate_bar_s=300.0))
    src = EncoderX2("three-stage", encoder=Encoder(ppr=60, eccentricity=0.003), radius_m=sc.vehicle.radius_m,
                    cruise_s=0.5)
    res = simulate(sc, x2_source=src)
    rec = src.record()
    assert rec.t[0] < -0.45 and rec.t[-1] == pytest.approx(0.3)
    # at the start of the braking the window is full: every kind of measurement exists
    at0 = np.searchsorted(rec.t, 0.0)
    assert np.all(np.isfinite([rec.x2_tsa[at0], rec.x2_notch[at0], rec.x2_measured[at0]]))
    # the build-up ends when the measurement, not the exact x2, passes -eps0
    t01 = [t for t, e in res.events if e == "phase 0 -> 1"][0]
    k = np.searchsorted(rec.t, t01 - 1e-9)
    assert rec.x2_measured[k] <= -sc.controller.eps[0] < rec.x2_measured[k - 1]


def test_fig67_scenario_needs_its_slow_build_up_with_the_exact_x2():
    """docs/reproductions.md, Sec. 6.4: at the default 1000 bar/s the printed Fig. 6.6 stalls in the release."""
    from switchobs.experiments import fig67_scenario

    sc = replace(fig67_scenario(), duration_s=1.5)
    fast = simulate(replace(sc, controller=replace(sc.controller, initial_rate_bar_s=1000.0)))
    assert [e for _, e in fast.events] == ["phase 0 -> 1"] and fast.series["phase"][-1] == 1.0
    assert fast.series["P_b"][-1] == 0.0
    assert simulate(sc).metrics.abs_cycles >= 3


# ---------------------------------------------------------------- Figs. 6.7-6.9 (docs/reproductions.md, Sec. 6.4)

def _fig67_runs(*kinds, stop_at_split=True, encoder=None):
    from switchobs.experiments import FIG67_ENCODER, FIG67_SPLIT_M_S, HalfWindowLate, fig67_scenario

    sc = fig67_scenario()
    if stop_at_split:                      # the seed's statements are scored above 60 km/h: stop there
        sc = replace(sc, stop_speed_m_s=FIG67_SPLIT_M_S)
    enc = FIG67_ENCODER if encoder is None else encoder
    radius = sc.vehicle.radius_m
    out = {}
    for kind in kinds:
        if kind == "exact":
            out[kind] = simulate(sc)
        elif kind == "half-window":
            out[kind] = simulate(sc, x2_source=HalfWindowLate(radius))
        elif kind == "tsa-ideal":
            out[kind] = simulate(sc, x2_source=EncoderX2("tsa", encoder=Encoder(ppr=60), radius_m=radius))
        else:
            out[kind] = simulate(sc, x2_source=EncoderX2(kind, encoder=enc, radius_m=radius))
    return out


def test_fig67_the_raw_tsa_is_blocked_in_the_hold_before_the_peak_as_the_seed_s_fig67():
    """Seed: "remains blocked in an arbitrary phase ... trapped at the point (-7, 0)"; needs e/r ~ 0.006."""
    from switchobs.experiments import (FIG67_BLOCKED_S, FIG67_ENCODER, FIG67_SMALL_ECCENTRICITY,
                                             excursion, longest_stay)

    res = _fig67_runs("tsa")["tsa"]
    dur, phase, slip, x2 = longest_stay(res)
    assert dur >= FIG67_BLOCKED_S and phase == 5
    # before the friction peak (-16 %), at rest in x2: ours (-7.8 %, 0.6 m/s²), the seed's (-7 %, 0). The point is
    # fitted (FIG67_ENCODER's e/r was derived from it); the run is deterministic, and 1 point of slip, 1 m/s² of x2
    # cover floating-point differences between machines (the six runs over eccentricity phase and initial speed of
    # docs/reproductions.md all block at (-8, 1)) while staying within 1.5 points of the seed's slip
    assert slip == pytest.approx(-0.078, abs=0.01) and abs(slip - (-0.07)) < 0.015
    assert x2 == pytest.approx(0.6, abs=1.0)
    assert res.series["phase"][-1] == 5.0 and excursion(res) < 10.0
    # with our Table 6.1 eccentricity the ripple is too small to fire the hold before the peak: it cycles
    small = _fig67_runs("tsa", encoder=replace(FIG67_ENCODER, eccentricity=FIG67_SMALL_ECCENTRICITY))["tsa"]
    assert longest_stay(small)[0] < FIG67_BLOCKED_S and small.metrics.abs_cycles >= 3


def test_fig67_the_three_stage_loop_cycles_closer_than_the_notch_and_as_a_perfect_encoder():
    from switchobs.experiments import FIG67_BLOCKED_S, excursion, longest_stay

    runs = _fig67_runs("notch", "three-stage", "tsa-ideal")
    exc = {kind: excursion(res) for kind, res in runs.items()}
    for res in runs.values():
        assert res.status == "stopped" and longest_stay(res)[0] < FIG67_BLOCKED_S and res.metrics.abs_cycles >= 4
    # Fig. 6.9: "about 35 m/s^2" beyond the thresholds (seed), ours 37.1, and less than the notch's (ours 57.5:
    # its delay). The run is deterministic; an excursion is the largest x2 past a threshold, which a switch
    # moved by one 1 ms step shifts by up to 2.8 m/s^2 (x2 changes by up to 2800 m/s^3 in this run), so 3 m/s^2 covers
    # floating-point differences between machines; the seed's 35 stays within 5
    assert exc["three-stage"] == pytest.approx(37.1, abs=3.0) and abs(exc["three-stage"] - 35.0) < 5.0
    assert exc["notch"] == pytest.approx(57.5, abs=5.0) and exc["three-stage"] < exc["notch"] - 10.0
    # the compensation removes the whole ripple: what is left is the TSA window's lag
    assert abs(exc["three-stage"] - exc["tsa-ideal"]) < 8.0


def test_fig67_below_60_kmh_the_tsa_window_lag_alone_loses_the_cycle():
    """The measured reason why no TSA-fed loop (a perfect encoder's neither) keeps cycling to a stop."""
    from switchobs.experiments import FIG67_SPLIT_M_S, excursion

    runs = _fig67_runs("exact", "half-window", stop_at_split=False)
    slow = {kind: res.series["vx"] < FIG67_SPLIT_M_S for kind, res in runs.items()}
    exact, late = runs["exact"], runs["half-window"]
    assert excursion(exact, slow["exact"]) < 1.0 and np.min(exact.series["lambda"][slow["exact"]]) > -0.5
    # the same x2, only half a 12-edge window late: far outside the thresholds, and the wheel locks
    assert excursion(late, slow["half-window"]) > 100.0
    assert np.min(late.series["lambda"][slow["half-window"]]) < -0.9
    # above 60 km/h the same lag costs little
    assert excursion(late, ~slow["half-window"]) < 45.0


def test_fig67_open_loop_the_three_stage_estimator_removes_the_ripple_during_the_braking():
    """Neither the deceleration nor the high-pass stage disturbs the identification: what is left is the lag."""
    from switchobs.experiments import fig67_open_loop, fig67_scenario

    err = fig67_open_loop(simulate(fig67_scenario()))
    centre, sample = ({kind: e[i] for kind, e in err.items()} for i in (0, 1))
    assert centre["three-stage"] < 1.5 * centre["tsa-ideal"] + 0.2 < 0.2 * centre["tsa"]
    # against the x2 at the sample the window's lag dominates, with or without imperfection
    assert sample["tsa-ideal"] > 5.0 * centre["tsa-ideal"]
    assert abs(sample["three-stage"] - sample["tsa-ideal"]) < 0.5
    assert sample["notch"] > sample["three-stage"]
