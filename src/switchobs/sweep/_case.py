"""Case specifications: small frozen records of primitives that name one run, hashable and picklable.

A case is everything :func:`switchobs.sweep.run_case` needs to rebuild its run
on any worker: no objects, only strings, numbers, booleans and tuples of them.
Its :attr:`case_id` is the hash of its canonical JSON, the key of its result
row, so that a sweep can be resumed and any single case re-run alone.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, fields
from typing import Any, ClassVar

from .._limits import MAX_ROAD_CHANGES
from ..exceptions import SimulationError
from ..loop import OBSERVER_KINDS, default_method
from ..model import builtin_names
from ..observers import METHODS
from ..plants import road_names

__all__ = ["BrakingCase", "CertifyCase", "Case", "CONTROLLERS", "case_from_json"]

#: Brake controllers of a braking case (``five-phase-tracking``: wheel-acceleration tracking (21)-(22) of seed 000).
CONTROLLERS = ("five-phase", "five-phase-tracking", "two-phase", "continuous")
_IMPLS = ("python", "c")


def _number(owner: str, key: str, value: Any, *, positive: bool = False, allow_none: bool = False,
            minimum: float | None = None) -> float | None:
    if value is None and allow_none:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise SimulationError(f"{owner}: {key} must be a finite number, got {value!r}")
    if positive and value <= 0:
        raise SimulationError(f"{owner}: {key} must be > 0, got {value!r}")
    if minimum is not None and value < minimum:
        raise SimulationError(f"{owner}: {key} must be >= {minimum:g}, got {value!r}")
    return float(value)


def _integer(owner: str, key: str, value: Any, *, minimum: int = 0) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise SimulationError(f"{owner}: {key} must be an integer >= {minimum}, got {value!r}")
    return value


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 80 else f"{text[:60]}... ({len(value) if hasattr(value, '__len__') else '?'} items)"


def _choice(owner: str, key: str, value: Any, choices: tuple[str, ...]) -> str:
    if value not in choices:
        raise SimulationError(f"{owner}: unknown {key} {value!r}; choose one of {', '.join(choices)}")
    return str(value)


class _CaseBase:
    """Canonical JSON, the hash that keys a result row, and a readable line."""

    kind: ClassVar[str]

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"kind": self.kind}
        for f in fields(self):  # type: ignore[arg-type]
            value = getattr(self, f.name)
            out[f.name] = [list(v) if isinstance(v, tuple) else v for v in value] if isinstance(value, tuple) \
                else value
        return out

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> Case:
        """The case of :meth:`to_json` (:func:`case_from_json`, which must give this class).

        Raises
        ------
        SimulationError
            Another kind of case, an unknown key or a value the case rejects.
        """
        case = case_from_json(data)
        if not isinstance(case, cls):
            raise SimulationError(f"a {cls.__name__} JSON needs kind {getattr(cls, 'kind', '?')!r}, got {case.kind!r}")
        return case

    @property
    def case_id(self) -> str:
        """16 hex digits of the SHA-256 of the canonical JSON: equal specs, equal ids, on any machine."""
        text = json.dumps(self.to_json(), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


@dataclass(frozen=True)
class BrakingCase(_CaseBase):
    """One emergency braking of the quarter car (seed 001 (2.1)) with a brake controller and an XBS observer.

    Parameters
    ----------
    road : str
        The initial road (Table 2.1 of seed 001 or Table I of seed 000, :func:`switchobs.plants.road_names`).
    speed_kmh : float
        Initial speed [km/h], > 0.
    changes : tuple of (road, time_s)
        Later roads and the times [s] they start (each a 25 ms transition, seed 000 Sec. IV-D), increasing.
    controller : str
        One of :data:`CONTROLLERS`.  The two-phase ABS keeps its start-up safeguard only when an observer
        closes the loop (as :func:`switchobs.plants.table41` does: on the true XBS its build-up ends as in
        seed 001 Fig. 4.3).
    observer : str
        ``none``, ``xbs3``, ``xbs4`` or ``adaptive`` (:class:`switchobs.loop.EstimatorSpec`).
    beta1, beta2, gamma : float, optional
        Observer rates (``beta2``: xbs3/xbs4 only) and adaptation gain; defaults those of the factory.
    impl : str
        ``python`` (reference observer) or ``c`` (the generated C, compiled once per process through the cache).
    method : str, optional
        The observer's step method (:data:`switchobs.observers.METHODS`); an encoder feeds it one step per
        measurement, which ``radau3`` and ``midpoint`` take at any length (``switchobs certify --discrete``).
        Default :func:`switchobs.loop.default_method` of the observer (radau3; rk4 for the adaptive one).
    in_loop : bool
        Controllers that need an XBS read the estimate (otherwise the true XBS; the observer runs beside).
    encoder_ppr : int
        0: the observer reads the plant's exact ``x2``; otherwise a ``encoder_ppr``-pulse encoder with three-stage
        compensation feeds it (:class:`switchobs.loop.EncoderLoopEstimator`).
    encoder_dnl, encoder_eccentricity, encoder_clock_hz, encoder_seed
        Encoder imperfections (:class:`switchobs.sensors.Encoder`; clock 0: exact time stamps).
    load_n : float
        Vertical load ``Fz`` [N] of the quarter car (2850 N: seed 001; 2500 N: the rig of seed 000), which sets
        ``a = R² Fz / J`` of the plant and of the observer.
    decel_m_s2 : float, optional
        Imposed deceleration of a drum test rig; ``None``: the free vehicle.
    duration_s, stop_kmh, dt_s : float
        Time bound, stop speed [km/h] and integration step (``BrakingScenario``).

    Examples
    --------
    >>> case = BrakingCase(road="wet-asphalt", speed_kmh=90, observer="xbs4")
    >>> case.case_id == BrakingCase(road="wet-asphalt", speed_kmh=90.0, observer="xbs4").case_id
    True
    >>> str(case)
    'braking wet-asphalt, 90 km/h, five-phase, xbs4 observer (python)'
    """

    kind: ClassVar[str] = "braking"

    road: str = "dry-asphalt"
    speed_kmh: float = 120.0
    changes: tuple[tuple[str, float], ...] = ()
    controller: str = "five-phase"
    observer: str = "none"
    beta1: float | None = None
    beta2: float | None = None
    gamma: float | None = None
    impl: str = "python"
    method: str | None = None
    in_loop: bool = True
    encoder_ppr: int = 0
    encoder_dnl: float = 0.01
    encoder_eccentricity: float = 0.003
    encoder_clock_hz: float = 1e6
    encoder_seed: int = 1
    load_n: float = 2850.0
    decel_m_s2: float | None = None
    duration_s: float = 60.0
    stop_kmh: float = 2.5
    dt_s: float = 1e-3

    def __post_init__(self) -> None:
        owner = "braking case"
        roads = road_names()
        _choice(owner, "road", self.road, roads)
        set_ = object.__setattr__
        if not isinstance(self.changes, (tuple, list)) or len(self.changes) > MAX_ROAD_CHANGES:
            raise SimulationError(f"{owner}: changes is a list of at most {MAX_ROAD_CHANGES} (road, time_s) "
                                  f"pairs (MAX_ROAD_CHANGES), got {_short(self.changes)}")
        changes = []
        for item in self.changes:
            if not (isinstance(item, (tuple, list)) and len(item) == 2):
                raise SimulationError(f"{owner}: each road change is (road, time_s), got {item!r}")
            changes.append((_choice(owner, "road", item[0], roads),
                            _number(owner, "road change time_s", item[1], positive=True)))
        times = [t for _, t in changes]
        if times != sorted(times) or len(set(times)) != len(times):
            raise SimulationError(f"{owner}: road change times must increase, got {times}")
        set_(self, "changes", tuple(changes))
        _choice(owner, "controller", self.controller, CONTROLLERS)
        _choice(owner, "observer", self.observer, OBSERVER_KINDS)
        _choice(owner, "impl", self.impl, _IMPLS)
        if self.method is None:
            set_(self, "method", default_method(self.observer))
        _choice(owner, "step method", self.method, tuple(METHODS))
        if not isinstance(self.in_loop, bool):
            raise SimulationError(f"{owner}: in_loop must be true or false, got {self.in_loop!r}")
        for key in ("beta1", "beta2", "gamma"):
            set_(self, key, _number(owner, key, getattr(self, key), positive=True, allow_none=True))
        if self.beta2 is not None and self.observer == "adaptive":
            raise SimulationError(f"{owner}: the adaptive observer has one rate; give beta1, not beta2")
        _integer(owner, "encoder_ppr", self.encoder_ppr)
        if self.encoder_ppr == 1:
            raise SimulationError(f"{owner}: encoder_ppr must be 0 (exact signals) or >= 2, got 1")
        _integer(owner, "encoder_seed", self.encoder_seed)
        for key in ("encoder_dnl", "encoder_eccentricity", "encoder_clock_hz"):
            set_(self, key, _number(owner, key, getattr(self, key), minimum=0.0))
        for key in ("speed_kmh", "load_n", "duration_s", "stop_kmh", "dt_s"):
            set_(self, key, _number(owner, key, getattr(self, key), positive=True))
        set_(self, "decel_m_s2", _number(owner, "decel_m_s2", self.decel_m_s2, positive=True, allow_none=True))

    def __str__(self) -> str:
        roads = " -> ".join([self.road] + [f"{r} at {t:g} s" for r, t in self.changes])
        obs = "no observer" if self.observer == "none" else f"{self.observer} observer"
        if self.beta1 is not None:
            obs += f", beta {self.beta1:g}" + ("" if self.beta2 is None else f"/{self.beta2:g}")
        if self.observer != "none":
            obs += f" ({self.impl}{'' if self.method == default_method(self.observer) else ', ' + self.method})"
        if self.encoder_ppr:
            obs += f", {self.encoder_ppr}-ppr encoder (seed {self.encoder_seed})"
        return f"braking {roads}, {self.speed_kmh:g} km/h, {self.controller}, {obs}"


@dataclass(frozen=True)
class CertifyCase(_CaseBase):
    """One certification (:func:`switchobs.certify.certify_model`) of a built-in model's observer.

    Parameters
    ----------
    model : str
        A built-in model (``abs-xbs3``, ``abs-xbs4``, ``abs-adaptive2``, ``normal-form-N``).
    spectrum : str
        Poles of ``A_plus``, comma-separated expressions that may use the names of ``betas``
        (``"-beta1,-beta1,-beta2,-beta2"``, seed 000 Sec. IV-D).
    betas : tuple of (name, value)
        Values of the names in ``spectrum`` (e.g. ``(("beta1", 100.0), ("beta2", 150.0))``).
    values : tuple of (name, value)
        Model parameter values (e.g. ``a = R² Fz / J``), exact decimals of the numbers.
    box : tuple of (name, low, high)
        Also certify the gains for every parameter value of this box (e.g. ``a`` over a load range).
    discrete : str, optional
        Also the sampled observer of this step method (h_max where one exists).
    dwell : bool
        Run the dwell-time bisection when no common Lyapunov matrix exists.

    Examples
    --------
    >>> str(CertifyCase(spectrum="-beta1,-beta1,-beta2,-beta2", betas=(("beta1", 100), ("beta2", 150))))
    'certify abs-xbs4, spectrum -beta1,-beta1,-beta2,-beta2 (beta1 = 100, beta2 = 150)'
    """

    kind: ClassVar[str] = "certify"

    model: str = "abs-xbs4"
    spectrum: str = "-beta1,-beta1,-beta2,-beta2"
    betas: tuple[tuple[str, float], ...] = ()
    values: tuple[tuple[str, float], ...] = ()
    box: tuple[tuple[str, float, float], ...] = ()
    discrete: str | None = None
    dwell: bool = True

    def __post_init__(self) -> None:
        owner = "certification case"
        known = builtin_names()
        if self.model not in known[:-1] and not str(self.model).startswith("normal-form-"):
            raise SimulationError(f"{owner}: unknown model {self.model!r}; a sweep certifies built-in models "
                                  f"({', '.join(known)})")
        if not isinstance(self.spectrum, str) or not self.spectrum.strip():
            raise SimulationError(f"{owner}: spectrum must be a text of comma-separated poles, got "
                                  f"{self.spectrum!r}")
        set_ = object.__setattr__
        for key in ("betas", "values", "box"):
            if not isinstance(getattr(self, key), (tuple, list)):
                raise SimulationError(f"{owner}: {key} must be a list, got {_short(getattr(self, key))}")
        for key in ("betas", "values"):
            pairs = []
            for item in getattr(self, key):
                if not (isinstance(item, (tuple, list)) and len(item) == 2 and isinstance(item[0], str)):
                    raise SimulationError(f"{owner}: each entry of {key} is (name, value), got {item!r}")
                pairs.append((item[0], _number(owner, f"{key}.{item[0]}", item[1])))
            set_(self, key, tuple(pairs))
        box = []
        for item in self.box:
            if not (isinstance(item, (tuple, list)) and len(item) == 3 and isinstance(item[0], str)):
                raise SimulationError(f"{owner}: each entry of box is (name, low, high), got {item!r}")
            lo, hi = (_number(owner, f"box.{item[0]}", v) for v in item[1:])
            if not lo < hi:  # type: ignore[operator]
                raise SimulationError(f"{owner}: box.{item[0]} needs low < high, got [{lo}, {hi}]")
            box.append((item[0], lo, hi))
        set_(self, "box", tuple(box))
        if self.discrete is not None:
            _choice(owner, "discrete step method", self.discrete, tuple(METHODS))
        if not isinstance(self.dwell, bool):
            raise SimulationError(f"{owner}: dwell must be true or false, got {self.dwell!r}")

    def __str__(self) -> str:
        betas = ", ".join(f"{k} = {v:g}" for k, v in self.betas)
        text = f"certify {self.model}, spectrum {self.spectrum}" + (f" ({betas})" if betas else "")
        if self.values:
            text += ", " + ", ".join(f"{k} = {v:g}" for k, v in self.values)
        if self.box:
            text += ", box " + ", ".join(f"{k} in [{lo:g}, {hi:g}]" for k, lo, hi in self.box)
        return text + (f", discrete {self.discrete}" if self.discrete else "")


Case = BrakingCase | CertifyCase
_KINDS: dict[str, type[BrakingCase] | type[CertifyCase]] = {"braking": BrakingCase, "certify": CertifyCase}


def case_from_json(data: dict[str, Any]) -> Case:
    """The case of :meth:`to_json` (lists become tuples); its :attr:`case_id` is the stored one."""
    data = dict(data)
    cls = _KINDS.get(data.pop("kind", None))
    if cls is None:
        raise SimulationError(f"a case needs kind 'braking' or 'certify', got {data!r}")
    names = {f.name for f in fields(cls)}
    unknown = sorted(set(data) - names)
    if unknown:
        raise SimulationError(f"{cls.kind} case: unknown key(s) {unknown}; known keys are {sorted(names)}")
    return cls(**{k: tuple(tuple(x) if isinstance(x, list) else x for x in v) if isinstance(v, list) else v
                  for k, v in data.items()})
