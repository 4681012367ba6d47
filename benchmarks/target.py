"""The generated step on its targets: text, data and stack bytes, and instructions per step on the emulator.

Per model (abs-xbs3 and abs-xbs4 with radau3, abs-adaptive2 with rk4, whose observer is not affine in its
state) and target (Cortex-M4F in float, Cortex-M7 in double and float), the observer of the tests (seed 000
and 001 gains) built with the target's flags (``switchobs.codegen.TARGETS``): ``arm-none-eabi-size`` of the
object, the worst-case stack of a ``_step`` call (``-fstack-usage`` and the call graph), and the
instructions of one ``_step`` call counted on ``qemu-system-arm -icount shift=0`` (``mps2-an386`` /
``mps2-an500``) over the braking record of the processor-in-the-loop test (``switchobs.loop.braking_record``:
1510 steps, a road change, a sensor dropout), minus the same loop through an empty function.  Against a
tuned hand-written float radau3 step of abs-xbs3 (:data:`HAND`: straight-line scalar code, the structural
zeros of ``Z = dt J`` exploited, cofactors, the same checks and status codes), built and counted the same way
in the same harness; and, to show why the Cortex-M4F refuses double, the generated double step there
(software floating point).

Instruction counts are exact and the same on every run (qemu counts, it does not time), so there is one run
of each, not a median; ``--quick`` counts over the first 300 rows of the record and publishes nothing.
Run: ``.venv/bin/python benchmarks/target.py [--quick]``.
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np
from _harness import publish

from switchobs.codegen import TARGETS, CObserver, measure_footprint, run_pil
from switchobs.exceptions import PrerequisiteError
from switchobs.loop import braking_record
from switchobs.observers import adaptive_xbs_observer, xbs3_observer, xbs4_observer

#: The goal of issue 26: the generated step within this factor of the tuned hand-written one.
GOAL = 1.2

#: abs-xbs3 radau3 by hand: x+ = x + dt D(Z)^-1 F(Z) f(x), Z = dt J, D = I - 2Z/3 + Z^2/6, F = I - Z/6 (the
#: 2-stage Radau IIA step of an affine ODE, docs/codegen.md "Implicit methods"), J = s A - g C,
#: f = J x + c with A = [[0,-a,0],[0,c,1],[0,0,0]], C = [1,0,0], c = b u + g y, g = s K(s), s = y/vx.
#: The checks and codes are those of the generated step (docs/codegen.md "Status codes").
HAND = r"""
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include "@P@.h"
typedef float real;
int32_t hand_step(real *x, const real *sig, const real *params, real dt);
static const real defaults[9] = {@DEFAULTS@};
int32_t hand_step(real *x, const real *sig, const real *params, real dt)
{
    const real *p = params != NULL ? params : defaults;
    real y, vx, u, s, g1, g2, g3, e, f1, f2, f3, z11, z12, z21, z22, z23, z31;
    real q11, q12, q13, q21, q22, q23, q31, q32, d11, d12, d13, d21, d22, d23, d31, d32, d33;
    real r1, r2, r3, c11, c12, c13, det, inv, n1, n2, n3;
    int i;
    if (x == NULL || sig == NULL) return 7;
    if (!(dt > 0.0f) || !isfinite(dt)) return 1;
    if (!isfinite(x[0]) || !isfinite(x[1]) || !isfinite(x[2])) return 2;
    if (!isfinite(sig[0]) || !isfinite(sig[1]) || !isfinite(sig[2])) return 3;
    for (i = 0; i < 9; ++i) if (!isfinite(p[i])) return 6;
    if (!(p[0] > 0.0f) || !(p[1] < 0.0f)) return 6;
    y = sig[0]; vx = sig[1]; u = sig[2];
    if (!(vx > 0.0f)) return 4;
    s = y / vx;
    if (!isfinite(s)) return 4;
    if (s > 0.0f) { g1 = s * p[3]; g2 = s * p[4]; g3 = s * p[5]; }
    else { g1 = s * p[6]; g2 = s * p[7]; g3 = s * p[8]; }
    e = y - x[0];
    f1 = -(s * p[0]) * x[1] + p[1] * u + g1 * e;
    f2 = s * (p[2] * x[1] + x[2]) + g2 * e;
    f3 = g3 * e;
    /* Z = dt J; z13 = z32 = z33 = 0 */
    z11 = -(dt * g1); z12 = -(dt * (s * p[0]));
    z21 = -(dt * g2); z22 = dt * (s * p[2]); z23 = dt * s;
    z31 = -(dt * g3);
    /* Z^2 (q33 = 0) */
    q11 = z11 * z11 + z12 * z21; q12 = z11 * z12 + z12 * z22; q13 = z12 * z23;
    q21 = z21 * z11 + z22 * z21 + z23 * z31; q22 = z21 * z12 + z22 * z22; q23 = z22 * z23;
    q31 = z31 * z11; q32 = z31 * z12;
    /* D = I - 2Z/3 + Z^2/6 */
    d11 = 1.0f - (2.0f / 3.0f) * z11 + q11 / 6.0f; d12 = -(2.0f / 3.0f) * z12 + q12 / 6.0f; d13 = q13 / 6.0f;
    d21 = -(2.0f / 3.0f) * z21 + q21 / 6.0f; d22 = 1.0f - (2.0f / 3.0f) * z22 + q22 / 6.0f;
    d23 = -(2.0f / 3.0f) * z23 + q23 / 6.0f;
    d31 = -(2.0f / 3.0f) * z31 + q31 / 6.0f; d32 = q32 / 6.0f; d33 = 1.0f;
    /* r = F f = f - Z f / 6 */
    r1 = f1 - (z11 * f1 + z12 * f2) / 6.0f;
    r2 = f2 - (z21 * f1 + z22 * f2 + z23 * f3) / 6.0f;
    r3 = f3 - (z31 * f1) / 6.0f;
    /* Cramer: D v = r */
    c11 = d22 * d33 - d23 * d32; c12 = d23 * d31 - d21 * d33; c13 = d21 * d32 - d22 * d31;
    det = d11 * c11 + d12 * c12 + d13 * c13;
    if (!(det < 0.0f || det > 0.0f) || !isfinite(det)) return 5;
    inv = dt / det;
    n1 = x[0] + inv * (r1 * c11 + d12 * (d23 * r3 - r2 * d33) + d13 * (r2 * d32 - d22 * r3));
    n2 = x[1] + inv * (d11 * (r2 * d33 - d23 * r3) + r1 * c12 + d13 * (d21 * r3 - r2 * d31));
    n3 = x[2] + inv * (d11 * (d22 * r3 - r2 * d32) + d12 * (r2 * d31 - d21 * r3) + r1 * c13);
    if (!isfinite(n1) || !isfinite(n2) || !isfinite(n3)) return 5;
    x[0] = n1; x[1] = n2; x[2] = n3;
    return 0;
}
"""

#: (model, method, reference observer, initial state of the record)
MODELS = (
    ("abs-xbs3", "radau3", lambda: xbs3_observer(100.0, 100.0, method="radau3"), {"z2": 0.5}),
    ("abs-xbs4", "radau3", lambda: xbs4_observer(10.0, 20.0, method="radau3"), {"z2": 0.5}),
    ("abs-adaptive2", "rk4", lambda: adaptive_xbs_observer(100.0, [1e4, 1e4]), {"c": 30.0, "d": 15.0}),
)
#: (target, real)
BUILDS = (("cortex-m4f", "float"), ("cortex-m7", "double"), ("cortex-m7", "float"))


def hand_source(gen) -> str:
    defaults = ", ".join(f"{float(np.float32(v)).hex()}f" for v in gen.default_params)
    return HAND.replace("@P@", gen.prefix).replace("@DEFAULTS@", defaults)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the first 300 rows of the record; publish nothing")
    args = parser.parse_args()
    rows_out, hand_rows, notes = [], [], []
    ratios = []
    for model, method, make, initial in MODELS:
        ref = make()
        rec = braking_record(ref, initial_state=initial)
        rows, dts = (rec.rows[:300], rec.dt[:300]) if args.quick else (rec.rows, rec.dt)
        for target, real in BUILDS:
            gen = CObserver.like(ref, real=real).generated
            fp = measure_footprint(gen, target)
            res = run_pil(gen, target, rows, dts, rec.x0)
            rows_out.append(f"| {model} | {method} | {real} | {target} | {fp.text_bytes} | {fp.data_bytes} | "
                            f"{fp.worst('_step')} | {res.instructions_per_step:.0f} | "
                            f"{'yes' if res.bit_identical else 'NO'} |")
            if model == "abs-xbs3" and real == "float":
                step = ("hand_step", hand_source(gen))
                hfp = measure_footprint(gen, target, step=step)
                hres = run_pil(gen, target, rows, dts, rec.x0, step=step)
                ok = np.array(res.target_status) == 0
                got, mine = np.array(res.target_states), np.array(hres.target_states)
                diff = float(np.max(np.abs(got[ok] - mine[ok]) / np.max(np.abs(got[ok]), axis=0)))
                same_status = res.target_status == hres.target_status
                ratio = res.instructions_per_step / hres.instructions_per_step
                ratios.append((target, ratio))
                hand_rows.append(f"| {target} | {fp.text_bytes} | {hfp.text_bytes} | {fp.worst('_step')} | "
                                 f"{hfp.worst('hand_step')} | {res.instructions_per_step:.0f} | "
                                 f"{hres.instructions_per_step:.0f} | {ratio:.2f} | {diff:.1e} | "
                                 f"{'yes' if same_status else 'NO'} |")
            if model == "abs-xbs3" and target == "cortex-m4f":
                soft = dataclasses.replace(TARGETS["cortex-m4f"], reals=("double",))
                dgen = CObserver.like(ref, real="double").generated
                sres = run_pil(dgen, soft, rows, dts, rec.x0)
                sfp = measure_footprint(dgen, soft)
                notes.append(f"Double on the Cortex-M4F (refused by `--target cortex-m4f`; built here anyway): "
                             f"abs-xbs3 radau3 takes {sres.instructions_per_step:.0f} instructions per step in "
                             f"software floating point, {sres.instructions_per_step / res.instructions_per_step:.0f}"
                             f"× the float step, text {sfp.text_bytes} B.")
    method = ("Instructions of one `<prefix>_step` call on `qemu-system-arm -icount shift=0` (mps2-an386 Cortex-M4, "
              "mps2-an500 Cortex-M7), the mean over the braking record of the processor-in-the-loop test "
              f"({rows.shape[0]} steps: dry asphalt then snow, both signs of y, one sensor dropout), minus the same "
              "loop through an empty function; exact counts (one run each). Sizes: `arm-none-eabi-size` of the "
              "object built with the target's flags (`-std=c99 -O2 -ffp-contract=off -fno-math-errno` and the CPU's); "
              "*stack*: worst-case bytes of a `_step` call (`-fstack-usage`, call graph); *bit-identical*: every row's "
              "status and state equal to the host build's.")
    table = ["| model | method | real | target | text B | data B | stack B | instructions per step | bit-identical |",
             "| --- | --- | --- | --- | ---: | ---: | ---: | ---: | --- |", *rows_out]
    hand = ["| target | gen. text B | hand text B | gen. stack B | hand stack B | gen. instructions | "
            "hand instructions | gen. / hand | largest state difference | same statuses |",
            "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |", *hand_rows]
    worst = max(r for _, r in ratios)
    notes.insert(0, "abs-xbs3 radau3 float against the tuned hand-written step of the same maths and checks "
                 "(`benchmarks/target.py`, `HAND`): *largest state difference* is relative to each entry's largest "
                 "magnitude (the two round differently, so they are not bit-identical).")
    notes.append(f"Goal (issue 26): at most {GOAL}× the hand-written instruction count: "
                 f"**{'met' if worst <= GOAL else 'not met'}** (worst {worst:.2f}×).")
    publish("target", method, [table, hand], notes, write=not args.quick)
    return 0


if __name__ == "__main__":
    try:
        raise SystemExit(main())
    except PrerequisiteError as exc:  # no cross compiler or qemu here: say so, keep the published results
        print(f"!!! benchmarks/target.py SKIPPED: {exc}; benchmarks/results/target.md is unchanged !!!")
        raise SystemExit(0) from None
