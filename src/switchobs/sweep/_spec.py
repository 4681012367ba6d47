"""Sweep spec files: a TOML description of the cases, the tables and the figures of a sweep.

Read like model files (:func:`switchobs.model.read_toml`: data only, no code), validated once here
with errors naming the key; ``docs/sweeps.md`` documents every key.  Layout::

    name = "table41"
    kind = "braking"                     # or "certify"
    [base]                               # fields of the case (BrakingCase / CertifyCase)
    [grid]                               # axes: a list, or {start, stop, num} / {start, stop, step}
    [monte_carlo]                        # count, root_seed and [monte_carlo.draw] (per grid point)
    [[table]]                            # rows = [...], column = "...", metric = "..."
    [[heatmap]]                          # x, y, metric
    [tune]                               # pick the Pareto-optimal (beta1, beta2) of the grid

A certification sweep's ``[base]`` may give ``load_n`` (sets ``a = R² Fz / J``) and ``load_range_n =
[low, high]`` (a box on ``a``), and its grid axes are the names of the spectrum (``beta1``, ``beta2``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

from .._atomic import safe_file_name
from .._json import fields_from_json
from .._limits import MAX_SWEEP_CASES
from ..exceptions import SimulationError, SwitchobsError
from ._analysis import check_summary, check_tunable
from ._case import BrakingCase, Case, CertifyCase, case_from_json
from ._grid import (Choice, Distribution, Integers, RoadChanges, Uniform, a_of_load, arange, arange_count,
                    certify_grid, check_case_count, grid, linspace, monte_carlo)

__all__ = ["SweepSpec", "load_sweep_spec", "sweep_spec_from_dict"]

_TOP = {"name", "description", "kind", "base", "grid", "monte_carlo", "table", "heatmap", "tune"}


@dataclass(frozen=True)
class TableSpec:
    rows: tuple[str, ...]
    column: str
    metric: str


@dataclass(frozen=True)
class HeatmapSpec:
    x: str
    y: str
    metric: str

    @property
    def filename(self) -> str:
        """``heatmap-<metric>-<y>-<x>.png``, reduced to a plain file name (names from a file are not paths)."""
        return safe_file_name(f"heatmap-{self.metric}-{self.y}-{self.x}", suffix=".png", fallback="heatmap")


@dataclass(frozen=True)
class SweepSpec:
    """A sweep read from a spec file: its cases and what to show of them."""

    name: str
    description: str
    kind: str
    cases: tuple[Case, ...]
    tables: tuple[TableSpec, ...]
    heatmaps: tuple[HeatmapSpec, ...]
    tune: bool

    @property
    def results_file(self) -> str:
        """The default results file: ``<name>.jsonl`` in the current directory, the name reduced to a plain
        file name (:func:`switchobs._atomic.safe_file_name`: ``name = "../../x"`` gives ``x.jsonl``)."""
        return safe_file_name(self.name, suffix=".jsonl", fallback="sweep")

    def to_json(self, *, include_cases: bool = False) -> dict[str, Any]:
        """The spec with its number of cases (and every case's :meth:`~BrakingCase.to_json` if ``include_cases``)."""
        out: dict[str, Any] = {"name": self.name, "description": self.description, "kind": self.kind,
                               "cases": len(self.cases), "tables": [vars(t) for t in self.tables],
                               "heatmaps": [vars(h) for h in self.heatmaps], "tune": self.tune}
        if include_cases:
            out["case_specs"] = [c.to_json() for c in self.cases]
        return out

    @classmethod
    def from_json(cls, data: Any) -> SweepSpec:
        """The spec of ``to_json(include_cases=True)``.

        Raises
        ------
        SimulationError
            No ``case_specs``, or a malformed case or key.
        """
        if not isinstance(data, dict) or not isinstance(data.get("case_specs"), list):
            raise SimulationError("a sweep spec JSON needs its 'case_specs'; write it with to_json(include_cases=True)")
        return fields_from_json(cls, data, error=SimulationError, what="sweep spec",
                                cases=tuple(case_from_json(c) for c in data["case_specs"]))

    def __str__(self) -> str:
        return f"sweep {self.name!r}: {len(self.cases)} {self.kind} cases" + (
            f" ({self.description})" if self.description else "")


def load_sweep_spec(path: str | Path, *, max_cases: int = MAX_SWEEP_CASES) -> SweepSpec:
    """Read and validate a sweep spec file: its cases (at most ``max_cases``, counted before any is built), its
    tables, heatmaps and tuning (checked against the cases before any case runs).

    Raises
    ------
    ModelError
        The file cannot be read or is not TOML.
    SimulationError
        A key or value is not admissible, or there are more than ``max_cases`` cases (named in the message).
    """
    from ..model import read_toml

    return sweep_spec_from_dict(read_toml(path, what="sweep spec file"), source=str(path), max_cases=max_cases)


def _table(data: Any, source: str, key: str) -> Mapping[str, Any]:
    if not isinstance(data, Mapping):
        raise SimulationError(f"{source}: [{key}] must be a table, got {data!r}")
    return data


def _keys(data: Mapping[str, Any], allowed: set[str], where: str) -> None:
    unknown = sorted(set(data) - allowed)
    if unknown:
        raise SimulationError(f"{where}: unknown key(s) {unknown}; known keys are {sorted(allowed)}")


def _axis(name: str, value: Any, where: str, max_cases: int) -> tuple[float, Callable[[], list[Any]]]:
    """The number of values of an axis and how to build them (counted first: a range may be astronomical)."""
    if isinstance(value, list) and value:
        return len(value), lambda: value
    if isinstance(value, Mapping):
        _keys(value, {"start", "stop", "num", "step"}, f"{where}.{name}")
        if "start" in value and "stop" in value and ("num" in value) != ("step" in value):
            start, stop = value["start"], value["stop"]
            try:
                if "num" in value:
                    num = value["num"]
                    linspace(start, stop, 1)  # checks start and stop
                    if isinstance(num, bool) or not (isinstance(num, int) and num >= 1):
                        raise SimulationError(f"num must be an integer >= 1, got {num!r}")
                    return num, lambda: linspace(start, stop, num, max_values=max_cases)
                step = value["step"]
                return arange_count(start, stop, step), lambda: arange(start, stop, step, max_values=max_cases)
            except SimulationError as exc:
                raise SimulationError(f"{where}.{name}: {exc}") from None
    raise SimulationError(f"{where}.{name}: an axis is a non-empty list or {{start, stop, num}} / "
                          f"{{start, stop, step}}, got {value!r}")


def _pairs(value: Any, where: str) -> tuple[Any, ...]:
    """TOML arrays (lists) as the tuples the case specs hold."""
    if isinstance(value, list):
        return tuple(_pairs(v, where) for v in value)
    return value


def _distribution(name: str, value: Any, where: str) -> Distribution:
    if not (isinstance(value, Mapping) and len(value) >= 1):
        raise SimulationError(f"{where}.{name}: a draw is {{uniform = [low, high]}}, {{choice = [...]}}, "
                              f"{{integers = [low, high]}} or {{roads = [...], count = [min, max], "
                              f"window_s = [t0, t1]}}, got {value!r}")
    try:
        if set(value) == {"uniform"}:
            low, high = value["uniform"]
            return Uniform(low, high)
        if set(value) == {"choice"} and isinstance(value["choice"], list):
            return Choice(tuple(_pairs(value["choice"], where)))
        if set(value) == {"integers"}:
            low, high = value["integers"]
            return Integers(low, high)
        if set(value) == {"roads", "count", "window_s"} and isinstance(value["roads"], list):
            cmin, cmax = value["count"]
            t0, t1 = value["window_s"]
            return RoadChanges(tuple(value["roads"]), cmin, cmax, (t0, t1))
    except SwitchobsError as exc:  # the draw's own check: it names the value
        raise SimulationError(f"{where}.{name}: {exc}") from None
    except (TypeError, ValueError):  # not a pair
        pass
    raise SimulationError(f"{where}.{name}: not an admissible draw: {value!r}")


def _views(data: Mapping[str, Any], key: str, source: str) -> list[Mapping[str, Any]]:
    """The ``[[table]]`` or ``[[heatmap]]`` entries: a list of tables."""
    items = data.get(key, [])
    if not isinstance(items, list):
        raise SimulationError(f"{source}: {key} must be a list of tables ([[{key}]]), got {items!r:.80}")
    return [_table(t, source, f"{key} {i + 1}") for i, t in enumerate(items)]


def sweep_spec_from_dict(data: Mapping[str, Any], *, source: str = "sweep spec",
                         max_cases: int = MAX_SWEEP_CASES) -> SweepSpec:
    """The :class:`SweepSpec` of the parsed TOML tables ``data`` (see the module notes).

    The whole spec is checked before any case runs: the number of cases (grid points times draws, counted
    before any is built, at most ``max_cases``), every case, and the fields and metrics of the tables,
    heatmaps and tuning against the cases.
    """
    _keys(data, _TOP, source)
    kind = data.get("kind", "braking")
    if kind not in ("braking", "certify"):
        raise SimulationError(f"{source}: kind must be 'braking' or 'certify', got {kind!r}")
    for key in ("name", "description"):
        if key in data and not isinstance(data[key], str):
            raise SimulationError(f"{source}: {key} must be a text, got {data[key]!r:.80}")
    base_data = dict(_table(data.get("base", {}), source, "base"))
    sized = {k: _axis(k, v, f"{source}: grid", max_cases)
             for k, v in _table(data.get("grid", {}), source, "grid").items()}
    mc = data.get("monte_carlo")
    count = 1
    if mc is not None:
        mc = _table(mc, source, "monte_carlo")
        _keys(mc, {"count", "root_seed", "draw"}, f"{source}: [monte_carlo]")
        count = mc.get("count")
        if isinstance(count, bool) or not (isinstance(count, int) and count >= 1):
            raise SimulationError(f"{source}: monte_carlo.count must be an integer >= 1, got {count!r}")
    shape = [f"grid {' x '.join(f'{n:.6g}' for n, _ in sized.values())}"] if sized else []
    if mc is not None:
        shape.append(f"{count} Monte-Carlo draws" + (" per grid point" if sized else ""))
    check_case_count(math.prod([n for n, _ in sized.values()]) * count,
                     f"{source}: cases of the sweep ({', '.join(shape) or 'one case'})", max_cases=max_cases)
    axes = {k: build() for k, (_, build) in sized.items()}
    if kind == "certify":
        for name in axes:
            if not name.isidentifier():
                raise SimulationError(f"{source}: [grid] of a certification sweep names the spectrum's "
                                      f"parameters (such as beta1); {name!r} is not a name")
        cases = _certify_cases(base_data, axes, source, max_cases)
    else:
        names = {f.name for f in fields(BrakingCase)}
        _keys(base_data, names, f"{source}: [base]")
        _keys(axes, names, f"{source}: [grid]")
        base = BrakingCase(**{k: _pairs(v, source) for k, v in base_data.items()})
        cases = grid(base, max_cases=max_cases, **{k: [_pairs(v, source) for v in vals] for k, vals in axes.items()}) \
            if axes else (base,)
    if mc is not None:
        draws = {k: _distribution(k, v, f"{source}: monte_carlo.draw")
                 for k, v in _table(mc.get("draw", {}), source, "monte_carlo.draw").items()}
        seed = mc.get("root_seed", 0)
        cases = tuple(c for base_case in cases
                      for c in monte_carlo(base_case, count, draws=draws, root_seed=seed, max_cases=max_cases))
    tables = []
    for i, t in enumerate(_views(data, "table", source)):
        where = f"{source}: [[table]] {i + 1}"
        _keys(t, {"rows", "column", "metric"}, where)
        rows = t.get("rows")
        if not (isinstance(rows, list) and rows and all(isinstance(r, str) for r in rows)) \
                or not isinstance(t.get("column"), str) or not isinstance(t.get("metric"), str):
            raise SimulationError(f"{where} needs rows = [fields], column = field, metric = name")
        check_summary(cases, rows=rows, column=t["column"], metric=t["metric"], where=where)
        tables.append(TableSpec(tuple(rows), t["column"], t["metric"]))
    heatmaps = []
    for i, h in enumerate(_views(data, "heatmap", source)):
        where = f"{source}: [[heatmap]] {i + 1}"
        _keys(h, {"x", "y", "metric"}, where)
        if not all(isinstance(h.get(k), str) for k in ("x", "y", "metric")):
            raise SimulationError(f"{where} needs x, y and metric (names)")
        check_summary(cases, rows=[h["y"]], column=h["x"], metric=h["metric"], where=where)
        heatmaps.append(HeatmapSpec(h["x"], h["y"], h["metric"]))
    tune = data.get("tune", {})
    if not isinstance(tune, Mapping) or set(tune) - {"enabled"} or not isinstance(tune.get("enabled", True), bool):
        raise SimulationError(f"{source}: [tune] takes only enabled = true/false")
    tune_on = bool(tune.get("enabled", "tune" in data))
    if tune_on and kind != "braking":
        raise SimulationError(f"{source}: [tune] picks observer gains from braking runs; kind is {kind!r}")
    if tune_on:
        check_tunable(cases)  # before the cases run, not after
    name = data.get("name", Path(source).stem)
    return SweepSpec(name=name, description=data.get("description", ""), kind=kind, cases=tuple(cases),
                     tables=tuple(tables), heatmaps=tuple(heatmaps), tune=tune_on)


def _certify_cases(base_data: dict[str, Any], axes: dict[str, list[Any]], source: str,
                   max_cases: int) -> tuple[CertifyCase, ...]:
    load = base_data.pop("load_n", None)
    load_range = base_data.pop("load_range_n", None)
    names = {f.name for f in fields(CertifyCase)}
    _keys(base_data, names, f"{source}: [base]")
    base_data = {k: _pairs(v, source) for k, v in base_data.items()}
    values = dict(base_data.get("values", ()))
    box = list(base_data.get("box", ()))
    try:
        if load is not None:
            values["a"] = a_of_load(float(load))
        if load_range is not None:
            low, high = (a_of_load(float(v)) for v in load_range)
            box.append(("a", low, high))
    except (TypeError, ValueError) as exc:
        raise SimulationError(f"{source}: load_n must be a number and load_range_n [low, high] in N ({exc})") \
            from None
    base_data["values"], base_data["box"] = tuple(values.items()), tuple(box)
    base = CertifyCase(**base_data)
    cases = certify_grid(base, max_cases=max_cases, **axes) if axes else (base,)
    _check_spectra(cases, source)
    return cases


def _check_spectra(cases: tuple[CertifyCase, ...], source: str) -> None:
    """Each distinct spectrum parsed in the names of its case's ``betas`` (as the case will), before any runs."""
    import sympy

    from ..model import make_symbol, parse_expression

    for spectrum, names in {(c.spectrum, tuple(k for k, _ in c.betas)) for c in cases}:
        try:
            symbols = {k: make_symbol(k) for k in names}
            poles = [parse_expression(p.strip(), symbols, what=f"spectrum pole {p.strip()!r}")
                     for p in spectrum.split(",")]
        except SwitchobsError as exc:
            raise SimulationError(f"{source}: [base] spectrum {spectrum!r}: {exc}") from None
        bad = [p for p in poles if p.has(sympy.zoo, sympy.nan, sympy.oo, -sympy.oo)]
        if bad:
            raise SimulationError(f"{source}: [base] spectrum {spectrum!r}: the pole {bad[0]} is not finite")
