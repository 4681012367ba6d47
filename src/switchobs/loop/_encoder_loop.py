"""The wheel-encoder chain inside the ABS loop, as a :class:`switchobs.plants.XbsEstimator`.

:func:`switchobs.plants.simulate` hands its estimator the plant's signals
``(t, x2, vx, u, dt)`` after every integration step, not the wheel angle.  The
angle is recovered from them: with ``x2 = R dω/dt - a_x`` and ``a_x = dvx/dt``
(seed 001 eq. (2.1)-(2.2)),

    R ω(t) = R ω(t - dt) + (vx(t) - vx(t - dt)) + ∫ x2 dt,

the integral by the trapezoidal rule (``x2`` is continuous: the pressure and the
tyre characteristic are), and ``θ`` by integrating ``ω`` linearly over the step,
from free rolling, ``ω(0) = vx(0) / R`` (the initial state of ``simulate``).
The simulation records the true ``ω``; :attr:`EncoderLoopRecord.omega_steps`
keeps the reconstruction so that the two can be compared after the run.

From that angle the encoder's edges are generated as the wheel turns (the
transition locations of :meth:`switchobs.sensors.Encoder.rotation_angles`, time
stamps floored to the capture timer), pushed into the streaming
:class:`~switchobs.sensors.TimeStamper` and, at each controller sample,
compensated by :class:`~switchobs.sensors.ThreeStageEstimator` (seed 001
Fig. 6.2).  The measured ``x2 = R α̂ - a_x`` drives the XBS observers.

Measurement time line.  A TSA estimate of order 2 fits one acceleration to the
last ``n`` edges: it describes the wheel at the centre of the window, about
half the window (10-30 ms in ABS braking) before the sample.  Feeding it to the
observer together with the *current* pressure rate would misalign the
observer's input and output by that lag, and the observer would explain the
mismatch by a wrong XBS.  So the observers advance in the measurement's time
line: from one window centre ``t_c`` (the mean time stamp of the window) to
the next, with ``u`` and ``vx`` averaged over the same interval from the
history of the plant signals.  Their estimate is then the XBS at ``t_c``, and
that delayed estimate is what the controller reads (seed 001 Fig. 4.6, output
feedback).
"""

from __future__ import annotations

import bisect
import math
from collections import deque
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from ..exceptions import SimulationError
from ..plants import Replay, replay_updates
from ..sensors import Encoder, NotchFilter, ThreeStageEstimator, TimeStamper
from ._adapter import ObserverXbsEstimator, SteppingObserver, check_xbs_signals, initial_xbs_state
from ._encoder_batch import EncoderMeasurements, EncoderSamples, _floats, encoder_measurements, fixed_edges
from ._stepping import step_through

__all__ = ["EncoderLoopEstimator", "EncoderLoopRecord", "EncoderX2", "X2_MEASUREMENTS"]

#: What :class:`EncoderX2` hands the controller: raw TSA, TSA + notch, TSA + three-stage (seed 001 Figs. 6.7-6.9).
X2_MEASUREMENTS: tuple[str, ...] = ("tsa", "notch", "three-stage")

Array = npt.NDArray[np.float64]

@dataclass(frozen=True, eq=False)
class EncoderLoopRecord(EncoderSamples):
    """What the encoder chain and the observers saw: an :class:`EncoderSamples` with the observers' estimates.

    Attributes
    ----------
    t, t_measured, x2_tsa, x2_notch, x2_measured, omega_tsa, omega_measured, vx : ndarray
        Of :class:`EncoderSamples` (NaN until the TSA window is full).
    estimates : dict of str -> ndarray
        XBS estimate of each encoder-fed observer at the samples (NaN before the first measurement).
    events : int
        Encoder edges generated.
    steps_t : ndarray
        Plant step ends.
    omega_steps : ndarray
        Reconstructed wheel speed at ``steps_t`` (compare with the simulated ``omega``).
    beside : dict of str -> ndarray
        Estimates at ``steps_t`` of the observers fed with the plant's exact ``x2``.
    """

    estimates: dict[str, Array]
    events: int
    steps_t: Array
    omega_steps: Array
    beside: dict[str, Array]

    def to_json(self) -> dict[str, Any]:
        """Arrays as lists (NaN as None)."""
        return {**super().to_json(), "estimates": {k: _floats(v) for k, v in self.estimates.items()},
                "events": self.events, "steps_t": _floats(self.steps_t), "omega_steps": _floats(self.omega_steps),
                "beside": {k: _floats(v) for k, v in self.beside.items()}}

    def __str__(self) -> str:
        ok = np.isfinite(self.t_measured)
        lag = f"{1e3 * float(np.mean(self.lag_s[ok])):.1f} ms" if np.any(ok) else "n/a"
        return (f"encoder loop: {self.t.size} samples, {self.events} edges, mean measurement lag {lag}, "
                f"observers {', '.join(self.estimates)}" + (f"; beside {', '.join(self.beside)}" if self.beside else ""))


