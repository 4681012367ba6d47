"""Figures of merit of a braking run: distances, friction, XBS error and Assumption 1.

Definitions (all over the recorded samples, trapezoidal integrals):

* ``mean_friction`` ``mū``: time average of the braking friction ``-mu(lambda(t))``
  over the whole run; ``braking_distance_m = vx(0)² / (2 g mū)`` is the braking
  distance as seed 001 Table 4.1 defines it (Sec. 4.4), ``None`` when the speed
  is imposed (drum) since the tyre force then does not stop the vehicle, and
  when the run ended before the stop (``mū`` would average part of a braking).
* ``stopping_distance_m``: distance actually travelled until the stop speed, or
  until the end of the run when the car did not stop (printed "distance travelled").
* XBS error ``e = mu_hat' - mu'``: RMS over the ABS-active part; after each road
  change (and from the ABS activation for the initial road) the re-convergence
  time is the time after the end of the transition from which ``|e|`` stays
  within 10 % of the peak-to-peak range of the true XBS over that segment.
* Assumption 1 of seed 001 (Sec. 3.2) on the measured output ``y = x2`` over the
  ABS-active part: the PE level ``min_t ∫_t^{t+T0} y² dς`` of (3.17), the zero
  crossings of ``y`` with their slopes (3.18) and their smallest separation, the
  dwell time (3.19); also the smallest eigenvalue of ``∫ Ψᵀ Ψ`` over windows of
  ``T1 = 1 s`` for the adaptive observer's regressor (3.7), and the final
  rescaled time ``τ = ∫ |y| / vx dt`` of (3.12).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from .._json import JsonRecord
from ..exceptions import SimulationError
from ._json import from_fields
from ._vehicle import GRAVITY

if TYPE_CHECKING:
    from ._plant import BrakingScenario

__all__ = ["BrakingMetrics", "Assumption1Status", "Reconvergence", "braking_metrics", "assumption1", "diverged",
           "distance_label"]


def distance_label(stopped: bool) -> str:
    """What ``stopping_distance_m`` is called in text: the stopping distance of a run that stopped, the
    distance travelled of one that ended first (time bound, failure).

    Examples
    --------
    >>> distance_label(True), distance_label(False)
    ('stopping distance', 'distance travelled')
    """
    return "stopping distance" if stopped else "distance travelled"

#: Defaults of the Assumption 1 check.
PE_WINDOW_S = 0.2
PE_MIN = 1.0            # (m/s²)² s: far below an ABS cycle (~ 50 (m/s²)² s per 0.2 s), far above y -> 0
DWELL_MIN_S = 0.002
PSI_WINDOW_S = 1.0


def _cumtrapz(t: npt.NDArray[np.float64], f: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    out = np.zeros_like(t)
    if len(t) > 1:
        out[1:] = np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(t))
    return out


@dataclass(frozen=True)
class Assumption1Status(JsonRecord, error=SimulationError):
    """Assumption 1 of seed 001 (Sec. 3.2) measured on a trajectory.

    Attributes
    ----------
    pe_window_s, pe_level : float, float | None
        ``T0`` and ``min_t ∫_t^{t+T0} y²`` (3.17).
    crossings : int
        Number of zero crossings of ``y``.
    dwell_time_s : float | None
        Smallest separation of consecutive crossings (3.19).
    min_crossing_slope : float | None
        Smallest ``|dy/dt|`` at a crossing (3.18).
    tau_final : float
        Rescaled time ``∫ |y| / vx dt`` (3.12) reached at the end.
    regressor_pe : float | None
        Smallest eigenvalue of the windowed ``∫ Ψᵀ Ψ`` (3.7), ``T1 = 1 s``.
    holds : bool
        ``pe_level >= pe_min``, transversal crossings (3.18), at least two of
        them, and ``dwell_time_s >= dwell_min_s``.
    """

    pe_window_s: float
    pe_level: float | None
    crossings: int
    dwell_time_s: float | None
    min_crossing_slope: float | None
    tau_final: float
    regressor_pe: float | None
    pe_min: float
    dwell_min_s: float
    holds: bool

    def to_json(self) -> dict[str, Any]:
        return asdict(self)

    def __str__(self) -> str:
        def f(v: float | None, fmt: str) -> str:
            return "n/a" if v is None else format(v, fmt)
        return (f"Assumption 1 {'holds' if self.holds else 'FAILS'}: PE level {f(self.pe_level, '.3g')} "
                f"(T0 = {self.pe_window_s:g} s, need >= {self.pe_min:g}), {self.crossings} zero crossings, "
                f"dwell {f(self.dwell_time_s, '.4f')} s, min |dy/dt| at crossings "
                f"{f(self.min_crossing_slope, '.3g')}, tau = {self.tau_final:.3g}, "
                f"regressor PE {f(self.regressor_pe, '.3g')}")


def assumption1(t: npt.ArrayLike, y: npt.ArrayLike, vx: npt.ArrayLike, u: npt.ArrayLike | None = None, *,
                a: float | None = None, b: float | None = None, pe_window_s: float = PE_WINDOW_S,
                pe_min: float = PE_MIN, dwell_min_s: float = DWELL_MIN_S) -> Assumption1Status:
    """Check Assumption 1 (seed 001 Sec. 3.2) on a sampled output ``y`` of the ABS.

    The measurements are those of :func:`switchobs.certify.trajectory_conditions`
    with the time scale ``s = y / vx``; the regressor ``Ψ = [[y²/vx, 0], [-(b/a) u, y/vx]]``
    of (3.3) is added when ``u, a, b`` are given (window ``T1 = 1 s``, Fig. 3.1).
    Windows longer than the record give ``None``.
    """
    # imported here: switchobs.certify pulls in cvxpy (about a second), which a simulation without
    # metrics does not need
    from ..certify import trajectory_conditions

    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    vx = np.asarray(vx, dtype=float)
    duration = float(t[-1] - t[0]) if len(t) > 1 else 0.0
    if duration <= 0.0:
        return Assumption1Status(pe_window_s=pe_window_s, pe_level=None, crossings=0, dwell_time_s=None,
                                 min_crossing_slope=None, tau_final=0.0, regressor_pe=None, pe_min=pe_min,
                                 dwell_min_s=dwell_min_s, holds=False)
    psi = None
    if u is not None and a is not None and b is not None and duration >= PSI_WINDOW_S:
        u = np.asarray(u, dtype=float)
        psi = np.zeros((len(t), 2, 2))
        psi[:, 0, 0] = y * y / vx
        psi[:, 1, 0] = -(b / a) * u
        psi[:, 1, 1] = y / vx
    report = trajectory_conditions(t, y, window=min(pe_window_s, duration), vx=vx, psi=psi,
                                   psi_window=PSI_WINDOW_S)
    level = report.pe_level_y if duration >= pe_window_s else None
    dwell = report.dwell_time_t if math.isfinite(report.dwell_time_t) else None
    slope = report.min_abs_slope if math.isfinite(report.min_abs_slope) else None
    holds = bool(level is not None and level >= pe_min and report.transversal and dwell is not None
                 and dwell >= dwell_min_s)
    return Assumption1Status(pe_window_s=pe_window_s, pe_level=level, crossings=len(report.crossings),
                             dwell_time_s=dwell, min_crossing_slope=slope, tau_final=report.tau_final,
                             regressor_pe=report.psi_pe_level, pe_min=pe_min, dwell_min_s=dwell_min_s,
                             holds=holds)


@dataclass(frozen=True)
class Reconvergence(JsonRecord, error=SimulationError):
    """Re-convergence of the XBS estimate after a road change (or after the ABS activation)."""

    label: str
    settle_start_s: float
    band: float
    time_s: float | None       # None: still outside the band at the end of the segment

    def to_json(self) -> dict[str, Any]:
        return asdict(self)


@dataclass(frozen=True)
class BrakingMetrics:
    """Scalar results of a braking run (see the module notes for the definitions)."""

    initial_speed_m_s: float
    final_speed_m_s: float
    stop_time_s: float | None
    stopping_distance_m: float
    mean_friction: float
    braking_distance_m: float | None
    abs_activation_s: float | None
    mean_friction_abs: float | None
    efficiency: float | None
    abs_cycles: int
    slip_mean: float | None
    slip_std: float | None
    xbs_rms_error: float | None
    reconvergence: tuple[Reconvergence, ...]
    assumption1: Assumption1Status | None

    def to_json(self) -> dict[str, Any]:
        out = asdict(self)
        out["reconvergence"] = [r.to_json() for r in self.reconvergence]
        out["assumption1"] = None if self.assumption1 is None else self.assumption1.to_json()
        return out

    @classmethod
    def from_json(cls, data: Any) -> BrakingMetrics:
        """The metrics of :meth:`to_json` (re-convergences and Assumption 1 included).

        Raises
        ------
        SimulationError
            A missing key or a malformed part; the message names it.
        """
        if not isinstance(data, dict) or not isinstance(data.get("reconvergence"), list):
            raise SimulationError(f"a braking metrics JSON needs 'reconvergence' as a list, got {data!r}")
        a1 = data.get("assumption1")
        return from_fields(cls, data, "braking metrics",
                           reconvergence=tuple(from_fields(Reconvergence, r, "re-convergence")
                                               for r in data["reconvergence"]),
                           assumption1=None if a1 is None else from_fields(Assumption1Status, a1, "Assumption 1"))

    def __str__(self) -> str:
        distance = (f"not reached, {distance_label(False)}" if self.stop_time_s is None else
                    f"{self.stop_time_s:.3f} s, {distance_label(True)}")
        lines = [f"stop: {distance} {self.stopping_distance_m:.2f} m, final speed {self.final_speed_m_s:.2f} m/s",
                 f"mean friction {self.mean_friction:.4f}" + (
                     "" if self.braking_distance_m is None else
                     f" -> braking distance (Table 4.1 definition) {self.braking_distance_m:.2f} m")]
        if self.abs_activation_s is not None:
            eff = "" if self.efficiency is None else f", {100 * self.efficiency:.1f} % of the peak"
            # None when the ABS became active at the last sample (a run cut short by a failure)
            mean_abs = "n/a" if self.mean_friction_abs is None else f"{self.mean_friction_abs:.4f}"
            lines.append(f"ABS active from {self.abs_activation_s:.3f} s: {self.abs_cycles} cycles, mean friction "
                         f"{mean_abs}{eff}, slip {self.slip_mean:.4f} ± {self.slip_std:.4f}")
        if self.xbs_rms_error is not None:
            rec = "; ".join(f"{r.label}: " + ("not re-converged" if r.time_s is None else f"{r.time_s:.3f} s")
                            for r in self.reconvergence)
            lines.append(f"XBS estimation error: RMS {self.xbs_rms_error:.4g}; re-convergence within 10 %: {rec}")
        if self.assumption1 is not None:
            lines.append(str(self.assumption1))
        return "\n".join(lines)


def _reconvergence(t: npt.NDArray[np.float64], err: npt.NDArray[np.float64], truth: npt.NDArray[np.float64],
                   start: float, stop: float, label: str) -> Reconvergence | None:
    sel = (t >= start) & (t <= stop)
    if np.count_nonzero(sel) < 2:
        return None
    ts, es, xs = t[sel], np.abs(err[sel]), truth[sel]
    band = 0.1 * float(np.max(xs) - np.min(xs))
    outside = np.nonzero(~(es <= band))[0]
    if len(outside) == 0:
        return Reconvergence(label, start, band, 0.0)
    last = int(outside[-1])
    if last == len(ts) - 1:
        return Reconvergence(label, start, band, None)
    return Reconvergence(label, start, band, float(ts[last + 1] - start))


def braking_metrics(series: dict[str, npt.NDArray[np.float64]], scenario: BrakingScenario,
                    road_starts: list[float], *, status: str, have_estimate: bool) -> BrakingMetrics:
    """Compute :class:`BrakingMetrics` from the recorded series of a run."""
    t, vx, mu = series["t"], series["vx"], series["mu"]
    v0 = scenario.speed_m_s
    duration = float(t[-1] - t[0])
    mean_mu = float(_cumtrapz(t, -mu)[-1] / duration) if duration > 0 else 0.0
    # with an imposed speed the tyre force does not stop the vehicle: no braking distance
    braking = None if scenario.speed_profile is not None or status != "stopped" else (
        v0 * v0 / (2.0 * GRAVITY * mean_mu) if mean_mu > 0 else None)
    phase = series["phase"]
    active = np.nonzero(phase >= 1)[0]
    t_abs = float(t[active[0]]) if len(active) else None
    cycles = int(np.count_nonzero((phase[1:] == 1) & (phase[:-1] != 1)))
    mean_abs = eff = slip_mean = slip_std = rms = None
    reconv: list[Reconvergence] = []
    a1 = None
    if t_abs is not None:
        sel = t >= t_abs
        ta = t[sel]
        span = float(ta[-1] - ta[0])
        if span > 0:
            mean_abs = float(_cumtrapz(ta, -mu[sel])[-1] / span)
            if not scenario.roads.changes:
                eff = mean_abs / -scenario.roads.initial.peak_friction
        slip_mean = float(np.mean(series["lambda"][sel]))
        slip_std = float(np.std(series["lambda"][sel]))
        veh = scenario.vehicle
        a1 = assumption1(ta, series["x2"][sel], vx[sel], series["u"][sel], a=veh.a, b=veh.b)
        if have_estimate:
            err = series["xbs_hat"] - series["xbs"]
            with np.errstate(over="ignore", invalid="ignore"):
                rms = float(np.sqrt(np.mean(err[sel] ** 2)))
            changes = scenario.roads.changes
            bounds = [t_abs] + [s + c.duration_s for s, c in zip(road_starts, changes)]
            labels = ["initial"] + [f"-> {c.road.name}" for c in changes[:len(road_starts)]]
            ends = [s for s in road_starts] + [float(t[-1])]
            for start, stop, label in zip(bounds, ends, labels):
                r = _reconvergence(t, err, series["xbs"], max(start, t_abs), stop, label)
                if r is not None:
                    reconv.append(r)
    stop_time = float(t[-1]) if status == "stopped" else None
    return BrakingMetrics(initial_speed_m_s=v0, final_speed_m_s=float(vx[-1]), stop_time_s=stop_time,
                          stopping_distance_m=float(series["x"][-1]), mean_friction=mean_mu,
                          braking_distance_m=braking, abs_activation_s=t_abs, mean_friction_abs=mean_abs,
                          efficiency=eff, abs_cycles=cycles, slip_mean=slip_mean, slip_std=slip_std,
                          xbs_rms_error=rms, reconvergence=tuple(reconv), assumption1=a1)


def diverged(estimate: npt.NDArray[np.float64], rms_error: float | None, label: str = "the observer") -> str | None:
    """Say so when an XBS estimate diverged: an infinite sample, or an error RMS that is not finite.

    NaN samples alone are not divergence (an estimator without a measurement yet reports NaN);
    an RMS error that overflows to ``inf`` is, since the estimate then left every physical range.
    """
    if np.isinf(estimate).any() or (rms_error is not None and not math.isfinite(rms_error)):
        return f"{label} diverged: its XBS estimate is not finite (estimation error RMS {rms_error})"
    return None
