"""A replay streamed in pieces equals the replay of the whole log bit for bit (switchobs.loop.stream_replay,
switchobs.logs.LogStream), and a long log replays in bounded memory.

The chain (TSA, three-stage, notch), the observer and the log's conversions carry their state from piece to
piece; the pieces here are cut at awkward places: every raster row its own piece, 7 rows (boundaries inside
the encoder's warm-up, before the first full TSA window), 1000 rows; the log's readers cut at 7 rows (a
table) or a fragment of a few records (MDF4).  Every column of the result is compared byte for byte, and the
summary field by field.
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import switchobs.logs._io as log_io
from switchobs.cli.main import main
from switchobs.exceptions import LogError
from switchobs.logs import ChannelMap, LogStream, braking_log_map, log_signals, read_log, replay_log, write_mdf, \
    write_table
from switchobs.loop import (REPLAY_CHUNK, CounterEdges, LogSignals, RateIntegral, ReplayResult, SpeedIntegral,
                            WheelSpeedEdges, edges_from_counts, edges_from_wheel_speed, ideal_encoder,
                            pressure_from_rate, replay, speed_from_acceleration, stream_replay)

from test_logs_replay import needs

WINDOW = 15


def drive(duration: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The drive of benchmarks/replay_log.py: 1 kHz speed and pressure, a slipping wheel's 60-ppr edges to 1 µs."""
    t = np.arange(int(round(duration * 1000)) + 1) / 1000.0
    vx = 20.0 + 5.0 * np.sin(2 * np.pi * t / 20.0)
    omega = vx / 0.3 * (1.0 - 0.02 * (1.0 + np.sin(2 * np.pi * 0.7 * t)))
    stamps, teeth = edges_from_wheel_speed(t, omega, ideal_encoder(60))
    return t, vx, 10.0 * np.sin(2 * np.pi * 2.0 * t), np.floor(stamps * 1e6) / 1e6, teeth


@pytest.fixture(scope="module")
def signals() -> LogSignals:
    t, vx, p, stamps, teeth = drive(1.5)
    return LogSignals(t, vx, p - p[0], stamps, teeth, ppr=60, source="drive")


def assert_same(a: ReplayResult, b: ReplayResult) -> None:
    for name in ReplayResult.COLUMNS:
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and x.tobytes() == y.tobytes(), name
    assert a.summary.to_json() == b.summary.to_json()      # (a NaN final estimate is None there)


@pytest.mark.parametrize("observer,impl", [("xbs4", "python"), ("xbs4", "c"), ("none", "python")])
def test_the_replay_in_pieces_equals_the_whole_log_bit_for_bit(signals, observer, impl):
    if impl == "c":
        pytest.importorskip("casadi")
    whole = replay(signals, observer=observer, impl=impl, chunk=signals.t.size)
    # the warm-up (a full TSA window of edges) spans several pieces of 7 rows
    assert np.flatnonzero(np.isfinite(whole.t_measured))[0] > 2 * 7
    assert whole.summary.outcome == "ok" and whole.summary.steps == (975 if observer != "none" else 0)
    for chunk in (1, 7, 1000):
        assert_same(whole, replay(signals, observer=observer, impl=impl, chunk=chunk))


