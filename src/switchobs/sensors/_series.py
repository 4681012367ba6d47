"""The common result of every speed/acceleration estimator, and error metrics against a truth."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from .._json import JsonRecord
from ..exceptions import SimulationError

__all__ = ["SpeedEstimate", "rms_error", "estimate_lag"]

Array = npt.NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class SpeedEstimate(JsonRecord, error=SimulationError):
    """Wheel speed and acceleration estimated at the controller samples.

    Attributes
    ----------
    t : ndarray
        Controller sample times (s).
    omega, alpha : ndarray
        Estimated speed (rad/s) and acceleration (rad/s^2); NaN while the
        estimator has no data yet (before the first TSA window is full).
    method : str
        ``"tsa"``, ``"notch"``, ``"three-stage"`` or ``"super-twisting"``.
    """

    t: Array
    omega: Array
    alpha: Array
    method: str

    def to_json(self) -> dict[str, Any]:
        def clean(a: Array) -> list[float | None]:
            return [None if math.isnan(x) else float(x) for x in a]
        return {"method": self.method, "t": self.t.tolist(), "omega": clean(self.omega),
                "alpha": clean(self.alpha)}

    def __str__(self) -> str:
        ok = np.isfinite(self.omega)
        return f"SpeedEstimate[{self.method}]: {self.t.size} samples ({np.count_nonzero(ok)} with data)"


def rms_error(estimate: Array, truth: Array, mask: npt.NDArray[np.bool_] | None = None) -> float:
    """Root-mean-square of ``estimate - truth`` over ``mask`` (and finite estimates)."""
    use = np.isfinite(estimate) if mask is None else mask & np.isfinite(estimate)
    if not np.any(use):
        return math.nan
    return float(np.sqrt(np.mean((estimate[use] - truth[use]) ** 2)))


def estimate_lag(t: Array, estimate: Array, truth: Array, *, max_lag_s: float = 0.1) -> float:
    """Delay (s) that best aligns ``estimate`` with ``truth`` (least squares over whole samples).

    Positive when the estimate lags.  Both signals are taken on the uniform
    grid ``t``; non-finite samples are ignored.  NaN when the truth is
    constant (a delay is then unobservable).
    """
    if np.ptp(truth[np.isfinite(truth)]) == 0.0:
        return math.nan
    dt = float(t[1] - t[0])
    best, best_err = 0.0, math.inf
    for shift in range(int(round(max_lag_s / dt)) + 1):
        est = estimate[shift:]
        tru = truth[: truth.size - shift]
        ok = np.isfinite(est) & np.isfinite(tru)
        if not np.any(ok):
            continue
        err = float(np.mean((est[ok] - tru[ok]) ** 2))
        if err < best_err:
            best, best_err = shift * dt, err
    return best
