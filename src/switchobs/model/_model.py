"""The model class of switchobs: systems linear after a singular time-rescaling.

    dz/dt = s(y, t) (A z + d(y)) + b(y) u,    y = C z

(seed 004, eq. (1); seed 000, eq. (7) and (20); seed 001, eq. (3.2)).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import random
import re
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import sympy as sp

from .._limits import (MAX_INPUT_FILE_BYTES, MAX_NAME_LENGTH, MAX_NUMBER_DIGITS, check_dimension, check_double,
                       decimal_fraction, digits, read_text)
from ..exceptions import DimensionError, ExpressionError, FreeSymbolError, ModelError, NotRealError
from ._expr import exact_number, non_finite, parse_expression
from ._interop import matrix_rows, statespace_matrices

__all__ = ["Model", "numeric", "make_symbol"]

_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")  # \Z: "$" would admit a trailing newline
_RESERVED = {"t", "pi", "E", "I"}


@functools.lru_cache(maxsize=4096)
def _clashes_with_sympy(name: str) -> bool:
    """Whether ``sympy.sympify(name)`` is anything but the symbol ``name`` (``exp``, ``oo``, ``beta``, ``S``,
    ``lambda``): an expression written with it (``--json``, ``to_dict``) would not read back as the model's."""
    try:
        value = sp.sympify(name)  # name is an identifier (checked first): a look-up, nothing is run
    except (sp.SympifyError, SyntaxError, TypeError, ValueError):
        return True
    return not (isinstance(value, sp.Symbol) and value.name == name)


def make_symbol(name: str, *, positive: bool = False, negative: bool = False) -> sp.Symbol:
    """The one way switchobs creates symbols, so that equal names give equal symbols."""
    if positive:
        return sp.Symbol(name, positive=True)
    if negative:
        return sp.Symbol(name, negative=True)
    return sp.Symbol(name, real=True)


_SIGNS = ("positive", "negative", "real")


def symbols_to_json(*exprs: Any) -> dict[str, str]:
    """``{name: "positive" | "negative" | "real"}`` for the free symbols of ``exprs`` (expressions or matrices).

    With an expression's text, what :func:`symbols_from_json` needs to rebuild it equal: to sympy, symbols of
    one name with other assumptions are other symbols.
    """
    out = {}
    for expr in exprs:
        for s in getattr(expr, "free_symbols", ()):
            out[s.name] = "positive" if s.is_positive else "negative" if s.is_negative else "real"
    return dict(sorted(out.items()))


def symbols_from_json(data: Any, *, what: str) -> dict[str, sp.Symbol]:
    """The symbols of :func:`symbols_to_json`, made by :func:`make_symbol`, by name (for :func:`parse_expression`).

    Raises
    ------
    ModelError
        Not a mapping of names to ``positive``, ``negative`` or ``real``; the message names ``what``.
    """
    if not isinstance(data, Mapping) or any(v not in _SIGNS for v in data.values()):
        raise ModelError(f"{what}: 'symbols' must map names to one of {', '.join(_SIGNS)}, got {data!r:.80}")
    return {str(k): make_symbol(str(k), positive=v == "positive", negative=v == "negative") for k, v in data.items()}


def _names(value: Any, key: str) -> tuple[str, ...]:
    if value is None:
        return ()
    if isinstance(value, str) or not isinstance(value, (list, tuple)):
        raise ModelError(f"'{key}' must be a list of names, got {value!r}")
    for name in value:
        if not isinstance(name, str) or not _IDENT.match(name):
            raise ModelError(f"'{key}' holds {name!r}, which is not a valid name (letters, digits, '_')")
        if name in _RESERVED or _clashes_with_sympy(name):
            raise ModelError(f"'{key}' holds the reserved name {name!r} (to sympy, which reads the JSON and "
                             "theory outputs back, it is a function or a constant); rename it")
    if len(set(value)) != len(value):
        dup = sorted({n for n in value if list(value).count(n) > 1})
        raise ModelError(f"'{key}' repeats the name(s) {dup}")
    return tuple(value)


