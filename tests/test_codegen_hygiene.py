"""Compiler hygiene of the generated C, with gcc and clang: strict warnings as errors, no double promotion in
float, -ffast-math refused, bounded static stack, a README example that runs, and AddressSanitizer + UBSan on
random and hostile inputs.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import warnings
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from switchobs.codegen import (GeneratedObserver, StepStatus, generate_observer, generate_super_twisting,
                               generate_vehicle_speed)
from switchobs.codegen._emit import kernel
from switchobs.exceptions import CodegenError
from switchobs.design import design
from switchobs.model import Model, builtin_model
from switchobs.spec import METHODS

from test_codegen_translate import random_model_toml

STRICT = ["-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Wconversion", "-Wfloat-conversion", "-Wdouble-promotion",
          "-Werror"]
#: The generated observers and their README example also compile clean with the warnings an ECU build adds
#: (no == or != between reals, no implicit sign change, no shadowing, no undefined macro in #if, ...).
STRICT_GENERATED = STRICT + ["-Wsign-conversion", "-Wfloat-equal", "-Wshadow", "-Wundef", "-Wcast-qual",
                             "-Wstrict-prototypes", "-Wmissing-prototypes"]
COMPILERS = ("gcc", "clang")
SPECTRA = {"abs-xbs3": "-40,-60,-60", "abs-xbs4": "-10,-10,-20,-20", "abs-adaptive2": "-15,-15"}


def compiler(cc: str) -> str:
    """``cc`` on PATH, or a loud skip: `make test` installs clang (target cc-tools) where it can."""
    path = shutil.which(cc)
    if path is None:
        message = (f"!!! {cc} is NOT INSTALLED: the generated C was not checked with {cc}; run `make cc-tools` "
                   f"(as root on Debian: apt-get install -y {cc}) !!!")
        warnings.warn(message)
        pytest.skip(message)
    return path


def builtin(name: str, real: str = "double", method: str = "rk4", **kw) -> GeneratedObserver:
    m = builtin_model(name)
    return generate_observer(m, design(m, SPECTRA[name]), real=real, method=method, **kw)


def adaptive(real: str = "double", **kw) -> GeneratedObserver:
    return builtin("abs-adaptive2", real, unknown=["c", "d"], Gamma=[50.0, 20.0], **kw)


def written(gen: GeneratedObserver, directory: Path) -> Path:
    gen.write(directory)
    return directory / f"{gen.prefix}.c"


def compile_c(cc: str, flags: list[str], sources: list[Path], out: Path, link: bool = False) -> None:
    cmd = [cc, *flags, *map(str, sources), "-o", str(out)] + (["-lm"] if link else ["-c"])
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    assert proc.returncode == 0, f"{' '.join(cmd)}\n{proc.stderr}"


def generated_cases() -> list[tuple[str, GeneratedObserver]]:
    cases = []
    for name in SPECTRA:
        for real in ("double", "float"):
            for method in METHODS:
                cases.append((f"{name}-{real}-{method}", builtin(name, real, method)))
    cases += [(f"adaptive-{r}", adaptive(r)) for r in ("double", "float")]
    cases += [(f"super-twisting-{r}", generate_super_twisting(400.0, 2000.0, real=r)) for r in ("double", "float")]
    cases += [(f"vehicle-speed-{r}", generate_vehicle_speed(24.0, real=r)) for r in ("double", "float")]
    rng = np.random.default_rng(11)
    for n in range(1, 7):
        text = random_model_toml(rng, n)
        model = Model.from_dict(__import__("tomllib").loads(text))
        for real in ("double", "float"):
            cases.append((f"random-{n}-{real}", generate_observer(model, (rng.normal(size=n), rng.normal(size=n)),
                                                                  real=real, h_max="1/64" if n % 2 else None)))
    for name in SPECTRA:
        for real in ("double", "float"):
            cases.append((f"{name}-{real}-substeps", builtin(name, real, h_max="1/100", max_substeps=16)))
    cases.append(("adaptive-float-substeps", adaptive("float", h_max="1/50")))
    cases += [(f"abs-xbs4-{r}-radau3-substeps", builtin("abs-xbs4", r, "radau3", h_max="1/100")) for r in ("double", "float")]
    cases.append(("constant-scale-substeps", generate_observer(constant_scale_model(), ([1.0, 2.0], [3.0, 4.0]),
                                                              h_max="1/100")))
    return cases


def constant_scale_model() -> Model:
    """s = 3: no scale kernel; the sub-step choice uses the constant |s|."""
    return Model.from_dict({"name": "const", "states": ["z1", "z2"], "A": [["0", "1"], ["-1", "0"]], "C": ["1", "0"],
                            "time_scale": "3", "inputs": ["u"], "b": ["0", "1"]})


@pytest.mark.slow
@pytest.mark.parametrize("cc", COMPILERS)
def test_generated_c_compiles_clean_with_strict_flags(tmp_path, cc):
    """STRICT_GENERATED (-std=c99 -Wall -Wextra -Wpedantic -Wconversion -Wsign-conversion -Wdouble-promotion
    -Wfloat-equal -Wshadow -Wundef -Wcast-qual -Wstrict-prototypes -Wmissing-prototypes -Werror), gcc and clang,
    also with the branch hints on."""
    cc = compiler(cc)
    cases = generated_cases()
    assert len(cases) == 3 * 2 * len(METHODS) + 2 + 2 + 2 + 12 + 6 + 2 + 2
    for i, (label, gen) in enumerate(cases):
        src = written(gen, tmp_path / label)
        hints = ["-DSWITCHOBS_BRANCH_HINTS"] if i % 2 else []
        compile_c(cc, STRICT_GENERATED + ["-O2", *hints], [src], tmp_path / label / "obj.o")
        if gen.real == "float":
            assert not re.search(r"\bdouble\b", gen.source + gen.header), label
            assert not re.search(r"(?<![\w.])\d+\.\d*(?:e[+-]?\d+)?(?![\w.]|f)", _code(gen.source)), label


def _code(text: str) -> str:
    """C text without comments (literals there need no suffix)."""
    return re.sub(r"/\*.*?\*/", "", text, flags=re.S)


def test_casadi_truth_tests_become_booleans_and_other_logic_is_refused():
    """casadi keeps comparisons in real temporaries and tests reals for truth (`a0=(a0<a1); (a0?a2:0); (!a0)`):
    they become bool temporaries, with real literals in the ternaries and no == or != between reals."""
    x = ca.SX.sym("x", 2)
    k = kernel("k", [("x", x)], ca.if_else(x[0] > 0, x[1], 2 * x[0]), real="float", prefix="p")
    assert "bool b0;" in k.body and "b0=(a0<a1);" in k.body and "(b0?a2:0.0f)" in k.body and "b0=(!b0);" in k.body
    assert not re.search(r"\(a\d+\?|\(!a\d+\)|[!=]=|\bdouble\b|\?\w+:0\)", k.body)
    with pytest.raises(CodegenError, match="unexpected logical operator"):
        kernel("k", [("x", x)], ca.logic_and(x[0], x[1]), real="double", prefix="p")


@pytest.mark.parametrize("cc", COMPILERS)
@pytest.mark.parametrize("flag", ["-ffast-math", "-ffinite-math-only"])
def test_fast_math_is_refused_with_the_reason(tmp_path, cc, flag):
    """-ffast-math deletes the NaN and infinity checks (a NaN speed would return OK): the C refuses to compile."""
    cc = compiler(cc)
    src = written(builtin("abs-xbs3", h_max="1/100"), tmp_path)
    cmd = [cc, "-std=c99", "-O2", flag, "-c", str(src), "-o", str(tmp_path / "obj.o")]
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    assert proc.returncode != 0
    assert "must not be compiled with -ffast-math or -ffinite-math-only" in proc.stderr
    assert "delete the checks that refuse NaN and infinite inputs" in proc.stderr


@pytest.mark.parametrize("name", sorted(SPECTRA))
def test_stack_is_static_and_within_the_documented_bound(tmp_path, name):
    """-fstack-usage: every frame is static (no VLA, no alloca), the deepest chain (_step, _run or _run_dt,
    then _rows, _advance, kernel) within STACK_REALS reals plus the frames of four calls; no heap, no writable
    global data (size: data = bss = 0)."""
    for real in ("double", "float"):
        for opt, h_max, method in (("-O0", None, "rk4"), ("-O2", None, "rk4"), ("-O2", "1/100", "rk4"),
                                   ("-O0", None, "radau3"), ("-O2", None, "radau3")):
            gen = builtin(name, real, method, h_max=h_max)
            d = tmp_path / f"{real}{opt}{h_max is not None}{method}"
            src = written(gen, d)
            compile_c("gcc", ["-std=c99", opt, "-fstack-usage"], [src], d / "obj.o")
            frames = {}
            for line in (d / "obj.su").read_text().splitlines():
                where, size, kind = line.split("\t")
                assert kind == "static", line
                frames[where.rsplit(":", 1)[1]] = int(size)
            p = gen.prefix
            entries = (f"{p}_step", f"{p}_run", f"{p}_run_dt")
            inner = [k for k in frames if k.startswith((f"{p}_rows", f"{p}_advance"))]  # with gcc's .part clones
            leaf = max(v for k, v in frames.items() if k not in entries and k not in inner)
            chain = max(frames[k] for k in entries) + sum(frames[k] for k in inner) + leaf
            width = 4 if real == "float" else 8
            # the x86-64 red zone (128 bytes) of the leaf kernel is not in its reported frame
            assert chain <= gen.stack_reals * width + 384 + 128
            size = subprocess.run(["size", str(d / "obj.o")], capture_output=True, text=True, check=True).stdout
            text_, data, bss = map(int, size.splitlines()[1].split()[:3])
            assert data == 0 and bss == 0 and text_ > 0
            assert not re.search(r"\b(malloc|calloc|realloc|free|alloca)\s*\(", gen.source)


@pytest.mark.parametrize("cc", COMPILERS)
@pytest.mark.parametrize("name, real", [("abs-xbs3", "double"), ("abs-xbs4", "float"), ("adaptive", "double"),
                                        ("super-twisting", "float"), ("abs-xbs3-substeps", "float")])
def test_readme_example_program_compiles_strict_and_runs(tmp_path, name, real, cc):
    cc = compiler(cc)
    if name == "adaptive":
        gen = adaptive(real)
    elif name == "super-twisting":
        gen = generate_super_twisting(400.0, 2000.0, real=real)
    elif name == "abs-xbs3-substeps":
        gen = builtin("abs-xbs3", real, h_max="1/1000", max_substeps=4)
    else:
        gen = builtin(name, real)
    src = written(gen, tmp_path)
    example = re.search(r"## Example\n\n```c\n(.*?)```", gen.readme, flags=re.S).group(1)
    (tmp_path / "example.c").write_text(example)
    compile_c(cc, STRICT_GENERATED + ["-O2", f"-I{tmp_path}"], [tmp_path / "example.c", src], tmp_path / "example",
              link=True)
    proc = subprocess.run([str(tmp_path / "example")], capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stdout
    values = [float(v) for v in re.findall(r"xhat\[\d+\] = (\S+)", proc.stdout)]
    assert len(values) == gen.nx and all(np.isfinite(values))


# --------------------------------------------------------------------------- sanitizers
DRIVER = r"""
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include "@P@.h"

