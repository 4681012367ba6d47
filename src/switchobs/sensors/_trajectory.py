"""Continuous wheel-angle trajectories theta(t) and their exact level-crossing times.

The encoder model needs the instants at which the wheel angle crosses each
tooth edge.  They are found by root finding on the continuous trajectory
(closed form or piecewise-polynomial interpolant), never by sampling, so the
only time error left in the simulated events is the one the timer clock adds
on purpose.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from ..exceptions import SimulationError
from ._validate import as_signal, check_increasing, check_positive

__all__ = ["AngleTrajectory", "constant_speed", "varying_speed", "trapezoid_speed", "rpm_to_rad_s", "MAX_RPM",
           "MAX_DURATION_S"]

Array = npt.NDArray[np.float64]
Signal = Callable[[Array], Array]

_EPS = np.finfo(float).eps
#: Highest wheel speed of the built-in profiles: a car wheel at 300 km/h turns at about 2700 rpm, a motor
#: test rig at a few 10 000 rpm.
MAX_RPM = 30_000.0
#: Longest built-in profile (its root-finding grid has a point every 10 ms).
MAX_DURATION_S = 3600.0


def rpm_to_rad_s(rpm: float) -> float:
    """Revolutions per minute to rad/s (1020 rpm is about 106.8 rad/s, seed 001 Fig. 5.4)."""
    return float(rpm) * 2.0 * math.pi / 60.0


@dataclass(frozen=True, eq=False)
class AngleTrajectory:
    """A non-reversing wheel angle ``theta(t)`` with ``omega = dtheta/dt`` and ``alpha = domega/dt``.

    Attributes
    ----------
    theta, omega, alpha : callable
        Vectorised functions of time (s) returning rad, rad/s, rad/s^2.
    t_start, t_end : float
        Time interval (s) on which the functions are defined.
    grid : ndarray
        Increasing times, ``grid[0] = t_start``, ``grid[-1] = t_end``, on which
        ``theta`` is non-decreasing; each grid cell brackets the crossings inside it.
    accel_x : callable or None
        Vehicle longitudinal acceleration ``a_x(t)`` (m/s^2), needed for the
        wheel acceleration offset ``x2 = R alpha - a_x`` (seed 001, (2.2)).
    radius_m : float or None
        Effective wheel radius ``R`` (m).
    name : str
        Label used in reports.
    """

    theta: Signal
    omega: Signal
    alpha: Signal
    t_start: float
    t_end: float
    grid: Array = field(repr=False)
    accel_x: Signal | None = None
    radius_m: float | None = None
    name: str = "trajectory"

    @property
    def duration_s(self) -> float:
        return self.t_end - self.t_start

    def crossing_times(self, levels: npt.ArrayLike) -> Array:
        """Exact instants at which ``theta(t)`` first reaches each of ``levels``.

        Each level is bracketed by a grid cell, then located by a vectorised
        safeguarded Newton iteration (Newton steps, bisection whenever a step
        leaves the bracket) until the step is at rounding level.

        Parameters
        ----------
        levels : array_like
            Angles (rad) inside ``(theta(t_start), theta(t_end)]``.

        Returns
        -------
        ndarray
            Crossing times (s), same shape as ``levels``.

        Raises
        ------
        SimulationError
            If ``theta`` decreases on the grid (the encoder model needs a
            wheel that does not turn backwards) or a level is out of range.
        """
        lv = np.asarray(levels, dtype=float)
        th = self.theta(self.grid)
        drop = np.flatnonzero(np.diff(th) < 0.0)
        if drop.size:
            i = int(drop[0])
            raise SimulationError(
                f"the wheel angle of {self.name!r} decreases between t={self.grid[i]:.6g} s and "
                f"t={self.grid[i + 1]:.6g} s; the encoder model needs omega >= 0 (no reversal)")
        if lv.size == 0:
            return lv.copy()
        if np.any(lv <= th[0]) or np.any(lv > th[-1]):
            raise SimulationError(
                f"crossing levels must lie in ({th[0]:.6g}, {th[-1]:.6g}] rad, got "
                f"[{lv.min():.6g}, {lv.max():.6g}]")
        j = np.clip(np.searchsorted(th, lv, side="left") - 1, 0, th.size - 2)
        lo, hi = self.grid[j].copy(), self.grid[j + 1].copy()
        span = th[j + 1] - th[j]
        x = lo + (hi - lo) * np.where(span > 0, (lv - th[j]) / np.where(span > 0, span, 1.0), 1.0)
        for _ in range(200):
            f = self.theta(x) - lv
            below = f < 0.0
            lo = np.where(below, x, lo)
            hi = np.where(below, hi, x)
            d = self.omega(x)
            with np.errstate(divide="ignore", invalid="ignore"):
                step = np.where(d > 0.0, f / d, np.inf)
            tol = 4.0 * _EPS * np.maximum(np.abs(x), 1e-300)
            converged = (np.abs(step) <= tol) | (hi - lo <= tol)
            xn = x - step
            outside = ~((xn > lo) & (xn < hi))
            x = np.where(converged, x, np.where(outside, 0.5 * (lo + hi), xn))
            if np.all(converged):
                break
        return x

    @classmethod
    def from_samples(
        cls,
        t: npt.ArrayLike,
        *,
        theta: npt.ArrayLike | None = None,
        omega: npt.ArrayLike | None = None,
        alpha: npt.ArrayLike | None = None,
        accel_x: npt.ArrayLike | Signal | None = None,
        radius_m: float | None = None,
        theta0: float = 0.0,
        name: str = "samples",
    ) -> AngleTrajectory:
        """Interpolate a sampled plant trajectory into a continuous one.

        Parameters
        ----------
        t : array_like
            Strictly increasing sample times (s).
        theta, omega, alpha : array_like, optional
            Wheel angle (rad), speed (rad/s), acceleration (rad/s^2) at ``t``.
            With ``theta`` the angle is interpolated by a Hermite polynomial using
            every derivative given (quintic with ``omega`` and ``alpha``, cubic with
            ``omega``, monotone PCHIP alone).  Without ``theta`` the speed is
            interpolated (Hermite with ``alpha``, else a cubic spline) and the angle
            is its exact antiderivative, starting at ``theta0``.
        accel_x : array_like or callable, optional
            Vehicle acceleration (m/s^2) at ``t`` (linear interpolation) or a function of time.
        radius_m : float, optional
            Effective wheel radius (m).
        theta0 : float
            Initial angle when only ``omega`` is given.
        name : str
            Label used in messages and reports.

        Raises
        ------
        SimulationError
            Missing angle and speed, non-increasing times, NaN samples or length mismatch.
        """
        tt = as_signal(t, "t")
        if tt.size < 2:
            raise SimulationError(f"a trajectory needs at least 2 samples, got {tt.size}")
        check_increasing(tt, "t")
        sig = {k: (None if v is None else as_signal(v, k, length=tt.size))
               for k, v in (("theta", theta), ("omega", omega), ("alpha", alpha))}
        if sig["theta"] is None and sig["omega"] is None:
            raise SimulationError("from_samples needs theta or omega (or both)")
        # scipy is imported where it is used, so that the command line's --help and errors never load it
        from scipy.interpolate import BPoly, CubicHermiteSpline, CubicSpline, PchipInterpolator

        if sig["theta"] is not None:
            derivs = [d for d in (sig["theta"], sig["omega"], sig["alpha"]) if d is not None]
            if sig["omega"] is None:
                pos = PchipInterpolator(tt, sig["theta"])
            elif sig["alpha"] is None:
                pos = CubicHermiteSpline(tt, sig["theta"], sig["omega"])
            else:
                pos = BPoly.from_derivatives(tt, np.column_stack(derivs))
        else:
            speed = (CubicSpline(tt, sig["omega"]) if sig["alpha"] is None
                     else CubicHermiteSpline(tt, sig["omega"], sig["alpha"]))
            pos = speed.antiderivative()
            # a PPoly stores the constant term of every piece last: shift them all
            pos.c[-1] += float(theta0) - float(pos(tt[0]))
        vel, acc = pos.derivative(), pos.derivative(2)
        ax_fun = _signal_function(accel_x, tt)
        r = None if radius_m is None else check_positive(radius_m, "radius_m")
        return cls(theta=pos, omega=vel, alpha=acc, t_start=float(tt[0]), t_end=float(tt[-1]),
                   grid=tt, accel_x=ax_fun, radius_m=r, name=name)


def _signal_function(value: npt.ArrayLike | Signal | None, t: Array) -> Signal | None:
    if value is None or callable(value):
        return value
    samples = as_signal(value, "accel_x", length=t.size)
    return lambda x: np.interp(x, t, samples)


def _rpm(value: float, name: str) -> float:
    """A wheel speed in ``(0, MAX_RPM]`` rpm, in rad/s."""
    rpm = check_positive(value, name)
    if rpm > MAX_RPM:
        raise SimulationError(f"{name} = {rpm:g} rpm lies above {MAX_RPM:g} rpm, beyond any wheel or test rig")
    return rpm_to_rad_s(rpm)


def _duration(value: float) -> float:
    """A profile length in ``(0, MAX_DURATION_S]`` seconds."""
    dur = check_positive(value, "duration_s")
    if dur > MAX_DURATION_S:
        raise SimulationError(f"duration_s = {dur:g} s lies above {MAX_DURATION_S:g} s, the longest profile")
    return dur


def _grid(t0: float, t1: float, step: float) -> Array:
    return np.linspace(t0, t1, max(2, math.ceil((t1 - t0) / step) + 1))


def constant_speed(rpm: float = 1020.0, duration_s: float = 10.0, *, theta0: float = 0.0) -> AngleTrajectory:
    """The constant-speed test-rig reference of seed 001 (Fig. 5.4, Table 6.1: 1020 rpm).

    ``theta(t) = theta0 + omega0 t`` on ``[0, duration_s]``.
    """
    w0 = _rpm(rpm, "rpm")
    dur = _duration(duration_s)
    return AngleTrajectory(
        theta=lambda t: theta0 + w0 * np.asarray(t, dtype=float),
        omega=lambda t: np.full(np.shape(t), w0),
        alpha=lambda t: np.zeros(np.shape(t)),
        t_start=0.0, t_end=dur, grid=_grid(0.0, dur, 1e-2), name=f"constant {rpm:g} rpm")


def varying_speed(
    rpm: float = 1020.0,
    duration_s: float = 10.0,
    *,
    amplitude_rad_s: float = 40.0,
    frequency_hz: float = 1.0,
    theta0: float = 0.0,
) -> AngleTrajectory:
    """A smooth time-varying rig reference (our stand-in for seed 001 Fig. 6.4).

    ``omega(t) = omega0 + A sin(2 pi f t)``, so ``alpha`` swings between
    ``+-2 pi f A`` (about 251 rad/s^2 with the defaults) and the speed stays
    positive as long as ``A < omega0``.

    Raises
    ------
    SimulationError
        If ``amplitude_rad_s >= omega0`` (the wheel would stop or reverse).
    """
    w0 = _rpm(rpm, "rpm")
    dur = _duration(duration_s)
    amp = check_positive(amplitude_rad_s, "amplitude_rad_s", allow_zero=True)
    f = check_positive(frequency_hz, "frequency_hz")
    if amp >= w0:
        raise SimulationError(
            f"amplitude_rad_s = {amp:g} must stay below the mean speed {w0:.4g} rad/s (no reversal)")
    wf = 2.0 * math.pi * f
    return AngleTrajectory(
        theta=lambda t: theta0 + w0 * np.asarray(t) + amp / wf * (1.0 - np.cos(wf * np.asarray(t))),
        omega=lambda t: w0 + amp * np.sin(wf * np.asarray(t)),
        alpha=lambda t: amp * wf * np.cos(wf * np.asarray(t)),
        t_start=0.0, t_end=dur, grid=_grid(0.0, dur, 1e-2),
        name=f"varying {rpm:g} rpm +- {amp:g} rad/s at {f:g} Hz")


def trapezoid_speed(low_rpm: float, high_rpm: float, duration_s: float = 10.0, *, segment_s: float = 1.0,
                    ramp_s: float | None = None, theta0: float = 0.0) -> AngleTrajectory:
    """Plateaus at constant speed joined by ramps at constant acceleration (a motor test rig's profile).

    A plateau of ``segment_s`` at ``low_rpm``, a ramp up of ``ramp_s``
    (default ``segment_s``), a plateau of ``segment_s`` at ``high_rpm``, a
    ramp down of ``ramp_s``, repeated.  Seed 001 Sec. 6.3 describes its
    time-varying reference (Fig. 6.4) by "the intervals in which the velocity
    or the acceleration are constant"; ``docs/encoders.md`` derives the speeds
    from its Table 6.1.

    Raises
    ------
    SimulationError
        If ``low_rpm >= high_rpm`` or a value is not positive.
    """
    lo = _rpm(low_rpm, "low_rpm")
    hi = _rpm(high_rpm, "high_rpm")
    if lo >= hi:
        raise SimulationError(f"low_rpm = {low_rpm:g} must be below high_rpm = {high_rpm:g}")
    dur = _duration(duration_s)
    seg = check_positive(segment_s, "segment_s")
    ramp = seg if ramp_s is None else check_positive(ramp_s, "ramp_s")
    period = 2.0 * (seg + ramp)
    starts = np.array([0.0, seg, seg + ramp, 2.0 * seg + ramp])     # lo plateau, ramp up, hi plateau, ramp down
    knots = (starts[None, :] + period * np.arange(math.ceil(dur / period) + 1)[:, None]).ravel()
    speeds = np.resize([lo, lo, hi, hi], knots.size)
    slopes = np.diff(speeds) / np.diff(knots)
    angles = theta0 + np.concatenate([[0.0], np.cumsum(0.5 * (speeds[1:] + speeds[:-1]) * np.diff(knots))])

    def cell(t: Array) -> tuple[Array, Array]:
        t = np.asarray(t, dtype=float)
        i = np.clip(np.searchsorted(knots, t, side="right") - 1, 0, slopes.size - 1)
        return i, t - knots[i]

    def theta(t: Array) -> Array:
        i, h = cell(t)
        return angles[i] + h * (speeds[i] + 0.5 * slopes[i] * h)

    def omega(t: Array) -> Array:
        i, h = cell(t)
        return speeds[i] + slopes[i] * h

    def alpha(t: Array) -> Array:
        return slopes[cell(t)[0]]

    return AngleTrajectory(theta=theta, omega=omega, alpha=alpha, t_start=0.0, t_end=dur,
                           grid=_grid(0.0, dur, 1e-2),
                           name=f"trapezoid {low_rpm:g}-{high_rpm:g} rpm, {seg:g} s plateaus, {ramp:g} s ramps")
