"""The encoder chain over a whole recorded run at once: what :class:`EncoderLoopEstimator` measures step by step.

When the controller does not read the estimate, the plant's trajectory does not depend on the
encoder chain, so the chain can run after the plant (e.g. after the compiled loop) on the recorded
steps: :func:`encoder_measurements` reconstructs the wheel, generates the edges, fits the TSA windows
and compensates the samples in a few array operations and one call of the three-stage kernel, and
gives the numbers the per-step :class:`EncoderLoopEstimator` gives (the same floating-point
operations on the same values; ``tests/test_loop_encoder_batch.py`` checks them bit for bit).
:meth:`EncoderMeasurements.observer_steps` lists the observer steps the per-step estimator takes.
:class:`EdgeChain` is the chain from the edges on fed in pieces (a log's replay streams through it);
:func:`measure_edges` feeds it once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from .._json import JsonRecord, array_to_json
from ..exceptions import SimulationError
from ..sensors import Encoder, NotchFilter, ThreeStageEstimator
from ..sensors._tsa import check_order_window, fit_windows

__all__ = ["EncoderSamples", "EncoderMeasurements", "encoder_measurements", "measure_edges", "edge_angles", "EdgeChain",
           "CHAIN_COLUMNS"]

Array = npt.NDArray[np.float64]


def _floats(a: Any) -> list[float | None]:
    """A 1-D array as a list of floats, NaN as None."""
    return array_to_json(np.asarray(a, dtype=float))  # type: ignore[no-any-return]


@dataclass(frozen=True, eq=False)
class EncoderSamples(JsonRecord, error=SimulationError):
    """The encoder chain's signals at the controller samples: the one measurement record.

    :class:`EncoderMeasurements` (the chain over a recorded run at once), :class:`EncoderLoopRecord` (the chain
    step by step inside the loop) and :class:`ReplayResult` (the chain over a log) are each this record with
    what their producer adds (subclasses: the same fields, in the same order, first).

    Attributes
    ----------
    t : ndarray
        Controller sample times [s].
    t_measured : ndarray
        Time the measurement of each sample describes: the mean time stamp of the TSA window
        (NaN until the window is full).
    x2_tsa, x2_notch, x2_measured : ndarray
        ``R α - a_x`` from the raw TSA, through the notch (centre ``ω_m``) and after three-stage
        compensation [m/s²] (seed 001 Secs. 5.2, 6.3, Fig. 6.2).
    omega_tsa, omega_measured : ndarray
        Raw TSA and compensated wheel speed [rad/s].
    vx : ndarray
        Vehicle speed at the samples [m/s].
    """

    t: Array
    t_measured: Array
    x2_tsa: Array
    x2_notch: Array
    x2_measured: Array
    omega_tsa: Array
    omega_measured: Array
    vx: Array

    #: The chain's signals, in field order.
    SIGNALS = ("t", "t_measured", "x2_tsa", "x2_notch", "x2_measured", "omega_tsa", "omega_measured", "vx")

    @property
    def lag_s(self) -> Array:
        """Age of the measurement at each sample, ``t - t_measured`` [s]."""
        return self.t - self.t_measured

    def signals(self) -> dict[str, Array]:
        """The chain's signals by name (:attr:`SIGNALS`): the fields a record derived from this one copies."""
        return {name: getattr(self, name) for name in self.SIGNALS}

    def to_json(self) -> dict[str, Any]:
        """The signals as lists (NaN as None)."""
        return {name: _floats(a) for name, a in self.signals().items()}

    def __str__(self) -> str:
        ok = np.isfinite(self.t_measured)
        lag = f"{1e3 * float(np.mean(self.lag_s[ok])):.1f} ms" if np.any(ok) else "n/a"
        return f"encoder samples: {self.t.size} ({int(np.count_nonzero(ok))} measured), mean measurement lag {lag}"


