"""The implicit step methods (midpoint, radau3) of the switched observer, in Python and in the generated C.

With the signals held the observer is the affine ODE f(x) = J x + c, J = s A - g C, and one step of a method
with stability function R = N / D is x+ = x + dt D(Z)^-1 F(Z) f(x), Z = dt J (switchobs.spec._methods).
C and Python evaluate the same cofactor solve (switchobs.spec.implicit_increment); they must agree to
1e-12 relative to the state's largest entry (docs/codegen.md), and do to rounding.
"""

from __future__ import annotations

import pickle
from fractions import Fraction

import numpy as np
import pytest
from _docs_blocks import assert_page_says, page_number

from switchobs.cli.main import main
from switchobs.codegen import CObserver, StepStatus, generate_observer
from switchobs.design import design
from switchobs.exceptions import CodegenError, ObserverInputError, SimulationError
from switchobs.model import Model, builtin_model
from switchobs.observers import AdaptiveSwitchedObserver, SwitchedObserver, adaptive_xbs_observer
from switchobs.spec import METHODS, STEP_METHODS, affine_jacobian, implicit_increment

#: Tolerance of C against the Python reference (double), relative to the largest entry of the state.
TOL = 1e-12
SPECTRA = {"abs-xbs3": "-40,-60,-60", "abs-xbs4": "-10,-10,-20,-20"}

#: Butcher tableaux of the two implicit methods: (a, b).
TABLEAUX = {
    "midpoint": (np.array([[0.5]]), np.array([1.0])),
    "radau3": (np.array([[5 / 12, -1 / 12], [3 / 4, 1 / 4]]), np.array([3 / 4, 1 / 4])),
}


def stage_solve(method: str, J: np.ndarray, c: np.ndarray, x: np.ndarray, dt: float) -> np.ndarray:
    """One Runge-Kutta step of x' = J x + c by solving the stage equations k_i = f(x + dt sum_j a_ij k_j) directly."""
    a, b = TABLEAUX[method]
    s, n = len(b), len(x)
    big = np.eye(s * n) - dt * np.kron(a, J)
    k = np.linalg.solve(big, np.tile(J @ x + c, s)).reshape(s, n)
    return x + dt * b @ k


def _safe(d: float) -> float:
    return d if d != 0.0 else 1.0


def test_methods_are_the_stability_functions():
    assert METHODS == ("rk4", "euler", "midpoint", "radau3") == tuple(STEP_METHODS)
    assert STEP_METHODS["midpoint"].increment == (1,)
    assert STEP_METHODS["radau3"].increment == (1, Fraction(-1, 6))
    assert [STEP_METHODS[m].explicit for m in METHODS] == [True, True, False, False]
    from switchobs.certify._discrete import STEP_METHODS as certified
    assert certified is STEP_METHODS


@pytest.mark.parametrize("method", ["midpoint", "radau3"])
@pytest.mark.parametrize("n", [1, 2, 3, 4, 5])
def test_increment_formula_equals_the_stage_equations(method, n):
    """x + dt D(Z)^-1 F(Z) f(x) is exactly one step of the Butcher tableau on a random affine system."""
    rng = np.random.default_rng(n)
    J = rng.normal(size=(n, n)) * 20.0
    c, x = rng.normal(size=n), rng.normal(size=n)
    for dt in (1e-3, 0.05, 0.7):
        inc, det = implicit_increment(STEP_METHODS[method], J.tolist(), (J @ x + c).tolist(), dt, _safe)
        want = stage_solve(method, J, c, x, dt)
        assert np.max(np.abs(x + dt * np.array(inc) - want)) <= 1e-12 * max(1.0, np.max(np.abs(want)))
        Z = dt * J
        D = np.eye(n) - Z / 2 if method == "midpoint" else np.eye(n) - 2 * Z / 3 + Z @ Z / 6
        assert det == pytest.approx(np.linalg.det(D), rel=1e-10)


