"""Check and search of the normal form dz/dt = s(y)(A z + d(y)) + b(y) u, y = C z.

The class is the one of seed 004 (Part III, "Observer normal form"): a change
of coordinates ``z = phi(x)`` and an output-dependent time scale ``s(y)`` turn
``dx/dt = f(x) + g(x) u, y = h(x)`` into a system that is linear up to output
injection in the time ``d tau = s(y) dt``.  Conditions: Krener & Respondek
(1985) for ``s = 1``, Respondek, Pogromsky & Nijmeijer (2004) for ``s(y)``.
Every verdict here is exact (sympy, with the sign assumptions of the file) and
every positive one is re-checked by substituting the coordinates back.
"""

from __future__ import annotations

import json
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import sympy as sp

from .._papers import cite
from .._progress import progress
from ..exceptions import ExpressionError, TransformError
from ..model import Model
from ._lie import as_output_function, bracket, integrate_exact, kappa, lie, simp
from ._system import System

__all__ = ["Step", "Transformation", "check_transformation", "search_transformation"]


@dataclass(frozen=True)
class Step:
    """One step of the derivation: a title and named expressions (``label``, value)."""

    title: str
    items: tuple[tuple[str, Any], ...]
    note: str = ""


@dataclass(frozen=True)
class Transformation:
    """The verdict on one system: the normal form, or the first condition that fails.

    Attributes
    ----------
    system : System
    mode : str
        ``"check"`` (candidate ``s`` and ``phi`` given) or ``"search"``.
    exists : bool
    failing : str or None
        The failing condition and where it fails (``exists`` False).
    steps : tuple of Step
        The derivation, in order (printed by ``str``, written by :meth:`to_markdown`).
    time_scale : sympy.Expr or None
        ``s(y)`` (with external signals, ``s(y, w)``).
    phi : tuple of sympy.Expr or None
        ``z = phi(x)``, ``z1 = h(x)``.
    jacobian : sympy.Expr or None
        ``det dphi/dx``: ``phi`` is a local diffeomorphism where it is non-zero.
    s_zeros : tuple of sympy.Expr
        The outputs ``y`` where ``s`` vanishes (the singular set of seed 004).
    phi_inverse : tuple of sympy.Expr or None
        ``x = phi^{-1}(z)`` in the symbols ``z1..zn`` when sympy finds a unique closed form (checked:
        ``phi(phi^{-1}(z)) = z``), else None.
    model : Model or None
        The normal form as a switchobs model (A, C, d, b, s), ready for ``design``.
    """

    system: System
    mode: str
    exists: bool
    failing: str | None
    steps: tuple[Step, ...]
    time_scale: sp.Expr | None = None
    phi: tuple[sp.Expr, ...] | None = None
    jacobian: sp.Expr | None = None
    s_zeros: tuple[sp.Expr, ...] = ()
    model: Model | None = None
    phi_inverse: tuple[sp.Expr, ...] | None = None

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"system": self.system.name, "mode": self.mode, "exists": self.exists,
                               "failing": self.failing}
        if self.exists:
            assert self.model is not None
            out.update({"time_scale": str(self.time_scale), "phi": [str(e) for e in self.phi or ()],
                        "jacobian": str(self.jacobian), "s_zeros": [str(e) for e in self.s_zeros],
                        "phi_inverse": None if self.phi_inverse is None else [str(e) for e in self.phi_inverse],
                        "model": self.model.to_dict()})
        out["steps"] = [{"title": s.title, "items": {label: _text(v) for label, v in s.items}, "note": s.note}
                        for s in self.steps]
        out["system_definition"] = self.system.to_dict()
        return out

    @classmethod
    def from_json(cls, data: Any) -> Transformation:
        """The transformation of :meth:`to_json`, derived again from ``system_definition`` (in check mode, with
        the candidate of its "Candidate" step) and compared with the stored JSON.

        Raises
        ------
        TransformError
            No ``system_definition``, an unknown mode, or a derivation that differs from the stored one (a
            file edited by hand, or written by another version).
        ModelError
            A system definition that does not read.
        """
        if not isinstance(data, Mapping) or not isinstance(data.get("system_definition"), Mapping):
            raise TransformError("a transformation JSON needs its 'system_definition' (Transformation.to_json "
                                 "writes it)")
        system = System.from_dict(data["system_definition"], source="transformation JSON")
        if data.get("mode") == "search":
            again = search_transformation(system)
        elif data.get("mode") == "check":
            candidate = next((list(s.get("items", {}).values()) for s in data.get("steps", [])
                              if s.get("title") == "Candidate"), None)
            if not candidate:
                raise TransformError("a check-mode transformation JSON needs its 'Candidate' step")
            again = check_transformation(system, candidate[0], candidate[1:])
        else:
            raise TransformError(f"a transformation JSON needs mode 'check' or 'search', got {data.get('mode')!r}")
        if json.loads(json.dumps(again.to_json())) != json.loads(json.dumps(dict(data))):
            raise TransformError(f"the derivation of {system.name!r} differs from the stored one: the JSON was "
                                 "edited or written by another version; derive it again")
        return again

    def __str__(self) -> str:
        lines = [f"switchobs transform: {self.system.name} ({self.mode} mode)"]
        for i, step in enumerate(self.steps, 1):
            lines.append(f"{i}. {step.title}")
            if step.note:
                lines.append(f"   {step.note}")
            lines += [f"   {label}{_separator(label)}{_text(value)}" for label, value in step.items]
        lines.append("verdict: " + ("the normal form exists (checked by substitution)" if self.exists
                                    else f"no transformation: {self.failing}"))
        return cite("\n".join(lines))

    def to_markdown(self) -> str:
        """The derivation as a markdown page with LaTeX (``switchobs transform --theory``)."""
        s = self.system
        lines = [f"# Normal form of `{s.name}`", "",
                 "<!-- generated by `switchobs transform --theory`; do not edit by hand -->", ""]
        if s.description:
            lines += [s.description, ""]
        lines += [f"Mode: {self.mode}. Target: $\\dot z = s(y)\\,(A z + d(y)) + b(y)\\,u,\\ y = C z$ "
                  "(seed 004, Part III).", ""]
        for i, step in enumerate(self.steps, 1):
            lines += [f"## {i}. {step.title}", ""]
            if step.note:
                lines += [step.note, ""]
            for label, value in step.items:
                if isinstance(value, (sp.Basic, sp.MatrixBase)):
                    lines.append(f"- ${_latex_label(label)} = {sp.latex(value)}$")
                else:
                    lines.append(f"- {label}{_separator(label)}`{value}`")
            lines.append("")
        lines += ["## Verdict", ""]
        lines.append("The normal form exists; substituting $z = \\varphi(x)$ back gives "
                     "$\\tfrac{\\partial\\varphi}{\\partial x}(f + g u) = s(y)(A\\varphi + d(y)) + b(y) u$ exactly."
                     if self.exists else f"No transformation exists: {self.failing}.")
        return cite("\n".join(lines) + "\n")

    def model_toml(self) -> str:
        """The normal form as a model file (``switchobs design MODEL.toml`` reads it)."""
        if self.model is None:
            raise TransformError(f"{self.system.name}: no transformation exists ({self.failing}); no model to write")
        data = self.model.to_dict()
        data["description"] = self.model.description
        positive = [k for k in self.system.positive if k in self.model.parameters or k in self.model.external]
        negative = [k for k in self.system.negative if k in self.model.parameters or k in self.model.external]
        lines = [f"# Generated by `switchobs transform` from the system {self.system.name!r}.",
                 "# z = phi(x): " + ", ".join(f"{z} = {e}" for z, e in zip(self.model.states, self.phi or ())),
                 f"# det dphi/dx = {self.jacobian}"]
        if self.phi_inverse is not None:
            lines.append("# x = phi^-1(z): " + ", ".join(f"{x} = {e}" for x, e in zip(self.system.states,
                                                                                     self.phi_inverse)))
        for key in ("name", "description", "states", "output", "A", "C", "d", "b", "time_scale", "parameters",
                    "external", "inputs"):
            lines.append(f"{key} = {_toml_value(data[key])}")
        lines += [f"positive = {_toml_value(positive)}", f"negative = {_toml_value(negative)}"]
        if "original" in data:
            lines += ["", "[original]  # x = phi^-1(z): the generated C reads the estimate back in these coordinates"]
            lines += [f"{k} = {_toml_value(v)}" for k, v in data["original"].items()]
        if data["values"]:
            lines += ["", "[values]"] + [f"{k} = {_toml_value(v)}" for k, v in data["values"].items()]
        if self.system.references:
            lines += ["", "[references]"] + [f"{k} = {_toml_value(v)}" for k, v in self.system.references.items()]
        return "\n".join(lines) + "\n"


