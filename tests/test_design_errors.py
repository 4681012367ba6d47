"""Bad input to the design core and to `switchobs design`: specific errors, clear messages, exit 2."""

import json
import subprocess
import sys

import pytest
import sympy as sp

from switchobs.design import design
from switchobs.exceptions import (CertificateError, DimensionError, ExpressionError, NotHurwitzError,
                                  NotObservableError, SpectrumError)
from switchobs.model import Model, builtin_model


def model(A, C):
    n = len(A)
    return Model.from_dict({"name": "t", "states": [f"x{i}" for i in range(n)], "A": A, "C": C,
                            "time_scale": "y"})


def test_unobservable_pair_names_direction():
    with pytest.raises(NotObservableError, match=r"direction v = \[0, 1\]"):
        design(model([["1", "0"], ["0", "2"]], ["1", "0"]), "-1,-2")


@pytest.mark.parametrize("spectrum, match", [
    ("-1,-2", "has 2 pole\\(s\\) but model 'abs-xbs3' has dimension 3"),
    ("-1,-2,0", "pole 0 has a non-negative real part"),
    ("-1,-2,3", "pole 3 has a non-negative real part"),
    ("-beta1,beta2,-beta2", "pole beta2 has a non-negative real part"),
    ("-1,-2,-c", "cannot decide the sign of the real part of pole -c"),
    ("-1,-2+I,-3", "not closed under complex conjugation"),
    ("-1,-2,-z1", "uses 'z1', a state or signal"),
    ("-1,,-2", "pole 2 of the spectrum"),
])
def test_bad_spectra(spectrum, match):
    with pytest.raises(SpectrumError, match=match):
        design(builtin_model("abs-xbs3"), spectrum)


def test_non_hurwitz_characteristic_polynomial():
    with pytest.raises(SpectrumError, match="is not Hurwitz"):
        design(builtin_model("abs-xbs3"), characteristic_polynomial="s^3 + s^2 + s + 5")


def test_non_hurwitz_given_gains_report_spectrum():
    m = builtin_model("abs-xbs3").numeric()
    with pytest.raises(NotHurwitzError, match=r"A_plus is not Hurwitz: its spectrum is \["):
        design(m, K_plus="0,0,0")


def test_gain_length_mismatch():
    with pytest.raises(DimensionError, match="K_plus has 2 entries but model 'abs-xbs3' has dimension 3"):
        design(builtin_model("abs-xbs3"), K_plus="1,2")


def test_gain_using_a_state_is_an_expression_error_not_a_shape_error():
    with pytest.raises(ExpressionError, match="K_plus entry 2 uses 'z1', a state or signal") as info:
        design(builtin_model("abs-xbs3"), K_plus="1,z1,2")
    assert not isinstance(info.value, DimensionError)


def test_K_minus_outside_hoang_family_is_refused():
    with pytest.raises(CertificateError, match="admits no common P"):
        design(builtin_model("abs-xbs3"), "-1,-2,-3", K_minus="1,2,3")


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "switchobs", *args], capture_output=True, text=True, timeout=120)


@pytest.mark.parametrize("args, match", [
    (["design", "abs-xbs3", "--spectrum", "-1,-2"], "has 2 pole"),
    (["design", "abs-xbs3", "--spectrum", "-1,-2,1"], "non-negative real part"),
    (["design", "nope-model", "--spectrum", "-1"], "unknown model 'nope-model'"),
    (["design", "abs-xbs3", "--spectrum", "-1,-2,-3", "--param", "a"], "--param expects NAME=VALUE"),
    (["design", "abs-xbs3", "--spectrum", "-1,-2,-3", "--param", "q=1"], "has no parameter 'q'"),
    (["design", "abs-xbs3", "--spectrum", "-1,-2,-3", "--param", "a=-1"], "declared positive"),
    (["design", "abs-xbs3"], "give the target with --spectrum"),
])
def test_cli_design_bad_input_exit_2_without_traceback(args, match):
    proc = run_cli(*args)
    assert proc.returncode == 2
    assert match in proc.stderr
    assert "Traceback" not in proc.stderr


