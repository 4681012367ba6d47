"""From an observer specification (kind, gains, implementation) to an estimator set up for a vehicle.

This is where the conventions of the observer models meet the plant's: the
models of seed 000 (abs-xbs3, abs-xbs4) write the brake input as ``+b u`` with
``b = -R γ_b / J``, seed 001's (abs-adaptive2) as ``-b u`` with
``b = +R γ_b / J``, so the sign of :attr:`QuarterCar.b` is flipped for the
former; ``a = R² Fz / J`` is the vehicle's; the 3D observer knows the road's
``c = -c2``.

A process can be handed observers built in another one (:func:`compiled_observers`,
:func:`install_observers`): a sweep's client builds each C observer of a study once and its Dask
workers take them instead of repeating the symbolic design.  What travels is the generated C source
(a :class:`switchobs.codegen.CObserver` pickles as its files and parameters), never a binary: each
process compiles it into, or finds it verified in, its own compiled-code cache
(:func:`switchobs.codegen.load_library`).
"""

from __future__ import annotations

import functools
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from .._json import JsonRecord
from .._validate import substep_bound
from ..exceptions import SimulationError
from ..plants import Burckhardt, QuarterCar, XbsEstimator, road
from ..spec import DEFAULT_METHOD
from ._adapter import LoadXbsEstimator, ObserverXbsEstimator

__all__ = ["EstimatorSpec", "xbs_estimator", "default_method", "OBSERVER_KINDS", "DEFAULT_BETA", "DEFAULT_GAMMA",
           "INITIAL_STATE", "compiled_observers", "install_observers"]

#: Observer kinds: the three reference XBS observers and ``none`` (no estimator).
OBSERVER_KINDS = ("xbs3", "xbs4", "adaptive", "none")
#: Default observer gains: error rates in the rescaled time tau (seed 000 Sec. III-E, IV-D; seed 001 (3.20)).
DEFAULT_BETA: Mapping[str, float] = {"xbs3": 150.0, "xbs4": 100.0, "adaptive": 100.0}
#: Default adaptation gain ``Gamma = gamma I`` of the adaptive observer (seed 001 eq. (3.4)).
DEFAULT_GAMMA = 1e4
#: Initial estimates: a small positive XBS (the stable side) and rough road parameters.
INITIAL_STATE: Mapping[str, Mapping[str, float]] = {"xbs3": {"z2": 0.5}, "xbs4": {"z2": 0.5},
                                                    "adaptive": {"c": 20.0, "d": 10.0}}
IMPLEMENTATIONS = ("python", "c")


def default_method(kind: str) -> str:
    """The step method of an observer kind when none is chosen.

    ``radau3`` (:data:`switchobs.spec.DEFAULT_METHOD`, certified for every step length) for the switched
    observers; ``rk4`` for the adaptive one, whose right-hand side is not affine in its state, so that only
    the explicit methods apply (:func:`switchobs.spec.require_explicit`).

    Examples
    --------
    >>> default_method("xbs4"), default_method("adaptive")
    ('radau3', 'rk4')
    """
    return "rk4" if kind == "adaptive" else DEFAULT_METHOD


