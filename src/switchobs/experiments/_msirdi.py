"""Seed 003 (M'Sirdi et al. 2008) Secs. III-B, IV and V: the vehicle-speed observer, the equivalent output
injections and the identification of ``theta_1`` and ``theta_2`` on the torque-driven quarter car.

The seed's own runs are on measured data (a Peugeot 406, Sec. VI) and give no number for Secs. III-B to V;
what it states is Theorem 3 (finite time for ``beta > eta``), (20)-(21) (``z_bar = xi`` as ``tau -> 0`` and
``delta / tau -> 0``) and that the RLS identifies ``theta_1``, ``theta_2``.  The set-up here is ours: the
quarter car of :mod:`switchobs.plants` (``J = 1.2``, ``R = 0.3``, ``F_z = 2850`` N) with the linear tyre (5)
of stiffness :data:`MSIRDI_STIFFNESS_N`, braked from 36 m/s by the torque :func:`msirdi_torque`, whose 2 Hz
modulation swings the slip between about 1 % and 6 % (persistent excitation of the regressors).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from ..plants import QuarterCar
from ..sensors import (AngleTrajectory, SpeedParameterEstimate, StiffnessEstimate, VehicleSpeedGain, WheelRun, identify_speed_parameters,
                       identify_stiffness, linear_tyre, low_pass, simulate_wheel, super_twisting, super_twisting_gains,
                       vehicle_speed_gain, vehicle_speed_observer)

__all__ = ["MSIRDI_STIFFNESS_N", "MSIRDI_SPEED0_M_S", "MSIRDI_DURATION_S", "MSIRDI_F_PLUS", "MSIRDI_START_S",
           "MSIRDI_INITIAL_ERROR_M_S", "MSIRDI_MARGINS", "MSIRDI_INJECTION_STEPS", "MSIRDI_ID_STEP_S",
           "MSIRDI_ID_TAU_S", "msirdi_torque", "msirdi_wheel", "ReachingRow", "theorem3_reaching", "InjectionRow",
           "equivalent_injection", "Identification", "identify_theta", "MSIRDI_COARSE_STEP_S", "MSIRDI_REACHING_STEP_S", "MsirdiRuns",
           "msirdi_runs"]

Array = npt.NDArray[np.float64]

#: Linear tyre stiffness C_x (N per unit slip), chosen by us (the seed identifies it from measured data).
MSIRDI_STIFFNESS_N = 60000.0
#: Initial speed (m/s) and duration (s) of the braking.
MSIRDI_SPEED0_M_S = 36.0
MSIRDI_DURATION_S = 3.0
#: Bound f+ of the super-twisting gain rule (12) (rad/s^2): |xi1| = R |F_x| / J stays below 900.
MSIRDI_F_PLUS = 1500.0
#: Start of the scoring and of the RLS (s): after both observers' finite-time transients (t2 of Sec. IV).
MSIRDI_START_S = 0.5
#: Initial error x3_hat(0) - x3(0) (m/s) of the Theorem 3 runs: positive, so that the braking force opposes it.
MSIRDI_INITIAL_ERROR_M_S = 2.0
#: Sample step of the Theorem 3 runs (s).
MSIRDI_REACHING_STEP_S = 1e-4
#: Margins (beta - eta) / eta of the Theorem 3 runs; the last two violate it.
MSIRDI_MARGINS: tuple[float, ...] = (2.0, 1.0, 0.5, 0.25, 0.1, -0.1, -0.5)
#: (delta, tau) of the injection runs: tau halves and delta / tau halves with it, as Sec. IV asks.
MSIRDI_INJECTION_STEPS: tuple[tuple[float, float], ...] = ((4e-4, 0.02), (1e-4, 0.01), (2.5e-5, 0.005))
#: Step and filter of the identification run: the super-twisting speed error is O(delta) (Theorem 2) and the
#: regressors see the slip through it, so the identification needs a fine step.
MSIRDI_ID_STEP_S = 1e-5
MSIRDI_ID_TAU_S = 0.01
#: The step twice as coarse, to show the bias of the identification shrink with the step.
MSIRDI_COARSE_STEP_S = 2e-5


def msirdi_torque(t: float) -> float:
    """Brake torque (N m): ``-800 (1 + 0.5 sin(4 pi t))``."""
    return -800.0 * (1.0 + 0.5 * math.sin(4.0 * math.pi * t))


def msirdi_wheel(vehicle: QuarterCar = QuarterCar()) -> WheelRun:
    """The braking run on the linear tyre of stiffness :data:`MSIRDI_STIFFNESS_N` (seed 003 (1)-(5))."""
    return simulate_wheel(msirdi_torque, linear_tyre(MSIRDI_STIFFNESS_N), speed0_m_s=MSIRDI_SPEED0_M_S,
                          duration_s=MSIRDI_DURATION_S, vehicle=vehicle)


def _xi2(run: WheelRun) -> Array:
    """``xi2 = dx3/dt = F_x / m`` on the run's grid (14)."""
    return run.force_n / float(run.vehicle.mass_kg)  # type: ignore[arg-type]


