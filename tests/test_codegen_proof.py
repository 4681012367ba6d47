"""The proof that the generated step has no run-time errors (Frama-C EVA over the declared ranges).

Each proof calls every public function of the header on any finite input (``<prefix>_proof.c``); zero
alarms under ``-warn-special-float non-finite`` is the claim of docs/codegen.md ("Proof of no run-time
errors").  A mutant without the determinant check shows that the analysis does find the division.
"""

from __future__ import annotations

import shutil
import subprocess
import sys

import numpy as np
import pytest

from switchobs.codegen import StepStatus, compile_observer, generate_observer, proof_driver, proof_record, prove
from switchobs.design import design
from switchobs.exceptions import CodegenError
from switchobs.model import builtin_model

pytestmark = pytest.mark.skipif(shutil.which("frama-c") is None,
                                reason="frama-c is not installed: the proof of no run-time errors is NOT checked")

#: Declared ranges of abs-xbs3 (ours): wheel acceleration offset and XBS state, speed 1-70 m/s, 0.01-10 ms
#: steps; every parameter within a factor 2 of its default (below).
XBS3_RANGES = {"z1": (-200.0, 200.0), "z2": (-100.0, 100.0), "z3": (-1e5, 1e5), "y": (-200.0, 200.0),
               "vx": (1.0, 70.0), "u": (-1e4, 1e4), "dt": (1e-5, 1e-2)}


def xbs3(method: str, real: str = "double", **options):
    m = builtin_model("abs-xbs3")
    gains = design(m, "-100,-100,-100")
    plain = generate_observer(m, gains)
    ranges = dict(XBS3_RANGES)
    for name, v in zip(plain.param_names, plain.default_params):
        ranges[name] = (min(0.5 * v, 2 * v), max(0.5 * v, 2 * v))
    return generate_observer(m, gains, method=method, real=real, ranges=ranges, **options)


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
    check = next(line for line in gen.source.splitlines() if "_DET_FLOOR)" in line)
    mutant = type(gen)(**{**{f: getattr(gen, f) for f in gen.__dataclass_fields__},
                          "source": gen.source.replace(check, "")})
    result = prove(mutant, directory=tmp_path)
    assert result.alarms > 0 and any("adet" in u for u in result.unproved), result.unproved


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
    with pytest.raises(CodegenError, match="none for z1, z2, z3, y, u"):
        proof_driver(gen)
    with pytest.raises(CodegenError, match=r"range of dt .* lo > 0"):
        generate_observer(m, design(m, "-100,-100,-100"), ranges={"dt": (0.0, 1.0)})
    with pytest.raises(CodegenError, match="'w': not a state, signal or parameter"):
        generate_observer(m, design(m, "-100,-100,-100"), ranges={"w": (0.0, 1.0)})


def test_cli_prove_writes_the_record_and_exits_0(tmp_path):
    gen = xbs3("radau3", "float")
    ranges = [f"--range={n}={lo!r}:{hi!r}" for n, (lo, hi) in gen.ranges.items()]
    cmd = [sys.executable, "-m", "switchobs.cli.main", "codegen", "abs-xbs3", "--spectrum=-100,-100,-100",
           "--method=radau3", "--real=float", *ranges, "--prove", "--out", str(tmp_path)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert "no alarm" in proc.stdout
    record = (tmp_path / f"{gen.prefix}_proof.md").read_text()
    assert "**0 alarm(s)**" in record
    assert (tmp_path / f"{gen.prefix}_proof.c").read_text() == gen.files[f"{gen.prefix}_proof.c"]
    bad = subprocess.run([*cmd[:-3], "--range=vx=1", "--out", str(tmp_path / "b")], capture_output=True,
                         text=True, timeout=120)
    assert bad.returncode == 2 and "NAME=LO:HI" in bad.stderr and len(bad.stderr.splitlines()) == 1
