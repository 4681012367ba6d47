"""Reading the ``to_json`` of the plant dataclasses back (one helper for their flat field dictionaries)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar

import numpy as np
import numpy.typing as npt

from .._json import array_from_json, fields_from_json
from ..exceptions import SimulationError

T = TypeVar("T")


def from_fields(cls: type[T], data: Any, what: str, **parsed: Any) -> T:
    """:func:`switchobs._json.fields_from_json` raising :class:`SimulationError`, the object named ``what``."""
    return fields_from_json(cls, data, error=SimulationError, what=what, **parsed)


def controller_from_json(data: Any, what: str) -> Any:
    """A :class:`FivePhaseABS`, :class:`SixPhaseABS`, :class:`TwoPhaseABS` or :class:`ContinuousXbsControl` by its
    JSON ``name``.

    Raises
    ------
    SimulationError
        No known ``name`` or a setting the controller rejects; the message names ``what``.
    """
    from ._controllers import ContinuousXbsControl, FivePhaseABS, SixPhaseABS, TwoPhaseABS

    kinds = {c.name: c for c in (FivePhaseABS, SixPhaseABS, TwoPhaseABS, ContinuousXbsControl)}
    if not isinstance(data, Mapping) or data.get("name") not in kinds:
        raise SimulationError(f"{what} needs a controller named one of {', '.join(kinds)}, got {data!r}")
    return from_fields(kinds[data["name"]], data, f"{data['name']} controller")


def run_from_json(data: Any, what: str) -> tuple[dict[str, npt.NDArray[np.float64]], tuple[tuple[float, str], ...]]:
    """The ``series`` (float arrays, ``null`` as NaN) and ``events`` of a run's ``to_json(include_series=True)``.

    Raises
    ------
    SimulationError
        No ``series`` (written without ``include_series=True``) or malformed events.
    """
    if not isinstance(data, Mapping) or not isinstance(data.get("series"), Mapping):
        raise SimulationError(f"a {what} JSON needs the series arrays; write it with to_json(include_series=True)")
    try:
        series = {str(k): array_from_json(col) for k, col in data["series"].items()}
        events = tuple((float(e["t"]), str(e["event"])) for e in data["events"])
    except (KeyError, TypeError, ValueError) as exc:
        raise SimulationError(f"not a {what} JSON ({type(exc).__name__}: {exc})") from None
    return series, events