@pytest.mark.parametrize("method", ["midpoint", "radau3"])
def test_python_observer_step_is_the_stage_solution(method):
    """The reference observer's step is one Radau IIA / midpoint step of its affine right-hand side."""
    m = builtin_model("abs-xbs3")
    g = design(m, "-100,-100,-100").numeric()
    obs = SwitchedObserver(m, g["K_plus"], g["K_minus"], method=method)
    A = np.array(obs.spec.model.A.subs({m.symbols[k]: v for k, v in m.values.items()}), dtype=float)
    C = np.array(m.C, dtype=float).reshape(-1)
    x = np.array([0.3, 0.45, -2.0])
    for sig in ([120.0, 1.5, 50.0], [-80.0, 2.0, -10.0]):
        s = sig[0] / sig[1]
        K = np.asarray(g["K_plus"] if s > 0 else g["K_minus"], dtype=float).reshape(-1)
        J = s * A - np.outer(s * K, C)
        f = obs.derivative(x, sig)
        got = obs.step(x, sig, 1e-3)
        want = stage_solve(method, J, f - J @ x, x, 1e-3)
        assert np.max(np.abs(got - want)) <= 1e-12 * np.max(np.abs(want))
        assert np.array_equal(np.array(affine_jacobian(A.tolist(), C.tolist(), s, (s * K).tolist())), J)


@pytest.mark.parametrize("name", sorted(SPECTRA))
@pytest.mark.parametrize("method", ["midpoint", "radau3"])
def test_c_equals_python_reference(name, method):
    m = builtin_model(name)
    g = design(m, SPECTRA[name]).numeric()
    ref = SwitchedObserver(m, g["K_plus"], g["K_minus"], method=method)
    c = CObserver.like(ref)
    assert c.method == method
    rng = np.random.default_rng(7)
    errors = []
    for _ in range(300):
        x = rng.normal(size=ref.size)
        sig = [rng.normal() * 60.0, rng.uniform(0.5, 5.0), rng.normal() * 100.0]
        dt = float(rng.choice([1e-3, 2e-3]))
        want = ref.step(x, sig, dt)
        errors.append(np.max(np.abs(c.step(x, sig, dt) - want)) / np.max(np.abs(want)))
    assert max(errors) <= TOL
    # docs/codegen.md: "observed <= BOUND, about half the steps bit-identical" holds for this pair
    bound = page_number("codegen.md", r"observed ≤ ([\d.e-]+), about half the steps bit-identical")
    assert max(errors) <= bound and 0.3 <= np.mean(np.array(errors) == 0.0) <= 0.7
    t = np.arange(3000) * 1e-3
    rows = np.column_stack([30 * np.sin(9 * t), 1.0 + 0 * t, 100 * np.cos(7 * t)])
    x0 = np.r_[rows[0, 0], np.zeros(ref.size - 1)]
    a, b = c.run(x0, rows, 1e-3), ref.run(x0, rows, 1e-3)
    assert np.max(np.abs(a - b)) <= TOL * np.max(np.abs(b))
    x = x0
    for i in range(50):  # run is repeated step, bit for bit
        x = ref.step(x, rows[i], 1e-3)
    assert np.array_equal(x, b[49])


def test_substepped_radau3_c_equals_python_and_run_equals_step():
    m = builtin_model("abs-xbs4")
    g = design(m, SPECTRA["abs-xbs4"]).numeric()
    ref = SwitchedObserver(m, g["K_plus"], g["K_minus"], method="radau3", h_max="1/50", max_substeps=8)
    c = CObserver.like(ref)
    assert c.generated.h_max == Fraction(1, 50) and c.generated.method == "radau3"
    t = np.arange(2000) * 1e-3
    rows = np.column_stack([30 * np.sin(9 * t), 1.0 + 0 * t, 100 * np.cos(7 * t)])  # |s| dt up to 0.03: 2 sub-steps
    x0 = np.r_[rows[0, 0], np.zeros(ref.size - 1)]
    a, b = c.run(x0, rows, 1e-3), ref.run(x0, rows, 1e-3)
    assert np.max(np.abs(a - b)) <= TOL * np.max(np.abs(b))
    x = x0
    for i in range(40):
        x = ref.step(x, rows[i], 1e-3)
    assert np.array_equal(x, b[39])
    stiff = [400.0, 1.0, 0.0]  # |s| dt = 0.4: 20 sub-steps > 8
    for obs in (c, ref):
        with pytest.raises(ObserverInputError, match="SUBSTEP_LIMIT"):
            obs.step(x0, stiff, 1e-3)


