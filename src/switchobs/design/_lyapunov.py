"""Exact solution of the observer-form Lyapunov equation (seed 004 Theorem 1; seed 000 eq. (24)-(28)).

For the observer normal form ``F`` with first column ``-alpha`` (so that
``det(sI - F) = s^n + alpha_1 s^(n-1) + ... + alpha_n``) and ``C = e_1'``,
``F' P + P F = -C' C`` has a solution with a *checkerboard Hankel* structure:
P is the observability Gramian, ``P_ij = ∫ y_i y_j dt`` with
``Y_i(s) = s^(n-i) / alpha(s)``, so by Parseval ``P_ij = 0`` when ``i + j`` is
odd and ``P_ij = (-1)^((j-i)/2) u_((i+j)/2)`` otherwise.  Only ``n`` unknowns
``u_1..u_n`` remain and only the first row of the equation is not satisfied
identically by the structure, which leaves an ``n x n`` linear system instead of
the ``n(n+1)/2`` unknowns of a naive solve.  The structure also gives
``D P D = P`` for ``D = diag(1, -1, 1, ...)``, which is why ``A_minus = D A_plus D``
shares ``P`` (Theorem 1).
"""

from __future__ import annotations

from collections.abc import Sequence
from fractions import Fraction
from functools import lru_cache
from typing import Any

import sympy as sp
from sympy import QQ
from sympy.polys.matrices import DomainMatrix

__all__ = ["observer_form_gramian", "checkerboard_from_u", "checkerboard_rows", "gramian_entries", "naive_lyapunov"]


