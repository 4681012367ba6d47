"""A torque-driven quarter car for the sensor chain, with the linear tyre of seed 003 or a Burckhardt road.

Vehicle constants and Burckhardt roads come from :mod:`switchobs.plants`
(:class:`~switchobs.plants.QuarterCar`, :func:`~switchobs.plants.road`); what
this module adds is a wheel driven by a known torque (seed 003 (1)-(3), ``T_f``
measured) and the linear tyre (5), which the identification of seed 003
needs.  Seed 001 (2.1) conventions, as in ``switchobs.plants``::

    J domega/dt = T - R F_x,   m dv/dt = F_x,   lambda = (R omega - v) / v,

with ``T < 0`` when braking.  The linear tyre of seed 003 (5) is written here
as ``F_x = C_x lambda``: seed 003 prints ``C_x (v - R omega) / v``, whose sign
together with its (2)-(3) would make a braked wheel accelerate the car; the
physically consistent sign is the one of seed 001.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.integrate import solve_ivp

from ..exceptions import SimulationError
from ..plants import Burckhardt, QuarterCar, road
from ._trajectory import AngleTrajectory
from ._validate import check_positive

__all__ = ["TyreForce", "linear_tyre", "burckhardt_tyre", "WheelRun", "simulate_wheel", "braking_trajectory"]

Array = npt.NDArray[np.float64]
TyreForce = Callable[[Array], Array]


def linear_tyre(stiffness_n: float) -> TyreForce:
    """``F_x = C_x lambda``: seed 003 (5), sign as in seed 001 (braking force < 0 for lambda < 0)."""
    cx = check_positive(stiffness_n, "stiffness_n")
    return lambda lam: cx * np.asarray(lam, dtype=float)


def burckhardt_tyre(surface: str | Burckhardt, load_n: float) -> TyreForce:
    """``F_x = F_z mu(lambda)`` with Burckhardt's odd characteristic (seed 001 (2.5), Table 2.1).

    ``surface`` is a road name of :func:`switchobs.plants.road` (``"dry-asphalt"``, ...)
    or a :class:`switchobs.plants.Burckhardt`.  The small-slip stiffness is
    ``C_x = F_z mu'(0) = F_z (c1 c2 - c3)``.
    """
    tyre = road(surface)
    fz = check_positive(load_n, "load_n")
    return lambda lam: fz * tyre.mu_array(lam)


@dataclass(frozen=True, eq=False)
class WheelRun:
    """Sampled quarter-car trajectory (all arrays on the same time grid; SI units, rad)."""

    t: Array
    theta: Array
    omega: Array
    alpha: Array
    speed_m_s: Array
    accel_x_m_s2: Array
    slip: Array
    force_n: Array
    torque_nm: Array
    vehicle: QuarterCar

    def trajectory(self, name: str = "quarter car") -> AngleTrajectory:
        """The wheel angle as a continuous :class:`AngleTrajectory` (quintic Hermite on the samples)."""
        return AngleTrajectory.from_samples(self.t, theta=self.theta, omega=self.omega, alpha=self.alpha,
                                            accel_x=self.accel_x_m_s2, radius_m=self.vehicle.radius_m, name=name)


def simulate_wheel(
    torque: Callable[[float], float],
    tyre: TyreForce,
    *,
    speed0_m_s: float,
    duration_s: float,
    vehicle: QuarterCar = QuarterCar(),
    sample_s: float = 1e-4,
) -> WheelRun:
    """Integrate the quarter car from free rolling under the torque ``torque(t)`` (N m, < 0 braking).

    Raises
    ------
    SimulationError
        If the wheel locks or the car stops within ``duration_s``.
    """
    J, R = vehicle.inertia_kg_m2, vehicle.radius_m
    m = float(vehicle.mass_kg)  # type: ignore[arg-type]  # set by QuarterCar.__post_init__

    def rhs(t: float, x: Array) -> list[float]:
        _, w, v = x
        f = float(tyre(np.array((R * w - v) / v)))
        return [w, (torque(t) - R * f) / J, f / m]

    def stopped(t: float, x: Array) -> float:
        return min(x[1] * R, x[2]) - 0.5
    stopped.terminal = True  # type: ignore[attr-defined]

    t_eval = np.linspace(0.0, duration_s, int(round(duration_s / sample_s)) + 1)
    sol = solve_ivp(rhs, (0.0, duration_s), [0.0, speed0_m_s / R, speed0_m_s], method="DOP853",
                    t_eval=t_eval, rtol=1e-11, atol=1e-10, events=stopped, max_step=sample_s * 10)
    if sol.status != 0:
        raise SimulationError(
            f"the wheel locked or the car stopped at t = {sol.t[-1]:.4g} s (< {duration_s:g} s); "
            "reduce the brake torque or the duration")
    theta, w, v = sol.y
    lam = (R * w - v) / v
    f = tyre(lam)
    torque_arr = np.array([torque(ti) for ti in sol.t])
    return WheelRun(t=sol.t, theta=theta, omega=w, alpha=(torque_arr - R * f) / J, speed_m_s=v,
                    accel_x_m_s2=f / m, slip=lam, force_n=f, torque_nm=torque_arr, vehicle=vehicle)


def braking_trajectory(
    duration_s: float = 10.0,
    *,
    speed0_kmh: float = 130.0,
    decel_m_s2: float = 3.0,
    modulation: float = 0.3,
    modulation_hz: float = 4.0,
    surface: str | Burckhardt = "dry-asphalt",
    vehicle: QuarterCar = QuarterCar(),
) -> WheelRun:
    """A braking manoeuvre on a Burckhardt road with a modulated brake torque.

    The torque ramps in over 0.2 s to the level that would decelerate the car
    at ``decel_m_s2`` and is modulated by ``+-modulation`` of that level at
    ``modulation_hz``, so the wheel acceleration swings as in ABS cycling.
    Defaults: dry asphalt of seed 001 Table 2.1 and the rig of seed 001
    Section 3.5 (``J = 1.2``, ``R = 0.3``, ``Fz = 2850``).
    """
    check_positive(duration_s, "duration_s")
    level = float(vehicle.mass_kg) * check_positive(decel_m_s2, "decel_m_s2") * vehicle.radius_m  # type: ignore[arg-type]
    wf = 2.0 * math.pi * check_positive(modulation_hz, "modulation_hz")

    def torque(t: float) -> float:
        ramp = min(t / 0.2, 1.0)
        return -level * ramp * (1.0 + modulation * math.sin(wf * t))
    return simulate_wheel(torque, burckhardt_tyre(surface, vehicle.load_n),
                          speed0_m_s=check_positive(speed0_kmh, "speed0_kmh") / 3.6,
                          duration_s=duration_s, vehicle=vehicle)
