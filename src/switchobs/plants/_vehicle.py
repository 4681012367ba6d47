"""Parameters of the quarter car (seed 001 eq. (2.1)), its brake actuator and speed profiles."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

from .._json import JsonRecord
from ..exceptions import SimulationError

__all__ = ["QuarterCar", "BrakeActuator", "PrescribedSpeed", "GRAVITY", "MAX_SPEED_KMH", "MAX_DELAY_S",
           "check_speed"]

GRAVITY = 9.81
#: Highest initial speed of a braking run: above any road car, and far below the speeds at which the tyre
#: and the step of the integrator stop making sense (a mistyped 1e9 km/h would "brake" over 1e19 m).
MAX_SPEED_KMH = 500.0
#: Longest actuator delay: brake hydraulics answer within tens of milliseconds; a delay of seconds is a
#: car without brakes, whose run only ends at its time bound.
MAX_DELAY_S = 1.0


def check_speed(owner: str, speed_m_s: float) -> None:
    """Refuse an initial speed (a finite number, checked by the caller) outside ``(0, MAX_SPEED_KMH]``."""
    if not 0.0 < speed_m_s <= MAX_SPEED_KMH / 3.6:
        raise SimulationError(f"{owner}: the initial speed {3.6 * speed_m_s:g} km/h lies outside "
                              f"(0, {MAX_SPEED_KMH:g}] km/h, the range of a road vehicle")


def _positive(owner: str, **values: float) -> None:
    for key, value in values.items():
        if not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
            raise SimulationError(f"{owner}: {key} must be a finite number > 0, got {value!r}")


@dataclass(frozen=True)
class QuarterCar(JsonRecord, error=SimulationError):
    """Wheel and corner mass of the quarter-car model (seed 001 eq. (2.1))::

        J dω/dt = -R Fx - γ_b P_b,    m dvx/dt = Fx,    Fx = Fz mu(lambda)

    Parameters
    ----------
    inertia_kg_m2 : float
        Wheel inertia ``J`` (``I`` in seed 000).
    radius_m : float
        Effective rolling radius ``R``.
    load_n : float
        Vertical load ``Fz``.
    brake_gain_nm_bar : float
        Brake efficiency ``γ_b`` [N·m/bar].
    mass_kg : float, optional
        Corner mass ``m``; default ``Fz / g`` so that ``a_x = g mu`` (then the
        braking distance of seed 001 Table 4.1, ``vx(0)² / (2 g mū)``, is the
        distance of a constant deceleration at the mean friction).

    Notes
    -----
    The defaults are the TU Delft rig of seed 001 Fig. 3.12 (``J = 1.2``,
    ``R = 0.3``, ``Fz = 2850``, ``γ_b = 17.5``); :meth:`hoang2014` gives the
    rig of seed 000 Fig. 2 (``Fz = 2500``).
    """

    inertia_kg_m2: float = 1.2
    radius_m: float = 0.3
    load_n: float = 2850.0
    brake_gain_nm_bar: float = 17.5
    mass_kg: float | None = None

    def __post_init__(self) -> None:
        _positive("QuarterCar", inertia_kg_m2=self.inertia_kg_m2, radius_m=self.radius_m, load_n=self.load_n,
                  brake_gain_nm_bar=self.brake_gain_nm_bar)
        if self.mass_kg is None:
            object.__setattr__(self, "mass_kg", self.load_n / GRAVITY)
        _positive("QuarterCar", mass_kg=self.mass_kg)

    @classmethod
    def hoang2014(cls) -> QuarterCar:
        """The TU Delft rig of seed 000 Fig. 2: ``I = 1.2``, ``R = 0.3``, ``Fz = 2500``, ``γ_b = 17.5``."""
        return cls(load_n=2500.0)

    @property
    def a(self) -> float:
        """``a = R² Fz / J`` (seed 000 Sec. II-B, seed 001 eq. (2.6))."""
        return self.radius_m ** 2 * self.load_n / self.inertia_kg_m2

    @property
    def b(self) -> float:
        """``b = R γ_b / J > 0`` of seed 001 eq. (2.6) (seed 000 writes ``b = -R γ_b / I`` with ``+b u``)."""
        return self.radius_m * self.brake_gain_nm_bar / self.inertia_kg_m2

    def to_json(self) -> dict[str, Any]:
        return {**asdict(self), "a": self.a, "b": self.b}


@dataclass(frozen=True)
class BrakeActuator(JsonRecord, error=SimulationError):
    """Brake-pressure actuator: rate limit, pressure range and an optional transport delay.

    Parameters
    ----------
    max_rate_bar_s : float
        Largest ``|dP_b/dt|`` the hydraulics deliver (``Ṗ_b^M`` of seed 000 Sec. V).
    max_pressure_bar : float
        Master-cylinder pressure: the ABS can hold or release but not exceed it
        (seed 001 Sec. 2.2.2).
    delay_s : float
        Delay between the commanded and the applied pressure rate; ``0`` or at
        least the integration step, at most :data:`MAX_DELAY_S`.
    """

    max_rate_bar_s: float = 2000.0
    max_pressure_bar: float = 250.0
    delay_s: float = 0.0

    def __post_init__(self) -> None:
        _positive("BrakeActuator", max_rate_bar_s=self.max_rate_bar_s, max_pressure_bar=self.max_pressure_bar)
        if not isinstance(self.delay_s, (int, float)) or not 0 <= self.delay_s <= MAX_DELAY_S:
            raise SimulationError(f"BrakeActuator: delay_s must lie in [0, {MAX_DELAY_S:g}] s (brake hydraulics "
                                  f"answer within tens of ms), got {self.delay_s!r}")

    def to_json(self) -> dict[str, Any]:
        return asdict(self)


@dataclass(frozen=True)
class PrescribedSpeed(JsonRecord, error=SimulationError):
    """Vehicle speed imposed from outside (a drum test rig): ``vx(t) = vx(0) - decel t``.

    Seed 001 Sec. 3.4 drives the wheel with ``vx(0) = 25 m/s`` and a constant
    deceleration of 1.96 m/s²; then ``a_x = -decel`` whatever the tyre force.
    """

    decel_m_s2: float = 1.96

    def __post_init__(self) -> None:
        _positive("PrescribedSpeed", decel_m_s2=self.decel_m_s2)

    def to_json(self) -> dict[str, Any]:
        return {"decel_m_s2": self.decel_m_s2}