def one_state_model() -> Model:
    """z' = s (z) + u with s = 1, y = z: J = 1 - g, so D(Z) = 1 - dt J / 2 vanishes at dt J = 2 exactly."""
    return Model.from_dict({"name": "one", "states": ["z"], "A": [["1"]], "C": ["1"], "time_scale": "1",
                            "inputs": ["u"], "b": ["1"]})


def test_singular_or_overflowing_solve_is_nonfinite_result_in_c_and_python():
    ref = SwitchedObserver(one_state_model(), [-1.0], [-1.0], method="midpoint")  # J = 1 - 1*(-1) = 2
    c = CObserver.like(ref)
    x = np.array([0.25])
    assert np.allclose(c.step(x, [0.0, 0.0], 0.5), ref.step(x, [0.0, 0.0], 0.5))  # D = 1/2: fine
    for obs in (c, ref):
        with pytest.raises(ObserverInputError) as err:
            obs.step(x, [0.0, 0.0], 1.0)  # dt J = 2: D(Z) = 0
        assert err.value.code == StepStatus.NONFINITE_RESULT
    huge = SwitchedObserver(builtin_model("abs-xbs3"), [1e200, 1e200, 1e200], [1e200, 1e200, 1e200],
                            method="radau3")
    for obs in (huge, CObserver.like(huge)):  # det D(Z) overflows: refused, not a silently wrong solve
        with pytest.raises(ObserverInputError) as err:
            obs.step([0.1, 0.2, 0.3], [1.0, 2.0, 3.0], 1e-3)
        assert err.value.code == StepStatus.NONFINITE_RESULT


def test_radau3_observer_pickles():
    m = builtin_model("abs-xbs4")
    g = design(m, SPECTRA["abs-xbs4"]).numeric()
    obs = SwitchedObserver(m, g["K_plus"], g["K_minus"], method="radau3", readout="z2")
    again = pickle.loads(pickle.dumps(obs))
    assert again.method == "radau3" and again.to_json() == obs.to_json()
    x, sig = [0.5, 0.4, -0.2, 3.0], [2.0, 20.0, 100.0]
    assert np.array_equal(again.step(x, sig, 1e-3), obs.step(x, sig, 1e-3))


