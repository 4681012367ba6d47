"""Tyre stiffness and effective radius from the equivalent output injections of the two sliding-mode observers.

Seed 003, Sections IV-V.  After the observer has converged, the low-pass
filtered injection ``z2_bar`` equals the unknown part of the wheel
acceleration, (20) and (25).  With the quarter car of seed 001 (2.1) and the
linear tyre ``F_x = C_x (R omega - v) / v`` (seed 003 (5), sign re-derived,
see :mod:`switchobs.sensors._quarter_car`)::

    xi1 = -R F_x / J = theta_11 / J - theta_12 omega / (J v),
    theta_1 = [R C_x, R^2 C_x],   phi_1 = [1 / J, -omega / (J v)]

(seed 003 (22)-(23) print ``phi_1 = [-1/J, x2/(J x3)]`` and ``theta_1 = [R C_x, R C_x]``:
the first is the sign of its (5), the second an extraction slip, since
``xi1`` in (7) carries ``R^2 C_x``).  ``R = theta_12 / theta_11`` when both
are identified; with a known radius the single parameter ``R C_x`` multiplies
``(1 - R omega / v) / J = -lambda / J``.

Section V-B does the same with the filtered injection ``z3_bar`` of the vehicle-speed observer
(:mod:`switchobs.sensors._vehicle_speed`), (21) and (26)::

    xi2 = F_x / m = -theta_21 / m + theta_22 omega / (m v),
    theta_2 = [C_x, R C_x],   phi_2 = [-1 / m, omega / (m v)]

(the seed prints ``phi_2 = [1/m, -x2/(m x3)]``, the sign of its (5) again), by the same RLS.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from .._json import JsonRecord, array_to_json
from ..exceptions import SimulationError
from ._super_twisting import low_pass
from ._validate import as_signal, check_increasing, check_positive, check_range

__all__ = ["StiffnessEstimate", "identify_stiffness", "SpeedParameterEstimate", "identify_speed_parameters"]

Array = npt.NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class StiffnessEstimate(JsonRecord, error=SimulationError):
    """Result of the RLS identification (27)-(30).

    Attributes
    ----------
    t : ndarray
        Times of the RLS updates (s).
    history : ndarray, shape (len(t), p)
        Estimates after each update: ``[R C_x, R^2 C_x]`` (``p = 2``) or ``[R C_x]``
        (``p = 1``, radius given).
    given_radius_m : float or None
        The radius supplied by the user, if any.
    """

    t: Array
    history: Array
    given_radius_m: float | None

    @property
    def stiffness_radius(self) -> float:
        """Identified ``R C_x`` (N m)."""
        return float(self.history[-1, 0])

    @property
    def radius_m(self) -> float:
        """Given radius, or the identified ``theta_12 / theta_11`` (m)."""
        if self.given_radius_m is not None:
            return self.given_radius_m
        return float(self.history[-1, 1] / self.history[-1, 0])

    @property
    def stiffness_n(self) -> float:
        """Longitudinal stiffness ``C_x = (R C_x) / R`` (N per unit slip)."""
        return self.stiffness_radius / self.radius_m

    def to_json(self, *, arrays: bool = False) -> dict[str, Any]:
        """The identified figures (with the update times and the estimate history if ``arrays``)."""
        out: dict[str, Any] = {"stiffness_radius_nm": self.stiffness_radius, "radius_m": self.radius_m,
                               "radius_identified": self.given_radius_m is None, "stiffness_n": self.stiffness_n,
                               "updates": int(self.t.size), "given_radius_m": self.given_radius_m}
        if arrays:
            out.update(t=array_to_json(self.t), history=array_to_json(self.history))
        return out

    def __str__(self) -> str:
        how = "identified" if self.given_radius_m is None else "given"
        return (f"StiffnessEstimate: R C_x = {self.stiffness_radius:.6g} N m, R = {self.radius_m:.5g} m ({how}), "
                f"C_x = {self.stiffness_n:.6g} N after {self.t.size} RLS updates")


def identify_stiffness(
    t: npt.ArrayLike,
    z2: npt.ArrayLike,
    omega_hat: npt.ArrayLike,
    speed_m_s: npt.ArrayLike,
    *,
    inertia_kg_m2: float,
    radius_m: float | None = None,
    tau_s: float = 0.01,
    start_s: float = 0.0,
    forgetting: float = 1.0,
    rho: float = 1e-8,
    nominal: npt.ArrayLike | None = None,
    rls_step_s: float = 1e-3,
) -> StiffnessEstimate:
    """Identify ``R C_x`` (and ``R``) from the super-twisting injection by recursive least squares.

    Parameters
    ----------
    t : array_like
        Uniform observer sample times (s).
    z2 : array_like
        Injection ``z2 = alpha sign(x1 - x1_hat)`` of the discrete observer.
    omega_hat : array_like
        Observer speed ``x2_hat`` (rad/s), used in the regressor in place of ``x2``.
    speed_m_s : array_like
        Measured vehicle speed ``v_x = x3`` (m/s), positive.
    inertia_kg_m2 : float
        Wheel inertia ``J`` (assumed known, as in seed 003 Section V).
    radius_m : float, optional
        Known effective radius; omit it to identify ``R`` as well.
    tau_s : float
        Time constant of the low-pass filter extracting the equivalent
        injection (20).  The regressor passes through the same filter, so the
        filter delay cancels in the regression (``theta`` is constant).
    start_s : float
        First time used (after the observer's finite-time transient).
    forgetting : float
        Forgetting factor ``sigma`` in [0.9, 1] of (29)-(30).
    rho : float
        ``Gamma_0 = I / rho``.
    nominal : array_like, optional
        Nominal ``theta_1_bar`` used inside the observer (24); the identified
        value is ``nominal + Delta theta``.  Default zero.
    rls_step_s : float
        Period of the RLS updates (s): the filtered signals vary on the scale
        of ``tau_s``, so updating at every observer step adds cost, not information.

    Returns
    -------
    StiffnessEstimate

    Raises
    ------
    SimulationError
        Bad lengths, NaN samples, non-positive speed, ``forgetting`` outside
        [0.9, 1], or no sample after ``start_s``.

    Notes
    -----
    (29)-(30) are used in their discrete form (seed 003, Remark 3)::

        K = Gamma phi / (sigma + phi' Gamma phi),  theta += K (h - phi' theta),
        Gamma = (Gamma - K phi' Gamma) / sigma.
    """
    tt = as_signal(t, "t")
    check_increasing(tt, "t")
    z = as_signal(z2, "z2", length=tt.size)
    w = as_signal(omega_hat, "omega_hat", length=tt.size)
    v = as_signal(speed_m_s, "speed_m_s", length=tt.size)
    if np.any(v <= 0.0):
        raise SimulationError(f"speed_m_s must stay positive (seed 003 divides by x3), min is {v.min():g}")
    J = check_positive(inertia_kg_m2, "inertia_kg_m2")
    if radius_m is None:
        phi = np.column_stack([np.full(tt.size, 1.0 / J), -w / (J * v)])
        given = None
    else:
        given = check_positive(radius_m, "radius_m")
        phi = ((1.0 - given * w / v) / J)[:, None]
    theta_bar = np.zeros(phi.shape[1]) if nominal is None else as_signal(nominal, "nominal", length=phi.shape[1])
    used, hist = _filtered_rls(tt, z, phi, tau_s=tau_s, start_s=start_s, forgetting=forgetting, rho=rho,
                              rls_step_s=rls_step_s, what="identify_stiffness")
    return StiffnessEstimate(t=used, history=hist + theta_bar, given_radius_m=given)


def _filtered_rls(
    t: Array,
    h: Array,
    phi: Array,
    *,
    tau_s: float,
    start_s: float,
    forgetting: float,
    rho: float,
    rls_step_s: float,
    initial: Array | None = None,
    what: str,
) -> tuple[Array, Array]:
    """The RLS of seed 003 (27)-(30) on the low-pass filtered injection ``h`` and regressor ``phi``.

    Shared by the identification of ``theta_1`` from ``z2`` (:func:`identify_stiffness`, Section V-A) and of
    ``theta_2`` from ``z3`` (:func:`identify_speed_parameters`, Section V-B): the seed
    applies "the same" least squares to both.  ``h`` and every column of ``phi`` pass through the first-order
    low-pass of time constant ``tau_s`` (Section IV), the RLS updates every ``rls_step_s`` from ``start_s``,
    starting from ``initial`` (default zero) with ``Gamma_0 = I / rho``.

    Returns
    -------
    (t_used, history) : the update times and the estimate after each update, shape ``(len(t_used), p)``.
    """
    sigma = check_range(forgetting, "forgetting (sigma)", 0.9, 1.0)
    rho = check_positive(rho, "rho")
    dt = float(t[1] - t[0]) if t.size > 1 else 0.0
    if t.size < 2 or np.max(np.abs(np.diff(t) - dt)) > 1e-6 * dt:
        raise SimulationError(f"{what} needs uniformly spaced samples (at least two)")
    p = phi.shape[1]
    zbar = low_pass(h, dt, tau_s)
    phibar = np.column_stack([low_pass(phi[:, j], dt, tau_s) for j in range(p)])
    every = max(1, int(round(check_positive(rls_step_s, "rls_step_s") / dt)))
    use = np.flatnonzero(t >= start_s)[::every]
    if use.size == 0:
        raise SimulationError(f"no sample at or after start_s = {start_s:g} s (last is {t[-1]:g} s)")
    est = np.zeros(p) if initial is None else np.array(initial, dtype=float)
    gamma = np.eye(p) / rho
    hist = np.empty((use.size, p))
    for row, i in enumerate(use):
        f = phibar[i]
        gf = gamma @ f
        gain = gf / (sigma + float(f @ gf))
        est = est + gain * (zbar[i] - float(f @ est))
        gamma = (gamma - np.outer(gain, gf)) / sigma
        hist[row] = est
    return t[use], hist


@dataclass(frozen=True, eq=False)
class SpeedParameterEstimate(JsonRecord, error=SimulationError):
    """Result of the RLS identification of ``theta_2 = [C_x, R C_x]`` from ``z3_bar`` (seed 003 Sec. V-B).

    Attributes
    ----------
    t : ndarray
        Times of the RLS updates (s).
    history : ndarray, shape (len(t), p)
        Estimates after each update: ``[C_x, R C_x]`` (``p = 2``, Remark 5) or ``[C_x]`` (``p = 1``,
        ``theta_22 = R C_x`` given, Remark 4).
    given_stiffness_radius_nm : float or None
        The ``R C_x`` supplied (Remark 4), if any.
    """

    t: Array
    history: Array
    given_stiffness_radius_nm: float | None

    @property
    def stiffness_n(self) -> float:
        """Identified ``theta_21 = C_x`` (N per unit slip)."""
        return float(self.history[-1, 0])

    @property
    def stiffness_radius(self) -> float:
        """Given ``R C_x``, or the identified ``theta_22`` (N m)."""
        if self.given_stiffness_radius_nm is not None:
            return self.given_stiffness_radius_nm
        return float(self.history[-1, 1])

    @property
    def radius_m(self) -> float:
        """``R = theta_22 / theta_21`` (m)."""
        return self.stiffness_radius / self.stiffness_n

    def to_json(self, *, arrays: bool = False) -> dict[str, Any]:
        """The identified figures (with the update times and the estimate history if ``arrays``)."""
        out: dict[str, Any] = {"stiffness_n": self.stiffness_n, "stiffness_radius_nm": self.stiffness_radius,
                               "radius_m": self.radius_m, "updates": int(self.t.size),
                               "given_stiffness_radius_nm": self.given_stiffness_radius_nm}
        if arrays:
            out.update(t=array_to_json(self.t), history=array_to_json(self.history))
        return out

    def __str__(self) -> str:
        how = "identified" if self.given_stiffness_radius_nm is None else "given"
        return (f"SpeedParameterEstimate: C_x = {self.stiffness_n:.6g} N, R C_x = {self.stiffness_radius:.6g} N m "
                f"({how}), R = {self.radius_m:.5g} m after {self.t.size} RLS updates")


def identify_speed_parameters(
    t: npt.ArrayLike,
    z3: npt.ArrayLike,
    omega_hat: npt.ArrayLike,
    speed_m_s: npt.ArrayLike,
    *,
    mass_kg: float,
    stiffness_radius_nm: float | None = None,
    initial: npt.ArrayLike | None = None,
    tau_s: float = 0.01,
    start_s: float = 0.0,
    forgetting: float = 1.0,
    rho: float = 1e-12,
    rls_step_s: float = 1e-3,
) -> SpeedParameterEstimate:
    """Identify ``theta_2 = [C_x, R C_x]`` from the vehicle-speed injection ``z3`` by the RLS of ``theta_1``.

    Parameters
    ----------
    t : array_like
        Uniform observer sample times (s).
    z3 : array_like
        Injection ``z3 = beta sign(x3 - x3_hat)`` of the discrete observer (15).
    omega_hat : array_like
        Wheel speed ``x2_hat`` of the super-twisting observer (rad/s), in the regressor in place of ``x2``.
    speed_m_s : array_like
        Measured vehicle speed ``x3`` (m/s), positive.
    mass_kg : float
        Vehicle (quarter) mass ``m``, assumed known as in seed 003 Section V.
    stiffness_radius_nm : float, optional
        ``theta_22 = R C_x`` "known or already estimated" (Remark 4, e.g. the ``R C_x`` of
        :func:`identify_stiffness`): only ``C_x`` is identified.  Omit it to identify both (Remark 5).
    initial : array_like, optional
        Initial RLS estimate ``[C_x, R C_x]`` (``[C_x]`` with Remark 4); Remark 5 starts from "the value
        produced by the previous step", the ``theta_1`` identification.  Default zero.
    tau_s, start_s, forgetting, rls_step_s
        As in :func:`identify_stiffness` (the same filter and RLS).
    rho : float
        ``Gamma_0 = I / rho``; smaller than for ``theta_1`` because ``phi_2`` scales as ``1 / m``.

    Returns
    -------
    SpeedParameterEstimate

    Raises
    ------
    SimulationError
        Bad lengths, NaN samples, non-positive speed or mass, ``forgetting`` outside [0.9, 1], or no sample
        after ``start_s``.

    References
    ----------
    Seed 003, (21), (22)-(23), (26), (27)-(30); Section V-B, Remarks 4-5.
    """
    tt = as_signal(t, "t")
    check_increasing(tt, "t")
    z = as_signal(z3, "z3", length=tt.size)
    w = as_signal(omega_hat, "omega_hat", length=tt.size)
    v = as_signal(speed_m_s, "speed_m_s", length=tt.size)
    if np.any(v <= 0.0):
        raise SimulationError(f"speed_m_s must stay positive (seed 003 divides by x3), min is {v.min():g}")
    m = check_positive(mass_kg, "mass_kg")
    ratio = w / (m * v)
    if stiffness_radius_nm is None:
        given, h, phi = None, z, np.column_stack([np.full(tt.size, -1.0 / m), ratio])
    else:
        # Remark 4: the known term theta_22 omega / (m v) moves to the left; the filter is linear
        given = check_positive(stiffness_radius_nm, "stiffness_radius_nm")
        h, phi = z - given * ratio, np.full((tt.size, 1), -1.0 / m)
    start = None if initial is None else as_signal(initial, "initial", length=phi.shape[1])
    used, hist = _filtered_rls(tt, h, phi, tau_s=tau_s, start_s=start_s, forgetting=forgetting, rho=rho,
                               rls_step_s=rls_step_s, initial=start, what="identify_speed_parameters")
    return SpeedParameterEstimate(t=used, history=hist, given_stiffness_radius_nm=given)
