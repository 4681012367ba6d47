"""Reproductions of the seeds' design equations, each compared exactly (simplify(x - y) == 0)."""

import pytest
import sympy as sp

from switchobs.design import design, observer_normal_form
from switchobs.model import builtin_model

b1, b2 = sp.symbols("beta1 beta2", positive=True)


def zero(expr) -> bool:
    if isinstance(expr, sp.MatrixBase):
        return all(sp.simplify(x) == 0 for x in expr)
    return sp.simplify(expr) == 0


@pytest.fixture(scope="module")
def xbs3():
    return builtin_model("abs-xbs3")


@pytest.fixture(scope="module")
def xbs3_symbols(xbs3):
    return [xbs3.symbols[k] for k in ("a", "c")]


@pytest.fixture(scope="module")
def xbs3_generic(xbs3):
    """K_plus = (k1, k2, k3) symbolic, K_minus = (m1, m2, m3) symbolic (Hoang family, conditional)."""
    return design(xbs3, K_plus="k1,k2,k3", K_minus="m1,m2,m3")


def gains(names):
    return sp.symbols(names, real=True)


def test_hoang2014_eq7_observability_iff_a_nonzero(xbs3):
    nf = observer_normal_form(xbs3)
    a = xbs3.symbols["a"]
    assert len(nf.observability_conditions) == 1
    cond = nf.observability_conditions[0]
    assert isinstance(cond, sp.Ne) and zero(cond.lhs - a) and cond.rhs == 0


def test_hoang2014_sec3e_beta_gains_plus_and_minus(xbs3, xbs3_symbols):
    a, c = xbs3_symbols
    d = design(xbs3, "-beta1,-beta2,-beta2")
    k1p = c + (b1 + 2 * b2)
    expected_plus = [k1p, -(b2**2 + 2 * b1 * b2 + c * k1p) / a, -b1 * b2**2 / a]
    k1m = c - (b1 + 2 * b2)
    expected_minus = [k1m, -(b2**2 + 2 * b1 * b2 + c * k1m) / a, b1 * b2**2 / a]
    assert all(zero(x - y) for x, y in zip(d.K_plus, expected_plus))
    assert all(zero(x - y) for x, y in zip(d.K_minus, expected_minus))


def test_hoang2014_sec3e_same_spectrum_plus_minus(xbs3):
    d = design(xbs3, "-beta1,-beta2,-beta2")
    s = sp.Symbol("s")
    target = (s + b1) * (s + b2) ** 2
    assert zero(d.A_plus.charpoly(s).as_expr() - target)
    assert zero(d.A_minus.charpoly(s).as_expr() - target)


def test_hoang2014_eq13_error_matrices(xbs3, xbs3_generic, xbs3_symbols):
    a, c = xbs3_symbols
    k1, k2, k3 = gains("k1 k2 k3")
    m1, m2, m3 = gains("m1 m2 m3")
    assert zero(xbs3_generic.A_plus - sp.Matrix([[-k1, -a, 0], [-k2, c, 1], [-k3, 0, 0]]))
    assert zero(xbs3_generic.A_minus - sp.Matrix([[m1, a, 0], [m2, -c, -1], [m3, 0, 0]]))


def test_hoang2014_eq23_characteristic_polynomial(xbs3_generic, xbs3_symbols):
    a, c = xbs3_symbols
    k1, k2, k3 = gains("k1 k2 k3")
    eta = sp.Symbol("s")
    eq23 = eta**3 + (k1 - c) * eta**2 - (c * k1 + a * k2) * eta - a * k3
    assert zero(xbs3_generic.characteristic_polynomial("plus") - eq23)


def _same_inequality(ours, lhs_minus_rhs):
    """ours is a relational equivalent to lhs_minus_rhs > 0 (same boundary, positive factor)."""
    ours_g = ours.lhs - ours.rhs if isinstance(ours, sp.StrictGreaterThan) else ours.rhs - ours.lhs
    ratio = sp.simplify(ours_g / lhs_minus_rhs)
    return ratio.is_positive is True


