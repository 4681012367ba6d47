"""Time-stamping algorithm (TSA): least-squares polynomial fit of the last encoder events.

Seed 001, (5.1)-(5.5) with the shift-and-scale of Appendix C: at each
controller sample the last ``n`` event times are referred to the oldest one
and divided by the window span ``Delta``, the order-``m`` polynomial is fitted
in that variable, and the derivatives are scaled back by ``1/Delta`` and
``1/Delta^2``.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from .._json import JsonRecord, array_to_json
from ..exceptions import SimulationError
from ._kernels import tsa_fit, use_kernels
from ._validate import as_signal, check_increasing, check_int, check_positive

__all__ = ["TsaEstimate", "time_stamping", "tsa_condition_number", "controller_times", "TimeStamper"]

Array = npt.NDArray[np.float64]


def check_order_window(order: Any, window: Any) -> tuple[int, int]:
    m = check_int(order, "order (polynomial order m)", minimum=2)
    n = check_int(window, "window (events n)", minimum=2)
    if n <= m:
        raise SimulationError(
            f"window n = {n} must exceed the polynomial order m = {m} (seed 001, (5.3) needs n > m >= 2)")
    return m, n


#: Numbers in the batched Vandermonde matrices of one call of :func:`_fit` (about 16 MB).
_FIT_CHUNK = 2_000_000


def _fit(tw: Array, thw: Array, t_eval: Array, order: int) -> tuple[Array, Array, Array]:
    """Batched least-squares fits, one per row of ``tw`` (K x n), evaluated at ``t_eval`` (K,).

    Times and angles are referred to the oldest event of each window, and time
    is divided by the window span (Appendix C), so the Vandermonde matrices
    have entries in [0, 1].
    """
    t0 = tw[:, :1]
    span = tw[:, -1:] - t0
    s = (tw - t0) / span
    powers = np.arange(order + 1)
    vander = s[:, :, None] ** powers
    q, r = np.linalg.qr(vander)
    rhs = np.einsum("kni,kn->ki", q, thw - thw[:, :1])
    p = np.linalg.solve(r, rhs[:, :, None])[:, :, 0]
    span = span[:, 0]
    se = (t_eval - t0[:, 0]) / span
    theta = thw[:, 0] + np.polynomial.polynomial.polyval(se, p.T, tensor=False)
    dp = p[:, 1:] * powers[1:]
    omega = np.polynomial.polynomial.polyval(se, dp.T, tensor=False) / span
    ddp = dp[:, 1:] * powers[1:-1]
    alpha = np.polynomial.polynomial.polyval(se, ddp.T, tensor=False) / span**2
    return theta, omega, alpha


@dataclass(frozen=True, eq=False)
class TsaEstimate(JsonRecord, error=SimulationError):
    """Position, speed and acceleration from the TSA at the controller sample times.

    Attributes
    ----------
    t : ndarray
        Controller sample times (s).
    theta, omega, alpha : ndarray
        Estimates (rad, rad/s, rad/s^2) from (5.1), (5.4), (5.5); NaN before the
        first ``window`` events are available.
    last_event : ndarray of int
        Index of the newest event used at each sample (-1 if none yet).
    order, window : int
        Polynomial order ``m`` and number of events ``n``.
    """

    t: Array
    theta: Array
    omega: Array
    alpha: Array
    last_event: npt.NDArray[np.int_]
    order: int
    window: int

    @property
    def valid(self) -> npt.NDArray[np.bool_]:
        """Samples at which at least ``window`` events were available."""
        return self.last_event >= self.window - 1

    def to_json(self, *, arrays: bool = False) -> dict[str, Any]:
        out: dict[str, Any] = {"order": self.order, "window": self.window, "samples": int(self.t.size),
                               "valid_samples": int(np.count_nonzero(self.valid))}
        if arrays:  # NaN (null) where fewer than `window` events were available
            out.update({k: array_to_json(getattr(self, k)) for k in ("t", "theta", "omega", "alpha", "last_event")})
        return out

    def __str__(self) -> str:
        return (f"TsaEstimate: m={self.order}, n={self.window}, {self.t.size} samples "
                f"({np.count_nonzero(self.valid)} valid)")


def time_stamping(
    times: npt.ArrayLike,
    angles: npt.ArrayLike,
    sample_times: npt.ArrayLike,
    *,
    order: int = 2,
    window: int = 15,
    compiled: bool | None = None,
) -> TsaEstimate:
    """Run the time-stamping algorithm at every controller sample.

    At sample time ``t`` the events with time stamp ``<= t`` are available;
    the last ``n`` of them are fitted by a polynomial of order ``m`` in the
    least-squares sense, (5.2)-(5.3), after the shift-and-scale of Appendix C,
    and the polynomial and its derivatives are evaluated at ``t``, (5.4)-(5.5).

    Parameters
    ----------
    times : array_like
        Event time stamps (s), strictly increasing.
    angles : array_like
        Angle assigned to each event (rad).
    sample_times : array_like
        Controller sample times (s), strictly increasing.
    order : int
        Polynomial order ``m`` (the seed uses 2).
    window : int
        Number of events ``n > m``.
    compiled : bool or None
        The C kernel (``True``), the numpy reference (``False``) or the kernel when a C compiler is
        installed (``None``); they agree to rounding.

    Returns
    -------
    TsaEstimate

    Raises
    ------
    SimulationError
        ``window <= order``, NaN entries, non-increasing time stamps or length mismatch.
    CodegenError
        ``compiled=True`` without a working C compiler.

    References
    ----------
    Seed 001, (5.1)-(5.5), Remark 2 and Appendix C.

    Examples
    --------
    >>> import numpy as np
    >>> t_ev = np.linspace(0.0, 0.1, 51)
    >>> est = time_stamping(t_ev, 3.0 * t_ev + 10.0 * t_ev**2, [0.1], order=2, window=5)
    >>> round(float(est.omega[0]), 9), round(float(est.alpha[0]), 9)
    (5.0, 20.0)
    """
    m, n = check_order_window(order, window)
    tt = as_signal(times, "event times")
    check_increasing(tt, "event times")
    th = as_signal(angles, "event angles", length=tt.size)
    ts = as_signal(sample_times, "sample times")
    check_increasing(ts, "sample times")
    last = np.searchsorted(tt, ts, side="right") - 1
    out = fit_windows(tt, th, last, ts, m, n, compiled=compiled)
    return TsaEstimate(t=ts, theta=out[0], omega=out[1], alpha=out[2], last_event=last, order=m, window=n)


def fit_windows(times: Array, angles: Array, last: npt.NDArray[np.int_], sample_times: Array, order: int,
                window: int, *, compiled: bool | None = None) -> Array:
    """``(theta, omega, alpha, t_mean)`` rows (4 x samples) of the fits of the events ``last - window + 1 ..
    last``, ``t_mean`` the mean of their time stamps (summed oldest first).

    NaN where ``last < window - 1``.  Each window's numbers are those of :meth:`TimeStamper.estimate`
    with the same ``compiled`` on the same events (the batched factorisations run the same LAPACK calls
    matrix by matrix; the C kernel runs window by window).
    """
    out = np.full((4, sample_times.size), np.nan)
    rows = np.flatnonzero(last >= window - 1)
    if rows.size and int(last[rows[-1]]) >= times.size:
        raise SimulationError(f"event {int(last[rows[-1]])} asked for of {times.size}")
    if use_kernels(compiled):
        out[:, rows] = tsa_fit(times, angles, last[rows], sample_times[rows], order, window)
        return out
    # the batched matrices hold rows x n x (m + 1) numbers: a chunk of rows at a time keeps memory bounded
    chunk = max(1, _FIT_CHUNK // (window * (order + 1)))
    for start in range(0, rows.size, chunk):
        sel = rows[start:start + chunk]
        idx = last[sel, None] + np.arange(-window + 1, 1)
        tw = times[idx]
        out[:3, sel] = _fit(tw, angles[idx], sample_times[sel], order)
        total = np.zeros(sel.size)
        for j in range(window):
            total = total + tw[:, j]
        out[3, sel] = total / window
    return out


def tsa_condition_number(times: npt.ArrayLike, *, order: int = 2, scaled: bool = True) -> float:
    """2-norm condition number of the TSA regression matrix ``A`` of (5.2).

    With ``scaled`` the times are first shifted by the oldest one and divided by
    the span (Appendix C).  The Appendix C example, times ``[22 .. 26] x 1e-5`` s
    with ``m = 2``, gives about ``5.97e9`` unscaled and ``16.66`` scaled.

    Raises
    ------
    SimulationError
        Fewer than ``order + 1`` times, NaN or non-increasing times.
    """
    tt = as_signal(times, "times")
    check_increasing(tt, "times")
    m, _ = check_order_window(order, tt.size)
    if scaled:
        tt = (tt - tt[0]) / (tt[-1] - tt[0])
    return float(np.linalg.cond(np.vander(tt, m + 1)))


def controller_times(t_start: float, t_end: float, rate_hz: float) -> Array:
    """Controller sample instants ``t_start + k / rate_hz`` up to ``t_end`` (inclusive)."""
    rate = check_positive(rate_hz, "rate_hz")
    count = int(math.floor((t_end - t_start) * rate + 1e-9)) + 1
    return t_start + np.arange(count) / rate


class TimeStamper:
    """Streaming TSA for closed-loop use: push events as they arrive, estimate at each sample.

    Keeps the last ``window`` events in a ring buffer; :meth:`estimate` runs the
    same scaled fit as :func:`time_stamping` on them.

    Parameters
    ----------
    order, window : int
        Polynomial order ``m`` and number of events ``n > m``.
    compiled : bool or None
        As :func:`time_stamping`: the estimates equal its estimates with the same ``compiled`` bit for bit.

    Raises
    ------
    SimulationError
        ``window <= order``.
    CodegenError
        ``compiled=True`` without a working C compiler.
    """

    def __init__(self, *, order: int = 2, window: int = 15, compiled: bool | None = None) -> None:
        self.order, self.window = check_order_window(order, window)
        self._compiled = use_kernels(compiled)
        self._t: deque[float] = deque(maxlen=self.window)
        self._th: deque[float] = deque(maxlen=self.window)

    def push(self, t: float, theta: float) -> None:
        """Record one event (time stamp in s, assigned angle in rad)."""
        if not (math.isfinite(t) and math.isfinite(theta)):
            raise SimulationError(f"event (t={t!r}, theta={theta!r}) is not finite")
        if self._t and t <= self._t[-1]:
            raise SimulationError(
                f"event time stamps must be strictly increasing: {t!r} after {self._t[-1]!r}")
        self._t.append(float(t))
        self._th.append(float(theta))

    def estimate(self, t: float) -> tuple[float, float, float]:
        """``(theta, omega, alpha)`` at time ``t``, NaNs until ``window`` events have arrived."""
        if len(self._t) < self.window:
            return math.nan, math.nan, math.nan
        if self._compiled:
            fit = tsa_fit(np.array(self._t), np.array(self._th), np.array([self.window - 1]), np.array([float(t)]),
                          self.order, self.window)
            return float(fit[0, 0]), float(fit[1, 0]), float(fit[2, 0])
        th, om, al = _fit(np.array([self._t]), np.array([self._th]), np.array([t]), self.order)
        return float(th[0]), float(om[0]), float(al[0])
