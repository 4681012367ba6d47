"""Property tests of the design core over random observable systems (hypothesis, exact arithmetic)."""

import control
import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from switchobs.design import design
from switchobs.model import Model

SETTINGS = settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])

small_int = st.integers(min_value=-4, max_value=4)
negative_rational = st.fractions(min_value=-6, max_value=-1, max_denominator=4)


@st.composite
def hurwitz_spectrum(draw, n):
    """Rational Hurwitz spectra with repeated poles and conjugate pairs."""
    poles = []
    while len(poles) < n:
        if n - len(poles) >= 2 and draw(st.booleans()):
            re, im = draw(negative_rational), draw(st.fractions(min_value=1, max_value=4, max_denominator=3))
            poles += [sp.Rational(re.numerator, re.denominator) + sp.I * sp.Rational(im.numerator, im.denominator),
                      sp.Rational(re.numerator, re.denominator) - sp.I * sp.Rational(im.numerator, im.denominator)]
        else:
            p = draw(negative_rational)
            poles += [sp.Rational(p.numerator, p.denominator)] * draw(st.integers(1, min(2, n - len(poles))))
    return poles


@st.composite
def observable_system(draw, coordinates):
    n = draw(st.integers(2, 6))
    a = [draw(small_int) for _ in range(n)]
    A = sp.Matrix(n, n, lambda i, j: a[i] if j == 0 else (1 if j == i + 1 else 0))
    C = sp.Matrix([[1] + [0] * (n - 1)])
    if coordinates == "random":
        while True:  # random rational change of coordinates z_model = S z_nf
            S = sp.Matrix(n, n, lambda i, j: draw(small_int) if i != j else draw(st.integers(1, 3)))
            if S.det() != 0:
                break
        A, C = S * A * S.inv(), C * S.inv()
    return n, A, C


def to_model(A: sp.Matrix, C: sp.Matrix) -> Model:
    n = A.rows
    return Model.from_dict({"name": "random", "states": [f"x{i}" for i in range(n)],
                            "A": [[str(A[i, j]) for j in range(n)] for i in range(n)],
                            "C": [str(c) for c in C], "time_scale": "y"})


def sylvester_positive(P: sp.Matrix) -> bool:
    return all(P[:k, :k].det() > 0 for k in range(1, P.rows + 1))


def check_design(A, C, spectrum):
    d = design(to_model(A, C), [str(p) for p in spectrum])
    s = sp.Symbol("s")
    target = sp.expand(sp.prod([s - p for p in spectrum]))
    assert sp.expand(d.A_plus.charpoly(s).as_expr() - target) == 0
    assert sp.expand(d.A_minus.charpoly(s).as_expr() - target) == 0
    for A_p, C_p in ((d.A_plus, d.C_plus), (d.A_minus, d.C_minus)):
        residual = A_p.T * d.P + d.P * A_p + C_p.T * C_p
        assert residual.applyfunc(sp.nsimplify).is_zero_matrix
    assert d.P.is_symmetric()
    assert sylvester_positive(sp.Matrix(d.P))
    assert all(d.verify().values())


@SETTINGS
@given(data=st.data())
def test_theorem1_certificate_random_normal_form(data):
    n, A, C = data.draw(observable_system("normal"))
    check_design(A, C, data.draw(hurwitz_spectrum(n)))


@SETTINGS
@given(data=st.data())
def test_theorem1_certificate_random_coordinates(data):
    n, A, C = data.draw(observable_system("random"))
    check_design(A, C, data.draw(hurwitz_spectrum(n)))


@pytest.mark.parametrize("seed", range(6))
def test_K_plus_agrees_with_control_place_and_acker(seed):
    """Observer gains by duality: place(A', C', poles)' (python-control) equals our K_plus."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 6))
    while True:
        A = sp.Matrix(n, n, lambda i, j: int(rng.integers(-3, 4)))
        C = sp.Matrix([[int(rng.integers(-2, 3)) for _ in range(n)]])
        if sp.Matrix.vstack(*[C * A**k for k in range(n)]).det() != 0:
            break
    poles = [-float(k) for k in rng.choice(np.arange(1, 12), size=n, replace=False)]
    d = design(to_model(A, C), [str(int(p)) for p in poles])
    ours = np.array(d.K_plus, dtype=float).reshape(-1)
    An, Cn = np.array(A, dtype=float), np.array(C, dtype=float)
    placed = control.place(An.T, Cn.T, poles).reshape(-1)
    acker = np.asarray(control.acker(An.T, Cn.T, poles)).reshape(-1)
    np.testing.assert_allclose(ours, placed, rtol=1e-6, atol=1e-6 * max(1.0, np.abs(ours).max()))
    np.testing.assert_allclose(ours, acker, rtol=1e-6, atol=1e-6 * max(1.0, np.abs(ours).max()))
    np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(An - np.outer(ours, Cn))),
                               np.sort_complex(np.array(poles, dtype=complex)), atol=1e-6)
