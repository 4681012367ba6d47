"""Hostile inputs, documented status codes, untouched state; bad generation requests; the codegen CLI."""

from __future__ import annotations

import ctypes
import dataclasses
import json
import math

import numpy as np
import pytest
import sympy as sp

from switchobs.cli.main import main
from switchobs.codegen import CObserver, StepStatus, compile_observer, generate_observer, generate_super_twisting
from switchobs.design import design
from switchobs.exceptions import CodegenError, DimensionError, FreeSymbolError, ModelError, ObserverInputError
from switchobs.model import Model, builtin_model
from switchobs.observers import SwitchedObserver, xbs4_observer

NAN, INF = math.nan, math.inf
X0 = [0.5, 0.4, -0.2, 3.0]
SIG = [2.0, 20.0, 100.0]


@pytest.fixture(scope="module")
def xbs4():
    ref = xbs4_observer(10.0, 20.0)
    return ref, CObserver.like(ref), CObserver.like(ref, real="float")


# (x, signals, dt) -> status of seed 000's 4D observer; the Python reference must agree on codes 1-5.
HOSTILE = [
    (X0, SIG, 0.0, StepStatus.BAD_DT),
    (X0, SIG, -1e-3, StepStatus.BAD_DT),
    (X0, SIG, NAN, StepStatus.BAD_DT),
    (X0, SIG, INF, StepStatus.BAD_DT),
    ([NAN, 0, 0, 0], SIG, 1e-3, StepStatus.NONFINITE_STATE),
    ([0, 0, 0, -INF], SIG, 1e-3, StepStatus.NONFINITE_STATE),
    (X0, [NAN, 20.0, 0.0], 1e-3, StepStatus.NONFINITE_SIGNAL),
    (X0, [1.0, INF, 0.0], 1e-3, StepStatus.NONFINITE_SIGNAL),
    (X0, [1.0, 20.0, -INF], 1e-3, StepStatus.NONFINITE_SIGNAL),
    (X0, [1.0, 0.0, 0.0], 1e-3, StepStatus.UNDEFINED_TIME_SCALE),     # vx = 0
    (X0, [1.0, -5.0, 0.0], 1e-3, StepStatus.UNDEFINED_TIME_SCALE),    # vx < 0
    (X0, [1e300, 1e-300, 0.0], 1e-3, StepStatus.UNDEFINED_TIME_SCALE),  # s = y/vx overflows
    ([1e306, -1e306, 1e306, 1e306], SIG, 1e-2, StepStatus.NONFINITE_RESULT),  # the step overflows
    (X0, [1e150, 20.0, 1e300], 1.0, StepStatus.NONFINITE_RESULT),
]


@pytest.mark.parametrize("x, sig, dt, status", HOSTILE)
def test_hostile_inputs_give_documented_codes_like_the_reference(xbs4, x, sig, dt, status):
    ref, c, _ = xbs4
    with pytest.raises(ObserverInputError) as c_err:
        c.step(x, sig, dt)
    with pytest.raises(ObserverInputError) as py_err:
        ref.step(x, sig, dt)
    assert c_err.value.code == py_err.value.code == int(status)
    assert status.name in str(c_err.value)


def _raw(c: CObserver):
    """The C step itself, on our own buffers, to see that a refused step writes nothing."""
    lib = ctypes.CDLL(str(c.library_path))
    real = ctypes.c_float if c.real == "float" else ctypes.c_double
    fn = getattr(lib, f"{c.generated.prefix}_step")
    fn.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, real]
    fn.restype = ctypes.c_int32
    dtype = np.float32 if c.real == "float" else np.float64
    return fn, dtype


