"""The generated C observer: its files and what they mean, and the proof driver that is one of them.

:class:`GeneratedObserver` is what :func:`switchobs.codegen.generate_observer` returns.  Its README
(:mod:`switchobs.codegen._readme`), its deviation record (:mod:`switchobs.codegen._misra`) and its EVA proof
driver ``<prefix>_proof.c`` (:func:`proof_driver`, run by :func:`switchobs.codegen.prove`) are made from it:
the modules that produce or consume it import this one, and it imports none of them but the MISRA record.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from fractions import Fraction
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from .._atomic import write_files
from .._json import fields_from_json
from ..exceptions import CodegenError, ModelError
from ..spec import Guard, StepStatus
from ._misra import misra_record

__all__ = ["GeneratedObserver", "proof_driver", "proof_command", "loop_unroll", "divisor_gaps", "EVA_PRECISION"]

#: ``-eva-precision`` of the proof (0-11): 3 keeps the refusal branches of the checks apart (at 1, 94 alarms on
#: abs-xbs3 radau3) within seconds per variant.
EVA_PRECISION = 3
#: Rows of the ``_run`` / ``_run_dt`` calls of the driver: their count is any of 0..ROWS.
PROOF_ROWS = 2


@dataclass(frozen=True)
class GeneratedObserver:
    """The generated C observer: the two C files, the README, and what they mean.

    Attributes
    ----------
    prefix : str
        C prefix of every public name (``switchobs_abs_xbs3``).
    real : {"double", "float"}
    method : {"rk4", "euler", "midpoint", "radau3"}
    kind : {"switched", "adaptive"}
    model_name : str
    state_names, signal_names, param_names : tuple of str
        In C order; states are in the model's own coordinates (adaptive:
        ``w``, then ``theta_hat``, then ``Upsilon`` row-major).
    default_params : tuple of float
        ``<prefix>_default_params``: the model values and designed gains used at generation.
    guards : tuple of Guard
        Conditions the step checks, in order, with their status codes.
    temporaries : int
        Scalar temporaries of the step kernel (casadi ``sz_w``).
    stack_reals : int
        Upper bound of the reals one ``_step`` call keeps on the stack
        (temporaries + the new state + ``s`` + one guard value).
    header, source, readme : str
        Text of ``<prefix>.h``, ``<prefix>.c`` and ``README.md`` (the fourth file, ``<prefix>_misra.md``, is
        :attr:`misra`, made from the two C files).
    casadi_version : str
    description : str
        What is observed (the model's description).
    equations : tuple of str
        The observer equations, as written in the files' comments.
    signal_roles : tuple of str
        What each signal is (measured output, external signal, input).
    references : mapping str -> str
    h_max : Fraction or None
        Certified bound on the step ``|s| dt`` in rescaled time (exact); None: no sub-stepping.
    h_max_c : float or None
        ``<PREFIX>_H_MAX``: ``h_max`` rounded down to ``real``.
    max_substeps : int or None
        ``<PREFIX>_MAX_SUBSTEPS``: most sub-steps of one step before ``SUBSTEP_LIMIT``.
    certificate : str or None
        The statement of the discrete certificate proved for this design and method (``--h-max auto``),
        recorded in the header and README; None: none was checked.
    original_names : tuple of str
        The original coordinates ``x = phi^{-1}(xhat)`` that ``<prefix>_original`` returns (the model's
        ``[original]`` table, written by ``switchobs transform``); empty: no such function.
    ranges : mapping str -> (float, float)
        Declared ranges ``[lo, hi]`` of states, signals, parameters and ``dt`` (the name ``dt``), as the C
        literals round them; the step refuses a value outside (``STATE_RANGE``, ``SIGNAL_RANGE``,
        ``BAD_PARAM``, ``BAD_DT``).  With a range for every input the files include the proof driver
        ``<prefix>_proof.c`` (:mod:`switchobs.codegen._proof`).
    det_floor : float or None
        ``<PREFIX>_DET_FLOOR`` of an implicit method (:meth:`switchobs.spec.StepMethod.det_floor`): the step
        refuses ``|det D(Z)|`` below it (``NONFINITE_RESULT``); None for an explicit method.
    step_function : casadi.Function
        One step *without* sub-stepping as a casadi Function ``(x, signals, params, dt) -> x_next``
        (not compared, not in JSON).
    """

    prefix: str
    real: str
    method: str
    kind: str
    model_name: str
    state_names: tuple[str, ...]
    signal_names: tuple[str, ...]
    param_names: tuple[str, ...]
    default_params: tuple[float, ...]
    guards: tuple[Guard, ...]
    temporaries: int
    stack_reals: int
    header: str
    source: str
    readme: str
    casadi_version: str
    description: str = ""
    equations: tuple[str, ...] = ()
    signal_roles: tuple[str, ...] = ()
    references: Mapping[str, str] = field(default_factory=dict)
    h_max: Fraction | None = None
    h_max_c: float | None = None
    max_substeps: int | None = None
    certificate: str | None = None
    original_names: tuple[str, ...] = ()
    ranges: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    det_floor: float | None = None
    step_function: ca.Function | None = field(default=None, repr=False, compare=False)

    @property
    def nx(self) -> int:
        return len(self.state_names)

    @property
    def ns(self) -> int:
        return len(self.signal_names)

    @property
    def np(self) -> int:
        return len(self.param_names)

    @cached_property
    def misra(self) -> str:
        """Text of ``<prefix>_misra.md``: the MISRA C:2012 deviation record of the two C files (made once: the
        scan of the C takes milliseconds, and every ``str`` of the observer lists its files)."""
        return misra_record(self.prefix, self.header, self.source)

    @property
    def unranged(self) -> tuple[str, ...]:
        """The inputs without a declared range (states, signals, parameters, ``dt``): the proof needs none."""
        names = (*self.state_names, *self.signal_names, *self.param_names, "dt")
        return tuple(n for n in names if n not in self.ranges)

    @property
    def files(self) -> dict[str, str]:
        """File name -> text (with the EVA proof driver ``<prefix>_proof.c`` when every input has a range)."""
        out = {f"{self.prefix}.h": self.header, f"{self.prefix}.c": self.source, "README.md": self.readme,
               f"{self.prefix}_misra.md": self.misra}
        if not self.unranged:
            out[f"{self.prefix}_proof.c"] = proof_driver(self)
        return out

    def param_index(self, name: str) -> int:
        """Index of a parameter in ``params`` (the value of ``<PREFIX>_P_<NAME>``)."""
        try:
            return self.param_names.index(name)
        except ValueError:
            raise ModelError(f"the generated observer has no parameter {name!r} "
                             f"(parameters: {list(self.param_names)})") from None

    def params_with(self, values: Mapping[str, float] | None = None) -> np.ndarray:
        """The default parameter vector with some entries replaced by name."""
        out = np.array(self.default_params, dtype=float)
        for name, value in (values or {}).items():
            out[self.param_index(name)] = float(value)
        return out

    def write(self, directory: str | Path, *, extra: Mapping[str, str] | None = None) -> tuple[Path, ...]:
        """Write :attr:`files` (``<prefix>.h``, ``<prefix>.c``, ``README.md``, ``<prefix>_misra.md``, with
        ranges for every input ``<prefix>_proof.c``) and ``extra`` (name -> text) into ``directory``
        (created if needed).

        All files appear together or none does (:func:`switchobs._atomic.write_files`).

        Raises
        ------
        OutputError
            If a file cannot be written (the message names it); nothing is left behind.
        """
        return write_files(directory, {**self.files, **(extra or {})}, what="the generated C into")

    def to_json(self, *, sources: bool = False) -> dict[str, Any]:
        """What the files hold and mean (and the files' text if ``sources``: what :meth:`from_json` reads)."""
        out = {
            "prefix": self.prefix, "real": self.real, "method": self.method, "kind": self.kind,
            "model": self.model_name, "nx": self.nx, "ns": self.ns, "np": self.np,
            "states": list(self.state_names), "signals": list(self.signal_names),
            "parameters": {n: v for n, v in zip(self.param_names, self.default_params)},
            "guards": [g.to_json() for g in self.guards],
            "status_codes": {s.name: int(s) for s in StepStatus},
            "temporaries": self.temporaries, "stack_reals": self.stack_reals,
            "h_max": None if self.h_max is None else str(self.h_max), "h_max_c": self.h_max_c,
            "max_substeps": self.max_substeps, "certificate": self.certificate,
            "files": sorted(self.files), "casadi_version": self.casadi_version,
            "references": dict(self.references), "original": list(self.original_names),
            "description": self.description, "equations": list(self.equations),
            "signal_roles": list(self.signal_roles),
            "ranges": {n: list(r) for n, r in self.ranges.items()}, "det_floor": self.det_floor,
        }
        if sources:
            out.update(header=self.header, source=self.source, readme=self.readme)
        return out

    @classmethod
    def from_json(cls, data: Any) -> GeneratedObserver:
        """The generated observer of ``to_json(sources=True)`` (without ``step_function``, the casadi function
        the C was generated from: the files do not need it).

        Raises
        ------
        ModelError
            No sources, a missing key or a malformed part; the message names it.
        """
        if not isinstance(data, Mapping) or "source" not in data:
            raise ModelError("a generated observer JSON needs its files; write it with to_json(sources=True)")
        try:
            flat = {**data, "model_name": data["model"], "state_names": data["states"],
                    "signal_names": data["signals"], "param_names": list(data["parameters"]),
                    "default_params": list(data["parameters"].values()), "original_names": data["original"],
                    "guards": [Guard.from_json(g) for g in data["guards"]],
                    "ranges": {n: (float(r[0]), float(r[1])) for n, r in data.get("ranges", {}).items()}}
        except (KeyError, TypeError, AttributeError) as exc:
            raise ModelError(f"not a generated observer JSON ({type(exc).__name__}: {exc})") from None
        return fields_from_json(cls, flat, error=ModelError, what="generated observer")

    def __str__(self) -> str:
        params = ", ".join(f"{n}={v:.6g}" for n, v in zip(self.param_names, self.default_params))
        lines = [
            f"generated C {self.kind} observer {self.prefix} for model {self.model_name!r} "
            f"({self.real}, {self.method}, casadi {self.casadi_version})",
            f"  files: {', '.join(sorted(self.files))}",
            f"  NX = {self.nx}: {', '.join(self.state_names)}",
            f"  NS = {self.ns}: {', '.join(self.signal_names)}",
            f"  NP = {self.np}: {params}",
            "  checks: " + ("; ".join(str(g) for g in self.guards) or "none beyond finiteness"),
            f"  stack: {self.temporaries} temporaries, at most {self.stack_reals} reals per step",
        ]
        if self.h_max is not None:
            lines.append(f"  sub-steps: |s|*dt <= H_MAX = {self.h_max_c!r} (certified h_max = {self.h_max}) per step, "
                         f"at most MAX_SUBSTEPS = {self.max_substeps}, else SUBSTEP_LIMIT = "
                         f"{int(StepStatus.SUBSTEP_LIMIT)}")
        if self.ranges:
            lines.append("  ranges: " + ", ".join(f"{n} in [{lo:.6g}, {hi:.6g}]" for n, (lo, hi) in self.ranges.items())
                         + ("" if not self.unranged else f"; none for {', '.join(self.unranged)} (no proof driver)"))
        if self.original_names:
            lines.append(f"  original coordinates: {', '.join(self.original_names)} = phi^-1(xhat) "
                         f"({self.prefix}_original)")
        return "\n".join(lines)


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
    return max(gen.nx, gen.np, PROOF_ROWS * gen.ns, PROOF_ROWS, len(gen.original_names))


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
        f" * 0..{PROOF_ROWS}, the optional pointers NULL or not.  The step refuses what lies outside the declared",
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
        f"#define ROWS {PROOF_ROWS}",
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
