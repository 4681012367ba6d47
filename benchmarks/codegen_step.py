"""Cost of one observer step: generated C against casadi's generated C, hand-written C and numba.

For abs-xbs3 and abs-xbs4 (seed 000), double and float:

* in C (``gcc -O2``, called across translation units, CPU time of 300 000 steps, median [min–max] of
  41 runs): ns per checked RK4 step of the generated ``<prefix>_step``, of casadi's own generated C for
  the same step (``Function.generate``, double only, no checks), of a tuned hand-written step (straight-line
  scalar code, the same checks) and of a natural hand-written one (arrays and a right-hand-side function,
  the same checks); code size (``size``) and stack (``-fstack-usage``);
* from Python (CPU time, median [min–max] of 5 runs of 100 000 rows, 20 alternated runs for ``CObserver.run``
  and numba): ns per step of ``CObserver.run``
  (the generated ``_run`` through ctypes, in the library ``CObserver`` builds: ``-O2`` plus ``HOST_FLAGS``,
  the host's instruction set like numba's JIT) against a numba ``njit`` loop of the same checked step, and
  batch against batch the Python reference ``run``; µs per single call of the casadi ``Function``, the
  Python reference ``step`` and the C step through ctypes.

numba is a benchmark-only extra (``pip install -e .[bench]``, done by ``make bench``); without it the numba
column says so.  Run: ``.venv/bin/python benchmarks/codegen_step.py [--quick]``.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import tempfile
from pathlib import Path

import casadi as ca
import numpy as np
from _harness import MIN_REPEATS, Stats, cpu, publish, ratio

from switchobs.codegen import CObserver
from switchobs.codegen._build import BUILD_FLAGS, HOST_FLAGS
from switchobs.observers import xbs3_observer, xbs4_observer

try:
    import numba
except ImportError:  # a benchmark-only extra: the table says that it is missing
    numba = None

STEPS = 300_000
RUN_ROWS = 100_000
#: C ``_run`` against numba: this many times ``--repeats`` runs each, alternated (each run takes milliseconds).
PAIR_RUNS = 4
CFLAGS = ["-std=c99", "-O2"]

# The checks of the generated step (status codes of the C API), shared by both hand-written steps.
CHECKS = r"""
    if (x == NULL || sig == NULL) return 7;
    if (!(dt > 0) || !isfinite(dt)) return 1;
    for (i = 0; i < N; ++i) if (!isfinite(x[i])) return 2;
    for (i = 0; i < 3; ++i) if (!isfinite(sig[i])) return 3;
    for (i = 0; i < NP; ++i) if (!isfinite(p[i])) return 6;
    if (!(p[0] > 0) || !(p[1] < 0)) return 6;
    if (!(sig[1] > 0)) return 4;
    y = sig[0];
    s = y / sig[1];
    if (!isfinite(s)) return 4;"""

# The same RK4 step written by hand (same parameter layout and checks as the generated code).
HAND = r"""
#include <math.h>
#include <stddef.h>
#include <stdint.h>
typedef REAL real;

/* The right-hand side on scalars, so that the whole step is straight-line code in registers. */
#if N == 3  /* abs-xbs3, seed 000 eq. (8): params a, b, c, K_plus (3), K_minus (3) */
#define NP 9
#define RHS(k, z) \
    e = y - z##0; \
    k##0 = s * (-(a * z##1)) + bu + g0 * e; \
    k##1 = s * (c * z##1 + z##2) + g1 * e; \
    k##2 = g2 * e;
#define LOAD const real a = p[0], c = p[2];
#define FOR_N(X) X(0) X(1) X(2)
#else       /* abs-xbs4, seed 000 eq. (20): params a, b, alpha1, alpha2, K_plus (4), K_minus (4) */
#define NP 12
#define RHS(k, z) \
    e = y - z##0; \
    k##0 = s * (-(a * z##1)) + bu + g0 * e; \
    k##1 = s * z##2 + g1 * e; \
    k##2 = s * (al1 * z##1 + al2 * z##2 + z##3) + g2 * e; \
    k##3 = g3 * e;
