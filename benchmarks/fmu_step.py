"""Cost of one FMU communication step against the bare C step it wraps.

For abs-xbs3 and abs-xbs4 (seed 000, the default method radau3, 1 ms steps), double and float: a C driver (``gcc -O2``, the FMU's
flags) linking the generated ``<prefix>.c`` and the FMI 3.0 and FMI 2.0 wrappers of ``switchobs.codegen.
generate_fmu`` steps a record of signals (a 40 rad/s sine in y, a falling vx) three ways, interleaved:

* *bare*: ``<prefix>_step(xhat, row, params, dt)`` per row, what an ECU task calls;
* *FMI 3.0*: ``fmi3SetFloat64`` (the three inputs), ``fmi3DoStep`` and ``fmi3GetFloat64`` (the state
  outputs) per row, what a co-simulation master calls per communication step;
* *FMI 2.0*: the same with ``fmi2SetReal`` / ``fmi2DoStep`` / ``fmi2GetReal``.

CPU time (``clock()``) of 200 000 rows, median [min–max] of 21 runs.  The goal (issue 27) is at most 1.5×
the bare step.  Run: ``.venv/bin/python benchmarks/fmu_step.py [--quick]`` (needs fmpy for the FMI headers).
"""

from __future__ import annotations

import argparse
import subprocess
import tempfile
from pathlib import Path

from _harness import Stats, publish

from switchobs.codegen import generate_fmu, generate_observer
from switchobs.codegen._fmu import fmi_headers
from switchobs.codegen._build import find_compiler
from switchobs.design import design
from switchobs.model import builtin_model

ROWS = 200_000
RUNS = 21
CFLAGS = ["-std=c99", "-O2", "-ffp-contract=off"]

DRIVER = r"""
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "fmi3Functions.h"
#include "fmi2Functions.h"
#include "{p}.h"

typedef {p}_real real;
static const fmi3ValueReference SIG[3] = {{ {sig} }}, OUT[{P}_NX] = {{ {out} }};

static void rows_of(real *rows, int n)
{{
    int k;
    for (k = 0; k < n; ++k) {{
        double t = 1e-3 * k;
        rows[3 * k] = (real)(30.0 * sin(40.0 * t));
        rows[3 * k + 1] = (real)(25.0 - 3.0 * t / 200.0);
        rows[3 * k + 2] = (real)(500.0 * cos(40.0 * t));
    }}
}}

int main(int argc, char **argv)
{{
    int n = atoi(argv[1]), runs = atoi(argv[2]), r, k, i;
    real *rows = malloc(sizeof(real) * 3u * (size_t)n), x[{P}_NX];
    double in[3], got[{P}_NX], sink = 0.0;
    fmi2CallbackFunctions cb = {{ NULL, calloc, free, NULL, NULL }};
    fmi3Instance f3 = fmi3InstantiateCoSimulation("b", "{token3}", NULL, fmi3False, fmi3False, fmi3False,
                                                  fmi3False, NULL, 0, NULL, NULL, NULL);
    fmi2Component f2 = fmi2Instantiate("b", fmi2CoSimulation, "{token2}", NULL, &cb, fmi2False, fmi2False);
    fmi3Boolean ev, term, early;
    fmi3Float64 last;
    if (rows == NULL || f3 == NULL || f2 == NULL) return 3;
    rows_of(rows, n);
    fmi3EnterInitializationMode(f3, fmi3False, 0.0, 0.0, fmi3False, 0.0);
    fmi3ExitInitializationMode(f3);
    fmi2SetupExperiment(f2, fmi2False, 0.0, 0.0, fmi2False, 0.0);
    fmi2EnterInitializationMode(f2);
    fmi2ExitInitializationMode(f2);
    for (r = 0; r < runs; ++r) {{
        clock_t c0, c1, c2, c3;
        for (i = 0; i < {P}_NX; ++i) x[i] = (real)0;
        c0 = clock();
        for (k = 0; k < n; ++k) if ({p}_step(x, rows + 3 * k, {p}_default_params, (real)1e-3) != 0) return 4;
        c1 = clock();
        for (k = 0; k < n; ++k) {{
            for (i = 0; i < 3; ++i) in[i] = (double)rows[3 * k + i];
            fmi3SetFloat64(f3, SIG, 3, in, 3);
            if (fmi3DoStep(f3, 1e-3 * k, 1e-3, fmi3True, &ev, &term, &early, &last) != fmi3OK) return 5;
            fmi3GetFloat64(f3, OUT, {P}_NX, got, {P}_NX);
        }}
        c2 = clock();
        for (k = 0; k < n; ++k) {{
            for (i = 0; i < 3; ++i) in[i] = (double)rows[3 * k + i];
            fmi2SetReal(f2, SIG, 3, in);
            if (fmi2DoStep(f2, 1e-3 * k, 1e-3, fmi2True) != fmi2OK) return 6;
            fmi2GetReal(f2, OUT, {P}_NX, got);
        }}
        c3 = clock();
        sink += x[0] + got[0];
        printf("%.6e %.6e %.6e\n", (double)(c1 - c0) / CLOCKS_PER_SEC / n, (double)(c2 - c1) / CLOCKS_PER_SEC / n,
               (double)(c3 - c2) / CLOCKS_PER_SEC / n);
    }}
    fmi3FreeInstance(f3);
    fmi2FreeInstance(f2);
    free(rows);
    return isfinite(sink) ? 0 : 7;
}}
"""