def test_the_pieces_are_handed_out_as_they_are_decided(signals):
    sizes: list[int] = []
    summary = stream_replay(signals, lambda piece: sizes.append(piece["t"].size), chunk=100, observer="none")
    assert sum(sizes) == summary.samples and len(sizes) == -(-signals.t.size // 100)
    assert max(sizes) <= 100 + 1 and min(sizes[1:-1]) >= 99      # no piece waits for the log's end
    assert REPLAY_CHUNK >= 60_001     # a minute at 1 kHz is one piece: the benchmark's log runs unsplit


@pytest.mark.parametrize("cuts", [[1, 2, 7, 1000, 1001, 3333], [2500]])
def test_the_conversions_in_pieces_equal_the_whole_arrays(cuts):
    rng = np.random.default_rng(1)
    n = 5000
    t = np.arange(n) / 1000.0
    omega, rate, ax = 60 + 10 * np.sin(3 * t), rng.normal(size=n), rng.normal(size=n)
    counts, ticks = np.cumsum(rng.integers(0, 3, n)).astype(float), np.round(t * 1e6)

    def pieces(piece, *arrays):
        bounds = [0, *cuts, n]
        return [piece(*(a[i:j] for a in arrays)) for i, j in zip(bounds[:-1], bounds[1:])]

    def joined(parts, k=None):
        return np.concatenate([p if k is None else p[k] for p in parts]).tobytes()

    assert joined(pieces(RateIntegral().piece, t, rate)) == pressure_from_rate(t, rate).tobytes()
    assert joined(pieces(SpeedIntegral(20.0).piece, t, ax)) == speed_from_acceleration(t, ax, 20.0).tobytes()
    wheel, whole = pieces(WheelSpeedEdges(ideal_encoder(60)).piece, t, omega), edges_from_wheel_speed(
        t, omega, ideal_encoder(60))
    counter, whole_c = pieces(CounterEdges(1e6).piece, counts, ticks), edges_from_counts(t, counts, ticks, 1e6)
    for k in (0, 1):
        assert joined(wheel, k) == whole[k].tobytes() and joined(counter, k) == whole_c[k].tobytes()
    assert whole[0].size > 2000 and whole_c[0].size > 4000


@pytest.fixture
def small_pieces(monkeypatch):
    """The readers cut at 7 table rows, or MDF4 fragments of 7 records of 8-byte channels."""
    monkeypatch.setattr(log_io, "CHUNK_ROWS", 7)
    monkeypatch.setattr(log_io, "MDF_FRAGMENT_BYTES", 7 * 24)


def write_log(path, layout: str, duration: float = 1.0):
    t, vx, p, stamps, teeth = drive(duration)
    if layout == "held":      # the pressure on its own raster (500 Hz, starting later): held on the speed's
        tp = t[10::2]
        write_mdf(path, [(t, {"vx": (vx, "m/s")}), (tp, {"p": (p[10::2], "bar")}),
                         (stamps, {"edge_time": (stamps, "s"), "edge_tooth": (teeth, "")})])
        return braking_log_map()
    if layout == "wheel":
        omega = vx / 0.3 * (1.0 - 0.02 * (1.0 + np.sin(2 * np.pi * 0.7 * t)))
        write_table(path, {"t": t, "vx": vx, "p": p, "w": omega})
        return ('[encoder]\nppr = 60\nwheel_speed = { channel = "w", unit = "rad/s" }\n'
                '[signals]\nspeed = { channel = "vx", unit = "m/s" }\npressure = { channel = "p", unit = "bar" }\n')
    if layout == "counter":
        seen = np.searchsorted(stamps, t, side="right")
        count = np.where(seen > 0, teeth[np.maximum(seen - 1, 0)], int(teeth[0]) - 1).astype(float)
        ticks = np.where(seen > 0, np.round(stamps[np.maximum(seen - 1, 0)] * 1e6), 0.0)
        write_table(path, {"t": t, "vx": vx, "p": p, "tooth_count": count, "capture_ticks": ticks})
        return braking_log_map("counter")
    if path.suffix == ".mf4":
        write_mdf(path, [(t, {"vx": (vx, "m/s"), "p": (p, "bar")}),
                         (stamps, {"edge_time": (stamps, "s"), "edge_tooth": (teeth, "")})])
    else:
        write_table(path, {"t": t, "vx": vx, "p": p, "edge_time": stamps, "edge_tooth": teeth.astype(float)})
    return braking_log_map()


@pytest.mark.parametrize("name,layout", [("log.mf4", "edges"), ("log.csv", "edges"), ("log.parquet", "edges"),
                                         ("log.mf4", "held"), ("log.csv", "counter"), ("log.parquet", "wheel")])
def test_a_log_read_in_small_pieces_replays_to_the_whole_log_bit_for_bit(tmp_path, request, name, layout):
    needs(name.split(".")[1])
    path = tmp_path / name
    cmap = ChannelMap.from_dict(__import__("tomllib").loads(write_log(path, layout)))
    whole = replay(log_signals(read_log(path), cmap), chunk=10**9, vehicle=cmap.vehicle)
    request.getfixturevalue("small_pieces")
    assert sum(1 for _ in LogStream(read_log(path), cmap).pieces()) > 100
    assert_same(whole, replay_log(path, cmap))
    pieces: list[dict] = []
    summary = stream_replay(LogStream(read_log(path), cmap), pieces.append, chunk=3)
    assert_same(whole, ReplayResult.join(pieces, summary))
    if layout == "held":
        assert "p held on the samples of vx" in whole.summary.source


@pytest.mark.parametrize("bad,message", [
    (np.arange(5, 10), "holds an empty cell at sample 5 (t = 0.005 s; 5 in a row, 7 in all)"),
    (None, "jump from 0.5 s to 0.56 s, a gap of 0.06 s above max_gap_s = 0.05 s"),
])
def test_a_bad_log_read_in_pieces_gives_the_whole_channels_message(tmp_path, small_pieces, capsys, bad, message):
    t, vx, p, stamps, teeth = drive(1.0)
    if bad is not None:      # a run of NaN across a piece boundary (7 rows) and two more later
        vx = vx.copy()
        vx[np.concatenate([bad, [500, 700]])] = np.nan
    else:                    # two gaps, the longer second: the message names the longest
        keep = ~(((t > 0.2) & (t < 0.24)) | ((t > 0.5) & (t < 0.56)))
        t, vx, p = t[keep], vx[keep], p[keep]
    write_table(tmp_path / "log.csv", {"t": t, "vx": vx, "p": p, "edge_time": stamps, "edge_tooth": teeth.astype(float)})
    cmap = ChannelMap.from_dict(__import__("tomllib").loads(braking_log_map()))
    with pytest.raises(LogError, match=__import__("re").escape(message)):
        replay_log(tmp_path / "log.csv", cmap)
    # the command: one line, exit 2, and no result, not even the pieces before the failure
    (tmp_path / "map.toml").write_text(braking_log_map(), encoding="utf-8")
    code = main(["replay", str(tmp_path / "log.csv"), "--channels", str(tmp_path / "map.toml"), "--out",
                 str(tmp_path / "out.mf4")])
    err = capsys.readouterr().err
    assert code == 2 and message in err and err.count("\n") == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["log.csv", "map.toml"]


#: The peak resident memory of this process's image (VmHWM, kB): not ru_maxrss, which counts the pages of the
#: test process it was started from.
MEASURE = """
import sys
from switchobs.cli.main import main
code = main(["replay", sys.argv[1], "--channels", sys.argv[2], "--observer-impl", "python", "--observer", "none",
             "--out", sys.argv[3]])
status = open("/proc/self/status").read()
print(int(next(line.split()[1] for line in status.splitlines() if line.startswith("VmHWM:"))))
"""


@pytest.mark.slow
def test_a_long_log_replays_in_the_memory_of_a_short_one(tmp_path):
    """Peak RSS of the replay of a 20-minute log against a 2-minute one: within 40 MB (the same pieces; the
    arrays of the long log's chain and result alone would be 20 times more, some 300 MB)."""
    needs("mf4")
    if not __import__("os").path.exists("/proc/self/status"):
        pytest.skip("no /proc/self/status (VmHWM): the peak memory of a long replay NOT checked")
    peaks = {}
    (tmp_path / "map.toml").write_text(braking_log_map(), encoding="utf-8")
    for minutes in (2, 20):
        t, vx, p, stamps, teeth = drive(60.0 * minutes)
        path = tmp_path / f"drive{minutes}.mf4"
        write_mdf(path, [(t, {"vx": (vx, "m/s"), "p": (p, "bar")}),
                         (stamps, {"edge_time": (stamps, "s"), "edge_tooth": (teeth, "")})])
        proc = subprocess.run([sys.executable, "-c", MEASURE, str(path), str(tmp_path / "map.toml"),
                               str(tmp_path / "out.mf4")], capture_output=True, text=True, check=False)
        assert proc.returncode == 0, proc.stderr
        peaks[minutes] = int(proc.stdout.split()[-1]) * 1024
    assert peaks[20] - peaks[2] < 40 * 2**20, peaks
