"""The proof that the generated step has no run-time errors (Frama-C EVA over the declared ranges).

Each proof calls every public function of the header on any finite input (``<prefix>_proof.c``); zero
alarms under ``-warn-special-float non-finite`` is the claim of docs/codegen.md ("Proof of no run-time
errors").  A mutant without the determinant check shows that the analysis does find the division.
"""

from __future__ import annotations

import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from switchobs.codegen import StepStatus, compile_observer, generate_observer, proof_driver, proof_record, prove
from switchobs.design import design
from switchobs.exceptions import CodegenError
from switchobs.model import builtin_model

ROOT = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.skipif(shutil.which("frama-c") is None,
                                reason="frama-c is not installed: the proof of no run-time errors is NOT checked")

#: Declared ranges of abs-xbs3 (ours): wheel acceleration offset and XBS states, speed 1-70 m/s, 0.01-10 ms
#: steps, every parameter within about a factor 2 of its default (poles at -100).  docs/codegen.md shows them.
XBS3_RANGES = {"z1": (-200, 200), "z2": (-100, 100), "z3": (-1e5, 1e5), "y": (-200, 200), "vx": (1, 70),
               "u": (-1e4, 1e4), "dt": (1e-5, 1e-2), "a": (100, 300), "b": (-8, -2), "c": (17, 68),
               "K_plus_z1": (167, 668), "K_plus_z2": (-441, -110), "K_plus_z3": (-10667, -2666),
               "K_minus_z1": (-532, -133), "K_minus_z2": (-224, -55), "K_minus_z3": (2666, 10667)}
#: The same as ``switchobs codegen --range`` (the command of docs/codegen.md).
RANGE_OPTION = "--range=" + ",".join(f"{n}={lo:g}:{hi:g}" for n, (lo, hi) in XBS3_RANGES.items())
PAGE_COMMAND = f"switchobs codegen abs-xbs3 --spectrum=-100,-100,-100 --method=radau3 {RANGE_OPTION} --prove --out gen"


def xbs3(method: str, real: str = "double", **options):
    m = builtin_model("abs-xbs3")
    return generate_observer(m, design(m, "-100,-100,-100"), method=method, real=real, ranges=XBS3_RANGES,
                             **options)


@pytest.mark.parametrize("method, real, options", [
    ("radau3", "double", {}),
    ("rk4", "float", {}),
    pytest.param("radau3", "float", {}, marks=pytest.mark.slow),
    pytest.param("midpoint", "double", {}, marks=pytest.mark.slow),
    pytest.param("euler", "double", {}, marks=pytest.mark.slow),
    pytest.param("rk4", "double", {"h_max": "1/100"}, marks=pytest.mark.slow),
])
def test_eva_finds_no_alarm_for_any_finite_input(method, real, options):
    gen = xbs3(method, real, **options)
    assert f"{gen.prefix}_proof.c" in gen.files
    result = prove(gen)
    assert result.alarms == 0, "\n".join(result.unproved)
    assert result.proved >= 4 and result.seconds < 120
    record = proof_record(gen, result)
    assert "**0 alarm(s)**" in record and result.command in record


def test_eva_finds_the_division_when_the_determinant_check_is_removed(tmp_path):
    """The analysis is not vacuous: without the DET_FLOOR refusal the solve's division is an alarm."""
    gen = xbs3("radau3")
    # the braced refusal: if (... DET_FLOOR ...) { return ...; }
    check = re.search(r"\n *if \([^\n]*_DET_FLOOR\)[^\n]*\{\n[^\n]*\n *\}(?=\n)", gen.source)
    assert check, "no DET_FLOOR refusal in the ranged step"
    mutant = type(gen)(**{**{f: getattr(gen, f) for f in gen.__dataclass_fields__},
                          "source": gen.source.replace(check.group(0), "")})
    result = prove(mutant, directory=tmp_path)
    assert result.alarms > 0 and any("inv" in u for u in result.unproved), result.unproved


