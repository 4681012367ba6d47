"""The generic switched observers: right-hand side, RK4 / Euler steps, run, continuity, refusals."""

import json
import math

import numpy as np
import pytest
import sympy as sp
from _docs_blocks import assert_page_says
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.linalg import expm

from switchobs.exceptions import (DimensionError, FreeSymbolError, ModelError, ObserverInputError,
                                  SimulationError)
from switchobs.model import Model, builtin_model
from switchobs.observers import (AdaptiveSwitchedObserver, ErrorCode, SwitchedObserver, xbs3_observer)

# A model exercising everything the observers accept: an external signal declared positive, two
# inputs, d(y) and b(y) with transcendental functions, and two parameters (q, r) that enter d and b
# linearly so that the adaptive observer can estimate them.
TOY = {
    "name": "toy",
    "states": ["x1", "x2", "x3"],
    "A": [["p1", "1", "0"], ["p2", "0", "1"], ["p3", "0", "0"]],
    "C": ["1", "0", "0"],
    "time_scale": "y/vx",
    "d": ["q*sin(y)", "exp(-y^2) + r", "p1*y"],
    "b": [["1", "y"], ["q", "cos(y)"], ["y^2", "r*y"]],
    "parameters": ["p1", "p2", "p3", "q", "r"],
    "external": ["vx"],
    "inputs": ["u1", "u2"],
    "positive": ["vx"],
    "values": {"p1": "-1", "p2": "-2", "p3": "-3", "q": "0.7", "r": "-1.3"},
}
K_PLUS = np.array([4.0, 5.0, 6.0])
K_MINUS = np.array([-2.0, 3.0, -6.0])


@pytest.fixture(scope="module")
def toy():
    return Model.from_dict(TOY)


@pytest.fixture(scope="module")
def toy_observer(toy):
    # rk4, not the default radau3: the tests below check the classic RK4 step against a reference
    return SwitchedObserver(toy, K_PLUS, K_MINUS, method="rk4")


@pytest.fixture(scope="module")
def toy_adaptive(toy):
    return AdaptiveSwitchedObserver(toy, K_PLUS, K_MINUS, unknown=("q", "r"), Gamma=[[2.0, 0.5], [0.5, 1.0]])


@pytest.fixture(scope="module")
def xbs3():
    return xbs3_observer(150.0, 150.0)


def reference_rhs(model, K_plus, K_minus):
    """s (A x + d + K (y - C x)) + b u straight from the model, by sympy.lambdify (independent of the engine)."""
    m = model.numeric()
    x = sp.Matrix([m.symbol(n) for n in m.states])
    sig = [m.symbol(n) for n in m.signals]
    u = sp.Matrix([m.symbol(n) for n in m.inputs])
    y = m.symbol(m.output)
    s = m.time_scale
    f = {}
    for sign, K in (("+", K_plus), ("-", K_minus)):
        Kc = sp.Matrix([sp.nsimplify(k) for k in K])
        f[sign] = sp.lambdify((list(x), *sig), list(s * (m.A * x + m.d + Kc * (y - (m.C * x)[0])) + m.b * u))
    s_fn = sp.lambdify(sig, s)
    return lambda xv, sv: np.array(f["+" if s_fn(*sv) > 0 else "-"](list(xv), *sv))


