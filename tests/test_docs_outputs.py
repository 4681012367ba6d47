"""The command output shown on the layer pages and in the guide is what the command prints today.

Blocks tested elsewhere: the guide's `design`, `classify` and `theory --check` (test_docs.py), the box and
synthesis runs of docs/certify.md (test_certify_box.py), `certify abs-adaptive2` and the planar `classify` of
docs/certify.md (test_figures.py, which runs them for the figures), the transform derivations
(test_transform.py), the scenario output of docs/abs.md and docs/encoders.md (test_reproductions.py).
"""

from __future__ import annotations

import json
import re
import shlex
import shutil
import subprocess
from pathlib import Path

import pytest
from _docs_blocks import matches_with_elisions, shown_output

from switchobs.cli.main import main

ROOT = Path(__file__).resolve().parents[1]


def run(command: str, capsys) -> tuple[int, str]:
    status = main(shlex.split(command)[1:])
    return status, capsys.readouterr().out.rstrip("\n")


def test_the_elision_rule_keeps_what_is_shown():
    printed = "a\nb\nc\nd - long tail\n"
    assert matches_with_elisions("a\n...\nd - long...", printed)
    assert matches_with_elisions("...\nc\nd - long tail", printed)
    assert not matches_with_elisions("a\n...\nc", printed)          # the last line is not shown
    assert not matches_with_elisions("a\nc\n...", printed)          # b is left out without a mark


