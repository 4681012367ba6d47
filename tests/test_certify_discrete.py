"""Discrete certificates of the sampled observer e+ = R(h A_pm) e, for every step length h (issue: certify what ships)."""

from dataclasses import replace
from fractions import Fraction

import numpy as np
import pytest
import sympy as sp

from switchobs.certify._discrete import (STEP_METHODS, DiscreteVerdict, check_discrete, decrease_polynomial,
                                         discrete_certificate)
from switchobs.report import speed_table
from switchobs.design import design_gains as design
from switchobs.exceptions import CertificateError
from switchobs.model import Model, builtin_model

DEMO = {"abs-xbs3": "-beta1,-beta2,-beta2", "abs-xbs4": "-beta1,-beta1,-beta2,-beta2"}


def exact_pair(d, values):
    """(A_plus, A_minus, C, P) of a design at numeric values, as lists of Fractions."""
    subs = {**{d.model.symbols[k]: v for k, v in d.model.values.items()},
            **{s: sp.Integer(values[s.name]) for s in d.design_symbols}}

    def frac(M):
        return [[Fraction(str(sp.nsimplify(x.subs(subs)))) for x in row] for row in M.tolist()]

    return frac(d.A_plus), frac(d.A_minus), frac(d.model.C), frac(d.P)


@pytest.fixture(scope="module", params=sorted(DEMO))
def demo_pair(request):
    """The demo designs: seed 000 Sec. III-E / IV-D gains at beta1 = beta2 = 100."""
    d = design(builtin_model(request.param), DEMO[request.param])
    return request.param, exact_pair(d, {"beta1": 100, "beta2": 100})


def random_pair(n, seed):
    """A random observable normal form with a random real Hurwitz spectrum and the Theorem 1 K_minus (seed 004)."""
    rng = np.random.default_rng(seed)
    a = [int(x) for x in rng.integers(-4, 5, n)]
    A = [[str(a[i]) if j == 0 else ("1" if j == i + 1 else "0") for j in range(n)] for i in range(n)]
    model = Model.from_dict({"name": "random", "states": [f"x{i}" for i in range(n)], "A": A,
                             "C": ["1"] + ["0"] * (n - 1), "time_scale": "y"})
    spectrum = ",".join(str(-int(x)) for x in rng.integers(1, 7, n))
    return exact_pair(design(model, spectrum), {})


def step_matrix(A, h, method):
    m = STEP_METHODS[method]
    Z = h * np.array(A, dtype=float)
    I = np.eye(len(A))
    N = sum(float(c) * np.linalg.matrix_power(Z, k) for k, c in enumerate(m.numerator))
    D = sum(float(c) * np.linalg.matrix_power(Z, k) for k, c in enumerate(m.denominator))
    return np.linalg.solve(D, N) if not m.explicit else N + 0 * I


def relative_decrease(A, P, h, method):
    """Eigenvalues of P - R'PR relative to P (generalised), numerically."""
    import scipy.linalg as sl

    Pf = np.array(P, dtype=float)
    R = step_matrix(A, h, method)
    return sl.eigh(Pf - R.T @ Pf @ R, Pf, eigvals_only=True)


H_GRID = np.concatenate([np.geomspace(1e-3, 10.0, 60), [1e-3, 0.0279, 0.15, 10.0]])


@pytest.mark.parametrize("method", ["radau3", "midpoint"])
def test_demo_design_sampled_observer_certified_for_every_step(demo_pair, method):
    name, (Ap, Am, C, P) = demo_pair
    cert = discrete_certificate(Ap, Am, C, P, method=method)
    assert cert.verdict is DiscreteVerdict.CERTIFIED and cert.h_max is None
    assert cert.strict is (method == "radau3")
    for A in (Ap, Am):
        for h in H_GRID:  # dense sampling plus the ABS extremes h = 0.0279 (h_rho of rk4) and 0.15
            ev = relative_decrease(A, P, h, method)
            assert ev.min() >= -1e-9, (name, method, h, ev.min())


@pytest.mark.parametrize("method", ["rk4", "euler"])
def test_demo_design_explicit_step_has_no_quadratic_certificate(demo_pair, method):
    """The continuous P (the only candidate, by uniqueness) increases along the step for small h: shown exactly and numerically."""
    name, (Ap, Am, C, P) = demo_pair
    cert = discrete_certificate(Ap, Am, C, P, method=method)
    assert cert.verdict is DiscreteVerdict.IMPOSSIBLE and not cert.certified
    assert all(m.witness and m.witness_value < 0 for m in cert.modes)
    # the per-mode bound of the issue: rk4 stops contracting at h_rho = 0.0279 for spectrum -100
    assert cert.h_rho == pytest.approx(0.0279 if method == "rk4" else 0.02, rel=2e-3)
    # numerically: at h = 0.01 the continuous P already increases in some direction (seed 000 design)
    assert relative_decrease(Ap, P, 0.01, method).min() < 0


