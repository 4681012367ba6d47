"""`switchobs demo`: the main job end to end, its encoder-in-the-loop estimator and its reference (21)."""

from __future__ import annotations

import io
import json
import math
import os
import re
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from switchobs.cli.main import main
from switchobs.exceptions import PrerequisiteError, SimulationError
from switchobs.loop import DemoSettings, EncoderLoopEstimator, ObserverXbsEstimator, demo_scenario
from switchobs.observers import xbs4_observer
from switchobs.plants import BrakingScenario, simulate
from switchobs.report import STAGES, Progress, Stage, check_prerequisites
from switchobs.sensors import Encoder

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def demo_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo")
    proc = subprocess.run([sys.executable, "-m", "switchobs", "demo", "--fast", "--out", str(out)],
                          capture_output=True, text=True, cwd=str(ROOT), timeout=300)
    return out, proc


@pytest.mark.slow
def test_demo_fast_exits_0_and_writes_the_report_the_certificates_the_c_code_and_the_figures(demo_run):
    out, proc = demo_run
    assert proc.returncode == 0, proc.stderr
    for name in ("report.md", "report.json", "certificate-abs-xbs3.json", "certificate-abs-xbs4.json",
                 "xbs.png", "wheel_acceleration.png", "switching.png", "encoder.png", "braking.png",
                 "c/switchobs_abs_xbs3/switchobs_abs_xbs3.c", "c/switchobs_abs_xbs4/switchobs_abs_xbs4.h"):
        path = out / name
        assert path.is_file() and path.stat().st_size > 0, name
        if name.endswith(".png"):
            assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    report = json.loads((out / "report.json").read_text())
    assert report["ok"] is True
    assert report["settings"]["fast"] is True
    assert report["files"] == sorted(report["files"])


@pytest.mark.slow
def test_demo_progress_lines_go_to_stderr_with_elapsed_times(demo_run):
    _, proc = demo_run
    stages = re.findall(r"^\[(\d)/6\] (\w+):", proc.stderr, flags=re.M)
    assert [s for _, s in stages] == [s.name for s in STAGES]
    assert proc.stderr.count("done in ") == len(STAGES)
    assert "Traceback" not in proc.stderr
    assert proc.stdout.startswith("switchobs demo (fast): report in ")
    assert "all checks hold" in proc.stdout


@pytest.mark.slow
def test_demo_certificates_pass_switchobs_verify(demo_run, capsys):
    out, _ = demo_run
    for model in ("abs-xbs3", "abs-xbs4"):
        assert main(["verify", str(out / f"certificate-{model}.json")]) == 0
        printed = capsys.readouterr().out
        assert printed.startswith(f"certificate about model {model}") and "\ncertificate holds exactly\n" in printed
        assert f"model: holds - the observer's A and C are those of model '{model}'" in printed


@pytest.mark.slow
def test_hoang2014_sec3e_sec4d_demo_gains_at_beta_100(demo_run):
    # seed 000 Sec. III-E: k1+ = beta1 + 2 beta2 + c, k3+ = -beta1 beta2^2 / a; Sec. IV-D: k1+ = alpha2 + 2(beta1 + beta2),
    # k4+- = -beta1^2 beta2^2 / a; Theorem 1: k1- = 2 a1 - k1+ with a1 = c (3D), alpha2 (4D)
    out, _ = demo_run
    models = {m["model"]: m for m in json.loads((out / "report.json").read_text())["models"]}
    a, c, alpha2 = 187.5, 34.0, 74.0
    k3, k4 = models["abs-xbs3"], models["abs-xbs4"]
    assert k3["K_plus"][0] == pytest.approx(100 + 200 + c)
    assert k3["K_plus"][2] == pytest.approx(-100 * 100**2 / a)
    assert k3["K_minus"][0] == pytest.approx(2 * c - k3["K_plus"][0])
    assert k4["K_plus"][0] == pytest.approx(alpha2 + 2 * (100 + 100))
    assert k4["K_plus"][3] == pytest.approx(-(100**2) * 100**2 / a) == k4["K_minus"][3]
    assert k4["K_minus"][0] == pytest.approx(2 * alpha2 - k4["K_plus"][0])
    for m in models.values():
        assert all(m["exact_checks"].values()) and m["certified"] and m["verified"]
        assert m["c_vs_python"] < 1e-12
        assert m["c_run_ns"] > 0


