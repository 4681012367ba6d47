"""``switchobs simulate``: scenarios, JSON, plots and one-line errors."""

import json

import pytest

from switchobs.cli.main import main


def run(capsys, *argv):
    code = main(["simulate", *argv])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_simulate_single_road_json_and_plot(capsys, tmp_path):
    png = tmp_path / "run.png"
    code, out, err = run(capsys, "--road", "wet-asphalt", "--speed-kmh", "60", "--controller", "two-phase",
                         "--observer", "adaptive", "--json", "--plot", str(png))
    assert code == 0 and err == ""
    data = json.loads(out)
    m = data["metrics"]
    assert data["status"] == "stopped" and data["observer_in_loop"] is True
    assert data["scenario"]["roads"]["initial"] == "wet-asphalt" and data["scenario"]["speed_kmh"] == pytest.approx(60)
    assert m["braking_distance_m"] == pytest.approx((60 / 3.6) ** 2 / (2 * 9.81 * m["mean_friction"]))
    assert 17.0 < m["braking_distance_m"] < 19.0          # seed 001 Table 4.1: 17.86 m
    assert m["xbs_rms_error"] is not None and m["assumption1"]["holds"] is True
    assert png.stat().st_size > 20_000 and png.read_bytes()[:4] == b"\x89PNG"


def test_simulate_scenario_text_reports_reconvergence(capsys):
    code, out, _ = run(capsys, "hoang-fig3", "--duration", "3.5", "--observer", "xbs3")
    assert code == 0
    assert out.startswith("Hoang et al. 2014 Fig. 3")
    assert "-> hoang-wet" in out and "re-convergence within 10 %" in out and "Assumption 1" in out


def test_simulate_aguado_sec34_uses_the_scenario_gains_of_its_adaptive_observer(capsys):
    # docs/reproductions.md, Sec. 3.4: beta = 150, Gamma = 1e4 I, with or without --observer adaptive;
    # --beta / --gamma override them, and another observer keeps its own defaults
    def rms(*argv):
        code, out, _ = run(capsys, "aguado-sec34", "--duration", "3.2", "--json", *argv)
        assert code == 0
        return json.loads(out)["metrics"]["xbs_rms_error"]
    scenario_default = rms()
    assert rms("--observer", "adaptive") == scenario_default == rms("--beta", "150", "--gamma", "10000")
    assert rms("--beta", "100") != scenario_default
    assert rms("--observer", "xbs4") == rms("--observer", "xbs4", "--beta", "100")


def test_simulate_two_axle_scenario_json(capsys, tmp_path):
    png = tmp_path / "sec36.png"
    code, out, _ = run(capsys, "aguado-sec36", "--duration", "1.5", "--json", "--plot", str(png))
    data = json.loads(out)
    assert code == 0 and data["observer"] == "adaptive" and data["description"].startswith("Aguado-Rojas 2020 Sec. 3.6")
    m = data["metrics"]
    assert m["front"]["load_max_n"] > data["scenario"]["vehicle"]["static_loads_n"][0]
    assert m["speed_error_mean_pct"] < 0 and png.exists()


@pytest.mark.parametrize("argv, name", [((), "six-phase"), (("--controller", "six-phase"), "six-phase"),
                                        (("--controller", "five-phase"), "five-phase")])
def test_simulate_two_axle_controller_choice(capsys, argv, name):
    code, out, _ = run(capsys, "aguado-sec36", "--duration", "1.0", "--json", *argv)
    data = json.loads(out)
    assert code == 0 and data["scenario"]["front"]["name"] == data["scenario"]["rear"]["name"] == name
    # both ABS take over before 1 s (seed 001 Sec. 3.6: 0.75 s front, 0.50 s rear)
    assert data["metrics"]["front"]["abs_cycles"] >= 1 and data["metrics"]["rear"]["abs_cycles"] >= 1


def test_simulate_six_phase_on_the_quarter_car(capsys):
    code, out, _ = run(capsys, "--speed-kmh", "60", "--controller", "six-phase", "--json")
    data = json.loads(out)
    assert code == 0 and data["status"] == "stopped" and data["scenario"]["controller"]["name"] == "six-phase"


