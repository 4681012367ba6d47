"""The port through which a simulation feeds an XBS estimator, and a trivial oracle.

The simulations of :mod:`switchobs.plants` never import an observer: they call
any object with the two methods of :class:`XbsEstimator` (structural typing).
The protocol lives here, with the simulations that call it, because a lower
layer defines the ports it calls; :mod:`switchobs.loop` implements it for the
Python reference observers, the compiled C observers and the encoder chain
(:func:`switchobs.loop.xbs_estimator`, :class:`switchobs.loop.ObserverXbsEstimator`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Protocol, runtime_checkable

import numpy as np
import numpy.typing as npt

from ..exceptions import SimulationError

__all__ = ["XbsEstimator", "LoadInput", "TrueXbs", "X2Measurement", "ReplayEstimator", "Replay", "replay_updates"]

Array = npt.NDArray[np.float64]
#: What a replay returns: the estimate after each sample (NaN at the first, as the loop records it), and the
#: index of the sample whose update refused its step with the refusal's message (the run stops there; the
#: estimates end at that sample, which holds the estimate from before), or ``None`` and ``""``.
Replay = tuple[Array, "int | None", str]


@runtime_checkable
class XbsEstimator(Protocol):
    """An on-line estimator of the extended braking stiffness ``mu'(lambda)``.

    The simulation calls :meth:`reset` once, at the first sample, then
    :meth:`update` after every accepted integration step (steps are split at
    the hybrid events, so ``dt`` is not constant).

    Signals, all in SI units except the pressure rate:

    ``y``
        measured wheel-acceleration offset ``x2 = R dω/dt - a_x`` [m/s²] at time ``t``
        (seed 000 Sec. II-B, seed 001 eq. (2.2)); it is ``z1`` of the observer models.
    ``vx``
        vehicle speed used by the observer [m/s] (the true speed, or an estimate
        for the two-axle vehicle of seed 001 Sec. 3.6).
    ``u``
        brake-pressure rate ``dP_b/dt`` [bar/s] averaged over the step, i.e.
        ``(P_b(t) - P_b(t - dt)) / dt``, so that ``∫ u dt`` is exact over the step.
    ``dt``
        length of the step just taken [s]; the observer advances from ``t - dt`` to ``t``.
    """

    def reset(self, t0: float, y0: float, vx0: float) -> None:
        """Restart the estimator at time ``t0`` from the first measurements."""
        ...

    def update(self, t: float, y: float, vx: float, u: float, dt: float) -> float:
        """Advance from ``t - dt`` to ``t`` and return the XBS estimate ``mu_hat'(t)``.

        May raise :class:`switchobs.exceptions.SimulationError` (e.g.
        ``ObserverInputError``) to refuse a step; the simulation (quarter car
        and two-axle vehicle alike) then stops with status ``observer-failed``.
        """
        ...


@runtime_checkable
class LoadInput(Protocol):
    """An estimator that also reads the wheel's vertical load (seed 001 Sec. 3.6: the observer's ``a``
    computed on line from the loads (3.36)).

    :func:`switchobs.plants.simulate_two_axle` calls :meth:`set_load` before :meth:`XbsEstimator.reset` and
    before every :meth:`XbsEstimator.update`, with the load (3.36) of the estimator's wheel computed from
    the *measured* acceleration (the biased accelerometer).  The quarter car does not call it (its load is
    constant).  :class:`switchobs.loop.LoadXbsEstimator` implements it.
    """

    def set_load(self, fz_n: float) -> None:
        """The vertical load [N] at the time of the next ``reset`` or ``update``."""
        ...


@runtime_checkable
class X2Measurement(Protocol):
    """A measured wheel-acceleration offset ``x2`` that the brake controller reads instead of the exact one.

    Seed 001 Sec. 6.4 (Figs. 6.7-6.9) closes the five-phase ABS on ``x2``
    computed from a wheel encoder: its thresholds then switch on the
    measurement, with its ripple and its delay.  :func:`switchobs.plants.simulate`
    (``x2_source=...``) calls :meth:`reset` at the first sample and
    :meth:`update` after every accepted step with the plant's exact signals
    (those of :class:`XbsEstimator`), and hands the returned value to the
    controller's rate, guards and transitions until the next step end.  The
    guards are then checked at the step ends (the measurement is piecewise
    constant).  :class:`switchobs.loop.EncoderX2` implements it with the
    encoder chain of :mod:`switchobs.sensors`.
    """

    def reset(self, t0: float, y0: float, vx0: float) -> None:
        """Restart the measurement chain at time ``t0`` from the exact signals."""
        ...

    def update(self, t: float, y: float, vx: float, u: float, dt: float) -> float:
        """Advance from ``t - dt`` to ``t`` and return the measured ``x2`` the controller reads from ``t`` on."""
        ...


class TrueXbs:
    """Oracle 'estimator' returning the true XBS; state feedback for tests and references.

    Parameters
    ----------
    truth : callable
        ``truth() -> float`` giving the plant's current ``mu'(lambda)``;
        ``simulate(..., estimator="true")`` binds it to the simulated wheel.

    Examples
    --------
    >>> est = TrueXbs(lambda: 0.25)
    >>> est.reset(0.0, -3.0, 30.0)
    >>> est.update(0.001, -3.1, 29.99, 100.0, 0.001)
    0.25
    """

    def __init__(self, truth: Callable[[], float]):
        self._truth = truth

    def reset(self, t0: float, y0: float, vx0: float) -> None:  # noqa: ARG002 - nothing to restart
        return None

    def update(self, t: float, y: float, vx: float, u: float, dt: float) -> float:  # noqa: ARG002
        return float(self._truth())


@runtime_checkable
class ReplayEstimator(Protocol):
    """An estimator that can run over a whole recorded run at once, as :func:`replay_updates` does step by step.

    When the controller does not read the estimate, the plant's run does not depend on the estimator, so
    :func:`switchobs.plants.simulate` runs the plant in the compiled loop first and replays the estimator
    over the recorded steps afterwards; an estimator with :meth:`replay` does that in bulk (e.g. the
    encoder chain of :class:`switchobs.loop.EncoderLoopEstimator`), any other one through
    :func:`replay_updates`.  Either way the estimates are those the interleaved loop gives.
    """

    def replay(self, t: Array, y: Array, vx: Array, u: Array, dt: Array) -> Replay:
        """:func:`replay_updates` on this estimator (same arguments, same result, same state left behind)."""
        ...


def replay_updates(estimator: XbsEstimator, t: Array, y: Array, vx: Array, u: Array, dt: Array) -> Replay:
    """Feed a recorded run to ``estimator`` as the simulation loop does: ``reset`` at the first sample, then
    ``update`` with each later sample and the step that ended there.

    Parameters
    ----------
    estimator : XbsEstimator
    t, y, vx, u, dt : ndarray
        The run's samples (:class:`XbsEstimator`'s signals; ``u[k]`` and ``dt[k]`` belong to the step that
        ended at sample ``k``, ``u[0]`` and ``dt[0]`` are not read).

    Returns
    -------
    Replay
        A :class:`switchobs.exceptions.SimulationError` raised by ``update`` ends the replay as it ends the
        run (status ``observer-failed``).
    """
    t_, y_, vx_, u_, dt_ = (np.asarray(a, dtype=float).tolist() for a in (t, y, vx, u, dt))
    estimator.reset(t_[0], y_[0], vx_[0])
    out = [math.nan]
    update = estimator.update
    for k in range(1, len(t_)):
        try:
            out.append(update(t_[k], y_[k], vx_[k], u_[k], dt_[k]))
        except SimulationError as exc:
            out.append(out[-1])
            return np.array(out, dtype=float), k, str(exc)
    return np.array(out, dtype=float), None, ""
