"""Boundary checks shared by the sensor modules (one place, one message style)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import numpy.typing as npt

from ..exceptions import SimulationError

__all__ = ["as_signal", "check_increasing", "check_int", "check_positive", "check_range"]


def as_signal(value: Any, name: str, *, length: int | None = None) -> npt.NDArray[np.float64]:
    """A finite 1-D float array, or a :class:`SimulationError` naming the first bad entry."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise SimulationError(f"{name} must be an array of numbers ({exc})") from None
    if arr.ndim != 1:
        raise SimulationError(f"{name} must be one-dimensional, got shape {arr.shape}")
    if length is not None and arr.size != length:
        raise SimulationError(f"{name} has {arr.size} samples; expected {length} (one per time stamp)")
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        i = int(bad[0])
        raise SimulationError(
            f"{name}[{i}] = {arr[i]} is not finite ({bad.size} non-finite sample(s)); "
            "remove or repair NaN/inf samples before estimation")
    return arr


def check_increasing(t: npt.NDArray[np.float64], name: str) -> None:
    """Refuse time stamps that are not strictly increasing, naming the first offending pair."""
    bad = np.flatnonzero(np.diff(t) <= 0.0)
    if bad.size:
        i = int(bad[0])
        raise SimulationError(
            f"{name} must be strictly increasing, but {name}[{i + 1}] = {t[i + 1]!r} <= "
            f"{name}[{i}] = {t[i]!r}; sort the time stamps or drop duplicates")


def check_int(value: Any, name: str, *, minimum: int) -> int:
    """An integer at least ``minimum`` (bools and non-integral floats refused)."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        if isinstance(value, float) and value.is_integer():
            value = int(value)
        else:
            raise SimulationError(f"{name} must be an integer, got {value!r}")
    if value < minimum:
        raise SimulationError(f"{name} must be at least {minimum}, got {value}")
    return int(value)


def check_positive(value: Any, name: str, *, allow_zero: bool = False) -> float:
    """A finite float > 0 (or >= 0 with ``allow_zero``)."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise SimulationError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(x) or x < 0.0 or (x == 0.0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise SimulationError(f"{name} must be finite and {bound}, got {value!r}")
    return x


def check_range(value: Any, name: str, low: float, high: float) -> float:
    """A finite float in the closed interval [low, high]."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise SimulationError(f"{name} must be a number, got {value!r}") from None
    if not (math.isfinite(x) and low <= x <= high):
        raise SimulationError(f"{name} must lie in [{low}, {high}], got {value!r}")
    return x
