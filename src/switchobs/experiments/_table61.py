"""Seed 001 Table 6.1 and the wheel-encoder measurements: the fit of its encoder on three seed cells, the
bounds that explain the cells outside 15 %, and the encoder runs quoted by the pages."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..sensors import (TABLE61_ENCODER, TABLE61_PROFILES, TABLE61_SEED, ChainSettings, Encoder,
                       NotchFilter, compare_estimators, constant_speed, controller_times,
                       time_stamping, trapezoid_speed)
from ..sensors._series import rms_error
from ._runs import Runs

__all__ = ["notch_from_zero", "TABLE61_FIT_UNITS", "EncoderFit", "constant_cells", "fit_table61_encoder",
           "tooth_error_bound", "speed_spread", "seed_speed_spread", "trapezoid_spread_bound", "NOTCH_RAMPS_S",
           "notch_to_tsa_ratios", "speed_exponents", "reference_1024", "tsa_orders"]


def notch_from_zero(profile: str, duration_s: float = 10.0) -> tuple[float, float]:
    """RMS errors (velocity, acceleration) of the Table 6.1 notch when its state starts at zero and the whole
    record is scored (no warm-up): our reading of the seed's notch row.

    Our notch starts at its first input (no start-up transient) and Table 6.1 is scored after 1 s; a filter
    whose state starts at 0 sees a step of the full speed at its first sample.  One zero sample fed before
    the record gives that state.
    """
    traj = TABLE61_PROFILES[profile][1](duration_s)
    events = TABLE61_ENCODER.events(traj)
    ts = controller_times(0.0, duration_s, 1000.0)
    tsa = time_stamping(events.times, events.angles, ts)
    fw, fa = NotchFilter(dt_s=1e-3, damping=0.5), NotchFilter(dt_s=1e-3, damping=0.5)
    valid = np.flatnonzero(tsa.valid)
    fw.update(0.0, float(tsa.omega[valid[0]]))
    fa.update(0.0, float(tsa.omega[valid[0]]))
    om = np.array([fw.update(float(tsa.omega[i]), float(tsa.omega[i])) for i in valid])
    al = np.array([fa.update(float(tsa.alpha[i]), float(tsa.omega[i])) for i in valid])
    return (float(np.sqrt(np.mean((om - traj.omega(ts[valid])) ** 2))),
            float(np.sqrt(np.mean((al - traj.alpha(ts[valid])) ** 2))))

#: Unit sizes of the two imperfections in the Table 6.1 fit: eccentricity e/r, per-event transition noise [cycle].
TABLE61_FIT_UNITS = (0.003, 0.004)

@dataclass(frozen=True)
class EncoderFit:
    """The Table 6.1 encoder fitted to three cells of the seed's constant row (see :func:`fit_table61_encoder`)."""

    eccentricity: float
    jitter_cycles: float
    deviation: tuple[float, float, float]
    eccentricity_cells: tuple[float, float, float]
    jitter_cells: tuple[float, float, float]

def constant_cells(encoder: Encoder, duration_s: float) -> tuple[float, float, float]:
    """The fitted cells: constant-speed TSA velocity and acceleration, notch acceleration."""
    c = compare_estimators(TABLE61_PROFILES["constant"][1](duration_s), encoder, estimators=("tsa", "notch"))
    return c["tsa"].rms_omega, c["tsa"].rms_alpha, c["notch"].rms_alpha

def fit_table61_encoder(duration_s: float = 10.0) -> EncoderFit:
    """Eccentricity and per-event transition noise fitted to three cells of seed 001 Table 6.1 (constant row).

    The cells are the TSA velocity and acceleration (0.3007 rad/s, 30.09 rad/s²) and the notch acceleration
    (7.95 rad/s²): the notch removes the first harmonic only, so the last says how much of the TSA
    acceleration error is first harmonic (93 %).  The two imperfections are independent, so their error powers
    add, and each error scales with the imperfection's size: one run of each at its unit size
    (:data:`TABLE61_FIT_UNITS`) gives the model, whose logarithmic deviations from the three cells are
    minimised by least squares (three cells, two unknowns).
    """
    from scipy.optimize import least_squares   # not at import: the CLI's --help must not load scipy

    e0, j0 = TABLE61_FIT_UNITS
    ecc = np.array(constant_cells(Encoder(ppr=60, eccentricity=e0, clock_hz=1e6, seed=1), duration_s))
    jit = np.array(constant_cells(Encoder(ppr=60, jitter_cycles=j0, clock_hz=1e6, seed=1), duration_s))
    seed = np.array([*TABLE61_SEED["constant"]["tsa"], TABLE61_SEED["constant"]["notch"][1]])

    def log_deviation(x: np.ndarray) -> np.ndarray:
        return np.log(np.hypot(x[0] * ecc, x[1] * jit) / seed)

    x = least_squares(log_deviation, [1.0, 1.0]).x
    dev = np.expm1(log_deviation(x))
    return EncoderFit(float(x[0] * e0), float(x[1] * j0), (float(dev[0]), float(dev[1]), float(dev[2])),
                      (float(ecc[0]), float(ecc[1]), float(ecc[2])), (float(jit[0]), float(jit[1]), float(jit[2])))