#define LOAD const real a = p[0], al1 = p[2], al2 = p[3];
#define FOR_N(X) X(0) X(1) X(2) X(3)
#endif

int32_t NAME(real *x, const real *sig, const real *p, real dt)
{
    real s, y, bu, h, dt6, e, g0, g1, g2, g3;
    real x0, x1, x2, x3, t0, t1, t2, t3, a0, a1, a2, a3, b0, b1, b2, b3, c0, c1, c2, c3, d0, d1, d2, d3;
    int i;
    LOAD
@CHECKS@
    x3 = t3 = a3 = b3 = c3 = d3 = g3 = 0;
#define GAIN(i) g##i = s > 0 ? s * p[NP - 2 * N + i] : s * p[NP - N + i];
#define LOADX(i) x##i = x[i];
    FOR_N(GAIN) FOR_N(LOADX)
    bu = sig[2] * p[1];
    h = (real)0.5 * dt;
    dt6 = dt / (real)6;
#define STAGE(i, k, step) t##i = x##i + step * k##i;
#define ST_A(i) STAGE(i, a, h)
#define ST_B(i) STAGE(i, b, h)
#define ST_C(i) STAGE(i, c, dt)
#define NEW(i) t##i = x##i + dt6 * (a##i + (real)2 * b##i + (real)2 * c##i + d##i);
#define BAD(i) if (!isfinite(t##i)) return 5;
#define STORE(i) x[i] = t##i;
    RHS(a, x) FOR_N(ST_A)
    RHS(b, t) FOR_N(ST_B)
    RHS(c, t) FOR_N(ST_C)
    RHS(d, t) FOR_N(NEW)
    FOR_N(BAD) FOR_N(STORE)
    return 0;
}
"""

# The same step as a person writes it first: arrays, a right-hand-side function, loops (same checks).
NATURAL = r"""
#include <math.h>
#include <stddef.h>
#include <stdint.h>
typedef REAL real;
#if N == 3
#define NP 9
#else
#define NP 12
#endif

static void rhs(const real *z, real s, real y, real bu, const real *g, const real *p, real *k)
{
    real e = y - z[0];
#if N == 3  /* abs-xbs3, seed 000 eq. (8) */
    k[0] = s * (-(p[0] * z[1])) + bu + g[0] * e;
    k[1] = s * (p[2] * z[1] + z[2]) + g[1] * e;
    k[2] = g[2] * e;
#else       /* abs-xbs4, seed 000 eq. (20) */
    k[0] = s * (-(p[0] * z[1])) + bu + g[0] * e;
    k[1] = s * z[2] + g[1] * e;
    k[2] = s * (p[2] * z[1] + p[3] * z[2] + z[3]) + g[2] * e;
    k[3] = g[3] * e;
#endif
}