@pytest.mark.parametrize("real", ["double", "float"])
def test_refused_step_leaves_state_untouched_and_null_pointers_are_refused(xbs4, real):
    c = xbs4[1] if real == "double" else xbs4[2]
    fn, dtype = _raw(c)
    for x, sig, dt, status in HOSTILE:
        with np.errstate(over="ignore"):
            xb, sb = np.array(x, dtype=dtype), np.array(sig, dtype=dtype)
        before = xb.copy()
        code = fn(xb.ctypes.data, sb.ctypes.data, None, dt)  # NULL params: the defaults
        assert code != 0
        assert np.array_equal(xb, before, equal_nan=True)
        if real == "double":
            assert code == status
    xb, sb = np.array(X0, dtype=dtype), np.array(SIG, dtype=dtype)
    assert fn(None, sb.ctypes.data, None, 1e-3) == StepStatus.BAD_ARGUMENT
    assert fn(xb.ctypes.data, None, None, 1e-3) == StepStatus.BAD_ARGUMENT
    assert fn(xb.ctypes.data, sb.ctypes.data, None, 1e-3) == 0 and not np.array_equal(xb, X0)


@pytest.mark.parametrize("name, value", [("a", 0.0), ("a", -1.0), ("b", 2.0), ("K_plus_z2", NAN), ("c", INF)])
def test_bad_runtime_parameter_is_refused(xbs4, name, value):
    _, c, _ = xbs4
    if name == "c":
        name = "alpha1"
    bad = c.with_params({name: value})
    with pytest.raises(ObserverInputError, match="BAD_PARAM") as err:
        bad.step(X0, SIG, 1e-3)
    assert err.value.code == StepStatus.BAD_PARAM
    assert name in str(err.value)


def test_run_stops_at_the_first_failing_row_and_names_it(xbs4):
    ref, c, _ = xbs4
    rows = np.tile(SIG, (10, 1))
    rows[6, 1] = 0.0  # vx = 0 at row 6
    with pytest.raises(ObserverInputError, match="row 6") as c_err:
        c.run(X0, rows, 1e-3)
    with pytest.raises(ObserverInputError, match="row 6") as py_err:
        ref.run(X0, rows, 1e-3)
    assert c_err.value.code == py_err.value.code == StepStatus.UNDEFINED_TIME_SCALE
    # the C run: xhat holds the state after the 6 good steps, rows 0..5 are written, the rest untouched
    lib = ctypes.CDLL(str(c.library_path))
    run = getattr(lib, f"{c.generated.prefix}_run")
    run.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int32, ctypes.c_void_p, ctypes.c_double,
                    ctypes.c_void_p]
    x = np.array(X0, dtype=float)
    traj = np.full((10, 4), -7.0)
    assert run(x.ctypes.data, np.ascontiguousarray(rows).ctypes.data, 10, None, 1e-3, traj.ctypes.data) == 4
    good = c.run(X0, rows[:6], 1e-3)
    assert np.array_equal(traj[:6], good) and np.all(traj[6:] == -7.0) and np.array_equal(x, good[-1])
    assert run(x.ctypes.data, None, 3, None, 1e-3, None) == StepStatus.BAD_ARGUMENT
    assert run(x.ctypes.data, None, -1, None, 1e-3, None) == StepStatus.BAD_ARGUMENT
    assert run(x.ctypes.data, None, 0, None, 1e-3, None) == StepStatus.BAD_ARGUMENT  # signals: never NULL
    with pytest.raises(ObserverInputError) as err:
        c.run(X0, np.empty((0, 3)), 0.0)  # dt is checked even without rows, as the reference does
    assert err.value.code == StepStatus.BAD_DT


def test_run_checks_dt_and_parameters_once_but_reports_what_step_reports(xbs4):
    """_run validates dt and the parameters before its loop; when they fail, the rows keep _step's order."""
    ref, c, _ = xbs4
    bad = c.with_params({"alpha1": NAN})
    rows = np.tile(SIG, (3, 1))
    for x0, row0, dt, status in ((X0, SIG, 1e-3, StepStatus.BAD_PARAM),
                                 (X0, (NAN, *SIG[1:]), 1e-3, StepStatus.NONFINITE_SIGNAL),
                                 ((NAN, *X0[1:]), SIG, 1e-3, StepStatus.NONFINITE_STATE),
                                 (X0, (NAN, *SIG[1:]), -1.0, StepStatus.BAD_DT)):
        rows[0] = row0
        with pytest.raises(ObserverInputError, match="row 0") as run_err:
            bad.run(x0, rows, dt)
        with pytest.raises(ObserverInputError) as step_err:
            bad.step(x0, row0, dt)
        assert run_err.value.code == step_err.value.code == status
    assert np.array_equal(c.run(X0, np.tile(SIG, (3, 1)), 1e-3)[-1],
                          c.step(c.step(c.step(X0, SIG, 1e-3), SIG, 1e-3), SIG, 1e-3))