def _match_all(ours, paper):
    assert len(ours) == len(paper)
    for g in paper:
        assert any(_same_inequality(o, g) for o in ours), f"no condition of ours matches {g} > 0"


def test_hoang2014_eq15_routh_plus(xbs3_generic, xbs3_symbols):
    a, c = xbs3_symbols
    k1, k2, k3 = gains("k1 k2 k3")
    eq15 = [k1 - c, -c * k1 / a - k2, -k3, k3 + (c * k1 + a * k2) * (c - k1) / a]
    _match_all(xbs3_generic.hurwitz_plus, eq15)


def test_hoang2014_eq16_routh_minus(xbs3_generic, xbs3_symbols):
    a, c = xbs3_symbols
    m1, m2, m3 = gains("m1 m2 m3")
    eq16 = [c - m1, -c * m1 / a - m2, m3, -(c * m1 + a * m2) * (c - m1) / a - m3]
    _match_all(xbs3_generic.hurwitz_minus, eq16)


def test_hoang2014_eq17_coupling_constraints(xbs3, xbs3_symbols):
    """Our family constraints and (17) define the same K_minus on the Hurwitz set (k3- != 0)."""
    a, c = xbs3_symbols
    k1, k2, k3 = gains("k1 k2 k3")
    d = design(xbs3, K_plus=[k1, k2, k3])
    km1, km2, km3 = d.family_symbols
    # (17) solved for k1-, k2- given a free k3-:
    sol17 = {km1: c - (c - k1) * km3 / k3}
    sol17[km2] = (c * k1 + a * k2 - c * sol17[km1]) / a
    for constraint in d.gain_constraints:
        assert zero(constraint.lhs.subs(sol17) - constraint.rhs)
    # and conversely: every solution of ours with k3- != 0 satisfies (17)
    sols = sp.solve([cst.lhs for cst in d.gain_constraints], [km1, km2], dict=True)
    sols = [s for s in sols if s]
    assert sols
    for s in sols:
        assert zero((c - s[km1]) / (a * km3) - (c - k1) / (a * k3))
        assert zero((c * k1 + a * k2) - (c * s[km1] + a * s[km2]))


def test_hoang2014_eq24_lyapunov_plus_entries(xbs3_generic, xbs3_symbols):
    a, c = xbs3_symbols
    k1, k2, k3 = gains("k1 k2 k3")
    P = xbs3_generic.P
    p22 = P[1, 1]
    assert zero(P[0, 0] - (c**2 - (c * k1 + a * k2)) / a**2 * p22)
    assert zero(P[0, 1] - c / a * p22)
    assert zero(P[0, 2] - p22 / a)
    assert P[1, 2] == 0
    assert zero(P[2, 2] - (c - k1) / (a * k3) * p22)


def test_hoang2014_eq25_output_scale_plus(xbs3_generic, xbs3_symbols):
    """(25): c1+^2 = 2 ((c - k1)(c k1 + a k2) + a k3) p22 / a^2; our C_plus = C, so c1+ = 1."""
    a, c = xbs3_generic.model.symbols["a"], xbs3_generic.model.symbols["c"]
    k1, k2, k3 = gains("k1 k2 k3")
    p22 = xbs3_generic.P[1, 1]
    c1_plus = xbs3_generic.C_plus[0]
    assert zero(c1_plus**2 - 2 * ((c - k1) * (c * k1 + a * k2) + a * k3) / a**2 * p22)


