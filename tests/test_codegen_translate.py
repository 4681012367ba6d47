"""Generated C observers against the Python references: same numbers, step by step and over whole runs.

References: the observers of switchobs.observers (seed 000 eq. (8)-(9), seed 001 eq. (3.4)), the
super-twisting observer of switchobs.sensors (seed 003 eq. (8)-(9), (13)), and an independent
pure-Python RK4 of the model equations built here from sympy (for random TOML models).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import sympy as sp
from _docs_blocks import assert_page_says
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from switchobs.codegen import (CObserver, StepStatus, compile_observer, default_prefix, generate_observer,
                               generate_super_twisting, generate_vehicle_speed)
from switchobs.design import design
from switchobs.exceptions import CodegenError
from switchobs.model import Model, builtin_model
from switchobs.observers import (AdaptiveSwitchedObserver, ErrorCode, SwitchedObserver, adaptive_xbs_observer,
                                 xbs3_observer, xbs4_observer)
from switchobs.sensors import super_twisting, super_twisting_gains, vehicle_speed_gain, vehicle_speed_observer

#: Agreement required of the double build (relative, norm-wise).
RTOL_DOUBLE = 1e-12
#: Documented tolerance of the float build: one step, relative to the state's inf-norm ...
RTOL_FLOAT_STEP = 1e-5
#: ... and over a 2000-step run, per state entry relative to that entry's largest magnitude.
RTOL_FLOAT_RUN = 1e-4


def rel_err(a: np.ndarray, b: np.ndarray) -> float:
    """max |a - b| / max(|b|, tiny): norm-wise relative error."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


def random_inputs(rng: np.random.Generator, size: int, n_signals: int = 3):
    x = rng.normal(size=size) * rng.choice([0.1, 1.0, 10.0])
    sig = np.array([rng.normal() * 20.0, rng.uniform(0.5, 40.0), rng.normal() * 300.0][:n_signals])
    dt = float(rng.choice([1e-4, 1e-3, 5e-3]))
    return x, sig, dt


# --------------------------------------------------------------------------- built-in observers
# rk4, not the default radau3: the explicit C step is the reference's bit for bit and the documented float
# tolerances are its own (the implicit steps: test_codegen_implicit.py)
REFERENCES = {
    "abs-xbs3": lambda: xbs3_observer(40.0, 60.0, method="rk4"),
    "abs-xbs4": lambda: xbs4_observer(10.0, 20.0, method="rk4"),
    "abs-adaptive2": lambda: adaptive_xbs_observer(15.0, [50.0, 20.0]),
}


@pytest.fixture(scope="module", params=sorted(REFERENCES))
def pair(request):
    ref = REFERENCES[request.param]()
    return ref, CObserver.like(ref)


def test_hoang2014_eq8_aguado_eq34_c_step_equals_python_reference(pair):
    ref, c = pair
    rng = np.random.default_rng(1)
    assert c.state_names == ref.state_names and c.signal_names == ref.signal_names
    worst = 0.0
    for _ in range(300):
        x, sig, dt = random_inputs(rng, ref.size)
        worst = max(worst, rel_err(c.step(x, sig, dt), ref.step(x, sig, dt)))
    assert worst <= RTOL_DOUBLE
    # what docs/codegen.md says was observed: bit-identical switched observers, the adaptive one to rounding
    if isinstance(ref, AdaptiveSwitchedObserver):
        assert_page_says("codegen.md", f"≤ {worst:.1e} for the adaptive one".replace("e-0", "e-"))
    else:
        assert worst == 0.0


def test_c_run_equals_python_run_and_repeated_steps(pair):
    ref, c = pair
    rng = np.random.default_rng(2)
    k = 3000
    t = np.arange(k) * 1e-3
    # signals of ABS size; much larger ones make the adaptive observer (not fed by its model) diverge
    rows = np.column_stack([10 * np.sin(9 * t) + 0.5 * rng.normal(size=k), 25 - 5 * t, 100 * np.cos(7 * t)])
    x0 = np.zeros(ref.size)
    x0[0] = rows[0, 0]
    traj_c, traj_py = c.run(x0, rows, 1e-3), ref.run(x0, rows, 1e-3)
    assert traj_c.shape == (k, ref.size)
    assert rel_err(traj_c, traj_py) <= RTOL_DOUBLE
    x = x0
    for i in range(50):
        x = c.step(x, rows[i], 1e-3)
    assert rel_err(x, traj_c[49]) == 0.0  # run is the same C loop as step


