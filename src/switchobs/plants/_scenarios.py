"""Built-in braking scenarios of the seeds and the Table 4.1 campaign of seed 001.

The seeds give the road sequences and a few speeds but not every setting; the
choices made here are listed in each scenario's ``description`` and in
``docs/abs.md``.  Seed 000 Figs. 3-4 and seed 001 Sec. 3.4 last longer than a
free quarter car on dry asphalt needs to stop (about 2.3 s from 25 m/s), so
they impose the vehicle speed (drum test rig) with the 1.96 m/s² deceleration
stated in seed 001 Sec. 3.4.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

from .._papers import cite
from .._progress import progress
from ..exceptions import SimulationError
from ._controllers import FivePhaseABS, SixPhaseABS, TwoPhaseABS
from ._estimator import XbsEstimator
from ._json import from_fields
from ._road import RoadChange, RoadSchedule
from ._simulate import BrakingResult, BrakingScenario, simulate
from ._two_axle import TwoAxleScenario
from ._vehicle import PrescribedSpeed, QuarterCar

__all__ = ["SCENARIOS", "TWO_AXLE_SCENARIOS", "aguado_sec36", "scenario", "scenario_names", "scenario_observer",
           "scenario_observer_gains", "scenario_description", "TABLE41_SEED", "TABLE41_ROADS", "TABLE41_SPEEDS_KMH",
           "Table41Row", "Table41Result", "table41"]

#: Transition length of the road changes (seed 000 Sec. IV-D: "transitions, (which last 25 ms)").
TRANSITION_S = 0.025


@dataclass(frozen=True)
class _Spec:
    description: str
    build: Callable[[], BrakingScenario | TwoAxleScenario]
    observer: str            # default --observer of the CLI
    gains: Mapping[str, float] = field(default_factory=dict)   # its beta / gamma where not the observer's defaults


def _hoang_fig3() -> BrakingScenario:
    roads = RoadSchedule("hoang-dry", [RoadChange("hoang-wet", at_time_s=3.0, duration_s=TRANSITION_S)])
    return BrakingScenario(roads, speed_m_s=25.0, name="hoang-fig3", vehicle=QuarterCar.hoang2014(),
                           controller=FivePhaseABS(),
                           speed_profile=PrescribedSpeed(1.96), duration_s=6.0)


def _hoang_fig4() -> BrakingScenario:
    roads = RoadSchedule("hoang-dry", [RoadChange("hoang-wet", at_time_s=3.0, duration_s=TRANSITION_S),
                                       RoadChange("hoang-snow", at_time_s=4.0, duration_s=TRANSITION_S)])
    return BrakingScenario(roads, speed_m_s=25.0, name="hoang-fig4", vehicle=QuarterCar.hoang2014(),
                           controller=FivePhaseABS(tracking=True),
                           speed_profile=PrescribedSpeed(1.96), duration_s=7.0)


def _aguado_sec34() -> BrakingScenario:
    roads = RoadSchedule("dry-asphalt", [RoadChange("wet-asphalt", at_time_s=3.0, duration_s=TRANSITION_S),
                                         RoadChange("dry-concrete", at_time_s=6.0, duration_s=TRANSITION_S)])
    return BrakingScenario(roads, speed_m_s=25.0, name="aguado-sec34",
                           controller=FivePhaseABS(),
                           speed_profile=PrescribedSpeed(1.96), duration_s=10.0)


SCENARIOS: dict[str, _Spec] = {
    "hoang-fig3": _Spec("seed 000 Fig. 3: dry road for 3 s then wet road (Table I), 25 ms transition; "
                        "rig of Fig. 2 (Fz = 2500 N), drum at 25 m/s - 1.96 m/s² t; five-phase ABS; "
                        "4D observer of Sec. IV", _hoang_fig3, "xbs4"),
    "hoang-fig4": _Spec("seed 000 Fig. 4: dry 3 s, wet 1 s, then snow (Table I); five-phase ABS with "
                        "wheel-acceleration tracking (21)-(22) in phases 1, 3, 4 fed by the 4D observer",
                        _hoang_fig4, "xbs4"),
    "aguado-sec34": _Spec("seed 001 Sec. 3.4: 25 m/s with a constant deceleration of 1.96 m/s², dry asphalt, "
                          "wet asphalt at 3 s, dry concrete at 6 s (Table 2.1); five-phase ABS; switched "
                          "adaptive observer (3.4) with beta = 150, Gamma = 1e4 I (chosen by us: the seed gives "
                          "none; docs/reproductions.md, Sec. 3.4)", _aguado_sec34, "adaptive",
                          {"beta": 150.0, "gamma": 1e4}),
}


def aguado_sec36(controller: str = "six-phase") -> TwoAxleScenario:
    """Seed 001 Sec. 3.6: two-axle vehicle from 180 km/h, braking from 0.25 s, dry asphalt -> snow at 2.5 s
    -> wet asphalt at 5 s, until 15 km/h.

    Parameters
    ----------
    controller : {"six-phase", "five-phase"}
        The ABS of both axles: the seed's six-phase algorithm, which we take to be the Bosch cycle of
        its Sec. 2.2.3 (:class:`SixPhaseABS`), or our five-phase ABS (the scenario before the six-phase
        one existed).  The rear thresholds are scaled by 0.6 because the rear wheel, unloaded by the
        load transfer and with a weaker brake, sees smaller wheel accelerations.  The six-phase ABS builds
        the pressure up at 270 bar/s, the driver's rate at which it takes over at about the seed's times
        (0.75 s front, 0.50 s rear: ours 0.74 s and 0.52 s).

    Raises
    ------
    SimulationError
        For another controller name.
    """
    roads = RoadSchedule("dry-asphalt", [RoadChange("snow", at_time_s=2.5, duration_s=TRANSITION_S),
                                         RoadChange("wet-asphalt", at_time_s=5.0, duration_s=TRANSITION_S)])
    if controller == "six-phase":
        six = SixPhaseABS(initial_rate_bar_s=270.0)
        front, rear = six, replace(six, a_minus=0.6 * six.a_minus, a_plus=0.6 * six.a_plus, a_big=0.6 * six.a_big)
    elif controller == "five-phase":
        five = FivePhaseABS()
        front, rear = five, replace(five, eps=tuple(0.6 * e for e in five.eps))
    else:
        raise SimulationError(f"aguado_sec36(): controller must be 'six-phase' or 'five-phase', got {controller!r}")
    return TwoAxleScenario(roads, speed_m_s=50.0, front=front, rear=rear, name="aguado-sec36")


#: Two-axle scenarios (run by :func:`switchobs.plants.simulate_two_axle`).
TWO_AXLE_SCENARIOS: dict[str, _Spec] = {
    "aguado-sec36": _Spec("seed 001 Sec. 3.6: two-axle vehicle from 180 km/h, dry asphalt -> snow at 2.5 s -> wet "
                          "asphalt at 5 s, stop at 15 km/h; load transfer (3.36), speed from a Kalman filter with a "
                          "0.5 m/s² accelerometer bias; six-phase (Bosch) ABS on each axle (or five-phase); switched "
                          "adaptive observer (3.4) per wheel with its load from (3.36) on line, Gamma = 5000 I (chosen "
                          "by us: the default 1e4 I diverges at the 1 ms step; docs/reproductions.md, Sec. 3.6)",
                          aguado_sec36, "adaptive", {"gamma": 5e3})}


def _spec(name: str) -> _Spec:
    """The built-in scenario ``name``, quarter car or two axles (``table41`` and unknown names refused)."""
    if name in TWO_AXLE_SCENARIOS:
        return TWO_AXLE_SCENARIOS[name]
    scenario(name)
    return SCENARIOS[name]


def scenario_observer(name: str) -> str:
    """The observer a built-in scenario uses by default (``xbs4`` or ``adaptive``)."""
    return _spec(name).observer


def scenario_observer_gains(name: str) -> dict[str, float]:
    """The observer gains a built-in scenario uses by default (``beta``, ``gamma``); the observer's own
    defaults (:data:`switchobs.loop.DEFAULT_BETA`, :data:`switchobs.loop.DEFAULT_GAMMA`, an empty mapping) for
    the others and for ``table41``.

    The seed gives no gains: ``aguado-sec34`` uses the ones of ``docs/reproductions.md`` (Sec. 3.4), where the
    seed's ordering of the observers holds, ``aguado-sec36`` the adaptation gain that stays stable at the
    1 ms step (Sec. 3.6).

    Examples
    --------
    >>> scenario_observer_gains("aguado-sec34")
    {'beta': 150.0, 'gamma': 10000.0}
    >>> scenario_observer_gains("aguado-sec36")
    {'gamma': 5000.0}
    >>> scenario_observer_gains("hoang-fig3")
    {}
    """
    return {} if name == "table41" else dict(_spec(name).gains)


def scenario_description(name: str) -> str:
    """What a built-in scenario reproduces and the settings chosen for it (the papers by author and year)."""
    return cite(_spec(name).description)


def scenario_names() -> tuple[str, ...]:
    """Built-in scenarios: :func:`scenario` builds the quarter-car ones, ``aguado-sec36`` is the two-axle
    vehicle (:func:`aguado_sec36`), ``table41`` is run by :func:`table41`."""
    return (*SCENARIOS, *TWO_AXLE_SCENARIOS, "table41")


def scenario(name: str) -> BrakingScenario:
    """A built-in scenario by name.

    Raises
    ------
    SimulationError
        For an unknown name; the message lists the known ones.
    """
    spec = SCENARIOS.get(name)
    if name in TWO_AXLE_SCENARIOS or name == "table41":
        raise SimulationError(f"{name!r} is not a quarter-car scenario; use "
                              f"{'aguado_sec36()' if name != 'table41' else 'table41()'}")
    if spec is None:
        raise SimulationError(f"unknown scenario {name!r}; known: {', '.join(scenario_names())}")
    return spec.build()


#: The roads and speeds of seed 001 Table 4.1.
TABLE41_ROADS = ("dry-asphalt", "wet-asphalt", "dry-concrete", "dry-cobblestones", "wet-cobblestones")
TABLE41_SPEEDS_KMH = (60.0, 120.0, 180.0)
#: Seed 001 Table 4.1: braking distance [m] (five-phase, two-phase) per (speed, road).
TABLE41_SEED: dict[tuple[float, str], tuple[float, float]] = {
    (60.0, "dry-asphalt"): (12.31, 12.18), (60.0, "wet-asphalt"): (18.09, 17.86),
    (60.0, "dry-concrete"): (13.24, 13.08), (60.0, "dry-cobblestones"): (14.34, 14.28),
    (60.0, "wet-cobblestones"): (38.46, 38.30),
    (120.0, "dry-asphalt"): (49.27, 48.78), (120.0, "wet-asphalt"): (72.38, 71.58),
    (120.0, "dry-concrete"): (52.97, 52.40), (120.0, "dry-cobblestones"): (57.34, 57.11),
    (120.0, "wet-cobblestones"): (153.88, 153.41),
    (180.0, "dry-asphalt"): (110.87, 109.90), (180.0, "wet-asphalt"): (162.88, 161.37),
    (180.0, "dry-concrete"): (119.27, 118.10), (180.0, "dry-cobblestones"): (129.01, 128.51),
    (180.0, "wet-cobblestones"): (346.08, 345.57),
}


@dataclass(frozen=True)
class Table41Row:
    """One cell pair of Table 4.1: our braking distances beside the seed's."""

    speed_kmh: float
    road: str
    five_phase_m: float
    two_phase_m: float
    seed_five_phase_m: float | None
    seed_two_phase_m: float | None
    five_phase_stopping_m: float
    two_phase_stopping_m: float
    five_phase_status: str = "stopped"
    two_phase_status: str = "stopped"

    @property
    def difference_m(self) -> float:
        return self.two_phase_m - self.five_phase_m

    @property
    def complete(self) -> bool:
        """Both runs reached the stop speed (otherwise the distances describe a truncated run)."""
        return self.five_phase_status == self.two_phase_status == "stopped"

    @property
    def two_phase_shorter(self) -> bool:
        return self.complete and self.two_phase_m < self.five_phase_m

    def to_json(self) -> dict[str, Any]:
        return {"speed_kmh": self.speed_kmh, "road": self.road, "five_phase_m": self.five_phase_m,
                "two_phase_m": self.two_phase_m, "difference_m": self.difference_m,
                "seed_five_phase_m": self.seed_five_phase_m, "seed_two_phase_m": self.seed_two_phase_m,
                "seed_difference_m": None if self.seed_five_phase_m is None else
                round(self.seed_two_phase_m - self.seed_five_phase_m, 2),
                "five_phase_stopping_m": self.five_phase_stopping_m,
                "two_phase_stopping_m": self.two_phase_stopping_m, "five_phase_status": self.five_phase_status,
                "two_phase_status": self.two_phase_status, "two_phase_shorter": self.two_phase_shorter}

    @classmethod
    def from_json(cls, data: Any) -> Table41Row:
        """The row of :meth:`to_json` (the derived differences and flags are not read).

        Raises
        ------
        SimulationError
            A missing key or a value the row rejects.
        """
        return from_fields(cls, data, "Table 4.1 row")


