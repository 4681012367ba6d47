"""Numeric designs stay numeric: exact rational arithmetic, no symbolic determinant (issue 12)."""

from __future__ import annotations

import io

import numpy as np
import pytest
import sympy as sp

from switchobs._progress import listening
from switchobs.exact import definiteness
from switchobs.cli.main import stderr_progress
from switchobs.design import design, hurwitz_conditions, observer_normal_form
from switchobs.design._routh import routh_first_column
from switchobs.exceptions import CertificateError
from switchobs.model import Model, builtin_model, parse_expression, rational_value


def _random_model(n: int, rng: np.random.Generator) -> Model:
    """An observable (A, C) with small rational entries, in no particular coordinates."""
    while True:
        A = [[str(sp.Rational(int(rng.integers(-4, 5)), int(rng.integers(1, 4)))) for _ in range(n)] for _ in range(n)]
        C = [str(int(rng.integers(-2, 3))) for _ in range(n)]
        Am, Cm = sp.Matrix(A).applyfunc(sp.Rational), sp.Matrix([C]).applyfunc(sp.Rational)
        O = sp.Matrix.vstack(*[Cm * Am**k for k in range(n)])
        if O.rank() == n:
            return Model.from_dict({"name": f"random-{n}", "states": [f"x{i}" for i in range(n)], "A": A, "C": C,
                                    "time_scale": "y"})


def _random_spectrum(n: int, rng: np.random.Generator) -> list[sp.Expr]:
    poles: list[sp.Expr] = []
    while len(poles) < n:
        re = -sp.Rational(int(rng.integers(1, 9)), int(rng.integers(1, 3)))
        if n - len(poles) >= 2 and rng.random() < 0.4:
            im = sp.Rational(int(rng.integers(1, 5)), 2)
            poles += [re + sp.I * im, re - sp.I * im]
        else:
            poles += [re] * (2 if n - len(poles) >= 2 and rng.random() < 0.2 else 1)
    return poles


def _ackermann(A: sp.Matrix, C: sp.Matrix, poles: list[sp.Expr]) -> sp.Matrix:
    """Observer Ackermann: ``K = phi(A) O^-1 e_n`` with ``phi`` the target polynomial."""
    n = A.rows
    s = sp.Symbol("s")
    coeffs = sp.Poly(sp.expand(sp.Mul(*[(s - p) for p in poles])), s).all_coeffs()
    phi = sp.zeros(n, n)
    for c in coeffs:  # Horner
        phi = phi * A + sp.expand(c) * sp.eye(n)
    O = sp.Matrix.vstack(*[C * A**k for k in range(n)])
    return phi * O.LUsolve(sp.Matrix([0] * (n - 1) + [1]))


@pytest.mark.parametrize("n", [2, 3, 4, 5, 7, 10, 16])
def test_numeric_design_is_ackermann_theorem1_and_exact_P(n):
    rng = np.random.default_rng(100 + n)
    model = _random_model(n, rng)
    poles = _random_spectrum(n, rng)
    d = design(model, poles)
    A, C = sp.Matrix(model.A), sp.Matrix(model.C)
    assert d.K_plus == sp.ImmutableMatrix(_ackermann(A, C, poles))
    # Theorem 1 (seed 004) in normal form: k_i^- = (-1)^i k_i^+ + (1 - (-1)^i) a_i
    nf = observer_normal_form(model)
    kp, km = nf.T * d.K_plus, nf.T * d.K_minus
    for i in range(1, n + 1):
        assert km[i - 1] == (-1)**i * kp[i - 1] + (1 - (-1)**i) * nf.a[i - 1]
    assert d.hurwitz_plus == () and d.gain_constraints == ()
    assert all(d.verify().values())
    assert all(x.is_Rational for x in d.P)
    assert definiteness([[x for x in d.P.row(i)] for i in range(n)], strict=True).holds


@pytest.mark.parametrize("n", [2, 3, 4, 5, 6])
def test_numeric_design_equals_the_symbolic_design_at_the_same_numbers(n):
    rng = np.random.default_rng(n)
    generic = builtin_model(f"normal-form-{n}")
    values = {f"a{i}": sp.Rational(int(rng.integers(-5, 6)), int(rng.integers(1, 4))) for i in range(1, n + 1)}
    poles = _random_spectrum(n, rng)
    symbolic = design(generic, poles, coupling=False).at(values)
    numeric = design(generic.with_values(values), poles)
    for name in ("K_plus", "K_minus", "P", "A_plus", "A_minus"):
        assert getattr(numeric, name) == getattr(symbolic, name).applyfunc(sp.cancel), name


