"""Tyre characteristics: Burckhardt's model, its road tables, and the exponential approximation.

Burckhardt (seed 000 eq. (5), seed 001 eq. (2.5))::

    mu(lambda) = c1 (1 - exp(-c2 lambda)) - c3 lambda

is tabulated with positive ``c_i`` for traction (``lambda > 0``).  The
characteristic is odd (seed 000 Sec. II-A), so for braking (``lambda < 0``) the
same formula holds with ``c1, c2`` negated and ``c3`` kept (seed 001 Fig. 2.4).
Here a :class:`Burckhardt` stores the table's positive values and evaluates the
odd extension, so ``mu'(lambda)`` (the extended braking stiffness, XBS) is even.

The exponential approximation (seed 000 eq. (18))::

    mu(lambda) = theta0 lambda + theta1 (exp(d1 lambda) - 1)/d1 + theta2 (exp(d2 lambda) - 1)/d2,  lambda <= 0

satisfies ``mu''' = alpha0 + alpha1 mu' + alpha2 mu''`` (eq. (19)) with
``alpha0 = d1 d2 theta0``, ``alpha1 = -d1 d2``, ``alpha2 = d1 + d2``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from .._json import JsonRecord
from ..exceptions import SimulationError

__all__ = ["Burckhardt", "ExponentialTyre", "ROADS", "road", "road_names", "fit_exponential",
           "relation19_alphas", "D1_HOANG", "D2_HOANG"]

#: Exponents of the approximation (18) (seed 000 Sec. IV-A: ``-c2`` ranges over [24, 50] in braking).
D1_HOANG = 22.0
D2_HOANG = 52.0


@dataclass(frozen=True)
class Burckhardt(JsonRecord, error=SimulationError):
    """Burckhardt's tyre characteristic with its odd extension to braking.

    Parameters
    ----------
    c1, c2, c3 : float
        Traction-side parameters (``c1, c2 > 0``, ``c3 >= 0``) as printed in
        seed 000 Table I and seed 001 Table 2.1.
    name : str
        Road name (informative).

    Notes
    -----
    For ``lambda < 0`` the model equals ``c1b (1 - exp(-c2b lambda)) - c3 lambda``
    with the braking parameters ``(c1b, c2b) = (-c1, -c2)`` (:attr:`braking`).
    The second derivative obeys seed 000 eq. (6), ``mu'' + c2b mu' + c2b c3 = 0``
    for ``lambda < 0``.  With ``c3 = 0`` (ice) the characteristic has no interior
    maximum and :attr:`optimal_slip` is ``-1`` (locked wheel).

    Examples
    --------
    >>> dry = road("hoang-dry")
    >>> round(dry.optimal_slip, 4), round(dry.peak_friction, 4)
    (-0.17, -1.17)
    >>> abs(dry.xbs(dry.optimal_slip)) < 1e-12
    True
    """

    c1: float
    c2: float
    c3: float
    name: str = ""

    def __post_init__(self) -> None:
        for key in ("c1", "c2", "c3"):
            value = getattr(self, key)
            if not isinstance(value, (int, float)) or not math.isfinite(value):
                raise SimulationError(f"Burckhardt parameter {key} must be a finite number, got {value!r}")
        if self.c1 <= 0 or self.c2 <= 0 or self.c3 < 0:
            raise SimulationError(
                f"Burckhardt parameters are given on the traction side and need c1 > 0, c2 > 0, c3 >= 0; "
                f"got (c1, c2, c3) = ({self.c1}, {self.c2}, {self.c3}) for road {self.name!r}")

    @property
    def braking(self) -> tuple[float, float, float]:
        """``(c1, c2, c3)`` of the braking half (``lambda < 0``): ``(-c1, -c2, c3)``."""
        return (-self.c1, -self.c2, self.c3)

    @property
    def c(self) -> float:
        """``c = -c2`` of the XBS models for braking (seed 000 eq. (7), seed 001 eq. (2.6)): ``+c2``."""
        return self.c2

    @property
    def d(self) -> float:
        """``d = -c2 c3`` of seed 001 eq. (2.6) for braking: ``+c2 c3`` (``-z3`` of seed 000 eq. (7))."""
        return self.c2 * self.c3

    def mu(self, lam: float) -> float:
        """Friction coefficient ``mu(lambda)`` (odd in ``lambda``)."""
        a = abs(lam)
        value = self.c1 * (1.0 - math.exp(-self.c2 * a)) - self.c3 * a
        return value if lam >= 0.0 else -value

    def xbs(self, lam: float) -> float:
        """Extended braking stiffness ``mu'(lambda) = c1 c2 exp(-c2 |lambda|) - c3`` (even)."""
        return self.c1 * self.c2 * math.exp(-self.c2 * abs(lam)) - self.c3

    def xbs2(self, lam: float) -> float:
        """Second derivative ``mu''(lambda)`` (odd)."""
        value = -self.c2 * self.c1 * self.c2 * math.exp(-self.c2 * abs(lam))
        return value if lam >= 0.0 else -value

    def mu_array(self, lam: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Vectorised :meth:`mu`."""
        lam = np.asarray(lam, dtype=float)
        a = np.abs(lam)
        return np.sign(lam) * (self.c1 * (1.0 - np.exp(-self.c2 * a)) - self.c3 * a)

    def xbs_array(self, lam: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Vectorised :meth:`xbs`."""
        lam = np.asarray(lam, dtype=float)
        return self.c1 * self.c2 * np.exp(-self.c2 * np.abs(lam)) - self.c3

    @property
    def optimal_slip(self) -> float:
        """Braking slip ``lambda* < 0`` where ``mu'(lambda*) = 0``: ``-ln(c1 c2 / c3) / c2`` (``-1`` if none)."""
        if self.c3 == 0.0 or self.c1 * self.c2 <= self.c3:
            return -1.0
        return max(-math.log(self.c1 * self.c2 / self.c3) / self.c2, -1.0)

    @property
    def peak_friction(self) -> float:
        """``mu(lambda*)``, the most negative friction coefficient reachable in braking."""
        return self.mu(self.optimal_slip)

    def to_json(self) -> dict[str, Any]:
        return {"name": self.name, "c1": self.c1, "c2": self.c2, "c3": self.c3,
                "optimal_slip": self.optimal_slip, "peak_friction": self.peak_friction}

    def __str__(self) -> str:
        return (f"Burckhardt {self.name or '(unnamed)'}: c1={self.c1:g}, c2={self.c2:g}, c3={self.c3:g} "
                f"(braking optimum lambda*={self.optimal_slip:.4f}, mu*={self.peak_friction:.4f})")


#: Road surfaces: seed 001 Table 2.1 (7 surfaces) and seed 000 Table I (prefix ``hoang-``).
ROADS: dict[str, Burckhardt] = {r.name: r for r in (
    Burckhardt(1.2801, 23.99, 0.52, "dry-asphalt"),
    Burckhardt(0.857, 33.822, 0.347, "wet-asphalt"),
    Burckhardt(1.1973, 25.168, 0.5373, "dry-concrete"),
    Burckhardt(1.3713, 6.4565, 0.6691, "dry-cobblestones"),
    Burckhardt(0.4004, 33.708, 0.1204, "wet-cobblestones"),
    Burckhardt(0.1946, 94.129, 0.0646, "snow"),
    Burckhardt(0.05, 306.39, 0.0, "ice"),
    Burckhardt(1.28, 24.0, 0.52, "hoang-dry"),
    Burckhardt(0.86, 34.0, 0.35, "hoang-wet"),
    Burckhardt(0.28, 50.0, 0.05, "hoang-snow"),
)}


def road_names() -> tuple[str, ...]:
    """Names accepted by :func:`road`, seed 001 Table 2.1 first."""
    return tuple(ROADS)


def road(name: str | Burckhardt) -> Burckhardt:
    """The Burckhardt characteristic of a named road surface.

    Parameters
    ----------
    name : str or Burckhardt
        One of :func:`road_names` (a :class:`Burckhardt` is returned unchanged).

    Raises
    ------
    SimulationError
        For an unknown name; the message lists the known ones.
    """
    if isinstance(name, Burckhardt):
        return name
    try:
        return ROADS[name]
    except (KeyError, TypeError):
        raise SimulationError(f"unknown road surface {name!r}; known: {', '.join(ROADS)}") from None


@dataclass(frozen=True)
class ExponentialTyre(JsonRecord, error=SimulationError):
    """The linearly parametrised approximation (18) of seed 000, for ``lambda <= 0``.

    Parameters
    ----------
    theta : tuple of 3 floats
        ``(theta0, theta1, theta2)``.
    d1, d2 : float
        Exponents, ``22`` and ``52`` in seed 000.
    name : str
    """

    theta: tuple[float, float, float]
    d1: float = D1_HOANG
    d2: float = D2_HOANG
    name: str = ""
    residual_rms: float = 0.0

    def mu(self, lam: npt.ArrayLike) -> npt.NDArray[np.float64]:
        lam = np.asarray(lam, dtype=float)
        t0, t1, t2 = self.theta
        return t0 * lam + t1 * np.expm1(self.d1 * lam) / self.d1 + t2 * np.expm1(self.d2 * lam) / self.d2

    def xbs(self, lam: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """``mu'(lambda) = theta0 + theta1 exp(d1 lambda) + theta2 exp(d2 lambda)``."""
        lam = np.asarray(lam, dtype=float)
        t0, t1, t2 = self.theta
        return t0 + t1 * np.exp(self.d1 * lam) + t2 * np.exp(self.d2 * lam)

    @property
    def alphas(self) -> tuple[float, float, float]:
        """``(alpha0, alpha1, alpha2)`` of relation (19)."""
        return relation19_alphas(self.theta[0], self.d1, self.d2)

    def to_json(self) -> dict[str, Any]:
        a0, a1, a2 = self.alphas
        return {"name": self.name, "theta": list(self.theta), "d1": self.d1, "d2": self.d2,
                "alpha0": a0, "alpha1": a1, "alpha2": a2, "residual_rms": self.residual_rms}

    def __str__(self) -> str:
        t0, t1, t2 = self.theta
        return (f"exponential tyre {self.name or '(unnamed)'}: theta=({t0:.4g}, {t1:.4g}, {t2:.4g}), "
                f"d1={self.d1:g}, d2={self.d2:g}, fit rms={self.residual_rms:.3g}")


def relation19_alphas(theta0: float, d1: float = D1_HOANG, d2: float = D2_HOANG) -> tuple[float, float, float]:
    """Coefficients of seed 000 eq. (19): ``(d1 d2 theta0, -d1 d2, d1 + d2)``."""
    return (d1 * d2 * theta0, -d1 * d2, d1 + d2)


def fit_exponential(tyre: Burckhardt | str, *, d1: float = D1_HOANG, d2: float = D2_HOANG,
                    points: int = 101) -> ExponentialTyre:
    """Least-squares fit of ``theta`` in (18) to a Burckhardt characteristic on ``lambda in [-1, 0]``.

    Parameters
    ----------
    tyre : Burckhardt or str
        The characteristic (or road name) to approximate, braking half.
    d1, d2 : float
        Exponents of (18); the defaults are seed 000's.
    points : int
        Number of equally spaced slips in ``[-1, 0]`` (101, a step of 0.01,
        reproduces seed 000 Table I to its printed digits).

    Returns
    -------
    ExponentialTyre

    Raises
    ------
    SimulationError
        If ``d1, d2`` are not distinct positive numbers or ``points < 3``.

    References
    ----------
    Seed 000 Sec. IV-A and Table I (dry road: theta = (-0.53, 25.22, 7.2)).

    Examples
    --------
    >>> fit = fit_exponential("hoang-dry")
    >>> [round(v, 2) for v in fit.theta]
    [-0.53, 25.22, 7.2]
    """
    tyre = road(tyre)
    if not (d1 > 0 and d2 > 0 and d1 != d2 and math.isfinite(d1) and math.isfinite(d2)):
        raise SimulationError(f"the exponents of (18) must be distinct positive numbers, got d1={d1}, d2={d2}")
    if int(points) != points or points < 3:
        raise SimulationError(f"the fit needs an integer number of points >= 3, got {points!r}")
    lam = np.linspace(-1.0, 0.0, int(points))
    basis = np.column_stack([lam, np.expm1(d1 * lam) / d1, np.expm1(d2 * lam) / d2])
    target = tyre.mu_array(lam)
    theta, *_ = np.linalg.lstsq(basis, target, rcond=None)
    rms = float(np.sqrt(np.mean((basis @ theta - target) ** 2)))
    return ExponentialTyre(theta=(float(theta[0]), float(theta[1]), float(theta[2])), d1=d1, d2=d2,
                           name=tyre.name, residual_rms=rms)