def checkerboard_from_u(u: Sequence[sp.Expr]) -> sp.ImmutableMatrix:
    """Assemble ``P_ij = (-1)^((j-i)/2) u_((i+j)/2)`` (1-based, ``i + j`` even), zero elsewhere."""
    n = len(u)

    def entry(i: int, j: int) -> sp.Expr:  # 0-based i, j
        if (i + j) % 2:
            return sp.Integer(0)
        sign = -1 if ((j - i) // 2) % 2 else 1
        return sign * u[(i + j) // 2]

    return sp.ImmutableMatrix(n, n, entry)


def _first_row_system(alpha: Sequence[Any], one: Any = sp.Integer(1)) -> tuple[list[list[Any]], list[Any]]:
    """The ``n x n`` system in ``u_1..u_n``: the first row of ``F'P + PF + e1 e1' = 0`` (checkerboard P), in the
    number type of ``one``."""
    n = len(alpha)
    rows, rhs = [], []
    for j in range(n):  # equation (1, j+1) of F'P + PF + e1 e1' = 0
        row = [one * 0] * n
        for k in range(n):  # - sum_k alpha_k P_kj   (+ alpha_k P_1k for j = 0)
            if (k + j) % 2 == 0:
                sign = -1 if ((j - k) // 2) % 2 else 1
                row[(k + j) // 2] += -alpha[k] * sign * (2 if j == 0 else 1)
        if j >= 1 and (j - 1) % 2 == 0:  # + P_{1, j}  (0-based column j-1)
            sign = -1 if ((j - 1) // 2) % 2 else 1
            row[(j - 1) // 2] += sign
        rows.append(row)
        rhs.append(-one if j == 0 else one * 0)
    return rows, rhs


@lru_cache(maxsize=32)
def _generic_solution(n: int) -> tuple[tuple[sp.Symbol, ...], tuple[sp.Expr, ...], sp.Expr]:
    """Numerators ``N_m`` and common denominator ``D`` of ``u_m`` for symbolic ``alpha``.

    Solved once per dimension over ``ZZ[alpha_1..alpha_n]`` fraction-free and
    cached; callers substitute their own coefficients.
    """
    alpha = sp.symbols(f"alpha_1:{n + 1}")
    rows, rhs = _first_row_system(alpha)
    M = DomainMatrix.from_list_sympy(n, n, rows)
    b = DomainMatrix.from_list_sympy(n, 1, [[r] for r in rhs])
    M, b = M.unify(b)
    M, b = M.to_field(), b.to_field()
    # Cramer-style fraction-free solve keeps polynomials, not rational functions.
    Mr = M.convert_to(M.domain.get_ring()) if hasattr(M.domain, "get_ring") else M
    br = b.convert_to(Mr.domain)
    num, den = Mr.solve_den(br)
    to = Mr.domain.to_sympy
    return alpha, tuple(to(num[m, 0].element) for m in range(n)), to(den)


def _rational_solution(alpha: Sequence[sp.Rational]) -> tuple[sp.Rational, ...]:
    """``u_1..u_n`` for rational ``alpha``: the same system solved directly over QQ (no generic solve)."""
    rows, rhs = _first_row_system([QQ.from_sympy(sp.sympify(a)) for a in alpha])
    n = len(alpha)
    M = DomainMatrix([[QQ.convert(x) for x in row] for row in rows], (n, n), QQ)
    b = DomainMatrix([[QQ.convert(r)] for r in rhs], (n, 1), QQ)
    u = M.lu_solve(b)
    return tuple(QQ.to_sympy(u[m, 0].element) for m in range(n))


def gramian_entries(alpha: Sequence[Fraction]) -> list[Fraction]:
    """``u_1..u_n`` of :func:`observer_form_gramian` for rational ``alpha``, on python-flint (the exact kernel's
    solve): ``P_ij = (-1)^((j-i)/2) u_((i+j)/2)`` for ``i + j`` even."""
    from ..exact import solve

    rows, rhs = _first_row_system(list(alpha), Fraction(1))
    return [x[0] for x in solve(rows, [[r] for r in rhs])]


def checkerboard_rows(u: Sequence[Any]) -> list[list[Any]]:
    """:func:`checkerboard_from_u` as a list of rows of ``u``'s own number type."""
    n = len(u)
    zero = u[0] * 0
    return [[zero if (i + j) % 2 else (-u[(i + j) // 2] if ((j - i) // 2) % 2 else u[(i + j) // 2])
             for j in range(n)] for i in range(n)]


def observer_form_gramian(alpha: Sequence[sp.Expr]) -> tuple[sp.ImmutableMatrix, tuple[sp.Expr, ...], sp.Expr]:
    """Solve ``F' P + P F = -e1 e1'`` for the observer form with coefficients ``alpha``.

    Parameters
    ----------
    alpha : sequence of sympy expressions
        Coefficients of the monic characteristic polynomial of ``F``.

    Returns
    -------
    P : sympy.ImmutableMatrix
        The unique solution when ``F`` is Hurwitz (entries ``N_m / D``).
    numerators : tuple
        ``N_1..N_n`` with ``u_m = N_m / D``.
    denominator : sympy.Expr
        ``D``, a multiple of the Hurwitz determinant ``Delta_(n-1)`` (non-zero
        when ``F`` is Hurwitz).  For rational ``alpha`` the system is solved
        directly over QQ: then ``N_m = u_m`` and ``D = 1``.
    """
    if all(sp.sympify(a).is_Rational for a in alpha):
        u = _rational_solution(alpha)
        return checkerboard_from_u(u), u, sp.Integer(1)
    n = len(alpha)
    generic, nums, den = _generic_solution(n)
    subs = dict(zip(generic, alpha))
    nums_sub = tuple(N.xreplace(subs) for N in nums)
    den_sub = den.xreplace(subs)
    u = [N / den_sub for N in nums_sub]
    return checkerboard_from_u(u), nums_sub, den_sub


def naive_lyapunov(A: sp.MatrixBase, Q: sp.MatrixBase) -> sp.Matrix:
    """Baseline: ``A' P + P A = -Q`` by ``sympy.linsolve`` on the n(n+1)/2 unknowns (benchmarks only)."""
    n = A.shape[0]
    p = sp.symbols(f"p0:{n * (n + 1) // 2}")
    it = iter(p)
    P = sp.zeros(n, n)
    for i in range(n):
        for j in range(i, n):
            P[i, j] = P[j, i] = next(it)
    eqs = [e for i, row in enumerate((A.T * P + P * A + Q).tolist()) for j, e in enumerate(row) if j >= i]
    (sol,) = sp.linsolve(eqs, p)
    return P.subs(dict(zip(p, sol)))