@dataclass(frozen=True)
class Model:
    """A system ``dz/dt = s(y,t)(A z + d(y)) + b(y) u, y = C z`` with one output.

    Build one with :meth:`Model.from_dict`, :meth:`Model.from_toml` or
    :func:`switchobs.builtin_model`; the constructor expects already-validated
    sympy objects.

    Attributes
    ----------
    name : str
    states : tuple of str
        State names, in order (``z1, z2, ...``).
    output : str
        Name of the measured output ``y`` (usable in ``d``, ``b``, ``time_scale``).
    A : sympy.ImmutableMatrix, n x n
        Constant matrix (may hold parameters).
    C : sympy.ImmutableMatrix, 1 x n
        Output row.
    d : sympy.ImmutableMatrix, n x 1
        Drift vector, function of ``y``, the external signals and the parameters.
    b : sympy.ImmutableMatrix, n x m
        Input matrix, function of ``y``, the external signals and the parameters.
    time_scale : sympy.Expr
        ``s(y, t)``, function of ``y``, the external signals and ``t``.
    parameters, external, inputs : tuple of str
    values : mapping str -> sympy.Rational
        Numeric values of (some of) the parameters.
    symbols : mapping str -> sympy.Symbol
        Every name of the model and its symbol (with its sign assumptions).
    description : str
    references : mapping str -> str
        Seed equation numbers, e.g. ``{"model": "seed 000 eq. (7)"}``.
    original : tuple of (str, sympy.Expr)
        The original coordinates ``x = phi^{-1}(z)`` of a model written by ``switchobs transform``
        (key ``[original]``): each name with its expression in the states, ``y``, the parameters and
        the external signals; empty when unknown.  The generated C evaluates it on the estimate.
    ranges : mapping str -> (float, float)
        Declared ranges ``[lo, hi]`` of states, the output, external signals, inputs, parameters and the
        step length ``dt`` (key ``[ranges]``): the generated C step refuses values outside them, and with
        a range for every one of them it is proved free of run-time errors (``switchobs codegen --prove``).
    """

    name: str
    states: tuple[str, ...]
    output: str
    A: sp.ImmutableMatrix
    C: sp.ImmutableMatrix
    d: sp.ImmutableMatrix
    b: sp.ImmutableMatrix
    time_scale: sp.Expr
    parameters: tuple[str, ...]
    external: tuple[str, ...]
    inputs: tuple[str, ...]
    values: Mapping[str, sp.Rational] = field(default_factory=dict)
    symbols: Mapping[str, sp.Symbol] = field(default_factory=dict)
    description: str = ""
    references: Mapping[str, str] = field(default_factory=dict)
    original: tuple[tuple[str, sp.Expr], ...] = ()
    ranges: Mapping[str, tuple[float, float]] = field(default_factory=dict)

    # ------------------------------------------------------------------ build
    @classmethod
    def from_dict(cls, data: Mapping[str, Any], *, source: str = "model") -> "Model":
        """Build a model from the keys of the TOML format (see ``docs/model-format.md``).

        Raises
        ------
        ModelError, ExpressionError, DimensionError
            Naming the key and the offending value.
        """
        known = {"name", "description", "states", "output", "A", "C", "d", "b", "time_scale",
                 "parameters", "external", "inputs", "values", "positive", "negative", "references", "original", "ranges"}
        name = check_keys(data, known, ("name", "states", "A", "C", "time_scale"), source)
        states = _names(data["states"], "states")
        if not states:
            raise ModelError(f"{source}: 'states' is empty; a model needs at least one state")
        check_dimension(len(states), what=f"{source}: the model", error=DimensionError)
        output = data.get("output", "y")
        _names([output], "output")
        parameters = _names(data.get("parameters"), "parameters")
        external = _names(data.get("external"), "external")
        inputs = _names(data.get("inputs"), "inputs")
        positive = set(_names(data.get("positive"), "positive"))
        negative = set(_names(data.get("negative"), "negative"))
        declared = list(states) + [output] + list(parameters) + list(external) + list(inputs)
        clash = sorted({n for n in declared if declared.count(n) > 1})
        if clash:
            raise ModelError(f"{source}: the name(s) {clash} are declared twice (states, output, "
                             "parameters, external and inputs must be distinct)")
        for sign_key, group in (("positive", positive), ("negative", negative)):
            stray = sorted(group - set(parameters) - set(external))
            if stray:
                raise ModelError(f"{source}: '{sign_key}' names {stray}, which are not parameters or external signals")
        if positive & negative:
            raise ModelError(f"{source}: {sorted(positive & negative)} declared both positive and negative")

        symbols = {n: make_symbol(n, positive=n in positive, negative=n in negative)
                   for n in declared}
        symbols["t"] = make_symbol("t")
        n = len(states)
        par = {k: symbols[k] for k in parameters}
        y_par = {**par, output: symbols[output]}
        s_names = {**y_par, **{k: symbols[k] for k in external}, "t": symbols["t"]}

        A = _matrix(matrix_rows(data["A"], name="A"), par, rows=n, cols=n, name="A")
        C_raw = matrix_rows(data["C"], name="C", part="C")
        if isinstance(C_raw, list) and C_raw and all(isinstance(r, list) for r in C_raw):
            if len(C_raw) != 1:
                raise DimensionError(f"'C' must be one row (one measured output); got {len(C_raw)} rows")
            C_raw = C_raw[0]
        if not isinstance(C_raw, list):
            raise DimensionError(f"'C' must be a row (a list of {n} expressions), got {C_raw!r}")
        C = _matrix([C_raw], par, rows=1, cols=n, name="C")
        # d and b may read the external signals as well: they are measured (seed 001 Sec. 3.6 feeds the load)
        signal_par = {**y_par, **{k: symbols[k] for k in external}}
        d = _vector(matrix_rows(data.get("d", [0] * n), name="d"), signal_par, n, "d")
        m = len(inputs)
        b_raw = matrix_rows(data.get("b", [[0] * m for _ in range(n)] if m != 1 else [0] * n), name="b")
        if m == 1 and isinstance(b_raw, list) and all(not isinstance(e, list) for e in b_raw):
            b = _vector(b_raw, signal_par, n, "b")
        else:
            b = _matrix(b_raw, signal_par, rows=n, cols=m, name="b")
        time_scale = _check_time_scale(parse_expression(data["time_scale"], s_names, what="time_scale"), source)

        values = read_values(data.get("values"), parameters, symbols, source)
        refs = data.get("references", {}) or {}
        original = _original(data.get("original"), declared, {**s_names, **{k: symbols[k] for k in states}},
                             n, source)
        return cls(name=name, states=states, output=output, A=A, C=C, d=d, b=b,
                   time_scale=time_scale, parameters=parameters, external=external, inputs=inputs,
                   values=values, symbols=symbols, description=str(data.get("description", "")),
                   references=dict(refs), original=original,
                   ranges=_ranges(data.get("ranges"), [*states, output, *external, *inputs, *parameters, "dt"], source))

    @classmethod
    def from_statespace(cls, sys: Any, *, time_scale: str | Any, name: str = "statespace",
                        states: list[str] | None = None, output: str = "y", external: list[str] | None = None,
                        description: str = "") -> "Model":
        """A model ``dz/dt = s(y, t)(A z) + B u, y = C z`` from a python-control ``StateSpace``.

        ``A`` and ``C`` are taken from ``sys`` (floats at their exact binary
        value); a non-zero ``B`` becomes the input matrix ``b`` with inputs
        named after ``sys.input_labels`` (``u1, u2, ...`` when those are not
        names, as python-control's ``u[0]``).

        Parameters
        ----------
        sys : control.StateSpace or control.TransferFunction
            Continuous-time, one output, ``D = 0``; a transfer function is realised by ``control.tf2ss``.
        time_scale : str or sympy expression
            ``s(y, t)``, the singular time scaling (seed 004 eq. (1)); in ``y``, the ``external``
            signals and ``t``.
        name, description : str
        states : list of str, optional
            State names (default: ``sys.state_labels`` if they are names, else ``z1 .. zn``).
        output : str
        external : list of str, optional
            Measured signals ``s`` may use besides ``y`` (the observers need them rather than ``t``).

        Raises
        ------
        DimensionError
            Several outputs.
        ModelError
            Discrete time, or a non-zero ``D`` (the model measures ``y = C z``).

        Examples
        --------
        >>> import control
        >>> m = Model.from_statespace(control.ss([[0, 1], [-2, -3]], [[0], [1]], [[1, 0]], 0), time_scale="y")
        >>> m.A, m.inputs
        (Matrix([
        [ 0,  1],
        [-2, -3]]), ('u1',))
        """
        A, B, C, D = statespace_matrices(sys, what="the system")
        if np.any(D != 0):
            raise ModelError(f"the StateSpace has D = {D.tolist()}, but a switchobs model measures y = C z; "
                             "give a system with D = 0 (the direct feedthrough is known and can be subtracted)")
        n, m = A.shape[0], B.shape[1] if np.any(B != 0) else 0

        def labels(given: Any, prefix: str, k: int) -> list[str]:
            given = list(given or [])
            ok = len(given) == k and all(_IDENT.match(x) and x not in _RESERVED for x in given)
            return given if ok else [f"{prefix}{i + 1}" for i in range(k)]

        data = {"name": name, "description": description, "A": A, "C": C, "output": output,
                "states": states if states is not None else labels(getattr(sys, "state_labels", None), "z", n),
                "inputs": labels(getattr(sys, "input_labels", None), "u", m), "time_scale": time_scale,
                "external": list(external or [])}
        if m:
            data["b"] = B
        return cls.from_dict(data, source="StateSpace")

    @classmethod
    def from_toml(cls, path: str | Path) -> "Model":
        """Read a model from a TOML file (keys as in :meth:`from_dict`); ``"-"`` reads standard input."""
        # a number written in a file is text: its decimal value
        data = read_toml(path, parse_float=str)
        return cls.from_dict(data, source="<stdin>" if str(path) == "-" else str(path))

    # -------------------------------------------------------------- queries
    @property
    def n(self) -> int:
        """State dimension."""
        return len(self.states)

    def symbol(self, name: str) -> sp.Symbol:
        """The symbol of a declared name (state, output, parameter, signal or ``t``)."""
        try:
            return self.symbols[name]
        except KeyError:
            raise ModelError(f"model {self.name!r} has no name {name!r}; known: {sorted(self.symbols)}") from None

    @property
    def parameter_symbols(self) -> tuple[sp.Symbol, ...]:
        return tuple(self.symbols[p] for p in self.parameters)

    @property
    def signals(self) -> tuple[str, ...]:
        """Measured signals in the order of the generated C API: y, external signals, inputs."""
        return (self.output, *self.external, *self.inputs)

    def with_values(self, values: Mapping[str, Any]) -> "Model":
        """Return the model with parameters replaced by exact numbers.

        The substituted parameters disappear from :attr:`parameters`.  Values
        are converted exactly (``"187.5"`` -> ``375/2``).
        """
        if not values:
            return self
        subs = {}
        for key, val in values.items():
            if key not in self.parameters:
                raise ModelError(f"model {self.name!r} has no parameter {key!r} "
                                 f"(parameters: {list(self.parameters)})")
            number = rational_value(val, what=f"parameter {key!r}")
            _check_sign(key, number, self.symbols[key])
            subs[self.symbols[key]] = number
        remaining = tuple(p for p in self.parameters if p not in values)
        for name in ("A", "C", "d", "b", "time_scale"):
            _check_number_size(getattr(self, name).subs(subs), name)
        _check_time_scale(self.time_scale.subs(subs), f"model {self.name!r} at these values")
        return Model(name=self.name, states=self.states, output=self.output,
                     A=self.A.subs(subs), C=self.C.subs(subs), d=self.d.subs(subs),
                     b=self.b.subs(subs), time_scale=self.time_scale.subs(subs),
                     parameters=remaining, external=self.external, inputs=self.inputs,
                     values={k: v for k, v in self.values.items() if k in remaining},
                     symbols=self.symbols, description=self.description, references=self.references,
                     original=tuple((k, e.subs(subs)) for k, e in self.original),
                     ranges={k: r for k, r in self.ranges.items() if k not in values})

    def numeric(self) -> "Model":
        """The model with all its stored :attr:`values` substituted."""
        return self.with_values(dict(self.values))

    def to_statespace(self, values: Mapping[str, Any] | None = None) -> Any:
        """The model as a python-control ``StateSpace`` ``dz/dt = A z + B u, y = C z``, where that is the model.

        Only a model whose time scaling is 1, whose drift ``d`` is 0 and whose input matrix ``b`` is constant
        is linear time-invariant; the parameters take their :attr:`values`, overridden by ``values``.

        Raises
        ------
        ModelError
            ``s`` is not 1, ``d`` is not 0, or ``b`` depends on ``y`` or a signal (the message names it).
        FreeSymbolError
            A parameter has no value.

        Examples
        --------
        >>> import control
        >>> m = Model.from_statespace(control.ss([[0, 1], [-2, -3]], [[0], [1]], [[1, 0]], 0), time_scale="1")
        >>> m.to_statespace().A.tolist()
        [[0.0, 1.0], [-2.0, -3.0]]
        """
        import control

        merged = {**self.values, **dict(values or {})}
        if sp.simplify(self.time_scale - 1) != 0:
            raise ModelError(f"model {self.name!r} has the time scaling s = {self.time_scale}; only s = 1 is a "
                             "StateSpace (a singular s is what the observers handle: use them, or to_nlsys)")
        if any(e != 0 for e in self.d):
            raise ModelError(f"model {self.name!r} has a drift d(y) = {list(self.d)}; only d = 0 is a StateSpace")
        signals = {self.symbols[k] for k in self.signals}
        if self.b.free_symbols & signals:
            raise ModelError(f"model {self.name!r} has an input matrix b(y) = {self.b.tolist()} depending on "
                             f"{sorted(str(x) for x in self.b.free_symbols & signals)}; only a constant b is a "
                             "StateSpace")
        A = numeric(self.A, merged, what="A")
        C = numeric(self.C, merged, what="C").reshape(1, -1)
        B = numeric(self.b, merged, what="b").reshape(self.n, -1) if self.inputs else np.zeros((self.n, 0))
        return control.ss(A, B, C, np.zeros((1, B.shape[1])), states=list(self.states), outputs=[self.output],
                          inputs=list(self.inputs) or None, name=self.name)

    def to_dict(self) -> dict[str, Any]:
        """The model in the TOML key format, every expression as a string."""
        return {
            "name": self.name,
            "states": list(self.states),
            "output": self.output,
            "A": [[str(e) for e in self.A.row(i)] for i in range(self.n)],
            "C": [str(e) for e in self.C],
            "d": [str(e) for e in self.d],
            "b": [[str(e) for e in self.b.row(i)] for i in range(self.n)],
            "time_scale": str(self.time_scale),
            "parameters": list(self.parameters),
            "external": list(self.external),
            "inputs": list(self.inputs),
            "values": {k: str(v) for k, v in self.values.items()},
            **({"original": {"states": [k for k, _ in self.original], "inverse": [str(e) for _, e in self.original]}}
               if self.original else {}),
            **({"ranges": {k: list(r) for k, r in self.ranges.items()}} if self.ranges else {}),
        }

    def to_json(self) -> dict[str, Any]:
        """Every key of :meth:`from_dict` (:meth:`to_dict` with the sign declarations, description and
        references): ``Model.from_json(m.to_json()) == m``."""
        signed = [*self.parameters, *self.external]
        declared = {*self.states, self.output, *signed, *self.inputs, "t"}
        return {**self.to_dict(),
                "positive": [k for k in signed if self.symbols[k].is_positive],
                "negative": [k for k in signed if self.symbols[k].is_negative],
                "description": self.description, "references": dict(self.references),
                # parameters replaced by numbers (with_values) keep their symbols, for the design's map back
                "substituted": {k: _sign_name(s) for k, s in self.symbols.items() if k not in declared}}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> "Model":
        """The model of :meth:`to_json` (validated as :meth:`from_dict` validates)."""
        if not isinstance(data, Mapping):
            raise ModelError(f"model JSON: expected an object, got {type(data).__name__}")
        data = dict(data)
        substituted = data.pop("substituted", {}) or {}
        model = cls.from_dict(data, source="model JSON")
        if not substituted:
            return model
        symbols = {**model.symbols, **{k: make_symbol(k, positive=v == "positive", negative=v == "negative")
                                        for k, v in dict(substituted).items()}}
        return dataclasses.replace(model, symbols=symbols)

    def __str__(self) -> str:
        return f"Model {self.name!r}: n={self.n}, states={list(self.states)}, s={self.time_scale}"

    def __repr__(self) -> str:
        params = f", parameters={list(self.parameters)}" if self.parameters else ""
        return f"<Model {self.name!r}: n={self.n}, output {self.output!r}, s = {self.time_scale}{params}>"

    def _repr_markdown_(self) -> str:
        """The model in a notebook: its equation and matrices in LaTeX."""
        rows = [f"**Model `{self.name}`** (n = {self.n}){': ' + self.description if self.description else ''}",
                "",
                r"$$\dot z = s(y, t)\,\big(A z + d(y)\big) + b(y)\,u,\qquad y = C z,\qquad "
                f"s = {_latex(self.time_scale)}$$",
                "",
                rf"$$A = {_latex(self.A)},\quad C = {_latex(self.C)}"
                + (rf",\quad d = {_latex(self.d)}" if any(e != 0 for e in self.d) else "")
                + (rf",\quad b = {_latex(self.b)}" if self.inputs else "") + "$$",
                "",
                f"states: {', '.join(f'`{z}`' for z in self.states)}; signals: "
                f"{', '.join(f'`{x}`' for x in self.signals)}"]
        if self.parameters:
            vals = ", ".join(f"${_latex(self.symbols[k])} = {_latex(self.values[k])}$" if k in self.values
                             else f"${_latex(self.symbols[k])}$" for k in self.parameters)
            rows[-1] += f"; parameters: {vals}"
        return "\n".join(rows)