@dataclass(frozen=True, eq=False)
class EncoderMeasurements(EncoderSamples):
    """The encoder chain's measurements at the controller samples of a run: an :class:`EncoderSamples` with
    what the observers and a replay need.

    Attributes
    ----------
    t, t_measured, x2_tsa, x2_notch, x2_measured, omega_tsa, omega_measured, vx : ndarray
        Of :class:`EncoderSamples` (NaN where the TSA window is not full yet).
    vx_measured : ndarray
        Vehicle speed at ``t_measured`` [m/s] (interpolated in the plant's steps).
    pressure_measured : ndarray
        ``∫ u dt`` from the start to ``t_measured`` [bar]: the brake pressure change.
    sample_step : ndarray of int
        For each sample, the index in the run's arrays (``t``, ``x2``, ``vx`` of
        :func:`encoder_measurements`) of the step end whose ``update()`` processes it: the estimate
        that call hands back already includes the sample.
    events : int
        Encoder edges generated.
    steps_t, omega_steps : ndarray
        Plant step ends (the start first, without the skipped steps) and the wheel speed
        reconstructed there [rad/s].
    vx_steps, pressure_steps : ndarray
        What the chain read at ``steps_t``: vehicle speed [m/s] and ``∫ u dt`` from the start [bar].
    edge_times : ndarray
        Time stamps of the encoder edges [s] (``events`` of them).
    edge_teeth : ndarray of int
        Each edge's count from tooth 0 of revolution 0: its nominal angle is
        ``nominal[k % E] + 2 π (k // E)`` for the ``E`` edges per revolution.
        With ``steps_t``, ``vx_steps`` and ``pressure_steps`` they are everything the chain measured
        from: a log of them replays to the same measurements (:func:`switchobs.loop.replay`).
    """

    vx_measured: Array
    pressure_measured: Array
    sample_step: npt.NDArray[np.int_]
    events: int
    steps_t: Array
    omega_steps: Array
    vx_steps: Array
    pressure_steps: Array
    edge_times: Array
    edge_teeth: npt.NDArray[np.int_]

    def observer_steps(self) -> tuple[int, npt.NDArray[np.int_], Array, Array]:
        """The observer steps of :class:`EncoderLoopEstimator` on these measurements.

        Returns
        -------
        first : int
            Sample of the first measurement (-1 if none): the observers start there,
            their first state at ``x2_measured[first]`` (``initial_xbs_state``).
        at : ndarray of int
            Samples at which the observers take a step: those whose ``t_measured`` is later than
            every earlier one.  From ``at[i]`` on (up to ``at[i + 1]``), the estimate is the readout
            of the state after step ``i``.
        span : ndarray
            Step lengths ``t_measured[at[i]] - t_measured[previous]`` [s].
        signals : ndarray (steps x 3)
            ``(y, vx, u)`` held over each step: the means of the bounding measurements of ``x2`` and
            ``vx``, and ``u`` the mean pressure rate of the interval.
        """
        ok = np.flatnonzero(np.isfinite(self.t_measured))
        if ok.size == 0:
            return -1, np.zeros(0, dtype=np.int_), np.zeros(0), np.zeros((0, 3))
        tc = self.t_measured[ok]
        newer = np.concatenate([[True], tc[1:] > np.maximum.accumulate(tc)[:-1]])
        taken = ok[newer]
        cur, prev = taken[1:], taken[:-1]
        span = self.t_measured[cur] - self.t_measured[prev]
        y, vx, p = self.x2_measured, self.vx_measured, self.pressure_measured
        signals = np.column_stack([0.5 * (y[prev] + y[cur]), 0.5 * (vx[prev] + vx[cur]),
                                   (p[cur] - p[prev]) / span])
        return int(taken[0]), cur, span, signals

    def to_json(self) -> dict[str, Any]:
        """Arrays as lists (NaN as None)."""
        out = super().to_json()
        out.update({k: _floats(getattr(self, k)) for k in (
            "vx_measured", "pressure_measured", "steps_t", "omega_steps", "vx_steps", "pressure_steps",
            "edge_times")})
        out.update(sample_step=self.sample_step.tolist(), events=self.events, edge_teeth=self.edge_teeth.tolist())
        return out

    def __str__(self) -> str:
        ok = np.isfinite(self.t_measured)
        lag = f"{1e3 * float(np.mean(self.lag_s[ok])):.1f} ms" if np.any(ok) else "n/a"
        return (f"encoder measurements: {self.t.size} samples ({int(np.count_nonzero(ok))} measured), "
                f"{self.events} edges, mean measurement lag {lag}")


