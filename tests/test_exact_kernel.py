"""The python-flint kernel of :mod:`switchobs.exact` against plain Fraction code on random matrices.

The references below are written here, the textbook way, in :class:`fractions.Fraction` only:
rational LDL' for definiteness, Gaussian elimination for the determinant and the rank,
row-by-column sums for products.  The kernel must give the same values, verdicts and failing
indices (the certificates' reasons name them).
"""

from fractions import Fraction
from random import Random

import pytest

from switchobs.exact import (charpoly, definiteness, ldl_psd, lyapunov_form, lyapunov_solve, matmul, nullspace, rank,
                             solve, transpose)
from switchobs.exact._exact import _eliminated_definiteness, _symmetric_integer_form
from switchobs.exceptions import DimensionError


# ------------------------------------------------------------------ Fraction references
def ref_matmul(A, B):
    return [[sum((Fraction(a) * Fraction(b) for a, b in zip(row, col)), Fraction(0)) for col in zip(*B)]
            for row in A]


def ref_ldl(M):
    """Rational LDL' with the semidefinite rule: ``(L, d, None)``, or ``(None, None, (index, kind))``."""
    n = len(M)
    A = [[Fraction(x) for x in row] for row in M]
    L = [[Fraction(int(i == j)) for j in range(n)] for i in range(n)]
    d = [Fraction(0)] * n
    for k in range(n):
        p = A[k][k]
        if p < 0:
            return None, None, (k, "negative")
        if p == 0:
            if any(A[k][j] != 0 for j in range(k + 1, n)):
                return None, None, (k, "coupling")
            d[k] = Fraction(0)
            continue
        d[k] = p
        for i in range(k + 1, n):
            L[i][k] = A[i][k] / p
        for i in range(k + 1, n):
            for j in range(k + 1, n):
                A[i][j] -= L[i][k] * A[k][j]
    return L, d, None


def ref_det_rank(M):
    A = [[Fraction(x) for x in row] for row in M]
    rows, cols = len(A), len(A[0])
    det, r = Fraction(1), 0
    for c in range(cols):
        piv = next((i for i in range(r, rows) if A[i][c] != 0), None)
        if piv is None:
            det = Fraction(0)
            continue
        if piv != r:
            A[r], A[piv] = A[piv], A[r]
            det = -det
        det *= A[r][c]
        for i in range(r + 1, rows):
            f = A[i][c] / A[r][c]
            A[i] = [x - f * y for x, y in zip(A[i], A[r])]
        r += 1
        if r == rows:
            break
    return (det if rows == cols and r == rows else Fraction(0)), r


# ------------------------------------------------------------------ random matrices
def _entry(rng, digits):
    num = rng.randint(-10 ** digits, 10 ** digits)
    return Fraction(num, 10 ** rng.randint(0, digits) * rng.choice((1, 3, 7)))   # decimals, some thirds