def _ranges(data: Any, names: list[str], source: str) -> dict[str, tuple[float, float]]:
    """The ``[ranges]`` table: name = [lo, hi] (numbers, or strings such as "375/2"), lo < hi, finite."""
    if data is None:
        return {}
    if not isinstance(data, Mapping):
        raise ModelError(f"{source}: 'ranges' must be a table name = [lo, hi], got {data!r:.80}")
    out = {}
    for key, value in data.items():
        if key not in names:
            raise ModelError(f"{source}: 'ranges' names {key!r}, which is not a state, signal, input, parameter "
                             f"or dt (names: {', '.join(names)})")
        if not isinstance(value, (list, tuple)) or len(value) != 2:
            raise ModelError(f"{source}: 'ranges' {key} must be [lo, hi], got {value!r:.80}")
        lo, hi = (float(rational_value(v, what=f"'ranges' {key}")) for v in value)
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise ModelError(f"{source}: 'ranges' {key} = {list(value)} must be finite with lo < hi")
        out[str(key)] = (lo, hi)
    return out


def _original(data: Any, declared: list[str], names: Mapping[str, sp.Symbol], n: int,
              source: str) -> tuple[tuple[str, sp.Expr], ...]:
    """The ``[original]`` table: ``states`` (n new names) and ``inverse`` (n expressions of the model's names)."""
    if data is None:
        return ()
    if not isinstance(data, Mapping) or set(data) != {"states", "inverse"}:
        raise ModelError(f"{source}: 'original' must be a table with exactly the keys 'states' and 'inverse', "
                         f"got {data!r}")
    states = _names(data["states"], "original.states")
    inverse = data["inverse"]
    if not isinstance(inverse, list) or len(states) != n or len(inverse) != n:
        raise DimensionError(f"{source}: 'original' needs {n} states and {n} inverse expressions (phi is a "
                             f"diffeomorphism of the {n} states), got {data['states']!r} and {inverse!r}")
    clash = sorted(set(states) & set(declared))
    if clash:
        raise ModelError(f"{source}: original.states {clash} clash with the model's names; rename them")
    exprs = [parse_expression(e, {k: v for k, v in names.items() if k != "t"}, what=f"original.inverse[{i + 1}]")
             for i, e in enumerate(inverse)]
    return tuple(zip(states, exprs))


