"""Quarter-car braking simulations: plant (2.1), controllers, event location, metrics, Table 4.1."""

from dataclasses import replace

import numpy as np
import pytest

from switchobs.exceptions import SimulationError
from switchobs.plants import (GRAVITY, TABLE41_SEED, BrakeActuator, BrakingScenario, ContinuousXbsControl,
                              FivePhaseABS, PrescribedSpeed, QuarterCar, RoadChange, RoadSchedule, TrueXbs,
                              TwoPhaseABS, XbsEstimator, assumption1, road, scenario, simulate, table41)


def _braking(name="dry-asphalt", kmh=60.0, **kw):
    return BrakingScenario(name, speed_m_s=kmh / 3.6, **kw)


@pytest.fixture(scope="module")
def dry60():
    return simulate(_braking())


def test_aguado2020_eq21_plant_outputs_are_consistent(dry60):
    s = dry60.series
    veh = dry60.scenario.vehicle
    r = road("dry-asphalt")
    assert dry60.status == "stopped" and s["vx"][-1] == pytest.approx(2.5 / 3.6, abs=1e-9)
    np.testing.assert_allclose(s["lambda"], (veh.radius_m * s["omega"] - s["vx"]) / s["vx"], atol=1e-12)
    np.testing.assert_allclose(s["mu"], r.mu_array(s["lambda"]), atol=1e-12)
    np.testing.assert_allclose(s["xbs"], r.xbs_array(s["lambda"]), atol=1e-9)
    # (2.1b) with m = Fz/g: a_x = g mu; (2.1a): J domega = -R Fz mu - gamma_b P_b
    np.testing.assert_allclose(s["ax"], GRAVITY * s["mu"], atol=1e-9)
    np.testing.assert_allclose(veh.inertia_kg_m2 * s["omega_dot"],
                               -veh.radius_m * veh.load_n * s["mu"] - veh.brake_gain_nm_bar * s["P_b"], atol=1e-8)
    np.testing.assert_allclose(s["x2"], veh.radius_m * s["omega_dot"] - s["ax"], atol=1e-9)
    # the recorded pressure rate integrates to the pressure, the speed to the distance
    t = s["t"]
    assert np.all(np.diff(t) > 0)
    assert np.all(np.abs(s["u"]) <= dry60.scenario.actuator.max_rate_bar_s + 1e-9)
    x = np.concatenate([[0.0], np.cumsum(0.5 * (s["vx"][1:] + s["vx"][:-1]) * np.diff(t))])
    np.testing.assert_allclose(s["x"], x, rtol=1e-4, atol=1e-4)


def test_five_phase_follows_its_automaton(dry60):
    eps = FivePhaseABS().eps
    allowed = {(0, 1), (1, 2), (2, 3), (2, 4), (3, 4), (4, 5), (5, 1)}
    s = dry60.series
    entered = 0.0
    for t, what in dry60.events:
        a, b = (int(v) for v in what.split()[1:4:2])
        if what.endswith("(stall timeout)"):      # the stall exit: a hold 5 or a release 1 that lasted too long
            assert (a, b) in {(5, 1), (5, 4), (1, 4)} and t - entered == pytest.approx(0.1)
            entered = t
            continue
        entered = t
        assert (a, b) in allowed
        x2 = np.interp(t, s["t"], s["x2"])
        thr = {(0, 1): -eps[0], (1, 2): eps[1], (2, 3): eps[2], (2, 4): eps[1], (3, 4): eps[3],
               (4, 5): -eps[4], (5, 1): -eps[5]}[(a, b)]
        assert x2 == pytest.approx(thr, abs=1e-6)     # event located on the threshold, not at a step end
    assert dry60.metrics.abs_cycles >= 3
    # phase 1 releases (down to 0 bar at most), 2 and 5 hold, 3 and 4 apply (open loop)
    assert {1, 2, 4, 5} <= set(s["phase"].astype(int))
    for p, sign in ((1, -1), (2, 0), (3, 1), (4, 1), (5, 0)):
        u = np.round(s["u"][s["phase"] == p], 9)
        assert np.all(np.sign(u) == sign) or (sign == -1 and np.all(u <= 0))


