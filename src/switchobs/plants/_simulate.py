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

import bisect
import math
import time
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import numpy.typing as npt

from ..exceptions import SimulationError
from ._controllers import ContinuousXbsControl, Controller, FivePhaseABS, SixPhaseABS, TwoPhaseABS
from ._compiled import compiled_support, compiler_available, run_compiled
from ._estimator import ReplayEstimator, TrueXbs, X2Measurement, XbsEstimator, replay_updates
from ._json import controller_from_json, from_fields, run_from_json
from ._hybrid import Crossing, HybridPlant, HybridRun, check_run_size, integrate
from ._metrics import BrakingMetrics, braking_metrics, diverged
from ._road import RoadSchedule, _RoadState
from ._tyre import Burckhardt
from ._vehicle import BrakeActuator, PrescribedSpeed, QuarterCar, check_speed

__all__ = ["BrakingScenario", "BrakingResult", "simulate", "SERIES"]

#: Columns of :attr:`BrakingResult.series`, in order.
SERIES = ("t", "omega", "vx", "x", "P_b", "lambda", "mu", "xbs", "x2", "ax", "omega_dot", "u", "phase",
          "xbs_hat", "x2_ref", "dx2_ref")


def _check(owner: str, key: str, value: Any, *, positive: bool = True, allow_zero: bool = False) -> None:
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
        raise SimulationError(f"{owner}: {key} must be a finite number, got {value!r}")
    if positive and (value < 0 or (value == 0 and not allow_zero)):
        raise SimulationError(f"{owner}: {key} must be {'>= 0' if allow_zero else '> 0'}, got {value!r}")