def _text(value: Any) -> str:
    """A vector as ``(a, b)``, a matrix as ``[[a, b], [c, d]]``, anything else as sympy prints it."""
    if isinstance(value, sp.MatrixBase):
        if value.rows == 1 or value.cols == 1:
            return "(" + ", ".join(str(e) for e in value) + ")"
        return "[" + ", ".join("[" + ", ".join(str(e) for e in value.row(i)) + "]" for i in range(value.rows)) + "]"
    return str(value)


def _toml_value(value: Any) -> str:
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    return json.dumps(str(value))  # a JSON string is a TOML basic string


def _separator(label: str) -> str:
    return " " if label.endswith(":") else " = "


_LATEX_WORDS = {"tau~": r"\tilde\tau", "tau": r"\tau", "phi": r"\varphi", "kappa": r"\kappa", "ad": r"\mathrm{ad}",
                "det": r"\det", "dphi": r"d\varphi"}


def _latex_label(label: str) -> str:
    """``[ad^0 tau~, g_1] along tau`` -> ``[\\mathrm{ad}^0 \\tilde\\tau, g_1] \\text{ along } \\tau``."""
    def word(m: re.Match) -> str:
        token = m.group(0)
        if token in _LATEX_WORDS:
            return _LATEX_WORDS[token]
        return rf"\text{{ {token} }}" if len(token) > 2 else token
    return re.sub(r"[A-Za-z]+~?", word, label)