def tooth_error_bound(duration_s: float = 10.0) -> tuple[float, float]:
    """How much per-tooth (fixed) transition noise the seed's constant row allows, in cycles.

    A fixed error per tooth is periodic in the angle, with power in every harmonic: the notch removes the
    first, the three-stage estimator the first M = 5, so harmonics 2-5 show as the gap between their
    acceleration errors.  The seed's gap is sqrt(7.9528² - 7.9405²) = 0.44 rad/s².  Returns that gap for
    0.01 cycle of tooth noise alone (seed's stage 1) and the tooth noise that would give the seed's gap.
    """
    c = compare_estimators(TABLE61_PROFILES["constant"][1](duration_s), Encoder(ppr=60, dnl_cycles=0.01, seed=1),
                           estimators=("notch", "three-stage"), settings=ChainSettings(highpass_hz=1.0))
    gap = math.sqrt(max(c["notch"].rms_alpha ** 2 - c["three-stage"].rms_alpha ** 2, 0.0))
    seed = TABLE61_SEED["constant"]
    seed_gap = math.sqrt(seed["notch"][1] ** 2 - seed["three-stage"][1] ** 2)
    return gap, 0.01 * seed_gap / gap

def speed_spread(omega: np.ndarray) -> float:
    """``mean(omega^4) / mean(omega^2)^2``: how unevenly a profile spreads its speeds (1 at constant speed)."""
    return float(np.mean(omega ** 4) / np.mean(omega ** 2) ** 2)

def seed_speed_spread() -> float:
    """The least ``mean(omega^4) / mean(omega^2)^2`` of the seed's varying profile that its Table 6.1 allows.

    The TSA error caused by the encoder scales as omega (velocity) and omega^2 (acceleration) (its window is a
    fixed angle), so ``v_var^2 = k_v^2 mean(omega^2) + lag_v^2`` and ``a_var^2 = k_a^2 mean(omega^4) + lag_a^2``
    with ``k`` from the constant row.  The three-stage estimate keeps the lag and removes the periodic part, so
    ``lag_a <= a_3s``; ``lag_v >= 0``.
    """
    s = TABLE61_SEED
    mean4 = (s["varying"]["tsa"][1] ** 2 - s["varying"]["three-stage"][1] ** 2) / s["constant"]["tsa"][1] ** 2
    mean2 = (s["varying"]["tsa"][0] / s["constant"]["tsa"][0]) ** 2
    return mean4 / mean2 ** 2

def trapezoid_spread_bound(points: int = 40) -> float:
    """The largest speed spread of a profile of equal-length plateaus and ramps (low speed from 0 to high)."""
    t = np.linspace(0.0, 4.0, 4001)[:-1]
    return max(speed_spread(trapezoid_speed(max(lo, 1e-3), 1000.0, 4.0).omega(t))
               for lo in np.linspace(0.0, 990.0, points))

#: Ramp lengths of the notch check: the Table 6.1 varying profile with ever steeper ramps.
NOTCH_RAMPS_S = (1.0, 0.5, 0.25, 0.1)

def notch_to_tsa_ratios(duration_s: float = 6.0) -> list[tuple[float, float, float]]:
    """(ramp, notch / TSA velocity error, notch / TSA acceleration error) on the varying profile's plateaus with
    ramps of :data:`NOTCH_RAMPS_S`."""
    out = []
    for ramp in NOTCH_RAMPS_S:
        c = compare_estimators(trapezoid_speed(312.0, 624.0, duration_s, ramp_s=ramp), TABLE61_ENCODER,
                               estimators=("tsa", "notch"))
        out.append((ramp, c["notch"].rms_omega / c["tsa"].rms_omega, c["notch"].rms_alpha / c["tsa"].rms_alpha))
    return out

def speed_exponents(duration_s: float = 6.0) -> tuple[float, float]:
    """Exponents of the TSA velocity and acceleration errors in the speed, at constant 312 and 1020 rpm."""
    lo, hi = (compare_estimators(constant_speed(rpm, duration_s), TABLE61_ENCODER, estimators=("tsa",))["tsa"]
              for rpm in (312.0, 1020.0))
    k = math.log(1020.0 / 312.0)
    return math.log(hi.rms_omega / lo.rms_omega) / k, math.log(hi.rms_alpha / lo.rms_alpha) / k

def reference_1024(profile: str, window: int, duration_s: float = 10.0) -> tuple[float, float, float]:
    """The varying-profile TSA cells against a 1024-ppr reference (TSA of ``window`` events, 1 MHz clock).

    Returns the reference's own RMS errors (velocity, acceleration) and the 60-ppr TSA acceleration cell
    scored against it instead of the exact trajectory.
    """
    traj = TABLE61_PROFILES[profile][1](duration_s)
    tsa = compare_estimators(traj, TABLE61_ENCODER, estimators=("tsa",))["tsa"]
    ev = Encoder(ppr=1024, clock_hz=1e6).events(traj)
    ref = time_stamping(ev.times, ev.angles, tsa.t, window=window)
    scored = tsa.t >= tsa.settings.warmup_s
    return (rms_error(ref.omega, traj.omega(tsa.t), scored), rms_error(ref.alpha, traj.alpha(tsa.t), scored),
            rms_error(tsa.alpha, ref.alpha, scored))

def tsa_orders(runs: Runs) -> tuple[float, float]:
    steps, _, e1, e2 = runs.super_twisting
    return (float(np.polyfit(np.log(steps), np.log(e1), 1)[0]), float(np.polyfit(np.log(steps), np.log(e2), 1)[0]))
