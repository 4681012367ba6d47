"""The C kernels of the encoder chain (``_kernels.c``), compiled once and cached, bound with ctypes.

The three-stage estimator runs some 40 µs per sample in numpy, almost all of it call overhead on
vectors of ten numbers; the C port runs it in under half a microsecond (``benchmarks/encoder_chain.py``).
The TSA fit's batched LAPACK factorisations of 15 x 3 matrices take about 1.5 µs a window, the C
Householder QR a fifth of that, and a window already fitted for the previous sample is not fitted again.  The library is built with the system C
compiler through :func:`switchobs.codegen.compile_sources` (cached by the SHA-256 of the source,
compiler and flags) the first time a kernel is asked for; without a compiler the Python reference runs.
"""

from __future__ import annotations

import ctypes
from importlib import resources
from typing import Any

import numpy as np
import numpy.typing as npt

from ..exceptions import CodegenError, SimulationError

__all__ = ["use_kernels", "three_stage_layout", "three_stage_run", "three_stage_update", "notch_run", "tsa_fit"]

Array = npt.NDArray[np.float64]

#: Scalars at the head of the three-stage state (the ST_* of _kernels.c).
_STATE_HEAD = 7
_LIBRARY: list[Any] = []


def _library() -> Any:
    if not _LIBRARY:
        from ..codegen import compile_sources, load_library

        source = resources.files(__package__).joinpath("_kernels.c").read_text(encoding="utf-8")
        lib = load_library(compile_sources({"switchobs_sensors.c": source}, ["switchobs_sensors.c"],
                                           "switchobs_sensors"))
        vp, i64, dbl = ctypes.c_void_p, ctypes.c_int64, ctypes.c_double
        lib.switchobs_three_stage_run.argtypes = [vp, vp, i64, vp, vp, vp, vp, vp]
        lib.switchobs_three_stage_update.argtypes = [vp, vp, dbl, dbl, dbl, vp]
        lib.switchobs_notch_run.argtypes = [vp, dbl, dbl, i64, vp, vp, vp]
        for fn in (lib.switchobs_three_stage_run, lib.switchobs_three_stage_update):
            fn.restype = ctypes.c_int
        lib.switchobs_notch_run.restype = None
        lib.switchobs_tsa_fit.argtypes = [i64, vp, vp, vp, vp, i64, i64, vp, vp]
        lib.switchobs_tsa_fit.restype = None
        _LIBRARY.append(lib)
    return _LIBRARY[0]


def use_kernels(compiled: bool | None) -> bool:
    """Whether to run the C kernels: ``compiled`` if given, else whether a C compiler is installed.

    Raises
    ------
    CodegenError
        ``compiled=True`` without a working compiler.
    """
    if compiled is False:
        return False
    try:
        from ..codegen import find_compiler
    except ImportError as exc:      # the compile machinery lives with codegen, which needs casadi
        if compiled is None:
            return False
        raise CodegenError(f"the C kernels of the encoder chain cannot be built: {exc}") from None
    if compiled is None:
        try:
            find_compiler()
        except CodegenError:
            return False
    _library()
    return True


def three_stage_layout(harmonics: int, size: int) -> tuple[int, int, int]:
    """``(length, gamma_w, gamma_a)``: the state's length and where the two ``Gamma`` matrices start (then
    the regressors of the ``size`` samples of the detrend's ring, ``2 d + 2`` numbers each)."""
    d = 2 * harmonics
    gamma_w = _STATE_HEAD + 5 * size
    gamma_a = gamma_w + d * d + d
    return gamma_a + d * d + d + size * (2 * d + 2), gamma_w, gamma_a


def _ptr(a: Array) -> int:
    return a.ctypes.data


def _check(code: int, cfg: Array) -> None:
    if code:   # the kernel's buffers hold MAX_HARMONICS harmonics, which ThreeStageEstimator checks first
        raise SimulationError(f"the three-stage kernel refused {int(cfg[0])} harmonics")


def three_stage_update(cfg: Array, state: Array, out: Array, theta: float, omega: float, alpha: float) -> None:
    """One sample; ``out`` (2,) receives ``(omega_r_hat, alpha_r_hat)``."""
    _check(_library().switchobs_three_stage_update(_ptr(cfg), _ptr(state), theta, omega, alpha, _ptr(out)), cfg)


def three_stage_run(cfg: Array, state: Array, theta: Array, omega: Array, alpha: Array) -> tuple[Array, Array]:
    """The samples in order (contiguous float64 arrays); the compensated speed and acceleration."""
    th, om, al = (np.ascontiguousarray(v, dtype=float) for v in (theta, omega, alpha))
    out_om, out_al = np.empty(th.size), np.empty(th.size)
    _check(_library().switchobs_three_stage_run(_ptr(cfg), _ptr(state), th.size, _ptr(th), _ptr(om), _ptr(al),
                                                _ptr(out_om), _ptr(out_al)), cfg)
    return out_om, out_al


def notch_run(dt: float, damping: float, u: Array, centre: Array, state: Array) -> Array:
    """The notch over the samples ``u`` with the centres ``centre`` (rad/s), from and into ``state``
    (4 float64: started, z1, z2, the previous sample)."""
    uu, cc = np.ascontiguousarray(u, dtype=float), np.ascontiguousarray(centre, dtype=float)
    out = np.empty(uu.size)
    _library().switchobs_notch_run(_ptr(state), dt, damping, uu.size, _ptr(uu), _ptr(cc), _ptr(out))
    return out


def tsa_fit(times: Array, angles: Array, last: npt.NDArray[np.int_], sample_times: Array, order: int,
            window: int) -> Array:
    """``(theta, omega, alpha, mean time stamp)`` rows (4 x samples) of the TSA fits of the events
    ``last - window + 1 .. last`` at ``sample_times`` (every ``last >= window - 1``): ``_tsa._fit`` in C."""
    tt, th, ts = (np.ascontiguousarray(v, dtype=float) for v in (times, angles, sample_times))
    idx = np.ascontiguousarray(last, dtype=np.int64)
    out = np.empty((4, idx.size))
    work = np.empty(window * (order + 2) + 2 * (order + 1))
    _library().switchobs_tsa_fit(idx.size, _ptr(tt), _ptr(th), _ptr(idx), _ptr(ts), window, order, _ptr(work),
                                 _ptr(out))
    return out
