"""Simulation evidence for synthesised gain pairs and box certificates (issue: robust and noise-aware gains).

Two runs, each rendered as a markdown block of ``docs/certify.md`` that a test
compares with a fresh run:

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

import math
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np
import numpy.typing as npt
import scipy.linalg

__all__ = ["EncoderComparison", "encoder_comparison", "BoxRun", "two_axle_box_check", "FLOOR_WINDOW_S",
           "LOAD_BOX", "DEMO_BOX"]

Array = npt.NDArray[np.float64]

#: Window of the moving average the noise floor is measured around [s] (the ABS cycles are ~10x longer).
FLOOR_WINDOW_S = 0.02
#: The load box of the demo's wheel (seed 000's rig: a = R^2 Fz / I from 150 to 230, nominal 187.5).
DEMO_BOX = ("a=150:230",)
#: The front wheel of the two-axle vehicle: static a = 297, load transfer up to a = 400 at 9 m/s^2.
LOAD_BOX = ("a=250:450",)


@dataclass(frozen=True)
class EncoderComparison:
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
    interval, certified for every step length); the pair is :func:`switchobs.certify.synthesize_box`
    over :data:`DEMO_BOX` at decay rate 100 in ``tau`` with ``noise_weight`` on the XBS error.
    """
    from ..certify import synthesize_box
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
