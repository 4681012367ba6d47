"""Exact differential-geometric tools: Lie derivatives, brackets, exact 1-forms, functions of the output."""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

import sympy as sp

__all__ = ["simp", "lie", "bracket", "integrate_exact", "as_output_function", "kappa"]


def simp(expr: sp.Expr) -> sp.Expr:
    """The one simplification of the package: exact, so that ``simp(e) == 0`` decides ``e = 0``."""
    return sp.simplify(sp.cancel(sp.together(expr)))


def lie(expr: sp.Expr, field: sp.MatrixBase, xs: Sequence[sp.Symbol]) -> sp.Expr:
    """The Lie derivative ``L_field expr``."""
    return sum((sp.diff(expr, x) * field[i] for i, x in enumerate(xs)), sp.Integer(0))


def bracket(X: sp.MatrixBase, Y: sp.MatrixBase, xs: Sequence[sp.Symbol]) -> sp.Matrix:
    """The Lie bracket ``[X, Y] = DY X - DX Y`` (so ``ad_f tau = [f, tau]``), simplified."""
    return (Y.jacobian(list(xs)) * X - X.jacobian(list(xs)) * Y).applyfunc(simp)


def integrate_exact(form: Sequence[sp.Expr], xs: Sequence[sp.Symbol]) -> sp.Expr | None:
    """A potential ``p`` with ``dp = form`` (zero at no particular point), or None when ``form`` is not closed.

    Integrates along one coordinate after the other: the remainder after the
    first ``i`` coordinates must not depend on them.
    """
    potential = sp.Integer(0)
    for i, x in enumerate(xs):
        rest = simp(form[i] - sp.diff(potential, x))
        if any(simp(sp.diff(rest, earlier)) != 0 for earlier in xs[:i] if rest.has(earlier)):
            return None
        if rest != 0:
            potential += sp.integrate(rest, x)
    return simp(potential)


def as_output_function(q: sp.Expr, h: sp.Expr, y: sp.Symbol, xs: Sequence[sp.Symbol]) -> sp.Expr | None:
    """``Q(y)`` with ``q(x) = Q(h(x))`` exactly, or None when ``q`` depends on more than the output."""
    if not q.free_symbols & set(xs):
        return q
    candidates = [x for x in xs if h.has(x)]
    if h in xs:
        value = q.subs(h, y)
    else:
        try:
            solutions = sp.solve(sp.Eq(h, y), candidates[0], dict=True)
        except NotImplementedError:
            return None
        if not solutions:
            return None
        value = q.subs(solutions[0])
    value = simp(value)
    if value.free_symbols & set(xs) or simp(q - value.subs(y, h)) != 0:
        return None
    return value


@lru_cache(maxsize=None)
def kappa(n: int) -> sp.Integer:
    """The constant with ``[ad^{n-2} tau, ad^{n-1} tau] = kappa_n (s'/s)(y) ad^{n-2} tau + (lower frame terms)``.

    Computed on the time-scaled observer form itself (``s = exp(z1)``, ``A`` the
    shift, ``d = 0``, so ``s'/s = 1``) rather than quoted: -2, 4, -7 for n = 2, 3, 4.
    """
    z = sp.symbols(f"z1:{n + 1}", real=True)
    s = sp.exp(z[0])
    f = sp.Matrix([s * z[i + 1] if i < n - 1 else 0 for i in range(n)])
    tau = sp.Matrix([0] * (n - 1) + [s ** (1 - n)])
    frame = [tau]
    for _ in range(1, n):
        frame.append(bracket(f, frame[-1], z))
    coefficients = sp.Matrix.hstack(*frame).LUsolve(bracket(frame[n - 2], frame[n - 1], z))
    return sp.Integer(simp(coefficients[n - 2]))