def window_mean(stamps: Iterable[float]) -> float:
    """Mean of the TSA window's time stamps, summed left to right (:func:`encoder_measurements` sums alike)."""
    total, count = 0.0, 0
    for s in stamps:
        total += s
        count += 1
    return total / count


class EncoderLoopEstimator:
    """XBS observers fed by a simulated wheel encoder with three-stage compensation, inside the ABS loop.

    Parameters
    ----------
    observers : sequence of (label, observer, initial_state)
        Observers with signals ``(y, vx, u)`` and a readout (the XBS): Python
        reference observers or compiled C observers (:class:`switchobs.codegen.CObserver`).
        The first one's estimate is returned to the controller; the others run beside it on
        the same measurements.  Empty: the chain only measures (:class:`EncoderX2`).  ``initial_state`` maps state names to initial values; the first
        state (the measured ``z1``) starts at the first measurement.  Each interval between two
        measurements is ONE observer step: the observer's own step method and step bound decide
        whether that is safe (``radau3`` and ``midpoint`` are certified for every step length,
        ``switchobs certify --discrete``; an ``rk4`` observer needs ``h_max``).
    encoder : Encoder
    radius_m : float
        Wheel radius ``R`` [m].
    rate_hz : float
        Controller rate of the TSA and the three-stage estimator.
    order, window, harmonics : int
        TSA order ``m`` and window ``n`` (seed 001 (5.2)-(5.5)), harmonics ``M`` of (6.2).
    initial_xbs : float
        Estimate returned before the first measurement (and always, without observers).
    notch_damping : float
        Damping ratio of the notch baseline (seed 001 Sec. 6.3: 0.5).
    beside : sequence of (label, ObserverXbsEstimator)
        Observers stepped with the plant's exact signals, for comparison.
    compiled : bool or None
        Run the three-stage estimator's C kernel (see :class:`switchobs.sensors.ThreeStageEstimator`).

    Raises
    ------
    SimulationError
        Bad settings or no observer.
    ModelError
        An observer whose signals are not ``(y, vx, u)``.
    """

    def __init__(self, observers: Sequence[tuple[str, SteppingObserver, dict[str, float]]], *,
                 encoder: Encoder, radius_m: float, rate_hz: float = 1000.0,
                 order: int = 2, window: int = 15, harmonics: int = 5, initial_xbs: float = 0.5,
                 notch_damping: float = 0.5, beside: Sequence[tuple[str, ObserverXbsEstimator]] = (),
                 compiled: bool | None = None):
        for label, obs, _ in observers:
            check_xbs_signals(obs, f"the encoder loop's observer {label!r}")
        for name, value in (("rate_hz", rate_hz), ("radius_m", radius_m)):
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise SimulationError(f"{name} must be finite and > 0, got {value!r}")
        self._observers = list(observers)
        self._beside = list(beside)
        self._encoder = encoder
        self._R = float(radius_m)
        self._rate = float(rate_hz)
        self._order, self._window, self._harmonics = order, window, harmonics
        self._initial_xbs = float(initial_xbs)
        self._damping = notch_damping
        self._compiled = compiled
        self._base = fixed_edges(encoder)
        self._nominal = encoder.nominal_angles()
        # validate the chain settings now rather than at the first sample
        TimeStamper(order=order, window=window, compiled=compiled)
        ThreeStageEstimator(harmonics, dt_s=1.0 / rate_hz, compiled=compiled)
        NotchFilter(dt_s=1.0 / rate_hz, damping=notch_damping)

    def describe(self) -> str:
        first = str(self._observers[0][1]).splitlines()[0] if self._observers else "no observer"
        return (f"{first} on x2 from a {self._encoder.ppr}-ppr encoder (TSA n = {self._window}, "
                f"three-stage M = {self._harmonics}, {self._rate:g} Hz)")

    # ------------------------------------------------------------------ XbsEstimator protocol
    def reset(self, t0: float, y0: float, vx0: float) -> None:
        """Start at free rolling (``ω = vx / R``, ``θ = 0``), as :func:`switchobs.plants.simulate` does."""
        self._t, self._x2, self._vx = float(t0), float(y0), float(vx0)
        self._omega = self._vx / self._R
        self._theta = 0.0
        self._U = 0.0                                  # ∫ u dt since t0: the pressure change [bar]
        self._rev, self._edge = 0, 0
        while self._level() <= 0.0:
            self._next_edge()
        self._pending: deque[tuple[float, float]] = deque()
        self._stamps: deque[float] = deque(maxlen=self._window)
        self._tsa = TimeStamper(order=self._order, window=self._window, compiled=self._compiled)
        self._comp = ThreeStageEstimator(self._harmonics, dt_s=1.0 / self._rate, compiled=self._compiled)
        self._notch = NotchFilter(dt_s=1.0 / self._rate, damping=self._damping)
        #: the latest measured x2 of each kind of X2_MEASUREMENTS (0, free rolling, before the first)
        self.latest_x2 = dict.fromkeys(X2_MEASUREMENTS, 0.0)
        self._k = math.floor(t0 * self._rate + 1e-9) + 1          # next controller sample
        self._hist_t, self._hist_vx, self._hist_U = [self._t], [self._vx], [0.0]
        self._last: tuple[float, float, float, float] | None = None   # (t_c, y, vx, ∫u) of the last measurement
        self._states: list[Any] = [None] * len(self._observers)
        self._estimate = self._initial_xbs
        self._events = 0
        self._rows: list[tuple[float, ...]] | Array = []                # arrays after replay()
        self._omega_steps: list[float] | Array = [self._omega]
        self._beside_rows: list[list[float]] | Array = []
        for _, est in self._beside:
            est.reset(t0, y0, vx0)
        self._beside_rows.append([est.estimate for _, est in self._beside])
        #: the batch chain's measurements of the run, kept by :meth:`replay` (with the edges and the signals it
        #: read: what a log of the run carries, :func:`switchobs.loop.replay`); None after the per-step loop
        self.measurements: EncoderMeasurements | None = None

    def update(self, t: float, y: float, vx: float, u: float, dt: float) -> float:
        """Advance the wheel over ``[t - dt, t]``, process the controller samples in it, return the estimate."""
        if dt <= 0.0:
            return self._estimate
        t0, x20, om0, th0 = self._t, self._x2, self._omega, self._theta
        om1 = max(om0 + ((vx - self._vx) + 0.5 * (x20 + y) * dt) / self._R, 0.0)   # the plant clamps ω >= 0 too
        th1 = th0 + 0.5 * (om0 + om1) * dt
        self._edges(t0, dt, om0, om1, th0, th1)
        self._t, self._x2, self._vx, self._omega, self._theta = float(t), float(y), float(vx), om1, th1
        self._U += u * dt
        self._hist_t.append(self._t)
        self._hist_vx.append(self._vx)
        self._hist_U.append(self._U)
        while (ts := self._k / self._rate) <= t + 1e-12:
            self._sample(ts)
            self._k += 1
        self._omega_steps.append(om1)
        self._beside_rows.append([est.update(t, y, vx, u, dt) for _, est in self._beside])
        return self._estimate

    # ------------------------------------------------------------------ internals
    def _level(self) -> float:
        return float(self._base[self._edge]) + 2.0 * math.pi * self._rev

    def _next_edge(self) -> None:
        self._edge += 1
        if self._edge == self._base.size:
            self._edge, self._rev = 0, self._rev + 1

    def _edges(self, t0: float, h: float, om0: float, om1: float, th0: float, th1: float) -> None:
        """Edges crossed while θ goes from th0 to th1, ω linear in time over the step."""
        k = 0.5 * (om1 - om0) / h
        clock = self._encoder.clock_hz
        while (level := self._level()) <= th1:
            d = level - th0
            # root of th0 + om0 τ + k τ² = level, in the form without cancellation
            root = om0 + math.sqrt(max(om0 * om0 + 4.0 * k * d, 0.0))
            tau = min(2.0 * d / root, h) if root > 0.0 else h
            stamp = t0 + tau
            if clock is not None:
                stamp = math.floor(stamp * clock) / clock
            self._pending.append((stamp, float(self._nominal[self._edge]) + 2.0 * math.pi * self._rev))
            self._events += 1
            self._next_edge()

    def _history(self, tq: float) -> tuple[float, float, float]:
        """``(vx, ∫u, a_x)`` at ``tq`` from the plant's step ends (linear within a step)."""
        ht = self._hist_t
        i = min(max(bisect.bisect_right(ht, tq) - 1, 0), len(ht) - 2)
        span = ht[i + 1] - ht[i]
        w = (tq - ht[i]) / span
        vx = self._hist_vx[i] + w * (self._hist_vx[i + 1] - self._hist_vx[i])
        U = self._hist_U[i] + w * (self._hist_U[i + 1] - self._hist_U[i])
        return vx, U, (self._hist_vx[i + 1] - self._hist_vx[i]) / span

    def _sample(self, ts: float) -> None:
        while self._pending and self._pending[0][0] <= ts:
            stamp, angle = self._pending.popleft()
            self._tsa.push(stamp, angle)
            self._stamps.append(stamp)
        vx_s = self._history(ts)[0]
        th_m, om_m, al_m = self._tsa.estimate(ts)
        if math.isnan(om_m):
            self._rows.append((ts, math.nan, math.nan, math.nan, math.nan, math.nan, math.nan, vx_s,
                               *(math.nan for _ in self._observers)))
            return
        om_c, al_c = self._comp.update(th_m, om_m, al_m)
        tc = window_mean(self._stamps)
        vx_c, U_c, ax_c = self._history(tc)
        y_meas = self._R * al_c - ax_c
        x2_tsa, x2_notch = self._R * al_m - ax_c, self._R * self._notch.update(al_m, om_m) - ax_c
        self.latest_x2 = {"tsa": x2_tsa, "notch": x2_notch, "three-stage": y_meas}
        if self._last is None:
            self._states = [initial_xbs_state(obs, y_meas, init) for _, obs, init in self._observers]
            self._last = (tc, y_meas, vx_c, U_c)
        elif tc > self._last[0]:
            # held over [t_c_prev, t_c]: the mean of the bounding measurements (as ObserverXbsEstimator
            # does), vx likewise, and u the interval's mean pressure rate, so that ∫u is exact
            tc0, y0, vx0, U0 = self._last
            span = tc - tc0
            y_hold, vx_hold, u_mean = 0.5 * (y0 + y_meas), 0.5 * (vx0 + vx_c), (U_c - U0) / span
            for i, (_, obs, _) in enumerate(self._observers):
                self._states[i] = obs.step(self._states[i], (y_hold, vx_hold, u_mean), span)
            self._last = (tc, y_meas, vx_c, U_c)
        estimates = [float(obs.readout(self._states[i])) for i, (_, obs, _) in enumerate(self._observers)]
        if estimates:
            self._estimate = estimates[0]
        self._rows.append((ts, tc, x2_tsa, x2_notch, y_meas, om_m, om_c, vx_s, *estimates))

    def record(self) -> EncoderLoopRecord:
        """What happened so far (call after the simulation)."""
        data = np.array(self._rows, dtype=float).reshape(-1, 8 + len(self._observers))
        beside = np.array(self._beside_rows, dtype=float).reshape(len(self._beside_rows), len(self._beside))
        return EncoderLoopRecord(
            t=data[:, 0], t_measured=data[:, 1], x2_tsa=data[:, 2], x2_notch=data[:, 3], x2_measured=data[:, 4],
            omega_tsa=data[:, 5], omega_measured=data[:, 6], vx=data[:, 7],
            estimates={label: data[:, 8 + i] for i, (label, _, _) in enumerate(self._observers)},
            events=self._events, steps_t=np.array(self._hist_t), omega_steps=np.array(self._omega_steps),
            beside={label: beside[:, i] for i, (label, _) in enumerate(self._beside)})


    # ------------------------------------------------------------------ ReplayEstimator protocol
    def replay(self, t: Array, y: Array, vx: Array, u: Array, dt: Array) -> Replay:
        """The run :func:`switchobs.plants.replay_updates` gives, the measurements first, the observers after.

        When the controller does not read the estimate, :func:`switchobs.plants.simulate` records the
        plant's run and hands it here whole (:class:`switchobs.plants.ReplayEstimator`).  The encoder chain
        measures over it (:meth:`_measure`); then each observer steps from measurement to measurement as
        :meth:`_sample` steps it, and the estimate after each plant step is that of the last measurement
        taken by then.  Estimates, refusals and :meth:`record` are those of the interleaved run, bit for
        bit; the estimator is left as after the run (:meth:`record`, no further :meth:`update`).  With
        observers beside (on the exact signals), a refused observer step or an error of the chain, the
        interleaved :func:`~switchobs.plants.replay_updates` runs instead.
        """
        if self._beside or not self._observers:
            return replay_updates(self, t, y, vx, u, dt)
        try:
            m = self._measure(t, y, vx, u, dt)
            ok = np.flatnonzero(np.isfinite(m.t_measured))
            stepped = [_observe(obs, init, m.t_measured[ok], m.x2_measured[ok], m.vx_measured[ok],
                                m.pressure_measured[ok]) for _, obs, init in self._observers]
        except SimulationError:
            return replay_updates(self, t, y, vx, u, dt)
        self.measurements = m
        columns = (m.t, m.t_measured, m.x2_tsa, m.x2_notch, m.x2_measured, m.omega_tsa, m.omega_measured, m.vx)
        estimates = np.full((m.t.size, len(self._observers)), np.nan)
        for k, (states, _) in enumerate(stepped):
            estimates[ok, k] = np.asarray(self._observers[k][1].readout(states), dtype=float)
        # what the interleaved run leaves for record(), as arrays (record() reads lists and arrays alike): as
        # lists they were a tuple per sample and a list per plant step, whose allocation set off the garbage
        # collector, which walks every object of the process (a third of a sweep case, more on a Dask worker)
        self._rows = np.column_stack([*columns, estimates])
        self._events, self._hist_t, self._omega_steps = m.events, m.steps_t.copy(), m.omega_steps.copy()
        self._beside_rows = np.empty((m.steps_t.size, 0))
        self._states = [states[-1] if len(states) else None for states, _ in stepped]
        self._last = stepped[0][1]
        if ok.size:
            j = ok[-1]
            self.latest_x2 = {"tsa": float(m.x2_tsa[j]), "notch": float(m.x2_notch[j]),
                              "three-stage": float(m.x2_measured[j])}
            self._estimate = float(estimates[j, 0])
        # the estimate after each plant step: that of the last measurement taken by then
        last = np.maximum.accumulate(np.where(np.isfinite(m.t_measured), np.arange(m.t.size), -1))
        upto = np.searchsorted(m.t, np.asarray(t, dtype=float) + 1e-12, side="right")
        at = np.where(upto > 0, last[np.maximum(upto - 1, 0)], -1) if m.t.size else np.full(upto.size, -1)
        hat = np.where(at >= 0, estimates[np.maximum(at, 0), 0] if m.t.size else 0.0, self._initial_xbs)
        hat[0] = math.nan
        return hat, None, ""

    def _measure(self, t: Array, y: Array, vx: Array, u: Array, dt: Array) -> EncoderMeasurements:
        """The chain alone over the run (:func:`encoder_measurements`; ``u`` and ``dt`` as
        :func:`~switchobs.plants.replay_updates` hands them, one per entry of ``t``, the first unused)."""
        return encoder_measurements(t, y, vx, np.asarray(u, dtype=float)[1:], np.asarray(dt, dtype=float)[1:],
                                    encoder=self._encoder, radius_m=self._R, rate_hz=self._rate,
                                    order=self._order, window=self._window, harmonics=self._harmonics,
                                    notch_damping=self._damping, compiled=self._compiled)


