"""Brake controllers: five-phase hybrid ABS, two-phase XBS ABS and the continuous XBS law.

Each controller is a frozen dataclass of tuning parameters (validated once)
whose :meth:`runtime` builds the mutable hybrid automaton used by the
simulation loop.  A runtime exposes

``rate(t, x2, v_wheel, vx, xbs) -> float``
    commanded pressure rate ``dP_b/dt`` [bar/s], a continuous function of the
    signals within a phase;
``guards(x2, xbs) -> tuple``
    one value per outgoing transition of the current phase; a transition fires
    when its value becomes ``> 0`` (the loop locates that instant);
``fire(t, index, x2, v_wheel, vx)``
    takes transition ``index``;
``breakpoint() -> float``
    next time at which ``rate`` has a kink (end of a reference trajectory);
``reference(t) -> (x2_ref, dx2_ref)``
    the wheel-acceleration reference the controller tracks and its slope
    (NaN when it tracks none); the simulations record it.

Sign conventions: ``x2 = R dω/dt - a_x`` is ``z1`` of the models; with
``b = R γ_b / J > 0`` the simplified wheel dynamics read
``dz1/dt = -(a/vx) z1 z2 - b u`` (seed 001 eq. (2.6)); seed 000 writes the same
physics with ``b = -R γ_b / I`` and ``+b u``.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

from .._json import JsonRecord
from ..exceptions import SimulationError
from ._vehicle import BrakeActuator, QuarterCar

__all__ = ["FivePhaseABS", "TwoPhaseABS", "ContinuousXbsControl", "Controller"]

#: Wheel speed floor [m/s] in the rates ``u_i / (R ω)``: near lock-up the command saturates anyway.
_V_WHEEL_FLOOR = 0.1


def _finite(owner: str, **values: float) -> None:
    for key, value in values.items():
        if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
            raise SimulationError(f"{owner}: {key} must be a finite number, got {value!r}")


def _positive(owner: str, **values: float) -> None:
    _finite(owner, **values)
    for key, value in values.items():
        if value <= 0:
            raise SimulationError(f"{owner}: {key} must be > 0, got {value!r}")


@dataclass(frozen=True)
class FivePhaseABS(JsonRecord, error=SimulationError):
    """Five-phase hybrid ABS on wheel-acceleration thresholds (seed 000 Fig. 5, seed 001 Fig. 6.6).

    Phases and transitions (``x2`` the wheel-acceleration offset)::

        0 initial apply  dP/dt = initial_rate        -> 1 when x2 <= -eps0
        1 release        dP/dt = -u1 / (R ω)          -> 2 when x2 >= eps1
        2 hold           dP/dt = 0                    -> 3 when x2 >= eps2, -> 4 when x2 <= eps1
        3 apply          dP/dt = +u3 / (R ω)          -> 4 when x2 <= eps3
        4 apply          dP/dt = +u4 / (R ω)          -> 5 when x2 <= -eps4
        5 hold           dP/dt = 0                    -> 1 when x2 <= -eps5

    Dividing the rates by the wheel speed makes the cycle in the
    ``(lambda, x2)`` plane independent of the speed: in the time
    ``s = ∫ dt / vx`` of seed 001 eq. (3.21), ``dx2/ds`` does not depend on ``vx``.

    With ``tracking=True`` the phases that change the pressure quickly (1, 3
    and 4, seed 000 Fig. 4) track the cubic reference (21) from the value of
    ``x2`` at the phase entry to the exit threshold with the law (22), using
    the XBS the simulation supplies (true value or an observer's estimate).

    Parameters
    ----------
    eps : 6 floats
        ``eps0 .. eps5`` [m/s²], all > 0.  The defaults are our tuning for the
        roads of seed 001 Table 4.1 (see ``docs/abs.md``); :meth:`fig66` gives
        the thresholds printed in seed 001 Sec. 6.4 (50, 30, 40, 20, 20, 30).
    u1, u3, u4 : float
        Rate parameters [bar·m/s²] (``dP/dt = u_i / (R ω)``), tuned with the
        default thresholds.
    initial_rate_bar_s : float
        Pressure build-up of the driver before the ABS takes over.
    tracking : bool
        Closed-loop wheel-acceleration control (21)-(22) in phases 1, 3, 4.
    alpha : float
        Gain ``alpha`` of (22) [1/s].
    overshoot : float
        The reference aims past the exit threshold by this fraction of the
        distance, so that the threshold is crossed in finite time.
    stall_timeout_s : float or None
        Longest stay in the release phase 1 and the hold phase 5 (default
        0.1 s): a hold 5 still below ``-eps4`` (a slow slide on the flat
        post-peak side) then releases (phase 1), any other expiry re-applies
        (phase 4).  Seed 001 Sec. 2.2.3 (the cycle of Fig. 2.2) never holds the
        pressure for good: once the wheel is back in the stable zone it is
        re-applied "slowly and in a stepwise manner ... alternating between the
        'apply pressure' and the 'hold pressure' settings until the wheel
        acceleration drops below the threshold"; the 4 -> 5 -> 4 alternation is
        that stepwise increase.  Fig. 6.6 as printed (``None``) has no such
        exit and stalls in hold 5: the wheel settles in the stable zone at a
        constant pressure after a change to a grippier road (the failure seed
        000 Sec. V reports: "might fail to cycle correctly ... considerable
        changes in the environment"), or slides slowly between ``-eps4`` and
        ``-eps5`` on the flattest characteristics (dry cobblestones above
        120 km/h: 3-6 s in hold 5, braking distance +12 % at 180 km/h).

    Raises
    ------
    SimulationError
        If a threshold is not positive or they are out of order
        (``eps2 > eps1``, ``eps2 > eps3`` and ``eps5 > eps4`` are required for
        every phase to be left through its exit).

    Notes
    -----
    The figure is lost in the seeds' text extraction; the graph above is rebuilt
    from its surviving labels (five phases, the seven guards ``x2 <= -eps0``,
    ``x2 >= eps1``, ``x2 >= eps2``, ``x2 <= eps1``, ``x2 <= eps3``,
    ``x2 <= -eps4``, ``x2 <= -eps5``, rates ``-u1, u3, u4`` over ``R ω``, holds
    in phases 2 and 5) and from seed 001 Sec. 6.4.
    """

    eps: tuple[float, float, float, float, float, float] = (110.0, 12.0, 40.0, 13.0, 19.0, 23.0)
    u1: float = 7000.0
    u3: float = 1250.0
    u4: float = 2400.0
    initial_rate_bar_s: float = 1000.0
    tracking: bool = False
    alpha: float = 150.0
    overshoot: float = 0.1
    stall_timeout_s: float | None = 0.1

    name = "five-phase"
    uses_xbs_default = False

    def __post_init__(self) -> None:
        eps = tuple(self.eps)
        if len(eps) != 6:
            raise SimulationError(f"five-phase ABS needs 6 thresholds eps0..eps5, got {len(eps)}: {eps!r}")
        _positive("five-phase ABS", **{f"eps{i}": e for i, e in enumerate(eps)})
        object.__setattr__(self, "eps", tuple(float(e) for e in eps))
        e0, e1, e2, e3, e4, e5 = self.eps
        for ok, text in ((e2 > e1, f"eps2 = {e2} must exceed eps1 = {e1} (phase 2 is entered at eps1 and left "
                                    f"upwards at eps2)"),
                         (e2 > e3, f"eps3 = {e3} must be below eps2 = {e2} (phase 3 is entered at eps2 and left "
                                   f"downwards at eps3)"),
                         (e5 > e4, f"eps5 = {e5} must exceed eps4 = {e4} (phase 5 is entered at -eps4 and left "
                                   f"downwards at -eps5)")):
            if not ok:
                raise SimulationError(f"five-phase ABS thresholds out of order: {text}")
        _positive("five-phase ABS", u1=self.u1, u3=self.u3, u4=self.u4,
                  initial_rate_bar_s=self.initial_rate_bar_s, alpha=self.alpha)
        _finite("five-phase ABS", overshoot=self.overshoot)
        if not 0.0 <= self.overshoot < 1.0:
            raise SimulationError(f"five-phase ABS: overshoot must be in [0, 1), got {self.overshoot}")
        if self.stall_timeout_s is not None:
            _positive("five-phase ABS", stall_timeout_s=self.stall_timeout_s)

    @property
    def uses_xbs(self) -> bool:
        return self.tracking

    @classmethod
    def fig66(cls) -> FivePhaseABS:
        """The thresholds of seed 001 Sec. 6.4 / Fig. 6.6: ``eps = (50, 30, 40, 20, 20, 30)`` m/s².

        With the flat post-peak characteristics of Table 2.1 the hold between
        ``-eps4`` and ``-eps5`` lets the slip run deep (about 90 % of the peak
        friction on dry asphalt); the default tuning keeps that hold short.
        Change the other parameters with :func:`dataclasses.replace`.
        """
        return cls(eps=(50.0, 30.0, 40.0, 20.0, 20.0, 30.0))

    def runtime(self, plant: QuarterCar, actuator: BrakeActuator) -> _FivePhaseRuntime:
        return _FivePhaseRuntime(self, plant, actuator)

    def to_json(self) -> dict[str, Any]:
        return {"name": self.name, **asdict(self), "eps": list(self.eps)}

    def __str__(self) -> str:
        eps = ", ".join(f"{e:g}" for e in self.eps)
        mode = f", tracking (21)-(22) alpha={self.alpha:g}" if self.tracking else ""
        if self.stall_timeout_s is not None:
            mode += f", stall timeout {self.stall_timeout_s:g} s"
        return f"five-phase ABS: eps=({eps}) m/s², u=({self.u1:g}, {self.u3:g}, {self.u4:g}){mode}"


class _FivePhaseRuntime:
    __slots__ = ("phase", "a", "b", "max_rate", "r0", "rates", "table", "tracking", "alpha", "overshoot",
                 "t0", "T", "ref0", "ref_a2", "ref_a3", "target", "timeout", "deadline")

    def __init__(self, cfg: FivePhaseABS, plant: QuarterCar, actuator: BrakeActuator):
        e0, e1, e2, e3, e4, e5 = cfg.eps
        self.phase = 0
        self.a = plant.a
        self.b = plant.b
        self.max_rate = actuator.max_rate_bar_s
        self.r0 = cfg.initial_rate_bar_s
        self.rates = (0.0, -cfg.u1, 0.0, cfg.u3, cfg.u4, 0.0)
        # per phase: (sign, threshold, next phase); fires when sign * (x2 - threshold) > 0
        self.table = (((-1.0, -e0, 1),),
                      ((1.0, e1, 2),),
                      ((1.0, e2, 3), (-1.0, e1, 4)),
                      ((-1.0, e3, 4),),
                      ((-1.0, -e4, 5),),
                      ((-1.0, -e5, 1),))
        self.tracking = cfg.tracking
        self.alpha = cfg.alpha
        self.overshoot = cfg.overshoot
        self.t0 = 0.0
        self.T = 0.0
        self.ref0 = self.ref_a2 = self.ref_a3 = self.target = 0.0
        self.timeout = cfg.stall_timeout_s
        self.deadline = math.inf

    def rate(self, t: float, x2: float, v_wheel: float, vx: float, xbs: float) -> float:
        p = self.phase
        if p == 0:
            return self.r0
        if self.tracking and p in (1, 3, 4):
            ref, dref = self.reference(t)
            # (22) with b > 0 and dz1/dt = -(a/vx) z1 z2 - b u: closed loop dxi/dt = -alpha xi
            return (-self.a / vx * xbs * x2 - dref + self.alpha * (x2 - ref)) / self.b
        r = self.rates[p]
        if r == 0.0:
            return 0.0
        return r / (v_wheel if v_wheel > _V_WHEEL_FLOOR else _V_WHEEL_FLOOR)

    def reference(self, t: float) -> tuple[float, float]:
        """The cubic (21) and its slope at ``t`` in the tracked phases 1, 3, 4; NaN otherwise."""
        if not (self.tracking and self.phase in (1, 3, 4)):
            return (math.nan, math.nan)
        tau = t - self.t0
        if tau < self.T:
            return (self.ref0 + tau * tau * (self.ref_a2 + self.ref_a3 * tau),
                    tau * (2.0 * self.ref_a2 + 3.0 * self.ref_a3 * tau))
        return (self.target, 0.0)

    #: the guards read x2 only, so they can be located within a step whatever the XBS source
    guards_use_xbs = False

    def guards(self, x2: float, xbs: float) -> tuple[float, ...]:
        return tuple(s * (x2 - thr) for s, thr, _ in self.table[self.phase])

    def fire(self, t: float, index: int, x2: float, v_wheel: float, vx: float) -> None:
        self._enter(self.table[self.phase][index][2], t, x2, v_wheel)

    def expire(self, t: float, x2: float, v_wheel: float, vx: float) -> None:
        """The stall timeout of the current phase has run out.

        A hold 5 still below ``-eps4`` is a slow slide on the flat side of the
        characteristic: release (phase 1).  Otherwise the wheel is under-braked:
        re-apply (phase 4).
        """
        self._enter(1 if self.phase == 5 and x2 <= self.table[4][0][1] else 4, t, x2, v_wheel)

    def _enter(self, p: int, t: float, x2: float, v_wheel: float) -> None:
        self.phase = p
        self.t0 = t
        # phase 2 always ends: x2 > 0 there, the wheel recovers and x2 decays below eps1 in the stable zone
        self.deadline = t + self.timeout if self.timeout is not None and p in (1, 5) else math.inf
        if self.tracking and p in (1, 3, 4):
            exit_thr = self.table[p][0][1]
            target = exit_thr + self.overshoot * (exit_thr - x2)
            span = target - x2
            # (21): cubic from x2 to target with zero slope at both ends; its peak slope 3|span|/(2T)
            # must stay within what the phase's open-loop rate (and the actuator) can produce
            open_loop = abs(self.rates[p]) / max(v_wheel, _V_WHEEL_FLOOR)
            rate = min(open_loop, self.max_rate)
            self.T = 1.5 * abs(span) / (self.b * rate)
            self.ref0 = x2
            self.ref_a2 = 3.0 * span / self.T ** 2
            self.ref_a3 = -2.0 * span / self.T ** 3
            self.target = target

    def breakpoint(self) -> float:
        if self.tracking and self.phase in (1, 3, 4):
            return self.t0 + self.T
        return self.deadline


@dataclass(frozen=True)
class TwoPhaseABS(JsonRecord, error=SimulationError):
    """Two-phase XBS-based hybrid ABS (seed 001 Fig. 4.3, law (4.3) without ``dz1*/dt``).

    Phase 1 tracks ``z1* = +z_ref`` until the XBS exceeds ``chi_b``; phase 2
    tracks ``z1* = -z_ref`` until it drops below ``chi_a``; the tracking law is
    ``u = (1/b)(-(a/vx) z1 z2 + (kp/vx)(z1 - z1*))`` (seed 001 eq. (4.3) with
    ``dz1*/dt = 0`` almost everywhere, Sec. 4.4).  A phase 0 builds the pressure
    up at the driver's rate until the XBS first drops below ``chi_a`` (or the
    wheel decelerates past ``start_decel_m_s2``).

    Parameters
    ----------
    z_ref : float
        ``z1^ref`` [m/s²], > 0.
    chi_a, chi_b : float
        XBS thresholds, ``chi_a <= 0 < chi_b``.
    kp : float
        Gain of (4.3) [m/s]; ``alpha = kp`` in the Poincaré analysis (Sec. 4.3).
    initial_rate_bar_s : float
    start_decel_m_s2 : float, optional
        Start-up safeguard (ours): phase 0 also ends when ``x2 <= -start_decel_m_s2``,
        so that an observer that has not converged during the pressure build-up
        (no excitation yet) cannot let the wheel lock; ``None`` disables it.

    Raises
    ------
    SimulationError
        For ``z_ref <= 0``, ``kp <= 0`` or thresholds out of order.
    """

    z_ref: float = 8.0
    chi_a: float = -0.1
    chi_b: float = 0.1
    kp: float = 3000.0
    initial_rate_bar_s: float = 1000.0
    start_decel_m_s2: float | None = 110.0

    name = "two-phase"
    uses_xbs = True

    def __post_init__(self) -> None:
        _positive("two-phase ABS", z_ref=self.z_ref, kp=self.kp, initial_rate_bar_s=self.initial_rate_bar_s)
        _finite("two-phase ABS", chi_a=self.chi_a, chi_b=self.chi_b)
        if self.start_decel_m_s2 is not None:
            _positive("two-phase ABS", start_decel_m_s2=self.start_decel_m_s2)
        if not self.chi_a <= 0.0 < self.chi_b:
            raise SimulationError(
                f"two-phase ABS thresholds out of order: need chi_a <= 0 < chi_b (seed 001 Sec. 4.2), "
                f"got chi_a = {self.chi_a}, chi_b = {self.chi_b}")

    def runtime(self, plant: QuarterCar, actuator: BrakeActuator) -> _TwoPhaseRuntime:
        return _TwoPhaseRuntime(self, plant)

    def to_json(self) -> dict[str, Any]:
        return {"name": self.name, **asdict(self)}

    def __str__(self) -> str:
        return (f"two-phase ABS: z_ref={self.z_ref:g} m/s², chi_a={self.chi_a:g}, chi_b={self.chi_b:g}, "
                f"kp={self.kp:g}")


class _TwoPhaseRuntime:
    __slots__ = ("phase", "a", "b", "r0", "z_ref", "chi_a", "chi_b", "kp", "start")
    guards_use_xbs = True
    deadline = math.inf

    def __init__(self, cfg: TwoPhaseABS, plant: QuarterCar):
        self.phase = 0
        self.a = plant.a
        self.b = plant.b
        self.r0 = cfg.initial_rate_bar_s
        self.z_ref = cfg.z_ref
        self.chi_a = cfg.chi_a
        self.chi_b = cfg.chi_b
        self.kp = cfg.kp
        self.start = -cfg.start_decel_m_s2 if cfg.start_decel_m_s2 is not None else -math.inf

    def rate(self, t: float, x2: float, v_wheel: float, vx: float, xbs: float) -> float:
        p = self.phase
        if p == 0:
            return self.r0
        z1_ref = self.z_ref if p == 1 else -self.z_ref
        return (-self.a * x2 * xbs + self.kp * (x2 - z1_ref)) / (vx * self.b)

    def guards(self, x2: float, xbs: float) -> tuple[float, ...]:
        if self.phase == 1:
            return (xbs - self.chi_b,)
        if self.phase == 0:
            return (self.chi_a - xbs, self.start - x2)
        return (self.chi_a - xbs,)

    def fire(self, t: float, index: int, x2: float, v_wheel: float, vx: float) -> None:
        self.phase = 2 if self.phase == 1 else 1

    def breakpoint(self) -> float:
        return math.inf

    def reference(self, t: float) -> tuple[float, float]:
        """No wheel-acceleration reference curve: (4.3) tracks the constant ``±z_ref`` (recorded as NaN)."""
        return (math.nan, math.nan)


@dataclass(frozen=True)
class ContinuousXbsControl(JsonRecord, error=SimulationError):
    """Continuous XBS regulation of seed 001 Sec. 4.1, eqs. (4.2)-(4.3).

    ``z1* = -kr z2 / (c z2 + d)`` and
    ``u = (1/b)(-(a/vx) z1 z2 + (kp/vx)(z1 - z1*) - dz1*/dt)`` with
    ``dz1*/dt = -(kr/vx) d z1 / (c z2 + d)``.  It drives ``(z1, z2)`` to the
    origin, so ``z1 -> 0`` is not persistently exciting (Assumption 1 fails) and
    an observer fed by it does not converge (seed 001 Figs. 4.1-4.2).  When the
    XBS it is given reaches ``c z2 + d <= 0`` the law is undefined and the
    simulation stops with status ``controller-singular`` (Fig. 4.2(b)).

    Parameters
    ----------
    kr, kp : float
        Gains of (4.2) and (4.3), > 0.
    c, d : float, optional
        Road parameters ``c = -c2``, ``d = -c2 c3`` (braking); default: those of
        the initial road.
    start_xbs : float
        The law takes over from the driver's ramp when the XBS drops below this value.
    initial_rate_bar_s : float
    """

    kr: float = 50.0
    kp: float = 3000.0
    c: float | None = None
    d: float | None = None
    start_xbs: float = 0.0
    initial_rate_bar_s: float = 1000.0

    name = "continuous"
    uses_xbs = True

    def __post_init__(self) -> None:
        _positive("continuous XBS control", kr=self.kr, kp=self.kp, initial_rate_bar_s=self.initial_rate_bar_s)
        _finite("continuous XBS control", start_xbs=self.start_xbs)
        for key in ("c", "d"):
            if getattr(self, key) is not None:
                _positive("continuous XBS control", **{key: getattr(self, key)})

    def runtime(self, plant: QuarterCar, actuator: BrakeActuator, *, c: float, d: float) -> _ContinuousRuntime:
        return _ContinuousRuntime(self, plant, self.c if self.c is not None else c,
                                  self.d if self.d is not None else d)

    def to_json(self) -> dict[str, Any]:
        return {"name": self.name, **asdict(self)}

    def __str__(self) -> str:
        return f"continuous XBS control (4.2)-(4.3): kr={self.kr:g}, kp={self.kp:g}"


class _ContinuousRuntime:
    __slots__ = ("phase", "a", "b", "r0", "kr", "kp", "c", "d", "start", "failure")
    guards_use_xbs = True
    deadline = math.inf

    def __init__(self, cfg: ContinuousXbsControl, plant: QuarterCar, c: float, d: float):
        self.phase = 0
        self.a = plant.a
        self.b = plant.b
        self.r0 = cfg.initial_rate_bar_s
        self.kr = cfg.kr
        self.kp = cfg.kp
        self.c = c
        self.d = d
        self.start = cfg.start_xbs
        self.failure: str | None = None

    def rate(self, t: float, x2: float, v_wheel: float, vx: float, xbs: float) -> float:
        if self.phase == 0:
            return self.r0
        den = self.c * xbs + self.d
        if den <= 0.0:
            if self.failure is None:
                self.failure = (f"c z2 + d = {den:.3g} <= 0 at t = {t:.4f} s (XBS {xbs:.4g}): the virtual "
                                f"reference (4.2) is undefined")
            return 0.0
        z1_ref = -self.kr * xbs / den
        dz1_ref = -self.kr * self.d * x2 / (vx * den)
        return (-self.a * x2 * xbs + self.kp * (x2 - z1_ref) - vx * dz1_ref) / (vx * self.b)

    def guards(self, x2: float, xbs: float) -> tuple[float, ...]:
        return (self.start - xbs,) if self.phase == 0 else ()

    def fire(self, t: float, index: int, x2: float, v_wheel: float, vx: float) -> None:
        self.phase = 1

    def breakpoint(self) -> float:
        return math.inf

    def reference(self, t: float) -> tuple[float, float]:
        """The virtual reference (4.2) is a function of the XBS, not a curve in time: recorded as NaN."""
        return (math.nan, math.nan)


Controller = FivePhaseABS | TwoPhaseABS | ContinuousXbsControl
