"""The braking loop of :func:`switchobs.plants.simulate` compiled to C, for sweeps of many runs.

``_closed_loop.c`` ports :func:`switchobs.plants.integrate` with the quarter car, the road schedule, the
five- and two-phase ABS and the estimator statement for statement (same floating-point operations in
the same order, the system libm as Python's :mod:`math`), so that a run gives the same samples, events
and metrics as the Python loop, about 30 times faster (``benchmarks/closed_loop.py``).  An estimator
takes part when it offers its C step (:meth:`CompiledEstimator.compiled`, e.g. an
:class:`switchobs.loop.ObserverXbsEstimator` around a compiled observer): its generated source is
compiled into the same library, so a step of the observer is a C call, not a Python one.  The
library is built once per observer source with the system compiler and cached
(:func:`switchobs.codegen.compile_sources`).

Not compiled (the Python loop runs them): the continuous XBS law, an actuator delay, estimators
without a C step (the Python reference observers, the encoder chain) that the controller reads;
:func:`compiled_support` names the reason.  An estimator without a C step that the controller does
not read is replayed over the compiled run (``step_lengths``, :func:`switchobs.plants.simulate`).
"""

from __future__ import annotations

import ctypes
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np

from ..exceptions import CodegenError, SimulationError
from ._controllers import FivePhaseABS, TwoPhaseABS
from ._estimator import TrueXbs
from ._hybrid import MAX_CASCADE, HybridRun

if TYPE_CHECKING:
    from ._plant import _QuarterCar

__all__ = ["CompiledObserver", "CompiledEstimator", "compiled_support", "compiler_available", "run_compiled"]

#: Layout of the parameter vector, of a road change's row, of the output vector and of an event's row.
_P = ("R", "J", "FZ", "GB", "M", "DECEL", "PRESCRIBED", "MAX_RATE", "P_MAX", "DT", "V_LOW", "V_STOP", "T_END",
      "V0", "C1", "C2", "C3", "KIND", "A", "B", "INITIAL_RATE", "TRACKING", "ALPHA", "OVERSHOOT", "HAS_TIMEOUT",
      "TIMEOUT", "U1", "U3", "U4", "EPS0", "EPS1", "EPS2", "EPS3", "EPS4", "EPS5", "Z_REF", "KP", "CHI_A", "CHI_B",
      "HAS_START", "START_DECEL", "EST", "USE_HAT", "LOCATABLE", "OBS_MEASURED_FIRST")
_CH = ("AT_TIME", "WHERE", "DURATION", "C1", "C2", "C3")
_OUT = ("T", "STEPS", "ROWS", "EVENTS", "OBSERVER_TIME", "ESTIMATE", "EST_Y", "EST_VX", "FAIL_DT",
        "CASCADE_INDEX", "CASCADE_PHASE", "FAIL_SIG", "FAIL_X")
_STATUS = ("duration", "stopped", "observer-failed", "cascade", "rows-full", "events-full")
_EVENTS = ("PHASE", "TIMEOUT", "ROAD_TIME", "ROAD_POSITION")
_EV_COLS = 4
_N_SIG = 3
_ENTRY = "switchobs_braking_run"
#: Largest first allocation of recorded rows and of events (a run that needs more is rerun with more room).
_FIRST_ROWS = 1 << 21
_FIRST_EVENTS = 4096


@dataclass(frozen=True)
class CompiledObserver:
    """An estimator's C step, run by the compiled loop in place of its ``reset``/``update``.

    The compiled loop reproduces :class:`switchobs.loop.ObserverXbsEstimator`: at the first sample
    the state is :attr:`initial` (its first entry replaced by the measurement ``x2`` when
    :attr:`measured_first`); each step calls ``<prefix>_step(x, sig, params, dt)`` with the signals
    ``((y_prev + y)/2, (vx_prev + vx)/2, u)`` held, then :attr:`readout` gives the estimate.

    Attributes
    ----------
    prefix : str
        Prefix of the generated functions (``<prefix>_step``).
    files : mapping of str to str
        The generated ``<prefix>.h`` and ``<prefix>.c`` (other files are ignored).
    readout : str
        C expression of the estimate in ``x[0] .. x[n-1]``.
    params, initial : tuple of float
        Runtime parameters of the step and the state at the first sample.
    measured_first : bool
        Whether the first state starts at the first measurement.
    refusal : callable
        ``refusal(x, signals, dt) -> str``: the message of the step from ``x`` that the C step
        refused (the run stops with status ``observer-failed`` and this message, as the Python loop
        does).
    finish : callable
        ``finish(x, estimate, y, vx)``: hands the final state back to the estimator.
    """

    prefix: str
    files: Mapping[str, str]
    readout: str
    params: tuple[float, ...]
    initial: tuple[float, ...]
    measured_first: bool
    refusal: Callable[[np.ndarray, np.ndarray, float], str]
    finish: Callable[[np.ndarray, float, float, float], None]


