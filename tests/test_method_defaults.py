"""The step method chosen when none is given is the certified one (radau3) wherever it applies, and choosing an
uncertified one (rk4, euler) for a switched observer says so in one line on stderr."""

from __future__ import annotations

import doctest

import pytest
import sympy as sp

from switchobs.cli.main import main
from switchobs.design import design
from switchobs.loop import EstimatorSpec, default_method
from switchobs.model import builtin_model
from switchobs.observers import AdaptiveSwitchedObserver, SwitchedObserver, adaptive_xbs_observer, xbs3_observer, \
    xbs4_observer
from switchobs.spec import CERTIFIED_METHODS, DEFAULT_METHOD, METHODS, uncertified_note
from switchobs.sweep import BrakingCase


def test_the_default_is_certified_for_every_step_on_the_demo_design():
    from switchobs.certify import discrete_certificate

    assert DEFAULT_METHOD == "radau3" and DEFAULT_METHOD in CERTIFIED_METHODS
    model = builtin_model("abs-xbs3")
    g = design(model, "-100,-100,-100")

    def exact(M):
        return M.xreplace({x: sp.Rational(str(model.values[str(x)])) for x in M.free_symbols})

    cert = discrete_certificate(exact(g.A_plus), exact(g.A_minus), model.C, exact(g.P), method=DEFAULT_METHOD)
    assert cert.certified and cert.h_max is None   # every step length, no bound needed


def test_uncertified_note_names_exactly_the_explicit_methods():
    assert [m for m in METHODS if uncertified_note(m) is not None] == ["rk4", "euler"]
    assert "'euler' is not certified" in uncertified_note("euler") and "n >= 2" in uncertified_note("euler")
    assert "\n" not in uncertified_note("rk4")
    result = doctest.testmod(__import__("switchobs.spec._methods", fromlist=["_"]))
    assert result.attempted >= 2 and result.failed == 0


def test_library_defaults_radau3_for_switched_and_rk4_for_adaptive_observers():
    model = builtin_model("abs-xbs3")
    g = design(model, "-40,-60,-60")
    assert SwitchedObserver(model, g).method == "radau3"
    assert xbs3_observer(10.0, 20.0).method == "radau3" and xbs4_observer(10.0, 20.0).method == "radau3"
    assert adaptive_xbs_observer(100.0, [1e3, 1e3]).method == "rk4"
    adaptive = builtin_model("abs-adaptive2")
    assert AdaptiveSwitchedObserver(adaptive, design(adaptive, "-10,-10").at({}), unknown=("c", "d"),
                                    Gamma=[1.0, 1.0]).method == "rk4"


@pytest.mark.parametrize("kind, method", [("xbs3", "radau3"), ("xbs4", "radau3"), ("adaptive", "rk4"),
                                          ("none", "radau3")])
def test_estimator_spec_and_sweep_case_take_the_kind_default(kind, method):
    assert default_method(kind) == method
    spec = EstimatorSpec(kind)
    assert spec.method == method
    assert EstimatorSpec.from_json(spec.to_json()) == spec
    assert "radau3" not in str(spec) and "rk4" not in str(spec)          # the default is not spelled out
    assert BrakingCase(observer=kind).method == method
    assert BrakingCase(observer=kind) == BrakingCase(observer=kind, method=method)
    if kind != "none":
        other = "midpoint" if kind != "adaptive" else "euler"
        assert str(EstimatorSpec(kind, method=other)).endswith(f", {other})")


def test_generate_observer_defaults(tmp_path):
    pytest.importorskip("casadi")
    from switchobs.codegen import generate_observer

    model = builtin_model("abs-xbs3")
    assert generate_observer(model, design(model, "-40,-60,-60")).method == "radau3"
    adaptive = builtin_model("abs-adaptive2")
    gen = generate_observer(adaptive, design(adaptive, "-10,-10").at({}), unknown=("c", "d"), Gamma=[1.0, 1.0])
    assert gen.method == "rk4"


def _cli(argv, capsys):
    status = main(argv)
    out = capsys.readouterr()
    return status, out.out, out.err


def test_codegen_default_and_the_note_of_an_uncertified_method(tmp_path, capsys):
    pytest.importorskip("casadi")
    base = ["codegen", "abs-xbs3", "--spectrum=-40,-60,-60"]
    status, out, err = _cli(base + ["--out", str(tmp_path / "a")], capsys)
    assert status == 0 and "(double, radau3," in out and err == ""
    status, out, err = _cli(base + ["--method", "rk4", "--out", str(tmp_path / "b")], capsys)
    assert status == 0 and "(double, rk4," in out
    assert err.splitlines() == [f"switchobs codegen: note: {uncertified_note('rk4')}"]
    status, out, err = _cli(["-q"] + base + ["--method", "euler", "--out", str(tmp_path / "c")], capsys)
    assert status == 0 and err == ""


def test_simulate_method_option(capsys):
    base = ["simulate", "--observer", "xbs3", "--duration", "0.05"]
    status, out, err = _cli(base, capsys)
    assert status == 0 and "(radau3," in out and err == ""
    status, out, err = _cli(base + ["--method", "rk4", "--observer-impl", "python"], capsys)
    assert status == 0 and "(rk4," in out and err.splitlines() == [f"switchobs simulate: note: "
                                                                     f"{uncertified_note('rk4')}"]
    status, out, err = _cli(base + ["--method", "rk4", "-q"], capsys)
    assert status == 0 and err == ""
    status, out, err = _cli(["simulate", "--observer", "adaptive", "--duration", "0.05", "--method", "euler"], capsys)
    assert status == 0 and "(euler," in out and err == ""       # no certified alternative there: no note
    status, out, err = _cli(["simulate", "--observer", "adaptive", "--duration", "0.05", "--method", "radau3"],
                            capsys)
    assert status == 2 and "implicit" in err and len(err.splitlines()) == 1
    status, out, err = _cli(["simulate", "--duration", "0.05", "--method", "radau3"], capsys)
    assert status == 2 and "--observer none runs no observer" in err


def test_beyond_the_cofactor_limit_the_default_is_rk4_and_said_to_be_uncertified(tmp_path, capsys):
    from switchobs.spec import default_method
    from switchobs.spec._methods import IMPLICIT_MAX_N

    n = IMPLICIT_MAX_N + 1
    assert default_method(IMPLICIT_MAX_N) == "radau3" and default_method(n) == "rk4"
    model = builtin_model(f"normal-form-{n}")
    spectrum = ",".join(str(-k) for k in range(1, n + 1))
    zeros = {f"a{i}": 0 for i in range(1, n + 1)}
    assert SwitchedObserver(model, design(model, spectrum).at(zeros), params=zeros).method == "rk4"
    pytest.importorskip("casadi")
    status, out, err = _cli(["codegen", f"normal-form-{n}", f"--spectrum={spectrum}"]
                            + [f"--param=a{i}=0" for i in range(1, n + 1)] + ["--out", str(tmp_path / "c")], capsys)
    assert status == 0 and "(double, rk4," in out
    assert err.splitlines() == [f"switchobs codegen: note: {uncertified_note('rk4')}"]
