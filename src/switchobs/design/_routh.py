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
from functools import lru_cache

import sympy as sp
from sympy import QQ
from sympy.polys.matrices import DomainMatrix

__all__ = ["hurwitz_determinants", "hurwitz_conditions", "readable_condition", "is_hurwitz_exact",
           "routh_first_column"]


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


@lru_cache(maxsize=32)
def _generic_conditions(n: int) -> tuple[tuple[sp.Symbol, ...], tuple[sp.Expr, ...]]:
    alpha = sp.symbols(f"alpha_1:{n + 1}")
    orders = list(range(n - 1, 1, -2))
    dets = hurwitz_determinants(alpha, orders)
    return alpha, (*alpha, *(dets[k] for k in sorted(orders)))


def hurwitz_conditions(alpha: Sequence[sp.Expr]) -> list[sp.Expr]:
    """Expressions ``g_i`` such that the polynomial is Hurwitz iff every ``g_i > 0``.

    Returns ``[alpha_1, ..., alpha_n, Delta_(n-1), Delta_(n-3), ...]`` (Hurwitz
    determinants of order >= 2 only; ``Delta_1 = alpha_1``).  The determinants
    are computed once per degree in generic coefficients and then substituted,
    so large symbolic coefficients are never expanded.
    """
    generic, conditions = _generic_conditions(len(alpha))
    subs = dict(zip(generic, (sp.sympify(a) for a in alpha)))
    return [g.xreplace(subs) for g in conditions]


def routh_first_column(alpha: Sequence[sp.Rational]) -> list[sp.Rational]:
    """First column of the Routh array of ``s^n + alpha_1 s^(n-1) + ... + alpha_n`` (rational ``alpha``).

    Exact rational arithmetic, ``O(n^2)`` operations and no determinant: the
    polynomial is Hurwitz iff all ``n + 1`` entries are positive (Routh).  The
    array stops at the first entry that is not positive (a zero there is the
    degenerate case in which the polynomial has roots on or to the right of
    the imaginary axis), so a shorter list means "not Hurwitz".

    Examples
    --------
    >>> routh_first_column([6, 11, 6])          # (s+1)(s+2)(s+3)
    [1, 6, 10, 6]
    >>> routh_first_column([1, 1, 2])           # not Hurwitz: Delta_2 = 1 - 2 < 0
    [1, 1, -1]
    """
    n = len(alpha)
    coeff = [QQ(1), *(QQ.from_sympy(sp.sympify(a)) for a in alpha)]
    width = n // 2 + 2
    prev = (coeff[0::2] + [QQ(0)] * width)[:width]
    cur = (coeff[1::2] + [QQ(0)] * width)[:width]
    column = [QQ(1)]
    for _ in range(n):
        pivot = cur[0]
        column.append(pivot)
        if pivot <= 0:
            break
        nxt = [(pivot * prev[j + 1] - prev[0] * cur[j + 1]) / pivot for j in range(width - 1)] + [QQ(0)]
        prev, cur = cur, nxt
    return [QQ.to_sympy(x) for x in column]


def is_hurwitz_exact(alpha: Sequence[sp.Expr]) -> bool | None:
    """Decide the Hurwitz property exactly; ``None`` when symbols leave it open.

    Rational coefficients go through the numeric Routh array
    (:func:`routh_first_column`); symbolic ones through the Hurwitz determinants.
    """
    if all(sp.sympify(a).is_Rational for a in alpha):
        column = routh_first_column(alpha)
        return len(column) == len(alpha) + 1 and all(x > 0 for x in column)
    verdicts = [sp.sympify(g).is_positive for g in hurwitz_conditions(alpha)]
    if all(v is True for v in verdicts):
        return True
    if any(v is False for v in verdicts):
        return False
    return None


def readable_condition(g: sp.Expr, unknowns: Sequence[sp.Symbol] = (), *, max_ops: int = 80) -> sp.Basic:
    """Turn ``g > 0`` into a readable relational.

    Common factors of known sign are dropped (a negative one flips the
    inequality), and when ``g`` is linear in one of ``unknowns`` (the gains,
    tried last to first) with a coefficient of known sign, that unknown is
    isolated, as the seeds write their Routh conditions (``k_3^+ < 0``,
    ``k_1^+ > c``).  Expressions of more than ``max_ops`` operations are
    returned as ``g > 0`` untouched: expanding and factoring them costs more
    than it clarifies.
    """
    g = sp.sympify(g)
    if g.is_positive is True:
        return sp.true
    if g.is_positive is False:
        return sp.false
    if sp.count_ops(g) > max_ops:
        return sp.StrictGreaterThan(g, 0, evaluate=False)
    sign = 1
    kept = []
    for factor in sp.Mul.make_args(sp.factor_terms(sp.cancel(g))):
        if factor.is_positive:
            continue
        if factor.is_negative:
            sign = -sign
            continue
        kept.append(factor)
    num, den = sp.fraction(sp.cancel(sp.Mul(*kept)))
    if den.is_negative:
        sign = -sign
    elif den.is_positive is not True:
        return sp.StrictGreaterThan(sign * sp.Mul(*kept), 0, evaluate=False)
    core = sp.expand(sign * num)
    for k in reversed(list(unknowns)):
        if k not in core.free_symbols:
            continue
        poly = sp.Poly(core, k)
        if poly.degree() != 1:
            continue
        coef, rest = poly.all_coeffs()
        if coef.is_positive is None and coef.is_negative is None:
            continue
        bound = _tidy(-rest / coef)
        return sp.StrictGreaterThan(k, bound, evaluate=False) if coef.is_positive else \
            sp.StrictLessThan(k, bound, evaluate=False)
    if core.is_positive or core.is_negative:  # e.g. 1 > 0 once positive factors are dropped
        return sp.true if core.is_positive else sp.false
    return sp.StrictGreaterThan(_tidy(core), 0, evaluate=False)


def _tidy(expr: sp.Expr, max_ops: int = 40) -> sp.Expr:
    """Factor small expressions for display; leave larger ones alone (factoring is costly)."""
    return sp.factor(expr) if sp.count_ops(expr) <= max_ops else sp.cancel(expr)