def test_numeric_design_in_other_coordinates_equals_the_symbolic_one():
    xbs3 = builtin_model("abs-xbs3")
    symbolic = design(xbs3, "-40,-60,-60").at({})
    numeric = design(xbs3.numeric(), "-40,-60,-60")
    for name in ("K_plus", "K_minus", "P"):
        assert getattr(numeric, name) == getattr(symbolic, name).applyfunc(sp.cancel), name


def test_routh_array_agrees_with_the_hurwitz_determinants():
    rng = np.random.default_rng(7)
    for _ in range(200):
        n = int(rng.integers(1, 8))
        alpha = [sp.Rational(int(rng.integers(-3, 30)), int(rng.integers(1, 5))) for _ in range(n)]
        column = routh_first_column(alpha)
        by_routh = len(column) == n + 1 and all(x > 0 for x in column)
        assert by_routh == all(g > 0 for g in hurwitz_conditions(alpha)), alpha


def _fraction_routh(alpha):
    """The rational Routh array, the textbook way, in Fractions."""
    from fractions import Fraction

    coeff = [Fraction(1), *(Fraction(str(a)) for a in alpha)]
    width = len(alpha) // 2 + 2
    prev, cur = (coeff[0::2] + [Fraction(0)] * width)[:width], (coeff[1::2] + [Fraction(0)] * width)[:width]
    column = [Fraction(1)]
    for _ in alpha:
        column.append(cur[0])
        if cur[0] <= 0:
            break
        prev, cur = cur, [(cur[0] * prev[j + 1] - prev[0] * cur[j + 1]) / cur[0] for j in range(width - 1)] + [0]
    return column


def test_the_fraction_free_routh_array_equals_the_rational_one():
    rng = np.random.default_rng(11)
    hurwitz = 0
    for k in range(300):
        n = int(rng.integers(1, 16))
        if k % 3:
            alpha = [sp.Rational(int(rng.integers(-5, 60)), int(rng.choice([1, 2, 3, 7, 10, 1000]))) for _ in range(n)]
        else:  # Hurwitz by construction: the array runs to the end
            alpha = list(sp.Poly(sp.Mul(*[sp.Symbol("s") + sp.Rational(int(rng.integers(1, 50)),
                                                                        int(rng.integers(1, 9))) for _ in range(n)]),
                                 sp.Symbol("s")).all_coeffs()[1:])
        column = routh_first_column(alpha)
        assert column == _fraction_routh(alpha) and all(isinstance(x, sp.Rational) for x in column), alpha
        hurwitz += len(column) == n + 1
    assert 100 <= hurwitz < 300


def test_flint_results_become_the_sympy_matrices_sympy_builds():
    import flint

    from switchobs.design._normal_form import flint_matrix, sympy_matrix

    for entries in ([[1, 0], [-3, 7]], [[sp.Rational(1, 3), 0], [2, sp.Rational(-10**40 - 1, 10**30)]]):
        expected = sp.ImmutableMatrix(entries)
        built = sympy_matrix(flint_matrix(expected))
        assert built == expected and built.args == expected.args and hash(built) == hash(expected)
        assert built._rep == expected._rep and built._rep.domain == expected._rep.domain
        assert built._rep.rep.fmt == expected._rep.rep.fmt
    assert flint_matrix(sp.Matrix([[sp.sqrt(2)]])) is None
    assert sympy_matrix(flint.fmpq_mat(2, 1, [0, 0])) == sp.zeros(2, 1)


@pytest.mark.parametrize("n", [3, 6, 9])
def test_the_normal_form_transformation_of_dense_and_triangular_models(n):
    rng = np.random.default_rng(200 + n)
    chain = Model.from_dict({"name": "chain", "states": [f"x{i}" for i in range(n)],
                             "A": [[str(sp.Rational(-int(rng.integers(1, 9)), 4)) if i == j else ("1" if j == i + 1
                                   else "0") for j in range(n)] for i in range(n)],
                             "C": ["1"] + ["0"] * (n - 1), "time_scale": "y"})
    for model in (_random_model(n, rng), chain):
        nf = observer_normal_form(model)
        A, C, O = sp.Matrix(model.A), sp.Matrix(model.C), nf.observability_matrix
        assert nf.T * nf.T_inv == sp.eye(n) and nf.T * A * nf.T_inv == nf.A
        assert C * nf.T_inv == sp.Matrix([[1] + [0] * (n - 1)])
        assert O == sp.Matrix.vstack(*[C * A**k for k in range(n)]) and nf.observability_determinant == O.det()


