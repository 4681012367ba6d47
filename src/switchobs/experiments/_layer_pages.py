"""The set-ups and runs behind the measured numbers of the layer pages (``docs/observers.md``, ``docs/abs.md``,
``docs/encoders.md``): the observers on the quarter car, the controllers' behaviour, the step halving, the
Poincare map against integration, and the wheel-encoder chain on profiles and brakings.

Not the seed reproductions of :mod:`._runs`: these runs describe our own observers, controllers and encoder
chain.  :class:`switchobs.experiments.Runs` makes each once; :mod:`switchobs.report` only renders them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from ..loop import EstimatorSpec, xbs_estimator
from ..observers import xbs3_observer
from ..plants import (BrakingMetrics, BrakingResult, BrakingScenario, ContinuousXbsControl, FivePhaseABS, SixPhaseABS,
                      TwoPhaseABS, road, road_names, scenario, simulate, simulate_return_map)
from ..sensors import (ROBUSTNESS_PROFILES, TABLE61_ENCODER, AngleTrajectory, ChainResult, ChainSettings, Encoder,
                       EncoderEvents, EstimatorComparison, WheelRun, braking_trajectory, compare_estimators,
                       constant_speed, encoder_chain, varying_speed)

__all__ = ["QUARTER_CAR_STEPS", "QUARTER_CAR_OBSERVERS", "QUARTER_CAR_BETAS", "quarter_car_scenario", "quarter_car",
           "STEP_HALVING_STEPS_S", "step_halving_controllers", "step_halving", "no_stall_exit", "continuous_law",
           "fig66_thresholds_run", "TWO_PHASE_START", "two_phase_start", "six_phase_roads", "POINCARE_KPS",
           "POINCARE_SETTING", "POINCARE_ZETAS", "simulated_return", "encoder_example", "imperfection_encoders",
           "imperfection_runs", "robustness_runs", "ChainBraking", "chain_braking", "CHAIN_ABS_SCENARIOS",
           "CHAIN_TSA_WINDOWS", "chain_abs", "chain_tsa_windows", "ENCODER_COMMANDS", "plant_trajectory"]

# ---------------------------------------------------------------- observers on the quarter car (observers.md)

#: The quarter-car comparison of docs/observers.md: plant steps [s], observers (kind, Gamma), rates.
QUARTER_CAR_STEPS = (1e-3, 2.5e-4)
QUARTER_CAR_OBSERVERS = (("xbs3", None), ("xbs4", None), ("adaptive", 1e4), ("adaptive", 1e3))
QUARTER_CAR_BETAS = (60.0, 100.0, 150.0)


def quarter_car_scenario(dt_s: float) -> BrakingScenario:
    """The five-phase ABS on dry asphalt (seed 001 Table 2.1) from 25 m/s at the plant step ``dt_s``."""
    return BrakingScenario("dry-asphalt", speed_m_s=25.0, dt_s=dt_s)


def quarter_car(dt_s: float, kind: str | None = None, gamma: float | None = None,
                beta: float | None = None) -> BrakingResult:
    """:func:`quarter_car_scenario` with the observer ``kind`` (rate ``beta``, adaptation ``gamma I``) beside the
    loop, or no observer when ``kind`` is None."""
    sc = quarter_car_scenario(dt_s)
    if kind is None:
        return simulate(sc)
    est = xbs_estimator(EstimatorSpec(kind, beta=beta, gamma=gamma), sc.vehicle, sc.roads.initial)
    with np.errstate(over="ignore", invalid="ignore"):     # Gamma = 1e4 I at beta = 60 diverges at 1 ms
        return simulate(sc, estimator=est, observer_in_loop=False)


# ---------------------------------------------------------------- controllers (abs.md)

#: The plant steps of the step-halving table of docs/abs.md [s].
STEP_HALVING_STEPS_S = (1e-3, 5e-4, 2.5e-4)


def step_halving_controllers() -> tuple[tuple[str, FivePhaseABS | TwoPhaseABS], ...]:
    """The controllers of the step-halving table, each with its page label."""
    return (("five-phase", FivePhaseABS()), ("two-phase (true XBS)", TwoPhaseABS()),
            ("five-phase + tracking (true XBS)", FivePhaseABS(tracking=True)))


def step_halving() -> dict[str, tuple[BrakingMetrics, ...]]:
    """Braking on wet asphalt from 90 km/h to standstill at each step of :data:`STEP_HALVING_STEPS_S`, per
    controller of :func:`step_halving_controllers` (the true XBS for those that read it)."""
    out = {}
    for label, ctrl in step_halving_controllers():
        sc = BrakingScenario("wet-asphalt", speed_m_s=90.0 / 3.6, controller=ctrl)
        out[label] = tuple(simulate(sc.with_step(dt), estimator="true" if ctrl.uses_xbs else None).metrics
                           for dt in STEP_HALVING_STEPS_S)
    return out


def no_stall_exit(name: str = "hoang-fig4") -> BrakingResult:
    """The built-in scenario ``name`` with its five-phase ABS's stall exit removed, no observer."""
    free = scenario(name)
    return simulate(replace(free, controller=replace(free.controller, stall_timeout_s=None)))


