"""Sets of cases: cartesian grids, ranges, Monte-Carlo draws with per-case seeds from one root seed.

A Monte-Carlo case ``i`` draws its random fields from ``numpy.random.default_rng(SeedSequence(root_seed,
spawn_key=(i,)))``, the ``i``-th child of the root seed: :func:`monte_carlo_case` rebuilds case ``i``
alone and gives the same spec (hence the same case id and numbers) as the whole draw.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields, replace
from typing import Any

import numpy as np

from .._limits import MAX_ROAD_CHANGES, MAX_SWEEP_CASES
from .._validate import check_work
from ..exceptions import SimulationError
from ._case import BrakingCase, Case, CertifyCase

__all__ = ["grid", "linspace", "arange", "Uniform", "Choice", "Integers", "RoadChanges", "Distribution",
           "monte_carlo", "monte_carlo_case", "certify_grid", "a_of_load", "check_case_count", "arange_count"]

_INT64 = 2**63


def check_case_count(count: float, what: str, *, max_cases: int = MAX_SWEEP_CASES) -> None:
    """Refuse ``count`` cases (or values of an axis) above ``max_cases``, before any of them is built.

    Raises
    ------
    SimulationError
        Naming ``what``, the count and the limit (:data:`switchobs._limits.MAX_SWEEP_CASES` by default).
    """
    check_work(what, count, max_cases, "use fewer values or draws, or raise the limit (--max-cases)",
               error=SimulationError)


def _fields(base: Case) -> set[str]:
    return {f.name for f in fields(base)}


def grid(base: Case, *, max_cases: int = MAX_SWEEP_CASES, **axes: Sequence[Any]) -> tuple[Case, ...]:
    """Every combination of the axes' values on top of ``base`` (the last axis varies fastest), at most
    ``max_cases`` of them (counted before any is built).

    Examples
    --------
    >>> cases = grid(BrakingCase(), road=["dry-asphalt", "snow"], speed_kmh=[60, 120, 180])
    >>> len(cases), cases[1].road, cases[1].speed_kmh
    (6, 'dry-asphalt', 120.0)
    """
    unknown = sorted(set(axes) - _fields(base))
    if unknown:
        raise SimulationError(f"{base.kind} cases have no field(s) {unknown}; fields: {sorted(_fields(base))}")
    for name, values in axes.items():
        if isinstance(values, (str, bytes)) or not isinstance(values, Sequence) or not values:
            raise SimulationError(f"grid axis {name!r} needs a non-empty list of values, got {values!r}")
    sizes = [len(v) for v in axes.values()]
    check_case_count(math.prod(sizes), f"a grid of {' x '.join(map(str, sizes))} cases", max_cases=max_cases)
    names = list(axes)
    return tuple(replace(base, **dict(zip(names, combo))) for combo in itertools.product(*axes.values()))


def _finite(what: str, **values: Any) -> None:
    for key, value in values.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise SimulationError(f"{what}: {key} must be a finite number, got {value!r}")


def linspace(start: float, stop: float, num: int, *, max_values: int = MAX_SWEEP_CASES) -> list[float]:
    """``num`` evenly spaced values from ``start`` to ``stop`` inclusive (plain floats), at most ``max_values``."""
    _finite("a range {start, stop, num}", start=start, stop=stop)
    if isinstance(num, bool) or not (isinstance(num, int) and num >= 1):
        raise SimulationError(f"a range needs num >= 1 values (an integer), got {num!r}")
    check_case_count(num, f"a range of num = {num} values", max_cases=max_values)
    return [float(v) for v in np.linspace(start, stop, num)]


def arange_count(start: float, stop: float, step: float) -> float:
    """How many values :func:`arange` gives (a float: it may be astronomically large), after checking the range."""
    _finite("a range {start, stop, step}", start=start, stop=stop, step=step)
    if not (step > 0 and stop >= start):
        raise SimulationError(f"a range needs step > 0 and stop >= start, got start {start}, stop {stop}, "
                              f"step {step}")
    ratio = (stop - start) / step + 1e-6  # inf for step = 1e-300 over a span of 10: counted, never built
    return float(math.floor(ratio)) + 1.0 if math.isfinite(ratio) else math.inf


def arange(start: float, stop: float, step: float, *, max_values: int = MAX_SWEEP_CASES) -> list[float]:
    """``start, start + step, ...`` up to ``stop`` inclusive (to within a millionth of a step), at most
    ``max_values`` values."""
    count = arange_count(start, stop, step)
    check_case_count(count, f"a range from {start:g} to {stop:g} in steps of {step:g}", max_cases=max_values)
    return [float(start + k * step) for k in range(int(count))]


@dataclass(frozen=True)
class Uniform:
    """A float drawn uniformly in ``[low, high)``."""

    low: float
    high: float

    def __post_init__(self) -> None:
        _finite("a uniform draw", low=self.low, high=self.high)
        if not self.low <= self.high:
            raise SimulationError(f"a uniform draw needs low <= high, got [{self.low!r}, {self.high!r}]")

    def draw(self, rng: np.random.Generator) -> float:
        return float(rng.uniform(self.low, self.high))


@dataclass(frozen=True)
class Choice:
    """One of ``values``, each equally likely."""

    values: tuple[Any, ...]

    def __post_init__(self) -> None:
        if not (isinstance(self.values, tuple) and self.values):
            raise SimulationError(f"a choice needs a non-empty tuple of values, got {self.values!r}")

    def draw(self, rng: np.random.Generator) -> Any:
        return self.values[int(rng.integers(len(self.values)))]


@dataclass(frozen=True)
class Integers:
    """An integer drawn uniformly in ``[low, high]`` (e.g. an encoder seed)."""

    low: int
    high: int

    def __post_init__(self) -> None:
        for key in ("low", "high"):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, int) or not -_INT64 <= value < _INT64:
                raise SimulationError(f"an integer draw needs a 64-bit integer {key}, got {value!r}")
        if not self.low <= self.high:
            raise SimulationError(f"an integer draw needs low <= high, got [{self.low!r}, {self.high!r}]")

    def draw(self, rng: np.random.Generator) -> int:
        return int(rng.integers(self.low, self.high, endpoint=True))


@dataclass(frozen=True)
class RoadChanges:
    """``count`` road changes (drawn in ``[count_min, count_max]``) at times uniform in ``window_s``,
    each to a road of ``roads``; the value of a :class:`BrakingCase`'s ``changes``."""

    roads: tuple[str, ...]
    count_min: int
    count_max: int
    window_s: tuple[float, float]

    def __post_init__(self) -> None:
        if not (isinstance(self.roads, tuple) and self.roads):
            raise SimulationError(f"road changes need a non-empty tuple of roads, got {self.roads!r}")
        for key in ("count_min", "count_max"):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= MAX_ROAD_CHANGES:
                raise SimulationError(f"road changes: {key} must be an integer in [0, {MAX_ROAD_CHANGES}] "
                                      f"(MAX_ROAD_CHANGES), got {value!r}")
        if not self.count_min <= self.count_max:
            raise SimulationError(f"road changes need count = [min, max] with min <= max, got "
                                  f"[{self.count_min}, {self.count_max}]")
        if not (isinstance(self.window_s, tuple) and len(self.window_s) == 2):
            raise SimulationError(f"road changes need window_s = [t0, t1], got {self.window_s!r}")
        t0, t1 = self.window_s
        _finite("road changes: window_s", t0=t0, t1=t1)
        if not 0 <= t0 <= t1:
            raise SimulationError(f"road changes need window_s = [t0, t1] with 0 <= t0 <= t1, got [{t0!r}, {t1!r}]")

    def draw(self, rng: np.random.Generator) -> tuple[tuple[str, float], ...]:
        count = int(rng.integers(self.count_min, self.count_max, endpoint=True))
        times = sorted(float(t) for t in rng.uniform(*self.window_s, size=count))
        return tuple((self.roads[int(rng.integers(len(self.roads)))], t) for t in times)