def measure(model: str, spectrum: str, real: str, rows: int, runs: int) -> tuple[Stats, Stats, Stats]:
    m = builtin_model(model)
    gen = generate_observer(m, design(m, spectrum), real=real)
    fmu3, fmu2 = generate_fmu(gen, fmi_version=3), generate_fmu(gen, fmi_version=2)
    vr = fmu3.value_references
    assert vr == {k: v for k, v in fmu2.value_references.items()} | {"time": 0}
    token = {v: f.model_description.split('"{', 1)[1].split('}"', 1)[0] for v, f in ((3, fmu3), (2, fmu2))}
    driver = DRIVER.format(p=gen.prefix, P=gen.prefix.upper(), sig=", ".join(str(vr[s]) for s in gen.signal_names),
                           out=", ".join(str(vr[f"xhat_{s}"]) for s in gen.state_names),
                           token3="{" + token[3] + "}", token2="{" + token[2] + "}")
    with tempfile.TemporaryDirectory() as tmp:
        files = {**gen.files, **fmi_headers(3), **fmi_headers(2), "driver.c": driver,
                 f"{gen.prefix}_fmi3.c": fmu3.wrapper, f"{gen.prefix}_fmi2.c": fmu2.wrapper}
        for name, text in files.items():
            (Path(tmp) / name).write_text(text)
        exe = Path(tmp) / "bench"
        subprocess.run([find_compiler(), *CFLAGS, "-o", str(exe), "driver.c", f"{gen.prefix}.c",
                        f"{gen.prefix}_fmi3.c", f"{gen.prefix}_fmi2.c", "-lm"], cwd=tmp, check=True)
        out = subprocess.run([str(exe), str(rows), str(runs)], capture_output=True, text=True, check=True).stdout
    cols = list(zip(*(map(float, line.split()) for line in out.splitlines())))
    return Stats(cols[0]), Stats(cols[1]), Stats(cols[2])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="20 000 rows, 5 runs, print only")
    args = parser.parse_args()
    rows, runs = (20_000, 5) if args.quick else (ROWS, RUNS)
    table = ["| model | real | bare `_step` ns | FMI 3.0 set + doStep + get ns | FMI 3.0 vs bare | "
             "FMI 2.0 set + doStep + get ns | FMI 2.0 vs bare |",
             "| --- | --- | ---: | ---: | --- | ---: | --- |"]
    for model, spectrum in (("abs-xbs3", "-40,-60,-60"), ("abs-xbs4", "-40,-60,-60,-60")):
        for real in ("double", "float"):
            bare, f3, f2 = measure(model, spectrum, real, rows, runs)
            table.append(f"| {model} | {real} | {bare.show(1e9)} | {f3.show(1e9)} | "
                         f"{f3.median / bare.median:.2f}× | {f2.show(1e9)} | {f2.median / bare.median:.2f}× |")
    publish("fmu_step", f"C: ns per 1 ms radau3 step (the default method), `gcc {' '.join(CFLAGS)}`, CPU time of {rows} rows, median "
            f"[min–max] of {runs} interleaved runs; *bare* is `<prefix>_step` per row, *FMI* a master's "
            "communication step: set the three inputs, `doStep`, get the state outputs.  The goal is at most "
            "1.5× the bare step.", [table], write=not args.quick)


if __name__ == "__main__":
    main()