@runtime_checkable
class CompiledEstimator(Protocol):
    """An estimator that the compiled loop can run: it offers its C step (or ``None`` if it has none)."""

    def compiled(self) -> CompiledObserver | None: ...


def _defines(obs: CompiledObserver | None, n_series: int, step_lengths: bool) -> str:
    # clock_gettime under -std=c99
    lines = ["#define _POSIX_C_SOURCE 199309L"] + [f"#define P_{name} {i}" for i, name in enumerate(_P)]
    if step_lengths:
        lines.append("#define RECORD_STEP 1")
    lines += [f"#define CH_{name} {i}" for i, name in enumerate(_CH)]
    lines.append(f"#define CH_COLS {len(_CH)}")
    lines += [f"#define OUT_{name} {i}" for i, name in enumerate(_OUT[:-2])]
    lines += [f"#define OUT_FAIL_SIG {len(_OUT) - 2}", f"#define OUT_FAIL_X {len(_OUT) - 2 + _N_SIG}"]
    lines += [f"#define ST_{name.upper().replace('-', '_')} {i}" for i, name in enumerate(_STATUS)]
    lines += [f"#define EV_{name} {i}" for i, name in enumerate(_EVENTS)]
    # a recorded row holds the columns of SERIES in order (record_row)
    lines += [f"#define EV_COLS {_EV_COLS}", f"#define N_SERIES {n_series + step_lengths}"]
    if obs is None:
        lines += ["#define OBS_NX 0", "#define OBS_NS 0"]
    else:
        lines += [f'#include "{obs.prefix}.h"', f"#define OBS_NX {len(obs.initial)}", f"#define OBS_NS {_N_SIG}",
                  f"#define OBS_STEP {obs.prefix}_step", f"#define OBS_READOUT(x) ({obs.readout})"]
    return "\n".join(lines) + "\n"


_LOADED: dict[Path, Any] = {}


def _library(obs: CompiledObserver | None, n_series: int, step_lengths: bool) -> Any:
    from ..codegen import compile_sources, load_library

    source = resources.files(__package__).joinpath("_closed_loop.c").read_text(encoding="utf-8")
    files = {"switchobs_braking.c": _defines(obs, n_series, step_lengths) + source}
    sources = ["switchobs_braking.c"]
    if obs is not None:
        for ext in ("h", "c"):
            files[f"{obs.prefix}.{ext}"] = obs.files[f"{obs.prefix}.{ext}"]
        sources.append(f"{obs.prefix}.c")
    path = compile_sources(files, sources, "switchobs_braking" if obs is None else f"switchobs_braking_{obs.prefix}")
    fn = _LOADED.get(path)
    if fn is None:
        lib = load_library(path)
        vp, i64 = ctypes.c_void_p, ctypes.c_int64
        fn = ctypes.CFUNCTYPE(ctypes.c_int32, vp, vp, ctypes.c_int32, vp, vp, vp, i64, vp, i64, vp)(
            ctypes.cast(getattr(lib, _ENTRY), vp).value)
        fn.library = lib   # keep the library loaded while the function is
        _LOADED[path] = fn
    return fn


