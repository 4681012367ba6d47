"""LMI synthesis of gain pairs: exact re-check, the single-output obstruction, agreement with certify."""

from __future__ import annotations

import json
from fractions import Fraction

import numpy as np
import pytest

from switchobs.certify import certify, certify_model
from switchobs.synthesis import noise_gain, synthesize, synthesize_box, synthesize_gains
from switchobs.exact import observer_pair
from switchobs.exact import fraction_matrix
from switchobs.synthesis._synthesis import decay_holds, hespanha_pair_holds
from switchobs.cli.main import main
from switchobs.design import design_gains
from switchobs.model import builtin_model

XBS3 = builtin_model("abs-xbs3")


def _floats(M):
    rows = M.tolist() if hasattr(M, "tolist") else M
    return np.array([[float(x) for x in row] for row in rows])


@pytest.mark.parametrize("spectrum, rate", [("-10,-20,-20", 10), ("-100,-100,-100", 100)])
def test_xbs3_synthesis_at_the_decay_rate_of_a_beta_design_without_noise_weight(spectrum, rate):
    beta = design_gains(XBS3.numeric(), spectrum)
    A = _floats(XBS3.numeric().A)
    assert np.max(np.linalg.eigvals(A - _floats(beta.K_plus) @ np.array([[1.0, 0, 0]])).real) \
        == pytest.approx(-rate, rel=1e-4)   # a triple pole: eigenvalues to ~1e-5
    res = synthesize(XBS3, decay_rate=rate, noise_weight=0.0, estimate=["z2"])
    assert res.feasible and res.formulation == "hespanha"
    rep = certify_model(XBS3, K_plus=res.gains()[0], K_minus=res.gains()[1], dwell=False)
    assert rep.certified and rep.hespanha.certified and rep.verdict.dwell_time == "any"


def _random_pair(seed: int, n: int, k: int):
    rng = np.random.default_rng(seed)
    A = rng.integers(-3, 4, size=(n, n))
    C = rng.integers(-2, 3, size=(k, n))
    C[:, 0] += (C[:, 0] == 0)            # no zero column in front: observable for these seeds
    return A, C


@pytest.mark.parametrize("seed, n, k", [(1, 2, 1), (2, 3, 1), (3, 4, 1), (4, 6, 1), (5, 3, 2), (6, 4, 2),
                                        (7, 6, 2)])
def test_random_models_the_pair_satisfies_the_lmis_exactly_and_certify_agrees(seed, n, k):
    A, C = _random_pair(seed, n, k)
    res = synthesize_gains(A.tolist(), C.tolist(), decay_rate=1, noise_weight=0.1)
    assert res.feasible, res.detail
    Cq = [[int(x) for x in row] for row in C]
    Ap = [[A[i][j] - sum(res.K_plus[i][m] * Cq[m][j] for m in range(k)) for j in range(n)] for i in range(n)]
    Am = [[-A[i][j] + sum(res.K_minus[i][m] * Cq[m][j] for m in range(k)) for j in range(n)] for i in range(n)]
    assert decay_holds(Ap, res.X_plus, res.decay_rate) == ""
    assert decay_holds(Am, res.X_minus, res.decay_rate) == ""
    assert hespanha_pair_holds(Ap, Am, res.P, Cq) == ""
    assert max(np.linalg.eigvals(_floats(Ap)).real) < -1 and max(np.linalg.eigvals(_floats(Am)).real) < -1
    rep = certify([Ap, Am], names=["A_plus", "A_minus"], output=Cq, dwell=False)
    assert rep.hespanha.certified and rep.verification.holds
    assert rep.strict.dual is not None and rep.strict.dual.certified      # and no strict CQLF, as proven


def test_strict_formulation_with_a_kernel_is_reported_infeasible_with_the_reason():
    res = synthesize(XBS3, decay_rate=10, strict=True)
    assert not res.feasible and res.formulation == "strict"
    assert "ker C" in res.detail and "(K_minus - K_plus) C" in res.detail
    two = synthesize_gains(_floats(XBS3.numeric().A), [[1, 0, 0], [0, 0, 1]], decay_rate=10, strict=True)
    assert not two.feasible and "ker C" in two.detail


def test_every_state_measured_gives_a_strict_common_P_with_the_decay_rate():
    A = _floats(XBS3.numeric().A)
    res = synthesize_gains(A, np.eye(3), decay_rate=20, noise_weight=0.01, estimate=[1])
    assert res.feasible and res.formulation == "strict" and res.X_plus is res.X_minus
    rep = certify([np.array(A) - _floats(res.K_plus), -np.array(A) + _floats(res.K_minus)], dwell=False)
    assert rep.strict.certified and rep.verdict.arbitrary_switching.value == "UGES"


