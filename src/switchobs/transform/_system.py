"""Nonlinear system files: dx/dt = f(x) + g(x) u, y = h(x) (seed 004, Part III; seed 000 eq. (4)).

The file format follows the model files (``docs/model-format.md``): the same
names rules, the same safe expression parser and the same exact numbers.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import sympy as sp

from .._limits import check_dimension
from ..exceptions import DimensionError, ModelError
from ..model import make_symbol, parse_expression
from ..model._model import _names, check_keys, read_toml, read_values

__all__ = ["System"]

_KNOWN = {"name", "description", "states", "f", "g", "h", "output", "inputs", "parameters", "external",
          "positive", "negative", "values", "references"}


@dataclass(frozen=True)
class System:
    """A single-output system ``dx/dt = f(x) + g(x) u, y = h(x)``.

    Build one with :meth:`System.from_dict` or :meth:`System.from_toml`.

    Attributes
    ----------
    name, description : str
    states : tuple of str
        State names ``x``.
    f : sympy.ImmutableMatrix, n x 1
        Drift, a function of the states, the parameters and the external signals.
    g : sympy.ImmutableMatrix, n x m
        Input vector fields (one column per input).
    h : sympy.Expr
        The measured output, a function of the states and the parameters.
    output : str
        Name the output takes in the normal form (``y``).
    inputs, parameters, external : tuple of str
        External signals (``vx``) are measured functions of time; the
        structural computation treats them as constants (see ``docs/transform.md``).
    positive, negative : tuple of str
        Sign assumptions (states, parameters or external signals).
    values : mapping str -> sympy.Rational
    symbols : mapping str -> sympy.Symbol
    references : mapping str -> str
    """

    name: str
    states: tuple[str, ...]
    f: sp.ImmutableMatrix
    g: sp.ImmutableMatrix
    h: sp.Expr
    output: str
    inputs: tuple[str, ...]
    parameters: tuple[str, ...]
    external: tuple[str, ...]
    positive: tuple[str, ...] = ()
    negative: tuple[str, ...] = ()
    values: Mapping[str, sp.Rational] = field(default_factory=dict)
    symbols: Mapping[str, sp.Symbol] = field(default_factory=dict)
    description: str = ""
    references: Mapping[str, str] = field(default_factory=dict)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], *, source: str = "system") -> "System":
        """Build a system from the keys of the TOML format (see ``docs/transform.md``).

        Raises
        ------
        ModelError, ExpressionError, DimensionError
            Naming the key and the offending value.
        """
        name = check_keys(data, _KNOWN, ("name", "states", "f", "h"), source)
        states = _names(data["states"], "states")
        if len(states) < 2:
            raise ModelError(f"{source}: 'states' has {len(states)} name(s); the normal form needs at least 2 states")
        check_dimension(len(states), what=f"{source}: the system", error=DimensionError)
        output = data.get("output", "y")
        _names([output], "output")
        inputs = _names(data.get("inputs"), "inputs")
        parameters = _names(data.get("parameters"), "parameters")
        external = _names(data.get("external"), "external")
        positive = _names(data.get("positive"), "positive")
        negative = _names(data.get("negative"), "negative")
        declared = [*states, output, *inputs, *parameters, *external]
        clash = sorted({n for n in declared if declared.count(n) > 1})
        if clash:
            raise ModelError(f"{source}: the name(s) {clash} are declared twice (states, output, inputs, "
                             "parameters and external must be distinct)")
        signed = set(states) | set(parameters) | set(external)
        for key, group in (("positive", positive), ("negative", negative)):
            stray = sorted(set(group) - signed)
            if stray:
                raise ModelError(f"{source}: '{key}' names {stray}, which are not states, parameters or "
                                 "external signals")
        if set(positive) & set(negative):
            raise ModelError(f"{source}: {sorted(set(positive) & set(negative))} declared both positive and negative")
        symbols = {n: make_symbol(n, positive=n in positive, negative=n in negative) for n in declared}
        n, m = len(states), len(inputs)
        drift_names = {k: symbols[k] for k in (*states, *parameters, *external)}
        f_raw = data["f"]
        if not isinstance(f_raw, list) or any(isinstance(e, list) for e in f_raw) or len(f_raw) != n:
            raise DimensionError(f"{source}: 'f' must be a flat list of {n} expressions (one per state), "
                                 f"got {f_raw!r}")
        f = sp.ImmutableMatrix([parse_expression(e, drift_names, what=f"f[{i + 1}]") for i, e in enumerate(f_raw)])
        g_raw = data.get("g", [[0] * m for _ in range(n)])
        if m == 1 and isinstance(g_raw, list) and all(not isinstance(e, list) for e in g_raw):
            g_raw = [[e] for e in g_raw]
        if (not isinstance(g_raw, list) or len(g_raw) != n
                or not all(isinstance(r, list) and len(r) == m for r in g_raw)):
            raise DimensionError(f"{source}: 'g' must hold {n} rows of {m} expression(s) (one row per state, "
                                 f"one column per input), got {g_raw!r}")
        g = sp.ImmutableMatrix(n, m, [parse_expression(e, drift_names, what=f"g[{i + 1}][{j + 1}]")
                                      for i, row in enumerate(g_raw) for j, e in enumerate(row)])
        h = parse_expression(data["h"], {k: symbols[k] for k in (*states, *parameters)}, what="h")
        if not h.free_symbols & {symbols[k] for k in states}:
            raise ModelError(f"{source}: the output h = {h} does not depend on the states")
        values = read_values(data.get("values"), parameters, symbols, source)
        references = data.get("references", {}) or {}
        if not isinstance(references, Mapping):
            raise ModelError(f"{source}: 'references' must be a table name = text, got {references!r}")
        return cls(name=name, states=states, f=f, g=g, h=h, output=output, inputs=inputs,
                   parameters=parameters, external=external, positive=positive, negative=negative,
                   values=values, symbols=symbols, description=str(data.get("description", "")),
                   references={str(k): str(v) for k, v in references.items()})

    def to_dict(self) -> dict[str, Any]:
        """The keys of the TOML format that :meth:`from_dict` reads back into an equal system (numbers exact)."""
        return {"name": self.name, "description": self.description, "states": list(self.states),
                "f": [str(e) for e in self.f], "g": [[str(e) for e in self.g.row(i)] for i in range(self.g.rows)],
                "h": str(self.h), "output": self.output, "inputs": list(self.inputs),
                "parameters": list(self.parameters), "external": list(self.external),
                "positive": list(self.positive), "negative": list(self.negative),
                "values": {k: str(v) for k, v in self.values.items()}, "references": dict(self.references)}

    @classmethod
    def from_toml(cls, path: str | Path) -> "System":
        """Read a system from a TOML file (keys as in :meth:`from_dict`)."""
        # the one bounded reader of model files: size, FIFOs, UTF-8; a number written in a file is its decimal value
        data = read_toml(path, what="system file", parse_float=str)
        return cls.from_dict(data, source=str(path))

    @property
    def n(self) -> int:
        return len(self.states)

    @property
    def state_symbols(self) -> tuple[sp.Symbol, ...]:
        return tuple(self.symbols[k] for k in self.states)

    @property
    def external_symbols(self) -> tuple[sp.Symbol, ...]:
        return tuple(self.symbols[k] for k in self.external)

    @property
    def output_symbol(self) -> sp.Symbol:
        return self.symbols[self.output]

    def parse(self, text: str, *, what: str, output: bool = False) -> sp.Expr:
        """Parse a candidate expression: in the states and parameters, or (``output``) in y, the external signals
        and the parameters (a time scale s(y, w))."""
        if output:
            names = (self.output, *self.parameters, *self.external)
        else:
            names = (*self.states, *self.parameters, *self.external)
        return parse_expression(text, {k: self.symbols[k] for k in names}, what=what)

    def __str__(self) -> str:
        return (f"System {self.name!r}: n={self.n}, states={list(self.states)}, y = {self.h}, "
                f"inputs={list(self.inputs)}, external={list(self.external)}")