@pytest.mark.parametrize("name", sorted(REFERENCES))
def test_float_build_within_documented_tolerance(name):
    ref = REFERENCES[name]()
    c = CObserver.like(ref, real="float")
    rng = np.random.default_rng(3)
    worst = 0.0
    for _ in range(200):
        x, sig, dt = random_inputs(rng, ref.size)
        x = x.astype(np.float32).astype(float)  # the same inputs reach both builds
        sig = sig.astype(np.float32).astype(float)
        worst = max(worst, rel_err(c.step(x, sig, dt), ref.step(x, sig, dt)))
    assert worst <= RTOL_FLOAT_STEP
    t = np.arange(2000) * 1e-3
    rows = np.column_stack([10 * np.sin(11 * t), 20 - 4 * t, 100 * np.cos(5 * t)]).astype(np.float32)
    x0 = np.r_[rows[0, 0], np.zeros(ref.size - 1)]
    a, b = c.run(x0, rows, 1e-3), ref.run(x0, rows.astype(float), 1e-3)
    scale = np.maximum(np.max(np.abs(b), axis=0), 1e-12)
    assert np.max(np.abs(a - b) / scale) <= RTOL_FLOAT_RUN


@pytest.mark.parametrize("name", ["abs-xbs3", "abs-adaptive2"])
def test_euler_option_equals_reference_euler(name):
    ref0 = REFERENCES[name]()
    kw = dict(unknown=ref0.unknown, Gamma=ref0.Gamma) if ref0.unknown else {}
    cls = AdaptiveSwitchedObserver if ref0.unknown else SwitchedObserver
    ref = cls(ref0.model, ref0.K_plus, ref0.K_minus, params=ref0.values, method="euler", **kw)
    c = CObserver.like(ref)
    assert c.method == "euler"
    rng = np.random.default_rng(4)
    for _ in range(100):
        x, sig, dt = random_inputs(rng, ref.size)
        assert rel_err(c.step(x, sig, dt), ref.step(x, sig, dt)) <= RTOL_DOUBLE
    x, sig, dt = random_inputs(rng, ref.size)
    # Euler really is x + dt f(x): one step equals the reference derivative times dt
    assert rel_err(c.step(x, sig, dt) - x, dt * ref.derivative(x, sig)) <= 1e-12


def test_hoang2014_eq9_gain_switch_and_continuity_at_s_zero():
    """K_plus acts only where s > 0, K_minus only where s < 0, and the correction vanishes at s = 0."""
    ref = xbs3_observer(40.0, 60.0)
    c = CObserver.like(ref)
    x, vx, u, dt = np.array([0.3, 0.4, -2.0]), 20.0, 50.0, 1e-3
    changed_minus = c.with_params({f"K_minus_{z}": 1e3 for z in ("z1", "z2", "z3")})
    changed_plus = c.with_params({f"K_plus_{z}": 1e3 for z in ("z1", "z2", "z3")})
    assert np.array_equal(c.step(x, [5.0, vx, u], dt), changed_minus.step(x, [5.0, vx, u], dt))
    assert not np.array_equal(c.step(x, [5.0, vx, u], dt), changed_plus.step(x, [5.0, vx, u], dt))
    assert np.array_equal(c.step(x, [-5.0, vx, u], dt), changed_plus.step(x, [-5.0, vx, u], dt))
    assert not np.array_equal(c.step(x, [-5.0, vx, u], dt), changed_minus.step(x, [-5.0, vx, u], dt))
    at_zero = c.step(x, [0.0, vx, u], dt)
    # s = 0: only b u moves the state, whatever the gains
    assert np.allclose(at_zero, x + dt * np.array([float(ref.model.values["b"]) * u, 0.0, 0.0]), rtol=0, atol=1e-15)
    for eps in (1e-6, 1e-9, 1e-12):
        jump = np.max(np.abs(c.step(x, [eps, vx, u], dt) - c.step(x, [-eps, vx, u], dt)))
        assert jump <= 1e3 * eps  # Lipschitz through s = 0, no jump


