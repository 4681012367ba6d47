"""Built-in models: the seeds' ABS models and the generic normal form."""

from __future__ import annotations

import re
import tomllib
from importlib import resources
from pathlib import Path

from .._limits import MAX_DIMENSION
from ..exceptions import ModelError
from ._model import Model

__all__ = ["builtin_model", "builtin_names", "load_model"]

_NORMAL_FORM = re.compile(r"^normal-form-(\d+)$")
_FILES = ("abs-xbs3", "abs-xbs4", "abs-adaptive2", "abs-adaptive2-load")


def builtin_names() -> tuple[str, ...]:
    """Names accepted by :func:`builtin_model` (``normal-form-N`` for any N >= 1)."""
    return (*_FILES, "normal-form-N")


def _normal_form(n: int) -> Model:
    """Generic observer normal form (seed 004, slide 'Observer normal form')."""
    a = [f"a{i}" for i in range(1, n + 1)]
    A = [[a[i] if j == 0 else ("1" if j == i + 1 else "0") for j in range(n)] for i in range(n)]
    return Model.from_dict({
        "name": f"normal-form-{n}",
        "description": f"generic observer normal form of dimension {n} (seed 004)",
        "states": [f"z{i}" for i in range(1, n + 1)],
        "A": A,
        "C": ["1"] + ["0"] * (n - 1),
        "time_scale": "y",
        "parameters": a,
        "references": {"model": "seed 004 'Observer normal form'", "gains": "seed 004 Theorem 1"},
    }, source=f"normal-form-{n}")


def builtin_model(name: str) -> Model:
    """Return a built-in model by name.

    Parameters
    ----------
    name : str
        ``abs-xbs3`` (seed 000 eq. (7)), ``abs-xbs4`` (seed 000 eq. (20)),
        ``abs-adaptive2`` (seed 001 eq. (3.2)), ``abs-adaptive2-load`` (the same with the load-dependent
        ``a`` a measured signal, seed 001 Sec. 3.6) or ``normal-form-N``.

    Raises
    ------
    ModelError
        For an unknown name; the message lists the known ones.
    """
    match = _NORMAL_FORM.match(name)
    if match:
        n = int(match.group(1))
        if not 1 <= n <= MAX_DIMENSION:
            raise ModelError(f"normal-form-N needs 1 <= N <= {MAX_DIMENSION} (MAX_DIMENSION), got N = {n}")
        return _normal_form(n)
    if name in _FILES:
        text = resources.files("switchobs.model").joinpath("builtin", f"{name}.toml").read_text("utf-8")
        return Model.from_dict(tomllib.loads(text, parse_float=str), source=f"built-in {name}")
    raise ModelError(f"unknown model {name!r}: give a built-in name ({', '.join(builtin_names())}) "
                     "or the path of a TOML file")


def load_model(spec: str | Path) -> Model:
    """A built-in name, the path of a TOML model file, or ``"-"``: a TOML model on standard input."""
    spec_str = str(spec)
    if spec_str == "-" or spec_str.endswith(".toml") or Path(spec_str).exists():
        return Model.from_toml(spec_str)
    return builtin_model(spec_str)
