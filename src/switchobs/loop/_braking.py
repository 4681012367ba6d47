"""One braking case from plain values, for sweeps: scenario, controller and observer built here, metrics back.

:func:`run_braking` is what a sweep calls once per case (``switchobs.sweep``): everything it needs
is a road (or schedule), a speed, a controller and an observer setting; the loop runs compiled to C
when it can (:func:`switchobs.plants.simulate`, ``compiled=None``), and the time series are dropped
unless asked for, so that a result is a few hundred bytes to send back from a worker.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from .._json import fields_from_json
from ..exceptions import SimulationError
from ..plants import (BrakingMetrics, BrakingScenario, ContinuousXbsControl, FivePhaseABS, QuarterCar, RoadSchedule,
                      TwoPhaseABS, simulate)
from ._factory import EstimatorSpec, xbs_estimator

__all__ = ["BrakingRun", "run_braking", "CONTROLLER_NAMES"]

#: Controllers by name (:func:`run_braking`).
CONTROLLER_NAMES = ("five-phase", "two-phase", "continuous")


@dataclass(frozen=True)
class BrakingRun:
    """The outcome of one braking case (:func:`run_braking`).

    Attributes
    ----------
    scenario : BrakingScenario
    observer : EstimatorSpec
    status, message : str
        As :class:`switchobs.plants.BrakingResult` (``stopped``, ``duration``, ...).
    metrics : BrakingMetrics
        Braking and stopping distance, mean slip, ABS cycles, XBS error and re-convergence per road.
    events : tuple of (float, str)
    steps : int
    simulated_time_s, wall_time_s : float
        Simulated time and the wall time of the whole case (set-up, loop, metrics).
    compiled : bool
        Whether the loop ran compiled to C.
    series : mapping of str to ndarray, or None
        The columns of :data:`switchobs.plants.SERIES` when asked for (``series=True``).
    """

    scenario: BrakingScenario
    observer: EstimatorSpec
    status: str
    message: str
    metrics: BrakingMetrics
    events: tuple[tuple[float, str], ...]
    steps: int
    simulated_time_s: float
    wall_time_s: float
    compiled: bool
    series: Mapping[str, npt.NDArray[np.float64]] | None = None

    @property
    def real_time_factor(self) -> float:
        """Simulated time over wall time."""
        return self.simulated_time_s / max(self.wall_time_s, 1e-12)

    def to_json(self, *, include_series: bool = False) -> dict[str, Any]:
        out: dict[str, Any] = {
            "scenario": self.scenario.to_json(), "observer": self.observer.to_json(), "status": self.status,
            "message": self.message, "metrics": self.metrics.to_json(),
            "events": [{"t": t, "event": e} for t, e in self.events],
            "cost": {"steps": self.steps, "simulated_time_s": self.simulated_time_s,
                     "wall_time_s": self.wall_time_s, "compiled": self.compiled}}
        if include_series and self.series is not None:
            out["series"] = {k: [None if math.isnan(v) else float(v) for v in arr] for k, arr in self.series.items()}
        return out

    @classmethod
    def from_json(cls, data: Any) -> BrakingRun:
        """The run of :meth:`to_json` (its series only if written with ``include_series=True``).

        Raises
        ------
        SimulationError
            A missing key or a malformed part; the message names it.
        """
        try:
            flat = {**data, **data["cost"], "events": [(e["t"], e["event"]) for e in data["events"]]}
        except (KeyError, TypeError) as exc:
            raise SimulationError(f"a braking run JSON needs 'cost' and 'events' with 't' and 'event' ({exc!r})") \
                from None
        return fields_from_json(cls, flat, error=SimulationError, what="braking run")

    def __str__(self) -> str:
        loop = "compiled loop" if self.compiled else "Python loop"
        lines = [str(self.scenario), f"  observer: {self.observer}",
                 f"  status: {self.status}" + (f" ({self.message})" if self.message else "")]
        lines += ["  " + line for line in str(self.metrics).splitlines()]
        lines.append(f"  cost: {self.steps} steps, {self.wall_time_s:.4f} s wall for {self.simulated_time_s:.3f} s "
                     f"simulated (x{self.real_time_factor:.0f} real time, {loop})")
        return "\n".join(lines)


def _controller(controller: Any, in_loop_estimate: bool) -> Any:
    if isinstance(controller, (FivePhaseABS, TwoPhaseABS, ContinuousXbsControl)):
        return controller
    if controller == "five-phase":
        return FivePhaseABS()
    if controller == "two-phase":
        # as table41: the start-up safeguard protects an observer that has not converged yet; on the
        # true XBS the build-up ends when the XBS drops below chi_a (seed 001 Fig. 4.3)
        return TwoPhaseABS() if in_loop_estimate else TwoPhaseABS(start_decel_m_s2=None)
    if controller == "continuous":
        return ContinuousXbsControl()
    raise SimulationError(f"unknown controller {controller!r}; choose one of {', '.join(CONTROLLER_NAMES)} "
                          f"or pass a controller object")


def run_braking(roads: str | RoadSchedule, speed_kmh: float, *, controller: Any = "five-phase",
                observer: EstimatorSpec | str = "none", observer_in_loop: bool = True,
                vehicle: QuarterCar | None = None, dt_s: float = 1e-3, duration_s: float = 60.0,
                series: bool = False, compiled: bool | None = None, name: str | None = None) -> BrakingRun:
    """Brake the free quarter car from ``speed_kmh`` to standstill on ``roads`` and return the metrics.

    Parameters
    ----------
    roads : str or RoadSchedule
        A road name (:func:`switchobs.plants.road_names`) or a schedule with changes.
    speed_kmh : float
        Initial speed [km/h].
    controller : str or controller
        ``five-phase``, ``two-phase`` (without the start-up safeguard when it reads the true XBS, as
        :func:`switchobs.plants.table41`), ``continuous``, or a controller object.
    observer : EstimatorSpec or str
        The XBS observer (:func:`xbs_estimator`; ``impl="c"`` keeps the whole loop compiled); ``none``
        runs without one (controllers that need an XBS read the true one).
    observer_in_loop : bool
        Controllers that need an XBS read the estimate (otherwise the observer runs beside the loop).
    vehicle : QuarterCar, optional
        Default :class:`QuarterCar` (the TU Delft rig of seed 001).
    dt_s, duration_s : float
        Integration step and time bound [s].
    series : bool
        Keep the time series in the result (default: metrics only).
    compiled : bool or None
        As :func:`switchobs.plants.simulate`: ``None`` compiles when possible.
    name : str, optional
        Scenario name (default ``braking-<road>-<speed>``).

    Returns
    -------
    BrakingRun

    Raises
    ------
    SimulationError
        On inadmissible settings (speed, step, controller name, ...).

    Examples
    --------
    >>> run = run_braking("dry-asphalt", 60, controller="two-phase")
    >>> run.status, round(run.metrics.braking_distance_m, 2)
    ('stopped', 12.42)
    """
    wall0 = time.perf_counter()
    if not (isinstance(speed_kmh, (int, float)) and math.isfinite(speed_kmh) and speed_kmh > 0):
        raise SimulationError(f"speed_kmh must be a positive number, got {speed_kmh!r}")
    spec = EstimatorSpec(observer) if isinstance(observer, str) else observer
    if not isinstance(spec, EstimatorSpec):
        raise SimulationError(f"observer must be an EstimatorSpec or an observer kind, got {observer!r}")
    ctrl = _controller(controller, spec.kind != "none" and observer_in_loop)
    schedule = roads if isinstance(roads, RoadSchedule) else RoadSchedule(roads)
    sc = BrakingScenario(schedule, speed_m_s=speed_kmh / 3.6, controller=ctrl,
                         name=name or f"braking-{schedule.initial.name}-{speed_kmh:g}",
                         vehicle=vehicle if vehicle is not None else QuarterCar(), dt_s=dt_s, duration_s=duration_s)
    est = xbs_estimator(spec, sc.vehicle, sc.roads.initial)
    res = simulate(sc, estimator=est, observer_in_loop=observer_in_loop, compiled=compiled)
    return BrakingRun(scenario=sc, observer=spec, status=res.status, message=res.message, metrics=res.metrics,
                      events=res.events, steps=res.steps, simulated_time_s=float(res.series["t"][-1]),
                      wall_time_s=time.perf_counter() - wall0, compiled=res.compiled, series=res.series if series else None)
