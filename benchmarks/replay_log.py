"""Cost of replaying a measurement log: a 60 s MDF4 log at 1 kHz with a 60-ppr encoder (issue 32).

CPU time, median [min–max] of 5 runs.  First the whole ``switchobs replay`` process as a user runs it (the C
observer with and without writing the result, and the Python reference), and the same command on a 1 s log
of the same drive: the difference of their medians is
the cost of the 59 s more after start-up (interpreter, imports, the observer's symbolic design, the compiled
observer's load), whose real-time factor is the issue's goal (at least 1000× real time).  The start-up varies
from run to run by more than that work on a shared machine, so the same commands are also timed in one
process after a first command (``main`` called again: the start-up paid once).  Then the stages in one
process: reading and mapping the log, the encoder chain (TSA, three-stage, notch), the observer's steps,
writing the result.
Last, the memory: the peak resident set (``/usr/bin/time -f %M``) of the same command with ``--out out.mf4``
on drives of one minute, ten minutes and an hour (the replay reads, runs and writes piece by piece, so the
peak should not grow with the log).
Run: ``.venv/bin/python benchmarks/replay_log.py [--quick] [--repeats 5]`` (``--quick``: a 10 s log, one run,
memory on 10 s and 60 s drives; printed only).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import shutil
import statistics
import subprocess
import tempfile
from pathlib import Path

import numpy as np
from _harness import MIN_REPEATS, Stats, cli_cpu, cpu, number, publish, switchobs_exe

from switchobs.logs import ChannelMap, braking_log_map, log_signals, read_log, write_mdf, write_result
from switchobs.loop import edges_from_wheel_speed, ideal_encoder, replay

DURATION_S, QUICK_DURATION_S, SHORT_S = 60.0, 10.0, 1.0
#: Drives whose peak memory is measured [s] (and with --quick).
MEMORY_S, QUICK_MEMORY_S = (60.0, 600.0, 3600.0), (10.0, 60.0)
MEMORY_REPEATS = 3


def write_drive(path: Path, duration: float) -> int:
    """A drive at 15-25 m/s with a slipping wheel and a cycling brake pressure, at 1 kHz, edges to 1 µs."""
    t = np.arange(int(round(duration * 1000)) + 1) / 1000.0
    vx = 20.0 + 5.0 * np.sin(2 * np.pi * t / 20.0)
    omega = vx / 0.3 * (1.0 - 0.02 * (1.0 + np.sin(2 * np.pi * 0.7 * t)))
    p = 10.0 * np.sin(2 * np.pi * 2.0 * t)
    stamps, teeth = edges_from_wheel_speed(t, omega, ideal_encoder(60))
    stamps = np.floor(stamps * 1e6) / 1e6
    write_mdf(path, [(t, {"vx": (vx, "m/s"), "p": (p, "bar")}),
                     (stamps, {"edge_time": (stamps, "s"), "edge_tooth": (teeth, "")})])
    return int(stamps.size)


def peak_memory(argv: list[str], repeats: int, cwd: Path) -> list[int]:
    """Peak resident set [kB] of whole ``switchobs ARGV`` processes (``/usr/bin/time -f %M``, GNU time: the
    child's own peak, not that of this process, which holds the long drives it wrote)."""
    timer = shutil.which("time", path="/usr/bin:/bin")
    if timer is None:
        raise SystemExit("the memory table needs GNU time (/usr/bin/time); install it (Debian: apt-get install time)")
    out = []
    for _ in range(repeats):
        proc = subprocess.run([timer, "-f", "%M", switchobs_exe(), *argv], cwd=cwd, capture_output=True, text=True)
        if proc.returncode != 0:
            raise SystemExit(f"switchobs {' '.join(argv)} failed ({proc.returncode}): {proc.stderr.strip()}")
        out.append(int(proc.stderr.strip().splitlines()[-1]))
    return out


def in_process(argv: list[str], repeats: int) -> Stats:
    """CPU time of ``switchobs ARGV`` run by ``main`` in this process, after a first call (not timed)."""
    from switchobs.cli.main import main as cli

    def run() -> None:
        with contextlib.redirect_stdout(io.StringIO()):
            if cli(argv) != 0:
                raise SystemExit(f"switchobs {' '.join(argv)} failed")
    run()
    return cpu(run, repeats)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help=f"smoke run: a {QUICK_DURATION_S:g} s log, one run; printed, not written")
    parser.add_argument("--repeats", type=int, help=f"runs per measurement (default {MIN_REPEATS}, 1 with --quick)")
    args = parser.parse_args()
    repeats = args.repeats or (1 if args.quick else MIN_REPEATS)
    duration = QUICK_DURATION_S if args.quick else DURATION_S
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        (d / "map.toml").write_text(braking_log_map(), encoding="utf-8")
        edges = write_drive(d / "long.mf4", duration)
        write_drive(d / "short.mf4", SHORT_S)
        whole = ["| `switchobs replay` | CPU, whole process [s] | 1 s log [s] | after start-up [s] | × real time |",
                 "| --- | ---: | ---: | ---: | ---: |"]
        for impl, out in (("c", ["--out", "out.mf4"]), ("c", []), ("python", ["--out", "out.mf4"])):
            cmd = ["--channels", "map.toml", "--observer-impl", impl, *out]
            long_ = cli_cpu(["replay", "long.mf4", *cmd], repeats, cwd=d)
            short = cli_cpu(["replay", "short.mf4", *cmd], repeats, cwd=d)
            work = long_.median - short.median
            whole.append(f"| `--observer-impl {impl}{' --out out.mf4' if out else ''}` | {long_.show()} "
                         f"| {short.show()} | {number(work)} | {number((duration - SHORT_S) / work)} |")
        # the same commands in one process after a first one: start-up (imports, the observer's design, the
        # compiled observer's load) paid once, the rest as the command does it (read, chain, observer, write)
        warm = [f"| `switchobs replay` after a first command in the process | {duration:g} s log [ms] "
                f"| {SHORT_S:g} s log [ms] | after start-up [ms] | × real time |", "| --- | ---: | ---: | ---: | ---: |"]
        for out in (["--out", "out.mf4"], ["--out", "out.parquet"], []):
            cmd = ["--channels", str(d / "map.toml"), "--observer-impl", "c", *[str(d / o) if o.startswith("out")
                                                                                 else o for o in out]]
            long_, short = (in_process(["replay", str(d / f), *cmd], repeats) for f in ("long.mf4", "short.mf4"))
            work = long_.median - short.median
            warm.append(f"| `--observer-impl c{' ' + out[0] + ' ' + out[1] if out else ''}` | {long_.show(1e3)} "
                        f"| {short.show(1e3)} | {number(1e3 * work)} | {number((duration - SHORT_S) / work)} |")
        cmap = ChannelMap.from_toml(d / "map.toml")
        signals = log_signals(read_log(d / "long.mf4"), cmap)
        result = replay(signals, impl="c")                        # builds and loads the C observer once
        stages = [("read and map the log (`read_log`, `log_signals`)",
                   cpu(lambda: log_signals(read_log(d / "long.mf4"), cmap), repeats)),
                  ("chain and C observer (`replay(..., impl=\"c\")`)", cpu(lambda: replay(signals, impl="c"), repeats)),
                  ("chain alone (`replay(..., observer=\"none\")`)",
                   cpu(lambda: replay(signals, observer="none"), repeats)),
                  ("write the result (`write_result`, MDF4)", cpu(lambda: write_result(result, d / "r.mf4"), repeats))]
        table = ["| stage (one process, after start-up) | CPU [ms] | × real time |", "| --- | ---: | ---: |"]
        for name, st in stages:
            table.append(f"| {name} | {st.show(1e3)} | {number(duration / st.median)} |")
        memory = ["| drive | samples | edges | log [MB] | peak RSS [MB] |", "| --- | ---: | ---: | ---: | ---: |"]
        for seconds in QUICK_MEMORY_S if args.quick else MEMORY_S:
            log = d / f"drive{seconds:g}.mf4"
            count = write_drive(log, seconds)
            peaks = peak_memory(["replay", log.name, "--channels", "map.toml", "--observer-impl", "c", "--out",
                                 "out.mf4"], MEMORY_REPEATS, d)
            shown = " [".join([number(statistics.median(peaks) / 1024), f"{number(min(peaks) / 1024)}–"
                               f"{number(max(peaks) / 1024)}]"])
            span = f"{seconds:g} s" if seconds < 60 else f"{seconds / 60:g} min" if seconds < 3600 else \
                f"{seconds / 3600:g} h"
            memory.append(f"| {span} | {int(seconds * 1000) + 1} | {count} | "
                          f"{number(log.stat().st_size / 1e6)} | {shown} |")
            log.unlink()
    method = (f"CPU time (user + system), median [min–max] of {repeats} runs. A {duration:g} s MDF4 log at 1 kHz (speed and brake pressure, {int(duration * 1000) + 1} samples) with "
              f"the {edges} edges of a 60-ppr encoder, time-stamped to 1 µs, replayed through the encoder chain "
              "(TSA n = 15, three-stage M = 5) and the xbs4 observer (radau3), the result written as MDF4. After "
              f"start-up: the whole process on this log minus the same command on a {SHORT_S:g} s log of the same "
              "drive; × real time is the log's extra seconds over that CPU time. On a shared machine the start-up "
              "alone varies from run to run by more than the replay's work, so this difference is noisy (even of "
              "either sign); the next table times the same commands without it.")
    method += (" In one process: `switchobs.cli.main.main` called with the same arguments after a first call (which "
               "paid the start-up), the 60 s log's command minus the 1 s log's. Memory: the peak resident set of "
               "`switchobs replay LOG --channels map.toml --observer-impl c --out out.mf4` (`/usr/bin/time -f %M`), "
               f"median [min–max] of {MEMORY_REPEATS} runs, on the same drive written by the project's MDF4 writer for "
               "one minute, ten minutes and an hour.")
    publish("replay_log", method, [whole, warm, table, memory], write=not args.quick)


if __name__ == "__main__":
    main()
