"""Poincaré map of the two-phase XBS ABS (seed 001 Sec. 4.3, eqs. (4.5)-(4.18)).

In the time ``s = ∫ dt / vx`` and with the XBS known, the closed loop of the
two-phase algorithm (Fig. 4.3) is::

    dz1/ds = -kp (z1 - z1*),    dz2/ds = (c z2 + d) z1                      (4.5)

with ``z1* = +z_ref`` in phase 1 (until ``z2`` rises to ``chi_b``) and
``z1* = -z_ref`` in phase 2 (until ``z2`` falls to ``chi_a``).  With
``ζ1 = z1 / z_ref``, ``ζ2 = z2 / (d z_ref)``, ``α = kp``, ``β = c z_ref``, the
first integrals of both phases give the return map on the section ``z2 = chi_a``
in closed form with the principal branch ``W0`` of the Lambert function::

    P = φ4 ∘ φ3 ∘ φ2 ∘ φ1,
    φ1(ζ) = ζ + ln(1 - ζ) - 1 + α κ        φ2(δ) = 1 + W0(-exp δ)
    φ3(ζ) = -ζ + ln(1 + ζ) - 1 + α κ       φ4(δ) = -1 - W0(-exp δ)          (4.13)
    κ = ln((1 + β ζa) / (1 + β ζb)) / β                                     (4.14)
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from .._json import JsonRecord
from ..exceptions import SimulationError, SolverFailure

__all__ = ["PoincareMap", "PoincareFixedPoint", "simulate_return_map"]


def _w0(x: float) -> float:
    # scipy is imported where it is used, so that the command line's --help and errors never load it
    from scipy.special import lambertw

    w = lambertw(x, 0)
    return float(w.real)


@dataclass(frozen=True)
class PoincareFixedPoint(JsonRecord, error=SimulationError):
    """Fixed point ``ζ1°`` of the map and its stability figures.

    Attributes
    ----------
    zeta : float
        ``ζ1° in (-1, 0)``: the normalised wheel acceleration ``z1 / z_ref`` at which phase 1 starts.
    derivative : float
        ``P'(ζ1°)``; the limit cycle is asymptotically stable if ``|P'| < 1``.
    factors : tuple of 4 floats
        ``(φ4', φ3', φ2', φ1')`` at the fixed point (eqs. (4.15)-(4.18)).
    alpha, alpha_bound : float
        ``α = kp`` and the sufficient bound ``(δ_up + 1) / κ`` with ``m -> 1``
        (``δ_up = ln(1/2) - 1/2``); ``α > alpha_bound`` guarantees ``|P'| < 1``.
    """

    zeta: float
    derivative: float
    factors: tuple[float, float, float, float]
    alpha: float
    alpha_bound: float

    @property
    def stable(self) -> bool:
        return abs(self.derivative) < 1.0

    @property
    def condition_holds(self) -> bool:
        return self.alpha > self.alpha_bound

    def to_json(self) -> dict[str, Any]:
        return {**asdict(self), "factors": list(self.factors), "stable": self.stable,
                "condition_holds": self.condition_holds}

    def __str__(self) -> str:
        return (f"fixed point ζ1° = {self.zeta:.6f}, P'(ζ1°) = {self.derivative:.4g} "
                f"({'stable' if self.stable else 'unstable'}); sufficient condition α = {self.alpha:g} > "
                f"{self.alpha_bound:.4g}: {'holds' if self.condition_holds else 'does not hold'}")


@dataclass(frozen=True)
class PoincareMap(JsonRecord, error=SimulationError):
    """The return map (4.13)-(4.14) of the two-phase ABS.

    Parameters
    ----------
    alpha : float
        ``α = kp`` (> 0).
    beta : float
        ``β = c z_ref`` (> 0 for braking: ``c = -c2 > 0``).
    zeta_a, zeta_b : float
        Section ``ζa = chi_a / (d z_ref)`` and switch ``ζb = chi_b / (d z_ref)``,
        ``ζa < ζb``, both with ``1 + β ζ > 0`` (physical XBS, ``z2 > -d/c``).

    Raises
    ------
    SimulationError
        For parameters outside that domain.

    Examples
    --------
    >>> pm = PoincareMap.from_abs(kp=3000.0, z_ref=8.0, chi_a=-0.1, chi_b=0.1, c=23.99, d=12.4748)
    >>> fp = pm.fixed_point()
    >>> fp.stable, fp.condition_holds
    (True, True)
    """

    alpha: float
    beta: float
    zeta_a: float
    zeta_b: float

    def __post_init__(self) -> None:
        for key in ("alpha", "beta", "zeta_a", "zeta_b"):
            value = getattr(self, key)
            if not isinstance(value, (int, float)) or not math.isfinite(value):
                raise SimulationError(f"Poincaré map: {key} must be a finite number, got {value!r}")
        if self.alpha <= 0 or self.beta <= 0:
            raise SimulationError(f"Poincaré map needs alpha = kp > 0 and beta = c z_ref > 0, "
                                  f"got alpha={self.alpha}, beta={self.beta}")
        if not self.zeta_a < self.zeta_b:
            raise SimulationError(f"Poincaré map needs zeta_a < zeta_b (chi_a < chi_b), "
                                  f"got {self.zeta_a} >= {self.zeta_b}")
        if 1.0 + self.beta * self.zeta_a <= 0.0:
            raise SimulationError(f"Poincaré map: 1 + beta zeta_a = {1 + self.beta * self.zeta_a:.4g} <= 0, "
                                  f"chi_a lies below the physical XBS range (z2 > -d/c)")

    @classmethod
    def from_abs(cls, *, kp: float, z_ref: float, chi_a: float, chi_b: float, c: float, d: float) -> PoincareMap:
        """Map of the two-phase ABS with gain ``kp``, reference ``z_ref``, thresholds and road ``c, d``."""
        if not (isinstance(z_ref, (int, float)) and z_ref > 0 and isinstance(d, (int, float)) and d > 0):
            raise SimulationError(f"Poincaré map needs z_ref > 0 and d > 0, got z_ref={z_ref!r}, d={d!r}")
        return cls(alpha=float(kp), beta=float(c * z_ref), zeta_a=float(chi_a / (d * z_ref)),
                   zeta_b=float(chi_b / (d * z_ref)))

    @property
    def kappa(self) -> float:
        """``κ`` of (4.14) (< 0)."""
        return math.log((1.0 + self.beta * self.zeta_a) / (1.0 + self.beta * self.zeta_b)) / self.beta

    def phi1(self, zeta: float) -> float:
        return zeta + math.log(1.0 - zeta) - 1.0 + self.alpha * self.kappa

    @staticmethod
    def phi2(delta: float) -> float:
        return 1.0 + _w0(-math.exp(delta))

    def phi3(self, zeta: float) -> float:
        return -zeta + math.log(1.0 + zeta) - 1.0 + self.alpha * self.kappa

    @staticmethod
    def phi4(delta: float) -> float:
        return -1.0 - _w0(-math.exp(delta))

    def switch_point(self, zeta: float) -> float:
        """``ζ1'``, the value of ``ζ1`` when phase 2 starts, from ``ζ1° = zeta`` (4.12a)."""
        self._check_domain(zeta)
        return self.phi2(self.phi1(zeta))

    def __call__(self, zeta: float) -> float:
        """``P(ζ1°)``: ``ζ1''`` at the next start of phase 1 (4.13)."""
        return self.phi4(self.phi3(self.switch_point(zeta)))

    def derivative(self, zeta: float) -> tuple[float, tuple[float, float, float, float]]:
        """``P'(ζ)`` and its factors ``(φ4', φ3', φ2', φ1')`` (Sec. 4.3.3)."""
        d1 = self.phi1(zeta)
        w1 = _w0(-math.exp(d1))
        z1p = 1.0 + w1
        d2 = self.phi3(z1p)
        w2 = _w0(-math.exp(d2))
        f1 = zeta / (zeta - 1.0)
        f2 = w1 / (1.0 + w1)
        f3 = -z1p / (1.0 + z1p)
        f4 = -w2 / (1.0 + w2)
        return f4 * f3 * f2 * f1, (f4, f3, f2, f1)

    @property
    def alpha_bound(self) -> float:
        """Sufficient bound of Sec. 4.3.3: ``α > (δ_up + 1) / κ`` with ``δ_up -> ln(1/2) - 1/2`` (``m -> 1``)."""
        return (math.log(0.5) - 0.5 + 1.0) / self.kappa

    def _check_domain(self, zeta: float) -> None:
        if not (isinstance(zeta, (int, float)) and -math.inf < zeta < 0.0):
            raise SimulationError(f"the Poincaré map is defined for ζ1° < 0 (z1 < 0 when phase 1 starts), "
                                  f"got {zeta!r}")

    def fixed_point(self) -> PoincareFixedPoint:
        """The fixed point ``P(ζ) = ζ`` in ``(-1, 0)`` and ``P'`` there.

        Raises
        ------
        SolverFailure
            If no sign change of ``P(ζ) - ζ`` is found in ``(-1, 0)``.
        """
        # with a large alpha |kappa| the cycle saturates (ζ1 within 1e-12 of -1): bracket to the last float
        lo, hi = math.nextafter(-1.0, 0.0), math.nextafter(0.0, -1.0)
        f_lo, f_hi = self(lo) - lo, self(hi) - hi
        if -8 * np.finfo(float).eps < f_lo < 0.0:
            f_lo = 0.0      # P rounds to -1: the fixed point is -1 to the last bit (e^(alpha kappa) < 1e-15)
        if not (f_lo >= 0.0 >= f_hi):
            raise SolverFailure(f"P(ζ) - ζ does not change sign on (-1, 0) ({f_lo:.3g}, {f_hi:.3g}); "
                                f"no fixed point for {self}")
        from scipy.optimize import brentq

        zeta = lo if f_lo == 0.0 else brentq(lambda z: self(z) - z, lo, hi, xtol=1e-15,
                                             rtol=4 * np.finfo(float).eps, maxiter=200)
        deriv, factors = self.derivative(zeta)
        return PoincareFixedPoint(zeta=float(zeta), derivative=float(deriv),
                                  factors=factors, alpha=self.alpha, alpha_bound=self.alpha_bound)

    def to_json(self) -> dict[str, Any]:
        return {**asdict(self), "kappa": self.kappa, "alpha_bound": self.alpha_bound}

    def __str__(self) -> str:
        return (f"Poincaré map (4.13): α={self.alpha:g}, β={self.beta:g}, ζa={self.zeta_a:.4g}, "
                f"ζb={self.zeta_b:.4g}, κ={self.kappa:.4g}")


