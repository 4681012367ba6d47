"""Common quadratic Lyapunov functions: Hespanha (seed 000/004), strict CQLF and its exact dual."""

from fractions import Fraction

import cvxpy as cp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from switchobs.certify import (as_family, classify_planar, common_lyapunov, infeasibility_certificate,
                               singular_sum, strict_common_lyapunov, verify_certificate)
from switchobs import lmi
from switchobs.exact import definiteness, lyapunov_form, matmul, transpose
from switchobs.certify._verify import planar_case_exact
from switchobs.exceptions import DimensionError, ModelError, NotHurwitzError, SolverFailure

F = Fraction
A_RIG = F(375, 2)  # a = R^2 Fz / I = 0.09 * 2500 / 1.2 (seed 000 Fig. 2)
C_RIG = F(34)      # c = -c2 = 34 (seed 000 Fig. 2)
BETAS = [(10, 20), (40, 60), (50, 100), (5, 5), (100, 7)]


def xbs3_family(b1, b2, a=A_RIG, c=C_RIG):
    """Gains of seed 000 Sec. III-E, error matrices of eq. (13)."""
    b1, b2 = F(b1), F(b2)
    kp1 = c + (b1 + 2 * b2)
    kp = [kp1, -(b2 ** 2 + 2 * b1 * b2 + c * kp1) / a, -b1 * b2 ** 2 / a]
    km1 = c - (b1 + 2 * b2)
    km = [km1, -(b2 ** 2 + 2 * b1 * b2 + c * km1) / a, b1 * b2 ** 2 / a]
    Ap = [[-kp[0], -a, 0], [-kp[1], c, 1], [-kp[2], 0, 0]]
    Am = [[km[0], a, 0], [km[1], -c, -1], [km[2], 0, 0]]
    return Ap, Am, kp


def xbs4_family(b1, b2, a=A_RIG, alpha1=F(-1144), alpha2=F(74)):
    """Gains of seed 000 Sec. IV-D (d1 = 22, d2 = 52 give alpha1 = -1144, alpha2 = 74), matrices of Sec. IV-C."""
    b1, b2 = F(b1), F(b2)
    kp1 = alpha2 + 2 * (b1 + b2)
    kp2 = (-alpha1 - kp1 * alpha2 - (b1 ** 2 + b2 ** 2 + 4 * b1 * b2)) / a
    kp3 = (-kp1 * alpha1 + a * kp2 * alpha2 - 2 * b1 * b2 * (b1 + b2)) / a
    kp4 = -b1 ** 2 * b2 ** 2 / a
    km1 = alpha2 - 2 * (b1 + b2)
    km2 = (-alpha1 - km1 * alpha2 - (b1 ** 2 + b2 ** 2 + 4 * b1 * b2)) / a
    km3 = (-km1 * alpha1 + a * km2 * alpha2 + 2 * b1 * b2 * (b1 + b2)) / a
    km4 = -b1 ** 2 * b2 ** 2 / a
    Ap = [[-kp1, -a, 0, 0], [-kp2, 0, 1, 0], [-kp3, alpha1, alpha2, 1], [-kp4, 0, 0, 0]]
    Am = [[km1, a, 0, 0], [km2, 0, -1, 0], [km3, -alpha1, -alpha2, -1], [km4, 0, 0, 0]]
    return Ap, Am


@pytest.mark.parametrize("b1, b2", BETAS)
def test_hoang2014_eq24_xbs3_tu_delft_hespanha_certified(b1, b2):
    Ap, Am, kp = xbs3_family(b1, b2)
    res = common_lyapunov([Ap, Am], names=["A_plus", "A_minus"], output=[[1, 0, 0]])
    assert res.certified and res.P is not None
    # the LMI finds the unique common P of seed 000 eq. (24), up to p22
    P = [[x / res.P[1][1] for x in row] for row in res.P]
    a, c = A_RIG, C_RIG
    expected = [[(c ** 2 - (c * kp[0] + a * kp[1])) / a ** 2, c / a, 1 / a],
                [c / a, 1, 0],
                [1 / a, 0, (c - kp[0]) / (a * kp[2])]]
    assert P == expected
    # C_plus, C_minus are multiples of C = (1 0 0) (eq. (25), (28))
    for C in res.C:
        assert len(C) == 1 and C[0][0] > 0 and C[0][1] == C[0][2] == 0