def test_runtime_model_parameter_equals_reference_built_with_it():
    """Model parameters are runtime parameters: changing c in C equals a reference built with c = 24."""
    m = builtin_model("abs-xbs3")
    gains = design(m, "-40,-60,-60").numeric({"c": 24})
    ref = SwitchedObserver(m, gains["K_plus"], gains["K_minus"], params={"c": 24})
    c = compile_observer(generate_observer(m, design(m, "-40,-60,-60")))
    c24 = c.with_params({"c": 24.0, **{f"K_plus_{z}": k for z, k in zip(m.states, gains["K_plus"])},
                         **{f"K_minus_{z}": k for z, k in zip(m.states, gains["K_minus"])}})
    rng = np.random.default_rng(5)
    for _ in range(50):
        x, sig, dt = random_inputs(rng, 3)
        assert rel_err(c24.step(x, sig, dt), ref.step(x, sig, dt)) <= RTOL_DOUBLE


def test_hoang2014_sec3e_design_symbols_default_params():
    """--param beta1/beta2 give the gains of seed 000 Sec. III-E as default parameters."""
    m = builtin_model("abs-xbs3")
    gen = generate_observer(m, design(m, "-beta1,-beta2,-beta2"), values={"beta1": 40, "beta2": 60})
    a, c, b1, b2 = 187.5, 34.0, 40.0, 60.0
    kp1 = c + b1 + 2 * b2
    km1 = c - (b1 + 2 * b2)
    expected = {"K_plus_z1": kp1, "K_plus_z2": -(b2**2 + 2 * b1 * b2 + c * kp1) / a, "K_plus_z3": -b1 * b2**2 / a,
                "K_minus_z1": km1, "K_minus_z2": -(b2**2 + 2 * b1 * b2 + c * km1) / a, "K_minus_z3": b1 * b2**2 / a,
                "a": a, "b": -4.375, "c": c}
    got = dict(zip(gen.param_names, gen.default_params))
    assert set(got) == set(expected)
    for k, v in expected.items():
        assert math.isclose(got[k], v, rel_tol=1e-15), k


def test_generated_observer_description_round_trips_json():
    m = builtin_model("abs-xbs4")
    gen = generate_observer(m, design(m, "-10,-10,-20,-20"), real="float")
    data = json.loads(json.dumps(gen.to_json()))
    assert data["prefix"] == "switchobs_abs_xbs4" == default_prefix("abs-xbs4")
    assert (data["nx"], data["ns"], data["np"]) == (4, 3, 12)
    assert data["status_codes"]["UNDEFINED_TIME_SCALE"] == 4
    assert [g["expr"] for g in data["guards"]] == ["a", "b", "vx"]
    assert "switchobs_abs_xbs4" in str(gen) and "NP = 12" in str(gen)
    assert default_prefix("my model-2.v1") == "switchobs_my_model_2_v1"


# --------------------------------------------------------------------------- random TOML models
_A_ENTRIES = ["0", "0", "1", "-2", "p1", "-p2", "p3/2", "3/4"]
_D_ENTRIES = ["0", "y", "p2*y", "sin(y)", "y^2", "exp(-y^2)", "atan(y)", "tanh(p3*y)", "sqrt(1+y^2)",
              "y/(1+y^2)", "log(2+cos(y))", "Abs(y)", "p1*y^3"]
_B_ENTRIES = ["0", "1", "p1", "-p2*y", "cos(y)", "1/p1"]
_SCALES = ["y/vx", "y", "y*vx", "sin(y)/vx", "y/sqrt(vx)", "(y+y^3)/(vx*p1)"]


def random_model_toml(rng: np.random.Generator, n: int) -> str:
    """A random model in the TOML format: any dimension, parameters everywhere, nonlinear d, b, s."""
    q = lambda items: '"' + str(rng.choice(items)) + '"'  # noqa: E731
    rows = ",\n     ".join("[" + ", ".join(q(_A_ENTRIES) for _ in range(n)) + "]" for _ in range(n))
    C = ", ".join(['"1"'] + [q(["0", "0", "p2"]) for _ in range(n - 1)])
    vals = "\n".join(f'p{i} = "{rng.integers(1, 40) / 8}"' for i in (1, 2, 3))
    return f"""
name = "random-{n}"
states = [{", ".join(f'"x{i}"' for i in range(1, n + 1))}]
A = [{rows}]
C = [{C}]
d = [{", ".join(q(_D_ENTRIES) for _ in range(n))}]
b = [{", ".join(q(_B_ENTRIES) for _ in range(n))}]
time_scale = {q(_SCALES)}
parameters = ["p1", "p2", "p3"]
external = ["vx"]
inputs = ["u"]
positive = ["p1", "vx"]
[values]
{vals}
"""


