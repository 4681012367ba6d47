"""The hybrid integrator of the plants: fixed-step RK4 with event location, on tuples of plain floats.

One integrator, :func:`integrate`, advances every simulated plant of switchobs
(the quarter car, the two-axle vehicle, the torque-driven wheel of
:mod:`switchobs.sensors`) through the :class:`HybridPlant` protocol.

Steps.  Classical Runge-Kutta steps of the plant's length (:meth:`HybridPlant.step_size`),
cut to end exactly on the plant's breakpoints (kinks of the right-hand side
known in advance: road transitions, ends of reference trajectories, stall
timeouts) and on the final time.  When a guard changes sign within a step, the
step is redone with the fraction ``θ`` of its length that puts the guard on its
switching surface (Illinois iteration on ``θ``, each trial a fresh RK4 step
from the step's start, :func:`locate_event`); switching instants are therefore
resolved to ``time_tol`` instead of to the step size, which keeps the limit
cycles of the hybrid controllers independent of the step.  After the step the
state is projected on its admissible set (:meth:`HybridPlant.clamp`: a wheel
speed or a pressure that overshot its bound).

Order at the end of a step.  (1) the discrete-time parts advance
(:meth:`HybridPlant.after_step`: observers, speed filters); (2) the sample is
recorded; (3) a terminal event (the stop speed) ends the run; (4) located
plant events and scheduled switches are taken (road changes); (5) each
controller whose stall timeout ran out (and that no located guard fired)
expires; (6) controller guards fire, the located one first, then any guard
that is positive at the new phase.

Two rules hold for every plant:

- *Guard cascades.*  Phase changes at one instant may cascade (a new phase's
  guard already positive), but more than :data:`MAX_CASCADE` rounds at one
  instant mean that thresholds contradict each other: :class:`SimulationError`
  naming the controller, its phase and the guard.
- *Observer failure.*  When a discrete-time part refuses a step (an observer
  raising :class:`switchobs.exceptions.ObserverInputError`, e.g. on a
  non-finite state), the sample is recorded and the run stops with status
  ``observer-failed`` and the refusal as its message.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
import numpy.typing as npt

from .._progress import progress
from .._validate import check_work
from ..exceptions import SimulationError

__all__ = ["rk4_step", "locate_event", "integrate", "HybridPlant", "HybridRun", "Crossing", "MAX_CASCADE",
           "MAX_STEPS"]

State = tuple[float, ...]
Rhs = Callable[[float, State], State]

#: Rounds of phase changes allowed at one instant before the thresholds are declared contradictory.
MAX_CASCADE = 8
#: Steps a run may take (each stores one row of the series, 8 bytes a column, and the plant's bookkeeping):
#: a bound on memory (some 400 MB) and time (about 20 s), checked before the first step from the time
#: bound over the initial step.
MAX_STEPS = 1_000_000
_BLOCK = 4096


def rk4_step(f: Rhs, t: float, y: State, h: float, k1: State) -> State:
    """One classical RK4 step of length ``h`` from ``(t, y)``, given ``k1 = f(t, y)``."""
    h2 = 0.5 * h
    k2 = f(t + h2, tuple(a + h2 * k for a, k in zip(y, k1)))
    k3 = f(t + h2, tuple(a + h2 * k for a, k in zip(y, k2)))
    k4 = f(t + h, tuple(a + h * k for a, k in zip(y, k3)))
    h6 = h / 6.0
    return tuple(a + h6 * (p + 2.0 * (q + r) + s) for a, p, q, r, s in zip(y, k1, k2, k3, k4))


def locate_event(f: Rhs, t: float, y: State, h: float, k1: State, guard: Callable[[float, State], float],
                 g_lo: float, g_hi: float, *, time_tol: float = 1e-10, max_iter: int = 60) -> float:
    """Fraction ``θ in (0, 1]`` of the step at which ``guard`` turns positive.

    Parameters
    ----------
    f, t, y, h, k1
        The step (as in :func:`rk4_step`).
    guard : callable
        ``guard(t, y) -> float``; evaluated on RK4 steps of length ``θ h``.
    g_lo, g_hi : float
        Guard at the start (``<= 0``) and at the end (``> 0``) of the step.

    Returns
    -------
    float
        The upper end of the final bracket, so that the guard is ``> 0`` there
        and the transition is taken on the far side of the surface; the bracket
        is narrower than ``time_tol`` seconds.
    """
    lo, hi = 0.0, 1.0
    side = 0
    for _ in range(max_iter):
        if (hi - lo) * h <= time_tol:
            break
        theta = hi - g_hi * (hi - lo) / (g_hi - g_lo)
        # keep the trial strictly inside the bracket so that it always shrinks
        span = hi - lo
        theta = min(max(theta, lo + 1e-3 * span), hi - 1e-3 * span)
        g = guard(t + theta * h, rk4_step(f, t, y, theta * h, k1))
        if g > 0.0:
            hi, g_hi = theta, g
            if side == 1:
                g_lo *= 0.5          # Illinois: the same end moved twice, halve the other's weight
            side = 1
        else:
            lo, g_lo = theta, g
            if side == -1:
                g_hi *= 0.5
            side = -1
    return hi


@dataclass(frozen=True)
class Crossing:
    """A guard of the plant (not of a controller) that turned positive over a step.

    Attributes
    ----------
    name : str
        What the guard watches (``stop``, ``road``, ...).
    guard : callable
        ``guard(t, y) -> float``, positive past the switching surface.
    g0, g1 : float
        Its values at the start and at the end of the step (``g1 > 0``).
    terminal : bool
        The run ends there (status ``stopped``, message ``text``).
    text : str
        Message of a terminal crossing.
    """

    name: str
    guard: Callable[[float, State], float]
    g0: float
    g1: float
    terminal: bool = False
    text: str = ""


class HybridPlant(Protocol):
    """What :func:`integrate` needs of a plant.

    A plant defines its states and recorded series, :meth:`initial_state`,
    :meth:`rhs`, :meth:`step_size` and :meth:`row`; the other hooks default to
    "nothing of that kind" (no controllers, no discrete-time parts, no guards
    of its own, no breakpoints, no bounds), so a plant subclasses this protocol
    and overrides what it has.  The right-hand side also leaves the plant's
    outputs of that evaluation (slips, forces, ``x2``) where :meth:`row`,
    :meth:`guard_values` and :meth:`transition_args` read them; the integrator
    always evaluates it at the point it asks about next.
    """

    #: Names of the continuous state ``y`` and of the recorded columns (``row``), in order.
    states: tuple[str, ...]
    series: tuple[str, ...]
    #: Controller runtimes (``phase``, ``deadline``, ``fire``, ``expire``, see
    #: :mod:`switchobs.plants._controllers`) and their labels in the events ("" or "front ").
    automata: Sequence[Any] = ()
    labels: Sequence[str] = ()
    #: Whether :meth:`after_step` changes the right-hand side (an estimate or a filtered speed in the loop).
    discrete_feedback: bool = False

    def initial_state(self) -> State: ...

    def rhs(self, t: float, y: State) -> State: ...

    def step_size(self, t: float, y: State) -> float: ...

    def row(self, t: float, y: State) -> tuple[float, ...]:
        """The recorded sample at ``(t, y)``, in the order of :attr:`series`."""
        ...

    def clamp(self, y: State) -> State:
        """``y`` projected on the admissible set (the same tuple when inside)."""
        return y

    def breakpoint(self, t: float) -> float:
        """Next known kink of the right-hand side after ``t`` (``inf`` if none)."""
        return math.inf

    def start(self, t: float, y: State) -> bool:
        """Start the discrete-time parts at the first sample; whether the right-hand side changed."""
        return False

    def after_step(self, t: float, y: State, h: float) -> str | None:
        """Advance the discrete-time parts over the step just taken; a message if one refused it."""
        return None

    def crossings(self, t: float, y: State, y1: State) -> list[Crossing]:
        """The plant's own guards positive at the end of the step ``(t, y) -> y1``."""
        return []

    def take(self, crossing: Crossing, t: float, y: State) -> str:
        """Act on a located, non-terminal crossing; the event text."""
        raise SimulationError(f"{type(self).__name__} has no non-terminal guard {crossing.name!r}")

    def at_breakpoint(self, t: float, y: State) -> tuple[bool, list[str]]:
        """Take the switches scheduled at ``t``: (right-hand side changed, event texts)."""
        return False, []

    def guard_values(self, k: int) -> tuple[float, ...]:
        """The outgoing guards of controller ``k`` at the last evaluation (``()`` while it is inactive)."""
        return ()

    def locatable(self, k: int) -> bool:
        """Whether controller ``k``'s guards are continuous along a step (so they can be located); asked once."""
        return True

    def transition_args(self, k: int, y: State) -> tuple[float, float, float]:
        """``(x2, v_wheel, vx)`` that controller ``k`` reads when it changes phase."""
        raise SimulationError(f"{type(self).__name__} has no controller {k}")

    def end_step(self, t: float, y: State) -> tuple[str, str] | None:
        """Bookkeeping after the transitions; ``(status, message)`` to end the run."""
        return None