def test_noise_weight_trades_decay_margin_for_a_smaller_noise_gain():
    fast = synthesize(XBS3, decay_rate=99, noise_weight=0.0, estimate=["z2"])
    quiet = synthesize(XBS3, decay_rate=99, noise_weight=0.01, estimate=["z2"])
    assert quiet.noise_gain["A_plus"] < fast.noise_gain["A_plus"]
    assert quiet.noise_gain["A_minus"] < fast.noise_gain["A_minus"]
    A = _floats(XBS3.numeric().A)
    Kp = _floats(quiet.K_plus)
    assert quiet.noise_gain["A_plus"] == pytest.approx(noise_gain(A - Kp @ np.array([[1.0, 0, 0]]), Kp,
                                                                  np.eye(3)[[1]]))


def test_cli_synthesize(tmp_path, capsys):
    out = tmp_path / "cert.json"
    assert main(["synthesize", "abs-xbs3", "--decay", "99", "--noise-weight", "0.01", "--estimate", "z2",
                 "--out", str(out), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["synthesis"]["feasible"] and data["certification"]["certified"]
    assert main(["verify", str(out)]) == 0
    capsys.readouterr()
    assert main(["synthesize", "abs-xbs3", "--decay", "-1"]) == 2
    assert main(["synthesize", "abs-xbs3", "--decay", "10", "--estimate", "z9"]) == 2
    err = capsys.readouterr().err
    assert "decay_rate must be positive" in err and "z9" in err


# ----------------------------------------------------------------------------- joint synthesis over a box
def test_box_synthesis_is_joint_over_the_load_range_and_the_box_certificate_agrees(tmp_path, capsys):
    """abs-xbs3 over a = R^2 Fz / I in [150, 230]: one X per mode for both vertices, exact; certify_box agrees."""
    out = tmp_path / "cert.json"
    assert main(["synthesize", "abs-xbs3", "--decay", "100", "--noise-weight", "0.1", "--estimate", "z2",
                 "--box", "a=150:230", "--out", str(out), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    syn = data["synthesis"]
    assert syn["feasible"] and syn["formulation"] == "polytopic" and syn["vertices"] == 2
    assert syn["box"] == {"a": ["150", "230"]} and syn["P"] is None
    assert data["certification"]["box"]["certified"]
    K_plus, K_minus, X_plus, X_minus = (fraction_matrix(syn[k]) for k in ("K_plus", "K_minus", "X_plus", "X_minus"))
    C = [[Fraction(1), Fraction(0), Fraction(0)]]
    for a in (150, 230):   # the vertices, re-checked here from the JSON alone
        A = fraction_matrix(XBS3.with_values({"a": a}).numeric().A.tolist())
        Ap, Am = observer_pair(A, C, K_plus, K_minus)
        assert decay_holds(Ap, X_plus, Fraction(100)) == "" and decay_holds(Am, X_minus, Fraction(100)) == ""
    for a in np.linspace(150, 230, 9):   # and so every point between them decays at the rate
        A = _floats(XBS3.with_values({"a": float(a)}).numeric().A)
        for M in (A - _floats(K_plus) @ _floats(C), -A + _floats(K_minus) @ _floats(C)):
            assert max(np.linalg.eigvals(M).real) < -100
    assert main(["verify", str(out)]) == 0


def test_box_synthesis_strict_needs_every_state_measured():
    res = synthesize_box(XBS3, ["a=150:230"], decay_rate=10, strict=True)
    assert not res.feasible and res.formulation == "polytopic-strict" and "ker C" in res.detail


def test_synthesised_pair_goes_through_codegen_and_the_c_observer_tracks_like_python():
    """Issue 19: a pair from ``synthesize`` (abs-xbs3 at the seed 000 Sec. III-E values) is generated as C by
    the same path as a symbolic design, and its certified step (radau3) runs in C as in Python on a record
    whose time scale changes sign (both modes are exercised)."""
    from switchobs.codegen import CObserver
    from switchobs.observers import SwitchedObserver

    model = builtin_model("abs-xbs3")
    res = synthesize(model, decay_rate=40, noise_weight=0.1, estimate=["z2"])
    assert res.feasible, res.detail
    K_plus, K_minus = ([float(Fraction(k[0])) for k in K] for K in (res.K_plus, res.K_minus))
    ref = SwitchedObserver(model, K_plus, K_minus, params=model.values, method="radau3")
    c_obs = CObserver.like(ref)
    dt, n = 1e-3, 3000
    t = np.arange(n) * dt
    x2 = 30 * np.sin(2 * np.pi * 1.5 * t)                    # wheel acceleration offset: s = x2/vx changes sign
    rows = np.column_stack([x2, np.full(n, 20.0), np.zeros(n)][: len(ref.signal_names)])
    x0 = np.array([x2[0] + 5.0, 0.5, -3.0])
    expected = ref.run(x0, rows, dt)
    got = c_obs.run(x0, rows, dt)
    assert np.all(np.isfinite(expected)) and np.any(x2 > 0) and np.any(x2 < 0)
    assert np.max(np.abs(got - expected)) <= 1e-9 * np.max(np.abs(expected))


# ----------------------------------------------------------------------------- preconditioning (issue 19)
XBS4 = builtin_model("abs-xbs4")


def test_xbs4_at_decay_40_is_certified_exactly_and_its_gains_round_trip_through_verify(tmp_path, capsys):
    """Before the Riccati coordinates the rounded gains of abs-xbs4 at rate 40 failed the exact check."""
    out = tmp_path / "cert.json"
    assert main(["synthesize", "abs-xbs4", "--decay", "40", "--out", str(out), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    syn = data["synthesis"]
    assert syn["feasible"] and syn["formulation"] == "hespanha" and data["certification"]["certified"]
    K_plus, K_minus, P, X_plus, X_minus = (fraction_matrix(syn[k]) for k in ("K_plus", "K_minus", "P", "X_plus",
                                                                             "X_minus"))
    A = fraction_matrix(XBS4.numeric().A.tolist())
    C = [[Fraction(1), Fraction(0), Fraction(0), Fraction(0)]]
    Ap, Am = observer_pair(A, C, K_plus, K_minus)   # rebuilt here from the JSON alone
    assert decay_holds(Ap, X_plus, Fraction(40)) == "" and decay_holds(Am, X_minus, Fraction(40)) == ""
    assert hespanha_pair_holds(Ap, Am, P, C) == ""
    assert max(np.linalg.eigvals(_floats(Ap)).real) < -40
    assert main(["verify", str(out)]) == 0


def test_riccati_scaling_puts_the_kalman_filters_at_the_identity():
    from scipy.linalg import solve_continuous_are

    from switchobs.synthesis._synthesis import riccati_scaling

    A, C = _floats(XBS4.numeric().A) / 40, np.array([[1.0, 0, 0, 0]])
    S = riccati_scaling(A, C, (1, -1))
    X0 = sum(np.linalg.inv(solve_continuous_are((s * A + np.eye(4)).T, C.T, np.eye(4), np.eye(1))) for s in (1, -1))
    assert np.allclose(np.linalg.solve(S.T, np.linalg.solve(S.T, X0).T), np.eye(4), atol=1e-8)
    assert np.allclose(S, np.triu(S))
    # a mode that no gain stabilises (an unobservable unstable state): no scaling, the LMI will say so
    assert np.array_equal(riccati_scaling(np.diag([-1.0, 1.0]), np.array([[1.0, 0.0]]), (1,)), np.eye(2))


def test_nominal_and_box_synthesis_share_the_preconditioning_and_need_it(monkeypatch):
    """Both paths solve in the coordinates of ``riccati_scaling``; without them abs-xbs4 at rate 100 fails."""
    from switchobs.synthesis import _synthesis

    calls = []
    real = _synthesis.riccati_scaling
    monkeypatch.setattr(_synthesis, "riccati_scaling", lambda *a: calls.append(a[2]) or real(*a))
    assert synthesize(XBS4, decay_rate=100).feasible
    assert synthesize_box(XBS3, ["a=150:230"], decay_rate=10, noise_weight=0.1, estimate=["z2"]).feasible
    assert calls == [(1,), (1,), (-1,)]     # the Hespanha K_plus; then one X per mode over the box
    monkeypatch.setattr(_synthesis, "riccati_scaling", lambda A, C, signs: np.eye(len(A)))
    assert not synthesize(XBS4, decay_rate=100).feasible


def test_decay_certificate_re_solves_for_the_rounded_gains_and_never_certifies_a_slow_matrix():
    from switchobs.synthesis._synthesis import decay_certificate

    A = [[Fraction(-3), Fraction(1000)], [Fraction(0), Fraction(-4)]]   # strongly non-normal, decays at 3
    bad_start = np.eye(2)                                                # He(A) + 4 I is not negative
    X, why = decay_certificate([A], Fraction(2), np.eye(2), bad_start)
    assert X is not None and why == "" and decay_holds(A, X, Fraction(2)) == ""
    X, why = decay_certificate([A], Fraction(3), np.eye(2), None)        # rate 3 is the abscissa itself
    assert X is None and why
    both = [A, [[Fraction(-4), Fraction(1000)], [Fraction(0), Fraction(-5)]]]   # A - I: a common X exists
    X, why = decay_certificate(both, Fraction(1), np.eye(2), bad_start)  # several matrices: the margin LMI
    assert X is not None and all(decay_holds(M, X, Fraction(1)) == "" for M in both)


def test_sixteen_states_normal_form_synthesis_is_certified():
    """normal-form-16 (a chain of integrators, Gramian condition number 6e10) did not finish in 120 s."""
    model = builtin_model("normal-form-16").with_values({f"a{i}": "0" for i in range(1, 17)})
    res = synthesize(model, decay_rate="1/2", noise_weight=0.1)
    assert res.feasible, res.detail
    assert max(np.linalg.eigvals(_floats(model.numeric().A) - _floats(res.K_plus) @ np.eye(1, 16)).real) < -0.5
