"""The wheel-acceleration reference (21) that a tracking five-phase ABS followed during a run.

:class:`switchobs.plants.FivePhaseABS` with ``tracking=True`` drives ``x2``
along the cubic (21) of seed 000 in phases 1, 3 and 4; the simulation records
the phase changes (``BrakingResult.events``) and ``x2`` but not the reference.
It is rebuilt here from the documented rule (``docs/abs.md``): on entering
phase ``p`` at ``t0`` with ``x2(t0) = x0``, the cubic goes from ``x0`` to
``target = thr + overshoot (thr - x0)`` (``thr`` the exit threshold of the
phase: ``eps1``, ``eps3``, ``-eps4``) with zero slope at both ends, over
``T = 1.5 |target - x0| / (b r)``, ``r = min(|u_p| / max(R ω(t0), 0.1), max rate)``.
``tests/test_demo.py`` replays the controller's own runtime and checks that
law (22) evaluated on this reference gives its pressure rate.
"""

from __future__ import annotations

import math
import re

import numpy as np
import numpy.typing as npt

from ..exceptions import SimulationError
from ..plants import BrakingResult, FivePhaseABS

__all__ = ["tracking_reference"]

Array = npt.NDArray[np.float64]

_PHASE_EVENT = re.compile(r"^phase (\d+) -> (\d+)")
#: Wheel-speed floor [m/s] of the phase rates u_i / (R ω) (FivePhaseABS).
_V_WHEEL_FLOOR = 0.1


def tracking_reference(result: BrakingResult) -> tuple[Array, Array]:
    """``(x2_ref, dx2_ref)`` at the samples of ``result.series["t"]``; NaN outside phases 1, 3, 4.

    Parameters
    ----------
    result : BrakingResult
        A run with a :class:`FivePhaseABS` controller with ``tracking=True``.

    Raises
    ------
    SimulationError
        If the controller does not track a reference.

    References
    ----------
    seed 000 eq. (21)-(22) and Fig. 4.
    """
    ctrl = result.scenario.controller
    if not (isinstance(ctrl, FivePhaseABS) and ctrl.tracking):
        raise SimulationError(f"the run's controller ({ctrl}) does not track a wheel-acceleration reference; "
                              "use FivePhaseABS(tracking=True)")
    s = result.series
    t, x2, omega = s["t"], s["x2"], s["omega"]
    R = result.scenario.vehicle.radius_m
    b = result.scenario.vehicle.b
    max_rate = result.scenario.actuator.max_rate_bar_s
    e0, e1, e2, e3, e4, e5 = ctrl.eps
    exit_threshold = {1: e1, 3: e3, 4: -e4}
    open_loop_rate = {1: ctrl.u1, 3: ctrl.u3, 4: ctrl.u4}
    ref = np.full(t.size, np.nan)
    dref = np.full(t.size, np.nan)
    entries = []
    for te, text in result.events:
        m = _PHASE_EVENT.match(text)
        if m:
            entries.append((te, int(m.group(2))))
    for k, (t0, phase) in enumerate(entries):
        t_next = entries[k + 1][0] if k + 1 < len(entries) else math.inf
        if phase not in exit_threshold:
            continue
        # the row recorded at the event time holds the x2 and ω the controller used (last one if repeated)
        i0 = int(np.searchsorted(t, t0, side="right")) - 1
        x0, v_wheel = float(x2[i0]), R * float(omega[i0])
        thr = exit_threshold[phase]
        target = thr + ctrl.overshoot * (thr - x0)
        span = target - x0
        rate = min(open_loop_rate[phase] / max(v_wheel, _V_WHEEL_FLOOR), max_rate)
        T = 1.5 * abs(span) / (b * rate)
        sel = (t >= t0) & (t < t_next)
        tau = np.minimum(t[sel] - t0, T)
        ref[sel] = x0 + span * (3.0 * (tau / T) ** 2 - 2.0 * (tau / T) ** 3) if T > 0 else target
        dref[sel] = span * (6.0 * tau / T ** 2 - 6.0 * tau ** 2 / T ** 3) if T > 0 else 0.0
    return ref, dref
