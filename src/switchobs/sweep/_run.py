"""One case, built and run where it lands: :func:`run_case` is pure (same case, same numbers, any process).

A braking case goes through the public closed loop (:func:`switchobs.loop.xbs_estimator`,
:class:`switchobs.loop.EncoderLoopEstimator`, :func:`switchobs.plants.simulate`) and keeps the
figures of merit, not the time series; a certification case goes through
:func:`switchobs.certify.certify_model` and keeps the verdict, the dwell time and the discrete
``h_max``.  A case that raises is a row with its error, never a lost sweep.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterable
from fractions import Fraction
from dataclasses import dataclass, field
from typing import Any

from ..exceptions import SwitchobsError
from ._case import BrakingCase, Case, CertifyCase, case_from_json

__all__ = ["CaseResult", "run_case", "STATUS_ERROR", "STATUS_LOST", "SERIES_COLUMNS", "NUMERIC_METRICS",
           "case_observers", "observer_settings", "build_observers"]

#: Status of a case that raised (its message is in :attr:`CaseResult.error`).
STATUS_ERROR = "error"
#: Status of a case the engine lost (its workers died more often than the scheduler allows); re-run on resume.
STATUS_LOST = "lost"
#: Columns kept by ``run_case(case, series=True)``.
SERIES_COLUMNS = ("t", "vx", "lambda", "P_b", "xbs", "xbs_hat", "phase")
#: The metrics of a row that a table or heatmap averages (numbers or true/false; None where a run has none),
#: by kind of case, each with the case field that must be set for the metric to exist (``observer``: an XBS
#: observer runs; ``discrete``: a sampled observer is certified; ``box``: a parameter box).  The other metrics
#: are texts or lists (``verdict``, ``segments``, ``h_max``...): rows hold them, tables cannot average them.
NUMERIC_METRICS: dict[str, dict[str, str | None]] = {
    "braking": {"braking_distance_m": None, "stopping_distance_m": None, "stop_time_s": None,
                "mean_friction": None, "abs_activation_s": None, "abs_cycles": None, "slip_mean": None,
                "efficiency": None, "steps": None, "simulated_s": None, "xbs_rms": "observer",
                "xbs_rms_settled": "observer", "reconvergence_max_s": "observer", "recovery_max_s": "observer"},
    "certify": {"certified": None, "dwell_time_value": None, "discrete_certified": "discrete",
                "box_certified": "box"},
}


def _clean(value: Any) -> Any:
    """JSON-safe: NaN and infinities become None (strict JSON has neither)."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    return value


@dataclass(frozen=True, eq=False)
class CaseResult:
    """The outcome of one case: a row of the results file.

    Attributes
    ----------
    case : BrakingCase or CertifyCase
    status : str
        Braking: the run's status (``stopped``, ``duration``, ``controller-singular``, ``observer-failed``);
        certification: ``certified`` or ``not-certified``; ``error`` (the case raised) or ``lost`` (the engine
        lost it).
    metrics : dict
        Plain JSON values (None where a figure does not exist); see ``docs/sweeps.md``.
    error : str or None
        ``ExceptionName: message`` of a case that raised.
    series : dict or None
        :data:`SERIES_COLUMNS` of a braking run, when asked for.
    wall_time_s : float
        Cost of the run (not part of the row: rows of equal cases are equal).
    """

    case: Case
    status: str
    metrics: dict[str, Any]
    error: str | None = None
    series: dict[str, list[float | None]] | None = None
    wall_time_s: float = field(default=0.0, compare=False)

    @property
    def case_id(self) -> str:
        return self.case.case_id

    @property
    def ok(self) -> bool:
        return self.status not in (STATUS_ERROR, STATUS_LOST)

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"case_id": self.case_id, "case": self.case.to_json(), "status": self.status,
                               "error": self.error, "metrics": _clean(self.metrics)}
        if self.series is not None:
            out["series"] = self.series
        return out

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> CaseResult:
        return cls(case=case_from_json(data["case"]), status=data["status"], metrics=data.get("metrics") or {},
                   error=data.get("error"), series=data.get("series"))

    def __str__(self) -> str:
        if not self.ok:
            return f"{self.case}: {self.status} ({self.error})"
        shown = ", ".join(f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}"
                          for k, v in self.metrics.items() if not isinstance(v, (list, dict)) and v is not None)
        return f"{self.case}: {self.status}; {shown}"


def run_case(case: Case, *, series: bool = False) -> CaseResult:
    """Run one case from its spec alone and return its metrics.

    Parameters
    ----------
    case : BrakingCase or CertifyCase
    series : bool
        Braking cases: also keep the :data:`SERIES_COLUMNS` time series.

    Returns
    -------
    CaseResult
        Errors raised on purpose by switchobs (bad settings, a failed compilation, a solver failure) are a
        result with status ``error``; anything else is a bug and propagates.

    Examples
    --------
    >>> res = run_case(BrakingCase(road="dry-asphalt", speed_kmh=60.0))
    >>> res.status, round(res.metrics["braking_distance_m"], 2)
    ('stopped', 12.64)
    """
    t0 = time.perf_counter()
    try:
        if isinstance(case, BrakingCase):
            status, metrics, kept = _braking(case, series)
        elif isinstance(case, CertifyCase):
            (status, metrics), kept = _certify(case), None
        else:
            raise TypeError(f"run_case() needs a BrakingCase or a CertifyCase, got {type(case).__name__}")
    except SwitchobsError as exc:
        return CaseResult(case, STATUS_ERROR, {}, error=f"{type(exc).__name__}: {exc}",
                          wall_time_s=time.perf_counter() - t0)
    return CaseResult(case, status, metrics, series=kept, wall_time_s=time.perf_counter() - t0)