def _symmetric(rng, n, digits, kind):
    """Positive definite, semidefinite of lower rank, indefinite, or with a zero leading block."""
    r = {"pd": n, "psd": max(1, n // 2), "indefinite": n, "zero": n}[kind]
    Y = [[_entry(rng, digits) for _ in range(r)] for _ in range(n)]
    M = ref_matmul(Y, transpose(Y))
    if kind == "indefinite":
        k = rng.randrange(n)
        M[k][k] -= 2 * M[k][k] + 1
    if kind == "zero":
        M = [[Fraction(0)] * n] + [[Fraction(0)] + row[1:] for row in M[1:]]
    return M


CASES = [(n, digits, kind, seed) for seed, (n, digits) in enumerate([(1, 2), (3, 5), (6, 30), (12, 60), (24, 8)])
         for kind in ("pd", "psd", "indefinite", "zero")]


@pytest.mark.parametrize("n, digits, kind, seed", CASES)
def test_definiteness_and_ldl_equal_the_fraction_ldl(n, digits, kind, seed):
    rng = Random(seed * 31 + n)
    M = _symmetric(rng, n, digits, kind)
    L, d, failure = ref_ldl(M)
    for strict in (True, False):
        got = definiteness(M, strict=strict)
        exact = _eliminated_definiteness(_symmetric_integer_form(M), strict=strict)
        assert got == exact   # the enclosure decides as the elimination does, or leaves it to it
        if strict:
            holds = failure is None and all(x > 0 for x in d)
            assert got.holds == holds
            if not holds:
                assert got.index == (failure[0] if failure else next(k for k, x in enumerate(d) if x == 0))
        else:
            assert got.holds == (failure is None)
            if failure:
                assert got.index == failure[0]
    factor = ldl_psd(M)
    assert (factor is None) == (failure is not None)
    if factor is not None:
        assert factor == (L, d)
        product = Fraction(1)
        for x in factor[1]:
            product *= x
        assert product == ref_det_rank(M)[0]   # det M = prod d: the last pivot of the elimination


@pytest.mark.parametrize("n, digits, seed", [(1, 3, 0), (4, 10, 1), (9, 40, 2), (16, 6, 3)])
def test_products_determinants_ranks_solutions_equal_the_fraction_code(n, digits, seed):
    rng = Random(seed)
    A = [[_entry(rng, digits) for _ in range(n)] for _ in range(n)]
    B = [[_entry(rng, digits) for _ in range(n + 1)] for _ in range(n)]
    Ai = [[rng.randint(-10 ** digits, 10 ** digits) for _ in range(n)] for _ in range(n)]
    assert matmul(A, B) == ref_matmul(A, B)
    assert matmul(Ai, Ai) == ref_matmul(Ai, Ai) and all(type(x) is int for row in matmul(Ai, Ai) for x in row)
    P = _symmetric(rng, n, digits, "pd")
    AtP = ref_matmul(transpose(A), P)
    assert lyapunov_form(A, P) == [[AtP[i][j] + AtP[j][i] for j in range(n)] for i in range(n)]
    det, r = ref_det_rank(A)
    assert rank(A) == r == n and det != 0
    X = solve(A, B)
    assert ref_matmul(A, X) == B
    # a rank-deficient product: rank, kernel and the singular solve
    low = ref_matmul([row[: max(1, n // 2)] for row in A], [row for row in B[: max(1, n // 2)]])
    assert rank(low) == ref_det_rank(low)[1]
    for v in nullspace(low):
        assert ref_matmul(low, [[x] for x in v]) == [[0]] * n
    assert len(nullspace(low)) == n + 1 - ref_det_rank(low)[1]
    if n > 1:
        square = [row[:n] for row in low]
        with pytest.raises(DimensionError, match=f"singular \\(rank {ref_det_rank(square)[1]}\\)"):
            solve(square, B)


def ref_charpoly(M):
    """``[1, c_1, ..., c_n]`` by Faddeev-LeVerrier: ``M_k = M M_(k-1) + c_(k-1) I``, ``c_k = -tr(M M_k) / k``."""
    n = len(M)
    eye = [[Fraction(int(i == j)) for j in range(n)] for i in range(n)]
    coeffs, Mk = [Fraction(1)], [[Fraction(0)] * n for _ in range(n)]
    for k in range(1, n + 1):
        Mk = [[x + coeffs[-1] * e for x, e in zip(row, erow)] for row, erow in zip(ref_matmul(M, Mk), eye)]
        coeffs.append(-sum(ref_matmul(M, Mk)[i][i] for i in range(n)) / k)
    return coeffs


@pytest.mark.parametrize("n, digits, seed", [(1, 3, 0), (3, 10, 1), (8, 40, 2), (12, 6, 3)])
def test_the_characteristic_polynomial_equals_the_fraction_code(n, digits, seed):
    rng = Random(seed)
    A = [[_entry(rng, digits) for _ in range(n)] for _ in range(n)]
    assert charpoly(A) == ref_charpoly(A)
    assert all(type(c) is Fraction for c in charpoly(A))


def test_the_exact_lyapunov_solution_solves_the_equation():
    A = [[Fraction(-3), Fraction(1, 7)], [Fraction(2, 3), Fraction(-5, 2)]]
    Q = [[Fraction(1), Fraction(0)], [Fraction(0), Fraction(2)]]
    P = lyapunov_solve(A, Q)
    AtP = ref_matmul(transpose(A), P)
    assert [[AtP[i][j] + AtP[j][i] + Q[i][j] for j in range(2)] for i in range(2)] == [[0, 0], [0, 0]]


def test_the_eigenvalue_enclosure_decides_hurwitz_as_the_routh_array_does():
    from switchobs.certify._family import _hurwitz_enclosed, _hurwitz_exact, _hurwitz_routh
    from switchobs.exact import integer_form

    rng = Random(5)
    decided = 0
    for n in (2, 5, 9):
        for shift in (Fraction(-3), Fraction(0), Fraction(3)):
            A = [[_entry(rng, 6) / 10 ** 6 + (shift if i == j else 0) for j in range(n)] for i in range(n)]
            enclosed = _hurwitz_enclosed(*integer_form(A))
            decided += enclosed is not None
            assert enclosed in (None, _hurwitz_routh(A)) and _hurwitz_exact(A) == _hurwitz_routh(A)
    assert decided >= 6
    # long entries take the enclosure first: the same verdicts
    huge = [[Fraction(-3 * 10 ** 1200 + 1, 10 ** 1200), Fraction(1)], [Fraction(0), Fraction(-1, 7)]]
    assert _hurwitz_enclosed(*integer_form(huge)) is True and _hurwitz_exact(huge)
    assert not _hurwitz_exact([[-x for x in row] for row in huge])
    # an eigenvalue on the axis: the balls straddle it, the exact Routh array refuses
    nilpotent = [[Fraction(0), Fraction(1)], [Fraction(0), Fraction(0)]]
    assert _hurwitz_enclosed(*integer_form(nilpotent)) is None and not _hurwitz_exact(nilpotent)


def test_the_design_recheck_of_a_numeric_design_runs_on_the_kernel(tmp_path):
    import sympy as sp

    from switchobs.design import design_gains
    from switchobs.design._normal_form import flint_matrix
    from switchobs.design._recheck import lyapunov_residual_is_zero
    from switchobs.model import load_model

    path = tmp_path / "decimal.toml"
    path.write_text('name = "decimal"\nstates = ["x1", "x2", "x3"]\noutput = "y"\n'
                    'A = [["-1.23457", "1", "0"], ["0.5", "-2.5", "1"], ["0", "0", "-0.731"]]\n'
                    'C = ["1", "0", "0"]\ntime_scale = "y"\n', encoding="utf-8")
    design = design_gains(load_model(str(path)), spectrum="-1,-1.5,-2.03125")
    Q = sp.Matrix(design.C_plus).T * sp.Matrix(design.C_plus)
    assert flint_matrix(design.A_plus) is not None and flint_matrix(sp.Matrix([[sp.Symbol("a")]])) is None
    assert lyapunov_residual_is_zero(design.A_plus, design.P, Q)
    assert not lyapunov_residual_is_zero(design.A_plus, design.P, 2 * Q)
    assert all(design.verify().values())
