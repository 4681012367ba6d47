"""Cost of replaying a measurement log: a 60 s MDF4 log at 1 kHz with a 60-ppr encoder (issue 32).

CPU time, median [min–max] of 5 runs.  First the whole ``switchobs replay`` process as a user runs it (the C
observer and the Python reference), and the same command on a 1 s log of the same drive: their difference is
the cost of the 59 s more after start-up (interpreter, imports, the observer's symbolic design, the compiled
observer's load), whose real-time factor is the issue's goal (at least 1000× real time).  Then the stages in
one process: reading and mapping the log, the encoder chain (TSA, three-stage, notch), the observer's steps,
writing the result.
Run: ``.venv/bin/python benchmarks/replay_log.py [--quick] [--repeats 5]`` (``--quick``: a 10 s log, one run;
printed only).
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np
from _harness import MIN_REPEATS, cli_cpu, cpu, number, publish

from switchobs.logs import ChannelMap, log_signals, read_log, write_mdf, write_result
from switchobs.loop import edges_from_wheel_speed, ideal_encoder, replay

DURATION_S, QUICK_DURATION_S, SHORT_S = 60.0, 10.0, 1.0
MAP = """
[encoder]
ppr = 60
edges = { channel = "edge_time", unit = "s", teeth = "edge_tooth" }
[signals]
speed = { channel = "vx", unit = "m/s" }
pressure = { channel = "p", unit = "bar" }
"""


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
        (d / "map.toml").write_text(MAP, encoding="utf-8")
        edges = write_drive(d / "long.mf4", duration)
        write_drive(d / "short.mf4", SHORT_S)
        whole = ["| `switchobs replay` | CPU, whole process [s] | 1 s log [s] | after start-up [s] | × real time |",
                 "| --- | ---: | ---: | ---: | ---: |"]
        for impl in ("c", "python"):
            cmd = ["--channels", "map.toml", "--observer-impl", impl, "--out", "out.mf4"]
            long_ = cli_cpu(["replay", "long.mf4", *cmd], repeats, cwd=d)
            short = cli_cpu(["replay", "short.mf4", *cmd], repeats, cwd=d)
            work = long_.median - short.median
            whole.append(f"| `--observer-impl {impl}` | {long_.show()} | {short.show()} | {number(work)} "
                         f"| {number((duration - SHORT_S) / work)} |")
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
    method = (f"CPU time (user + system), median [min–max] of {repeats} runs. A {duration:g} s MDF4 log at 1 kHz (speed and brake pressure, {int(duration * 1000) + 1} samples) with "
              f"the {edges} edges of a 60-ppr encoder, time-stamped to 1 µs, replayed through the encoder chain "
              "(TSA n = 15, three-stage M = 5) and the xbs4 observer (radau3), the result written as MDF4. After "
              f"start-up: the whole process on this log minus the same command on a {SHORT_S:g} s log of the same "
              "drive; × real time is the log's extra seconds over that CPU time.")
    publish("replay_log", method, [whole, table], write=not args.quick)


if __name__ == "__main__":
    main()