@pytest.mark.parametrize("b1, b2", BETAS[:3])
def test_hoang2014_sec4d_xbs4_tu_delft_hespanha_certified(b1, b2):
    Ap, Am = xbs4_family(b1, b2)
    res = common_lyapunov([Ap, Am], names=["A_plus", "A_minus"], output=[[1, 0, 0, 0]])
    assert res.certified
    assert definiteness(res.P, strict=True).holds
    for A, C in zip((Ap, Am), res.C):
        W = lyapunov_form([[F(x) for x in r] for r in A], res.P)
        CtC = matmul(transpose(C), C)
        assert definiteness([[-(W[i][j] + CtC[i][j]) for j in range(4)] for i in range(4)], strict=False).holds
        # non-strict: A' P + P A is exactly -gamma C' C with C = e1', so it is singular
        assert not definiteness([[-x for x in r] for r in W], strict=True).holds
        assert [row[1:] for row in C] == [[0, 0, 0]] * len(C)


@pytest.mark.parametrize("b1, b2", [(10, 20), (50, 100)])
def test_hoang2014_xbs_theorem1_pairs_have_no_strict_cqlf(b1, b2):
    for fam in (xbs3_family(b1, b2)[:2], xbs4_family(b1, b2)):
        res = strict_common_lyapunov(list(fam), names=["A_plus", "A_minus"])
        assert not res.certified and res.dual is not None and res.dual.certified
        assert res.dual.kind == "singular-sum" and res.solver is None      # decided exactly, without an LMI
        lmi = infeasibility_certificate(list(fam), names=["A_plus", "A_minus"])   # the LMI dual agrees
        assert lmi.certified and lmi.kind == "no-strict-cqlf"


def seed004_planar_example(k1, k2, a=A_RIG, c=C_RIG):
    """seed 004 'two-dimensional example': A1 = [[-k1+, -a], [-k2+, c]], A2 = [[k1-, a], [k2-, -c]].

    K- is Theorem 1's for the pair (A, C) = ([[0, -a], [0, c]], (1 0)), derived in the model's
    coordinates: equal spectra give k1- = 2c - k1+, k2- = k2+ + 2 c (k1+ - c) / a (the unique K- of
    Theorem 1; with c = 0 this is seed 001 Proposition 1, k1- = -k1+, k2- = k2+).
    """
    k1, k2 = F(k1), F(k2)
    km1 = 2 * c - k1
    km2 = k2 + 2 * c * (k1 - c) / a
    return [[-k1, -a], [-k2, c]], [[km1, a], [km2, -c]]


@pytest.mark.parametrize("k1, k2, c", [(84, F(-7312, 375), C_RIG), (60, -30, C_RIG), (8, F(-2, 25), 0),
                                       (3, -1, 0)])
def test_seed004_2d_example_has_no_strict_cqlf(k1, k2, c):
    A1, A2 = seed004_planar_example(k1, k2, c=c)
    assert classify_planar(A1, A2).case == "ii"  # Gamma = -sqrt(det A1 det A2) exactly
    res = strict_common_lyapunov([A1, A2])
    assert not res.certified and not res.feasible
    assert res.dual is not None and res.dual.certified and res.dual.kind == "singular-sum"
    assert res.dual.v == (0, 1)                                          # the kernel of C = (1 0)
    assert strict_common_lyapunov([A1, A2], dual=False).margin < 1e-7   # the LMI finds no strict P either
    hesp = common_lyapunov([A1, A2], output=[[1, 0]])
    assert hesp.certified


@pytest.mark.parametrize("n", [2, 3, 5])
def test_theorem1_dual_certificate_R_equals_e2e2_in_any_dimension(n):
    """In normal form A_minus = D A_plus D (D = diag(1,-1,1,...)); its even part kills e2, so R_p = e2 e2'."""
    rng = np.random.default_rng(n)
    roots = -rng.integers(1, 6, n)
    coeffs = np.poly(roots)[1:]  # s^n + c1 s^(n-1) + ...
    Ap = [[F(int(-coeffs[i])) if j == 0 else F(int(j == i + 1)) for j in range(n)] for i in range(n)]
    D = [(-1) ** i for i in range(n)]
    Am = [[Ap[i][j] * D[i] * D[j] for j in range(n)] for i in range(n)]
    R = [[F(int(i == j == 1)) for j in range(n)] for i in range(n)]
    doc = {"format": "switchobs-certificate", "version": 1,
           "family": {"names": ["A_plus", "A_minus"], "matrices": [Ap, Am]},
           "certificates": [{"kind": "no-strict-cqlf", "R": [R, R]}],
           "verdict": {"arbitrary_switching": "unknown", "dwell_time": None, "strict_cqlf": "none",
                       "common_lyapunov": "unknown"}}
    assert verify_certificate(doc).holds
    res = strict_common_lyapunov([Ap, Am])
    assert not res.certified and res.dual.v == tuple(int(i == 1) for i in range(n))   # R_p = v v' = e2 e2'


