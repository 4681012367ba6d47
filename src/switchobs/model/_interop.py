"""The one boundary for matrices from the Python ecosystem: lists, NumPy, sympy and python-control.

Every public entry that takes a matrix or a vector (the model's ``A`` and ``C``,
a spectrum, gains, a switched family) reads it here, so that a NumPy array, a
sympy ``Matrix`` and a ``control.StateSpace`` are accepted the same way
everywhere, and every number follows the one float rule of
:func:`~switchobs.model.exact_number` (a float is its exact binary value).
python-control is imported only when a state-space object is built, never to
recognise one, so that reading lists stays cheap.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import sympy as sp

from ..exact import Matrix, fraction_matrix
from ..exceptions import DimensionError, ModelError
from ._expr import exact_number

__all__ = ["is_statespace", "statespace_matrices", "matrix_rows", "entries", "user_matrix"]


def is_statespace(value: Any) -> bool:
    """``value`` is a python-control ``StateSpace`` (recognised without importing control)."""
    return any(c.__name__ == "StateSpace" and c.__module__.startswith("control")
               for c in type(value).__mro__)


def statespace_matrices(sys: Any, *, what: str = "system") -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(A, B, C, D)`` of a continuous-time single-output ``control.StateSpace`` (a ``TransferFunction`` is
    converted by ``control.tf2ss``, its controllable canonical realisation).

    Raises
    ------
    DimensionError
        More than one output: a switchobs model measures one ``y = C z``.
    ModelError
        A discrete-time system (the model is ``dz/dt = ...``), an improper transfer function, or neither a
        StateSpace nor a TransferFunction.
    """
    if not hasattr(sys, "A") and hasattr(sys, "num") and hasattr(sys, "den"):
        import control

        try:
            sys = control.tf2ss(sys)
        except ValueError as exc:
            raise ModelError(f"{what}: the TransferFunction has no state-space realisation ({exc}); give a "
                             "proper one") from None
    missing = [k for k in ("A", "B", "C", "D") if not hasattr(sys, k)]
    if missing:
        raise ModelError(f"{what} must be a control.StateSpace or TransferFunction, got {type(sys).__name__}")
    A, B, C, D = (np.asarray(getattr(sys, k)) for k in ("A", "B", "C", "D"))
    if C.shape[0] != 1:
        raise DimensionError(f"{what} has {C.shape[0]} outputs; a switchobs model measures one output y = C z "
                             "(select one, e.g. sys[0, :])")
    dt = getattr(sys, "dt", 0)
    if dt not in (0, None):
        raise ModelError(f"{what} is a discrete-time system (dt = {dt}); switchobs models are continuous-time "
                         "(convert with control.d2c or give the continuous model)")
    return A, B, C, D


def _convert(value: Any, what: str) -> Any:
    if isinstance(value, (list, tuple)):
        return [_convert(v, f"{what}[{i + 1}]") for i, v in enumerate(value)]
    return exact_number(value, what=what)


def matrix_rows(value: Any, *, name: str, part: str = "A") -> Any:
    """A matrix (or vector) as nested lists of exact entries, whatever it came as.

    Parameters
    ----------
    value : list of rows, numpy.ndarray, sympy matrix, control.StateSpace or other
        NumPy arrays of any integer, float or complex dtype; sympy matrices with
        numbers, ``Float`` s or expressions; a ``StateSpace`` gives its matrix
        ``part``.  Anything else is returned unchanged for the caller's own check.
    name : str
        The matrix's name in messages.
    part : {"A", "C"}
        Which matrix a ``StateSpace`` gives (``"C"`` must be one output row).

    Returns
    -------
    list
        Nested lists (a 1-D array gives a flat list); numbers are exact sympy
        numbers (:func:`exact_number`), strings are left for the expression parser.

    Raises
    ------
    DimensionError
        A ``StateSpace`` with several outputs given for ``C``; an array of more than two dimensions.
    ExpressionError
        A boolean, NaN or infinite entry.
    """
    if is_statespace(value):
        A, _, C, _ = statespace_matrices(value, what=f"the StateSpace given for {name}")
        value = A if part == "A" else C
    if isinstance(value, sp.MatrixBase):
        value = value.tolist()
    elif isinstance(value, np.ndarray):
        if value.dtype.kind not in "biufcO" or value.ndim > 2:
            raise DimensionError(f"{name} must be a vector or matrix of numbers, got an array of dtype "
                                 f"{value.dtype} and shape {value.shape}")
        # element by element, not tolist(): NumPy scalars keep their exact value (a longdouble too)
        value = value[()] if value.ndim == 0 else list(value) if value.ndim == 1 else [list(r) for r in value]
    return _convert(value, name)


def entries(value: Any, *, name: str) -> Any:
    """A flat sequence of exact entries (a spectrum, gains, coefficients) from any vector-like value.

    A column or row matrix (NumPy or sympy) is flattened; a string is returned
    unchanged (the comma-separated form of the command line).
    """
    if isinstance(value, str):
        return value
    rows = matrix_rows(value, name=name)
    if isinstance(rows, list) and rows and all(isinstance(r, list) for r in rows):
        if min(len(rows), len(rows[0])) != 1:
            raise DimensionError(f"{name} must be a vector, got a {len(rows)} x {len(rows[0])} matrix")
        return [e for r in rows for e in r]
    return rows


def user_matrix(value: Any, *, what: str, part: str = "A", rows: int | None = None,
                cols: int | None = None) -> Matrix:
    """A user's matrix (list of rows, NumPy, sympy, ``control.StateSpace`` for ``part``) as exact rationals.

    The boundary of exact matrix work: :func:`matrix_rows` reads the
    container and the numbers (a float is its exact binary value), then the
    exact layer checks the shape.  A flat sequence is one row.
    """
    return fraction_matrix(matrix_rows(value, name=what, part=part), what=what, rows=rows, cols=cols)
