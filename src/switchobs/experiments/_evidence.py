"""Simulation evidence for synthesised gain pairs and box certificates (issue: robust and noise-aware gains).

Two runs, each rendered as a markdown block of ``docs/certify.md`` (by
:func:`switchobs.report.synthesis_evidence`) that a test compares with a fresh run:

* :func:`encoder_comparison`: the demo's braking (:func:`switchobs.loop.demo_scenario`,
  dry -> wet -> snow, 60-ppr encoder with three-stage compensation) with the
  4D XBS observer of the seed (Theorem 1, every pole at ``-beta``,
  ``beta = 100``) in the loop and, on the same measurements, the pair
  synthesised by the polytopic LMIs over the load box at the same decay
  rate.  Per observer: the settled XBS error per road segment, the error in
  the :data:`switchobs.loop.SETTLE_S` after each road change (re-convergence)
  and the noise floor, the RMS of the estimate around its own moving average
  (window :data:`FLOOR_WINDOW_S`) on the settled samples.
* :func:`two_axle_box_check`: a braking of the two-axle vehicle (seed 001
  Sec. 3.6), whose front load ``Fz(t)`` follows the load transfer (3.36), so
  ``a(t) = R^2 Fz(t) / J`` moves; the front wheel's 3D observer error with
  the nominal gains and the on-line ``a(t)`` (the seed's choice) obeys
  ``de/dtau = A_sigma(a(t)) e``, integrated along the run's ``a(t)`` and
  switching signal ``s = x2 / vx``; the box certificate covers it when
  ``a(t)`` stays in the box and the run's dwell times exceed ``tau_D``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from fractions import Fraction
from typing import Any

import numpy as np
import numpy.typing as npt

from .._json import JsonRecord
from ..exceptions import SimulationError

__all__ = ["EncoderComparison", "encoder_comparison", "BoxRun", "two_axle_box_check",
           "FLOOR_WINDOW_S", "LOAD_BOX", "DEMO_BOX"]

Array = npt.NDArray[np.float64]

#: Window of the moving average the noise floor is measured around [s] (the ABS cycles are ~10x longer).
FLOOR_WINDOW_S = 0.02
#: The load box of the demo's wheel (seed 000's rig: a = R^2 Fz / I from 150 to 230, nominal 187.5).
DEMO_BOX = ("a=150:230",)
#: The front wheel of the two-axle vehicle: static a = 297, load transfer up to a = 400 at 9 m/s^2.
LOAD_BOX = ("a=250:450",)


@dataclass(frozen=True)
class EncoderComparison(JsonRecord, error=SimulationError):
    """Errors of the seed's design and the synthesised pair on the demo braking with the 60-ppr encoder.

    Attributes
    ----------
    labels : tuple of str
    gains : dict
        ``label -> (K_plus, K_minus)`` as printed floats.
    settled : dict
        ``label -> {segment: RMS of |XBS estimate - XBS|}`` outside the settling windows.
    transient : dict
        ``label -> RMS error in the SETTLE_S after the road changes``.
    floor : dict
        ``label -> RMS of estimate - moving average`` on the settled samples.
    exact : dict
        ``label -> settled RMS error over the run with the exact x2`` (no encoder).
    """

    labels: tuple[str, ...]
    gains: dict[str, tuple[str, str]]
    settled: dict[str, dict[str, float]]
    transient: dict[str, float]
    floor: dict[str, float]
    exact: dict[str, float]

    def to_json(self) -> dict[str, Any]:
        return {"labels": list(self.labels), "gains": {k: list(v) for k, v in self.gains.items()},
                "settled": self.settled, "transient": self.transient, "floor": self.floor, "exact": self.exact}

    def table(self) -> str:
        """The markdown block of ``docs/certify.md``."""
        segs = list(next(iter(self.settled.values())))
        head = ("| observer | K_plus / K_minus | " + " | ".join(f"settled error, {s}" for s in segs)
                + " | error after road changes | noise floor | settled error, exact x2 |")
        rows = [head, "|" + "---|" * (6 + len(segs) - 1)]
        for label in self.labels:
            rows.append(f"| {label} | {self.gains[label][0]} / {self.gains[label][1]} | "
                        + " | ".join(f"{self.settled[label][s]:.4f}" for s in segs)
                        + f" | {self.transient[label]:.4f} | {self.floor[label]:.4f} | {self.exact[label]:.4f} |")
        return "\n".join(rows)

    def __str__(self) -> str:
        return self.table()


def _moving_average(x: Array, width: int) -> Array:
    kernel = np.ones(width) / width
    return np.convolve(x, kernel, mode="same")


def encoder_comparison(*, fast: bool = True, noise_weight: float = 0.1) -> EncoderComparison:
    """Run the demo braking with the ``beta = 100`` 4D observer in the loop and the synthesised pair beside it.

    Both are the Python reference observers with the Radau IIA step (one step per measurement
    interval, certified for every step length); the pair is :func:`switchobs.synthesis.synthesize_box`
    over :data:`DEMO_BOX` at decay rate 100 in ``tau`` with ``noise_weight`` on the XBS error.
    """
    from ..synthesis import synthesize_box
    from ..loop import (DEFAULT_BETA, INITIAL_STATE, SETTLE_S, DemoSettings, EncoderLoopEstimator,
                        ObserverXbsEstimator, demo_scenario, road_segments, segment_errors)
    from ..model import builtin_model
    from ..observers import SwitchedObserver, xbs4_observer
    from ..plants import simulate
    from ..sensors import Encoder

    settings = DemoSettings.for_mode(fast)
    sc = demo_scenario(settings)
    params = {"a": sc.vehicle.a, "b": -sc.vehicle.b}
    model = builtin_model("abs-xbs4")
    beta = DEFAULT_BETA["xbs4"]
    exact_params = {k: str(Fraction(v).limit_denominator(10 ** 6)) for k, v in params.items()}
    syn = synthesize_box(model, DEMO_BOX, decay_rate=int(beta), noise_weight=noise_weight, estimate=["z2"],
                         values=exact_params)
    if not syn.feasible:
        raise RuntimeError(f"the synthesis for the comparison failed: {syn.detail}")
    beta_obs = xbs4_observer(beta, beta, params=params, method="radau3")
    lmi_obs = SwitchedObserver(model, [float(r[0]) for r in syn.K_plus], [float(r[0]) for r in syn.K_minus],
                               params=params, method="radau3", readout="z2")
    labels = (f"Theorem 1, poles at -{beta:g} (seed)", f"LMI over a in [150, 230], W = {noise_weight:g}")
    init = dict(INITIAL_STATE["xbs4"])
    encoder = Encoder(ppr=settings.encoder_ppr, dnl_cycles=settings.dnl_cycles,
                      eccentricity=settings.eccentricity, clock_hz=settings.clock_hz, seed=settings.encoder_seed)
    est = EncoderLoopEstimator([(labels[0], beta_obs, init), (labels[1], lmi_obs, init)], encoder=encoder,
                               radius_m=sc.vehicle.radius_m, window=settings.tsa_window,
                               harmonics=settings.harmonics,
                               beside=[(lb, ObserverXbsEstimator(o, initial_state=init))
                                       for lb, o in zip(labels, (beta_obs, lmi_obs))])
    result = simulate(sc, estimator=est)
    rec = est.record()
    s = result.series
    t_abs = result.metrics.abs_activation_s or 0.0
    segs = road_segments(sc, t_abs, float(s["t"][-1]))
    changes = [c.at_time_s for c in sc.roads.changes]
    width = max(int(round(FLOOR_WINDOW_S * 1000.0)), 3)   # the encoder loop samples at 1 kHz
    settled, transient, floor, exact = {}, {}, {}, {}
    for label in labels:
        xbs = np.interp(rec.t, s["t"], s["xbs"])
        est_x = rec.estimates[label]
        rows = segment_errors(label, rec.t, est_x - xbs, segs, changes)
        settled[label] = {r.segment: r.rms_settled for r in rows}
        after = np.zeros(rec.t.size, dtype=bool)
        for tc in changes:
            after |= (rec.t >= tc) & (rec.t < tc + SETTLE_S)
        ok = np.isfinite(est_x) & (rec.t >= t_abs)
        transient[label] = float(np.sqrt(np.mean((est_x - xbs)[after & ok] ** 2)))
        steady = ok & ~after
        smooth = _moving_average(np.where(ok, est_x, 0.0), width)
        inner = steady & (np.convolve(ok.astype(float), np.ones(width), mode="same") == width)
        floor[label] = float(np.sqrt(np.mean((est_x - smooth)[inner] ** 2)))
        ex = rec.beside[label]
        ex_rows = segment_errors(label, rec.steps_t, ex - np.interp(rec.steps_t, s["t"], s["xbs"]), segs, changes)
        exact[label] = next(r.rms_settled for r in ex_rows if r.segment == "whole run")
    gains = {labels[0]: tuple(", ".join(f"{float(x):.5g}" for x in K) for K in (beta_obs.K_plus, beta_obs.K_minus)),
             labels[1]: tuple(", ".join(f"{float(r[0]):.5g}" for r in K) for K in (syn.K_plus, syn.K_minus))}
    return EncoderComparison(labels, gains, settled, transient, floor, exact)


@dataclass(frozen=True)
class BoxRun(JsonRecord, error=SimulationError):
    """The box certificate of the front wheel's 3D observer against a two-axle braking (:func:`two_axle_box_check`).

    Attributes
    ----------
    box : str
        The certified box.
    certificate : str
        Its verdict (``BoxCertificate.__str__``).
    tau_D : float or None
        Certified dwell time in ``tau``.
    a_range : (float, float)
        ``a(t) = R^2 Fz(t) / J`` seen while braking.
    a_static : float
        The nominal (static-load) ``a`` of the design.
    inside : bool
        ``a(t)`` stayed inside the certified box.
    dwell_min, dwell_median : float
        Shortest and median interval between sign changes of ``s = x2 / vx_hat``, in ``tau``.
    tau_total : float
        Rescaled time of the braking.
    error_start, error_end : float
        ``|e|`` of the error equation at the start of braking and at the end of the run.
    duration_s : float
    """

    box: str
    certificate: str
    tau_D: float | None
    a_range: tuple[float, float]
    a_static: float
    inside: bool
    dwell_min: float
    dwell_median: float
    tau_total: float
    error_start: float
    error_end: float
    duration_s: float

    def to_json(self) -> dict[str, Any]:
        return {"box": self.box, "certificate": self.certificate, "tau_D": self.tau_D, "a_range": list(self.a_range),
                "a_static": self.a_static, "inside": self.inside, "dwell_min": self.dwell_min,
                "dwell_median": self.dwell_median, "tau_total": self.tau_total, "error_start": self.error_start,
                "error_end": self.error_end, "duration_s": self.duration_s}

    def text(self) -> str:
        """The generated sentence of ``docs/certify.md``."""
        dwell = ("all of them at least tau_D" if self.tau_D is not None and self.dwell_min >= self.tau_D else
                 f"{'some' if self.tau_D is not None else 'no certificate, so none'} shorter than tau_D = "
                 f"{self.tau_D if self.tau_D is None else f'{self.tau_D:.4g}'}")
        return (f"Front wheel, {self.duration_s:g} s of braking on dry asphalt: a(t) = R²Fz(t)/J ranged over "
                f"[{self.a_range[0]:.1f}, {self.a_range[1]:.1f}] (static {self.a_static:.1f}), "
                f"{'inside' if self.inside else 'NOT inside'} the certified box {self.box} ({self.certificate}). "
                f"The switching signal s = x2/vx_hat changed sign with intervals of {self.dwell_min:.3g} (shortest) "
                f"and {self.dwell_median:.3g} (median) in tau, {dwell}; over tau = {self.tau_total:.3g} the "
                f"error of the observer with the nominal gains and the on-line a(t) fell from "
                f"|e| = {self.error_start:.3g} to {self.error_end:.3g}.")

    def __str__(self) -> str:
        return self.text()


def two_axle_box_check(*, duration_s: float = 2.45, beta: int = 100,
                       initial_error: Sequence[float] = (0.0, 0.5, 10.0)) -> BoxRun:
    """Certify the front wheel's ``beta`` design over :data:`LOAD_BOX` and follow its error through a braking.

    The error of the 3D observer (abs-xbs3, gains of Theorem 1 with every pole at ``-beta`` at the static
    load, ``a`` updated on line from the load as the seed does) is ``de/dt = |s| A_sigma(a(t)) e`` with
    ``A_plus = A(a) - K_plus C``, ``A_minus = -A(a) + K_minus C`` and ``s = x2 / vx_hat`` from the run; it is
    integrated exactly between the run's samples (``s`` and ``a`` held), from ``initial_error`` at the
    start of braking.
    """
    from ..certify import certify_box
    from ..design import design_gains
    from ..model import builtin_model
    from ..plants import aguado_sec36, road, simulate_two_axle

    # the five-phase ABS this check was written with: its dwell times are the ones the text reports
    sc = replace(aguado_sec36("five-phase"), duration_s=duration_s)
    corner = sc.vehicle.corner("front")
    values = {k: str(Fraction(v).limit_denominator(1000))
              for k, v in (("a", corner.a), ("b", -corner.b), ("c", road(sc.roads.initial).c))}
    model = builtin_model("abs-xbs3")
    numeric = model.with_values(values)
    design = design_gains(numeric.numeric(), ",".join([f"-{beta}"] * 3))
    K_plus, K_minus = ([str(x) for x in K] for K in (design.K_plus, design.K_minus))
    cert = certify_box(model, LOAD_BOX, K_plus, K_minus, values=values, search=False)
    run = simulate_two_axle(sc)
    s = run.series
    braking = s["t"] >= sc.brake_start_s
    veh = sc.vehicle
    a_t = veh.radius_m ** 2 * s["Fz_f"] / veh.inertia_kg_m2
    lo, hi = float(np.min(a_t[braking])), float(np.max(a_t[braking]))
    box = cert.requested
    inside = float(box.lower[0]) <= lo and hi <= float(box.upper[0])
    # the error equation along the run
    import scipy.linalg  # not at import: the CLI's --help must not load scipy through report

    C = np.array([[1.0, 0.0, 0.0]])
    Kp = np.array([[float(Fraction(k))] for k in K_plus])
    Km = np.array([[float(Fraction(k))] for k in K_minus])
    base = {k: float(Fraction(v)) for k, v in values.items()}
    t = s["t"][braking]
    sig = (s["x2_f"] / s["vx_hat"])[braking]
    e = np.array(initial_error, dtype=float)
    start = float(np.linalg.norm(e))
    tau = 0.0
    switches = []
    # in balanced coordinates (z3 is ~1e5 times z1 in these gains) the matrix exponentials cost a few squarings
    _, (d, _) = scipy.linalg.matrix_balance(np.abs(_xbs3_A(base["a"], base["c"]) - Kp @ C), permute=False,
                                            separate=True)
    e = e / d
    for k in range(t.size - 1):
        h = abs(sig[k]) * (t[k + 1] - t[k])
        A = _xbs3_A(a_t[braking][k], base["c"])
        M = A - Kp @ C if sig[k] > 0 else -A + Km @ C
        e = scipy.linalg.expm(h * (M * d[None, :]) / d[:, None]) @ e
        if k and np.sign(sig[k]) != np.sign(sig[k - 1]) and sig[k] != 0:
            switches.append(tau)
        tau += h
    e = e * d
    dwell = np.diff(switches) if len(switches) > 1 else np.array([tau])
    return BoxRun(str(box), str(cert).splitlines()[0], None if cert.tau_D is None else float(cert.tau_D),
                  (lo, hi), float(corner.a), inside and cert.certified, float(np.min(dwell)),
                  float(np.median(dwell)), float(tau), start, float(np.linalg.norm(e)), duration_s)


def _xbs3_A(a: float, c: float) -> Array:
    """``A`` of abs-xbs3 (seed 000 (7)): ``[[0, -a, 0], [0, c, 1], [0, 0, 0]]``."""
    return np.array([[0.0, -a, 0.0], [0.0, c, 1.0], [0.0, 0.0, 0.0]])
