"""Plug an observer into the ABS simulations: the ``XbsEstimator`` port of :mod:`switchobs.plants`.

The plant simulation calls an estimator through the structural protocol
:class:`switchobs.plants.XbsEstimator` (``reset``/``update``); this module
turns any observer with ``step``/``readout`` (:class:`SteppingObserver`: the
Python reference observers and the compiled C observers alike) into one.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import Any, Protocol

import numpy as np

from ..exceptions import DimensionError, ModelError, ObserverInputError, SimulationError
from ..plants import CompiledObserver

__all__ = ["ObserverXbsEstimator", "LoadXbsEstimator", "SteppingObserver", "initial_xbs_state", "c_readout",
           "c_observer_type"]


def c_observer_type() -> type | None:
    """:class:`switchobs.codegen.CObserver`, or None where casadi is not installed (a base install): no
    compiled observer can exist there, and the loops run the Python observers without the codegen package."""
    try:
        from ..codegen import CObserver
    except ImportError:
        return None
    return CObserver

#: Tokens of a readout that C evaluates as Python does: state names, number literals, + - * / and parentheses.
_TOKEN = re.compile(r"\s*(?:(?P<state>x\d+)|(?P<number>\d+\.?\d*(?:[eE][+-]?\d+)?)|(?P<op>[-+*/()]))")


class SteppingObserver(Protocol):
    """What the adapter needs: the Python reference observers and a binding of the generated C both qualify."""

    @property
    def state_names(self) -> tuple[str, ...]: ...

    @property
    def signal_names(self) -> tuple[str, ...]: ...

    def step(self, xhat: Any, signals: Any, dt: float) -> np.ndarray: ...

    def readout(self, xhat: Any) -> float: ...


def check_xbs_signals(observer: SteppingObserver, label: str = "an XBS estimator",
                      signals: tuple[str, ...] = ("vx", "u")) -> None:
    """Refuse an observer whose signals are not ``(y, *signals)`` (``(y, vx, u)``: the XBS models of seeds 000
    and 001)."""
    if tuple(observer.signal_names)[1:] != signals:
        raise ModelError(f"{label} needs an observer with signals (y, {', '.join(signals)}), got "
                         f"{tuple(observer.signal_names)}")


def initial_xbs_state(observer: SteppingObserver, y0: float, initial_state: Mapping[str, float]) -> np.ndarray:
    """The observer's state at the first measurement ``y0``.

    The first state (the measured ``z1`` or ``w1`` of the XBS models) starts at
    ``y0``, the named ones at their given values, the others at 0.
    """
    names = tuple(observer.state_names)
    x = np.zeros(len(names))
    x[0] = y0
    for k, v in initial_state.items():
        x[names.index(k)] = v
    return x


def c_readout(code: str) -> str | None:
    """A readout printed in ``x0, x1, ...`` (:attr:`SwitchedObserver.readout_code`) as a C expression in ``x[i]``.

    Only arithmetic that C evaluates as Python does is translated (``+ - * /``, parentheses, number
    literals, made ``double`` so that no division is an integer one); ``None`` for anything else.

    Examples
    --------
    >>> c_readout("-0.25*x2*x0 + x1")
    '-0.25*x[2]*x[0]+x[1]'
    >>> c_readout("1/2*x0")
    '1.0/2.0*x[0]'
    >>> c_readout("numpy.exp(x0)") is None
    True
    """
    if "**" in code or "//" in code:
        return None                        # powers and floor divisions, which C spells otherwise
    out, pos = [], 0
    code = code.rstrip()
    while pos < len(code):
        m = _TOKEN.match(code, pos)
        if m is None or m.end() == pos:
            return None
        pos = m.end()
        if m.group("state"):
            out.append(f"x[{m.group('state')[1:]}]")
        elif m.group("number"):
            num = m.group("number")
            out.append(num if any(c in num for c in ".eE") else f"{num}.0")
        else:
            out.append(m.group("op"))
    return "".join(out)


class ObserverXbsEstimator:
    """An XBS observer seen as a :class:`switchobs.plants.XbsEstimator`.

    Between two calls the observer advances over ``[t - dt, t]`` by one
    :meth:`step` with the signals held at ``((y_prev + y)/2, (vx_prev + vx)/2, u)``:
    the mean of the two samples bounding the step (``u`` is already the
    step's mean pressure rate), which makes the hold error second order in
    ``dt`` instead of first order for the previous sample.

    Parameters
    ----------
    observer : SteppingObserver
        E.g. :func:`xbs3_observer`, :func:`xbs4_observer`,
        :func:`adaptive_xbs_observer`; signals must be ``(y, vx, u)`` and it
        must have a readout (the XBS estimate).
    initial_state : mapping of state name to value, optional
        Initial estimates (e.g. ``{"z2": 0.5}`` or ``{"c": 30, "d": 15}``);
        unnamed entries start at 0 except the first one (the measured ``z1``
        or ``w1`` of the XBS models), which starts at the first measurement ``y0``.

    Examples
    --------
    >>> from switchobs.observers import xbs3_observer
    >>> est = ObserverXbsEstimator(xbs3_observer(10.0, 20.0), initial_state={"z2": 0.3})
    >>> est.reset(0.0, -5.0, 20.0)
    >>> round(est.update(0.001, -5.1, 19.99, 120.0, 0.001), 6)
    0.297506
    """

    #: The signals after ``y`` that the observer must take.
    _signals: tuple[str, ...] = ("vx", "u")

    def __init__(self, observer: SteppingObserver, *, initial_state: Mapping[str, float] | None = None):
        check_xbs_signals(observer, signals=self._signals)
        names = tuple(observer.state_names)
        unknown = sorted(set(initial_state or {}) - set(names))
        if unknown:
            raise DimensionError(f"initial_state names {unknown}, which are not observer states {list(names)}")
        self.observer = observer
        self._initial = dict(initial_state or {})
        self._state = np.zeros(len(names))
        self._y = self._vx = 0.0
        self._estimate = float("nan")

    @property
    def state(self) -> np.ndarray:
        """The current observer state (a copy)."""
        return self._state.copy()

    @property
    def estimate(self) -> float:
        """The last XBS estimate."""
        return self._estimate

    def describe(self) -> str:
        """One line naming the observer, for the simulation report."""
        return str(self.observer).splitlines()[0]

    def reset(self, t0: float, y0: float, vx0: float) -> None:  # noqa: ARG002 - the observer is time-invariant
        """Restart from the first measurements (protocol :class:`switchobs.plants.XbsEstimator`)."""
        x = initial_xbs_state(self.observer, y0, self._initial)
        self._state = x
        self._y, self._vx = float(y0), float(vx0)
        self._estimate = self._readout(x)

    def compiled(self) -> CompiledObserver | None:
        """The C step of a compiled double-precision observer for the compiled braking loop; else ``None``.

        The loop then does what :meth:`reset` and :meth:`update` do, with the generated
        ``<prefix>_step`` (:class:`switchobs.codegen.CObserver` calls the same function).
        """
        obs = self.observer
        # exact behaviour: a subclass of either class may step differently from the function the loop calls
        if type(obs) is not c_observer_type() or type(self) is not ObserverXbsEstimator:
            return None
        generated = obs.generated
        code = obs.readout_code
        readout = c_readout(code) if code is not None else None
        if readout is None or generated.real != "double" or generated.ns != 3:
            return None
        measured_first = tuple(obs.state_names)[0] not in self._initial
        initial = initial_xbs_state(obs, 0.0, self._initial)

        def refusal(x: np.ndarray, sig: np.ndarray, dt: float) -> str:
            # the same step through the binding raises what the Python loop reports
            try:
                obs.step(x, sig, dt)
            except ObserverInputError as exc:
                return str(exc)
            raise SimulationError(f"the observer step from {x.tolist()} with signals {sig.tolist()} and dt = {dt!r} "
                                  "failed in the compiled loop but not through its binding")

        def finish(x: np.ndarray, estimate: float, y: float, vx: float) -> None:
            self._state, self._estimate, self._y, self._vx = x.copy(), estimate, y, vx

        return CompiledObserver(prefix=generated.prefix, files=generated.files, readout=readout,
                                params=tuple(float(v) for v in obs.params), initial=tuple(initial.tolist()),
                                measured_first=measured_first, refusal=refusal, finish=finish)

    def update(self, t: float, y: float, vx: float, u: float, dt: float) -> float:  # noqa: ARG002
        """Advance over ``[t - dt, t]`` and return the XBS estimate; a step of length 0 changes nothing.

        Raises
        ------
        ObserverInputError
            As :meth:`SwitchedObserver.step`, checked on the held (mean)
            signals (e.g. a held ``vx <= 0``, ``dt < 0``).
        """
        if dt != 0.0:
            self._state = self.observer.step(self._state, self._held(y, vx, u), dt)
            self._estimate = self._readout(self._state)
        self._y, self._vx = float(y), float(vx)
        return self._estimate

    def _held(self, y: float, vx: float, u: float) -> tuple[float, ...]:
        """The signals held over the step that ends at the sample ``(y, vx)``."""
        return (0.5 * (self._y + y), 0.5 * (self._vx + vx), u)

    def _readout(self, x: np.ndarray) -> float:
        return float(self.observer.readout(x))


class LoadXbsEstimator(ObserverXbsEstimator):
    """An XBS observer that reads the wheel load, seen as an estimator that takes it (:class:`switchobs.plants.LoadInput`).

    Seed 001 Sec. 3.6 computes the adaptive observer's ``a = R^2 Fz / J`` on line from the loads (3.36).
    The observer (``adaptive_xbs_observer(..., load_signal=True)``) takes ``a`` as its third signal and
    reads out ``a`` times the XBS; this estimator holds ``a`` over a step at the mean of the two bounding
    samples (as ``y`` and ``vx``) and divides the readout by it.  Until :meth:`set_load` is called (the
    quarter car never calls it) the load is ``load_n``.

    Parameters
    ----------
    observer : SteppingObserver
        Signals ``(y, vx, a, u)``, a readout equal to ``a`` times the XBS.
    load_n : float
        The static load [N] (``QuarterCar.load_n``).
    load_gain : float
        ``R^2 / J`` [1/kg], so that ``a = load_gain * Fz``.
    initial_state : mapping, optional
        As for :class:`ObserverXbsEstimator`.

    Examples
    --------
    >>> from switchobs.observers import adaptive_xbs_observer
    >>> obs = adaptive_xbs_observer(100.0, [5e3, 5e3], params={"b": 4.375}, load_signal=True)
    >>> est = LoadXbsEstimator(obs, load_n=2850.0, load_gain=0.3 ** 2 / 1.2, initial_state={"c": 20.0, "d": 10.0})
    >>> est.reset(0.0, -5.0, 20.0)
    >>> est.set_load(3000.0)
    >>> round(est.update(0.001, -5.1, 19.99, 120.0, 0.001), 6)
    0.452495
    """

    _signals = ("vx", "a", "u")

    def __init__(self, observer: SteppingObserver, *, load_n: float, load_gain: float,
                 initial_state: Mapping[str, float] | None = None):
        super().__init__(observer, initial_state=initial_state)
        for name, value in (("load_n", load_n), ("load_gain", load_gain)):
            if not (isinstance(value, (int, float)) and np.isfinite(value) and value > 0):
                raise SimulationError(f"LoadXbsEstimator: {name} must be a finite number > 0, got {value!r}")
        self.load_gain = float(load_gain)
        self._a = self._a_prev = self._a_held = self.load_gain * float(load_n)

    def set_load(self, fz_n: float) -> None:
        """The wheel's vertical load [N] at the next sample (protocol :class:`switchobs.plants.LoadInput`)."""
        self._a = self.load_gain * float(fz_n)

    def reset(self, t0: float, y0: float, vx0: float) -> None:
        self._a_prev = self._a_held = self._a
        super().reset(t0, y0, vx0)

    def update(self, t: float, y: float, vx: float, u: float, dt: float) -> float:
        """As :meth:`ObserverXbsEstimator.update`, with ``a`` held at the mean of the last two loads given."""
        self._a_held = 0.5 * (self._a_prev + self._a)
        estimate = super().update(t, y, vx, u, dt)
        self._a_prev = self._a
        return estimate

    def _held(self, y: float, vx: float, u: float) -> tuple[float, ...]:
        return (0.5 * (self._y + y), 0.5 * (self._vx + vx), self._a_held, u)

    def _readout(self, x: np.ndarray) -> float:
        return float(self.observer.readout(x)) / self._a_held