@pytest.mark.slow
def test_demo_ships_the_certified_sampled_observer(demo_run):
    """Issue 'certify what ships': the C in the loop is the radau3 step, and its certificate covers every dt."""
    out, _ = demo_run
    for m in json.loads((out / "report.json").read_text())["models"]:
        assert m["method"] == "radau3" and "certified for every dt" in m["discrete"]
        cert = json.loads((out / m["certificate"]).read_text()) if not Path(m["certificate"]).is_absolute() \
            else json.loads(Path(m["certificate"]).read_text())
        assert cert["discrete"]["method"] == "radau3" and cert["discrete"]["verdict"] == "certified"
        assert cert["discrete"]["h_max"] == "inf" and cert["discrete"]["strict"] is True
        header = next((out / "c").glob(f"*{m['model'].replace('-', '_')}*/*.h")).read_text()
        assert "2-stage Radau IIA" in header


@pytest.mark.slow
def test_demo_braking_numbers_are_physical(demo_run):
    out, _ = demo_run
    b = json.loads((out / "report.json").read_text())["braking"]
    assert b["status"] == "duration"                       # fast mode ends on the snow, before the stop
    assert b["omega_reconstruction_max"] < 0.05            # rad/s, against the simulated wheel
    assert 5.0 < b["lag_mean_ms"] < 30.0                   # half a 15-edge window at 100-144 km/h
    errors = {(e["estimator"], e["segment"]): e for e in b["errors"]}
    exact = errors[("xbs4 (C), exact x2, beside", "hoang-dry")]
    encoder = errors[("xbs4 (C), encoder, in the loop", "hoang-dry")]
    # the observer tracks the XBS on exact measurements; the encoder's lag makes it worse (docs/encoders.md)
    assert exact["median"] < 0.1
    assert encoder["median"] > exact["median"]
    assert b["x2_rms"]["three-stage"]["hoang-dry"] < b["x2_rms"]["raw TSA"]["hoang-dry"]
    md = (out / "report.md").read_text()
    for heading in ("## 1. Models and rig", "## 2. Symbolic design", "## 3. Certificates", "## 4. Generated C",
                    "## 5. Braking with the generated C observer in the loop", "## 6. Limits"):
        assert heading in md
    assert "What is in the loop" in md and "switchobs verify" in md


def test_demo_stops_cleanly_without_a_c_compiler(tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "CC"}
    env["PATH"] = str(tmp_path)                 # an empty directory: no gcc, no cc
    proc = subprocess.run([sys.executable, "-m", "switchobs", "demo", "--fast", "--out", str(tmp_path / "o")],
                          capture_output=True, text=True, env=env, timeout=120)
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert proc.stderr.strip().splitlines() == [
        "switchobs demo: error: stage 'codegen' cannot run: no C compiler found (tried gcc, cc on PATH); "
        "install gcc or set CC"]
    assert not (tmp_path / "o").exists()        # checked before anything runs


