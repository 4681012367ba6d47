"""Certified sub-stepping: a step with |s| dt > H_MAX is split into ceil(|s| dt / H_MAX) steps of dt / n.

The tests choose rk4 (not the default radau3, certified for every step): the bound is what rk4 needs, and
its C step makes the Python reference's operations bit for bit.

The error of the switched observer evolves in the rescaled time tau = ∫|s| dt (seed 000 eq. (13), seed 004),
so one step of dt with the signals held is a step h = |s| dt of the sampled error dynamics e+ = R(h A_sigma) e.
For abs-xbs3 with the spectrum {-100, -100, -100} RK4 is stable per mode only for h up to ~0.0279; a braking
record down to 1 m/s with |x2| = 150 m/s^2 at 1 kHz asks for h = 0.15.
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
from _docs_blocks import assert_page_says

from switchobs import certify
from switchobs.cli.main import main
from switchobs.codegen import StepStatus, compile_observer, generate_observer
from switchobs.design import design
from switchobs.exceptions import CodegenError, ObserverInputError, SimulationError
from switchobs.model import builtin_model
from switchobs.observers import AdaptiveSwitchedObserver, ErrorCode, SwitchedObserver, adaptive_xbs_observer
from switchobs.codegen import CObserver

H_MAX = Fraction(1, 100)
#: The plant's XBS (mu') in the braking record, constant: z3 = -c z2 keeps dz2/dt = s (c z2 + z3) = 0.
XBS = 0.5


@pytest.fixture(scope="module")
def xbs3():
    m = builtin_model("abs-xbs3")
    return m, design(m, "-100,-100,-100")


def braking_record(dt: float) -> np.ndarray:
    """Rows (y, vx, u) of a braking wheel at the midpoints of the steps, consistent with the model abs-xbs3.

    vx falls from 30 m/s to 1 m/s in 1.5 s and stays there; x2 = y = 150 sin(2 pi 3 t) m/s^2;
    z2 = XBS and z3 = -c XBS are constant, and u = (dy/dt + s a z2) / b makes dz1/dt = y' exactly.
    """
    m = builtin_model("abs-xbs3")
    a, b = float(m.values["a"]), float(m.values["b"])
    t = (np.arange(round(2.0 / dt)) + 0.5) * dt
    vx = np.maximum(30.0 - 29.0 * t / 1.5, 1.0)
    y = 150.0 * np.sin(6.0 * np.pi * t)
    u = (150.0 * 6.0 * np.pi * np.cos(6.0 * np.pi * t) + y / vx * a * XBS) / b
    return np.column_stack([y, vx, u])


def rk4_matrix(Z: np.ndarray) -> np.ndarray:
    """R(Z) = I + Z + Z^2/2 + Z^3/6 + Z^4/24: one RK4 step of de/dtau = A e with Z = h A."""
    out = term = np.eye(len(Z))
    for k in range(1, 5):
        term = term @ Z / k
        out = out + term
    return out


def test_rk4_per_mode_bound_of_the_demo_design_is_above_h_max(xbs3):
    """rho(R(h A_pm)) < 1 at h = 1/100 for both modes, and reaches 1 near h = 0.0279 (the divergence below)."""
    _, d = xbs3
    num = d.numeric()
    for name in ("A_plus", "A_minus"):
        A = num[name]
        rho = lambda h: max(abs(np.linalg.eigvals(rk4_matrix(h * A))))  # noqa: E731
        assert rho(float(H_MAX)) < 0.4
        assert rho(0.0275) < 1.0 < rho(0.0282)


def test_braking_record_diverges_without_substeps_and_stays_bounded_with_h_max(xbs3):
    m, d = xbs3
    rows = braking_record(1e-3)
    h = np.abs(rows[:, 0] / rows[:, 1]) * 1e-3
    assert 0.149 < h.max() <= 0.15
    plain = compile_observer(generate_observer(m, d, method="rk4"))
    with pytest.raises(ObserverInputError) as err:  # regression fact: one RK4 step per sample blows up
        plain.run([0.0, 0.0, 0.0], rows, 1e-3)
    assert err.value.code == StepStatus.NONFINITE_RESULT
    row = int(str(err.value).split("row ")[1].split(":")[0])
    assert h[:row].max() > 0.0279  # it failed after steps beyond the per-mode bound
    certified = compile_observer(generate_observer(m, d, method="rk4", h_max=H_MAX, max_substeps=16))
    traj = certified.run([0.0, 0.0, 0.0], rows, 1e-3)
    assert np.isfinite(traj).all()
    error = np.abs(traj[:, 1] - XBS)
    assert error[1000:].max() < 1.1  # bounded: the XBS estimate stays within 1.1 of 0.5 at h up to 0.15
    # what remains is the hold of fast signals, not the sub-stepping: ten times the rate, a tenth of the error
    fine = certified.run([0.0, 0.0, 0.0], braking_record(1e-4), 1e-4)
    assert np.abs(fine[10000:, 1] - XBS).max() < 0.15 * error[1000:].max()
    assert_page_says("codegen.md", f"against {error[1000:].max():.3g} for the sub-stepped RK4")


def test_braking_record_radau3_stays_bounded_without_substeps(xbs3):
    """radau3 is certified for every dt: the same record, one step per sample, stays bounded like sub-stepped rk4."""
    m, d = xbs3
    rows = braking_record(1e-3)
    gen = generate_observer(m, d, method="radau3")
    assert gen.h_max is None and "_H_MAX" not in gen.header
    traj = compile_observer(gen).run([0.0, 0.0, 0.0], rows, 1e-3)
    assert np.isfinite(traj).all()
    assert np.abs(traj[1000:, 1] - XBS).max() < 1.1  # the criterion of the sub-stepped rk4 above
    midpoint = compile_observer(generate_observer(m, d, method="midpoint")).run([0.0, 0.0, 0.0], rows, 1e-3)
    # docs/codegen.md quotes both errors: the record holds the signals at the step midpoints
    assert_page_says("codegen.md", f"observed {np.abs(traj[1000:, 1] - XBS).max():.2g} against")
    assert_page_says("codegen.md", f"midpoint {np.abs(midpoint[1000:, 1] - XBS).max():.1g}, as the record")


def needed_substeps(rows: np.ndarray, dt: float, h_max_c: float) -> np.ndarray:
    a = np.abs(rows[:, 0] / rows[:, 1]) * dt
    return np.where(a <= h_max_c, 1, np.ceil(a / h_max_c)).astype(int)


def test_substep_limit_fires_exactly_when_max_substeps_is_too_small(xbs3):
    m, d = xbs3
    rows = braking_record(1e-3)
    num = d.numeric()
    enough = generate_observer(m, d, method="rk4", h_max=H_MAX, max_substeps=64)
    n = needed_substeps(rows, 1e-3, enough.h_max_c)
    most = int(n.max())
    assert most == 15  # |s| dt reaches 0.1499993 (just below 0.15): 15 sub-steps of at most H_MAX
    first = int(np.argmax(n == most))
    for limit in (most, most - 1):
        c = compile_observer(generate_observer(m, d, method="rk4", h_max=H_MAX, max_substeps=limit))
        ref = SwitchedObserver(m, num["K_plus"], num["K_minus"], h_max=H_MAX, max_substeps=limit, method="rk4")
        if limit == most:
            assert np.array_equal(c.run([0.0, 0.0, 0.0], rows, 1e-3), ref.run([0.0, 0.0, 0.0], rows, 1e-3))
            continue
        for obs in (c, ref):
            with pytest.raises(ObserverInputError, match=f"row {first}:") as err:
                obs.run([0.0, 0.0, 0.0], rows, 1e-3)
            assert err.value.code == StepStatus.SUBSTEP_LIMIT == ErrorCode.SUBSTEP_LIMIT
            x = np.array([0.1, 0.2, 0.3])
            with pytest.raises(ObserverInputError, match="SUBSTEP_LIMIT"):
                obs.step(x, rows[first], 1e-3)


def test_nonstiff_step_is_todays_step_and_a_stiff_step_is_n_steps_of_dt_over_n(xbs3):
    m, d = xbs3
    plain = compile_observer(generate_observer(m, d, method="rk4"))
    bounded = compile_observer(generate_observer(m, d, method="rk4", h_max=H_MAX, max_substeps=64))
    x = np.array([0.3, 0.45, -2.0])
    calm = [2.0, 20.0, 50.0]  # |s| dt = 1e-4
    assert np.array_equal(bounded.step(x, calm, 1e-3), plain.step(x, calm, 1e-3))
    stiff = [120.0, 1.5, 50.0]  # |s| dt = 0.08 -> 9 sub-steps (H_MAX is a little below 1/100)
    dt = 1e-3
    manual = x
    for _ in range(9):
        manual = plain.step(manual, stiff, dt / 9)
    assert np.array_equal(bounded.step(x, stiff, dt), manual)


@pytest.mark.parametrize("real", ["double", "float"])
def test_h_max_literal_is_rounded_down(xbs3, real):
    m, d = xbs3
    for h in (Fraction(1, 100), Fraction(1, 3), Fraction(7, 250), 0.1, "2/7"):
        gen = generate_observer(m, d, h_max=h, real=real)
        exact = Fraction(repr(h)) if isinstance(h, float) else Fraction(h)
        assert gen.h_max == exact and Fraction(gen.h_max_c) <= exact
        above = (np.nextafter(np.float32(gen.h_max_c), np.float32(1)) if real == "float"
                 else math.nextafter(gen.h_max_c, 1.0))
        assert Fraction(float(above)) > exact  # the largest real not above the bound
        line = next(ln for ln in gen.header.splitlines() if ln.startswith("#define SWITCHOBS_ABS_XBS3_H_MAX "))
        assert float(line.split()[2].rstrip("f")) == gen.h_max_c
        assert "#define SWITCHOBS_ABS_XBS3_MAX_SUBSTEPS 64" in gen.header
        assert "rounded DOWN" in gen.header and "SUBSTEP_LIMIT" in gen.readme
    assert "#define SWITCHOBS_ABS_XBS3_H_MAX" not in generate_observer(m, d).header  # no bound: no sub-steps


@pytest.mark.parametrize("name", ["abs-xbs3", "abs-xbs4", "abs-adaptive2"])
def test_substepped_c_equals_python_reference(name):
    """Random states and stiff signals: C and Python choose the same n; bit for bit for the switched observers."""
    m = builtin_model(name)
    if name == "abs-adaptive2":
        base = adaptive_xbs_observer(15.0, [50.0, 20.0])
        ref = AdaptiveSwitchedObserver(m, base.K_plus, base.K_minus, unknown=("c", "d"), Gamma=[50.0, 20.0],
                                       h_max="1/50", max_substeps=8)
    else:
        g = design(m, "-40,-60,-60" if name == "abs-xbs3" else "-10,-10,-20,-20").numeric()
        ref = SwitchedObserver(m, g["K_plus"], g["K_minus"], h_max="1/50", max_substeps=8, method="rk4")
    c = CObserver.like(ref)
    assert c.generated.h_max == Fraction(1, 50) and c.generated.max_substeps == 8
    rng = np.random.default_rng(5)
    codes = {0: 0, int(StepStatus.SUBSTEP_LIMIT): 0}
    for _ in range(300):
        x = rng.normal(size=ref.size)
        sig = [rng.normal() * 60.0, rng.uniform(0.5, 5.0), rng.normal() * 100.0]
        dt = float(rng.choice([1e-3, 2e-3]))
        try:
            want = ref.step(x, sig, dt)
        except ObserverInputError as err:
            with pytest.raises(ObserverInputError) as c_err:
                c.step(x, sig, dt)
            assert c_err.value.code == err.code
            codes[err.code] += 1
            continue
        got = c.step(x, sig, dt)
        codes[0] += abs(sig[0] / sig[1]) * dt > 1 / 50  # count the steps that were split
        if name == "abs-adaptive2":  # the reference folds b/a into one constant (docs/codegen.md)
            assert np.max(np.abs(got - want)) <= 1e-12 * np.max(np.abs(want))
        else:
            assert np.array_equal(got, want)
    assert codes[0] > 100 and codes[int(StepStatus.SUBSTEP_LIMIT)] > 3
    t = np.arange(2000) * 1e-3
    rows = np.column_stack([30 * np.sin(9 * t), 1.0 + 0 * t, 100 * np.cos(7 * t)])  # |s| dt up to 0.03: 2 sub-steps
    x0 = np.r_[rows[0, 0], np.zeros(ref.size - 1)]
    a, b = c.run(x0, rows, 1e-3), ref.run(x0, rows, 1e-3)
    if name == "abs-adaptive2":
        assert np.max(np.abs(a - b)) <= 1e-12 * np.max(np.abs(b))
    else:
        assert np.array_equal(a, b)
    x = x0
    for i in range(40):  # run sub-steps like step, row by row
        x = ref.step(x, rows[i], 1e-3)
    assert np.array_equal(x, b[39])


def test_bad_bounds_are_refused():
    m = builtin_model("abs-xbs3")
    g = ([1.0, 2.0, 3.0], [4.0, 5.0, 6.0])
    for bad, message in ((0, "must be > 0"), (-0.5, "must be > 0"), ("x", "positive finite number"),
                         (math.inf, "positive finite number"), (True, "positive finite number"),
                         (Fraction(1, 10**400), "below the smallest positive double")):
        with pytest.raises(CodegenError, match=message):
            generate_observer(m, g, h_max=bad)
        with pytest.raises(SimulationError, match=message):
            SwitchedObserver(m, *g, h_max=bad)
    for bad in (0, -3, 2.5, 2**24 + 1):
        with pytest.raises(CodegenError, match="max_substeps"):
            generate_observer(m, g, h_max=0.01, max_substeps=bad)
    with pytest.raises(CodegenError, match="no effect without h_max"):
        generate_observer(m, g, max_substeps=8)


class _Certificate:
    certified = True
    h_max = Fraction(1, 100)
    statement = "certified while |s(y,t)|*dt <= 1/100 (a stand-in)"


def test_cli_h_max_value_and_auto(tmp_path, capsys, monkeypatch):
    assert main(["codegen", "abs-xbs3", "--spectrum", "-100,-100,-100", "--h-max", "1/100", "--max-substeps", "20",
                 "--out", str(tmp_path / "v")]) == 0
    header = (tmp_path / "v" / "switchobs_abs_xbs3.h").read_text()
    assert "#define SWITCHOBS_ABS_XBS3_H_MAX 0.009999999999999998" in header
    assert "#define SWITCHOBS_ABS_XBS3_MAX_SUBSTEPS 20" in header and "--h-max=1/100" in header
    seen = {}

    def fake(A_plus, A_minus, C, P, *, method):
        seen.update(A_plus=A_plus, A_minus=A_minus, C=C, P=P, method=method)
        return _Certificate()

    monkeypatch.setattr(certify, "discrete_certificate", fake)
    assert main(["codegen", "abs-xbs3", "--spectrum", "-beta1,-beta2,-beta2", "--param", "beta1=100",
                 "--param", "beta2=100", "--h-max", "auto", "--out", str(tmp_path / "a")]) == 0
    header = (tmp_path / "a" / "switchobs_abs_xbs3.h").read_text()
    assert "H_MAX 0.009999999999999998" in header and "(a stand-in)" in header
    assert seen["method"] == "radau3" and not seen["A_plus"].free_symbols   # the default method and seen["A_minus"][0, 0] == -266
    assert not seen["P"].free_symbols and seen["P"].is_symmetric() and list(seen["C"]) == [1, 0, 0]
    capsys.readouterr()
    monkeypatch.delattr(certify, "discrete_certificate")
    assert main(["codegen", "abs-xbs3", "--spectrum", "-100,-100,-100", "--h-max", "auto",
                 "--out", str(tmp_path / "n")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "discrete_certificate" in err and not (tmp_path / "n").exists()
    assert main(["codegen", "super-twisting", "--param", "lam=400", "--param", "alpha=2000", "--h-max", "0.01",
                 "--out", str(tmp_path / "s")]) == 2
    assert main(["codegen", "abs-adaptive2", "--spectrum", "-15,-15", "--unknown", "c,d", "--gamma", "50,20",
                 "--h-max", "auto", "--out", str(tmp_path / "ad")]) == 2
    assert "give --h-max VALUE" in capsys.readouterr().err


def test_constant_time_scale_substeps_like_the_reference():
    """s = 3 is folded into the kernel; the sub-step count uses the constant |s| in C as in Python."""
    from test_codegen_hygiene import constant_scale_model

    model = constant_scale_model()
    ref = SwitchedObserver(model, [1.0, 2.0], [3.0, 4.0], h_max="1/100", max_substeps=5, method="rk4")
    c = CObserver.like(ref)
    assert "_scale(" not in c.generated.source and "a = 3.0 * dt;" in c.generated.source  # s is a literal
    x = [0.4, -0.2]
    for dt in (1e-3, 0.01, 0.015):  # |s| dt = 0.003 (one step), 0.03 (4 sub-steps: H_MAX < 1/100), 0.045 (5)
        assert np.array_equal(c.step(x, [1.0, 2.0], dt), ref.step(x, [1.0, 2.0], dt))
    for obs in (c, ref):
        with pytest.raises(ObserverInputError, match="SUBSTEP_LIMIT"):
            obs.step(x, [1.0, 2.0], 0.02)  # 6 sub-steps > 5