typedef @REAL@ real;
#define NX @PU@_NX
#define NS @PU@_NS
#define NP @PU@_NP
#define SIGNED_SIGNAL @SIGNED@  /* index of a signal that must be > 0, or -1 */

static unsigned long long state = 88172645463325252ULL;
static double urand(void)
{
    state ^= state << 13; state ^= state >> 7; state ^= state << 17;
    return (double)(state >> 11) * (1.0 / 9007199254740992.0);
}
static real gauss(double scale)
{
    return (real)(scale * sqrt(-2.0 * log(urand() + 1e-300)) * cos(6.283185307179586 * urand()));
}

static real hostile(void)
{
    const real table[] = {(real)NAN, (real)INFINITY, -(real)INFINITY, (real)0, -(real)0, @MAX@, -@MAX@,
                          @TINY@, -@TINY@, (real)1, (real)-1, (real)1e30, (real)-1e30};
    return table[(unsigned)(urand() * (double)(sizeof table / sizeof table[0])) % (sizeof table / sizeof table[0])];
}

static int check(real *x, const real *sig, const real *par, real dt, long *counts)
{
    real saved[NX];
    int32_t i, status;
    memcpy(saved, x, sizeof saved);
    status = @P@_step(x, sig, par, dt);
    if (status < 0 || status > 8) return 100;
    if (status != 0 && memcmp(saved, x, sizeof saved) != 0) return 101;
    if (status == 0) for (i = 0; i < NX; ++i) if (!isfinite(x[i])) return 102;
    counts[status] += 1;
    return 0;
}