def test_the_ranged_step_refuses_outside_its_ranges_with_the_documented_codes():
    obs = compile_observer(xbs3("radau3"))
    x, sig = np.array([1.0, 0.5, 10.0]), np.array([2.0, 20.0, 100.0])
    assert np.all(np.isfinite(obs.step(x, sig, 1e-3)))
    cases = [(np.array([300.0, 0.5, 10.0]), sig, 1e-3, StepStatus.STATE_RANGE),
             (x, np.array([2.0, 0.5, 100.0]), 1e-3, StepStatus.SIGNAL_RANGE),
             (x, np.array([2.0, 20.0, 2e4]), 1e-3, StepStatus.SIGNAL_RANGE),
             (x, sig, 0.5, StepStatus.BAD_DT)]
    for xs, ss, dt, code in cases:
        with pytest.raises(Exception) as info:
            obs.step(xs, ss, dt)
        assert getattr(info.value, "code", None) == int(code), (xs, ss, dt, info.value)


def test_the_proof_needs_a_range_of_every_input():
    m = builtin_model("abs-xbs3")
    gen = generate_observer(m, design(m, "-100,-100,-100"), ranges={"vx": (1.0, 70.0)})
    assert f"{gen.prefix}_proof.c" not in gen.files and "z1" in gen.unranged and "dt" in gen.unranged
    assert "No proof driver: `z1`, `z2`, `z3`, `y`, `u`," in gen.readme and "| `vx` | 1.0 | 70.0 |" in gen.readme
    with pytest.raises(CodegenError, match="none for z1, z2, z3, y, u"):
        proof_driver(gen)
    with pytest.raises(CodegenError, match=r"range of dt .* lo > 0"):
        generate_observer(m, design(m, "-100,-100,-100"), ranges={"dt": (0.0, 1.0)})
    with pytest.raises(CodegenError, match="'w': not a state, signal or parameter"):
        generate_observer(m, design(m, "-100,-100,-100"), ranges={"w": (0.0, 1.0)})


def test_cli_prove_writes_the_record_and_exits_0(tmp_path):
    gen = xbs3("radau3", "float")
    cmd = [sys.executable, "-m", "switchobs.cli.main", "codegen", "abs-xbs3", "--spectrum=-100,-100,-100",
           "--method=radau3", "--real=float", RANGE_OPTION, "--prove", "--out", str(tmp_path)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert "no alarm" in proc.stdout
    record = (tmp_path / f"{gen.prefix}_proof.md").read_text()
    assert "**0 alarm(s)**" in record
    assert (tmp_path / f"{gen.prefix}_proof.c").read_text() == gen.files[f"{gen.prefix}_proof.c"]
    assert result_command(gen) in (tmp_path / "README.md").read_text() and result_command(gen) in record
    bad = subprocess.run([*cmd[:-3], "--range=vx=1", "--out", str(tmp_path / "b")], capture_output=True,
                         text=True, timeout=120)
    assert bad.returncode == 2 and "NAME=LO:HI" in bad.stderr and len(bad.stderr.splitlines()) == 1


def result_command(gen) -> str:
    from switchobs.codegen._proof import proof_command

    return " ".join(proof_command(gen.prefix))


def test_the_proof_shown_on_the_codegen_page_is_what_the_command_prints(tmp_path, monkeypatch, capsys):
    from _docs_blocks import matches_with_elisions, shown_output

    from switchobs.cli.main import main

    monkeypatch.chdir(tmp_path)
    assert main(shlex.split(PAGE_COMMAND)[1:]) == 0
    out = capsys.readouterr().out.rstrip("\n")
    assert matches_with_elisions(shown_output("codegen.md", PAGE_COMMAND), out), out
    shown_record = re.search(r"```text\n(# Proof of no run-time errors.*?)```", (ROOT / "docs/codegen.md").read_text(),
                             re.S)
    assert shown_record, "docs/codegen.md shows no proof record"
    record = (tmp_path / "gen/switchobs_abs_xbs3_proof.md").read_text()
    assert matches_with_elisions(shown_record.group(1), record), record


def test_the_ranged_files_compile_clean_with_strict_warnings(tmp_path):
    cc = shutil.which("gcc")
    if cc is None:
        pytest.skip("gcc is not installed: the strict compile of the ranged step is NOT checked")
    for method, real, options in [("radau3", "float", {}), ("rk4", "double", {"h_max": "1/100"})]:
        gen = xbs3(method, real, **options)
        for name, text in gen.files.items():
            (tmp_path / name).write_text(text)
        proc = subprocess.run([cc, "-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Wconversion", "-Wfloat-conversion",
                               "-Wdouble-promotion", "-Werror", "-c", str(tmp_path / f"{gen.prefix}.c"), "-o",
                               str(tmp_path / "x.o")], capture_output=True, text=True)
        assert proc.returncode == 0, proc.stderr
