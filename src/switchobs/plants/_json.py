"""Reading the ``to_json`` of the plant dataclasses back (one helper for their flat field dictionaries)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import MISSING, fields
from typing import Any, TypeVar

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
