"""Boxes of a model's parameters, and the model's ``A`` as a polynomial in them.

``a=150:230`` on the command line, ``{"a": (150, 230)}`` in Python: a box ``lower_i <= theta_i <=
upper_i`` of named parameters (exact rationals) around the model's nominal values, over which the
box certificates (:mod:`switchobs.certify`) and the box gain synthesis (:mod:`switchobs.synthesis`)
hold.  :func:`model_terms` writes ``A(theta) = sum_m theta^m M_m``; the vertices of the polytope
containing ``{A(theta)}`` are :func:`switchobs.exact.vertex_matrices`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import sympy as sp

from .._limits import check_double
from ..exact import Interval, Matrix, to_fraction
from ..exceptions import CertificateError, FreeSymbolError, ModelError
from ._model import Model

__all__ = ["ParameterBox", "parse_box", "model_terms", "bound_text"]


@dataclass(frozen=True)
class ParameterBox:
    """A box ``lower_i <= theta_i <= upper_i`` of named parameters (exact rationals)."""

    names: tuple[str, ...]
    lower: tuple[Fraction, ...]
    upper: tuple[Fraction, ...]

    @property
    def intervals(self) -> list[Interval]:
        return list(zip(self.lower, self.upper))

    def scaled(self, nominal: Sequence[Fraction], rho: Fraction) -> "ParameterBox":
        """``nominal + rho (box - nominal)``: the box shrunk towards the nominal point."""
        return ParameterBox(self.names, tuple(v - rho * (v - lo) for v, lo in zip(nominal, self.lower)),
                            tuple(v + rho * (hi - v) for v, hi in zip(nominal, self.upper)))

    def contains(self, point: Sequence[Fraction]) -> bool:
        return all(lo <= v <= hi for v, lo, hi in zip(point, self.lower, self.upper))

    def to_json(self) -> dict[str, list[str]]:
        return {nm: [str(lo), str(hi)] for nm, lo, hi in zip(self.names, self.lower, self.upper)}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> "ParameterBox":
        """The box of :meth:`to_json` (``{name: [lower, upper]}``, exact).

        Raises
        ------
        CertificateError
            Not a mapping of names to two rationals.
        """
        if not isinstance(data, Mapping) or not all(isinstance(v, list) and len(v) == 2 for v in data.values()):
            raise CertificateError(f"a parameter box must map names to [lower, upper], got {data!r}")
        return cls(tuple(str(nm) for nm in data), tuple(to_fraction(v[0], what=f"box {nm} lower")
                                                        for nm, v in data.items()),
                   tuple(to_fraction(v[1], what=f"box {nm} upper") for nm, v in data.items()))

    def __str__(self) -> str:
        return ", ".join(f"{nm} in [{bound_text(lo)}, {bound_text(hi)}]" for nm, lo, hi in zip(self.names, self.lower, self.upper))


def bound_text(x: Fraction) -> str:
    """A box bound as printed: an integer exactly, else 6 significant digits."""
    return str(x) if x.denominator == 1 else f"{float(x):.6g}"


def parse_box(items: Sequence[str] | Mapping[str, Sequence[Any]]) -> ParameterBox:
    """``["a=150:230", "c=20:40"]`` (the command line's form) or ``{"a": (150, 230)}`` -> :class:`ParameterBox`.

    Raises
    ------
    ModelError
        Malformed item, repeated name or empty interval.
    """
    pairs: list[tuple[str, Any, Any]] = []
    if isinstance(items, Mapping):
        for name, rng in items.items():
            if not isinstance(rng, (list, tuple)) or len(rng) != 2:
                raise ModelError(f"box for {name!r} must be (lower, upper), got {rng!r}")
            pairs.append((str(name), rng[0], rng[1]))
    else:
        for item in items:
            name, sep, rng = str(item).partition("=")
            lo, colon, hi = rng.partition(":")
            if not sep or not colon or not name.strip() or not lo.strip() or not hi.strip():
                raise ModelError(f"--box expects NAME=LOWER:UPPER, e.g. a=150:230, got {item!r}")
            pairs.append((name.strip(), lo, hi))
    if not pairs:
        raise ModelError("the parameter box is empty; give at least one NAME=LOWER:UPPER")
    names = [p[0] for p in pairs]
    if len(set(names)) != len(names):
        raise ModelError(f"the box names a parameter twice: {names}")
    lower, upper = [], []
    for name, lo, hi in pairs:
        try:
            a, b = (check_double(to_fraction(x, what=f"box {name} {end}"), what=f"box {name} {end}",
                                 error=CertificateError, text=str(x)) for x, end in ((lo, "lower"), (hi, "upper")))
        except CertificateError as exc:
            raise ModelError(str(exc)) from None
        if a > b:
            raise ModelError(f"box {name} = [{a}, {b}] is empty; write LOWER:UPPER with LOWER <= UPPER")
        lower.append(a)
        upper.append(b)
    return ParameterBox(tuple(names), tuple(lower), tuple(upper))


def model_terms(model: Model, box: ParameterBox, values: Mapping[str, Any] | None = None
                ) -> tuple[list[tuple[list[int], Matrix]], list[Fraction], tuple[str, ...]]:
    """``A(theta) = sum_m theta^m M_m`` for the box parameters, the others at their values.

    Returns
    -------
    terms : list of (exponents, exact matrix)
    nominal : the box parameters' nominal values
    inactive : box parameters that do not enter ``A`` (they enter ``d`` or ``b`` only, which the
        observer injects from measured signals: they do not change the error dynamics' stability)

    Raises
    ------
    ModelError
        A box name that is not a parameter, a nominal value outside the box, or ``A``
        not polynomial in the box parameters.
    FreeSymbolError
        Another parameter has no value.
    """
    merged = {k: v for k, v in model.values.items()}
    merged.update(dict(values or {}))
    for nm in box.names:
        if nm not in model.parameters:
            raise ModelError(f"box parameter {nm!r} is not a parameter of model {model.name!r} "
                             f"(parameters: {list(model.parameters)})")
        if nm not in merged:
            raise FreeSymbolError(f"box parameter {nm!r} has no nominal value; give it with --param {nm}=VALUE")
    nominal = [to_fraction(sp.Rational(str(merged[nm])), what=nm) for nm in box.names]
    if not box.contains(nominal):
        raise ModelError(f"the nominal point ({', '.join(f'{nm} = {v}' for nm, v in zip(box.names, nominal))}) "
                         f"is outside the box {box}; the box must contain the design point")
    fixed = model.with_values({k: v for k, v in merged.items() if k not in box.names and k in model.parameters})
    syms = [model.symbols[nm] for nm in box.names]
    n = model.n
    coeffs: dict[tuple[int, ...], list[list[Fraction]]] = {}
    for i in range(n):
        for j in range(n):
            expr = sp.expand(fixed.A[i, j])
            left = sorted(str(s) for s in expr.free_symbols - set(syms))
            if left:
                raise FreeSymbolError(f"A[{i + 1},{j + 1}] = {expr} still depends on {left}; give their values")
            try:
                poly = sp.Poly(expr, *syms)
            except sp.PolynomialError:
                raise ModelError(f"A[{i + 1},{j + 1}] = {expr} is not polynomial in the box parameters "
                                 f"{list(box.names)}; box certificates need polynomial dependence "
                                 "(reparametrise, e.g. box the load Fz instead of 1/Fz)") from None
            for mono, c in poly.terms():
                coeffs.setdefault(tuple(mono), [[Fraction(0)] * n for _ in range(n)])[i][j] = \
                    to_fraction(c, what=f"A[{i + 1},{j + 1}]")
    zero = tuple(0 for _ in syms)
    coeffs.setdefault(zero, [[Fraction(0)] * n for _ in range(n)])
    terms = [(list(m), coeffs[m]) for m in sorted(coeffs)]
    active = {i for m, _ in terms for i, e in enumerate(m) if e}
    inactive = tuple(nm for i, nm in enumerate(box.names) if i not in active)
    return terms, nominal, inactive
