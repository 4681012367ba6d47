"""Recorded data in: the encoder chain and an XBS observer over a measurement log's signals.

A log gives what the chain of :class:`EncoderLoopEstimator` reads in the loop, without the plant: the
encoder's edges (time stamps, and the tooth each one belongs to), the vehicle speed and the brake pressure
on a raster of samples.  :class:`LogSignals` holds them in SI units (the table a reader of MDF4, CSV or
Parquet files fills: :mod:`switchobs.logs`); the helpers below turn what loggers record into it (tooth
counts with a capture clock, wheel speed samples, a pressure rate, an accelerometer).  :func:`replay` runs
the chain (:func:`measure_edges`: TSA seed 001 (5.1)-(5.5), three-stage compensation Fig. 6.2, notch Sec.
6.3) and the observer over them, one observer step from measurement to measurement with the signals held
(the zero-order hold of the generated C step, seed 000 eq. (13)), and returns a :class:`ReplayResult`.

:class:`ReplayStream` runs the same piece by piece (:func:`stream_replay`: each piece's samples handed out as
soon as the inputs decide them, the chain's, the observer's and the conversions' state carried across; the
pieces joined equal the whole arrays' result bit for bit), so that a log of any length replays in the memory
of a piece; :func:`replay` is that stream joined.

A log of a simulated braking that carries the samples the chain read in the simulation
(:attr:`EncoderLoopEstimator.measurements`) replays to the simulation's estimates bit for bit: the same
function computes both.  Signals recorded on different rasters are resampled onto one by
:func:`zero_order_hold` first (:mod:`switchobs.logs` does it for a log).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
import numpy.typing as npt

from .._json import JsonRecord, array_to_json
from .._limits import MAX_LOG_SAMPLES
from .._progress import progress
from ..exceptions import LogError, ObserverInputError, SimulationError
from ..plants import QuarterCar
from ..sensors import Encoder
from ._adapter import ObserverXbsEstimator, initial_xbs_state
from ._encoder_batch import EdgeChain, EncoderMeasurements, EncoderSamples, edge_angles, wheel_edges
from ._factory import INITIAL_STATE, EstimatorSpec, xbs_estimator
from ._stepping import step_through

__all__ = ["LogSignals", "ReplayResult", "ReplaySummary", "replay", "stream_replay", "ReplayStream", "REPLAY_CHUNK",
           "SignalPiece", "SignalSource", "RateIntegral", "SpeedIntegral", "CounterEdges", "WheelSpeedEdges", "zero_order_hold", "pressure_from_rate",
           "speed_from_acceleration", "edges_from_counts", "edges_from_wheel_speed", "measurements_signals", "ideal_encoder"]

Array = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int_]


def _finite(name: str, a: Array) -> None:
    bad = np.flatnonzero(~np.isfinite(a))
    if bad.size:
        i = int(bad[0])
        raise LogError(f"{name} holds {float(a[i])!r} at sample {i} ({bad.size} samples not finite); "
                       "cut the log before the gap or fill it")


def _increasing(name: str, t: Array) -> None:
    back = np.flatnonzero(np.diff(t) <= 0.0)
    if back.size:
        i = int(back[0])
        what = "repeats" if t[i + 1] == t[i] else "goes back"
        raise LogError(f"{name} {what} at sample {i + 1}: {float(t[i + 1])!r} s after {float(t[i])!r} s; "
                       "time stamps must be strictly increasing")


def _size(name: str, a: npt.NDArray[Any]) -> None:
    if a.size > MAX_LOG_SAMPLES:
        raise LogError(f"{name} has {a.size} samples (limit MAX_LOG_SAMPLES = {MAX_LOG_SAMPLES}); "
                       "cut the log into shorter pieces")


@dataclass(frozen=True, eq=False)
class LogSignals:
    """What the encoder chain reads from a log, in SI units: the table :func:`replay` takes.

    Attributes
    ----------
    t : ndarray
        Sample times of ``vx`` and ``pressure`` [s], strictly increasing.
    vx : ndarray
        Vehicle speed [m/s] (the chain takes ``a_x = dvx/dt`` from it, seed 001 eq. (2.2)).
    pressure : ndarray
        Brake pressure change since ``t[0]``, ``∫ u dt`` [bar] (the observer's input ``u`` is its rate).
    edge_times : ndarray
        Time stamps of the encoder edges [s], strictly increasing.
    edge_teeth : ndarray of int
        Each edge's count from tooth 0 of revolution 0 (strictly increasing; a gap is a missed edge).
    ppr : int
        Pulses per revolution of the encoder; ``both_edges``: rising and falling edges are stamped.
    source : str
        Where the signals come from, for the summary.

    Raises
    ------
    LogError
        Arrays of different lengths, NaN or infinite samples, time stamps or teeth not strictly increasing,
        more than ``MAX_LOG_SAMPLES`` samples or edges.
    """

    t: Array
    vx: Array
    pressure: Array
    edge_times: Array
    edge_teeth: IntArray
    ppr: int
    both_edges: bool = False
    source: str = "signals"

    def __post_init__(self) -> None:
        for name in ("t", "vx", "pressure", "edge_times"):
            a = np.asarray(getattr(self, name), dtype=float)
            if a.ndim != 1:
                raise LogError(f"{name} must be one-dimensional, got shape {a.shape}")
            _size(name, a)
            _finite(name, a)
            object.__setattr__(self, name, a)
        teeth = np.asarray(self.edge_teeth)
        if teeth.shape != self.edge_times.shape or (teeth.size and not np.issubdtype(teeth.dtype, np.integer)):
            raise LogError(f"edge_teeth must hold one integer per edge ({self.edge_times.size}), "
                           f"got shape {teeth.shape} of {teeth.dtype}")
        object.__setattr__(self, "edge_teeth", teeth.astype(np.int_))
        for name in ("vx", "pressure"):
            if getattr(self, name).shape != self.t.shape:
                raise LogError(f"{name} has {getattr(self, name).size} samples, t {self.t.size}: "
                               "give one value per sample")
        if self.t.size < 2:
            raise LogError(f"the log has {self.t.size} signal samples; at least 2 are needed")
        _increasing("the signals' time", self.t)
        _increasing("the encoder edges' time", self.edge_times)
        if np.any(np.diff(self.edge_teeth) <= 0):
            i = int(np.flatnonzero(np.diff(self.edge_teeth) <= 0)[0])
            raise LogError(f"the tooth count goes from {int(self.edge_teeth[i])} to {int(self.edge_teeth[i + 1])} "
                           f"at edge {i + 1}; it must increase (a wheel turning backwards is not replayed)")
        if not (isinstance(self.ppr, int) and 1 <= self.ppr <= 100_000):
            raise LogError(f"ppr must be an integer in [1, 100000], got {self.ppr!r}")

    def pieces(self, rows: int | None = None) -> Iterator[SignalPiece]:
        """The signals in pieces of ``rows`` raster rows (default :data:`REPLAY_CHUNK`), each with the edges up
        to its last time (the chain decides a sample once an edge is stamped after it), the rest with the
        last: views of the arrays, no copies."""
        rows = REPLAY_CHUNK if rows is None else rows
        size, e_at = self.t.size, 0
        for a in range(0, size, rows):
            b = min(a + rows, size)
            e_to = self.edge_times.size if b == size else \
                int(np.searchsorted(self.edge_times, self.t[b - 1], side="right"))
            yield SignalPiece(self.t[a:b], self.vx[a:b], self.pressure[a:b], self.edge_times[e_at:e_to],
                              self.edge_teeth[e_at:e_to], done=b == size)
            e_at = e_to

    @property
    def encoder(self) -> Encoder:
        """An encoder of this tooth count (its nominal angles are what the chain assigns to the edges)."""
        return ideal_encoder(self.ppr, both_edges=self.both_edges)

    def __str__(self) -> str:
        return (f"{self.source}: {self.t.size} samples over {float(self.t[-1] - self.t[0]):.3f} s, "
                f"{self.edge_times.size} edges of a {self.ppr}-ppr encoder")


def ideal_encoder(ppr: int, *, both_edges: bool = False) -> Encoder:
    """An encoder without transition errors or eccentricity: edges at the nominal angles."""
    return Encoder(ppr=ppr, both_edges=both_edges, dnl_cycles=0.0, jitter_cycles=0.0, eccentricity=0.0)


def zero_order_hold(t: npt.ArrayLike, values: npt.ArrayLike, at: npt.ArrayLike) -> Array:
    """``values`` (sampled at ``t``) at the times ``at``: each the last sample at or before it.

    The zero-order hold the generated C step assumes of its signals; ``at`` must not start before ``t[0]``.
    """
    tt, vv, aa = (np.asarray(a, dtype=float) for a in (t, values, at))
    i = np.searchsorted(tt, aa, side="right") - 1
    if i.size and i[0] < 0:
        raise LogError(f"no sample at or before {float(aa[0])!r} s (the channel starts at {float(tt[0])!r} s)")
    return vv[i]


def _running(start: float, steps: Array) -> Array:
    """``start`` plus the running sum of ``steps``, added one after another (``start`` first): the value at
    each of them, as ``np.cumsum`` of the whole series gives it when ``start`` is its sum so far."""
    return np.cumsum(np.concatenate([[start], steps]))[1:]


class RateIntegral:
    """``∫ u dt`` [bar] of a pressure rate [bar/s] held from each sample to the next (ZOH), from the first
    sample on, fed in pieces (:func:`pressure_from_rate` is one piece)."""

    def __init__(self) -> None:
        self._last: tuple[float, float, float] | None = None     # (t, rate, integral) of the last sample

    def piece(self, t: Array, rate: Array) -> Array:
        """The integral at the samples ``t`` (the next ones)."""
        if t.size == 0:
            return np.zeros(0)
        if self._last is None:
            out = np.cumsum(np.concatenate([[0.0], rate[:-1] * np.diff(t)]))
        else:
            t0, u0, total = self._last
            out = _running(total, np.concatenate([[u0 * (t[0] - t0)], rate[:-1] * np.diff(t)]))
        self._last = (float(t[-1]), float(rate[-1]), float(out[-1]))
        return out


class SpeedIntegral:
    """Vehicle speed [m/s] from a longitudinal accelerometer [m/s²] (trapezoidal rule) and the speed at the
    first sample, fed in pieces (:func:`speed_from_acceleration` is one piece).

    Raises
    ------
    LogError
        An initial speed that is not finite and > 0.
    """

    def __init__(self, initial_speed_m_s: float) -> None:
        if not (math.isfinite(initial_speed_m_s) and initial_speed_m_s > 0):
            raise LogError(f"the initial speed must be finite and > 0 m/s, got {initial_speed_m_s!r}")
        self._v0 = initial_speed_m_s
        self._last: tuple[float, float, float] | None = None     # (t, ax, sum of the increments)

    def piece(self, t: Array, ax: Array) -> Array:
        """The speed at the samples ``t`` (the next ones)."""
        if t.size == 0:
            return np.zeros(0)
        if self._last is None:
            total = np.cumsum(np.concatenate([[0.0], 0.5 * (ax[:-1] + ax[1:]) * np.diff(t)]))
        else:
            t0, a0, carried = self._last
            tt, aa = np.concatenate([[t0], t]), np.concatenate([[a0], ax])
            total = _running(carried, 0.5 * (aa[:-1] + aa[1:]) * np.diff(tt))
        self._last = (float(t[-1]), float(ax[-1]), float(total[-1]))
        return self._v0 + total


def pressure_from_rate(t: npt.ArrayLike, rate: npt.ArrayLike) -> Array:
    """``∫ u dt`` from ``t[0]`` [bar] of a pressure rate [bar/s] held from each sample to the next (ZOH)."""
    return RateIntegral().piece(np.asarray(t, dtype=float), np.asarray(rate, dtype=float))


def speed_from_acceleration(t: npt.ArrayLike, ax: npt.ArrayLike, initial_speed_m_s: float) -> Array:
    """Vehicle speed [m/s] from a longitudinal accelerometer [m/s²] (trapezoidal rule) and the speed at ``t[0]``."""
    return SpeedIntegral(initial_speed_m_s).piece(np.asarray(t, dtype=float), np.asarray(ax, dtype=float))


class CounterEdges:
    """Edges from an ECU's sampled tooth counter and its capture register, fed in pieces
    (:func:`edges_from_counts` is one piece; the rules there).

    Raises
    ------
    LogError
        A counter that is not an integer or goes back, or an edge count beyond ``MAX_LOG_SAMPLES``.
    """

    def __init__(self, clock_hz: float) -> None:
        self._clock = float(clock_hz)
        self._last: tuple[float, float] | None = None     # (count, capture [s]) of the last sample
        self._first = 0.0                                # the first sample's count
        self._at = 0                                     # samples so far

    def piece(self, counts: Array, ticks: Array) -> tuple[Array, IntArray]:
        """The edges the next samples' counts and captures give: time stamps [s] and teeth."""
        c, stamps = np.asarray(counts, dtype=float), np.asarray(ticks, dtype=float) / self._clock
        if c.size and not np.array_equal(c, np.round(c)):
            raise LogError("the tooth counter holds values that are not integers")
        if c.size == 0:
            return np.zeros(0), np.zeros(0, dtype=np.int_)
        if self._last is None:          # base: the sample index of c[0] below in the whole log
            self._first, base = float(c[0]), 0
        else:                           # the last sample before, for the rise to the first of these
            c, stamps = np.concatenate([[self._last[0]], c]), np.concatenate([[self._last[1]], stamps])
            base = self._at - 1
        self._at = base + c.size
        rise = np.diff(c)
        if np.any(rise < 0):
            i = int(np.flatnonzero(rise < 0)[0])
            raise LogError(f"the tooth counter goes back from {c[i]:.0f} to {c[i + 1]:.0f} at sample {base + i + 1}; "
                           "it must not decrease (unwrap a wrapping counter first)")
        total = int(c[-1] - self._first)
        if total > MAX_LOG_SAMPLES:
            raise LogError(f"the tooth counter counts {total} edges (limit MAX_LOG_SAMPLES = {MAX_LOG_SAMPLES})")
        self._last = (float(c[-1]), float(stamps[-1]))
        new = np.flatnonzero(rise > 0) + 1
        d = rise[new - 1].astype(np.int64)
        last, prev = stamps[new], stamps[new - 1]     # the register held the previous count's edge one sample before
        group = np.repeat(np.arange(new.size), d)
        j = np.arange(group.size) - np.repeat(np.cumsum(d) - d, d) + 1          # 1..d within each sample
        times = np.where(j == d[group], last[group], prev[group] + (j / d[group]) * (last[group] - prev[group]))
        teeth = np.repeat(c[new].astype(np.int64) - d, d) + j
        return times, teeth.astype(np.int_)


def edges_from_counts(t: npt.ArrayLike, counts: npt.ArrayLike, ticks: npt.ArrayLike, clock_hz: float
                      ) -> tuple[Array, IntArray]:
    """Edges from an ECU's sampled tooth counter and its capture register.

    At each sample the counter holds the edges counted so far and the capture register the timer value
    ``ticks`` (at ``clock_hz``) of the latest.  An edge's tooth is the count just after it.  When the count
    rose by ``d > 1`` since the previous sample, the ``d - 1`` edges between are given time stamps evenly
    between the previous capture and this one (their own captures were overwritten: the TSA fit sees them
    as a wheel turning at constant speed over that interval).

    Returns
    -------
    edge_times, edge_teeth : ndarray
        [s] and tooth counts.

    Raises
    ------
    LogError
        A counter that goes back or an edge count beyond ``MAX_LOG_SAMPLES``.
    """
    return CounterEdges(clock_hz).piece(np.asarray(counts, dtype=float), np.asarray(ticks, dtype=float))


class WheelSpeedEdges:
    """The edges an ideal ``encoder`` gives on a wheel turning at sampled speeds, fed in pieces
    (:func:`edges_from_wheel_speed` is one piece; the angle carried on from piece to piece).

    Raises
    ------
    LogError
        A negative wheel speed.
    """

    def __init__(self, encoder: Encoder) -> None:
        self._encoder = encoder
        self._last: tuple[float, float, float] | None = None     # (t, omega, angle) of the last sample

    def piece(self, t: Array, omega: Array) -> tuple[Array, IntArray]:
        """The edges the wheel crosses up to the last of the samples ``t`` (speeds ``omega`` [rad/s])."""
        tt, om = np.asarray(t, dtype=float), np.asarray(omega, dtype=float)
        if np.any(om < 0):
            raise LogError(f"the wheel speed is negative ({float(om[om < 0][0])!r} rad/s); it must be >= 0")
        if tt.size == 0:
            return np.zeros(0), np.zeros(0, dtype=np.int_)
        if self._last is None:
            above, h = 0.0, np.diff(tt)
            theta = np.cumsum(np.concatenate([[0.0], 0.5 * (om[:-1] + om[1:]) * h]))
        else:
            t0, om0, above = self._last
            tt, om = np.concatenate([[t0], tt]), np.concatenate([[om0], om])
            h = np.diff(tt)
            theta = np.concatenate([[above], _running(above, 0.5 * (om[:-1] + om[1:]) * h)])
        self._last = (float(tt[-1]), float(om[-1]), float(theta[-1]))
        stamps, _, _, teeth = wheel_edges(self._encoder, tt, h, om, theta, above=above)
        return stamps, teeth


def edges_from_wheel_speed(t: npt.ArrayLike, omega: npt.ArrayLike, encoder: Encoder) -> tuple[Array, IntArray]:
    """The edges an ideal ``encoder`` gives on a wheel turning at the sampled speeds ``omega`` [rad/s].

    The angle is integrated from 0 at ``t[0]`` with the speed linear between samples, and the edges are
    located on it as the simulated chain locates them (:class:`EncoderLoopEstimator`): a log of wheel speeds
    goes through the same TSA and compensation as one of edges.
    """
    return WheelSpeedEdges(encoder).piece(np.asarray(t, dtype=float), np.asarray(omega, dtype=float))


@dataclass(frozen=True)
class ReplaySummary(JsonRecord, error=SimulationError):
    """What a replay did, in a few numbers (:meth:`ReplayResult.to_json` has the signals too).

    Attributes
    ----------
    source : str
    observer : str
        The observer (kind, gains, implementation) and ``method`` its step method.
    samples, measured, steps, edges : int
        Controller samples, those with a full TSA window, observer steps taken, encoder edges.
    outcome : str
        ``ok``, or ``observer-failed`` (the observer refused a step: ``message`` names the status).
    message : str
    rate_hz : float
        The controller (sample) rate of the chain.
    xbs_final : float
        The last estimate (NaN when none).
    """

    source: str
    observer: str
    method: str
    samples: int
    measured: int
    steps: int
    edges: int
    outcome: str
    message: str
    rate_hz: float
    xbs_final: float

    def to_json(self) -> dict[str, Any]:
        """The fields (a NaN ``xbs_final`` as None)."""
        out: dict[str, Any] = {f: getattr(self, f) for f in self.__dataclass_fields__}
        out["xbs_final"] = None if math.isnan(self.xbs_final) else self.xbs_final
        return out

    def __str__(self) -> str:
        final = "n/a" if math.isnan(self.xbs_final) else f"{self.xbs_final:.4f}"
        text = (f"replay of {self.source}: {self.samples} samples at {self.rate_hz:g} Hz ({self.measured} measured), "
                f"{self.edges} edges; {self.observer}: {self.steps} steps, {self.outcome}; final XBS estimate {final}")
        return text + (f"\n{self.message}" if self.message else "")


@dataclass(frozen=True, eq=False)
class ReplayResult(EncoderSamples):
    """The encoder chain's signals and the observer's estimates at the controller samples of a replayed log:
    an :class:`EncoderSamples` with the estimates and how the replay ended.

    Attributes
    ----------
    t, t_measured, x2_tsa, x2_notch, x2_measured, omega_tsa, omega_measured, vx : ndarray
        Of :class:`EncoderSamples` (NaN until the TSA window is full).
    xbs_hat : ndarray
        The observer's XBS estimate at each sample (NaN before the first measurement and from a refused step).
    status : ndarray of int
        :class:`switchobs.spec.StepStatus` of the observer step taken at each sample (0 where none is taken).
    summary : ReplaySummary
        What was replayed and how it ended (``summary.to_json()``: the few numbers ``switchobs replay --json``
        prints).
    """

    xbs_hat: Array
    status: IntArray
    summary: ReplaySummary

    #: The columns of :meth:`arrays`, in order.
    COLUMNS = (*EncoderSamples.SIGNALS, "xbs_hat", "status")

    def to_json(self) -> dict[str, Any]:
        """The signals as lists (NaN as None) and the summary."""
        return {**{name: array_to_json(a) for name, a in self.arrays().items()}, "summary": self.summary.to_json()}

    def arrays(self) -> dict[str, npt.NDArray[Any]]:
        """The signals by name (:attr:`COLUMNS`)."""
        return {name: getattr(self, name) for name in self.COLUMNS}

    @classmethod
    def join(cls, pieces: Sequence[Mapping[str, npt.NDArray[Any]]], summary: ReplaySummary) -> ReplayResult:
        """The result of the pieces :func:`stream_replay` hands out, in order."""
        if not pieces:
            return cls(**{k: np.zeros(0, dtype=np.int_ if k == "status" else float) for k in cls.COLUMNS},
                       summary=summary)
        return cls(**{k: pieces[0][k] if len(pieces) == 1 else np.concatenate([p[k] for p in pieces])
                      for k in cls.COLUMNS}, summary=summary)

    def to_dataframe(self) -> Any:
        """The signals as a pandas DataFrame indexed by nothing but the row (pandas must be installed)."""
        try:
            import pandas as pd
        except ImportError:
            from ..exceptions import PrerequisiteError
            raise PrerequisiteError("to_dataframe needs pandas: pip install pandas "
                                    "(or use ReplayResult.arrays())") from None
        return pd.DataFrame(self.arrays())

    def __str__(self) -> str:
        return str(self.summary)


#: Raster rows of a log fed to the chain at a time by :func:`stream_replay` (a minute at 1 kHz): the chain's and
#: the observer's arrays of one piece, a few tens of MB, whatever the log's length.
REPLAY_CHUNK = 65_536


class ReplayStream:
    """The encoder chain and an XBS observer over a log's signals fed in pieces (what :func:`replay` runs).

    :meth:`push` hands the next raster rows and edges to the chain (:class:`EdgeChain`), :meth:`drain` the
    controller samples they decide with the observer's estimates, and :meth:`summary` how the replay ended.
    The observer steps from measurement to measurement as :meth:`EncoderMeasurements.observer_steps` lists
    them, its state and the last measurement it stepped from carried across pieces: the columns drained
    piece by piece, joined, are those of the whole log at once bit for bit.

    Parameters
    ----------
    ppr, both_edges
        The encoder (:class:`LogSignals`).
    observer, method, beta, impl, vehicle, rate_hz, order, window, harmonics, notch_damping, compiled
        As :func:`replay`.

    Raises
    ------
    SimulationError
        Bad chain or observer settings.
    """

    def __init__(self, *, ppr: int, both_edges: bool = False, observer: str = "xbs4", method: str = "radau3",
                 beta: float | None = None, impl: str = "python", vehicle: QuarterCar | None = None,
                 rate_hz: float = 1000.0, order: int = 2, window: int = 15, harmonics: int = 5,
                 notch_damping: float = 0.5, compiled: bool | None = None) -> None:
        vehicle = QuarterCar() if vehicle is None else vehicle
        spec = EstimatorSpec(observer, beta=beta, impl=impl, method=method)
        progress(f"replay: building the {spec}")
        est = xbs_estimator(spec, vehicle, "dry-asphalt") if observer != "none" else None
        self._obs = est.observer if isinstance(est, ObserverXbsEstimator) else None
        self.described = str(spec) if self._obs is not None else "no observer (the chain only)"
        self._initial = INITIAL_STATE.get(observer, {})
        self._encoder = ideal_encoder(ppr, both_edges=both_edges)
        self._chain = EdgeChain(radius_m=vehicle.radius_m, rate_hz=rate_hz, order=order, window=window,
                                harmonics=harmonics, notch_damping=notch_damping, compiled=compiled)
        self._method, self.rate_hz, self._window = method, float(rate_hz), window
        self._samples = self._measured = self._steps = self._taken = 0
        self._newest = -math.inf                 # the latest t_measured so far
        self._last: tuple[float, float, float, float] | None = None   # (t, y, vx, p) of the last measurement taken
        self._x: Array | None = None             # the observer's state after it
        self._hat = math.nan                     # its readout, the estimate until the next step
        self._outcome = "ok"
        self._refusal: tuple[int, str] | None = None     # the step refused and why
        self._final = math.nan                   # the estimate at the last sample

    def push(self, t: Array, vx: Array, pressure: Array, edge_times: Array, edge_teeth: IntArray, *,
             done: bool = False) -> None:
        """The next raster rows (time [s], speed [m/s], ``∫ u dt`` [bar]) and edges (time stamps [s], teeth);
        ``done``: the last ones."""
        self._chain.push_raster(t, vx, pressure, done=done)
        self._chain.push_edges(edge_times, edge_angles(self._encoder, edge_teeth), done=done)

    def drain(self) -> dict[str, npt.NDArray[Any]]:
        """The samples decided so far: :attr:`ReplayResult.COLUMNS` by name."""
        m = self._chain.drain()
        size = m["t"].size
        hat, status = np.full(size, self._hat), np.zeros(size, dtype=np.int_)
        ok = np.flatnonzero(np.isfinite(m["t_measured"]))
        tc = m["t_measured"][ok]
        # the samples whose measurement is newer than every earlier one (observer_steps)
        newer = tc > np.concatenate([[self._newest], np.maximum.accumulate(tc)[:-1]])
        taken = ok[newer]
        self._samples += size
        self._measured += ok.size
        if tc.size:
            self._newest = max(self._newest, float(tc.max()))
        y, vx, p, tm = m["x2_measured"], m["vx_measured"], m["pressure_measured"], m["t_measured"]
        marks, values = np.zeros(0, dtype=np.int_), np.zeros(0)
        if taken.size and self._last is None:       # the first measurement: the observer starts there
            start = int(taken[0])
            if self._obs is not None:
                self._x = initial_xbs_state(self._obs, float(y[start]), self._initial)
                marks, values = taken[:1], self._readout(self._x[None, :])
            self._last = (float(tm[start]), float(y[start]), float(vx[start]), float(p[start]))
            taken = taken[1:]
        self._taken += taken.size
        if taken.size:
            assert self._last is not None
            t0, y0, v0, p0 = self._last
            tt, yy, vv, pp = (np.concatenate([[a], b[taken]]) for a, b in ((t0, tm), (y0, y), (v0, vx), (p0, p)))
            if self._x is not None and self._outcome == "ok":
                span = tt[1:] - tt[:-1]
                rows = np.column_stack([0.5 * (yy[:-1] + yy[1:]), 0.5 * (vv[:-1] + vv[1:]), (pp[1:] - pp[:-1]) / span])
                states, refused, code, text = _step(self._obs, self._x, rows, span)
                done = states.shape[0] - 1
                self._steps += done
                marks = np.concatenate([marks, taken[:done]])
                values = np.concatenate([values, self._readout(states[1:])])
                self._x = states[-1]
                if refused is not None:
                    marks, values = np.append(marks, taken[refused]), np.append(values, math.nan)
                    status[taken[refused]] = code
                    # numbered among all the steps, which summary() counts at the end
                    self._outcome, self._refusal = "observer-failed", (self._steps + 1, text)
            self._last = (float(tt[-1]), float(yy[-1]), float(vv[-1]), float(pp[-1]))
        if marks.size:
            # from each step's sample on, the readout of the state after it (module notes of observer_steps)
            which = np.cumsum(np.bincount(marks, minlength=size)) - 1     # the marks at or before each sample
            hat = np.where(which >= 0, values[np.maximum(which, 0)], self._hat)
            self._hat = float(values[-1])
        if self._outcome != "ok":
            self._x = None
        if size:
            self._final = float(hat[-1])
        return {**{k: m[k] for k in EncoderSamples.SIGNALS}, "xbs_hat": hat, "status": status}

    def _readout(self, states: Array) -> Array:
        return np.asarray(self._obs.readout(states), dtype=float)

    def summary(self, source: str) -> ReplaySummary:
        """How the replay of everything pushed ended (after the last :meth:`drain`).

        Raises
        ------
        LogError
            A log shorter than the chain's warm-up (no full TSA window, or a single measurement).
        """
        if self._taken == 0:
            raise LogError(f"the log is shorter than the chain's warm-up: {self._chain.edges} edges give "
                           f"{self._measured} measurements at {self.rate_hz:g} Hz (a TSA window of {self._window} "
                           "edges, then two measurements for one observer step)")
        message = "" if self._refusal is None else \
            f"step {self._refusal[0]} of {self._taken} refused: {self._refusal[1]}"
        return ReplaySummary(source=source, observer=self.described, method=self._method, samples=self._samples,
                             measured=self._measured, steps=self._steps, edges=self._chain.edges,
                             outcome=self._outcome, message=message, rate_hz=self.rate_hz,
                             xbs_final=self._final)


@dataclass(frozen=True, eq=False)
class SignalPiece:
    """The next raster rows (time [s], speed [m/s], ``∫ u dt`` [bar]) and edges (time stamps [s], teeth) of a
    log's signals, in SI units: what :class:`ReplayStream` is pushed; ``done`` on the last."""

    t: Array
    vx: Array
    pressure: Array
    edge_times: Array
    edge_teeth: IntArray
    done: bool = False


class SignalSource(Protocol):
    """Signals fed piece by piece (:class:`LogSignals`; ``switchobs.logs.LogStream`` reads a log so):
    the encoder's ``ppr`` and ``both_edges``, the pieces, and ``source`` (final once they are read)."""

    ppr: int
    both_edges: bool

    @property
    def source(self) -> str: ...

    def pieces(self, rows: int | None = None) -> Iterator[SignalPiece]: ...


def stream_replay(signals: SignalSource, write: Callable[[dict[str, npt.NDArray[Any]]], object], *,
                  chunk: int | None = None, **options: Any) -> ReplaySummary:
    """Run the chain and the observer over ``signals`` piece by piece (at most ``chunk`` raster rows each, if
    given), handing each piece's samples to ``write`` (:attr:`ReplayResult.COLUMNS` by name) as they are
    decided; the options are those of :func:`replay`.  The pieces joined equal :func:`replay`'s result
    bit for bit, whatever their boundaries; only a piece's arrays are held at a time besides what
    ``signals`` holds (a :class:`LogSignals` its arrays, a log read piece by piece one piece).

    Returns
    -------
    ReplaySummary

    Raises
    ------
    LogError, SimulationError
        As :func:`replay` (the warm-up's error after the last piece).
    """
    if chunk is not None and not (isinstance(chunk, int) and chunk >= 1):
        raise SimulationError(f"chunk must be an integer >= 1, got {chunk!r}")
    stream = ReplayStream(ppr=signals.ppr, both_edges=signals.both_edges, **options)
    progress(f"replay: encoder chain at {stream.rate_hz:g} Hz")
    for piece in signals.pieces(chunk):
        stream.push(piece.t, piece.vx, piece.pressure, piece.edge_times, piece.edge_teeth, done=piece.done)
        write(stream.drain())
    return stream.summary(signals.source)


def replay(signals: LogSignals, *, observer: str = "xbs4", method: str = "radau3", beta: float | None = None,
           impl: str = "python", vehicle: QuarterCar | None = None, rate_hz: float = 1000.0, order: int = 2,
           window: int = 15, harmonics: int = 5, notch_damping: float = 0.5, compiled: bool | None = None,
           chunk: int = REPLAY_CHUNK) -> ReplayResult:
    """Run the encoder chain and an XBS observer over a log's signals.

    Parameters
    ----------
    signals : LogSignals
    observer : {"xbs3", "xbs4", "adaptive", "none"}
        The observer (:func:`xbs_estimator`; ``none``: the chain only).  ``beta``, ``impl`` (``python`` or
        ``c``) and ``method`` as :class:`EstimatorSpec`; ``radau3`` is certified for every step length, which
        one step per measurement interval needs.
    vehicle : QuarterCar, optional
        The wheel radius, inertia, load and brake gain the observer's model and the chain use
        (default ``QuarterCar()``).
    rate_hz, order, window, harmonics, notch_damping, compiled
        As :class:`EncoderLoopEstimator`: controller rate, TSA order ``m`` and window ``n`` (seed 001
        (5.2)-(5.5)), harmonics ``M`` of (6.2), the notch's damping, the C kernels.
    chunk : int, optional
        Raster rows run at a time (:func:`stream_replay`; default :data:`REPLAY_CHUNK`; the result does not
        depend on it).

    Returns
    -------
    ReplayResult

    Raises
    ------
    LogError
        A log shorter than the chain's warm-up (no full TSA window, or a single measurement).
    SimulationError
        Bad chain or observer settings.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0.0, 0.5, 501)                       # free rolling at 20 m/s, a 60-ppr wheel
    >>> stamps, teeth = edges_from_wheel_speed(t, np.full(t.size, 20.0 / 0.3), Encoder(ppr=60))
    >>> sig = LogSignals(t, np.full(t.size, 20.0), np.zeros(t.size), stamps, teeth, ppr=60)
    >>> res = replay(sig)
    >>> res.summary.outcome, res.summary.measured > 400, abs(float(np.nanmean(res.omega_measured)) - 20 / 0.3) < 1e-6
    ('ok', True, True)
    """
    pieces: list[dict[str, npt.NDArray[Any]]] = []
    summary = stream_replay(signals, pieces.append, chunk=chunk, observer=observer, method=method, beta=beta,
                            impl=impl, vehicle=vehicle, rate_hz=rate_hz, order=order, window=window,
                            harmonics=harmonics, notch_damping=notch_damping, compiled=compiled)
    return ReplayResult.join(pieces, summary)


def _step(obs: Any, x0: Array, rows: Array, span: Array) -> tuple[Array, int | None, int, str]:
    """The states from ``x0`` through the steps (``x0`` first), the step refused (or None), its status code and
    the refusal's text.  The whole run in one call (:func:`step_through`); after a refusal, the steps before it
    again one by one to find where it was."""
    try:
        return np.vstack([x0, step_through(obs, x0, rows, span)]), None, 0, ""
    except SimulationError:
        pass
    out, x = [x0], x0
    for i, (row, dt) in enumerate(zip(rows.tolist(), span.tolist())):
        try:
            x = np.asarray(obs.step(x, row, dt), dtype=float)
        except ObserverInputError as exc:   # its message names the StepStatus and its code
            return np.vstack(out), i, int(exc.code), str(exc)
        out.append(x)
    return np.vstack(out), None, 0, ""


def measurements_signals(m: EncoderMeasurements, ppr: int, *, both_edges: bool = False,
                         source: str = "simulation") -> LogSignals:
    """The samples the chain read in a simulated run (:attr:`EncoderLoopEstimator.measurements`) as a log's
    signals: replaying them gives the run's measurements and estimates bit for bit."""
    return LogSignals(m.steps_t, m.vx_steps, m.pressure_steps, m.edge_times, m.edge_teeth, ppr=ppr,
                      both_edges=both_edges, source=source)
