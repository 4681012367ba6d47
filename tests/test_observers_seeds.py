"""The XBS observers of the seeds on the simplified models for which they are exact.

The true system is the observer's own model (seed 000 eq. (7) and (20), seed 001
eq. (3.2)) with a prescribed wheel-acceleration offset ``z1(t) = Y sin(2 pi f t)``
(zero crossings every half period, as in an ABS cycle); the input ``u`` is the
one that produces this ``z1`` (solved from the first row of the model), and the
truth and the observer are integrated together with DOP853 between the zero
crossings, so that the observer's continuous-time equations are tested, not a
discretisation.
"""

import math

import numpy as np
import pytest
import sympy as sp
from _docs_blocks import assert_page_says
from scipy.integrate import solve_ivp
from scipy.linalg import expm

from switchobs.design import design
from switchobs.exceptions import SpectrumError
from switchobs.model import builtin_model
from switchobs.observers import adaptive_xbs_observer, xbs3_observer, xbs4_observer, xbs_gains

A_RIG, B_RIG = 187.5, -4.375      # seed 000 Fig. 2: a = R^2 Fz / I, b = -R gamma_b / I


def tex(x: float) -> str:
    """``x`` with two significant digits as docs/observers.md writes it: ``22.1``, ``$1.1\\times10^{-7}$``."""
    if abs(x) >= 1e-2:
        return f"{x:.3g}"
    mantissa, exponent = f"{x:.1e}".split("e")
    return f"${mantissa}\\times10^{{{int(exponent)}}}$"


# --------------------------------------------------------------------------- truth
def _model_rhs(model):
    m = model.numeric()
    z = sp.Matrix([m.symbol(n) for n in m.states])
    sig = [m.symbol(n) for n in m.signals]
    u = sp.Matrix([m.symbol(n) for n in m.inputs])
    return sp.lambdify((list(z), *sig), list(m.time_scale * (m.A * z + m.d) + m.b * u)), float(m.b[0])


def simulate_truth(model, observer, xhat0, z_rest0, *, amplitude, freq, T, vx0=25.0, decel=2.0, samples=8):
    """Truth with prescribed z1 and the observer, integrated jointly; also tau = ∫|y|/vx dt."""
    f, b1 = _model_rhs(model)
    w = 2 * math.pi * freq
    n = model.n

    def y_of(t):
        return amplitude * np.sin(w * t)

    def vx_of(t):
        return vx0 - decel * t

    def u_of(t, zr):
        return (amplitude * w * math.cos(w * t) - f([y_of(t), *zr], y_of(t), vx_of(t), 0.0)[0]) / b1

    def rhs(t, X):
        zr, xh = X[:n - 1], X[n - 1:-1]
        y, vx, u = y_of(t), vx_of(t), u_of(t, zr)
        return np.concatenate([f([y, *zr], y, vx, u)[1:], observer.derivative(xh, [y, vx, u]), [abs(y) / vx]])

    X = np.concatenate([z_rest0, xhat0, [0.0]])
    ts, Xs = [0.0], [X]
    edges = np.arange(0.0, T + 1e-12, 0.5 / freq)
    for t0, t1 in zip(edges[:-1], edges[1:]):
        sol = solve_ivp(rhs, (t0, t1), X, method="DOP853", rtol=1e-10, atol=1e-12,
                        t_eval=np.linspace(t0, t1, samples + 1)[1:])
        X = sol.y[:, -1]
        ts += list(sol.t)
        Xs += list(sol.y.T)
    t = np.array(ts)
    Xs = np.array(Xs)
    z = np.column_stack([y_of(t), Xs[:, :n - 1]])
    u = np.array([u_of(tk, zr) for tk, zr in zip(t, Xs[:, :n - 1])])
    return {"t": t, "z": z, "xhat": Xs[:, n - 1:-1], "tau": Xs[:, -1], "u": u, "vx": vx_of(t),
            "crossings": np.searchsorted(t, edges)}


def switched_matrices(obs, A=None):
    A = obs.A if A is None else A
    return A - np.outer(obs.K_plus, obs.C), -A + np.outer(obs.K_minus, obs.C)


def product_of_modes(A_plus, A_minus, tau, crossings):
    """prod exp(A_sigma dtau) over the half periods (y > 0 first), seed 000 eq. (14)."""
    M = np.eye(A_plus.shape[0])
    for k, (i, j) in enumerate(zip(crossings[:-1], crossings[1:])):
        M = expm((A_plus if k % 2 == 0 else A_minus) * (tau[j] - tau[i])) @ M
    return M


