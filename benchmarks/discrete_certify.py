"""What certifying the sampled observer costs: the generated C step with certified sub-stepping.

Step half (this file's :func:`step_timings`): for abs-xbs3 and abs-xbs4 with the demo design (all poles at
-100, beta1 = beta2 = 100) and ``h_max = 1/100``, the generated ``<prefix>_step`` compiled with the
sub-stepping (``--h-max``) against today's step (no ``H_MAX``), both in one binary and timed alternately
in the same run (``REPEATS`` runs of ``STEPS`` chained steps, state reset every 4096 steps):

* non-stiff signals (``|s| dt <= 5e-4``, one step each): ns per step of both, median and spread
  (min-max over the runs), and the median of the paired ratios (goal: <= 1.05);
* stiff signals (``|s| dt`` up to 0.09, low speed and large wheel acceleration): ns per step of the
  sub-stepped C, the mean number of sub-steps, and ns per sub-step (today's step is not stable there:
  its state overflows, so it is not timed on these signals);
* the radau3 step (2-stage Radau IIA, certified for every dt, no sub-steps) of the same design in the
  same binary and run, on both signal sets: ns per step, median.

The certificate-timing half (how long ``switchobs.certify.discrete_certificate`` takes) is added by
the certify layer next to :func:`step_timings`.
Run: ``.venv/bin/python benchmarks/discrete_certify.py``.
"""

from __future__ import annotations

import re
import shutil
import statistics
import subprocess
import tempfile
from fractions import Fraction
from pathlib import Path

import numpy as np

from switchobs.codegen import generate_observer
from switchobs.design import design
from switchobs.model import builtin_model

STEPS = 200_000
REPEATS = 31
H_MAX = Fraction(1, 100)
DESIGNS = {"abs-xbs3": "-100,-100,-100", "abs-xbs4": "-100,-100,-100,-100"}
CFLAGS = ["-std=c99", "-O2"]

DRIVER = r"""
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <time.h>
#include "plain.h"
#include "bounded.h"
#include "implicit.h"
#define ROWS 4096
#define NX PLAIN_NX
typedef int32_t (*stepper)(double *, const double *, const double *, double);
static double now(void) { struct timespec t; clock_gettime(CLOCK_MONOTONIC, &t); return t.tv_sec + 1e-9 * t.tv_nsec; }
static double bench(stepper f, const double *rows, long steps, long *failures)
{
    double x[NX];
    long k;
    int i;
    double t0 = now();
    for (k = 0; k < steps; ++k) {
        if ((k & (ROWS - 1)) == 0) for (i = 0; i < NX; ++i) x[i] = 0.1 * (i + 1);
        if (f(x, rows + (k & (ROWS - 1)) * 3, NULL, 1e-3) != 0) ++*failures;
    }
    return (now() - t0) / (double)steps * 1e9;
}
int main(void)
{
    static double calm[3 * ROWS], stiff[3 * ROWS];
    long r, fail = 0;
    for (r = 0; r < ROWS; ++r) {
        calm[3 * r] = 10.0 * sin(0.01 * (double)r);          /* |s| dt <= 10 / 20 * 1e-3 */
        calm[3 * r + 1] = 20.0;
        calm[3 * r + 2] = 100.0 * cos(0.013 * (double)r);
        stiff[3 * r] = 135.0 * sin(0.01 * (double)r);        /* |s| dt up to 0.09: up to 9 sub-steps */
        stiff[3 * r + 1] = 1.5;
        stiff[3 * r + 2] = 100.0 * cos(0.013 * (double)r);
    }
    for (r = 0; r < @REPEATS@; ++r) {   /* alternate, so that both see the same machine load */
        printf("calm %.4f %.4f\n", bench(plain_step, calm, @STEPS@, &fail), bench(bounded_step, calm, @STEPS@, &fail));
        printf("stiff %.4f\n", bench(bounded_step, stiff, @STEPS@ / 4, &fail));
        printf("radau3 %.4f %.4f\n", bench(implicit_step, calm, @STEPS@, &fail),
               bench(implicit_step, stiff, @STEPS@, &fail));
    }
    printf("failures %ld\n", fail);
    return 0;
}
"""


def _run(cmd: list[str], cwd: Path) -> str:
    return subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, check=True).stdout


