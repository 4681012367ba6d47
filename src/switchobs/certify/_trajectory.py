"""Trajectory conditions of the singular time-rescaling (Assumption 1) and Theorem 3's constants.

Sampled signals are taken as piecewise linear between samples, so that
``tau(t) = ∫ |s| dt`` and the windowed energies ``∫ y^2`` are integrated
exactly for that interpolant (zero crossings inside a step are split out).

* Persistency of excitation, seed 004 eq. (6) / seed 001 eq. (3.17):
  ``mu0 = min_t ∫_t^{t+T0} y^2`` (and the same for ``s``).
* Zero crossings with transversality, seed 001 eq. (3.18): the sign changes of
  ``y``, each with its slope; a sample exactly at 0 without a sign change is a
  tangency (slope 0), which violates (3.18).
* Dwell time, seed 004 eq. (7) / seed 001 eq. (3.19): ``T_D`` is the smallest
  gap between consecutive crossings; ``tau_D`` the corresponding smallest
  increase of ``tau`` (seed 001 Sec. 3.2.2: a dwell time in ``t`` gives one in ``tau``).
* Persistency of excitation of the adaptive observer's regressor, seed 001
  eq. (3.7) and Fig. 3.1: the eigenvalues of ``∫_t^{t+T1} Psi' Psi``.
* Admissible controllers, seed 004 Theorem 3: ``a0, d0, s0, b0`` and
  ``alpha = s0 (a0 + d0) / b0`` on ``Sigma = Omega ∩ {|Cz| <= eps}``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import sympy as sp

from .._json import JsonRecord
from ..exceptions import DimensionError, ModelError, SimulationError
from ..model import Model

__all__ = ["ZeroCrossing", "TrajectoryReport", "time_rescaling", "windowed_energy", "pe_level",
           "zero_crossings", "regressor_excitation", "trajectory_conditions", "AdmissibleConstants",
           "admissible_constants"]


def _signal(t: np.ndarray, x: Any, name: str) -> np.ndarray:
    arr = np.asarray(x, dtype=float)
    if arr.shape != t.shape:
        raise DimensionError(f"{name} has shape {arr.shape} but t has shape {t.shape}; give one sample per time")
    if not np.all(np.isfinite(arr)):
        bad = int(np.flatnonzero(~np.isfinite(arr))[0])
        raise SimulationError(f"{name} is not finite at sample {bad} (t = {t[bad]:.6g}): {arr[bad]}")
    return arr


def _time(t: Any) -> np.ndarray:
    tt = np.asarray(t, dtype=float)
    if tt.ndim != 1 or tt.size < 2:
        raise DimensionError(f"t must be a 1-D array of at least 2 samples, got shape {tt.shape}")
    if not np.all(np.isfinite(tt)):
        raise SimulationError("t holds non-finite values")
    steps = np.diff(tt)
    if np.any(steps <= 0):
        k = int(np.flatnonzero(steps <= 0)[0])
        raise SimulationError(f"t must increase strictly; t[{k}] = {tt[k]:.6g} >= t[{k + 1}] = {tt[k + 1]:.6g}")
    return tt


def time_rescaling(t: Any, s: Any) -> np.ndarray:
    """``tau(t) = ∫_0^t |s| dt`` for a piecewise-linear ``s`` (seed 004; seed 001 eq. (3.12)-(3.13)).

    On a step where ``s`` changes sign the two triangles are integrated
    separately: ``dt (s_a^2 + s_b^2) / (2 |s_b - s_a|)``.

    Examples
    --------
    >>> float(time_rescaling([0, 1, 2], [1, -1, -1])[-1])
    1.5
    """
    tt = _time(t)
    ss = _signal(tt, s, "s")
    a, b, dt = ss[:-1], ss[1:], np.diff(tt)
    same = a * b >= 0
    inc = np.where(same, dt * np.abs(a + b) / 2,
                   dt * (a * a + b * b) / (2 * np.where(same, 1.0, np.abs(b - a))))
    return np.concatenate([[0.0], np.cumsum(inc)])


def _cumulative_square(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    a, b, dt = y[:-1], y[1:], np.diff(t)
    return np.concatenate([[0.0], np.cumsum(dt * (a * a + a * b + b * b) / 3)])


def windowed_energy(t: Any, y: Any, window: float) -> tuple[np.ndarray, np.ndarray]:
    """``(starts, E)`` with ``E[k] = ∫_{t_k}^{t_k + window} y^2`` for every start with a full window."""
    tt = _time(t)
    yy = _signal(tt, y, "y")
    if not window > 0 or window > tt[-1] - tt[0]:
        raise SimulationError(f"window {window} must be positive and at most the record length {tt[-1] - tt[0]:.6g}")
    F = _cumulative_square(tt, yy)
    starts = tt[tt + window <= tt[-1] + 1e-12 * max(1.0, abs(tt[-1]))]
    return starts, np.interp(starts + window, tt, F) - np.interp(starts, tt, F)


def pe_level(t: Any, y: Any, window: float) -> float:
    """``mu0 = min_t ∫_t^{t+T0} y^2`` (seed 004 eq. (6), seed 001 eq. (3.17)); positive means PE on the record."""
    return float(np.min(windowed_energy(t, y, window)[1]))


@dataclass(frozen=True)
class ZeroCrossing(JsonRecord, error=SimulationError):
    """A zero of the output: time, slope ``dy/dt`` there, and the rescaled time ``tau``."""

    t: float
    slope: float
    tau: float

    def to_json(self) -> dict[str, float]:
        return {"t": self.t, "slope": self.slope, "tau": self.tau}


def zero_crossings(t: Any, y: Any, tau: Any | None = None) -> tuple[ZeroCrossing, ...]:
    """Sign changes of ``y`` (linear interpolation) with their slopes (seed 001 eq. (3.18)).

    A sample exactly at zero between samples of one sign is a tangency and is
    reported with slope 0.
    """
    tt = _time(t)
    yy = _signal(tt, y, "y")
    tau_arr = np.zeros_like(tt) if tau is None else _signal(tt, tau, "tau")
    out: list[ZeroCrossing] = []
    sign = np.sign(yy)
    n = len(tt)
    # a scan over the samples in which only sign changes and zeros act: visit those indices alone
    crossing = (sign[:-1] != 0) & (sign[1:] != 0) & (sign[:-1] != sign[1:])
    zero = sign[1:] == 0
    zero[-1:] = False                      # a zero at the last sample ends the record, not a run
    k = 0
    for active in np.flatnonzero(crossing | zero).tolist():
        if active < k:
            continue                       # inside a run of zeros already handled
        k = active
        if crossing[k]:
            frac = yy[k] / (yy[k] - yy[k + 1])
            tc = tt[k] + frac * (tt[k + 1] - tt[k])
            slope = (yy[k + 1] - yy[k]) / (tt[k + 1] - tt[k])
            out.append(ZeroCrossing(float(tc), float(slope), float(tau_arr[k] + frac * (tau_arr[k + 1] - tau_arr[k]))))
            k += 1
            continue
        # a run of zeros after k: a crossing through zero or a tangency
        j = k + 1
        while j < n - 1 and sign[j] == 0:
            j += 1
        before, after = sign[k], sign[j]
        if before != 0 and after != 0 and before != after and j == k + 2:
            slope = (yy[j] - yy[k]) / (tt[j] - tt[k])
        else:
            slope = 0.0
        if before != 0 or after != 0:
            out.append(ZeroCrossing(float(tt[k + 1]), float(slope), float(tau_arr[k + 1])))
        k = j
    return tuple(out)


def regressor_excitation(t: Any, psi: Any, window: float) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues of ``∫_t^{t+T1} Psi' Psi`` over the record (seed 001 eq. (3.7), Fig. 3.1).

    Parameters
    ----------
    t : (N,) array
    psi : (N, p, q) array, the regressor ``Psi(t)`` (a (N, q) array is one row)
    window : float, ``T1``

    Returns
    -------
    starts : (M,) array
    eigenvalues : (M, q) array, ascending; ``min(eigenvalues[:, 0])`` is ``mu1``.
    """
    tt = _time(t)
    P = np.asarray(psi, dtype=float)
    if P.ndim == 2:
        P = P[:, None, :]
    if P.ndim != 3 or P.shape[0] != tt.size:
        raise DimensionError(f"psi must have shape (N, p, q) with N = {tt.size}, got {np.asarray(psi).shape}")
    if not np.all(np.isfinite(P)):
        raise SimulationError("psi holds non-finite values")
    G = np.einsum("kpi,kpj->kij", P, P)
    # trapezoid on Psi'Psi (products of linear interpolants are not linear; the error is O(dt^2))
    incr = 0.5 * (G[1:] + G[:-1]) * np.diff(tt)[:, None, None]
    cum = np.concatenate([np.zeros((1,) + G.shape[1:]), np.cumsum(incr, axis=0)])
    if not window > 0 or window > tt[-1] - tt[0]:
        raise SimulationError(f"window {window} must be positive and at most the record length {tt[-1] - tt[0]:.6g}")
    starts = tt[tt + window <= tt[-1] + 1e-12 * max(1.0, abs(tt[-1]))]
    q = G.shape[1]
    W = np.empty((starts.size, q, q))
    for i in range(q):
        for j in range(q):
            W[:, i, j] = np.interp(starts + window, tt, cum[:, i, j]) - np.interp(starts, tt, cum[:, i, j])
    return starts, np.linalg.eigvalsh(W)


