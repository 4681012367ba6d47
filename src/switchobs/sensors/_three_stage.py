"""Harmonic compensation of encoder imperfections: the three-stage estimator and the notch baseline.

Seed 001, Section 6.2.  The TSA speed and acceleration carry a periodic
perturbation in the measured angle, (6.5)-(6.6):

    omega_m = omega_r + Phi_w' theta',      Phi_w = D phi(theta_m) omega_m
    alpha_m = alpha_r + Phi_a' theta'',     Phi_a = D phi(theta_m) alpha_m - D^2 psi(theta_m) omega_m^2

Stage 1 high-passes the measured signal (removing the slow true signal),
stage 2 identifies the Fourier coefficients with the normalised RLS with
forgetting (6.8), stage 3 subtracts the identified perturbation.  The notch
filter of Section 6.3 (damping 0.5, centred on the wheel revolution
frequency, i.e. on ``omega_m`` itself in rad/s) is the comparison baseline.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from ..exceptions import SimulationError
from ._kernels import notch_run, three_stage_layout, three_stage_run, three_stage_update, use_kernels
from ._series import SpeedEstimate
from ._tsa import TsaEstimate
from ._validate import check_int, check_positive, check_range

__all__ = ["ThreeStageEstimator", "NotchFilter", "three_stage", "notch", "notch_series", "MAX_HARMONICS",
           "check_harmonics"]

Array = npt.NDArray[np.float64]


#: Most harmonics of the perturbation model (6.2): the seed takes ceil(N / n) + 1 = 5, and the least squares
#: cost (2 M)^2 per sample.
MAX_HARMONICS = 200


def check_harmonics(value: Any) -> int:
    """The number ``M`` of harmonics, an integer in ``[1, MAX_HARMONICS]``."""
    m = check_int(value, "harmonics (M)", minimum=1)
    if m > MAX_HARMONICS:
        raise SimulationError(f"harmonics (M) = {m} lies above {MAX_HARMONICS}; the seed uses ceil(N/n) + 1 "
                              f"(5 for N = 60 teeth and n = 15 events)")
    return m


class _HighPass:
    """First-order high-pass ``s / (s + 2 pi f_c)``, backward-Euler discretised (stage 1)."""

    def __init__(self, cutoff_hz: float, dt_s: float) -> None:
        tau = 1.0 / (2.0 * math.pi * cutoff_hz)
        self.a = tau / (tau + dt_s)
        self._x: float | None = None
        self._y = 0.0

    def __call__(self, x: float) -> float:
        # starts at rest on the first sample, so the mean speed never enters the regression
        self._y = 0.0 if self._x is None else self.a * (self._y + x - self._x)
        self._x = x
        return self._y


class _RevolutionDetrend:
    """Stage 1 (ours): each sample minus its local trend, the mean over the wheel revolution(s) centred on it.

    The perturbation (6.2) is periodic in the angle, so its mean over one or
    two revolutions vanishes, while a smooth true signal differs from those
    centred means by ``T^2 f''/24`` and ``4 T^2 f''/24`` (``T`` one
    revolution); their Richardson combination cancels that term (no phase
    lead, no leak of a speed swing).  Samples where the term is large against
    the speed (``curvature``) are left out.  The result is available one
    revolution late: it feeds the
    identification only, whose coefficients are constant, while the
    compensation (stage 3) stays on the current sample.  The window is the
    revolution at the current measured speed.  Below ``1 / max_revolution_s``
    revolutions per second no sample is returned (the identification pauses):
    a revolution then lasts as long as a change of speed, and nothing separates
    the two.
    """

    def __init__(self, dt_s: float, max_revolution_s: float = 0.25, curvature: float = 0.03) -> None:
        self._dt = dt_s
        self.curvature = curvature
        self.size = max(8, 2 * int(math.ceil(max_revolution_s / dt_s)) + 6)
        self._rows = np.zeros((self.size, 3))     # theta, omega, alpha
        self._sums = np.zeros((self.size, 2))     # running sums of omega and alpha
        self._k = -1

    def __call__(self, theta: float, omega: float, alpha: float) -> tuple[float, float, float, float, float] | None:
        """Push a sample; return ``(theta, omega, alpha, zeta_omega, zeta_alpha)`` of the centre sample, if any."""
        k, n = self._k + 1, self.size
        self._k = k
        self._rows[k % n] = theta, omega, alpha
        self._sums[k % n] = self._sums[(k - 1) % n] + (omega, alpha) if k else (omega, alpha)
        if omega == 0.0:
            return None
        half = math.pi / (abs(omega) * self._dt)      # half a revolution, in samples (not rounded)
        centre = k - math.ceil(2.0 * half + 0.5)
        if centre - 2.0 * half - 1.5 < max(0, k - n + 1):
            return None

        def integral(x: float) -> npt.NDArray[np.float64]:
            # running sum of the samples, each spread over [i - 1/2, i + 1/2), up to x (fractional)
            j = math.floor(x - 0.5)
            return self._sums[j % n] + (x - 0.5 - j) * self._rows[(j + 1) % n, 1:]

        one = (integral(centre + half) - integral(centre - half)) / (2.0 * half)
        two = (integral(centre + 2.0 * half) - integral(centre - 2.0 * half)) / (4.0 * half)
        row = self._rows[centre % n]
        # where the T^2 f'' term is large against the speed the expansion is not to be trusted
        if abs(one[0] - two[0]) > self.curvature * abs(omega):
            return None
        mean = (4.0 * one - two) / 3.0
        return (float(row[0]), float(row[1]), float(row[2]), float(row[1] - mean[0]), float(row[2] - mean[1]))


class _Rls:
    """Normalised least squares with forgetting (6.8), one step of ``dt`` per sample.

    (6.8b) is integrated on the information matrix ``Gamma^{-1}``, whose
    derivative ``-beta Gamma^{-1} + Phi Phi' / m^2`` is affine: an Euler step
    there and Sherman-Morrison back keep ``Gamma`` symmetric positive definite
    for any ``dt < 1 / beta``; (6.8a) then uses the updated ``Gamma``, so the
    error along ``Phi`` contracts by a factor in (0, 1] (no step-size limit).
    """

    def __init__(self, gamma0: Array, kappa: float, beta: float, dt_s: float) -> None:
        self.gamma = np.diag(gamma0).astype(float)
        self.theta = np.zeros(gamma0.size)
        self._kappa, self._dt = kappa, dt_s
        self.decay = 1.0 / (1.0 - beta * dt_s)

    def step(self, phi: Array, phi_sq: float, zeta: float) -> None:
        # phi_sq = Phi' Phi from the closed form of Section 6.2 (no dot product needed)
        w = self._dt / (1.0 + self._kappa * phi_sq)
        g = self.gamma * self.decay
        gphi = g @ phi
        self.gamma = g - np.outer(gphi, gphi) * (w / (1.0 + w * float(phi @ gphi)))
        err = float(phi @ self.theta) - zeta
        self.theta -= (self.gamma @ phi) * (w * err)


class ThreeStageEstimator:
    """Streaming three-stage estimator of seed 001, Fig. 6.2 (one sample per :meth:`update`).

    Parameters
    ----------
    harmonics : int
        Number ``M >= 1`` of harmonics of the revolution in the perturbation model (6.2).
    dt_s : float
        Controller sample period (s).
    kappa, beta : float
        Normalisation and forgetting constants of (6.8) (seed: 1 and 0.1).
    gamma0 : float or sequence of float
        Initial gains ``gamma_1 > gamma_2 > ... > gamma_M`` of
        ``Gamma_0 = diag[gamma_1, gamma_1, gamma_2, gamma_2, ...]``; a scalar ``g``
        means ``gamma_k = g / k``.  The default is a weak prior, so the
        estimates are close to the least-squares fit of the data seen so far
        after a few revolutions.
    highpass_hz : float, optional
        Stage 1.  ``None`` (default, ours): subtract the mean over the
        surrounding revolution and identify half a revolution late (see
        ``docs/encoders.md``).  A number: the seed's first-order high-pass with
        that cut-off (seed: 1 Hz), whose phase lead ``atan(f_c / f_rev)``
        rotates the identified coefficients slightly and which lets a speed
        swing near the revolution frequency into the regression: at 600 rpm
        with a +-40 rad/s swing at 1 Hz it makes the estimate six times worse
        than the raw TSA.
    compiled : bool or None
        Run the C port of the estimator (``_kernels.c``; ``benchmarks/encoder_chain.py`` times both):
        ``None`` (default) when a C compiler is installed, ``True`` always, ``False`` never (the Python
        reference).  The two agree to rounding: the C sums its dot products left to right, numpy's
        BLAS does not (``tests/test_sensors_kernels.py`` bounds the difference).

    Raises
    ------
    SimulationError
        ``harmonics < 1``, non-positive constants, ``beta * dt_s >= 1`` or a
        ``gamma0`` of the wrong length or not decreasing.
    CodegenError
        ``compiled=True`` without a working C compiler.

    References
    ----------
    Seed 001, (6.2)-(6.8) and Section 6.3 (``kappa = 1``, ``beta = 0.1``, ``theta_0 = 0``).
    """

    def __init__(
        self,
        harmonics: int = 5,
        *,
        dt_s: float = 1e-3,
        kappa: float = 1.0,
        beta: float = 0.1,
        gamma0: float | Sequence[float] = 1e5,
        highpass_hz: float | None = None,
        compiled: bool | None = None,
    ) -> None:
        self.harmonics = check_harmonics(harmonics)
        self.dt_s = check_positive(dt_s, "dt_s")
        kappa = check_positive(kappa, "kappa")
        beta = check_positive(beta, "beta", allow_zero=True)
        if beta * self.dt_s >= 1.0:
            raise SimulationError(f"beta * dt_s = {beta * self.dt_s:g} must be below 1")
        if highpass_hz is not None:
            highpass_hz = check_positive(highpass_hz, "highpass_hz")
        k = np.arange(1, self.harmonics + 1, dtype=float)
        if np.ndim(gamma0) == 0:
            gam = check_positive(gamma0, "gamma0") / k
        else:
            gam = np.asarray([check_positive(g, "gamma0 entry") for g in gamma0])  # type: ignore[union-attr]
            if gam.size != self.harmonics:
                raise SimulationError(f"gamma0 has {gam.size} entries; expected one per harmonic ({self.harmonics})")
            if np.any(np.diff(gam) > 0):
                raise SimulationError(f"gamma0 = {gam.tolist()} must be non-increasing (gamma_1 >= gamma_2 >= ...)")
        self._k = k
        self._d = np.repeat(k, 2)
        self._sigma2 = float(np.sum(k**2))
        self._sigma4 = float(np.sum(k**4))
        g0 = np.repeat(gam, 2)
        rls = (_Rls(g0, kappa, beta, self.dt_s), _Rls(g0, kappa, beta, self.dt_s))
        detrend = _RevolutionDetrend(self.dt_s) if highpass_hz is None else None
        highpass = None if highpass_hz is None else (_HighPass(highpass_hz, self.dt_s),
                                                     _HighPass(highpass_hz, self.dt_s))
        self._cfg: Array | None = None
        if use_kernels(compiled):
            # the C kernel runs alone on the initial state of the Python stages, laid out as _kernels.c reads it
            size = 0 if detrend is None else detrend.size
            self._cfg = np.array([self.harmonics, self.dt_s, kappa, rls[0].decay, self._sigma2, self._sigma4,
                                  0.0 if detrend is None else detrend.curvature, size, float(detrend is None),
                                  0.0 if highpass is None else highpass[0].a])
            length, gw, ga = three_stage_layout(self.harmonics, size)
            self._state = np.zeros(length)
            self._state[0] = -1.0          # the detrend's sample counter before the first sample
            d = 2 * self.harmonics
            for at, r in zip((gw, ga), rls):
                self._state[at:at + d * d] = r.gamma.ravel()
            self._theta_at = (gw + d * d, ga + d * d)
            self._out = np.empty(2)
        else:
            self._rls_w, self._rls_a = rls
            self._detrend = detrend
            if highpass is not None:
                self._hp_w, self._hp_a = highpass

    @property
    def compiled(self) -> bool:
        """Whether the C kernel runs the estimator."""
        return self._cfg is not None

    def _coefficients(self, which: int) -> Array:
        if self._cfg is None:
            return (self._rls_w, self._rls_a)[which].theta.copy()
        start = self._theta_at[which]
        return self._state[start:start + 2 * self.harmonics].copy()

    @property
    def coefficients_velocity(self) -> Array:
        """Current ``theta'_hat = [a'_1, b'_1, a'_2, b'_2, ...]`` of (6.5)."""
        return self._coefficients(0)

    @property
    def coefficients_acceleration(self) -> Array:
        """Current ``theta''_hat = [a''_1, b''_1, ...]`` of (6.6)."""
        return self._coefficients(1)

    def regressors(self, theta_m: float, omega_m: float, alpha_m: float) -> tuple[Array, Array, float, float]:
        """``(Phi_w, Phi_a, |Phi_w|^2, |Phi_a|^2)`` of (6.5)-(6.6), the norms in closed form.

        ``Phi_w = D phi omega_m`` and ``Phi_a = D phi alpha_m - D^2 psi omega_m^2`` with
        ``phi = [cos t, -sin t, cos 2t, -sin 2t, ...]``, ``psi = [sin t, cos t, ...]``,
        ``D = diag[1, 1, 2, 2, ...]``; since ``D phi`` and ``D^2 psi`` are orthogonal,
        ``|Phi_w|^2 = s2 omega^2`` and ``|Phi_a|^2 = s2 alpha^2 + s4 omega^4`` with
        ``s2 = sum k^2``, ``s4 = sum k^4`` (seed 001, Section 6.2).
        """
        kt = self._k * theta_m
        c, s = np.cos(kt), np.sin(kt)
        dphi = np.empty(2 * self.harmonics)
        dphi[0::2], dphi[1::2] = c, -s
        dphi *= self._d
        d2psi = np.empty(2 * self.harmonics)
        d2psi[0::2], d2psi[1::2] = s, c
        d2psi *= self._d**2
        w2 = omega_m * omega_m
        return (dphi * omega_m, dphi * alpha_m - d2psi * w2, self._sigma2 * w2,
                self._sigma2 * alpha_m * alpha_m + self._sigma4 * w2 * w2)

    def update(self, theta_m: float, omega_m: float, alpha_m: float) -> tuple[float, float]:
        """Feed one TSA sample; return ``(omega_r_hat, alpha_r_hat)``.

        Parameters
        ----------
        theta_m, omega_m, alpha_m : float
            TSA angle (rad), speed (rad/s) and acceleration (rad/s^2), (5.1), (5.4), (5.5).
        """
        if self._cfg is not None:
            three_stage_update(self._cfg, self._state, self._out, theta_m, omega_m, alpha_m)
            return float(self._out[0]), float(self._out[1])
        phi_w, phi_a, nw, na = self.regressors(theta_m, omega_m, alpha_m)
        if self._detrend is None:
            self._rls_w.step(phi_w, nw, self._hp_w(omega_m))
            self._rls_a.step(phi_a, na, self._hp_a(alpha_m))
        elif (centre := self._detrend(theta_m, omega_m, alpha_m)) is not None:
            th, w, a, zeta_w, zeta_a = centre
            cw, ca, cnw, cna = self.regressors(th, w, a)
            self._rls_w.step(cw, cnw, zeta_w)
            self._rls_a.step(ca, cna, zeta_a)
        return (omega_m - float(phi_w @ self._rls_w.theta), alpha_m - float(phi_a @ self._rls_a.theta))

    def run(self, theta_m: npt.ArrayLike, omega_m: npt.ArrayLike, alpha_m: npt.ArrayLike) -> tuple[Array, Array]:
        """Feed the samples in order (as :meth:`update` one at a time); return the compensated series.

        Parameters
        ----------
        theta_m, omega_m, alpha_m : array_like
            TSA samples of equal length, all finite (the valid samples of a :class:`TsaEstimate`).
        """
        th, om, al = (np.asarray(v, dtype=float).ravel() for v in (theta_m, omega_m, alpha_m))
        if not th.size == om.size == al.size:
            raise SimulationError(f"theta_m, omega_m and alpha_m have {th.size}, {om.size} and {al.size} samples; "
                                  "give one of each per sample")
        if self._cfg is not None:
            return three_stage_run(self._cfg, self._state, th, om, al)
        out = np.array([self.update(a, b, c) for a, b, c in zip(th.tolist(), om.tolist(), al.tolist())])
        return out.reshape(-1, 2)[:, 0].copy(), out.reshape(-1, 2)[:, 1].copy()