def _mean_substeps(h_max_c: float) -> float:
    """Mean sub-steps of the stiff rows of the driver (the arithmetic of the generated step)."""
    r = np.arange(4096)
    a = np.abs(135.0 * np.sin(0.01 * r) / 1.5) * 1e-3
    return float(np.mean(np.where(a <= h_max_c, 1, np.ceil(a / h_max_c))))


def step_timings(model_name: str, cc: str, tmp: Path) -> dict[str, float]:
    """Today's step vs the sub-stepped step of one model, compiled with ``cc`` (see the module docstring)."""
    model = builtin_model(model_name)
    gains = design(model, DESIGNS[model_name])
    plain = generate_observer(model, gains, prefix="plain")
    bounded = generate_observer(model, gains, prefix="bounded", h_max=H_MAX)
    implicit = generate_observer(model, gains, prefix="implicit", method="radau3")
    d = tmp / f"{model_name}-{Path(cc).name}"
    for gen in (plain, bounded, implicit):
        gen.write(d)
    (d / "driver.c").write_text(DRIVER.replace("@REPEATS@", str(REPEATS)).replace("@STEPS@", str(STEPS)))
    for name in ("plain", "bounded", "implicit", "driver"):
        _run([cc, *CFLAGS, "-c", f"{name}.c"], d)
    _run([cc, "-o", "bench", "driver.o", "plain.o", "bounded.o", "implicit.o", "-lm"], d)
    out = _run(["./bench"], d)
    calm = [(float(a), float(b)) for a, b in re.findall(r"calm (\S+) (\S+)", out)]
    stiff = [float(v) for v in re.findall(r"^stiff (\S+)", out, re.M)]
    radau = [(float(a), float(b)) for a, b in re.findall(r"radau3 (\S+) (\S+)", out)]
    failures = int(re.search(r"failures (\d+)", out).group(1))
    plain_ns, bounded_ns = [a for a, _ in calm], [b for _, b in calm]
    substeps = _mean_substeps(bounded.h_max_c)
    return {"plain": statistics.median(plain_ns), "plain_min": min(plain_ns), "plain_max": max(plain_ns),
            "bounded": statistics.median(bounded_ns), "bounded_min": min(bounded_ns),
            "bounded_max": max(bounded_ns), "ratio": statistics.median(b / a for a, b in calm),
            "stiff": statistics.median(stiff), "stiff_min": min(stiff), "stiff_max": max(stiff),
            "substeps": substeps, "per_substep": statistics.median(stiff) / substeps, "failures": failures,
            "radau3": statistics.median(a for a, _ in radau), "radau3_stiff": statistics.median(b for _, b in radau)}


def main() -> None:
    compilers = [cc for cc in ("gcc", "clang") if shutil.which(cc)]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for model_name in DESIGNS:
            for cc in compilers:
                rows.append((model_name, cc, step_timings(model_name, cc, Path(tmp))))
    print(f"Generated C step (double, -O2), h_max = {H_MAX}: ns per step, median [min-max] of {REPEATS} runs")
    print("| model | compiler | today's step ns | with sub-stepping, non-stiff ns | ratio (median of pairs) "
          "| stiff ns per step | sub-steps per stiff step | ns per sub-step | radau3 ns, non-stiff | radau3 ns, stiff |")
    print("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for model_name, cc, t in rows:
        print(f"| {model_name} | {cc} | {t['plain']:.1f} [{t['plain_min']:.1f}-{t['plain_max']:.1f}] "
              f"| {t['bounded']:.1f} [{t['bounded_min']:.1f}-{t['bounded_max']:.1f}] | {t['ratio']:.3f} "
              f"| {t['stiff']:.1f} [{t['stiff_min']:.1f}-{t['stiff_max']:.1f}] | {t['substeps']:.2f} "
              f"| {t['per_substep']:.1f} | {t['radau3']:.1f} | {t['radau3_stiff']:.1f} |")
    bad = sum(t["failures"] for _, _, t in rows)
    if bad:
        print(f"warning: {bad} benchmark steps were refused")
    worst = max(t["ratio"] for _, _, t in rows)
    print(f"goal: non-stiff step with sub-stepping <= 1.05x today's: {'met' if worst <= 1.05 else 'NOT met'} "
          f"(worst ratio {worst:.3f})")


if __name__ == "__main__":
    main()