def python_rk4(model: Model, K_plus, K_minus, method: str = "rk4"):
    """An independent pure-Python step of dz/dt = s (A z + d + K (y - C z)) + b u, K by the sign of s."""
    vals = {model.symbols[k]: v for k, v in model.values.items()}
    A = np.array(model.A.subs(vals), dtype=float)
    C = np.array(model.C.subs(vals), dtype=float).reshape(-1)
    sig = [model.symbols[s] for s in model.signals]
    s_fn = sp.lambdify(sig, model.time_scale.subs(vals), "math")
    d_fn = sp.lambdify(sig, list(model.d.subs(vals)), "math")
    b_fn = sp.lambdify(sig, list(model.b.subs(vals)), "math")
    Kp, Km = np.asarray(K_plus, float), np.asarray(K_minus, float)

    def step(x, signals, dt):
        s = s_fn(*signals)
        K = Kp if s > 0 else Km
        y, u = signals[0], signals[-1]
        d, b = np.array(d_fn(*signals), float), np.array(b_fn(*signals), float)
        f = lambda z: s * (A @ z + d + K * (y - C @ z)) + b * u  # noqa: E731
        k1 = f(x)
        if method == "euler":
            return x + dt * k1
        k2 = f(x + 0.5 * dt * k1)
        k3 = f(x + 0.5 * dt * k2)
        k4 = f(x + dt * k3)
        return x + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    return step