def _sign_name(symbol: sp.Symbol) -> str:
    return "positive" if symbol.is_positive else "negative" if symbol.is_negative else "real"


def read_toml(path: str | Path, *, what: str = "model file", parse_float: Any = float) -> dict[str, Any]:
    """The tables of a TOML file (data only: TOML cannot run code; ``"-"`` is standard input), with one-line
    errors naming the file.

    Raises
    ------
    ModelError
        The file cannot be read, is larger than :data:`~switchobs._limits.MAX_INPUT_FILE_BYTES`, is not UTF-8 or
        not valid TOML.
    """
    text, where = read_text(path, what=what, max_bytes=MAX_INPUT_FILE_BYTES, error=ModelError)
    try:
        return tomllib.loads(text, parse_float=parse_float)
    except tomllib.TOMLDecodeError as exc:
        raise ModelError(f"{what} {where!r} is not valid TOML: {exc}") from None


def rational_value(value: Any, *, what: str) -> sp.Rational:
    """Convert a user number (int, float, decimal or fraction string) to an exact rational.

    One rule for every stage: text (a string, a TOML file, the command line)
    is the exact decimal it spells (``"0.1"`` is ``1/10``); a float (Python,
    NumPy or sympy) is its exact binary value (``0.1`` is
    ``3602879701896397/36028797018963968``), the number the computer actually
    holds, as the certificate checker reads it (:func:`exact_number`).
    A value is meant as a double: it must be 0 or a normal double in magnitude
    (``"1e400"`` and ``"1e-400"`` are refused), with at most
    :data:`~switchobs._limits.MAX_NUMBER_DIGITS` digits.
    """
    try:
        number = exact_number(value, what=what)
    except ExpressionError as exc:
        raise ModelError(str(exc)) from None
    if isinstance(number, sp.Rational):
        exact = Fraction(int(number.p), int(number.q))
        if max(digits(exact.numerator), digits(exact.denominator)) > MAX_NUMBER_DIGITS:
            raise ModelError(f"{what}: the value has more than {MAX_NUMBER_DIGITS} digits "
                             f"(limit {MAX_NUMBER_DIGITS})")
    else:  # text (a decimal or a fraction), size-checked before it is expanded
        exact = decimal_fraction(str(value), what=what, error=ModelError)
    check_double(exact, what=what, error=ModelError, text=str(value).strip())
    return sp.Rational(exact.numerator, exact.denominator)