@dataclass(frozen=True)
class Table41Result:
    """Seed 001 Table 4.1 reproduced: braking distance ``vx(0)² / (2 g mū)`` per road and speed."""

    rows: tuple[Table41Row, ...]
    five_phase: FivePhaseABS
    two_phase: TwoPhaseABS
    observer: str
    wall_time_s: float

    @property
    def two_phase_always_shorter(self) -> bool:
        return all(r.two_phase_shorter for r in self.rows)

    def to_json(self) -> dict[str, Any]:
        return {"rows": [r.to_json() for r in self.rows], "five_phase": self.five_phase.to_json(),
                "two_phase": self.two_phase.to_json(), "observer": self.observer,
                "two_phase_always_shorter": self.two_phase_always_shorter, "wall_time_s": self.wall_time_s}

    @classmethod
    def from_json(cls, data: Any) -> Table41Result:
        """The table of :meth:`to_json`: rows and both controllers' settings (compares with ``==``).

        Raises
        ------
        SimulationError
            A missing key or a malformed row or controller; the message names it.
        """
        if not isinstance(data, dict) or not isinstance(data.get("rows"), list):
            raise SimulationError(f"a Table 4.1 JSON needs 'rows' as a list, got {data!r}")
        return from_fields(cls, data, "Table 4.1", rows=tuple(Table41Row.from_json(r) for r in data["rows"]),
                           five_phase=from_fields(FivePhaseABS, data.get("five_phase"), "five-phase controller"),
                           two_phase=from_fields(TwoPhaseABS, data.get("two_phase"), "two-phase controller"))

    def _repr_markdown_(self) -> str:
        """The table in a notebook: braking distance :math:`v_x(0)^2 / (2 g \\bar\\mu)` per road and speed."""
        def cell(ours: float, seed: float | None) -> str:
            return f"{ours:.2f}" + ("" if seed is None else f" ({seed:.2f})")
        lines = [r"**Seed 001 Table 4.1**: braking distance $v_x(0)^2 / (2 g \bar\mu)$ [m], ours (seed)", "",
                 "| speed [km/h] | road | five-phase | two-phase | $\\Delta$ |", "|---:|---|---:|---:|---:|"]
        for r in self.rows:
            sd = None if r.seed_five_phase_m is None else r.seed_two_phase_m - r.seed_five_phase_m
            flag = "" if r.complete else f" (runs: {r.five_phase_status}, {r.two_phase_status})"
            lines.append(f"| {r.speed_kmh:.0f} | {r.road}{flag} | {cell(r.five_phase_m, r.seed_five_phase_m)} | "
                         f"{cell(r.two_phase_m, r.seed_two_phase_m)} | {cell(r.difference_m, sd)} |")
        lines += ["", f"two-phase shorter on every road and speed: **{self.two_phase_always_shorter}** "
                      f"(observer: {self.observer})"]
        return cite("\n".join(lines))

    def __str__(self) -> str:
        def seed(v: float | None) -> str:
            return "   n/a" if v is None else f"{v:7.2f}"
        lines = ["Seed 001 Table 4.1, braking distance vx(0)^2/(2 g mu_bar) [m] (ours | seed)",
                 f"{'speed':>6} {'road':<17} {'five-phase':>17} {'two-phase':>17} {'difference':>17}"]
        for r in self.rows:
            sd = None if r.seed_five_phase_m is None else r.seed_two_phase_m - r.seed_five_phase_m
            flag = "" if r.complete else f"  (runs: {r.five_phase_status}, {r.two_phase_status})"
            lines.append(f"{r.speed_kmh:6.0f} {r.road:<17} {r.five_phase_m:8.2f} |{seed(r.seed_five_phase_m)} "
                         f"{r.two_phase_m:8.2f} |{seed(r.seed_two_phase_m)} {r.difference_m:8.2f} |{seed(sd)}{flag}")
        lines.append(f"two-phase shorter on every road and speed: {self.two_phase_always_shorter} "
                     f"(observer: {self.observer}; {self.wall_time_s:.1f} s wall)")
        return cite("\n".join(lines))