def test_the_recheck_refuses_a_characteristic_polynomial_the_matrices_do_not_have():
    import dataclasses

    rng = np.random.default_rng(5)
    d = design(_random_model(5, rng), _random_spectrum(5, rng))
    assert not d.normal_form.is_identity and d._normal_form_similarity() is not None
    assert d.verify()["charpoly_plus"] and d.verify()["charpoly_minus"]
    wrong = tuple(a + (1 if i == 2 else 0) for i, a in enumerate(d.alpha_plus))
    checks = dataclasses.replace(d, alpha_plus=wrong, alpha_minus=wrong).verify()
    assert not checks["charpoly_plus"] and not checks["charpoly_minus"]
    singular = dataclasses.replace(d, normal_form=dataclasses.replace(d.normal_form, T_inv=2 * d.normal_form.T_inv))
    assert singular._normal_form_similarity() is None and singular.verify()["charpoly_plus"]


def test_numeric_K_minus_outside_the_family_is_refused_and_inside_accepted():
    model = builtin_model("abs-xbs3").numeric()
    d = design(model, "-40,-60,-60")
    with pytest.raises(CertificateError, match="not proportional"):
        design(model, K_plus=list(d.K_plus), K_minus=[d.K_minus[0] + 1, d.K_minus[1], d.K_minus[2]])
    family = design(model, K_plus=list(d.K_plus), K_minus=list(d.K_minus))
    assert family.choice == "hoang-family" and family.gain_constraints == ()
    assert all(family.verify().values())
    asked = design(model, K_plus=list(d.K_plus), K_minus=list(d.K_minus), coupling=True)
    assert len(asked.gain_constraints) == 2


def test_coupling_constraints_are_kept_for_symbolic_designs():
    assert len(design(builtin_model("abs-xbs3"), "-beta1,-beta2,-beta2").gain_constraints) == 2
    assert design(builtin_model("abs-xbs3").numeric(), "-40,-60,-60").gain_constraints == ()


def test_a_float_is_its_exact_binary_value_and_text_its_decimal():
    binary = sp.Rational(*(0.1).as_integer_ratio())
    assert rational_value(0.1, what="x") == binary != sp.Rational(1, 10)
    assert rational_value("0.1", what="x") == sp.Rational(1, 10)
    assert parse_expression(0.1, {}) == binary and parse_expression("0.1", {}) == sp.Rational(1, 10)
    model = builtin_model("normal-form-2").with_values({"a1": -1, "a2": -2})
    assert design(model, K_plus=[0.1, 3]).K_plus[0] == binary
    assert design(model, K_plus="0.1,3").K_plus[0] == sp.Rational(1, 10)
    assert design(model, [-0.1, -2]).spectrum[0] == -binary


def test_toml_numbers_are_read_as_the_decimals_they_spell(tmp_path):
    path = tmp_path / "m.toml"
    path.write_text('name = "m"\nstates = ["x1", "x2"]\nA = [[-0.1, 1], [0, -2]]\nC = [1, 0]\n'
                    'time_scale = "y"\nparameters = ["p"]\nb = ["p", "0"]\ninputs = ["u"]\n[values]\np = 0.3\n')
    model = Model.from_toml(path)
    assert model.A[0, 0] == sp.Rational(-1, 10) and model.values["p"] in ("0.3", sp.Rational(3, 10))


def test_design_reports_its_stages_with_the_size():
    notes: list[str] = []
    with listening(notes.append):
        design(builtin_model("abs-xbs3").numeric(), "-40,-60,-60")
    assert "design: observer normal form (n = 3)" in notes
    assert any(note.startswith("design: common Lyapunov matrix P") for note in notes)


def test_cli_progress_lines_name_the_command(monkeypatch):
    err = io.StringIO()
    monkeypatch.setattr("sys.stderr", err)
    stderr_progress("certify", after_s=0.0)("certify: strict LMI (n = 64, 2 modes)")
    assert err.getvalue().startswith("switchobs certify: [") and "(n = 64, 2 modes)" in err.getvalue()


def test_cli_progress_is_throttled_and_silent_where_the_command_has_its_own_stages(monkeypatch):
    err = io.StringIO()
    monkeypatch.setattr("sys.stderr", err)
    show = stderr_progress("certify", after_s=0.0)
    for k in range(20):  # a bisection announcing every solve: not twenty lines
        show(f"certify: dwell time (LMI solve {k})")
    assert err.getvalue().count("\n") == 1
    stderr_progress("demo", after_s=0.0)("design: coupling constraints (n = 4)")
    assert err.getvalue().count("\n") == 1
