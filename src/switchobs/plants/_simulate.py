"""Emergency-braking simulation of the quarter car with a hybrid brake controller.

The plant is the non-simplified quarter car of seed 001 eq. (2.1) (seed 000
eq. (1)-(3)); the controller is a hybrid automaton of
:mod:`switchobs.plants._controllers`; an optional :class:`XbsEstimator` is
stepped once per accepted step with the measured signals.

Integration
-----------
Classical RK4 with a fixed step ``dt_s`` (default 1 ms).  Below
``low_speed_m_s`` (default 5 m/s) the step shrinks as ``dt_s * vx /
low_speed_m_s``: that is a fixed step in the time ``s = ∫ dt / vx`` of seed 001
eq. (3.21), in which the wheel dynamics does not depend on the speed, so the
stiffness ``a mu'(lambda) / vx`` never leaves the RK4 stability region
(``|h a mu' / vx| <= 1.3`` for the roads of Table 2.1 with the default rig).
Steps end exactly on the known breakpoints (start and end of the road
transitions, end of a reference trajectory, the final time); controller phase
changes, position-triggered road changes and the final stop are located within
the step.  Only the controller's guards that read an observer's estimate are
checked at the step ends, where the estimate changes.  The integrator and its
rules (order of the transitions, guard cascades, an observer refusing a step)
are those of :func:`switchobs.plants.integrate`, shared with the
two-axle vehicle and the wheel of :mod:`switchobs.sensors`.

Replay
------
When the controller does not read the estimate (the observer beside the loop, or a
controller that needs no XBS), the plant's run does not depend on the estimator: the
plant then runs in the compiled loop alone, recording the length of every step, and the
estimator is fed the recorded samples afterwards, ``reset`` and one ``update`` per step
with the same arguments as in the interleaved loop (:func:`replay_updates`, or the
estimator's own :meth:`ReplayEstimator.replay`).  The run is cut where the estimator
refuses a step, as the interleaved loop stops there; the result is that of the Python
loop bit for bit.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from ..exceptions import SimulationError
from ._compiled import compiled_support, compiler_available, run_compiled
from ._estimator import ReplayEstimator, TrueXbs, X2Measurement, XbsEstimator, replay_updates
from ._json import run_from_json
from ._hybrid import HybridRun, check_run_size, integrate
from ._metrics import BrakingMetrics, braking_metrics, diverged
from ._plant import SERIES, BrakingScenario, _QuarterCar

__all__ = ["BrakingScenario", "BrakingResult", "simulate", "SERIES"]


@dataclass(frozen=True)
class BrakingResult:
    """Time histories and metrics of one braking simulation.

    Attributes
    ----------
    scenario : BrakingScenario
    status : str
        ``stopped`` (reached the stop speed), ``duration`` (time bound reached),
        ``controller-singular`` (the continuous law became undefined) or
        ``observer-failed`` (the estimator refused a step, e.g. a non-finite state).
    message : str
        Details of the status.
    series : dict of str -> ndarray
        The columns of :data:`SERIES`: time, wheel speed ``omega``, ``vx``,
        travelled distance ``x``, pressure ``P_b`` [bar], slip ``lambda``,
        friction ``mu``, true XBS ``xbs``, ``x2 = R dω/dt - a_x``, ``ax``,
        ``omega_dot``, applied ``u = dP_b/dt`` [bar/s], controller ``phase``,
        estimate ``xbs_hat`` (NaN without estimator), the wheel-acceleration
        reference the controller tracks ``x2_ref`` and its slope ``dx2_ref``
        (seed 000 (21); NaN when it tracks none, :class:`FivePhaseABS` with
        ``tracking=True`` in phases 1, 3, 4).
    events : tuple of (float, str)
        Phase changes and road changes with their times.
    metrics : BrakingMetrics
    observer : str
        Description of the estimator (``none`` without).
    observer_in_loop : bool
        Whether the controller used the estimate (otherwise the true XBS).
    wall_time_s, observer_time_s, steps : float, float, int
        Cost of the run (measured, for the benchmark).
    compiled : bool
        Whether the loop ran compiled to C (``simulate(compiled=...)``); the results are the same.
    """

    scenario: BrakingScenario
    status: str
    message: str
    series: dict[str, npt.NDArray[np.float64]]
    events: tuple[tuple[float, str], ...]
    metrics: BrakingMetrics
    observer: str
    observer_in_loop: bool
    wall_time_s: float
    observer_time_s: float
    steps: int
    compiled: bool = False

    @property
    def failure(self) -> str | None:
        """Why the run failed, or ``None``: the exit status 1 of ``switchobs simulate``.

        A run fails when the estimator refused a step (``observer-failed``), the
        continuous law became undefined (``controller-singular``), or the estimate
        diverged (:func:`diverged`).  Reaching the time bound before the stop is
        not a failure here: whether the bound was the point of the run (a drum
        scenario, a chosen window) is the caller's to say.
        """
        if self.status in ("observer-failed", "controller-singular"):
            return f"{self.status}: {self.message}"
        return diverged(self.series["xbs_hat"], self.metrics.xbs_rms_error)

    def to_json(self, *, include_series: bool = False) -> dict[str, Any]:
        out: dict[str, Any] = {
            "scenario": self.scenario.to_json(), "status": self.status, "message": self.message,
            "failure": self.failure,
            "observer": self.observer, "observer_in_loop": self.observer_in_loop,
            "metrics": self.metrics.to_json(),
            "cost": {"steps": self.steps, "wall_time_s": self.wall_time_s, "observer_time_s": self.observer_time_s,
                     "simulated_time_s": float(self.series["t"][-1])},
            "events": [{"t": t, "event": e} for t, e in self.events], "compiled": self.compiled,
        }
        if include_series:
            out["series"] = {k: [None if math.isnan(v) else float(v) for v in arr]
                             for k, arr in self.series.items()}
        return out

    @classmethod
    def from_json(cls, data: Any) -> BrakingResult:
        """The result of ``to_json(include_series=True)``: the series as float arrays (``null`` as NaN).

        The series are NumPy arrays, so compare two results by their
        ``to_json(include_series=True)`` (scenario, metrics and events compare with ``==``).

        Raises
        ------
        SimulationError
            No ``series`` (written without ``include_series=True``), a missing key or a malformed part.
        """
        series, events = run_from_json(data, "braking result")
        try:
            cost = data["cost"]
            return cls(BrakingScenario.from_json(data["scenario"]), str(data["status"]), str(data["message"]),
                       series, events, BrakingMetrics.from_json(data["metrics"]), str(data["observer"]),
                       bool(data["observer_in_loop"]), float(cost["wall_time_s"]), float(cost["observer_time_s"]),
                       int(cost["steps"]), bool(data.get("compiled", False)))
        except (KeyError, TypeError, ValueError) as exc:
            if isinstance(exc, SimulationError):
                raise
            raise SimulationError(f"not a braking result JSON ({type(exc).__name__}: {exc})") from None

    def __repr__(self) -> str:
        return (f"<BrakingResult {self.scenario.name!r}: {self.status}, {self.steps} steps to "
                f"t = {float(self.series['t'][-1]):.3g} s, observer {self.observer}>")

    def _repr_markdown_(self) -> str:
        """The run in a notebook: scenario, status, metrics and the series available as NumPy arrays."""
        m = self.metrics.to_json()
        numbers = [(k, v) for k, v in m.items() if isinstance(v, (int, float)) and not isinstance(v, bool)]
        table = ["| metric | value |", "|---|---|"] + [f"| `{k}` | {v:.6g} |" for k, v in numbers]
        return "\n".join([f"**Braking** `{self.scenario.name}`: {self.scenario}", "",
                          f"status: **{self.status}**{' (' + self.message + ')' if self.message else ''}; "
                          f"observer: {self.observer}{' (in the loop)' if self.observer_in_loop else ''}", "",
                          *table, "",
                          f"series (NumPy, `result.series[...]` or `result.to_numpy()`): "
                          f"{', '.join(f'`{k}`' for k in self.series)}"])

    def to_numpy(self) -> np.ndarray:
        """The series as one structured array (a field per column of :data:`SERIES`, a row per step)."""
        names = list(self.series)
        out = np.empty(len(self.series["t"]), dtype=[(k, float) for k in names])
        for k in names:
            out[k] = self.series[k]
        return out

    def __str__(self) -> str:
        lines = [str(self.scenario), f"  status: {self.status}" + (f" ({self.message})" if self.message else ""),
                 f"  observer: {self.observer}" + (" (in the loop)" if self.observer_in_loop and
                                                    self.observer != "none" else "")]
        lines += ["  " + line for line in str(self.metrics).splitlines()]
        sim_t = float(self.series["t"][-1])
        lines.append(f"  cost: {self.steps} steps, {self.wall_time_s:.3f} s wall for {sim_t:.3f} s simulated "
                     f"(x{sim_t / max(self.wall_time_s, 1e-12):.1f} real time)")
        return "\n".join(lines)


def _replayed(plant: _QuarterCar) -> HybridRun | None:
    """The plant in the compiled loop without the estimator, then the estimator over the recorded samples
    (:class:`ReplayEstimator` or :func:`replay_updates`): the run, samples and estimates of the Python
    loop that interleaves them, cut where the estimator refuses a step.  ``None`` (run the Python loop)
    when the compiled loop raises: the interleaved run may stop at a refused step before that point."""
    est, plant.estimator = plant.estimator, None
    try:
        run = run_compiled(plant, None, step_lengths=True)
    except SimulationError:
        return None
    finally:
        plant.estimator = est
    t_obs = time.perf_counter()
    s = dict(run.series)
    dt = s.pop("dt")
    p = s["P_b"]
    u = np.zeros_like(p)
    u[1:] = (p[1:] - p[:-1]) / dt[1:]           # after_step's mean pressure rate over each step
    if isinstance(est, ReplayEstimator):
        hat, refused, message = est.replay(s["t"], s["x2"], s["vx"], u, dt)
    else:
        hat, refused, message = replay_updates(est, s["t"], s["x2"], s["vx"], u, dt)
    plant.observer_time_s = time.perf_counter() - t_obs
    status, steps, events = run.status, run.steps, run.events
    if refused is not None:
        # the interleaved loop records the refused step's sample and stops before its events
        t_stop = float(s["t"][refused])
        s = {k: v[:refused + 1] for k, v in s.items()}
        events = tuple(e for e in events if e[0] < t_stop)
        plant.road.starts = [t for t in plant.road.starts if t < t_stop]
        status, steps = "observer-failed", refused
    else:
        message = run.message
    s["xbs_hat"] = np.asarray(hat, dtype=float)
    return HybridRun(series=s, events=events, status=status, message=message, steps=steps,
                     wall_time_s=run.wall_time_s + plant.observer_time_s)


def _run(plant: _QuarterCar, compiled: bool | None) -> BrakingResult:
    """The braking run of ``plant``: compiled to C where :func:`compiled_support` allows it (``compiled``: see
    :func:`simulate`), replayed when the controller does not read the estimate, else the Python loop."""
    sc = plant.sc
    run: HybridRun | None = None
    if compiled is not False:
        obs, reason = compiled_support(plant)
        # an estimator the controller does not read cannot change the plant's run: the plant runs
        # compiled and the estimator over its samples afterwards (module notes)
        replay = (reason is not None and plant.estimator is not None and not plant.use_hat
                  and compiled_support(plant, estimator=False)[1] is None)
        if reason is not None and not replay and compiled:
            raise SimulationError(f"scenario {sc.name!r} cannot run in the compiled loop: {reason}")
        if (reason is None or replay) and (compiled or compiler_available()):
            check_run_size(plant, sc.duration_s, sc.name)  # integrate() checks the Python loop's run
            run = _replayed(plant) if replay else run_compiled(plant, obs)
    ran_compiled = run is not None
    if run is None:
        run = integrate(plant, sc.duration_s, name=sc.name)
    est = plant.estimator
    metrics = braking_metrics(run.series, sc, plant.road.starts, status=run.status,
                              have_estimate=est is not None)
    observer = "none" if est is None else (est.describe() if hasattr(est, "describe") else type(est).__name__)
    return BrakingResult(scenario=sc, status=run.status, message=run.message, series=run.series,
                         events=run.events, metrics=metrics, observer=observer, observer_in_loop=plant.use_hat,
                         wall_time_s=run.wall_time_s, observer_time_s=plant.observer_time_s, steps=run.steps,
                         compiled=ran_compiled)


def simulate(scenario: BrakingScenario, *, estimator: XbsEstimator | str | None = None,
             observer_in_loop: bool = True, compiled: bool | None = None,
             x2_source: X2Measurement | None = None) -> BrakingResult:
    """Simulate one emergency braking.

    Parameters
    ----------
    scenario : BrakingScenario
    estimator : XbsEstimator, "true" or None
        Observer stepped along the run (an object with ``reset``/``update``,
        see :class:`XbsEstimator`); ``"true"`` plugs the :class:`TrueXbs`
        oracle (sampled true XBS).
    observer_in_loop : bool
        If true (default) controllers that need an XBS read the estimate
        (output feedback, seed 001 Fig. 4.6); otherwise they read the true XBS
        and the estimator runs in parallel (Fig. 4.5).
    compiled : bool or None
        Run the loop compiled to C (:mod:`switchobs.plants._compiled`: the same operations as the
        Python loop, the same results, about 30 times faster): ``None`` (default) when the scenario
        and the estimator allow it (five- or two-phase ABS, no actuator delay, no estimator, the true
        XBS, an estimator with a C step such as a compiled observer, or any estimator the controller
        does not read, replayed over the compiled run: module notes) and a C compiler is installed,
        otherwise the Python loop; ``True`` requires it; ``False`` runs the Python loop.
    x2_source : X2Measurement, optional
        A measurement of ``x2`` that the controller reads instead of the exact one (seed 001
        Figs. 6.7-6.9: the ABS closed on the encoder, :class:`switchobs.loop.EncoderX2`); its
        guards are then checked at the step ends.  Runs in the Python loop only.

    Returns
    -------
    BrakingResult

    Raises
    ------
    SimulationError
        On inadmissible settings, when the controller switches endlessly
        without time passing, or with ``compiled=True`` for a run the compiled
        loop does not cover.
    CodegenError
        With ``compiled=True`` and no C compiler, or when the compilation fails.

    Examples
    --------
    >>> sc = BrakingScenario("dry-asphalt", speed_m_s=60 / 3.6)
    >>> res = simulate(sc)
    >>> res.status, 0.95 < res.metrics.efficiency < 1.0
    ('stopped', True)
    """
    if not isinstance(scenario, BrakingScenario):
        raise SimulationError(f"simulate() needs a BrakingScenario, got {type(scenario).__name__}")
    if isinstance(estimator, str):
        if estimator != "true":
            raise SimulationError(f"estimator must be an XbsEstimator object, 'true' or None, got {estimator!r}")
        plant = _QuarterCar(scenario, None, observer_in_loop, x2_source)
        plant.estimator = TrueXbs(plant.true_xbs)
        plant.use_hat = bool(observer_in_loop and scenario.controller.uses_xbs)
        plant.discrete_feedback = plant.use_hat or x2_source is not None
        return _run(plant, compiled)
    if x2_source is not None and not isinstance(x2_source, X2Measurement):
        raise SimulationError(f"the x2 source {x2_source!r} lacks reset(t0, y0, vx0) and "
                              f"update(t, y, vx, u, dt)")
    if estimator is not None and not isinstance(estimator, XbsEstimator):
        raise SimulationError(f"the estimator {estimator!r} lacks reset(t0, y0, vx0) and "
                              f"update(t, y, vx, u, dt)")
    return _run(_QuarterCar(scenario, estimator, observer_in_loop, x2_source), compiled)
