"""Cost of the wheel-encoder chain over 10 s of braking (60-ppr encoder, 1 kHz controller).

Prints microseconds per encoder event and per controller sample for every
stage, and the real-time factor (simulated seconds per second of computing).
Goal of issue 5: the three-stage estimator at least 10x faster than real time.
Run: ``.venv/bin/python benchmarks/encoder_chain.py``.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from switchobs.sensors import (ChainSettings, Encoder, ThreeStageEstimator, TimeStamper, braking_trajectory,
                               controller_times, encoder_chain, notch, three_stage, time_stamping)

DURATION_S = 10.0
REPEATS = 3


def best_of(fn: Callable[[], object]) -> float:
    times = []
    for _ in range(REPEATS):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


def main() -> None:
    start = time.perf_counter()
    run = braking_trajectory(DURATION_S)
    plant_s = time.perf_counter() - start
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
        ("encoder events (simulation side)", best_of(lambda: encoder.events(traj))),
        ("TSA, batch", best_of(lambda: time_stamping(events.times, events.angles, ts))),
        ("TSA, streaming (push + estimate)", best_of(streaming_tsa)),
        ("notch stage only", best_of(lambda: notch(tsa))),
        ("three-stage stage only", best_of(lambda: three_stage(tsa))),
        ("three-stage, streaming update()", best_of(streaming_three_stage)),
    ]
    for name in ("tsa", "notch", "three-stage", "super-twisting"):
        rows.append((f"chain '{name}' (events -> x2)",
                     best_of(lambda name=name: encoder_chain(traj, encoder, estimator=name,
                                                             settings=ChainSettings()))))
    print(f"10 s braking from 130 km/h on dry asphalt: {n_ev} events of a 60-ppr encoder, "
          f"{n_s} controller samples at 1 kHz (plant simulation {plant_s:.2f} s, not counted)")
    print(f"{'stage':<36}{'total [ms]':>12}{'us/event':>11}{'us/sample':>11}{'x real time':>13}")
    for name, seconds in rows:
        print(f"{name:<36}{1e3 * seconds:>12.1f}{1e6 * seconds / n_ev:>11.2f}{1e6 * seconds / n_s:>11.2f}"
              f"{DURATION_S / seconds:>13.1f}")


if __name__ == "__main__":
    main()
