"""Cost of one observer step: generated C vs hand-written C vs casadi from Python vs the Python reference.

For abs-xbs3 and abs-xbs4 (seed 000), double and float, prints

* ns per checked RK4 step (``<prefix>_step``, -O2) of the generated C and of a
  hand-written C implementation of the same step with the same checks (both
  called across translation units, best of 41 runs of 300 000 steps);
* code size (``size`` of the object file) and the stack of ``_step``
  (``-fstack-usage``, ``_step`` + ``_advance`` + kernel frames);
* µs per call of the same step as a casadi ``Function`` from Python, of the
  Python reference observer's ``step`` and ``run``, and ns per step of the
  C ``_run`` driven from Python through ctypes (100 000 rows), with the ratio
  to the pure-Python per-step reference.

Goals (issue 6): generated C within 1.1x of hand-written, < 60 ns per RK4 step
for abs-xbs4, ``_run`` from Python >= 500x faster per step than pure Python.
Run: ``.venv/bin/python benchmarks/codegen_step.py``.
"""

from __future__ import annotations

import re
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from switchobs.codegen import CObserver
from switchobs.observers import xbs3_observer, xbs4_observer

STEPS = 300_000
RUN_ROWS = 100_000
CFLAGS = ["-std=c99", "-O2"]

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
    if (x == NULL || sig == NULL) return 7;
    if (!(dt > 0) || !isfinite(dt)) return 1;
    for (i = 0; i < N; ++i) if (!isfinite(x[i])) return 2;
    for (i = 0; i < 3; ++i) if (!isfinite(sig[i])) return 3;
    for (i = 0; i < NP; ++i) if (!isfinite(p[i])) return 6;
    if (!(p[0] > 0) || !(p[1] < 0)) return 6;
    if (!(sig[1] > 0)) return 4;
    y = sig[0];
    s = y / sig[1];
    if (!isfinite(s)) return 4;
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

DRIVER = r"""
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <time.h>
#include "@P@.h"
typedef @REAL@ real;
int32_t hand_@M@(real *x, const real *sig, const real *p, real dt);
#define ROWS 4096
#define REPEATS 41  /* the best of many short runs: robust to the other processes of a shared machine */
static double now(void) { struct timespec t; clock_gettime(CLOCK_MONOTONIC, &t); return t.tv_sec + 1e-9 * t.tv_nsec; }
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
    long r, fail_gen = 0, fail_hand = 0;
    double best_gen = 1e30, best_hand = 1e30, t;
    for (r = 0; r < ROWS; ++r) {
        rows[3 * r] = (real)(10.0 * sin(0.01 * (double)r));
        rows[3 * r + 1] = (real)(20.0 - 2e-3 * (double)r);
        rows[3 * r + 2] = (real)(100.0 * cos(0.013 * (double)r));
    }
    for (r = 0; r < REPEATS; ++r) {   /* alternate, so that both see the same machine load */
        t = bench(@P@_step, rows, @STEPS@, &fail_gen); if (t < best_gen) best_gen = t;
        t = bench(hand_@M@, rows, @STEPS@, &fail_hand); if (t < best_hand) best_hand = t;
    }
    printf("generated %.3f hand %.3f failures %ld %ld\n", best_gen, best_hand, fail_gen, fail_hand);
    return 0;
}
"""


def _run(cmd: list[str], cwd: Path) -> str:
    return subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, check=True).stdout