def cycle_rates(A_plus, A_minus, tau, crossings):
    """Decay rate in tau of each full cycle: -log rho(e^{A_- dtau2} e^{A_+ dtau1}) / (dtau1 + dtau2)."""
    taus = tau[crossings]
    rates = []
    for k in range(0, len(taus) - 2, 2):
        d1, d2 = taus[k + 1] - taus[k], taus[k + 2] - taus[k + 1]
        M = expm(A_minus * d2) @ expm(A_plus * d1)
        rates.append(-math.log(max(abs(np.linalg.eigvals(M)))) / (d1 + d2))
    return np.array(rates)


# seed 000 Fig. 2 rig tyre (c2 = -34, c3 = 0.65): c = 34, z3 = -c2 c3 = 22.1
XBS3 = {"beta": 150.0, "z_rest0": [-0.3, 22.1], "xhat0": [0.0, 0.5, 0.0]}
# Table I dry road: theta0 = -0.53, alpha0 = d1 d2 theta0 = -606.32 (seed 000 eq. (19))
XBS4 = {"beta": 200.0, "z_rest0": [-0.3, 10.0, 22 * 52 * -0.53], "xhat0": [0.0, 0.5, 0.0, 0.0]}


@pytest.fixture(scope="module")
def run3():
    obs = xbs3_observer(XBS3["beta"], XBS3["beta"])
    return obs, simulate_truth(builtin_model("abs-xbs3"), obs, np.array(XBS3["xhat0"]), XBS3["z_rest0"],
                               amplitude=20.0, freq=8.0, T=1.0)


@pytest.fixture(scope="module")
def run4():
    obs = xbs4_observer(XBS4["beta"], XBS4["beta"])
    return obs, simulate_truth(builtin_model("abs-xbs4"), obs, np.array(XBS4["xhat0"]), XBS4["z_rest0"],
                               amplitude=20.0, freq=8.0, T=1.0)


# --------------------------------------------------------------------------- gains
@pytest.mark.parametrize("beta1, beta2, c", [(10.0, 20.0, 34.0), (150.0, 150.0, 24.0), (3.0, 70.0, 50.0)])
def test_hoang2014_sec3e_gains(beta1, beta2, c):
    """The numeric gains equal the closed formulas of seed 000 Sec. III-E."""
    a = A_RIG
    k1p = c + (beta1 + 2 * beta2)
    k1m = c - (beta1 + 2 * beta2)
    expected_plus = [k1p, -(beta2**2 + 2 * beta1 * beta2 + c * k1p) / a, -beta1 * beta2**2 / a]
    expected_minus = [k1m, -(beta2**2 + 2 * beta1 * beta2 + c * k1m) / a, beta1 * beta2**2 / a]
    K_plus, K_minus = xbs_gains("abs-xbs3", {"beta1": beta1, "beta2": beta2}, params={"c": c})
    np.testing.assert_allclose(K_plus, expected_plus, rtol=1e-14)
    np.testing.assert_allclose(K_minus, expected_minus, rtol=1e-14)
    obs = xbs3_observer(beta1, beta2, params={"c": c})
    A_plus, A_minus = switched_matrices(obs)
    # eq. (17): (c - k1-)/(a k3-) = (c - k1+)/(a k3+) > 0 and c k1+ + a k2+ = c k1- + a k2- < 0
    assert math.isclose((c - K_minus[0]) / (a * K_minus[2]), (c - K_plus[0]) / (a * K_plus[2]), rel_tol=1e-12)
    assert (c - K_plus[0]) / (a * K_plus[2]) > 0
    assert math.isclose(c * K_plus[0] + a * K_plus[1], c * K_minus[0] + a * K_minus[1], rel_tol=1e-12)
    for M in (A_plus, A_minus):
        np.testing.assert_allclose(np.poly(M), np.poly([-beta1, -beta2, -beta2]), rtol=1e-9)


@pytest.mark.parametrize("beta1, beta2", [(10.0, 20.0), (200.0, 200.0)])
def test_hoang2014_sec4d_gains(beta1, beta2):
    """The numeric gains equal the closed formulas of seed 000 Sec. IV-D (two double eigenvalues)."""
    a, al1, al2 = A_RIG, -22.0 * 52.0, 22.0 + 52.0
    exp_p, exp_m = [], []
    for sign, out in ((1, exp_p), (-1, exp_m)):
        k1 = al2 + sign * 2 * (beta1 + beta2)
        k2 = (-al1 - k1 * al2 - (beta1**2 + beta2**2 + 4 * beta1 * beta2)) / a
        k3 = (-k1 * al1 + a * k2 * al2 - sign * 2 * beta1 * beta2 * (beta1 + beta2)) / a
        out += [k1, k2, k3, -beta1**2 * beta2**2 / a]
    K_plus, K_minus = xbs_gains("abs-xbs4", {"beta1": beta1, "beta2": beta2})
    np.testing.assert_allclose(K_plus, exp_p, rtol=1e-13)
    np.testing.assert_allclose(K_minus, exp_m, rtol=1e-13)