class _Fails(Exception):
    """Internal: the first condition that fails, with where it fails."""


class _Derivation:
    """The shared state of one check or search: the system's symbols and the steps so far."""

    def __init__(self, system: System, mode: str):
        self.system = system
        self.mode = mode
        self.xs = list(system.state_symbols)
        self.ws = set(system.external_symbols)
        self.y = system.output_symbol
        self.steps: list[Step] = []

    def step(self, title: str, items: Sequence[tuple[str, Any]], note: str = "") -> None:
        self.steps.append(Step(title, tuple(items), note))

    def fail(self, condition: str) -> Transformation:
        return Transformation(self.system, self.mode, False, condition, tuple(self.steps))

    def in_output(self, q: sp.Expr, what: str, *, external_ok: bool = False) -> sp.Expr:
        value = as_output_function(q, self.system.h, self.y, self.xs)
        if value is None:
            raise _Fails(f"{what} = {q} is not a function of the output y = {self.system.h} alone")
        if not external_ok and value.free_symbols & self.ws:
            raise _Fails(f"{what} = {value} depends on the external signal(s) "
                         f"{sorted(map(str, value.free_symbols & self.ws))}; the model class allows them in s only")
        return value

    # --------------------------------------------------------------- normal form
    def normal_form(self, phi: Sequence[sp.Expr], s_y: sp.Expr) -> Transformation:
        """Extract A, C, d(y), b(y) from z = phi(x) and s(y), and verify the form by substitution."""
        system, xs, y = self.system, self.xs, self.y
        n = system.n
        phi = [simp(e) for e in phi]
        if simp(phi[0] - system.h) != 0:
            raise _Fails(f"the first coordinate z1 = {phi[0]} is not the output y = {system.h} (C = (1, 0, ..., 0))")
        progress(f"transform: Jacobian of phi (n = {n})")
        J = sp.Matrix([[sp.diff(e, x) for x in xs] for e in phi])
        det = sp.factor(simp(J.det()))
        if det == 0:
            raise _Fails("phi is not a diffeomorphism: det dphi/dx is identically zero")
        frame = J.inv().applyfunc(simp)  # column j is d/dz_j in the x-coordinates
        s_x = s_y.subs(y, system.h)
        scaled = (J * system.f).applyfunc(lambda e: simp(e / s_x))
        inputs = (J * system.g).applyfunc(simp)
        progress(f"transform: A, d(y), b(y) (n = {n})")
        A = sp.zeros(n, n)
        d = sp.zeros(n, 1)
        for k in range(n):
            for j in range(1, n):
                entry = simp(lie(scaled[k], frame[:, j], xs))
                if entry.free_symbols & (set(xs) | self.ws):
                    raise _Fails(f"d(f_{k + 1}/s)/dz_{j + 1} = {entry} is not constant: the time-scaled field is "
                                 f"not affine in z_{j + 1}")
                A[k, j] = entry
            rest = simp(scaled[k] - sum((A[k, j] * phi[j] for j in range(1, n)), sp.Integer(0)))
            d[k] = self.in_output(rest, f"d_{k + 1}")
        b = sp.zeros(n, inputs.shape[1])
        for k in range(n):
            for i in range(inputs.shape[1]):
                b[k, i] = self.in_output(inputs[k, i], f"b_{k + 1}" + (f",{i + 1}" if inputs.shape[1] > 1 else ""))
        taken = set(system.symbols)
        letter = next(c for c in ("z", "w", "zeta", "xi") if not {f"{c}{k + 1}" for k in range(n)} & taken)
        zs = [sp.Symbol(f"{letter}{k + 1}", real=True) for k in range(n)]
        self.step("Normal form", [("A", sp.ImmutableMatrix(A)), ("C", sp.ImmutableMatrix([[1] + [0] * (n - 1)])),
                                  ("d(y)", sp.ImmutableMatrix(d)), ("b(y)", sp.ImmutableMatrix(b))],
                  "A z collects the terms linear in z2..zn; the first column of A is zero (terms in y alone are "
                  "in d(y)).")
        u = sp.Matrix([sp.Symbol(f"_u{i}") for i in range(system.g.shape[1])])
        left, right = J * system.f, s_x * (A * sp.Matrix(phi) + d.subs(y, system.h))
        if u:
            left, right = left + J * system.g * u, right + b.subs(y, system.h) * u
        residual = (left - right).applyfunc(simp)
        if residual != sp.zeros(n, 1):  # only a bug in the extraction could get here
            raise _Fails(f"substituting back leaves {list(residual)}")
        zeros = _solve(s_y, y) if s_y.has(y) else ()
        self.step("Diffeomorphism and singular set",
                  [("det dphi/dx", det),
                   ("s(y) = 0 at:", "not solved in closed form" if zeros is None else
                    ", ".join(f"{y} = {e}" for e in zeros) if zeros else "no y")],
                  "phi is a local diffeomorphism where det dphi/dx != 0; the observer is singular where s "
                  "vanishes (seed 004).")
        self.step("Substitution check", [("dphi/dx (f + g u) - (s(y)(A phi + d(y)) + b(y) u)",
                                          sp.ImmutableMatrix(residual))])
        inverse = self.inverse(phi, zs)
        self.step("Inverse coordinates", [(str(x), e) for x, e in zip(xs, inverse)] if inverse else
                  [("x = phi^-1(z):", "no unique closed form found")])
        model = self.model(A, d, b, s_y, zs, inverse)
        return Transformation(system, self.mode, True, None, tuple(self.steps), s_y, tuple(phi), det,
                              tuple(zeros or ()), model, inverse)

    def inverse(self, phi: Sequence[sp.Expr], zs: Sequence[sp.Symbol]) -> tuple[sp.Expr, ...] | None:
        """``x = phi^{-1}(z)`` when sympy solves ``phi(x) = z`` with a single solution, checked by substitution."""
        progress(f"transform: inverse coordinates (n = {self.system.n})")
        solutions = _solve([p - z for p, z in zip(phi, zs)], self.xs)
        if solutions is None or len(solutions) != 1 or set(solutions[0]) != set(self.xs):
            return None
        inverse = tuple(simp(solutions[0][x]) for x in self.xs)
        back = {x: e for x, e in zip(self.xs, inverse)}
        if any(simp(p.subs(back) - z) != 0 for p, z in zip(phi, zs)):
            return None
        return inverse

    def model(self, A: sp.Matrix, d: sp.Matrix, b: sp.Matrix, s_y: sp.Expr, zs: Sequence[sp.Symbol],
              inverse: tuple[sp.Expr, ...] | None) -> Model:
        """The model; with ``[original]`` (and the parameters phi^-1 uses) when a model file can hold phi^-1
        (only its safe functions), so that the generated C reads the estimate back in x."""
        if inverse is not None:
            try:
                return self._model(A, d, b, s_y, zs, inverse)
            except ExpressionError:
                pass
        return self._model(A, d, b, s_y, zs, None)

    def _model(self, A: sp.Matrix, d: sp.Matrix, b: sp.Matrix, s_y: sp.Expr, zs: Sequence[sp.Symbol],
               inverse: tuple[sp.Expr, ...] | None) -> Model:
        system = self.system
        used = set().union(*(e.free_symbols for e in (*A, *d, *b, s_y, *(inverse or ()))))
        parameters = [p for p in system.parameters if system.symbols[p] in used]
        signed = set(parameters) | set(system.external)
        data = {
            "name": system.name,
            "description": f"normal form of {system.name} (switchobs transform, {self.mode} mode)",
            "states": [str(z) for z in zs], "output": system.output,
            "A": [[str(e) for e in A.row(i)] for i in range(A.rows)], "C": ["1"] + ["0"] * (A.rows - 1),
            "d": [str(e) for e in d],
            "b": ([str(e) for e in b] if b.shape[1] == 1 else [[str(e) for e in b.row(i)] for i in range(b.rows)]),
            "time_scale": str(s_y), "parameters": parameters, "external": list(system.external),
            "inputs": list(system.inputs),
            "positive": [k for k in system.positive if k in signed],
            "negative": [k for k in system.negative if k in signed],
            "values": {k: str(v) for k, v in system.values.items() if k in parameters},
            "references": dict(system.references),
        }
        if inverse is not None:
            data["original"] = {"states": list(system.states), "inverse": [str(e) for e in inverse]}
        return Model.from_dict(data, source=f"normal form of {system.name}")


