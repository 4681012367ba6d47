"""Measurement chain to the observer (x2 = R alpha_hat - a_x), the encoder CLI, and the feed of an XBS observer."""

from __future__ import annotations

import json

import numpy as np
import pytest

from switchobs.cli.main import main
from switchobs.exceptions import SimulationError
from switchobs.observers import xbs3_observer
from switchobs.plants import road, scenario, simulate
from switchobs.sensors import (ESTIMATORS, AngleTrajectory, ChainSettings, Encoder, braking_trajectory,
                               compare_estimators, constant_speed, encoder_chain)

ENCODER = Encoder(ppr=60, dnl_cycles=0.01, eccentricity=0.003, clock_hz=1e6, seed=1)
DRY = road("dry-asphalt")  # seed 001 Table 2.1, the road of braking_trajectory


@pytest.fixture(scope="module")
def braking():
    return braking_trajectory(4.0)


@pytest.fixture(scope="module")
def braking_comparison(braking):
    return compare_estimators(braking.trajectory(), ENCODER, settings=ChainSettings(warmup_s=1.0))


def test_ideal_encoder_constant_speed_tsa_chain_is_exact():
    res = encoder_chain(constant_speed(1020.0, 1.0), Encoder(ppr=60), estimator="tsa")
    assert res.rms_omega < 1e-9 and res.rms_alpha < 1e-5
    assert res.x2 is None and np.isnan(res.rms_x2)
    assert res.t[1] - res.t[0] == pytest.approx(1e-3)


def test_aguado_eq22_chain_output_is_R_alpha_hat_minus_ax(braking, braking_comparison):
    traj = braking.trajectory()
    for r in braking_comparison.results:
        assert r.x2 is not None and r.t.size == 4001
        ok = np.isfinite(r.alpha)
        np.testing.assert_allclose(r.x2[ok], traj.radius_m * r.alpha[ok] - traj.accel_x(r.t[ok]), atol=1e-12)
    truth = braking_comparison["tsa"].x2_true
    x2_plant = braking.vehicle.radius_m * braking.alpha - braking.accel_x_m_s2
    # the quintic Hermite interpolant reproduces the plant's alpha at its samples up to rounding of
    # theta (~300 rad) over 1e-4 s cells: ~1e-5 rad/s^2
    np.testing.assert_allclose(truth[::10], x2_plant[::100], atol=1e-4)


def test_three_stage_gives_the_best_x2_on_a_braking_run(braking_comparison):
    c = braking_comparison
    assert c["three-stage"].rms_x2 < 0.6 * c["tsa"].rms_x2
    assert c["three-stage"].rms_x2 < c["notch"].rms_x2
    assert c["notch"].lag_alpha_s > c["three-stage"].lag_alpha_s
    assert all(np.isfinite(r.rms_x2) for r in c.results)


def test_chain_feeds_the_xbs3_observer(braking, braking_comparison):
    # the chain's x2 is the observer's output y (seed 000 (7)); its quality shows in the XBS estimate
    car = braking.vehicle
    # abs-xbs3 writes b = -R gamma_b / I and c = -c2 (braking c2 < 0): seed 000 (7)
    params = {"a": car.a, "b": -car.b, "c": DRY.c}
    obs = xbs3_observer(10.0, 20.0, params=params)
    t = braking_comparison["tsa"].t
    speed = np.interp(t, braking.t, braking.speed_m_s)
    # T = -gamma_b P_b, so the observer input u = dP_b/dt is -dT/dt / gamma_b
    pressure_rate = np.interp(t, braking.t, -np.gradient(braking.torque_nm, braking.t) / car.brake_gain_nm_bar)
    xbs = DRY.xbs_array(np.interp(t, braking.t, braking.slip))
    errors = {}
    for r in braking_comparison.results:
        first = int(np.argmax(np.isfinite(r.x2)))
        states = obs.run([r.x2[first], 20.0, 0.0], np.column_stack([r.x2, speed, pressure_rate])[first:], 1e-3)
        late = t[first:] >= 2.0
        errors[r.estimator] = float(np.sqrt(np.mean((states[late, 1] - xbs[first:][late]) ** 2)))
    assert errors["three-stage"] < 0.5 * errors["tsa"]


