"""Road-surface schedules: changes of the tyre characteristic at given times or positions.

A change blends the old and the new characteristic over ``duration_s`` with the
C¹ weight ``w = 3 s² - 2 s³`` (``s`` the elapsed fraction), as the 25 ms
transitions of seed 000 Sec. IV-D.  Both ``mu`` and ``mu'`` are blended with
the same weight, so the true XBS during a transition is the derivative of the
friction that acts on the wheel.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from .._json import JsonRecord
from ..exceptions import SimulationError
from ._json import from_fields
from ._tyre import Burckhardt, road

__all__ = ["RoadChange", "RoadSchedule"]


@dataclass(frozen=True)
class RoadChange(JsonRecord, error=SimulationError):
    """A change to ``road`` starting at a time or when the wheel reaches a position.

    Parameters
    ----------
    road : Burckhardt or str
        New surface (a name of :func:`switchobs.plants.road_names`).
    at_time_s : float, optional
        Start of the transition [s].
    at_position_m : float, optional
        Travelled distance at which the transition starts [m] (exactly one of
        ``at_time_s`` and ``at_position_m``).
    duration_s : float
        Length of the smooth transition [s], ``0`` for a jump.
    """

    road: Burckhardt
    at_time_s: float | None = None
    at_position_m: float | None = None
    duration_s: float = 0.025

    def __post_init__(self) -> None:
        object.__setattr__(self, "road", road(self.road))
        if (self.at_time_s is None) == (self.at_position_m is None):
            raise SimulationError(
                f"a road change to {self.road.name!r} needs exactly one of at_time_s and at_position_m, "
                f"got at_time_s={self.at_time_s!r}, at_position_m={self.at_position_m!r}")
        where = self.at_time_s if self.at_time_s is not None else self.at_position_m
        if not isinstance(where, (int, float)) or not math.isfinite(where) or where < 0:
            raise SimulationError(f"a road change must start at a finite time or position >= 0, got {where!r}")
        if not isinstance(self.duration_s, (int, float)) or not math.isfinite(self.duration_s) \
                or self.duration_s < 0:
            raise SimulationError(f"road transition duration must be finite and >= 0 s, got {self.duration_s!r}")

    def to_json(self) -> dict[str, Any]:
        return {"road": self.road.name, "at_time_s": self.at_time_s, "at_position_m": self.at_position_m,
                "duration_s": self.duration_s}


@dataclass(frozen=True)
class RoadSchedule:
    """The initial surface followed by changes, applied in the given order.

    Parameters
    ----------
    initial : Burckhardt or str
    changes : sequence of RoadChange

    Raises
    ------
    SimulationError
        If time-triggered changes are not in increasing order or overlap
        (a change starting before the previous transition has ended).

    Examples
    --------
    >>> s = RoadSchedule("dry-asphalt", [RoadChange("wet-asphalt", at_time_s=3.0)])
    >>> [r.name for r in s.roads]
    ['dry-asphalt', 'wet-asphalt']
    """

    initial: Burckhardt
    changes: tuple[RoadChange, ...] = ()

    def __init__(self, initial: Burckhardt | str, changes: Sequence[RoadChange] = ()):
        object.__setattr__(self, "initial", road(initial))
        changes = tuple(changes)
        for ch in changes:
            if not isinstance(ch, RoadChange):
                raise SimulationError(f"road changes must be RoadChange objects, got {ch!r}")
        end = -math.inf
        for ch in changes:
            if ch.at_time_s is None:
                continue
            if ch.at_time_s < end:
                raise SimulationError(
                    f"road change to {ch.road.name!r} at t={ch.at_time_s} s starts before the previous "
                    f"transition ends (t={end} s); order the changes by time and keep them apart")
            end = ch.at_time_s + ch.duration_s
        object.__setattr__(self, "changes", changes)

    @property
    def roads(self) -> tuple[Burckhardt, ...]:
        return (self.initial, *(c.road for c in self.changes))

    def to_json(self) -> dict[str, Any]:
        return {"initial": self.initial.name, "changes": [c.to_json() for c in self.changes]}

    @classmethod
    def from_json(cls, data: Any) -> RoadSchedule:
        """The schedule of :meth:`to_json` (roads by name).

        Raises
        ------
        SimulationError
            A missing key, an unknown road or a change the schedule rejects.
        """
        if not isinstance(data, dict) or not isinstance(data.get("changes", []), list):
            raise SimulationError(f"a road schedule JSON needs 'initial' and a list of 'changes', got {data!r}")
        if "initial" not in data:
            raise SimulationError("a road schedule JSON needs 'initial'")
        return cls(data["initial"], [from_fields(RoadChange, c, "road change") for c in data.get("changes", [])])

    def __str__(self) -> str:
        parts = [self.initial.name]
        for c in self.changes:
            where = f"t={c.at_time_s:g} s" if c.at_time_s is not None else f"x={c.at_position_m:g} m"
            parts.append(f"{c.road.name} at {where}")
        return " -> ".join(parts)


class _RoadState:
    """Mutable evaluator of the current (possibly blended) characteristic, for the inner loop."""

    __slots__ = ("schedule", "next_index", "a", "b", "t0", "duration", "blending", "starts")

    def __init__(self, schedule: RoadSchedule):
        self.schedule = schedule
        self.next_index = 0
        r = schedule.initial
        self.a = (r.c1, r.c2, r.c3)
        self.b = self.a
        self.t0 = 0.0
        self.duration = 0.0
        self.blending = False
        self.starts: list[float] = []     # actual start times of the changes, for metrics

    @property
    def pending(self) -> RoadChange | None:
        changes = self.schedule.changes
        return changes[self.next_index] if self.next_index < len(changes) else None

    def start_change(self, t: float) -> None:
        """Begin the next change at time ``t`` (an event found by the simulation)."""
        change = self.schedule.changes[self.next_index]
        if self.blending:
            raise SimulationError(
                f"road change to {change.road.name!r} starts at t={t:.4f} s during the previous transition; "
                f"keep the changes further apart")
        self.next_index += 1
        self.starts.append(t)
        r = change.road
        self.b = (r.c1, r.c2, r.c3)
        self.t0 = t
        self.duration = change.duration_s
        if change.duration_s > 0.0:
            self.blending = True
        else:
            self.a = self.b

    def end_change(self) -> None:
        self.a = self.b
        self.blending = False

    def breakpoint(self) -> float:
        """Next scheduled kink of the characteristic: the end of a transition or a change at a given time."""
        if self.blending:
            return self.t0 + self.duration
        pending = self.pending
        if pending is not None and pending.at_time_s is not None:
            return pending.at_time_s
        return math.inf

    def at_breakpoint(self, t: float) -> tuple[bool, list[str]]:
        """Take the scheduled switch due at ``t``: ``(characteristic changed, event texts)``."""
        pending = self.pending
        if self.blending and t >= self.t0 + self.duration - 1e-12:
            self.end_change()
            return True, []
        if not self.blending and pending is not None and pending.at_time_s is not None \
                and t >= pending.at_time_s - 1e-12:
            self.start_change(t)
            return True, [f"road -> {pending.road.name}"]
        return False, []

    def weight(self, t: float) -> float:
        s = (t - self.t0) / self.duration
        if s <= 0.0:
            return 0.0
        if s >= 1.0:
            return 1.0
        return s * s * (3.0 - 2.0 * s)

    def eval(self, lam: float, t: float) -> tuple[float, float]:
        """``(mu, mu')`` at slip ``lam`` and time ``t`` (odd/even extensions as in :class:`Burckhardt`)."""
        al = -lam if lam < 0.0 else lam
        c1, c2, c3 = self.a
        e = math.exp(-c2 * al)
        mu = c1 * (1.0 - e) - c3 * al
        xbs = c1 * c2 * e - c3
        if self.blending:
            w = self.weight(t)
            c1, c2, c3 = self.b
            e = math.exp(-c2 * al)
            mu += w * (c1 * (1.0 - e) - c3 * al - mu)
            xbs += w * (c1 * c2 * e - c3 - xbs)
        return (-mu if lam < 0.0 else mu), xbs
