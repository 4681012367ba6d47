"""CPU time of the ABS braking simulation in-process and as the whole ``switchobs simulate`` process.

Scenario ``aguado-sec34`` (seed 001 Sec. 3.4: 25 m/s on a drum decelerating at 1.96 m/s², dry asphalt ->
wet asphalt at 3 s -> dry concrete at 6 s, five-phase ABS), RK4 at 1 ms, with each reference observer of
:mod:`switchobs.observers` run beside the loop (and the generated C twin of the adaptive one), and the
two-phase ABS with the adaptive observer in the loop.  In-process: CPU time of ``simulate`` (the
observer built before, not counted), the real-time factor (simulated time / CPU time), the observer's
share and the cost per step.  Whole process: ``switchobs simulate aguado-sec34`` as a user runs it
(interpreter, imports, the cold symbolic design of the observer, the simulation, printing).
Run: ``python benchmarks/abs_sim.py [--quick] [--repeats 5]``.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace

from _harness import MIN_REPEATS, Stats, cli_cpu, cpu, number, publish

from switchobs.loop import EstimatorSpec, xbs_estimator
from switchobs.plants import TwoPhaseABS, scenario, simulate, table41


def measure(label: str, sc, observer: str, repeats: int, in_loop: bool = True, impl: str = "python") -> str:
    cpu_s, shares, steps, sim = [], [], 0, 0.0
    for _ in range(repeats):
        est = xbs_estimator(EstimatorSpec(observer, impl=impl), sc.vehicle, sc.roads.initial)
        c0 = time.process_time()
        res = simulate(sc, estimator=est, observer_in_loop=in_loop)
        cpu_s.append(time.process_time() - c0)
        shares.append(res.observer_time_s / res.wall_time_s)
        steps, sim = res.steps, float(res.series["t"][-1])
    t = Stats(tuple(cpu_s))
    name = observer if impl == "python" else f"{observer} (C)"
    share = sorted(shares)[len(shares) // 2]
    return (f"| {label} | {name} | {steps} | {t.show()} | {number(sim / t.median)} | {100 * share:.0f} % | "
            f"{number(1e6 * t.median / steps)} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="smoke run: no observer and the adaptive one only, 2 runs"
                             "; printed, not written to benchmarks/results")
    parser.add_argument("--repeats", type=int, default=MIN_REPEATS)
    args = parser.parse_args()
    if args.quick:  # a smoke run: two runs show that it works
        args.repeats = min(args.repeats, 2)
    sc = scenario("aguado-sec34")
    observers = ("none", "adaptive") if args.quick else ("none", "xbs3", "xbs4", "adaptive")
    table = ["| run | observer | steps | CPU [s] | × real time | observer share | µs/step |",
             "| --- | --- | ---: | ---: | ---: | ---: | ---: |"]
    for obs in observers:
        table.append(measure("five-phase, beside", sc, obs, args.repeats, in_loop=False))
        print(table[-1], flush=True)
    if not args.quick:
        table.append(measure("five-phase, beside", sc, "adaptive", args.repeats, in_loop=False, impl="c"))
        table.append(measure("two-phase, in the loop", replace(sc, controller=TwoPhaseABS()), "adaptive",
                             args.repeats))
    notes = []
    if not args.quick:
        campaign = cpu(table41, args.repeats)
        notes.append(f"Seed 001 Table 4.1 campaign (30 free-vehicle brakings to standstill, true XBS), in-process: "
                     f"{campaign.show()} s CPU.")
    cli = ["| command (whole process) | CPU [s] | × real time |", "| --- | ---: | ---: |"]
    for argv in (["simulate", "aguado-sec34"], ["simulate", "aguado-sec34", "--observer", "none"]):
        t = cli_cpu(argv, args.repeats)
        cli.append(f"| `switchobs {' '.join(argv)}` | {t.show()} | {number(sc.duration_s / t.median)} |")
        print(cli[-1], flush=True)
    publish("abs_sim",
            f"The {sc.duration_s:g} s `{sc.name}` scenario, RK4 at dt = {sc.dt_s * 1e3:g} ms; CPU time "
            f"(`time.process_time` in-process, `RUSAGE_CHILDREN` for a whole `switchobs` process), median "
            f"[min–max] of {args.repeats} runs; × real time = simulated time / median CPU time. The observer's "
            "share is of the simulation's wall time (median run). The whole process adds the interpreter, the "
            "imports and the cold symbolic design of the observer: what a user waits for.",
            [table, cli], notes, write=not args.quick)


if __name__ == "__main__":
    main()