def _check_number_size(expr: sp.Basic, name: str) -> None:
    """Exact numbers stay printable and cheap once values are substituted (``a**64`` at ``a = 1e300``), and
    finite (``1/a`` at ``a = 0``)."""
    if non_finite(expr):
        raise ModelError(f"'{name}' is not finite at these values ({_brief(expr)}: a division by zero?); "
                         "give other values")
    for atom in expr.atoms(sp.Rational):
        if max(digits(int(atom.p)), digits(int(atom.q))) > MAX_NUMBER_DIGITS:
            raise ModelError(f"'{name}' holds an exact number of about {max(digits(int(atom.p)), digits(int(atom.q)))} "
                             f"digits at these values (limit {MAX_NUMBER_DIGITS}); give smaller values or "
                             "rescale the model")


def _brief(expr: sp.Basic) -> str:
    text = str(expr)
    return text if len(text) <= 80 else text[:77] + "..."


#: Sample points of the zero test of a time scale (a fixed seed: the same model gets the same answer).
_ZERO_PROBES = 4


def _check_time_scale(expr: sp.Expr, source: str) -> sp.Expr:
    """``expr`` unless it is identically zero (``(a-2)*y`` at ``a = 2``, ``sin(y)**2 + cos(y)**2 - 1``): then the
    rescaled time never advances and the observer never moves (seed 004 eq. (1) needs ``s`` zero only on a
    thin set).

    A value clearly away from zero at one of a few random points decides at once; only a time scale that
    vanishes at all of them is simplified symbolically.
    """
    if expr == 0:
        raise ModelError(f"{source}: 'time_scale' is identically zero; the observer would never move")
    rng = random.Random(0)
    names = sorted(expr.free_symbols, key=str)
    for _ in range(_ZERO_PROBES):
        point = {x: sp.Rational(rng.randint(1, 999), rng.randint(1, 99))
                 * (1 if x.is_positive else -1 if x.is_negative else rng.choice((-1, 1))) for x in names}
        value = expr.xreplace(point).evalf(30)
        if value.is_number and value.is_finite and abs(value) > sp.Rational(1, 10**20):
            return expr
    if sp.simplify(expr) == 0:
        raise ModelError(f"{source}: 'time_scale' = {_brief(expr)} is identically zero; the observer would "
                         "never move")
    return expr