@pytest.mark.parametrize("ctrl", [FivePhaseABS(), TwoPhaseABS(), FivePhaseABS(tracking=True)],
                         ids=["five-phase", "two-phase", "five-phase-tracking"])
def test_results_change_less_than_1_percent_when_the_step_is_halved(ctrl):
    sc = _braking("wet-asphalt", 90.0, controller=ctrl)
    a = simulate(sc, estimator="true" if ctrl.uses_xbs else None).metrics
    b = simulate(sc.with_step(sc.dt_s / 2), estimator="true" if ctrl.uses_xbs else None).metrics
    for key in ("braking_distance_m", "stopping_distance_m", "mean_friction", "stop_time_s"):
        assert getattr(a, key) == pytest.approx(getattr(b, key), rel=0.01), key
    assert a.abs_cycles == pytest.approx(b.abs_cycles, rel=0.1)


def test_step_halving_with_observer_and_road_changes():
    from switchobs.loop import ObserverXbsEstimator
    from switchobs.observers import adaptive_xbs_observer
    sc = replace(scenario("aguado-sec34"), duration_s=4.0)

    def run(dt):
        est = ObserverXbsEstimator(adaptive_xbs_observer(100.0, [1e4, 1e4], params={"a": sc.vehicle.a,
                                                                                   "b": sc.vehicle.b}),
                                   initial_state={"c": 20.0, "d": 10.0})
        return simulate(sc.with_step(dt), estimator=est).metrics
    a, b = run(1e-3), run(5e-4)
    assert a.mean_friction == pytest.approx(b.mean_friction, rel=0.01)
    assert a.stopping_distance_m == pytest.approx(b.stopping_distance_m, rel=0.01)
    assert a.xbs_rms_error == pytest.approx(b.xbs_rms_error, rel=0.05)


@pytest.fixture(scope="module")
def table41_runs():
    return table41()


def test_aguado2020_table41_two_phase_shorter(table41_runs):
    res = table41_runs
    assert len(res.rows) == 15 and res.two_phase_always_shorter
    for row in res.rows:
        seed5, seed2 = TABLE41_SEED[(row.speed_kmh, row.road)]
        # magnitude: our distances within 5 % of the thesis's (exact equality is not expected: the
        # five-phase parameters are ours), the five-phase with its stall exit included
        assert row.five_phase_m == pytest.approx(seed5, rel=0.05)
        assert row.two_phase_m == pytest.approx(seed2, rel=0.04)
        # the simulated stop distance agrees (to 0.5 %: at 60 km/h on dry cobblestones the two-phase start-up
        # on the true XBS brakes less in the first 0.1 s, which the time-averaged friction of the table weighs less)
        assert row.two_phase_stopping_m < 1.005 * row.five_phase_stopping_m
    assert "two-phase shorter on every road and speed: True" in str(res)


def _peak_share(speed_kmh, name, distance_m):
    return (speed_kmh / 3.6) ** 2 / (2 * GRAVITY * distance_m) / abs(road(name).peak_friction)


def test_aguado2020_table41_difference_column_wider_on_two_roads_and_why(table41_runs):
    """The Difference column is wider than the seed's (up to 3.3 m against 1.5 m); the page explains it by the
    share of the peak friction each ABS uses, per road: this pins that explanation."""
    def shares(road_name, five, two):
        """Mean share of the peak over the speeds: (five-phase, two-phase)."""
        rows = [r for r in table41_runs.rows if r.road == road_name]
        return tuple(np.mean([_peak_share(r.speed_kmh, road_name, getattr(r, f)) for r in rows]) for f in (five, two))
    roads = sorted({r.road for r in table41_runs.rows})
    seed = {n: shares(n, "seed_five_phase_m", "seed_two_phase_m") for n in roads}
    ours = {n: shares(n, "five_phase_m", "two_phase_m") for n in roads}
    # the seed's own data: on wet cobblestones its two-phase uses least of the peak, barely above its five-phase
    assert min(seed, key=lambda n: seed[n][1]) == "wet-cobblestones"
    assert seed["wet-cobblestones"][1] - seed["wet-cobblestones"][0] < 0.005
    assert all(seed[n][1] - seed[n][0] > 0.005 for n in roads if n not in ("wet-cobblestones", "dry-cobblestones"))
    # ours: the two-phase on wet cobblestones is as close to the peak as on the dry roads
    assert ours["wet-cobblestones"][1] > 0.99 > seed["wet-cobblestones"][1] + 0.01
    # and the widest gaps in metres sit on the two cobblestone roads
    widest = sorted(table41_runs.rows, key=lambda r: (r.two_phase_m - r.five_phase_m)
                    - (r.seed_two_phase_m - r.seed_five_phase_m))[:4]
    assert {r.road for r in widest} <= {"wet-cobblestones", "dry-cobblestones"}