def check_transformation(system: System, time_scale: str | sp.Expr, phi: Sequence[str | sp.Expr]) -> Transformation:
    """Check mode: does ``z = phi(x)`` with the time scale ``s(y)`` give the normal form?

    Parameters
    ----------
    system : System
    time_scale : str or sympy.Expr
        ``s`` in the output name, the parameters and the external signals (``"y/vx"``).
    phi : sequence of str or sympy.Expr
        ``z1, ..., zn`` in the states and parameters; ``z1`` must be the output.

    Returns
    -------
    Transformation
        With ``exists`` False and the failing condition when the candidate does not work.

    Raises
    ------
    TransformError, ExpressionError
        For a candidate of the wrong length or with unknown names.
    """
    der = _Derivation(system, "check")
    if len(phi) != system.n:
        raise TransformError(f"phi has {len(phi)} component(s) but the system has {system.n} states "
                             f"({', '.join(system.states)}); give one expression per state")
    s_y = time_scale if isinstance(time_scale, sp.Basic) else system.parse(time_scale, what="s", output=True)
    if s_y == 0:
        raise TransformError("the time scale s is identically zero; the normal form needs s != 0 somewhere")
    phi_x = [e if isinstance(e, sp.Basic) else system.parse(e, what=f"phi[{k + 1}]") for k, e in enumerate(phi)]
    der.step("System", _system_items(system))
    der.step("Candidate", [("s(y)", s_y)] + [(f"z{k + 1}", e) for k, e in enumerate(phi_x)])
    try:
        return der.normal_form(phi_x, s_y)
    except _Fails as exc:
        return der.fail(str(exc))