int32_t NAME(real *x, const real *sig, const real *p, real dt)
{
    real s, y, bu, g[N], k1[N], k2[N], k3[N], k4[N], t[N];
    int i;
@CHECKS@
    for (i = 0; i < N; ++i) g[i] = s > 0 ? s * p[NP - 2 * N + i] : s * p[NP - N + i];
    bu = sig[2] * p[1];
    rhs(x, s, y, bu, g, p, k1);
    for (i = 0; i < N; ++i) t[i] = x[i] + dt / 2 * k1[i];
    rhs(t, s, y, bu, g, p, k2);
    for (i = 0; i < N; ++i) t[i] = x[i] + dt / 2 * k2[i];
    rhs(t, s, y, bu, g, p, k3);
    for (i = 0; i < N; ++i) t[i] = x[i] + dt * k3[i];
    rhs(t, s, y, bu, g, p, k4);
    for (i = 0; i < N; ++i) t[i] = x[i] + dt / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
    for (i = 0; i < N; ++i) if (!isfinite(t[i])) return 5;
    for (i = 0; i < N; ++i) x[i] = t[i];
    return 0;
}
"""

DRIVER = r"""
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <time.h>
#include "@P@.h"
typedef @REAL@ real;
int32_t hand_@M@(real *x, const real *sig, const real *p, real dt);
int32_t natural_@M@(real *x, const real *sig, const real *p, real dt);
#if @CASADI@
#include "casadi_@M@.h"
static int32_t casadi_wrap(real *x, const real *sig, const real *p, real dt)
{   /* casadi's calling convention: argument and result pointers, a work vector; no checks */
    static casadi_real w[@CASADI_W@], next[@PU@_NX];
    const casadi_real *arg[4];
    casadi_real *res[1];
    int i;
    arg[0] = x; arg[1] = sig; arg[2] = p; arg[3] = &dt; res[0] = next;
    if (casadi_@M@(arg, res, NULL, w, 0) != 0) return 1;
    for (i = 0; i < @PU@_NX; ++i) x[i] = next[i];
    return 0;
}
#endif
#define ROWS 4096
#define REPEATS 41
static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}
typedef int32_t (*stepper)(real *, const real *, const real *, real);
static double bench(stepper f, const real *rows, long steps, long *failures)
{
    real x[@PU@_NX];
    long k;
    int i;
    double t0 = now();
    for (k = 0; k < steps; ++k) {
        if ((k & (ROWS - 1)) == 0) for (i = 0; i < @PU@_NX; ++i) x[i] = (real)(0.1 * (i + 1));
        if (f(x, rows + (k & (ROWS - 1)) * 3, @P@_default_params, (real)1e-3) != 0) ++*failures;
    }
    return (now() - t0) / (double)steps * 1e9;
}
int main(void)
{
    static real rows[3 * ROWS];
    stepper fns[4];
    const char *names[4] = {"generated", "hand", "natural", "casadi"};
    long r, failures = 0;
    int f, nf = @CASADI@ ? 4 : 3;
    fns[0] = @P@_step; fns[1] = hand_@M@; fns[2] = natural_@M@;
#if @CASADI@
    fns[3] = casadi_wrap;
#endif
    for (r = 0; r < ROWS; ++r) {
        rows[3 * r] = (real)(10.0 * sin(0.01 * (double)r));
        rows[3 * r + 1] = (real)(20.0 - 2e-3 * (double)r);
        rows[3 * r + 2] = (real)(100.0 * cos(0.013 * (double)r));
    }
    for (r = 0; r < REPEATS; ++r)   /* interleaved, so that all see the same machine load */
        for (f = 0; f < nf; ++f) printf("%s %.4f\n", names[f], bench(fns[f], rows, @STEPS@, &failures));
    printf("failures %ld\n", failures);
    return 0;
}
"""


def _run(cmd: list[str], cwd: Path) -> str:
    return subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, check=True).stdout


def casadi_source(obs: CObserver, model: str, d: Path) -> int:
    """casadi's own C for the same step (renamed ``casadi_<model>``); returns its work-vector size."""
    f = obs.generated.step_function
    args = f.sx_in()
    g = ca.Function(f"casadi_{model}", args, f.call(args))
    g.generate(f"casadi_{model}.c", {"with_header": True})
    for name in (f"casadi_{model}.c", f"casadi_{model}.h"):
        Path(name).replace(d / name)
    return max(int(g.sz_w()), 1)


