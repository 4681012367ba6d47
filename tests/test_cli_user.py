"""A conventional command line: help without a command, the sub-command's usage for its own bad options, ASCII
terminals, complete MODEL lists."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from switchobs.cli.main import build_parser, main
from switchobs.model import builtin_names

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("argv", [[], ["-q"]])
def test_no_command_prints_the_help(argv, capsys):
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: switchobs") and "synthesize" in out and "transform" in out


def test_an_unknown_option_is_refused_by_its_command_pointing_to_its_usage(capsys):
    # one line, as every refusal (docs/errors.md), from the command's own parser, not the top-level one
    with pytest.raises(SystemExit) as stop:
        main(["design", "abs-xbs3", "--bogus"])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert err == "switchobs design: error: unrecognized arguments: --bogus (see switchobs design --help)\n"


def test_an_ascii_terminal_gets_ascii_matrices_and_no_encoding_error(tmp_path):
    env = {**os.environ, "PYTHONIOENCODING": "ascii", "PYTHONPATH": str(ROOT / "src")}
    for argv in (["design", "abs-xbs3", "--spectrum=-beta1,-beta2,-beta2"], ["simulate", "--duration", "0.1"]):
        proc = subprocess.run([sys.executable, "-m", "switchobs", *argv], cwd=tmp_path, env=env, capture_output=True,
                              timeout=300)
        assert proc.returncode == 0, proc.stderr.decode("ascii", "replace")
        assert proc.stdout.isascii() and b"Error" not in proc.stderr
    assert b"K_plus =" in subprocess.run([sys.executable, "-m", "switchobs", "design", "abs-xbs3",
                                          "--spectrum=-1,-2,-3"], cwd=tmp_path, env=env, capture_output=True,
                                         timeout=300).stdout


@pytest.mark.parametrize("command", ["design", "certify", "codegen", "synthesize"])
def test_the_model_help_lists_every_built_in_model(command):
    text = " ".join(build_parser(command)._subparsers._group_actions[0].choices[command].format_help().split())
    assert all(name in text for name in builtin_names()), text


def test_sweep_limit_and_a_plots_directory_that_does_not_exist_yet(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    spec = ROOT / "examples" / "sweep_table41.toml"
    assert main(["sweep", str(spec), "--limit", "2", "--scheduler", "none", "--out", "t.jsonl",
                 "--plots", "figs/new"]) == 0
    assert len(Path("t.jsonl").read_text("utf-8").splitlines()) == 2
    assert [p.suffix for p in Path("figs/new").iterdir()] == [".png"]
    capsys.readouterr()
    assert main(["sweep", str(spec), "--limit", "0", "--scheduler", "none", "--out", "u.jsonl"]) == 2
    assert "--limit must be >= 1, got 0" in capsys.readouterr().err and not Path("u.jsonl").exists()


def test_heatmap_labels_are_human_names_with_units():
    from switchobs.sweep import BrakingCase, plot_heatmap, run_case

    results = [run_case(BrakingCase(road=r, speed_kmh=v, duration_s=0.3)) for r in ("dry-asphalt", "snow")
               for v in (40.0, 60.0)]
    fig = plot_heatmap(results, x="speed_kmh", y="road", metric="stopping_distance_m")
    axis = fig.axes[0]
    assert axis.get_xlabel() == "initial speed [km/h]" and axis.get_title() == "mean distance travelled [m]"
    assert fig.axes[1].get_ylabel() == "distance travelled [m]"


def test_a_run_that_did_not_stop_is_labelled_by_its_distance_travelled():
    from switchobs.plants import distance_label

    assert distance_label(False) == "distance travelled" and distance_label(True) == "stopping distance"


def test_synthesize_warns_about_poles_far_beyond_the_decay_asked(capsys):
    assert main(["synthesize", "abs-xbs3", "--decay", "99"]) == 0
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("switchobs synthesize: warning: a pole at |lambda| = ")
    assert "--noise-weight 0.01" in err[0]
    assert main(["synthesize", "abs-xbs3", "--decay", "99", "--noise-weight", "0.01"]) == 0   # the hint works
    assert capsys.readouterr().err == ""
    assert main(["-q", "synthesize", "abs-xbs3", "--decay", "99"]) == 0
    assert capsys.readouterr().err == ""


def test_design_json_expressions_parse_back_as_the_guide_says():
    import sympy as sp

    from switchobs.design import design
    from switchobs.model import builtin_model, parse_expression

    g = design(builtin_model("abs-adaptive2"), "-beta,-beta")
    poly = g.characteristic_polynomial("plus")
    text = g.to_json()["characteristic_polynomial_plus"]
    with pytest.raises((TypeError, sp.SympifyError)):   # why the guide does not say sympify: beta is a function
        sp.expand(sp.sympify(text) - poly)
    assert sp.simplify(parse_expression(text, {str(x): x for x in poly.free_symbols}) - poly) == 0


def test_bash_completion_is_generated_from_the_parsers(tmp_path, capsys):
    import shutil

    with pytest.raises(SystemExit) as stop:
        main(["--completion", "bash"])
    assert stop.value.code == 0
    script = tmp_path / "switchobs.bash"
    script.write_text(capsys.readouterr().out, encoding="utf-8")
    bash = shutil.which("bash")
    if bash is None:
        pytest.skip("bash is not installed: the completion script is NOT checked")

    def complete(*words: str) -> list[str]:
        probe = (f"source {script}; COMP_WORDS=({' '.join(words)}); COMP_CWORD={len(words) - 1}; _switchobs; "
                 'printf "%s\\n" "${COMPREPLY[@]}"')
        proc = subprocess.run([bash, "-c", probe], capture_output=True, text=True, cwd=tmp_path, timeout=60)
        assert proc.returncode == 0, proc.stderr
        return proc.stdout.split()

    assert complete("switchobs", "synth") == ["synthesize"]
    assert complete("switchobs", "simulate", "--met") == ["--method"]
    assert complete("switchobs", "-q", "design", "abs-adaptive2-") == ["abs-adaptive2-load"]
    assert "--limit" in complete("switchobs", "sweep", "--")


def test_braking_figure_labels_its_road_changes_and_names_the_observer():
    from dataclasses import replace

    from switchobs.loop import xbs_estimator
    from switchobs.plants import plot_braking, scenario, simulate

    sc = replace(scenario("hoang-fig3"), duration_s=3.5)
    fig = plot_braking(simulate(sc, estimator=xbs_estimator("xbs4", sc.vehicle, sc.roads.initial)))
    assert [t.get_text() for t in fig.axes[0].texts] == ["→ hoang-wet"]
    title = fig._suptitle.get_text()
    assert "switched observer of abs-xbs4 (radau3)" in title and "SwitchedObserver" not in title


_VALUED_MODEL = """
name = "valued"
states = ["z1", "z2"]
output = "y"
parameters = ["a", "c"]
positive = ["a"]
A = [[0, 1], ["c", 0]]
C = [1, 0]
time_scale = "y"

