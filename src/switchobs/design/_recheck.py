"""Exact re-check of the observer-form Lyapunov equations once per dimension, then by substitution.

Re-checking ``A_plus' P + P A_plus = -C' C`` for a fully symbolic design cancels rational functions of
all its symbols (2N of them for normal-form-N with gains k1..kN), which takes minutes from N = 7 on.
The equation is instead proved once per dimension ``n`` for generic coefficients: with
``F(alpha)`` the observer form (first column ``-alpha``, ones above the diagonal), ``Sigma =
diag(1, -1, 1, ...)`` and ``P(alpha) = N(alpha) / D(alpha)`` the checkerboard solution of
:func:`~switchobs.design._lyapunov.observer_form_gramian`,

    F' N + N F + D e1 e1' = 0   and   (Sigma F Sigma)' N + N (Sigma F Sigma) + D e1 e1' = 0

hold in the polynomial ring ``ZZ[alpha]`` (seed 004 Theorem 1; seed 000 eq. (24)-(28)).  A design
whose matrices are these at ``alpha = alpha_plus`` then satisfies both equations by substitution (a
ring homomorphism), as long as ``D(alpha_plus)`` is not the zero polynomial, which one exact
evaluation at a point shows.  The per-design part only compares matrices; a design of another shape
(a model not in observer normal form, a given ``K_minus``) is re-checked directly by the caller.
"""

from __future__ import annotations

import random
from collections.abc import Sequence
from functools import lru_cache

import flint
import sympy as sp
from sympy.polys.matrices import DomainMatrix

from ._lyapunov import _generic_solution, checkerboard_from_u
from ._normal_form import flint_matrix, normal_form_matrix

__all__ = ["lyapunov_by_substitution", "lyapunov_residual_is_zero"]


def _observer_form(alpha: Sequence[sp.Expr]) -> sp.ImmutableMatrix:
    return normal_form_matrix([-a for a in alpha])


def lyapunov_residual_is_zero(A: sp.MatrixBase, P: sp.MatrixBase, Q: sp.MatrixBase) -> bool:
    """``A' P + P A + Q == 0`` exactly for a symmetric ``P`` (``A' P + (A' P)'``: one product; the design's
    re-check tests the symmetry of its ``P`` on its own): for numbers on python-flint's ``fmpq_mat``, else in the
    polynomial ring or field of the entries (DomainMatrix).

    Ring arithmetic instead of ``cancel()`` on expressions: exact, and orders of magnitude faster for
    fully symbolic matrices.  A numeric 32-state design with 6-digit data has 4000-digit entries, whose products
    took 86 s in DomainMatrix's sparse Python loops; flint multiplies them in C.
    """
    numbers = [flint_matrix(M) for M in (A, P, Q)]
    if all(M is not None for M in numbers):
        Af, Pf, Qf = numbers
        AtP = Af.transpose() * Pf
        return AtP + AtP.transpose() + Qf == flint.fmpq_mat(Qf.nrows(), Qf.ncols())
    mats = [DomainMatrix.from_Matrix(sp.Matrix(M)) for M in (A, P, Q)]
    dom = mats[0].domain.unify(mats[1].domain).unify(mats[2].domain)
    A_, P_, Q_ = (M.convert_to(dom) for M in mats)
    return (A_.transpose() * P_ + P_ * A_ + Q_).is_zero_matrix


def _sigma(n: int) -> sp.Matrix:
    return sp.diag(*[(-1) ** i for i in range(n)])


@lru_cache(maxsize=32)
def _generic_identities_hold(n: int) -> bool:
    """Both equations with the denominator cleared, exactly in ``ZZ[alpha_1..alpha_n]`` (once per n)."""
    alpha, nums, den = _generic_solution(n)
    F = _observer_form(alpha)
    S = _sigma(n)
    N = checkerboard_from_u(nums)
    E = sp.zeros(n, n)
    E[0, 0] = den
    return all(lyapunov_residual_is_zero(A, N, E) for A in (F, S * F * S))


def _denominator_nonzero(den: sp.Expr, alpha: Sequence[sp.Expr], n: int) -> bool:
    """``D(alpha)`` is not the zero polynomial: exact evaluation at a few integer points."""
    symbols = sorted(set().union(*(sp.sympify(a).free_symbols for a in alpha)), key=lambda s: s.name)
    generic = _generic_solution(n)[0]
    rng = random.Random(n)
    for _ in range(3):
        point = {s: sp.Integer(rng.randint(2, 10**6)) for s in symbols}
        values = {g: sp.sympify(a).xreplace(point) for g, a in zip(generic, alpha)}
        if den.xreplace(values) != 0:
            return True
    return False


def lyapunov_by_substitution(A_plus: sp.MatrixBase, A_minus: sp.MatrixBase, P: sp.MatrixBase,
                             C_plus: sp.MatrixBase, C_minus: sp.MatrixBase, alpha: Sequence[sp.Expr]
                             ) -> bool | None:
    """Both Lyapunov equations of a design in observer normal form, re-checked by substitution.

    Returns
    -------
    bool or None
        True when the generic identities hold and the design is their instance at ``alpha`` (so
        ``A_plus' P + P A_plus = -C_plus' C_plus`` and the same for minus hold exactly); None when the
        design is not of that shape (``A_plus`` not ``F(alpha)``, ``A_minus`` not ``Sigma A_plus Sigma``,
        ``C`` not ``e1'``, ``P`` not the checkerboard solution) and must be re-checked directly.
    """
    n = len(alpha)
    e1 = sp.Matrix([[1] + [0] * (n - 1)])
    F = _observer_form(alpha)
    S = _sigma(n)
    if sp.Matrix(C_plus) != e1 or sp.Matrix(C_minus) != e1:
        return None
    if any(sp.expand(x) != 0 for x in (sp.Matrix(A_plus) - F)) or \
            any(sp.expand(x) != 0 for x in (sp.Matrix(A_minus) - S * F * S)):
        return None
    generic, nums, den = _generic_solution(n)
    subs = dict(zip(generic, alpha))
    den_a = den.xreplace(subs)
    expected = checkerboard_from_u([N.xreplace(subs) / den_a for N in nums])
    if sp.ImmutableMatrix(P) != expected or not _denominator_nonzero(den, alpha, n):
        return None
    return _generic_identities_hold(n)
