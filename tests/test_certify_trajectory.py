"""Assumption 1 on sampled signals (seed 001 (3.7), (3.17)-(3.19); seed 004 (6)-(7)) and Theorem 3's constants."""

import numpy as np
import pytest
from _docs_blocks import assert_page_says

from switchobs.certify import (admissible_constants, pe_level, regressor_excitation, time_rescaling,
                               trajectory_conditions, zero_crossings)
from switchobs.exceptions import DimensionError, ModelError, SimulationError
from switchobs.model import Model, builtin_model


def test_seed001_eq312_tau_is_exact_for_piecewise_linear_s():
    # s = t - 1 on [0, 2]: two triangles of area 1/2 even when the zero falls between samples
    t = np.array([0.0, 0.7, 2.0])
    tau = time_rescaling(t, t - 1)
    assert tau[-1] == pytest.approx(1.0, abs=1e-15)
    assert np.all(np.diff(tau) >= 0)


def test_seed001_eq317_pe_level_of_a_sine():
    t = np.linspace(0, 20, 20001)
    # ∫ sin^2 over any window of length 2 pi is pi
    assert pe_level(t, np.sin(t), 2 * np.pi) == pytest.approx(np.pi, rel=1e-6)
    # a signal that dies out is not PE on the record
    assert pe_level(t, np.sin(t) * (t < 5), 2 * np.pi) == 0.0


def test_seed001_eq318_zero_crossings_slopes_and_tangency():
    t = np.linspace(0, 4, 401)
    cr = zero_crossings(t, np.cos(np.pi * t / 2) + 0.0)
    assert [round(c.t, 6) for c in cr] == [1.0, 3.0]
    assert cr[0].slope == pytest.approx(-np.pi / 2, rel=1e-3) and cr[1].slope == pytest.approx(np.pi / 2, rel=1e-3)
    # y = (t-1)^2 touches zero at t = 1 without crossing: a tangency, slope 0, violates (3.18)
    t = np.linspace(0, 2, 201)
    touch = zero_crossings(t, (t - 1) ** 2)
    assert len(touch) == 1 and touch[0].slope == 0.0 and touch[0].t == pytest.approx(1.0)


def test_seed001_sec322_dwell_time_in_t_and_tau():
    t = np.linspace(0, 10, 20001)
    vx = 20.0
    rep = trajectory_conditions(t, np.sin(t), window=2 * np.pi, vx=np.full_like(t, vx))
    assert rep.dwell_time_t == pytest.approx(np.pi, rel=1e-6)
    # between two zeros of sin, tau grows by ∫_0^pi |sin| / vx = 2 / vx
    assert rep.dwell_time_tau == pytest.approx(2 / vx, rel=1e-6)
    assert rep.pe_level_s == pytest.approx(np.pi / vx ** 2, rel=1e-5)
    assert rep.transversal and rep.satisfies(mu0=3.0, T_D=3.0) and not rep.satisfies(mu0=3.2)
    assert rep.to_json()["crossings"][0]["t"] == pytest.approx(np.pi, rel=1e-6)


def test_seed001_fig31_regressor_excitation():
    t = np.linspace(0, 30, 30001)
    psi = np.stack([np.sin(t), np.cos(t)], axis=1)  # one row Psi = [sin t, cos t]
    _, eig = regressor_excitation(t, psi, 2 * np.pi)
    assert eig[:, 0].min() == pytest.approx(np.pi, rel=1e-4) and eig[:, 1].max() == pytest.approx(np.pi, rel=1e-4)
    # a regressor with a dead column is not PE: lambda_min stays 0
    dead = np.stack([np.sin(t), np.zeros_like(t)], axis=1)
    assert regressor_excitation(t, dead, 2 * np.pi)[1][:, 0].max() == pytest.approx(0.0, abs=1e-12)
    rep = trajectory_conditions(t, np.sin(t), window=2 * np.pi, psi=psi)
    assert rep.psi_pe_level == pytest.approx(np.pi, rel=1e-4)


