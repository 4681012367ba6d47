"""Poincaré map of the two-phase ABS, seed 001 Sec. 4.3, eqs. (4.5)-(4.18)."""

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from switchobs.exceptions import SimulationError
from switchobs.plants import PoincareMap, road, simulate_return_map

DRY = road("dry-asphalt")
CASES = [  # (kp, z_ref, chi_a, chi_b, road)
    (50.0, 8.0, -0.1, 0.1, "dry-asphalt"),
    (300.0, 5.0, -0.2, 0.05, "wet-asphalt"),
    (20.0, 12.0, 0.0, 0.3, "snow"),
]


@pytest.mark.parametrize("kp, z_ref, chi_a, chi_b, name", CASES)
@pytest.mark.parametrize("zeta0", [-0.95, -0.6, -0.2, -0.01])
def test_aguado2020_eq413_analytic_return_map_matches_simulation_of_eq45(kp, z_ref, chi_a, chi_b, name, zeta0):
    r = road(name)
    pm = PoincareMap.from_abs(kp=kp, z_ref=z_ref, chi_a=chi_a, chi_b=chi_b, c=r.c, d=r.d)
    z1_switch, z1_return = simulate_return_map(zeta0 * z_ref, kp=kp, z_ref=z_ref, chi_a=chi_a, chi_b=chi_b,
                                               c=r.c, d=r.d)
    assert pm.switch_point(zeta0) == pytest.approx(z1_switch / z_ref, rel=1e-6)     # (4.12a)
    assert pm(zeta0) == pytest.approx(z1_return / z_ref, rel=1e-6)                   # (4.13)
    assert 0.0 < pm.switch_point(zeta0) < 1.0 and -1.0 < pm(zeta0) < 0.0


@pytest.mark.parametrize("kp, z_ref, chi_a, chi_b, name", CASES)
def test_aguado2020_fixed_point_and_derivative(kp, z_ref, chi_a, chi_b, name):
    r = road(name)
    pm = PoincareMap.from_abs(kp=kp, z_ref=z_ref, chi_a=chi_a, chi_b=chi_b, c=r.c, d=r.d)
    fp = pm.fixed_point()
    assert pm(fp.zeta) == pytest.approx(fp.zeta, abs=1e-12)
    h = 1e-6
    assert fp.derivative == pytest.approx((pm(fp.zeta + h) - pm(fp.zeta - h)) / (2 * h), rel=1e-5)
    f4, f3, f2, f1 = fp.factors
    assert 0 < f1 < 1 and -1 < f3 < 0 and f2 < 0 < f4          # signs of (4.15)-(4.18)
    # the fixed point is a cycle of the simulated (4.5): one more lap returns to it
    _, back = simulate_return_map(fp.zeta * z_ref, kp=kp, z_ref=z_ref, chi_a=chi_a, chi_b=chi_b, c=r.c, d=r.d)
    assert back / z_ref == pytest.approx(fp.zeta, rel=1e-6)
    assert pm.kappa < 0


@settings(max_examples=25, deadline=None)
@given(kp=st.floats(1.0, 5000.0), z_ref=st.floats(1.0, 30.0), depth=st.floats(0.0, 0.9),
       chi_b=st.floats(0.01, 2.0), name=st.sampled_from(["dry-asphalt", "wet-asphalt", "dry-concrete", "snow"]))
def test_aguado2020_sec433_sufficient_condition_gives_stable_cycle(kp, z_ref, depth, chi_b, name):
    r = road(name)
    chi_a = -depth * r.c3          # physical XBS: z2 > -d/c = -c3
    pm = PoincareMap.from_abs(kp=kp, z_ref=z_ref, chi_a=chi_a, chi_b=chi_b, c=r.c, d=r.d)
    fp = pm.fixed_point()
    # alpha > (delta_up + 1)/kappa with m -> 1, delta_up = ln(1/2) - 1/2
    assert fp.alpha_bound == pytest.approx((math.log(0.5) + 0.5) / pm.kappa)
    if fp.condition_holds:
        assert abs(fp.derivative) < 1.0 and fp.stable


def test_sufficient_condition_is_not_necessary():
    pm = PoincareMap.from_abs(kp=10.0, z_ref=8.0, chi_a=-0.1, chi_b=0.1, c=DRY.c, d=DRY.d)
    fp = pm.fixed_point()
    assert not fp.condition_holds and fp.stable       # kp = 10 < 95.2, yet |P'| = 0.28
    assert "does not hold" in str(fp) and fp.to_json()["stable"] is True


def test_poincare_bad_input():
    with pytest.raises(SimulationError, match="zeta_a < zeta_b"):
        PoincareMap.from_abs(kp=10.0, z_ref=8.0, chi_a=0.2, chi_b=0.1, c=DRY.c, d=DRY.d)
    with pytest.raises(SimulationError, match="alpha = kp > 0"):
        PoincareMap(alpha=-1.0, beta=1.0, zeta_a=-0.1, zeta_b=0.1)
    with pytest.raises(SimulationError, match="physical XBS range"):
        PoincareMap.from_abs(kp=10.0, z_ref=8.0, chi_a=-0.6, chi_b=0.1, c=DRY.c, d=DRY.d)
    pm = PoincareMap.from_abs(kp=10.0, z_ref=8.0, chi_a=-0.1, chi_b=0.1, c=DRY.c, d=DRY.d)
    with pytest.raises(SimulationError, match=r"defined for ζ1° < 0 .* got 0.5"):
        pm(0.5)
    with pytest.raises(SimulationError, match="starts with z1 < 0"):
        simulate_return_map(1.0, kp=10.0, z_ref=8.0, chi_a=-0.1, chi_b=0.1, c=DRY.c, d=DRY.d)