def _planted(n: int, count: int = 2, seed: int = 0) -> tuple[list[np.ndarray], np.ndarray]:
    rng = np.random.default_rng(seed)
    G = rng.integers(-3, 4, (n, n))
    P = G @ G.T + n * np.eye(n, dtype=int)
    Pinv = np.linalg.inv(P)
    mats = []
    for _ in range(count):
        S = rng.integers(-4, 5, (n, n))
        Q = rng.integers(-2, 3, (n, n))
        Q = Q @ Q.T + np.eye(n, dtype=int)
        mats.append(Pinv @ ((S - S.T) - Q / 2))  # A' P + P A = -Q
    return mats, P


@st.composite
def planted_family(draw):
    return _planted(draw(st.integers(2, 5)), draw(st.integers(2, 3)), draw(st.integers(0, 10 ** 6)))


@settings(max_examples=20, deadline=None)
@given(planted_family())
def test_random_pairs_with_a_planted_common_P_are_certified(data):
    mats, _ = data
    strict = strict_common_lyapunov(mats)
    hesp = common_lyapunov(mats)
    assert strict.certified and hesp.certified
    # the exact certificate holds for the matrices as given (floats taken exactly)
    fam = as_family(mats)
    for A in fam.exact:
        W = lyapunov_form(A, strict.P)
        assert definiteness([[-x for x in r] for r in W], strict=True).holds


@st.composite
def unbounded_planar_pair(draw):
    """Random Hurwitz 2x2 pairs in Balde-Boscain-Mason case (i) (Gamma < -sqrt(det A1 det A2))."""
    seed = draw(st.integers(0, 10 ** 6))
    rng = np.random.default_rng(seed)
    while True:
        mats = []
        while len(mats) < 2:
            A = rng.integers(-9, 10, (2, 2))
            if A[0, 0] + A[1, 1] < 0 and A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0] > 0:
                mats.append(A.tolist())
        if planar_case_exact(*[as_family([M], hurwitz=False).exact[0] for M in mats]) == "i":
            return mats


@settings(max_examples=15, deadline=None)
@given(unbounded_planar_pair())
def test_pairs_with_unbounded_trajectories_are_never_certified(mats):
    strict = strict_common_lyapunov(mats)
    hesp = common_lyapunov(mats)
    assert not strict.certified and not hesp.certified
    assert strict.dual is not None and strict.dual.certified  # and infeasibility is proven


def test_infeasibility_certificate_excludes_even_non_strict_P_for_case_i():
    A1 = [[-1, -100], [10, -1]]
    A2 = [[-1, 10], [-100, -1]]
    assert classify_planar(A1, A2).case == "i"
    d = infeasibility_certificate([A1, A2])
    assert d.certified and d.kind == "no-common-lyapunov" and d.margin > 0
    R = d.R
    S = [[sum(matmul(A, Rp)[i][j] + matmul(A, Rp)[j][i] for A, Rp in zip(as_family([A1, A2]).exact, R))
          for j in range(2)] for i in range(2)]
    assert definiteness(S, strict=False).holds and any(x != 0 for row in S for x in row)


def test_bad_input_is_named():
    with pytest.raises(DimensionError, match="not square"):
        strict_common_lyapunov([[[1, 2, 3], [4, 5, 6]]])
    with pytest.raises(DimensionError, match="same size"):
        strict_common_lyapunov([[[-1, 0], [0, -1]], [[-1]]])
    with pytest.raises(ModelError, match=r"A_2\[1\]\[2\].*not finite"):
        strict_common_lyapunov([[[-1, 0], [0, -1]], [[-1, float("nan")], [0, -1]]])
    with pytest.raises(ModelError, match="not finite"):
        common_lyapunov([[[-1, float("inf")], [0, -1]]])
    with pytest.raises(NotHurwitzError, match=r"A_minus is not Hurwitz: its spectrum is \[-1, 2\]"):
        common_lyapunov([[[-1, 0], [0, -1]], [[-1, 0], [0, 2]]], names=["A_plus", "A_minus"])
    with pytest.raises(DimensionError, match="empty"):
        common_lyapunov([])


def test_solver_failure_is_reported_not_certified(monkeypatch):
    def broken(self, *args, **kwargs):
        raise cp.SolverError("simulated breakdown")

    monkeypatch.setattr(cp.Problem, "solve", broken)
    with pytest.raises(SolverFailure, match="CLARABEL: error .*simulated breakdown.*SCS: error"):
        strict_common_lyapunov([[[-1, 0], [0, -2]]])