[values]
a = "2"
c = "{c}"
"""


def _valued(tmp_path: Path, c: str) -> str:
    path = tmp_path / f"valued{c.replace('/', '_')}.toml"
    path.write_text(_VALUED_MODEL.format(c=c), encoding="utf-8")
    return str(path)


def test_design_shows_the_symbolic_result_then_the_same_at_the_model_values(tmp_path, capsys):
    """One rule with certify: a model's [values] are used; the symbolic output stays as it was, first."""
    import json

    from switchobs.design import design
    from switchobs.model import load_model

    model = _valued(tmp_path, "3")
    assert main(["design", model, "--gains-plus", "k1,k2", "--symbolic"]) == 0
    symbolic = capsys.readouterr().out
    assert "at the model's values" not in symbolic
    assert main(["design", model, "--gains-plus", "k1,k2"]) == 0
    both = capsys.readouterr().out
    assert both.startswith(symbolic)
    evaluated = both[len(symbolic):]
    assert evaluated.startswith("at the model's values a = 2, c = 3 (switchobs design --symbolic leaves this out):")
    at = design(load_model(model), K_plus="k1,k2").at()
    for condition in at.hurwitz_plus:       # the conditions with c = 3 substituted, as GainDesign.at() gives them
        assert f"    {condition}" in evaluated
    assert main(["design", model, "--gains-plus", "k1,k2", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["at_values"]["values"] == {"a": "2", "c": "3"}
    assert data["at_values"]["K_minus"] == at.to_json()["K_minus"]
    assert data["at_values"]["hurwitz_plus"] == at.to_json()["hurwitz_plus"]
    assert main(["design", model, "--gains-plus", "k1,k2", "--json", "--symbolic"]) == 0
    assert "at_values" not in json.loads(capsys.readouterr().out)


def test_design_at_values_that_break_a_condition_says_so_and_exits_1(tmp_path, capsys):
    """With K_plus = [1, 1] the Routh conditions need c < 1: the symbolic design holds, its value c = 5 does not."""
    model = _valued(tmp_path, "5")
    assert main(["design", model, "--gains-plus", "1,1", "--no-verify"]) == 1
    out = capsys.readouterr().out
    assert out.splitlines()[-1].startswith("at the model's values: at these values the A_plus Routh–Hurwitz "
                                           "condition fails:"), out
    assert main(["design", model, "--gains-plus", "1,1", "--no-verify", "--symbolic"]) == 0