def test_hoang2014_eq26_eq28_lyapunov_minus(xbs3, xbs3_symbols):
    """With K_minus in the family (17), P also has the form (26) and C_minus obeys (28)."""
    a, c = xbs3_symbols
    k1, k2, k3, m3 = gains("k1 k2 k3 m3")
    m1 = c - (c - k1) * m3 / k3
    m2 = (c * k1 + a * k2 - c * m1) / a
    d = design(xbs3, K_plus=[k1, k2, k3], K_minus=[m1, m2, m3])
    P = d.P
    p22 = P[1, 1]
    assert zero(P[0, 0] - (c**2 - (c * m1 + a * m2)) / a**2 * p22)
    assert zero(P[2, 2] - (c - m1) / (a * m3) * p22)
    assert zero(d.C_minus[0] ** 2 + 2 * ((c - m1) * (c * m1 + a * m2) + a * m3) / a**2 * p22)
    residual = d.A_minus.T * P + P * d.A_minus + d.C_minus.T * d.C_minus
    assert all(zero(x) for x in residual)


def test_hoang2014_sec4d_beta_gains_plus_and_minus():
    m = builtin_model("abs-xbs4")
    a, al1, al2 = (m.symbols[k] for k in ("a", "alpha1", "alpha2"))
    d = design(m, "-beta1,-beta1,-beta2,-beta2")

    def paper(sign):
        k1 = al2 + sign * 2 * (b1 + b2)
        k2 = (-al1 - k1 * al2 - (b1**2 + b2**2 + 4 * b1 * b2)) / a
        k3 = (-k1 * al1 + a * k2 * al2 - sign * 2 * b1 * b2 * (b1 + b2)) / a
        k4 = -(b1**2) * b2**2 / a
        return [k1, k2, k3, k4]

    assert all(zero(x - y) for x, y in zip(d.K_plus, paper(+1)))
    assert all(zero(x - y) for x, y in zip(d.K_minus, paper(-1)))
    assert all(d.verify().values())


def test_aguado2020_prop1_eq320_gains_and_conditions():
    m = builtin_model("abs-adaptive2")
    a = m.symbols["a"]
    k1, k2 = gains("k1 k2")
    d = design(m, K_plus=[k1, k2])
    assert zero(d.K_minus[0] + k1) and zero(d.K_minus[1] - k2)  # k1- = -k1+, k2- = k2+
    # Hurwitz iff k1+ > 0 and k2+ < 0 (a > 0), as in (3.20)
    _match_all(d.hurwitz_plus, [k1, -k2])
    assert all(d.verify().values())
    # P+ = P-: one P solves both equations with C_plus = C_minus = C
    assert list(d.C_plus) == list(d.C_minus) == [1, 0]
    # the proof's characteristic polynomials, l^2 + k1+ l - a k2+ and l^2 - k1- l - a k2-: with a > 0 (declared,
    # a = R^2 Fz / J) their coefficients are positive exactly under (3.20)
    lam = sp.Symbol("lambda")
    assert a.is_positive
    assert zero(d.A_plus.charpoly(lam).as_expr() - (lam ** 2 + k1 * lam - a * k2))
    assert zero(d.A_minus.charpoly(lam).as_expr() - (lam ** 2 - d.K_minus[0] * lam - a * d.K_minus[1]))


@pytest.mark.parametrize("n", [2, 3, 4, 5])
def test_pasillas_theorem1_normal_form_formula(n):
    """k_i^- = (-1)^i k_i^+ + (1 - (-1)^i) a_i, A_minus = D A_plus D, checkerboard P (seed 004 Thm 1)."""
    m = builtin_model(f"normal-form-{n}")
    k = gains(" ".join(f"k{i}" for i in range(1, n + 1)))
    d = design(m, K_plus=list(k))
    a = [m.symbols[f"a{i}"] for i in range(1, n + 1)]
    for i in range(1, n + 1):
        assert zero(d.K_minus[i - 1] - ((-1) ** i * k[i - 1] + (1 - (-1) ** i) * a[i - 1]))
    D = sp.diag(*[(-1) ** i for i in range(n)])
    assert zero(D * d.A_plus * D - d.A_minus)
    assert all(d.P[i, j] == 0 for i in range(n) for j in range(n) if (i + j) % 2)
    assert all(d.verify().values())
