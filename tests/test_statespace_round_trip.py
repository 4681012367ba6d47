"""Certifying the float StateSpace pair that GainDesign.to_statespace exported: the design's verdict, or a
warning that names the structure the rounding lost."""

import warnings

import pytest

from switchobs.certify import certify, certify_model
from switchobs.design import design_gains
from switchobs.exceptions import StructureLostWarning
from switchobs.model import load_model

control = pytest.importorskip("control", reason="python-control is not installed: the round trip is NOT checked")


@pytest.fixture(scope="module")
def exported():
    model = load_model("abs-xbs3")
    design = design_gains(model, spectrum="-10,-20,-20")
    return model, design, design.to_statespace("plus"), design.to_statespace("minus")


def test_a_rounded_export_warns_and_points_to_the_design(exported):
    model, design, plus, minus = exported
    with pytest.warns(StructureLostWarning, match=r"rounding broke A_plus \+ A_minus = \(K_minus - K_plus\) C "
                                                  r"\(off by .* relative\).*certify_model\(model, gains=design\)"):
        rounded = certify([plus, minus], names=["A_plus", "A_minus"], output=plus.C, dwell=False)
    assert not rounded.hespanha.certified            # the float pair lost the exact common P ...
    exact = certify_model(model, gains=design, dwell=False)
    assert exact.hespanha.certified and exact.verdict != rounded.verdict   # ... which the design keeps


def test_a_pair_that_is_not_an_export_gets_no_warning(exported):
    _, _, plus, minus = exported
    other = control.ss(minus.A, minus.B * 1.01, minus.C, 0)   # B_minus is not K_minus: no Theorem 1 pair
    with warnings.catch_warnings():
        warnings.simplefilter("error", StructureLostWarning)
        report = certify([plus, other], names=["A_plus", "A_minus"], output=plus.C, dwell=False)
    assert not report.hespanha.certified
