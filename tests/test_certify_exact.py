"""Exact kernel of the certificates: definiteness, kernels, observability, rigorous exp enclosure."""

from fractions import Fraction

import mpmath
import numpy as np
import pytest
import scipy.linalg
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from switchobs.exact._exact import (Definiteness, _eliminated_definiteness, _enclosed_definiteness,
                                      _full_rank_mod_p, arithmetic, definiteness, expm_enclosure, fraction_matrix,
                                      integer_form, lyapunov_form, nullspace, observable, rank, to_fraction)
from switchobs.exact import factor_rows, range_basis, short_sqrt_lower
from switchobs.exceptions import CertificateError, DimensionError


@st.composite
def symmetric_int(draw):
    n = draw(st.integers(1, 5))
    r = draw(st.integers(0, n))
    Y = np.array(draw(st.lists(st.integers(-4, 4), min_size=n * r, max_size=n * r)), dtype=object).reshape(n, r)
    shift = draw(st.lists(st.integers(-1, 1), min_size=n, max_size=n))
    M = (Y @ Y.T if r else np.zeros((n, n), dtype=object)) + np.diag(shift)
    return [[int(x) for x in row] for row in M]


@settings(max_examples=25, deadline=None)
@given(symmetric_int())
def test_definiteness_agrees_with_sympy_on_integer_matrices(M):
    S = sp.Matrix(M)
    assert definiteness(M, strict=True).holds == bool(S.is_positive_definite)
    assert definiteness(M, strict=False).holds == bool(S.is_positive_semidefinite)
    for strict in (True, False):
        assert definiteness(M, strict=strict) == _eliminated_definiteness(M, strict=strict)


def test_the_enclosure_proves_an_ill_conditioned_matrix_and_leaves_zero_pivots_to_the_exact_elimination():
    n = 12
    hilbert = [[Fraction(1, i + j + 1) for j in range(n)] for i in range(n)]   # smallest eigenvalue 1.05e-16
    N = integer_form(hilbert)[0]
    assert _enclosed_definiteness(N, strict=True) == Definiteness(True)
    assert definiteness(hilbert, strict=True).holds
    shifted = [[x - (Fraction(1, 10**15) if i == j else 0) for j, x in enumerate(row)]
               for i, row in enumerate(hilbert)]
    refuted = _enclosed_definiteness(integer_form(shifted)[0], strict=True)   # a minor proven negative
    assert refuted is not None and refuted == _eliminated_definiteness(integer_form(shifted)[0], strict=True)
    assert not refuted.holds
    # a zero pivot is beyond the balls: the exact elimination names it
    singular = [[1, 1, 0], [1, 1, 0], [0, 0, 1]]
    assert _enclosed_definiteness(singular, strict=True) is None
    assert _enclosed_definiteness(singular, strict=False) is None
    assert definiteness(singular, strict=True).reason == "the principal minor on rows/columns [1, 2] is zero"
    assert definiteness(singular, strict=False).holds
    bad = definiteness([[1, 2], [2, 1]], strict=True)
    assert not bad.holds and bad.reason == "the principal minor on rows/columns [1, 2] is negative"
    for kind in ("exact", "interval"):   # both names decide the same way
        with arithmetic(kind):
            assert definiteness([[1, 2], [2, 1]], strict=True) == bad
    with pytest.raises(CertificateError, match="arithmetic 'float' is unknown"):
        with arithmetic("float"):
            pass


def test_definiteness_semidefinite_zero_pivot_rule():
    # a zero pivot with a zero row is allowed, with a nonzero coupling it is not
    assert definiteness([[0, 0], [0, 1]], strict=False).holds
    assert not definiteness([[0, 0], [0, 1]], strict=True).holds
    bad = definiteness([[0, 1], [1, 5]], strict=False)
    assert not bad.holds and "coupling" in bad.reason


