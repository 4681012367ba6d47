"""Interop with the Python control ecosystem: lists, NumPy, sympy and python-control at every matrix entry."""

from __future__ import annotations

from fractions import Fraction

import control
import numpy as np
import pytest
import sympy as sp

from switchobs.certify import as_family, certify, classify_planar, common_lyapunov, discrete_certificate
from switchobs.design import design_gains
from switchobs.exceptions import DimensionError, ExpressionError, ModelError, SpectrumError
from switchobs.model import Model, exact_number, matrix_rows, parse_expression

A = [[0, 1], [-2, -3]]
BASE = {"name": "m", "states": ["z1", "z2"], "time_scale": "y"}


def _model(**over):
    return Model.from_dict({**BASE, "A": A, "C": [1, 0], **over})


@pytest.mark.parametrize("value", [
    A, np.array(A), np.array(A, dtype=np.int8), np.array(A, dtype=np.float32), np.array(A, dtype=np.longdouble),
    sp.Matrix(A), sp.Matrix(A) * sp.Float(1.0), [[np.float64(0), np.int64(1)], [np.float64(-2), -3.0]],
    control.ss(A, [[0], [1]], [[1, 0]], 0),
])
def test_model_A_from_any_container(value):
    assert _model(A=value).A == sp.Matrix(A)


@pytest.mark.parametrize("C", [[1, 0], [[1, 0]], np.array([1, 0]), np.array([[1.0, 0.0]]), sp.Matrix([[1, 0]]),
                               control.ss(A, [[0], [1]], [[1, 0]], 0)])
def test_model_C_from_any_container(C):
    assert _model(C=C).C == sp.Matrix([[1, 0]])


def test_floats_are_their_exact_binary_value_everywhere():
    """The one float rule (docs/design.md): NumPy, Python and sympy floats give the same rational."""
    exact = sp.Rational(*(0.1).as_integer_ratio())
    for x in (0.1, np.float64(0.1), sp.Float(0.1), np.array([0.1])[0]):
        assert exact_number(x) == exact
    assert exact_number(np.float32(0.1)) == sp.Rational(*np.float32(0.1).as_integer_ratio())
    assert exact_number("0.1") == "0.1"  # text is left to the parser, which reads the decimal
    assert parse_expression("0.1", {}) == sp.Rational(1, 10)
    assert _model(A=[[0, 0.1], [-2, -3]]).A[0, 1] == exact
    assert _model(A=sp.Matrix([[0, sp.Float(0.1)], [-2, -3]])).A[0, 1] == exact


def test_numpy2_scalars_never_reach_the_parser():
    """np.float64(-40) prints as 'np.float64(-40.0)' under NumPy 2; it must be read as a number."""
    m = _model()
    ref = design_gains(m, "-40,-60")
    for spec in (np.array([-40, -60]), [np.float64(-40), np.float64(-60)], [np.int64(-40), np.int32(-60)],
                 sp.Matrix([-40, -60]), np.array([[-40.0], [-60.0]])):
        assert design_gains(m, spec).K_plus == ref.K_plus
    assert design_gains(m, characteristic_polynomial=np.array([1.0, 100.0, 2400.0])).K_plus == ref.K_plus
    assert design_gains(m, K_plus=np.array(ref.numeric()["K_plus"])).K_plus == ref.K_plus
    assert design_gains(m, K_plus=sp.Matrix([sp.Float(97.0), 2107])).K_plus == ref.K_plus


def test_sympy_matrix_with_symbols_maps_names_to_the_model():
    a = sp.Symbol("a")  # no assumptions: matched by name to the model's parameter
    m = Model.from_dict({**BASE, "A": sp.Matrix([[0, 1], [-a, -3]]), "C": [1, 0], "parameters": ["a"]})
    assert m.A[1, 0] == -m.symbols["a"]
    with pytest.raises(ExpressionError, match="unknown name"):
        Model.from_dict({**BASE, "A": sp.Matrix([[0, 1], [-a, -3]]), "C": [1, 0]})


