"""An observer stepped through a record of signals with one step length per row (the encoder's measurements
come at uneven intervals), in one C call for a compiled observer.

A :class:`switchobs.codegen.CObserver` runs the rows in its generated ``<prefix>_run_dt``, whose states are
those of :meth:`CObserver.step` row after row, bit for bit; other observers step in Python.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from ._adapter import SteppingObserver, c_observer_type

Array = npt.NDArray[np.float64]


def step_through(obs: SteppingObserver, x0: Array, rows: Array, dts: Array) -> Array:
    """The states after each row of ``rows`` (signals held over the step), row ``i`` a step of ``dts[i]``.

    Raises
    ------
    SimulationError
        A refusal of the observer at the first row it refuses (e.g. ``ObserverInputError``).
    """
    if type(obs) is c_observer_type():  # exact behaviour: a subclass may step differently from the generated C
        return obs.run_dt(x0, rows, dts)
    out = np.empty((len(dts), len(x0)))
    x: Any = x0
    for i, (row, dt) in enumerate(zip(rows.tolist(), dts.tolist())):
        x = obs.step(x, row, dt)
        out[i] = x
    return out