def test_chain_runs_on_a_closed_loop_abs_braking_of_switchobs_plants():
    # seed 000 Fig. 3 five-phase ABS; the chain's truth must be the plant's own x2 = R omega_dot - a_x
    sc = scenario("hoang-fig3")
    s = simulate(sc).series
    keep = np.concatenate([[True], np.diff(s["t"]) > 0])
    traj = AngleTrajectory.from_samples(s["t"][keep], omega=s["omega"][keep], alpha=s["omega_dot"][keep],
                                        accel_x=s["ax"][keep], radius_m=sc.vehicle.radius_m, name="hoang-fig3")
    res = encoder_chain(traj, ENCODER, estimator="tsa", settings=ChainSettings(warmup_s=0.5))
    tk = s["t"][keep]
    np.testing.assert_allclose(traj.radius_m * traj.alpha(tk) - traj.accel_x(tk), s["x2"][keep], atol=1e-8)
    # ABS cycling is fast: the TSA's lag, not the encoder ripple, dominates the x2 error
    assert res.lag_alpha_s >= 0.005
    assert 1.0 < res.rms_x2 < 0.6 * float(np.sqrt(np.mean(s["x2"] ** 2)))


def test_comparison_json_and_table(braking_comparison):
    data = json.loads(json.dumps(braking_comparison.to_json()))
    assert [r["estimator"] for r in data["results"]] == list(ESTIMATORS)
    assert data["settings"]["window"] == 15 and data["encoder"]["ppr"] == 60
    text = str(braking_comparison)
    assert "three-stage" in text and "x2 [m/s^2]" in text
    single = braking_comparison["notch"].to_json(arrays=True)
    assert len(single["x2"]) == 4001 and single["x2"][0] is None


def test_chain_accepts_sampled_trajectories():
    t = np.linspace(0.0, 2.0, 2001)
    traj = AngleTrajectory.from_samples(t, omega=100.0 + 5.0 * np.sin(2 * t), accel_x=np.full(t.size, -2.0),
                                        radius_m=0.3)
    res = encoder_chain(traj, Encoder(ppr=48), estimator="three-stage")
    assert res.rms_omega < 0.05 and res.x2 is not None
    assert res.rms_x2 == pytest.approx(0.3 * res.rms_alpha, rel=1e-9)


def test_unknown_estimator_raises():
    with pytest.raises(SimulationError, match="unknown estimator 'kalman'; choose one of tsa, notch"):
        encoder_chain(constant_speed(600.0, 0.5), estimator="kalman")


@pytest.mark.parametrize("kwargs, match", [
    ({"window": 2}, "window n = 2 must exceed"),
    ({"harmonics": 0}, "harmonics"),
    ({"rate_hz": -1.0}, "rate_hz"),
    ({"st_substeps": 0}, "st_substeps"),
])
def test_bad_chain_settings_raise(kwargs, match):
    with pytest.raises(SimulationError, match=match):
        ChainSettings(**kwargs)


def test_cli_encoder_prints_the_table(capsys, tmp_path):
    png = tmp_path / "enc.png"
    assert main(["encoder", "--duration", "2", "--plot", str(png)]) == 0
    out = capsys.readouterr().out
    for name in ESTIMATORS:
        assert name in out
    assert png.stat().st_size > 10000


def test_cli_encoder_json(capsys):
    assert main(["encoder", "--duration", "2", "--profile", "varying", "--estimator", "three-stage", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    (row,) = data["results"]
    assert row["estimator"] == "three-stage" and 0 < row["rms_omega_rad_s"] < 0.3


@pytest.mark.parametrize("argv, match", [
    (["--ppr", "1"], "ppr (pulses per revolution) must be at least 2, got 1"),
    (["--events", "2"], "window n = 2 must exceed the polynomial order m = 2"),
    (["--harmonics", "0"], "harmonics (M) must be at least 1, got 0"),
    (["--warmup", "5", "--duration", "2"], "--warmup 5 must be shorter than --duration 2"),
    (["--duration", "1.5", "--plot", "/nonexistent/dir/x.png"], "cannot write the plot"),
])
def test_cli_encoder_bad_input_is_one_line_exit_2(capsys, argv, match):
    try:
        code = main(["encoder", *argv])
    except SystemExit as exc:  # --plot is checked when the command line is read (argparse exits)
        code = exc.code
    assert code == 2
    err = capsys.readouterr().err
    assert match in err and err.count("\n") == 1 and "Traceback" not in err


def test_comparison_plot_draws_estimation_errors(braking_comparison):
    """`encoder --plot` shows estimate - truth per estimator (issue 16), not estimates over a hidden truth."""
    from switchobs.sensors import plot_comparison

    fig = plot_comparison(braking_comparison)
    speed, accel = fig.axes
    assert speed.get_ylabel() == "speed error [rad/s]" and accel.get_ylabel() == "acceleration error [rad/s^2]"
    r = braking_comparison.results[0]
    drawn = next(line for line in speed.lines if line.get_label() == r.estimator).get_ydata()
    shown = (r.t >= r.t[0] + r.settings.warmup_s) & (r.t <= r.t[0] + r.settings.warmup_s + 1.0)
    np.testing.assert_allclose(drawn, (r.omega - r.omega_true)[shown])