def check_keys(data: Any, known: set[str], required: Sequence[str], source: str) -> str:
    """The ``name`` of a model or system file's table, after checking it is a table with only ``known``
    keys and every ``required`` one."""
    if not isinstance(data, Mapping):
        raise ModelError(f"{source}: expected a table of keys, got {type(data).__name__}")
    unknown = sorted(set(data) - known)
    if unknown:
        raise ModelError(f"{source}: unknown key(s) {unknown}; known keys are {sorted(known)}")
    for key in required:
        if key not in data:
            raise ModelError(f"{source}: missing required key {key!r}")
    name = data["name"]
    if not isinstance(name, str) or not name.strip():
        raise ModelError(f"{source}: 'name' must be a non-empty string, got {name!r}")
    # The name is quoted in messages, reports and generated files (C comments, casadi function names): one
    # line of printable text, of bounded length.
    if not name.isprintable() or len(name) > MAX_NAME_LENGTH:
        raise ModelError(f"{source}: 'name' must be one line of printable text of at most {MAX_NAME_LENGTH} "
                         f"characters, got {name[:MAX_NAME_LENGTH]!r}{'...' if len(name) > MAX_NAME_LENGTH else ''}")
    return name


def read_values(values_raw: Any, parameters: Sequence[str], symbols: Mapping[str, sp.Symbol],
                source: str) -> dict[str, sp.Rational]:
    """The ``[values]`` table of a model or system file: exact values of declared parameters, signs checked."""
    values_raw = values_raw or {}
    if not isinstance(values_raw, Mapping):
        raise ModelError(f"{source}: 'values' must be a table name = number, got {values_raw!r}")
    values = {}
    for key, val in values_raw.items():
        if key not in parameters:
            raise ModelError(f"{source}: 'values' gives {key!r}, which is not a parameter "
                             f"(parameters: {list(parameters)})")
        values[key] = rational_value(val, what=f"values.{key}")
        _check_sign(key, values[key], symbols[key])
    return values


