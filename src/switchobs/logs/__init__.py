"""Measurement logs in and out: MDF4, Parquet and CSV files for ``switchobs replay``.

A test-track log (ASAM MDF 4 from CANape, INCA or a Vector logger; CSV or Parquet from analysis tools) is
opened by :func:`read_log`, its channels are mapped to what the encoder chain needs by a
:class:`ChannelMap` (a small TOML file, ``docs/replay.md``), :func:`log_signals` converts them to the
:class:`switchobs.loop.LogSignals` in SI units that :func:`switchobs.loop.replay` runs, and
:func:`write_result` writes the :class:`switchobs.loop.ReplayResult` back as a log.  MDF4 needs
``asammdf`` and Parquet ``pyarrow`` (``pip install "switchobs[logs]"``); CSV needs neither.

Public API
----------
replay_log                -- a log file and a channel map -> ReplayResult (the Python twin of ``switchobs replay``)
ChannelMap, ChannelSpec, UNITS -- the channel map and the units it may declare
read_log, Log, Channel    -- a log's channels, read on demand (size-checked first)
log_signals               -- a log and a map -> LogSignals (units, counters, wheel speeds, resampling)
LogStream                 -- the same piece by piece (what ``switchobs replay`` runs: memory bounded)
write_result              -- a ReplayResult as an MDF4, Parquet or CSV log
result_writer, LogWriter  -- a result (any table) written piece by piece, atomically (``switchobs replay --out``)
plot_replay               -- its figure (wheel speed, x2, XBS estimate; matplotlib)
write_table, write_mdf, write_braking_log -- write logs (a simulated braking's chain inputs, in a layout)
braking_log_map           -- the channel map of a log write_braking_log writes (TOML text)
FORMATS, log_format       -- file endings of the formats

Example
-------
>>> import tempfile, pathlib
>>> from switchobs.loop import ReplayResult
>>> d = pathlib.Path(tempfile.mkdtemp())
>>> _ = write_table(d / "log.csv", {"t": [0.0, 0.001], "vx": [20.0, 20.0]})
>>> read_log(d / "log.csv").channel("vx", what="speed").values.tolist()
[20.0, 20.0]
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..exceptions import LogError
from ..loop import EncoderMeasurements, ReplayResult, stream_replay
from ._io import CHUNK_ROWS, FORMATS, Channel, Log, LogWriter, log_format, read_log, write_mdf, write_table
from ._map import UNITS, ChannelMap, ChannelSpec, LogStream, log_signals
from ._plot import plot_replay

__all__ = ["replay_log", "ChannelMap", "ChannelSpec", "UNITS", "read_log", "Log", "Channel", "log_signals",
           "write_result", "write_table", "write_mdf", "write_braking_log", "braking_log_map", "FORMATS", "log_format",
           "CHUNK_ROWS", "RESULT_UNITS", "plot_replay", "LogWriter", "result_writer", "LogStream"]

#: Units of the columns :func:`write_result` writes.
RESULT_UNITS: dict[str, str] = {"t": "s", "t_measured": "s", "x2_tsa": "m/s^2", "x2_notch": "m/s^2",
                                "x2_measured": "m/s^2", "omega_tsa": "rad/s", "omega_measured": "rad/s",
                                "vx": "m/s", "xbs_hat": "", "status": ""}


def replay_log(path: str | Path, channels: ChannelMap | str | Path, *, observer: str = "xbs4",
               method: str = "radau3", beta: float | None = None, impl: str = "python",
               compiled: bool | None = None) -> ReplayResult:
    """Replay the log ``path`` through the encoder chain and an XBS observer (``switchobs replay``), read
    piece by piece (:class:`LogStream`); the result is its pieces joined.

    Parameters
    ----------
    path : str or Path
        An MDF4 (``.mf4``), Parquet (``.parquet``) or CSV (``.csv``) log.
    channels : ChannelMap or path
        The channel map (or its TOML file).
    observer, method, beta, impl, compiled
        As :func:`switchobs.loop.replay`; the chain settings and the vehicle come from the map.

    Raises
    ------
    LogError
        A log or map that cannot be replayed (one line naming the channel, the value and the limit).
    PrerequisiteError
        asammdf or pyarrow missing for an MDF4 or Parquet log.
    """
    cmap = channels if isinstance(channels, ChannelMap) else ChannelMap.from_toml(channels)
    stream = LogStream(read_log(path, time_channel=cmap.time.channel, time_factor=cmap.time.factor), cmap)
    pieces: list[dict[str, Any]] = []
    summary = stream_replay(stream, pieces.append, observer=observer, method=method, beta=beta, impl=impl,
                            vehicle=cmap.vehicle, compiled=compiled, **cmap.chain_options())
    return ReplayResult.join(pieces, summary)


def result_writer(path: str | Path, *, fmt: str | None = None) -> LogWriter:
    """A :class:`LogWriter` of the replay's signals (:attr:`ReplayResult.COLUMNS`, units
    :data:`RESULT_UNITS`; an MDF4 file of one group, ``t`` its master), to append the pieces of
    :func:`switchobs.loop.stream_replay` to as they come."""
    return LogWriter(path, {k: (RESULT_UNITS[k], np.int64 if k == "status" else float) for k in ReplayResult.COLUMNS},
                     fmt=fmt)


def write_result(result: ReplayResult, path: str | Path, *, fmt: str | None = None) -> Path:
    """Write the replay's signals (:meth:`ReplayResult.arrays`) as a log, atomically (format by the ending,
    or ``fmt``): an MDF4 file of one group with units (:data:`RESULT_UNITS`), or a table."""
    with result_writer(path, fmt=fmt) as out:
        out.append(result.arrays())
    return Path(path)


def _unknown_layout(layout: str) -> LogError:
    return LogError(f"unknown log layout {layout!r}; use edges or counter")


def write_braking_log(path: str | Path, measurements: EncoderMeasurements, *, layout: str = "edges",
                      rate_hz: float = 1000.0, clock_hz: float = 1e6) -> Path:
    """Write what the encoder chain read in a simulated braking as a log (tests and the docs' example).

    Parameters
    ----------
    measurements : EncoderMeasurements
        :attr:`switchobs.loop.EncoderLoopEstimator.measurements` of the run.
    layout : {"edges", "counter"}
        ``edges``: the speed ``vx`` [m/s] and pressure change ``p`` [bar] at the plant's steps, and one row
        per edge (``edge_time`` [s], ``edge_tooth``): replays to the run's estimates bit for bit.
        ``counter``: everything sampled at ``rate_hz`` (``vx``, ``p`` interpolated linearly in the steps, a
        tooth counter ``tooth_count`` and the capture ``capture_ticks`` of its latest edge at ``clock_hz``),
        as an ECU records it.

    Returns
    -------
    Path
    """
    m = measurements
    if layout == "edges":
        if log_format(path) == "mdf":
            return write_mdf(path, [(m.steps_t, {"vx": (m.vx_steps, "m/s"), "p": (m.pressure_steps, "bar")}),
                                    (m.edge_times, {"edge_time": (m.edge_times, "s"),
                                                    "edge_tooth": (m.edge_teeth, "")})])
        return write_table(path, {"t": m.steps_t, "vx": m.vx_steps, "p": m.pressure_steps,
                                  "edge_time": m.edge_times, "edge_tooth": m.edge_teeth.astype(float)})
    if layout != "counter":
        raise _unknown_layout(layout)
    t = np.arange(int(np.ceil(m.steps_t[0] * rate_hz)), int(np.floor(m.steps_t[-1] * rate_hz)) + 1) / rate_hz
    seen = np.searchsorted(m.edge_times, t, side="right")        # edges stamped by each sample
    count = np.where(seen > 0, m.edge_teeth[np.maximum(seen - 1, 0)], int(m.edge_teeth[0]) - 1)
    ticks = np.where(seen > 0, np.round(m.edge_times[np.maximum(seen - 1, 0)] * clock_hz), 0.0)
    columns: dict[str, Any] = {"t": t, "vx": np.interp(t, m.steps_t, m.vx_steps),
                               "p": np.interp(t, m.steps_t, m.pressure_steps),
                               "tooth_count": count.astype(float), "capture_ticks": ticks}
    if log_format(path) == "mdf":
        return write_mdf(path, [(t, {k: (v, {"vx": "m/s", "p": "bar"}.get(k, "")) for k, v in columns.items()
                                     if k != "t"})])
    return write_table(path, columns)


def braking_log_map(layout: str = "edges", *, ppr: int = 60, clock_hz: float = 1e6) -> str:
    """The channel map (TOML text) of a log in ``layout`` of :func:`write_braking_log` (its channel names and
    units), for an encoder of ``ppr`` pulses per revolution; ``clock_hz`` is the capture clock of the
    ``counter`` layout.  The maps of ``docs/replay.md``.

    Raises
    ------
    LogError
        An unknown layout.

    Examples
    --------
    >>> print(braking_log_map())
    [encoder]
    ppr = 60
    edges = { channel = "edge_time", unit = "s", teeth = "edge_tooth" }
    [signals]
    speed = { channel = "vx", unit = "m/s" }
    pressure = { channel = "p", unit = "bar" }
    <BLANKLINE>
    """
    if layout == "edges":
        encoder = 'edges = { channel = "edge_time", unit = "s", teeth = "edge_tooth" }'
    elif layout == "counter":
        # 1e6, not %g's 1e+06: the page's spelling (TOML reads both)
        clock = f"{clock_hz:g}".replace("e+0", "e").replace("e+", "e")
        encoder = f'counter = {{ channel = "tooth_count", capture = "capture_ticks", clock_hz = {clock} }}'
    else:
        raise _unknown_layout(layout)
    return (f"[encoder]\nppr = {ppr}\n{encoder}\n[signals]\nspeed = {{ channel = \"vx\", unit = \"m/s\" }}\n"
            'pressure = { channel = "p", unit = "bar" }\n')