def reference_adaptive_rhs(model, K_plus, K_minus, unknown, Gamma):
    """Seed 001 eq. (3.4a)-(3.4c) written out with numpy, Psi = d(s d + b u)/dtheta by sympy."""
    theta = [model.symbols[k] for k in unknown]
    m = model.with_values({k: v for k, v in model.values.items() if k not in unknown})
    sig = [m.symbol(n) for n in m.signals]
    u = sp.Matrix([m.symbol(n) for n in m.inputs])
    F = m.time_scale * m.d + m.b * u
    Psi = sp.lambdify(sig, F.jacobian(theta))
    c0 = sp.lambdify(sig, F.subs({t: 0 for t in theta}))
    s_fn = sp.lambdify(sig, m.time_scale)
    A = np.array(m.A, dtype=float)
    C = np.array(m.C, dtype=float).reshape(1, -1)
    n, p = model.n, len(unknown)

    def rhs(xv, sv):
        w, th, U = xv[:n], xv[n:n + p], xv[n + p:].reshape(n, p)
        s = s_fn(*sv)
        K = s * (K_plus if s > 0 else K_minus)
        P = np.array(Psi(*sv), dtype=float)
        e = sv[0] - (C @ w)[0]
        w_dot = s * A @ w + np.array(c0(*sv), dtype=float).ravel() + P @ th + (K + U @ Gamma @ U.T @ C.ravel()) * e
        th_dot = Gamma @ U.T @ C.ravel() * e
        U_dot = (s * A - np.outer(K, C)) @ U + P
        return np.concatenate([w_dot, th_dot, U_dot.ravel()])
    return rhs


def rk4_reference(f, x, sig, dt):
    k1 = f(x, sig)
    k2 = f(x + dt / 2 * k1, sig)
    k3 = f(x + dt / 2 * k2, sig)
    k4 = f(x + dt * k3, sig)
    return x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)


finite = st.floats(-3.0, 3.0, allow_nan=False)
nonzero_y = st.floats(0.05, 3.0) | st.floats(-3.0, -0.05)


@settings(max_examples=25, deadline=None)
@given(x=st.lists(finite, min_size=3, max_size=3), y=nonzero_y, vx=st.floats(0.5, 40.0),
       u=st.lists(finite, min_size=2, max_size=2))
def test_derivative_is_the_switched_observer_of_the_model(toy, toy_observer, x, y, vx, u):
    """dzhat/dt = s (A zhat + d + K(s)(y - C zhat)) + b u (seed 000 eq. (8)-(9), seed 004)."""
    ref = reference_rhs(toy, K_PLUS, K_MINUS)
    sig = [y, vx, *u]
    np.testing.assert_allclose(toy_observer.derivative(x, sig), ref(np.array(x), sig), rtol=1e-12, atol=1e-12)


@settings(max_examples=25, deadline=None)
@given(x=st.lists(finite, min_size=3, max_size=3), th=st.lists(finite, min_size=2, max_size=2),
       U=st.lists(finite, min_size=6, max_size=6), y=nonzero_y, vx=st.floats(0.5, 40.0),
       u=st.lists(finite, min_size=2, max_size=2))
