"""The 1000-case Monte-Carlo robustness study (``examples/sweep_robustness.toml``) as a user runs it.

Workload: ``switchobs sweep examples/sweep_robustness.toml --out <tmp>/robustness.jsonl --plots <tmp>`` (the
4D XBS observer on a 60-ppr encoder beside the five-phase ABS, four (beta1, beta2) pairs × 250 random roads,
road changes, speeds and encoder seeds, the heatmaps and the tuned pair) on the default local Dask cluster,
one whole ``switchobs`` process from start to exit.  Measured:

* its wall time and the CPU time of the process and its Dask workers (``RUSAGE_CHILDREN``, what
  ``/usr/bin/time`` reports), once: the study is the repetition;
* the CPU time per case, in-process on the first cases of the study (``run_case``, ``time.process_time``,
  after one warm-up case that designs and compiles the observer), median [min–max].

Then a small study on a real cluster: the spec with 50 draws per gain pair (200 cases, four C observers),
``switchobs sweep ... --scheduler none`` against the same command on a cluster of separate processes
started before it (``dask scheduler`` and two ``dask worker --nthreads 1``, fresh for each run: their first
case would import the stack and build the four observers), wall time of the whole ``switchobs`` process,
median [min–max] of ``--repeats`` runs, and the same study run a second time on a cluster whose workers
ran it once (warm: the stack imported, the observers installed): the difference of the two is the start-up
of fresh workers.  The workers are warmed once per study: they import the stack while the command builds the
C observers, which every worker then takes before the first batch (``switchobs.sweep`` module notes).  The
rows of every run must be the same bytes.  Beside them, two in-process runs started together: what a
second process gets from the machine's other core (on a shared machine, maybe nothing).

Run: ``python benchmarks/sweep_robustness.py [--quick] [--count N] [--sample K] [--repeats R]`` (``--count``:
draws per gain pair instead of the spec's 250; ``--quick``: 2 draws, 4 sampled cases, a 20-case cluster
study once, printed and not written).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from _harness import MIN_REPEATS, Stats, cpu, number, publish, switchobs_exe

from switchobs.sweep import load_sweep_spec, read_results, run_case

ROOT = Path(__file__).resolve().parents[1]
SPEC = ROOT / "examples" / "sweep_robustness.toml"


@contextmanager
def dask_cluster(workdir: Path, workers: int = 2) -> Iterator[str]:
    """A Dask scheduler and ``workers`` single-threaded workers as separate processes; yields the address."""
    dask = str(Path(sys.executable).with_name("dask"))
    info = workdir / "scheduler.json"
    info.unlink(missing_ok=True)
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, "cwd": workdir}
    procs = [subprocess.Popen([dask, "scheduler", "--port", "0", "--dashboard-address", ":0",
                               "--scheduler-file", str(info)], **quiet)]
    try:
        deadline = time.monotonic() + 60
        while not info.exists():
            if time.monotonic() > deadline:
                raise SystemExit("the dask scheduler did not start within 60 s")
            time.sleep(0.1)
        time.sleep(0.2)                            # the file is written whole, then read
        address = json.loads(info.read_text())["address"]
        procs += [subprocess.Popen([dask, "worker", address, "--nthreads", "1", "--nworkers", "1",
                                    "--dashboard-address", ":0"], **quiet) for _ in range(workers)]
        import distributed

        with distributed.Client(address, timeout="60s") as client:
            client.wait_for_workers(workers, timeout=120)
        yield address
    finally:
        for proc in reversed(procs):
            proc.terminate()
        for proc in procs:
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()


def small_study(tmp: Path, count: int, repeats: int) -> tuple[list[str], int, float]:
    """Rows of the in-process / cluster table for the spec with ``count`` draws per pair, its cases, and the
    start-up of fresh workers (the median wall of the fresh cluster's run less that of the warm one)."""
    spec = tmp / f"robustness-{count}.toml"
    spec.write_text(re.sub(r"(?m)^count = \d+", f"count = {count}", SPEC.read_text()), encoding="utf-8")
    cases = len(load_sweep_spec(spec).cases)
    walls: dict[str, list[float]] = {"none": [], "cluster": [], "again": [], "pair": []}
    cpus: dict[str, list[float]] = {"none": [], "cluster": []}

    def run(where: str, address: str | None, at_once: int = 1) -> float:
        """Wall time until ``at_once`` copies of the command, started together, have all exited."""
        commands = []
        for copy in range(at_once):
            out = tmp / f"small-{where}{copy or ''}.jsonl"
            out.unlink(missing_ok=True)
            commands.append(["sweep", str(spec), "--out", str(out), "-q", "--scheduler", address or "none"])
        t0 = time.perf_counter()
        procs = [subprocess.Popen([switchobs_exe(), *c], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                  text=True) for c in commands]
        errors = [proc.communicate()[1] for proc in procs]
        wall = time.perf_counter() - t0
        for command, proc, error in zip(commands, procs, errors):
            if proc.returncode != 0:
                raise SystemExit(f"switchobs {' '.join(command)} failed ({proc.returncode}): {error.strip()}")
        return wall

    for _ in range(repeats):                     # interleaved: a change of the machine's load hits all four
        for where in ("none", "cluster", "again", "pair"):
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            with dask_cluster(tmp) if where != "none" else _nothing() as address:
                if where == "again":
                    run("warm-up", address)      # the same study once before: its workers are warm
                # the pair: two in-process runs at once, what the machine's second core gives a second process
                walls[where].append(run(where, address, 2 if where == "pair" else 1))
            after = resource.getrusage(resource.RUSAGE_CHILDREN)   # the cluster's processes reaped by now
            if where in cpus:
                cpus[where].append((after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime))
    (none, cluster), (cpu_none, cpu_cluster) = ((Stats(tuple(d["none"])), Stats(tuple(d["cluster"])))
                                                for d in (walls, cpus))
    again, pair = Stats(tuple(walls["again"])), Stats(tuple(walls["pair"]))
    first = (tmp / "small-none.jsonl").read_bytes()
    if any((tmp / f"small-{where}.jsonl").read_bytes() != first for where in ("cluster", "again", "pair", "pair1")):
        raise SystemExit("the cluster's rows differ from the in-process rows")
    rows = [f"| the spec with `count = {count}` draws per pair ({cases} cases) | wall, whole process [s] | cases/s "
            "| CPU, all processes [s] |", "| --- | ---: | ---: | ---: |",
            f"| `--scheduler none` (in-process) | {none.show()} | {number(cases / none.median)} | {cpu_none.show()} |",
            f"| `--scheduler tcp://…`: `dask scheduler`, 2 × `dask worker --nthreads 1`, just started "
            f"| {cluster.show()} | {number(cases / cluster.median)} | {cpu_cluster.show()} |",
            f"| the same study again on the same cluster (its workers warm) | {again.show()} "
            f"| {number(cases / again.median)} | – |",
            f"| two `--scheduler none` runs at once, until both exit (what a second process gets here) "
            f"| {pair.show()} | {number(2 * cases / pair.median)} | – |"]
    return rows, cases, cluster.median - again.median


@contextmanager
def _nothing() -> Iterator[None]:
    yield None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="2 draws per pair, 4 sampled cases; not written")
    parser.add_argument("--count", type=int, help="draws per gain pair (default: the spec's)")
    parser.add_argument("--sample", type=int, default=20, help="cases timed in-process (default 20)")
    parser.add_argument("--repeats", type=int, default=MIN_REPEATS, help="runs of the small study on each engine")
    args = parser.parse_args()
    count = 2 if args.quick else args.count
    sample = 4 if args.quick else args.sample
    with tempfile.TemporaryDirectory() as tmp:
        spec_path = SPEC
        if count is not None:
            spec_path = Path(tmp) / "robustness.toml"
            spec_path.write_text(re.sub(r"(?m)^count = \d+", f"count = {count}", SPEC.read_text()), encoding="utf-8")
        cases = load_sweep_spec(spec_path).cases
        out, plots = Path(tmp) / "robustness.jsonl", Path(tmp) / "plots"
        plots.mkdir()
        command = ["sweep", str(spec_path), "--out", str(out), "--plots", str(plots), "-q"]
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        load0 = os.getloadavg()[0]
        t0 = time.perf_counter()
        proc = subprocess.run([switchobs_exe(), *command], capture_output=True, text=True, check=False)
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        if proc.returncode != 0:
            raise SystemExit(f"switchobs {' '.join(command)} failed ({proc.returncode}): {proc.stderr.strip()}")
        work = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        rows = read_results(out)
        figures = sorted(p.name for p in plots.iterdir())
        tuned = next((line.split(";")[0].removeprefix("chosen: ") for line in proc.stdout.splitlines()
                      if line.startswith("chosen:")), "none")
    simulated = sum(r.metrics.get("simulated_s") or 0.0 for r in rows)
    statuses = {s: sum(r.status == s for r in rows) for s in sorted({r.status for r in rows})}
    run_case(cases[0])  # the observer's design and C build, cached per process: not a case's cost
    per_case = Stats(tuple(cpu(lambda c=c: run_case(c), 1).values[0] for c in cases[:sample]))
    shown = "`switchobs sweep examples/sweep_robustness.toml --out robustness.jsonl --plots DIR`" if count is None \
        else f"the same with `count = {count}` draws per pair"
    table = ["| study | cases | wall [s] | CPU, process + workers [s] | CPU per case, in-process [s] | "
             "simulated [s] | load average at the start |",
             "| --- | ---: | ---: | ---: | ---: | ---: | ---: |",
             f"| {shown} | {len(rows)} | {number(wall)} | {number(work)} | {per_case.show()} | {number(simulated)} | "
             f"{load0:.1f} |"]
    notes = [f"Statuses: {', '.join(f'{n} {s}' for s, n in statuses.items())}; figures: {', '.join(figures)}; "
             f"tuned pair: {tuned}. The CPU per case is the median [min–max] over the first {len(per_case.values)} "
             f"cases of the study ({number(sum(per_case.values) / len(per_case.values))} s on average). On a "
             f"machine shared with other jobs (load average above its cores) the wall time measures the queue "
             f"for the processors; the CPU time is the work."]
    with tempfile.TemporaryDirectory() as tmp:
        small, small_cases, start_up = small_study(Path(tmp), 5 if args.quick else 50, 1 if args.quick else args.repeats)
    notes.append(f"The {small_cases}-case study: wall time from the command's start to its exit, median [min–max] "
                 f"of {1 if args.quick else args.repeats} runs of each, interleaved; the cluster's processes are "
                 "started before each run and stopped after it; the cluster rows include building the four C "
                 "observers in the command (the workers import the stack meanwhile) and handing them to every "
                 "worker; the warm row's cluster ran the study once before (untimed). The start-up of fresh "
                 f"workers, the difference of the two cluster rows' medians: {number(start_up)} s. The rows of "
                 "every run are the same bytes. Two in-process runs started together end after the pair's wall "
                 "time: twice one run's when the machine's other jobs leave our processes one core, then no "
                 "parallel run can gain. CPU: the command's, and for the cluster also its scheduler's "
                 "and workers' from their start to their stop (their start-up included).")
    publish("sweep_robustness",
            "The Monte-Carlo robustness study on the default local Dask cluster (one single-threaded worker "
            "process per core), as one whole `switchobs` process from start to exit (interpreter start-up, "
            "cluster start, the C observers' design and build, once each in the command and then handed to "
            "every worker, the cases, the tables, plots and tuning), run once; the encoder chain runs over the "
            "compiled plant's run afterwards (`switchobs.plants.simulate`, replay).",
            [table, small], notes, write=not args.quick)


if __name__ == "__main__":
    main()