def _stepped(c: CObserver, x0, rows: np.ndarray, dts: np.ndarray) -> tuple[np.ndarray, int | None, int | None]:
    """``c.step`` row after row: the states, and the row and code of the first refusal (None if none)."""
    x, out = np.asarray(x0, dtype=float), []
    for i, (row, dt) in enumerate(zip(rows, dts)):
        try:
            x = c.step(x, row, dt)
        except ObserverInputError as err:
            return np.array(out).reshape(-1, c.size), i, err.code
        out.append(x)
    return np.array(out).reshape(-1, c.size), None, None


def _raw_run_dt(c: CObserver):
    lib = ctypes.CDLL(str(c.library_path))
    fn = getattr(lib, f"{c.generated.prefix}_run_dt")
    fn.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int32, ctypes.c_void_p, ctypes.c_void_p,
                   ctypes.c_void_p]
    fn.restype = ctypes.c_int32
    return lambda *args: fn(*(a.ctypes.data if isinstance(a, np.ndarray) else a for a in args))


def _irregular(rng: np.random.Generator, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Rows (y, vx, u) and step lengths from 10 µs to 5 ms, log-uniform (measurements at uneven intervals)."""
    rows = np.column_stack([rng.normal(0.0, 3.0, k), rng.uniform(2.0, 40.0, k), rng.normal(0.0, 100.0, k)])
    return rows, 10.0 ** rng.uniform(-5.0, np.log10(5e-3), k)


def _sub_stepped() -> CObserver:
    m = builtin_model("abs-xbs3")
    return compile_observer(generate_observer(m, design(m, "-40,-60,-60"), method="radau3", h_max="1/4000",
                                              max_substeps=64))


def _adaptive() -> CObserver:
    m = builtin_model("abs-adaptive2")
    return compile_observer(generate_observer(m, design(m, "-15,-15"), unknown=["c", "d"], Gamma=[50.0, 20.0]))


@pytest.mark.parametrize("which", ["double", "float", "radau3-substeps", "adaptive"])
def test_run_dt_equals_step_row_by_row_bit_for_bit(xbs4, which):
    """_run_dt: row k a step of dt[k]; the states are _step's row by row, bit for bit; equal steps give _run."""
    c = {"double": xbs4[1], "float": xbs4[2]}.get(which) or (_sub_stepped() if which == "radau3-substeps"
                                                             else _adaptive())
    rng = np.random.default_rng(7)
    rows, dts = _irregular(rng, 400)
    x0 = np.zeros(c.size)
    x0[0] = 0.5
    if which == "radau3-substeps":  # some rows are split into sub-steps of H_MAX, others are not
        a = np.abs(rows[:, 0] / rows[:, 1]) * dts
        assert np.any(a > 1 / 4000) and np.any(a <= 1 / 4000)
    traj = c.run_dt(x0, rows, dts)
    stepped, failed, _ = _stepped(c, x0, rows, dts)
    assert failed is None and np.all(np.isfinite(traj))
    assert traj.dtype == np.float64 and np.array_equal(traj, stepped)
    assert np.array_equal(c.run_dt(x0, rows, np.full(len(rows), 1e-3)), c.run(x0, rows, 1e-3))
    assert c.run_dt(x0, rows[:0], dts[:0]).shape == (0, c.size)


@pytest.mark.parametrize("bad", [0.0, -1e-3, NAN, INF, -INF])
def test_run_dt_refuses_a_bad_step_length_at_its_row(xbs4, bad):
    _, c, c32 = xbs4
    rows, dts = np.tile(SIG, (10, 1)), np.full(10, 1e-3)
    dts[5] = bad
    for obs in (c, c32):
        with pytest.raises(ObserverInputError, match="row 5") as err:
            obs.run_dt(X0, rows, dts)
        assert err.value.code == StepStatus.BAD_DT and f"dt = {bad!r} must be finite and > 0" in str(err.value)
    # the C: xhat holds the state after the 5 good steps, rows 0..4 are written, the rest untouched
    x, traj = np.array(X0, dtype=float), np.full((10, 4), -7.0)
    assert _raw_run_dt(c)(x, np.ascontiguousarray(rows), 10, None, dts, traj) == StepStatus.BAD_DT
    good = c.run(X0, rows[:5], 1e-3)
    assert np.array_equal(traj[:5], good) and np.all(traj[5:] == -7.0) and np.array_equal(x, good[-1])


def test_run_dt_reports_the_first_failing_row_with_the_status_step_reports(xbs4):
    """Bad rows and bad parameters: the row and code of _step row by row (a bad dt makes every row check
    everything again, in _step's order)."""
    _, c, _ = xbs4
    bad_params = c.with_params({"alpha1": NAN})
    rows, dts = np.tile(SIG, (8, 1)), np.linspace(1e-3, 2e-3, 8)
    cases = []
    r = rows.copy()
    r[6, 1] = 0.0  # vx = 0
    cases.append((c, X0, r, dts, 6, StepStatus.UNDEFINED_TIME_SCALE))
    r, d = rows.copy(), dts.copy()
    r[2, 0], d[5] = NAN, NAN
    cases.append((c, X0, r, d, 2, StepStatus.NONFINITE_SIGNAL))
    d = dts.copy()
    d[3] = -1.0
    cases.append((c, (NAN, *X0[1:]), rows, d, 0, StepStatus.NONFINITE_STATE))
    cases.append((bad_params, X0, rows, dts, 0, StepStatus.BAD_PARAM))
    d = dts.copy()
    d[0] = 0.0
    cases.append((bad_params, X0, rows, d, 0, StepStatus.BAD_DT))
    r = rows.copy()
    r[4] = [1e150, 20.0, 1e300]
    d = dts.copy()
    d[4] = 1.0
    cases.append((c, X0, r, d, 4, StepStatus.NONFINITE_RESULT))
    for obs, x0, r, d, row, status in cases:
        _, failed, code = _stepped(obs, x0, r, d)
        assert (failed, code) == (row, status)
        with pytest.raises(ObserverInputError, match=f"row {row}:") as err:
            obs.run_dt(x0, r, d)
        assert err.value.code == status


def test_run_dt_refuses_null_pointers_and_a_dt_that_is_not_one_number_per_row(xbs4):
    _, c, _ = xbs4
    run_dt = _raw_run_dt(c)
    x, rows, dts = np.array(X0, dtype=float), np.tile(SIG, (3, 1)), np.full(3, 1e-3)
    assert run_dt(x, rows, 3, None, None, None) == StepStatus.BAD_ARGUMENT
    assert run_dt(x, None, 3, None, dts, None) == StepStatus.BAD_ARGUMENT
    assert run_dt(None, rows, 3, None, dts, None) == StepStatus.BAD_ARGUMENT
    assert run_dt(x, rows, -1, None, dts, None) == StepStatus.BAD_ARGUMENT
    assert run_dt(x, None, 0, None, None, None) == StepStatus.BAD_ARGUMENT  # as the header says: never NULL
    assert run_dt(x, rows, 0, None, None, None) == 0 and np.array_equal(x, X0)
    assert run_dt(x, rows, 3, None, dts, None) == 0 and np.array_equal(x, c.run(X0, rows, 1e-3)[-1])
    with pytest.raises(DimensionError, match="one step length per row"):
        c.run_dt(X0, rows, dts[:2])
    with pytest.raises(DimensionError, match="one step length per row"):
        c.run_dt(X0, rows, 1e-3)
    with pytest.raises(ObserverInputError, match="BAD_DT") as err:
        c.run_dt(X0, rows, ["fast", "slow", "slow"])
    assert err.value.code == StepStatus.BAD_DT


def test_domain_guards_of_d_and_b_match_the_reference(tmp_path):
    """Division by zero and log of a non-positive number in d(y): NONFINITE_RESULT in C and in Python."""
    path = tmp_path / "dom.toml"
    path.write_text('name = "dom"\nstates = ["z1", "z2"]\nA = [["0", "1"], ["0", "0"]]\nC = ["1", "0"]\n'
                    'd = ["1/(y - 1)", "log(y + 2)"]\nb = ["1/m", "0"]\ntime_scale = "y/(w - 3)"\n'
                    'parameters = ["m"]\nexternal = ["w"]\ninputs = ["u"]\n[values]\nm = "2"\n')
    model = Model.from_toml(path)
    gen = generate_observer(model, ([1.0, 2.0], [3.0, 4.0]))
    assert [(str(g.expr), g.kind, g.status) for g in gen.guards] == [
        ("m", "nonzero", StepStatus.BAD_PARAM), ("w - 3", "nonzero", StepStatus.UNDEFINED_TIME_SCALE),
        ("y - 1", "nonzero", StepStatus.NONFINITE_RESULT), ("y + 2", "positive", StepStatus.NONFINITE_RESULT)]
    c, ref = compile_observer(gen), SwitchedObserver(model, [1.0, 2.0], [3.0, 4.0])
    cases = [([1.0, 5.0, 0.0], StepStatus.NONFINITE_RESULT), ([-2.0, 5.0, 0.0], StepStatus.NONFINITE_RESULT),
             ([-3.0, 5.0, 0.0], StepStatus.NONFINITE_RESULT), ([0.5, 3.0, 0.0], StepStatus.UNDEFINED_TIME_SCALE)]
    for sig, status in cases:
        for obs in (c, ref):
            with pytest.raises(ObserverInputError) as err:
                obs.step([0.1, 0.2], sig, 1e-3)
            assert err.value.code == status
    assert np.allclose(c.step([0.1, 0.2], [0.5, 5.0, 1.0], 1e-3), ref.step([0.1, 0.2], [0.5, 5.0, 1.0], 1e-3),
                       rtol=1e-12, atol=0)
    with pytest.raises(ObserverInputError, match="BAD_PARAM"):
        c.with_params({"m": 0.0}).step([0.1, 0.2], [0.5, 5.0, 1.0], 1e-3)


def test_wrong_shapes_are_dimension_errors(xbs4):
    _, c, _ = xbs4
    with pytest.raises(DimensionError, match=r"expected \(4,\)"):
        c.step([1.0, 2.0], SIG, 1e-3)
    with pytest.raises(DimensionError, match=r"\(y, vx, u\)"):
        c.step(X0, [1.0, 2.0], 1e-3)
    with pytest.raises(DimensionError, match="signal_rows"):
        c.run(X0, [1.0, 2.0, 3.0], 1e-3)
    with pytest.raises(ModelError, match="no parameter 'zeta'"):
        c.with_params({"zeta": 1.0})


# --------------------------------------------------------------------------- generation errors
def test_generation_refuses_bad_requests(tmp_path):
    m = builtin_model("abs-xbs3")
    g = ([1.0, 2.0, 3.0], [4.0, 5.0, 6.0])
    with pytest.raises(CodegenError, match="not a C identifier"):
        generate_observer(m, g, prefix="9lives")
    with pytest.raises(CodegenError, match="C keyword"):
        generate_observer(m, g, prefix="double")
    with pytest.raises(CodegenError, match="real must be"):
        generate_observer(m, g, real="half")
    with pytest.raises(CodegenError, match="method must be"):
        generate_observer(m, g, method="rk45")
    with pytest.raises(DimensionError, match="K_plus has 2 entries"):
        generate_observer(m, ([1.0, 2.0], [4.0, 5.0, 6.0]))
    with pytest.raises(CodegenError, match="not finite"):
        generate_observer(m, ([1.0, NAN, 3.0], [4.0, 5.0, 6.0]))
    with pytest.raises(FreeSymbolError, match="beta1"):
        generate_observer(m, design(m, "-beta1,-2,-3"))
    with pytest.raises(ModelError, match="declared positive"):
        generate_observer(m, g, values={"a": -1})
    with pytest.raises(ModelError, match="neither parameters"):
        generate_observer(m, g, values={"zz": 1})
    with pytest.raises(ModelError, match=r"\['a', 'b', 'c'\] of model 'abs-xbs3' have no value"):
        generate_observer(dataclasses.replace(m, values={}), g)
    t = m.symbols["t"]
    with pytest.raises(CodegenError, match="depends on the time t"):
        generate_observer(dataclasses.replace(m, time_scale=m.time_scale * (1 + t)), g)
    y = m.symbols["y"]
    with pytest.raises(CodegenError, match="cannot generate C for"):
        generate_observer(dataclasses.replace(m, d=sp.ImmutableMatrix([sp.Heaviside(y), 0, 0])), g)
    clash = tmp_path / "clash.toml"
    clash.write_text('name = "clash"\nstates = ["z1"]\nA = [["k + K"]]\nC = ["1"]\ntime_scale = "y"\n'
                     'parameters = ["k", "K"]\n[values]\nk = "1"\nK = "2"\n')
    with pytest.raises(CodegenError, match=r"same C macro name\(s\) \['K'\]"):
        generate_observer(Model.from_toml(clash), ([1.0], [2.0]))


def test_adaptive_generation_refuses_bad_gamma_and_unknowns():
    m = builtin_model("abs-adaptive2")
    g = ([30.0, -1.2], [-30.0, -1.2])
    with pytest.raises(CodegenError, match="needs Gamma"):
        generate_observer(m, g, unknown=["c", "d"])
    with pytest.raises(CodegenError, match="positive definite"):
        generate_observer(m, g, unknown=["c", "d"], Gamma=[[1.0, 2.0], [2.0, 1.0]])
    with pytest.raises(DimensionError, match=r"expected \(2, 2\)"):
        generate_observer(m, g, unknown=["c", "d"], Gamma=[1.0, 2.0, 3.0])
    # The unknowns are checked by the observer contract (switchobs.spec), for Python and C alike.
    with pytest.raises(ModelError, match="no parameter 'q' to estimate"):
        generate_observer(m, g, unknown=["q"], Gamma=[1.0])
    with pytest.raises(ModelError, match=r"\['a'\] appear in A"):
        generate_observer(m, g, unknown=["a"], Gamma=[1.0])
    with pytest.raises(CodegenError, match="only used by the adaptive"):
        generate_observer(m, g, Gamma=[1.0, 1.0])
    with pytest.raises(CodegenError, match="must be a finite number > 0"):
        generate_super_twisting(-1.0, 10.0)


def test_compiler_failure_and_missing_compiler_are_codegen_errors(tmp_path):
    gen = generate_observer(builtin_model("abs-xbs3"), ([1.0, 2.0, 3.0], [4.0, 5.0, 6.0]), prefix="broken_x")
    broken = dataclasses.replace(gen, source=gen.source + "\nthis is not C;\n")
    with pytest.raises(CodegenError, match="failed on the generated broken_x.c"):
        compile_observer(broken, cache_dir=tmp_path)
    with pytest.raises(CodegenError, match="no C compiler found"):
        compile_observer(gen, compiler="no-such-cc-xyz", cache_dir=tmp_path)



def test_host_tuned_library_equals_the_portable_build_and_falls_back_without_march_native(tmp_path, xbs4):
    """HOST_FLAGS change speed, not results; a compiler that refuses them still gets the portable build."""
    from switchobs.codegen._build import HOST_FLAGS, compile_shared, find_compiler

    _, tuned, _ = xbs4
    t = np.arange(400) * 1e-3
    rows = np.column_stack([30 * np.sin(9 * t), 20 - 10 * t, 100 * np.cos(7 * t)])
    want = tuned.run(X0, rows, 1e-3)
    log = tmp_path / "calls"
    refusing = tmp_path / "cc-without-march-native"
    refusing.write_text(f'#!/bin/sh\necho "$@" >> {log}\n'
                        f'for a in "$@"; do [ "$a" = "{HOST_FLAGS[0]}" ] && exit 1; done\n'
                        f'exec {find_compiler()} "$@"\n')
    refusing.chmod(0o755)
    fallback = CObserver(tuned.generated, compiler=str(refusing), cache_dir=tmp_path)
    calls = log.read_text().splitlines()
    assert len(calls) == 2 and HOST_FLAGS[0] in calls[0].split() and HOST_FLAGS[0] not in calls[1].split()
    assert np.array_equal(fallback.run(X0, rows, 1e-3), want)
    portable = ctypes.CDLL(str(compile_shared(tuned.generated, cache_dir=tmp_path, host=False)))
    run = getattr(portable, f"{tuned.generated.prefix}_run")
    run.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int32, ctypes.c_void_p, ctypes.c_double,
                    ctypes.c_void_p]
    x, traj = np.array(X0), np.empty_like(want)
    assert run(x.ctypes.data, rows.ctypes.data, len(rows), tuned.params.ctypes.data, 1e-3, traj.ctypes.data) == 0
    assert np.array_equal(traj, want) and np.array_equal(x, want[-1])


