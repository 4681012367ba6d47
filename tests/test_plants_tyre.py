"""Tyre models: Burckhardt (seed 000 eq. (5)-(6), Table I; seed 001 eq. (2.5), Table 2.1) and (18)-(19)."""

import math

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from switchobs.exceptions import SimulationError
from switchobs.plants import (D1_HOANG, D2_HOANG, ROADS, Burckhardt, ExponentialTyre, fit_exponential,
                              relation19_alphas, road, road_names)

# seed 000 Table I, approximate model columns
TABLE1_THETA = {"hoang-dry": (-0.53, 25.22, 7.2), "hoang-wet": (-0.36, 8.86, 24.0), "hoang-snow": (-0.05, 0.24, 14.0)}


def test_aguado2020_table21_seven_surfaces_and_hoang_table1():
    assert road_names()[:7] == ("dry-asphalt", "wet-asphalt", "dry-concrete", "dry-cobblestones",
                                "wet-cobblestones", "snow", "ice")
    assert (ROADS["wet-cobblestones"].c1, ROADS["wet-cobblestones"].c2, ROADS["wet-cobblestones"].c3) == \
        (0.4004, 33.708, 0.1204)
    assert (road("hoang-snow").c1, road("hoang-snow").c2, road("hoang-snow").c3) == (0.28, 50.0, 0.05)
    # seed 001 Fig. 2.4: for lambda < 0, c1 and c2 are negative and c3 positive
    assert road("dry-asphalt").braking == (-1.2801, -23.99, 0.52)


@pytest.mark.parametrize("name", [n for n in road_names() if n != "ice"])
def test_burckhardt_optimum_is_where_xbs_vanishes(name):
    r = road(name)
    lam = r.optimal_slip
    assert -1.0 < lam < 0.0
    assert abs(r.xbs(lam)) < 1e-12
    grid = np.linspace(-1.0, 0.0, 20001)
    assert r.peak_friction <= r.mu_array(grid).min() + 1e-12      # most negative friction in braking


def test_ice_has_no_interior_optimum():
    assert road("ice").optimal_slip == -1.0
    assert np.all(road("ice").xbs_array(np.linspace(-1, 0, 101)) > 0)


@settings(max_examples=25, deadline=None)
@given(c1=st.floats(0.05, 2.0), c2=st.floats(1.0, 300.0), c3=st.floats(0.0, 1.0), lam=st.floats(-1.0, 1.0))
def test_burckhardt_odd_extension_and_derivatives(c1, c2, c3, lam):
    r = Burckhardt(c1, c2, c3)
    assert r.mu(-lam) == pytest.approx(-r.mu(lam), abs=1e-14)
    assert r.xbs(-lam) == pytest.approx(r.xbs(lam), abs=1e-12)
    h = 1e-6
    if abs(lam) > 2 * h:
        assert r.xbs(lam) == pytest.approx((r.mu(lam + h) - r.mu(lam - h)) / (2 * h), rel=1e-5, abs=1e-6)
        assert r.xbs2(lam) == pytest.approx((r.xbs(lam + h) - r.xbs(lam - h)) / (2 * h), rel=1e-4, abs=1e-4)
    if lam < 0:
        # seed 000 eq. (6) with the braking parameters (c2b = -c2)
        c2b = r.braking[1]
        assert r.xbs2(lam) + c2b * r.xbs(lam) + c2b * c3 == pytest.approx(0.0, abs=1e-9 * max(1.0, c1 * c2 * c2))


def test_hoang2014_eq6_symbolic_identity():
    lam, c1, c2, c3 = sp.symbols("lambda c1 c2 c3", real=True)
    mu = c1 * (1 - sp.exp(-c2 * lam)) - c3 * lam
    assert sp.simplify(sp.diff(mu, lam, 2) + c2 * sp.diff(mu, lam) + c2 * c3) == 0


def test_hoang2014_eq19_symbolic_identity():
    lam, t0, t1, t2, d1, d2 = sp.symbols("lambda theta0 theta1 theta2 d1 d2", real=True)
    mu = t0 * lam + t1 * (sp.exp(d1 * lam) - 1) / d1 + t2 * (sp.exp(d2 * lam) - 1) / d2
    a0, a1, a2 = relation19_alphas(t0, d1, d2)
    rhs = a0 + a1 * sp.diff(mu, lam) + a2 * sp.diff(mu, lam, 2)
    assert sp.simplify(sp.diff(mu, lam, 3) - rhs) == 0
    assert relation19_alphas(-0.53) == pytest.approx((22 * 52 * -0.53, -1144.0, 74.0))


@pytest.mark.parametrize("name", list(TABLE1_THETA))
def test_hoang2014_table1_exponential_fit(name):
    fit = fit_exponential(name)
    theta = TABLE1_THETA[name]
    assert (fit.d1, fit.d2) == (D1_HOANG, D2_HOANG) == (22.0, 52.0)
    # dry and snow to the printed digits; the wet row is printed as (-0.36, 8.86, 24): we get (-0.36, 8.89, 24.08)
    assert fit.theta[0] == pytest.approx(theta[0], abs=0.006)
    assert fit.theta[1] == pytest.approx(theta[1], abs=0.006 if name != "hoang-wet" else 0.05)
    assert fit.theta[2] == pytest.approx(theta[2], abs=0.006 if name != "hoang-wet" else 0.1)
    lam = np.linspace(-1, 0, 201)
    assert np.max(np.abs(fit.mu(lam) - road(name).mu_array(lam))) < 0.025   # Fig. 1: the curves overlap
    assert fit.xbs(-0.1) == pytest.approx(np.gradient(fit.mu(lam), lam)[180], rel=0.02)


def test_exponential_tyre_satisfies_relation19_numerically():
    fit = fit_exponential("dry-asphalt")
    a0, a1, a2 = fit.alphas
    t0, t1, t2 = fit.theta
    lam = np.linspace(-1, 0, 11)
    e1, e2 = np.exp(22 * lam), np.exp(52 * lam)
    mu2 = t1 * 22 * e1 + t2 * 52 * e2
    mu3 = t1 * 22 ** 2 * e1 + t2 * 52 ** 2 * e2
    np.testing.assert_allclose(mu3, a0 + a1 * fit.xbs(lam) + a2 * mu2, rtol=1e-10, atol=1e-10 * mu3.max())
    assert isinstance(fit, ExponentialTyre) and "theta=" in str(fit) and fit.to_json()["alpha1"] == -1144.0


def test_unknown_road_and_bad_parameters():
    with pytest.raises(SimulationError, match=r"unknown road surface 'gravel'; known: dry-asphalt"):
        road("gravel")
    with pytest.raises(SimulationError, match=r"c1 > 0, c2 > 0, c3 >= 0; got \(c1, c2, c3\) = \(-1.0"):
        Burckhardt(-1.0, 20.0, 0.5)
    with pytest.raises(SimulationError, match="c2 must be a finite number, got nan"):
        Burckhardt(1.0, math.nan, 0.5)
    with pytest.raises(SimulationError, match="distinct positive numbers, got d1=22, d2=22"):
        fit_exponential("snow", d1=22, d2=22)
    with pytest.raises(SimulationError, match="points >= 3, got 2"):
        fit_exponential("snow", points=2)