class NotchFilter:
    """Second-order notch ``(s^2 + w0^2) / (s^2 + 2 xi w0 s + w0^2)`` with a time-varying centre.

    Realised as ``u`` minus a state-variable band-pass whose states are scaled
    by ``w0`` (their equilibrium for a constant input does not depend on
    ``w0``, so a centre that follows the noisy measured speed does not inject
    errors), discretised by the trapezoidal rule with the centre pre-warped so
    that the notch sits exactly on ``w0`` at every sample.

    Parameters
    ----------
    dt_s : float
        Sample period (s).
    damping : float
        Damping ratio ``xi`` in (0, 1) (seed 001, Section 6.3: 0.5).
    """

    def __init__(self, *, dt_s: float = 1e-3, damping: float = 0.5) -> None:
        self.dt_s = check_positive(dt_s, "dt_s")
        self.damping = check_range(damping, "damping", 0.0, 1.0)
        if self.damping in (0.0, 1.0):
            raise SimulationError(f"damping must lie strictly between 0 and 1, got {damping!r}")
        self._z1 = self._z2 = 0.0
        self._u: float | None = None

    def run(self, u: npt.ArrayLike, centre_rad_s: npt.ArrayLike, *, compiled: bool | None = None) -> Array:
        """:meth:`update` over the samples ``u`` with the centres ``centre_rad_s`` (equal lengths), the filter's
        state carried on: a series filtered in pieces equals it filtered at once.

        ``compiled`` as in :class:`ThreeStageEstimator`: the C port gives the same numbers bit for bit.
        """
        uu, cc = np.asarray(u, dtype=float).ravel(), np.asarray(centre_rad_s, dtype=float).ravel()
        if uu.size != cc.size:
            raise SimulationError(f"u has {uu.size} samples and centre_rad_s {cc.size}; give one centre per sample")
        if not use_kernels(compiled):
            return np.array([self.update(a, b) for a, b in zip(uu.tolist(), cc.tolist())], dtype=float)
        # the kernel's state is this filter's, handed over and back (the same floats)
        state = np.array([0.0 if self._u is None else 1.0, self._z1, self._z2, 0.0 if self._u is None else self._u])
        out = notch_run(self.dt_s, self.damping, uu, cc, state)
        if state[0] != 0.0:
            self._z1, self._z2, self._u = float(state[1]), float(state[2]), float(state[3])
        return out

    def update(self, u: float, center_rad_s: float) -> float:
        """Filter one sample ``u`` with the notch centred at ``center_rad_s`` (rad/s)."""
        # pre-warped centre times half the step; the clamp keeps tan finite near Nyquist
        g = math.tan(min(abs(center_rad_s) * self.dt_s / 2.0, 1.5))
        if self._u is None:
            self._z1, self._z2, self._u = u, 0.0, u
        # z1' = w z2,  z2' = w (u - z1 - 2 xi z2),  y = u - 2 xi z2
        xi2 = 2.0 * self.damping
        r1 = self._z1 + g * self._z2
        r2 = self._z2 + g * (self._u + u - self._z1 - xi2 * self._z2)
        det = 1.0 + xi2 * g + g * g
        self._z1 = ((1.0 + xi2 * g) * r1 + g * r2) / det
        self._z2 = (r2 - g * r1) / det
        self._u = u
        return u - xi2 * self._z2