@dataclass(frozen=True)
class TrajectoryReport(JsonRecord, error=SimulationError):
    """Assumption 1 (seed 001 (3.17)-(3.19), seed 004 (6)-(7)) measured on a record.

    Attributes
    ----------
    duration : float
    tau_final : float
        ``tau`` at the end of the record.
    pe_window : float
        ``T0``.
    pe_level_y : float
        ``min ∫ y^2`` over windows of length ``T0`` (seed 001 (3.17)).
    pe_level_s : float
        ``min ∫ s^2`` over the same windows (seed 004 (6)).
    crossings : tuple of ZeroCrossing
    min_abs_slope : float
        Smallest ``|dy/dt|`` at a crossing (transversality (3.18); 0 for a tangency).
    dwell_time_t, dwell_time_tau : float
        Smallest gap between consecutive crossings in ``t`` (3.19) and in ``tau``
        (``inf`` with fewer than two crossings).
    psi_pe_window, psi_pe_level : float or None
        ``T1`` and ``min lambda_min(∫ Psi' Psi)`` (seed 001 (3.7), Fig. 3.1).
    """

    duration: float
    tau_final: float
    pe_window: float
    pe_level_y: float
    pe_level_s: float
    crossings: tuple[ZeroCrossing, ...]
    min_abs_slope: float
    dwell_time_t: float
    dwell_time_tau: float
    psi_pe_window: float | None = None
    psi_pe_level: float | None = None

    @property
    def transversal(self) -> bool:
        return self.min_abs_slope > 0

    def satisfies(self, *, mu0: float = 0.0, T_D: float = 0.0) -> bool:
        """Assumption 1 on this record with the given constants (strict PE and dwell inequalities)."""
        return self.pe_level_y > mu0 and self.transversal and self.dwell_time_t >= T_D and self.dwell_time_t > 0

    def to_json(self) -> dict[str, Any]:
        return {"duration": self.duration, "tau_final": self.tau_final, "pe_window": self.pe_window,
                "pe_level_y": self.pe_level_y, "pe_level_s": self.pe_level_s,
                "crossings": [c.to_json() for c in self.crossings], "min_abs_slope": self.min_abs_slope,
                "transversal": self.transversal, "dwell_time_t": self.dwell_time_t,
                "dwell_time_tau": self.dwell_time_tau, "psi_pe_window": self.psi_pe_window,
                "psi_pe_level": self.psi_pe_level}

    def __str__(self) -> str:
        lines = [f"trajectory conditions over {self.duration:.6g} s (tau reaches {self.tau_final:.6g}):",
                 f"  PE (3.17): min over windows of {self.pe_window:g} s of ∫y^2 = {self.pe_level_y:.6g}, "
                 f"of ∫s^2 = {self.pe_level_s:.6g}",
                 f"  {len(self.crossings)} zero crossings, smallest |dy/dt| = {self.min_abs_slope:.6g} "
                 f"({'transversal' if self.transversal else 'NOT transversal'}, (3.18))",
                 f"  dwell time (3.19): T_D = {self.dwell_time_t:.6g} s, in tau: {self.dwell_time_tau:.6g}"]
        if self.psi_pe_level is not None:
            lines.append(f"  regressor PE (3.7): min eigenvalue of ∫Psi'Psi over {self.psi_pe_window:g} s = "
                         f"{self.psi_pe_level:.6g}")
        return "\n".join(lines)