# --------------------------------------------------------------------------- CLI
def test_cli_codegen_writes_the_files_and_json(tmp_path, capsys):
    out = tmp_path / "gen"
    code = main(["codegen", "abs-xbs3", "--spectrum", "-beta1,-beta2,-beta2", "--param", "beta1=40",
                 "--param", "beta2=60", "--real", "float", "--out", str(out), "--json"])
    assert code == 0
    data = json.loads(capsys.readouterr().out)
    assert sorted(p.name for p in out.iterdir()) == ["README.md", "switchobs_abs_xbs3.c", "switchobs_abs_xbs3.h",
                                                     "switchobs_abs_xbs3_misra.md"]
    assert data["real"] == "float" and data["parameters"]["K_plus_z1"] == 194.0
    header = (out / "switchobs_abs_xbs3.h").read_text()
    assert "typedef float switchobs_abs_xbs3_real;" in header
    assert ("int32_t switchobs_abs_xbs3_step(switchobs_abs_xbs3_real *xhat, const switchobs_abs_xbs3_real *signals, "
            "const switchobs_abs_xbs3_real *params, switchobs_abs_xbs3_real dt);") in header
    assert "--spectrum=-beta1,-beta2,-beta2" in header  # the command that regenerates the files
    assert main(["codegen", "abs-adaptive2", "--spectrum", "-15,-15", "--unknown", "c,d", "--gamma", "50,0;0,20",
                 "--prefix", "adapt", "--out", str(tmp_path / "ad")]) == 0
    assert "#define ADAPT_X_UPSILON_W2_D 7" in (tmp_path / "ad" / "adapt.h").read_text()
    assert main(["codegen", "super-twisting", "--param", "lam=400", "--param", "alpha=2000",
                 "--out", str(tmp_path / "st")]) == 0
    assert "SWITCHOBS_SUPER_TWISTING_P_ALPHA 1" in (tmp_path / "st" / "switchobs_super_twisting.h").read_text()
    assert main(["codegen", "vehicle-speed", "--param", "beta=24", "--out", str(tmp_path / "vs")]) == 0
    assert "#define SWITCHOBS_VEHICLE_SPEED_X_Z3 1" in (tmp_path / "vs" / "switchobs_vehicle_speed.h").read_text()
    assert "The gain `beta` of M'Sirdi et al. 2008 eq. (15)" in (tmp_path / "vs" / "README.md").read_text()