def _check_sign(name: str, value: sp.Rational, symbol: sp.Symbol) -> None:
    if symbol.is_positive and not value > 0:
        raise ModelError(f"parameter {name!r} is declared positive but was given the value {value}")
    if symbol.is_negative and not value < 0:
        raise ModelError(f"parameter {name!r} is declared negative but was given the value {value}")


def _matrix(data: Any, names: Mapping[str, sp.Symbol], *, rows: int, cols: int, name: str) -> sp.ImmutableMatrix:
    """Validate a list of rows of expression strings: the one shape check of the model layer."""
    if not isinstance(data, list) or not all(isinstance(r, list) for r in data):
        raise DimensionError(f"'{name}' must be a list of {rows} rows, got {data!r}")
    if len(data) != rows:
        raise DimensionError(f"'{name}' has the wrong number of rows; expected {rows} instead of {len(data)}")
    for i, row in enumerate(data):
        if len(row) != cols:
            raise DimensionError(f"'{name}' row {i + 1} has the wrong number of entries; "
                                 f"expected {cols} instead of {len(row)}")
    return sp.ImmutableMatrix([[parse_expression(e, names, what=f"{name}[{i + 1}][{j + 1}]")
                                for j, e in enumerate(row)] for i, row in enumerate(data)])


def _vector(data: Any, names: Mapping[str, sp.Symbol], n: int, name: str) -> sp.ImmutableMatrix:
    if not isinstance(data, list) or any(isinstance(e, list) for e in data):
        raise DimensionError(f"'{name}' must be a flat list of {n} expressions, got {data!r}")
    if len(data) != n:
        raise DimensionError(f"'{name}' has the wrong length; expected {n} instead of {len(data)}")
    return sp.ImmutableMatrix([parse_expression(e, names, what=f"{name}[{i + 1}]") for i, e in enumerate(data)])