def test_demo_stops_cleanly_when_a_package_does_not_import(monkeypatch, capsys, tmp_path):
    monkeypatch.setitem(sys.modules, "casadi", None)      # `import casadi` now raises ImportError
    with pytest.raises(PrerequisiteError, match=r"stage 'codegen' cannot run: importing casadi failed"):
        check_prerequisites(STAGES)
    assert main(["demo", "--fast", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("switchobs demo: error: stage 'codegen' cannot run: importing casadi")


def test_demo_cli_stops_cleanly_when_matplotlib_is_broken(tmp_path):
    # a package earlier on sys.path that fails to import, as a broken installation would
    fake = tmp_path / "fake" / "matplotlib"
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text('raise ImportError("matplotlib is broken (simulated)")\n')
    env = {**os.environ, "PYTHONPATH": str(tmp_path / "fake")}
    proc = subprocess.run([sys.executable, "-m", "switchobs", "demo", "--fast", "--out", str(tmp_path / "o")],
                          capture_output=True, text=True, env=env, timeout=120)
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [
        "switchobs demo: error: stage 'report' cannot run: importing matplotlib failed (matplotlib is broken "
        "(simulated)); reinstall switchobs and its dependencies (pip install --force-reinstall \"switchobs\")"]
    assert not (tmp_path / "o").exists()


def test_prerequisites_name_the_first_stage_that_cannot_run(monkeypatch):
    monkeypatch.setitem(sys.modules, "no_such_package_xyz", None)
    with pytest.raises(PrerequisiteError, match="stage 'b' cannot run: importing no_such_package_xyz"):
        check_prerequisites([Stage("a", ("math",)), Stage("b", ("no_such_package_xyz",)), Stage("c", ("os",))])


@pytest.mark.parametrize("module", ["_progress", "_markdown", "_theory"])
def test_report_docstring_examples(module):
    import doctest
    import importlib

    result = doctest.testmod(importlib.import_module(f"switchobs.report.{module}"), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0


def test_progress_reports_each_stage_and_a_failure():
    stream = io.StringIO()
    progress = Progress(2, stream=stream)
    with progress.stage("one", "first"):
        progress.note("inside")
    with pytest.raises(ValueError), progress.stage("two", "second"):
        raise ValueError("boom")
    lines = stream.getvalue().splitlines()
    assert lines[0] == "[1/2] one: first"
    assert lines[1] == "      inside"
    assert re.fullmatch(r"      done in \d+\.\d s \(total \d+\.\d s\)", lines[2])
    assert lines[3] == "[2/2] two: second"
    assert re.fullmatch(r"      two failed after \d+\.\d s", lines[4])
    assert set(progress.summary()) == {"one"}


# ------------------------------------------------------------------ encoder in the loop
def _short_demo_scenario(duration_s: float = 1.2) -> BrakingScenario:
    return replace(demo_scenario(DemoSettings()), duration_s=duration_s)


@pytest.fixture(scope="module")
def loop_run():
    sc = _short_demo_scenario()
    obs = xbs4_observer(100.0, 100.0, method="radau3")  # certified for every step: one step per sample
    est = EncoderLoopEstimator([("xbs4", obs, {"z2": 0.5})],
                               encoder=Encoder(ppr=60, dnl_cycles=0.01, eccentricity=0.003, clock_hz=1e6, seed=1),
                               radius_m=sc.vehicle.radius_m,
                               beside=[("exact", ObserverXbsEstimator(obs, initial_state={"z2": 0.5}))])
    result = simulate(sc, estimator=est)
    return sc, result, est.record()


def test_encoder_loop_rebuilds_the_wheel_speed_of_the_simulation(loop_run):
    sc, result, rec = loop_run
    s = result.series
    assert rec.steps_t.size == np.unique(s["t"]).size == rec.omega_steps.size
    omega = np.interp(rec.steps_t, s["t"], s["omega"])
    assert np.max(np.abs(rec.omega_steps - omega)) < 0.02          # of about 130 rad/s
    # the edges are those of the rebuilt angle: 60 per revolution
    revolutions = np.trapezoid(rec.omega_steps, rec.steps_t) / (2 * math.pi)
    assert abs(rec.events - 60 * revolutions) <= 2


def test_encoder_loop_measurement_is_the_window_centre_and_the_observer_is_in_the_loop(loop_run):
    sc, result, rec = loop_run
    s = result.series
    ok = np.isfinite(rec.t_measured)
    assert np.all(rec.t_measured[ok] < rec.t[ok])
    # 15 edges at omega: half the window is 7 edge periods, 2 pi / 60 / omega each
    omega = np.interp(rec.t[ok], s["t"], s["omega"])
    expected = 7 * (2 * math.pi / 60) / omega
    assert np.median(rec.lag_s[ok] / expected) == pytest.approx(1.0, abs=0.15)
    # the estimate the controller read is the encoder-fed one, held between samples
    xbs_hat = s["xbs_hat"][s["t"] > rec.t[ok][0] + 0.01]
    assert set(np.round(xbs_hat, 12)) <= set(np.round(rec.estimates["xbs4"], 12)) | {0.5}
    # on exact x2 the same observer is far closer to the truth (the encoder lag dominates)
    late = rec.steps_t > 0.3
    exact_err = np.median(np.abs(rec.beside["exact"][late] - np.interp(rec.steps_t[late], s["t"], s["xbs"])))
    late_s = (rec.t > 0.3) & ok
    enc_err = np.median(np.abs(rec.estimates["xbs4"][late_s] - np.interp(rec.t[late_s], s["t"], s["xbs"])))
    assert exact_err < 0.1 < enc_err


def test_encoder_loop_rejects_bad_settings():
    obs = xbs4_observer(100.0, 100.0)
    enc = Encoder(ppr=60)
    # without observers the chain only measures (EncoderX2) and returns the initial estimate
    assert EncoderLoopEstimator([], encoder=enc, radius_m=0.3).describe().startswith("no observer on x2")
    with pytest.raises(SimulationError, match="rate_hz must be finite and > 0, got -1"):
        EncoderLoopEstimator([("x", obs, {})], encoder=enc, radius_m=0.3, rate_hz=-1.0)
    with pytest.raises(SimulationError, match="window n = 2 must exceed"):
        EncoderLoopEstimator([("x", obs, {})], encoder=enc, radius_m=0.3, window=2)


# ------------------------------------------------------------------ reference (21)
def test_hoang2014_eq21_eq22_recorded_reference_reproduces_the_controller_rate():
    """Replay the controller's own runtime through the recorded events; law (22) on the reference (21)
    the simulation recorded must give the rate the runtime computes."""
    sc = _short_demo_scenario(1.5)
    result = simulate(sc, estimator="true")
    s = result.series
    ref, dref = s["x2_ref"], s["dx2_ref"]
    ctrl = sc.controller
    rt = ctrl.runtime(sc.vehicle, sc.actuator)
    veh = sc.vehicle
    R = veh.radius_m
    checked = 0
    events = [(t, e) for t, e in result.events if e.startswith("phase ")]
    for k, (t0, text) in enumerate(events):
        i = int(np.searchsorted(s["t"], t0, side="right")) - 1
        x2, v_wheel, vx = s["x2"][i], R * s["omega"][i], s["vx"][i]
        if "stall timeout" in text:
            rt.expire(t0, x2, v_wheel, vx)
        else:
            g = rt.guards(x2, s["xbs"][i], s["lambda"][i])
            rt.fire(t0, int(np.argmax(g)), x2, v_wheel, vx)
        assert rt.phase == int(text.split("-> ")[1].split()[0])
        t1 = events[k + 1][0] if k + 1 < len(events) else math.inf
        sel = np.nonzero((s["t"] > t0) & (s["t"] < t1))[0][::3]
        for j in sel:
            expected = rt.rate(s["t"][j], s["x2"][j], R * s["omega"][j], s["vx"][j], s["xbs"][j])
            if rt.phase in (1, 3, 4):
                law = (-veh.a / s["vx"][j] * s["xbs"][j] * s["x2"][j] - dref[j]
                       + ctrl.alpha * (s["x2"][j] - ref[j])) / veh.b
                assert law == pytest.approx(expected, rel=1e-9, abs=1e-9)
                checked += 1
            else:
                assert math.isnan(ref[j])
    assert checked > 100


@pytest.mark.slow
def test_a_diverged_observer_fails_the_demo(demo_run):
    """A non-finite XBS error over the run fails the demo's checks (exit 1), as it fails `switchobs simulate`."""
    from dataclasses import replace

    from switchobs.report import DemoReport

    out, _ = demo_run
    report = DemoReport.from_json(json.loads((out / "report.json").read_text()))
    assert report.ok and not report.diverged
    errors = tuple(replace(e, rms=float("nan")) if e.segment == "whole run" and "beside" in e.estimator else e
                   for e in report.braking.errors)
    broken = replace(report, braking=replace(report.braking, errors=errors))
    assert not broken.ok and broken.diverged and all("beside" in name for name in broken.diverged)
    text = str(broken)
    assert "(diverged)" in text and text.endswith("SOME CHECKS FAILED")
