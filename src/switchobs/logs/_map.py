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
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from .._limits import MAX_INPUT_FILE_BYTES, read_text
from ..exceptions import LogError, SwitchobsError
from ..loop import (LogSignals, edges_from_counts, edges_from_wheel_speed, ideal_encoder, pressure_from_rate,
                    speed_from_acceleration, zero_order_hold)
from ..plants import QuarterCar
from ._io import Channel, Log

__all__ = ["UNITS", "MAX_GAP_S", "ChannelSpec", "ChannelMap", "log_signals"]

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


def _values(ch: Channel, what: str, factor: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """A signal channel's time stamps and SI values; every cell must hold a finite number."""
    bad = np.flatnonzero(~ch.present | ~np.isfinite(ch.values))
    if bad.size:
        i = int(bad[0])
        run = int(np.argmax(np.concatenate([np.diff(bad) != 1, [True]]))) + 1
        shown = "an empty cell" if not ch.present[i] else repr(float(ch.values[i]))
        raise LogError(f"{what}: channel {ch.name!r} holds {shown} at sample {i} (t = {float(ch.t[i])!r} s; "
                       f"{run} in a row, {bad.size} in all); cut the log before the gap or fill it")
    _time_ok(ch, what)
    return ch.t, ch.values * factor if factor != 1.0 else ch.values


def _time_ok(ch: Channel, what: str) -> None:
    bad = np.flatnonzero(~np.isfinite(ch.t))
    if bad.size:
        raise LogError(f"{what}: channel {ch.name!r} has the time stamp {float(ch.t[bad[0]])!r} at sample {int(bad[0])}")
    back = np.flatnonzero(np.diff(ch.t) <= 0.0)
    if back.size:
        i = int(back[0])
        how = "repeats" if ch.t[i + 1] == ch.t[i] else "goes back"
        raise LogError(f"{what}: the time of channel {ch.name!r} {how} at sample {i + 1}: {float(ch.t[i + 1])!r} s "
                       f"after {float(ch.t[i])!r} s; time stamps must be strictly increasing")


def _unit_agrees(ch: Channel, spec: ChannelSpec, kind: str, what: str) -> None:
    """A file that records units (MDF4) must record the one the map declares (after the spellings of UNITS)."""
    if ch.unit and _ALIASES.get(ch.unit.strip(), ch.unit.strip()) != _ALIASES.get(spec.unit.strip(), spec.unit.strip()):
        raise LogError(f"{what}: channel {ch.name!r} is recorded in {ch.unit!r}, the channel map declares "
                       f"{spec.unit!r} ({kind}); correct the map")


def log_signals(log: Log, cmap: ChannelMap) -> LogSignals:
    """The signals of ``log`` that ``cmap`` names, in SI units, as :func:`switchobs.loop.replay` takes them.

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
    def signal(spec: ChannelSpec, kind: str, what: str) -> tuple[np.ndarray, np.ndarray]:
        ch = log.channel(spec.channel, what=what)
        _unit_agrees(ch, spec, kind, what)
        return _values(ch, what, spec.factor)

    log.want([s.channel for s in (cmap.speed, cmap.acceleration, cmap.pressure, cmap.pressure_rate, cmap.edges,
                                  cmap.wheel_speed) if s is not None]
             + [str(n) for n in (cmap.teeth, cmap.counter, cmap.capture) if n])
    first = ("speed", cmap.speed) if cmap.speed is not None else ("acceleration", cmap.acceleration)
    second = ("pressure", cmap.pressure) if cmap.pressure is not None else ("pressure_rate", cmap.pressure_rate)
    assert first[1] is not None and second[1] is not None
    (t, v1), (t2, v2) = (signal(s, kind, f"[signals] {kind}") for kind, s in (first, second))
    note = ""
    if not np.array_equal(t, t2):
        cover = (t >= t2[0]) & (t <= t2[-1])
        if np.count_nonzero(cover) < 2:
            raise LogError(f"the {first[1].channel!r} ({t[0]!r}..{t[-1]!r} s) and {second[1].channel!r} "
                           f"({t2[0]!r}..{t2[-1]!r} s) channels do not overlap in time")
        t, v1 = t[cover], v1[cover]
        v2 = zero_order_hold(t2, v2, t)
        note = f" ({second[1].channel} held on the samples of {first[1].channel})"
    gap = float(cmap.chain.get("max_gap_s", MAX_GAP_S))
    steps = np.diff(t)
    if steps.size and float(steps.max()) > gap:
        i = int(np.argmax(steps))
        raise LogError(f"the samples of {first[1].channel!r} jump from {float(t[i])!r} s to {float(t[i + 1])!r} s, "
                       f"a gap of {float(steps[i]):.4g} s above max_gap_s = {gap:g} s; cut the log at the gap "
                       "or raise [chain] max_gap_s")
    vx = v1 if first[0] == "speed" else speed_from_acceleration(t, v1, float(cmap.initial_speed_m_s or 0.0))
    pressure = v2 - v2[0] if second[0] == "pressure" else pressure_from_rate(t, v2)
    stamps, teeth = _edges(log, cmap)
    return LogSignals(t, vx, pressure, stamps, teeth, ppr=cmap.ppr, both_edges=cmap.both_edges,
                      source=f"{log.path.name}{note}")


def _edges(log: Log, cmap: ChannelMap) -> tuple[np.ndarray, np.ndarray]:
    if cmap.edges is not None:
        ch = log.channel(cmap.edges.channel, what="[encoder] edges")
        _unit_agrees(ch, cmap.edges, "time", "[encoder] edges")
        keep = ch.present
        stamps = ch.values[keep] * cmap.edges.factor if cmap.edges.factor != 1.0 else ch.values[keep]
        if cmap.teeth is not None:
            tc = log.channel(cmap.teeth, what="[encoder] edges teeth")
            if tc.values.size != ch.values.size or not np.array_equal(tc.present, keep):
                raise LogError(f"[encoder] edges: the teeth channel {cmap.teeth!r} does not have a value at exactly "
                               f"the edges of {ch.name!r}")
            raw = tc.values[keep]
            if not np.all(np.isfinite(raw)) or not np.array_equal(raw, np.round(raw)):
                raise LogError(f"[encoder] edges: the teeth channel {cmap.teeth!r} holds values that are not integers")
            teeth = raw.astype(np.int64)
        else:
            teeth = cmap.first_tooth + np.arange(stamps.size, dtype=np.int64)
        if not np.all(np.isfinite(stamps)):
            i = int(np.flatnonzero(~np.isfinite(stamps))[0])
            raise LogError(f"[encoder] edges: channel {ch.name!r} holds {float(stamps[i])!r} at edge {i}")
        return stamps, teeth
    if cmap.counter is not None:
        count = log.channel(cmap.counter, what="[encoder] counter")
        capture = log.channel(str(cmap.capture), what="[encoder] counter capture")
        tc, counts = _values(count, "[encoder] counter")
        tk, ticks = _values(capture, "[encoder] counter capture")
        if not np.array_equal(tc, tk):
            raise LogError(f"[encoder] counter: {count.name!r} and {capture.name!r} must be sampled together")
        return edges_from_counts(tc, counts, ticks, float(cmap.clock_hz or 1.0))
    assert cmap.wheel_speed is not None
    ch = log.channel(cmap.wheel_speed.channel, what="[encoder] wheel_speed")
    _unit_agrees(ch, cmap.wheel_speed, "wheel_speed", "[encoder] wheel_speed")
    tw, om = _values(ch, "[encoder] wheel_speed", cmap.wheel_speed.factor)
    return edges_from_wheel_speed(tw, om, ideal_encoder(cmap.ppr, both_edges=cmap.both_edges))
