"""Throughput of the sweep engine: runs/s on 1 and 2 Dask workers, its overhead, the single-run real-time factor.

Workload: 48 free-vehicle brakings to 2.5 km/h (six roads of seed 001 Table 2.1 × 40, 60, …, 180 km/h,
five-phase ABS, the 4D XBS observer of seed 000 beside the loop on exact signals), the kind of case a
design-space sweep runs by the thousand.  Measured in the same run:

* the bare loop a user would write instead, ``[run_case(c) for c in cases]`` in-process (CPU time);
* the engine in-process, ``run_sweep(cases, scheduler="none")`` with its results file (CPU time): the
  difference is the engine's own cost per run (rows, JSON, the file, progress);
* the engine on a ``LocalCluster`` of 1 and 2 single-threaded worker processes (started and warmed up
  before timing): wall time of the sweep, runs/s, and the CPU time the workers spent (summed over them);
  the parallel efficiency is ``rate(2 workers) / (2 rate(1 worker))``;
* one 10 s braking on a drum (seed 001 Sec. 3.4 roads: dry asphalt, wet asphalt at 3 s, dry concrete at
  6 s; 1.96 m/s²) as a sweep case with the Python and the generated C observer (the compiled loop), and with
  the C observer fed by a 60-ppr encoder (beside the loop: the plant compiled, the encoder chain and the
  observer replayed over its run): simulated time / CPU time.

Run: ``python benchmarks/sweep.py [--quick] [--repeats 5]``.
"""

from __future__ import annotations

import argparse
import logging
import tempfile
import time
from dataclasses import replace
from pathlib import Path

from _harness import MIN_REPEATS, Stats, cpu, number, publish

from switchobs.sweep import BrakingCase, grid, run_case, run_sweep
from switchobs.sweep._engine import BATCHES_PER_WORKER

ROADS = ("dry-asphalt", "wet-asphalt", "dry-concrete", "dry-cobblestones", "wet-cobblestones", "snow")
# enough cases that a sweep lasts seconds on the compiled loop: a one-second sweep measures Dask's latency
SPEEDS = (40.0, 60.0, 80.0, 100.0, 120.0, 140.0, 160.0, 180.0)


def cases(quick: bool) -> tuple[BrakingCase, ...]:
    base = BrakingCase(observer="xbs4", beta1=100.0, beta2=150.0)
    return grid(base, road=ROADS[:2] if quick else ROADS, speed_kmh=SPEEDS[:2] if quick else SPEEDS)


def on_cluster(workload, workers: int, repeats: int) -> tuple[Stats, Stats]:
    """Wall time of the sweep and the CPU time of its workers, on a warm LocalCluster of ``workers`` processes."""
    import distributed

    with distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0",
                                  silence_logs=logging.ERROR) as cluster, distributed.Client(cluster) as client:
        run_sweep(workload[:workers], scheduler=client)  # imports and first designs on every worker, not timed
        walls, cpus = [], []
        for _ in range(repeats):
            before = sum(client.run(time.process_time).values())
            t0 = time.perf_counter()
            run_sweep(workload, scheduler=client)
            walls.append(time.perf_counter() - t0)
            cpus.append(sum(client.run(time.process_time).values()) - before)
    return Stats(tuple(walls)), Stats(tuple(cpus))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="4 cases, 1 repeat; printed, not written")
    parser.add_argument("--repeats", type=int, default=MIN_REPEATS)
    args = parser.parse_args()
    repeats = 1 if args.quick else args.repeats
    workload = cases(args.quick)
    n = len(workload)
    run_case(workload[0])  # the symbolic design of the observer, cached per process, is not a run's cost
    bare_s, engine_s = [], []
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "rows.jsonl"
        for _ in range(repeats):  # interleaved, so that a change of the machine's load hits both alike
            bare_s += cpu(lambda: [run_case(c) for c in workload], 1).values
            engine_s += cpu(lambda: run_sweep(workload, path=path, scheduler="none"), 1,
                            setup=lambda: path.unlink(missing_ok=True)).values
    bare, engine = Stats(tuple(bare_s)), Stats(tuple(engine_s))
    overhead = (engine.median - bare.median) / n
    rows = ["| engine | workers | wall [s] | runs/s | worker CPU [s] | CPU per run [ms] |",
            "| --- | ---: | ---: | ---: | ---: | ---: |",
            f"| bare loop `[run_case(c) for c in cases]` (CPU time) | 1 (in-process) | {bare.show()} | "
            f"{number(n / bare.median)} | {bare.show()} | {number(1e3 * bare.median / n)} |",
            f"| `run_sweep(scheduler=\"none\")` (CPU time) | 1 (in-process) | {engine.show()} | "
            f"{number(n / engine.median)} | {engine.show()} | {number(1e3 * engine.median / n)} |"]
    rates = {}
    for workers in (1, 2):
        wall, work = on_cluster(workload, workers, repeats)
        rates[workers] = n / wall.median
        rows.append(f"| Dask `LocalCluster` | {workers} | {wall.show()} | {number(rates[workers])} | {work.show()} | "
                    f"{number(1e3 * work.median / n)} |")
        print(rows[-1], flush=True)
    efficiency = rates[2] / (2 * rates[1])
    single = ["| 10 s drum braking (seed 001 Sec. 3.4 roads) | observer | CPU [s] | × real time |",
              "| --- | --- | ---: | ---: |"]
    drum = BrakingCase(road="dry-asphalt", changes=(("wet-asphalt", 3.0), ("dry-concrete", 6.0)), speed_kmh=90.0,
                       decel_m_s2=1.96, duration_s=10.0, observer="xbs4")
    # the C observer runs in the compiled loop; the encoder chain (Python) is replayed over the compiled run
    for impl, ppr in ((("python", 0),) if args.quick else (("python", 0), ("c", 0), ("c", 60))):
        case = replace(drum, impl=impl, encoder_ppr=ppr, method="radau3" if ppr else drum.method)
        sim = run_case(case).metrics["simulated_s"]  # also compiles the C observer once (cached)
        t = cpu(lambda: run_case(case), repeats)
        loop = f"xbs4 ({impl}), {ppr}-ppr encoder" if ppr else f"xbs4 ({impl})"
        single.append(f"| `run_case`, five-phase ABS | {loop} | {t.show()} | {number(sim / t.median)} |")
    notes = [f"Parallel efficiency from 1 to 2 workers: {100 * efficiency:.0f} % "
             f"({number(rates[1])} → {number(rates[2])} runs/s, wall time; "
             f"on a machine shared with other jobs the workers' CPU time shows the work itself). Engine overhead in-process: "
             f"{1e3 * overhead:.3g} ms per run ({100 * overhead * n / bare.median:.2g} % of a bare run), median "
             f"of {repeats}; the Dask rows add the scheduling (about {BATCHES_PER_WORKER} batches per worker) and the transfer of "
             f"the rows."]
    publish("sweep",
            f"{n} brakings to standstill (roads {', '.join(ROADS[:2] if args.quick else ROADS)} × "
            f"{'/'.join(f'{v:g}' for v in (SPEEDS[:2] if args.quick else SPEEDS))} km/h, five-phase ABS, "
            f"xbs4 observer beside the loop, exact signals). In-process rows: CPU time (`time.process_time`); "
            f"Dask rows: wall time of the sweep and the CPU time of its workers (summed), on a warm cluster of "
            f"single-threaded worker processes; median [min–max] of {repeats} runs.",
            [rows, single], notes, write=not args.quick)


if __name__ == "__main__":
    main()
