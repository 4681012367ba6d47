"""A GainDesign, evaluated with `.at`, is what certify, the observers and codegen take (no string round-trip)."""

import numpy as np
import pytest
import sympy as sp

from switchobs.certify import certify_model
from switchobs.codegen import generate_observer
from switchobs.design import design_gains
from switchobs.exceptions import FreeSymbolError, ModelError, SimulationError
from switchobs.model import builtin_model
from switchobs.observers import SwitchedObserver, xbs3_observer, xbs_gains

BETAS = {"beta1": 10, "beta2": 20}


@pytest.fixture(scope="module")
def xbs3():
    model = builtin_model("abs-xbs3")
    return model, design_gains(model, "-beta1,-beta2,-beta2")


def test_hoang2014_sec3e_design_at_values_is_exact_and_still_verifies(xbs3):
    model, d = xbs3
    at = d.at(BETAS)
    assert at.is_numeric and not d.is_numeric
    assert list(at.K_plus) == [sp.Integer(84), sp.Rational(-7312, 375), sp.Rational(-64, 3)]
    assert at.model.parameters == () and at.hurwitz_plus == ()
    assert all(at.verify().values())
    np.testing.assert_array_equal(at.gains_for(model)[0], d.numeric(BETAS)["K_plus"])
    # parameter overrides are honoured, exactly
    assert at.K_plus[0] - d.at({**BETAS, "c": 24}).K_plus[0] == model.values["c"] - 24


def test_hoang2014_certify_model_takes_the_design(xbs3):
    model, d = xbs3
    at = d.at(BETAS)
    by_design = certify_model(model, gains=at, dwell=False)
    by_text = certify_model(model, K_plus=[str(k) for k in at.K_plus], K_minus=[str(k) for k in at.K_minus],
                            dwell=False)
    assert by_design.document == by_text.document and by_design.certified
    with pytest.raises(FreeSymbolError, match="beta1"):
        certify_model(model, gains=d)
    with pytest.raises(ModelError, match="gain design is for model 'abs-xbs3'"):
        certify_model(builtin_model("abs-xbs4"), gains=at)


def test_observers_and_codegen_take_the_design(xbs3):
    model, d = xbs3
    at = d.at(BETAS)
    Kp, Km = at.gains_for(model)
    obs = SwitchedObserver(model, at, readout="z2")
    assert obs.spec == SwitchedObserver(model, Kp, Km, readout="z2").spec
    assert xbs3_observer(10.0, 20.0).spec == obs.spec
    np.testing.assert_array_equal(xbs_gains("abs-xbs3", BETAS)[1], Km)
    gen = generate_observer(model, at)
    assert gen.files == generate_observer(model, (Kp, Km)).files
    # evaluating exactly first rounds once (the symbolic path may differ in the last bit)
    np.testing.assert_allclose(gen.default_params, generate_observer(model, d, values=BETAS).default_params,
                               rtol=1e-15)
    with pytest.raises(SimulationError, match="do not give K_minus"):
        SwitchedObserver(model, at, Km)
    with pytest.raises(SimulationError, match="K_minus is missing"):
        SwitchedObserver(model, Kp)
    with pytest.raises(FreeSymbolError, match="beta1"):
        SwitchedObserver(model, d)
