"""The channel map: which channels of a log the encoder chain reads, in which units (a small TOML file).

::

    [time]                 # tables only (CSV, Parquet): the time column; an MDF4 channel has its master
    channel = "t"
    unit = "s"

    [encoder]              # exactly one of edges, counter, wheel_speed
    ppr = 60
    edges = { channel = "edge_time", unit = "s", teeth = "edge_tooth" }
    # counter = { channel = "tooth_count", capture = "capture_ticks", clock_hz = 1e6 }
    # wheel_speed = { channel = "wheel_speed", unit = "rpm" }

    [signals]              # speed or acceleration, pressure or pressure_rate
    speed = { channel = "vx", unit = "km/h" }
    pressure = { channel = "p_brake", unit = "bar" }

    [chain]                # optional: rate_hz, order, window, harmonics, notch_damping, max_gap_s
    [vehicle]              # optional: the fields of switchobs.plants.QuarterCar

``docs/replay.md`` describes every key.  :func:`log_signals` turns a log and a map into the
:class:`switchobs.loop.LogSignals` the replay takes: units converted to SI, edges from counters or wheel
speeds, and the pressure held (zero-order hold) on the speed's samples when it was recorded on others.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from .._limits import MAX_INPUT_FILE_BYTES, MAX_LOG_SAMPLES, read_text
from ..exceptions import LogError, SwitchobsError
from ..loop import (REPLAY_CHUNK, CounterEdges, LogSignals, RateIntegral, SignalPiece, SpeedIntegral, WheelSpeedEdges,
                    ideal_encoder)
from ..plants import QuarterCar
from ._io import Log, join_pieces

__all__ = ["UNITS", "MAX_GAP_S", "ChannelSpec", "ChannelMap", "log_signals", "LogStream"]

#: Units each kind of channel may declare, with the factor to SI (value * factor).
UNITS: dict[str, dict[str, float]] = {
    "time": {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9},
    "speed": {"m/s": 1.0, "km/h": 1.0 / 3.6, "mph": 0.44704},
    "acceleration": {"m/s^2": 1.0, "g": 9.80665},
    "pressure": {"bar": 1.0, "Pa": 1e-5, "kPa": 1e-2, "MPa": 10.0, "psi": 0.0689475729},
    "pressure_rate": {"bar/s": 1.0, "Pa/s": 1e-5, "kPa/s": 1e-2, "MPa/s": 10.0, "psi/s": 0.0689475729},
    "wheel_speed": {"rad/s": 1.0, "rpm": 2.0 * math.pi / 60.0, "rev/s": 2.0 * math.pi, "deg/s": math.pi / 180.0},
}
#: Spellings read as the unit of :data:`UNITS` (a file's own unit text is compared after them).
_ALIASES = {"m/s²": "m/s^2", "m/s2": "m/s^2", "kph": "km/h", "kmh": "km/h", "1/min": "rpm", "U/min": "rpm",
            "µs": "us", "sec": "s"}
_CHAIN_KEYS = {"rate_hz": float, "order": int, "window": int, "harmonics": int, "notch_damping": float,
               "max_gap_s": float}
#: Default longest step of the signal raster [s] (``[chain] max_gap_s``): over a longer gap the linear
#: interpolation of the speed and the pressure between its ends is no longer a measurement.
MAX_GAP_S = 0.05


def _unit(kind: str, text: Any, where: str) -> float:
    if not isinstance(text, str):
        raise LogError(f"channel map: {where}: unit must be a string, got {text!r}")
    name = _ALIASES.get(text.strip(), text.strip())
    table = UNITS[kind]
    if name not in table:
        raise LogError(f"channel map: {where}: unknown unit {text!r} for {kind.replace('_', ' ')}; "
                       f"use one of {', '.join(table)}")
    return table[name]


@dataclass(frozen=True)
class ChannelSpec:
    """A channel of the log and the unit its values are in (``factor`` to SI)."""

    channel: str
    unit: str
    factor: float


def _table(data: Mapping[str, Any], key: str, allowed: set[str], where: str) -> dict[str, Any]:
    value = data.get(key, {})
    if not isinstance(value, Mapping):
        raise LogError(f"channel map: [{where}] must be a table, got {value!r}")
    extra = sorted(set(value) - allowed)
    if extra:
        raise LogError(f"channel map: [{where}] has the unknown key {extra[0]!r}; it takes {', '.join(sorted(allowed))}")
    return dict(value)


def _spec(value: Any, kind: str, where: str, extra: frozenset[str] = frozenset()
          ) -> tuple[ChannelSpec, dict[str, Any]]:
    if not isinstance(value, Mapping) or not isinstance(value.get("channel"), str) or not value["channel"]:
        raise LogError(f"channel map: {where} must be a table {{ channel = \"NAME\", unit = \"...\" }}, got {value!r}")
    unknown = sorted(set(value) - {"channel", "unit"} - set(extra))
    if unknown:
        raise LogError(f"channel map: {where} has the unknown key {unknown[0]!r}")
    if "unit" not in value:
        raise LogError(f"channel map: {where} declares no unit; add unit = one of {', '.join(UNITS[kind])}")
    return (ChannelSpec(value["channel"], str(value["unit"]), _unit(kind, value["unit"], where)),
            {k: value[k] for k in extra if k in value})


@dataclass(frozen=True)
class ChannelMap:
    """Which channels of a log the chain reads (:func:`ChannelMap.from_toml`; ``docs/replay.md``).

    Attributes
    ----------
    time : ChannelSpec
        The time column of a table.
    ppr, both_edges : int, bool
        The encoder.
    edges, teeth, first_tooth
        Edge time stamps, optionally each edge's tooth count (else counted from ``first_tooth``).
    counter, capture, clock_hz
        A sampled tooth counter and the capture register of its latest edge (timer ticks at ``clock_hz``).
    wheel_speed : ChannelSpec or None
        Wheel speed samples (the edges of an ideal encoder are located on their integral).
    speed, acceleration, initial_speed_m_s
        Vehicle speed, or a longitudinal accelerometer integrated from ``initial_speed_m_s``.
    pressure, pressure_rate : ChannelSpec or None
        Brake pressure, or its rate.
    chain : dict
        Chain settings (``rate_hz``, ``order``, ``window``, ``harmonics``, ``notch_damping``) and
        ``max_gap_s``, the longest step of the signal raster (default :data:`MAX_GAP_S`).
    vehicle : QuarterCar
    source : str
        The file the map was read from.
    """

    time: ChannelSpec
    ppr: int
    both_edges: bool = False
    edges: ChannelSpec | None = None
    teeth: str | None = None
    first_tooth: int = 1
    counter: str | None = None
    capture: str | None = None
    clock_hz: float | None = None
    wheel_speed: ChannelSpec | None = None
    speed: ChannelSpec | None = None
    acceleration: ChannelSpec | None = None
    initial_speed_m_s: float | None = None
    pressure: ChannelSpec | None = None
    pressure_rate: ChannelSpec | None = None
    chain: dict[str, Any] = field(default_factory=dict)
    vehicle: QuarterCar = field(default_factory=QuarterCar)
    source: str = "channel map"

    @classmethod
    def from_toml(cls, path: str | Path) -> ChannelMap:
        """Read a channel map file (``-``: standard input), at most ``MAX_INPUT_FILE_BYTES``.

        Raises
        ------
        LogError
            Unreadable or malformed TOML, unknown keys or units, a missing or doubly named channel.
        """
        text, where = read_text(path, what="channel map", max_bytes=MAX_INPUT_FILE_BYTES, error=LogError)
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise LogError(f"channel map {where!r} is not valid TOML: {exc}") from None
        return cls.from_dict(data, source=where)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], *, source: str = "channel map") -> ChannelMap:
        """The map of a parsed TOML document (:meth:`from_toml`)."""
        extra = sorted(set(data) - {"time", "encoder", "signals", "chain", "vehicle"})
        if extra:
            raise LogError(f"channel map: unknown table [{extra[0]}]; it has [time], [encoder], [signals], "
                           "[chain] and [vehicle]")
        tm = _table(data, "time", {"channel", "unit"}, "time")
        time = ChannelSpec(str(tm.get("channel", "t")), str(tm.get("unit", "s")),
                           _unit("time", tm.get("unit", "s"), "[time] unit"))
        enc = _table(data, "encoder", {"ppr", "both_edges", "edges", "counter", "wheel_speed", "first_tooth"},
                     "encoder")
        ppr = enc.get("ppr")
        if not isinstance(ppr, int) or isinstance(ppr, bool) or not 1 <= ppr <= 100_000:
            raise LogError(f"channel map: [encoder] ppr must be an integer in [1, 100000], got {ppr!r}")
        kinds = [k for k in ("edges", "counter", "wheel_speed") if k in enc]
        if len(kinds) != 1:
            raise LogError("channel map: [encoder] takes exactly one of edges, counter, wheel_speed; "
                           f"got {', '.join(kinds) or 'none'}")
        kw: dict[str, Any] = {"time": time, "ppr": ppr, "both_edges": bool(enc.get("both_edges", False)),
                              "source": source}
        first = enc.get("first_tooth", 1)
        if not isinstance(first, int) or isinstance(first, bool) or first < 0:
            raise LogError(f"channel map: [encoder] first_tooth must be an integer >= 0, got {first!r}")
        kw["first_tooth"] = first
        if "edges" in enc:
            kw["edges"], more = _spec(enc["edges"], "time", "[encoder] edges", frozenset({"teeth"}))
            kw["teeth"] = more.get("teeth")
        elif "counter" in enc:
            c = enc["counter"]
            if not isinstance(c, Mapping) or set(c) != {"channel", "capture", "clock_hz"}:
                raise LogError("channel map: [encoder] counter must be { channel = \"COUNT\", capture = \"TICKS\", "
                               f"clock_hz = 1e6 }}, got {c!r}")
            clock = c["clock_hz"]
            if not isinstance(clock, (int, float)) or not math.isfinite(clock) or clock <= 0:
                raise LogError(f"channel map: [encoder] counter clock_hz must be a number > 0, got {clock!r}")
            kw.update(counter=str(c["channel"]), capture=str(c["capture"]), clock_hz=float(clock))
        else:
            kw["wheel_speed"] = _spec(enc["wheel_speed"], "wheel_speed", "[encoder] wheel_speed")[0]
        sig = _table(data, "signals", {"speed", "acceleration", "pressure", "pressure_rate"}, "signals")
        for pair in (("speed", "acceleration"), ("pressure", "pressure_rate")):
            given = [k for k in pair if k in sig]
            if len(given) != 1:
                raise LogError(f"channel map: [signals] takes exactly one of {pair[0]}, {pair[1]}; "
                               f"got {', '.join(given) or 'none'}")
        if "speed" in sig:
            kw["speed"] = _spec(sig["speed"], "speed", "[signals] speed")[0]
        else:
            kw["acceleration"], more = _spec(sig["acceleration"], "acceleration", "[signals] acceleration",
                                             frozenset({"initial_speed"}))
            v0 = more.get("initial_speed")
            if not isinstance(v0, Mapping) or set(v0) != {"value", "unit"} or not isinstance(v0["value"], (int, float)):
                raise LogError("channel map: [signals] acceleration needs initial_speed = { value = 16.7, "
                               f"unit = \"m/s\" }} (the speed at the log's start), got {v0!r}")
            kw["initial_speed_m_s"] = float(v0["value"]) * _unit("speed", v0["unit"], "initial_speed")
        if "pressure" in sig:
            kw["pressure"] = _spec(sig["pressure"], "pressure", "[signals] pressure")[0]
        else:
            kw["pressure_rate"] = _spec(sig["pressure_rate"], "pressure_rate", "[signals] pressure_rate")[0]
        chain = _table(data, "chain", set(_CHAIN_KEYS), "chain")
        for k, v in chain.items():
            typ = _CHAIN_KEYS[k]
            if typ is float and isinstance(v, int) and not isinstance(v, bool):
                chain[k] = v = float(v)
            if not isinstance(v, typ) or isinstance(v, bool):
                raise LogError(f"channel map: [chain] {k} must be {typ.__name__}, got {v!r}")
        gap = chain.get("max_gap_s", MAX_GAP_S)
        if not (math.isfinite(gap) and gap > 0):
            raise LogError(f"channel map: [chain] max_gap_s must be a number > 0, got {gap!r}")
        kw["chain"] = chain
        veh = _table(data, "vehicle", {f.name for f in fields(QuarterCar)}, "vehicle")
        try:
            kw["vehicle"] = QuarterCar(**veh)
        except (SwitchobsError, TypeError) as exc:
            raise LogError(f"channel map: [vehicle]: {exc}") from None
        cmap = cls(**kw)
        named = cmap.channels()
        twice = sorted({n for n in named if named.count(n) > 1})
        if twice:
            raise LogError(f"channel map: the channel {twice[0]!r} is named twice; each signal needs its own channel")
        return cmap

    def channels(self) -> list[str]:
        """The log channels the map names (the time column of a table excluded)."""
        out = [s.channel for s in (self.edges, self.wheel_speed, self.speed, self.acceleration, self.pressure,
                                   self.pressure_rate) if s is not None]
        return out + [n for n in (self.teeth, self.counter, self.capture) if n is not None]

    @property
    def rate_hz(self) -> float:
        return float(self.chain.get("rate_hz", 1000.0))

    def chain_options(self) -> dict[str, Any]:
        """The chain settings as :func:`switchobs.loop.replay` takes them."""
        return {k: v for k, v in self.chain.items() if k != "max_gap_s"}


class _Cells:
    """The checks of a signal channel read in pieces: every cell a finite number, then its time stamps finite
    and strictly increasing; the message of the first failure as the whole channel gives it (the run and
    the count of bad cells need every piece)."""

    def __init__(self, name: str, what: str) -> None:
        self.name, self.what = name, what
        self._at = 0                                   # samples so far
        self._bad: tuple[int, float, str] | None = None   # the first bad cell: sample, time, what it holds
        self._run = self._count = 0
        self._open = False                             # the run of bad cells reaches the last sample so far
        self._time: str | None = None                  # the first time stamp that is not finite
        self._back: str | None = None                  # the first that does not increase
        self._last = math.nan

    def feed(self, t: np.ndarray, values: np.ndarray, present: np.ndarray) -> None:
        bad = np.flatnonzero(~present | ~np.isfinite(values))
        # the bad cells from bad[0] on that follow one another
        lead = int(np.argmax(np.concatenate([np.diff(bad) != 1, [True]]))) + 1 if bad.size else 0
        if self._bad is None and bad.size:
            i = int(bad[0])
            shown = "an empty cell" if not present[i] else repr(float(values[i]))
            self._bad, self._run = (self._at + i, float(t[i]), shown), lead
            self._open = i + lead == t.size          # the run may go on in the next piece
        elif self._open:
            grows = bool(bad.size) and bad[0] == 0
            self._run += lead if grows else 0
            self._open = grows and lead == t.size
        self._count += bad.size
        if self._time is None and not np.all(np.isfinite(t)):
            j = int(np.flatnonzero(~np.isfinite(t))[0])
            self._time = (f"{self.what}: channel {self.name!r} has the time stamp {float(t[j])!r} at sample "
                          f"{self._at + j}")
        if self._back is None and t.size:
            tt = np.concatenate([[self._last], t]) if self._at else t
            back = np.flatnonzero(np.diff(tt) <= 0.0)
            if back.size:
                i = int(back[0])
                how = "repeats" if tt[i + 1] == tt[i] else "goes back"
                k = self._at - 1 + i if self._at else i
                self._back = (f"{self.what}: the time of channel {self.name!r} {how} at sample {k + 1}: "
                              f"{float(tt[i + 1])!r} s after {float(tt[i])!r} s; time stamps must be strictly "
                              "increasing")
            self._last = float(t[-1])
        self._at += t.size

    def error(self) -> str | None:
        if self._bad is not None:
            i, ti, shown = self._bad
            return (f"{self.what}: channel {self.name!r} holds {shown} at sample {i} (t = {ti!r} s; {self._run} in "
                    f"a row, {self._count} in all); cut the log before the gap or fill it")
        return self._time or self._back


def _unit_agrees(unit: str, spec: ChannelSpec, kind: str, what: str) -> None:
    """A file that records units (MDF4) must record the one the map declares (after the spellings of UNITS)."""
    if unit and _ALIASES.get(unit.strip(), unit.strip()) != _ALIASES.get(spec.unit.strip(), spec.unit.strip()):
        raise LogError(f"{what}: channel {spec.channel!r} is recorded in {unit!r}, the channel map declares "
                       f"{spec.unit!r} ({kind}); correct the map")


class _Order:
    """A series that must increase strictly across pieces (the edges' time stamps, their teeth)."""

    def __init__(self, message: Any) -> None:
        self._message, self._at, self._last = message, 0, None
        self.error: str | None = None

    def feed(self, values: np.ndarray) -> None:
        if self.error is None and values.size:
            vv = values if self._last is None else np.concatenate([[self._last], values])
            back = np.flatnonzero(np.diff(vv) <= 0)
            if back.size:
                i = int(back[0])
                self.error = self._message(self._at - (self._last is not None) + i + 1, vv[i], vv[i + 1])
            self._last = values[-1]
        self._at += values.size


class LogStream:
    """The signals of a log that a channel map names, read and converted piece by piece: the
    :class:`switchobs.loop.SignalSource` that ``switchobs replay`` runs (:func:`log_signals` joins it).

    Each piece holds raster rows (the speed's samples, a few MB of them: one read piece) in SI units and the
    edges up to their last time (counters and wheel speeds turned into edges as they come, the pressure held
    on the speed's samples when it has its own).  The checks of :func:`log_signals` run on every piece;
    from the first failure on nothing more is handed out, the rest of the log is read for the message (which
    counts over the whole channel), and the first failure in the order :func:`log_signals` checks is raised
    after the last piece.

    Parameters
    ----------
    log : Log
    cmap : ChannelMap
    """

    def __init__(self, log: Log, cmap: ChannelMap) -> None:
        self.log, self.cmap = log, cmap
        self.ppr, self.both_edges = cmap.ppr, cmap.both_edges
        self._note = ""
        self._signal = ("speed", cmap.speed) if cmap.speed is not None else ("acceleration", cmap.acceleration)
        self._rate = ("pressure", cmap.pressure) if cmap.pressure is not None else ("pressure_rate",
                                                                                      cmap.pressure_rate)
        assert self._signal[1] is not None and self._rate[1] is not None
        self._checks: list[Any] = []

    @property
    def source(self) -> str:
        """The log's name, and how the pressure was held (known once the pieces are read)."""
        return f"{self.log.path.name}{self._note}"

    def _spec_channel(self, kind: str, spec: ChannelSpec) -> str:
        what = f"[signals] {kind}"
        _unit_agrees(self.log.unit(spec.channel, what=what), spec, kind, what)
        return what

    # ------------------------------------------------------------------ the raster
    def _raster(self) -> Iterator[tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """The speed's samples (those the pressure covers) with the speed and the pressure in SI units."""
        (k1, s1), (k2, s2) = self._signal, self._rate
        assert s1 is not None and s2 is not None
        w1, w2 = self._spec_channel(k1, s1), self._spec_channel(k2, s2)
        c1, c2 = _Cells(s1.channel, w1), _Cells(s2.channel, w2)
        overlap = _Overlap(s1.channel, s2.channel)
        self._checks += [c1, c2, overlap]
        if self.log.time_base(s1.channel, what=w1) == self.log.time_base(s2.channel, what=w2):
            for t, cols in self.log.pieces([s1.channel, s2.channel], what=w1):
                (v1, p1), (v2, p2) = cols[s1.channel], cols[s2.channel]
                c1.feed(t, v1, p1)
                c2.feed(t, v2, p2)
                overlap.same(t)
                yield t, v1 * s1.factor if s1.factor != 1.0 else v1, v2 * s2.factor if s2.factor != 1.0 else v2
            return
        # the pressure recorded on its own time stamps: held (its last sample at or before) on the speed's,
        # over the time both cover
        held = _Hold(self.log.pieces([s2.channel], what=w2), s2.channel, c2, s2.factor)
        for t, cols in self.log.pieces([s1.channel], what=w1):
            v1, p1 = cols[s1.channel]
            c1.feed(t, v1, p1)
            if c1.error() is not None or c2.error() is not None:
                continue                     # no more values: the checks read on for the message
            keep, v2 = held.at(t)
            overlap.held(t, keep, held)
            if keep.size:
                yield t[keep], (v1[keep] * s1.factor if s1.factor != 1.0 else v1[keep]), v2
        held.finish()
        overlap.held_end(held)
        if overlap.differs:
            self._note = f" ({s2.channel} held on the samples of {s1.channel})"

    # ------------------------------------------------------------------ the edges
    def _edges(self) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """The edges' time stamps [s] and teeth, piece by piece."""
        cmap, log = self.cmap, self.log
        if cmap.edges is not None:
            what = "[encoder] edges"
            _unit_agrees(log.unit(cmap.edges.channel, what=what), cmap.edges, "time", what)   # the edges first
            edges = _EdgeCells(cmap.edges.channel, cmap.teeth, cmap.first_tooth)
            self._checks.append(edges)
            names = [cmap.edges.channel] + ([cmap.teeth] if cmap.teeth is not None else [])
            if cmap.teeth is not None:
                log.time_base(cmap.teeth, what="[encoder] edges teeth")
            for _, cols in log.pieces(names, what=what):
                stamps, teeth = edges.feed(cols, cmap.edges.factor)
                yield stamps, teeth
            return
        if cmap.counter is not None:
            count, capture = _Cells(cmap.counter, "[encoder] counter"), _Cells(str(cmap.capture),
                                                                               "[encoder] counter capture")
            self._checks += [count, capture]
            log.time_base(cmap.counter, what="[encoder] counter")          # each named by what it is for
            log.time_base(str(cmap.capture), what="[encoder] counter capture")
            counter = CounterEdges(float(cmap.clock_hz or 1.0))
            for t, cols in log.pieces([cmap.counter, str(cmap.capture)], what="[encoder] counter"):
                (c, cp), (k, kp) = cols[cmap.counter], cols[str(cmap.capture)]
                count.feed(t, c, cp)
                capture.feed(t, k, kp)
                if count.error() is None and capture.error() is None:
                    yield counter.piece(c, k)
            return
        assert cmap.wheel_speed is not None
        what = "[encoder] wheel_speed"
        _unit_agrees(log.unit(cmap.wheel_speed.channel, what=what), cmap.wheel_speed, "wheel_speed", what)
        cells = _Cells(cmap.wheel_speed.channel, what)
        self._checks.append(cells)
        wheel = WheelSpeedEdges(ideal_encoder(cmap.ppr, both_edges=cmap.both_edges))
        factor = cmap.wheel_speed.factor
        for t, cols in log.pieces([cmap.wheel_speed.channel], what=what):
            om, present = cols[cmap.wheel_speed.channel]
            cells.feed(t, om, present)
            if cells.error() is None:
                yield wheel.piece(t, om * factor if factor != 1.0 else om)

    # ------------------------------------------------------------------ both, in time order
    def pieces(self, rows: int | None = None) -> Iterator[SignalPiece]:
        """The pieces: raster rows (as read, at most ``rows`` a piece, default
        :data:`switchobs.loop.REPLAY_CHUNK`) with the edges up to their last time.

        Raises
        ------
        LogError
            After the last piece, the first check that failed (those of :func:`log_signals`).
        """
        self._checks = []
        cmap, rows = self.cmap, REPLAY_CHUNK if rows is None else rows
        gap_limit = float(cmap.chain.get("max_gap_s", MAX_GAP_S))
        gap = _Gap(self._signal[1].channel if self._signal[1] is not None else "", gap_limit)
        speed = SpeedIntegral(float(cmap.initial_speed_m_s or 0.0)) if self._signal[0] == "acceleration" else None
        rate = RateIntegral() if self._rate[0] == "pressure_rate" else None
        first_pressure: list[float] = []
        raster, edges = self._raster(), self._edges()
        # the checks LogSignals makes of the whole signals, made piece by piece
        finite = [_Finite("vx"), _Finite("pressure"), _Finite("edge_times")]
        stamps_order = _Order(lambda i, a, b: (f"the encoder edges' time {'repeats' if a == b else 'goes back'} at "
                                               f"sample {i}: {float(b)!r} s after {float(a)!r} s; time stamps "
                                               "must be strictly increasing"))
        teeth_order = _Order(lambda i, a, b: (f"the tooth count goes from {int(a)} to {int(b)} at edge {i}; it must "
                                              "increase (a wheel turning backwards is not replayed)"))
        counts = {"t": 0, "edge_times": 0}
        waiting: list[tuple[np.ndarray, np.ndarray]] = []
        newest, edges_done = -math.inf, False

        def failed() -> bool:
            return any(c.error() is not None for c in self._checks) or gap.error() is not None or any(
                f.error is not None for f in finite) or stamps_order.error is not None or teeth_order.error is not None

        def take_edges(until: float) -> tuple[np.ndarray, np.ndarray]:
            nonlocal newest, edges_done
            while not edges_done and newest <= until:
                got = next(edges, None)
                if got is None:
                    edges_done = True
                elif got[0].size:
                    waiting.append(got)
                    newest = float(got[0][-1])
            out = (join_pieces([w[0] for w in waiting], float), join_pieces([w[1] for w in waiting], np.int_))
            waiting.clear()
            finite[2].feed(out[0])
            stamps_order.feed(out[0])
            teeth_order.feed(out[1])
            counts["edge_times"] += out[0].size
            return out

        for t_all, v1_all, v2_all in raster:
            for a in range(0, t_all.size, rows):
                t, v1, v2 = (x[a:a + rows] for x in (t_all, v1_all, v2_all))
                gap.feed(t)
                vx = v1 if speed is None else speed.piece(t, v1)
                if rate is None:
                    if not first_pressure:
                        first_pressure.append(float(v2[0]))
                    pressure = v2 - first_pressure[0]
                else:
                    pressure = rate.piece(t, v2)
                finite[0].feed(vx)
                finite[1].feed(pressure)
                counts["t"] += t.size
                stamps, teeth = take_edges(float(t[-1]))
                if failed():
                    break
                yield SignalPiece(t, vx, pressure, stamps, teeth)
            if failed():
                break
        if failed():
            for _ in raster:            # read on: the messages count over whole channels
                pass
            for _ in edges:
                pass
        else:
            stamps, teeth = take_edges(math.inf)
            for name, n in counts.items():
                if n > MAX_LOG_SAMPLES:
                    raise LogError(f"{name} has {n} samples (limit MAX_LOG_SAMPLES = {MAX_LOG_SAMPLES}); "
                                   "cut the log into shorter pieces")
            if not failed():
                if counts["t"] < 2:
                    raise LogError(f"the log has {counts['t']} signal samples; at least 2 are needed")
                yield SignalPiece(np.zeros(0), np.zeros(0), np.zeros(0), stamps, teeth, done=True)
                return
        for message in ([c.error() for c in self._checks] + [gap.error()] + [f.error for f in finite]
                        + [stamps_order.error, teeth_order.error]):
            if message is not None:
                raise LogError(message)


class _Overlap:
    """Whether the speed's and the pressure's time stamps differ, and that they overlap (two samples)."""

    def __init__(self, first: str, second: str) -> None:
        self._names = (first, second)
        self.differs = False
        self._kept = 0
        self._span: list[float] = []      # the speed's first and last time stamps
        self._message: str | None = None

    def same(self, t: np.ndarray) -> None:
        self._kept += t.size

    def held(self, t: np.ndarray, keep: np.ndarray, hold: _Hold) -> None:
        if t.size:
            self._span = [self._span[0] if self._span else float(t[0]), float(t[-1])]
        self._kept += keep.size
        self.differs = self.differs or keep.size != t.size or not hold.same

    def held_end(self, hold: _Hold) -> None:
        self.differs = self.differs or not hold.same or hold.count != self._kept
        if self.differs and self._kept < 2 and self._span and hold.span:
            (a, b), (c, d) = self._span, hold.span
            self._message = (f"the {self._names[0]!r} ({a!r}..{b!r} s) and {self._names[1]!r} ({c!r}..{d!r} s) "
                             "channels do not overlap in time")

    def error(self) -> str | None:
        return self._message


class _Hold:
    """The pressure recorded on its own time stamps, held on the speed's (:func:`zero_order_hold`), read
    piece by piece as far as the speed's samples reach."""

    def __init__(self, pieces: Iterator[tuple[np.ndarray, dict[str, tuple[np.ndarray, np.ndarray]]]], name: str,
                 cells: _Cells, factor: float) -> None:
        self._pieces, self._name, self._cells, self._factor = pieces, name, cells, factor
        self._t, self._v = np.zeros(0), np.zeros(0)
        self._done = False
        self.same = True            # every speed sample so far is one of the pressure's time stamps
        self.count = 0              # the pressure's samples
        self.span: list[float] = []

    def _read(self) -> bool:
        got = next(self._pieces, None)
        if got is None:
            self._done = True
            return False
        t, cols = got
        v, present = cols[self._name]
        self._cells.feed(t, v, present)
        self.count += t.size
        if t.size:
            self.span = [self.span[0] if self.span else float(t[0]), float(t[-1])]
            self._t = np.concatenate([self._t, t])
            self._v = np.concatenate([self._v, v * self._factor if self._factor != 1.0 else v])
        return True

    def at(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Which of the samples ``t`` the pressure covers, and its held values there."""
        while not self._done and (self._t.size == 0 or self._t[-1] < t[-1]):
            self._read()
        if self._cells.error() is not None or self._t.size == 0:
            return np.zeros(0, dtype=np.int_), np.zeros(0)
        end = self._t[-1] if self._done else math.inf
        keep = np.flatnonzero((t >= self.span[0]) & (t <= end))
        i = np.searchsorted(self._t, t[keep], side="right") - 1
        self.same = self.same and bool(np.all(self._t[i] == t[keep]))
        out = self._v[i]
        # the samples later speed samples can hold: from the last at or before this piece's end
        drop = max(int(np.searchsorted(self._t, t[-1], side="right")) - 1, 0)
        self._t, self._v = self._t[drop:].copy(), self._v[drop:].copy()
        return keep, out

    def finish(self) -> None:
        """Read the rest (its checks see the whole channel)."""
        while not self._done:
            self._read()


class _Gap:
    """The longest step of the raster, against ``max_gap_s``."""

    def __init__(self, name: str, limit: float) -> None:
        self._name, self._limit = name, limit
        self._last: float | None = None
        self._worst: tuple[float, float, float] | None = None   # (step, from, to), the first of the longest

    def feed(self, t: np.ndarray) -> None:
        if t.size == 0:
            return
        tt = t if self._last is None else np.concatenate([[self._last], t])
        steps = np.diff(tt)
        if steps.size:
            i = int(np.argmax(steps))
            if self._worst is None or steps[i] > self._worst[0]:
                self._worst = (float(steps[i]), float(tt[i]), float(tt[i + 1]))
        self._last = float(t[-1])

    def error(self) -> str | None:
        if self._worst is None or self._worst[0] <= self._limit:
            return None
        step, a, b = self._worst
        return (f"the samples of {self._name!r} jump from {a!r} s to {b!r} s, a gap of {step:.4g} s above "
                f"max_gap_s = {self._limit:g} s; cut the log at the gap or raise [chain] max_gap_s")


class _Finite:
    """A converted signal must be finite (the check of LogSignals), counted over all its pieces."""

    def __init__(self, name: str) -> None:
        self._name, self._at, self._first, self._count = name, 0, None, 0
        self.error: str | None = None

    def feed(self, a: np.ndarray) -> None:
        bad = np.flatnonzero(~np.isfinite(a))
        if bad.size:
            if self._first is None:
                self._first = (self._at + int(bad[0]), float(a[bad[0]]))
            self._count += bad.size
            i, v = self._first
            self.error = (f"{self._name} holds {v!r} at sample {i} ({self._count} samples not finite); "
                          "cut the log before the gap or fill it")
        self._at += a.size


class _EdgeCells:
    """The edges channel (and its teeth) read in pieces: the edges where it holds a value, the teeth at
    exactly those, integers, and the time stamps finite."""

    def __init__(self, name: str, teeth: str | None, first_tooth: int) -> None:
        self._name, self._teeth, self._next = name, teeth, first_tooth
        self._mask = self._integers = False
        self._stamp: str | None = None
        self._kept = 0

    def feed(self, cols: Mapping[str, tuple[np.ndarray, np.ndarray]], factor: float) -> tuple[np.ndarray, np.ndarray]:
        values, keep = cols[self._name]
        stamps = values[keep] * factor if factor != 1.0 else values[keep]
        if self._teeth is not None:
            tv, tp = cols[self._teeth]
            self._mask = self._mask or not np.array_equal(tp, keep)
            raw = tv[keep]
            self._integers = self._integers or not (np.all(np.isfinite(raw)) and np.array_equal(raw, np.round(raw)))
            teeth = raw.astype(np.int64) if not (self._mask or self._integers) else np.zeros(0, dtype=np.int64)
        else:
            teeth = self._next + np.arange(self._kept, self._kept + stamps.size, dtype=np.int64)
        if self._stamp is None and not np.all(np.isfinite(stamps)):
            i = int(np.flatnonzero(~np.isfinite(stamps))[0])
            self._stamp = (f"[encoder] edges: channel {self._name!r} holds {float(stamps[i])!r} at edge "
                           f"{self._kept + i}")
        self._kept += stamps.size
        if self.error() is not None:
            return np.zeros(0), np.zeros(0, dtype=np.int_)
        return stamps, teeth.astype(np.int_)

    def error(self) -> str | None:
        if self._mask:
            return (f"[encoder] edges: the teeth channel {self._teeth!r} does not have a value at exactly the edges "
                    f"of {self._name!r}")
        if self._integers:
            return f"[encoder] edges: the teeth channel {self._teeth!r} holds values that are not integers"
        return self._stamp


def log_signals(log: Log, cmap: ChannelMap) -> LogSignals:
    """The signals of ``log`` that ``cmap`` names, in SI units, as :func:`switchobs.loop.replay` takes them:
    the pieces of :class:`LogStream` joined.

    The speed's samples (or the accelerometer's, integrated) are the raster: the chain interpolates the speed
    linearly between them and takes ``a_x`` as its slope, so the speed is never resampled.  A pressure (or
    rate) recorded on other time stamps is held onto that raster by :func:`switchobs.loop.zero_order_hold`
    (its last sample at or before each), over the time both cover.  Edges are never resampled.

    Raises
    ------
    LogError
        A missing channel, a unit the file contradicts, empty or non-finite samples, time stamps not
        strictly increasing or a step of the raster longer than ``max_gap_s``, edges that do not increase.
    """
    stream = LogStream(log, cmap)
    parts = list(stream.pieces())
    t, vx, pressure, stamps = (join_pieces([getattr(p, k) for p in parts], float) for k in ("t", "vx", "pressure",
                                                                                      "edge_times"))
    return LogSignals(t, vx, pressure, stamps, join_pieces([p.edge_teeth for p in parts], np.int_), ppr=cmap.ppr,
                      both_edges=cmap.both_edges, source=stream.source)
