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

from ..exceptions import SimulationError
from ._case import BrakingCase, Case, CertifyCase

__all__ = ["grid", "linspace", "arange", "Uniform", "Choice", "Integers", "RoadChanges", "Distribution",
           "monte_carlo", "monte_carlo_case", "certify_grid", "a_of_load"]


def _fields(base: Case) -> set[str]:
    return {f.name for f in fields(base)}


def grid(base: Case, **axes: Sequence[Any]) -> tuple[Case, ...]:
    """Every combination of the axes' values on top of ``base`` (the last axis varies fastest).

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
    names = list(axes)
    return tuple(replace(base, **dict(zip(names, combo))) for combo in itertools.product(*axes.values()))


def linspace(start: float, stop: float, num: int) -> list[float]:
    """``num`` evenly spaced values from ``start`` to ``stop`` inclusive (plain floats)."""
    if not (isinstance(num, int) and num >= 1):
        raise SimulationError(f"a range needs num >= 1 values, got {num!r}")
    return [float(v) for v in np.linspace(start, stop, num)]


def arange(start: float, stop: float, step: float) -> list[float]:
    """``start, start + step, ...`` up to ``stop`` inclusive (to within a millionth of a step)."""
    if not (math.isfinite(step) and step > 0 and stop >= start):
        raise SimulationError(f"a range needs step > 0 and stop >= start, got start {start}, stop {stop}, "
                              f"step {step}")
    count = int(math.floor((stop - start) / step + 1e-6)) + 1
    return [float(start + k * step) for k in range(count)]


@dataclass(frozen=True)
class Uniform:
    """A float drawn uniformly in ``[low, high)``."""

    low: float
    high: float

    def draw(self, rng: np.random.Generator) -> float:
        return float(rng.uniform(self.low, self.high))


@dataclass(frozen=True)
class Choice:
    """One of ``values``, each equally likely."""

    values: tuple[Any, ...]

    def draw(self, rng: np.random.Generator) -> Any:
        return self.values[int(rng.integers(len(self.values)))]


@dataclass(frozen=True)
class Integers:
    """An integer drawn uniformly in ``[low, high]`` (e.g. an encoder seed)."""

    low: int
    high: int

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


def monte_carlo(base: Case, count: int, *, draws: Mapping[str, Distribution], root_seed: int) -> tuple[Case, ...]:
    """``count`` cases whose fields in ``draws`` are random, case ``i`` from the ``i``-th child of ``root_seed``.

    Examples
    --------
    >>> draws = {"speed_kmh": Uniform(30, 200), "road": Choice(("dry-asphalt", "snow"))}
    >>> cases = monte_carlo(BrakingCase(), 100, draws=draws, root_seed=7)
    >>> cases[42] == monte_carlo_case(BrakingCase(), 42, draws=draws, root_seed=7)
    True
    """
    if not (isinstance(count, int) and count >= 1):
        raise SimulationError(f"a Monte-Carlo study needs count >= 1 cases, got {count!r}")
    return tuple(monte_carlo_case(base, i, draws=draws, root_seed=root_seed) for i in range(count))


def a_of_load(load_n: float, *, vehicle: Any = None) -> float:
    """``a = R² Fz / J`` of the quarter car (seed 001 eq. (2.6)) at the load ``Fz = load_n``."""
    from ..plants import QuarterCar

    base = vehicle if vehicle is not None else QuarterCar()
    return replace(base, load_n=float(load_n)).a


def certify_grid(base: CertifyCase, **betas: Sequence[float]) -> tuple[CertifyCase, ...]:
    """Certification cases over every combination of the spectrum's names (``beta1=[...], beta2=[...]``).

    Examples
    --------
    >>> cases = certify_grid(CertifyCase(), beta1=[50, 100], beta2=[100, 150, 200])
    >>> len(cases), cases[-1].betas
    (6, (('beta1', 100.0), ('beta2', 200.0)))
    """
    for name, values in betas.items():
        if isinstance(values, (str, bytes)) or not isinstance(values, Sequence) or not values:
            raise SimulationError(f"certify grid axis {name!r} needs a non-empty list of values, got {values!r}")
    fixed = [(k, v) for k, v in base.betas if k not in betas]
    names = list(betas)
    return tuple(replace(base, betas=tuple(fixed + list(zip(names, combo))))
                 for combo in itertools.product(*betas.values()))