def continuous_law() -> dict[str, BrakingResult]:
    """Seed 001 Figs. 4.1-4.2: the continuous law (4.2)-(4.3) and the two-phase ABS on dry asphalt from
    90 km/h, the adaptive observer beside the loop (``simulate --controller continuous --observer adaptive
    --parallel``)."""
    res = {}
    for name, controller in (("continuous", ContinuousXbsControl()), ("two-phase", TwoPhaseABS())):
        sc = BrakingScenario("dry-asphalt", speed_m_s=90.0 / 3.6, controller=controller)
        est = xbs_estimator(EstimatorSpec("adaptive"), sc.vehicle, sc.roads.initial)
        res[name] = simulate(sc, estimator=est, observer_in_loop=False)
    return res


def fig66_thresholds_run() -> BrakingResult:
    """The five-phase ABS with the thresholds printed in seed 001 Sec. 6.4 (``FivePhaseABS.fig66()``) on dry
    asphalt from 120 km/h."""
    return simulate(BrakingScenario("dry-asphalt", speed_m_s=120.0 / 3.6, controller=FivePhaseABS.fig66()))


#: The road and initial speed [km/h] where the two-phase ABS of ``table41`` leaves its build-up latest.
TWO_PHASE_START = ("dry-cobblestones", 180.0)


def two_phase_start() -> BrakingResult:
    """The two-phase ABS without its start-up safeguard (as ``table41`` runs it) at :data:`TWO_PHASE_START`."""
    name, speed = TWO_PHASE_START
    return simulate(BrakingScenario(name, speed_m_s=speed / 3.6, controller=TwoPhaseABS(start_decel_m_s2=None)))


def six_phase_roads() -> dict[str, BrakingResult]:
    """Our six-phase ABS at 120 km/h on each road of seed 001 Table 2.1 with a friction peak (all but ice,
    whose ``c3 = 0``)."""
    ours = SixPhaseABS()
    return {name: simulate(BrakingScenario(name, speed_m_s=120.0 / 3.6, controller=ours))
            for name in road_names()[:7] if road(name).d > 0}


#: The two-phase ABS of the Poincare table (docs/abs.md): gains, and where the maps are compared.
POINCARE_KPS = (10.0, 50.0, 100.0, 300.0, 3000.0)
POINCARE_SETTING = {"z_ref": 8.0, "chi_a": -0.1, "chi_b": 0.1}
POINCARE_ZETAS = (-0.9, -0.5, -0.1)


def simulated_return(kp: float, zeta: float) -> float:
    """The return map (4.13) of the two-phase ABS on dry asphalt measured by integration (``simulate_return_map``)
    from ``zeta``, in the units of ``zeta`` (``z1 / z_ref``)."""
    dry, z_ref = road("dry-asphalt"), POINCARE_SETTING["z_ref"]
    _, back = simulate_return_map(zeta * z_ref, kp=kp, c=dry.c, d=dry.d, **POINCARE_SETTING)
    return back / z_ref


# ---------------------------------------------------------------- the wheel-encoder chain (encoders.md)

#: The commands whose output docs/encoders.md shows, and the trajectories they run (as the CLI builds them).
ENCODER_COMMANDS: tuple[tuple[str, Callable[[], AngleTrajectory]], ...] = (
    ("switchobs encoder", lambda: constant_speed(1020.0, 10.0)),
    ("switchobs encoder --profile varying", lambda: varying_speed(1020.0, 10.0)),
    ("switchobs encoder --profile braking", lambda: braking_trajectory(10.0).trajectory("braking, dry asphalt, 130 km/h")),
)


def plant_trajectory(res: BrakingResult) -> AngleTrajectory:
    s = res.series
    keep = np.concatenate([[True], np.diff(s["t"]) > 0])      # event-located steps repeat times
    return AngleTrajectory.from_samples(s["t"][keep], omega=s["omega"][keep], alpha=s["omega_dot"][keep],
                                        accel_x=s["ax"][keep], radius_m=res.scenario.vehicle.radius_m,
                                        name=res.scenario.name)



def encoder_example() -> tuple[EncoderEvents, ChainResult]:
    """The first example of docs/encoders.md: the Table 6.1 encoder's events on the varying profile and the
    three-stage chain on a 10 s braking."""
    events = TABLE61_ENCODER.events(varying_speed(1020, 10.0))
    return events, encoder_chain(braking_trajectory(10.0).trajectory(), TABLE61_ENCODER, estimator="three-stage")