def test_aguado2020_eq34_adaptive_derivative(toy, toy_adaptive, x, th, U, y, vx, u):
    """The adaptive observer is (3.4a)-(3.4c) with Psi = d(s d + b u)/dtheta, for any linear parametrisation."""
    ref = reference_adaptive_rhs(toy, K_PLUS, K_MINUS, ("q", "r"), toy_adaptive.Gamma)
    xv = np.array([*x, *th, *U])
    sig = [y, vx, *u]
    np.testing.assert_allclose(toy_adaptive.derivative(xv, sig), ref(xv, sig), rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("which", ["switched", "adaptive"])
def test_step_is_one_classic_rk4_step_with_held_signals(toy, toy_observer, toy_adaptive, which):
    obs = toy_observer if which == "switched" else toy_adaptive
    rng = np.random.default_rng(4)
    for _ in range(10):
        x = rng.normal(size=obs.size)
        sig = [rng.choice([-1, 1]) * rng.uniform(0.1, 2), rng.uniform(1, 30), *rng.normal(size=2)]
        ref = rk4_reference(lambda xv, sv: obs.derivative(xv, sv), x, sig, 0.01)
        np.testing.assert_allclose(obs.step(x, sig, 0.01), ref, rtol=1e-13, atol=1e-13)


def test_euler_step_is_x_plus_dt_f(toy):
    obs = SwitchedObserver(toy, K_PLUS, K_MINUS, method="euler")
    x, sig = np.array([0.3, -1.0, 2.0]), [-0.7, 12.0, 0.4, -2.0]
    np.testing.assert_allclose(obs.step(x, sig, 0.02), x + 0.02 * obs.derivative(x, sig), rtol=1e-15)


@pytest.mark.parametrize("method", ["rk4", "euler"])
@pytest.mark.parametrize("which", ["switched", "adaptive"])
def test_run_is_bitwise_repeated_step(toy, toy_adaptive, method, which):
    """``run`` vectorises the per-step quantities but executes the same arithmetic as ``step``."""
    obs = (SwitchedObserver(toy, K_PLUS, K_MINUS, method=method) if which == "switched" else
           AdaptiveSwitchedObserver(toy, K_PLUS, K_MINUS, unknown=("q", "r"), Gamma=toy_adaptive.Gamma,
                                    method=method))
    rng = np.random.default_rng(7)
    t = np.arange(300) * 1e-3
    rows = np.column_stack([2 * np.sin(20 * t), 20 - t, np.cos(5 * t), rng.normal(size=t.size)])
    x0 = rng.normal(size=obs.size)
    traj = obs.run(x0, rows, 1e-3)
    x = x0
    for k, row in enumerate(rows):
        x = obs.step(x, row, 1e-3)
        assert np.array_equal(x, traj[k]), k
    assert traj.shape == (300, obs.size)


def _piecewise_exact(obs, x0, rows, H):
    """Exact solution of the observer ODE with piecewise-constant signals (abs-xbs3: affine in x)."""
    x = np.asarray(x0, float)
    A, C = obs.A, obs.C
    for y, vx, u in rows:
        s = y / vx
        K = obs.K_plus if s > 0 else obs.K_minus
        M = s * (A - np.outer(K, C))
        c = s * K * y + np.array([obs.values["b"] * u, 0.0, 0.0])
        aug = np.zeros((4, 4))
        aug[:3, :3], aug[:3, 3] = M, c
        x = (expm(aug * H) @ np.append(x, 1.0))[:3]
    return x


@pytest.mark.parametrize("method, order", [("rk4", 4), ("euler", 1)])
def test_convergence_order_against_exact_piecewise_solution(method, order):
    method_names = {"rk4": "RK4", "euler": "Euler"}
    obs = xbs3_observer(150.0, 150.0, method=method)
    H = 4e-3
    t = np.arange(25) * H
    rows = np.column_stack([20 * np.sin(2 * np.pi * 8 * t + 0.3), 25 - 2 * t, -300 * np.cos(2 * np.pi * 8 * t)])
    x0 = [1.0, 0.5, 0.0]
    exact = _piecewise_exact(obs, x0, rows, H)
    errors = []
    for m in (4, 8, 16, 32):
        traj = obs.run(x0, np.repeat(rows, m, axis=0), H / m)
        errors.append(np.linalg.norm(traj[-1] - exact) / np.linalg.norm(exact))
    observed = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(observed - order) < 0.25), (errors, observed)
    assert_page_says("observers.md", ", ".join(f"{o:.2f}" for o in observed) + f" for {method_names[method]}")


def test_hoang2014_eq9_correction_continuous_at_s_zero(xbs3):
    """k_i(z1) z1 (z1 - zhat1) is continuous: the right-hand side tends to b u from both signs of y."""
    x = np.array([3.0, 0.4, -2.0])
    vx, u = 20.0, 150.0
    at_zero = xbs3.derivative(x, [0.0, vx, u])
    np.testing.assert_array_equal(at_zero, [xbs3.values["b"] * u, 0.0, 0.0])
    for eps in (1e-3, 1e-6, 1e-9):
        up, down = xbs3.derivative(x, [eps, vx, u]), xbs3.derivative(x, [-eps, vx, u])
        lipschitz = 2 * (np.abs(xbs3.A).sum() + np.abs(xbs3.K_plus).max()) * (np.abs(x).sum() + 1) / vx
        assert np.abs(up - at_zero).max() <= lipschitz * eps
        assert np.abs(down - at_zero).max() <= lipschitz * eps
    # the gain itself jumps (K_plus != K_minus): only the product with s is continuous
    assert not np.allclose(xbs3.K_plus, xbs3.K_minus)