def _status(result: BrakingResult) -> str:
    """The run's status, ``diverged`` for a run that stopped with a diverged estimate (not a complete row)."""
    return "diverged" if result.status == "stopped" and result.failure is not None else result.status


def table41(*, roads: Sequence[str] = TABLE41_ROADS, speeds_kmh: Sequence[float] = TABLE41_SPEEDS_KMH,
            five_phase: FivePhaseABS | None = None, two_phase: TwoPhaseABS | None = None, dt_s: float = 1e-3,
            estimator_factory: Callable[[BrakingScenario], XbsEstimator] | None = None,
            observer: str = "none", compiled: bool | None = None) -> Table41Result:
    """Run the Table 4.1 campaign: each road and speed with both ABS algorithms, free quarter car to 2.5 km/h.

    Parameters
    ----------
    roads, speeds_kmh : sequences
        Subsets of the table (defaults: all five roads, 60/120/180 km/h).
    five_phase, two_phase : controllers, optional
        Defaults: :class:`FivePhaseABS` and :class:`TwoPhaseABS` defaults, the
        latter without the start-up safeguard when it reads the true XBS.
    dt_s : float
        Integration step.
    estimator_factory : callable, optional
        ``scenario -> XbsEstimator`` to close the two-phase loop on an observer
        (output feedback); default: the true XBS (state feedback).
    observer : str
        Label of the estimator for the report.
    compiled : bool or None
        As :func:`simulate`: the loop compiled to C when possible (default), required, or not.

    Returns
    -------
    Table41Result
    """
    five_phase = five_phase or FivePhaseABS()
    # the start-up safeguard protects an observer that has not converged yet; on the true XBS the
    # build-up ends as printed in seed 001 Fig. 4.3, when the XBS drops below chi_a
    two_phase = two_phase or (TwoPhaseABS() if estimator_factory is not None else TwoPhaseABS(start_decel_m_s2=None))
    t0 = time.perf_counter()
    rows = []
    runs, run = 2 * len(speeds_kmh) * len(roads), 0
    for v in speeds_kmh:
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise SimulationError(f"Table 4.1 speeds must be positive numbers in km/h, got {v!r}")
        for name in roads:
            out: list[BrakingResult] = []
            for ctrl in (five_phase, two_phase):
                run += 1
                progress(f"simulate: Table 4.1 [{run}/{runs}] {ctrl.name}, {name}, {v:g} km/h")
                sc = BrakingScenario(name, speed_m_s=v / 3.6, controller=ctrl, dt_s=dt_s,
                                     name=f"table41-{name}-{v:g}")
                est = estimator_factory(sc) if (estimator_factory is not None and ctrl.uses_xbs) else None
                out.append(simulate(sc, estimator=est, compiled=compiled))
            seed = TABLE41_SEED.get((float(v), name))
            rows.append(Table41Row(speed_kmh=float(v), road=name,
                                   five_phase_m=out[0].metrics.braking_distance_m or math.nan,
                                   two_phase_m=out[1].metrics.braking_distance_m or math.nan,
                                   seed_five_phase_m=None if seed is None else seed[0],
                                   seed_two_phase_m=None if seed is None else seed[1],
                                   five_phase_stopping_m=out[0].metrics.stopping_distance_m,
                                   two_phase_stopping_m=out[1].metrics.stopping_distance_m,
                                   five_phase_status=_status(out[0]), two_phase_status=_status(out[1])))
    return Table41Result(rows=tuple(rows), five_phase=five_phase, two_phase=two_phase, observer=observer,
                         wall_time_s=time.perf_counter() - t0)

