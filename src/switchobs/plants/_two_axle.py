"""Two-axle vehicle of seed 001 Sec. 3.6, at the level supported here.

Modelled: one front and one rear wheel, each standing for the two wheels of its
axle, with their own brake, ABS controller and (optionally) XBS observer; the
vertical loads follow the quasi-static load transfer (3.36)::

    Fzf = Wf - ΔFz a_x,    Fzr = Wr + ΔFz a_x,    ΔFz = M h / (2 L)

solved together with ``M a_x = 2 (Fzf mu_f + Fzr mu_r)``; the vehicle speed fed
to the controllers and observers is not the true one but the output of a
scalar Kalman filter driven by a biased accelerometer (turn-on bias 0.5 m/s²
plus a slow random walk) and corrected by the fastest wheel's ``R ω`` (the
approach of seed 001 Sec. 3.6, whose filter [19] is not specified further).
The measured wheel-acceleration offset is ``R dω/dt - a_x^meas``.

Not modelled (seed 001 simulates them with a full vehicle model [30]):
suspension and pitch dynamics (the load transfer is instantaneous), tyre
relaxation length, left/right differences, position-triggered road changes.
An estimator that reads the load (:class:`LoadInput`, e.g. the adaptive observer
with ``load_signal=True``) gets its wheel's load (3.36) computed with the
*measured* acceleration before each update, as seed 001 computes the observer's
``a`` on line; the others keep their static-load ``a``.

Integration as the quarter car's (:func:`switchobs.plants.integrate`),
with one controller per axle; the controllers take over at ``brake_start_s``.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from ..exceptions import SimulationError
from ._controllers import FivePhaseABS, SixPhaseABS, TwoPhaseABS
from ._estimator import LoadInput, XbsEstimator
from ._hybrid import Crossing, HybridPlant, integrate
from ._json import controller_from_json, from_fields, run_from_json
from ._metrics import _cumtrapz, distance_label, diverged
from ._road import RoadSchedule, _RoadState
from ._vehicle import GRAVITY, BrakeActuator, QuarterCar, check_speed

__all__ = ["TwoAxleVehicle", "Accelerometer", "TwoAxleScenario", "TwoAxleResult", "simulate_two_axle"]


def _positive(owner: str, **values: float) -> None:
    for key, value in values.items():
        if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value) or value <= 0:
            raise SimulationError(f"{owner}: {key} must be a finite number > 0, got {value!r}")


@dataclass(frozen=True)
class TwoAxleVehicle:
    """Mass, geometry and wheels of a two-axle passenger car (illustrative values).

    Parameters
    ----------
    mass_kg, wheelbase_m, cg_to_front_m, cg_height_m : float
        ``M``, ``L``, the distance from the centre of gravity to the front axle, ``h``.
    inertia_kg_m2, radius_m : float
        Wheel ``J`` and ``R``.
    brake_gain_front_nm_bar, brake_gain_rear_nm_bar : float
        ``γ_b`` of the front and rear brakes.
    """

    mass_kg: float = 1400.0
    wheelbase_m: float = 2.6
    cg_to_front_m: float = 1.1
    cg_height_m: float = 0.55
    inertia_kg_m2: float = 1.2
    radius_m: float = 0.3
    brake_gain_front_nm_bar: float = 17.5
    brake_gain_rear_nm_bar: float = 10.0

    def __post_init__(self) -> None:
        _positive("TwoAxleVehicle", **{k: v for k, v in asdict(self).items()})
        if self.cg_to_front_m >= self.wheelbase_m:
            raise SimulationError(f"TwoAxleVehicle: the centre of gravity ({self.cg_to_front_m} m behind the front "
                                  f"axle) must lie within the wheelbase {self.wheelbase_m} m")

    @property
    def static_loads(self) -> tuple[float, float]:
        """``(Wf, Wr)``: static load of one front and one rear wheel [N]."""
        w = self.mass_kg * GRAVITY / (2.0 * self.wheelbase_m)
        return (w * (self.wheelbase_m - self.cg_to_front_m), w * self.cg_to_front_m)

    @property
    def load_transfer(self) -> float:
        """``ΔFz = M h / (2 L)`` [N per m/s²] of (3.36), per wheel."""
        return self.mass_kg * self.cg_height_m / (2.0 * self.wheelbase_m)

    def loads(self, ax: float) -> tuple[float, float]:
        """Per-wheel vertical loads (3.36) at the longitudinal acceleration ``ax``."""
        wf, wr = self.static_loads
        dz = self.load_transfer
        return (wf - dz * ax, wr + dz * ax)

    def corner(self, axle: str) -> QuarterCar:
        """The quarter car of one wheel at its static load (gives ``a`` and ``b`` to controllers and observers)."""
        wf, wr = self.static_loads
        load, gain = (wf, self.brake_gain_front_nm_bar) if axle == "front" else (wr, self.brake_gain_rear_nm_bar)
        return QuarterCar(inertia_kg_m2=self.inertia_kg_m2, radius_m=self.radius_m, load_n=load,
                          brake_gain_nm_bar=gain, mass_kg=self.mass_kg / 4.0)

    def to_json(self) -> dict[str, Any]:
        return {**asdict(self), "static_loads_n": list(self.static_loads), "load_transfer_n_per_m_s2":
                self.load_transfer}

    @classmethod
    def from_json(cls, data: Any) -> TwoAxleVehicle:
        """The vehicle of :meth:`to_json` (the derived loads are not read).

        Raises
        ------
        SimulationError
            A missing key or a value the vehicle rejects.
        """
        return from_fields(cls, data, "two-axle vehicle")


@dataclass(frozen=True)
class Accelerometer:
    """Longitudinal accelerometer with a turn-on bias and a slow random-walk drift.

    ``a_meas(t) = a_x(t) + bias_m_s2 + w(t)``, ``w`` a random walk of intensity
    ``drift_m_s2_per_sqrt_s`` sampled every 10 ms and interpolated linearly
    (reproducible through ``seed``).  Seed 001 Sec. 3.6: "an additive dynamic
    bias with a turn-on component of 0.5 m/s²".
    """

    bias_m_s2: float = 0.5
    drift_m_s2_per_sqrt_s: float = 0.02
    seed: int = 0

    def __post_init__(self) -> None:
        for key in ("bias_m_s2", "drift_m_s2_per_sqrt_s"):
            value = getattr(self, key)
            if not isinstance(value, (int, float)) or not math.isfinite(value):
                raise SimulationError(f"Accelerometer: {key} must be a finite number, got {value!r}")
        if self.drift_m_s2_per_sqrt_s < 0:
            raise SimulationError(f"Accelerometer: drift must be >= 0, got {self.drift_m_s2_per_sqrt_s}")

    def bias_profile(self, duration_s: float) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        grid = np.arange(0.0, duration_s + 0.02, 0.01)
        rng = np.random.default_rng(self.seed)
        steps = rng.normal(0.0, self.drift_m_s2_per_sqrt_s * math.sqrt(0.01), len(grid))
        steps[0] = 0.0
        return grid, self.bias_m_s2 + np.cumsum(steps)


@dataclass(frozen=True)
class TwoAxleScenario:
    """A straight-line braking of the two-axle vehicle (seed 001 Sec. 3.6).

    Parameters
    ----------
    roads : RoadSchedule or str
        Time-triggered changes only (both axles change together).
    speed_m_s : float
    front, rear : controllers
        One per axle (default: :class:`FivePhaseABS` with the stall timeout of the scenarios).
    vehicle, actuator, accelerometer
    brake_start_s : float
        The driver starts braking (seed: 0.25 s).
    speed_filter_q, speed_filter_r : float
        Kalman filter intensities: accelerometer noise [(m/s²)² s] and wheel-speed noise [(m/s)²].
    duration_s, stop_speed_m_s, dt_s, low_speed_m_s : float
        As in :class:`BrakingScenario` (the seed stops at 15 km/h).
    name : str
    speed_from_filter : bool
        ``False``: the controllers and observers read the true speed instead of the filter's (with an
        ideal accelerometer, ``Accelerometer(0, 0)``, the "true signals" run of seed 001 Fig. 3.18).
    """

    roads: RoadSchedule
    speed_m_s: float
    front: FivePhaseABS | SixPhaseABS | TwoPhaseABS = field(default_factory=FivePhaseABS)
    rear: FivePhaseABS | SixPhaseABS | TwoPhaseABS = field(default_factory=FivePhaseABS)
    vehicle: TwoAxleVehicle = field(default_factory=TwoAxleVehicle)
    actuator: BrakeActuator = field(default_factory=BrakeActuator)
    accelerometer: Accelerometer = field(default_factory=Accelerometer)
    brake_start_s: float = 0.25
    speed_filter_q: float = 0.5
    speed_filter_r: float = 0.05
    duration_s: float = 30.0
    stop_speed_m_s: float = 15.0 / 3.6
    dt_s: float = 1e-3
    low_speed_m_s: float = 5.0
    name: str = "two-axle"
    speed_from_filter: bool = True

    def __post_init__(self) -> None:
        if isinstance(self.roads, str):
            object.__setattr__(self, "roads", RoadSchedule(self.roads))
        if not isinstance(self.roads, RoadSchedule):
            raise SimulationError(f"roads must be a RoadSchedule or a road name, got {self.roads!r}")
        if any(c.at_time_s is None for c in self.roads.changes):
            raise SimulationError("the two-axle vehicle supports road changes at given times only "
                                  "(at_position_m would reach the two axles at different times)")
        for ctrl in (self.front, self.rear):
            if not isinstance(ctrl, (FivePhaseABS, SixPhaseABS, TwoPhaseABS)):
                raise SimulationError(f"two-axle controllers must be FivePhaseABS, SixPhaseABS or TwoPhaseABS, "
                                      f"got {ctrl!r}")
        _positive(f"scenario {self.name!r}", speed_m_s=self.speed_m_s, duration_s=self.duration_s,
                  stop_speed_m_s=self.stop_speed_m_s, dt_s=self.dt_s, speed_filter_q=self.speed_filter_q,
                  speed_filter_r=self.speed_filter_r, low_speed_m_s=self.low_speed_m_s)
        check_speed(f"scenario {self.name!r}", self.speed_m_s)
        if not (isinstance(self.brake_start_s, (int, float)) and 0 <= self.brake_start_s < self.duration_s):
            raise SimulationError(f"brake_start_s must lie in [0, duration_s), got {self.brake_start_s!r}")
        if self.stop_speed_m_s >= self.speed_m_s:
            raise SimulationError(f"the stop speed {self.stop_speed_m_s:g} m/s must be below the initial speed "
                                  f"{self.speed_m_s:g} m/s")
        if self.dt_s > 0.01:
            raise SimulationError(f"dt_s = {self.dt_s} s is too coarse; use at most 0.01 s")
        if self.actuator.delay_s > 0:
            raise SimulationError("the two-axle simulation has no actuator delay; use delay_s = 0")

    def to_json(self) -> dict[str, Any]:
        return {"name": self.name, "roads": self.roads.to_json(), "speed_m_s": self.speed_m_s,
                "front": self.front.to_json(), "rear": self.rear.to_json(), "vehicle": self.vehicle.to_json(),
                "actuator": self.actuator.to_json(), "accelerometer": asdict(self.accelerometer),
                "brake_start_s": self.brake_start_s, "speed_filter_q": self.speed_filter_q,
                "speed_filter_r": self.speed_filter_r, "duration_s": self.duration_s,
                "stop_speed_m_s": self.stop_speed_m_s, "dt_s": self.dt_s, "low_speed_m_s": self.low_speed_m_s,
                "speed_from_filter": self.speed_from_filter}

    @classmethod
    def from_json(cls, data: Any) -> TwoAxleScenario:
        """The scenario of :meth:`to_json` (roads by name, the controllers by their ``name``).

        Raises
        ------
        SimulationError
            A missing key, an unknown controller or road, or a value the scenario rejects.
        """
        if not isinstance(data, dict):
            raise SimulationError(f"a two-axle scenario JSON must be an object, got {data!r}")
        return from_fields(cls, data, "two-axle scenario", roads=RoadSchedule.from_json(data.get("roads")),
                           front=controller_from_json(data.get("front"), "a two-axle scenario JSON (front)"),
                           rear=controller_from_json(data.get("rear"), "a two-axle scenario JSON (rear)"),
                           vehicle=TwoAxleVehicle.from_json(data.get("vehicle")),
                           actuator=from_fields(BrakeActuator, data.get("actuator"), "actuator"),
                           accelerometer=from_fields(Accelerometer, data.get("accelerometer"), "accelerometer"))

    def __str__(self) -> str:
        return (f"two-axle scenario {self.name}: {self.roads}, {self.speed_m_s * 3.6:.0f} km/h, "
                f"front {self.front.name}, rear {self.rear.name}, speed from a Kalman filter "
                f"(accelerometer bias {self.accelerometer.bias_m_s2:g} m/s²)")


#: Columns of :attr:`TwoAxleResult.series`.
TWO_AXLE_SERIES = ("t", "vx", "vx_hat", "ax", "ax_meas", "x", "omega_f", "omega_r", "lambda_f", "lambda_r",
                   "x2_f", "x2_r", "xbs_f", "xbs_r", "xbs_hat_f", "xbs_hat_r", "P_f", "P_r", "Fz_f", "Fz_r",
                   "phase_f", "phase_r", "x2_ref_f", "x2_ref_r")


@dataclass(frozen=True)
class TwoAxleResult:
    """Time histories and figures of a two-axle braking.

    Metrics (``metrics`` dict): ``stopping_distance_m``, ``stop_time_s``,
    ``mean_deceleration_m_s2``, ``speed_error_mean_pct`` (mean of
    ``(vx_hat - vx)/vx`` over the braking, in %; seed 001 reports -18 %),
    ``speed_error_max_pct``, per axle: ``load_min_n``/``load_max_n``,
    ``slip_mean`` (``None`` before the ABS takes over), ``abs_cycles``, ``xbs_rms_error`` (after braking starts),
    ``observer_failure`` (``None`` or when and why the observer refused a step;
    the run then stops with status ``observer-failed``, as the quarter car's does).

    ``status`` is ``stopped``, ``duration`` or ``observer-failed``; ``message`` details it.
    """

    scenario: TwoAxleScenario
    status: str
    message: str
    series: dict[str, npt.NDArray[np.float64]]
    events: tuple[tuple[float, str], ...]
    metrics: dict[str, Any]
    wall_time_s: float
    steps: int

    @property
    def failure(self) -> str | None:
        """Why the run failed, or ``None`` (as :attr:`BrakingResult.failure`, per axle)."""
        if self.status == "observer-failed":
            return f"{self.status}: {self.message}"
        for axle in ("front", "rear"):
            why = diverged(self.series[f"xbs_hat_{axle[0]}"], self.metrics[axle]["xbs_rms_error"],
                           f"the {axle} observer")
            if why is not None:
                return why
        return None

    def to_json(self, *, include_series: bool = False) -> dict[str, Any]:
        out = {"scenario": self.scenario.to_json(), "status": self.status, "message": self.message,
               "failure": self.failure,
               "metrics": self.metrics,
               "events": [{"t": t, "event": e} for t, e in self.events],
               "cost": {"steps": self.steps, "wall_time_s": self.wall_time_s}}
        if include_series:
            out["series"] = {k: [None if math.isnan(v) else float(v) for v in a] for k, a in self.series.items()}
        return out

    @classmethod
    def from_json(cls, data: Any) -> TwoAxleResult:
        """The result of ``to_json(include_series=True)``: the series as float arrays (``null`` as NaN).

        The series are NumPy arrays, so compare two results by their
        ``to_json(include_series=True)`` (scenario, metrics and events compare with ``==``).

        Raises
        ------
        SimulationError
            No ``series``, a missing key or a malformed part; the message names it.
        """
        series, events = run_from_json(data, "two-axle result")
        try:
            cost = data["cost"]
            return cls(TwoAxleScenario.from_json(data["scenario"]), str(data["status"]), str(data["message"]),
                       series, events, dict(data["metrics"]), float(cost["wall_time_s"]), int(cost["steps"]))
        except (KeyError, TypeError, ValueError) as exc:
            if isinstance(exc, SimulationError):
                raise
            raise SimulationError(f"not a two-axle result JSON ({type(exc).__name__}: {exc})") from None

    @property
    def _status_text(self) -> str:
        return self.status + (f" ({self.message})" if self.status == "observer-failed" else "")

    @property
    def _distance_text(self) -> str:
        """The distance metric under the name it deserves: a run that did not stop only travelled it."""
        what = distance_label(self.status == "stopped")
        return f"{what} {self.metrics['stopping_distance_m']:.2f} m"

    def _repr_markdown_(self) -> str:
        """The run in a notebook: status, the vehicle figures and one row per axle."""
        m = self.metrics
        lines = [f"**Two-axle braking**: {self.scenario}", "",
                 f"status: **{self._status_text}**; {self._distance_text}, mean deceleration "
                 f"{m['mean_deceleration_m_s2']:.2f} m/s²; speed estimate error "
                 f"$(\\hat v_x - v_x)/v_x$: mean {m['speed_error_mean_pct']:.1f} %, worst "
                 f"{m['speed_error_max_pct']:.1f} %", "",
                 "| axle | load $F_z$ [N] | ABS cycles | mean slip $\\lambda$ | XBS RMS error |", "|---|---|---:|---:|---:|"]
        for axle in ("front", "rear"):
            a = m[axle]
            xbs = "–" if a["xbs_rms_error"] is None else f"{a['xbs_rms_error']:.3g}"
            if a["observer_failure"]:
                xbs += f" (observer failed at {a['observer_failure'].split(':')[0]})"
            lines.append(f"| {axle} | {a['load_min_n']:.0f}–{a['load_max_n']:.0f} | {a['abs_cycles']} | "
                         f"{_slip_text(a['slip_mean'])} | {xbs} |")
        lines += ["", f"series (NumPy, `result.series[...]`): {', '.join(f'`{k}`' for k in self.series)}"]
        return "\n".join(lines)

    def __str__(self) -> str:
        m = self.metrics
        lines = [str(self.scenario), f"  status: {self._status_text}; {self._distance_text},"
                 f" mean deceleration {m['mean_deceleration_m_s2']:.2f} m/s²",
                 f"  speed estimate error: mean {m['speed_error_mean_pct']:.1f} %, worst "
                 f"{m['speed_error_max_pct']:.1f} %"]
        for axle in ("front", "rear"):
            a = m[axle]
            xbs = "" if a["xbs_rms_error"] is None else f", XBS RMS error {a['xbs_rms_error']:.3g}"
            if a["observer_failure"]:
                xbs += f", observer failed at {a['observer_failure'].split(':')[0]}"
            lines.append(f"  {axle}: load {a['load_min_n']:.0f}-{a['load_max_n']:.0f} N, {a['abs_cycles']} cycles, "
                         f"mean slip {_slip_text(a['slip_mean'])}{xbs}")
        lines.append(f"  cost: {self.steps} steps, {self.wall_time_s:.3f} s wall")
        return "\n".join(lines)


def _slip_text(slip: float | None) -> str:
    """The mean slip of an axle, or a dash when its ABS never took over (a run stopped during the build-up)."""
    return "–" if slip is None else f"{slip:.3f}"


def simulate_two_axle(scenario: TwoAxleScenario, *,
                      estimators: tuple[XbsEstimator | None, XbsEstimator | None] = (None, None),
                      observer_in_loop: bool = True) -> TwoAxleResult:
    """Simulate a straight-line braking of the two-axle vehicle (seed 001 Sec. 3.6).

    Parameters
    ----------
    scenario : TwoAxleScenario
    estimators : (front, rear)
        XBS observers fed with the measured ``x2`` of their wheel, the
        estimated speed and the wheel's pressure rate; one that is a :class:`LoadInput` also with the
        wheel's load (3.36) from the measured acceleration.
    observer_in_loop : bool
        Two-phase controllers read the estimate (else the true XBS).

    Returns
    -------
    TwoAxleResult
    """
    if not isinstance(scenario, TwoAxleScenario):
        raise SimulationError(f"simulate_two_axle() needs a TwoAxleScenario, got {type(scenario).__name__}")
    return _TwoAxle(scenario, estimators, observer_in_loop).run()


class _TwoAxle(HybridPlant):
    """The two-axle vehicle with its two controllers, speed filter and estimators as a :class:`HybridPlant`."""

    states = ("omega_f", "omega_r", "vx", "x", "P_f", "P_r")
    series = TWO_AXLE_SERIES
    labels = ("front ", "rear ")
    discrete_feedback = True          # the filtered speed vx_hat feeds the controllers

    def __init__(self, sc: TwoAxleScenario, estimators: tuple[XbsEstimator | None, XbsEstimator | None],
                 in_loop: bool):
        if len(estimators) != 2:
            raise SimulationError(f"give one estimator (or None) per axle, got {len(estimators)}")
        for est in estimators:
            if est is not None and not isinstance(est, XbsEstimator):
                raise SimulationError(f"the estimator {est!r} lacks reset(t0, y0, vx0) and update(t, y, vx, u, dt)")
        veh = sc.vehicle
        self.sc = sc
        self.R, self.J = veh.radius_m, veh.inertia_kg_m2
        self.gains = (veh.brake_gain_front_nm_bar, veh.brake_gain_rear_nm_bar)
        self.W = veh.static_loads
        self.dz = veh.load_transfer
        self.M = veh.mass_kg
        self.road = _RoadState(sc.roads)
        self.automata = (sc.front.runtime(veh.corner("front"), sc.actuator),
                         sc.rear.runtime(veh.corner("rear"), sc.actuator))
        self.est = estimators
        self.load_fed = tuple(isinstance(e, LoadInput) for e in estimators)
        self.use_hat = tuple(bool(e is not None and in_loop and c.uses_xbs) for e, c in zip(estimators,
                                                                                          (sc.front, sc.rear)))
        self.hat = [math.nan, math.nan]
        self.failed: list[str | None] = [None, None]
        self.vx_hat = sc.speed_m_s
        self.p_var = sc.speed_filter_r
        self.p_prev = [0.0, 0.0]
        self.bias_t, self.bias_v = sc.accelerometer.bias_profile(sc.duration_s)
        self.max_rate, self.p_max = sc.actuator.max_rate_bar_s, sc.actuator.max_pressure_bar
        # outputs of the last rhs evaluation, per wheel (front, rear) where they are two
        self.braking = False
        self.lam = self.mu = self.xbs = self.fz = self.x2 = self.slip_ref = (0.0, 0.0)
        self.ax = self.ax_meas = 0.0

    def bias(self, t: float) -> float:
        return float(np.interp(t, self.bias_t, self.bias_v))

    def initial_state(self) -> tuple[float, ...]:
        v0 = self.sc.speed_m_s
        return (v0 / self.R, v0 / self.R, v0, 0.0, 0.0, 0.0)

    def rhs(self, t: float, y: tuple[float, ...]) -> tuple[float, ...]:
        omf, omr, vx, _x, pf, pr = y
        R = self.R
        lf, lr = (R * omf - vx) / vx, (R * omr - vx) / vx
        muf, xf = self.road.eval(lf, t)
        mur, xr = self.road.eval(lr, t)
        wf, wr = self.W
        ax = 2.0 * (wf * muf + wr * mur) / (self.M + 2.0 * self.dz * (muf - mur))
        fzf, fzr = wf - self.dz * ax, wr + self.dz * ax
        dof = (-R * fzf * muf - self.gains[0] * pf) / self.J
        dor = (-R * fzr * mur - self.gains[1] * pr) / self.J
        if omf <= 0.0 and dof < 0.0:
            dof = 0.0
        if omr <= 0.0 and dor < 0.0:
            dor = 0.0
        ax_meas = ax + self.bias(t)
        x2f, x2r = R * dof - ax_meas, R * dor - ax_meas
        self.braking = t >= self.sc.brake_start_s
        rates = []
        for k, (ctrl, x2, om, p, xbs) in enumerate(((self.automata[0], x2f, omf, pf, xf),
                                                    (self.automata[1], x2r, omr, pr, xr))):
            if not self.braking:
                u = 0.0
            else:
                u = ctrl.rate(t, x2, R * om, self.vx_hat, self.hat[k] if self.use_hat[k] else xbs)
                u = min(max(u, -self.max_rate), self.max_rate)
                if (p <= 0.0 and u < 0.0) or (p >= self.p_max and u > 0.0):
                    u = 0.0
            rates.append(u)
        self.lam, self.mu, self.xbs, self.fz, self.x2 = (lf, lr), (muf, mur), (xf, xr), (fzf, fzr), (x2f, x2r)
        # the slip the controllers see: against the estimated speed (the seed's reference speed vRef)
        vh = self.vx_hat
        self.slip_ref = ((R * omf - vh) / vh, (R * omr - vh) / vh)
        self.ax, self.ax_meas = ax, ax_meas
        return (dof, dor, ax, vx, rates[0], rates[1])

    def clamp(self, y: tuple[float, ...]) -> tuple[float, ...]:
        omf, omr, vx, x, pf, pr = y
        if omf < 0.0 or omr < 0.0 or not (0.0 <= pf <= self.p_max and 0.0 <= pr <= self.p_max):
            return (max(omf, 0.0), max(omr, 0.0), vx, x, min(max(pf, 0.0), self.p_max),
                    min(max(pr, 0.0), self.p_max))
        return y

    def step_size(self, t: float, y: tuple[float, ...]) -> float:
        sc = self.sc
        return sc.dt_s if y[2] >= sc.low_speed_m_s else sc.dt_s * y[2] / sc.low_speed_m_s

    def breakpoint(self, t: float) -> float:
        tb = self.road.breakpoint()
        for c in self.automata:
            kink = c.breakpoint()
            if kink > t + 1e-12:
                tb = min(tb, kink)
        if t < self.sc.brake_start_s:
            tb = min(tb, self.sc.brake_start_s)
        return tb

    def start(self, t: float, y: tuple[float, ...]) -> bool:
        for k, est in enumerate(self.est):
            if est is not None:
                self.feed_load(k)
                est.reset(t, self.x2[k], self.vx_hat)
        return False

    def feed_load(self, k: int) -> None:
        """Give estimator ``k`` its wheel's load (3.36) computed with the measured acceleration, if it reads one."""
        if self.load_fed[k]:
            self.est[k].set_load(self.sc.vehicle.loads(self.ax_meas)[k])

    def after_step(self, t: float, y: tuple[float, ...], h: float) -> str | None:
        sc = self.sc
        if sc.speed_from_filter:
            # speed estimate: predict with the biased accelerometer, correct with the fastest wheel
            self.vx_hat += h * self.ax_meas
            self.p_var += sc.speed_filter_q * h
            gain = self.p_var / (self.p_var + sc.speed_filter_r)
            self.vx_hat += gain * (self.R * max(y[0], y[1]) - self.vx_hat)
            self.p_var *= 1.0 - gain
        else:
            self.vx_hat = y[2]
        failure = None
        for k, est in enumerate(self.est):
            pressure = y[4 + k]
            u, self.p_prev[k] = (pressure - self.p_prev[k]) / h, pressure
            if est is not None and failure is None:
                try:
                    self.feed_load(k)
                    self.hat[k] = est.update(t, self.x2[k], self.vx_hat, u, h)
                except SimulationError as exc:    # e.g. ObserverInputError: the run stops (integrate's rule)
                    self.failed[k] = f"t = {t:.4f} s: {exc}"
                    failure = f"{self.labels[k]}observer: {exc}"
        return failure

    def crossings(self, t: float, y: tuple[float, ...], y1: tuple[float, ...]) -> list[Crossing]:
        v_stop = self.sc.stop_speed_m_s
        if y1[2] > v_stop:
            return []
        return [Crossing("stop", lambda tt, yy: v_stop - yy[2], v_stop - y[2], v_stop - y1[2], terminal=True,
                         text=f"vx reached {v_stop:.3f} m/s")]

    def at_breakpoint(self, t: float, y: tuple[float, ...]) -> tuple[bool, list[str]]:
        return self.road.at_breakpoint(t)

    def guard_values(self, k: int) -> tuple[float, ...]:
        if not self.braking:          # the controllers take over when the driver brakes
            return ()
        return self.automata[k].guards(self.x2[k], self.hat[k] if self.use_hat[k] else self.xbs[k],
                                       self.slip_ref[k])

    def locatable(self, k: int) -> bool:
        return not (self.use_hat[k] and self.automata[k].guards_use_xbs)

    def transition_args(self, k: int, y: tuple[float, ...]) -> tuple[float, float, float]:
        return (self.x2[k], self.R * y[k], self.vx_hat)

    def row(self, t: float, y: tuple[float, ...]) -> tuple[float, ...]:
        ref_f, ref_r = self.automata[0].reference(t)[0], self.automata[1].reference(t)[0]
        return (t, y[2], self.vx_hat, self.ax, self.ax_meas, y[3], y[0], y[1], *self.lam, *self.x2, *self.xbs,
                *self.hat, y[4], y[5], *self.fz, float(self.automata[0].phase), float(self.automata[1].phase),
                ref_f, ref_r)

    def run(self) -> TwoAxleResult:
        sc = self.sc
        run = integrate(self, sc.duration_s, name=sc.name)
        return TwoAxleResult(scenario=sc, status=run.status, message=run.message, series=run.series,
                             events=run.events, metrics=_metrics(run.series, sc, run.status, self.est, self.failed),
                             wall_time_s=run.wall_time_s, steps=run.steps)


def _metrics(s: dict[str, npt.NDArray[np.float64]], sc: TwoAxleScenario, status: str,
             estimators: tuple[XbsEstimator | None, XbsEstimator | None],
             failed: list[str | None]) -> dict[str, Any]:
    t = s["t"]
    braking = t >= sc.brake_start_s
    tb = t[braking]
    rel = (s["vx_hat"] - s["vx"]) / s["vx"]
    span = float(tb[-1] - tb[0]) if len(tb) > 1 else 0.0
    out: dict[str, Any] = {
        "stopping_distance_m": float(s["x"][-1]), "stop_time_s": float(t[-1]) if status == "stopped" else None,
        "mean_deceleration_m_s2": float(-_cumtrapz(tb, s["ax"][braking])[-1] / span) if span > 0 else 0.0,
        "speed_error_mean_pct": float(100 * np.mean(rel[braking])),
        "speed_error_max_pct": float(100 * rel[braking][np.argmax(np.abs(rel[braking]))]),
    }
    for k, axle in enumerate(("front", "rear")):
        sfx = "_f" if k == 0 else "_r"
        phase = s["phase" + sfx]
        err = None
        if estimators[k] is not None:
            e = (s["xbs_hat" + sfx] - s["xbs" + sfx])[braking]
            err = float(np.sqrt(np.nanmean(e ** 2))) if np.any(np.isfinite(e)) else None
        out[axle] = {"load_min_n": float(np.min(s["Fz" + sfx])), "load_max_n": float(np.max(s["Fz" + sfx])),
                     "slip_mean": float(np.mean(s["lambda" + sfx][phase >= 1])) if np.any(phase >= 1) else None,
                     "abs_cycles": int(np.count_nonzero((phase[1:] == 1) & (phase[:-1] != 1))),
                     "xbs_rms_error": err, "observer_failure": failed[k]}
    return out