def _observe(obs: SteppingObserver, init: dict[str, float], tc: Array, y: Array, vx: Array, U: Array
             ) -> tuple[Array, tuple[float, float, float, float] | None]:
    """One observer over the measurements ``(t_c, y, vx, ∫u)`` as :meth:`EncoderLoopEstimator._sample` steps it:
    its state at each measurement and the last measurement it stepped to.

    The first measurement starts the state; a later one is stepped to when its ``t_c`` is past the last
    one stepped to (the largest so far), with the held signals of :meth:`_sample`.
    """
    if tc.size == 0:
        return np.empty((0, len(obs.state_names))), None
    later = np.zeros(tc.size, dtype=bool)
    later[1:] = tc[1:] > np.maximum.accumulate(tc)[:-1]
    to = np.flatnonzero(later)
    start = np.concatenate([[0], to[:-1]]).astype(int)
    span = tc[to] - tc[start]
    rows = np.column_stack([0.5 * (y[start] + y[to]), 0.5 * (vx[start] + vx[to]), (U[to] - U[start]) / span])
    x0 = initial_xbs_state(obs, float(y[0]), init)
    states = np.vstack([x0, step_through(obs, x0, rows, span)])[np.cumsum(later)]
    j = int(to[-1]) if to.size else 0
    return states, (float(tc[j]), float(y[j]), float(vx[j]), float(U[j]))