def c_timings(obs: CObserver, model: str, tmp: Path) -> dict:
    gen = obs.generated
    d = tmp / f"{gen.prefix}-{gen.real}"
    gen.write(d)
    use_casadi = gen.real == "double"  # casadi_real is double
    work = casadi_source(obs, model, d) if use_casadi else 1
    (d / "hand.c").write_text(HAND.replace("@CHECKS@", CHECKS))
    (d / "natural.c").write_text(NATURAL.replace("@CHECKS@", CHECKS))
    (d / "driver.c").write_text(DRIVER.replace("@P@", gen.prefix).replace("@PU@", gen.prefix.upper())
                                .replace("@REAL@", gen.real).replace("@M@", model).replace("@STEPS@", str(STEPS))
                                .replace("@CASADI@", str(int(use_casadi))).replace("@CASADI_W@", str(work)))
    defs = [f"-DREAL={gen.real}", f"-DN={gen.nx}"]
    _run(["gcc", *CFLAGS, "-fstack-usage", "-c", f"{gen.prefix}.c"], d)
    _run(["gcc", *CFLAGS, *defs, f"-DNAME=hand_{model}", "-fstack-usage", "-c", "hand.c"], d)
    _run(["gcc", *CFLAGS, *defs, f"-DNAME=natural_{model}", "-c", "natural.c"], d)
    objs = ["driver.o", f"{gen.prefix}.o", "hand.o", "natural.o"]
    if use_casadi:
        _run(["gcc", *CFLAGS, "-c", f"casadi_{model}.c"], d)
        objs.append(f"casadi_{model}.o")
    _run(["gcc", *CFLAGS, "-c", "driver.c"], d)
    _run(["gcc", "-o", "bench", *objs, "-lm"], d)
    out = _run(["./bench"], d)
    runs: dict[str, list[float]] = {}
    for name, value in re.findall(r"^(\w+) (\S+)$", out, re.M):
        runs.setdefault(name, []).append(float(value))
    failures = int(runs.pop("failures")[0])
    sizes = {obj: int(_run(["size", obj], d).splitlines()[1].split()[0]) for obj in (f"{gen.prefix}.o", "hand.o")}
    frames = {}
    for su in (f"{gen.prefix}.su", "hand.su"):
        for line in (d / su).read_text().splitlines():
            where, size, _ = line.split("\t")
            frames[where.rsplit(":", 1)[1]] = int(size)
    p = gen.prefix
    # the chain of one _step call, with the parts gcc splits off (``<name>.part.0``) and not inlined
    chain = {f"{p}_step", f"{p}_rows", f"{p}_advance", f"{p}_kernel"}
    stack_gen = sum(size for name, size in frames.items() if name.split(".")[0] in chain)
    return {**{k: Stats(tuple(v)) for k, v in runs.items()}, "failures": failures,
            "gen_size": sizes[f"{gen.prefix}.o"], "hand_size": sizes["hand.o"],
            "gen_stack": stack_gen, "hand_stack": frames[f"hand_{model}"]}