def test_aguado2020_table41_two_phase_shorter_with_the_adaptive_observer_in_the_loop():
    from switchobs.loop import xbs_estimator
    res = table41(speeds_kmh=(60.0,), estimator_factory=lambda sc: xbs_estimator("adaptive", sc.vehicle,
                                                                                  sc.roads.initial),
                  observer="adaptive")
    assert all(r.complete for r in res.rows) and res.two_phase_always_shorter
    for row in res.rows:
        assert row.two_phase_m == pytest.approx(TABLE41_SEED[(60.0, row.road)][1], rel=0.04)


def test_braking_distance_definition_of_table41(dry60):
    m = dry60.metrics
    t, mu = dry60.series["t"], dry60.series["mu"]
    mean = -np.trapezoid(mu, t) / t[-1]
    assert m.mean_friction == pytest.approx(mean, rel=1e-12)
    assert m.braking_distance_m == pytest.approx((60 / 3.6) ** 2 / (2 * GRAVITY * mean), rel=1e-12)
    assert 0.9 < m.efficiency < 1.0


def test_two_phase_cycle_keeps_xbs_between_thresholds():
    ctrl = TwoPhaseABS()
    res = simulate(_braking("dry-concrete", 120.0, controller=ctrl))
    s = res.series
    cyc = (s["phase"] >= 1) & (s["t"] > 0.8)
    # the XBS oscillates around 0 (optimal slip): overshoots of the thresholds stay small
    assert ctrl.chi_a - 0.25 < s["xbs"][cyc].min() < ctrl.chi_a
    assert ctrl.chi_b < s["xbs"][cyc].max() < ctrl.chi_b + 0.25
    lam_opt = road("dry-concrete").optimal_slip
    assert abs(res.metrics.slip_mean - lam_opt) < 0.03
    assert res.metrics.assumption1.holds


def test_aguado2020_sec41_continuous_control_loses_persistency_of_excitation():
    from switchobs.loop import ObserverXbsEstimator
    from switchobs.observers import adaptive_xbs_observer
    veh = QuarterCar()

    def observer():
        return ObserverXbsEstimator(adaptive_xbs_observer(100.0, [1e4, 1e4], params={"a": veh.a, "b": veh.b}),
                                    initial_state={"c": 20.0, "d": 10.0})
    cont = simulate(_braking("dry-asphalt", 90.0, controller=ContinuousXbsControl()), estimator=observer(),
                    observer_in_loop=False)
    hyb = simulate(_braking("dry-asphalt", 90.0, controller=TwoPhaseABS()), estimator=observer(),
                   observer_in_loop=False)
    s = cont.series
    late = s["t"] > 1.0
    # the state-feedback law settles the wheel (Fig. 4.1): z2 and z1 stop moving and z1 keeps one sign
    # (on the non-simplified plant z1 -> a_x lambda, about 2 m/s², instead of 0 on the model (4.1))
    assert np.ptp(s["xbs"][late]) < 0.01 and np.ptp(s["x2"][late]) < 0.1
    a1 = cont.metrics.assumption1
    assert a1.crossings <= 1 and a1.dwell_time_s is None and not a1.holds
    h1 = hyb.metrics.assumption1
    assert h1.holds and h1.crossings > 20 and h1.regressor_pe > 3 * a1.regressor_pe
    # the observer run beside the loop settles on a wrong XBS; with the two-phase ABS it tracks the truth
    err_c = np.abs(s["xbs_hat"] - s["xbs"])[late]
    err_h = np.abs(hyb.series["xbs_hat"] - hyb.series["xbs"])[hyb.series["t"] > 1.0]
    assert np.median(err_c) > 0.2 and np.median(err_c) > 3 * np.median(err_h)


