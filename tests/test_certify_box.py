"""Certificates over parameter boxes: vertex LMIs re-checked exactly, never certifying an unstable point."""

from __future__ import annotations

import copy
import json
from fractions import Fraction

import numpy as np
import pytest

from switchobs.certify import CertificationReport, certify_box, certify_model, verify_certificate
from switchobs.model import parse_box
from switchobs.certify._box import BoxCertificate, model_terms
from switchobs.certify._box_check import check_box_data
from switchobs.exact import evaluate_terms
from switchobs.cli.main import main
from switchobs.design import design_gains
from switchobs.exceptions import CertificateError, ModelError
from switchobs.model import Model, builtin_model

XBS3 = builtin_model("abs-xbs3")


def _gains(model: Model, spectrum: str) -> tuple:
    d = design_gains(model.numeric(), spectrum)
    return d.K_plus, d.K_minus


def _sampled_pairs(model: Model, box, K_plus, K_minus, count: int = 7):
    """A_plus, A_minus on a grid of the box (floats), for the soundness checks."""
    terms, _, _ = model_terms(model, box)
    Kp = np.array([[float(x)] for x in K_plus])
    Km = np.array([[float(x)] for x in K_minus])
    C = np.array([[float(x) for x in model.C]])
    axes = [np.linspace(float(lo), float(hi), count) for lo, hi in box.intervals]
    for point in np.array(np.meshgrid(*axes)).reshape(len(axes), -1).T:
        values = [np.prod([float(p) ** e for p, e in zip(point, m)]) for m, _ in terms]
        A = sum(v * np.array([[float(x) for x in r] for r in M]) for v, (_, M) in zip(values, terms))
        yield A - Kp @ C, -A + Km @ C


def test_box_certificate_of_the_demo_design_is_rechecked_exactly_and_by_verify():
    rep = certify_model(XBS3, spectrum="-100,-100,-100", box=["a=150:230", "c=20:40"], dwell=False)
    box = rep.box
    assert box.certified and box.kind == "dwell-time" and box.vertices == 4
    assert check_box_data(box.data, rep.family.exact) == ""
    assert BoxCertificate.from_json(json.loads(json.dumps(box.to_json()))) == box
    back = CertificationReport.from_json(json.loads(json.dumps(rep.to_json())))
    assert back.to_json() == rep.to_json() and back.box == box and back.document == rep.document
    with pytest.raises(CertificateError, match="parameter box"):
        BoxCertificate.from_json({**box.to_json(), "requested": {"a": ["1"]}})
    check = verify_certificate(rep.document)
    assert check.holds and any(c.name == "box" and c.holds for c in check.checks)
    tampered = copy.deepcopy(rep.document)
    tampered["box"]["certificate"]["P_minus"][0][0][0] = "-1"
    bad = verify_certificate(tampered)
    assert not bad.holds and "P_A_minus,0 > 0 fails" in next(c.detail for c in bad.checks if c.name == "box")
    wider = copy.deepcopy(rep.document)
    wider["box"]["box"]["c"] = ["20", "60"]      # a box the matrices were not made for
    assert not verify_certificate(wider).holds


def test_box_containing_an_unstable_point_is_never_certified():
    # the beta1 = 10, beta2 = 20 gains lose A_plus stability as c grows towards k1 = 84
    K_plus, K_minus = _gains(XBS3, "-10,-20,-20")
    box = parse_box(["c=20:90"])
    unstable = [c for c in np.linspace(20, 90, 141) if np.max(np.linalg.eigvals(
        np.array([[0, -187.5, 0], [0, c, 1], [0, 0, 0]]) - np.array([[float(x)] for x in K_plus])
        @ np.array([[1.0, 0, 0]])).real) >= 0]
    assert unstable, "the planted box must contain an unstable point"
    res = certify_box(XBS3, box, K_plus, K_minus)
    assert not res.certified and res.scale < 1
    assert res.box is not None and float(res.box.upper[0]) < min(unstable)
    for Ap, Am in _sampled_pairs(XBS3, res.box, K_plus, K_minus):
        assert np.max(np.linalg.eigvals(Ap).real) < 0 and np.max(np.linalg.eigvals(Am).real) < 0


def test_certified_box_is_sound_on_a_grid_and_the_sub_box_search_is_monotone():
    K_plus, K_minus = _gains(XBS3, "-10,-20,-20")
    res = certify_box(XBS3, ["a=150:230", "c=20:40"], K_plus, K_minus)
    assert not res.certified and Fraction(0) < res.scale < 1
    for Ap, Am in _sampled_pairs(XBS3, res.box, K_plus, K_minus):
        assert np.max(np.linalg.eigvals(Ap).real) < 0 and np.max(np.linalg.eigvals(Am).real) < 0
    # the matrices of the largest sub-box certify every smaller scaled box
    nominal = [Fraction(375, 2), Fraction(34)]
    for rho in (res.scale / 2, res.scale / 4, Fraction(0)):
        data = copy.deepcopy(res.data)
        data["box"] = res.requested.scaled(nominal, rho).to_json()
        assert check_box_data(data) == ""
    # and do not certify the requested box itself
    data = copy.deepcopy(res.data)
    data["box"] = res.requested.to_json()
    assert check_box_data(data) != ""