@pytest.mark.parametrize("page, commands", [
    ("certify.md", ["switchobs certify abs-xbs3 --spectrum=-10,-20,-20 --out cert.json", "switchobs verify cert.json"]),
    ("guide.md", ['switchobs certify abs-xbs3 --spectrum "-100,-100,-100" --out cert.json',
                  "switchobs verify cert.json"]),
    ("design.md", ['switchobs design abs-xbs3 --gains-plus "k1,k2,k3"']),
    ("guide.md", ["switchobs codegen abs-xbs3 --spectrum=-100,-100,-100 --out gen"]),
    ("guide.md", ["switchobs encoder --duration 4"]),
])
def test_cli_output_shown_on_the_page_is_what_the_command_prints(page, commands, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    for command in commands:
        status, out = run(command, capsys)
        assert status == 0, out
        assert matches_with_elisions(shown_output(page, command), out), f"docs/{page}: `{command}` prints\n{out}"


def test_the_tampered_certificate_of_the_certify_page_fails_as_shown(tmp_path, monkeypatch, capsys):
    # "After changing one entry of P (P[3][3] = 1/100), verify exits 1 and says which inequality breaks"
    monkeypatch.chdir(tmp_path)
    assert run("switchobs certify abs-xbs3 --spectrum=-10,-20,-20 --out cert.json", capsys)[0] == 0
    doc = json.loads(Path("cert.json").read_text("utf-8"))
    hespanha = next(c for c in doc["certificates"] if c["kind"] == "hespanha")
    hespanha["P"][2][2] = "1/100"
    Path("tampered.json").write_text(json.dumps(doc), encoding="utf-8")
    status, out = run("switchobs verify tampered.json", capsys)
    assert status == 1
    assert matches_with_elisions(shown_output("certify.md", "switchobs verify tampered.json"), out), out


def test_simulate_output_shown_in_the_guide_is_what_the_command_prints(capsys):
    status, out = run("switchobs simulate hoang-fig3", capsys)
    assert status == 0
    # the wall-clock figures of the cost line differ between runs: its step count is what the page can show
    shown = shown_output("guide.md", "switchobs simulate hoang-fig3")
    cost = re.compile(r"(  cost: \d+ steps), .*")
    assert cost.sub(r"\1", out) == cost.sub(r"\1", shown)


def test_codegen_output_and_the_c_example_of_the_codegen_page(tmp_path, monkeypatch, capsys):
    command = ("switchobs codegen abs-xbs4 --spectrum=-beta1,-beta1,-beta2,-beta2 --param beta1=10 "
               "--param beta2=20 --out gen")
    monkeypatch.chdir(tmp_path)
    status, out = run(command, capsys)
    assert status == 0 and out == shown_output("codegen.md", command)
    page = (ROOT / "docs" / "codegen.md").read_text("utf-8")
    program = re.search(r"```c\n(#include <stdio.h>.*?)```", page, re.S).group(1)
    readme = (tmp_path / "gen" / "README.md").read_text("utf-8")
    assert program == re.search(r"## Example\n\n```c\n(.*?)```", readme, re.S).group(1)
    header = (tmp_path / "gen" / "switchobs_abs_xbs4.h").read_text("utf-8")
    assert "#define SWITCHOBS_ABS_XBS4_SZ_W 42" in header and "_STACK_REALS 53" in header   # radau3, the default
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.skip("no C compiler")
    line = re.search(r"^\$ (cc .*?) && \./ex\n(.*?)\n```", page, re.S | re.M)
    (tmp_path / "gen" / "ex.c").write_text(program, encoding="utf-8")
    build = subprocess.run(shlex.split(line.group(1)), cwd=tmp_path / "gen", capture_output=True, text=True)
    assert build.returncode == 0, build.stderr
    ran = subprocess.run(["./ex"], cwd=tmp_path / "gen", capture_output=True, text=True)
    assert ran.returncode == 0 and ran.stdout.rstrip("\n") == line.group(2)


def test_the_table41_sweep_of_the_sweeps_page_prints_what_the_page_shows(tmp_path, monkeypatch, capsys):
    command = "switchobs sweep examples/sweep_table41.toml --scheduler none --out table41.jsonl --plots figures/"
    (tmp_path / "examples").mkdir()
    shutil.copy(ROOT / "examples" / "sweep_table41.toml", tmp_path / "examples")
    (tmp_path / "figures").mkdir()
    monkeypatch.chdir(tmp_path)
    status, out = run(command, capsys)
    assert status == 0
    # the run's wall time and rate differ between runs; the rest (every distance) is what the page shows
    clock = re.compile(r" in [\d.]+ s, [\d.]+ cases/s\)")
    assert clock.sub(")", out) == clock.sub(")", shown_output("sweeps.md", command))


def test_the_usage_example_of_the_observers_page_prints_what_the_page_shows(capsys):
    page = (ROOT / "docs" / "observers.md").read_text("utf-8")
    code, shown = re.search(r"## Usage\n\n```python\n(.*?)```\n\nprints\n\n```\n(.*?)```", page, re.S).groups()
    *body, last = code.rstrip("\n").splitlines()
    namespace: dict = {}
    exec("\n".join(body), namespace)   # noqa: S102 - our own documentation
    with pytest.raises(Exception) as refused:   # the last line shows a refused step
        exec(last, namespace)   # noqa: S102
    error = refused.value
    printed = capsys.readouterr().out + f"{type(error).__module__}.{type(error).__qualname__}: {error}\n"
    assert printed == shown
    names = re.search(r">>> (adaptive_xbs_observer\(.*?\)\.state_names)\n(.*?)\n```", page, re.S)
    assert repr(eval(names.group(1), namespace)) == names.group(2)   # noqa: S307


@pytest.mark.slow
def test_the_demo_output_of_the_guide_is_what_the_demo_prints(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["demo"]) == 0
    captured = capsys.readouterr()
    # the stages' clocks and the C timings differ between runs and machines; every other figure is shown
    clocks = [(re.compile(r"done in [\d.]+ s \(total [\d.]+ s\)"), "done in _"),
              (re.compile(r"\d+ ns per step"), "_ ns per step"), (re.compile(r"\) \d+ ns$", re.M), ") _ ns")]

    def steady(text: str) -> str:
        for pattern, fixed in clocks:
            text = pattern.sub(fixed, text)
        return text
    printed = captured.err.rstrip("\n") + "\n" + captured.out.rstrip("\n")
    assert steady(printed) == steady(shown_output("guide.md", "switchobs demo"))
