"""``switchobs encoder``: simulate an imperfect wheel encoder and score the speed/acceleration estimators."""

from __future__ import annotations

import argparse
import sys

from ..exceptions import SimulationError
from .._figures import save_figure
from ..sensors import (ESTIMATORS, TABLE61_ENCODER, AngleTrajectory, ChainSettings, Encoder, braking_trajectory,
                       compare_estimators, constant_speed, plot_comparison, varying_speed)
from ._common import emit_json, figure_file

__all__ = ["register"]

PROFILES = ("constant", "varying", "braking")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "encoder",
        description="Simulate a wheel encoder with transition noise and eccentricity, estimate the wheel "
                    "speed and acceleration at the controller rate and print the RMS errors against the "
                    "exact trajectory (Aguado-Rojas 2020 Table 6.1 layout).")
    p.add_argument("--ppr", type=int, default=60, help="pulses per revolution N (default 60)")
    p.add_argument("--events", type=int, default=15, help="TSA window n (default 15)")
    p.add_argument("--order", type=int, default=2, help="TSA polynomial order m (default 2)")
    p.add_argument("--harmonics", type=int, default=5, help="harmonics M of the three-stage estimator (default 5)")
    p.add_argument("--rpm", type=float, default=1020.0, help="mean wheel speed for constant/varying (default 1020)")
    p.add_argument("--profile", choices=PROFILES, default="constant",
                   help="constant speed, sinusoidal speed (+-40 rad/s at 1 Hz), or a quarter-car braking run")
    p.add_argument("--duration", type=float, default=10.0, help="simulated time in s (default 10)")
    p.add_argument("--estimator", choices=("all", *ESTIMATORS), default="all", help="estimator (default all)")
    p.add_argument("--rate-hz", type=float, default=1000.0, help="controller rate (default 1000)")
    enc = TABLE61_ENCODER
    p.add_argument("--dnl", type=float, default=enc.dnl_cycles,
                   help=f"per-tooth transition noise bound eps in encoder cycles (default {enc.dnl_cycles:g})")
    p.add_argument("--jitter", type=float, default=enc.jitter_cycles,
                   help=f"per-event transition noise bound in encoder cycles (default {enc.jitter_cycles:g})")
    p.add_argument("--eccentricity", type=float, default=enc.eccentricity,
                   help=f"code-track eccentricity e/r (default {enc.eccentricity:g})")
    p.add_argument("--clock-hz", type=float, default=1e6, help="timer clock; 0 for exact time stamps (default 1e6)")
    p.add_argument("--both-edges", action="store_true", help="use rising and falling edges")
    p.add_argument("--seed", type=int, default=1, help="seed of the transition errors (default 1)")
    p.add_argument("--warmup", type=float, default=1.0, help="seconds left out of the statistics (default 1)")
    p.add_argument("--json", action="store_true", help="print the results as JSON")
    p.add_argument("--plot", metavar="PNG", type=figure_file,
                   help="save the speed and acceleration estimation errors of every estimator")
    p.set_defaults(func=run)


def _trajectory(args: argparse.Namespace) -> AngleTrajectory:
    if args.profile == "constant":
        return constant_speed(args.rpm, args.duration)
    if args.profile == "varying":
        return varying_speed(args.rpm, args.duration)
    return braking_trajectory(args.duration).trajectory("braking, dry asphalt, 130 km/h")


def run(args: argparse.Namespace) -> int:
    if args.warmup >= args.duration:
        raise SimulationError(f"--warmup {args.warmup:g} must be shorter than --duration {args.duration:g}")
    encoder = Encoder(ppr=args.ppr, dnl_cycles=args.dnl, jitter_cycles=args.jitter, eccentricity=args.eccentricity,
                      both_edges=args.both_edges, clock_hz=args.clock_hz or None, seed=args.seed)
    settings = ChainSettings(rate_hz=args.rate_hz, order=args.order, window=args.events,
                             harmonics=args.harmonics, warmup_s=args.warmup)
    estimators = ESTIMATORS if args.estimator == "all" else (args.estimator,)
    comparison = compare_estimators(_trajectory(args), encoder, estimators=estimators, settings=settings)
    if args.json:
        emit_json(comparison.to_json())
    else:
        print(comparison)
    if args.plot:
        save_figure(plot_comparison(comparison), args.plot)
        if not args.json:
            print(f"plot written to {args.plot}")
    if comparison.failure is not None:
        print(f"switchobs encoder: failed: {comparison.failure}", file=sys.stderr)
        return 1
    return 0
