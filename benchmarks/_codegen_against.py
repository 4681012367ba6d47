"""The generated step of this tree against the one of another git revision, in one binary.

A change of the emitter (``switchobs.codegen``) must keep the step as fast as it was and its results
bit-identical.  Run separately, two benchmark runs on a shared machine differ by more than the few per cent
that matter; here both emitters generate the same observers (prefixes ``old_<i>`` and ``new_<i>``), which are
compiled into one driver and timed alternately, run after run, so that both see the same load:

* ``step``: ``STEPS`` chained ``<prefix>_step`` calls over 4096 rows of non-stiff signals (state reset
  every 4096 steps), ns per step;
* ``run``: ``<prefix>_run`` over the same 4096 rows, ns per row;

median of the runs of each and the median of the paired ratios new/old (the figure to hold within
1.05).  The driver also compares the two trajectories bit for bit (``memcmp``) and fails when they differ.
Variants: abs-xbs3 and abs-xbs4 (the designs of ``codegen_step.py``), double and float, rk4, radau3 and rk4
with ``h_max = 1/100``; compilers gcc and clang (where installed), ``-std=c99 -O2``.

Not run by ``make bench`` (it publishes nothing; a helper of emitter changes).  Run:
``.venv/bin/python benchmarks/_codegen_against.py --old REV [--quick]`` (``REV``: any git revision,
e.g. ``main``; ``--quick``: abs-xbs3 double, gcc, 5 runs).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
STEPS = 200_000
REPEATS = 21
CFLAGS = ["-std=c99", "-O2"]
DESIGNS = {"abs-xbs3": "-40,-60,-60", "abs-xbs4": "-10,-10,-20,-20"}
VARIANTS = [(model, real, method, h_max) for model in DESIGNS for real in ("double", "float")
            for method, h_max in (("rk4", None), ("radau3", None), ("rk4", "1/100"))]

#: Run with the emitter under test on PYTHONPATH: writes the files of each variant with its prefix.
GENERATE = r"""
import json, sys
from pathlib import Path
from switchobs.codegen import generate_observer
from switchobs.design import design
from switchobs.model import builtin_model
out, tag, variants, designs = Path(sys.argv[1]), sys.argv[2], json.loads(sys.argv[3]), json.loads(sys.argv[4])
for i, (model, real, method, h_max) in enumerate(variants):
    m = builtin_model(model)
    gen = generate_observer(m, design(m, designs[model]), real=real, method=method, h_max=h_max,
                            prefix=f"{tag}_{i}")
    for name, text in gen.files.items():
        if name.startswith(gen.prefix):
            (out / name).write_text(text)