def test_gain_arguments_are_checked():
    with pytest.raises(SpectrumError, match="beta2 = -1.0 must be finite and > 0"):
        xbs3_observer(10.0, -1.0)
    with pytest.raises(SpectrumError, match="beta1 = nan"):
        xbs4_observer(math.nan, 1.0)
    with pytest.raises(SpectrumError, match=r"missing \['beta2'\]"):
        xbs_gains("abs-xbs3", {"beta1": 1.0})
    with pytest.raises(SpectrumError, match=r"takes \['beta'\], not \['beta1'\]"):
        xbs_gains("abs-adaptive2", {"beta1": 1.0})
    with pytest.raises(SpectrumError, match="no XBS gain formula for model 'normal-form-3'"):
        xbs_gains("normal-form-3", {"beta": 1.0})


# --------------------------------------------------------------------------- exactness
@pytest.mark.parametrize("which", ["xbs3", "xbs4"])
def test_hoang2014_eq14_error_is_the_switched_linear_system_in_tau(run3, run4, which):
    """e(tau) = prod exp(A_sigma dtau) e(0): the observer is exact for (7) and (20) (eq. (10)-(14), Sec. IV-C)."""
    obs, r = run3 if which == "xbs3" else run4
    e = r["z"] - r["xhat"]
    A_plus, A_minus = switched_matrices(obs)
    M = product_of_modes(A_plus, A_minus, r["tau"], r["crossings"])
    assert np.linalg.norm(M @ e[0] - e[-1]) <= 1e-11 * np.linalg.norm(e[0])
    assert np.linalg.norm(e[-1]) < 1e-5 * np.linalg.norm(e[0])
    norm0, norm1 = np.linalg.norm(e[0]), np.linalg.norm(e[-1])
    assert_page_says("observers.md", f"$\\lVert e\\rVert$ from {tex(norm0).strip('$')} to {tex(norm1)}")


@pytest.mark.parametrize("which", ["xbs3", "xbs4"])
def test_hoang2014_error_decays_exponentially_in_tau_at_the_switched_rate(run3, run4, which):
    """log|e| is linear in tau with the rate of the cycle products (eigenvalues alone do not bound it).

    Each half period of z1 lasts only dtau ~ 0.03 in the rescaled time (the
    slip swing of the cycle), much less than 1/beta, so the decay is not
    min(beta) but -log rho(e^{A_- dtau} e^{A_+ dtau}) / (2 dtau), computed here
    from the spectrum of the cycle products.
    """
    obs, r = run3 if which == "xbs3" else run4
    norm = np.linalg.norm(r["z"] - r["xhat"], axis=1)
    A_plus, A_minus = switched_matrices(obs)
    rates = cycle_rates(A_plus, A_minus, r["tau"], r["crossings"])
    sel = r["tau"] > r["tau"][r["crossings"][2]]           # after the first cycle's transient
    slope, _ = np.polyfit(r["tau"][sel], np.log(norm[sel]), 1)
    assert rates.min() > 0
    assert 0.9 * rates.min() < -slope < 1.1 * rates.max(), (slope, rates.min(), rates.max())
    assert -slope < (XBS3 if which == "xbs3" else XBS4)["beta"]
    assert_page_says("observers.md", f"fitted {-slope:.1f}; cycle-product rates {rates.min():.1f}-{rates.max():.1f}")


def test_hoang2014_appendix_common_lyapunov_function_never_increases(run3):
    """V = e' P e with the common P of the design (eq. (24)-(28)): dV/dtau = -|C_sigma e|^2 <= 0."""
    obs, r = run3
    beta = XBS3["beta"]
    P = design(builtin_model("abs-xbs3"), "-beta1,-beta2,-beta2").numeric({"beta1": beta, "beta2": beta})["P"]
    assert np.linalg.eigvalsh(P).min() > 0
    e = r["z"] - r["xhat"]
    V = np.einsum("ki,ij,kj->k", e, P, e)
    assert np.all(np.diff(V) <= 1e-9 * V[:-1])
    assert V[-1] < 1e-10 * V[0]