int main(void)
{
    real x[NX], sig[NS], par[NP], rows[4 * NS], traj[4 * NX], dts[4], dt;
    long counts[9] = {0};
    int32_t i, k, bad;
    for (k = 0; k < 20000; ++k) {
        double scale = pow(10.0, (double)(int)(urand() * 9.0) - 3.0);
        for (i = 0; i < NX; ++i) x[i] = gauss(scale);
        for (i = 0; i < NS; ++i) sig[i] = gauss(10.0);
        if (SIGNED_SIGNAL >= 0) sig[SIGNED_SIGNAL] = (real)(0.5 + 40.0 * urand());
        for (i = 0; i < NP; ++i) par[i] = @P@_default_params[i];
        dt = (real)(urand() < 0.5 ? 1e-3 : 1e-2 * urand());
        switch (k % 5) {
        case 1: x[(int)(urand() * NX) % NX] = hostile(); break;
        case 2: sig[(int)(urand() * NS) % NS] = hostile(); break;
        case 3: par[(int)(urand() * NP) % NP] = hostile(); break;
        case 4: dt = hostile(); break;
        default: break;
        }
        bad = check(x, sig, par, dt, counts);
        if (bad) { printf("failure %d at iteration %d\n", bad, k); return bad; }
        for (i = 0; i < 4 * NS; ++i) rows[i] = sig[i % NS];
        if (k % 7 == 0) rows[NS + (int)(urand() * NS) % NS] = hostile();
        bad = @P@_run(x, rows, 4, k % 3 ? par : NULL, dt, k % 2 ? traj : NULL);
        if (bad < 0 || bad > 8) return 103;
        for (i = 0; i < 4; ++i) dts[i] = (real)(1e-3 * (1.0 + urand()));
        if (k % 11 == 0) dts[(int)(urand() * 4.0) % 4] = hostile();
        bad = @P@_run_dt(x, rows, 4, k % 3 ? par : NULL, dts, k % 2 ? traj : NULL);
        if (bad < 0 || bad > 8) return 104;
    }
    for (i = 0; i < 9; ++i) printf("count %d %ld\n", (int)i, counts[i]);
    for (i = 0; i < NX; ++i) x[i] = (real)0.1;
    for (i = 0; i < NS; ++i) sig[i] = (real)1;
    for (i = 0; i < NP; ++i) par[i] = @P@_default_params[i];
    printf("case dt0 %d\n", @P@_step(x, sig, par, (real)0));
    x[0] = (real)NAN; printf("case xnan %d\n", @P@_step(x, sig, par, (real)1e-3)); x[0] = (real)0.1;
    sig[0] = (real)INFINITY; printf("case siginf %d\n", @P@_step(x, sig, par, (real)1e-3)); sig[0] = (real)1;
    par[0] = (real)NAN; printf("case parnan %d\n", @P@_step(x, sig, par, (real)1e-3)); par[0] = @P@_default_params[0];
    if (SIGNED_SIGNAL >= 0) {
        sig[SIGNED_SIGNAL] = (real)0;
        printf("case scale0 %d\n", @P@_step(x, sig, par, (real)1e-3));
    }
    printf("case null %d\n", @P@_step(NULL, sig, par, (real)1e-3));
    return 0;
}
"""


def sanitizer_cases() -> list[GeneratedObserver]:
    dom = Model.from_dict({"name": "dom", "states": ["z1", "z2"], "A": [["0", "1"], ["-m", "0"]], "C": ["1", "0"],
                           "d": ["1/(y - 1)", "log(y + 2) + sqrt(y + 3)"], "b": ["1/m", "y^(3/2)"],
                           "time_scale": "y/(w - 3)", "parameters": ["m"], "external": ["w"], "inputs": ["u"],
                           "values": {"m": "2"}})
    return [builtin("abs-xbs4"), builtin("abs-xbs3", "float"), adaptive(), adaptive("float"),
            generate_observer(dom, ([1.0, 2.0], [3.0, 4.0])), generate_super_twisting(400.0, 2000.0, real="float"),
            builtin("abs-xbs4", h_max="1/100", max_substeps=16), builtin("abs-xbs3", "float", h_max="1/100"),
            builtin("abs-xbs4", method="radau3"), builtin("abs-xbs3", "float", "radau3", h_max="1/100")]


#: (case, compiler): every case with gcc; with clang the sub-stepped ones and one adaptive (clang's runtime is
#: the same sanitizer family, so a few cases suffice to keep the test time low).
SANITIZED = [(i, "gcc") for i in range(10)] + [(i, "clang") for i in (3, 6, 7, 8)]


@pytest.mark.slow
@pytest.mark.parametrize("index, cc", SANITIZED)
def test_asan_ubsan_on_random_and_hostile_inputs(tmp_path, index, cc):
    cc = compiler(cc)
    gen = sanitizer_cases()[index]
    src = written(gen, tmp_path)
    signed = next((gen.signal_names.index(g.expr.name) for g in gen.guards
                   if g.kind == "positive" and g.expr.is_Symbol and g.expr.name in gen.signal_names), -1)
    is_float = gen.real == "float"
    driver = (DRIVER.replace("@P@", gen.prefix).replace("@PU@", gen.prefix.upper()).replace("@REAL@", gen.real)
              .replace("@SIGNED@", str(signed)).replace("@MAX@", "FLT_MAX" if is_float else "DBL_MAX")
              .replace("@TINY@", "1.4e-45f" if is_float else "4.9e-324"))
    (tmp_path / "driver.c").write_text(driver)
    flags = ["-std=c99", "-g", "-O1", "-fno-omit-frame-pointer", f"-I{tmp_path}",
             "-fsanitize=address,undefined,float-divide-by-zero,float-cast-overflow", "-fno-sanitize-recover=all"]
    compile_c(cc, flags, [tmp_path / "driver.c", src], tmp_path / "driver", link=True)
    proc = subprocess.run([str(tmp_path / "driver")], capture_output=True, text=True, check=False, timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "runtime error" not in proc.stderr and "AddressSanitizer" not in proc.stderr
    counts = {int(a): int(b) for a, b in re.findall(r"count (\d) (\d+)", proc.stdout)}
    cases = dict(re.findall(r"case (\w+) (\d+)", proc.stdout))
    assert counts[0] > 5000  # most random steps succeed
    assert counts[StepStatus.NONFINITE_STATE] > 0 and counts[StepStatus.BAD_DT] > 0
    assert counts[StepStatus.NONFINITE_SIGNAL] > 0 and counts[StepStatus.BAD_PARAM] > 0
    assert int(cases["dt0"]) == StepStatus.BAD_DT
    assert int(cases["xnan"]) == StepStatus.NONFINITE_STATE
    assert int(cases["siginf"]) == StepStatus.NONFINITE_SIGNAL
    assert int(cases["parnan"]) == StepStatus.BAD_PARAM
    assert int(cases["null"]) == StepStatus.BAD_ARGUMENT
    if signed >= 0:
        assert int(cases["scale0"]) == StepStatus.UNDEFINED_TIME_SCALE
    # hostile signals and dt (1e30) make |s| dt too large for any sub-step budget
    assert (counts[StepStatus.SUBSTEP_LIMIT] > 0) == (gen.h_max is not None)