@dataclass(frozen=True)
class BrakingScenario:
    """Everything that defines one braking simulation.

    Parameters
    ----------
    roads : RoadSchedule or str
        Surface(s); a road name means one surface throughout.
    speed_m_s : float
        Initial vehicle speed ``vx(0)`` [m/s], in ``(0, MAX_SPEED_KMH / 3.6]``.
    controller : FivePhaseABS, TwoPhaseABS or ContinuousXbsControl
    name : str
    vehicle : QuarterCar
    actuator : BrakeActuator
    speed_profile : PrescribedSpeed, optional
        ``None``: the vehicle decelerates by its own tyre force (2.1b);
        otherwise the speed is imposed (drum test rig).
    duration_s : float
        Upper bound of the simulated time [s], > 0.
    stop_speed_m_s : float
        The run ends when ``vx`` reaches it (2.5 km/h by default, the lower
        bound of seed 001 eq. (2.3)).
    dt_s : float
        Integration step [s] (see the module notes), in ``(0, 0.01]``.
    low_speed_m_s : float
        Speed below which the step shrinks proportionally to ``vx``.

    Raises
    ------
    SimulationError
        On any non-positive speed, duration or step, or a stop speed not below
        the initial speed.
    """

    roads: RoadSchedule
    speed_m_s: float
    controller: Controller = field(default_factory=FivePhaseABS)
    name: str = "braking"
    vehicle: QuarterCar = field(default_factory=QuarterCar)
    actuator: BrakeActuator = field(default_factory=BrakeActuator)
    speed_profile: PrescribedSpeed | None = None
    duration_s: float = 60.0
    stop_speed_m_s: float = 2.5 / 3.6
    dt_s: float = 1e-3
    low_speed_m_s: float = 5.0

    def __post_init__(self) -> None:
        if isinstance(self.roads, (str, Burckhardt)):
            object.__setattr__(self, "roads", RoadSchedule(self.roads))
        if not isinstance(self.roads, RoadSchedule):
            raise SimulationError(f"roads must be a RoadSchedule or a road name, got {self.roads!r}")
        if not isinstance(self.controller, (FivePhaseABS, SixPhaseABS, TwoPhaseABS, ContinuousXbsControl)):
            raise SimulationError(f"unknown controller {self.controller!r}")
        owner = f"scenario {self.name!r}"
        _check(owner, "initial speed speed_m_s", self.speed_m_s)
        check_speed(owner, self.speed_m_s)
        _check(owner, "duration_s", self.duration_s)
        _check(owner, "stop_speed_m_s", self.stop_speed_m_s)
        _check(owner, "dt_s", self.dt_s)
        _check(owner, "low_speed_m_s", self.low_speed_m_s, allow_zero=True)
        if self.dt_s > 0.01:
            raise SimulationError(f"{owner}: dt_s = {self.dt_s} s is too coarse for the wheel dynamics; "
                                  f"use at most 0.01 s (default 0.001 s)")
        if self.stop_speed_m_s >= self.speed_m_s:
            raise SimulationError(f"{owner}: the stop speed {self.stop_speed_m_s:g} m/s must be below the "
                                  f"initial speed {self.speed_m_s:g} m/s")
        if 0.0 < self.actuator.delay_s < self.dt_s:
            raise SimulationError(f"{owner}: an actuator delay of {self.actuator.delay_s:g} s is shorter than "
                                  f"the step {self.dt_s:g} s; use 0 or at least one step")

    @property
    def speed_kmh(self) -> float:
        return self.speed_m_s * 3.6

    def with_step(self, dt_s: float) -> BrakingScenario:
        """The same scenario integrated with another step (for convergence checks)."""
        return replace(self, dt_s=dt_s)

    def to_json(self) -> dict[str, Any]:
        return {"name": self.name, "roads": self.roads.to_json(), "speed_m_s": self.speed_m_s,
                "speed_kmh": self.speed_kmh, "controller": self.controller.to_json(),
                "vehicle": self.vehicle.to_json(), "actuator": self.actuator.to_json(),
                "speed_profile": None if self.speed_profile is None else self.speed_profile.to_json(),
                "duration_s": self.duration_s, "stop_speed_m_s": self.stop_speed_m_s, "dt_s": self.dt_s,
                "low_speed_m_s": self.low_speed_m_s}

    @classmethod
    def from_json(cls, data: Any) -> BrakingScenario:
        """The scenario of :meth:`to_json`: roads by name, the controller by its ``name``.

        Raises
        ------
        SimulationError
            A missing key, an unknown controller or road, or a value the scenario rejects.
        """
        if not isinstance(data, dict):
            raise SimulationError(f"a braking scenario JSON must be an object, got {data!r}")
        profile = data.get("speed_profile")
        return from_fields(cls, data, "braking scenario", roads=RoadSchedule.from_json(data.get("roads")),
                           controller=controller_from_json(data.get("controller"), "a braking scenario JSON"),
                           vehicle=from_fields(QuarterCar, data.get("vehicle"), "vehicle"),
                           actuator=from_fields(BrakeActuator, data.get("actuator"), "actuator"),
                           speed_profile=None if profile is None else from_fields(PrescribedSpeed, profile,
                                                                                   "speed profile"))

    def __str__(self) -> str:
        profile = "free vehicle (2.1b)" if self.speed_profile is None else \
            f"prescribed deceleration {self.speed_profile.decel_m_s2:g} m/s²"
        return (f"scenario {self.name}: {self.roads}, {self.speed_kmh:.0f} km/h, {profile}, "
                f"{self.controller}, dt={self.dt_s * 1e3:g} ms")


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


