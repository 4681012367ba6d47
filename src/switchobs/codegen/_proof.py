"""A proof that the generated step has no run-time errors: the Frama-C EVA driver and its run.

With a declared range for every state, signal, parameter and ``dt``
(``generate_observer(ranges=...)``, ``switchobs codegen --range``) the step
refuses, by comparisons only, every input outside that box before it
computes anything, and checks locally what its arithmetic needs: ``|det D(Z)|``
at least ``DET_FLOOR`` before the implicit solve's one division, at most
``MAX_SUBSTEPS`` sub-steps, each sub-step's state back in its box.  The
driver ``<prefix>_proof.c`` calls every public function of the header on
nondeterministic inputs -- every real *any finite value* (the interval builtins
of Frama-C), the row count, the pointers NULL or not -- and EVA, with
``-warn-special-float non-finite`` (an operation that may give an infinity or a
NaN is an alarm), shows that no call has a run-time error: no division by zero,
no overflow to infinity, no NaN, no invalid memory access, no uninitialised
read, no signed overflow, no float-to-int conversion out of range.  So every
call that returns OK was computed without one, for every finite input.

:func:`prove` runs it and returns the alarm count read from Frama-C's report;
:func:`proof_record` is the ``<prefix>_proof.md`` that records the command and
the result next to the code.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from .._json import JsonRecord
from ..exceptions import CodegenError, PrerequisiteError

if TYPE_CHECKING:
    from ._generate import GeneratedObserver

__all__ = ["ProofResult", "proof_driver", "proof_command", "loop_unroll", "divisor_gaps", "prove", "proof_record",
           "EVA_PRECISION"]

#: ``-eva-precision`` of the proof (0-11): 3 keeps the refusal branches of the checks apart (at 1, 94 alarms on
#: abs-xbs3 radau3) within seconds per variant.
EVA_PRECISION = 3
#: Rows of the ``_run`` / ``_run_dt`` calls of the driver: their count is any of 0..ROWS.
_ROWS = 2


def divisor_gaps(gen: GeneratedObserver) -> tuple[str, ...]:
    """The divisors of the model (its ``nonzero`` guards: denominators of ``d``, ``b``, ``s`` and of the
    parameters) that the declared ranges do not keep away from 0, each with its interval over the ranges.

    The step refuses such a divisor only when it is exactly 0 (``NONFINITE_RESULT``...), so a value next to 0
    passes and the division by it may overflow: EVA reports it.  Empty when every divisor's interval (interval
    arithmetic on the declared ranges, :class:`sympy.AccumBounds`) excludes 0, or has no declared range.
    """
    import sympy as sp

    out = []
    for guard in gen.guards:
        names = {s.name for s in guard.expr.free_symbols}
        if guard.kind != "nonzero" or not names <= set(gen.ranges):
            continue
        env = {s: sp.AccumBounds(*(sp.Rational(v) for v in gen.ranges[s.name])) for s in guard.expr.free_symbols}
        try:
            value = guard.expr.subs(env)
            lo, hi = (value.min, value.max) if isinstance(value, sp.AccumBounds) else (value, value)
            holds_zero = bool(lo <= 0) and bool(hi >= 0)
        except (TypeError, ValueError):  # an expression interval arithmetic cannot bound: no hint
            continue
        if holds_zero:
            out.append(f"{guard.expr} ({guard.reason}) is in [{float(lo):g}, {float(hi):g}] over the declared ranges")
    return tuple(out)


def loop_unroll(gen: GeneratedObserver) -> int:
    """``-eva-auto-loop-unroll`` of the proof: the longest loop over an array of the API or the driver.

    Those loops (state, parameters, signal rows, original state) are unrolled whole, so that every entry they
    write is known written: unrolled only 4 times, the copies of abs-adaptive2's 8 states through ``cur`` read
    as uninitialised (6 alarms).  The sub-step loop (``MAX_SUBSTEPS`` turns, 64 by default) stays analysed by
    widening, bounded by its ``j < n`` and the state checks of every sub-step (unrolled whole, abs-xbs3 rk4
    ``--h-max 1/100`` took 88 s instead of 37 s on a loaded machine, with the same 0 alarms).
    """
    return max(gen.nx, gen.np, _ROWS * gen.ns, _ROWS, len(gen.original_names))


def proof_command(gen: GeneratedObserver, *, precision: int = EVA_PRECISION) -> list[str]:
    """The Frama-C command of the proof, run in the directory of the generated files."""
    p = gen.prefix
    return ["frama-c", "-eva", "-eva-precision", str(precision), "-eva-auto-loop-unroll", str(loop_unroll(gen)),
            "-warn-special-float", "non-finite",
            "-warn-signed-overflow", "-eva-no-show-progress", f"{p}.c", f"{p}_proof.c"]


def proof_driver(gen: GeneratedObserver) -> str:
    """The text of ``<prefix>_proof.c``: ``main`` calls every public function on any finite inputs.

    Raises
    ------
    CodegenError
        Some input has no declared range (:attr:`GeneratedObserver.unranged`): the proof would not hold.
    """
    if gen.unranged:
        raise CodegenError(f"the proof needs a declared range of every state, signal, parameter and dt; none for "
                           f"{', '.join(gen.unranged)} (give them with --range NAME=LO:HI)")
    p, P, real = gen.prefix, gen.prefix.upper(), gen.real
    draw = "Frama_C_float_interval(-FLT_MAX, FLT_MAX)" if real == "float" else \
        "Frama_C_double_interval(-DBL_MAX, DBL_MAX)"
    original = [] if not gen.original_names else [
        f"    status = {p}_original(x, sig, (const {real} *)Frama_C_nondet_ptr(par, NULL), xo);"]
    lines = [
        f"/* {p}_proof.c -- generated by switchobs; do not edit.",
        " * Frama-C EVA driver of the proof that the step has no run-time errors: every public function of",
        f" * {p}.h is called on nondeterministic inputs, each real ANY finite value, the row counts any of",
        f" * 0..{_ROWS}, the optional pointers NULL or not.  The step refuses what lies outside the declared",
        f" * ranges of {p}.h before computing anything, so no alarm means no run-time error for every",
        " * finite input.  Run in this directory (the result is in " + f"{p}_proof.md):",
        " *   " + " ".join(proof_command(gen)),
        " */",
        f'#include "{p}.h"',
        "",
        "#include <float.h>",
        "#include <stddef.h>",
        "#include \"__fc_builtin.h\"",
        "",
        f"#define ROWS {_ROWS}",
        "",
        f"static {real} any_real(void) {{ return {draw}; }}",
        "",
        "int main(void)",
        "{",
        f"    {real} x[{P}_NX], sig[ROWS * {P}_NS], par[{P}_NP], dts[ROWS], traj[ROWS * {P}_NX];",
        *([f"    {real} xo[{P}_NO];"] if gen.original_names else []),
        "    int32_t i, rows, status;",
        f"    for (i = 0; i < {P}_NX; ++i) {{ x[i] = any_real(); }}",
        f"    for (i = 0; i < ROWS * {P}_NS; ++i) {{ sig[i] = any_real(); }}",
        f"    for (i = 0; i < {P}_NP; ++i) {{ par[i] = any_real(); }}",
        "    for (i = 0; i < ROWS; ++i) { dts[i] = any_real(); }",
        f"    status = {p}_step(x, sig, par, any_real());",
        f"    status = {p}_step(x, sig, NULL, any_real());",
        "    rows = Frama_C_interval(0, ROWS);",
        f"    status = {p}_run(x, sig, rows, (const {real} *)Frama_C_nondet_ptr(par, NULL), any_real(),",
        f"        ({real} *)Frama_C_nondet_ptr(traj, NULL));",
        f"    status = {p}_run_dt(x, sig, rows, (const {real} *)Frama_C_nondet_ptr(par, NULL), dts,",
        f"        ({real} *)Frama_C_nondet_ptr(traj, NULL));",
        *original,
        f"    (void){p}_status_message(Frama_C_interval(-2147483647 - 1, 2147483647));",
        "    return (int)status;",
        "}",
        "",
    ]
    return "\n".join(lines)


@dataclass(frozen=True)
class ProofResult(JsonRecord, error=CodegenError):
    """One EVA run of the proof driver.

    Attributes
    ----------
    prefix : str
    command : str
        The command as run, in the directory of the generated files.
    frama_c_version : str
    alarms : int
        Alarms EVA emitted (each a possible run-time error) plus the properties it could not prove or found
        invalid (its summary); 0 is the proof.
    proved : int
        Properties EVA validated (the preconditions of the libc and builtin functions the code calls).
    seconds : float
        Wall time of the run.
    unproved : tuple of str
        The report's lines of every property not proved (empty when ``alarms`` is 0).
    """

    prefix: str
    command: str
    frama_c_version: str
    alarms: int
    proved: int
    seconds: float
    unproved: tuple[str, ...] = ()

    @property
    def ok(self) -> bool:
        return self.alarms == 0

    def to_json(self) -> dict:
        return {"prefix": self.prefix, "command": self.command, "frama_c_version": self.frama_c_version,
                "alarms": self.alarms, "proved": self.proved, "seconds": self.seconds,
                "unproved": list(self.unproved)}

    def __str__(self) -> str:
        verdict = "no alarm: no run-time error for any finite input" if self.ok else f"{self.alarms} alarm(s)"
        return f"EVA proof of {self.prefix}: {verdict} ({self.proved} properties valid, {self.seconds:.1f} s)"


_ALARMS = re.compile(r"^\s*(\d+) alarms? generated by the analysis", re.M)
_PROPERTIES = re.compile(r"^\s*(Assertions|Preconditions)\s+(\d+) valid\s+(\d+) unknown\s+(\d+) invalid", re.M)
_COVERAGE = re.compile(r"(\d+) functions analyzed \(out of (\d+)\)")


def _frama_c() -> str:
    exe = shutil.which("frama-c")
    if exe is None:
        raise PrerequisiteError("frama-c is not installed: the proof of no run-time errors needs Frama-C EVA "
                                "(Debian: apt-get install frama-c-base)")
    return exe


def prove(gen: GeneratedObserver, *, directory: str | Path | None = None, timeout: float = 600.0,
          precision: int = EVA_PRECISION) -> ProofResult:
    """Run Frama-C EVA on ``<prefix>.c`` with the driver ``<prefix>_proof.c`` and count the alarms.

    Parameters
    ----------
    gen : GeneratedObserver
        Generated with a range for every input (else :class:`CodegenError`).
    directory : path, optional
        Where the files are (written there when missing); default a temporary directory.
    timeout : float
        Seconds before the run is abandoned (:class:`PrerequisiteError`).

    Raises
    ------
    CodegenError
        An input without a range.
    PrerequisiteError
        frama-c missing, failing or timing out (the message has its last output line).
    """
    driver = proof_driver(gen)
    exe = _frama_c()
    with tempfile.TemporaryDirectory(prefix="switchobs-proof-") as tmp:
        where = Path(directory) if directory is not None else Path(tmp)
        where.mkdir(parents=True, exist_ok=True)
        for name, text in {**gen.files, f"{gen.prefix}_proof.c": driver}.items():
            if name.endswith((".c", ".h")):
                (where / name).write_text(text)
        cmd = proof_command(gen, precision=precision)
        version = subprocess.run([exe, "-version"], capture_output=True, text=True, timeout=60).stdout.strip()
        t0 = time.perf_counter()
        try:
            # frama-c resolves the file names against $PWD, which a change of directory alone leaves stale
            proc = subprocess.run([exe, *cmd[1:]], cwd=where, capture_output=True, text=True, timeout=timeout,
                                  env={**os.environ, "PWD": str(where.resolve())})
        except subprocess.TimeoutExpired:
            raise PrerequisiteError(f"frama-c did not finish the proof of {gen.prefix} within {timeout:g} s") from None
        seconds = time.perf_counter() - t0
    found, props, cover = _ALARMS.search(proc.stdout), _PROPERTIES.findall(proc.stdout), _COVERAGE.search(proc.stdout)
    if proc.returncode != 0 or found is None or cover is None:
        last = [line for line in (proc.stderr + proc.stdout).splitlines() if "rror" in line][:1] or \
            (proc.stderr or proc.stdout).strip().splitlines()[-1:] or ["no output"]
        raise PrerequisiteError(f"frama-c failed on the proof of {gen.prefix} (exit {proc.returncode}): {last[0]}")
    if cover.group(1) != cover.group(2):  # a function not analysed would be a hole in the proof
        raise PrerequisiteError(f"frama-c analysed {cover.group(1)} of the {cover.group(2)} functions of {gen.prefix}")
    out = proc.stdout.splitlines()
    unproved = tuple(f"{out[i].split(': Warning')[0].replace('[eva:alarm] ', '')}: {out[i + 1].strip()}"
                     for i in range(len(out) - 1) if out[i].startswith("[eva:alarm]"))
    alarms = int(found.group(1)) + sum(int(u) + int(v) for _, _, u, v in props)
    return ProofResult(prefix=gen.prefix, command=" ".join(cmd), frama_c_version=version, alarms=alarms,
                       proved=sum(int(v) for _, v, _, _ in props), seconds=round(seconds, 1), unproved=unproved)


def proof_record(gen: GeneratedObserver, result: ProofResult) -> str:
    """The text of ``<prefix>_proof.md``: what is proved, over which ranges, the command and its result."""
    rows = "\n".join(f"| `{n}` | {lo!r} | {hi!r} |" for n, (lo, hi) in gen.ranges.items())
    lines = [
        f"# Proof of no run-time errors: `{gen.prefix}`",
        "",
        f"Frama-C EVA ({result.frama_c_version}) on `{gen.prefix}.c` with the driver `{gen.prefix}_proof.c`, which",
        "calls every public function of the header with every real any finite value, the row counts any of",
        f"0..{_ROWS} and the optional pointers NULL or not; `-warn-special-float non-finite` makes every operation",
        "that may give an infinity or a NaN an alarm.  The step refuses, by comparisons only, every input",
        "outside these declared ranges (state: `STATE_RANGE`, also a new state outside them; signal: `SIGNAL_RANGE`;",
        "parameter: `BAD_PARAM`; `dt`: `BAD_DT`) before it computes anything:",
        "",
        "| name | min | max |",
        "| --- | ---: | ---: |",
        rows,
        "",
        f"Method {gen.method}, real {gen.real}"
        + ("" if gen.det_floor is None else f", `|det D(Z)| >= DET_FLOOR = {gen.det_floor!r}` checked before the "
           "division")
        + ("" if gen.max_substeps is None else f", at most `MAX_SUBSTEPS = {gen.max_substeps}` sub-steps, each "
           "sub-step's state checked against its range") + ".",
        "",
        "Command (in this directory):",
        "",
        "    " + result.command,
        "",
        f"Result: **{result.alarms} alarm(s)**, {result.proved} properties valid, {result.seconds:.1f} s wall.",
    ]
    if result.ok:
        lines += ["", "No alarm: no call of the public functions has a run-time error (division by zero, overflow "
                  "to an infinity, NaN, invalid memory access, uninitialised read, signed overflow, invalid "
                  "conversion) for any finite input, so every call that returns OK is covered."]
    else:
        lines += ["", "Not proved:", "", *(f"- `{u}`" for u in result.unproved)]
        gaps = divisor_gaps(gen)
        if gaps:
            lines += ["", "The declared ranges do not keep these divisors away from 0 (declare ranges that do):", "",
                      *(f"- `{g}`" for g in gaps)]
    return "\n".join(lines) + "\n"