def simulate_return_map(z1_start: float, *, kp: float, z_ref: float, chi_a: float, chi_b: float, c: float,
                        d: float, rtol: float = 1e-12, atol: float = 1e-13) -> tuple[float, float]:
    """Return map of (4.5) measured by integration: ``(z1 at phase-2 start, z1 at next phase-1 start)``.

    Starts on the section ``z2 = chi_a`` with ``z1 = z1_start < 0`` in phase 1,
    integrates (DOP853 with event location) until ``z2`` rises to ``chi_b``,
    switches the reference and integrates until ``z2`` falls back to ``chi_a``.

    Raises
    ------
    SimulationError
        If ``z1_start >= 0``.
    SolverFailure
        If a phase does not end within a generous time.
    """
    from scipy.integrate import solve_ivp

    if not z1_start < 0:
        raise SimulationError(f"the return map starts with z1 < 0 on the section z2 = chi_a, got {z1_start}")

    def phase(z0: tuple[float, float], ref: float, target: float, direction: float) -> tuple[float, float]:
        def f(s: float, z: np.ndarray) -> list[float]:
            return [-kp * (z[0] - ref), (c * z[1] + d) * z[0]]

        def event(s: float, z: np.ndarray) -> float:
            return z[1] - target
        event.terminal = True
        event.direction = direction
        # the phase lasts a few 1/(d z_ref) + 1/kp in s: integrate far enough
        horizon = 50.0 * (1.0 / kp + (abs(chi_b - chi_a) + 1.0) / (d * z_ref))
        sol = solve_ivp(f, (0.0, horizon), list(z0), method="DOP853", rtol=rtol, atol=atol, events=event)
        if sol.status != 1 or not len(sol.t_events[0]):
            raise SolverFailure(f"the phase with z1* = {ref:g} did not reach z2 = {target:g} within s = {horizon:g}")
        zf = sol.y_events[0][0]
        return float(zf[0]), float(zf[1])

    z1p, _ = phase((z1_start, chi_a), z_ref, chi_b, 1.0)
    z1pp, _ = phase((z1p, chi_b), -z_ref, chi_a, -1.0)
    return z1p, z1pp