class _QuarterCar(HybridPlant):
    """The quarter car with its controller and estimator as a :class:`HybridPlant`; plain floats, no numpy per step."""

    states = ("omega", "vx", "x", "P_b")
    series = SERIES
    labels = ("",)

    def __init__(self, sc: BrakingScenario, estimator: XbsEstimator | None, in_loop: bool,
                 x2_source: X2Measurement | None = None):
        veh = sc.vehicle
        self.sc = sc
        self.R = veh.radius_m
        self.J = veh.inertia_kg_m2
        self.Fz = veh.load_n
        self.gb = veh.brake_gain_nm_bar
        self.m = veh.mass_kg
        self.road = _RoadState(sc.roads)
        self.prescribed = sc.speed_profile is not None
        self.decel = sc.speed_profile.decel_m_s2 if sc.speed_profile is not None else 0.0
        self.max_rate = sc.actuator.max_rate_bar_s
        self.p_max = sc.actuator.max_pressure_bar
        self.delay = sc.actuator.delay_s
        ctrl = sc.controller
        if isinstance(ctrl, ContinuousXbsControl):
            first = sc.roads.initial
            self.ctrl = ctrl.runtime(veh, sc.actuator, c=first.c, d=first.d)
        else:
            self.ctrl = ctrl.runtime(veh, sc.actuator)
        self.automata = (self.ctrl,)
        self.estimator = estimator
        # the controller reads the estimate only if it needs an XBS and the estimator is in the loop
        self.use_hat = bool(estimator is not None and in_loop and ctrl.uses_xbs)
        self.x2_source = x2_source
        # a measured x2 is held between step ends, so the controller's rate changes only there
        self.discrete_feedback = self.use_hat or x2_source is not None
        self.x2_meas = 0.0
        self.xbs_hat = math.nan
        self.observer_time_s = 0.0
        self.p_prev = 0.0
        self.hist_t: list[float] = []
        self.hist_u: list[float] = []
        # outputs of the last rhs evaluation
        self.o_lam = self.o_mu = self.o_xbs = self.o_omdot = self.o_ax = self.o_x2 = self.o_ucmd = self.o_u = 0.0

    def true_xbs(self) -> float:
        return self.o_xbs

    def initial_state(self) -> tuple[float, ...]:
        v0 = self.sc.speed_m_s
        return (v0 / self.R, v0, 0.0, 0.0)

    def rhs(self, t: float, y: tuple[float, ...]) -> tuple[float, float, float, float]:
        om, vx, _x, P = y
        R = self.R
        lam = (R * om - vx) / vx
        mu, xbs = self.road.eval(lam, t)
        fx = self.Fz * mu
        omdot = (-R * fx - self.gb * P) / self.J
        if om <= 0.0 and omdot < 0.0:
            omdot = 0.0               # locked wheel: static friction holds it at rest
        ax = -self.decel if self.prescribed else fx / self.m
        x2 = R * omdot - ax
        if self.delay > 0.0:
            ucmd = self._delayed(t - self.delay)
        else:
            ucmd = self.ctrl.rate(t, x2 if self.x2_source is None else self.x2_meas, R * om, vx,
                                  self.xbs_hat if self.use_hat else xbs)
        u = ucmd
        if u > self.max_rate:
            u = self.max_rate
        elif u < -self.max_rate:
            u = -self.max_rate
        if (P <= 0.0 and u < 0.0) or (P >= self.p_max and u > 0.0):
            u = 0.0
        self.o_lam, self.o_mu, self.o_xbs, self.o_omdot, self.o_ax, self.o_x2 = lam, mu, xbs, omdot, ax, x2
        self.o_ucmd, self.o_u = ucmd, u
        return (omdot, ax, vx, u)

    def _delayed(self, t: float) -> float:
        ht = self.hist_t
        if not ht or t < ht[0]:
            return 0.0
        i = bisect.bisect_right(ht, t) - 1
        if i >= len(ht) - 1:
            return self.hist_u[-1]
        t0, t1 = ht[i], ht[i + 1]
        if t1 <= t0:
            return self.hist_u[i + 1]
        w = (t - t0) / (t1 - t0)
        return self.hist_u[i] + w * (self.hist_u[i + 1] - self.hist_u[i])

    def _remember_command(self, t: float, y: tuple[float, ...]) -> None:
        """Controller output at a step end, for the delayed actuator."""
        xbs = self.xbs_hat if self.use_hat else self.o_xbs
        self.hist_t.append(t)
        self.hist_u.append(self.ctrl.rate(t, self._ctrl_x2(), self.R * y[0], y[1], xbs))

    def _ctrl_x2(self) -> float:
        """The ``x2`` the controller reads: the exact one, or the measurement held since the last step end."""
        return self.o_x2 if self.x2_source is None else self.x2_meas

    def clamp(self, y: tuple[float, ...]) -> tuple[float, ...]:
        om, vx, x, P = y
        if om < 0.0 or P < 0.0 or P > self.p_max:
            return (max(om, 0.0), vx, x, min(max(P, 0.0), self.p_max))
        return y

    def step_size(self, t: float, y: tuple[float, ...]) -> float:
        dt, v_low = self.sc.dt_s, self.sc.low_speed_m_s
        return dt if y[1] >= v_low else dt * y[1] / v_low

    def breakpoint(self, t: float) -> float:
        kink = self.ctrl.breakpoint()
        return min(self.road.breakpoint(), kink if kink > t + 1e-12 else math.inf)

    def start(self, t: float, y: tuple[float, ...]) -> bool:
        if self.x2_source is not None:
            self.x2_source.reset(t, self.o_x2, y[1])
            self.x2_meas = self.o_x2
        if self.estimator is not None:
            t_obs = time.perf_counter()
            self.estimator.reset(t, self.o_x2, y[1])
            self.observer_time_s += time.perf_counter() - t_obs
        if self.delay > 0.0:
            self._remember_command(t, y)
            return True
        return False

    def after_step(self, t: float, y: tuple[float, ...], h: float) -> str | None:
        u_mean, self.p_prev = (y[3] - self.p_prev) / h, y[3]
        if self.x2_source is not None:
            try:
                self.x2_meas = float(self.x2_source.update(t, self.o_x2, y[1], u_mean, h))
            except SimulationError as exc:
                return str(exc)
        if self.estimator is None:
            return None
        t_obs = time.perf_counter()
        try:
            self.xbs_hat = self.estimator.update(t, self.o_x2, y[1], u_mean, h)
        except SimulationError as exc:     # e.g. ObserverInputError: the run stops (integrate's rule)
            return str(exc)
        finally:
            self.observer_time_s += time.perf_counter() - t_obs
        return None

    def crossings(self, t: float, y: tuple[float, ...], y1: tuple[float, ...]) -> list[Crossing]:
        out = []
        v_stop = self.sc.stop_speed_m_s
        if y1[1] <= v_stop:
            out.append(Crossing("stop", lambda tt, yy: v_stop - yy[1], v_stop - y[1], v_stop - y1[1],
                                terminal=True, text=f"vx reached {v_stop:.3f} m/s"))
        pending = self.road.pending
        if not self.road.blending and pending is not None and pending.at_position_m is not None \
                and y1[2] >= pending.at_position_m:
            x_change = pending.at_position_m
            out.append(Crossing("road", lambda tt, yy: yy[2] - x_change, y[2] - x_change, y1[2] - x_change))
        return out

    def take(self, crossing: Crossing, t: float, y: tuple[float, ...]) -> str:
        pending = self.road.pending
        self.road.start_change(t)
        return f"road -> {pending.road.name} (x = {y[2]:.2f} m)"

    def at_breakpoint(self, t: float, y: tuple[float, ...]) -> tuple[bool, list[str]]:
        return self.road.at_breakpoint(t)

    def guard_values(self, k: int) -> tuple[float, ...]:
        return self.ctrl.guards(self._ctrl_x2(), self.xbs_hat if self.use_hat else self.o_xbs, self.o_lam)

    def locatable(self, k: int) -> bool:
        return self.x2_source is None and not (self.use_hat and self.ctrl.guards_use_xbs)

    def transition_args(self, k: int, y: tuple[float, ...]) -> tuple[float, float, float]:
        return (self._ctrl_x2(), self.R * y[0], y[1])

    def end_step(self, t: float, y: tuple[float, ...]) -> tuple[str, str] | None:
        failure = getattr(self.ctrl, "failure", None)
        if failure:
            return "controller-singular", failure
        if self.delay > 0.0:
            self._remember_command(t, y)
            if len(self.hist_t) > 4096:
                keep = bisect.bisect_left(self.hist_t, t - 2.0 * self.delay - self.sc.dt_s)
                del self.hist_t[:keep], self.hist_u[:keep]
        return None

    def row(self, t: float, y: tuple[float, ...]) -> tuple[float, ...]:
        return (t, y[0], y[1], y[2], y[3], self.o_lam, self.o_mu, self.o_xbs, self.o_x2, self.o_ax, self.o_omdot,
                self.o_u, float(self.ctrl.phase), self.xbs_hat, *self.ctrl.reference(t))

    def _replayed(self) -> HybridRun | None:
        """The plant in the compiled loop without the estimator, then the estimator over the recorded samples
        (:class:`ReplayEstimator` or :func:`replay_updates`): the run, samples and estimates of the Python
        loop that interleaves them, cut where the estimator refuses a step.  ``None`` (run the Python loop)
        when the compiled loop raises: the interleaved run may stop at a refused step before that point."""
        est, self.estimator = self.estimator, None
        try:
            run = run_compiled(self, None, step_lengths=True)
        except SimulationError:
            return None
        finally:
            self.estimator = est
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
        self.observer_time_s = time.perf_counter() - t_obs
        status, steps, events = run.status, run.steps, run.events
        if refused is not None:
            # the interleaved loop records the refused step's sample and stops before its events
            t_stop = float(s["t"][refused])
            s = {k: v[:refused + 1] for k, v in s.items()}
            events = tuple(e for e in events if e[0] < t_stop)
            self.road.starts = [t for t in self.road.starts if t < t_stop]
            status, steps = "observer-failed", refused
        else:
            message = run.message
        s["xbs_hat"] = np.asarray(hat, dtype=float)
        return HybridRun(series=s, events=events, status=status, message=message, steps=steps,
                         wall_time_s=run.wall_time_s + self.observer_time_s)

    def run(self, compiled: bool | None) -> BrakingResult:
        sc = self.sc
        run: HybridRun | None = None
        if compiled is not False:
            obs, reason = compiled_support(self)
            # an estimator the controller does not read cannot change the plant's run: the plant runs
            # compiled and the estimator over its samples afterwards (module notes)
            replay = (reason is not None and self.estimator is not None and not self.use_hat
                      and compiled_support(self, estimator=False)[1] is None)
            if reason is not None and not replay and compiled:
                raise SimulationError(f"scenario {sc.name!r} cannot run in the compiled loop: {reason}")
            if (reason is None or replay) and (compiled or compiler_available()):
                check_run_size(self, sc.duration_s, sc.name)  # integrate() checks the Python loop's run
                run = self._replayed() if replay else run_compiled(self, obs)
        ran_compiled = run is not None
        if run is None:
            run = integrate(self, sc.duration_s, name=sc.name)
        est = self.estimator
        metrics = braking_metrics(run.series, sc, self.road.starts, status=run.status,
                                  have_estimate=est is not None)
        observer = "none" if est is None else (est.describe() if hasattr(est, "describe") else type(est).__name__)
        return BrakingResult(scenario=sc, status=run.status, message=run.message, series=run.series,
                             events=run.events, metrics=metrics, observer=observer, observer_in_loop=self.use_hat,
                             wall_time_s=run.wall_time_s, observer_time_s=self.observer_time_s, steps=run.steps,
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
        return plant.run(compiled)
    if x2_source is not None and not isinstance(x2_source, X2Measurement):
        raise SimulationError(f"the x2 source {x2_source!r} lacks reset(t0, y0, vx0) and "
                              f"update(t, y, vx, u, dt)")
    if estimator is not None and not isinstance(estimator, XbsEstimator):
        raise SimulationError(f"the estimator {estimator!r} lacks reset(t0, y0, vx0) and "
                              f"update(t, y, vx, u, dt)")
    return _QuarterCar(scenario, estimator, observer_in_loop, x2_source).run(compiled)