def test_adaptive_observer_refuses_implicit_methods(tmp_path, capsys):
    m = builtin_model("abs-adaptive2")
    base = adaptive_xbs_observer(15.0, [50.0, 20.0])
    for method in ("midpoint", "radau3"):
        with pytest.raises(SimulationError, match=f"method '{method}' is implicit.*not affine in its state"):
            AdaptiveSwitchedObserver(m, base.K_plus, base.K_minus, unknown=("c", "d"), Gamma=[50.0, 20.0],
                                     method=method)
        with pytest.raises(CodegenError, match=f"method '{method}' is implicit.*use rk4 or euler"):
            generate_observer(m, (base.K_plus, base.K_minus), unknown=("c", "d"), Gamma=[50.0, 20.0], method=method)
    assert main(["codegen", "abs-adaptive2", "--spectrum", "-15,-15", "--unknown", "c,d", "--gamma", "50,20",
                 "--method", "radau3", "--out", str(tmp_path / "ad")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "radau3" in err and not (tmp_path / "ad").exists()


def test_cli_auto_with_radau3_needs_no_bound_and_rk4_has_no_certificate(tmp_path, capsys):
    assert main(["codegen", "abs-xbs3", "--spectrum", "-100,-100,-100", "--method", "radau3", "--h-max", "auto",
                 "--out", str(tmp_path / "r")]) == 0
    header = (tmp_path / "r" / "switchobs_abs_xbs3.h").read_text()
    readme = (tmp_path / "r" / "README.md").read_text()
    assert "_H_MAX" not in header and "certified for every dt" in header and "Radau IIA" in header
    assert "This file: `radau3`; certified for every dt" in readme
    capsys.readouterr()
    for method in ("rk4", "euler"):
        assert main(["codegen", "abs-xbs3", "--spectrum", "-100,-100,-100", "--method", method, "--h-max", "auto",
                     "--out", str(tmp_path / method)]) == 1
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and f"method {method} has no discrete certificate" in err
        assert "--method radau3" in err and "--h-max VALUE" in err and not (tmp_path / method).exists()


def test_implicit_step_refused_beyond_the_cofactor_size_limit():
    """The cofactor solve grows like 2^n: beyond IMPLICIT_MAX_N the method is refused with the way out."""
    from switchobs.exceptions import ModelError
    from switchobs.spec import STEP_METHODS, implicit_increment
    from switchobs.spec._methods import IMPLICIT_MAX_N

    n = IMPLICIT_MAX_N + 1
    J = [[-1.0 if i == j else None for j in range(n)] for i in range(n)]
    with pytest.raises(ModelError, match=rf"n = {n} > {IMPLICIT_MAX_N}; use an explicit method"):
        implicit_increment(STEP_METHODS["radau3"], J, [1.0] * n, 0.1, lambda d: d if d != 0 else 1.0)
    # at the limit's other side a decoupled system steps each state alike: (1 - z/6) / (1 - 2z/3 + z^2/6), z = -0.1
    inc, det = implicit_increment(STEP_METHODS["radau3"], [[-1.0, None], [None, -1.0]], [1.0, 1.0], 0.1,
                                  lambda d: d if d != 0 else 1.0)
    z = -0.1
    assert inc[0] == inc[1] and inc[0] == pytest.approx((1 - z / 6) / (1 - 2 * z / 3 + z * z / 6), rel=1e-14)
    assert det == pytest.approx((1 - 2 * z / 3 + z * z / 6) ** 2, rel=1e-14)


def _tex(x: float) -> str:
    """``7.8e-04`` as docs/codegen.md writes it: ``$7.8\\cdot 10^{-4}$``."""
    mantissa, exponent = f"{x:.1e}".split("e")
    return f"${mantissa}\\cdot 10^{{{int(exponent)}}}$"


def test_float_builds_of_the_implicit_steps_on_the_random_signals_of_the_c_test():
    """docs/codegen.md, Limitations: the float step's deviation from the double step and the condition of D(Z)."""
    worst, cond, h = {}, 0.0, 0.0
    for name in sorted(SPECTRA):
        m = builtin_model(name)
        g = design(m, SPECTRA[name]).numeric()
        for method in ("rk4", "radau3"):
            ref = SwitchedObserver(m, g["K_plus"], g["K_minus"], method=method)
            c = CObserver.like(ref, real="float")
            A, C = np.asarray(ref.A, float), np.asarray(ref.C, float).reshape(1, -1)
            rng = np.random.default_rng(7)        # the inputs of test_c_equals_python_reference
            errors = []
            for _ in range(300):
                x = rng.normal(size=ref.size).astype(np.float32).astype(float)
                sig = np.array([rng.normal() * 60.0, rng.uniform(0.5, 5.0), rng.normal() * 100.0])
                sig = sig.astype(np.float32).astype(float)
                dt = float(rng.choice([1e-3, 2e-3]))
                want = ref.step(x, sig, dt)
                errors.append(np.max(np.abs(c.step(x, sig, dt) - want)) / np.max(np.abs(want)))
                if method == "radau3" and name == "abs-xbs4":
                    s = sig[0] / sig[1]
                    K = np.asarray(ref.K_plus if s > 0 else ref.K_minus, float).reshape(-1, 1)
                    Z = dt * s * (A - K @ C)
                    cond = max(cond, np.linalg.cond(np.eye(ref.size) - 2 * Z / 3 + Z @ Z / 6))
                    h = max(h, abs(s) * dt)
            worst[name, method] = max(errors)
    assert worst["abs-xbs4", "radau3"] > worst["abs-xbs4", "rk4"]   # the solve costs accuracy in float
    assert_page_says("codegen.md", f"(condition number up to {_tex(cond)} on abs-xbs4 for\n  the random signals of the "
                                   f"C-vs-Python test, $\\lvert s\\rvert\\,dt$ up to {h:.2f})")
    radau3 = _tex(worst["abs-xbs4", "radau3"]), _tex(worst["abs-xbs3", "radau3"])
    assert_page_says("codegen.md", f"by up to {radau3[0]}\n  relative to the state's largest "
                                   f"entry there (radau3, abs-xbs4; {radau3[1]}\n  on abs-xbs3, "
                                   f"against {_tex(max(worst['abs-xbs3', 'rk4'], worst['abs-xbs4', 'rk4']))} for RK4;")