def search_transformation(system: System) -> Transformation:
    """Search mode: find ``s(y)`` and ``z = phi(x)`` from ``f``, ``g``, ``h`` alone, or name the failing condition.

    The steps (seed 004, Part III; Respondek, Pogromsky & Nijmeijer 2004):
    observability map ``O = (h, L_f h, ..., L_f^{n-1} h)``; the vector field
    ``tau`` with ``L_tau L_f^k h = delta_{k,n-1}``; the frame ``ad_f^k tau``;
    the time-scale equation ``[ad^{n-2} tau, ad^{n-1} tau] = kappa_n (s'/s)(y)
    ad^{n-2} tau + (lower terms)``, solved by ``s = exp(int s'/s dy)``; for
    ``f~ = f/s(h)`` and ``tau~ = s^{n-1} tau`` the commutativity
    ``[ad^i tau~, ad^j tau~] = 0`` and ``[ad^j tau~, g] = 0`` (``j <= n-2``, so
    that ``b`` depends on ``y`` only); ``phi`` integrates the coframe dual to
    ``d/dz_k = (-1)^{n-k} ad^{n-k}_{f~} tau~``.  External signals are
    constants in the computation; the coordinates must not depend on them.
    """
    der = _Derivation(system, "search")
    xs, y, n = der.xs, der.y, system.n
    f, g, h = sp.Matrix(system.f), sp.Matrix(system.g), system.h
    der.step("System", _system_items(system))
    try:
        progress(f"transform: Lie derivatives and observability map (n = {n})")
        lies = [h]
        for _ in range(n):
            lies.append(simp(lie(lies[-1], f, xs)))
        dO = sp.Matrix([[sp.diff(e, x) for x in xs] for e in lies[:n]])
        det_o = sp.factor(simp(dO.det()))
        der.step("Lie derivatives", [(f"L_f^{k} h", e) for k, e in enumerate(lies)] + [("det dO/dx", det_o)],
                 "O = (h, L_f h, ..., L_f^{n-1} h) is the observability map; the rank condition is det dO/dx != 0.")
        if det_o == 0:
            raise _Fails("the observability rank condition fails: det dO/dx = 0 identically (the output does not "
                         "determine the state)")
        tau = dO.LUsolve(sp.Matrix([0] * (n - 1) + [1])).applyfunc(simp)
        progress(f"transform: frame ad_f^k tau (n = {n})")
        frame = [tau]
        for _ in range(1, n):
            frame.append(bracket(f, frame[-1], xs))
        der.step("Vector field tau and its frame", [("tau", tau.T)] + [(f"ad_f^{k} tau", v.T) for k, v in
                                                                       enumerate(frame) if k],
                 "tau solves L_tau L_f^k h = delta_{k,n-1} (k = 0..n-1).")
        progress(f"transform: time-scale equation (n = {n})")
        top = bracket(frame[n - 2], frame[n - 1], xs)
        coefficient = simp(sp.Matrix.hstack(*frame).LUsolve(top)[n - 2])
        ratio = simp(coefficient / kappa(n))
        equation = [(f"[ad^{n - 2} tau, ad^{n - 1} tau] along ad^{n - 2} tau", coefficient), ("kappa_n", kappa(n)),
                    ("s'/s = coefficient / kappa_n", ratio)]
        note = (f"In the normal form this coefficient is kappa_n s'(y)/s(y) (kappa_{n} = {kappa(n)}), so it must be a "
                "function of y alone; s is fixed up to a constant factor"
                + (", chosen to take the external signals out of f/s." if der.ws else "."))
        try:
            log_derivative = der.in_output(ratio, "s'(y)/s(y)", external_ok=True)
        except _Fails:
            der.step("Time scale", equation, note)
            raise
        s0 = sp.exp(sp.integrate(log_derivative, y)) if log_derivative != 0 else sp.Integer(1)
        if s0.has(sp.Integral):
            der.step("Time scale", [*equation, ("s'(y)/s(y)", log_derivative)], note)
            raise _Fails(f"s'(y)/s(y) = {log_derivative} has no closed-form integral (sympy); give s in check mode")
        s_y = simp(s0 * _external_factor((f / s0.subs(y, h)).applyfunc(simp), der.ws))
        der.step("Time scale", [*equation, ("s'(y)/s(y)", log_derivative), ("s(y)", s_y)], note)
        scaled = (f / s_y.subs(y, h)).applyfunc(simp)
        progress(f"transform: commutativity of the time-scaled frame (n = {n})")
        tframe = [(tau * s_y.subs(y, h) ** (n - 1)).applyfunc(simp)]
        for _ in range(1, n):
            tframe.append(bracket(scaled, tframe[-1], xs))
        checks = []
        for i in range(n):
            for j in range(i + 1, n):
                value = bracket(tframe[i], tframe[j], xs)
                checks.append((f"[ad^{i} tau~, ad^{j} tau~]", value.T))
                if value != sp.zeros(n, 1):
                    der.step("Commutativity", checks, "f~ = f/s(h), tau~ = s(h)^(n-1) tau.")
                    raise _Fails(f"the time-scaled frame does not commute: [ad^{i} tau~, ad^{j} tau~] = "
                                 f"{list(value)} != 0 (f~ = f/s, s = {s_y})")
        for j in range(n - 1):
            for i in range(g.shape[1]):
                value = bracket(tframe[j], g[:, i], xs)
                checks.append((f"[ad^{j} tau~, g_{i + 1}]", value.T))
                if value != sp.zeros(n, 1):
                    der.step("Commutativity", checks, "f~ = f/s(h), tau~ = s(h)^(n-1) tau.")
                    raise _Fails(f"the input vector field is not output-dependent in the new coordinates: "
                                 f"[ad^{j} tau~, g_{i + 1}] = {list(value)} != 0")
        der.step("Commutativity", checks, "f~ = f/s(h), tau~ = s(h)^(n-1) tau; all brackets vanish.")
        progress(f"transform: coordinates by integration of the coframe (n = {n})")
        basis = sp.Matrix.hstack(*[(-1) ** (n - k) * tframe[n - k] for k in range(1, n + 1)])
        coframe = basis.inv().applyfunc(simp)
        phi = [h]
        for k in range(1, n):
            potential = integrate_exact(list(coframe.row(k)), xs)
            # commuting frames have closed coframes: only sympy's simplification or integration can fail here
            if potential is None or potential.has(sp.Integral):
                raise _Fails(f"the 1-form dz_{k + 1} = {list(coframe.row(k))} has no closed-form integral (sympy); "
                             "give phi in check mode")
            phi.append(potential)
        der.step("Coordinates", [(f"z{k + 1}", e) for k, e in enumerate(phi)],
                 "dz_k is the coframe dual to d/dz_k = (-1)^(n-k) ad^(n-k) tau~ (integration constants zero).")
        moving = sorted({str(w) for e in phi for w in e.free_symbols & der.ws})
        if moving:
            raise _Fails(f"the coordinates depend on the external signal(s) {moving}; with time-varying signals "
                         "dz/dt would gain their derivatives")
        return der.normal_form(phi, s_y)
    except _Fails as exc:
        return der.fail(str(exc))


def _solve(equations: Any, unknowns: Any) -> list | None:
    """sympy's solutions (dicts for a system, values for one equation), or None when it cannot solve."""
    try:
        if isinstance(equations, list):
            return sp.solve(equations, unknowns, dict=True)
        return sp.solve(equations, unknowns)
    except NotImplementedError:
        return None


def _external_factor(field: sp.Matrix, ws: set[sp.Symbol]) -> sp.Expr:
    """The factor of ``field`` in the external signals alone, when all components share it (else 1)."""
    if not ws:
        return sp.Integer(1)
    factors = None
    for e in field:
        if e == 0:
            continue
        mine = sp.Mul(*[a for a in sp.factor(e).as_ordered_factors() if a.free_symbols and a.free_symbols <= ws])
        if factors is not None and simp(mine - factors) != 0:
            return sp.Integer(1)
        factors = mine
    return factors if factors is not None else sp.Integer(1)


def _system_items(system: System) -> list[tuple[str, Any]]:
    items: list[tuple[str, Any]] = [("f(x)", system.f.T), ("h(x)", system.h)]
    if system.g.shape[1]:
        items.insert(1, ("g(x)", system.g.T if system.g.shape[1] == 1 else system.g))
    return items