@pytest.mark.parametrize("argv, message", [
    (["abs-xbs3"], "give the gains with --spectrum"),
    (["abs-xbs3", "--spectrum", "-beta1,-2,-3"], "beta1"),
    (["abs-xbs3", "--spectrum", "-1,-2,-3", "--prefix", "1x"], "not a C identifier"),
    (["abs-xbs3", "--spectrum", "-1,-2,-3", "--param", "a=-2"], "declared positive"),
    (["abs-xbs3", "--spectrum", "-1,-2,-3", "--gamma", "1"], "give --unknown too"),
    (["abs-adaptive2", "--spectrum", "-1,-1", "--unknown", "c,d", "--gamma", "x"], "--gamma expects numbers"),
    (["super-twisting", "--param", "lam=1"], "missing ['alpha']"),
    (["super-twisting", "--param", "lam=1", "--param", "alpha=2", "--method", "rk4"], "Euler scheme"),
    (["vehicle-speed", "--param", "lam=1"], "takes --param beta=... (M'Sirdi et al. 2008 (15), Theorem 3: beta > eta); "
                                            "missing ['beta'], unexpected ['lam']"),
    (["vehicle-speed", "--param", "beta=-3"], "beta = -3.0 must be a finite number > 0"),
    (["vehicle-speed", "--param", "beta=3", "--h-max", "0.1"], "no rescaled-time certificate"),
    (["nope-model", "--spectrum", "-1"], "unknown model 'nope-model'"),
])
def test_cli_codegen_errors_are_one_line_exit_2(tmp_path, capsys, argv, message):
    assert main(["codegen", *argv, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("switchobs codegen: error: ") and message in err and err.count("\n") == 1


def _raw_run(c: CObserver):
    lib = ctypes.CDLL(str(c.library_path))
    fn = getattr(lib, f"{c.generated.prefix}_run")
    fn.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int32, ctypes.c_void_p, ctypes.c_double,
                   ctypes.c_void_p]
    fn.restype = ctypes.c_int32
    return lambda *args: fn(*(a.ctypes.data if isinstance(a, np.ndarray) else a for a in args))


def test_a_run_of_zero_steps_checks_what_the_header_promises(xbs4):
    """The header: xhat and signals are never NULL, and n_steps = 0 checks dt, then xhat (issue 25)."""
    _, c, _ = xbs4
    run = _raw_run(c)
    x, rows = np.array(X0, dtype=float), np.tile(SIG, (2, 1))
    assert run(x, None, 0, None, 1e-3, None) == StepStatus.BAD_ARGUMENT
    assert run(None, rows, 0, None, 1e-3, None) == StepStatus.BAD_ARGUMENT
    assert run(x, rows, 0, None, NAN, None) == StepStatus.BAD_DT
    assert run(x, rows, 0, None, -1.0, None) == StepStatus.BAD_DT
    bad = np.array([NAN, 0.0, 0.0, 0.0])
    assert run(bad, rows, 0, None, 1e-3, None) == StepStatus.NONFINITE_STATE
    assert _raw_run_dt(c)(bad, rows, 0, None, None, None) == StepStatus.NONFINITE_STATE
    assert run(x, rows, 0, None, 1e-3, None) == 0 and np.array_equal(x, X0)
    header = c.generated.files[f"{c.generated.prefix}.h"]
    assert "n_steps = 0" in header and "BAD_DT" in header and "NONFINITE_STATE" in header
    # the binding says the same, with and without rows
    for rows_given in (rows[:0], rows):
        with pytest.raises(ObserverInputError) as err:
            c.run(bad, rows_given, 1e-3)
        assert err.value.code == StepStatus.NONFINITE_STATE
    with pytest.raises(ObserverInputError) as err:
        c.run_dt(bad, rows[:0], [])
    assert err.value.code == StepStatus.NONFINITE_STATE