def observer_settings(cases: Iterable[Case]) -> list[tuple[Any, Any, str]]:
    """The ``(spec, vehicle, initial road)`` of each distinct C observer the braking ``cases`` run (the
    settings :func:`switchobs.loop.compiled_observers` builds)."""
    from ..loop import EstimatorSpec
    from ..plants import QuarterCar

    seen: dict[tuple[Any, ...], tuple[Any, Any, str]] = {}
    for case in cases:
        if isinstance(case, BrakingCase) and case.observer != "none" and case.impl == "c":
            spec = EstimatorSpec(case.observer, beta=case.beta1, beta2=case.beta2, gamma=case.gamma,
                                 impl=case.impl, method=case.method)
            # xbs3 reads the initial road; the others do not: one setting per what the observer depends on
            road = case.road if case.observer == "xbs3" else ""
            seen.setdefault((spec, case.load_n, road), (spec, QuarterCar(load_n=case.load_n), case.road))
    return list(seen.values())


def build_observers(settings: Iterable[tuple[Any, Any, str]]) -> dict[Any, Any]:
    """The C observers of ``settings`` (:func:`observer_settings`), each built once in this process (the
    symbolic design, the C generation and the compilation): what a sweep hands its workers
    (:func:`switchobs.loop.install_observers`) so that none repeats them.  A setting that cannot be built is
    left out: its cases report the error."""
    from ..loop import compiled_observers

    built: dict[Any, Any] = {}
    for setting in settings:
        try:
            built.update(compiled_observers([setting]))
        except SwitchobsError:
            continue
    return built


def case_observers(cases: Iterable[Case]) -> dict[Any, Any]:
    """:func:`build_observers` of the cases' :func:`observer_settings`."""
    return build_observers(observer_settings(cases))


def _controller(case: BrakingCase) -> Any:
    from ..plants import ContinuousXbsControl, FivePhaseABS, TwoPhaseABS

    if case.controller == "five-phase":
        return FivePhaseABS()
    if case.controller == "five-phase-tracking":
        return FivePhaseABS(tracking=True)
    if case.controller == "continuous":
        return ContinuousXbsControl()
    closes_loop = case.observer != "none" and case.in_loop
    return TwoPhaseABS() if closes_loop else TwoPhaseABS(start_decel_m_s2=None)


def _braking(case: BrakingCase, series: bool) -> tuple[str, dict[str, Any], dict[str, Any] | None]:
    import numpy as np

    from ..loop import INITIAL_STATE, SETTLE_S, EncoderLoopEstimator, EstimatorSpec, road_segments, \
        segment_errors, xbs_estimator
    from ..plants import BrakingScenario, PrescribedSpeed, QuarterCar, RoadChange, RoadSchedule, simulate
    from ..sensors import Encoder

    vehicle = QuarterCar(load_n=case.load_n)
    roads = RoadSchedule(case.road, [RoadChange(r, at_time_s=t) for r, t in case.changes])
    sc = BrakingScenario(roads, speed_m_s=case.speed_kmh / 3.6, controller=_controller(case), vehicle=vehicle,
                         speed_profile=None if case.decel_m_s2 is None else PrescribedSpeed(case.decel_m_s2),
                         duration_s=case.duration_s, stop_speed_m_s=case.stop_kmh / 3.6, dt_s=case.dt_s,
                         name=f"sweep-{case.case_id}")
    spec = EstimatorSpec(case.observer, beta=case.beta1, beta2=case.beta2, gamma=case.gamma, impl=case.impl,
                         method=case.method)
    est = xbs_estimator(spec, vehicle, roads.initial)
    if est is not None and case.encoder_ppr:
        encoder = Encoder(ppr=case.encoder_ppr, dnl_cycles=case.encoder_dnl, eccentricity=case.encoder_eccentricity,
                          clock_hz=case.encoder_clock_hz or None, seed=case.encoder_seed)
        est = EncoderLoopEstimator([(str(spec), est.observer, dict(INITIAL_STATE[case.observer]))],
                                   encoder=encoder, radius_m=vehicle.radius_m)
    res = simulate(sc, estimator=est, observer_in_loop=case.in_loop)
    m, s = res.metrics, res.series
    out: dict[str, Any] = {
        "braking_distance_m": m.braking_distance_m, "stopping_distance_m": m.stopping_distance_m,
        "stop_time_s": m.stop_time_s, "mean_friction": m.mean_friction, "abs_activation_s": m.abs_activation_s,
        "abs_cycles": m.abs_cycles, "slip_mean": m.slip_mean, "efficiency": m.efficiency,
        "xbs_rms": m.xbs_rms_error, "steps": res.steps, "simulated_s": float(s["t"][-1])}
    if est is not None and m.abs_activation_s is not None:
        t = s["t"]
        segs = road_segments(sc, m.abs_activation_s, float(t[-1]))
        rows = segment_errors("xbs", t, s["xbs_hat"] - s["xbs"], segs, [c.at_time_s for c in roads.changes])
        out["segments"] = [{"segment": r.segment, "rms": r.rms, "rms_settled": r.rms_settled} for r in rows]
        whole = [r for r in rows if r.segment == "whole run"]
        out["xbs_rms_settled"] = whole[0].rms_settled if whole else None
        out["reconvergence"] = [{"label": r.label, "time_s": r.time_s} for r in m.reconvergence]
        after = [r for r in m.reconvergence if r.label != "initial"] or list(m.reconvergence)
        # a road change never re-converged from makes the worst case infinite, which JSON writes as null
        out["reconvergence_max_s"] = max((math.inf if r.time_s is None else r.time_s for r in after),
                                         default=None)
        # a change followed by less than SETTLE_S of its road has no noise floor to recover to: not scored
        recover = [_recovery(t, s["xbs_hat"] - s["xbs"], s["xbs"], c.at_time_s + c.duration_s, end)
                   for c, end in zip(roads.changes, [c.at_time_s for c in roads.changes[1:]] + [float(t[-1])])
                   if c.at_time_s + c.duration_s + SETTLE_S < end]
        out["recovery_s"] = recover
        out["recovery_max_s"] = max((math.inf if r is None else r for r in recover), default=None)
    kept = None
    if series:
        kept = {k: [None if not np.isfinite(v) else float(v) for v in s[k]] for k in SERIES_COLUMNS}
    return res.status, out, kept