@dataclass(frozen=True)
class EstimatorSpec(JsonRecord, error=SimulationError):
    """Which XBS observer closes the loop, and how it is built.

    Parameters
    ----------
    kind : str
        One of :data:`OBSERVER_KINDS`.
    beta : float, optional
        Observer rate in the rescaled time (``beta1 = beta2 = beta``); default :data:`DEFAULT_BETA`.
    gamma : float, optional
        Adaptive observer only (the others ignore it): ``Gamma = gamma I``; default :data:`DEFAULT_GAMMA`.
    impl : str
        ``python`` (reference observer) or ``c`` (the generated C twin, compiled
        with the system compiler, :meth:`switchobs.codegen.CObserver.like`).
    beta2 : float, optional
        xbs3 and xbs4 only: the second rate (spectra ``{-beta1, -beta2, -beta2}`` and
        ``{-beta1, -beta1, -beta2, -beta2}``, seed 000 Secs. III-E, IV-D) with ``beta1 = beta``;
        default ``beta`` (the adaptive observer has one rate and refuses it).
    method : str, optional
        Step method of the observer (``radau3``, ``midpoint``, ``rk4``, ``euler``; the adaptive observer
        takes the explicit ones): ``radau3`` and ``midpoint`` are certified for every step length
        (``switchobs certify --discrete``), which one step per encoder measurement needs.  Default
        :func:`default_method` of the kind (radau3; rk4 for the adaptive observer).
    h_max : float, optional
        Bound on the observer's step in rescaled time ``|s| dt``: a longer step is split into
        ``ceil(|s| dt / h_max)`` sub-steps (:class:`switchobs.observers.SwitchedObserver`, the ``h_max`` of a
        discrete certificate, ``<PREFIX>_H_MAX`` of the C build); default none (one step per sample).
    max_substeps : int, optional
        With ``h_max`` only: most sub-steps of one step before the observer refuses it (``SUBSTEP_LIMIT``);
        default the observer's (``max_substeps`` of :class:`switchobs.observers.SwitchedObserver`).

    Raises
    ------
    SimulationError
        For an unknown kind or implementation, a ``beta2`` for the adaptive observer, or a malformed ``h_max`` /
        ``max_substeps`` (the gains are checked by the observer constructors, e.g.
        :func:`switchobs.observers.xbs4_observer`).

    Examples
    --------
    >>> EstimatorSpec("xbs4")  # doctest: +NORMALIZE_WHITESPACE
    EstimatorSpec(kind='xbs4', beta=None, gamma=None, impl='python', beta2=None, method='radau3', h_max=None,
                  max_substeps=None)
    >>> str(EstimatorSpec("adaptive", beta=80))
    'adaptive observer, beta 80, gamma 10000 (python)'
    >>> str(EstimatorSpec("xbs4", beta=80, beta2=120))
    'xbs4 observer, beta 80/120 (python)'
    >>> str(EstimatorSpec("adaptive", h_max=1e-4, max_substeps=1000))
    'adaptive observer, beta 100, gamma 10000 (python, |s| dt <= 0.0001 in at most 1000 sub-steps)'
    """

    kind: str
    beta: float | None = None
    gamma: float | None = None
    impl: str = "python"
    beta2: float | None = None
    method: str | None = None
    h_max: float | None = None
    max_substeps: int | None = None

    def __post_init__(self) -> None:
        if self.kind not in OBSERVER_KINDS:
            raise SimulationError(f"unknown observer {self.kind!r}; choose one of {', '.join(OBSERVER_KINDS)}")
        if self.method is None:
            object.__setattr__(self, "method", default_method(self.kind))
        if self.impl not in IMPLEMENTATIONS:
            raise SimulationError(f"unknown observer implementation {self.impl!r}; choose python or c")
        if self.beta2 is not None and self.kind == "adaptive":
            raise SimulationError(f"the adaptive observer has one rate beta (seed 001 (3.20)); drop beta2 = "
                                  f"{self.beta2!r}")
        if self.kind != "none":
            substep_bound(self.h_max, self.max_substeps, error=SimulationError)

    def to_json(self) -> dict[str, Any]:
        return {"kind": self.kind, "beta": self.beta, "beta2": self.beta2, "gamma": self.gamma, "impl": self.impl,
                "method": self.method, "h_max": self.h_max, "max_substeps": self.max_substeps}

    def __str__(self) -> str:
        if self.kind == "none":
            return "no observer"
        beta = DEFAULT_BETA[self.kind] if self.beta is None else self.beta
        text = f"{self.kind} observer, beta {beta:g}" + ("" if self.beta2 is None else f"/{self.beta2:g}")
        if self.kind == "adaptive":
            text += f", gamma {DEFAULT_GAMMA if self.gamma is None else self.gamma:g}"
        bound = substep_bound(self.h_max, self.max_substeps, error=SimulationError)
        substeps = "" if bound is None else f", |s| dt <= {float(bound[0]):g} in at most {bound[1]} sub-steps"
        return f"{text} ({self.impl}{'' if self.method == default_method(self.kind) else ', ' + self.method}{substeps})"


def xbs_estimator(spec: EstimatorSpec | str, vehicle: QuarterCar, initial_road: Burckhardt | str, *,
                  load_signal: bool = False) -> XbsEstimator | None:
    """The observer of ``spec`` set up for ``vehicle``, as an estimator for the ABS simulations.

    Parameters
    ----------
    spec : EstimatorSpec or str
        An observer kind is read as ``EstimatorSpec(kind)``.
    vehicle : QuarterCar
        Gives ``a = R² Fz / J`` and ``b`` (sign flipped for the models of
        seed 000, see the module notes).  For the two-axle vehicle pass the
        corner of the wheel (:meth:`TwoAxleVehicle.corner`).
    initial_road : Burckhardt or str
        The road the 3D observer assumes (``c = -c2``); ignored by the others.
    load_signal : bool
        Adaptive observer only: read ``a = R² Fz / J`` on line from the load the two-axle vehicle feeds
        (seed 001 Sec. 3.6, :class:`LoadXbsEstimator`; ``vehicle.load_n`` until it does).

    Returns
    -------
    ObserverXbsEstimator or None
        ``None`` for ``kind = "none"``; otherwise started from
        :data:`INITIAL_STATE`.

    Raises
    ------
    SimulationError
        ``load_signal`` for another kind than ``adaptive``.

    Examples
    --------
    >>> from switchobs.plants import QuarterCar
    >>> est = xbs_estimator("xbs4", QuarterCar(), "dry-asphalt")
    >>> est.describe()
    "SwitchedObserver of model 'abs-xbs4' (radau3, ZOH signals y, vx, u)"
    >>> xbs_estimator(EstimatorSpec("none"), QuarterCar(), "dry-asphalt") is None
    True
    """
    if isinstance(spec, str):
        spec = EstimatorSpec(spec)
    if not isinstance(spec, EstimatorSpec):
        raise SimulationError(f"xbs_estimator() needs an EstimatorSpec or an observer kind, got {spec!r}")
    if load_signal and spec.kind != "adaptive":
        raise SimulationError(f"load_signal: only the adaptive observer reads the load on line, not {spec.kind!r}")
    if spec.kind == "none":
        return None
    obs = _observer(*_observer_key(spec, vehicle, initial_road, load_signal))
    if load_signal:
        return LoadXbsEstimator(obs, load_n=vehicle.load_n, load_gain=vehicle.radius_m ** 2 / vehicle.inertia_kg_m2,
                                initial_state=INITIAL_STATE["adaptive"])
    return ObserverXbsEstimator(obs, initial_state=INITIAL_STATE[spec.kind])


