"""Recorded data in: logs written from the project's own braking simulations, replayed through the encoder chain
and the observer (``switchobs replay``, :func:`switchobs.logs.replay_log`).

A log that carries the samples the chain read in the simulation (the edges' time stamps and teeth, the speed and
the pressure change at the plant's steps) replays to the simulation's estimates bit for bit, in every format.
Logs in other layouts, units and rasters replay within stated tolerances of them:

- tier 1, the same signal at the same or a finer resolution (a 1 kHz or 500 Hz tooth counter with a 1 MHz
  capture clock; wheel speed in rpm, an accelerometer in g and a pressure rate at 2 kHz): the RMS difference of
  the XBS estimate from the simulation's is at most ``TIER1_RMS``;
- tier 2, information lost (the speed at 100 Hz, the pressure at 500 Hz on its own raster; a raster with gaps
  of 15-30 ms): at most ``TIER2_RMS``, and the estimate's RMS error against the true XBS at most ``TIER2_ERROR``
  times the simulation's.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from switchobs.cli.main import main
from switchobs.exceptions import LogError
from switchobs.logs import (ChannelMap, braking_log_map, read_log, replay_log, write_braking_log, write_mdf,
                            write_result, write_table)
from switchobs.loop import (INITIAL_STATE, EncoderLoopEstimator, EstimatorSpec, LogSignals, ReplayResult,
                            edges_from_counts, measurements_signals, replay, xbs_estimator)
from switchobs.plants import BrakingScenario, RoadChange, RoadSchedule, simulate
from switchobs.sensors import Encoder

#: Tolerances of the module notes (XBS, dimensionless); measured: tier 1 at most 0.09, tier 2 at most 1.11 and
#: error ratios 0.89-0.94 (python -m pytest tests/test_logs_replay.py -k tier -s prints them).
TIER1_RMS, TIER2_RMS, TIER2_ERROR = 0.15, 1.5, 1.1

SC = BrakingScenario(RoadSchedule("dry-asphalt", [RoadChange("snow", at_time_s=0.6)]), speed_m_s=60 / 3.6,
                     duration_s=1.5, stop_speed_m_s=10 / 3.6)

#: The channel maps of the logs write_braking_log writes (the maps of docs/replay.md).
EDGES_MAP, COUNTER_MAP = braking_log_map("edges"), braking_log_map("counter")


def needs(fmt: str) -> None:
    """Skip loudly when the format's reader is not installed."""
    package = {"mf4": "asammdf", "parquet": "pyarrow"}.get(fmt)
    if package is not None:
        try:
            __import__(package)
        except ImportError:
            pytest.skip(f"{package} is not installed: replay of {fmt} logs NOT checked")


class Run:
    """A simulated braking with the encoder-fed observer, what its chain read and the estimates it gave."""

    def __init__(self, impl: str):
        spec = EstimatorSpec("xbs4", impl=impl, method="radau3")
        est = xbs_estimator(spec, SC.vehicle, SC.roads.initial)
        self.loop = EncoderLoopEstimator([(str(spec), est.observer, dict(INITIAL_STATE["xbs4"]))],
                                         encoder=Encoder(ppr=60, seed=5), radius_m=SC.vehicle.radius_m)
        self.result = simulate(SC, estimator=self.loop)
        assert self.loop.measurements is not None, "the encoder chain ran per step, not over the recorded run"
        self.m = self.loop.measurements
        record = self.loop.record()
        self.estimates = record.estimates[str(spec)]
        self.t = record.t
        self.true = np.interp(record.t, self.result.series["t"], self.result.series["xbs"])


@pytest.fixture(scope="module")
def run() -> Run:
    return Run("python")


