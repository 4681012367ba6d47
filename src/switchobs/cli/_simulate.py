"""``switchobs simulate [SCENARIO]``: ABS braking simulations with the reference XBS observers.

Without SCENARIO: a straight-line emergency braking on one road from a given
speed to standstill (the set-up of seed 001 Table 4.1).  Scenarios:
``hoang-fig3``, ``hoang-fig4``, ``aguado-sec34``, ``aguado-sec36`` (the
two-axle vehicle) and ``table41`` (both ABS algorithms on every road and speed
of seed 001 Table 4.1).  ``--controller`` picks the ABS: on ``aguado-sec36``
``six-phase`` (its default) or ``five-phase`` (:func:`aguado_sec36`).
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import replace
from typing import Any

import numpy as np

from .._figures import save_figure
from ..exceptions import SimulationError
from ..loop import DEFAULT_GAMMA, OBSERVER_KINDS, EstimatorSpec, xbs_estimator
from ..plants import (TABLE41_ROADS, TABLE41_SPEEDS_KMH, BrakeActuator, BrakingResult, BrakingScenario,
                      ContinuousXbsControl, FivePhaseABS, SixPhaseABS, TwoPhaseABS, XbsEstimator, aguado_sec36, plot_braking,
                      plot_table41, plot_two_axle, road, road_names, scenario, scenario_description,
                      scenario_names, scenario_observer, scenario_observer_gains, simulate, simulate_two_axle, table41)
from ..spec import METHODS
from ._common import emit_json, figure_file, note_uncertified

__all__ = ["register"]

CONTROLLERS = ("five-phase", "six-phase", "two-phase", "continuous")
#: The ABS algorithms the two-axle scenario builds (:func:`aguado_sec36`).
TWO_AXLE_CONTROLLERS = ("six-phase", "five-phase")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("simulate",
                       description="Simulate an emergency braking of the quarter car of Aguado-Rojas 2020 (2.1) with a "
                                   "hybrid ABS and an XBS observer; print the metrics or JSON, draw the plots.")
    p.add_argument("scenario", nargs="?", metavar="SCENARIO",
                   help=f"built-in scenario: {', '.join(scenario_names())} (default: braking on --road "
                        f"from --speed-kmh to standstill)")
    p.add_argument("--road", help=f"road surface: {', '.join(road_names())} (default dry-asphalt)")
    p.add_argument("--speed-kmh", type=float, help="initial speed [km/h] (default 120)")
    p.add_argument("--controller", choices=CONTROLLERS,
                   help="ABS algorithm (default five-phase; aguado-sec36: six-phase, and only six-phase or "
                        "five-phase)")
    p.add_argument("--tracking", action="store_true",
                   help="five-phase: closed-loop wheel-acceleration tracking (21)-(22) in phases 1, 3, 4")
    p.add_argument("--observer", choices=OBSERVER_KINDS,
                   help="XBS observer (default: none, or the scenario's); controllers that need an XBS read "
                        "its estimate, or the true XBS with --observer none")
    p.add_argument("--observer-impl", choices=("python", "c"), default="python",
                   help="observer implementation: the Python reference or the generated C (switchobs codegen, "
                        "double, compiled with the system gcc)")
    p.add_argument("--method", choices=METHODS,
                   help="the observer's step method (default radau3, certified for every step; the adaptive "
                        "observer: rk4, as it takes explicit steps only); rk4 and euler are not certified for the "
                        "switched observers (a note says so)")
    p.add_argument("--parallel", action="store_true",
                   help="run the observer beside the loop: the controller reads the true XBS (Aguado-Rojas 2020 Fig. 4.5)")
    p.add_argument("--beta", type=float, help="observer rate beta in the rescaled time (default: the scenario's "
                                              "for its own observer, else per observer)")
    p.add_argument("--gamma", type=float, help=f"adaptive observer: Gamma = gamma I (default: the scenario's for "
                                               f"its own observer, else {DEFAULT_GAMMA:g})")
    p.add_argument("--static-load", action="store_true",
                   help="aguado-sec36, adaptive observer: keep each wheel's static load in a = R^2 Fz / J instead "
                        "of reading Fz from (3.36) on line (Aguado-Rojas 2020 Sec. 3.6)")
    p.add_argument("--duration", type=float, help="time bound [s] (default: scenario's, or 60)")
    p.add_argument("--dt", type=float, help="integration step [s] (default 0.001)")
    p.add_argument("--delay", type=float, help="actuator delay [s] (0 or >= the step)")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.add_argument("--series", action="store_true", help="with --json: include the time series")
    p.add_argument("--plot", metavar="PNG", type=figure_file, help="write the figure to this file")
    p.set_defaults(func=run)


def _controller(args: argparse.Namespace, base: Any) -> Any:
    if args.controller is None:
        ctrl = base
    elif args.controller == "five-phase":
        ctrl = base if isinstance(base, FivePhaseABS) else FivePhaseABS()
    elif args.controller == "six-phase":
        ctrl = base if isinstance(base, SixPhaseABS) else SixPhaseABS()
    elif args.controller == "two-phase":
        ctrl = TwoPhaseABS()
    else:
        ctrl = ContinuousXbsControl()
    if args.tracking:
        if not isinstance(ctrl, FivePhaseABS):
            raise SimulationError(f"--tracking applies to the five-phase ABS, not to {ctrl.name}")
        ctrl = replace(ctrl, tracking=True)
    return ctrl


def _scenario(args: argparse.Namespace) -> tuple[BrakingScenario, str]:
    if args.scenario is not None:
        sc = scenario(args.scenario)
        if args.road is not None:
            raise SimulationError(f"--road does not apply to the scenario {args.scenario!r}, which fixes its roads")
        observer = scenario_observer(args.scenario)
    else:
        sc = BrakingScenario(road(args.road or "dry-asphalt"), speed_m_s=120 / 3.6,
                             name=f"braking-{args.road or 'dry-asphalt'}")
        observer = "none"
    changes: dict[str, Any] = {"controller": _controller(args, sc.controller), **_timing_changes(args)}
    if args.delay is not None:
        changes["actuator"] = BrakeActuator(delay_s=args.delay)
    return replace(sc, **changes), (args.observer or observer)


def _timing_changes(args: argparse.Namespace) -> dict[str, Any]:
    """Scenario fields set by --speed-kmh, --duration and --dt, validated."""
    changes: dict[str, Any] = {}
    if args.speed_kmh is not None:
        if not args.speed_kmh > 0:
            raise SimulationError(f"--speed-kmh must be > 0, got {args.speed_kmh:g}")
        changes["speed_m_s"] = args.speed_kmh / 3.6
    if args.duration is not None:
        if not args.duration > 0:
            raise SimulationError(f"--duration must be > 0 s, got {args.duration:g}")
        changes["duration_s"] = args.duration
    if args.dt is not None:
        changes["dt_s"] = args.dt
    return changes


def _spec(args: argparse.Namespace, kind: str) -> EstimatorSpec:
    """The observer of --observer with --beta and --gamma, else the gains the scenario chose for its own observer."""
    gains = scenario_observer_gains(args.scenario) if args.scenario is not None else {}
    if gains and kind != scenario_observer(args.scenario):
        gains = {}
    return EstimatorSpec(kind, beta=gains.get("beta") if args.beta is None else args.beta,
                         gamma=gains.get("gamma") if args.gamma is None else args.gamma, impl=args.observer_impl,
                         method=_method(args, kind))


def _method(args: argparse.Namespace, kind: str) -> str | None:
    """--method, checked against the observer; a note on stderr for an uncertified step of a switched observer."""
    if args.method is None:
        return None
    if kind == "none":
        raise SimulationError(f"--method {args.method} is the observer's step method; --observer none runs no "
                              "observer")
    if kind != "adaptive":   # the adaptive observer has explicit steps only and no discrete certificate
        note_uncertified(args, args.method)
    return args.method


def _table41(args: argparse.Namespace) -> int:
    for opt in ("road", "speed_kmh", "controller", "duration", "delay"):
        if getattr(args, opt) is not None or (opt == "controller" and args.tracking):
            raise SimulationError(f"--{opt.replace('_', '-')} does not apply to table41, which runs both ABS "
                                  f"algorithms on the roads and speeds of seed 001 Table 4.1")
    kind = args.observer or "none"
    factory = None
    if kind == "none":
        _method(args, kind)   # refuses --method
    else:
        spec = _spec(args, kind)

        def factory(sc: BrakingScenario) -> XbsEstimator | None:
            return xbs_estimator(spec, sc.vehicle, sc.roads.initial)
    result = table41(roads=TABLE41_ROADS, speeds_kmh=TABLE41_SPEEDS_KMH, dt_s=args.dt or 1e-3,
                     estimator_factory=factory, observer=kind)
    if args.plot:
        save_figure(plot_table41(result), args.plot)
    if args.json:
        emit_json(result.to_json())
    else:
        print(result)
    return 0 if result.two_phase_always_shorter else 1


def _two_axle(args: argparse.Namespace) -> int:
    for opt in ("road", "tracking", "delay"):
        if getattr(args, opt) not in (None, False):
            raise SimulationError(f"--{opt} does not apply to the two-axle scenario {args.scenario!r}")
    controller = args.controller or TWO_AXLE_CONTROLLERS[0]
    if controller not in TWO_AXLE_CONTROLLERS:
        raise SimulationError(f"--controller {controller} does not apply to the two-axle scenario {args.scenario!r}; "
                              f"use {' or '.join(TWO_AXLE_CONTROLLERS)}")
    sc = aguado_sec36(controller)
    changes = _timing_changes(args)
    if changes.get("duration_s", math.inf) <= sc.brake_start_s:
        raise SimulationError(f"--duration {args.duration:g} s ends before the braking of {args.scenario} starts "
                              f"({sc.brake_start_s:g} s); give more than {sc.brake_start_s:g}")
    sc = replace(sc, **changes)
    kind = args.observer or scenario_observer(args.scenario)
    if args.static_load and kind != "adaptive":
        raise SimulationError(f"--static-load applies to the adaptive observer, which reads the load on line; "
                              + ("--observer none runs no observer" if kind == "none" else
                                 f"the {kind} observer always keeps its wheel's static load"))
    # the adaptive observer reads its wheel's load (3.36) on line as in the seed, the others keep a = R^2 Fz / J
    # of the corner's static load
    spec, online = _spec(args, kind), kind == "adaptive" and not args.static_load
    ests = tuple(xbs_estimator(spec, sc.vehicle.corner(axle), sc.roads.initial, load_signal=online)
                 for axle in ("front", "rear"))
    result = simulate_two_axle(sc, estimators=ests, observer_in_loop=not args.parallel)
    if args.plot:
        save_figure(plot_two_axle(result), args.plot)
    if args.json:
        data = result.to_json(include_series=args.series)
        data["description"] = scenario_description(args.scenario)
        data["observer"] = kind
        data["observer_load"] = "online" if online else "static"
        emit_json(data)
    else:
        print(scenario_description(args.scenario))
        print(result)
        if kind != "none":
            print(f"  per wheel: {spec}, {'load (3.36) read on line' if online else 'static load'}")
    return _verdict(result.failure, kind)


def _verdict(failure: str | None, kind: str) -> int:
    """Exit status 1 with the reason on stderr for a failed run, 0 otherwise (docs/errors.md)."""
    if failure is None:
        return 0
    if kind == "adaptive" and "not finite" in failure:
        # the explicit step of the adaptive observer, not the observer, diverges (docs/reproductions.md, Sec. 3.6)
        failure += "; the adaptive observer's explicit step diverges for a large gamma: try --gamma 5000 or --dt 0.0005"
    print(f"switchobs simulate: failed: {failure}", file=sys.stderr)
    return 1


def _unfinished(args: argparse.Namespace, result: BrakingResult) -> str | None:
    """The default run brakes "to standstill": ending at the default time bound before the stop fails it.

    A named scenario's bound and a --duration the user gave are the window asked for, not a failure.
    """
    if result.status != "duration" or args.scenario is not None or args.duration is not None:
        return None
    return (f"the car did not stop within the default time bound of {result.scenario.duration_s:g} s "
            f"(final speed {result.metrics.final_speed_m_s:.2f} m/s); give a longer --duration")


def run(args: argparse.Namespace) -> int:
    # an overflowing observer is reported once, as a failed or diverged run, not also by numpy's warnings
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        return _run(args)


def _run(args: argparse.Namespace) -> int:
    if args.series and not args.json:
        raise SimulationError("--series only applies with --json")
    if args.static_load and args.scenario != "aguado-sec36":
        raise SimulationError("--static-load only applies to the two-axle scenario aguado-sec36, whose loads move "
                              "(3.36); a quarter car's load is static")
    if args.scenario == "table41":
        return _table41(args)
    if args.scenario == "aguado-sec36":
        return _two_axle(args)
    sc, kind = _scenario(args)
    est = xbs_estimator(_spec(args, kind), sc.vehicle, sc.roads.initial)
    result = simulate(sc, estimator=est, observer_in_loop=not args.parallel)
    if args.plot:
        save_figure(plot_braking(result), args.plot)
    if args.json:
        data = result.to_json(include_series=args.series)
        if args.scenario is not None:
            data["description"] = scenario_description(args.scenario)
        emit_json(data)
    else:
        if args.scenario is not None:
            print(scenario_description(args.scenario))
        print(result)
    return _verdict(result.failure or _unfinished(args, result), kind)
