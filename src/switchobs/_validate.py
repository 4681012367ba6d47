"""Boundary validation of user arrays shared by the layers (below every layer, like ``exceptions``)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from fractions import Fraction
from typing import Any

import numpy as np

from ._limits import DOUBLE_MAX, decimal_fraction
from .exceptions import DimensionError

__all__ = ["named_vector", "signal_matrix", "adaptation_gain", "substep_bound", "round_down", "check_work",
           "DEFAULT_MAX_SUBSTEPS"]

#: Sub-steps allowed per step when a step bound h_max is given and max_substeps is not.
DEFAULT_MAX_SUBSTEPS = 64


def named_vector(values: Any, names: Sequence[str], what: str) -> np.ndarray:
    """``values`` as a float vector with one entry per name; DimensionError naming the shape otherwise."""
    try:
        arr = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise DimensionError(f"{what} must be {len(names)} numbers ({', '.join(names)}), got {values!r}") from None
    if arr.shape != (len(names),):
        raise DimensionError(f"{what} has the wrong shape; expected ({len(names)},) for ({', '.join(names)}) "
                             f"instead of {arr.shape}")
    return arr


def signal_matrix(rows: Any, names: Sequence[str]) -> np.ndarray:
    """Rows of signals (one column per name) as a float array; DimensionError naming the shape otherwise."""
    try:
        arr = np.asarray(rows, dtype=float)
    except (TypeError, ValueError):
        raise DimensionError(f"signal_rows must be a k x {len(names)} array of numbers") from None
    if arr.ndim != 2 or arr.shape[1] != len(names):
        raise DimensionError(f"signal_rows has the wrong shape; expected (k, {len(names)}) "
                             f"for ({', '.join(names)}) instead of {arr.shape}")
    return arr


def adaptation_gain(Gamma: Any, unknown: Sequence[str], *, error: type[Exception]) -> np.ndarray:
    """The adaptation gain Gamma = Gamma' > 0 of seed 001 eq. (3.4) (a diagonal may be given as a vector).

    ``error`` is the exception class of the calling layer for a missing or
    non-positive Gamma; shape problems raise DimensionError.
    """
    p = len(unknown)
    if Gamma is None:
        raise error(f"the adaptive observer needs Gamma, a {p} x {p} symmetric positive definite "
                    f"adaptation gain for ({', '.join(unknown)}) (seed 001 eq. (3.4))")
    try:
        G = np.asarray(Gamma, dtype=float)
    except (TypeError, ValueError):
        raise DimensionError(f"Gamma must be a {p} x {p} matrix of numbers, got {Gamma!r}") from None
    if G.shape == (p,):
        G = np.diag(G)
    if G.shape != (p, p):
        raise DimensionError(f"Gamma has the wrong shape; expected ({p}, {p}) (or a diagonal of {p}) for "
                             f"({', '.join(unknown)}) instead of {G.shape}")
    if not np.isfinite(G).all():
        raise error(f"Gamma = {G.tolist()} has a non-finite entry")
    if not np.allclose(G, G.T, rtol=1e-12, atol=0.0):
        raise error(f"Gamma = {G.tolist()} is not symmetric (seed 001 eq. (3.4) needs Gamma = Gamma' > 0)")
    eig = np.linalg.eigvalsh(G)
    if eig.min() <= 0.0:
        raise error(f"Gamma is not positive definite: its eigenvalues are {eig.tolist()} "
                    "(seed 001 eq. (3.4) needs Gamma = Gamma' > 0)")
    return G


def substep_bound(h_max: Any, max_substeps: Any, *, error: type[Exception]) -> tuple[Fraction, int] | None:
    """The certified step bound in rescaled time as an exact rational, and the sub-step limit.

    ``h_max`` is a positive finite number, a :class:`fractions.Fraction` or a
    decimal / fraction string (``"1/100"``); a float is read as the decimal it
    prints as (``0.01`` is 1/100), like every number of a model.  ``None``
    means no bound (no sub-stepping) and then ``max_substeps`` must be ``None``
    too; otherwise ``max_substeps`` defaults to :data:`DEFAULT_MAX_SUBSTEPS`.
    """
    if h_max is None:
        if max_substeps is not None:
            raise error(f"max_substeps = {max_substeps!r} has no effect without h_max; give h_max too")
        return None
    try:
        if isinstance(h_max, bool):
            raise TypeError
        if isinstance(h_max, str):  # size first: "1e999999999" must not be expanded
            exact = decimal_fraction(h_max, what="h_max", error=ValueError)
        else:
            exact = Fraction(repr(float(h_max))) if isinstance(h_max, (float, np.floating)) else Fraction(h_max)
    except (TypeError, ValueError, ZeroDivisionError, OverflowError) as exc:
        detail = f" ({exc})" if "limit" in str(exc) else ""  # a size refusal names its limit; keep it
        raise error(f"h_max = {h_max!r} must be a positive finite number such as 0.01 or 1/100{detail}") from None
    if exact <= 0:
        raise error(f"h_max = {h_max!r} must be > 0 (a step bound in the rescaled time tau)")
    limit = DEFAULT_MAX_SUBSTEPS if max_substeps is None else max_substeps
    # 2**24: exact in IEEE single, so that the float build's ceil(q) <= MAX_SUBSTEPS fits its int32_t
    if isinstance(limit, bool) or not isinstance(limit, (int, np.integer)) or not 1 <= limit <= 2**24:
        raise error(f"max_substeps = {max_substeps!r} must be an integer in 1 .. 16777216")
    return exact, int(limit)


def round_down(value: Fraction, real: str = "double", *, error: type[Exception]) -> float:
    """The largest ``real`` (double or IEEE single) not above the positive rational ``value``.

    A certified bound must not grow when it is written as a floating-point
    literal, so it is rounded towards zero, not to nearest.
    """
    single = real == "float"
    largest = float(np.finfo(np.float32).max) if single else DOUBLE_MAX
    if value > largest:  # it would silently become the largest real, another bound than the one given
        raise error(f"h_max = {float(value):.4g} overflows a {real} (largest {largest:.4g}); give a smaller bound")
    try:
        near = float(np.float32(float(value))) if single else float(value)
    except OverflowError:
        near = math.inf
    while not math.isfinite(near) or Fraction(near) > value:
        near = float(np.nextafter(np.float32(near), np.float32(0.0))) if single else math.nextafter(near, 0.0)
    if not near > 0.0:
        raise error(f"h_max = {value} is below the smallest positive {real}; give a larger bound")
    return near


def check_work(what: str, estimate: float, limit: float, fix: str, *, error: type[Exception]) -> None:
    """Refuse a run whose estimated size ``estimate`` (edges, samples, steps...) exceeds ``limit``.

    Called before anything of that size is allocated, so that a hostile or
    mistyped option ends with one message naming the estimate, the limit and
    the way out (``fix``) instead of exhausting memory or time.  A NaN
    estimate is refused too.
    """
    if not estimate <= limit:
        raise error(f"{what}: about {estimate:.3g}, above the limit of {limit:.3g}; {fix}")