def test_aguado2020_fig42_continuous_law_singular_with_bad_estimate():
    class Far:   # an estimate that crosses c z2 + d = 0 (Fig. 4.2(b))
        def reset(self, t0, y0, vx0):
            self.v = 0.0

        def update(self, t, y, vx, u, dt):
            self.v -= 2.0 * dt
            return self.v
    res = simulate(_braking(controller=ContinuousXbsControl()), estimator=Far())
    assert res.status == "controller-singular" and "c z2 + d" in res.message


def _longest_stay(res, phase):
    t, ph = res.series["t"], res.series["phase"]
    edges = np.flatnonzero(np.diff(np.concatenate([[0], (ph == phase).astype(int), [0]])))
    return max((t[min(j, len(t) - 1)] - t[i] for i, j in zip(edges[::2], edges[1::2])), default=0.0)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["dry-asphalt", "wet-asphalt", "dry-concrete", "dry-cobblestones",
                                  "wet-cobblestones", "snow", "ice"])
def test_aguado2020_sec223_five_phase_never_stalls_in_hold_5(name):
    # seed 001 Sec. 2.2.3: the pressure is re-applied stepwise after a hold; Fig. 6.6 as printed stalls in
    # hold 5 on dry cobblestones above 120 km/h and on ice (3-15 s); the stall exit bounds every stay
    ctrl = FivePhaseABS()
    for kmh in (30.0, 120.0, 200.0):
        res = simulate(_braking(name, kmh, controller=ctrl, duration_s=6.0))
        assert res.metrics.abs_cycles >= 2, (name, kmh)
        assert _longest_stay(res, 5) <= ctrl.stall_timeout_s + 1e-9, (name, kmh)
    printed = simulate(_braking("dry-cobblestones", 180.0, controller=replace(ctrl, stall_timeout_s=None)))
    assert _longest_stay(printed, 5) > 3.0


def _sec34_run(spec, duration_s=None):
    from switchobs.loop import xbs_estimator
    sc = scenario("aguado-sec34")
    sc = sc if duration_s is None else replace(sc, duration_s=duration_s)
    return simulate(sc, estimator=xbs_estimator(spec, sc.vehicle, sc.roads.initial)).metrics


def _reconverged(metrics, label):
    return next(r.time_s for r in metrics.reconvergence if r.label == label)


@pytest.mark.slow
def test_aguado2020_sec34_adaptive_reconverges_and_beats_the_augmented_observers_at_the_scenario_gains():
    # seed 001 Sec. 3.4 with the gains of the scenario (and of the CLI and docs/reproductions.md, chosen by us):
    # back within the 10 % band 0.1 s after each road change, and a lower RMS error than the augmented observers of
    # seed 000 at any of the rates tried; the library defaults (beta = 100) leave the band until late on wet asphalt
    from switchobs.loop import EstimatorSpec
    from switchobs.plants import scenario_observer_gains
    gains = scenario_observer_gains("aguado-sec34")
    m = _sec34_run(EstimatorSpec("adaptive", **gains))
    for label in ("-> wet-asphalt", "-> dry-concrete"):
        assert _reconverged(m, label) is not None and _reconverged(m, label) <= 0.1
    augmented = [_sec34_run(EstimatorSpec(kind, beta=beta)).xbs_rms_error
                 for kind in ("xbs3", "xbs4") for beta in (70.0, 100.0, 150.0)]
    assert m.xbs_rms_error < min(augmented)
    assert gains["beta"] != 100.0 and not _reconverged(_sec34_run(EstimatorSpec("adaptive")), "-> wet-asphalt") < 1.0


class _Recorder:
    """An adaptive-observer estimator keeping (c_hat, d_hat, Upsilon_w1_c, Upsilon_w1_d) after every sample."""

    def __init__(self, gamma, beta=100.0, initial=None, h_max=1e-4):
        from switchobs.loop import INITIAL_STATE, ObserverXbsEstimator
        from switchobs.observers import adaptive_xbs_observer
        car = scenario("aguado-sec34").vehicle
        obs = adaptive_xbs_observer(beta, [gamma, gamma], params={"a": car.a, "b": car.b}, h_max=h_max,
                                    max_substeps=None if h_max is None else 1000)
        self.est = ObserverXbsEstimator(obs, initial_state=initial or INITIAL_STATE["adaptive"])
        self.theta = []

    def reset(self, t0, y0, vx0):
        self.est.reset(t0, y0, vx0)
        self.theta = [self.est.state[2:6]]

    def update(self, t, y, vx, u, dt):
        out = self.est.update(t, y, vx, u, dt)
        self.theta.append(self.est.state[2:6])
        return out