def trajectory_conditions(t: Any, y: Any, *, window: float, s: Any | None = None, vx: Any | None = None,
                          psi: Any | None = None, psi_window: float | None = None) -> TrajectoryReport:
    """Measure Assumption 1 on sampled signals.

    Parameters
    ----------
    t : (N,) array, strictly increasing times [s]
    y : (N,) array, the output (wheel-acceleration offset for the ABS models)
    window : float
        PE window ``T0`` [s].
    s : (N,) array, optional
        Time scale ``s(y, t)``; default ``y / vx`` if ``vx`` is given, else ``y``.
    vx : (N,) array, optional
        Vehicle speed [m/s] (must be positive).
    psi : (N, p, q) array, optional
        Regressor of the adaptive observer (seed 001 eq. (3.2)).
    psi_window : float, optional
        ``T1`` (default ``window``).

    Returns
    -------
    TrajectoryReport

    Raises
    ------
    DimensionError, SimulationError

    Examples
    --------
    >>> t = np.linspace(0, 10, 2001)
    >>> r = trajectory_conditions(t, np.sin(t), window=2 * np.pi)
    >>> round(r.dwell_time_t, 3), len(r.crossings)
    (3.142, 3)
    """
    tt = _time(t)
    yy = _signal(tt, y, "y")
    if s is None:
        if vx is not None:
            v = _signal(tt, vx, "vx")
            if np.any(v <= 0):
                k = int(np.flatnonzero(v <= 0)[0])
                raise SimulationError(f"vx must be positive; vx = {v[k]:.6g} at t = {tt[k]:.6g}")
            ss = yy / v
        else:
            ss = yy
    else:
        ss = _signal(tt, s, "s")
    tau = time_rescaling(tt, ss)
    cr = zero_crossings(tt, yy, tau)
    gaps_t = np.diff([c.t for c in cr]) if len(cr) > 1 else np.array([np.inf])
    gaps_tau = np.diff([c.tau for c in cr]) if len(cr) > 1 else np.array([np.inf])
    psi_level = None
    if psi is not None:
        psi_level = float(np.min(regressor_excitation(tt, psi, psi_window or window)[1][:, 0]))
    return TrajectoryReport(
        duration=float(tt[-1] - tt[0]), tau_final=float(tau[-1]), pe_window=float(window),
        pe_level_y=pe_level(tt, yy, window), pe_level_s=pe_level(tt, ss, window), crossings=cr,
        min_abs_slope=float(min((abs(c.slope) for c in cr), default=np.inf)),
        dwell_time_t=float(np.min(gaps_t)), dwell_time_tau=float(np.min(gaps_tau)),
        psi_pe_window=None if psi is None else float(psi_window or window), psi_pe_level=psi_level)


