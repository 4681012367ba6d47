"""Routh–Hurwitz conditions, symbolic and exact (seed 000 eq. (15)-(16), (23)).

A monic polynomial ``s^n + alpha_1 s^(n-1) + ... + alpha_n`` with real
coefficients is Hurwitz iff (Liénard–Chipart) all ``alpha_i > 0`` and the
Hurwitz determinants ``Delta_(n-1), Delta_(n-3), ...`` (those of order >= 2)
are positive.  Keeping every ``alpha_i > 0`` (one more than the minimal
Liénard–Chipart set) gives the conditions in the form the seeds write them,
e.g. the four inequalities of seed 000 (15) for n = 3.
"""

from __future__ import annotations

from collections.abc import Sequence

import sympy as sp
from sympy.polys.matrices import DomainMatrix

__all__ = ["hurwitz_determinants", "hurwitz_conditions", "readable_condition", "is_hurwitz_exact"]


def _hurwitz_matrix(alpha: Sequence[sp.Expr]) -> list[list[sp.Expr]]:
    n = len(alpha)
    coeff = [sp.Integer(1), *alpha]

    def c(k: int) -> sp.Expr:
        return coeff[k] if 0 <= k <= n else sp.Integer(0)

    return [[c(2 * (j + 1) - (i + 1)) for j in range(n)] for i in range(n)]


def hurwitz_determinants(alpha: Sequence[sp.Expr], orders: Sequence[int]) -> dict[int, sp.Expr]:
    """Leading principal minors ``Delta_k`` of the Hurwitz matrix, for the requested orders.

    Computed fraction-free over the polynomial ring of the coefficients
    (Bareiss), which stays fast for fully symbolic coefficients.
    """
    H = _hurwitz_matrix(alpha)
    out = {}
    for k in orders:
        block = [row[:k] for row in H[:k]]
        dm = DomainMatrix.from_list_sympy(k, k, block)
        out[k] = dm.domain.to_sympy(dm.det())
    return out


def hurwitz_conditions(alpha: Sequence[sp.Expr]) -> list[sp.Expr]:
    """Expressions ``g_i`` such that the polynomial is Hurwitz iff every ``g_i > 0``.

    Returns ``[alpha_1, ..., alpha_n, Delta_(n-1), Delta_(n-3), ...]`` (Hurwitz
    determinants of order >= 2 only; ``Delta_1 = alpha_1``).
    """
    n = len(alpha)
    orders = [k for k in range(n - 1, 1, -2)]
    dets = hurwitz_determinants(alpha, orders)
    return [*alpha, *(dets[k] for k in sorted(orders))]


def is_hurwitz_exact(alpha: Sequence[sp.Expr]) -> bool | None:
    """Decide the Hurwitz property exactly; ``None`` when symbols leave it open."""
    verdicts = [sp.sympify(g).is_positive for g in hurwitz_conditions(alpha)]
    if all(v is True for v in verdicts):
        return True
    if any(v is False for v in verdicts):
        return False
    return None


def readable_condition(g: sp.Expr, unknowns: Sequence[sp.Symbol] = (), *, max_ops: int = 400) -> sp.Basic:
    """Turn ``g > 0`` into a readable relational.

    Positive factors are dropped, negative ones flip the inequality, and when
    ``g`` is linear in one of ``unknowns`` (the gains, tried last to first)
    with a coefficient of known sign, that unknown is isolated, as the seeds
    write their Routh conditions (``k_3^+ < 0``, ``k_1^+ > c``).  Large
    expressions (more than ``max_ops`` operations) are returned as ``g > 0``
    untouched, because factoring them costs more than it clarifies.
    """
    g = sp.sympify(g)
    if g.is_positive is True:
        return sp.true
    if g.is_positive is False:
        return sp.false
    if sp.count_ops(g) > max_ops:
        return sp.StrictGreaterThan(g, 0, evaluate=False)
    g = sp.factor(sp.cancel(g))
    sign = 1
    kept = []
    for factor in sp.Mul.make_args(g):
        if factor.is_positive:
            continue
        if factor.is_negative:
            sign = -sign
            continue
        kept.append(factor)
    core = sp.expand(sp.Mul(*kept))
    num, den = sp.fraction(sp.cancel(core))
    if den.is_positive is not True and den.is_negative is not True:
        return sp.StrictGreaterThan(sign * core, 0, evaluate=False)
    if den.is_negative:
        sign = -sign
    core = sp.expand(num)
    for k in reversed(list(unknowns)):
        if k not in core.free_symbols:
            continue
        poly = sp.Poly(core, k)
        if poly.degree() != 1:
            continue
        coef, rest = poly.all_coeffs()
        coef_sign = (sign * coef).is_positive
        if coef_sign is None:
            continue
        bound = sp.factor(-rest / coef)
        return sp.StrictGreaterThan(k, bound, evaluate=False) if coef_sign else \
            sp.StrictLessThan(k, bound, evaluate=False)
    return sp.StrictGreaterThan(sp.factor(sign * core), 0, evaluate=False)
