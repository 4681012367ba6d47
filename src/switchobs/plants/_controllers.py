"""Brake controllers: five-phase and six-phase (Bosch) hybrid ABS, two-phase XBS ABS and the continuous XBS law.

Each controller is a frozen dataclass of tuning parameters (validated once)
whose :meth:`runtime` builds the mutable hybrid automaton used by the
simulation loop.  A runtime exposes

``rate(t, x2, v_wheel, vx, xbs) -> float``
    commanded pressure rate ``dP_b/dt`` [bar/s], a continuous function of the
    signals within a phase;
``guards(x2, xbs, slip) -> tuple``
    one value per outgoing transition of the current phase; a transition fires
    when its value becomes ``> 0`` (the loop locates that instant); ``slip`` is
    the wheel slip ``(R ω - v_ref) / v_ref`` with the vehicle speed the
    controller is given as reference;
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

__all__ = ["FivePhaseABS", "SixPhaseABS", "TwoPhaseABS", "ContinuousXbsControl", "Controller"]

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

    def guards(self, x2: float, xbs: float, slip: float) -> tuple[float, ...]:
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
class SixPhaseABS(JsonRecord, error=SimulationError):
    """Six-phase ABS on wheel-deceleration thresholds ``-a``, ``+a``, ``+A`` and a slip threshold ``lambda1``.

    The classical Bosch cycle of seed 001 Sec. 2.2.3 (Fig. 2.2, after [94, p. 82]), which we take as the
    "six-phase ABS control algorithm" of seed 001 Sec. 3.6 (that section names it without describing
    it): after the driver's build-up (Bosch phase 1) six control phases follow.  ``x2`` is the
    wheel-acceleration offset, ``slip`` the wheel slip against the reference speed the controller is
    given (the vehicle speed, or its estimate on the two-axle vehicle: the seed's ``vRef``)::

        ours Bosch
        0    1  apply (driver)  dP/dt = initial_rate      -> 6 when x2 <= -a
        6    2  hold            dP/dt = 0                 -> 1 when slip <= -lambda1
        1    3  release         dP/dt = -u_release / (R ω) -> 2 when x2 >= -a (and slip >= -lock_slip)
        2    4  hold            dP/dt = 0                 -> 3 when x2 >= +A
        3    5  apply           dP/dt = +u_apply / (R ω)   -> 4 when x2 <= +A
        4    6  hold            dP/dt = 0                 -> 5 when x2 <= +a
        5    7  slow apply      dP/dt = +u_step / (R ω)    -> 1 when x2 <= -a (Bosch phase 8 = second phase 3)

    Our numbers keep phase 1 the release (as in :class:`FivePhaseABS`, so that the ABS cycles of the
    metrics count releases); :attr:`BOSCH` maps them to Bosch's.  As the seed says, ``lambda1`` is used in
    the first cycle only: from the second cycle on the release starts at ``-a`` directly.

    What the seed gives: the phases, their order, the three modulator settings of each and the
    thresholds that end them (Sec. 2.2.3); that ``-a`` is not the opposite of ``+a``; that ``+A`` is
    "relatively high"; that the phase-7 increase is slow, "alternating between the 'apply pressure' and
    the 'hold pressure' settings", and (Sec. 2.2.2) that valve pulse-width modulation sets the rate of a
    pressure change.  What we chose (the seed gives no value, and Fig. 2.2 is lost in the text
    extraction):

    * the threshold values (defaults tuned on the roads of Table 2.1, see ``docs/abs.md``);
    * the rates, divided by ``R ω`` like the five-phase ABS's so that the cycle in the ``(lambda, x2)``
      plane does not depend on the speed;
    * phase 7 as a continuous slow apply at the mean rate of the apply/hold pulse train (the seed's
      PWM remark): pulses would only add a ripple of the pulse period;
    * the exits the description lacks (without them the cycle stalls): a Bosch hold 2 or 4 (ours 6 or 2)
      that lasts ``hold_timeout_s`` goes on to the slow apply (in hold 2 the ``-a`` crossing was a false
      alarm of the stable zone, in hold 4 the wheel recovered without reaching ``+A``, as on ice or snow);
      a hold 4 whose ``x2`` falls ``rerelease_margin`` below ``-a`` releases again; a release lasts at
      least ``release_min_bar``; a hold or apply in which the slip passes ``-lock_slip`` releases (a locked wheel has ``dω/dt = 0``, so ``x2 =
      -a_x > -a`` and the deceleration thresholds alone never see it), and that release ends only when
      the slip is back above ``-lock_slip``.

    Parameters
    ----------
    a_minus, a_plus, a_big : float
        The thresholds ``-a``, ``+a`` and ``+A`` as positive magnitudes [m/s²]: the guards read
        ``x2 <= -a_minus``, ``x2 <= a_plus``, ``x2 >= a_big``; ``a_big > a_plus`` is required.
    slip_threshold : float
        ``lambda1`` (> 0) of the first cycle.
    lock_slip : float
        Lock protection (ours), ``slip_threshold < lock_slip < 1``.
    u_release, u_apply, u_step : float
        Rate parameters [bar·m/s²] of phases 1 (Bosch 3), 3 (Bosch 5) and 5 (Bosch 7); ``u_step < u_apply``.
    initial_rate_bar_s : float
        The driver's build-up (phase 0).
    hold_timeout_s : float
        Longest stay in the holds 6 and 2 (Bosch 2 and 4) before the slow apply.
    rerelease_margin : float
        A hold 2 (Bosch 4) whose ``x2`` falls this far below ``-a`` releases again (ours: the stepwise
        release of a wheel that does not recover) [m/s²].
    release_min_bar : float
        A release drops at least about this pressure before ``x2 >= -a`` can end it (ours: in the real
        cycle the brake's lag keeps the deceleration below ``-a`` after the release starts; without a lag
        ``x2`` would cross ``-a`` at once) [bar].

    Raises
    ------
    SimulationError
        A value that is not positive or thresholds and rates out of order.
    """

    a_minus: float = 70.0
    a_plus: float = 8.0
    a_big: float = 20.0
    slip_threshold: float = 0.1
    lock_slip: float = 0.6
    u_release: float = 7000.0
    u_apply: float = 3000.0
    u_step: float = 2000.0
    initial_rate_bar_s: float = 1000.0
    hold_timeout_s: float = 0.1
    rerelease_margin: float = 10.0
    release_min_bar: float = 25.0

    name = "six-phase"
    uses_xbs = False
    #: Bosch's number (seed 001 Sec. 2.2.3) of each of our phases 0..6.
    BOSCH = (1, 3, 4, 5, 6, 7, 2)

    def __post_init__(self) -> None:
        owner = "six-phase ABS"
        _positive(owner, a_minus=self.a_minus, a_plus=self.a_plus, a_big=self.a_big,
                  slip_threshold=self.slip_threshold, lock_slip=self.lock_slip, u_release=self.u_release,
                  u_apply=self.u_apply, u_step=self.u_step, initial_rate_bar_s=self.initial_rate_bar_s,
                  hold_timeout_s=self.hold_timeout_s, rerelease_margin=self.rerelease_margin,
                  release_min_bar=self.release_min_bar)
        for ok, text in ((self.a_big > self.a_plus, f"+A = {self.a_big} must exceed +a = {self.a_plus} (the hold "
                                                    f"after +A lasts until +a)"),
                         (self.slip_threshold < self.lock_slip < 1.0,
                          f"need lambda1 < lock_slip < 1, got lambda1 = {self.slip_threshold}, lock_slip = "
                          f"{self.lock_slip}"),
                         (self.u_step < self.u_apply, f"the slow apply u_step = {self.u_step} must be below "
                                                      f"u_apply = {self.u_apply}")):
            if not ok:
                raise SimulationError(f"six-phase ABS settings out of order: {text}")

    def runtime(self, plant: QuarterCar, actuator: BrakeActuator) -> _SixPhaseRuntime:
        return _SixPhaseRuntime(self)

    def to_json(self) -> dict[str, Any]:
        return {"name": self.name, **asdict(self)}

    def __str__(self) -> str:
        return (f"six-phase ABS: -a={-self.a_minus:g}, +a={self.a_plus:g}, +A={self.a_big:g} m/s², "
                f"lambda1={self.slip_threshold:g}, u=({self.u_release:g}, {self.u_apply:g}, {self.u_step:g}), "
                f"hold timeout {self.hold_timeout_s:g} s")


class _SixPhaseRuntime:
    __slots__ = ("phase", "r0", "rates", "a_minus", "a_plus", "a_big", "margin", "lam1", "lock", "timeout",
                 "deadline", "armed", "pulse")
    guards_use_xbs = False

    def __init__(self, cfg: SixPhaseABS):
        self.phase = 0
        self.r0 = cfg.initial_rate_bar_s
        self.rates = (0.0, -cfg.u_release, 0.0, cfg.u_apply, 0.0, cfg.u_step, 0.0)
        self.a_minus, self.a_plus, self.a_big = cfg.a_minus, cfg.a_plus, cfg.a_big
        self.margin = cfg.rerelease_margin
        self.lam1, self.lock = cfg.slip_threshold, cfg.lock_slip
        self.timeout = cfg.hold_timeout_s
        self.deadline = math.inf
        self.armed = True
        # duration of the shortest release per m/s of wheel speed: it drops about release_min_bar
        self.pulse = cfg.release_min_bar / cfg.u_release

    def rate(self, t: float, x2: float, v_wheel: float, vx: float, xbs: float) -> float:
        if self.phase == 0:
            return self.r0
        r = self.rates[self.phase]
        if r == 0.0:
            return 0.0
        return r / (v_wheel if v_wheel > _V_WHEEL_FLOOR else _V_WHEEL_FLOOR)

    def guards(self, x2: float, xbs: float, slip: float) -> tuple[float, ...]:
        p = self.phase
        locking = -self.lock - slip
        if p == 0:
            return (-self.a_minus - x2,)
        if p == 6:
            return (-self.lam1 - slip,)
        if p == 1:
            return (min(x2 + self.a_minus, slip + self.lock),) if self.armed else ()
        if p == 2:
            return (x2 - self.a_big, -self.a_minus - self.margin - x2, locking)
        if p == 3:
            return (self.a_big - x2,)
        if p == 4:
            return (self.a_plus - x2, locking)
        return (-self.a_minus - x2, locking)

    #: where each guard of :meth:`guards` leads, per phase
    _NEXT = ((6,), (2,), (3, 1, 1), (4,), (5, 1), (1, 1), (1,))

    def fire(self, t: float, index: int, x2: float, v_wheel: float, vx: float) -> None:
        self._enter(self._NEXT[self.phase][index], t, v_wheel)

    def expire(self, t: float, x2: float, v_wheel: float, vx: float) -> None:
        """The shortest release is over (its exit guard is armed now), or a hold 6 or 2 (Bosch 2 or 4)
        lasted ``hold_timeout_s``: the wheel is stable, apply slowly (5)."""
        if self.phase == 1:
            self.armed = True
            self.deadline = math.inf
        else:
            self._enter(5, t, v_wheel)

    def _enter(self, p: int, t: float, v_wheel: float) -> None:
        self.phase = p
        self.armed = p != 1
        if p == 1:
            self.deadline = t + self.pulse * max(v_wheel, _V_WHEEL_FLOOR)
        else:
            self.deadline = t + self.timeout if p in (2, 6) else math.inf

    def breakpoint(self) -> float:
        return self.deadline

    def reference(self, t: float) -> tuple[float, float]:
        """No wheel-acceleration reference curve (recorded as NaN)."""
        return (math.nan, math.nan)


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

    def guards(self, x2: float, xbs: float, slip: float) -> tuple[float, ...]:
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

    def guards(self, x2: float, xbs: float, slip: float) -> tuple[float, ...]:
        return (self.start - xbs,) if self.phase == 0 else ()

    def fire(self, t: float, index: int, x2: float, v_wheel: float, vx: float) -> None:
        self.phase = 1

    def breakpoint(self) -> float:
        return math.inf

    def reference(self, t: float) -> tuple[float, float]:
        """The virtual reference (4.2) is a function of the XBS, not a curve in time: recorded as NaN."""
        return (math.nan, math.nan)


Controller = FivePhaseABS | SixPhaseABS | TwoPhaseABS | ContinuousXbsControl