# ----------------------------------------------------------------- Theorem 3
@dataclass(frozen=True)
class AdmissibleConstants(JsonRecord, error=SimulationError):
    """Constants of Theorem 3 (seed 004) on ``Sigma = Omega ∩ {|Cz| <= epsilon}``.

    Attributes
    ----------
    a0, d0, s0 : float
        Maxima of ``|C A z|``, ``|C d(y)|``, ``|s(y)|`` on ``Sigma``.
    b0 : float
        Minimum of ``|C b(y)|`` on ``Sigma`` (``b_sign`` gives the sign of ``C b``:
        Theorem 3 is written for ``C b > 0``; for ``C b < 0`` read ``u`` as ``-u``).
    b1 : float
        Maximum of ``|C b(y)|`` on ``Sigma``.
    alpha : float
        ``s0 (a0 + d0) / b0``: inside the slab an admissible control has constant
        sign and ``|u| > alpha``.
    beta : float or None
        The actuator bound given (``beta > alpha``), if any.
    epsilon : float
    dwell_time_t, dwell_time_tau : float or None
        With ``beta``: lower bounds of the dwell time between zero crossings of
        ``y``: ``2 epsilon / v`` in ``t`` and
        ``2 min(∫_0^eps min|s| dy, ∫_-eps^0 min|s| dy) / v`` in ``tau``, with
        ``v = s0 (a0 + d0) + b1 beta``.  Derivation: in the slab
        ``dy/dt = s (C A z + C d) + C b u`` keeps the sign of ``C b u`` and has modulus
        at most ``v``, so after a crossing ``y`` cannot turn back inside the
        slab: it leaves it on one side and re-enters it before the next
        crossing, covering ``epsilon`` twice (``dtau = |s| dt >= |s(y)| |dy| / v``).
    b_sign : int
    """

    a0: float
    d0: float
    s0: float
    b0: float
    b1: float
    alpha: float
    beta: float | None
    epsilon: float
    dwell_time_t: float | None
    dwell_time_tau: float | None
    b_sign: int

    def to_json(self) -> dict[str, Any]:
        return {k: getattr(self, k) for k in ("a0", "d0", "s0", "b0", "b1", "alpha", "beta", "epsilon",
                                              "dwell_time_t", "dwell_time_tau", "b_sign")}

    def __str__(self) -> str:
        lines = [f"Theorem 3 constants on Sigma (|y| <= {self.epsilon:g}):",
                 f"  a0 = {self.a0:.6g}, d0 = {self.d0:.6g}, s0 = {self.s0:.6g}, b0 = {self.b0:.6g} "
                 f"(C b {'> 0' if self.b_sign > 0 else '< 0'})",
                 f"  alpha = s0 (a0 + d0) / b0 = {self.alpha:.6g}"]
        if self.beta is not None:
            lines.append(f"  beta = {self.beta:.6g}: dwell time >= {self.dwell_time_t:.6g} s in t, "
                         f">= {self.dwell_time_tau:.6g} in tau")
        else:
            lines.append("  any beta > alpha is admissible for (i)")
        return "\n".join(lines)