@pytest.mark.parametrize("n,seed", [(2, 1), (3, 2), (4, 3), (5, 4), (6, 5)])
def test_random_designs_radau3_certified_rk4_refuted_from_n3(n, seed):
    Ap, Am, C, P = random_pair(n, seed)
    radau = discrete_certificate(Ap, Am, C, P, method="radau3")
    assert radau.certified and radau.strict
    for A in (Ap, Am):
        for h in np.geomspace(1e-3, 100.0, 25):
            assert relative_decrease(A, P, h, "radau3").min() > -1e-9
    rk4 = discrete_certificate(Ap, Am, C, P, method="rk4")
    assert rk4.verdict is (DiscreteVerdict.IMPOSSIBLE if n >= 3 else DiscreteVerdict.INCONCLUSIVE)
    euler = discrete_certificate(Ap, Am, C, P, method="euler")
    assert euler.verdict is DiscreteVerdict.IMPOSSIBLE


def test_radau3_decrease_identity_symbolic():
    """D'PD - N'PN = h L'QL + h^3/12 A'QA + h^4/36 (A^2)'P A^2 for a generic 2x2 A and P (module doc)."""
    h = sp.Symbol("h")
    A = sp.Matrix(2, 2, sp.symbols("a0:4"))
    p0, p1, p2 = sp.symbols("p0:3")
    P = sp.Matrix([[p0, p1], [p1, p2]])
    Q = -(A.T * P + P * A)
    I = sp.eye(2)
    D, N = I - 2 * h * A / 3 + h**2 * A**2 / 6, I + h * A / 3
    L = I - h * A / 6
    rhs = h * L.T * Q * L + h**3 / 12 * A.T * Q * A + h**4 / 36 * (A**2).T * P * A**2
    assert (D.T * P * D - N.T * P * N - rhs).expand() == sp.zeros(2, 2)


def test_decrease_polynomial_matches_step_matrix():
    A = [[Fraction(-3), Fraction(1)], [Fraction(-2), Fraction(0)]]
    P = [[Fraction(2), Fraction(1, 3)], [Fraction(1, 3), Fraction(1)]]
    for method, m in STEP_METHODS.items():
        W = decrease_polynomial(A, P, m)
        h = 0.37
        Wf = sum(np.array(Wk, dtype=float) * h**k for k, Wk in enumerate(W))
        Z = h * np.array(A, dtype=float)
        D = sum(float(c) * np.linalg.matrix_power(Z, k) for k, c in enumerate(m.denominator))
        N = sum(float(c) * np.linalg.matrix_power(Z, k) for k, c in enumerate(m.numerator))
        Pf = np.array(P, dtype=float)
        assert np.allclose(Wf, D.T @ Pf @ D - N.T @ Pf @ N, atol=1e-12), method


def tamper(section, path, value):
    import copy

    out = copy.deepcopy(section)
    node = out
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    return out


def test_stored_sections_recheck_and_tampering_is_rejected(demo_pair):
    _, (Ap, Am, C, P) = demo_pair
    for method in ("radau3", "rk4"):
        section = discrete_certificate(Ap, Am, C, P, method=method).to_json()
        again = check_discrete(Ap, Am, C, section["P_d"], section["method"], section)
        assert again.to_json()["verdict"] == section["verdict"]
    good = discrete_certificate(Ap, Am, C, P, method="radau3").to_json()
    bad_P = [row[:] for row in good["P_d"]]
    bad_P[0][0] = str(Fraction(bad_P[0][0]) * Fraction(101, 100))
    cases = [
        tamper(good, ["h_max"], "1/10"),          # a finite bound claimed where none was proved: claims differ
        tamper(good, ["method"], "rk4"),           # the method changed: the rk4 analysis refutes it
        tamper(good, ["modes", 0, "sos", 2, "middle", 0, 0], "-1"),
        tamper(good, ["strict"], False),
    ]
    for section in cases:
        with pytest.raises(CertificateError):
            check_discrete(Ap, Am, C, section["P_d"], section["method"], section)
    with pytest.raises(CertificateError):
        check_discrete(Ap, Am, C, bad_P, "radau3", {**good, "P_d": bad_P})
    refuted = discrete_certificate(Ap, Am, C, P, method="rk4").to_json()
    forged = tamper(refuted, ["modes", 0, "witness", "u"], ["1"] + ["0"] * (len(Ap) - 1))
    with pytest.raises(CertificateError):
        check_discrete(Ap, Am, C, P, "rk4", forged)


def test_unknown_method_is_named():
    with pytest.raises(CertificateError, match="unknown step method 'rk45'"):
        discrete_certificate([[-1]], [[-1]], [[1]], [[1]], method="rk45")


