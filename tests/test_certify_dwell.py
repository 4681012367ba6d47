"""Geromel–Colaneri dwell time: certified bound, periodic switching above it contracts, below it may not."""

import dataclasses
from fractions import Fraction

import numpy as np
import pytest
import scipy.linalg
from _docs_blocks import assert_page_says

from switchobs.certify import classify_planar, dwell_time, verify_certificate
from switchobs.certify._verify import _check_dwell

LIBERZON = ([["-0.1", -1], [2, "-0.1"]], [["-0.1", -2], [1, "-0.1"]])   # Liberzon (2003), Sec. 2.1.3
BRANICKY = ([[-1, -100], [10, -1]], [[-1, 10], [-100, -1]])            # case (i): unbounded switching exists
PAIRS = {"liberzon": LIBERZON, "branicky": BRANICKY}


def _float(M):
    return np.array([[float(Fraction(str(x))) for x in r] for r in M])


@pytest.fixture(scope="module")
def results():
    return {name: dwell_time(list(pair)) for name, pair in PAIRS.items()}


@pytest.mark.parametrize("name", list(PAIRS))
def test_periodic_switching_slower_than_tau_D_contracts(name, results):
    A1, A2 = (_float(M) for M in PAIRS[name])
    res = results[name]
    assert res.certified and res.tau_D is not None
    T = float(res.tau_D)
    worst = 0.0
    for t1 in np.linspace(T, 3 * T, 15):
        for t2 in np.linspace(T, 3 * T, 15):
            Phi = scipy.linalg.expm(A2 * t2) @ scipy.linalg.expm(A1 * t1)
            worst = max(worst, max(abs(np.linalg.eigvals(Phi))))
    assert worst < 1
    if name == "liberzon":   # docs/certify.md, "Unstable under fast switching"
        tau = res.tau_D
        assert_page_says("certify.md", f"$\\tau_D = {tau.numerator}/{tau.denominator} = {float(tau):.4g}$ "
                                       f"(LMI infeasible at {res.tau_lower:.5g})")
        assert_page_says("certify.md", f"(max {worst:.3g} on a 15×15 grid)")
        assert_page_says("certify.md", f"case (iv), $R = {classify_planar(*PAIRS[name]).R:.5g} > 1$")


@pytest.mark.parametrize("name", list(PAIRS))
def test_fast_switching_can_be_unstable_and_tau_D_exceeds_it(name, results):
    """Each matrix is Hurwitz, classify says unbounded trajectories exist, and a fast periodic switching diverges."""
    pair = PAIRS[name]
    cls = classify_planar(*pair)
    assert cls.stability == "unbounded"
    A1, A2 = (_float(M) for M in pair)
    if cls.case == "iv":
        # the worst switching of the BBM construction: its half-turn product has eigenvalue -R, |R| > 1
        Phi = cls.half_turn_product([A1, A2])
        assert max(abs(np.linalg.eigvals(Phi))) > 1
        durations = [dt for _, dt in cls.worst_switching]
    else:
        # case (i): a convex combination is not Hurwitz, so fast periodic switching diverges
        t = 1e-3
        Phi = scipy.linalg.expm(A2 * t) @ scipy.linalg.expm(A1 * t)
        assert max(np.linalg.eigvals(0.5 * (A1 + A2)).real) > 0
        assert max(abs(np.linalg.eigvals(Phi))) > 1
        durations = [t, t]
    assert min(durations) < float(results[name].tau_D)


def test_dwell_certificate_holds_for_every_longer_dwell_time(results):
    """Geromel-Colaneri: the same P_p certify any T >= tau_D (checked exactly at 3/2 tau_D and 4 tau_D)."""
    res = results["liberzon"]
    cert = res.certificate()
    for factor in (Fraction(3, 2), Fraction(4)):
        longer = dataclasses.replace(cert, tau_D=str(res.tau_D * factor))   # certificate() is a schema entry
        assert _check_dwell(res.family.names, res.family.exact, longer).holds


def test_dwell_certificate_fails_well_below_tau_D(results):
    res = results["liberzon"]
    shorter = dataclasses.replace(res.certificate(), tau_D=str(res.tau_D / 4))
    check = _check_dwell(res.family.names, res.family.exact, shorter)
    assert not check.holds
    assert check.detail.startswith("exp(A_") and "tau_D) - P_A_" in check.detail and "< 0 fails" in check.detail


def test_bisection_brackets_tau_D(results):
    res = results["liberzon"]
    assert res.tau_lower < res.tau_numeric <= res.tau_lower * (1 + 2e-3)
    assert res.tau_numeric <= float(res.tau_D) < 7 * res.tau_numeric


def test_dwell_certificate_round_trips_through_verify(results):
    res = results["branicky"]
    doc = {"format": "switchobs-certificate", "version": 1,
           "family": res.family.to_json(), "certificates": [res.certificate().to_json()],
           "verdict": {"arbitrary_switching": "unknown", "dwell_time": str(res.tau_D), "strict_cqlf": "unknown",
                       "common_lyapunov": "unknown"}}
    assert verify_certificate(doc).holds


@pytest.mark.slow
def test_hoang2014_xbs4_dwell_time_certified_despite_a_thin_margin():
    """abs-xbs4 (seed 000 Sec. IV), beta = (40, 60): the GC margin near the bound is at solver accuracy."""
    from switchobs.certify import certify_model
    from switchobs.model import builtin_model

    rep = certify_model(builtin_model("abs-xbs4"), spectrum="-40,-40,-60,-60", dwell=True)
    assert rep.dwell is not None and rep.dwell.certified
    assert rep.verdict.dwell_time == "any" and rep.verification.holds
    kinds = [c["kind"] for c in rep.document["certificates"]]
    assert "dwell-time" in kinds and "hespanha" in kinds