def _extremes_1d(f: Any, lo: float, hi: float) -> tuple[float, float]:
    """Numerical (min, max) of a scalar function on [lo, hi]: dense grid then bounded refinement."""
    import scipy.optimize  # scipy costs about 0.4 s to import: only where the trajectory analysis runs

    grid = np.linspace(lo, hi, 2001)
    vals = np.array([f(x) for x in grid], dtype=float)
    out = []
    for sgn in (1.0, -1.0):
        k = int(np.argmin(sgn * vals))
        a, b = grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]
        best = sgn * vals[k]
        if b > a:
            r = scipy.optimize.minimize_scalar(lambda x: sgn * f(x), bounds=(a, b), method="bounded")
            best = min(best, float(r.fun))
        out.append(sgn * best)
    return out[0], out[1]


def admissible_constants(model: Model, *, bounds: Mapping[str, Sequence[float]], epsilon: float,
                         beta: float | None = None) -> AdmissibleConstants:
    """Constants ``alpha`` (and the dwell-time bounds for a given ``beta``) of Theorem 3 (seed 004).

    Parameters
    ----------
    model : Model
        With numeric parameter values (use ``model.numeric()``); one input.
    bounds : mapping name -> (low, high)
        The box ``Omega`` for every state, and ranges of the external signals
        in ``s`` (e.g. ``vx``).
    epsilon : float
        Half-width of the slab ``|C z| <= epsilon``.
    beta : float, optional
        Bound on ``|u|``; must exceed ``alpha``.

    Returns
    -------
    AdmissibleConstants

    Raises
    ------
    ModelError
        Free parameters, several inputs, ``s`` depending on ``t``, ``C d`` or ``C b`` reading an external
        signal, missing bounds, or ``C b(y)`` vanishing on the slab.
    SimulationError
        Empty/inverted bounds, ``epsilon <= 0`` or ``beta <= alpha``.

    Notes
    -----
    ``a0`` is an exact linear program (``C A z`` is linear in ``z``, the set is a
    box cut by the slab); ``d0``, ``s0``, ``b0`` are maximised numerically over
    the output range (dense grid plus bounded refinement) and the external
    signals' box (its corners and a grid; ``s`` in the built-in models is
    monotone in ``vx``).

    Examples
    --------
    >>> from switchobs.model import builtin_model
    >>> m = builtin_model("abs-xbs3").numeric()
    >>> c = admissible_constants(m, bounds={"z1": (-50, 50), "z2": (-2, 30), "z3": (-400, 400),
    ...                                     "vx": (5, 40)}, epsilon=1.0)
    >>> round(c.alpha, 3)   # s0 = 1/5, a0 = a * 30, b0 = 35/8
    257.143
    """
    import scipy.integrate
    import scipy.optimize

    if len(model.inputs) != 1:
        raise ModelError(f"Theorem 3 is stated for one input; model {model.name!r} has {len(model.inputs)}")
    if model.parameters:
        raise ModelError(f"model {model.name!r} still has free parameters {list(model.parameters)}; "
                         "call model.numeric() or give the parameter values")
    if not epsilon > 0:
        raise SimulationError(f"epsilon must be positive, got {epsilon}")
    tsym = model.symbols["t"]
    signals_in_d = sorted(e for e in model.external if model.symbols[e] in (model.C * model.d)[0].free_symbols
                          | (model.C * model.b)[0].free_symbols)
    if signals_in_d:
        raise ModelError(f"C d and C b of model {model.name!r} read the external signal(s) {signals_in_d}; "
                         "Theorem 3's a0 and b0 are bounds over y alone")
    if tsym in model.time_scale.free_symbols:
        raise ModelError(f"s = {model.time_scale} depends on t; Theorem 3's s0 needs s(y) on a compact set")
    box = []
    for name in model.states:
        if name not in bounds:
            raise ModelError(f"bounds miss the state {name!r}; give (low, high) for every state of Omega")
        lo, hi = (float(v) for v in bounds[name])
        if not lo <= hi:
            raise SimulationError(f"bounds of {name!r} are inverted: ({lo}, {hi})")
        box.append((lo, hi))
    ext = {}
    ysym = model.symbols[model.output]
    for sym in model.time_scale.free_symbols - {ysym}:
        if sym.name not in bounds:
            raise ModelError(f"s = {model.time_scale} depends on {sym.name!r}; give its range in bounds")
        lo, hi = (float(v) for v in bounds[sym.name])
        if not lo <= hi:
            raise SimulationError(f"bounds of {sym.name!r} are inverted: ({lo}, {hi})")
        ext[sym] = (lo, hi)
    C = np.array([float(x) for x in model.C], dtype=float)
    CA = np.array([float(x) for x in (model.C * model.A)], dtype=float)
    # output range on Sigma
    y_lo = max(-epsilon, float(sum(min(c * lo, c * hi) for c, (lo, hi) in zip(C, box))))
    y_hi = min(epsilon, float(sum(max(c * lo, c * hi) for c, (lo, hi) in zip(C, box))))
    if y_lo > y_hi:
        raise SimulationError(f"the slab |Cz| <= {epsilon} does not meet the box Omega")
    A_ub = np.vstack([C, -C])
    b_ub = np.array([epsilon, epsilon])
    a0 = 0.0
    for sgn in (1.0, -1.0):
        r = scipy.optimize.linprog(-sgn * CA, A_ub=A_ub, b_ub=b_ub, bounds=box, method="highs")
        if r.status != 0:
            raise SimulationError(f"the linear program for a0 failed: {r.message}")
        a0 = max(a0, float(-r.fun))
    Cd = sp.lambdify(ysym, (model.C * model.d)[0], "numpy")
    Cb = sp.lambdify(ysym, (model.C * model.b)[0], "numpy")
    d_min, d_max = _extremes_1d(lambda y: float(Cd(y)), y_lo, y_hi)
    d0 = max(abs(d_min), abs(d_max))
    b_min, b_max = _extremes_1d(lambda y: float(Cb(y)), y_lo, y_hi)
    if b_min <= 0 <= b_max:
        raise ModelError(f"C b(y) = {(model.C * model.b)[0]} vanishes on |y| <= {epsilon} (range "
                         f"[{b_min:.6g}, {b_max:.6g}]); Theorem 3 needs it bounded away from 0")
    b_sign = 1 if b_min > 0 else -1
    b0, b1 = min(abs(b_min), abs(b_max)), max(abs(b_min), abs(b_max))
    syms = list(ext)
    s_fun = sp.lambdify([ysym] + syms, model.time_scale, "numpy")
    grids = [np.linspace(lo, hi, 9) for lo, hi in ext.values()]
    mesh = [g.ravel() for g in np.meshgrid(*grids, indexing="ij")] if grids else []
    combos = list(zip(*mesh)) if mesh else [()]

    def abs_s_max(y: float) -> float:
        return max(abs(float(s_fun(y, *c))) for c in combos)

    def abs_s_min(y: float) -> float:
        return min(abs(float(s_fun(y, *c))) for c in combos)

    s0 = _extremes_1d(abs_s_max, y_lo, y_hi)[1]
    alpha = s0 * (a0 + d0) / b0
    T_t = T_tau = None
    if beta is not None:
        if not beta > alpha:
            raise SimulationError(f"beta = {beta} is not admissible: Theorem 3 needs beta > alpha = {alpha:.6g}")
        v = s0 * (a0 + d0) + b1 * beta
        T_t = 2 * epsilon / v
        up = scipy.integrate.quad(abs_s_min, 0.0, max(y_hi, 0.0), limit=200)[0] if y_hi > 0 else 0.0
        down = scipy.integrate.quad(abs_s_min, min(y_lo, 0.0), 0.0, limit=200)[0] if y_lo < 0 else 0.0
        T_tau = 2 * min(up, down) / v
    return AdmissibleConstants(a0=float(a0), d0=float(d0), s0=float(s0), b0=float(b0), b1=float(b1),
                               alpha=float(alpha), beta=None if beta is None else float(beta),
                               epsilon=float(epsilon), dwell_time_t=None if T_t is None else float(T_t),
                               dwell_time_tau=None if T_tau is None else float(T_tau), b_sign=b_sign)
