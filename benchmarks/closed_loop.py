"""CPU time of a braking run in the compiled loop against the Python loop it ports, and of Table 4.1.

The same runs twice in one process: ``simulate(..., compiled=False)`` (the Python loop: plant, tyre,
controller and integrator in Python, one call into the observer per step) and ``compiled=True`` (the
loop compiled to C with the generated C observer inside it, :mod:`switchobs.plants._compiled`).  Both
give the same samples bit for bit (checked here on every row); the time includes the metrics of the
run.  Runs: the 10 s ``aguado-sec34`` scenario (five-phase ABS, adaptive observer beside the loop), the
same with the two-phase ABS and the observer in the loop, a free-vehicle braking from 120 km/h on dry
asphalt with the 4D observer in the loop through :func:`switchobs.loop.run_braking` (what a sweep
calls per case, observer built once and cached), and the 30 runs of seed 001 Table 4.1 (true XBS).
Run: ``python benchmarks/closed_loop.py [--quick] [--repeats 5]``.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace

import numpy as np
from _harness import MIN_REPEATS, Stats, cpu, number, publish, ratio

from switchobs.loop import EstimatorSpec, run_braking, xbs_estimator
from switchobs.plants import TwoPhaseABS, scenario, simulate, table41


def braking(label: str, sc, spec: EstimatorSpec, in_loop: bool, repeats: int) -> str:
    """One row: the Python loop and the compiled loop on the same scenario, C observer in both."""
    stats, results = {}, {}
    for compiled in (False, True):
        values = []
        for _ in range(repeats):
            est = xbs_estimator(spec, sc.vehicle, sc.roads.initial)
            c0 = time.process_time()
            res = simulate(sc, estimator=est, observer_in_loop=in_loop, compiled=compiled)
            values.append(time.process_time() - c0)
        stats[compiled], results[compiled] = Stats(tuple(values)), res
    ref, fast = results[False], results[True]
    same = all(np.array_equal(ref.series[k], fast.series[k], equal_nan=True) for k in ref.series)
    if not (same and ref.events == fast.events and fast.compiled):
        raise SystemExit(f"{label}: the compiled loop differs from the Python loop")
    sim = float(ref.series["t"][-1])
    py, c = stats[False], stats[True]
    return (f"| {label} | {ref.steps} | {py.show(1e3)} | {number(sim / py.median)} | {c.show(1e3)} | "
            f"{number(sim / c.median)} | {ratio(c.median, py.median)} | {number(1e9 * c.median / ref.steps)} |")


def case(repeats: int) -> str:
    """run_braking end to end (scenario, cached observer, compiled loop, metrics), series dropped."""
    spec = EstimatorSpec("xbs4", impl="c")
    kwargs = dict(controller="five-phase", observer=spec)
    runs = {compiled: run_braking("dry-asphalt", 120, compiled=compiled, **kwargs) for compiled in (False, True)}
    stats = {compiled: cpu(lambda c=compiled: run_braking("dry-asphalt", 120, compiled=c, **kwargs), repeats)
             for compiled in (False, True)}
    if runs[False].metrics != runs[True].metrics:
        raise SystemExit("run_braking: the compiled loop's metrics differ from the Python loop's")
    sim = runs[True].simulated_time_s
    py, c = stats[False], stats[True]
    return (f"| `run_braking` 120 km/h dry asphalt, five-phase, xbs4 in the loop | {runs[True].steps} | "
            f"{py.show(1e3)} | {number(sim / py.median)} | {c.show(1e3)} | {number(sim / c.median)} | "
            f"{ratio(c.median, py.median)} | {number(1e9 * c.median / runs[True].steps)} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="smoke run: one scenario, 2 repeats; printed, not written to benchmarks/results")
    parser.add_argument("--repeats", type=int, default=MIN_REPEATS)
    args = parser.parse_args()
    repeats = 2 if args.quick else args.repeats
    sc = scenario("aguado-sec34")
    adaptive = EstimatorSpec("adaptive", impl="c")
    # warm-up: build the observers and the libraries (compiled once, cached)
    simulate(sc, estimator=xbs_estimator(adaptive, sc.vehicle, sc.roads.initial), compiled=True)
    table = ["| run | steps | Python loop [ms] | × real time | compiled loop [ms] | × real time | speed-up | "
             "ns/step, compiled (whole run) |", "| --- | ---: | ---: | ---: | ---: | ---: | --- | ---: |"]
    table.append(braking("`aguado-sec34` 10 s, five-phase, adaptive (C) beside", sc, adaptive, False, repeats))
    print(table[-1], flush=True)
    if not args.quick:
        table.append(braking("`aguado-sec34` 10 s, two-phase, adaptive (C) in the loop",
                             replace(sc, controller=TwoPhaseABS()), adaptive, True, repeats))
        print(table[-1], flush=True)
        table.append(case(repeats))
        print(table[-1], flush=True)
    notes = []
    if not args.quick:
        slow = cpu(lambda: table41(compiled=False), repeats)
        fast = cpu(lambda: table41(compiled=True), repeats)
        if table41(compiled=False).rows != table41(compiled=True).rows:
            raise SystemExit("table41: the compiled loop's rows differ from the Python loop's")
        notes.append(f"Seed 001 Table 4.1 (30 free-vehicle brakings to standstill, true XBS, metrics included), one "
                     f"core, serially: {slow.show()} s CPU in the Python loop, {fast.show()} s in the compiled loop "
                     f"({ratio(fast.median, slow.median)}); the goal is 5 s on 2 cores.")
    publish("closed_loop",
            "RK4 at dt = 1 ms with event location; CPU time (`time.process_time`) of `simulate` including the "
            f"run's metrics, the observer built before (not counted), median [min–max] of {repeats} runs; "
            "× real time = simulated time / median CPU time; ns/step: the compiled run's CPU time (loop and metrics) per step. Both loops use "
            "the generated C observer and give the same samples and events bit for bit (checked on each row). "
            "The goal of issue 14 is 300× real time for a 10 s run with the C observer.",
            [table], notes, write=not args.quick)


if __name__ == "__main__":
    main()