Distribution = Uniform | Choice | Integers | RoadChanges


def _check_draws(base: Case, draws: Mapping[str, Distribution]) -> list[tuple[str, Distribution]]:
    unknown = sorted(set(draws) - _fields(base))
    if unknown:
        raise SimulationError(f"{base.kind} cases have no field(s) {unknown} to draw")
    for name, dist in draws.items():
        if not isinstance(dist, (Uniform, Choice, Integers, RoadChanges)):
            raise SimulationError(f"draw {name!r}: expected Uniform, Choice, Integers or RoadChanges, got {dist!r}")
    return sorted(draws.items())  # the order of the keys must not change the numbers


def monte_carlo_case(base: Case, index: int, *, draws: Mapping[str, Distribution], root_seed: int) -> Case:
    """Case ``index`` of :func:`monte_carlo` alone (the same spec as in the whole draw)."""
    if not (isinstance(root_seed, int) and root_seed >= 0 and isinstance(index, int) and index >= 0):
        raise SimulationError(f"root_seed and index must be integers >= 0, got {root_seed!r}, {index!r}")
    rng = np.random.default_rng(np.random.SeedSequence(root_seed, spawn_key=(index,)))
    return replace(base, **{name: dist.draw(rng) for name, dist in _check_draws(base, draws)})