def write_map(tmp_path: Path, text: str, name: str = "map.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def compare(run: Run, res: ReplayResult) -> tuple[float, float]:
    """RMS difference from the simulation's estimate, and the ratio of the RMS errors against the true XBS."""
    assert np.array_equal(res.t, run.t)
    ok = np.isfinite(run.estimates) & np.isfinite(res.xbs_hat)
    assert ok.sum() > 0.9 * ok.size
    diff = float(np.sqrt(np.mean((res.xbs_hat - run.estimates)[ok] ** 2)))
    err_sim = np.sqrt(np.mean((run.estimates - run.true)[ok] ** 2))
    err_rep = np.sqrt(np.mean((res.xbs_hat - run.true)[ok] ** 2))
    print(f"rms difference {diff:.4f}, error ratio {err_rep / err_sim:.4f}")
    return diff, float(err_rep / err_sim)


# ------------------------------------------------------------------ the same samples: bit for bit
@pytest.mark.parametrize("fmt", ["mf4", "parquet", "csv"])
def test_a_log_of_the_chains_samples_replays_to_the_simulations_estimates_bit_for_bit(run, fmt, tmp_path):
    needs(fmt)
    log = write_braking_log(tmp_path / f"braking.{fmt}", run.m, layout="edges")
    res = replay_log(log, write_map(tmp_path, EDGES_MAP), observer="xbs4", method="radau3")
    assert np.array_equal(res.xbs_hat, run.estimates, equal_nan=True)
    assert np.array_equal(res.x2_measured, run.m.x2_measured, equal_nan=True)
    assert res.summary.outcome == "ok" and res.summary.edges == run.m.events and not np.any(res.status)


def test_the_c_observer_replays_its_simulation_bit_for_bit(tmp_path):
    if shutil.which("gcc") is None and shutil.which("cc") is None:
        pytest.skip("no C compiler is installed: the C observer's replay NOT checked")
    c_run = Run("c")
    res = replay(measurements_signals(c_run.m, 60), impl="c", vehicle=SC.vehicle)
    assert np.array_equal(res.xbs_hat, c_run.estimates, equal_nan=True)
    assert "(c)" in res.summary.observer and res.summary.method == "radau3"   # the default is not spelled out


def test_the_command_writes_the_estimates_status_and_chain_signals_in_the_logs_format(run, tmp_path, capsys):
    needs("mf4")
    log = write_braking_log(tmp_path / "braking.mf4", run.m)
    out, plot = tmp_path / "result.mf4", tmp_path / "replay.png"
    code = main(["replay", str(log), "--channels", str(write_map(tmp_path, EDGES_MAP)), "--out", str(out),
                 "--plot", str(plot)])
    printed = capsys.readouterr().out
    assert code == 0 and "(python): 408 steps, ok" in printed and f"signals written to {out}" in printed
    back = read_log(out)
    assert set(ReplayResult.COLUMNS) - {"t"} <= set(back.names)
    xbs = back.channel("xbs_hat", what="check")
    assert np.array_equal(xbs.values, run.estimates, equal_nan=True) and np.array_equal(xbs.t, run.t)
    assert back.channel("x2_measured", what="check").unit == "m/s^2"
    assert plot.stat().st_size > 10_000
    # another ending: the log's format
    other = tmp_path / "result.bin"
    assert main(["replay", str(log), "--channels", str(write_map(tmp_path, EDGES_MAP)), "--out", str(other)]) == 0
    assert other.read_bytes()[:3] == b"MDF"


# ------------------------------------------------------------------ other layouts, units and rasters
def test_tier1_a_tooth_counter_with_a_capture_clock(run, tmp_path):
    for rate, fmt in ((1000.0, "csv"), (500.0, "parquet")):
        needs(fmt)
        log = write_braking_log(tmp_path / f"counter.{fmt}", run.m, layout="counter", rate_hz=rate)
        diff, _ = compare(run, replay_log(log, write_map(tmp_path, COUNTER_MAP)))
        assert 0.0 < diff <= TIER1_RMS, rate


def test_tier1_wheel_speed_in_rpm_an_accelerometer_in_g_and_a_pressure_rate(run, tmp_path):
    needs("parquet")
    m, t = run.m, np.arange(0.0, 1.5 + 1e-9, 0.0005)
    vx = np.interp(t, m.steps_t, m.vx_steps)
    p = np.interp(t, m.steps_t, m.pressure_steps)
    write_table(tmp_path / "wheel.parquet", {
        "time_ms": t * 1e3, "WheelRpm": np.interp(t, m.steps_t, m.omega_steps) * 60 / (2 * np.pi),
        "AccX": np.gradient(vx, t) / 9.80665, "dP": np.concatenate([np.diff(p) / np.diff(t), [0.0]])})
    cmap = write_map(tmp_path, """
[time]
channel = "time_ms"
unit = "ms"
[encoder]
ppr = 60
wheel_speed = { channel = "WheelRpm", unit = "rpm" }
[signals]
acceleration = { channel = "AccX", unit = "g", initial_speed = { value = 60, unit = "km/h" } }
pressure_rate = { channel = "dP", unit = "bar/s" }
""")
    diff, _ = compare(run, replay_log(tmp_path / "wheel.parquet", cmap))
    assert 0.0 < diff <= TIER1_RMS


def test_tier2_channels_on_their_own_rasters_and_units_in_an_mdf4(run, tmp_path):
    needs("mf4")
    m = run.m
    t100, t500 = np.arange(0.0, 1.5 + 1e-9, 0.01), np.arange(0.0, 1.5 + 1e-9, 0.002)
    write_mdf(tmp_path / "units.mf4", [
        (t100, {"VehSpd": (np.interp(t100, m.steps_t, m.vx_steps) * 3.6, "km/h")}),
        (t500, {"BrkPrs": (np.interp(t500, m.steps_t, m.pressure_steps) * 100.0, "kPa")}),
        (m.edge_times, {"WhlEdge": (m.edge_times * 1e3, "ms"), "WhlTooth": (m.edge_teeth, "")})])
    cmap = write_map(tmp_path, """
[encoder]
ppr = 60
edges = { channel = "WhlEdge", unit = "ms", teeth = "WhlTooth" }
[signals]
speed = { channel = "VehSpd", unit = "km/h" }
pressure = { channel = "BrkPrs", unit = "kPa" }
""")
    res = replay_log(tmp_path / "units.mf4", cmap)
    assert "BrkPrs held on the samples of VehSpd" in res.summary.source
    diff, ratio = compare(run, res)
    assert 0.0 < diff <= TIER2_RMS and ratio <= TIER2_ERROR


def test_tier2_a_raster_with_gaps(run, tmp_path):
    needs("parquet")
    m, keep = run.m, np.ones(run.m.steps_t.size, dtype=bool)
    for a, b in ((0.3, 0.32), (0.7, 0.715), (1.1, 1.13)):
        keep &= ~((m.steps_t > a) & (m.steps_t < b))
    write_table(tmp_path / "gaps.parquet", {"t": m.steps_t[keep], "vx": m.vx_steps[keep], "p": m.pressure_steps[keep],
                                            "edge_time": m.edge_times, "edge_tooth": m.edge_teeth.astype(float)})
    diff, ratio = compare(run, replay_log(tmp_path / "gaps.parquet", write_map(tmp_path, EDGES_MAP)))
    assert 0.0 < diff <= TIER2_RMS and ratio <= TIER2_ERROR
    # a gap longer than max_gap_s is refused
    with pytest.raises(LogError, match=r"a gap of 0.0[23]\d* s above max_gap_s = 0.02 s"):
        replay_log(tmp_path / "gaps.parquet", write_map(tmp_path, EDGES_MAP + "[chain]\nmax_gap_s = 0.02\n"))


def test_edges_without_teeth_count_from_first_tooth_and_the_chain_runs_without_an_observer(run, tmp_path, capsys):
    needs("parquet")
    m = run.m
    assert np.all(np.diff(m.edge_teeth) == 1)       # no edge missed: the count from the first tooth is the teeth
    write_table(tmp_path / "b.parquet", {"t": m.steps_t, "vx": m.vx_steps, "p": m.pressure_steps,
                                         "edge_time": m.edge_times})
    cmap = EDGES_MAP.replace(', teeth = "edge_tooth" }', " }\nfirst_tooth = %d" % m.edge_teeth[0])
    res = replay_log(tmp_path / "b.parquet", write_map(tmp_path, cmap))
    assert np.array_equal(res.xbs_hat, run.estimates, equal_nan=True)
    assert main(["replay", str(tmp_path / "b.parquet"), "--channels", str(write_map(tmp_path, cmap)),
                 "--observer", "none"]) == 0
    assert "no observer (the chain only): 0 steps, ok; final XBS estimate n/a" in capsys.readouterr().out


def test_a_counter_that_skips_edges_between_samples_spreads_them_evenly():
    t = np.arange(4) * 1e-3
    times, teeth = edges_from_counts(t, [5, 6, 9, 9], [100, 900, 2400, 2400], 1e6)
    assert teeth.tolist() == [6, 7, 8, 9]
    assert np.allclose(times, [900e-6, 1400e-6, 1900e-6, 2400e-6], rtol=0, atol=1e-15)


# ------------------------------------------------------------------ Python API
def test_the_result_as_a_dataframe_arrays_and_json(run, tmp_path):
    res = replay(measurements_signals(run.m, 60), vehicle=SC.vehicle)
    df = res.to_dataframe()
    assert list(df.columns) == list(ReplayResult.COLUMNS) and len(df) == res.t.size
    assert np.array_equal(df["xbs_hat"].to_numpy(), res.arrays()["xbs_hat"], equal_nan=True)
    summary = res.summary.to_json()
    assert summary["outcome"] == "ok" and summary["samples"] == res.t.size and summary["steps"] == 408
    needs("parquet")
    write_result(res, tmp_path / "r.parquet")
    assert np.array_equal(read_log(tmp_path / "r.parquet").channel("status", what="x").values, res.status)


def test_a_refused_step_ends_the_estimates_with_its_status_code(run, tmp_path, capsys):
    # beta 3e4 in rk4 over a measurement interval of about 1 ms overflows (as tests/test_replay.py's loop run)
    res = replay(measurements_signals(run.m, 60), vehicle=SC.vehicle, method="rk4", beta=3e4)
    assert res.summary.outcome == "observer-failed" and "NONFINITE_RESULT" in res.summary.message
    k = int(np.flatnonzero(res.status)[0])
    assert res.status[k] == 5 and np.all(np.isnan(res.xbs_hat[k:])) and np.isfinite(res.xbs_hat[k - 1])
    needs("csv")
    log = write_braking_log(tmp_path / "b.csv", run.m)
    code = main(["replay", str(log), "--channels", str(write_map(tmp_path, EDGES_MAP)), "--method", "rk4",
                 "--beta", "3e4"])
    assert code == 1 and "NONFINITE_RESULT" in capsys.readouterr().err


# ------------------------------------------------------------------ bad logs and maps: one line, exit 2
def _bad(tmp_path: Path, capsys, log: Path, cmap: str, *extra: str) -> str:
    out = tmp_path / "out.csv"
    code = main(["replay", str(log), "--channels", str(write_map(tmp_path, cmap, "bad.toml")), "--out", str(out),
                 *extra])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and err.startswith("switchobs replay: error:"), err
    assert "Traceback" not in err and not out.exists()
    return err


def _table(tmp_path: Path, name: str = "log.csv", **columns) -> Path:
    t = np.arange(200) * 1e-3
    base = {"t": t, "vx": np.full(200, 20.0), "p": np.zeros(200), "edge_time": 5e-3 + np.arange(60) * 3e-3,
            "edge_tooth": np.arange(1.0, 61.0)}
    base.update(columns)
    return write_table(tmp_path / name, base)


def test_a_missing_channel_is_named_with_those_present(tmp_path, capsys):
    err = _bad(tmp_path, capsys, _table(tmp_path), EDGES_MAP.replace('"vx"', '"VehSpd"'))
    assert "channel 'VehSpd' is not in the log" in err and "'vx'" in err and "'edge_time'" in err


@pytest.mark.parametrize("old, new, message", [
    ('unit = "m/s" }', 'unit = "furlong/s" }', "unknown unit 'furlong/s' for speed; use one of m/s, km/h, mph"),
    (', unit = "bar" }', ' }', "declares no unit"),
    ('pressure = { channel = "p", unit = "bar" }', 'pressure = { channel = "vx", unit = "bar" }',
     "the channel 'vx' is named twice"),
    ('ppr = 60', 'ppr = 0', "ppr must be an integer in [1, 100000], got 0"),
    ('[signals]', '[signal]', "unknown table [signal]"),
])
def test_a_bad_channel_map_is_one_line(tmp_path, capsys, old, new, message):
    assert message in _bad(tmp_path, capsys, _table(tmp_path), EDGES_MAP.replace(old, new))


NAN_RUN = np.where((np.arange(200) >= 50) & (np.arange(200) < 53), np.nan, 20.0)


@pytest.mark.parametrize("name, column, values, message", [
    ("log.csv", "t", np.concatenate([np.arange(100), [98.5], np.arange(101, 200)]) * 1e-3, "goes back at sample 100"),
    ("log.csv", "t", np.concatenate([np.arange(100), [99], np.arange(101, 200)]) * 1e-3, "repeats at sample 100"),
    ("log.parquet", "vx", NAN_RUN, "holds nan at sample 50 (t = 0.05 s; 3 in a row, 3 in all)"),
    ("log.csv", "vx", NAN_RUN, "holds an empty cell at sample 50 (t = 0.05 s; 3 in a row, 3 in all)"),
])
def test_a_bad_raster_or_samples_are_one_line(tmp_path, capsys, name, column, values, message):
    needs(name.split(".")[1])
    assert message in _bad(tmp_path, capsys, _table(tmp_path, name, **{column: values}), EDGES_MAP)


def test_a_log_shorter_than_the_chains_warm_up(tmp_path, capsys):
    log = _table(tmp_path, edge_time=5e-3 + np.arange(10) * 3e-3, edge_tooth=np.arange(1.0, 11.0))
    assert "shorter than the chain's warm-up: 10 edges" in _bad(tmp_path, capsys, log, EDGES_MAP)


def test_a_huge_log_is_refused_by_its_size_unread(tmp_path, capsys):
    huge = tmp_path / "huge.mf4"
    with open(huge, "wb") as f:
        f.truncate(10 * 1024 ** 3)        # 10 GiB, sparse: refused before it is opened
    assert "has 10737418240 bytes (limit MAX_LOG_BYTES" in _bad(tmp_path, capsys, huge, EDGES_MAP)


def test_a_unit_the_mdf4_contradicts_and_channels_in_several_groups(tmp_path, capsys):
    needs("mf4")
    t = np.arange(200) * 1e-3
    e = 5e-3 + np.arange(60) * 3e-3
    log = write_mdf(tmp_path / "log.mf4", [(t, {"vx": (np.full(200, 72.0), "km/h"), "p": (np.zeros(200), "bar")}),
                                           (e, {"edge_time": (e, "s"), "edge_tooth": (np.arange(1, 61), "")})])
    assert "recorded in 'km/h', the channel map declares 'm/s'" in _bad(tmp_path, capsys, log, EDGES_MAP)
    twice = write_mdf(tmp_path / "twice.mf4", [(t, {"vx": (np.full(200, 20.0), "m/s"), "p": (np.zeros(200), "bar")}),
                                               (t, {"vx": (np.full(200, 20.0), "m/s")}),
                                               (e, {"edge_time": (e, "s"), "edge_tooth": (np.arange(1, 61), "")})])
    assert "channel 'vx' is in 2 groups" in _bad(tmp_path, capsys, twice, EDGES_MAP)


def test_log_signals_refuse_teeth_that_do_not_increase():
    t = np.arange(3) * 1e-3
    with pytest.raises(LogError, match="the tooth count goes from 5 to 5 at edge 1"):
        LogSignals(t, np.ones(3), np.zeros(3), np.array([1e-4, 2e-4]), np.array([5, 5]), ppr=60)


def test_the_channel_map_reads_its_defaults(tmp_path):
    cmap = ChannelMap.from_toml(write_map(tmp_path, EDGES_MAP))
    assert cmap.rate_hz == 1000.0 and cmap.time.channel == "t" and cmap.channels() == ["edge_time", "vx", "p",
                                                                                       "edge_tooth"]


# ------------------------------------------------------------------ docs/replay.md runs as shown
DOCS = Path(__file__).resolve().parents[1] / "docs"


def _block(info: str) -> str:
    import re
    text = (DOCS / "replay.md").read_text("utf-8")
    found = re.search(r"^```" + re.escape(info) + r"\n(.*?)^```", text, re.S | re.M)
    assert found, f"docs/replay.md has no ```{info} block"
    return found.group(1)


def test_the_units_table_of_the_page_is_the_codes():
    import re
    from switchobs.logs import UNITS
    text = (DOCS / "replay.md").read_text("utf-8")
    rows = dict(re.findall(r"^\| (\w+) \| (`.*`) \|$", text, re.M))
    assert {k: [u.strip("`") for u in v.split(", ")] for k, v in rows.items() if k in UNITS} == \
        {k: list(v) for k, v in UNITS.items()}


def test_the_pages_channel_maps_are_those_of_the_written_logs():
    assert _block('toml title="edges.toml"') == braking_log_map("edges")
    assert _block('toml title="counter.toml"') == braking_log_map("counter", ppr=60, clock_hz=1e6)
    assert "ppr = 7\n" in braking_log_map(ppr=7) and "clock_hz = 32768 }" in braking_log_map("counter", clock_hz=32768)
    with pytest.raises(LogError, match="unknown log layout 'wheel'"):
        braking_log_map("wheel")


def test_the_pages_example_runs_as_shown(tmp_path, monkeypatch, capsys):
    from _docs_blocks import matches_with_elisions, shown_output
    needs("mf4")
    needs("parquet")
    monkeypatch.chdir(tmp_path)
    for name in ("edges.toml", "counter.toml"):
        (tmp_path / name).write_text(_block(f'toml title="{name}"'), encoding="utf-8")
    exec(compile(_block('python title="make_logs.py"'), "make_logs.py", "exec"), {"__name__": "make_logs"})
    printed = capsys.readouterr().out.strip()
    assert f"It prints `{printed}`" in (DOCS / "replay.md").read_text("utf-8")
    for command, stream, status in (
            ("switchobs replay braking.mf4 --channels edges.toml --out replayed.mf4", "out", 0),
            ("switchobs replay braking_ecu.csv --channels counter.toml --out replayed.parquet --json", "out", 0),
            ("switchobs replay braking.mf4 --channels counter.toml", "err", 2)):
        code = main(command.split()[1:])
        captured = capsys.readouterr()
        shown = getattr(captured, stream).rstrip("\n")
        assert code == status, captured.err
        assert matches_with_elisions(shown_output("replay.md", command), shown), f"`{command}` prints\n{shown}"
    # the Python block, on the files the example wrote
    scope: dict = {}
    exec(_api_block(), scope)
    assert scope["result"].summary.outcome == "ok" and (tmp_path / "replayed.parquet").is_file()


def _api_block():
    import re
    text = (DOCS / "replay.md").read_text("utf-8")
    found = re.search(r"^```python\n(from switchobs\.logs import replay_log.*?)^```", text, re.S | re.M)
    assert found, "docs/replay.md has no Python API block"
    return compile(found.group(1), "replay.md", "exec")


@pytest.mark.parametrize("module", ["switchobs.loop._replay", "switchobs.logs"])
def test_docstring_examples(module):
    import doctest
    import importlib

    result = doctest.testmod(importlib.import_module(module), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0


def test_more_samples_than_the_limit_are_refused(tmp_path, monkeypatch):
    import switchobs.logs._io as io
    import switchobs.loop._replay as replay_module
    monkeypatch.setattr(replay_module, "MAX_LOG_SAMPLES", 150)
    t = np.arange(151) * 1e-3
    with pytest.raises(LogError, match=r"t has 151 samples \(limit MAX_LOG_SAMPLES = 150\)"):
        LogSignals(t, np.ones(151), np.zeros(151), np.zeros(0), np.zeros(0, dtype=int), ppr=60)
    monkeypatch.setattr(io, "MAX_LOG_SAMPLES", 150)
    with pytest.raises(LogError, match=r"more than 150 rows \(limit MAX_LOG_SAMPLES\)"):
        log = read_log(_table(tmp_path))        # a CSV file's rows are counted as its columns are read
        log.channel(log.names[0], what="the test")