def test_polynomial_dependence_is_certified_by_monomial_lifting():
    # a = R^2 Fz / I with the wheel radius uncertain: A is quadratic in r
    data = XBS3.to_dict()
    data.update(name="xbs3-radius", parameters=["r", "b", "c"], positive=["r", "vx"], negative=["b"],
                values={"r": "3/10", "b": "-35/8", "c": "34"})
    data["A"] = [["0", "-r**2*2500/(6/5)", "0"], ["0", "c", "1"], ["0", "0", "0"]]
    data.pop("d")
    model = Model.from_dict(data)
    K_plus, K_minus = _gains(model, "-100,-100,-100")
    res = certify_box(model, ["r=0.28:0.32"], K_plus, K_minus, pieces=2)
    assert res.certified and res.vertices == 3        # r^2 over two pieces of [0.28, 0.32]: 3 distinct ends
    assert check_box_data(res.data) == ""
    terms, _, _ = model_terms(model, res.box)
    assert [m for m, _ in terms] == [[0], [2]]
    assert evaluate_terms(terms, [Fraction(1), Fraction(9, 100)])[0][1] == Fraction(-1875, 10)


@pytest.mark.parametrize("box, message", [
    (["q=1:2"], "not a parameter"),
    (["a=100:120"], "outside the box"),
    (["a=230:150"], "is empty"),
    (["a150:230"], "NAME=LOWER:UPPER"),
])
def test_bad_boxes_are_refused_with_the_reason(box, message):
    K_plus, K_minus = _gains(XBS3, "-100,-100,-100")
    with pytest.raises(ModelError, match=message):
        certify_box(XBS3, box, K_plus, K_minus)


def test_a_parameter_outside_A_does_not_change_the_certificate():
    K_plus, K_minus = _gains(XBS3, "-100,-100,-100")
    res = certify_box(XBS3, ["b=-5:-4"], K_plus, K_minus)
    assert res.inactive == ("b",) and res.certified


def test_cli_certify_with_a_box(tmp_path, capsys):
    out = tmp_path / "cert.json"
    assert main(["certify", "abs-xbs3", "--spectrum=-100,-100,-100", "--no-dwell", "--box", "a=150:230",
                 "--out", str(out)]) == 0
    assert "box a in [150, 230]: certified exactly" in capsys.readouterr().out
    assert main(["verify", str(out)]) == 0
    assert "box: holds" in capsys.readouterr().out
    assert main(["certify", "abs-xbs3", "--spectrum=-10,-20,-20", "--no-dwell", "--box", "c=20:90"]) == 1
    assert "largest certified sub-box" in capsys.readouterr().out
    assert main(["certify", "abs-xbs3", "--spectrum=-10,-20,-20", "--box", "c=20"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "NAME=LOWER:UPPER" in err


@pytest.mark.slow
@pytest.mark.parametrize("command", [
    "switchobs certify abs-xbs3 --spectrum=-100,-100,-100 --no-dwell --box a=150:230 --box c=20:40",
    "switchobs certify abs-xbs3 --spectrum=-10,-20,-20 --no-dwell --box a=150:230 --box c=20:40",
    "switchobs synthesize abs-xbs3 --decay 100 --noise-weight 0.1 --estimate z2",
    "switchobs synthesize abs-xbs3 --decay 100 --noise-weight 0.1 --estimate z2 --box a=150:230",
])
def test_cli_output_shown_on_the_certify_page_is_what_the_command_prints(command, capsys):
    import re
    import shlex
    from pathlib import Path

    page = (Path(__file__).resolve().parents[1] / "docs" / "certify.md").read_text("utf-8")
    block = re.search(r"^\$ " + re.escape(command) + r"\n(.*?)\n```", page, re.S | re.M)
    assert block, f"certify.md has no output of `{command}`"
    main(shlex.split(command)[1:])
    assert capsys.readouterr().out.rstrip("\n") == block.group(1).rstrip("\n")


def test_moderately_sized_box_is_certified_from_the_nominal_bracket_and_a_tampered_jump_is_rejected():
    # normal-form-8 (a chain of integrators, badly conditioned): the dwell time is bracketed on the nominal
    # point and the vertex LMIs are solved once or twice; the exact vertex check still decides
    n = 8
    model = builtin_model(f"normal-form-{n}")
    values = {f"a{i}": "0" for i in range(1, n + 1)}
    spectrum = ",".join(str(-1 - Fraction(i, n - 1)) for i in range(n))
    K_plus, K_minus = _gains(model.with_values(values), spectrum)
    res = certify_box(model, ["a1=-1/100:1/100", "a2=-1/100:1/100"], K_plus, K_minus, values=values, search=False)
    assert res.certified and res.kind == "dwell-time" and res.vertices == 4
    assert check_box_data(res.data) == ""
    cert = res.data["certificate"]
    K = cert["segments"]
    tampered = copy.deepcopy(res.data)
    # P_plus,K just below P_minus,0: the switch from A_plus to A_minus may then increase V
    P_minus_0 = [[Fraction(x) for x in row] for row in cert["P_minus"][0]]
    tampered["certificate"]["P_plus"][K] = [[str(x * (1 - Fraction(1, 2 ** 20))) for x in row] for row in P_minus_0]
    assert "P_A_plus" in check_box_data(tampered)
    shorter = copy.deepcopy(res.data)
    shorter["certificate"]["tau_D"] = str(Fraction(cert["tau_D"]) / 1000)
    assert check_box_data(shorter) != ""
