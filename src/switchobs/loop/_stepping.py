"""An observer stepped through a record of signals with one step length per row (the encoder's measurements
come at uneven intervals), in one C call for a compiled observer.

A :class:`switchobs.codegen.CObserver` runs its rows with a fixed ``dt`` (``<prefix>_run``); here a small
driver compiled with the observer's generated source (once per source, through the codegen cache) calls
``<prefix>_step`` row after row with each row's ``dt``: the function :meth:`CObserver.step` calls, so the
states are the same bit for bit, without a ctypes call per row.  Other observers step in Python.
"""

from __future__ import annotations

import ctypes
from typing import Any

import numpy as np
import numpy.typing as npt

from ..exceptions import SimulationError
from ._adapter import SteppingObserver

Array = npt.NDArray[np.float64]

_DRIVER = """#include <stdint.h>
#include "{prefix}.h"

int32_t switchobs_steps(double *x, const double *sig, const double *dt, int64_t k, const double *params,
                        double *traj, int64_t *done)
{{
    int64_t i, j;
    for (i = 0; i < k; ++i) {{
        int32_t code = {prefix}_step(x, sig + {ns} * i, params, dt[i]);
        if (code != 0) {{ *done = i; return code; }}
        for (j = 0; j < {nx}; ++j) traj[{nx} * i + j] = x[j];
    }}
    *done = k;
    return 0;
}}
"""
_DRIVERS: dict[int, tuple[Any, Any]] = {}


def _driver(obs: Any) -> Any:
    """The compiled ``switchobs_steps`` of a double-precision C observer, or ``None`` for any other observer."""
    from ..codegen import CObserver, compile_sources

    if type(obs) is not CObserver or obs.generated.real != "double":
        return None
    gen = obs.generated
    known = _DRIVERS.get(id(gen))
    if known is not None:
        return known[1]
    files = {f"{gen.prefix}.{ext}": gen.files[f"{gen.prefix}.{ext}"] for ext in ("h", "c")}
    files["switchobs_steps.c"] = _DRIVER.format(prefix=gen.prefix, ns=gen.ns, nx=gen.nx)
    path = compile_sources(files, ["switchobs_steps.c", f"{gen.prefix}.c"], f"switchobs_steps_{gen.prefix}")
    lib = ctypes.CDLL(str(path))
    vp = ctypes.c_void_p
    call = ctypes.CFUNCTYPE(ctypes.c_int32, vp, vp, vp, ctypes.c_int64, vp, vp, vp)(
        ctypes.cast(lib.switchobs_steps, vp).value)
    call.library = lib  # keep the library loaded while the function is
    _DRIVERS[id(gen)] = (gen, call)  # the entry keeps gen alive, so its id is not reused
    return call


def step_through(obs: SteppingObserver, x0: Array, rows: Array, dts: Array) -> Array:
    """The states after each row of ``rows`` (signals held over the step), row ``i`` a step of ``dts[i]``.

    Raises
    ------
    SimulationError
        The refusal :meth:`obs.step` raises at the first row it refuses (e.g. ``ObserverInputError``).
    """
    k, n = len(dts), len(x0)
    call = _driver(obs)
    if call is None:
        out = np.empty((k, n))
        x: Any = x0
        for i, (row, dt) in enumerate(zip(rows.tolist(), dts.tolist())):
            x = obs.step(x, row, dt)
            out[i] = x
        return out
    x = np.array(x0, dtype=float)
    sig = np.ascontiguousarray(rows, dtype=float)
    steps = np.ascontiguousarray(dts, dtype=float)
    traj = np.empty((k, n))
    done = ctypes.c_int64(0)
    code = call(x.ctypes.data, sig.ctypes.data, steps.ctypes.data, k, obs.params.ctypes.data, traj.ctypes.data,
                ctypes.addressof(done))
    if code != 0:
        i = done.value
        before = traj[i - 1] if i else np.asarray(x0, dtype=float)
        obs.step(before, sig[i], float(steps[i]))  # raises the refusal, as a step of the binding does
        raise SimulationError(f"the observer step from {before.tolist()} with signals {sig[i].tolist()} and "
                              f"dt = {steps[i]!r} failed in the compiled steps but not through its binding")
    return traj