# --------------------------------------------------------------------------- refusals
GOOD_X, GOOD_SIG = [1.0, 0.5, 0.0], [10.0, 20.0, 5.0]


@pytest.mark.parametrize("x, sig, dt, code, match", [
    (GOOD_X, GOOD_SIG, 0.0, ErrorCode.BAD_DT, "dt = 0.0"),
    (GOOD_X, GOOD_SIG, -1e-3, ErrorCode.BAD_DT, "dt = -0.001"),
    (GOOD_X, GOOD_SIG, math.nan, ErrorCode.BAD_DT, "dt = nan"),
    (GOOD_X, GOOD_SIG, math.inf, ErrorCode.BAD_DT, "dt = inf"),
    ([math.nan, 0.5, 0.0], GOOD_SIG, 1e-3, ErrorCode.NONFINITE_STATE, "state z1 = nan"),
    ([1.0, 0.5, -math.inf], GOOD_SIG, 1e-3, ErrorCode.NONFINITE_STATE, "state z3 = -inf"),
    (GOOD_X, [math.nan, 20.0, 5.0], 1e-3, ErrorCode.NONFINITE_SIGNAL, "signal y = nan"),
    (GOOD_X, [10.0, 20.0, math.inf], 1e-3, ErrorCode.NONFINITE_SIGNAL, "signal u = inf"),
    (GOOD_X, [10.0, 0.0, 5.0], 1e-3, ErrorCode.UNDEFINED_TIME_SCALE, "signal vx = 0.0 must be > 0"),
    (GOOD_X, [10.0, -3.0, 5.0], 1e-3, ErrorCode.UNDEFINED_TIME_SCALE, "signal vx = -3.0 must be > 0"),
    (GOOD_X, [1e300, 1e-300, 5.0], 1e-3, ErrorCode.UNDEFINED_TIME_SCALE, "time scaling s = inf"),
    ([0.0, 1e306, 0.0], [1e3, 1e-3, 0.0], 1e-3, ErrorCode.NONFINITE_RESULT, "non-finite state"),
    ([math.nan, 0.5, 0.0], [10.0, 0.0, 5.0], -1.0, ErrorCode.BAD_DT, "dt"),            # first check wins
    ([math.nan, 0.5, 0.0], [10.0, 0.0, 5.0], 1e-3, ErrorCode.NONFINITE_STATE, "z1"),
])
def test_step_refusals_carry_the_documented_code(xbs3, x, sig, dt, code, match):
    with pytest.raises(ObserverInputError, match=match) as info:
        xbs3.step(x, sig, dt)
    assert info.value.code == code


def test_run_reports_the_first_failing_row_with_the_step_code(xbs3):
    rows = np.tile(GOOD_SIG, (10, 1))
    rows[6, 1] = 0.0
    rows[8, 0] = math.nan
    with pytest.raises(ObserverInputError, match="row 6: signal vx = 0.0") as info:
        xbs3.run(GOOD_X, rows, 1e-3)
    assert info.value.code == ErrorCode.UNDEFINED_TIME_SCALE
    rows[3] = [1e3, 1e-300, 0.0]   # s = 1e303 is finite, the step overflows
    with pytest.raises(ObserverInputError, match="row 3: the step produced a non-finite state") as info:
        xbs3.run(GOOD_X, rows, 1e-3)
    assert info.value.code == ErrorCode.NONFINITE_RESULT
    with pytest.raises(ObserverInputError) as info:
        xbs3.run(GOOD_X, rows, 0.0)
    assert info.value.code == ErrorCode.BAD_DT


def _small(time_scale, d1):
    return Model.from_dict({"name": "small", "states": ["x1"], "A": [["-1"]], "C": ["1"], "time_scale": time_scale,
                            "d": [d1], "external": ["w"]})