def test_definiteness_names_the_failing_minor():
    res = definiteness([[2, 0, 0], [0, 1, 3], [0, 3, 1]], strict=False)
    assert not res.holds and res.reason == "the principal minor on rows/columns [1, 2, 3] is negative"


def test_definiteness_refuses_non_symmetric_and_non_square():
    with pytest.raises(DimensionError, match="not symmetric"):
        definiteness([[1, 2], [3, 4]], strict=True)
    with pytest.raises(DimensionError, match="square"):
        definiteness([[1, 2]], strict=True)


def test_rational_parsing_is_exact_and_rejects_non_finite():
    assert to_fraction("187.5") == Fraction(375, 2)
    assert to_fraction("-375/2") == Fraction(-375, 2)
    assert to_fraction(sp.Rational(7, 3)) == Fraction(7, 3)
    assert to_fraction(0.5) == Fraction(1, 2)
    for bad in ("nan", "inf", float("nan"), float("inf"), "x"):
        with pytest.raises(CertificateError):
            to_fraction(bad)
    with pytest.raises(CertificateError, match="irrational"):
        to_fraction(sp.sqrt(2))
    with pytest.raises(DimensionError, match="rectangular"):
        fraction_matrix([[1, 2], [3]])


def test_rank_nullspace_observability():
    assert rank([[1, 2], [2, 4]]) == 1
    N = nullspace([[Fraction(1), Fraction(2), Fraction(3)]])
    assert len(N) == 2 and all(v[0] + 2 * v[1] + 3 * v[2] == 0 for v in N)
    A = fraction_matrix([[-84, "-375/2", 0], ["7312/375", 34, 1], ["64/3", 0, 0]])
    assert observable(A, [[Fraction(1), Fraction(0), Fraction(0)]]) == (True, 3)
    # a diagonal A with a single-state output is not observable
    assert observable(fraction_matrix([[1, 0], [0, 2]]), fraction_matrix([[1, 0]])) == (False, 1)
    # the modular rank proves full rank only: (diag(1, 1 + p), e1 + e2) is unobservable modulo p = 2^61 - 1
    p = (1 << 61) - 1
    A, C = fraction_matrix([[1, 0], [0, 1 + p]]), fraction_matrix([[1, 1]])
    assert not _full_rank_mod_p(A, C) and observable(A, C) == (True, 2)


@pytest.mark.parametrize("A, T", [
    ([[-1, 5], [-3, -2]], "3/2"),
    ([[-84, "-375/2", 0], ["7312/375", 34, 1], ["64/3", 0, 0]], "1/10"),
    ([["-1/10", -1], [2, "-1/10"]], "17/5"),
])
def test_expm_enclosure_contains_scipy_value(A, T):
    Af = fraction_matrix(A)
    E, w, err = expm_enclosure(Af, Fraction(T), 128)
    approx = np.array([[x / 2 ** w for x in row] for row in E], dtype=float)
    ref = scipy.linalg.expm(np.array(Af, dtype=float) * float(Fraction(T)))
    assert err < Fraction(1, 10 ** 20)
    assert np.allclose(approx, ref, rtol=1e-11, atol=1e-11 * np.abs(ref).max())


def test_expm_enclosure_is_rigorous_for_exactly_known_exponentials():
    # nilpotent: exp(N T) = I + N T exactly
    N = fraction_matrix([[0, 3], [0, 0]])
    T = Fraction(7, 3)
    E, w, err = expm_enclosure(N, T, 64)
    exact = [[Fraction(1), 3 * T], [Fraction(0), Fraction(1)]]
    dev = max(sum(abs(Fraction(E[i][j], 2 ** w) - exact[i][j]) for j in range(2)) for i in range(2))
    assert dev <= err
    # scalar: exp(-5/2 * 3) against 50-digit mpmath
    E, w, err = expm_enclosure([[Fraction(-5, 2)]], Fraction(3), 96)
    with mpmath.workdps(50):
        true = mpmath.exp(mpmath.mpf(-15) / 2)
        assert abs(mpmath.mpf(E[0][0]) / 2 ** w - true) <= mpmath.mpf(err.numerator) / err.denominator


