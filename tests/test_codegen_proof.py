"""The proof that the generated step has no run-time errors (Frama-C EVA over the declared ranges).

Each proof calls every public function of the header on any finite input (``<prefix>_proof.c``); zero
alarms under ``-warn-special-float non-finite`` is the claim of docs/codegen.md ("Proof of no run-time
errors").  A mutant without the determinant check shows that the analysis does find the division, and a
user model whose declared range of a divisor holds 0 shows that it finds the model's own divisions.

The variants: abs-xbs3, abs-xbs4, abs-adaptive2, a user model whose d(y) and b(y) divide by signals, and the
super-twisting observer, each with every method it admits and both real types.  ``make test`` proves a
representative subset (every method and both real types at least once, every kind of observer);
``make prove`` (``SWITCHOBS_PROVE_ALL=1``) proves all of them.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from switchobs.codegen import GeneratedObserver, StepStatus, compile_observer, generate_observer, proof_driver, \
    proof_record, prove
from switchobs.design import design
from switchobs.exceptions import CodegenError
from switchobs.model import builtin_model
from switchobs.spec import METHODS
from switchobs.report._repro_target import PROOF_ROWS, XBS3_RANGES, proved_observer

ROOT = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.skipif(shutil.which("frama-c") is None,
                                reason="frama-c is not installed: the proof of no run-time errors is NOT checked")

#: The same as ``switchobs codegen --range`` (the command of docs/codegen.md).
RANGE_OPTION = "--range=" + ",".join(f"{n}={lo:g}:{hi:g}" for n, (lo, hi) in XBS3_RANGES.items())
PAGE_COMMAND = f"switchobs codegen abs-xbs3 --spectrum=-100,-100,-100 --method=radau3 {RANGE_OPTION} --prove --out gen"


def xbs3(method: str, real: str = "double", **options):
    return proved_observer("abs-xbs3", method, real, options.pop("h_max", None), **options)


def ranged(name: str, method: str, real: str, h_max: str | None = None,
           ranges: dict[str, tuple[float, float]] | None = None) -> GeneratedObserver:
    """The observer ``name`` with a declared range of every input (docs/codegen.md's proof table's)."""
    return proved_observer(name, method, real, h_max, ranges)


#: (observer, method, real, h_max) of ``make test`` besides the proof table of docs/codegen.md ("On the target",
#: :data:`PROOF_ROWS`, kept equal to a fresh run by tests/test_reproductions.py): with it, every method (rk4
#: sub-stepped too), both real types and every kind of observer.
VARIANTS = [("abs-xbs3", "radau3", "double", None), ("abs-xbs3", "rk4", "float", None),
            ("user", "euler", "float", None), ("user", "midpoint", "double", None),
            ("abs-adaptive2", "rk4", "double", "1/50")]
#: The rest of the matrix (``make prove``): every method each observer admits, rk4 sub-stepped, both reals.
_METHODS = {"abs-xbs3": ("euler", "rk4", "midpoint", "radau3"), "abs-xbs4": ("euler", "rk4", "midpoint", "radau3"),
            "user": ("euler", "rk4", "midpoint", "radau3"), "abs-adaptive2": ("euler", "rk4"),
            "super-twisting": ("euler",), "vehicle-speed": ("euler",)}
_H_MAX = {"abs-xbs3": "1/100", "abs-xbs4": "1/100", "user": "1/100", "abs-adaptive2": "1/50"}
ALL_VARIANTS = [(name, method, real, h_max) for name, methods in _METHODS.items() for real in ("double", "float")
                for method, h_max in [*((m, None) for m in methods),
                                      *((("rk4", _H_MAX[name]),) if name in _H_MAX else ())]]
EXTRA = [v for v in ALL_VARIANTS if v not in VARIANTS]
assert set(VARIANTS) | set(PROOF_ROWS) <= set(ALL_VARIANTS)
assert {m for _, m, _, h in (*VARIANTS, *PROOF_ROWS) if h is None} == set(METHODS)
assert {r for _, _, r, _ in VARIANTS} == {"double", "float"} and any(h for *_, h in VARIANTS)


@pytest.mark.parametrize("name, method, real, h_max", [
    *VARIANTS,
    *(pytest.param(*v, marks=pytest.mark.slow) for v in (EXTRA if os.environ.get("SWITCHOBS_PROVE_ALL") == "1"
                                                          else ())),
])
def test_eva_finds_no_alarm_for_any_finite_input(name, method, real, h_max):
    gen = ranged(name, method, real, h_max)
    assert f"{gen.prefix}_proof.c" in gen.files
    result = prove(gen)
    assert result.alarms == 0, "\n".join(result.unproved)
    assert result.proved >= 4 and result.seconds < 120
    record = proof_record(gen, result)
    assert "**0 alarm(s)**" in record and result.command in record


def test_eva_finds_the_division_by_a_signal_whose_range_holds_zero():
    """The user model's y - 1 divides b(y): with y declared in [0.5, 200] (1 inside) the proof fails on it, and
    the README and the record name that divisor beforehand."""
    from switchobs.codegen import divisor_gaps

    gen = ranged("user", "euler", "double", ranges={"y": (0.5, 200)})
    gaps = divisor_gaps(gen)
    assert gaps == ("y - 1 (denominator of 1/(y - 1)) is in [-0.5, 199] over the declared ranges",)
    assert f"- `{gaps[0]}`" in gen.readme and f"`{gaps[0]}`" in (ROOT / "docs/codegen.md").read_text("utf-8")
    proved = ranged("user", "euler", "double")  # y in [1.5, 200]
    assert not divisor_gaps(proved) and "divisor" not in proved.readme
    result = prove(gen)
    assert result.alarms > 0 and any("division_by_zero" in u or "is_nan_or_infinite" in u or "non-finite" in u
                                     for u in result.unproved), result.unproved
    assert f"- `{gaps[0]}`" in proof_record(gen, result)


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
    from switchobs.codegen import proof_command

    return " ".join(proof_command(gen))


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
    """The host gcc with the flags of the style guide, and arm-none-eabi-gcc with the target's warning flags
    (-Werror, docs/codegen.md "On the target") for the Cortex-M4F (float) and the Cortex-M7 (double)."""
    from switchobs.codegen import TARGETS
    from switchobs.codegen._target import WARNING_FLAGS

    cc, cross = shutil.which("gcc"), shutil.which("arm-none-eabi-gcc")
    if cc is None or cross is None:
        pytest.skip("gcc or arm-none-eabi-gcc is not installed: the strict compile of the ranged step is NOT checked")
    for name, method, real, h_max in [("abs-xbs3", "radau3", "float", None), ("abs-xbs3", "rk4", "double", "1/100"),
                                      ("abs-adaptive2", "rk4", "float", "1/50"), ("user", "midpoint", "double", None),
                                      ("super-twisting", "euler", "float", None)]:
        gen = ranged(name, method, real, h_max)
        for file, text in gen.files.items():
            (tmp_path / file).write_text(text)
        source, obj = str(tmp_path / f"{gen.prefix}.c"), str(tmp_path / "x.o")
        target = TARGETS["cortex-m4f" if real == "float" else "cortex-m7"]
        for cmd in ([cc, "-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Wconversion", "-Wfloat-conversion",
                     "-Wdouble-promotion", "-Werror", "-c", source, "-o", obj],
                    [cross, *target.flags, "-Werror", *WARNING_FLAGS, "-c", source, "-o", obj]):
            proc = subprocess.run(cmd, capture_output=True, text=True)
            assert proc.returncode == 0, (name, method, real, cmd[0], proc.stderr)


@pytest.mark.parametrize("real", ["double", "float"])
def test_run_with_no_row_checks_dt_and_the_state_against_their_declared_ranges(real):
    """The zero-step contract of the ranged build: what a step checks without a row, ranges included (the C
    _run itself, called past CObserver's own checks, and CObserver.run)."""
    obs = compile_observer(xbs3("radau3", real))
    lo, hi = obs.generated.ranges["dt"]
    dtype = np.float64 if real == "double" else np.float32
    none = np.zeros((0, obs.generated.ns), dtype=dtype)

    def c_run(x, dt):
        x = np.array(x, dtype=dtype)
        before = x.copy()
        code = obs._run_addr(x.ctypes.data, none.ctypes.data, 0, obs._params_addr, dt, 0)
        assert x.tobytes() == before.tobytes()  # no row changes nothing
        return code

    inside, outside = [1.0, 0.5, 10.0], [300.0, 0.5, 10.0]
    assert c_run(inside, 1e-3) == int(StepStatus.OK)
    for dt in (0.5, 2 * hi, lo / 2, 0.0, -1e-3, np.nan, np.inf):
        assert c_run(inside, dt) == int(StepStatus.BAD_DT), dt
        with pytest.raises(Exception, match="BAD_DT") as info:
            obs.run(inside, none, dt)
        assert info.value.code == int(StepStatus.BAD_DT)
    assert c_run(outside, 1e-3) == int(StepStatus.STATE_RANGE)
    assert c_run([np.nan, 0.5, 10.0], 1e-3) == int(StepStatus.NONFINITE_STATE)
    with pytest.raises(Exception, match="STATE_RANGE"):
        obs.run(outside, none, 1e-3)
    # the same codes as the first step of one row, at the range's ends too (compared in the real type: a double
    # just below DT_MIN rounds up to it in float, and the C accepts it)
    row = np.array([[2.0, 20.0, 100.0]])
    for dt in (lo, hi, float(np.nextafter(lo, 0.0)), float(np.nextafter(hi, 1.0)), 0.5):
        accepted = lo <= float(dtype(dt)) <= hi
        assert (c_run(inside, dt) == int(StepStatus.OK)) == accepted, dt
        one = obs._run_addr(np.array(inside, dtype=dtype).ctypes.data, row.astype(dtype).ctypes.data, 1,
                            obs._params_addr, dt, 0)
        assert (one == int(StepStatus.OK)) == accepted, dt
        if accepted:
            assert obs.run(inside, none, dt).shape == (0, 3)
        else:
            with pytest.raises(Exception, match="BAD_DT"):
                obs.run(inside, none, dt)


def test_cli_proves_the_super_twisting_observer_with_its_declared_ranges(tmp_path):
    from switchobs.report._repro_target import STATE_SIGNAL_RANGES

    gen = ranged("super-twisting", "euler", "float")
    option = "--range=" + ",".join(f"{n}={lo!r}:{hi!r}" for n, (lo, hi) in gen.ranges.items())
    assert set(STATE_SIGNAL_RANGES["super-twisting"]) < set(gen.ranges)  # lam and alpha too
    proc = subprocess.run([sys.executable, "-m", "switchobs.cli.main", "codegen", "super-twisting", "--param",
                           "lam=400", "--param", "alpha=2000", "--real=float", option, "--prove", "--out",
                           str(tmp_path)], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert "no alarm" in proc.stdout
    assert (tmp_path / f"{gen.prefix}_proof.c").read_text() == gen.files[f"{gen.prefix}_proof.c"]
    assert "**0 alarm(s)**" in (tmp_path / f"{gen.prefix}_proof.md").read_text()


def test_the_codegen_page_states_the_matrix_that_make_prove_proves():
    page = (ROOT / "docs/codegen.md").read_text("utf-8")
    assert f"each in double and float ({len(ALL_VARIANTS)} variants)" in page
    assert "SWITCHOBS_PROVE_ALL=1" in (ROOT / "Makefile").read_text("utf-8")
