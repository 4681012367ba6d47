"""Cost of the wheel-encoder chain over 10 s of braking (60-ppr encoder, 1 kHz controller).

CPU time (``time.process_time``), median [min–max] of 5 runs, per encoder event and per controller
sample for every stage, and the real-time factor (simulated seconds per CPU second); beside it the whole
``switchobs encoder`` process as a user runs it (interpreter, imports, simulation, all estimators).
Goal of issue 5: the three-stage estimator at least 10x faster than real time.  Then the chain inside
the ABS loop (issue 14): the per-step ``EncoderLoopEstimator`` against ``encoder_measurements`` on the
same recorded 10 s braking, each with the Python three-stage estimator and with its C kernel; goal: the
chain of a 10 s braking well under 0.1 s CPU.
Run: ``.venv/bin/python benchmarks/encoder_chain.py [--quick] [--repeats 5]`` (``--quick``: a 2 s braking, one
run, without the whole chains; printed only).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from _harness import MIN_REPEATS, cli_cpu, cpu, number, publish, ratio

from switchobs.loop import EncoderLoopEstimator, encoder_measurements
from switchobs.plants import BrakingScenario, FivePhaseABS, QuarterCar, RoadChange, RoadSchedule, simulate
from switchobs.sensors import (ChainSettings, Encoder, ThreeStageEstimator, TimeStamper, braking_trajectory,
                               controller_times, encoder_chain, notch, three_stage, time_stamping)

DURATION_S = 10.0
QUICK_DURATION_S = 2.0


class _Recorder:
    """An estimator that keeps what the plant hands it: the arrays of ``encoder_measurements``."""

    def reset(self, t0: float, y0: float, vx0: float) -> None:
        self.rows = [(t0, y0, vx0, 0.0, 0.0)]

    def update(self, t: float, y: float, vx: float, u: float, dt: float) -> float:
        self.rows.append((t, y, vx, u, dt))
        return 0.5


def loop_table(repeats: int, duration: float) -> tuple[list[str], str]:
    """The chain of the ABS loop on one recorded braking: per step and at once, Python and C estimator."""
    vehicle = QuarterCar()
    roads = RoadSchedule("dry-asphalt", [RoadChange("snow", at_time_s=1.0)])
    sc = BrakingScenario(roads, speed_m_s=50.0, controller=FivePhaseABS(), vehicle=vehicle, duration_s=duration,
                         stop_speed_m_s=10.0 / 3.6)
    rec = _Recorder()
    simulate(sc, estimator=rec, observer_in_loop=False)
    rows = np.array(rec.rows)
    t, x2, vx, u, dt = rows.T
    encoder = Encoder(ppr=60, dnl_cycles=0.01, eccentricity=0.003, clock_hz=1e6, seed=1)

    def per_step(compiled: bool) -> None:
        chain = EncoderLoopEstimator((), encoder=encoder, radius_m=vehicle.radius_m, compiled=compiled)
        chain.reset(t[0], x2[0], vx[0])
        for i in range(1, t.size):
            chain.update(t[i], x2[i], vx[i], u[i], dt[i])

    def at_once(compiled: bool) -> None:
        encoder_measurements(t, x2, vx, u[1:], dt[1:], encoder=encoder, radius_m=vehicle.radius_m,
                             compiled=compiled)

    meas = encoder_measurements(t, x2, vx, u[1:], dt[1:], encoder=encoder, radius_m=vehicle.radius_m)
    timed = [("per step: `EncoderLoopEstimator.update`, Python three-stage (before)",
              cpu(lambda: per_step(False), repeats)),
             ("per step: `EncoderLoopEstimator.update`, C three-stage", cpu(lambda: per_step(True), repeats)),
             ("whole run: `encoder_measurements`, Python three-stage", cpu(lambda: at_once(False), repeats)),
             ("whole run: `encoder_measurements`, C three-stage", cpu(lambda: at_once(True), repeats))]
    before = timed[0][1].median
    table = ["| encoder chain of the ABS loop | CPU [ms] | µs/sample | × real time | against before |",
             "| --- | ---: | ---: | ---: | --- |"]
    for name, st in timed:
        against = ratio(st.median, before) if st.median != before else "–"
        table.append(f"| {name} | {st.show(1e3)} | {number(1e6 * st.median / meas.t.size)} "
                     f"| {number(duration / st.median)} | {against} |")
    method = (f"The chain inside the ABS loop: {duration:g} s of five-phase ABS braking from 180 km/h, dry asphalt "
              f"then snow from 1 s ({t.size - 1} plant steps, {meas.events} edges, {meas.t.size} controller samples), "
              "recorded once; then the chain on the recorded steps (wheel reconstruction, edges, TSA, three-stage, "
              "notch, the plant's history at the window centres), without observers. Per step is what the loop "
              "runs when the controller reads the estimate; whole run is `switchobs.loop.encoder_measurements` after "
              "the plant (the same numbers bit for bit). Before: the per-step chain as it was, the Python "
              "three-stage estimator.")
    return table, method


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help=f"smoke run: a {QUICK_DURATION_S:g} s braking, one run, the stages without the whole "
                             "chains; printed, not written to benchmarks/results")
    parser.add_argument("--repeats", type=int, help=f"runs per measurement (default {MIN_REPEATS}, 1 with --quick)")
    args = parser.parse_args()
    args.repeats = args.repeats or (1 if args.quick else MIN_REPEATS)
    duration = QUICK_DURATION_S if args.quick else DURATION_S

    start = time.process_time()
    run = braking_trajectory(duration)
    plant_s = time.process_time() - start
    traj = run.trajectory("braking")
    encoder = Encoder(ppr=60, dnl_cycles=0.01, eccentricity=0.003, clock_hz=1e6, seed=1)
    events = encoder.events(traj)
    ts = controller_times(0.0, duration, 1000.0)
    tsa = time_stamping(events.times, events.angles, ts)
    n_ev, n_s = len(events), ts.size

    def streaming_tsa() -> None:
        stamper, k = TimeStamper(order=2, window=15), 0
        for t in ts:
            while k < n_ev and events.times[k] <= t:
                stamper.push(float(events.times[k]), float(events.angles[k]))
                k += 1
            stamper.estimate(float(t))

    def streaming_three_stage(compiled: bool) -> None:
        est = ThreeStageEstimator(5, compiled=compiled)
        for i in np.flatnonzero(tsa.valid):
            est.update(float(tsa.theta[i]), float(tsa.omega[i]), float(tsa.alpha[i]))

    ThreeStageEstimator(compiled=True)     # builds or loads the C kernels before anything is timed
    rows = [
        ("encoder events (simulation side)", cpu(lambda: encoder.events(traj), args.repeats)),
        ("TSA, batch", cpu(lambda: time_stamping(events.times, events.angles, ts), args.repeats)),
        ("TSA, streaming (push + estimate)", cpu(streaming_tsa, args.repeats)),
    ]
    for label, compiled in (("Python", False), ("C", True)):
        rows += [
            (f"notch stage only, {label}", cpu(lambda c=compiled: notch(tsa, compiled=c), args.repeats)),
            (f"three-stage stage only, {label}", cpu(lambda c=compiled: three_stage(tsa, compiled=c), args.repeats)),
            (f"three-stage, streaming `update()`, {label}",
             cpu(lambda c=compiled: streaming_three_stage(c), args.repeats)),
        ]
    chains = () if args.quick else ("tsa", "notch", "three-stage", "super-twisting")
    for name in chains:
        rows.append((f"chain `{name}` (events → $x_2$)",
                     cpu(lambda name=name: encoder_chain(traj, encoder, estimator=name, settings=ChainSettings()),
                         args.repeats)))
    table = ["| stage | CPU [ms] | µs/event | µs/sample | × real time |", "| --- | ---: | ---: | ---: | ---: |"]
    for name, t in rows:
        table.append(f"| {name} | {t.show(1e3)} | {number(1e6 * t.median / n_ev)} | {number(1e6 * t.median / n_s)} "
                     f"| {number(duration / t.median)} |")
    loop, loop_method = loop_table(args.repeats, duration)
    cli = ["| command (whole process) | CPU [s] | × real time |", "| --- | ---: | ---: |"]
    for argv in (["encoder", "--duration", f"{duration:g}"],
                 ["encoder", "--profile", "braking", "--estimator", "three-stage",
                  *(["--duration", f"{duration:g}"] if args.quick else [])]):
        t = cli_cpu(argv, args.repeats)
        cli.append(f"| `switchobs {' '.join(argv)}` | {t.show()} | {number(duration / t.median)} |")
    publish("encoder_chain",
            f"{duration:g} s of braking from 130 km/h on dry asphalt: {n_ev} events of a 60-ppr encoder, {n_s} "
            f"controller samples at 1 kHz (the plant simulation, {plant_s:.2f} s CPU, not counted); CPU time "
            f"(`time.process_time`), median [min–max] of {args.repeats} runs; × real time = simulated time / "
            "median CPU time. The whole `switchobs encoder` process (`RUSAGE_CHILDREN`) adds the interpreter, "
            "the imports and the simulation of the wheel: what a user waits for. Python and C: the three-stage "
            "estimator and the notch in Python (the reference) or their C port (`compiled=True`, the default with a "
            "C compiler); the chains run the default.",
            [table, cli, [loop_method], loop], write=not args.quick)


if __name__ == "__main__":
    main()
