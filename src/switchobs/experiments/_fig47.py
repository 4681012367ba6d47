"""Seed 001 Fig. 4.7: the two-phase ABS of Chapter 4 against the five-phase ABS, wet asphalt, 120 km/h.

The seed compares the two "qualitatively" in the phase plane of the wheel slip and states that "with the
two-phase algorithm [...] a smaller variation of the wheel slip with respect to its optimal value is obtained".
The runs are the Table 4.1 cell of that road and speed (:func:`switchobs.plants.table41`'s controllers and
scenario); the number is the RMS of ``lambda - lambda*`` while the ABS is active.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..plants import BrakingResult, BrakingScenario, FivePhaseABS, TwoPhaseABS, road, simulate

__all__ = ["FIG47_ROAD", "FIG47_SPEED_KMH", "Fig47", "fig47_runs"]

FIG47_ROAD = "wet-asphalt"
FIG47_SPEED_KMH = 120.0


@dataclass(frozen=True)
class Fig47:
    """The Fig. 4.7 brakings: ``five`` and ``two`` (the Table 4.1 controllers on the true XBS)."""

    five: BrakingResult
    two: BrakingResult

    @staticmethod
    def slip_deviation(result: BrakingResult) -> float:
        """RMS of ``lambda - lambda*`` from the ABS activation to the stop (``lambda*``: the road's optimal slip)."""
        s = result.series
        active = s["t"] >= result.metrics.abs_activation_s
        return float(np.sqrt(np.mean((s["lambda"][active] - road(FIG47_ROAD).optimal_slip) ** 2)))

    @staticmethod
    def slip_range(result: BrakingResult) -> tuple[float, float]:
        """5th and 95th percentiles of the slip while the ABS is active."""
        s = result.series
        lo, hi = np.percentile(s["lambda"][s["t"] >= result.metrics.abs_activation_s], [5.0, 95.0])
        return float(lo), float(hi)


def fig47_runs() -> Fig47:
    """Both ABS algorithms on wet asphalt from 120 km/h, as the Table 4.1 campaign runs them (the two-phase ABS
    without its start-up safeguard on the true XBS)."""
    out = [simulate(BrakingScenario(FIG47_ROAD, speed_m_s=FIG47_SPEED_KMH / 3.6, controller=ctrl,
                                    name=f"fig47-{ctrl.name}"))
           for ctrl in (FivePhaseABS(), TwoPhaseABS(start_decel_m_s2=None))]
    return Fig47(out[0], out[1])