def _steps(t: npt.ArrayLike, x2: npt.ArrayLike, vx: npt.ArrayLike, u: npt.ArrayLike,
           dt: npt.ArrayLike | None) -> tuple[Array, Array, Array, Array, Array, npt.NDArray[np.int_]]:
    """The run's arrays, checked, without the steps of non-positive length (``update`` ignores them), and the
    indices of the step ends kept."""
    arrays = [np.asarray(a, dtype=float) for a in (t, x2, vx)]
    tt = arrays[0]
    if tt.ndim != 1 or tt.size < 1:
        raise SimulationError(f"t must be a 1-D array of step ends with the start first, got shape {tt.shape}")
    for name, a in zip(("x2", "vx"), arrays[1:]):
        if a.shape != tt.shape:
            raise SimulationError(f"{name} has shape {a.shape}, t {tt.shape}: give one value per step end")
    uu = np.asarray(u, dtype=float)
    hh = np.diff(tt) if dt is None else np.asarray(dt, dtype=float)
    for name, a in (("u", uu), ("dt", hh)):
        if a.shape != (tt.size - 1,):
            raise SimulationError(f"{name} has shape {a.shape}; give one value per step ({tt.size - 1})")
    for name, a in (("t", tt), ("x2", arrays[1]), ("vx", arrays[2]), ("u", uu), ("dt", hh)):
        if not np.all(np.isfinite(a)):
            raise SimulationError(f"{name} holds {float(a[~np.isfinite(a)][0])!r}; the run's arrays must be finite")
    keep = np.concatenate([[True], hh > 0.0])
    return tt[keep], arrays[1][keep], arrays[2][keep], uu[keep[1:]], hh[keep[1:]], np.flatnonzero(keep)


def _wheel(x2: Array, vx: Array, h: Array, radius: float) -> tuple[Array, Array]:
    """Wheel speed and angle at the step ends, as :meth:`EncoderLoopEstimator.update` reconstructs them."""
    inc = ((vx[1:] - vx[:-1]) + 0.5 * (x2[:-1] + x2[1:]) * h) / radius
    om = np.cumsum(np.concatenate([[vx[0] / radius], inc]))
    # the running sum is update()'s sum while the clamp at 0 does not act; from its first action, a loop
    low = np.flatnonzero(0.0 > om[1:])
    if low.size:
        w, out = float(om[low[0]]), om.tolist()
        for i in range(int(low[0]) + 1, om.size):
            w = max(w + float(inc[i - 1]), 0.0)
            out[i] = w
        om = np.array(out)
    theta = np.cumsum(np.concatenate([[0.0], 0.5 * (om[:-1] + om[1:]) * h]))
    return om, theta


def fixed_edges(encoder: Encoder) -> Array:
    """The rotation angles of the encoder's edges; refuses a per-event jitter, which the loop does not model."""
    if encoder.jitter_cycles > 0:
        raise SimulationError(f"jitter_cycles = {encoder.jitter_cycles:g}: the ABS loop's encoder chain has fixed "
                              f"edges only; use jitter_cycles=0 (switchobs.sensors.encoder_chain models the jitter)")
    return encoder.rotation_angles()


def edge_angles(encoder: Encoder, teeth: npt.ArrayLike) -> Array:
    """Nominal angles of the edges counted ``teeth`` from tooth 0 of revolution 0 [rad] (seed 001 Sec. 5.3.1):
    ``nominal[k % E] + 2 π (k // E)``, the angles the chain assigns to the edges it generates."""
    nominal = encoder.nominal_angles()
    k = np.asarray(teeth, dtype=np.int64)
    rev, j = np.divmod(k, nominal.size)
    return nominal[j] + 2.0 * math.pi * rev.astype(float)