def test_hoang2014_discretised_observer_tracks_xbs_at_1khz():
    """The RK4 step with held signals on sampled (7): XBS error floor at 1 kHz, second order in dt (mean hold)."""
    obs = xbs3_observer(XBS3["beta"], XBS3["beta"], method="rk4")   # the page's paragraph on RK4 and Euler
    r = simulate_truth(builtin_model("abs-xbs3"), obs, np.array(XBS3["xhat0"]), XBS3["z_rest0"],
                       amplitude=20.0, freq=8.0, T=1.0, samples=250)   # 4 kHz samples
    sig = np.column_stack([r["z"][:, 0], r["vx"], r["u"]])
    floors, previous = [], []
    for stride in (4, 2):                                            # 1 kHz and 2 kHz
        s = sig[::stride]
        late = r["t"][stride::stride] > 0.75
        for held, out in ((0.5 * (s[:-1] + s[1:]), floors), (s[:-1], previous)):   # mean / previous sample
            traj = obs.run(XBS3["xhat0"], held, stride * 2.5e-4)
            out.append(np.abs(obs.readout(traj) - r["z"][stride::stride, 1])[late].max())
    assert floors[0] < 0.03          # z2 swings over [-0.3, 0.4]; initial error 0.8
    assert floors[0] / floors[1] > 3.0
    assert previous[0] > floors[0] and previous[1] > floors[1]
    assert_page_says("observers.md", f"tracks the XBS within {floors[0]:.2g} after convergence")
    assert_page_says("observers.md", f"at 2 kHz within {floors[1]:.2g} (second order)")
    assert_page_says("observers.md", f"previous sample instead gives {previous[0]:.2g} and {previous[1]:.2g}")


# --------------------------------------------------------------------------- seed 001
@pytest.fixture(scope="module")
def adaptive():
    return adaptive_xbs_observer(60.0, [1e4, 1e4])


def test_aguado2020_eq34_with_the_regressor_of_eq33(adaptive):
    """The generic adaptive observer on abs-adaptive2 is (3.4) with A(t,y), B, Psi, C of (3.3) typed from the seed."""
    a, b = 187.5, 35 / 8
    Gamma = np.diag([1e4, 1e4])
    rng = np.random.default_rng(33)
    for _ in range(6):
        w, th, U = rng.normal(size=2), rng.normal(size=2) * 10, rng.normal(size=(2, 2))
        y, vx, u = rng.choice([-1, 1]) * rng.uniform(1, 60), rng.uniform(3, 40), rng.normal() * 500
        A = y / vx * np.array([[0, -a], [0, 0]])
        B = np.array([-b, 0])
        Psi = np.array([[y**2 / vx, 0], [-b / a * u, y / vx]])
        C = np.array([1.0, 0.0])
        K = y / vx * (adaptive.K_plus if y > 0 else adaptive.K_minus)          # (3.8), (3.15)
        innov = y - C @ w
        w_dot = A @ w + B * u + Psi @ th + (K + U @ Gamma @ U.T @ C) * innov
        th_dot = Gamma @ U.T @ C * innov
        U_dot = (A - np.outer(K, C)) @ U + Psi
        expected = np.concatenate([w_dot, th_dot, U_dot.ravel()])
        got = adaptive.derivative(np.concatenate([w, th, U.ravel()]), [y, vx, u])
        np.testing.assert_allclose(got, expected, rtol=1e-11, atol=1e-9)


def test_aguado2020_eq320_gain_conditions(adaptive):
    """k1+ > 0, k2+ < 0, k1- = -k1+ < 0, k2- = k2+ < 0; A_+ and A_- of (3.16) share the double pole -beta."""
    kp, km = adaptive.K_plus, adaptive.K_minus
    assert kp[0] > 0 and kp[1] < 0 and km[0] == -kp[0] and km[1] == kp[1]
    A_plus, A_minus = switched_matrices(adaptive)
    for M in (A_plus, A_minus):
        np.testing.assert_allclose(np.poly(M), [1.0, 120.0, 3600.0], rtol=1e-12)


@pytest.fixture(scope="module")
def adaptive_run(adaptive):
    """Truth (3.1) on dry asphalt (seed 001 Table 2.1: c = -c2 = 23.99, d = -c2 c3 = 12.4748) in w coordinates."""
    xhat0 = np.array([0.0, 0.0, 10.0, 5.0, 0.0, 0.0, 0.0, 0.0])   # theta_hat(0) = (10, 5), Upsilon(0) = 0
    # w2(0) = z2(0) + (c/a) z1(0) = z2(0) = -0.3 since z1(0) = 0
    return simulate_truth(builtin_model("abs-adaptive2"), adaptive, xhat0, [-0.3], amplitude=40.0, freq=4.0, T=4.0)