def test_bad_containers_are_named():
    with pytest.raises(ExpressionError, match="boolean"):
        _model(A=np.array([[True, False], [False, True]]))
    with pytest.raises(ExpressionError, match="finite"):
        _model(A=np.array([[0, np.nan], [-2, -3]]))
    with pytest.raises(DimensionError, match="2 outputs"):
        _model(C=control.ss(A, [[0], [1]], np.eye(2), 0))
    with pytest.raises(DimensionError, match="dtype"):
        matrix_rows(np.array([["a", "b"]]), name="A")
    with pytest.raises(ModelError, match="discrete-time"):
        Model.from_statespace(control.ss(A, [[0], [1]], [[1, 0]], 0, dt=0.1), time_scale="y")
    with pytest.raises(ModelError, match="D ="):
        Model.from_statespace(control.ss(A, [[0], [1]], [[1, 0]], [[1]]), time_scale="y")
    with pytest.raises(SpectrumError, match="sign"):
        design_gains(_model(), "-1,-2").to_statespace("up")


def test_from_statespace_and_back():
    sys = control.ss(A, [[0], [1]], [[1, 0]], 0)
    m = Model.from_statespace(sys, time_scale="y", name="mass")
    assert (m.A, m.C, m.inputs, m.states) == (sp.Matrix(A), sp.Matrix([[1, 0]]), ("u1",), ("z1", "z2"))
    assert m.b == sp.Matrix([[0], [1]])
    d = design_gains(m, np.array([-4.0, -5.0]))
    for sign, K in (("plus", d.numeric()["K_plus"]), ("minus", d.numeric()["K_minus"])):
        err = d.to_statespace(sign)
        assert isinstance(err, control.StateSpace)
        np.testing.assert_array_equal(err.A, d.numeric()[f"A_{sign}"])
        np.testing.assert_array_equal(err.C, [[1.0, 0.0]])
        np.testing.assert_array_equal(err.B.ravel(), -K if sign == "plus" else K)
        assert sorted(np.round(control.poles(err).real, 9)) == [-5.0, -4.0]  # Theorem 1: same spectrum
    assert set(d.to_numpy()) >= {"K_plus", "K_minus", "A_plus", "A_minus", "P"}


def test_certify_takes_numpy_sympy_and_statespace():
    A1, A2 = [[-1, -1], [1, 0]], [[-1, 1], [-1, 0]]
    ref = certify([A1, A2], output=[[1, 0]])
    for fam, out in (([np.array(A1, float), sp.Matrix(A2) * sp.Float(1.0)], np.array([[1.0, 0.0]])),
                     ([control.ss(A1, [[1], [0]], [[1, 0]], 0), control.ss(A2, [[1], [0]], [[1, 0]], 0)],
                      control.ss(A1, [[1], [0]], [[1, 0]], 0))):
        rep = certify(fam, output=out)
        assert rep.verdict == ref.verdict and rep.family.exact == ref.family.exact
    fam = as_family([sp.Matrix([[-1.5, 0], [0, -1]])])
    assert fam.exact[0][0][0] == Fraction(-3, 2)  # a float sympy Matrix is not "irrational"
    assert np.asarray(ref.family).shape == (2, 2, 2)
    assert classify_planar(np.array(A1), sp.Matrix(A2)).case == ref.planar.case
    assert common_lyapunov([np.array(A1), np.array(A2)], output=np.array([1, 0])).certified
    cert = discrete_certificate(np.array([[-2, 1], [-1, 0]]), sp.Matrix([[-2, -1], [1, 0]]), np.array([[1, 0]]),
                                np.eye(2), method="radau3")
    assert cert.certified


def _chain3():
    """The python-control model of examples/python_control_notebook.py: dz/dt = v (A z) + B u, y = C z."""
    A3 = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, -2.0, -2.0]])
    B3, C3 = np.array([[0.0], [0.0], [1.0]]), np.array([[1.0, 0.0, 0.0]])
    model = Model.from_statespace(control.ss(A3, B3, C3, 0), time_scale="v", external=["v"], name="chain3")
    plant = control.nlsys(lambda t, x, u, p: u[0] * (A3 @ x) + B3[:, 0] * u[1], lambda t, x, u, p: C3 @ x,
                          inputs=["v", "u1"], outputs=["y"], states=3, name="plant")
    return model, plant