@pytest.mark.slow
def test_aguado2020_sec34_the_road_change_not_the_step_limits_the_adaptive_observer():
    # docs/reproductions.md, Sec. 3.4: sub-stepped, Gamma = 3e4 I runs at beta = 100 (it blows up at the plain 1 kHz
    # step), yet the RMS error grows with Gamma; the change to wet asphalt kicks c_hat from the dry road's value past
    # the wet one's, and the wet ABS cycle hardly excites c: at the scenario's gains c_hat is not re-identified
    from switchobs.plants import scenario_observer_gains
    sc = scenario("aguado-sec34")
    dry, wet = road("dry-asphalt"), road("wet-asphalt")

    def run(rec):
        with np.errstate(over="ignore", invalid="ignore"):
            res = simulate(sc, estimator=rec)
        return res, np.array(rec.theta)

    plain, _ = run(_Recorder(3e4, h_max=None))
    assert not plain.metrics.xbs_rms_error < 1e3
    runs = {g: run(_Recorder(g)) for g in (1e4, 3e4, 1e5)}
    rms = [res.metrics.xbs_rms_error for res, _ in runs.values()]
    assert rms[0] < rms[1] < rms[2] < 1.0
    res, theta = runs[1e4]
    t = res.series["t"]
    before, after = theta[np.searchsorted(t, 3.0), 0], theta[np.searchsorted(t, 3.1), 0]
    assert abs(before - dry.c) < 0.05 * dry.c and after > wet.c + 0.5 * (wet.c - dry.c) + 10.0

    def excitation(a, b):   # smallest eigenvalue of the integral of Upsilon_1' Upsilon_1, which drives (3.4b)
        keep = (t >= a) & (t < b)
        u1, dt = theta[keep, 2:4], np.diff(t[keep], append=t[keep][-1])
        return np.linalg.eigvalsh(np.einsum("ki,kj,k->ij", u1, u1, dt))[0]
    dry_x, wet_x, concrete_x = excitation(1.5, 2.5), excitation(4.0, 5.0), excitation(8.0, 9.0)
    assert wet_x < min(dry_x, concrete_x) and 1.0 / (1e4 * wet_x) > 2.0     # the slowest time constant: seconds
    gains = scenario_observer_gains("aguado-sec34")
    chosen, theta = run(_Recorder(gains["gamma"], beta=gains["beta"], h_max=None))
    assert abs(theta[np.searchsorted(chosen.series["t"], 5.99), 0] - wet.c) > 0.2 * wet.c
    # the initial estimates are forgotten by the first change: the start of the ABS identifies dry asphalt
    short = replace(sc, duration_s=3.0)
    for initial in ({"c": 40.0, "d": 20.0}, {"c": dry.c, "d": dry.d}):
        rec = _Recorder(1e4, initial=initial)
        simulate(short, estimator=rec)
        assert rec.theta[-1][:2] == pytest.approx([dry.c, dry.d], rel=0.05)