def numba_loop(n: int):
    """A numba ``njit`` loop of the same checked RK4 step in scalar code (the right-hand sides of HAND), or None."""
    if numba is None:
        return None
    xbs3 = n == 3

    @numba.njit(inline="always")
    def rhs(z0, z1, z2, z3, s, y, bu, g0, g1, g2, g3, p):  # noqa: ANN001, ANN202 - numba
        e = y - z0
        if xbs3:  # seed 000 eq. (8)
            return s * (-(p[0] * z1)) + bu + g0 * e, s * (p[2] * z1 + z2) + g1 * e, g2 * e, 0.0
        return (s * (-(p[0] * z1)) + bu + g0 * e, s * z2 + g1 * e,  # seed 000 eq. (20)
                s * (p[2] * z1 + p[3] * z2 + z3) + g2 * e, g3 * e)

    @numba.njit
    def run(x0, rows, p, dt, traj):  # noqa: ANN001, ANN202 - numba
        x_0, x_1, x_2 = x0[0], x0[1], x0[2]
        x_3 = 0.0 if xbs3 else x0[3]
        np_ = p.shape[0]
        h = 0.5 * dt
        for k in range(rows.shape[0]):
            if not (dt > 0.0) or not np.isfinite(dt):
                return 1
            if not (np.isfinite(x_0) and np.isfinite(x_1) and np.isfinite(x_2) and np.isfinite(x_3)):
                return 2
            y, v, u = rows[k, 0], rows[k, 1], rows[k, 2]
            if not (np.isfinite(y) and np.isfinite(v) and np.isfinite(u)):
                return 3
            for i in range(np_):
                if not np.isfinite(p[i]):
                    return 6
            if not (p[0] > 0.0) or not (p[1] < 0.0):
                return 6
            if not (v > 0.0):
                return 4
            s = y / v
            if not np.isfinite(s):
                return 4
            o = np_ - 2 * n if s > 0.0 else np_ - n
            g0, g1, g2 = s * p[o], s * p[o + 1], s * p[o + 2]
            g3 = 0.0 if xbs3 else s * p[o + 3]
            bu = u * p[1]
            a0, a1, a2, a3 = rhs(x_0, x_1, x_2, x_3, s, y, bu, g0, g1, g2, g3, p)
            b0, b1, b2, b3 = rhs(x_0 + h * a0, x_1 + h * a1, x_2 + h * a2, x_3 + h * a3, s, y, bu, g0, g1, g2, g3, p)
            c0, c1, c2, c3 = rhs(x_0 + h * b0, x_1 + h * b1, x_2 + h * b2, x_3 + h * b3, s, y, bu, g0, g1, g2, g3, p)
            d0, d1, d2, d3 = rhs(x_0 + dt * c0, x_1 + dt * c1, x_2 + dt * c2, x_3 + dt * c3, s, y, bu,
                                 g0, g1, g2, g3, p)
            dt6 = dt / 6.0
            x_0 += dt6 * (a0 + 2.0 * b0 + 2.0 * c0 + d0)
            x_1 += dt6 * (a1 + 2.0 * b1 + 2.0 * c1 + d1)
            x_2 += dt6 * (a2 + 2.0 * b2 + 2.0 * c2 + d2)
            x_3 += dt6 * (a3 + 2.0 * b3 + 2.0 * c3 + d3)
            if not (np.isfinite(x_0) and np.isfinite(x_1) and np.isfinite(x_2) and np.isfinite(x_3)):
                return 5
            traj[k, 0], traj[k, 1], traj[k, 2] = x_0, x_1, x_2
            if not xbs3:
                traj[k, 3] = x_3
        return 0

    return run


def per_call(fn, number: int, repeats: int) -> Stats:
    return cpu(lambda: [fn() for _ in range(number)], repeats).scaled(1 / number)


