"""Boundary validation of user arrays shared by the layers (below every layer, like ``exceptions``)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .exceptions import DimensionError

__all__ = ["named_vector", "signal_matrix", "adaptation_gain"]


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