def test_simulate_sec36_adaptive_divergence_names_its_cause_and_the_fix(capsys):
    # seed 001 Sec. 3.6 with the adaptive observer: gamma = 1e4 diverges at the 1 ms explicit step
    # (docs/reproductions.md); the failure says so, and the scenario's own gamma runs
    code, _, err = run(capsys, "aguado-sec36", "--duration", "1.5", "--observer", "adaptive", "--gamma", "10000")
    assert code == 1 and err.count("\n") == 1
    assert "front observer diverged" in err and "--gamma 5000" in err
    code, out, err = run(capsys, "aguado-sec36", "--duration", "1.5")
    assert code == 0 and err == "" and "adaptive observer, beta 100, gamma 5000" in out


def test_simulate_sec36_reads_the_load_on_line_unless_told_not_to_and_refuses_what_does_not_apply(capsys):
    """Seed 001 Sec. 3.6: the observers' a = R^2 Fz / J follows (3.36); --static-load keeps the corner's."""
    def front_rms(*extra):
        code, out, _ = run(capsys, "aguado-sec36", "--duration", "1.5", "--json", *extra)
        data = json.loads(out)
        assert code == 0
        return data["observer_load"], data["metrics"]["front"]["xbs_rms_error"]
    online, static = front_rms(), front_rms("--static-load")
    assert online[0] == "online" and static[0] == "static" and online[1] != static[1]
    for extra, message in ((("--static-load", "--observer", "xbs4"), "the xbs4 observer always keeps"),
                           (("--duration", "0.2"), "--duration 0.2 s ends before the braking of aguado-sec36 starts"),
                           (("--static-load", "hoang-fig3"), "only applies to the two-axle scenario")):
        args = [a for a in extra if a != "hoang-fig3"]
        scenario = "hoang-fig3" if "hoang-fig3" in extra else "aguado-sec36"
        code, _, err = run(capsys, scenario, *args)
        assert code == 2 and message in err and err.count("\n") == 1


def test_simulate_series_in_json(capsys):
    code, out, _ = run(capsys, "--speed-kmh", "40", "--json", "--series")
    series = json.loads(out)["series"]
    assert code == 0 and len(series["t"]) == len(series["x2"]) > 100 and series["xbs_hat"][0] is None


@pytest.mark.slow
def test_simulate_table41_cli(capsys, tmp_path):
    png = tmp_path / "t41.png"
    code, out, _ = run(capsys, "table41", "--json", "--plot", str(png))
    data = json.loads(out)
    assert code == 0 and data["two_phase_always_shorter"] is True and len(data["rows"]) == 15
    row = next(r for r in data["rows"] if r["road"] == "dry-asphalt" and r["speed_kmh"] == 120)
    assert row["seed_five_phase_m"] == 49.27 and row["seed_two_phase_m"] == 48.78
    assert png.exists()


@pytest.mark.parametrize("argv, message", [
    (["--road", "gravel"], "unknown road surface 'gravel'"),
    (["--speed-kmh", "-5"], "--speed-kmh must be > 0, got -5"),
    (["--duration", "-1"], "--duration must be > 0 s, got -1"),
    (["--observer", "xbs3", "--beta", "-1"], "beta1 = -1.0 must be finite and > 0"),
    (["aguado-sec36", "--controller", "two-phase"],
     "--controller two-phase does not apply to the two-axle scenario 'aguado-sec36'; use six-phase or five-phase"),
    (["aguado-sec36", "--tracking"], "--tracking does not apply to the two-axle scenario"),
    (["--controller", "two-phase", "--tracking"], "--tracking applies to the five-phase ABS"),
    (["fig99"], "unknown scenario 'fig99'"),
    (["aguado-sec34", "--road", "snow"], "--road does not apply to the scenario 'aguado-sec34'"),
    (["table41", "--speed-kmh", "60"], "--speed-kmh does not apply to table41"),
    (["--dt", "0.5"], "dt_s = 0.5 s is too coarse"),
    (["--series"], "--series only applies with --json"),
])
def test_simulate_bad_input_one_line_exit_2(capsys, argv, message):
    code, out, err = run(capsys, *argv)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and err.startswith("switchobs simulate: error: ") and message in err
