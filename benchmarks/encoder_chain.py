"""Cost of the wheel-encoder chain over 10 s of braking (60-ppr encoder, 1 kHz controller).

CPU time (``time.process_time``), median [min–max] of 5 runs, per encoder event and per controller
sample for every stage, and the real-time factor (simulated seconds per CPU second); beside it the whole
``switchobs encoder`` process as a user runs it (interpreter, imports, simulation, all estimators).
Goal of issue 5: the three-stage estimator at least 10x faster than real time.
Run: ``.venv/bin/python benchmarks/encoder_chain.py [--quick] [--repeats 5]``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from _harness import MIN_REPEATS, cli_cpu, cpu, number, publish

from switchobs.sensors import (ChainSettings, Encoder, ThreeStageEstimator, TimeStamper, braking_trajectory,
                               controller_times, encoder_chain, notch, three_stage, time_stamping)

DURATION_S = 10.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="smoke run: the stages without the whole chains"
                             "; printed, not written to benchmarks/results")
    parser.add_argument("--repeats", type=int, default=MIN_REPEATS)
    args = parser.parse_args()

    start = time.process_time()
    run = braking_trajectory(DURATION_S)
    plant_s = time.process_time() - start
    traj = run.trajectory("braking")
    encoder = Encoder(ppr=60, dnl_cycles=0.01, eccentricity=0.003, clock_hz=1e6, seed=1)
    events = encoder.events(traj)
    ts = controller_times(0.0, DURATION_S, 1000.0)
    tsa = time_stamping(events.times, events.angles, ts)
    n_ev, n_s = len(events), ts.size

    def streaming_tsa() -> None:
        stamper, k = TimeStamper(order=2, window=15), 0
        for t in ts:
            while k < n_ev and events.times[k] <= t:
                stamper.push(float(events.times[k]), float(events.angles[k]))
                k += 1
            stamper.estimate(float(t))

    def streaming_three_stage() -> None:
        est = ThreeStageEstimator(5)
        for i in np.flatnonzero(tsa.valid):
            est.update(float(tsa.theta[i]), float(tsa.omega[i]), float(tsa.alpha[i]))

    rows = [
        ("encoder events (simulation side)", cpu(lambda: encoder.events(traj), args.repeats)),
        ("TSA, batch", cpu(lambda: time_stamping(events.times, events.angles, ts), args.repeats)),
        ("TSA, streaming (push + estimate)", cpu(streaming_tsa, args.repeats)),
        ("notch stage only", cpu(lambda: notch(tsa), args.repeats)),
        ("three-stage stage only", cpu(lambda: three_stage(tsa), args.repeats)),
        ("three-stage, streaming `update()`", cpu(streaming_three_stage, args.repeats)),
    ]
    chains = () if args.quick else ("tsa", "notch", "three-stage", "super-twisting")
    for name in chains:
        rows.append((f"chain `{name}` (events → $x_2$)",
                     cpu(lambda name=name: encoder_chain(traj, encoder, estimator=name, settings=ChainSettings()),
                         args.repeats)))
    table = ["| stage | CPU [ms] | µs/event | µs/sample | × real time |", "| --- | ---: | ---: | ---: | ---: |"]
    for name, t in rows:
        table.append(f"| {name} | {t.show(1e3)} | {number(1e6 * t.median / n_ev)} | {number(1e6 * t.median / n_s)} "
                     f"| {number(DURATION_S / t.median)} |")
    cli = ["| command (whole process) | CPU [s] | × real time |", "| --- | ---: | ---: |"]
    for argv in (["encoder", "--duration", "10"], ["encoder", "--profile", "braking", "--estimator", "three-stage"]):
        t = cli_cpu(argv, args.repeats)
        cli.append(f"| `switchobs {' '.join(argv)}` | {t.show()} | {number(DURATION_S / t.median)} |")
    publish("encoder_chain",
            f"{DURATION_S:g} s of braking from 130 km/h on dry asphalt: {n_ev} events of a 60-ppr encoder, {n_s} "
            f"controller samples at 1 kHz (the plant simulation, {plant_s:.2f} s CPU, not counted); CPU time "
            f"(`time.process_time`), median [min–max] of {args.repeats} runs; × real time = simulated time / "
            "median CPU time. The whole `switchobs encoder` process (`RUSAGE_CHILDREN`) adds the interpreter, "
            "the imports and the simulation of the wheel: what a user waits for.",
            [table, cli], write=not args.quick)


if __name__ == "__main__":
    main()
