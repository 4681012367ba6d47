"""Recorded data in: the encoder chain and an XBS observer over a measurement log's signals.

A log gives what the chain of :class:`EncoderLoopEstimator` reads in the loop, without the plant: the
encoder's edges (time stamps, and the tooth each one belongs to), the vehicle speed and the brake pressure
on a raster of samples.  :class:`LogSignals` holds them in SI units (the table a reader of MDF4, CSV or
Parquet files fills: :mod:`switchobs.logs`); the helpers below turn what loggers record into it (tooth
counts with a capture clock, wheel speed samples, a pressure rate, an accelerometer).  :func:`replay` runs
the chain (:func:`measure_edges`: TSA seed 001 (5.1)-(5.5), three-stage compensation Fig. 6.2, notch Sec.
6.3) and the observer over them, one observer step from measurement to measurement with the signals held
(the zero-order hold of the generated C step, seed 000 eq. (13)), and returns a :class:`ReplayResult`.

A log of a simulated braking that carries the samples the chain read in the simulation
(:attr:`EncoderLoopEstimator.measurements`) replays to the simulation's estimates bit for bit: the same
function computes both.  Signals recorded on different rasters are resampled onto one by
:func:`zero_order_hold` first (:mod:`switchobs.logs` does it for a log).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from .._json import JsonRecord, array_to_json
from .._limits import MAX_LOG_SAMPLES
from .._progress import progress
from ..exceptions import LogError, ObserverInputError, SimulationError
from ..plants import QuarterCar
from ..sensors import Encoder
from ._adapter import ObserverXbsEstimator, initial_xbs_state
from ._encoder_batch import EncoderMeasurements, EncoderSamples, edge_angles, measure_edges, wheel_edges
from ._factory import INITIAL_STATE, EstimatorSpec, xbs_estimator
from ._stepping import step_through

__all__ = ["LogSignals", "ReplayResult", "ReplaySummary", "replay", "zero_order_hold", "pressure_from_rate",
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


def pressure_from_rate(t: npt.ArrayLike, rate: npt.ArrayLike) -> Array:
    """``∫ u dt`` from ``t[0]`` [bar] of a pressure rate [bar/s] held from each sample to the next (ZOH)."""
    tt, uu = np.asarray(t, dtype=float), np.asarray(rate, dtype=float)
    return np.cumsum(np.concatenate([[0.0], uu[:-1] * np.diff(tt)]))


def speed_from_acceleration(t: npt.ArrayLike, ax: npt.ArrayLike, initial_speed_m_s: float) -> Array:
    """Vehicle speed [m/s] from a longitudinal accelerometer [m/s²] (trapezoidal rule) and the speed at ``t[0]``."""
    tt, aa = np.asarray(t, dtype=float), np.asarray(ax, dtype=float)
    if not (math.isfinite(initial_speed_m_s) and initial_speed_m_s > 0):
        raise LogError(f"the initial speed must be finite and > 0 m/s, got {initial_speed_m_s!r}")
    return initial_speed_m_s + np.cumsum(np.concatenate([[0.0], 0.5 * (aa[:-1] + aa[1:]) * np.diff(tt)]))


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
    c = np.asarray(counts, dtype=float)
    stamps = np.asarray(ticks, dtype=float) / float(clock_hz)
    if c.size and not np.array_equal(c, np.round(c)):
        raise LogError("the tooth counter holds values that are not integers")
    rise = np.diff(c)
    if np.any(rise < 0):
        i = int(np.flatnonzero(rise < 0)[0])
        raise LogError(f"the tooth counter goes back from {c[i]:.0f} to {c[i + 1]:.0f} at sample {i + 1}; "
                       "it must not decrease (unwrap a wrapping counter first)")
    total = int(c[-1] - c[0]) if c.size else 0
    if total > MAX_LOG_SAMPLES:
        raise LogError(f"the tooth counter counts {total} edges (limit MAX_LOG_SAMPLES = {MAX_LOG_SAMPLES})")
    new = np.flatnonzero(rise > 0) + 1
    d = rise[new - 1].astype(np.int64)
    last, prev = stamps[new], stamps[new - 1]     # the register held the previous count's edge one sample before
    group = np.repeat(np.arange(new.size), d)
    j = np.arange(group.size) - np.repeat(np.cumsum(d) - d, d) + 1          # 1..d within each sample
    times = np.where(j == d[group], last[group], prev[group] + (j / d[group]) * (last[group] - prev[group]))
    teeth = np.repeat(c[new].astype(np.int64) - d, d) + j
    return times, teeth.astype(np.int_)


def edges_from_wheel_speed(t: npt.ArrayLike, omega: npt.ArrayLike, encoder: Encoder) -> tuple[Array, IntArray]:
    """The edges an ideal ``encoder`` gives on a wheel turning at the sampled speeds ``omega`` [rad/s].

    The angle is integrated from 0 at ``t[0]`` with the speed linear between samples, and the edges are
    located on it as the simulated chain locates them (:class:`EncoderLoopEstimator`): a log of wheel speeds
    goes through the same TSA and compensation as one of edges.
    """
    tt, om = np.asarray(t, dtype=float), np.asarray(omega, dtype=float)
    if np.any(om < 0):
        raise LogError(f"the wheel speed is negative ({float(om[om < 0][0])!r} rad/s); it must be >= 0")
    h = np.diff(tt)
    theta = np.cumsum(np.concatenate([[0.0], 0.5 * (om[:-1] + om[1:]) * h]))
    stamps, _, _, teeth = wheel_edges(encoder, tt, h, om, theta)
    return stamps, teeth


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


def replay(signals: LogSignals, *, observer: str = "xbs4", method: str = "radau3", beta: float | None = None,
           impl: str = "python", vehicle: QuarterCar | None = None, rate_hz: float = 1000.0, order: int = 2,
           window: int = 15, harmonics: int = 5, notch_damping: float = 0.5, compiled: bool | None = None
           ) -> ReplayResult:
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
    vehicle = QuarterCar() if vehicle is None else vehicle
    spec = EstimatorSpec(observer, beta=beta, impl=impl, method=method)
    progress(f"replay: building the {spec}")
    est = xbs_estimator(spec, vehicle, "dry-asphalt") if observer != "none" else None
    progress(f"replay: encoder chain over {signals.edge_times.size} edges at {rate_hz:g} Hz")
    angles = edge_angles(signals.encoder, signals.edge_teeth)
    m = measure_edges(signals.t, signals.vx, signals.pressure, signals.edge_times, angles, signals.edge_teeth,
                      radius_m=vehicle.radius_m, rate_hz=rate_hz, order=order, window=window,
                      harmonics=harmonics, notch_damping=notch_damping, compiled=compiled)
    first, at, span, rows = m.observer_steps()
    if first < 0 or at.size == 0:
        raise LogError(f"the log is shorter than the chain's warm-up: {signals.edge_times.size} edges give "
                       f"{int(np.count_nonzero(np.isfinite(m.t_measured)))} measurements at {rate_hz:g} Hz "
                       f"(a TSA window of {window} edges, then two measurements for one observer step)")
    hat = np.full(m.t.size, np.nan)
    status = np.zeros(m.t.size, dtype=np.int_)
    outcome, message, steps = "ok", "", 0
    if isinstance(est, ObserverXbsEstimator):
        obs = est.observer
        progress(f"replay: {rows.shape[0]} observer steps")
        x0 = initial_xbs_state(obs, float(m.x2_measured[first]), INITIAL_STATE[observer])
        states, refused, code, message = _step(obs, x0, rows, span)
        steps = states.shape[0] - 1
        # from each step's sample on, the readout of the state after it (module notes of observer_steps)
        taken = np.concatenate([[first], at[:steps]])
        which = np.searchsorted(taken, np.arange(m.t.size), side="right") - 1
        readout = np.asarray(obs.readout(states), dtype=float)
        hat = np.where(which >= 0, readout[np.maximum(which, 0)], np.nan)
        if refused is not None:
            hat[at[refused]:] = np.nan
            status[at[refused]] = code
            outcome = "observer-failed"
        described = str(spec)
    else:
        described = "no observer (the chain only)"
    summary = ReplaySummary(source=signals.source, observer=described, method=method, samples=int(m.t.size),
                            measured=int(np.count_nonzero(np.isfinite(m.t_measured))), steps=steps,
                            edges=m.events, outcome=outcome, message=message, rate_hz=float(rate_hz),
                            xbs_final=float(hat[-1]) if hat.size else math.nan)
    return ReplayResult(**m.signals(), xbs_hat=hat, status=status, summary=summary)


def _step(obs: Any, x0: Array, rows: Array, span: Array) -> tuple[Array, int | None, int, str]:
    """The states from ``x0`` through the steps (``x0`` first), the step refused (or None), its status code and
    a message.  The whole run in one call (:func:`step_through`); after a refusal, the steps before it again
    one by one to find where it was."""
    try:
        return np.vstack([x0, step_through(obs, x0, rows, span)]), None, 0, ""
    except SimulationError:
        pass
    out, x = [x0], x0
    for i, (row, dt) in enumerate(zip(rows.tolist(), span.tolist())):
        try:
            x = np.asarray(obs.step(x, row, dt), dtype=float)
        except ObserverInputError as exc:   # its message names the StepStatus and its code
            return np.vstack(out), i, int(exc.code), f"step {i + 1} of {span.size} refused: {exc}"
        out.append(x)
    return np.vstack(out), None, 0, ""


def measurements_signals(m: EncoderMeasurements, ppr: int, *, both_edges: bool = False,
                         source: str = "simulation") -> LogSignals:
    """The samples the chain read in a simulated run (:attr:`EncoderLoopEstimator.measurements`) as a log's
    signals: replaying them gives the run's measurements and estimates bit for bit."""
    return LogSignals(m.steps_t, m.vx_steps, m.pressure_steps, m.edge_times, m.edge_teeth, ppr=ppr,
                      both_edges=both_edges, source=source)