def python_timings(ref, obs: CObserver, repeats: int, rows_n: int) -> dict:
    x = np.array([0.1, 0.2, 0.3, 0.4][:ref.size])
    sig = (5.0, 20.0, 100.0)
    fn = obs.generated.step_function
    par = np.array(obs.params, dtype=float)
    t = np.arange(rows_n) * 1e-3
    rows = np.column_stack([10 * np.sin(9 * t), np.full_like(t, 20.0), 100 * np.cos(7 * t)])
    small = rows[:5000]
    out = {"casadi_call": per_call(lambda: fn(x, sig, par, 1e-3), 500, repeats),
           "py_step": per_call(lambda: ref.step(x, sig, 1e-3), 2000, repeats),
           "c_step": per_call(lambda: obs.step(x, sig, 1e-3), 2000, repeats),
           "py_run": cpu(lambda: ref.run(x, small, 1e-3), repeats).scaled(1 / small.shape[0])}
    runs = {"c_run": lambda: obs.run(x, rows, 1e-3)}
    loop = numba_loop(ref.size) if obs.real == "double" else None
    if loop is not None:
        traj = np.empty((rows_n, ref.size))
        if loop(x, rows, par, 1e-3, traj) != 0:  # also compiles it, outside the timing
            raise SystemExit("the numba loop refused a step")
        if not np.allclose(traj, obs.run(x, rows, 1e-3), rtol=1e-9, atol=1e-9):
            raise SystemExit("the numba loop does not compute the generated step")
        runs["numba_run"] = lambda: loop(x, rows, par, 1e-3, traj)
    times: dict[str, list[float]] = {name: [] for name in runs}
    for _ in range(PAIR_RUNS * repeats):  # alternated, so that both see the same machine load
        for name, run in runs.items():
            times[name] += cpu(run, 1).values
    out.update({name: Stats(tuple(v)).scaled(1 / rows_n) for name, v in times.items()})
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="smoke run: abs-xbs4 only, 20 000 rows from Python"
                             "; printed, not written to benchmarks/results")
    parser.add_argument("--repeats", type=int, default=MIN_REPEATS)
    args = parser.parse_args()
    refs = {"xbs4": xbs4_observer(10.0, 20.0)}
    if not args.quick:
        refs = {"xbs3": xbs3_observer(40.0, 60.0), **refs}
    rows_n = 20_000 if args.quick else RUN_ROWS
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        for model, ref in refs.items():
            for real in ("double", "float"):
                obs = CObserver.like(ref, real=real)
                results.append((f"abs-{model}", real, c_timings(obs, model, Path(tmp)),
                                python_timings(ref, obs, args.repeats, rows_n)))
    c_table = ["| model | real | generated C ns | casadi's generated C ns | tuned hand C ns | natural hand C ns "
               "| generated vs casadi | vs tuned | vs natural | gen. size B | hand size B | gen. stack B "
               "| hand stack B |",
               "| --- | --- | ---: | ---: | ---: | ---: | --- | --- | --- | ---: | ---: | ---: | ---: |"]
    py_table = ["| model | real | C `_run` via `CObserver.run` ns/step | numba `njit` loop ns/step | `_run` vs numba "
                "| Python reference `run` ns/step | `_run` vs Python `run` | casadi `Function` call µs "
                "| Python `step` µs | C step via ctypes µs |",
                "| --- | --- | ---: | ---: | --- | ---: | --- | ---: | ---: | ---: |"]
    for model, real, c, p in results:
        gen = c["generated"]
        cas = c.get("casadi")
        c_table.append(
            f"| {model} | {real} | {gen.show()} | {cas.show() if cas else '–'} | {c['hand'].show()} | "
            f"{c['natural'].show()} | {ratio(gen.median, cas.median) if cas else '–'} | "
            f"{ratio(gen.median, c['hand'].median)} | {ratio(gen.median, c['natural'].median)} | "
            f"{c['gen_size']} | {c['hand_size']} | {c['gen_stack']} | {c['hand_stack']} |")
        nb = p.get("numba_run")
        nb_s = nb.show(1e9) if nb else ("numba not installed" if numba is None else "– (double only)")
        py_table.append(
            f"| {model} | {real} | {p['c_run'].show(1e9)} | {nb_s} | "
            f"{ratio(p['c_run'].median, nb.median) if nb else '–'} | {p['py_run'].show(1e9)} | "
            f"{ratio(p['c_run'].median, p['py_run'].median)} | {p['casadi_call'].show(1e6)} | "
            f"{p['py_step'].show(1e6)} | {p['c_step'].show(1e6)} |")
    notes = []
    bad = sum(c["failures"] for _, _, c, _ in results)
    if bad:
        notes.append(f"Warning: {bad} benchmark steps were refused (state reset every 4096 steps).")
    publish("codegen_step",
            f"C: ns per RK4 step, `gcc {' '.join(CFLAGS)}`, CPU time of {STEPS} steps, median [min–max] of 41 "
            "interleaved runs; *generated* is `<prefix>_step` with all its checks, *casadi's generated C* is "
            "`Function.generate` of the same step (no checks, double only), *tuned hand C* is straight-line "
            "scalar code with the same checks, *natural hand C* the same step written with arrays and a "
            "right-hand-side function; *gen. stack*: the frames of `_step`, `_rows`, `_advance` and the kernel "
            "(those not inlined). From Python: CPU time per step (`time.process_time`), median [min–max] "
            f"of {args.repeats} runs of {rows_n} rows, in the library `CObserver` builds (`gcc {' '.join(BUILD_FLAGS)} "
            f"{' '.join(HOST_FLAGS)}`); C `_run` and the numba loop alternated, {PAIR_RUNS * args.repeats} runs "
            "each; the numba loop is the same checked step "
            f"(numba {numba.__version__ if numba else 'not installed'}), compiled before timing; "
            "*vs*: how the generated code compares (faster or slower).",
            [c_table, py_table], notes, write=not args.quick)


if __name__ == "__main__":
    main()