def test_hoang2014_fig3_perturbed_by_the_25ms_transition_then_reconverged_in_a_fraction_of_a_second():
    """Seed 000 Fig. 3 (dry -> wet, transitions "which last 25 ms", Sec. IV-D): "highly perturbed by the swift road
    transition but [...] once the transition is over, it converges again in a fraction of a second"."""
    from switchobs.experiments import Runs, reconverged
    from switchobs.plants import scenario_observer

    sc = scenario("hoang-fig3")
    (change,) = sc.roads.changes
    assert change.duration_s == pytest.approx(0.025) and change.road.name == "hoang-wet"
    assert scenario_observer("hoang-fig3") == "xbs4"      # the unknown-road observer of Sec. IV, as the figure's
    res = Runs().default_run("hoang-fig3")
    s, t0 = res.series, change.at_time_s
    err = np.abs(s["xbs_hat"] - s["xbs"])
    back = next(r for r in res.metrics.reconvergence if r.label == "-> hoang-wet")
    # perturbed: the error during the transition and just after it is many times the 10 % band it re-enters, while
    # before the change it stays well inside it
    assert back.settle_start_s == pytest.approx(t0 + change.duration_s)
    assert err[(s["t"] >= t0) & (s["t"] < t0 + 0.2)].max() > 20 * back.band
    assert err[(s["t"] > t0 - 0.5) & (s["t"] < t0)].max() < 0.5 * back.band
    # re-converged "in a fraction of a second": ours 0.141 s after the end of the transition (docs/reproductions.md);
    # the run is deterministic, and 20 ms (20 samples of the 1 kHz loop) covers floating-point differences
    # between machines while staying far below the seed's second
    assert reconverged(res, "-> hoang-wet") == pytest.approx(0.141, abs=0.02) and back.time_s < 1.0


def test_hoang2014_sec5_five_phase_stalls_after_a_road_change_without_timeout():
    sc = scenario("aguado-sec34")
    stuck = simulate(replace(sc, controller=replace(sc.controller, stall_timeout_s=None)))
    ok = simulate(sc)
    late = [t for t, e in stuck.events if e.startswith("phase") and t > 6.0]
    assert not late                       # no phase change after the switch to dry concrete: stalled
    assert sum(1 for t, e in ok.events if e.startswith("phase") and t > 6.0) > 10
    assert any("stall timeout" in e for _, e in ok.events)


def test_observer_protocol_receives_the_measured_signals():
    class Recorder:
        def reset(self, t0, y0, vx0):
            self.rows = [(t0, y0, vx0, 0.0, 0.0)]

        def update(self, t, y, vx, u, dt):
            self.rows.append((t, y, vx, u, dt))
            return 0.0
    rec = Recorder()
    assert isinstance(rec, XbsEstimator)
    res = simulate(_braking(), estimator=rec, observer_in_loop=False)
    rows = np.array(rec.rows)
    s = res.series
    np.testing.assert_allclose(rows[:, 0], s["t"])
    np.testing.assert_allclose(rows[:, 1], s["x2"])
    np.testing.assert_allclose(rows[:, 2], s["vx"])
    np.testing.assert_allclose(np.diff(s["t"]), rows[1:, 4])
    np.testing.assert_allclose(np.cumsum(rows[1:, 3] * rows[1:, 4]), s["P_b"][1:], atol=1e-9)
    oracle = simulate(_braking(controller=TwoPhaseABS()), estimator="true")
    assert oracle.metrics.xbs_rms_error < 1e-12 and oracle.observer == "TrueXbs"
    assert TrueXbs(lambda: 1.5).update(0.0, 0.0, 1.0, 0.0, 0.1) == 1.5


def test_road_changes_by_time_and_position_blend_smoothly():
    roads = RoadSchedule("dry-asphalt", [RoadChange("wet-asphalt", at_time_s=0.6, duration_s=0.025),
                                         RoadChange("snow", at_position_m=20.0, duration_s=0.05)])
    res = simulate(BrakingScenario(roads, speed_m_s=25.0, speed_profile=PrescribedSpeed(1.96), duration_s=1.5))
    starts = [(t, e) for t, e in res.events if e.startswith("road")]
    assert starts[0][0] == pytest.approx(0.6, abs=1e-12)
    t, x = res.series["t"], res.series["x"]
    assert np.interp(starts[1][0], t, x) == pytest.approx(20.0, abs=1e-9)
    # the prescribed speed: vx = 25 - 1.96 t exactly; x2 uses a_x = -1.96
    np.testing.assert_allclose(res.series["vx"], 25.0 - 1.96 * t, atol=1e-9)
    np.testing.assert_allclose(res.series["ax"], -1.96)
    assert res.metrics.braking_distance_m is None
    # blended friction: no jump at the transitions
    mu = res.series["mu"]
    assert np.max(np.abs(np.diff(mu))) < 0.05


