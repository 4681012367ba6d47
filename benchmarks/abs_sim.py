"""Benchmark of the ABS braking simulation (issue 4): a 10 s braking scenario at the documented step.

Scenario ``aguado-sec34`` (seed 001 Sec. 3.4: 25 m/s on a drum decelerating at
1.96 m/s², dry asphalt -> wet asphalt at 3 s -> dry concrete at 6 s, five-phase
ABS), RK4 at 1 ms, with each reference observer of :mod:`switchobs.observers`
run beside the loop (and the generated C twin of the adaptive one, issue 6), and the two-phase ABS with the adaptive observer in the
loop.  Prints wall and CPU time (best of ``REPEAT``), the real-time factor
(simulated time / wall time, and / process CPU time, which other jobs on
the machine do not inflate), the share of the wall time spent in the
observer's ``update`` and the cost per step.  Run: ``python benchmarks/abs_sim.py``.
"""

from __future__ import annotations

import time
from dataclasses import replace

from switchobs.loop import EstimatorSpec, xbs_estimator
from switchobs.plants import TwoPhaseABS, scenario, simulate, table41

REPEAT = 3


def measure(label: str, sc, observer: str, in_loop: bool = True, impl: str = "python") -> None:
    best = None
    for _ in range(REPEAT):
        est = xbs_estimator(EstimatorSpec(observer, impl=impl), sc.vehicle, sc.roads.initial)
        c0 = time.process_time()
        res = simulate(sc, estimator=est, observer_in_loop=in_loop)
        cpu = time.process_time() - c0
        if best is None or res.wall_time_s < best[0].wall_time_s:
            best = (res, cpu)
    res, cpu = best
    sim = float(res.series["t"][-1])
    share = res.observer_time_s / res.wall_time_s
    name = observer if impl == "python" else f"{observer} (C)"
    print(f"| {label:<22} | {name:<12} | {res.steps:6d} | {res.wall_time_s:6.3f} | {cpu:6.3f} | "
          f"{sim / res.wall_time_s:13.1f} | {sim / cpu:12.1f} | {100 * share:12.1f} % | "
          f"{1e6 * res.wall_time_s / res.steps:7.1f} |")


def main() -> None:
    sc = scenario("aguado-sec34")
    print(f"ABS simulation benchmark: {sc.duration_s:g} s scenario {sc.name}, RK4 dt = {sc.dt_s * 1e3:g} ms "
          f"(best of {REPEAT})")
    print("| run                    | observer     | steps  | wall s | CPU s  | x real (wall) | x real (CPU) | observer share | us/step |")
    print("|------------------------|--------------|--------|--------|--------|---------------|--------------|----------------|---------|")
    for obs in ("none", "xbs3", "xbs4", "adaptive"):
        measure("five-phase, beside", sc, obs, in_loop=False)
    measure("five-phase, beside", sc, "adaptive", in_loop=False, impl="c")
    measure("two-phase, in the loop", replace(sc, controller=TwoPhaseABS()), "adaptive")
    t0 = time.perf_counter()
    res = table41()
    print(f"\nseed 001 Table 4.1 campaign (30 free-vehicle brakings to standstill, true XBS): "
          f"{time.perf_counter() - t0:.2f} s wall; two-phase shorter everywhere: {res.two_phase_always_shorter}")


if __name__ == "__main__":
    main()
