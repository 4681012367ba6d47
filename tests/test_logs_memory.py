"""Reading a long log holds the channels the map names and a chunk, not the whole file (switchobs.logs._io notes).

A 5-minute drive at 1 kHz with a 60-ppr encoder (300001 signal rows, about 190000 edges: more rows than
one chunk of ``CHUNK_ROWS``) beside 20 channels the map does not name, written by the project in each
format, is read and mapped (``read_log``, ``log_signals``) in a fresh process under ``tracemalloc``
(numpy's buffers included) and, for Parquet, pyarrow's memory pool.  The peak above what the reading
returns (the ``LogSignals`` arrays, 10 MB) is bounded by twice those arrays and an allowance for the
reader: a few chunks for CSV, pyarrow's page buffers for Parquet, asammdf's decoded fragment for MDF4.
Measured peaks, read in pieces and joined (``log_signals``): Parquet 95 MB (the signals' and the edges'
batches side by side), CSV 25 MB, MDF4 81 MB (1 MiB fragments); before, whole columns into arrays of their
size: Parquet 65 MB, CSV 26 MB, MDF4 114 MB (asammdf's 32 MiB fragments); reading every column as whole
tables did (before the chunked readers): Parquet 182 MB and CSV 136 MB, which these bounds refuse.  The
replay itself does not join the pieces (``tests/test_replay_stream.py`` measures its peak).
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from switchobs.logs import CHUNK_ROWS, braking_log_map, write_mdf, write_table
from switchobs.loop import edges_from_wheel_speed, ideal_encoder

from test_logs_replay import needs

DURATION_S = 300.0
UNUSED = 20
#: The reading's peak above the arrays it returns: at most TIMES times them plus the reader's allowance [bytes].
TIMES = 2.0
ALLOWANCE = {"csv": 8 * 8 * CHUNK_ROWS, "parquet": 64 * 2**20, "mf4": 4 * 32 * 2**20}

MEASURE = """
import json, sys, tracemalloc
from switchobs.logs import ChannelMap, log_signals, read_log
cmap = ChannelMap.from_toml(sys.argv[2])
pool = None
if sys.argv[1].endswith(".parquet"):
    import pyarrow
    pool = pyarrow.default_memory_pool()
tracemalloc.start()
signals = log_signals(read_log(sys.argv[1]), cmap)
peak = tracemalloc.get_traced_memory()[1] + (pool.max_memory() if pool is not None else 0)
kept = sum(getattr(signals, k).nbytes for k in ("t", "vx", "pressure", "edge_times", "edge_teeth"))
print(json.dumps({"peak": peak, "kept": kept, "edges": int(signals.edge_times.size)}))
"""


@pytest.fixture(scope="module")
def drive():
    """The samples of benchmarks/replay_log.py's drive over DURATION_S, and UNUSED channels of noise."""
    t = np.arange(int(DURATION_S * 1000) + 1) / 1000.0
    vx = 20.0 + 5.0 * np.sin(2 * np.pi * t / 20.0)
    omega = vx / 0.3 * (1.0 - 0.02 * (1.0 + np.sin(2 * np.pi * 0.7 * t)))
    stamps, teeth = edges_from_wheel_speed(t, omega, ideal_encoder(60))
    rng = np.random.default_rng(3)
    unused = {f"aux{i}": rng.normal(size=t.size) for i in range(UNUSED)}
    return t, vx, 10.0 * np.sin(2 * np.pi * 2.0 * t), np.floor(stamps * 1e6) / 1e6, teeth, unused


@pytest.mark.slow
@pytest.mark.parametrize("ending", ["mf4", "parquet", "csv"])
def test_reading_a_long_log_holds_the_named_channels_and_a_few_chunks(tmp_path, drive, ending):
    needs(ending)
    t, vx, p, stamps, teeth, unused = drive
    assert t.size > CHUNK_ROWS and stamps.size > 100_000
    path = tmp_path / f"drive.{ending}"
    if ending == "mf4":
        write_mdf(path, [(t, {"vx": (vx, "m/s"), "p": (p, "bar"), **{k: (v, "") for k, v in unused.items()}}),
                         (stamps, {"edge_time": (stamps, "s"), "edge_tooth": (teeth, "")})])
    else:
        write_table(path, {"t": t, "vx": vx, "p": p, **unused, "edge_time": stamps, "edge_tooth": teeth.astype(float)})
    (tmp_path / "map.toml").write_text(braking_log_map(), encoding="utf-8")
    proc = subprocess.run([sys.executable, "-c", MEASURE, str(path), str(tmp_path / "map.toml")],
                          capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr
    got = json.loads(proc.stdout)
    assert got["edges"] == stamps.size
    extra, kept = got["peak"] - got["kept"], got["kept"]
    assert extra <= TIMES * kept + ALLOWANCE[ending], (ending, extra / kept)
