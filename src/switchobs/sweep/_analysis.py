"""What a person reads from a sweep: pivot tables of a metric, the Pareto front of the gains, the tuned pair.

Gain tuning (:func:`tune_betas`) scores each observer gain pair over the cases run with it (the same
draws of roads, speeds and encoder seeds for every pair: a common random numbers design) by two
costs: the worst re-convergence time after a road change, ``recovery_max_s`` (slow gains; the running
RMS of the error back at its noise floor, the re-convergence time a noisy measurement leaves
measurable), and the settled XBS error RMS, ``xbs_rms_settled`` (noisy gains; the
:data:`switchobs.loop.SETTLE_S` after each change left out).  A pair that never re-converges in some
case costs ``inf``.  The chosen pair is
the point of the Pareto front nearest the utopia point (both costs at their best over the front) once
each cost is scaled to ``[0, 1]`` over the front.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, fields
from typing import Any

from .._json import JsonRecord, fields_from_json
from ..exceptions import SimulationError
from ._case import BrakingCase
from ._run import NUMERIC_METRICS, CaseResult

__all__ = ["SummaryTable", "summary_table", "pareto_front", "TunedDesign", "tune_betas", "check_tunable",
           "design_command", "check_summary"]


def _field(result: CaseResult, name: str) -> Any:
    """A case field, a spectrum name of a certification case (``beta1``), or ``status``."""
    if hasattr(result.case, name):
        return getattr(result.case, name)
    betas = dict(getattr(result.case, "betas", ()))
    if name in betas:
        return betas[name]
    if name == "status":
        return result.status
    raise SimulationError(f"{result.case.kind} cases have no field {name!r}")


def check_summary(cases: Sequence[Any], *, rows: Sequence[str], column: str, metric: str,
                  where: str = "a table") -> None:
    """Refuse, before any case runs, a table or heatmap of ``cases`` that could only print dashes.

    ``rows`` and ``column`` must be case fields (a spectrum name of a certification case such as ``beta1``,
    or ``status``), and ``metric`` a number of the cases' rows
    (:data:`switchobs.sweep._run.NUMERIC_METRICS`) that exists for some case.

    Raises
    ------
    SimulationError
        Naming ``where``, the offending name and the names there are.
    """
    if not cases:
        return
    kinds = sorted({c.kind for c in cases})
    names = {"status"} | {f.name for c in {type(c): c for c in cases}.values() for f in fields(c)}
    names |= {k for c in cases for k, _ in getattr(c, "betas", ())}
    for name in [*rows, column]:
        if name not in names:
            raise SimulationError(f"{where}: {'/'.join(kinds)} cases have no field {name!r}; fields: "
                                  f"{', '.join(sorted(names))}")
    numbers = {k: v for kind in kinds for k, v in NUMERIC_METRICS[kind].items()}
    if metric not in numbers:
        raise SimulationError(f"{where}: {metric!r} is not a number of {'/'.join(kinds)} rows, which a table "
                              f"averages; choose one of {', '.join(numbers)}")
    need = numbers[metric]
    if need is not None and not any(getattr(c, need, None) not in (None, "none", ()) for c in cases):
        raise SimulationError(f"{where}: metric {metric!r} exists only for cases that set {need}, and every case "
                              f"has {need} = {getattr(cases[0], need, None)!r}")


def _mean(values: Sequence[Any]) -> float | None:
    """The mean of the numbers (a verdict true/false counts 1/0: the mean is the share that holds)."""
    numbers = [float(v) for v in values if isinstance(v, (int, float))]
    return sum(numbers) / len(numbers) if numbers else None


@dataclass(frozen=True)
class SummaryTable(JsonRecord, error=SimulationError):
    """The mean of ``metric`` over the cases of each (row, column) cell (None: no number in the cell).

    A true/false metric (``certified``) counts 1/0: its mean is the share of the cell's cases where it holds.
    """

    metric: str
    rows: tuple[str, ...]
    column: str
    row_keys: tuple[tuple[Any, ...], ...]
    column_keys: tuple[Any, ...]
    cells: tuple[tuple[float | None, ...], ...]
    counts: tuple[tuple[int, ...], ...]

    def to_json(self) -> dict[str, Any]:
        return {"metric": self.metric, "rows": list(self.rows), "column": self.column,
                "row_keys": [list(k) for k in self.row_keys], "column_keys": list(self.column_keys),
                "cells": [list(r) for r in self.cells], "counts": [list(c) for c in self.counts]}

    def __str__(self) -> str:
        def fmt(v: Any) -> str:
            return "-" if v is None else (f"{v:.4g}" if isinstance(v, float) else str(v))
        head = [*self.rows, *(f"{self.column}={fmt(c)}" for c in self.column_keys)]
        body = [[*(fmt(k) for k in key), *(fmt(v) for v in row)] for key, row in zip(self.row_keys, self.cells)]
        widths = [max(len(r[i]) for r in [head, *body]) for i in range(len(head))]
        lines = [f"mean {self.metric}"] + ["  ".join(c.rjust(w) for c, w in zip(r, widths)) for r in [head, *body]]
        return "\n".join(lines)


def summary_table(results: Sequence[CaseResult], *, rows: Sequence[str], column: str, metric: str) -> SummaryTable:
    """Pivot ``metric`` by the case fields ``rows`` (one table row per combination) and ``column``.

    Cases that failed are left out; keys keep the order they first appear in.

    Raises
    ------
    SimulationError
        A field or metric the cases do not have (:func:`check_summary`).
    """
    check_summary([r.case for r in results], rows=rows, column=column, metric=metric)
    cells: dict[tuple[Any, ...], dict[Any, list[Any]]] = {}
    columns: dict[Any, None] = {}
    for r in results:
        if not r.ok:
            continue
        key = tuple(_field(r, name) for name in rows)
        col = _field(r, column)
        columns.setdefault(col, None)
        cells.setdefault(key, {}).setdefault(col, []).append(r.metrics.get(metric))
    cols = tuple(columns)
    return SummaryTable(metric=metric, rows=tuple(rows), column=column, row_keys=tuple(cells), column_keys=cols,
                        cells=tuple(tuple(_mean(c.get(k, [])) for k in cols) for c in cells.values()),
                        counts=tuple(tuple(len(c.get(k, [])) for k in cols) for c in cells.values()))


def pareto_front(points: Sequence[tuple[float, float]]) -> list[int]:
    """Indices of the points no other point dominates (both coordinates minimised), by the first coordinate.

    Examples
    --------
    >>> pareto_front([(1, 5), (2, 2), (3, 3), (4, 1), (2, 6)])
    [0, 1, 3]
    """
    front = []
    for i, (x, y) in enumerate(points):
        dominated = any((a <= x and b <= y) and (a < x or b < y) for j, (a, b) in enumerate(points) if j != i)
        if not dominated and math.isfinite(x) and math.isfinite(y):
            front.append(i)
    return sorted(front, key=lambda i: (points[i][0], points[i][1]))


@dataclass(frozen=True)
class TunedDesign:
    """The Pareto-optimal gain pair picked from a sweep, and the command that designs it.

    Attributes
    ----------
    observer : str
    beta1, beta2 : float
    reconvergence_s, noise_rms : float
        Its costs (see the module notes).
    pairs : tuple of (beta1, beta2, reconvergence_s, noise_rms, cases)
        Every pair scored.
    front : tuple of int
        Indices into ``pairs`` of the Pareto front, by re-convergence time.
    command : str
        The ``switchobs design`` command whose spectrum and parameters give the chosen gains.
    """

    observer: str
    beta1: float
    beta2: float
    reconvergence_s: float
    noise_rms: float
    pairs: tuple[tuple[float, float, float, float, int], ...]
    front: tuple[int, ...]
    command: str

    def to_json(self) -> dict[str, Any]:
        def num(v: float) -> float | None:
            return v if math.isfinite(v) else None
        return {"observer": self.observer, "beta1": self.beta1, "beta2": self.beta2,
                "reconvergence_s": self.reconvergence_s, "noise_rms": self.noise_rms,
                "pairs": [{"beta1": b1, "beta2": b2, "reconvergence_s": num(r), "noise_rms": num(n), "cases": c}
                          for b1, b2, r, n, c in self.pairs],
                "front": list(self.front), "command": self.command}

    @classmethod
    def from_json(cls, data: Any) -> TunedDesign:
        """The design of :meth:`to_json` (a ``null`` cost of a pair, never re-converged, is ``inf`` again).

        Raises
        ------
        SimulationError
            A missing key or a malformed pair.
        """
        try:
            costs = ("reconvergence_s", "noise_rms")
            pairs = [[p["beta1"], p["beta2"], *(math.inf if p[k] is None else p[k] for k in costs), p["cases"]]
                     for p in data["pairs"]]
        except (KeyError, TypeError) as exc:
            raise SimulationError(f"a tuned design JSON needs 'pairs' with beta1, beta2, reconvergence_s, noise_rms "
                                  f"and cases ({exc!r})") from None
        return fields_from_json(cls, {**data, "pairs": pairs}, error=SimulationError, what="tuned design")

    def __str__(self) -> str:
        lines = [f"Pareto front of {self.observer} gains (worst re-convergence after a road change vs settled "
                 f"XBS error RMS, over {self.pairs[0][4]} cases per pair):"]
        for i in self.front:
            b1, b2, r, n, _ = self.pairs[i]
            mark = "  <- chosen" if (b1, b2) == (self.beta1, self.beta2) else ""
            lines.append(f"  beta1 {b1:8.4g}  beta2 {b2:8.4g}  re-convergence {r:7.3f} s  noise RMS {n:.4g}{mark}")
        lines.append(f"chosen: beta1 = {self.beta1:g}, beta2 = {self.beta2:g}; design it with:")
        lines.append(f"  {self.command}")
        return "\n".join(lines)


def design_command(case: BrakingCase, beta1: float, beta2: float) -> str:
    """The ``switchobs design`` command of the observer of ``case`` with the rates ``beta1``, ``beta2``.

    The observer is the one the loop builds for the case's vehicle and road
    (:func:`switchobs.loop.xbs_estimator`): its model, the spectrum of its ``A_plus = A - K_plus C`` and
    the parameters where they differ from the built-in model's values.
    """
    import numpy as np

    from ..loop import EstimatorSpec, xbs_estimator
    from ..plants import QuarterCar

    if case.observer == "none":
        raise SimulationError("no gains to tune without an observer; use xbs3, xbs4 or adaptive")
    spec = EstimatorSpec(case.observer, beta=beta1, beta2=None if case.observer == "adaptive" else beta2,
                         method=case.method)
    obs = xbs_estimator(spec, QuarterCar(load_n=case.load_n), case.road).observer  # type: ignore[union-attr]
    # the spectrum is a multiset of -beta1 and -beta2 (seed 000 Secs. III-E, IV-D; seed 001 (3.20)); the float
    # eigenvalues of its multiple poles are only good to a few digits, so each names the nearest rate
    rates = (beta1, beta2)
    poles = sorted((-min(rates, key=lambda b: abs(ev.real + b))
                    for ev in np.linalg.eigvals(obs.A - np.outer(obs.K_plus, obs.C))), reverse=True)
    stored = {k: float(v) for k, v in obs.model.values.items()}
    params = [f" --param {k}={v:.12g}" for k, v in sorted(obs.values.items())
              if k not in stored or abs(stored[k] - v) > 1e-12 * max(1.0, abs(v))]
    spectrum = ",".join(f"{p:.6g}" for p in poles)
    return f"switchobs design {obs.model.name} --spectrum={spectrum}{''.join(params)}"


def check_tunable(cases: Sequence[Any]) -> list[str]:
    """Refuse cases :func:`tune_betas` cannot tune, before they run: several observer kinds, or a case
    without ``beta1``; returns the one observer kind.

    Raises
    ------
    SimulationError
        Naming the offending kinds or case.
    """
    braking = [c for c in cases if isinstance(c, BrakingCase) and c.observer != "none"]
    kinds = sorted({c.observer for c in braking})
    if len(kinds) != 1:
        raise SimulationError(f"tuning needs braking results of one observer kind, got {kinds or 'none'}")
    for case in braking:
        if case.beta1 is None:
            raise SimulationError(f"tuning needs beta1 (and beta2) in every case (a [grid] of them); {case} has "
                                  "none")
    return kinds


def tune_betas(results: Sequence[CaseResult], *,
               reconvergence: Callable[[CaseResult], float | None] | None = None,
               noise: Callable[[CaseResult], float | None] | None = None) -> TunedDesign:
    """Pick the Pareto-optimal ``(beta1, beta2)`` from braking results run on a grid of observer gains.

    Parameters
    ----------
    results : sequence of CaseResult
        Braking cases of one observer kind with ``beta1`` (and ``beta2``) set; failed cases count as never
        re-converging.
    reconvergence, noise : callable, optional
        The two costs of a case (defaults: ``recovery_max_s``, ``xbs_rms_settled``; None or a failure
        is ``inf``); a cost of None leaves the case out of that mean (the default re-convergence of a case
        without a road change early enough to score, an empty ``recovery_s``).  A pair's cost is the mean
        over its cases.

    Raises
    ------
    SimulationError
        No braking results with an observer and gains, several observer kinds, or no pair with finite costs.
    """
    def metric(key: str) -> Callable[[CaseResult], float | None]:
        def get(r: CaseResult) -> float | None:
            if key == "recovery_max_s" and r.ok and r.metrics.get("recovery_s") == []:
                return None  # no road change scored in this run: nothing to say about re-convergence
            v = r.metrics.get(key) if r.ok else None
            return math.inf if v is None else float(v)
        return get

    def mean(cost: Callable[[CaseResult], float | None], rs: list[CaseResult]) -> float:
        scored = [v for v in map(cost, rs) if v is not None]
        return sum(scored) / len(scored) if scored else math.inf
    reconvergence = reconvergence or metric("recovery_max_s")
    noise = noise or metric("xbs_rms_settled")
    braking = [r for r in results if isinstance(r.case, BrakingCase) and r.case.observer != "none"]
    kinds = check_tunable([r.case for r in braking])
    groups: dict[tuple[float, float], list[CaseResult]] = {}
    for r in braking:
        case = r.case
        assert isinstance(case, BrakingCase) and case.beta1 is not None
        groups.setdefault((case.beta1, case.beta2 if case.beta2 is not None else case.beta1), []).append(r)
    pairs = tuple((b1, b2, mean(reconvergence, rs), mean(noise, rs), len(rs)) for (b1, b2), rs in groups.items())
    front = pareto_front([(p[2], p[3]) for p in pairs])
    if not front:
        raise SimulationError("no gain pair re-converged after every road change in every case; widen the beta "
                              "grid or lengthen the runs")
    lo = [min(pairs[i][k] for i in front) for k in (2, 3)]
    span = [max(max(pairs[i][k] for i in front) - lo[j], 1e-300) for j, k in enumerate((2, 3))]
    best = min(front, key=lambda i: ((pairs[i][2] - lo[0]) / span[0]) ** 2 + ((pairs[i][3] - lo[1]) / span[1]) ** 2)
    b1, b2, r, n, _ = pairs[best]
    first = braking[0].case
    assert isinstance(first, BrakingCase)
    return TunedDesign(observer=kinds[0], beta1=b1, beta2=b2, reconvergence_s=r, noise_rms=n, pairs=pairs,
                       front=tuple(front), command=design_command(first, b1, b2))