#: ``(kind, beta, beta2, gamma, impl, method, a, b, c, h_max, max_substeps)``: the arguments of :func:`_observer`.
ObserverKey = tuple[Any, ...]


def _observer_key(spec: EstimatorSpec, vehicle: QuarterCar, initial_road: Burckhardt | str,
                  load_signal: bool = False) -> ObserverKey:
    """The arguments of :func:`_observer` for the observer of ``spec`` (not ``none``) on ``vehicle``."""
    beta = DEFAULT_BETA[spec.kind] if spec.beta is None else spec.beta
    beta2 = beta if spec.beta2 is None else spec.beta2
    gamma = (DEFAULT_GAMMA if spec.gamma is None else spec.gamma) if spec.kind == "adaptive" else None
    assert spec.method is not None               # __post_init__ sets it
    bound = (spec.h_max, spec.max_substeps)
    if load_signal:
        return ("adaptive-load", beta, beta2, gamma, spec.impl, spec.method, None, vehicle.b, None, *bound)
    c = road(initial_road).c if spec.kind == "xbs3" else None
    return (spec.kind, beta, beta2, gamma, spec.impl, spec.method, vehicle.a, vehicle.b, c, *bound)


#: Observers handed to this process by :func:`install_observers`, by their :func:`_observer` arguments.
_INSTALLED: dict[ObserverKey, Any] = {}


def compiled_observers(settings: Iterable[tuple[EstimatorSpec, QuarterCar, Burckhardt | str]]
                       ) -> dict[ObserverKey, Any]:
    """The C observers (``impl = "c"``) of ``(spec, vehicle, initial_road)`` settings, each built once here:
    what :func:`install_observers` takes in another process (module notes).  Other settings are left out."""
    out: dict[ObserverKey, Any] = {}
    for spec, vehicle, initial_road in settings:
        if spec.kind != "none" and spec.impl == "c":
            key = _observer_key(spec, vehicle, initial_road)
            if key not in out:
                out[key] = _observer(*key)
    return out


def install_observers(observers: Mapping[ObserverKey, Any]) -> int:
    """Use ``observers`` (from :func:`compiled_observers`, unpickled here: each C observer compiled into or
    found in this process's own compiled-code cache) for their settings instead of building them; their
    number."""
    _INSTALLED.update(observers)
    return len(observers)


def _observer(kind: str, beta: float, beta2: float, gamma: float | None, impl: str, method: str, a: float | None,
              b: float, c: float | None, h_max: float | None, max_substeps: int | None) -> Any:
    """The observer of :func:`xbs_estimator`: one installed in this process, else :func:`_build_observer`."""
    key = (kind, beta, beta2, gamma, impl, method, a, b, c, h_max, max_substeps)
    installed = _INSTALLED.get(key)
    return installed if installed is not None else _build_observer(*key)


@functools.lru_cache(maxsize=64)
def _build_observer(kind: str, beta: float, beta2: float, gamma: float | None, impl: str, method: str,
                    a: float | None, b: float, c: float | None, h_max: float | None,
                    max_substeps: int | None) -> Any:
    """The observer of :func:`xbs_estimator`, built once per setting: the symbolic set-up and the C
    generation take 0.05-0.7 s, a braking run in the compiled loop 0.02 s; an observer holds no
    run state (the estimator does), so runs can share it."""
    from ..observers import adaptive_xbs_observer, xbs3_observer, xbs4_observer

    bound = {"h_max": h_max, "max_substeps": max_substeps}
    if kind == "xbs3":
        obs = xbs3_observer(beta, beta2, params={"a": a, "b": -b, "c": c}, method=method, **bound)
    elif kind == "xbs4":
        obs = xbs4_observer(beta, beta2, params={"a": a, "b": -b}, method=method, **bound)
    elif kind == "adaptive":
        obs = adaptive_xbs_observer(beta, [gamma, gamma], params={"a": a, "b": b}, method=method, **bound)
    else:   # "adaptive-load": a is a signal
        obs = adaptive_xbs_observer(beta, [gamma, gamma], params={"b": b}, method=method, load_signal=True, **bound)
    if impl == "c":
        from ..codegen import CObserver

        obs = CObserver.like(obs)  # the generated C twin: same model, gains, parameters and readout
    return obs