def test_trajectory_bad_input():
    t = np.linspace(0, 1, 11)
    with pytest.raises(SimulationError, match="increase strictly"):
        trajectory_conditions(t[::-1], t, window=0.5)
    with pytest.raises(DimensionError, match="one sample per time"):
        trajectory_conditions(t, t[:5], window=0.5)
    with pytest.raises(SimulationError, match="vx must be positive"):
        trajectory_conditions(t, t, window=0.5, vx=t - 0.5)
    with pytest.raises(SimulationError, match="not finite at sample 3"):
        trajectory_conditions(t, np.where(np.arange(11) == 3, np.nan, t), window=0.5)
    with pytest.raises(SimulationError, match="window"):
        pe_level(t, t, 5.0)


BOUNDS = {"z1": (-50, 50), "z2": (-2, 30), "z3": (-400, 400), "vx": (5, 40)}


def test_seed004_theorem3_constants_for_xbs3():
    m = builtin_model("abs-xbs3").numeric()
    c = admissible_constants(m, bounds=BOUNDS, epsilon=1.0, beta=1000.0)
    a, b = 187.5, 35 / 8
    # C A z = -a z2, d = 0, s = y / vx, C b = b < 0
    assert c.a0 == pytest.approx(a * 30) and c.d0 == 0.0
    assert c.s0 == pytest.approx(1.0 / 5) and c.b0 == pytest.approx(b) and c.b_sign == -1
    assert c.alpha == pytest.approx((1.0 / 5) * a * 30 / b)
    v = c.s0 * c.a0 + b * 1000.0
    assert c.dwell_time_t == pytest.approx(2 * 1.0 / v)
    # tau grows at least by 2 ∫_0^eps y / vx_max dy / v = eps^2 / vx_max / v
    assert c.dwell_time_tau == pytest.approx(1.0 / 40 / v, rel=1e-6)
    # docs/certify.md quotes this run
    assert_page_says("certify.md", f"$a_0 = {c.a0:g}$,\n$d_0 = {c.d0:g}$, $s_0 = {c.s0:g}$, $b_0 = {c.b0:g}$")
    assert_page_says("certify.md", f"$\\alpha = {c.alpha:.4g}$")
    t_D, tau_D = (f"{x:.1e}".replace("e-0", "\\cdot10^{-") + "}" for x in (c.dwell_time_t, c.dwell_time_tau))
    assert_page_says("certify.md", f"for $\\beta = 1000$: ${t_D}$ s and\n${tau_D}$")


def test_seed004_theorem3_d0_for_the_adaptive_model():
    m = builtin_model("abs-adaptive2").numeric()
    c = admissible_constants(m, bounds={"w1": (-50, 50), "w2": (-20, 30), "vx": (5, 40)}, epsilon=2.0)
    # C d(y) = c y with c = 23.99 for dry asphalt: d0 = c eps
    assert c.d0 == pytest.approx(23.99 * 2.0, rel=1e-9) and c.beta is None and c.dwell_time_t is None


def test_theorem3_bad_input():
    m = builtin_model("abs-xbs3").numeric()
    with pytest.raises(SimulationError, match="beta = 10 is not admissible"):
        admissible_constants(m, bounds=BOUNDS, epsilon=1.0, beta=10)
    with pytest.raises(ModelError, match="free parameters"):
        admissible_constants(builtin_model("abs-xbs3"), bounds=BOUNDS, epsilon=1.0)
    with pytest.raises(ModelError, match="bounds miss the state 'z3'"):
        admissible_constants(m, bounds={"z1": (-1, 1), "z2": (0, 1), "vx": (5, 40)}, epsilon=1.0)
    vanishing = Model.from_dict({"name": "v", "states": ["z1", "z2"], "A": [["0", "1"], ["0", "0"]],
                                 "C": ["1", "0"], "time_scale": "y", "b": ["y", "0"], "inputs": ["u"]})
    with pytest.raises(ModelError, match="vanishes"):
        admissible_constants(vanishing, bounds={"z1": (-1, 1), "z2": (-1, 1)}, epsilon=0.5)