def test_domain_errors_map_to_time_scale_and_result_codes():
    obs = SwitchedObserver(_small("y/(w - 1)", "log(y)"), [1.0], [-1.0])
    with pytest.raises(ObserverInputError, match="time scaling s = nan") as info:
        obs.step([0.0], [1.0, 1.0], 1e-3)          # division by zero in s
    assert info.value.code == ErrorCode.UNDEFINED_TIME_SCALE
    with pytest.raises(ObserverInputError) as info:
        obs.step([0.0], [-1.0, 3.0], 1e-3)         # log of a negative y in d(y)
    assert info.value.code == ErrorCode.NONFINITE_RESULT
    with pytest.raises(ObserverInputError, match="row 1") as info:
        obs.run([0.0], [[2.0, 3.0], [-1.0, 3.0]], 1e-3)
    assert info.value.code == ErrorCode.NONFINITE_RESULT
    assert obs.step([0.0], [2.0, 3.0], 1e-3)[0] != 0.0


def test_shapes_are_checked(xbs3):
    with pytest.raises(DimensionError, match=r"xhat has the wrong shape; expected \(3,\)"):
        xbs3.step([1.0, 2.0], GOOD_SIG, 1e-3)
    with pytest.raises(DimensionError, match=r"signals has the wrong shape.*\(y, vx, u\)"):
        xbs3.step(GOOD_X, [1.0, 2.0, 3.0, 4.0], 1e-3)
    with pytest.raises(DimensionError, match=r"signal_rows has the wrong shape"):
        xbs3.run(GOOD_X, [1.0, 2.0, 3.0], 1e-3)
    with pytest.raises(DimensionError, match="K_plus has the wrong shape"):
        SwitchedObserver(builtin_model("abs-xbs3"), [1.0, 2.0], [1.0, 2.0, 3.0])
    assert xbs3.run(GOOD_X, np.empty((0, 3)), 1e-3).shape == (0, 3)


def test_model_problems_are_refused():
    with pytest.raises(FreeSymbolError, match=r"\['a1', 'a2', 'a3'\] have no value"):
        SwitchedObserver(builtin_model("normal-form-3"), [1, 2, 3], [1, 2, 3])
    with pytest.raises(ModelError, match="depends on t explicitly"):
        SwitchedObserver(_small("y*(1 + t)", "0"), [1.0], [1.0])
    with pytest.raises(FreeSymbolError, match="K_plus still depends on"):
        SwitchedObserver(builtin_model("abs-xbs3"), sp.Matrix(sp.symbols("k1:4")), [1, 2, 3])
    with pytest.raises(SimulationError, match=r"K_minus = \[1.0, nan, 3.0\] has a non-finite entry"):
        SwitchedObserver(builtin_model("abs-xbs3"), [1, 2, 3], [1, math.nan, 3])
    with pytest.raises(SimulationError, match="unknown discretisation method 'rk45'"):
        SwitchedObserver(builtin_model("abs-xbs3"), [1, 2, 3], [1, 2, 3], method="rk45")
    with pytest.raises(ModelError, match="no parameter 'zz'"):
        SwitchedObserver(builtin_model("abs-xbs3"), [1, 2, 3], [1, 2, 3], params={"zz": 1})


def test_params_override_model_values():
    model = builtin_model("abs-xbs3")
    obs = SwitchedObserver(model, [1, 2, 3], [1, 2, 3], params={"c": "24"})
    assert obs.values == {"a": 187.5, "b": -4.375, "c": 24.0}
    assert obs.A[1, 1] == 24.0


