"""One braking: its scenario, and the quarter car with its controller and estimator as a hybrid plant.

:class:`BrakingScenario` says what is simulated; :class:`_QuarterCar` is the plant of
:func:`switchobs.plants.simulate` (seed 001 eq. (2.1), seed 000 eqs. (1)-(3)) that
:func:`switchobs.plants.integrate` steps, or that :mod:`switchobs.plants._compiled` ports to C.  The
metrics (:mod:`switchobs.plants._metrics`), the compiled loop and the simulation (:mod:`switchobs.plants._simulate`)
all read these two, so they sit below them.
"""

from __future__ import annotations

import bisect
import math
import time
from dataclasses import dataclass, field, replace
from typing import Any

from ..exceptions import SimulationError
from ._controllers import ContinuousXbsControl, Controller, FivePhaseABS, SixPhaseABS, TwoPhaseABS
from ._estimator import X2Measurement, XbsEstimator
from ._json import controller_from_json, from_fields
from ._hybrid import Crossing, HybridPlant
from ._road import RoadSchedule, _RoadState
from ._tyre import Burckhardt
from ._vehicle import BrakeActuator, PrescribedSpeed, QuarterCar, check_speed

__all__ = ["BrakingScenario", "SERIES"]


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