#: Window of the running RMS of the XBS error in the recovery time [s].
RECOVERY_WINDOW_S = 0.1


def _recovery(t: Any, err: Any, truth: Any, start: float, stop: float) -> float | None:
    """Time after ``start`` when the running RMS of ``err`` (:data:`RECOVERY_WINDOW_S`) first falls to its noise
    floor: twice the segment's settled RMS (after :data:`switchobs.loop.SETTLE_S`), or the 10 % band of the
    re-convergence time (:class:`switchobs.plants.Reconvergence`) if wider; None if it never does.

    With a noisy measurement (an encoder) the error never stays in the 10 % band; this is the
    re-convergence time that noise leaves measurable.
    """
    import numpy as np

    from ..loop import SETTLE_S

    sel = (t >= start) & (t <= stop) & np.isfinite(err)
    ts, e2 = t[sel], err[sel] ** 2
    settled = ts >= start + SETTLE_S
    if ts.size < 2 or not np.any(settled):
        return None
    floor = max(2.0 * float(np.sqrt(np.mean(e2[settled]))), 0.1 * float(np.ptp(truth[sel])))
    energy = np.concatenate([[0.0], np.cumsum(0.5 * (e2[1:] + e2[:-1]) * np.diff(ts))])
    back = np.searchsorted(ts, ts - RECOVERY_WINDOW_S)
    span = ts - ts[back]
    with np.errstate(invalid="ignore", divide="ignore"):
        running = np.sqrt((energy - energy[back]) / span)
    hit = np.nonzero((span >= 0.5 * RECOVERY_WINDOW_S) & (running <= floor))[0]
    return float(ts[hit[0]] - start) if hit.size else None


def _certify(case: CertifyCase) -> tuple[str, dict[str, Any]]:
    from ..certify import certify_model
    from ..model import builtin_model, make_symbol, parse_expression, rational_value

    model = builtin_model(case.model)
    names = {k: make_symbol(k) for k, _ in case.betas}
    at = {names[k]: rational_value(repr(v), what=f"betas.{k}") for k, v in case.betas}
    poles = [str(parse_expression(p.strip(), names, what=f"spectrum pole {p.strip()!r}").subs(at))
             for p in case.spectrum.split(",")]
    report = certify_model(model, values={k: repr(v) for k, v in case.values}, spectrum=poles,
                           dwell=case.dwell, discrete=case.discrete,
                           box={k: [repr(lo), repr(hi)] for k, lo, hi in case.box} or None)
    dwell = report.verdict.dwell_time
    metrics: dict[str, Any] = {
        "certified": report.certified, "verdict": report.text, "strict_cqlf": report.verdict.strict_cqlf.value,
        "dwell_time": None if dwell is None else dwell,
        "dwell_time_value": None if dwell in (None, "any") else float(Fraction(dwell)),
        "spectrum": poles}
    if case.discrete is not None:
        d = report.discrete
        metrics["discrete_certified"] = bool(report.discrete_certified)
        metrics["h_max"] = None if d is None else d.h_max_text()
    if case.box:
        b = report.box
        metrics["box_certified"] = b is not None and b.certified
        metrics["box_scale"] = None if b is None else str(b.scale)
        metrics["box_kind"] = None if b is None else b.kind
    return ("certified" if report.certified else "not-certified"), metrics
