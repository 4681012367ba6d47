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

from collections.abc import Mapping
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

from .._json import fields_from_json
from ..exceptions import SimulationError
from ._case import BrakingCase, Case, CertifyCase, case_from_json
from ._grid import (Choice, Distribution, Integers, RoadChanges, Uniform, a_of_load, arange, certify_grid, grid,
                    linspace, monte_carlo)

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
        return f"heatmap-{self.metric}-{self.y}-{self.x}.png"


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


def load_sweep_spec(path: str | Path) -> SweepSpec:
    """Read and validate a sweep spec file.

    Raises
    ------
    ModelError
        The file cannot be read or is not TOML.
    SimulationError
        A key or value is not admissible (named in the message).
    """
    from ..model import read_toml

    return sweep_spec_from_dict(read_toml(path, what="sweep spec file"), source=str(path))


def _table(data: Any, source: str, key: str) -> Mapping[str, Any]:
    if not isinstance(data, Mapping):
        raise SimulationError(f"{source}: [{key}] must be a table, got {data!r}")
    return data


def _keys(data: Mapping[str, Any], allowed: set[str], where: str) -> None:
    unknown = sorted(set(data) - allowed)
    if unknown:
        raise SimulationError(f"{where}: unknown key(s) {unknown}; known keys are {sorted(allowed)}")


def _axis(name: str, value: Any, where: str) -> list[Any]:
    if isinstance(value, list) and value:
        return value
    if isinstance(value, Mapping):
        _keys(value, {"start", "stop", "num", "step"}, f"{where}.{name}")
        if "start" in value and "stop" in value and ("num" in value) != ("step" in value):
            if "num" in value:
                return linspace(value["start"], value["stop"], value["num"])
            return arange(value["start"], value["stop"], value["step"])
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
            return Uniform(float(low), float(high))
        if set(value) == {"choice"} and isinstance(value["choice"], list) and value["choice"]:
            return Choice(tuple(_pairs(value["choice"], where)))
        if set(value) == {"integers"}:
            low, high = value["integers"]
            if isinstance(low, int) and isinstance(high, int) and low <= high:
                return Integers(low, high)
        if set(value) == {"roads", "count", "window_s"}:
            cmin, cmax = value["count"]
            t0, t1 = value["window_s"]
            if isinstance(cmin, int) and isinstance(cmax, int) and 0 <= cmin <= cmax and value["roads"]:
                return RoadChanges(tuple(value["roads"]), cmin, cmax, (float(t0), float(t1)))
    except (TypeError, ValueError):
        pass
    raise SimulationError(f"{where}.{name}: not an admissible draw: {value!r}")


def sweep_spec_from_dict(data: Mapping[str, Any], *, source: str = "sweep spec") -> SweepSpec:
    """The :class:`SweepSpec` of the parsed TOML tables ``data`` (see the module notes)."""
    _keys(data, _TOP, source)
    kind = data.get("kind", "braking")
    if kind not in ("braking", "certify"):
        raise SimulationError(f"{source}: kind must be 'braking' or 'certify', got {kind!r}")
    base_data = dict(_table(data.get("base", {}), source, "base"))
    axes = {k: _axis(k, v, f"{source}: grid") for k, v in _table(data.get("grid", {}), source, "grid").items()}
    if kind == "certify":
        cases = _certify_cases(base_data, axes, source)
    else:
        names = {f.name for f in fields(BrakingCase)}
        _keys(base_data, names, f"{source}: [base]")
        _keys(axes, names, f"{source}: [grid]")
        base = BrakingCase(**{k: _pairs(v, source) for k, v in base_data.items()})
        cases = grid(base, **{k: [_pairs(v, source) for v in vals] for k, vals in axes.items()}) if axes else (base,)
    mc = data.get("monte_carlo")
    if mc is not None:
        mc = _table(mc, source, "monte_carlo")
        _keys(mc, {"count", "root_seed", "draw"}, f"{source}: [monte_carlo]")
        draws = {k: _distribution(k, v, f"{source}: monte_carlo.draw")
                 for k, v in _table(mc.get("draw", {}), source, "monte_carlo.draw").items()}
        count, seed = mc.get("count"), mc.get("root_seed", 0)
        cases = tuple(c for base_case in cases
                      for c in monte_carlo(base_case, count, draws=draws, root_seed=seed))
    tables = []
    for i, t in enumerate(data.get("table", [])):
        t = _table(t, source, f"table {i + 1}")
        _keys(t, {"rows", "column", "metric"}, f"{source}: [[table]] {i + 1}")
        rows = t.get("rows")
        if not (isinstance(rows, list) and rows and all(isinstance(r, str) for r in rows)) \
                or not isinstance(t.get("column"), str) or not isinstance(t.get("metric"), str):
            raise SimulationError(f"{source}: [[table]] {i + 1} needs rows = [fields], column = field, "
                                  f"metric = name")
        tables.append(TableSpec(tuple(rows), t["column"], t["metric"]))
    heatmaps = []
    for i, h in enumerate(data.get("heatmap", [])):
        h = _table(h, source, f"heatmap {i + 1}")
        _keys(h, {"x", "y", "metric"}, f"{source}: [[heatmap]] {i + 1}")
        if not all(isinstance(h.get(k), str) for k in ("x", "y", "metric")):
            raise SimulationError(f"{source}: [[heatmap]] {i + 1} needs x, y and metric (names)")
        heatmaps.append(HeatmapSpec(h["x"], h["y"], h["metric"]))
    tune = data.get("tune", {})
    if not isinstance(tune, Mapping) or set(tune) - {"enabled"}:
        raise SimulationError(f"{source}: [tune] takes only enabled = true/false")
    tune_on = bool(tune.get("enabled", "tune" in data))
    if tune_on and kind != "braking":
        raise SimulationError(f"{source}: [tune] picks observer gains from braking runs; kind is {kind!r}")
    name = data.get("name", Path(source).stem)
    return SweepSpec(name=str(name), description=str(data.get("description", "")), kind=kind, cases=tuple(cases),
                     tables=tuple(tables), heatmaps=tuple(heatmaps), tune=tune_on)


def _certify_cases(base_data: dict[str, Any], axes: dict[str, list[Any]], source: str) -> tuple[Case, ...]:
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
    return certify_grid(base, **axes) if axes else (base,)
