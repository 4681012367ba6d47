"""Cost of the Python reference observers per step (``step``, ``run``, the ABS adapter) against the C twin.

CPU time (``time.process_time``), median [min–max] of 5 runs over N steps (default 10 000, i.e. 10 s of
signals at 1 kHz); the baseline a user would pick for speed is the generated C of the same observer,
``CObserver.like(observer).run`` (compiled before timing).  Build is the constructor's CPU time (the first
one per model includes the cold symbolic design).
Usage: ``python benchmarks/observer_step.py [--quick] [--steps N] [--repeats 5]``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from _harness import MIN_REPEATS, cpu, number, publish, ratio

from switchobs.codegen import CObserver
from switchobs.loop import ObserverXbsEstimator
from switchobs.observers import adaptive_xbs_observer, xbs3_observer, xbs4_observer


def _signals(n: int, dt: float) -> np.ndarray:
    """An ABS-like record: y oscillating at 6 Hz, vx decreasing from 25 m/s, u of a few hundred bar/s."""
    t = np.arange(n) * dt
    return np.column_stack([30 * np.sin(2 * np.pi * 6 * t), 25 - 1.5 * t, 400 * np.cos(2 * np.pi * 6 * t)])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=10_000)
    parser.add_argument("--repeats", type=int, default=MIN_REPEATS)
    parser.add_argument("--quick", action="store_true",
                        help="smoke run: 1 000 steps; printed, not written to benchmarks/results")
    args = parser.parse_args()
    n, dt = (1_000 if args.quick else args.steps), 1e-3
    rows = _signals(n, dt)
    makers = [
        ("xbs3 (abs-xbs3, n=3)", lambda m: xbs3_observer(100.0, 100.0, method=m)),
        ("xbs4 (abs-xbs4, n=4)", lambda m: xbs4_observer(100.0, 100.0, method=m)),
        ("adaptive (abs-adaptive2, n=8)", lambda m: adaptive_xbs_observer(60.0, [1e3, 1e3], method=m)),
    ]
    table = ["| observer | method | build [s] | `step` [µs] | `run` [µs] | adapter update [µs] | C `_run` [µs] "
             "| `run` vs C `_run` | `run` of 10 s at 1 kHz [ms] |",
             "| --- | --- | ---: | ---: | ---: | ---: | ---: | --- | ---: |"]
    for name, make in makers:
        for method in ("rk4", "euler"):
            t0 = time.process_time()
            obs = make(method)
            build = time.process_time() - t0
            x0 = np.zeros(obs.size)
            x0[0] = rows[0, 0]

            def by_step() -> None:
                x = x0
                for row in rows:
                    x = obs.step(x, row, dt)

            est = ObserverXbsEstimator(obs)
            y, vx, u = rows[:, 0].tolist(), rows[:, 1].tolist(), rows[:, 2].tolist()

            def by_adapter() -> None:
                est.reset(0.0, y[0], vx[0])
                for k in range(1, n):
                    est.update(k * dt, y[k], vx[k], u[k], dt)

            c_obs = CObserver.like(obs)
            t_step = cpu(by_step, args.repeats).scaled(1e6 / n)
            t_run = cpu(lambda: obs.run(x0, rows, dt), args.repeats).scaled(1e6 / n)
            t_adapter = cpu(by_adapter, args.repeats).scaled(1e6 / (n - 1))
            t_c = cpu(lambda: c_obs.run(x0, rows, dt), args.repeats).scaled(1e6 / n)
            table.append(f"| {name} | {method} | {number(build)} | {t_step.show()} | {t_run.show()} | "
                         f"{t_adapter.show()} | {t_c.show()} | {ratio(t_run.median, t_c.median)} | "
                         f"{number(t_run.median * 10_000 / 1e3)} |")
            print(table[-1], flush=True)
    publish("observer_step",
            f"{n} steps of dt = {dt * 1e3:g} ms of ABS-like signals; CPU time (`time.process_time`), median "
            f"[min–max] of {args.repeats} runs, µs per step; *C `_run`*: the generated C of the same observer "
            "through `CObserver.like(observer).run`; *vs*: the Python `run` against it.",
            [table], write=not args.quick)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