def test_adaptive_problems_are_refused(toy):
    G = np.eye(2)
    with pytest.raises(ModelError, match=r"\['p1'\] appear in A"):
        AdaptiveSwitchedObserver(toy, K_PLUS, K_MINUS, unknown=("p1", "q"), Gamma=G)
    nonlinear = Model.from_dict({**TOY, "d": ["q^2*y", "r", "0"]})
    with pytest.raises(ModelError, match="not linear in q"):
        AdaptiveSwitchedObserver(nonlinear, K_PLUS, K_MINUS, unknown=("q", "r"), Gamma=G)
    with pytest.raises(SimulationError, match="not positive definite"):
        AdaptiveSwitchedObserver(toy, K_PLUS, K_MINUS, unknown=("q", "r"), Gamma=[[1, 0], [0, -1]])
    with pytest.raises(SimulationError, match="not symmetric"):
        AdaptiveSwitchedObserver(toy, K_PLUS, K_MINUS, unknown=("q", "r"), Gamma=[[1, 0.5], [0, 1]])
    with pytest.raises(DimensionError, match=r"Gamma has the wrong shape; expected \(2, 2\)"):
        AdaptiveSwitchedObserver(toy, K_PLUS, K_MINUS, unknown=("q", "r"), Gamma=np.eye(3))
    with pytest.raises(SimulationError, match="needs Gamma"):
        AdaptiveSwitchedObserver(toy, K_PLUS, K_MINUS, unknown=("q", "r"), Gamma=None)
    with pytest.raises(ModelError, match="no parameter 'zz' to estimate"):
        AdaptiveSwitchedObserver(toy, K_PLUS, K_MINUS, unknown=("zz",), Gamma=[1.0])
    with pytest.raises(ModelError, match="'q' is estimated"):
        AdaptiveSwitchedObserver(toy, K_PLUS, K_MINUS, unknown=("q", "r"), Gamma=G, params={"q": 1})
    with pytest.raises(ModelError, match="non-empty list"):
        AdaptiveSwitchedObserver(toy, K_PLUS, K_MINUS, unknown=(), Gamma=G)


def test_adaptive_state_layout_is_w_theta_upsilon_row_major(toy_adaptive):
    assert toy_adaptive.state_names == ("x1", "x2", "x3", "q", "r", "Upsilon_x1_q", "Upsilon_x1_r",
                                        "Upsilon_x2_q", "Upsilon_x2_r", "Upsilon_x3_q", "Upsilon_x3_r")
    assert toy_adaptive.signal_names == ("y", "vx", "u1", "u2")


def test_readout_on_states_and_trajectories(toy, toy_adaptive):
    obs = SwitchedObserver(toy, K_PLUS, K_MINUS, readout="x2 - p1*x1")
    assert obs.readout([1.0, 2.0, 3.0]) == 3.0
    np.testing.assert_array_equal(obs.readout(np.array([[1.0, 2.0, 3.0], [0.0, 1.0, 0.0]])), [3.0, 1.0])
    adaptive = AdaptiveSwitchedObserver(toy, K_PLUS, K_MINUS, unknown=("q", "r"), Gamma=np.eye(2),
                                        readout="x1*q + r")
    assert adaptive.readout(np.arange(11.0)) == 0.0 * 3 + 4.0
    with pytest.raises(SimulationError, match="has no readout"):
        toy_adaptive.readout(np.zeros(11))
    with pytest.raises(DimensionError, match="readout expects a state of length 3"):
        obs.readout([1.0, 2.0])


def test_to_json_and_str(xbs3, toy_adaptive):
    data = json.loads(json.dumps(xbs3.to_json()))
    assert data["model"] == "abs-xbs3" and data["method"] == "radau3"   # the default: certified for every dt
    assert data["K_plus"] == xbs3.K_plus.tolist()
    assert data["error_codes"] == {"OK": 0, "BAD_DT": 1, "NONFINITE_STATE": 2, "NONFINITE_SIGNAL": 3,
                                   "UNDEFINED_TIME_SCALE": 4, "NONFINITE_RESULT": 5, "SUBSTEP_LIMIT": 8}
    assert "readout: z2" in str(xbs3) and "K_minus" in str(xbs3)
    assert json.loads(json.dumps(toy_adaptive.to_json()))["Gamma"] == [[2.0, 0.5], [0.5, 1.0]]
    assert "estimated: q, r" in str(toy_adaptive)
    assert "def advance" in xbs3.source


@pytest.mark.parametrize("module", ["_observer", "_xbs"])
def test_docstring_examples_run(module):
    import doctest
    import importlib

    result = doctest.testmod(importlib.import_module(f"switchobs.observers.{module}"))
    assert result.attempted > 0 and result.failed == 0
