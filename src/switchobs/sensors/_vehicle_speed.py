"""First-order sliding-mode observer of the vehicle speed ``x3 = v_x``, and its equivalent output injection.

Seed 003 (M'Sirdi et al. 2008), Section III-B::

    dx3/dt = f2(t, x3, u) + xi2(t, x2, x3, u),   f2 = 0,   y2 = x3                         (14)
    dx3_hat/dt = z3,   z3 = beta sign(x3 - x3_hat)                                        (15)
    dx3_tilde/dt = xi2 - beta sign(x3_tilde)                                              (16)

The speed is measured; the observer exists for its injection: once the
sliding motion is reached (Theorem 3, ``beta > eta >= |xi2|``), the low-pass
filtered ``z3`` equals the unknown acceleration ``xi2 = F_x / m`` (19), (21),
from which ``theta_2 = [C_x, R C_x]`` is identified
(:func:`~switchobs.sensors.identify_speed_parameters`, Section V-B).
The discrete observer is the explicit Euler step of (15), the analogue of the
seed's (13) for the super-twisting observer.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from .._json import JsonRecord, array_to_json
from ..exceptions import SimulationError
from ._validate import as_signal, check_increasing, check_positive

__all__ = ["VehicleSpeedGain", "vehicle_speed_gain", "VehicleSpeedObserver", "VehicleSpeedRun",
           "vehicle_speed_observer"]

Array = npt.NDArray[np.float64]


@dataclass(frozen=True)
class VehicleSpeedGain(JsonRecord, error=SimulationError):
    """Gain ``beta`` of (15) and the bound ``eta`` of Theorem 3 it was drawn from.

    Attributes
    ----------
    beta : float
        Gain of ``z3 = beta sign(x3 - x3_hat)`` (m/s^2).
    eta : float
        Bound on the unknown acceleration, ``|dx3/dt| = |xi2| <= eta`` (m/s^2).
    """

    beta: float
    eta: float

    @property
    def margin(self) -> float:
        """``beta - eta``: the least rate at which ``|x3_tilde|`` falls before the sliding motion (17)."""
        return self.beta - self.eta

    @property
    def satisfies_theorem3(self) -> bool:
        """Whether ``beta > eta`` (Theorem 3)."""
        return self.beta > self.eta

    def reaching_time_bound(self, initial_error: float) -> float:
        """Bound ``|x3_tilde(0)| / (beta - eta)`` on the time ``t1`` of Theorem 3 (s); ``inf`` if ``beta <= eta``.

        From (17), ``d|x3_tilde|/dt = sign(x3_tilde) xi2 - beta <= -(beta - eta)`` until ``x3_tilde = 0``.
        """
        return abs(float(initial_error)) / self.margin if self.satisfies_theorem3 else math.inf

    def to_json(self) -> dict[str, Any]:
        return {"beta": self.beta, "eta": self.eta, "margin": self.margin,
                "satisfies_theorem3": self.satisfies_theorem3}

    def __str__(self) -> str:
        ok = "satisfies" if self.satisfies_theorem3 else "violates"
        return f"VehicleSpeedGain: beta = {self.beta:.4g} m/s^2 (eta = {self.eta:.4g}; {ok} Theorem 3)"


def vehicle_speed_gain(eta: float, *, beta: float | None = None) -> VehicleSpeedGain:
    """The gain of the observer (15) for an acceleration bound ``eta`` (Theorem 3: ``beta > eta``).

    Parameters
    ----------
    eta : float
        Bound on ``|xi2| = |F_x| / m`` (m/s^2), e.g. the largest deceleration the tyre can give.
    beta : float, optional
        Gain of ``z3``; default ``2 eta`` (the default of :func:`super_twisting_gains` for ``alpha``).

    Raises
    ------
    SimulationError
        ``eta <= 0`` or ``beta <= eta`` (Theorem 3 is strict).

    Examples
    --------
    >>> g = vehicle_speed_gain(12.0)
    >>> g.beta, g.satisfies_theorem3, g.reaching_time_bound(3.0)
    (24.0, True, 0.25)
    """
    e = check_positive(eta, "eta")
    b = 2.0 * e if beta is None else check_positive(beta, "beta")
    if b <= e:
        raise SimulationError(f"beta = {b:g} must exceed eta = {e:g} (seed 003, Theorem 3)")
    return VehicleSpeedGain(beta=b, eta=e)


class VehicleSpeedObserver:
    """The observer (15); :meth:`step` is its explicit Euler step.

    Parameters
    ----------
    gain : VehicleSpeedGain
    x3_0 : float
        Initial speed estimate (m/s); the seed gives none.
    """

    def __init__(self, gain: VehicleSpeedGain, *, x3_0: float) -> None:
        self.gain = gain
        self.x3_hat = float(x3_0)

    def derivative(self, x3: float) -> float:
        """Right-hand side of (15): ``z3 = beta sign(x3 - x3_hat)``."""
        e = x3 - self.x3_hat
        return self.gain.beta * ((e > 0.0) - (e < 0.0))

    def step(self, x3: float, dt: float) -> float:
        """Advance by ``dt`` with the measurement ``x3(t_i)``; returns the injection ``z3(t_i)``."""
        z3 = self.derivative(x3)
        self.x3_hat += dt * z3
        return z3


@dataclass(frozen=True, eq=False)
class VehicleSpeedRun(JsonRecord, error=SimulationError):
    """Estimates of the discrete observer (15) at the measurement times.

    Attributes
    ----------
    t : ndarray
        Measurement times ``t_i`` (s).
    x3_hat : ndarray
        Estimate at ``t_i`` (before the update with ``x3(t_i)``).
    error : ndarray
        ``x3_tilde = x3(t_i) - x3_hat(t_i)``: the measured speed is the observer's input, so its error is known.
    z3 : ndarray
        Injection ``beta sign(x3_tilde)`` used over ``[t_i, t_{i+1})``.
    gain : VehicleSpeedGain
    """

    t: Array
    x3_hat: Array
    error: Array
    z3: Array
    gain: VehicleSpeedGain

    @property
    def reaching_time_s(self) -> float:
        """First time the error changes sign: the discrete ``t1`` of Theorem 3 (s); ``nan`` if it never does."""
        s = np.sign(self.error)
        if s[0] == 0.0:
            return float(self.t[0])
        flip = np.flatnonzero(s[1:] * s[0] <= 0.0)
        return float(self.t[flip[0] + 1]) if flip.size else math.nan

    def to_json(self, *, arrays: bool = False) -> dict[str, Any]:
        """The gain, the reaching time and the final estimate (with the time series if ``arrays``)."""
        out: dict[str, Any] = {"gain": self.gain.to_json(), "samples": int(self.t.size),
                               "reaching_time_s": self.reaching_time_s, "x3_hat_final": float(self.x3_hat[-1])}
        if arrays:
            out.update({k: array_to_json(getattr(self, k)) for k in ("t", "x3_hat", "error", "z3")})
        return out

    def __str__(self) -> str:
        return (f"VehicleSpeedRun: {self.t.size} steps, sliding from t1 = {self.reaching_time_s:.4g} s, "
                f"x3_hat(end) = {self.x3_hat[-1]:.6g} m/s; {self.gain}")


def vehicle_speed_observer(
    t: npt.ArrayLike,
    x3: npt.ArrayLike,
    *,
    gain: VehicleSpeedGain,
    x3_0: float | None = None,
) -> VehicleSpeedRun:
    """Run the discrete sliding-mode observer (15) of the vehicle speed over sampled measurements.

    Parameters
    ----------
    t : array_like
        Strictly increasing measurement times (s); steps may vary.
    x3 : array_like
        Measured vehicle speed ``v_x`` (m/s) at ``t``.
    gain : VehicleSpeedGain
    x3_0 : float, optional
        Initial estimate (m/s, positive like the speed); default the first measurement (no reaching phase).

    Returns
    -------
    VehicleSpeedRun

    References
    ----------
    Seed 003, (14)-(17) and Theorem 3: for ``beta > eta`` the error vanishes after a finite ``t1 <=
    |x3_tilde(0)| / (beta - eta)``; the discrete observer then stays within ``(beta + eta) delta``.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(0.0, 1.0, 1e-3)
    >>> run = vehicle_speed_observer(t, 30.0 - 5.0 * t, gain=vehicle_speed_gain(5.0, beta=10.0), x3_0=31.0)
    >>> round(run.reaching_time_s, 3)                # |x3_tilde(0)| / (beta - 5) = 0.2 s
    0.2
    """
    tt = as_signal(t, "t")
    check_increasing(tt, "t")
    y = as_signal(x3, "x3 (speed measurements)", length=tt.size)
    obs = VehicleSpeedObserver(gain, x3_0=float(y[0]) if x3_0 is None else check_positive(x3_0, "x3_0"))
    n = tt.size
    xh, z3 = np.empty(n), np.zeros(n)
    dts = np.append(np.diff(tt), 0.0)
    for i in range(n):
        xh[i] = obs.x3_hat
        z3[i] = obs.step(float(y[i]), float(dts[i]))
    return VehicleSpeedRun(t=tt, x3_hat=xh, error=y - xh, z3=z3, gain=gain)