def _dt(tsa: TsaEstimate) -> float:
    if tsa.t.size < 2:
        raise SimulationError("an estimator needs at least two controller samples")
    steps = np.diff(tsa.t)
    dt = float(np.median(steps))
    if np.max(np.abs(steps - dt)) > 1e-6 * dt:
        raise SimulationError("the controller samples must be uniformly spaced")
    return dt


def three_stage(
    tsa: TsaEstimate,
    *,
    harmonics: int = 5,
    kappa: float = 1.0,
    beta: float = 0.1,
    gamma0: float | Sequence[float] = 1e5,
    highpass_hz: float | None = None,
    compiled: bool | None = None,
) -> SpeedEstimate:
    """Run the three-stage estimator over a TSA record (seed 001, Fig. 6.2).

    Parameters are those of :class:`ThreeStageEstimator`; the sample period is
    read from ``tsa.t``.  Samples without a TSA value stay NaN.

    Examples
    --------
    >>> from switchobs.sensors import Encoder, constant_speed, time_stamping, controller_times
    >>> ev = Encoder(ppr=60, eccentricity=0.004).events(constant_speed(1020, 3.0))
    >>> tsa = time_stamping(ev.times, ev.angles, controller_times(0.0, 3.0, 1000.0))
    >>> est = three_stage(tsa, harmonics=5)
    >>> late = slice(2000, None)  # after two seconds: the eccentricity ripple is gone
    >>> bool(np.std(est.omega[late]) < 0.2 * np.std(tsa.omega[late]))
    True
    """
    est = ThreeStageEstimator(harmonics, dt_s=_dt(tsa), kappa=kappa, beta=beta, gamma0=gamma0,
                              highpass_hz=highpass_hz, compiled=compiled)
    om, al = np.full(tsa.t.size, np.nan), np.full(tsa.t.size, np.nan)
    ok = tsa.valid
    om[ok], al[ok] = est.run(tsa.theta[ok], tsa.omega[ok], tsa.alpha[ok])
    return SpeedEstimate(t=tsa.t, omega=om, alpha=al, method="three-stage")