def test_garbage_solution_is_never_certified(monkeypatch):
    """A solver that claims a large margin with a wrong P: the exact check refuses it."""
    info = lmi.SolveInfo("FAKE", "optimal", ("FAKE: optimal",), 0.0, 0.0)

    def fake_margin(mats, H, **kwargs):
        return np.array([[1.0, 0.0], [0.0, -1.0]]), 0.5, info

    monkeypatch.setattr("switchobs.certify._lyapunov.primal_margin", fake_margin)
    A1, A2 = [[-1, -100], [10, -1]], [[-1, 10], [-100, -1]]
    strict = strict_common_lyapunov([A1, A2], dual=False)
    hesp = common_lyapunov([A1, A2], dual=False)
    assert strict.feasible and not strict.certified and "P > 0 fails" in strict.detail
    assert hesp.feasible and not hesp.certified


def test_inaccurate_solves_fall_back_and_are_still_checked_exactly(monkeypatch):
    original = cp.Problem.solve

    def inaccurate(self, *args, **kwargs):
        out = original(self, *args, **kwargs)
        self._status = cp.OPTIMAL_INACCURATE
        return out

    monkeypatch.setattr(cp.Problem, "solve", inaccurate)
    res = strict_common_lyapunov([[[-1, 2], [0, -3]], [[-2, 0], [1, -1]]])
    assert res.solver.status == "optimal_inaccurate"
    assert res.solver.attempts == ("CLARABEL: optimal_inaccurate", "SCS: optimal_inaccurate")
    assert res.certified == _strict_holds(res)


def _strict_holds(res):
    return res.P is not None and all(
        definiteness([[-x for x in r] for r in lyapunov_form(A, res.P)], strict=True).holds
        for A in res.family.exact)


def test_default_solver_order_follows_the_measured_cross_over():
    assert lmi.by_size(lmi.DEFAULT_SOLVERS, lmi.SCS_FIRST_FROM_N - 1) == ("CLARABEL", "SCS")
    assert lmi.by_size(lmi.DEFAULT_SOLVERS, lmi.SCS_FIRST_FROM_N) == ("SCS", "CLARABEL")
    assert lmi.by_size(["CLARABEL"], 64) == ("CLARABEL",)  # an explicit choice is kept
    assert lmi.by_size(("SCS", "CLARABEL"), 2) == ("SCS", "CLARABEL")


def test_a_large_planted_pair_is_certified_exactly_with_scs_first():
    n = lmi.SCS_FIRST_FROM_N
    mats, _ = _planted(n, seed=n)
    res = strict_common_lyapunov(mats, dual=False)
    assert res.certified and res.solver.solver == "SCS"
    for A in as_family(mats).exact:
        assert definiteness([[-x for x in r] for r in lyapunov_form(A, res.P)], strict=True).holds


def _singular_sum_doc(As, v, strict_cqlf="none"):
    return {"format": "switchobs-certificate", "version": 1,
            "family": {"names": [f"A_{i + 1}" for i in range(len(As))], "matrices": As},
            "certificates": [{"kind": "singular-sum", "v": v}],
            "verdict": {"arbitrary_switching": "unknown", "dwell_time": None, "strict_cqlf": strict_cqlf,
                        "common_lyapunov": "unknown"}}


def test_singular_sum_certificate_is_checked_exactly_and_tampering_fails():
    A1, A2 = [["-1", "-1"], ["1", "0"]], [["-1", "1"], ["-1", "0"]]   # A1 + A2 = [[-2, 0], [0, 0]]
    cert = singular_sum([A1, A2])
    assert cert.v == (0, 1) and cert.certificate().to_json() == {"kind": "singular-sum", "v": ["0", "1"],
                                                                 "method": "exact kernel of sum_p A_p"}
    assert verify_certificate(_singular_sum_doc([A1, A2], ["0", "1"])).holds
    assert verify_certificate(_singular_sum_doc([A1, A2], ["0", "-7/3"])).holds        # any kernel vector
    for v, reason in ((["1", "0"], "entry 1 is nonzero"), (["0", "0"], "v is zero")):
        rep = verify_certificate(_singular_sum_doc([A1, A2], v))
        check = next(c for c in rep.checks if c.name == "singular-sum")
        assert not rep.holds and reason in check.detail
    wrong_claim = verify_certificate(_singular_sum_doc([A1, A2], ["0", "1"], strict_cqlf="exists"))
    assert not wrong_claim.holds and "strict_cqlf" in wrong_claim.checks[-1].detail


def test_singular_sum_is_none_for_a_nonsingular_sum():
    assert singular_sum([[[-1, 2], [-3, -4]], [[-2, 0], [1, -1]]]) is None