class EncoderX2:
    """The encoder chain's measured ``x2`` as the brake controller's input (seed 001 Sec. 6.4, Figs. 6.7-6.9).

    A :class:`switchobs.plants.X2Measurement`: pass it as ``simulate(..., x2_source=EncoderX2(...))``
    and the five-phase thresholds switch on ``x2 = R α̂ - a_x`` computed at each controller sample
    from the encoder's edges, as :class:`EncoderLoopEstimator` generates them, instead of on the exact
    ``x2``.  ``a_x`` is the plant's (the seed's accelerometer is not the subject there).

    Parameters
    ----------
    measurement : {"tsa", "notch", "three-stage"}
        Raw TSA (Fig. 6.7), TSA through the notch centred on ``ω_m`` (Fig. 6.8), TSA with the
        three-stage compensation (Fig. 6.9).
    encoder, radius_m, rate_hz, order, window, harmonics, notch_damping
        As :class:`EncoderLoopEstimator`; the defaults are seed 001 Sec. 6.4's TSA (``m = 2``,
        ``n = 12``, ``M = 6``) at 1 kHz.
    cruise_s : float
        The chain runs this long at the initial speed, wheel free rolling, before the braking
        starts (a car cruises before its driver brakes): the TSA window is full and the
        three-stage parameters and the notch have settled when the controller first reads them
        (seed 001 Sec. 6.3: "once the estimated parameters have converged").  0: from cold.

    Raises
    ------
    SimulationError
        An unknown measurement or bad chain settings.
    """

    def __init__(self, measurement: str = "three-stage", *, encoder: Encoder, radius_m: float,
                 rate_hz: float = 1000.0, order: int = 2, window: int = 12, harmonics: int = 6,
                 notch_damping: float = 0.5, cruise_s: float = 2.0):
        if measurement not in X2_MEASUREMENTS:
            raise SimulationError(f"unknown x2 measurement {measurement!r}; use one of {', '.join(X2_MEASUREMENTS)}")
        if not (isinstance(cruise_s, (int, float)) and math.isfinite(cruise_s) and cruise_s >= 0):
            raise SimulationError(f"cruise_s must be finite and >= 0, got {cruise_s!r}")
        self.measurement = measurement
        self.cruise_s = float(cruise_s)
        self._dt = 1.0 / rate_hz
        self.encoder = encoder
        self.chain = EncoderLoopEstimator((), encoder=encoder, radius_m=radius_m, rate_hz=rate_hz, order=order,
                                          window=window, harmonics=harmonics, notch_damping=notch_damping)

    def reset(self, t0: float, y0: float, vx0: float) -> None:
        """Start the chain ``cruise_s`` before ``t0`` and run it at constant speed, free rolling, up to ``t0``."""
        steps = round(self.cruise_s / self._dt)
        self.chain.reset(t0 - steps * self._dt, 0.0, vx0)
        for k in range(steps - 1, -1, -1):
            self.chain.update(t0 - k * self._dt, 0.0, vx0, 0.0, self._dt)

    def update(self, t: float, y: float, vx: float, u: float, dt: float) -> float:
        self.chain.update(t, y, vx, u, dt)
        return self.chain.latest_x2[self.measurement]

    def record(self) -> EncoderLoopRecord:
        """The chain's record of the run (call after the simulation)."""
        return self.chain.record()

    def __str__(self) -> str:
        return f"x2 from a {self.encoder.ppr}-ppr encoder, {self.measurement}"