@dataclass(frozen=True)
class HybridRun:
    """What :func:`integrate` returns: the recorded series by name, events, final status and cost."""

    series: dict[str, npt.NDArray[np.float64]]
    events: tuple[tuple[float, str], ...]
    status: str
    message: str
    steps: int
    wall_time_s: float


def check_run_size(plant: HybridPlant, t_end: float, name: str) -> None:
    """Refuse, before any work, a time bound that is not finite and positive or that implies more than
    :data:`MAX_STEPS` stored steps (``t_end`` over the initial step): the Python loop and the compiled
    loop both store every step."""
    if not (isinstance(t_end, (int, float)) and math.isfinite(t_end) and t_end > 0.0):
        raise SimulationError(f"scenario {name!r}: the time bound must be finite and > 0 s, got {t_end!r}")
    h0 = plant.step_size(0.0, plant.initial_state())
    check_work(f"scenario {name!r}: integration steps of {h0:g} s over {t_end:g} s (each one stored)",
               t_end / h0, MAX_STEPS,
               "use a larger step or a shorter time bound", error=SimulationError)


def integrate(plant: HybridPlant, t_end: float, *, name: str) -> HybridRun:
    """Integrate ``plant`` from ``t = 0`` to ``t_end`` or to a terminal event (module notes).

    Parameters
    ----------
    plant : HybridPlant
    t_end : float
        Time bound [s].
    name : str
        The scenario's name, for error messages and the progress notes (one per tenth of ``t_end``).

    Returns
    -------
    HybridRun
        ``status``: ``duration``, ``stopped``, ``observer-failed`` or the
        plant's own (:meth:`HybridPlant.end_step`).

    Raises
    ------
    SimulationError
        When phase changes cascade more than :data:`MAX_CASCADE` rounds at one instant, or when
        ``t_end`` over the initial step exceeds :data:`MAX_STEPS` (refused before the first step).
    """
    check_run_size(plant, t_end, name)
    wall0 = time.perf_counter()
    # bound methods as locals: this loop runs once per step, in plain Python
    rhs, step_size, breakpoint, crossings = plant.rhs, plant.step_size, plant.breakpoint, plant.crossings
    clamp, after_step, row, guard_values = plant.clamp, plant.after_step, plant.row, plant.guard_values
    automata = plant.automata
    located = [k for k in range(len(automata)) if plant.locatable(k)]
    t = 0.0
    y = plant.initial_state()
    k1 = rhs(t, y)
    if plant.start(t, y):
        k1 = rhs(t, y)
    # rows are packed into arrays of doubles every _BLOCK steps: a tuple of float objects costs some
    # 36 bytes a number, a packed one 8
    rows = [row(t, y)]
    blocks: list[npt.NDArray[np.float64]] = []
    events: list[tuple[float, str]] = []
    g_old = [guard_values(k) for k in range(len(automata))]
    status, message = "duration", f"reached the time bound {t_end:g} s"
    steps = 0
    # a counted note per tenth of the time bound: one comparison a step, and a bar on the terminal
    tenths, next_note = 0, 0.1 * t_end
    while True:
        h = step_size(t, y)
        tb = min(t_end, breakpoint(t))
        at_break = t + h >= tb - 1e-12
        if at_break:
            h = tb - t
        y1 = rk4_step(rhs, t, y, h, k1)
        k_end = rhs(t + h, y1)
        candidates: list[tuple[Callable[[float, State], float], float, float, Any]] = [
            (_controller_guard(plant, k, i), g0, g1, (k, i))
            for k in located for i, (g0, g1) in enumerate(zip(g_old[k], guard_values(k))) if g1 > 0.0]
        candidates += [(c.guard, c.g0, c.g1, c) for c in crossings(t, y, y1)]
        found: Any = None
        best = 2.0
        for guard, g0, g1, what in candidates:
            theta = locate_event(rhs, t, y, h, k1, guard, min(g0, 0.0), g1)
            if theta < best:
                best, found = theta, what
        if found is not None and best < 1.0:
            h *= best
            at_break = False
            y1 = rk4_step(rhs, t, y, h, k1)
            k_end = rhs(t + h, y1)
        t += h
        y = clamp(y1)
        if y is not y1:
            k_end = rhs(t, y)
        steps += 1
        if t >= next_note:
            tenths = min(10, int(10.0 * t / t_end))
            next_note = (tenths + 1) * 0.1 * t_end
            progress(f"simulate: {name} [{tenths}/10] t = {t:.3g} s of {t_end:g} s")
        failure = after_step(t, y, h)
        rows.append(row(t, y))
        if len(rows) == _BLOCK:
            blocks.append(np.array(rows, dtype=float))
            rows.clear()
        if failure is not None:
            status, message = "observer-failed", failure
            break
        changed = plant.discrete_feedback
        if isinstance(found, Crossing):
            if found.terminal:
                status, message = "stopped", found.text
                break
            events.append((t, plant.take(found, t, y)))
            changed = True
        if at_break:
            switched, texts = plant.at_breakpoint(t, y)
            changed = changed or switched
            events += [(t, text) for text in texts]
        # k_end must be the derivative at (t, y) under the current phase, road and estimate
        if changed:
            k_end = rhs(t, y)
        k_end, g_old = _transitions(plant, t, y, found if isinstance(found, tuple) else None, events, k_end, name)
        halt = plant.end_step(t, y)
        if halt is not None:
            status, message = halt
            break
        k1 = k_end
        if t >= t_end - 1e-12:
            break
    blocks.append(np.array(rows, dtype=float).reshape(-1, len(plant.series)))
    data = np.concatenate(blocks)
    return HybridRun(series={col: data[:, i].copy() for i, col in enumerate(plant.series)}, events=tuple(events),
                     status=status, message=message, steps=steps, wall_time_s=time.perf_counter() - wall0)


