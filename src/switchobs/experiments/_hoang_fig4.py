"""Seed 000 Fig. 4 and Sec. III-E: the wheel-acceleration tracking (21)-(22) and the brake pressure per road, and
the noise of the XBS estimate by the sign of the wheel acceleration on the encoder-fed run.

Sec. III-E reports that "the noise of the observed variable z2_hat is bigger when the wheel acceleration is
positive", and offers "that the norm of K^+ is bigger than that of K^-" as a possible explanation.  We measure the
noise the encoder puts on the estimate (the encoder-fed estimate minus the one fed the exact ``x2``, at the time
the measurement describes, high-passed) by the sign of ``x2``, and compare the ratio with two predictions: the
ratio of the gain norms, and the ratio of the H2 norms, in the rescaled time ``tau``, from a noise on the output
to the error of ``z2`` (the error dynamics ``de/dtau = A_± e + K_± n``, seed 000 (13)): in ``tau`` the noise
enters through ``K_±`` and is shaped by ``A_±``, so the noise an estimate carries is the H2 norm of that
transfer, not ``|K_±|`` alone.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from ..loop import (INITIAL_STATE, DemoSettings, EncoderLoopEstimator, EncoderLoopRecord, EstimatorSpec,
                    ObserverXbsEstimator, xbs_estimator)
from ..plants import BrakingResult, scenario, simulate
from ..sensors import Encoder

__all__ = ["FIG4_ROADS", "FIG4_TRACKING_PHASES", "FIG4_SETTLE_S", "FIG4_OBSERVERS", "FIG4_NOISE_WINDOW",
           "Fig4Road", "fig4_roads", "Fig4Encoder", "fig4_encoder_run", "NoiseGains", "noise_gains"]

Array = npt.NDArray[np.float64]

#: The roads of ``hoang-fig4`` with their spans [s] (seed 000 Fig. 4: dry for three seconds, wet for one, snow).
FIG4_ROADS = (("dry", 0.0, 3.0), ("wet", 3.0, 4.0), ("snow", 4.0, 7.0))

#: The phases of the five-phase ABS in which (21)-(22) track ``x2*`` (seed 000 Fig. 4 caption).
FIG4_TRACKING_PHASES = (1, 3, 4)

#: After each road change the tracking error is also given without this span [s]: the 25 ms transition and the
#: observer's re-convergence (``docs/reproductions.md``, Fig. 4: 0.10 s and 0.23 s).
FIG4_SETTLE_S = 0.25

#: The observers of the encoder-fed run: the 4D observer of Sec. IV in the loop (the seed's Fig. 4) and the 3D
#: observer of Sec. III-E beside it (knows the dry road's c), both with the seed's beta1 = beta2 = 100.
FIG4_OBSERVERS: Mapping[str, EstimatorSpec] = {"xbs4": EstimatorSpec("xbs4", beta=100.0),
                                               "xbs3": EstimatorSpec("xbs3", beta=100.0)}

#: The noise is the difference high-passed by removing its moving mean over this many samples (11 ms at the
#: chain's 1 kHz): shorter than an ABS phase, so the slow part of the difference (the notch's and the window's
#: lag) goes, longer than the few samples a measurement error lasts.
FIG4_NOISE_WINDOW = 11


@dataclass(frozen=True)
class Fig4Road:
    """Tracking and pressure on one road of a Fig. 4 run.

    Attributes
    ----------
    road : str
    tracking_share : float
        Share of the road's samples in the tracking phases.
    tracking_rms, settled_rms : float
        RMS of ``xi = x2 - x2*`` over those samples [m/s²]; the same without the first :data:`FIG4_SETTLE_S` of
        the road (the road change, or the observer's convergence from its initial state on the first).
    reference_rms : float
        RMS of ``x2*`` over the same samples [m/s²] (the scale of the tracking error).
    pressure_mean, pressure_max : float
        Brake pressure on the road [bar].
    """

    road: str
    tracking_share: float
    tracking_rms: float
    settled_rms: float
    reference_rms: float
    pressure_mean: float
    pressure_max: float


def fig4_roads(result: BrakingResult) -> tuple[Fig4Road, ...]:
    """Per road of :data:`FIG4_ROADS`, the tracking error of (22) and the pressure of a ``hoang-fig4`` run."""
    s = result.series
    t = s["t"]
    tracking = np.isin(s["phase"], FIG4_TRACKING_PHASES) & np.isfinite(s["x2_ref"])
    xi = s["x2"] - s["x2_ref"]
    out = []
    for name, a, b in FIG4_ROADS:
        on = (t >= a) & (t < b)
        sel = on & tracking
        settled = sel & (t >= a + FIG4_SETTLE_S)
        out.append(Fig4Road(name, float(np.count_nonzero(sel) / np.count_nonzero(on)),
                            float(np.sqrt(np.mean(xi[sel] ** 2))), float(np.sqrt(np.mean(xi[settled] ** 2))),
                            float(np.sqrt(np.mean(s["x2_ref"][sel] ** 2))), float(np.mean(s["P_b"][on])),
                            float(np.max(s["P_b"][on]))))
    return tuple(out)


@dataclass(frozen=True)
class Fig4Encoder:
    """The ``hoang-fig4`` braking with the observers of :data:`FIG4_OBSERVERS` fed by the demo's encoder chain.

    Attributes
    ----------
    result : BrakingResult
        The run (the tracking law reads the encoder-fed ``xbs4`` estimate).
    record : EncoderLoopRecord
        What the chain and the observers saw; ``beside`` holds each observer fed the exact ``x2``.
    """

    result: BrakingResult
    record: EncoderLoopRecord

    def noise(self, label: str, spans: tuple[tuple[float, float], ...] | None = None) -> tuple[float, float]:
        """RMS of the encoder's noise on the estimate of ``label`` while ``x2 > 0`` and while ``x2 < 0``,
        over the samples in the ``spans`` ``(a, b)`` [s] (default: every road of :data:`FIG4_ROADS` without
        :data:`FIG4_SETTLE_S` at its start, the observers' convergence from their initial state included;
        module notes)."""
        spans = tuple((a + FIG4_SETTLE_S, b) for _, a, b in FIG4_ROADS) if spans is None else spans
        rec, s = self.record, self.result.series
        tm = rec.t_measured
        ok = np.isfinite(tm) & np.isfinite(rec.estimates[label])
        tm_ = np.where(ok, tm, rec.t)
        diff = np.where(ok, rec.estimates[label] - np.interp(tm_, rec.steps_t, rec.beside[label]), 0.0)
        w = FIG4_NOISE_WINDOW
        kernel = np.ones(w)
        hp = diff - np.convolve(diff, kernel / w, mode="same")
        inside = np.zeros(rec.t.size, dtype=bool)
        for a, b in spans:
            inside |= (rec.t >= a) & (rec.t < b)
        inner = ok & (np.convolve(ok.astype(float), kernel, mode="same") == w) & inside
        x2 = np.interp(tm_, s["t"], s["x2"])
        return (float(np.sqrt(np.mean(hp[inner & (x2 > 0.0)] ** 2))),
                float(np.sqrt(np.mean(hp[inner & (x2 < 0.0)] ** 2))))


def fig4_encoder_run() -> Fig4Encoder:
    """``hoang-fig4`` with the demo's 60-ppr encoder chain (:class:`switchobs.loop.DemoSettings`) feeding the
    observers of :data:`FIG4_OBSERVERS` (``xbs4`` in the loop), each also fed the exact ``x2`` beside."""
    sc = scenario("hoang-fig4")
    st = DemoSettings()
    encoder = Encoder(ppr=st.encoder_ppr, dnl_cycles=st.dnl_cycles, eccentricity=st.eccentricity,
                      clock_hz=st.clock_hz, seed=st.encoder_seed)
    fed, beside = [], []
    for label, spec in FIG4_OBSERVERS.items():
        obs = xbs_estimator(spec, sc.vehicle, sc.roads.initial).observer
        fed.append((label, obs, dict(INITIAL_STATE[spec.kind])))
        beside.append((label, ObserverXbsEstimator(obs, initial_state=INITIAL_STATE[spec.kind])))
    est = EncoderLoopEstimator(fed, encoder=encoder, radius_m=sc.vehicle.radius_m, window=st.tsa_window,
                               harmonics=st.harmonics, beside=beside)
    return Fig4Encoder(simulate(sc, estimator=est), est.record())


@dataclass(frozen=True)
class NoiseGains:
    """Two predictions of the noise ratio between the modes of a switched observer (module notes).

    Attributes
    ----------
    norm_plus, norm_minus : float
        ``|K_plus|``, ``|K_minus|`` (Euclidean, model coordinates).
    h2_plus, h2_minus : float
        H2 norm in ``tau`` from a noise on the output to the error of the estimated state, for
        ``A_+ = A - K_+ C`` and ``A_- = -A + K_- C``.
    """

    norm_plus: float
    norm_minus: float
    h2_plus: float
    h2_minus: float


def noise_gains(spec: EstimatorSpec, state: str = "z2") -> NoiseGains:
    """:class:`NoiseGains` of the observer of ``spec`` on the ``hoang-fig4`` vehicle and its first road."""
    from scipy.linalg import solve_continuous_lyapunov

    sc = scenario("hoang-fig4")
    obs = xbs_estimator(spec, sc.vehicle, sc.roads.initial).observer
    A, C = np.array(obs.A, dtype=float), np.array(obs.C, dtype=float).reshape(1, -1)
    i = obs.state_names.index(state)
    kp, km = (np.array(K, dtype=float).reshape(-1, 1) for K in (obs.K_plus, obs.K_minus))
    # controllability Gramian of (A_±, K_±): its diagonal entry is the squared H2 norm to that state
    w_plus = solve_continuous_lyapunov(A - kp @ C, -kp @ kp.T)
    w_minus = solve_continuous_lyapunov(-A + km @ C, -km @ km.T)
    return NoiseGains(float(np.linalg.norm(kp)), float(np.linalg.norm(km)), float(math.sqrt(w_plus[i, i])),
                      float(math.sqrt(w_minus[i, i])))
