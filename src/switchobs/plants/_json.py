"""Reading the ``to_json`` of the plant dataclasses back (one helper for their flat field dictionaries)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import MISSING, fields
import math
from typing import Any, TypeVar

import numpy as np
import numpy.typing as npt

from ..exceptions import SimulationError

T = TypeVar("T")


def from_fields(cls: type[T], data: Any, what: str, **parsed: Any) -> T:
    """``cls(**fields)`` from a ``to_json`` dictionary: one key per init field, lists as tuples.

    Parameters
    ----------
    cls : dataclass type
    data : mapping
        The JSON; keys that are not fields (derived values such as ``speed_kmh``) are ignored,
        a missing field takes its default.
    what : str
        Names the object in error messages.
    **parsed
        Fields already read by the caller (nested objects).

    Raises
    ------
    SimulationError
        Not a mapping, a missing required field, or a value the class rejects; the message names ``what``.
    """
    if not isinstance(data, Mapping):
        raise SimulationError(f"a {what} JSON must be an object, got {data!r}")
    kwargs: dict[str, Any] = {}
    for f in fields(cls):  # type: ignore[arg-type]
        if not f.init:
            continue
        if f.name in parsed:
            kwargs[f.name] = parsed[f.name]
        elif f.name in data:
            value = data[f.name]
            kwargs[f.name] = tuple(value) if isinstance(value, list) else value
        elif f.default is MISSING and f.default_factory is MISSING:
            raise SimulationError(f"a {what} JSON needs {f.name!r}")
    try:
        return cls(**kwargs)
    except SimulationError:
        raise
    except (TypeError, ValueError) as exc:
        raise SimulationError(f"not a {what} JSON ({type(exc).__name__}: {exc})") from None


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
        series = {str(k): np.array([math.nan if v is None else float(v) for v in col], dtype=np.float64)
                  for k, col in data["series"].items()}
        events = tuple((float(e["t"]), str(e["event"])) for e in data["events"])
    except (KeyError, TypeError, ValueError) as exc:
        raise SimulationError(f"not a {what} JSON ({type(exc).__name__}: {exc})") from None
    return series, events