def test_aguado2020_prop2_parameters_converge_under_pe(adaptive, adaptive_run):
    """theta_hat -> (c, d) and z2_hat -> z2 when Psi is PE (seed 001 Proposition 2)."""
    r = adaptive_run
    theta_hat = r["xhat"][-1, 2:4]
    np.testing.assert_allclose(theta_hat, [23.99, 12.4748], rtol=1e-4)
    z2 = r["z"][:, 1] - 23.99 / 187.5 * r["z"][:, 0]        # z2 = w2 - (c/a) w1
    err = np.abs(adaptive.readout(r["xhat"]) - z2)
    assert err[0] > 0.1 and err[-1] < 1e-5
    # PE (3.7) with T1 = 1 s as in seed 001 Fig. 3.1: the smallest eigenvalue of each window's integral
    t = r["t"]
    y, vx, u = r["z"][:, 0], r["vx"], r["u"]
    Psi = np.stack([np.stack([y**2 / vx, 0 * y], -1), np.stack([-35 / 8 / 187.5 * u, y / vx], -1)], -2)
    PtP = np.einsum("kji,kjl->kil", Psi, Psi)
    mu1 = [np.linalg.eigvalsh(np.trapezoid(PtP[sel], t[sel], axis=0)).min()
           for sel in ((t >= k) & (t <= k + 1) for k in range(3))]
    assert min(mu1) > 1.0
    rel = np.max(np.abs(r["xhat"][:, 2:4] / np.array([23.99, 12.4748]) - 1), axis=1)
    within = [t[np.flatnonzero(rel > tol)[-1] + 1] for tol in (0.1, 0.01, 0.001)]
    below = t[np.flatnonzero(err >= 0.01)[-1] + 1]
    assert_page_says("observers.md", "$\\hat\\theta(4\\,\\text{s}) = (%.5f, %.5f)$" % tuple(theta_hat))
    assert_page_says("observers.md", "within 10 %% after %.2f s, 1 %% after %.2f s, 0.1 %% after %.2f s"
                     % tuple(within))
    assert_page_says("observers.md", f"XBS error from {tex(err[0])} to {tex(err[-1])} (below 0.01 after {below:.2f} s)")
    assert_page_says("observers.md", f"PE level (3.7) with $T_1 = 1$ s: {min(mu1):.2f}-{max(mu1):.2f}")


def test_aguado2020_eq333_eta_is_the_switched_linear_system(adaptive, adaptive_run):
    """eta = w_tilde - Upsilon theta_tilde obeys d eta/dtau = A_sigma eta exactly (3.33), (3.16)."""
    r = adaptive_run
    xh = r["xhat"]
    w_tilde = xh[:, :2] - r["z"]       # the truth of abs-adaptive2 is already in w coordinates
    theta_tilde = xh[:, 2:4] - np.array([23.99, 12.4748])
    U = xh[:, 4:].reshape(-1, 2, 2)
    eta = w_tilde - np.einsum("kij,kj->ki", U, theta_tilde)
    A_plus, A_minus = switched_matrices(adaptive)
    stop = r["crossings"][8]
    M = product_of_modes(A_plus, A_minus, r["tau"], r["crossings"][:9])
    assert np.linalg.norm(M @ eta[0] - eta[stop]) <= 1e-7 * np.linalg.norm(eta[0])


def test_adaptive_rk4_step_has_order_four():
    """The adaptive right-hand side is nonlinear (Upsilon Gamma Upsilon'): order 4 against a 512x finer RK4."""
    obs = adaptive_xbs_observer(60.0, [1e3, 1e3])
    H = 4e-3
    t = np.arange(25) * H
    rows = np.column_stack([40 * np.sin(2 * np.pi * 4 * t + 0.2), 25 - 2 * t, 800 * np.cos(2 * np.pi * 4 * t)])
    x0 = [8.0, 0.2, 20.0, 10.0, 0.3, 0.0, 0.0, 0.01]
    ref = obs.run(x0, np.repeat(rows, 512, axis=0), H / 512)[-1]
    errors = [np.linalg.norm(obs.run(x0, np.repeat(rows, m, axis=0), H / m)[-1] - ref) for m in (4, 8, 16)]
    observed = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(observed - 4) < 0.3), (errors, observed)
    assert_page_says("observers.md", f"order {observed[0]:.1f}-{observed[-1]:.1f} against a")
