"""Symbolic designs past N = 7: the re-check by substitution and the compact text (issue 18)."""

import dataclasses

import pytest
import sympy as sp

from switchobs.cli.main import main
from switchobs.design import design_gains
from switchobs.design._recheck import lyapunov_by_substitution
from switchobs.model import builtin_model


def _gains(n: int) -> str:
    return ",".join(f"k{i}" for i in range(1, n + 1))


def _substituted(d) -> bool | None:
    return lyapunov_by_substitution(d.A_plus, d.A_minus, d.P, d.C_plus, d.C_minus, d.alpha_plus)


@pytest.mark.parametrize("n, target", [(3, "gains"), (5, "gains"), (4, "spectrum")])
def test_pasillas_theorem1_recheck_by_substitution_holds(n, target):
    model = builtin_model(f"normal-form-{n}")
    if target == "gains":
        d = design_gains(model, K_plus=_gains(n))
    else:
        d = design_gains(model, ",".join(f"-l{i}" for i in range(1, n + 1)))
    assert _substituted(d) is True
    assert all(d.verify().values())


def test_recheck_by_substitution_refuses_a_tampered_P_and_verify_then_fails():
    d = design_gains(builtin_model("normal-form-3"), K_plus=_gains(3))
    P = sp.Matrix(d.P)
    P[0, 0] += 1
    bad = dataclasses.replace(d, P=sp.ImmutableMatrix(P))
    assert _substituted(bad) is None
    checks = bad.verify()
    assert checks["lyapunov_plus"] is False and checks["lyapunov_minus"] is False


def test_recheck_by_substitution_refuses_another_shape():
    d = design_gains(builtin_model("normal-form-3"), K_plus=_gains(3))
    assert lyapunov_by_substitution(d.A_plus.T, d.A_minus, d.P, d.C_plus, d.C_minus, d.alpha_plus) is None
    assert lyapunov_by_substitution(d.A_plus, d.A_plus, d.P, d.C_plus, d.C_minus, d.alpha_plus) is None


def test_text_is_full_up_to_n4_and_compact_beyond():
    small = design_gains(builtin_model("normal-form-3"), K_plus=_gains(3))
    assert str(small) == small.describe(full=True)
    assert "common Lyapunov matrix P =" in str(small)
    big = design_gains(builtin_model("normal-form-5"), K_plus=_gains(5))
    text = str(big)
    assert "u_m = N_m / D" in text and "N_5 = " in text and "--full" in text
    assert "K_plus = [k1, k2, k3, k4, k5]" in text
    full = big.describe(full=True)
    assert "common Lyapunov matrix P =" in full and "⎡" not in full  # sstr rows, not the pretty printer
    assert len(text) < len(full)


def test_cli_design_compact_full_and_progress(capsys):
    assert main(["design", "normal-form-5", "--gains-plus", _gains(5)]) == 0
    out, err = capsys.readouterr()
    assert "u_m = N_m / D" in out and "all hold exactly" in out
    assert "[1/2] design:" in err and "[2/2] re-check:" in err
    assert main(["design", "normal-form-5", "--gains-plus", _gains(5), "--full", "--no-verify"]) == 0
    out, err = capsys.readouterr()
    assert "common Lyapunov matrix P =" in out and "exact re-check" not in out
    assert "[1/1] design:" in err
    assert main(["design", "normal-form-3", "--gains-plus", _gains(3)]) == 0
    assert capsys.readouterr().err == ""


@pytest.mark.slow
def test_cli_design_normal_form_8_all_symbolic_rechecks_exactly(capsys):
    assert main(["design", "normal-form-8", "--gains-plus", _gains(8)]) == 0
    assert "all hold exactly" in capsys.readouterr().out
