"""The measurement chain: wheel trajectory -> encoder events -> estimator -> x2 at the controller rate.

What an ABS observer really sees as its output is the wheel acceleration
offset ``x2 = R alpha - a_x`` (seed 001, (2.2)) computed from the encoder.
This module runs the whole chain on any continuous trajectory and scores it
against the exact ``theta(t)``, which plays the role of the seed's 1024-ppr
reference encoder (Table 6.1).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from .._progress import progress
from .._json import JsonRecord
from .._validate import check_work
from ..exceptions import SimulationError
from ._encoder import Encoder, EncoderEvents
from ._series import SpeedEstimate, estimate_lag, rms_error
from ._super_twisting import low_pass, super_twisting, super_twisting_gains
from ._three_stage import check_harmonics, notch, three_stage
from ._trajectory import AngleTrajectory, constant_speed, rpm_to_rad_s, trapezoid_speed, varying_speed
from ._tsa import check_order_window, controller_times, time_stamping
from ._validate import check_int, check_positive

__all__ = ["ESTIMATORS", "TABLE61_SEED", "TABLE61_ENCODER", "TABLE61_PROFILES", "ROBUSTNESS_PROFILES",
           "ChainSettings", "ChainResult", "EstimatorComparison", "encoder_chain",
           "compare_estimators", "check_chain_work", "MAX_EDGES", "MAX_SAMPLES", "MAX_TSA_WORK",
           "MAX_RLS_WORK", "MAX_LAG_WORK"]

Array = npt.NDArray[np.float64]

#: Estimators of the chain, in the order of the comparison tables.
ESTIMATORS: tuple[str, ...] = ("tsa", "notch", "three-stage", "super-twisting")

# Work limits of one run of the chain, checked before the events are generated (check_chain_work): each
# bounds memory (about 1 GB) or time (minutes), far above what the seed's set-ups need (10 s at 1020 rpm and
# 1 kHz: 10 200 edges, 10 001 samples, 1.1e5 with the super-twisting observer's sub-steps).
#: Encoder edges (each costs some 200 bytes while the crossings are located).
MAX_EDGES = 1_000_000
#: Estimator samples: controller samples, times the sub-steps of the super-twisting observer.
MAX_SAMPLES = 1_000_000
#: Numbers in the TSA least-squares problems, samples x window n x (order m + 1), over all estimators.
MAX_TSA_WORK = 1e8
#: Multiply-adds of the three-stage least squares, 2 (2 M)^2 per sample.
MAX_RLS_WORK = 1e9
#: Sample pairs compared by the lag estimate, samples x shifts within 0.1 s, over all estimators.
MAX_LAG_WORK = 2e8


@dataclass(frozen=True)
class ChainSettings:
    """Settings of every stage of the chain (defaults: seed 001 Sections 5.2, 6.3 and our tuning).

    Parameters
    ----------
    rate_hz : float
        Controller rate (Hz).
    order, window : int
        TSA polynomial order ``m`` and events ``n`` (seed: 2 and 15).
    harmonics : int
        Harmonics ``M`` of the three-stage estimator (seed: 5 = ceil(N/n) + 1).
    kappa, beta : float
        Constants of the RLS (6.8) (seed: 1 and 0.1).
    gamma0 : float
        Scale of ``Gamma_0``: ``gamma_k = gamma0 / k`` (a weak prior, so the
        least squares converge within a few revolutions).
    highpass_hz : float or None
        Stage 1 of the three-stage estimator: ``None`` (ours) the mean over the
        surrounding revolution, a number the seed's high-pass cut-off (1 Hz).
    damping : float
        Notch damping ratio (seed: 0.5).
    st_f_plus : float
        Acceleration bound ``f+`` (rad/s^2) for the super-twisting gains (12).
    st_tau_s : float
        Low-pass time constant of the equivalent output injection (s).
    st_substeps : int
        Observer steps per controller sample: the super-twisting observer runs
        at ``rate_hz * st_substeps`` on the angle given by the TSA polynomial
        (Theorem 2 of seed 003: the speed error is O(step)).
    warmup_s : float
        Initial interval left out of the error statistics (transients).
    """

    rate_hz: float = 1000.0
    order: int = 2
    window: int = 15
    harmonics: int = 5
    kappa: float = 1.0
    beta: float = 0.1
    gamma0: float = 1e5
    highpass_hz: float | None = None
    damping: float = 0.5
    st_f_plus: float = 500.0
    st_tau_s: float = 0.005
    st_substeps: int = 10
    warmup_s: float = 1.0

    def __post_init__(self) -> None:
        check_positive(self.rate_hz, "rate_hz")
        check_order_window(self.order, self.window)
        check_harmonics(self.harmonics)
        for name in ("kappa", "gamma0", "st_f_plus", "st_tau_s"):
            check_positive(getattr(self, name), name)
        if self.highpass_hz is not None:
            check_positive(self.highpass_hz, "highpass_hz")
        check_positive(self.beta, "beta", allow_zero=True)
        check_positive(self.warmup_s, "warmup_s", allow_zero=True)
        check_int(self.st_substeps, "st_substeps", minimum=1)

    def to_json(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> "ChainSettings":
        """The settings of :meth:`to_json` (validated again)."""
        return cls(**data)


def _ms(seconds: float) -> str:
    return "-" if math.isnan(seconds) else f"{1e3 * seconds:.0f}"


def _clean(a: Array | None) -> list[float | None] | None:
    return None if a is None else [None if math.isnan(x) else float(x) for x in a]


@dataclass(frozen=True, eq=False)
class ChainResult:
    """Estimated wheel speed, acceleration and ``x2`` at the controller samples, with their errors.

    Attributes
    ----------
    estimator : str
        One of :data:`ESTIMATORS`.
    t, omega, alpha : ndarray
        Controller times (s), estimated speed (rad/s) and acceleration (rad/s^2).
    omega_true, alpha_true : ndarray
        Exact values from the continuous trajectory.
    x2, x2_true : ndarray or None
        Measured ``R alpha_hat - a_x`` and the exact ``R alpha - a_x`` (m/s^2),
        when the trajectory carries a radius and ``a_x(t)``.
    events : int
        Number of encoder events.
    rms_omega, rms_alpha, rms_x2 : float
        RMS errors after ``settings.warmup_s`` (``rms_x2`` NaN without ``x2``).
    lag_omega_s, lag_alpha_s : float
        Delay that best aligns the estimate with the truth (0.1 s search).
    settings : ChainSettings
    """

    estimator: str
    t: Array
    omega: Array
    alpha: Array
    omega_true: Array
    alpha_true: Array
    x2: Array | None
    x2_true: Array | None
    events: int
    rms_omega: float
    rms_alpha: float
    rms_x2: float
    lag_omega_s: float
    lag_alpha_s: float
    settings: ChainSettings

    def summary(self) -> dict[str, Any]:
        """The scalar figures as plain JSON types (NaN as None)."""
        def num(x: float) -> float | None:
            return None if math.isnan(x) else float(x)
        return {"estimator": self.estimator, "events": self.events, "samples": int(self.t.size),
                "rms_omega_rad_s": num(self.rms_omega), "rms_alpha_rad_s2": num(self.rms_alpha),
                "rms_x2_m_s2": num(self.rms_x2), "lag_omega_s": num(self.lag_omega_s),
                "lag_alpha_s": num(self.lag_alpha_s)}

    def to_json(self, *, arrays: bool = False) -> dict[str, Any]:
        out = {**self.summary(), "settings": self.settings.to_json()}
        if arrays:
            out.update(t=self.t.tolist(), omega=_clean(self.omega), alpha=_clean(self.alpha),
                       omega_true=self.omega_true.tolist(), alpha_true=self.alpha_true.tolist(),
                       x2=_clean(self.x2), x2_true=_clean(self.x2_true))
        return out

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> "ChainResult":
        """The result of ``to_json(arrays=True)`` (``None`` in the arrays and figures is NaN again).

        Raises
        ------
        SimulationError
            A summary written without the arrays.
        """
        if "t" not in data:
            raise SimulationError("this chain result was written without its arrays; write it with "
                                  "to_json(arrays=True) to read it back")

        def arr(x: Any) -> Array | None:
            return None if x is None else np.array([math.nan if v is None else v for v in x], dtype=float)

        def num(x: Any) -> float:
            return math.nan if x is None else float(x)

        return cls(str(data["estimator"]), arr(data["t"]), arr(data["omega"]), arr(data["alpha"]),
                   arr(data["omega_true"]), arr(data["alpha_true"]), arr(data["x2"]), arr(data["x2_true"]),
                   int(data["events"]), num(data["rms_omega_rad_s"]), num(data["rms_alpha_rad_s2"]),
                   num(data["rms_x2_m_s2"]), num(data["lag_omega_s"]), num(data["lag_alpha_s"]),
                   ChainSettings.from_json(data["settings"]))

    def __str__(self) -> str:
        x2 = "" if math.isnan(self.rms_x2) else f", x2 {self.rms_x2:.4g} m/s^2"
        return (f"{self.estimator}: RMS error omega {self.rms_omega:.4g} rad/s, alpha {self.rms_alpha:.4g} rad/s^2"
                f"{x2}; lag {_ms(self.lag_omega_s)} / {_ms(self.lag_alpha_s)} ms "
                f"({self.events} events, {self.t.size} samples)")


@dataclass(frozen=True, eq=False)
class EstimatorComparison(JsonRecord, error=SimulationError):
    """Several estimators on the same events: our counterpart of seed 001 Table 6.1."""

    trajectory: str
    encoder: Encoder
    results: tuple[ChainResult, ...]

    def __getitem__(self, estimator: str) -> ChainResult:
        for r in self.results:
            if r.estimator == estimator:
                return r
        raise KeyError(estimator)

    @property
    def failure(self) -> str | None:
        """Why the comparison has no figures, or ``None``: the exit status 1 of ``switchobs encoder``.

        A speed or acceleration RMS error that is NaN (no estimate after the warm-up) or infinite is a
        failed run; ``rms_x2`` and the lags may be NaN by design (no ``x2`` in the trajectory, a
        constant truth) and print as "-".
        """
        bad = [r.estimator for r in self.results
               if not (math.isfinite(r.rms_omega) and math.isfinite(r.rms_alpha))]
        if not bad:
            return None
        return (f"no finite RMS error for {', '.join(bad)}: no estimate after the warm-up "
                f"({self.results[0].settings.warmup_s:g} s), or the estimate diverged")

    def to_json(self, *, arrays: bool = False) -> dict[str, Any]:
        """The figures of each estimator (its whole :meth:`ChainResult.to_json` with the arrays if ``arrays``)."""
        enc = {k: v for k, v in asdict(self.encoder).items() if not k.startswith("_")}
        return {"trajectory": self.trajectory, "encoder": enc, "failure": self.failure,
                "settings": self.results[0].settings.to_json() if self.results else None,
                "results": [r.to_json(arrays=True) if arrays else r.summary() for r in self.results]}

    def __str__(self) -> str:
        e = self.encoder
        lines = [f"{self.trajectory}: {e.ppr}-ppr encoder (dnl {e.dnl_cycles:g} cycle, jitter {e.jitter_cycles:g} "
                 f"cycle, e/r {e.eccentricity:g}, "
                 f"clock {'exact' if e.clock_hz is None else f'{e.clock_hz:g} Hz'}), "
                 f"RMS errors after {self.results[0].settings.warmup_s:g} s",
                 f"{'estimator':<16}{'omega [rad/s]':>15}{'alpha [rad/s^2]':>17}{'x2 [m/s^2]':>12}"
                 f"{'lag w [ms]':>12}{'lag a [ms]':>12}"]
        for r in self.results:
            x2 = "-" if math.isnan(r.rms_x2) else f"{r.rms_x2:.4f}"
            lines.append(f"{r.estimator:<16}{r.rms_omega:>15.4f}{r.rms_alpha:>17.3f}{x2:>12}"
                         f"{_ms(r.lag_omega_s):>12}{_ms(r.lag_alpha_s):>12}")
        return "\n".join(lines)


def _check_estimator(name: str) -> str:
    if name not in ESTIMATORS:
        raise SimulationError(f"unknown estimator {name!r}; choose one of {', '.join(ESTIMATORS)}")
    return name


def check_chain_work(trajectory: AngleTrajectory, encoder: Encoder, settings: ChainSettings,
                     estimators: tuple[str, ...]) -> None:
    """Refuse, before any work, a run of the chain that would exhaust memory or time or give no statistics.

    Estimates the encoder edges from the angle swept, the samples from the rate and the duration, and the
    work of the TSA fits, the three-stage least squares and the lag search (limits ``MAX_*`` of this module).

    Raises
    ------
    SimulationError
        An estimate above its limit, more harmonics than the wheel resolves (``n_edges / 2``), a TSA
        window that the run's edges never fill, fewer than 2 samples, or none after the warm-up.
    """
    fix = "shorten the duration or lower the rate"
    th0, th1 = (float(v) for v in trajectory.theta(np.array([trajectory.t_start, trajectory.t_end])))
    edges = encoder.n_edges * (th1 - th0) / (2.0 * math.pi)
    check_work(f"{encoder.n_edges} edges per revolution over {(th1 - th0) / (2.0 * math.pi):.3g} revolutions",
               edges, MAX_EDGES, "lower the speed, the duration or the pulses per revolution",
               error=SimulationError)
    if edges < settings.window:
        raise SimulationError(f"the TSA window of n = {settings.window} events never fills: the run produces "
                              f"about {edges:.0f} edges; lower the window or lengthen the run")
    if "three-stage" in estimators and settings.harmonics > encoder.n_edges // 2:
        raise SimulationError(f"harmonics (M) = {settings.harmonics} exceeds {encoder.n_edges // 2}, the most an "
                              f"encoder with {encoder.n_edges} edges per revolution resolves (half the edges)")
    span = trajectory.t_end - trajectory.t_start
    samples = math.floor(span * settings.rate_hz + 1e-9) + 1
    # the same samples and warm-up test as controller_times and _score
    if samples < 2 or (samples - 1) / settings.rate_hz < settings.warmup_s:
        raise SimulationError(f"the statistics need 2 samples and one after the warm-up of {settings.warmup_s:g} "
                              f"s; at {settings.rate_hz:g} Hz over {span:g} s there are {samples}; lengthen the "
                              f"run, raise the rate or shorten the warm-up")
    fine = samples * settings.st_substeps if "super-twisting" in estimators else 0
    tsa_runs = samples * sum(name != "super-twisting" for name in estimators) + fine
    check_work(f"estimator samples at {settings.rate_hz:g} Hz over {span:g} s", samples + fine, MAX_SAMPLES,
               fix, error=SimulationError)
    check_work(f"TSA least-squares numbers ({tsa_runs} fits of {settings.window} events, order "
               f"{settings.order})", tsa_runs * settings.window * (settings.order + 1), MAX_TSA_WORK,
               f"lower the window n or the order m, or {fix}", error=SimulationError)
    if "three-stage" in estimators:
        check_work(f"three-stage least-squares multiply-adds ({settings.harmonics} harmonics, {samples} samples)",
                   2.0 * samples * (2 * settings.harmonics) ** 2, MAX_RLS_WORK,
                   f"lower the harmonics M, or {fix}", error=SimulationError)
    check_work(f"sample pairs of the lag search ({samples} samples, {round(0.1 * settings.rate_hz)} shifts)",
               2.0 * len(estimators) * samples * round(0.1 * settings.rate_hz), MAX_LAG_WORK, fix,
               error=SimulationError)


def _super_twisting_estimate(events: EncoderEvents, ts: Array, s: ChainSettings) -> SpeedEstimate:
    fine = controller_times(float(ts[0]), float(ts[-1]), s.rate_hz * s.st_substeps)
    tsa = time_stamping(events.times, events.angles, fine, order=s.order, window=s.window)
    ok = tsa.valid
    om, al = np.full(fine.size, np.nan), np.full(fine.size, np.nan)
    if np.count_nonzero(ok) >= 2:
        run = super_twisting(fine[ok], tsa.theta[ok], gains=super_twisting_gains(s.st_f_plus))
        om[ok] = run.x2_hat
        al[ok] = low_pass(run.z2, 1.0 / (s.rate_hz * s.st_substeps), s.st_tau_s)
    pick = np.round((ts - fine[0]) * s.rate_hz * s.st_substeps).astype(int)
    return SpeedEstimate(t=ts, omega=om[pick], alpha=al[pick], method="super-twisting")


def _estimate(events: EncoderEvents, ts: Array, estimator: str, s: ChainSettings) -> SpeedEstimate:
    if estimator == "super-twisting":
        return _super_twisting_estimate(events, ts, s)
    tsa = time_stamping(events.times, events.angles, ts, order=s.order, window=s.window)
    if estimator == "notch":
        return notch(tsa, damping=s.damping)
    if estimator == "three-stage":
        return three_stage(tsa, harmonics=s.harmonics, kappa=s.kappa, beta=s.beta, gamma0=s.gamma0,
                           highpass_hz=s.highpass_hz)
    return SpeedEstimate(t=ts, omega=tsa.omega, alpha=tsa.alpha, method="tsa")


def _score(trajectory: AngleTrajectory, est: SpeedEstimate, events: int, s: ChainSettings) -> ChainResult:
    t = est.t
    w, a = trajectory.omega(t), trajectory.alpha(t)
    scored = t >= trajectory.t_start + s.warmup_s
    x2 = x2_true = None
    rms_x2 = math.nan
    if trajectory.radius_m is not None and trajectory.accel_x is not None:
        ax = trajectory.accel_x(t)
        x2, x2_true = trajectory.radius_m * est.alpha - ax, trajectory.radius_m * a - ax
        rms_x2 = rms_error(x2, x2_true, scored)
    after = np.where(scored, 1.0, np.nan)
    return ChainResult(
        estimator=est.method, t=t, omega=est.omega, alpha=est.alpha, omega_true=w, alpha_true=a,
        x2=x2, x2_true=x2_true, events=events,
        rms_omega=rms_error(est.omega, w, scored), rms_alpha=rms_error(est.alpha, a, scored), rms_x2=rms_x2,
        lag_omega_s=estimate_lag(t, est.omega * after, w), lag_alpha_s=estimate_lag(t, est.alpha * after, a),
        settings=s)


def encoder_chain(
    trajectory: AngleTrajectory,
    encoder: Encoder = Encoder(),
    *,
    estimator: str = "three-stage",
    settings: ChainSettings = ChainSettings(),
) -> ChainResult:
    """Turn a wheel trajectory into the measured speed, acceleration and ``x2`` at the controller rate.

    Parameters
    ----------
    trajectory : AngleTrajectory
        The plant's wheel angle (e.g. :meth:`AngleTrajectory.from_samples` on a
        simulated quarter car, which also carries ``R`` and ``a_x(t)``).
    encoder : Encoder
        The wheel encoder (imperfections, clock).
    estimator : {"tsa", "notch", "three-stage", "super-twisting"}
        Raw TSA (seed 001 (5.4)-(5.5)), TSA + notch (Section 6.3), TSA +
        three-stage (Section 6.2), or the super-twisting observer (seed 003)
        fed with the TSA angle.
    settings : ChainSettings

    Returns
    -------
    ChainResult
        ``x2 = R alpha_hat - a_x`` sampled at ``settings.rate_hz``: the
        measured output of the XBS observers (seed 000 (7), seed 001 (2.6)).

    Raises
    ------
    SimulationError
        Unknown estimator, or bad encoder/trajectory settings.

    Examples
    --------
    >>> from switchobs.sensors import Encoder, constant_speed, encoder_chain
    >>> res = encoder_chain(constant_speed(1020, 2.0), Encoder(ppr=60), estimator="tsa")
    >>> res.rms_omega < 1e-9
    True
    """
    _check_estimator(estimator)
    check_chain_work(trajectory, encoder, settings, (estimator,))
    events = encoder.events(trajectory)
    ts = controller_times(trajectory.t_start, trajectory.t_end, settings.rate_hz)
    return _score(trajectory, _estimate(events, ts, estimator, settings), len(events), settings)


def compare_estimators(
    trajectory: AngleTrajectory,
    encoder: Encoder = Encoder(),
    *,
    estimators: tuple[str, ...] = ESTIMATORS,
    settings: ChainSettings = ChainSettings(),
) -> EstimatorComparison:
    """Run several estimators on the same encoder events (seed 001 Table 6.1 layout)."""
    for name in estimators:
        _check_estimator(name)
    check_chain_work(trajectory, encoder, settings, estimators)
    progress(f"encoder: edges of the {trajectory.name} trajectory")
    events = encoder.events(trajectory)
    ts = controller_times(trajectory.t_start, trajectory.t_end, settings.rate_hz)
    results = []
    for k, name in enumerate(estimators, 1):
        progress(f"encoder: [{k}/{len(estimators)}] {name} estimator ({len(events)} edges)")
        results.append(_score(trajectory, _estimate(events, ts, name, settings), len(events), settings))
    return EstimatorComparison(trajectory=trajectory.name, encoder=encoder, results=tuple(results))


#: Seed 001 Table 6.1: RMS (velocity [rad/s], acceleration [rad/s^2]) per profile and estimator.
TABLE61_SEED: dict[str, dict[str, tuple[float, float]]] = {
    "constant": {"tsa": (0.3007, 30.0886), "notch": (3.0730, 7.9528), "three-stage": (0.0716, 7.9405)},
    "varying": {"tsa": (0.1430, 12.8528), "notch": (5.2597, 33.5899), "three-stage": (0.0783, 5.9237)},
}
#: Our encoder for Table 6.1: an eccentricity and a per-event transition noise fitted by least squares to three
#: cells of the seed's constant row (TSA velocity and acceleration, notch acceleration); the report's
#: ``fit_table61_encoder`` recomputes them and docs/encoders.md says why no per-tooth error is left.
TABLE61_ENCODER = Encoder(ppr=60, eccentricity=0.00347, jitter_cycles=0.00424, clock_hz=1e6, seed=1)
#: Table 6.1 speed profiles: name -> (how it was chosen, trajectory of the given duration).  The varying one
#: follows the seed's hints (docs/encoders.md): constant-speed and constant-acceleration intervals, and an RMS
#: speed of 0.476 x 1020 rpm, the ratio of the seed's varying and constant TSA velocity errors.
TABLE61_PROFILES: dict[str, tuple[str, Callable[[float], AngleTrajectory]]] = {
    "constant": ("1020 rpm (seed 001 Fig. 5.4)", lambda duration_s: constant_speed(1020.0, duration_s)),
    "varying": ("plateaus at 312 and 624 rpm joined by 1 s ramps at 32.7 rad/s², 1 s per segment (derived from "
                "the seed's hints, see [Wheel encoders](encoders.md))",
                lambda duration_s: trapezoid_speed(312.0, 624.0, duration_s)),
}


def _constant(rpm: float) -> Callable[[float], AngleTrajectory]:
    return lambda duration_s: constant_speed(rpm, duration_s)


def _swing(rpm: float, amplitude_rad_s: float) -> Callable[[float], AngleTrajectory]:
    return lambda duration_s: varying_speed(rpm, duration_s, amplitude_rad_s=amplitude_rad_s)


#: The speed range over which the three-stage estimator must not be worse than the raw TSA (300-1500 rpm):
#: constant speeds, the sinusoidal swing at the relative size of the former Table 6.1 profile (+-40 rad/s at
#: 1020 rpm, i.e. +-37.5 %), the +-40 rad/s swing at lower mean speeds, and the Table 6.1 varying profile.
ROBUSTNESS_PROFILES: tuple[tuple[str, Callable[[float], AngleTrajectory]], ...] = (
    *((f"constant {rpm:g} rpm", _constant(rpm)) for rpm in (300.0, 600.0, 1500.0)),
    *((f"{rpm:g} rpm ± 37.5 % at 1 Hz", _swing(rpm, 0.375 * rpm_to_rad_s(rpm))) for rpm in (300.0, 600.0, 1500.0)),
    *((f"{rpm:g} rpm ± 40 rad/s at 1 Hz", _swing(rpm, 40.0)) for rpm in (470.0, 600.0, 1020.0)),
    ("Table 6.1 varying", TABLE61_PROFILES["varying"][1]),
)