def wheel_edges(encoder: Encoder, t: Array, h: Array, om: Array, theta: Array, *, above: float = 0.0
                ) -> tuple[Array, Array, npt.NDArray[np.int_], npt.NDArray[np.int_]]:
    """Time stamps, assigned angles, generating steps and tooth counts of the edges the wheel crosses while its
    angle goes through ``theta`` at the step ends ``t`` (speed ``om``, linear over each step of length ``h``),
    as ``EncoderLoopEstimator._edges`` generates them: the edges at angles above ``above`` (``theta[0]`` of a
    later piece of the run, whose earlier edges are crossed)."""
    two_pi = 2.0 * math.pi
    base, nominal = fixed_edges(encoder), encoder.nominal_angles()
    first = max(int(above // two_pi) - 1, 0)          # no edge of an earlier revolution lies above
    revs = np.arange(first, int(theta[-1] // two_pi) + 2, dtype=float)
    levels = (base[None, :] + two_pi * revs[:, None]).ravel()
    angles = (nominal[None, :] + two_pi * revs[:, None]).ravel()
    fired = (levels > above) & (levels <= theta[-1])
    teeth = first * base.size + np.flatnonzero(fired)
    levels, angles = levels[fired], angles[fired]
    step = np.searchsorted(theta, levels, side="left")       # first step end at or past the level
    t0, hs, om0, om1, th0 = t[step - 1], h[step - 1], om[step - 1], om[step], theta[step - 1]
    k = 0.5 * (om1 - om0) / hs
    d = levels - th0
    disc = om0 * om0 + 4.0 * k * d
    root = om0 + np.sqrt(np.where(0.0 > disc, 0.0, disc))
    with np.errstate(divide="ignore", invalid="ignore"):
        tau = 2.0 * d / root
    tau = np.where(root > 0.0, np.where(hs < tau, hs, tau), hs)
    stamps = t0 + tau
    if encoder.clock_hz is not None:
        stamps = np.floor(stamps * encoder.clock_hz) / encoder.clock_hz
    return stamps, angles, step, teeth


def encoder_measurements(t: npt.ArrayLike, x2: npt.ArrayLike, vx: npt.ArrayLike, u: npt.ArrayLike,
                         dt: npt.ArrayLike | None = None, *, encoder: Encoder, radius_m: float,
                         rate_hz: float = 1000.0, order: int = 2, window: int = 15, harmonics: int = 5,
                         notch_damping: float = 0.5, compiled: bool | None = None) -> EncoderMeasurements:
    """The encoder chain of :class:`EncoderLoopEstimator` run over a whole recorded run at once.

    The arguments are those the plant hands the estimator: ``reset(t[0], x2[0], vx[0])``, then
    ``update(t[i], x2[i], vx[i], u[i - 1], dt[i - 1])`` for each step ``i >= 1``.  The wheel is
    reconstructed from them (seed 001 eq. (2.1)-(2.2)), the edges generated, the TSA fitted at each
    controller sample on the edges the per-step chain has at that sample (seed 001 (5.1)-(5.5)), and
    the samples compensated (Fig. 6.2) and notch-filtered; the numbers equal those of the
    per-step estimator with the same ``compiled`` (bit for bit: the same operations on the same values).

    Parameters
    ----------
    t, x2, vx : array_like
        Step ends with the start first (``N + 1`` values): time [s], ``x2`` [m/s²], vehicle speed [m/s].
    u : array_like
        Pressure rate over each step (``N`` values) [bar/s]: ``simulate`` hands the estimator the
        step's mean, ``(P_b[i] - P_b[i - 1]) / dt[i - 1]``.
    dt : array_like, optional
        Step lengths (``N`` values) [s]; ``np.diff(t)`` if omitted.  ``simulate`` hands the estimator the
        integrator's step ``h``, which ``np.diff(t)`` reproduces only to rounding: pass it for equality
        bit for bit.  Steps with ``dt <= 0`` are skipped, as :meth:`EncoderLoopEstimator.update` skips them.
    encoder, radius_m, rate_hz, order, window, harmonics, notch_damping, compiled
        As :class:`EncoderLoopEstimator`.

    Returns
    -------
    EncoderMeasurements
        Per controller sample; :meth:`EncoderMeasurements.observer_steps` gives the observer's steps.

    Raises
    ------
    SimulationError
        Arrays of the wrong shapes or not finite, bad chain settings, or two edges on one timer tick
        (the error the per-step chain raises).
    CodegenError
        ``compiled=True`` without a working C compiler.

    Examples
    --------
    >>> import numpy as np
    >>> from switchobs.sensors import Encoder
    >>> t = np.linspace(0.0, 1.0, 1001)                      # free rolling at 20 m/s for 1 s
    >>> m = encoder_measurements(t, np.zeros(t.size), np.full(t.size, 20.0), np.zeros(1000),
    ...                          encoder=Encoder(ppr=60), radius_m=0.3)
    >>> m.events, round(float(np.nanmean(m.omega_measured)), 6)
    (636, 66.666667)
    """
    _check_chain(radius_m, rate_hz)
    tt, yy, vv, uu, hh, kept = _steps(t, x2, vx, u, dt)
    om, theta = _wheel(yy, vv, hh, float(radius_m))
    stamps, angles, edge_step, teeth = wheel_edges(encoder, tt, hh, om, theta)
    pressure = np.cumsum(np.concatenate([[0.0], uu * hh]))
    return measure_edges(tt, vv, pressure, stamps, angles, teeth, generated=edge_step, kept=kept, omega=om,
                         radius_m=radius_m, rate_hz=rate_hz, order=order, window=window, harmonics=harmonics,
                         notch_damping=notch_damping, compiled=compiled)


def _check_chain(radius_m: float, rate_hz: float) -> None:
    if not (isinstance(radius_m, (int, float)) and math.isfinite(radius_m) and radius_m > 0):
        raise SimulationError(f"radius_m must be finite and > 0, got {radius_m!r}")
    if not (isinstance(rate_hz, (int, float)) and math.isfinite(rate_hz) and rate_hz > 0):
        raise SimulationError(f"rate_hz must be finite and > 0, got {rate_hz!r}")


def measure_edges(tt: Array, vv: Array, pressure: Array, stamps: Array, angles: Array,
                  teeth: npt.NDArray[np.int_], *, radius_m: float, generated: npt.NDArray[np.int_] | None = None,
                  kept: npt.NDArray[np.int_] | None = None, omega: Array | None = None, rate_hz: float = 1000.0,
                  order: int = 2, window: int = 15, harmonics: int = 5, notch_damping: float = 0.5,
                  compiled: bool | None = None) -> EncoderMeasurements:
    """The chain of :func:`encoder_measurements` from the edges on: TSA, three-stage, notch at the samples.

    Parameters
    ----------
    tt, vv, pressure : ndarray
        Signal raster (strictly increasing) [s], vehicle speed there [m/s] and ``∫ u dt`` from the start
        [bar]; linear in between (the plant's step ends in a simulation, the samples of a log in a replay).
    stamps, angles, teeth : ndarray
        Edge time stamps (strictly increasing) [s], their angles [rad] and tooth counts.
    generated : ndarray of int, optional
        The raster index at which each edge became known (a simulated edge: the step that crossed it); without
        it, an edge is known at its time stamp.
    kept : ndarray of int, optional
        Index of each raster point in the caller's arrays (for ``sample_step``); default ``arange``.
    omega : ndarray, optional
        The wheel speed at the raster (``omega_steps``); NaN without it.
    radius_m, rate_hz, order, window, harmonics, notch_damping, compiled
        As :func:`encoder_measurements`.

    Raises
    ------
    SimulationError
        Bad settings, or two edges on one timer tick.
    """
    chain = EdgeChain(radius_m=radius_m, rate_hz=rate_hz, order=order, window=window, harmonics=harmonics,
                      notch_damping=notch_damping, compiled=compiled)
    vv, pressure = np.asarray(vv, dtype=float), np.asarray(pressure, dtype=float)
    chain.push_raster(tt, vv, pressure, done=True)
    chain.push_edges(stamps, angles, generated, done=True)
    out = chain.drain()
    kept = np.arange(tt.size) if kept is None else kept
    return EncoderMeasurements(
        **{name: out[name] for name in EncoderSamples.SIGNALS}, vx_measured=out["vx_measured"],
        pressure_measured=out["pressure_measured"], sample_step=kept[out["step"]], events=int(stamps.size),
        steps_t=tt, omega_steps=np.full(tt.size, np.nan) if omega is None else omega, vx_steps=vv,
        pressure_steps=pressure, edge_times=stamps, edge_teeth=np.asarray(teeth, dtype=np.int_))


#: The columns :meth:`EdgeChain.drain` hands back: the chain's signals, then what the observer's steps read.
CHAIN_COLUMNS = (*EncoderSamples.SIGNALS, "vx_measured", "pressure_measured", "step")


class EdgeChain:
    """The chain of :func:`measure_edges` fed in pieces: the raster and the edges pushed as they are read, the
    controller samples handed back as soon as the inputs decide them, the state carried across pieces.

    A sample at ``k / rate`` is decided once the raster reaches it (a point at or past it) and the edges
    do (one stamped after it, or the end of the edges).  The TSA fits each sample's own window; the
    three-stage estimator and the notch keep their state; the raster and the edges are kept back only as
    far as later samples can reach (the oldest edge of the next TSA window, the raster point before it), so
    the chain holds a few windows, not the log.  Every number equals that of the whole arrays at once (the
    same operations on the same values, each sample's only from its own inputs and the carried state):
    :func:`measure_edges` is this chain fed once.

    Parameters
    ----------
    radius_m, rate_hz, order, window, harmonics, notch_damping, compiled
        As :func:`encoder_measurements`.

    Raises
    ------
    SimulationError
        Bad settings.
    """

    def __init__(self, *, radius_m: float, rate_hz: float = 1000.0, order: int = 2, window: int = 15,
                 harmonics: int = 5, notch_damping: float = 0.5, compiled: bool | None = None) -> None:
        self._m, self._n = check_order_window(order, window)
        _check_chain(radius_m, rate_hz)
        self._rate, self._radius = float(rate_hz), float(radius_m)
        self._comp = ThreeStageEstimator(harmonics, dt_s=1.0 / self._rate, compiled=compiled)
        self._compiled = self._comp.compiled     # decided once (a compiler looked for), for the TSA and the notch
        self._notch = NotchFilter(dt_s=1.0 / self._rate, damping=notch_damping)
        empty = np.zeros(0)
        # the raster from its point r0 on, the edges from e0 on (global indices of the whole inputs)
        self._tt, self._vv, self._pp, self._r0 = empty, empty, empty, 0
        self._stamps, self._angles, self._e0 = empty, empty, 0
        self._gen: npt.NDArray[np.int_] | None = None
        self._raster_done = self._edges_done = False
        self._k: int | None = None      # the next controller sample, k / rate
        self._pushed = 0                # edges pushed by the last sample handed back
        self.edges = 0                  # edges received

    @staticmethod
    def _append(kept: Array, new: npt.ArrayLike, dtype: Any = float) -> Any:
        new = np.asarray(new, dtype=dtype)
        return new if kept.size == 0 else np.concatenate([kept, new])

    def push_raster(self, t: npt.ArrayLike, vx: npt.ArrayLike, pressure: npt.ArrayLike, *, done: bool = False
                    ) -> None:
        """The next points of the raster (time [s], speed [m/s], ``∫ u dt`` [bar]); ``done``: the last ones."""
        t = np.asarray(t, dtype=float)
        if self._k is None and t.size:
            self._k = math.floor(float(t[0]) * self._rate + 1e-9) + 1
        self._tt, self._vv, self._pp = (self._append(a, b) for a, b in ((self._tt, t), (self._vv, vx),
                                                                       (self._pp, pressure)))
        self._raster_done = self._raster_done or done

    def push_edges(self, stamps: npt.ArrayLike, angles: npt.ArrayLike,
                   generated: npt.ArrayLike | None = None, *, done: bool = False) -> None:
        """The next edges (time stamps [s], angles [rad], the raster index each became known at, if any);
        ``done``: the last ones."""
        stamps = np.asarray(stamps, dtype=float)
        self._stamps, self._angles = self._append(self._stamps, stamps), self._append(self._angles, angles)
        if generated is not None:
            self._gen = self._append(np.zeros(0, dtype=np.int_) if self._gen is None else self._gen, generated,
                                     np.int_)
        self.edges += int(stamps.size)
        self._edges_done = self._edges_done or done

    def _ready(self) -> Array:
        """The times of the samples the inputs pushed so far decide."""
        tt, first = self._tt, max(self._r0, 1)
        if self._k is None or self._r0 + tt.size < 2:
            return np.zeros(0)
        reach = float(tt[-1]) + 1e-12
        ts = np.arange(self._k, max(self._k, math.floor(reach * self._rate) + 2), dtype=float) / self._rate
        ts = ts[ts <= reach]
        if not self._edges_done:   # a sample's edges are known once one is stamped after it
            ts = ts[:np.searchsorted(ts, self._stamps[-1], side="left")] if self._stamps.size else ts[:0]
        if self._gen is not None and not self._edges_done and ts.size:
            step = first + np.searchsorted(tt[first - self._r0:] + 1e-12, ts, side="left")
            ts = ts[:np.searchsorted(step, self._gen[-1], side="left")] if self._gen.size else ts[:0]
        return ts

    def drain(self) -> dict[str, npt.NDArray[Any]]:
        """The samples decided by the inputs pushed so far (:data:`CHAIN_COLUMNS`: the signals of
        :class:`EncoderSamples`, ``vx_measured``, ``pressure_measured`` and ``step``, the global raster index
        of the point that reaches each).

        Raises
        ------
        SimulationError
            Two edges on one timer tick.
        """
        n, rate, radius = self._n, self._rate, self._radius
        ts = self._ready()
        tt, vv, pressure, stamps, r0, e0 = self._tt, self._vv, self._pp, self._stamps, self._r0, self._e0
        first = max(r0, 1)
        # each sample processed by the first raster point that reaches it (global index); the point before it
        # is the last at or before the sample (reach = t + 1e-12 >= t), the start of its interval
        step = first + np.searchsorted(tt[first - r0:] + 1e-12, ts, side="left")
        # edges pushed by each sample: those generated by then, up to the first stamped after it
        pushed = e0 + np.searchsorted(stamps, ts, side="right")
        if self._gen is not None:
            pushed = np.minimum(e0 + np.searchsorted(self._gen, step, side="right"), pushed)
        if pushed.size:
            seen = max(self._pushed - 1 - e0, 0)
            clash = np.flatnonzero(np.diff(stamps[seen:int(pushed[-1]) - e0]) <= 0.0)
            if clash.size:
                i = seen + int(clash[0])
                raise SimulationError(f"event time stamps must be strictly increasing: {float(stamps[i + 1])!r} "
                                      f"after {float(stamps[i])!r}")

        def history(tq: Array, i: npt.NDArray[np.int_]) -> tuple[Array, Array, Array]:
            # EncoderLoopEstimator._history at tq in the raster's interval i (local index of the kept raster)
            span = tt[i + 1] - tt[i]
            w = (tq - tt[i]) / span
            dv = vv[i + 1] - vv[i]
            return vv[i] + w * dv, pressure[i] + w * (pressure[i + 1] - pressure[i]), dv / span

        # every window of a sample still to come starts at or after pushed - n of the last sample: the kept
        # edges' local indices hold each window whole
        fits = fit_windows(stamps, self._angles, pushed - e0 - 1, ts, self._m, n, compiled=self._compiled)
        ok = np.flatnonzero(pushed >= n)
        tc = fits[3]                          # the window's mean time stamp, as window_mean sums it
        th_m, om_m, al_m = fits[0, ok], fits[1, ok], fits[2, ok]
        om_c, al_c = self._comp.run(th_m, om_m, al_m)
        notched = self._notch.run(al_m, om_m, compiled=self._compiled)
        # the interval of each measurement's time, of the steps recorded by its sample
        before = step - r0 - 1
        vx_c, p_c, ax_c = history(tc[ok], np.minimum(np.maximum(np.searchsorted(tt, tc[ok], side="right") - 1, 0),
                                                     before[ok]))

        def at_samples(values: Array) -> Array:
            out = np.full(ts.size, np.nan)
            out[ok] = values
            return out

        out = {"t": ts, "t_measured": tc, "x2_tsa": at_samples(radius * al_m - ax_c),
               "x2_notch": at_samples(radius * notched - ax_c), "x2_measured": at_samples(radius * al_c - ax_c),
               "omega_tsa": at_samples(om_m), "omega_measured": at_samples(om_c), "vx": history(ts, before)[0],
               "vx_measured": at_samples(vx_c), "pressure_measured": at_samples(p_c), "step": step}
        if ts.size:
            assert self._k is not None
            self._k += ts.size
            self._pushed = int(pushed[-1])
            self._trim(float(ts[-1]) + 1.0 / rate)
        return out

    def _trim(self, t_next: float) -> None:
        """Keep what samples from ``t_next`` on can reach: the edges from the oldest of the next window, the
        raster from the point before the earlier of that edge and ``t_next`` (copies: the pieces pushed are
        let go)."""
        e_keep = max(self._pushed - self._n, 0)
        drop = e_keep - self._e0
        if drop > 0:
            self._stamps, self._angles = self._stamps[drop:].copy(), self._angles[drop:].copy()
            if self._gen is not None:
                self._gen = self._gen[drop:].copy()
            self._e0 = e_keep
        oldest = min(float(self._stamps[0]), t_next) if self._stamps.size else t_next
        drop = max(int(np.searchsorted(self._tt, oldest, side="right")) - 2, 0)
        if drop > 0:
            self._tt, self._vv, self._pp = (a[drop:].copy() for a in (self._tt, self._vv, self._pp))
            self._r0 += drop