def test_actuator_delay_and_rate_limit():
    base = _braking(controller=FivePhaseABS())
    slow = simulate(replace(base, actuator=BrakeActuator(max_rate_bar_s=300.0)))
    assert np.max(np.abs(slow.series["u"])) <= 300.0 + 1e-9
    delayed = simulate(replace(base, actuator=BrakeActuator(delay_s=0.01)))
    ref = simulate(base)
    assert delayed.status == "stopped"
    assert delayed.metrics.braking_distance_m != pytest.approx(ref.metrics.braking_distance_m, rel=1e-4)
    # the applied rate lags the command by the delay: the first pressure change starts 10 ms late
    first = delayed.series["t"][np.argmax(delayed.series["P_b"] > 0)]
    assert first == pytest.approx(0.01, abs=2e-3)


def test_assumption1_on_known_signals():
    t = np.linspace(0.0, 2.0, 20001)
    y = 10.0 * np.sin(2 * np.pi * 5 * t)
    st = assumption1(t, y, np.full_like(t, 20.0))
    assert st.crossings == 19 and st.dwell_time_s == pytest.approx(0.1, abs=1e-6)
    assert st.min_crossing_slope == pytest.approx(100 * np.pi, rel=1e-3)
    assert st.pe_level == pytest.approx(10.0, rel=1e-3)          # ∫ 100 sin² over 0.2 s
    assert st.tau_final == pytest.approx(2 * 10 * 2 / np.pi / 20, rel=1e-3)
    assert st.holds and st.regressor_pe is None
    assert not assumption1(t, 1e-3 * y, np.full_like(t, 20.0)).holds       # PE level 1e-5 < 1
    short = assumption1(t[:1000], y[:1000], np.full(1000, 20.0))             # 0.1 s < T0
    assert short.pe_level is None and not short.holds


@pytest.mark.parametrize("make, match", [
    (lambda: _braking(kmh=-10.0), r"initial speed speed_m_s must be > 0, got -2.7"),
    (lambda: _braking(duration_s=-1.0), r"duration_s must be > 0, got -1.0"),
    (lambda: _braking("gravel"), r"unknown road surface 'gravel'"),
    (lambda: FivePhaseABS(eps=(50, 30, 20, 10, 20, 30)), r"thresholds out of order: eps2 = 20.0 must exceed eps1"),
    (lambda: FivePhaseABS(eps=(50, 30, 40, 20, 30, 20)), r"out of order: eps5 = 20.0 must exceed eps4 = 30.0"),
    (lambda: FivePhaseABS(eps=(50, 30, 40)), r"needs 6 thresholds"),
    (lambda: FivePhaseABS(u1=0.0), r"u1 must be > 0, got 0.0"),
    (lambda: TwoPhaseABS(chi_a=0.2, chi_b=0.1), r"thresholds out of order: need chi_a <= 0 < chi_b"),
    (lambda: _braking(dt_s=0.05), r"dt_s = 0.05 s is too coarse"),
    (lambda: _braking(stop_speed_m_s=30.0), r"stop speed 30 m/s must be below the initial speed"),
    (lambda: _braking(actuator=BrakeActuator(delay_s=1e-4)), r"delay of 0.0001 s is shorter than the step"),
    (lambda: RoadSchedule("snow", [RoadChange("ice", at_time_s=2.0), RoadChange("snow", at_time_s=1.0)]),
     r"starts before the previous transition ends"),
    (lambda: RoadChange("ice"), r"needs exactly one of at_time_s and at_position_m"),
    (lambda: scenario("fig99"), r"unknown scenario 'fig99'; known: hoang-fig3"),
    (lambda: simulate(_braking(), estimator="oracle"), r"estimator must be an XbsEstimator object, 'true' or None"),
    (lambda: simulate(_braking(), estimator=object()), r"lacks reset\(t0, y0, vx0\)"),
])
def test_bad_input_is_refused_with_a_clear_message(make, match):
    with pytest.raises(SimulationError, match=match):
        make()


def test_results_serialise_to_plain_json(dry60):
    import json
    data = json.loads(json.dumps(dry60.to_json(include_series=True)))
    assert data["status"] == "stopped" and data["metrics"]["assumption1"]["holds"] is True
    assert data["scenario"]["controller"]["eps"] == list(FivePhaseABS().eps)
    assert len(data["series"]["t"]) == len(dry60.series["t"])
    assert "braking distance (Table 4.1 definition)" in str(dry60)