def test_speed_table_in_abs_units():
    """h = |x2| dt / vx: at 1 kHz and |x2| <= 150 m/s^2, h_rho = 0.0279 needs vx >= 5.38 m/s; 1 m/s needs 5.38 kHz."""
    v, rate = speed_table(0.0279, accel_max=150.0, rate_hz=1000.0, speed_min=1.0)
    assert v == pytest.approx(5.376, rel=1e-3) and rate == pytest.approx(5376, rel=1e-3)
    assert speed_table(None, accel_max=150.0, rate_hz=1000.0, speed_min=1.0) == (0.0, 0.0)


# ----------------------------------------------------------------------------- certificate, verify, CLI, docs
@pytest.fixture(scope="module")
def xbs3_discrete():
    from switchobs.certify import certify_model

    model = builtin_model("abs-xbs3")
    return {m: certify_model(model, spectrum="-100,-100,-100", discrete=m, dwell=False) for m in ("radau3", "rk4")}


def test_certificate_discrete_section_verifies_and_rejects_tampering(xbs3_discrete):
    import copy

    from switchobs.certify import verify_certificate

    for method, rep in xbs3_discrete.items():
        assert rep.document["discrete"]["method"] == method
        assert verify_certificate(rep.document).holds
    assert xbs3_discrete["radau3"].discrete_certified is True
    assert xbs3_discrete["rk4"].discrete_certified is False and xbs3_discrete["rk4"].certified
    doc = xbs3_discrete["radau3"].document
    for path, value in ((["discrete", "h_max"], "1/100"), (["discrete", "method"], "rk4"),
                        (["discrete", "P_d", 1, 1], "1/2"), (["discrete", "strict"], False)):
        bad = copy.deepcopy(doc)
        node = bad
        for key in path[:-1]:
            node = node[key]
        node[path[-1]] = value
        report = verify_certificate(bad)
        assert not report.holds and [c.name for c in report.checks if not c.holds] == ["discrete"], path


def test_cli_certify_discrete_exit_codes_and_units(tmp_path, capsys):
    from switchobs.cli.main import main

    out = tmp_path / "cert.json"
    assert main(["certify", "abs-xbs3", "--spectrum=-100,-100,-100", "--no-dwell", "--discrete", "radau3",
                 "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "certified for every |s(y,t)|*dt" in text and "strictly decreases" in text
    assert main(["verify", str(out)]) == 0
    assert main(["certify", "abs-xbs3", "--spectrum=-100,-100,-100", "--no-dwell", "--discrete", "rk4"]) == 1
    text = capsys.readouterr().out
    assert "impossible" in text and "NOT certified" in text and "vx >= 5.39 m/s" in text
    assert main(["certify", "abs-xbs3", "--spectrum=-100,-100,-100", "--discrete", "rk4", "--rate-hz", "0"]) == 2
    assert "--rate-hz" in capsys.readouterr().err


def test_docs_sampled_observer_table_is_a_fresh_run():
    """docs/certify.md quotes switchobs.report.sampled_observer_table for the demo designs verbatim."""
    import re
    from pathlib import Path

    from switchobs.report import sampled_observer_table

    doc = (Path(__file__).resolve().parents[1] / "docs" / "certify.md").read_text("utf-8")
    quoted = re.search(r"<!-- sampled-observer-table:start -->\n(.*?)\n<!-- sampled-observer-table:end -->", doc,
                       re.S).group(1)
    fresh = sampled_observer_table([("abs-xbs3", "-beta1,-beta2,-beta2"), ("abs-xbs4", "-beta1,-beta1,-beta2,-beta2")])
    assert quoted == fresh


def test_discrete_certificate_and_certification_report_round_trip_through_json(xbs3_discrete):
    """SOS proofs (radau3) and witnesses (rk4) read back exactly; a report writes the same JSON again."""
    import json

    from switchobs.certify import CertificationReport, DiscreteCertificate

    for method, rep in xbs3_discrete.items():
        cert = rep.discrete
        assert DiscreteCertificate.from_json(json.loads(json.dumps(cert.to_json()))) == cert
        assert "reasons" not in rep.document["discrete"]  # the document's section is unchanged
        section = DiscreteCertificate.from_json(rep.document["discrete"])
        assert section == replace(cert, reasons=())
        back = CertificationReport.from_json(json.loads(json.dumps(rep.to_json())))
        assert back.to_json() == rep.to_json()
        assert (back.family.exact, back.discrete, back.discrete_method, back.verification, back.verdict,
                back.document) == (rep.family.exact, rep.discrete, method, rep.verification, rep.verdict,
                                   rep.document)
    bad = xbs3_discrete["rk4"].discrete.to_json()
    with pytest.raises(CertificateError, match="'P_d' as a list"):
        DiscreteCertificate.from_json({**bad, "P_d": "nope"})
    with pytest.raises(CertificateError, match="malformed witness"):
        DiscreteCertificate.from_json({**bad, "modes": [{"name": "A_plus", "h_rho": None, "witness": {"u": []}}]})
    with pytest.raises(CertificateError, match="certification report"):
        CertificationReport.from_json({k: v for k, v in xbs3_discrete["rk4"].to_json().items() if k != "hespanha"})