def _controller_guard(plant: HybridPlant, k: int, i: int) -> Callable[[float, State], float]:
    def guard(t: float, y: State) -> float:
        plant.rhs(t, y)
        return plant.guard_values(k)[i]
    return guard


def _transitions(plant: HybridPlant, t: float, y: State, located: tuple[int, int] | None,
                 events: list[tuple[float, str]], k_end: State, name: str
                 ) -> tuple[State, list[tuple[float, ...]]]:
    """Stall timeouts, then the located guard and the cascade of guards positive at ``t``.

    Returns the final ``k_end`` and the controllers' guards at ``(t, y)`` in their final phases.
    """
    automata, labels = plant.automata, plant.labels
    fired = [located] if located is not None else []
    for k, ctrl in enumerate(automata):
        if located is None or located[0] != k:
            if t >= ctrl.deadline - 1e-12:
                before = ctrl.phase
                ctrl.expire(t, *plant.transition_args(k, y))
                events.append((t, f"{labels[k]}phase {before} -> {ctrl.phase} (stall timeout)"))
                k_end = plant.rhs(t, y)
    rounds = 0
    while True:
        if not fired:
            values = [plant.guard_values(k) for k in range(len(automata))]
            for k, guards in enumerate(values):
                index = next((i for i, g in enumerate(guards) if g > 0.0), -1)
                if index >= 0:
                    fired.append((k, index))
            if not fired:
                return k_end, values
        rounds += 1
        if rounds > MAX_CASCADE:
            k, index = fired[0]
            raise SimulationError(
                f"scenario {name!r}: the {labels[k]}controller changed phase {MAX_CASCADE} times at "
                f"t = {t:.6f} s without time passing and its guard {index} of phase {automata[k].phase} is "
                f"still positive; check its thresholds")
        for k, index in fired:
            ctrl = automata[k]
            before = ctrl.phase
            ctrl.fire(t, index, *plant.transition_args(k, y))
            events.append((t, f"{labels[k]}phase {before} -> {ctrl.phase}"))
        fired = []
        k_end = plant.rhs(t, y)