def compiled_support(plant: _QuarterCar, *, estimator: bool = True) -> tuple[CompiledObserver | None, str | None]:
    """The estimator's C step and ``None``, or ``None`` and why the compiled loop cannot run ``plant``
    (``estimator=False``: ``plant`` without its estimator)."""
    sc = plant.sc
    # exact types: a subclass may change the runtime the C code ports
    if type(sc.controller) not in (FivePhaseABS, TwoPhaseABS):
        return None, f"the controller {type(sc.controller).__name__} runs in the Python loop only"
    if sc.actuator.delay_s > 0.0:
        return None, "an actuator delay runs in the Python loop only"
    if plant.x2_source is not None:
        return None, "a measured x2 (x2_source) runs in the Python loop only"
    est = plant.estimator
    if not estimator or est is None or (isinstance(est, TrueXbs) and getattr(est, "_truth", None) == plant.true_xbs):
        return None, None
    parts = est.compiled() if isinstance(est, CompiledEstimator) else None
    if parts is None:
        return None, (f"the estimator {type(est).__name__} has no C step (use a compiled observer, "
                      f"EstimatorSpec(..., impl='c'))")
    return parts, None


def _parameters(plant: _QuarterCar, obs: CompiledObserver | None) -> np.ndarray:
    sc, veh = plant.sc, plant.sc.vehicle
    ctrl = sc.controller
    first = sc.roads.initial
    values: dict[str, float] = {
        "R": plant.R, "J": plant.J, "FZ": plant.Fz, "GB": plant.gb, "M": plant.m, "DECEL": plant.decel,
        "PRESCRIBED": float(plant.prescribed), "MAX_RATE": plant.max_rate, "P_MAX": plant.p_max, "DT": sc.dt_s,
        "V_LOW": sc.low_speed_m_s, "V_STOP": sc.stop_speed_m_s, "T_END": sc.duration_s, "V0": sc.speed_m_s,
        "C1": first.c1, "C2": first.c2, "C3": first.c3, "A": veh.a, "B": veh.b,
        "INITIAL_RATE": ctrl.initial_rate_bar_s,
        "EST": 0.0 if plant.estimator is None else (2.0 if obs is not None else 1.0),
        "USE_HAT": float(plant.use_hat), "LOCATABLE": float(plant.locatable(0)),
        "OBS_MEASURED_FIRST": float(obs is not None and obs.measured_first)}
    if isinstance(ctrl, FivePhaseABS):
        values.update({"KIND": 0.0, "TRACKING": float(ctrl.tracking), "ALPHA": ctrl.alpha,
                       "OVERSHOOT": ctrl.overshoot, "HAS_TIMEOUT": float(ctrl.stall_timeout_s is not None),
                       "TIMEOUT": ctrl.stall_timeout_s or 0.0, "U1": ctrl.u1, "U3": ctrl.u3, "U4": ctrl.u4,
                       **{f"EPS{i}": e for i, e in enumerate(ctrl.eps)}})
    else:
        values.update({"KIND": 1.0, "Z_REF": ctrl.z_ref, "KP": ctrl.kp, "CHI_A": ctrl.chi_a, "CHI_B": ctrl.chi_b,
                       "HAS_START": float(ctrl.start_decel_m_s2 is not None),
                       "START_DECEL": ctrl.start_decel_m_s2 or 0.0})
    return np.array([float(values.get(name, 0.0)) for name in _P])


def _event_text(code: int, a: float, b: float, roads: tuple[Any, ...]) -> str:
    kind = _EVENTS[code]
    if kind == "PHASE":
        return f"phase {int(a)} -> {int(b)}"
    if kind == "TIMEOUT":
        return f"phase {int(a)} -> {int(b)} (stall timeout)"
    change = roads[int(a)]
    if kind == "ROAD_TIME":
        return f"road -> {change.road.name}"
    return f"road -> {change.road.name} (x = {b:.2f} m)"