@settings(max_examples=18, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(n=st.integers(1, 6), seed=st.integers(0, 10**6), method=st.sampled_from(["rk4", "euler"]))
def test_random_toml_models_up_to_n6_match_pure_python_rk4(tmp_path, n, seed, method):
    rng = np.random.default_rng(seed)
    path = tmp_path / f"random-{seed}.toml"
    path.write_text(random_model_toml(rng, n))
    model = Model.from_toml(path)
    Kp, Km = rng.normal(size=n) * 5, rng.normal(size=n) * 5
    c = compile_observer(generate_observer(model, (Kp, Km), method=method))
    ref = python_rk4(model, Kp, Km, method)
    reference_observer = SwitchedObserver(model, Kp, Km, method=method)
    for _ in range(20):
        x, sig, dt = random_inputs(rng, n)
        sig[0] /= 10.0  # keep y^3 terms moderate
        expected = ref(x, sig, dt)
        got = c.step(x, sig, dt)
        assert rel_err(got, expected) <= RTOL_DOUBLE
        assert rel_err(got, reference_observer.step(x, sig, dt)) <= RTOL_DOUBLE


def test_constant_and_parameter_time_scalings(tmp_path):
    """s = 2 (no switching at all) and s = -k (always the K_minus branch) are generated and match the reference."""
    for scale, expect_minus in (("2", False), ("-k", True)):
        path = tmp_path / "const.toml"
        path.write_text(f'name = "const"\nstates = ["z1", "z2"]\nA = [["0", "1"], ["-k", "0"]]\nC = ["1", "0"]\n'
                        f'time_scale = "{scale}"\nparameters = ["k"]\npositive = ["k"]\n[values]\nk = "3"\n')
        model = Model.from_toml(path)
        Kp, Km = [1.0, 2.0], [-5.0, 7.0]
        c, ref = compile_observer(generate_observer(model, (Kp, Km))), SwitchedObserver(model, Kp, Km)
        unused = c.with_params({"K_plus_z1" if expect_minus else "K_minus_z1": 1e6})
        rng = np.random.default_rng(9)
        for _ in range(20):
            x, _, dt = random_inputs(rng, 2)
            sig = [rng.normal()]
            assert rel_err(c.step(x, sig, dt), ref.step(x, sig, dt)) <= RTOL_DOUBLE
            assert np.array_equal(unused.step(x, sig, dt), c.step(x, sig, dt))


# --------------------------------------------------------------------------- super-twisting (seed 003)
def test_msirdi2008_eq13_super_twisting_c_equals_sensors_reference():
    g = super_twisting_gains(1000.0)
    t = np.cumsum(np.r_[0.0, np.random.default_rng(6).uniform(2e-4, 6e-4, size=3000)])  # irregular samples
    x1 = 80 * t + 0.05 * np.sin(30 * t)
    f1 = -5.0 * np.ones_like(t)
    ref = super_twisting(t, x1, gains=g, f1=f1)
    c = compile_observer(generate_super_twisting(g.lam, g.alpha))
    assert c.state_names == ("x1_hat", "x2_hat", "z2") and c.signal_names == ("x1", "f1")
    x = np.array([x1[0], 0.0, 0.0])
    dts = np.diff(t)
    for i in range(t.size - 1):
        x = c.step(x, [x1[i], f1[i]], dts[i])
        expected = np.array([ref.x1_hat[i + 1], ref.x2_hat[i + 1], ref.z2[i]])
        assert rel_err(x, expected) <= RTOL_DOUBLE
    # after the sliding motion is reached x2_hat follows the true speed 80 + 1.5 cos(30 t) (Theorem 2)
    assert abs(x[1] - (80 + 1.5 * math.cos(30 * t[-1]))) < 2.0


def test_msirdi2008_super_twisting_float_tracks_double():
    """In float the sign decisions differ sample by sample; the speed estimate still agrees on average."""
    g = super_twisting_gains(1000.0)
    t = np.arange(4001) * 2.5e-4
    rows = np.column_stack([60 * t, np.zeros_like(t)])
    dbl = compile_observer(generate_super_twisting(g.lam, g.alpha)).run([0.0, 0.0, 0.0], rows, 2.5e-4)
    flt = compile_observer(generate_super_twisting(g.lam, g.alpha, real="float")).run([0.0, 0.0, 0.0], rows,
                                                                                      2.5e-4)
    late = slice(2000, None)
    assert np.sqrt(np.mean((flt[late, 1] - dbl[late, 1]) ** 2)) < 0.01 * 60
    assert abs(np.mean(flt[late, 1]) - 60.0) < 0.5 and abs(np.mean(dbl[late, 1]) - 60.0) < 0.5


def test_msirdi2008_eq15_vehicle_speed_c_equals_sensors_reference():
    g = vehicle_speed_gain(12.0)
    t = np.cumsum(np.r_[0.0, np.random.default_rng(7).uniform(2e-4, 6e-4, size=3000)])  # irregular samples
    x3 = 36.0 - 8.0 * t + 0.3 * np.sin(25 * t)
    ref = vehicle_speed_observer(t, x3, gain=g, x3_0=38.0)
    c = compile_observer(generate_vehicle_speed(g.beta))
    assert c.state_names == ("x3_hat", "z3") and c.signal_names == ("x3",)
    x = np.array([38.0, 0.0])
    dts = np.diff(t)
    for i in range(t.size - 1):
        x = c.step(x, [x3[i]], dts[i])
        assert rel_err(x, np.array([ref.x3_hat[i + 1], ref.z3[i]])) <= RTOL_DOUBLE
    # Theorem 3: |dx3/dt| <= 8 + 7.5 < beta = 24, so the sliding motion is reached and kept
    assert ref.reaching_time_s < 2.0 / (g.beta - 15.5) and abs(x[0] - x3[-1]) < (g.beta + 15.5) * 6e-4
    with pytest.raises(CodegenError, match=r"beta = -1.0 must be a finite number > 0 \(M'Sirdi et al. 2008 eq. \(15\)\)"):
        generate_vehicle_speed(-1.0)


def test_error_codes_shared_with_python_reference():
    """One enum for Python and C (switchobs.spec); the Python reference ends with codes 0-5, and 8 with a step bound."""
    from switchobs.spec import REFERENCE_STATUSES

    assert ErrorCode is StepStatus
    assert [int(s) for s in REFERENCE_STATUSES] == [0, 1, 2, 3, 4, 5, 8]
    assert {StepStatus.BAD_PARAM, StepStatus.BAD_ARGUMENT}.isdisjoint(REFERENCE_STATUSES)


def test_docstring_examples_of_the_codegen_modules_run():
    import doctest

    from switchobs.codegen import _build, _generate

    for module in (_generate, _build):
        result = doctest.testmod(module)
        assert result.attempted > 0 and result.failed == 0, module.__name__
