"""The observer contract: one description of a switched (adaptive) observer for Python and C.

The observer right-hand side (seed 000 eq. (8)-(9), seed 004; with unknowns
seed 001 eq. (3.4)) is written, in the Python reference and in the generated
C alike, as ``s (A w) + c + Psi theta + g e`` with the affine split

    s d(y) + b(y) u = c(y, u) + Psi(y, u) theta,      c = (s d + b u) at theta = 0,
                                                       Psi = d(s d + b u)/dtheta,

``g = s K(s)`` and ``e = y - C w``.  :class:`ObserverSpec` holds the model,
the gains, the estimated parameters and this split, computed once and
checked once (the strict linearity test of seed 001 eq. (3.2)): the
observers (``switchobs.observers``) lower it to floats, the code generator
(``switchobs.codegen``) to casadi.  :class:`StepStatus` is the one set of
status codes of a step (the discretisations are in ``_methods``), and
:func:`domain_guards` says where the right-hand side is defined.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import IntEnum
from typing import Any

import sympy as sp

from .._json import fields_from_json
from ..exceptions import ModelError
from ..model import Model, parse_expression, rational_value, symbols_from_json, symbols_to_json

__all__ = ["SCALE", "STATUS_TEXT", "REFERENCE_STATUSES", "StepStatus", "Guard", "domain_guards",
           "ObserverSpec"]

#: The symbol standing for the time scaling ``s`` in :attr:`ObserverSpec.drift` and ``regressor``.
SCALE = sp.Symbol("s", real=True)


class StepStatus(IntEnum):
    """Status of one observer step; the state is left unchanged unless the status is ``OK``.

    The Python reference observers raise :class:`~switchobs.exceptions.ObserverInputError`
    with ``code`` 1-5; the generated ``<prefix>_step`` returns the same codes for
    the same cases, and 6 and 7, which exist only in C, where parameters are
    runtime inputs and pointers may be NULL.  Code 8 (``SUBSTEP_LIMIT``) exists
    only with a step bound ``H_MAX`` (C) or ``h_max`` (Python), in both.  Codes 9
    (``STATE_RANGE``) and 10 (``SIGNAL_RANGE``) exist only in C generated with
    declared ranges (``generate_observer(ranges=...)``, the domain over which
    the step is proved free of run-time errors); a declared range of ``dt`` or
    of a parameter extends ``BAD_DT`` and ``BAD_PARAM``.  The checks run in the
    order ``BAD_ARGUMENT``, ``BAD_DT``, ``NONFINITE_STATE``, ``STATE_RANGE``,
    ``NONFINITE_SIGNAL``, ``SIGNAL_RANGE``, ``BAD_PARAM``, ``UNDEFINED_TIME_SCALE``,
    ``SUBSTEP_LIMIT``, then the domain of ``d`` and ``b`` and the result
    (``NONFINITE_RESULT``, and ``STATE_RANGE`` for a new state outside its
    range); the first failing check is reported.
    """

    OK = 0
    BAD_DT = 1                # dt is not finite or dt <= 0
    NONFINITE_STATE = 2       # an entry of xhat is NaN or +-inf
    NONFINITE_SIGNAL = 3      # a signal (y, external, input) is NaN or +-inf
    UNDEFINED_TIME_SCALE = 4  # a signal declared positive/negative has the wrong sign, a denominator of s is 0,
                              # or s is not finite
    NONFINITE_RESULT = 5      # d(y), b(y) undefined (zero denominator, log of a non-positive number, ...)
                              # or the new state is not finite (overflow)
    BAD_PARAM = 6             # a parameter is not finite, violates its declared sign, or a parameter-only
                              # denominator is 0 (C only)
    BAD_ARGUMENT = 7          # xhat or signals is NULL, or n_steps < 0 (C only)
    SUBSTEP_LIMIT = 8         # |s|*dt exceeds MAX_SUBSTEPS*H_MAX (or is not finite): the step would need more
                              # sub-steps than allowed
    STATE_RANGE = 9           # an entry of xhat, or of the new state, lies outside its declared range (C only)
    SIGNAL_RANGE = 10         # a signal lies outside its declared range (C only)


#: One-line description of each status (also returned by ``<prefix>_status_message``).
STATUS_TEXT: dict[StepStatus, str] = {
    StepStatus.OK: "ok",
    StepStatus.BAD_DT: "dt is not finite or dt <= 0",
    StepStatus.NONFINITE_STATE: "an entry of xhat is not finite",
    StepStatus.NONFINITE_SIGNAL: "a signal is not finite",
    StepStatus.UNDEFINED_TIME_SCALE: "the time scaling s is undefined at these signals",
    StepStatus.NONFINITE_RESULT: "d(y) or b(y) is undefined, or the new state is not finite",
    StepStatus.BAD_PARAM: "a parameter is not finite or violates its declared sign",
    StepStatus.BAD_ARGUMENT: "a required pointer is NULL or n_steps < 0",
    StepStatus.SUBSTEP_LIMIT: "|s|*dt exceeds MAX_SUBSTEPS*H_MAX (more sub-steps than allowed)",
    StepStatus.STATE_RANGE: "an entry of xhat or of the new state is outside its declared range",
    StepStatus.SIGNAL_RANGE: "a signal is outside its declared range",
}

#: The statuses a Python reference step can end with (its parameters are fixed numbers, its inputs arrays).
REFERENCE_STATUSES: tuple[StepStatus, ...] = (*(s for s in StepStatus if s <= StepStatus.NONFINITE_RESULT),
                                               StepStatus.SUBSTEP_LIMIT)


# ----------------------------------------------------------------------------- guards
@dataclass(frozen=True)
class Guard:
    """A condition the right-hand side needs: ``expr`` is ``kind`` (positive, negative, nonzero, nonnegative).

    ``status`` is what the step returns when the condition fails,
    ``reason`` says where the condition comes from.
    """

    expr: sp.Expr
    kind: str
    status: StepStatus
    reason: str

    def to_json(self) -> dict[str, Any]:
        return {"expr": str(self.expr), "kind": self.kind, "status": int(self.status),
                "status_name": self.status.name, "reason": self.reason, "symbols": symbols_to_json(self.expr)}

    @classmethod
    def from_json(cls, data: Any) -> Guard:
        """The guard of :meth:`to_json` (``expr`` parsed over its ``symbols``).

        Raises
        ------
        ModelError
            A missing key, an expression that does not parse, or an unknown status.
        """
        if not isinstance(data, Mapping) or not isinstance(data.get("expr"), str):
            raise ModelError(f"a guard JSON needs its 'expr' text, got {data!r:.80}")
        names = symbols_from_json(data.get("symbols", {}), what="guard")
        return fields_from_json(cls, data, error=ModelError, what="guard",
                                expr=parse_expression(data["expr"], names, what="guard expression"))

    def __str__(self) -> str:
        sym = {"positive": "> 0", "negative": "< 0", "nonzero": "!= 0", "nonnegative": ">= 0"}[self.kind]
        return f"{self.expr} {sym}  ({self.reason}; else {self.status.name} = {int(self.status)})"


def _domain_conditions(expr: sp.Expr) -> list[tuple[sp.Expr, str, str]]:
    """(argument, kind, reason) of every partial operation in ``expr``, innermost first."""
    out: list[tuple[sp.Expr, str, str]] = []

    def walk(e: sp.Basic) -> None:
        for arg in e.args:
            walk(arg)
        if e.is_Pow and e.exp.is_Rational and not e.base.is_Number:
            if not e.exp.is_Integer:
                out.append((e.base, "positive" if e.exp < 0 else "nonnegative", f"base of {sp.sstr(e)}"))
            elif e.exp < 0:
                out.append((e.base, "nonzero", f"denominator of {sp.sstr(e)}"))
        elif e.is_Pow and not e.exp.is_Rational:
            out.append((e.base, "positive", f"base of the real power {sp.sstr(e)}"))
        elif isinstance(e, sp.log):
            out.append((e.args[0], "positive", f"argument of {sp.sstr(e)}"))

    walk(sp.sympify(expr))
    return out


def domain_guards(model: Model) -> tuple[Guard, ...]:
    """Where the model's right-hand side is defined, as guards in the order a step checks them.

    Parameters first (their declared signs, then parameter-only conditions:
    ``BAD_PARAM``), then the external signals declared positive/negative and
    the conditions of ``time_scale`` (``UNDEFINED_TIME_SCALE``), then the
    conditions of ``d`` and ``b`` (``NONFINITE_RESULT``, as a domain error in
    the Python reference).  A condition already implied by an earlier one is dropped.
    """
    params = set(model.parameter_symbols)
    guards: list[Guard] = []

    def add(expr: sp.Expr, kind: str, status: StepStatus, reason: str) -> None:
        for g in guards:
            if sp.simplify(g.expr - expr) == 0 and (g.kind == kind or g.kind in ("positive", "negative")
                                                    and kind in ("nonzero", "nonnegative")):
                return
        guards.append(Guard(sp.sympify(expr), kind, status, reason))

    def declared_sign(name: str, status: StepStatus, label: str) -> None:
        sym = model.symbols[name]
        for kind in ("positive", "negative"):
            if getattr(sym, f"is_{kind}"):
                add(sym, kind, status, f"{label} {name} is declared {kind}")

    for name in model.parameters:
        declared_sign(name, StepStatus.BAD_PARAM, "parameter")
    everything = [model.time_scale, *model.A, *model.C, *model.d, *model.b]
    for expr in everything:
        for arg, kind, reason in _domain_conditions(expr):
            if arg.free_symbols <= params:
                add(arg, kind, StepStatus.BAD_PARAM, reason)
    for name in model.external:
        declared_sign(name, StepStatus.UNDEFINED_TIME_SCALE, "signal")
    for arg, kind, reason in _domain_conditions(model.time_scale):
        add(arg, kind, StepStatus.UNDEFINED_TIME_SCALE, f"{reason} in the time scaling s = {model.time_scale}")
    for expr in [*model.d, *model.b]:
        for arg, kind, reason in _domain_conditions(expr):
            add(arg, kind, StepStatus.NONFINITE_RESULT, reason)
    return tuple(guards)


# ----------------------------------------------------------------------------- the spec
def _nonlinear_term(parts: list[tuple[str, sp.Expr]], theta: tuple[sp.Symbol, ...]
                    ) -> tuple[str, tuple[sp.Symbol, ...]] | None:
    """The first term of the ``(name, expression)`` parts with a nonzero second derivative in ``theta``.

    ``s d + b u`` is linear in ``theta`` iff every entry of ``d`` and ``b`` is
    (``s`` and ``u`` are independent of it), so the entries are tested one by one.
    """
    for a, b in itertools.combinations_with_replacement(theta, 2):
        for where, expr in parts:
            if sp.diff(expr, a, b) == 0:
                continue
            syms = (a,) if a == b else (a, b)
            terms = [term for term in sp.Add.make_args(sp.expand(expr)) if sp.diff(term, a, b) != 0]
            return f"term {sp.sstr(terms[0] if terms else expr)} of {where}", syms
    return None


@dataclass(frozen=True)
class ObserverSpec:
    """One switched (adaptive) observer of a model, as both the Python reference and the C consume it.

    Parameters
    ----------
    model : Model
        The model with its parameters as symbols (values are in ``values``).
    K_plus, K_minus : tuple of float
        The gains (length ``n``), already validated numbers.
    values : mapping name -> sympy.Rational
        Values of the known parameters used by this observer (the Python
        reference substitutes them; the C uses them as runtime defaults).
    unknown : tuple of str
        Parameters estimated online (seed 001 eq. (3.4)); empty for the switched observer.
    Gamma : tuple of tuples of float
        The ``p x p`` adaptation gain, already validated (empty without unknowns).

    Attributes
    ----------
    drift : tuple of sympy.Expr
        ``c_i = (s d_i + (b u)_i)`` at ``theta = 0``, in the model's symbols and :data:`SCALE`.
    regressor : tuple of tuples of sympy.Expr
        ``Psi_ij = dc_i/dtheta_j`` (``n x p``).  A structurally zero entry is ``0``.
    signal_signs : tuple of int
        Per signal (``Model.signals``): ``+1`` declared positive, ``-1`` negative, ``0`` free.

    Raises
    ------
    ModelError
        An unknown is not a parameter, appears in ``A``, ``C`` or ``s``, or
        ``s d + b u`` is not linear in the unknowns (the message names the term).
    """

    model: Model
    K_plus: tuple[float, ...]
    K_minus: tuple[float, ...]
    values: Mapping[str, sp.Rational] = field(default_factory=dict)
    unknown: tuple[str, ...] = ()
    Gamma: tuple[tuple[float, ...], ...] = ()
    drift: tuple[sp.Expr, ...] = field(init=False, repr=False, compare=False)
    regressor: tuple[tuple[sp.Expr, ...], ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        model = self.model
        for name in self.unknown:
            if name not in model.parameters:
                raise ModelError(f"model {model.name!r} has no parameter {name!r} to estimate "
                                 f"(parameters: {list(model.parameters)})")
        theta = tuple(model.symbols[u] for u in self.unknown)
        for what, expr in (("A", model.A), ("C", model.C), ("time_scale", model.time_scale)):
            hit = sorted(str(s) for s in set(theta) & expr.free_symbols)
            if hit:
                raise ModelError(f"the estimated parameter(s) {hit} appear in {what} of model {model.name!r}; "
                                 "the adaptive observer needs them only in d(y) and b(y)")
        inputs = [model.symbols[u] for u in model.inputs]
        rows = [SCALE * model.d[i] + sum((model.b[i, j] * inputs[j] for j in range(len(inputs))), sp.Integer(0))
                for i in range(model.n)]
        parts = [(f"d[{i + 1}]", model.d[i]) for i in range(model.n)]
        parts += [(f"b[{i + 1}][{j + 1}]", model.b[i, j]) for i in range(model.n) for j in range(len(inputs))]
        bad = _nonlinear_term(parts, theta)
        if bad is not None:
            where, syms = bad
            raise ModelError(f"s d(y) + b(y) u of model {model.name!r} is not linear in "
                             f"{' and '.join(map(str, syms))} ({where}); the adaptive observer needs d(y) and "
                             "b(y) affine in the estimated parameters (seed 001 eq. (3.2))")
        zero = {t: 0 for t in theta}
        object.__setattr__(self, "drift", tuple(_or_zero(row.xreplace(zero)) for row in rows))
        object.__setattr__(self, "regressor", tuple(tuple(_or_zero(sp.diff(row, t)) for t in theta) for row in rows))

    # ------------------------------------------------------------------ layout
    @property
    def n(self) -> int:
        return self.model.n

    @property
    def p(self) -> int:
        return len(self.unknown)

    @property
    def size(self) -> int:
        """Length of the observer state ``(w, theta_hat, Upsilon row-major)``."""
        return self.n + self.p + self.n * self.p

    @property
    def state_names(self) -> tuple[str, ...]:
        """The state layout: the model's states, the unknowns, ``Upsilon_<state>_<unknown>``."""
        states = self.model.states
        return (*states, *self.unknown, *[f"Upsilon_{z}_{u}" for z in states for u in self.unknown])

    @property
    def signal_names(self) -> tuple[str, ...]:
        """``y``, the external signals, the inputs (``Model.signals``)."""
        return tuple(self.model.signals)

    @property
    def signal_signs(self) -> tuple[int, ...]:
        syms = [self.model.symbols[name] for name in self.model.signals]
        return tuple(1 if s.is_positive else -1 if s.is_negative else 0 for s in syms)

    @property
    def known_parameters(self) -> tuple[str, ...]:
        """The parameters that are not estimated (runtime parameters of the C observer)."""
        return tuple(q for q in self.model.parameters if q not in self.unknown)

    @property
    def known_model(self) -> Model:
        """The model with the unknowns removed from its parameters (they are states of the observer)."""
        if not self.unknown:
            return self.model
        m, known = self.model, self.known_parameters
        return Model(name=m.name, states=m.states, output=m.output, A=m.A, C=m.C, d=m.d, b=m.b,
                     time_scale=m.time_scale, parameters=known, external=m.external, inputs=m.inputs,
                     values={k: v for k, v in m.values.items() if k in known}, symbols=m.symbols,
                     description=m.description, references=m.references)

    def guards(self) -> tuple[Guard, ...]:
        """:func:`domain_guards` of the known parameters and the signals."""
        return domain_guards(self.known_model)

    def to_json(self) -> dict[str, Any]:
        return {"model": self.model.name, "K_plus": list(self.K_plus), "K_minus": list(self.K_minus),
                "values": {k: str(v) for k, v in self.values.items()}, "unknown": list(self.unknown),
                "Gamma": [list(r) for r in self.Gamma], "drift": [str(c) for c in self.drift],
                "regressor": [[str(q) for q in row] for row in self.regressor],
                "state_names": list(self.state_names), "signal_names": list(self.signal_names),
                "model_definition": self.model.to_json()}

    @classmethod
    def from_json(cls, data: Any) -> ObserverSpec:
        """The spec of :meth:`to_json`: the model from ``model_definition``, the values exact (``drift`` and
        ``regressor`` are derived again).

        Raises
        ------
        ModelError
            No ``model_definition``, a malformed value or key, or a spec the model rejects.
        """
        if not isinstance(data, Mapping) or not isinstance(data.get("values"), Mapping) \
                or "model_definition" not in data:
            raise ModelError(f"an observer spec JSON needs 'values' and 'model_definition', got {data!r:.80}")
        return fields_from_json(cls, data, error=ModelError, what="observer spec",
                                model=Model.from_json(data["model_definition"]),
                                values={str(k): rational_value(v, what=f"value of {k}")
                                        for k, v in data["values"].items()})

    def __str__(self) -> str:
        lines = [f"observer spec of model {self.model.name!r}: state {', '.join(self.state_names)}; "
                 f"signals {', '.join(self.signal_names)}",
                 f"  K_plus = {list(self.K_plus)}, K_minus = {list(self.K_minus)}",
                 "  c = s d + b u at theta = 0: " + ", ".join(map(str, self.drift))]
        if self.unknown:
            lines += [f"  Psi = dc/d({', '.join(self.unknown)}): {[[str(q) for q in r] for r in self.regressor]}",
                      f"  Gamma = {[list(r) for r in self.Gamma]}"]
        return "\n".join(lines)


def _or_zero(expr: sp.Expr) -> sp.Expr:
    """``0`` for an expression that expands to zero, so that no consumer emits a term for it."""
    return sp.Integer(0) if sp.expand(expr) == 0 else expr
