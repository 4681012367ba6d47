"""Super-twisting observer of the wheel speed from angle measurements, and its equivalent output injection.

Seed 003 (M'Sirdi et al. 2008), after Davila, Fridman and Levant (2005)::

    dx1_hat/dt = x2_hat + z1,              z1 = lambda |x1 - x1_hat|^(1/2) sign(x1 - x1_hat)     (8)-(9)
    dx2_hat/dt = f1(t, x1, x2_hat, u) + z2, z2 = alpha sign(x1 - x1_hat)

with ``x1 = theta`` measured, ``x2 = omega``, ``f1`` the known part of the
wheel acceleration (``u / J``, or 0 without a torque signal).  The gains
follow (12), the discrete observer is the Euler scheme (13), and once the
sliding motion is reached the low-pass filtered ``z2`` (the equivalent output
injection, (20)) equals the unknown part ``xi1`` of the acceleration.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from .._json import JsonRecord, array_to_json
from ..exceptions import SimulationError
from ._validate import as_signal, check_increasing, check_positive

__all__ = ["SuperTwistingGains", "super_twisting_gains", "SuperTwistingObserver", "SuperTwistingRun",
           "super_twisting", "low_pass"]

Array = npt.NDArray[np.float64]
KnownAcceleration = Callable[[float, float], float]


@dataclass(frozen=True)
class SuperTwistingGains(JsonRecord, error=SimulationError):
    """Gains ``(lambda, alpha)`` of (9) and the data of the rule (12) they were drawn from.

    Attributes
    ----------
    lam, alpha : float
        Gains of ``z1`` and ``z2``.
    f_plus : float
        Bound ``f+`` of (11) on the unknown acceleration ``|F|`` (rad/s^2).
    p : float
        The constant ``0 < p < 1`` of (12).
    """

    lam: float
    alpha: float
    f_plus: float
    p: float

    @property
    def lam_min(self) -> float:
        """Right-hand side of (12): ``sqrt(2 / (alpha - f+)) (alpha + f+) (1 + p) / (1 - p)``."""
        return _lam_bound(self.alpha, self.f_plus, self.p)

    @property
    def satisfies_rule(self) -> bool:
        """Whether ``alpha > f+`` and ``lambda`` exceeds the bound of (12)."""
        return self.alpha > self.f_plus and self.lam > self.lam_min

    def to_json(self) -> dict[str, Any]:
        return {"lam": self.lam, "alpha": self.alpha, "f_plus": self.f_plus, "p": self.p,
                "lam_min": self.lam_min, "satisfies_rule": self.satisfies_rule}

    def __str__(self) -> str:
        ok = "satisfies" if self.satisfies_rule else "violates"
        return (f"SuperTwistingGains: lambda = {self.lam:.4g}, alpha = {self.alpha:.4g} "
                f"(f+ = {self.f_plus:.4g}, p = {self.p:g}; {ok} (12), lambda_min = {self.lam_min:.4g})")


def _lam_bound(alpha: float, f_plus: float, p: float) -> float:
    return math.sqrt(2.0 / (alpha - f_plus)) * (alpha + f_plus) * (1.0 + p) / (1.0 - p)


def super_twisting_gains(
    f_plus: float, *, alpha: float | None = None, p: float = 0.1, margin: float = 1.05,
) -> SuperTwistingGains:
    """Gains satisfying the rule (12) of seed 003 for an acceleration bound ``f+``.

    ``alpha > f+`` and ``lambda > sqrt(2 / (alpha - f+)) (alpha + f+) (1 + p) / (1 - p)``.
    The extracted seed text prints ``(alpha + f+)^(1+p)``; the product form
    above is the one of Davila, Fridman and Levant (2005), the paper (12) is
    quoted from, and the only one with consistent units (``lambda`` scales as
    ``sqrt(alpha)``).

    Parameters
    ----------
    f_plus : float
        Bound on the unknown acceleration (rad/s^2), condition (11).
    alpha : float, optional
        Gain of ``z2``; default ``2 f+``.
    p : float
        Constant in (0, 1) of (12).
    margin : float
        ``lambda = margin * lambda_min`` (must exceed 1: (12) is strict).

    Raises
    ------
    SimulationError
        ``f_plus <= 0``, ``alpha <= f_plus``, ``p`` outside (0, 1) or ``margin <= 1``.

    Examples
    --------
    >>> g = super_twisting_gains(1000.0)
    >>> g.alpha, g.satisfies_rule
    (2000.0, True)
    """
    fp = check_positive(f_plus, "f_plus")
    a = 2.0 * fp if alpha is None else check_positive(alpha, "alpha")
    if a <= fp:
        raise SimulationError(f"alpha = {a:g} must exceed f_plus = {fp:g} (seed 003, (12))")
    if not 0.0 < p < 1.0:
        raise SimulationError(f"p = {p!r} must lie strictly between 0 and 1 (seed 003, (12))")
    if not margin > 1.0:
        raise SimulationError(f"margin = {margin!r} must exceed 1: the inequality (12) is strict")
    return SuperTwistingGains(lam=margin * _lam_bound(a, fp, p), alpha=a, f_plus=fp, p=p)


class SuperTwistingObserver:
    """The observer (8)-(9); :meth:`step` is its Euler discretisation (13).

    Parameters
    ----------
    gains : SuperTwistingGains
    x1_0 : float
        Initial angle estimate (the seed starts with ``x1_hat(0) = x1(0)``).
    x2_0 : float
        Initial speed estimate (the seed: 0).

    Notes
    -----
    The extracted seed text of (13) shows a stray ``- x_hat(t_i)`` inside each
    bracket; (13) is the explicit Euler scheme of (8)-(9), which is what
    :meth:`step` implements.
    """

    def __init__(self, gains: SuperTwistingGains, *, x1_0: float, x2_0: float = 0.0) -> None:
        self.gains = gains
        self.x1_hat, self.x2_hat = float(x1_0), float(x2_0)

    def derivative(self, x1: float, f1: float = 0.0) -> tuple[float, float, float]:
        """Right-hand side of (8) with the corrections (9): ``(dx1_hat, dx2_hat, z2)``."""
        e = x1 - self.x1_hat
        sgn = (e > 0.0) - (e < 0.0)
        z1 = self.gains.lam * math.sqrt(abs(e)) * sgn
        z2 = self.gains.alpha * sgn
        return self.x2_hat + z1, f1 + z2, z2

    def step(self, x1: float, dt: float, f1: float = 0.0) -> float:
        """Advance by ``dt`` with the measurement ``x1(t_i)`` (13); returns the injection ``z2(t_i)``."""
        d1, d2, z2 = self.derivative(x1, f1)
        self.x1_hat += dt * d1
        self.x2_hat += dt * d2
        return z2


@dataclass(frozen=True, eq=False)
class SuperTwistingRun(JsonRecord, error=SimulationError):
    """Estimates of the discrete observer (13) at the measurement times.

    Attributes
    ----------
    t : ndarray
        Measurement times ``t_i`` (s).
    x1_hat, x2_hat : ndarray
        Estimates at ``t_i`` (before the update with ``x1(t_i)``).
    z2 : ndarray
        Injection ``alpha sign(x1 - x1_hat)`` used over ``[t_i, t_{i+1})``.
    gains : SuperTwistingGains
    """

    t: Array
    x1_hat: Array
    x2_hat: Array
    z2: Array
    gains: SuperTwistingGains

    def to_json(self, *, arrays: bool = False) -> dict[str, Any]:
        """The gains and the final estimate (with the time series if ``arrays``)."""
        out: dict[str, Any] = {"gains": self.gains.to_json(), "samples": int(self.t.size),
                               "x2_hat_final": float(self.x2_hat[-1])}
        if arrays:
            out.update({k: array_to_json(getattr(self, k)) for k in ("t", "x1_hat", "x2_hat", "z2")})
        return out

    def __str__(self) -> str:
        return f"SuperTwistingRun: {self.t.size} steps, x2_hat(end) = {self.x2_hat[-1]:.6g}; {self.gains}"


def super_twisting(
    t: npt.ArrayLike,
    x1: npt.ArrayLike,
    *,
    gains: SuperTwistingGains,
    f1: npt.ArrayLike | KnownAcceleration | None = None,
    x2_0: float = 0.0,
) -> SuperTwistingRun:
    """Run the discrete super-twisting observer (13) over sampled angle measurements.

    Parameters
    ----------
    t : array_like
        Strictly increasing measurement times (s); steps may vary.
    x1 : array_like
        Measured angle (rad) at ``t``.
    gains : SuperTwistingGains
    f1 : array_like or callable, optional
        Known part of the acceleration: samples at ``t``, or ``f1(t, x2_hat)``
        (the form (24) with nominal parameters); default 0.
    x2_0 : float
        Initial speed estimate.

    Returns
    -------
    SuperTwistingRun

    References
    ----------
    Seed 003, (8), (9), (13); Theorem 2: after a transient ``|x1 - x1_hat| <= g1 delta^2``
    and ``|x2 - x2_hat| <= g2 delta``.
    """
    tt = as_signal(t, "t")
    check_increasing(tt, "t")
    y = as_signal(x1, "x1 (angle measurements)", length=tt.size)
    fun = f1 if callable(f1) else None
    known = np.zeros(tt.size) if f1 is None else (None if fun else as_signal(f1, "f1", length=tt.size))
    obs = SuperTwistingObserver(gains, x1_0=float(y[0]), x2_0=x2_0)
    n = tt.size
    x1h, x2h, z2 = np.empty(n), np.empty(n), np.zeros(n)
    dts = np.append(np.diff(tt), 0.0)
    for i in range(n):
        x1h[i], x2h[i] = obs.x1_hat, obs.x2_hat
        fi = fun(float(tt[i]), obs.x2_hat) if fun is not None else known[i]  # type: ignore[index]
        z2[i] = obs.step(float(y[i]), float(dts[i]), float(fi))
    return SuperTwistingRun(t=tt, x1_hat=x1h, x2_hat=x2h, z2=z2, gains=gains)


def low_pass(x: npt.ArrayLike, dt_s: float, tau_s: float) -> Array:
    """First-order low-pass ``1 / (tau s + 1)``, exactly discretised for a piecewise-constant input.

    Used for the equivalent output injection (seed 003, Section IV): ``tau``
    small enough to keep the slow component, ``dt / tau`` small enough to remove
    the switching.  Starts from the first sample.
    """
    xs = as_signal(x, "signal")
    a = math.exp(-check_positive(dt_s, "dt_s") / check_positive(tau_s, "tau_s"))
    # imported here: scipy.signal alone takes about a second, which `switchobs <cmd> --help` must not pay
    from scipy.signal import lfilter

    y, _ = lfilter([1.0 - a], [1.0, -a], xs, zi=[a * xs[0]] if xs.size else [0.0])
    return y
