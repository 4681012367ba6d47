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

from ..exceptions import SimulationError
from ..plants import Burckhardt, Crossing, HybridPlant, QuarterCar, integrate, road
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

    Classical RK4 on the sample grid (``sample_s``, adjusted to divide
    ``duration_s``) with the hybrid integrator of :mod:`switchobs.plants`
    (:func:`switchobs.plants.integrate`); the stop of the wheel or of the car
    is located within its step.

    Raises
    ------
    SimulationError
        If the wheel locks or the car stops within ``duration_s``.
    """
    plant = _Wheel(torque, tyre, vehicle, check_positive(speed0_m_s, "speed0_m_s"),
                   check_positive(duration_s, "duration_s"), check_positive(sample_s, "sample_s"))
    run = integrate(plant, duration_s, name="wheel")
    if run.status == "stopped":
        raise SimulationError(
            f"the wheel locked or the car stopped at t = {run.series['t'][-1]:.4g} s (< {duration_s:g} s); "
            "reduce the brake torque or the duration")
    s = run.series
    t, theta, w, v = s["t"], s["theta"], s["omega"], s["v"]
    R, J = vehicle.radius_m, vehicle.inertia_kg_m2
    lam = (R * w - v) / v
    f = tyre(lam)
    torque_arr = np.array([torque(ti) for ti in t])
    return WheelRun(t=t, theta=theta, omega=w, alpha=(torque_arr - R * f) / J, speed_m_s=v,
                    accel_x_m_s2=f / plant.m, slip=lam, force_n=f, torque_nm=torque_arr, vehicle=vehicle)


class _Wheel(HybridPlant):
    """The torque-driven quarter car as a :class:`switchobs.plants.HybridPlant`: no controller, one terminal guard."""

    states = ("theta", "omega", "v")
    series = ("t", "theta", "omega", "v")

    def __init__(self, torque: Callable[[float], float], tyre: TyreForce, vehicle: QuarterCar, speed0_m_s: float,
                 duration_s: float, sample_s: float):
        self.torque, self.tyre = torque, tyre
        self.R, self.J = vehicle.radius_m, vehicle.inertia_kg_m2
        self.m = float(vehicle.mass_kg)  # type: ignore[arg-type]  # set by QuarterCar.__post_init__
        self.v0 = speed0_m_s
        # the sample grid k h, h = duration / n, is computed on demand: a long run is refused by the
        # integrator's step limit before anything of its size is allocated
        self.n = max(int(round(duration_s / sample_s)), 1)
        self.duration = duration_s
        self.h = duration_s / self.n

    def initial_state(self) -> tuple[float, ...]:
        return (0.0, self.v0 / self.R, self.v0)

    def rhs(self, t: float, y: tuple[float, ...]) -> tuple[float, float, float]:
        _, w, v = y
        f = float(self.tyre(np.array((self.R * w - v) / v)))
        return (w, (self.torque(t) - self.R * f) / self.J, f / self.m)

    def step_size(self, t: float, y: tuple[float, ...]) -> float:
        return self.h

    def breakpoint(self, t: float) -> float:
        """The next sample: steps end on the grid without accumulating rounding."""
        k = int(t / self.h + 0.5) + 1
        return k * self.h if k < self.n else self.duration

    def crossings(self, t: float, y: tuple[float, ...], y1: tuple[float, ...]) -> list[Crossing]:
        R = self.R
        g1 = 0.5 - min(y1[1] * R, y1[2])
        if g1 <= 0.0:
            return []
        return [Crossing("stop", lambda tt, yy: 0.5 - min(yy[1] * R, yy[2]), 0.5 - min(y[1] * R, y[2]), g1,
                         terminal=True, text="the wheel or the car stopped")]

    def row(self, t: float, y: tuple[float, ...]) -> tuple[float, ...]:
        return (t, *y)


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
