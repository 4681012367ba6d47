"""Reading a frozen dataclass back from its ``to_json`` (standard library and NumPy only; every layer may use it).

Most results write one JSON key per field, with tuples as lists, enums as
their values, nested results as their own ``to_json``, arrays as lists with
NaN as ``null``, and non-finite floats either as themselves (``json`` writes
``NaN``/``Infinity``) or as ``null``.  :func:`fields_from_json` undoes that
from the field type hints, and :class:`JsonRecord` makes it the class's
``from_json``; a class whose JSON has another shape writes its own
``from_json`` and passes the parts it read as ``parsed``.

Keys that are not fields (values the class derives, such as a tyre's
``peak_friction``) are not read, except a key that names a string class
constant (a controller's ``name``, a case's ``kind``): it must match, so
the JSON of one class is not read silently as another with its defaults.
"""

from __future__ import annotations

import dataclasses
import enum
import functools
import inspect
import math
import sys
import types
import typing
from collections.abc import Mapping
from fractions import Fraction
from pathlib import Path
from typing import Any, ClassVar, TypeVar

import numpy as np

from .exceptions import SwitchobsError

__all__ = ["JsonRecord", "fields_from_json", "array_from_json", "array_to_json"]

T = TypeVar("T")


class JsonRecord:
    """Gives a frozen dataclass ``from_json`` (the inverse of its ``to_json``) through :func:`fields_from_json`.

    A subclass names the exception of its layer: ``class Run(JsonRecord, error=SimulationError)``
    (subclasses of a record inherit it).
    """

    json_error: ClassVar[type[SwitchobsError]] = SwitchobsError

    def __init_subclass__(cls, *, error: type[SwitchobsError] | None = None, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if error is not None:
            cls.json_error = error

    @classmethod
    def from_json(cls: type[T], data: Any) -> T:
        """The object of ``to_json`` (as ``json.loads`` gives it back).

        Raises
        ------
        SwitchobsError
            The layer's error (:attr:`json_error`): not an object, a missing field, a value of the wrong kind
            or one the class rejects; the message names the class.
        """
        return fields_from_json(cls, data, error=cls.json_error)  # type: ignore[attr-defined]


def fields_from_json(cls: type[T], data: Any, *, error: type[SwitchobsError], what: str | None = None,
                     **parsed: Any) -> T:
    """``cls(**fields)`` from a ``to_json`` object, each value converted back by its field's type hint.

    Parameters
    ----------
    cls : dataclass type
    data : mapping
        The JSON; a missing field takes its default, keys that are not fields are not read (module notes).
    error : SwitchobsError subclass
        Raised on a malformed JSON.
    what : str, optional
        Names the object in error messages (default: the class name).
    **parsed
        Fields the caller has already read (parts whose JSON has another shape).

    Raises
    ------
    error
        Not a mapping, a missing required field, a mismatched class constant, or a value the type hints or
        the class reject; the message names ``what``.
    """
    what = what or cls.__name__
    if not isinstance(data, Mapping):
        raise error(f"a {what} JSON must be an object, got {data!r:.80}")
    for key, value in data.items():
        constant = getattr(cls, key, None) if key not in _hints(cls) else None
        if isinstance(constant, str) and value != constant:
            raise error(f"a {what} JSON has {key} {constant!r}, got {value!r}")
    kwargs: dict[str, Any] = {}
    for f in dataclasses.fields(cls):  # type: ignore[arg-type]
        if not f.init:
            continue
        if f.name in parsed:
            kwargs[f.name] = parsed[f.name]
        elif f.name in data:
            try:
                kwargs[f.name] = _decode(_hints(cls)[f.name], data[f.name], error)
            except SwitchobsError:
                raise
            except (TypeError, ValueError, ArithmeticError) as exc:
                raise error(f"a {what} JSON has a bad {f.name!r} ({type(exc).__name__}: {exc})") from None
        elif f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            raise error(f"a {what} JSON needs {f.name!r}{_written_with(cls)}")
    try:
        return cls(**kwargs)
    except SwitchobsError:
        raise
    except (TypeError, ValueError) as exc:
        raise error(f"not a {what} JSON ({type(exc).__name__}: {exc})") from None


def array_to_json(a: Any) -> list[Any]:
    """A NumPy array as nested lists, NaN as ``null`` (strict JSON has no NaN)."""
    arr = np.asarray(a)
    if arr.dtype.kind != "f":
        return arr.tolist()  # type: ignore[no-any-return]
    return np.where(np.isnan(arr), None, arr.astype(object)).tolist()  # type: ignore[no-any-return]


def array_from_json(value: Any, dtype: Any = np.float64) -> np.ndarray[Any, Any]:
    """The array of :func:`array_to_json` (``null`` as NaN in a float array)."""
    if np.dtype(dtype).kind == "f":
        return np.array(_nulls_to_nan(value), dtype=dtype)
    return np.array(value, dtype=dtype)


def _nulls_to_nan(value: Any) -> Any:
    if isinstance(value, list):
        return [_nulls_to_nan(v) for v in value]
    return math.nan if value is None else value


def _written_with(cls: type) -> str:
    """How to write a JSON that can be read back, when ``to_json`` leaves parts out by default."""
    to_json = getattr(cls, "to_json", None)
    if to_json is None:
        return ""
    flags = [p.name for p in inspect.signature(to_json).parameters.values()
             if p.kind is p.KEYWORD_ONLY and p.default is False]
    return f"; write it with to_json({flags[0]}=True) to read it back" if flags else ""


@functools.cache
def _hints(cls: type) -> dict[str, Any]:
    """Each field's type, resolved in its class's module; a name that module does not import reads as Any."""
    out: dict[str, Any] = {}
    for klass in reversed(cls.__mro__):
        if not dataclasses.is_dataclass(klass):
            continue
        namespace = vars(sys.modules[klass.__module__])
        for f in dataclasses.fields(klass):
            hint = f.type
            if isinstance(hint, str):
                try:
                    hint = eval(hint, namespace)  # noqa: S307 - our own annotations, not input
                except (NameError, AttributeError, TypeError):
                    hint = Any
            out[f.name] = hint
    return out


def _decode(hint: Any, value: Any, error: type[SwitchobsError]) -> Any:
    """``value`` read back as ``hint`` (values of no type read here pass to the class to judge)."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if origin is typing.Union or origin is types.UnionType:
        options = [a for a in args if a is not type(None)]
        if value is None:
            return None
        return _decode(options[0], value, error) if len(options) == 1 else value
    if hint is float:
        if value is None:
            return math.nan
        return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else value
    if hint is Fraction:
        return Fraction(str(value))
    if hint is Path:
        return Path(value)
    if isinstance(hint, type) and issubclass(hint, enum.Enum):
        return hint(value)
    if origin is np.ndarray:
        dtype_args = typing.get_args(args[1]) if len(args) == 2 else ()
        return array_from_json(value, dtype_args[0] if dtype_args and dtype_args[0] is not Any else np.float64)
    if isinstance(hint, type) and dataclasses.is_dataclass(hint) and isinstance(value, Mapping):
        reader = getattr(hint, "from_json", None)
        return reader(value) if reader is not None else fields_from_json(hint, value, error=error)
    if not isinstance(value, (list, tuple, Mapping)):
        return value
    if origin is list:
        return [_decode(args[0] if args else Any, v, error) for v in value]
    if origin is tuple or hint is tuple:
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_decode(args[0], v, error) for v in value)
        if args and len(args) == len(value):
            return tuple(_decode(a, v, error) for a, v in zip(args, value))
        return tuple(value)
    if origin in (dict, Mapping) or hint in (dict, Mapping):
        inner = args[1] if len(args) == 2 else Any
        return {k: _decode(inner, v, error) for k, v in value.items()}
    if isinstance(value, list) and hint is Any:
        return value
    return tuple(value) if isinstance(value, list) else value