def test_factor_rows_gives_exact_lower_factor_with_the_same_range():
    W = fraction_matrix([["9/4", 0, 0], [0, 0, 0], [0, 0, 0]])
    C = factor_rows(W)
    assert len(C) == 1 and C[0][1] == C[0][2] == 0 and 0 < C[0][0] <= Fraction(3, 2)
    assert factor_rows(fraction_matrix([[1, 2], [2, 1]])) is None
    q = short_sqrt_lower(Fraction(2))
    assert q * q <= 2 < (q + Fraction(1, 2 ** 19)) ** 2


def test_range_basis_snaps_a_noisy_coordinate_face():
    v = np.array([1.0, 3e-5, -2e-5])
    basis = range_basis(np.outer(v, v) * 4.0 + 1e-10 * np.eye(3), 1e-5)
    assert basis == [[Fraction(1)], [Fraction(0)], [Fraction(0)]]


@settings(max_examples=25, deadline=None)
@given(st.integers(1, 4).flatmap(lambda n: st.tuples(
    st.lists(st.lists(st.fractions(max_denominator=50), min_size=n, max_size=n), min_size=n, max_size=n),
    st.lists(st.lists(st.fractions(max_denominator=2**20), min_size=n, max_size=n), min_size=n, max_size=n))))
def test_lyapunov_form_on_a_common_denominator_equals_fraction_arithmetic(AP):
    A, upper = AP
    n = len(A)
    P = [[upper[min(i, j)][max(i, j)] for j in range(n)] for i in range(n)]  # symmetric, as P is
    expected = [[sum(A[k][i] * P[k][j] + P[i][k] * A[k][j] for k in range(n)) for j in range(n)] for i in range(n)]
    got = lyapunov_form(A, P)
    assert got == expected
    assert all(type(x) is Fraction for row in got for x in row)


def test_lyapunov_form_keeps_integers_integer():
    got = lyapunov_form([[1, 2], [3, 4]], [[2, 1], [1, 2]])
    assert got == [[10, 15], [15, 20]]  # A' P = [[5, 7], [8, 10]] plus its transpose
    assert all(type(x) is int for row in got for x in row)


def _python_int_bareiss(M, strict):
    """The elimination as it was before python-flint: Python ints on d*M; (holds, failing index)."""
    from switchobs.exact import integer_form

    a, _ = integer_form([[Fraction(x) for x in row] for row in M])
    n, prev = len(a), 1
    for k in range(n):
        p = a[k][k]
        if p < 0 or (p == 0 and strict):
            return False, k
        if p == 0:
            if any(a[k][j] != 0 for j in range(k + 1, n)):
                return False, k
            continue
        for i in range(k + 1, n):
            for j in range(i, n):
                a[i][j] = a[j][i] = (p * a[i][j] - a[i][k] * a[k][j]) // prev
        prev = p
    return True, None


@pytest.mark.parametrize("seed", range(6))
def test_flint_elimination_decides_and_locates_as_the_python_int_elimination_did(seed):
    # random rationals of 20-digit numerators and denominators, positive definite, semidefinite with a kernel
    # (zero pivots), and indefinite: the same verdict and the same failing index as before
    rng = np.random.default_rng(seed)
    n = 12
    for rank_, shift in [(n, 0), (n - 3, 0), (n, -1)]:
        Y = [[Fraction(int(rng.integers(-10**9, 10**9)), int(rng.integers(1, 10**9))) for _ in range(rank_)]
             for _ in range(n)]
        M = [[sum((Y[i][k] * Y[j][k] for k in range(rank_)), Fraction(0)) + (shift if i == j == n // 2 else 0)
              for j in range(n)] for i in range(n)]
        for strict in (True, False):
            got = definiteness(M, strict=strict)
            assert (got.holds, got.index) == _python_int_bareiss(M, strict)