def test_cli_design_bad_toml_files(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "x"\nstates = ["z1", "z2"]\nA = [["0","1"],["0","0"]]\nC = [["1","0"],["0","1"]]\n'
                   'time_scale = "y"\n')
    proc = run_cli("design", str(bad), "--spectrum", "-1,-2")
    assert proc.returncode == 2 and "'C' must be one row" in proc.stderr and "Traceback" not in proc.stderr
    unsafe = tmp_path / "unsafe.toml"
    unsafe.write_text('name = "x"\nstates = ["z1"]\nA = [["__import__(\'os\')"]]\nC = ["1"]\ntime_scale = "y"\n')
    proc = run_cli("design", str(unsafe), "--spectrum", "-1")
    assert proc.returncode == 2 and "'__import__' is not allowed" in proc.stderr
    unobservable = tmp_path / "unobs.toml"
    unobservable.write_text('name = "u"\nstates = ["p", "q"]\nA = [["1","0"],["0","2"]]\nC = ["1","0"]\n'
                            'time_scale = "y"\n')
    proc = run_cli("design", str(unobservable), "--spectrum", "-1,-2")
    assert proc.returncode == 2 and "not observable" in proc.stderr and "v = [0, 1]" in proc.stderr


JSON_KEYS = {"model", "n", "states", "A", "C", "K_plus", "K_minus", "A_plus", "A_minus", "hurwitz_plus",
             "hurwitz_minus", "P", "C_plus", "C_minus", "gain_constraints", "normal_form"}


@pytest.mark.parametrize("model_name, spectrum", [("abs-xbs3", "-beta1,-beta2,-beta2"),
                                                  ("abs-xbs4", "-beta1,-beta1,-beta2,-beta2")])
def test_cli_design_json_round_trips_through_sympify(model_name, spectrum):
    proc = run_cli("design", model_name, "--spectrum", spectrum, "--json")
    assert proc.returncode == 0, proc.stderr
    data = json.loads(proc.stdout)
    assert JSON_KEYS <= set(data) and {"T", "a"} <= set(data["normal_form"])
    assert all(data["verified"].values())
    d = design(builtin_model(model_name), spectrum)
    names = {str(s): s for s in d.model.symbols.values()} | {str(s): s for s in d.design_symbols}
    for key in ("K_plus", "K_minus"):
        parsed = sp.Matrix([sp.sympify(x, locals=names) for x in data[key]])
        assert (parsed - getattr(d, key)).applyfunc(sp.simplify).is_zero_matrix
    P = sp.Matrix([[sp.sympify(x, locals=names) for x in row] for row in data["P"]])
    assert (P - d.P).applyfunc(sp.simplify).is_zero_matrix
    for c in data["gain_constraints"] + data["hurwitz_plus"] + data["hurwitz_minus"]:
        sp.sympify(c, locals=names)


def test_cli_design_user_toml_numeric_params(tmp_path):
    path = tmp_path / "m.toml"
    path.write_text('name = "mine"\nstates = ["p", "q"]\nA = [["0","-g"],["1","0"]]\nC = ["1","0"]\n'
                    'time_scale = "y/v"\nparameters = ["g"]\nexternal = ["v"]\npositive = ["v"]\n')
    proc = run_cli("design", str(path), "--spectrum", "-2,-3", "--param", "g=9.81", "--json")
    assert proc.returncode == 0, proc.stderr
    data = json.loads(proc.stdout)
    A_plus = sp.Matrix([[sp.sympify(x) for x in row] for row in data["A_plus"]])
    assert sp.expand(A_plus.charpoly(sp.Symbol("s")).as_expr() - (sp.Symbol("s") + 2) * (sp.Symbol("s") + 3)) == 0