"""

DRIVER = r"""
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>
#include "old_@I@.h"
#include "new_@I@.h"
#define ROWS 4096
#define NX OLD_@I@_NX
typedef @REAL@ real;
typedef int32_t (*stepper)(real *, const real *, const real *, real);
typedef int32_t (*runner)(real *, const real *, int32_t, const real *, real, real *);
static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}
static void reset(real *x)
{
    int i;
    for (i = 0; i < NX; ++i) x[i] = (real)(0.1 * (i + 1));
}
static double step(stepper f, const real *rows, long steps, long *failures)
{
    real x[NX];
    long k;
    double t0 = now();
    for (k = 0; k < steps; ++k) {
        if ((k & (ROWS - 1)) == 0) reset(x);
        if (f(x, rows + (k & (ROWS - 1)) * 3, NULL, (real)1e-3) != 0) ++*failures;
    }
    return (now() - t0) / (double)steps * 1e9;
}
static double run(runner f, const real *rows, long steps, real *traj, long *failures)
{
    real x[NX];
    long k;
    double t0 = now();
    for (k = 0; k < steps / ROWS; ++k) {
        reset(x);
        if (f(x, rows, ROWS, NULL, (real)1e-3, traj) != 0) ++*failures;
    }
    return (now() - t0) / (double)(steps / ROWS * ROWS) * 1e9;
}
int main(void)
{
    static real rows[3 * ROWS], old_traj[NX * ROWS], new_traj[NX * ROWS];
    long r, failures = 0;
    for (r = 0; r < ROWS; ++r) {
        rows[3 * r] = (real)(10.0 * sin(0.01 * (double)r));
        rows[3 * r + 1] = (real)(20.0 - 2e-3 * (double)r);
        rows[3 * r + 2] = (real)(100.0 * cos(0.013 * (double)r));
    }
    for (r = 0; r < @REPEATS@; ++r) {   /* alternated, so that both see the same machine load */
        printf("step %.4f %.4f\n", step(old_@I@_step, rows, @STEPS@, &failures),
               step(new_@I@_step, rows, @STEPS@, &failures));
        printf("run %.4f %.4f\n", run(old_@I@_run, rows, @STEPS@, old_traj, &failures),
               run(new_@I@_run, rows, @STEPS@, new_traj, &failures));
    }
    printf("failures %ld\n", failures);
    printf("identical %d\n", memcmp(old_traj, new_traj, sizeof old_traj) == 0);
    return 0;
}
"""


def _run(cmd: list[str], cwd: Path, env: dict[str, str] | None = None) -> str:
    proc = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, check=False, env=env)
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed:\n{proc.stderr}")
    return proc.stdout


def generate(src: Path, out: Path, tag: str, variants: list) -> None:
    env = {**os.environ, "PYTHONPATH": str(src)}
    _run([sys.executable, "-c", GENERATE, str(out), tag, json.dumps(variants), json.dumps(DESIGNS)], out, env)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--old", required=True, metavar="REV", help="git revision of the emitter to compare with")
    parser.add_argument("--quick", action="store_true", help="abs-xbs3 double, gcc, 5 runs")
    parser.add_argument("--repeats", type=int, default=REPEATS)
    parser.add_argument("--branch-hints", action="store_true",
                        help="compile this tree's files with -DSWITCHOBS_BRANCH_HINTS (__builtin_expect, clang)")
    args = parser.parse_args()
    variants = VARIANTS[:3] if args.quick else VARIANTS
    repeats = 5 if args.quick else args.repeats
    compilers = [cc for cc in (("gcc",) if args.quick else ("gcc", "clang")) if shutil.which(cc)]
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        old_src = d / "old"
        old_src.mkdir()
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", args.old, "src"], capture_output=True,
                                 check=False)
        if archive.returncode != 0:
            raise SystemExit(f"git archive {args.old} failed: {archive.stderr.decode().strip()}")
        subprocess.run(["tar", "-x", "-C", str(old_src)], input=archive.stdout, check=True)
        generate(old_src / "src", d, "old", variants)
        generate(ROOT / "src", d, "new", variants)
        print(f"old: {args.old}, new: the working tree; ns per step (run: per row), median of {repeats} "
              f"alternated runs; ratio: median of the paired new/old")
        print("| model | real | method | compiler | old step | new step | ratio | old run | new run | ratio | "
              "bit-identical |")
        print("| --- | --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | --- |")
        worst = 0.0
        for i, (model, real, method, h_max) in enumerate(variants):
            for cc in compilers:
                (d / f"driver_{i}.c").write_text(DRIVER.replace("@I@", str(i)).replace("@REAL@", real)
                                                 .replace("@REPEATS@", str(repeats)).replace("@STEPS@", str(STEPS)))
                objs = []
                for name in (f"old_{i}", f"new_{i}", f"driver_{i}"):
                    hints = ["-DSWITCHOBS_BRANCH_HINTS"] if args.branch_hints and name.startswith("new") else []
                    _run([cc, *CFLAGS, *hints, "-c", f"{name}.c", "-o", f"{name}-{cc}.o"], d)
                    objs.append(f"{name}-{cc}.o")
                _run([cc, "-o", f"bench_{i}_{cc}", *objs, "-lm"], d)
                out = _run([f"./bench_{i}_{cc}"], d)
                cells = []
                for what in ("step", "run"):
                    pairs = [(float(a), float(b)) for a, b in re.findall(rf"^{what} (\S+) (\S+)$", out, re.M)]
                    paired = statistics.median(b / a for a, b in pairs)
                    worst = max(worst, paired)
                    cells += [f"{statistics.median(a for a, _ in pairs):.1f}",
                              f"{statistics.median(b for _, b in pairs):.1f}", f"{paired:.3f}"]
                same = re.search(r"identical (\d)", out).group(1) == "1"
                failures = int(re.search(r"failures (\d+)", out).group(1))
                label = method + ("" if h_max is None else f" h_max={h_max}")
                print(f"| {model} | {real} | {label} | {cc} | {' | '.join(cells)} | "
                      f"{'yes' if same else 'NO'}{'' if failures == 0 else f' ({failures} failed steps)'} |",
                      flush=True)
                if not same:
                    raise SystemExit(f"the trajectories of {model} {real} {label} ({cc}) differ")
        print(f"worst paired ratio: {worst:.3f}")


if __name__ == "__main__":
    main()