def _eta(run: WheelRun) -> float:
    """The bound ``eta = max |xi2|`` of Theorem 3, on the run."""
    return float(np.max(np.abs(_xi2(run))))


@dataclass(frozen=True)
class ReachingRow:
    """One run of the observer (15) from ``x3_hat(0) = x3(0) + e0`` (Theorem 3)."""

    margin: float            # (beta - eta) / eta
    beta: float              # m/s^2
    eta: float               # m/s^2
    mean_xi2: float          # mean |xi2| over the run (m/s^2): what beta must beat on average to reach x3
    reached_s: float         # first sign change of x3_tilde, nan if none
    bound_s: float           # |e0| / (beta - eta), inf if beta <= eta
    lower_s: float           # |e0| / (beta + eta): no observer reaches sooner
    band_m_s: float          # (beta + eta) delta: the discrete sliding band
    after_max_m_s: float     # largest |x3_tilde| after reached_s (nan if never reached)
    final_error_m_s: float   # x3_tilde at the end of the run


def theorem3_reaching(run: WheelRun, margins: Sequence[float] = MSIRDI_MARGINS, *, delta_s: float = MSIRDI_REACHING_STEP_S,
                      initial_error_m_s: float = MSIRDI_INITIAL_ERROR_M_S) -> tuple[ReachingRow, ...]:
    """The observer (15) with ``beta = (1 + margin) eta`` on the measured speed of ``run``, sampled at ``delta_s``."""
    t = np.arange(0.0, MSIRDI_DURATION_S, delta_s)
    v = np.interp(t, run.t, run.speed_m_s)
    eta = _eta(run)
    mean = float(np.mean(np.abs(_xi2(run))))
    rows = []
    for m in margins:
        beta = (1.0 + m) * eta
        # built directly, not by vehicle_speed_gain: the negative margins violate Theorem 3 on purpose
        obs = vehicle_speed_observer(t, v, gain=VehicleSpeedGain(beta=beta, eta=eta),
                                     x3_0=float(v[0]) + initial_error_m_s)
        t1 = obs.reaching_time_s
        after = np.abs(obs.error[t >= t1]) if math.isfinite(t1) else np.array([math.nan])
        rows.append(ReachingRow(margin=m, beta=beta, eta=eta, mean_xi2=mean, reached_s=t1,
                                bound_s=obs.gain.reaching_time_bound(initial_error_m_s),
                                lower_s=abs(initial_error_m_s) / (beta + eta), band_m_s=(beta + eta) * delta_s,
                                after_max_m_s=float(after.max()), final_error_m_s=float(obs.error[-1])))
    return tuple(rows)


@dataclass(frozen=True)
class InjectionRow:
    """The filtered injections (20)-(21) against the unknown accelerations, after ``MSIRDI_START_S``."""

    delta_s: float
    tau_s: float
    xi1_rms: float           # RMS of z2_bar - xi1 (rad/s^2)
    xi1_rel: float           # that RMS / max |xi1|
    xi2_rms: float           # RMS of z3_bar - xi2 (m/s^2)
    xi2_rel: float           # that RMS / max |xi2|


def _observers(run: WheelRun, traj: AngleTrajectory, delta_s: float) -> tuple[Array, Array, Array, Array, Array]:
    """Both observers on the run sampled at ``delta_s``: ``(t, z2, x2_hat, z3, x3)``."""
    t = np.arange(0.0, MSIRDI_DURATION_S, delta_s)
    J = run.vehicle.inertia_kg_m2
    u = np.array([msirdi_torque(x) for x in t])
    st = super_twisting(t, traj.theta(t), gains=super_twisting_gains(MSIRDI_F_PLUS), f1=u / J)
    v = np.interp(t, run.t, run.speed_m_s)
    sp = vehicle_speed_observer(t, v, gain=vehicle_speed_gain(_eta(run)))
    return t, st.z2, st.x2_hat, sp.z3, v