def run_compiled(plant: _QuarterCar, obs: CompiledObserver | None, *, step_lengths: bool = False) -> HybridRun:
    """Run ``plant`` (supported, :func:`compiled_support`) in the compiled loop; what :func:`integrate` returns.

    Also sets what the Python loop leaves on the plant and the estimator: the road changes' start times,
    the observer's time and its final state.  With ``step_lengths`` the series also hold ``dt``, the length
    of the step that ended at each sample (0 at the first), exactly as the loop took it (``t`` differences
    are rounded): what an estimator replayed over the run afterwards is handed.

    Raises
    ------
    SimulationError
        As :func:`switchobs.plants.integrate` (phase changes cascading at one instant).
    CodegenError
        When no C compiler is found or the compilation fails.
    """
    wall0 = time.perf_counter()
    sc = plant.sc
    fn = _library(obs, len(plant.series), step_lengths)
    columns = (*plant.series, "dt") if step_lengths else plant.series
    params = _parameters(plant, obs)
    changes = sc.roads.changes
    ch = np.array([[1.0 if c.at_time_s is not None else 0.0,
                    c.at_time_s if c.at_time_s is not None else c.at_position_m,
                    c.duration_s, c.road.c1, c.road.c2, c.road.c3] for c in changes], dtype=float).reshape(-1, len(_CH))
    nx = 0 if obs is None else len(obs.initial)
    x = np.array(obs.initial if obs is not None else (0.0,), dtype=float)
    op = np.array(obs.params if obs is not None else (0.0,), dtype=float)
    out = np.zeros(len(_OUT) - 2 + _N_SIG + max(nx, 1))
    # room for twice the nominal steps (the step shrinks below low_speed_m_s, events split steps), at most
    # 2^21 rows (256 MB) at first; a run that needs more is rerun (deterministic) with 4 times the room
    cap = min(int(2 * sc.duration_s / sc.dt_s) + 1024, _FIRST_ROWS)
    events_cap = _FIRST_EVENTS
    while True:
        rows = np.empty((cap, len(columns)))
        events = np.empty((events_cap, _EV_COLS))
        if obs is not None:
            x = np.array(obs.initial, dtype=float)
        status = _STATUS[fn(params.ctypes.data, ch.ctypes.data, len(changes), x.ctypes.data, op.ctypes.data,
                            rows.ctypes.data, cap, events.ctypes.data, events_cap, out.ctypes.data)]
        if status == "rows-full":
            cap *= 4
        elif status == "events-full":
            events_cap *= 8
        else:
            break
    idx = {name: i for i, name in enumerate(_OUT)}
    t = float(out[idx["T"]])
    n_events = int(out[idx["EVENTS"]])
    if status == "cascade":
        raise SimulationError(
            f"scenario {sc.name!r}: the controller changed phase {MAX_CASCADE} times at t = {t:.6f} s without "
            f"time passing and its guard {int(out[idx['CASCADE_INDEX']])} of phase "
            f"{int(out[idx['CASCADE_PHASE']])} is still positive; check its thresholds")
    n_rows = int(out[idx["ROWS"]])
    data = rows[:n_rows]
    ev = events[:n_events]
    event_list = tuple((float(e[0]), _event_text(int(e[1]), float(e[2]), float(e[3]), changes)) for e in ev)
    plant.road.starts = [float(e[0]) for e in ev if _EVENTS[int(e[1])] in ("ROAD_TIME", "ROAD_POSITION")]
    plant.observer_time_s = float(out[idx["OBSERVER_TIME"]])
    if status == "duration":
        message = f"reached the time bound {sc.duration_s:g} s"
    elif status == "stopped":
        message = f"vx reached {sc.stop_speed_m_s:.3f} m/s"
    else:
        base = len(_OUT) - 2
        message = obs.refusal(out[base + _N_SIG:base + _N_SIG + nx].copy(), out[base:base + _N_SIG].copy(),
                              float(out[idx["FAIL_DT"]]))
    if obs is not None:
        obs.finish(x, float(out[idx["ESTIMATE"]]), float(out[idx["EST_Y"]]), float(out[idx["EST_VX"]]))
    series = {col: data[:, i].copy() for i, col in enumerate(columns)}
    return HybridRun(series=series, events=event_list, status=status, message=message,
                     steps=int(out[idx["STEPS"]]), wall_time_s=time.perf_counter() - wall0)


def compiler_available() -> bool:
    """Whether a C compiler is installed (without one, the automatic choice runs the Python loop)."""
    try:
        from ..codegen import find_compiler
    except ImportError:    # without casadi (a base install) the codegen package is missing: the Python loop runs
        return False
    try:
        find_compiler()
    except CodegenError:
        return False
    return True