def monte_carlo(base: Case, count: int, *, draws: Mapping[str, Distribution], root_seed: int,
                max_cases: int = MAX_SWEEP_CASES) -> tuple[Case, ...]:
    """``count`` cases whose fields in ``draws`` are random, case ``i`` from the ``i``-th child of ``root_seed``
    (at most ``max_cases``).

    Examples
    --------
    >>> draws = {"speed_kmh": Uniform(30, 200), "road": Choice(("dry-asphalt", "snow"))}
    >>> cases = monte_carlo(BrakingCase(), 100, draws=draws, root_seed=7)
    >>> cases[42] == monte_carlo_case(BrakingCase(), 42, draws=draws, root_seed=7)
    True
    """
    if isinstance(count, bool) or not (isinstance(count, int) and count >= 1):
        raise SimulationError(f"a Monte-Carlo study needs count >= 1 cases (an integer), got {count!r}")
    check_case_count(count, f"a Monte-Carlo study of count = {count} cases", max_cases=max_cases)
    return tuple(monte_carlo_case(base, i, draws=draws, root_seed=root_seed) for i in range(count))


def a_of_load(load_n: float, *, vehicle: Any = None) -> float:
    """``a = R² Fz / J`` of the quarter car (seed 001 eq. (2.6)) at the load ``Fz = load_n``."""
    from ..plants import QuarterCar

    base = vehicle if vehicle is not None else QuarterCar()
    return replace(base, load_n=float(load_n)).a


def certify_grid(base: CertifyCase, *, max_cases: int = MAX_SWEEP_CASES,
                 **betas: Sequence[float]) -> tuple[CertifyCase, ...]:
    """Certification cases over every combination of the spectrum's names (``beta1=[...], beta2=[...]``), at
    most ``max_cases``.

    Examples
    --------
    >>> cases = certify_grid(CertifyCase(), beta1=[50, 100], beta2=[100, 150, 200])
    >>> len(cases), cases[-1].betas
    (6, (('beta1', 100.0), ('beta2', 200.0)))
    """
    for name, values in betas.items():
        if isinstance(values, (str, bytes)) or not isinstance(values, Sequence) or not values:
            raise SimulationError(f"certify grid axis {name!r} needs a non-empty list of values, got {values!r}")
    sizes = [len(v) for v in betas.values()]
    check_case_count(math.prod(sizes), f"a certification grid of {' x '.join(map(str, sizes))} cases",
                     max_cases=max_cases)
    fixed = [(k, v) for k, v in base.betas if k not in betas]
    names = list(betas)
    return tuple(replace(base, betas=tuple(fixed + list(zip(names, combo))))
                 for combo in itertools.product(*betas.values()))