def notch(tsa: TsaEstimate, *, damping: float = 0.5, compiled: bool | None = None) -> SpeedEstimate:
    """Notch-filter baseline: TSA speed and acceleration through a notch tuned to ``omega_m``.

    The centre follows the measured speed, i.e. the wheel's revolution
    frequency in rad/s (dynamic notch of seed 001, Section 6.3).  ``compiled``
    as in :class:`ThreeStageEstimator`; here the C port gives the same numbers bit for bit.
    """
    dt = _dt(tsa)
    om, al = np.full(tsa.t.size, np.nan), np.full(tsa.t.size, np.nan)
    ok = tsa.valid
    om[ok], al[ok] = (notch_series(tsa.omega[ok], tsa.omega[ok], dt_s=dt, damping=damping, compiled=compiled),
                      notch_series(tsa.alpha[ok], tsa.omega[ok], dt_s=dt, damping=damping, compiled=compiled))
    return SpeedEstimate(t=tsa.t, omega=om, alpha=al, method="notch")


def notch_series(u: npt.ArrayLike, centre_rad_s: npt.ArrayLike, *, dt_s: float, damping: float = 0.5,
                 compiled: bool | None = None) -> Array:
    """A fresh :class:`NotchFilter` over the samples ``u``, centred at ``centre_rad_s`` at each (equal lengths).

    ``compiled`` as in :class:`ThreeStageEstimator`: the C port gives the same numbers bit for bit.
    """
    return NotchFilter(dt_s=dt_s, damping=damping).run(u, centre_rad_s, compiled=compiled)