def numeric(expr: Any, values: Mapping[Any, Any] | None = None, *, what: str = "expression") -> np.ndarray:
    """The one symbolic-to-numeric gate: substitute ``values`` and convert to float.

    Parameters
    ----------
    expr : sympy expression or matrix
    values : mapping of Symbol or name to number, optional
        Names are matched against the free symbols of ``expr`` by name.
    what : str
        Name used in the error message.

    Returns
    -------
    numpy.ndarray
        A float array of the shape of ``expr`` (0-d for a scalar).

    Raises
    ------
    FreeSymbolError
        If free symbols remain after substitution; the message names them.
    NotRealError
        If the value has a nonzero imaginary part.
    """
    scalar = not isinstance(expr, sp.MatrixBase)
    m = sp.Matrix([[expr]]) if scalar else sp.Matrix(expr)
    by_name = {str(s): s for s in m.free_symbols}
    subs = {}
    for key, val in (values or {}).items():
        sym = key if isinstance(key, sp.Basic) else by_name.get(str(key))
        if sym is not None:
            subs[sym] = val
    if subs:
        m = m.subs(subs)
    free = sorted(map(str, m.free_symbols))
    if free:
        raise FreeSymbolError(f"{what} still depends on {free}; give their values")
    out = np.array(m.evalf(), dtype=complex)
    if np.any(np.abs(out.imag) > 0):
        raise NotRealError(f"{what} is not real at these values: {out}; check the values under square roots "
                           "and logarithms")
    out = out.real.astype(float)
    return out[0, 0] if scalar else out


def _latex(expr: Any) -> str:
    """LaTeX of ``expr`` with long rationals to 6 digits (a float entry ``-2.1`` is a 52-bit fraction)."""
    from .._display import readable

    return sp.latex(readable(expr))