def imperfection_encoders() -> tuple[tuple[str, Encoder], ...]:
    """The Table 6.1 encoder's imperfections one at a time (and a fixed per-tooth error it does not have), each
    with its page label."""
    t61 = TABLE61_ENCODER
    return (("ideal, exact clock", Encoder(ppr=60)),
            ("fixed per-tooth noise only (0.01 cycle)", Encoder(ppr=60, dnl_cycles=0.01, seed=1)),
            (f"per-event transition noise only ({t61.jitter_cycles:g} cycle)",
             Encoder(ppr=60, jitter_cycles=t61.jitter_cycles, seed=t61.seed)),
            (f"eccentricity only ({t61.eccentricity:g})", Encoder(ppr=60, eccentricity=t61.eccentricity)))


def imperfection_runs() -> list[tuple[str, EstimatorComparison]]:
    """TSA and three-stage estimates at a constant 1020 rpm for 10 s with each encoder of
    :func:`imperfection_encoders`."""
    return [(label, compare_estimators(constant_speed(1020.0, 10.0), enc, estimators=("tsa", "three-stage")))
            for label, enc in imperfection_encoders()]


def robustness_runs() -> list[tuple[str, EstimatorComparison, EstimatorComparison]]:
    """Each 6 s profile of ``ROBUSTNESS_PROFILES`` through the Table 6.1 encoder: TSA and three-stage with our
    stage 1, and the three-stage with the seed's 1 Hz high-pass."""
    return [(label, compare_estimators(traj(6.0), TABLE61_ENCODER, estimators=("tsa", "three-stage")),
             compare_estimators(traj(6.0), TABLE61_ENCODER, estimators=("three-stage",),
                                settings=ChainSettings(highpass_hz=1.0)))
            for label, traj in ROBUSTNESS_PROFILES]


@dataclass(frozen=True)
class ChainBraking:
    """The chain on a torque-driven braking and the 3D XBS observer fed by each of its ``x2``.

    ``xbs_errors`` maps ``"exact"`` and each estimator to the RMS XBS error of the observer after 2 s;
    ``t`` and ``xbs`` are the chain's sample times and the true XBS at them.
    """

    run: WheelRun
    comparison: EstimatorComparison
    xbs_errors: dict[str, float]
    t: np.ndarray
    xbs: np.ndarray


def chain_braking() -> ChainBraking:
    """A 10 s braking of ``braking_trajectory`` through the Table 6.1 encoder, every estimator, and the 3D XBS
    observer (seed 000 (7), road known) fed by the exact ``x2`` and by each estimate."""
    run = braking_trajectory(10.0)
    cmp = compare_estimators(run.trajectory(), TABLE61_ENCODER)
    car, dry = run.vehicle, road("dry-asphalt")
    obs = xbs3_observer(10.0, 20.0, params={"a": car.a, "b": -car.b, "c": dry.c})   # seed 000 (7) signs
    t = cmp.results[0].t
    speed = np.interp(t, run.t, run.speed_m_s)
    # T = -gamma_b P_b, so the observer input u = dP_b/dt is -dT/dt / gamma_b
    rate = np.interp(t, run.t, -np.gradient(run.torque_nm, run.t) / car.brake_gain_nm_bar)
    xbs = dry.xbs_array(np.interp(t, run.t, run.slip))

    def xbs_error(x2: np.ndarray) -> float:
        first = int(np.argmax(np.isfinite(x2)))
        states = obs.run([x2[first], 20.0, 0.0], np.column_stack([x2, speed, rate])[first:], 1e-3)
        late = t[first:] >= 2.0
        return float(np.sqrt(np.mean((states[late, 1] - xbs[first:][late]) ** 2)))

    errors = {"exact": xbs_error(cmp.results[0].x2_true), **{r.estimator: xbs_error(r.x2) for r in cmp.results}}
    return ChainBraking(run, cmp, errors, t, xbs)


#: The closed-loop brakings the open-loop chain reads (built-in scenarios, no observer).
CHAIN_ABS_SCENARIOS = ("hoang-fig3", "aguado-sec34")
#: The TSA windows (events) compared on ``hoang-fig3``.
CHAIN_TSA_WINDOWS = (6, 10, 15)


def chain_abs(trajectories: dict[str, AngleTrajectory]) -> dict[str, EstimatorComparison]:
    """Every estimator through the Table 6.1 encoder on each trajectory, scored after 0.5 s."""
    return {name: compare_estimators(traj, TABLE61_ENCODER, settings=ChainSettings(warmup_s=0.5))
            for name, traj in trajectories.items()}


def chain_tsa_windows(trajectory: AngleTrajectory) -> dict[str, tuple[float, ...]]:
    """RMS ``x2`` error of the TSA at each window of :data:`CHAIN_TSA_WINDOWS`, with a perfect encoder and the
    Table 6.1 one."""
    encoders: tuple[tuple[str, Encoder], ...] = (("ideal", Encoder(ppr=60)), ("Table 6.1 encoder", TABLE61_ENCODER))
    return {label: tuple(encoder_chain(trajectory, enc, estimator="tsa",
                                       settings=ChainSettings(window=n, warmup_s=0.5)).rms_x2
                         for n in CHAIN_TSA_WINDOWS) for label, enc in encoders}