def test_observer_to_nlsys_interconnected_with_a_plant_equals_its_own_run():
    """Seed 004 Theorem 1 on the python-control side: the observer (to_nlsys) interconnected with the plant,
    v = cos t crossing zero, simulated by input_output_response, equals SwitchedObserver.run on the same
    measurements (held at the step midpoints) up to the error of holding them over the 2 ms steps."""
    from switchobs.observers import SwitchedObserver

    model, plant = _chain3()
    observer = SwitchedObserver(model, design_gains(model, np.array([-2.0, -3.0, -4.0])))
    nl = observer.to_nlsys()
    assert (nl.input_labels, nl.output_labels, nl.state_labels) == (["y", "v", "u1"],
                                                                    ["z1_hat", "z2_hat", "z3_hat"], ["z1", "z2", "z3"])
    loop = control.interconnect([plant, nl], inputs=["v", "u1"], outputs=["y", *nl.output_labels])
    dt = 2e-3
    t = np.arange(0.0, 4.0, dt)
    v, u = np.cos(t), 0.5 * np.sin(0.7 * t)
    resp = control.input_output_response(loop, t, np.vstack([v, u]), X0=[1.0, -1.0, 0.5, 0.0, 0.0, 0.0],
                                         solve_ivp_kwargs={"max_step": 5 * dt, "rtol": 1e-9, "atol": 1e-12})
    y, xhat = resp.outputs[0], resp.outputs[1:].T
    mid = lambda s: (s[:-1] + s[1:]) / 2  # noqa: E731
    own = observer.run(np.zeros(3), np.column_stack([mid(y), mid(v), mid(u)]), dt)
    scale = np.abs(xhat).max()
    assert np.abs(own - xhat[1:]).max() <= 2e-5 * scale
    # and the estimate converges to the plant's state while v changes sign twice (tau = 2.24 at t = 4 s)
    assert np.linalg.norm(resp.states[:3, -1] - xhat[-1]) < 0.2 * np.linalg.norm(resp.states[:3, 0])


def test_error_systems_of_both_modes_are_statespace_with_the_design_poles():
    model, _ = _chain3()
    gains = design_gains(model, np.array([-2.0, -3.0, -4.0]))
    for sign in ("plus", "minus"):
        err = gains.to_statespace(sign)
        assert isinstance(err, control.StateSpace)
        assert np.allclose(np.sort(control.poles(err).real), [-4.0, -3.0, -2.0])


def test_to_statespace_round_trip_and_transfer_function_input():
    A3, B3, C3 = [[0.0, 1.0], [-2.0, -3.0]], [[0.0], [1.0]], [[1.0, 0.0]]
    m = Model.from_statespace(control.ss(A3, B3, C3, 0), time_scale="1")
    sys = m.to_statespace()
    assert isinstance(sys, control.StateSpace)
    assert (sys.A.tolist(), sys.B.tolist(), sys.C.tolist(), sys.D.tolist()) == (A3, B3, C3, [[0.0]])
    assert (sys.state_labels, sys.input_labels, sys.output_labels) == (["z1", "z2"], ["u1"], ["y"])
    tf = control.tf([2.0], [1.0, 3.0, 2.0])
    from_tf = Model.from_statespace(tf, time_scale="1").to_statespace()
    assert np.allclose(np.sort(control.poles(from_tf).real), [-2.0, -1.0])
    assert control.dcgain(from_tf) == pytest.approx(1.0)        # 2 / 2, the transfer function's
    with pytest.raises(ModelError, match="no state-space realisation .*non-proper"):
        Model.from_statespace(control.tf([1.0, 0.0, 0.0], [1.0, 1.0]), time_scale="1")
    with pytest.raises(ModelError, match="must be a control.StateSpace or TransferFunction, got list"):
        Model.from_statespace([[1.0]], time_scale="1")


def test_to_statespace_refuses_what_is_not_linear_time_invariant():
    from switchobs.model import builtin_model

    with pytest.raises(ModelError, match=r"time scaling s = y/vx; only s = 1"):
        builtin_model("abs-xbs3").to_statespace()
    m = Model.from_dict({**BASE, "A": A, "C": [1, 0], "time_scale": "1", "d": ["0", "y**2"]})
    with pytest.raises(ModelError, match=r"drift d\(y\)"):
        m.to_statespace()
