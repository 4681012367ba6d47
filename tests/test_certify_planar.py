"""Balde–Boscain–Mason planar classification (seed 004), cross-checked against the LMIs and products of expm."""

from fractions import Fraction

import numpy as np
import pytest
import scipy.linalg
import sympy as sp
from _docs_blocks import assert_page_says
from hypothesis import given, settings
from hypothesis import strategies as st

from switchobs.certify import classify_planar, common_lyapunov, strict_common_lyapunov
from switchobs.exceptions import DimensionError, NotHurwitzError

LIBERZON = ([["-0.1", -1], [2, "-0.1"]], [["-0.1", -2], [1, "-0.1"]])   # unstable under fast switching
IV_STABLE = ([[-1, 2], [-1, -2]], [[-4, 5], [-3, 2]])                   # case iv with R < 1
IV_UNBOUNDED = ([[-3, 1], [-5, 1]], [[-1, 6], [-6, -3]])                # case iv with R > 1


def test_seed001_prop1_pair_is_case_ii_identically():
    """A+ = [[-k1,-a],[-k2,0]], A- = [[-k1,a],[k2,0]] (seed 001 eq. (3.16), (3.20)): Gamma = -sqrt(det det)."""
    k1, a = sp.symbols("k1 a", positive=True)
    k2 = sp.Symbol("k2", negative=True)
    Ap = sp.Matrix([[-k1, -a], [-k2, 0]])
    Am = sp.Matrix([[-k1, a], [k2, 0]])
    gamma = (Ap.trace() * Am.trace() - (Ap * Am).trace()) / 2
    assert sp.simplify(gamma + sp.sqrt(Ap.det() * Am.det())) == 0
    res = classify_planar([[-8, "-375/2"], ["2/25", 0]], [[-8, "375/2"], ["-2/25", 0]])
    assert res.case == "ii" and res.stability == "UGS-not-UGES"
    assert res.gamma == Fraction(-15) and res.det1 == res.det2 == Fraction(15)


def test_seed004_2d_example_is_case_ii_with_a_singular_sum_proof():
    """docs/certify.md, "Seed 004, 2D example": a = 187.5, c = 34, k+ = (60, -30), Theorem 1's k- = (8, -7714/375)."""
    A1, A2 = [[-60, "-375/2"], [30, 34]], [[8, "375/2"], ["-7714/375", -34]]
    res = classify_planar(A1, A2)
    assert res.case == "ii" and res.gamma == -3585 and res.det1 == res.det2 == 3585
    assert_page_says("certify.md", f"$\\Gamma = {res.gamma} = -\\sqrt{{{res.det1}\\cdot {res.det2}}}$")
    strict = strict_common_lyapunov([A1, A2])
    assert not strict.certified and strict.dual.kind == "singular-sum" and tuple(strict.dual.v) == (0, 1)


def test_case_i_gamma_below_minus_sqrt_det_product():
    res = classify_planar([[-1, -100], [10, -1]], [[-1, 10], [-100, -1]])
    assert res.case == "i" and res.stability == "unbounded"
    assert res.gamma < 0 and res.gamma ** 2 > res.det1 * res.det2


def test_case_iii_strict_cqlf_and_R_below_one():
    res = classify_planar([[-1, 2], [-3, -4]], [["-0.1", -2], [1, "-0.1"]])
    assert res.case == "iii" and res.strict_cqlf_exists and res.R < 1
    assert strict_common_lyapunov([[[-1, 2], [-3, -4]], [["-0.1", -2], [1, "-0.1"]]]).certified


@pytest.mark.parametrize("pair, stability, above_one", [(LIBERZON, "unbounded", True),
                                                        (IV_UNBOUNDED, "unbounded", True),
                                                        (IV_STABLE, "UGES", False)])
def test_case_iv_R_is_the_eigenvalue_of_the_worst_half_turn(pair, stability, above_one):
    res = classify_planar(*pair)
    assert res.case == "iv" and res.stability == stability and (res.R > 1) == above_one
    mats = [np.array([[float(Fraction(str(x))) for x in r] for r in M]) for M in pair]
    Phi = res.half_turn_product(mats)
    eig = np.linalg.eigvals(Phi)
    # the worst trajectory maps its starting ray to the opposite ray, scaled by R
    assert np.min(np.abs(eig + res.R)) < 1e-8 * max(res.R, 1)
    # no strict CQLF in case iv, proven exactly by the dual
    strict = strict_common_lyapunov(pair)
    assert not strict.certified and strict.dual is not None and strict.dual.certified


def test_case_iv_stable_pair_contracts_under_random_periodic_switching():
    res = classify_planar(*IV_STABLE)
    A1, A2 = (np.array(M, dtype=float) for M in IV_STABLE)
    rng = np.random.default_rng(0)
    for _ in range(200):
        t1, t2 = rng.exponential(0.3, 2)
        assert max(abs(np.linalg.eigvals(scipy.linalg.expm(A2 * t2) @ scipy.linalg.expm(A1 * t1)))) < 1
    assert res.R < 1
    assert_page_says("certify.md", f"A case (iv) pair with $R = {res.R:.3g}$")


@st.composite
def hurwitz_pair(draw):
    seed = draw(st.integers(0, 10 ** 6))
    rng = np.random.default_rng(seed)
    mats = []
    while len(mats) < 2:
        A = rng.integers(-6, 7, (2, 2))
        if A[0, 0] + A[1, 1] < 0 and A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0] > 0:
            mats.append(A.tolist())
    return mats


@settings(max_examples=20, deadline=None)
@given(hurwitz_pair())
def test_classification_agrees_with_the_strict_lmi(mats):
    res = classify_planar(*mats)
    strict = strict_common_lyapunov(mats)
    if res.case == "iii":
        assert strict.certified and res.R < 1
    else:
        assert not strict.certified
        assert strict.dual is not None and strict.dual.certified
    if res.stability == "unbounded":  # BBM (i) or (iv) with R > 1: not even a non-strict common P
        assert not common_lyapunov(mats).certified


def test_bad_input():
    with pytest.raises(DimensionError, match="2x2"):
        classify_planar([[-1, 0, 0], [0, -1, 0], [0, 0, -1]], [[-1, 0, 0], [0, -1, 0], [0, 0, -1]])
    with pytest.raises(NotHurwitzError, match=r"A2 is not Hurwitz .*spectrum \[-1, 1\]"):
        classify_planar([[-1, 0], [0, -1]], [[1, 0], [0, -1]])
    with pytest.raises(NotHurwitzError, match="A1 is not Hurwitz"):
        classify_planar([[0, 1], [-1, 0]], [[-1, 0], [0, -1]])
