"""Cost of the Python reference observers: microseconds per step, ``step`` vs ``run`` (and the ABS adapter).

Usage: ``python benchmarks/observer_step.py [--steps N]``.  Prints a markdown
table; each figure is the best of 3 repetitions over N steps (default 10 000,
i.e. 10 s of signals at 1 kHz).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from switchobs.loop import ObserverXbsEstimator
from switchobs.observers import adaptive_xbs_observer, xbs3_observer, xbs4_observer


def _best(fn, repeat: int = 3) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def _signals(n: int, dt: float) -> np.ndarray:
    """An ABS-like record: y oscillating at 6 Hz, vx decreasing from 25 m/s, u of a few hundred bar/s."""
    t = np.arange(n) * dt
    return np.column_stack([30 * np.sin(2 * np.pi * 6 * t), 25 - 1.5 * t, 400 * np.cos(2 * np.pi * 6 * t)])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=10_000)
    args = parser.parse_args()
    n, dt = args.steps, 1e-3
    rows = _signals(n, dt)
    makers = [
        ("xbs3 (abs-xbs3, n=3)", lambda m: xbs3_observer(100.0, 100.0, method=m)),
        ("xbs4 (abs-xbs4, n=4)", lambda m: xbs4_observer(100.0, 100.0, method=m)),
        ("adaptive (abs-adaptive2, n=8)", lambda m: adaptive_xbs_observer(60.0, [1e3, 1e3], method=m)),
    ]
    print(f"{n} steps of dt = {dt * 1e3:g} ms (best of 3); µs per step")
    print()
    print("| observer | method | build [s] | step [µs] | run [µs] | adapter update [µs] | run of 10 s at 1 kHz [s] |")
    print("| --- | --- | ---: | ---: | ---: | ---: | ---: |")
    for name, make in makers:
        for method in ("rk4", "euler"):
            t0 = time.perf_counter()
            obs = make(method)
            build = time.perf_counter() - t0
            x0 = np.zeros(obs.size)
            x0[0] = rows[0, 0]

            def by_step() -> None:
                x = x0
                for row in rows:
                    x = obs.step(x, row, dt)

            def by_run() -> None:
                obs.run(x0, rows, dt)

            est = ObserverXbsEstimator(obs)
            y, vx, u = rows[:, 0].tolist(), rows[:, 1].tolist(), rows[:, 2].tolist()

            def by_adapter() -> None:
                est.reset(0.0, y[0], vx[0])
                for k in range(1, n):
                    est.update(k * dt, y[k], vx[k], u[k], dt)

            t_step, t_run, t_adapter = _best(by_step), _best(by_run), _best(by_adapter)
            ten_s = t_run * 10_000 / n
            print(f"| {name} | {method} | {build:.2f} | {t_step / n * 1e6:.2f} | {t_run / n * 1e6:.2f} | "
                  f"{t_adapter / (n - 1) * 1e6:.2f} | {ten_s:.3f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