def equivalent_injection(run: WheelRun, steps: Sequence[tuple[float, float]] = MSIRDI_INJECTION_STEPS, *,
                         trajectory: AngleTrajectory | None = None) -> tuple[InjectionRow, ...]:
    """``z2_bar`` against ``xi1 = -R F_x / J`` and ``z3_bar`` against ``xi2 = F_x / m`` (seed 003 (20)-(21)).

    ``trajectory`` is ``run.trajectory()``, given when the caller has it: its quintic Hermite pieces cost
    more than a run of the observers."""
    R, J = run.vehicle.radius_m, run.vehicle.inertia_kg_m2
    traj = run.trajectory() if trajectory is None else trajectory
    rows = []
    for delta, tau in steps:
        t, z2, _, z3, _ = _observers(run, traj, delta)
        xi1 = np.interp(t, run.t, -R * run.force_n / J)
        xi2 = np.interp(t, run.t, _xi2(run))
        late = t >= MSIRDI_START_S
        e1 = float(np.sqrt(np.mean((low_pass(z2, delta, tau) - xi1)[late] ** 2)))
        e2 = float(np.sqrt(np.mean((low_pass(z3, delta, tau) - xi2)[late] ** 2)))
        rows.append(InjectionRow(delta_s=delta, tau_s=tau, xi1_rms=e1, xi1_rel=e1 / float(np.max(np.abs(xi1))),
                                 xi2_rms=e2, xi2_rel=e2 / float(np.max(np.abs(xi2)))))
    return tuple(rows)


@dataclass(frozen=True)
class Identification:
    """``theta_1`` (Sec. V-A) and ``theta_2`` (Sec. V-B, Remarks 4 and 5) identified on one run."""

    theta1: StiffnessEstimate            # [R C_x, R^2 C_x] from z2_bar
    theta2_remark4: SpeedParameterEstimate   # C_x from z3_bar, R C_x taken from theta1
    theta2_remark5: SpeedParameterEstimate   # [C_x, R C_x] from z3_bar, started from theta1's values
    stiffness_n: float                   # the truth, C_x
    radius_m: float                      # the truth, R

    @property
    def truth(self) -> dict[str, float]:
        """The true ``theta_11, theta_12, theta_21, theta_22``."""
        c, r = self.stiffness_n, self.radius_m
        return {"theta_11": r * c, "theta_12": r * r * c, "theta_21": c, "theta_22": r * c}

    @property
    def identified(self) -> dict[str, tuple[float, ...]]:
        """``theta_11, theta_12`` (V-A), ``theta_21`` (Remark 4), ``theta_21, theta_22`` (Remark 5)."""
        t1, r4, r5 = self.theta1.history[-1], self.theta2_remark4.history[-1], self.theta2_remark5.history[-1]
        return {"theta_11": (float(t1[0]),), "theta_12": (float(t1[1]),), "theta_21": (float(r4[0]), float(r5[0])),
                "theta_22": (float(r5[1]),)}


def identify_theta(run: WheelRun, *, delta_s: float = MSIRDI_ID_STEP_S, tau_s: float = MSIRDI_ID_TAU_S,
                   trajectory: AngleTrajectory | None = None) -> Identification:
    """Both observers on ``run``, then the RLS (27)-(30) on ``z2_bar`` for ``theta_1`` and on ``z3_bar`` for
    ``theta_2``: Remark 4 with ``theta_22 = R C_x`` from the ``theta_1`` step, Remark 5 both entries from
    ``theta_1``'s values.  ``J`` and ``m`` are known (Sec. V); ``trajectory`` as in :func:`equivalent_injection`."""
    traj = run.trajectory() if trajectory is None else trajectory
    t, z2, x2_hat, z3, v = _observers(run, traj, delta_s)
    veh = run.vehicle
    th1 = identify_stiffness(t, z2, x2_hat, v, inertia_kg_m2=veh.inertia_kg_m2, tau_s=tau_s, start_s=MSIRDI_START_S)
    m = float(veh.mass_kg)  # type: ignore[arg-type]
    rc = th1.stiffness_radius
    r4 = identify_speed_parameters(t, z3, x2_hat, v, mass_kg=m, stiffness_radius_nm=rc, tau_s=tau_s,
                                   start_s=MSIRDI_START_S)
    r5 = identify_speed_parameters(t, z3, x2_hat, v, mass_kg=m, initial=[th1.stiffness_n, rc], tau_s=tau_s,
                                   start_s=MSIRDI_START_S)
    return Identification(theta1=th1, theta2_remark4=r4, theta2_remark5=r5, stiffness_n=MSIRDI_STIFFNESS_N,
                          radius_m=veh.radius_m)


@dataclass(frozen=True)
class MsirdiRuns:
    """Every run of this module on one braking (what ``switchobs reproduce`` quotes)."""

    reaching: tuple[ReachingRow, ...]
    injection: tuple[InjectionRow, ...]
    identification: Identification           # delta = MSIRDI_ID_STEP_S
    coarse: Identification                   # delta = MSIRDI_COARSE_STEP_S


def msirdi_runs() -> MsirdiRuns:
    """:func:`theorem3_reaching`, :func:`equivalent_injection` and :func:`identify_theta` (at two steps) on
    :func:`msirdi_wheel`."""
    run = msirdi_wheel()
    traj = run.trajectory()
    return MsirdiRuns(reaching=theorem3_reaching(run), injection=equivalent_injection(run, trajectory=traj),
                      identification=identify_theta(run, trajectory=traj),
                      coarse=identify_theta(run, delta_s=MSIRDI_COARSE_STEP_S, trajectory=traj))