def c_timings(obs: CObserver, model: str, tmp: Path) -> dict[str, float]:
    gen = obs.generated
    d = tmp / f"{gen.prefix}-{gen.real}"
    gen.write(d)
    (d / "hand.c").write_text(HAND)
    (d / "driver.c").write_text(DRIVER.replace("@P@", gen.prefix).replace("@PU@", gen.prefix.upper())
                                .replace("@REAL@", gen.real).replace("@M@", model).replace("@STEPS@", str(STEPS)))
    hand = [f"-DREAL={gen.real}", f"-DN={gen.nx}", f"-DNAME=hand_{model}"]
    _run(["gcc", *CFLAGS, "-fstack-usage", "-c", f"{gen.prefix}.c"], d)
    _run(["gcc", *CFLAGS, *hand, "-fstack-usage", "-c", "hand.c"], d)
    _run(["gcc", *CFLAGS, "-c", "driver.c"], d)
    _run(["gcc", "-o", "bench", "driver.o", f"{gen.prefix}.o", "hand.o", "-lm"], d)
    out = _run(["./bench"], d)
    g, h, fg, fh = re.match(r"generated (\S+) hand (\S+) failures (\d+) (\d+)", out).groups()
    sizes = {}
    for obj in (f"{gen.prefix}.o", "hand.o"):
        sizes[obj] = int(_run(["size", obj], d).splitlines()[1].split()[0])
    frames = {}
    for su in (f"{gen.prefix}.su", "hand.su"):
        for line in (d / su).read_text().splitlines():
            where, size, _ = line.split("\t")
            frames[where.rsplit(":", 1)[1]] = int(size)
    p = gen.prefix
    stack_gen = frames[f"{p}_step"] + frames.get(f"{p}_advance", 0) + frames.get(f"{p}_kernel", 0)
    return {"gen_ns": float(g), "hand_ns": float(h), "failures": int(fg) + int(fh),
            "gen_size": sizes[f"{gen.prefix}.o"], "hand_size": sizes["hand.o"],
            "gen_stack": stack_gen, "hand_stack": frames[f"hand_{model}"]}


def per_call(fn, number: int) -> float:
    best = float("inf")
    for _ in range(5):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        best = min(best, (time.perf_counter() - t0) / number)
    return best


def python_timings(ref, obs: CObserver) -> dict[str, float]:
    x = np.array([0.1, 0.2, 0.3, 0.4][:ref.size])
    sig = (5.0, 20.0, 100.0)
    fn = obs.generated.step_function
    par = np.array(obs.params, dtype=float)
    t = np.arange(RUN_ROWS) * 1e-3
    rows = np.column_stack([10 * np.sin(9 * t), np.full_like(t, 20.0), 100 * np.cos(7 * t)])
    small = rows[:5000]
    py_run = per_call(lambda: ref.run(x, small, 1e-3), 1) / small.shape[0]
    c_run = per_call(lambda: obs.run(x, rows, 1e-3), 1) / RUN_ROWS
    py_step = per_call(lambda: ref.step(x, sig, 1e-3), 5000)
    return {"casadi_us": per_call(lambda: fn(x, sig, par, 1e-3), 2000) * 1e6, "py_step_us": py_step * 1e6,
            "py_run_us": py_run * 1e6, "c_step_us": per_call(lambda: obs.step(x, sig, 1e-3), 5000) * 1e6,
            "c_run_ns": c_run * 1e9, "ratio": py_step / c_run}


def main() -> None:
    refs = {"xbs3": xbs3_observer(40.0, 60.0), "xbs4": xbs4_observer(10.0, 20.0)}
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for model, ref in refs.items():
            for real in ("double", "float"):
                obs = CObserver.like(ref, real=real)
                rows.append((f"abs-{model}", real, c_timings(obs, model, Path(tmp)), python_timings(ref, obs)))
    print("C step, -O2 (ns per checked RK4 step, best of 41 x 3e5 steps); code size (bytes of text); stack of _step")
    print(f"| model | real | generated C ns | hand-written C ns | ratio | gen. size | hand size | gen. stack B "
          f"| hand stack B |")
    print("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for model, real, c, _ in rows:
        print(f"| {model} | {real} | {c['gen_ns']:.1f} | {c['hand_ns']:.1f} | {c['gen_ns'] / c['hand_ns']:.2f} "
              f"| {c['gen_size']} | {c['hand_size']} | {c['gen_stack']} | {c['hand_stack']} |")
    print()
    print("From Python (per step): casadi Function call, Python reference step / run, C step via ctypes, C _run")
    print("| model | real | casadi Function µs | Python step µs | Python run µs | C step (ctypes) µs "
          "| C _run ns | Python step / C _run |")
    print("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    for model, real, _, p in rows:
        print(f"| {model} | {real} | {p['casadi_us']:.1f} | {p['py_step_us']:.2f} | {p['py_run_us']:.2f} "
              f"| {p['c_step_us']:.2f} | {p['c_run_ns']:.1f} | {p['ratio']:.0f}x |")
    bad = sum(c["failures"] for _, _, c, _ in rows)
    if bad:
        print(f"warning: {bad} benchmark steps were refused (state reset every 4096 steps)")


if __name__ == "__main__":
    main()
