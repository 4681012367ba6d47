"""What `switchobs demo` costs: its stages, the whole process, and the generated C step it ships.

Runs the whole ``switchobs demo`` process ``--repeats`` times (default 5) into a temporary directory and
reads each run's ``report.json``: the wall time of each stage (the demo's own stage clock) and the C
observers' ``<prefix>_run`` ns per step (best of 3 inside the demo) and one ``<prefix>_step`` through ctypes.
The whole process is timed in CPU (``RUSAGE_CHILDREN``) beside its wall time.  The table goes to
``benchmarks/results/demo.md`` (rendered into the docs by ``benchmarks/render_docs.py``).
Run: ``python benchmarks/demo.py [--quick] [--repeats 5]`` (``--quick``: ``demo --fast``, printed only).
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import tempfile
import time
from pathlib import Path

from _harness import MIN_REPEATS, Stats, publish, switchobs_exe

def one_run(out: Path, fast: bool) -> tuple[float, float, dict]:
    """CPU and wall seconds of one whole ``switchobs demo`` process, and its report."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run([switchobs_exe(), "demo", "--out", str(out), *(["--fast"] if fast else [])],
                          capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise SystemExit(f"switchobs demo failed ({proc.returncode}): {proc.stderr.strip()[-400:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, wall, json.loads((out / "report.json").read_text(encoding="utf-8"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="switchobs demo --fast, 2 runs; print, do not publish")
    parser.add_argument("--repeats", type=int, default=MIN_REPEATS)
    args = parser.parse_args()
    if args.quick:  # a smoke run: two runs show that it works
        args.repeats = min(args.repeats, 2)
    cpus, walls, reports = [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(max(args.repeats, 1)):
            cpu, wall, report = one_run(Path(tmp) / f"run{i}", args.quick)
            cpus.append(cpu)
            walls.append(wall)
            reports.append(report)
    stages = list(reports[0]["timings"])  # the report stage writes report.json, so it is not in it
    stage = {name: Stats(tuple(r["timings"][name] for r in reports)) for name in stages}
    header = "| | " + " | ".join(stages) + " | these stages | whole process |"
    table = [header, "|---|" + "---:|" * (len(stages) + 2),
             "| wall time [s] | " + " | ".join(stage[s].show() for s in stages)
             + f" | {Stats(tuple(sum(r['timings'][s] for s in stages) for r in reports)).show()} "
               f"| {Stats(tuple(walls)).show()} |",
             "| CPU time [s] | " + " | ".join("–" for _ in stages) + f" | – | {Stats(tuple(cpus)).show()} |"]
    models = [m["model"] for m in reports[0]["models"]]
    c_table = ["| model | C `_run` [ns/step] | C `_step` via ctypes [µs] |", "|---|---:|---:|"]
    for k, name in enumerate(models):
        run_ns = Stats(tuple(r["models"][k]["c_run_ns"] * 1e-9 for r in reports))
        step_us = Stats(tuple(r["models"][k]["c_step_us"] * 1e-6 for r in reports))
        c_table.append(f"| {name} | {run_ns.show(1e9)} | {step_us.show(1e6)} |")
    method = (f"`switchobs demo{' --fast' if args.quick else ''}` as a whole process, {len(reports)} runs: "
              "the wall time of each stage (the demo's own stage clock, `time.perf_counter`; the last stage, "
              "which writes the figures and the report, is only in the whole process) and of the whole "
              "process, and its CPU time (`RUSAGE_CHILDREN`: interpreter, imports and every stage), median "
              "[min–max]; the generated C step the demo ships, as the demo measures it (`<prefix>_run` over "
              f"{reports[0]['settings'].get('timing_steps', 'the')} ABS-like samples, best of 3, and one "
              "`<prefix>_step` through ctypes), median [min–max] over the runs.")
    notes = ["The braking stage simulates the whole emergency braking with the encoder chain and the C observers "
             "in the loop. Goal (whole demo under 3 minutes, `--fast` well under a minute): "
             f"{'**met**' if max(walls) < 180 else '**not met**'} (slowest run {max(walls):.1f} s wall)."]
    publish("demo", method, [table, c_table], notes, write=not args.quick)


if __name__ == "__main__":
    main()
