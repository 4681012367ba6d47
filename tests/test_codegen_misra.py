"""MISRA C:2012 of the generated C, checked with cppcheck 2.10's misra addon (``cppcheck --addon=misra
--enable=style --std=c99 <prefix>.c``, which also reports the header it includes): no finding of a mandatory or
required guideline in any generated .c or .h, and every advisory finding listed in the deviation record
``<prefix>_misra.md`` -- which lists nothing that cppcheck does not find, besides the guidelines it marks as not
checked by the addon.  The default run checks abs-xbs3 with every method (sub-stepped rk4 too) and both real
types, and keeps the table of docs/codegen.md equal to that run; the slow matrix adds abs-xbs4, abs-adaptive2, a
user model with d(y) and b(y), the adaptive and the super-twisting observers.  clang-tidy's narrowing checks run
on float variants.
"""

from __future__ import annotations

import collections
import ctypes
import itertools
import math
import re
import shutil
import subprocess
import tomllib
import warnings
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from switchobs.codegen import (GeneratedObserver, compile_sources, generate_observer, generate_super_twisting,
                               generate_vehicle_speed)
from switchobs.codegen._emit import kernel
from switchobs.codegen._misra import CATEGORY, deviations, functions, identifier_clashes, misra_findings
from switchobs.design import design
from switchobs.model import Model, builtin_model
from switchobs.spec import METHODS

ROOT = Path(__file__).resolve().parent.parent
SPECTRA = {"abs-xbs3": "-40,-60,-60", "abs-xbs4": "-10,-10,-20,-20", "abs-adaptive2": "-15,-15"}
#: every method, and rk4 sub-stepped (--h-max)
STEPS = [(m, None) for m in METHODS] + [("rk4", "1/100")]
REALS = ("double", "float")
def cppcheck(tmp_path: Path) -> str:
    """cppcheck with a working misra addon (it reports a known violation of rule 14.4), or a loud skip."""
    exe = shutil.which("cppcheck")
    message = ("!!! cppcheck is NOT INSTALLED: the MISRA C:2012 status of the generated C was NOT checked; "
               "as root on Debian: apt-get install -y cppcheck !!!")
    if exe is not None:
        probe = tmp_path / "probe.c"
        probe.write_text("int f(int a);\nint f(int a) { if (a) { return 1; } return 0; }\n")
        proc = subprocess.run([exe, "--addon=misra", "-q", "--template={file}:{line}:{id}", str(probe)],
                              capture_output=True, text=True, check=False)
        if "misra-c2012-14.4" in proc.stderr:
            return exe
        message = (f"!!! cppcheck's misra addon does not work ({proc.stderr.strip()[:200]!r}): the MISRA C:2012 "
                   "status of the generated C was NOT checked !!!")
    warnings.warn(message)
    pytest.skip(message)


def builtin(name: str, real: str, method: str, h_max: str | None = None) -> GeneratedObserver:
    m = builtin_model(name)
    return generate_observer(m, design(m, SPECTRA[name]), real=real, method=method, h_max=h_max)


def user_model() -> Model:
    """examples/my_model.toml with a nonlinear d(y) and b(y) (log, a division, a power: domain guards)."""
    data = tomllib.loads((ROOT / "examples" / "my_model.toml").read_text("utf-8"))
    data.update(name="my-wheel-db", d=["0", "k*y", "log(y + 2)"], b=["b", "0", "1/(y - 1) + y^(3/2)"])
    return Model.from_dict(data)


def user(real: str, method: str, h_max: str | None = None) -> GeneratedObserver:
    return generate_observer(user_model(), ([1.0, 2.0, 3.0], [-1.0, 2.0, 3.0]), real=real, method=method,
                             h_max=h_max)


def adaptive(real: str, h_max: str | None = None) -> GeneratedObserver:
    m = builtin_model("abs-adaptive2")
    return generate_observer(m, design(m, SPECTRA["abs-adaptive2"]), real=real, unknown=["c", "d"],
                             Gamma=[50.0, 20.0], h_max=h_max)


def _label(method: str, h_max: str | None) -> str:
    return method if h_max is None else f"{method} h_max={h_max}"


def findings(exe: str, gen: GeneratedObserver, directory: Path) -> list[tuple[str, int, str]]:
    """(file name, line, rule or cppcheck id) of every finding of cppcheck's misra run on ``<prefix>.c``."""
    return misra_findings(exe, gen.prefix, gen.files, directory)


def where(gen: GeneratedObserver, file: str, line: int) -> str:
    """The identifier a finding is about: the macro a header line defines, the function a source line is in,
    or the object a file-scope source line defines."""
    text = (gen.header if file.endswith(".h") else gen.source).splitlines()[line - 1]
    if file.endswith(".h"):
        return re.match(r"#define (\w+)", text).group(1)
    for name, (first, last) in functions(gen.source).items():
        if first <= line <= last:
            return name
    return re.search(rf"\b({gen.prefix}_\w+)\s*[\[=(]", text).group(1)


def check(gen: GeneratedObserver, found: list[tuple[str, int, str]]) -> collections.Counter:
    """The MISRA assertions of one observer; returns the findings counted by rule."""
    rules = collections.Counter(rule for _, _, rule in found)
    assert set(rules) <= set(CATEGORY), f"cppcheck findings that are no MISRA C:2012 rule: {rules}"
    required = {r: n for r, n in rules.items() if CATEGORY[r] in ("Mandatory", "Required")}
    assert not required, f"{gen.prefix} ({gen.real}, {gen.method}): mandatory/required findings {required}: " + \
        "; ".join(f"{f}:{n} rule {r}" for f, n, r in found if r in required)
    recorded = deviations(gen.prefix, gen.header, gen.source)
    reported = {(d.rule, w) for d in recorded if d.reported for w in d.where}
    seen = {(rule, where(gen, file, line)) for file, line, rule in found}
    assert seen <= reported, f"findings missing from the deviation record: {sorted(seen - reported)}"
    assert reported <= seen, f"deviations that cppcheck does not report: {sorted(reported - seen)}"
    assert any(file.endswith(".h") for file, _, _ in found)  # the header was analysed too
    rows = {row.split(" | ")[0].removeprefix("| Rule ").removeprefix("| "): row
            for row in gen.misra.splitlines() if row.startswith("| ") and " | Advisory | " in row}
    for rule, ident in seen:
        assert f"`{ident}`" in rows[rule], (rule, ident)
    assert not identifier_clashes(gen.prefix, gen.header, gen.source)
    return rules


# ----------------------------------------------------------------------------- default run: abs-xbs3
@pytest.fixture(scope="module")
def xbs3_runs(tmp_path_factory) -> dict[tuple[str, str], tuple[GeneratedObserver, list]]:
    tmp = tmp_path_factory.mktemp("misra")
    exe = cppcheck(tmp)
    runs = {}
    for real in REALS:
        for method, h_max in STEPS:
            gen = builtin("abs-xbs3", real, method, h_max)
            runs[(real, _label(method, h_max))] = (gen, findings(exe, gen, tmp / f"{real}-{method}-{h_max is None}"))
    return runs


@pytest.mark.parametrize("real", REALS)
@pytest.mark.parametrize("step", [_label(m, h) for m, h in STEPS])
def test_abs_xbs3_has_no_required_finding_and_its_advisory_ones_are_recorded(xbs3_runs, real, step):
    gen, found = xbs3_runs[(real, step)]
    rules = check(gen, found)
    assert set(rules) == {"2.5", "8.7", "15.5"}  # what stays, each a deviation of the record


def docs_table(runs: dict) -> list[str]:
    """The table of docs/codegen.md: cppcheck's findings on abs-xbs3 by category and rule."""
    advisory = sorted({r for _, found in runs.values() for _, _, r in found},
                      key=lambda r: tuple(map(int, r.split("."))))
    lines = ["| real | method | mandatory | required | " + " | ".join(f"advisory {r}" for r in advisory) + " |",
             "| --- | --- | ---: | ---: | " + " | ".join("---:" for _ in advisory) + " |"]
    for (real, step), (_, found) in runs.items():
        count = collections.Counter(r for _, _, r in found)
        by = collections.Counter(CATEGORY[r] for r in count.elements())
        lines.append(f"| {real} | {step} | {by['Mandatory']} | {by['Required']} | "
                     + " | ".join(str(count[r]) for r in advisory) + " |")
    return lines


def test_docs_misra_table_is_a_fresh_cppcheck_run(xbs3_runs):
    page = (ROOT / "docs" / "codegen.md").read_text("utf-8")
    block = re.search(r"<!-- misra:abs-xbs3 .*?-->\n(.*?)\n<!-- /misra:abs-xbs3 -->", page, flags=re.S)
    assert block, "docs/codegen.md has no <!-- misra:abs-xbs3 --> block"
    fresh = "\n".join(docs_table(xbs3_runs))
    assert block.group(1) == fresh, f"docs/codegen.md's MISRA table differs from a fresh run; it is now:\n{fresh}"


def test_record_and_readme_name_the_deviations_and_a_long_prefix_breaks_rule_5_1():
    gen = builtin("abs-xbs3", "float", "radau3")
    assert f"{gen.prefix}_misra.md" in gen.files and gen.files[f"{gen.prefix}_misra.md"] == gen.misra
    summary = gen.readme.split("## MISRA C:2012")[1].split("\n## ")[0]
    assert f"`{gen.prefix}_misra.md`" in summary
    for d in deviations(gen.prefix, gen.header, gen.source):
        assert re.search(rf"(rule|Dir) {re.escape(d.rule.removeprefix('Dir '))} \(advisory\)", summary), d.rule
    assert "Not met" not in gen.misra
    m = builtin_model("abs-xbs3")
    long = generate_observer(m, design(m, SPECTRA["abs-xbs3"]), prefix="p" * 27)
    assert ("5.1", f"{'p' * 27}_run", f"{'p' * 27}_run_dt") in identifier_clashes(long.prefix, long.header, long.source)
    assert "**Not met (required):**" in long.misra and "at most 26 characters" in long.misra
    assert "except rule 5.1" in long.readme
    ok = generate_observer(m, design(m, SPECTRA["abs-xbs3"]), prefix="p" * 26)
    assert not identifier_clashes(ok.prefix, ok.header, ok.source)


@pytest.mark.parametrize("name, real, method, h_max", [
    ("abs-xbs3", "double", "radau3", None), ("abs-xbs3", "float", "radau3", None),
    ("abs-xbs3", "double", "rk4", "1/100"),
    ("user", "double", "midpoint", None), ("super-twisting", "float", "euler", None)])
def test_ranged_build_has_no_required_finding_and_its_advisory_ones_are_recorded(tmp_path, name, real, method, h_max):
    """The proved build (declared ranges of every input: range checks, the det floor before the one division,
    the sub-step's state checks, next initialised, the zero-row range checks) is MISRA-checked like the
    unranged one, the user model (whose d and b divide by signals) and the super-twisting observer too."""
    from switchobs.report._repro_target import proved_observer

    gen = proved_observer(name, method, real, h_max)
    assert f"{gen.prefix}_proof.c" in gen.files
    assert (f"{gen.prefix.upper()}_DET_FLOOR" in gen.header) == (method in ("radau3", "midpoint"))
    rules = check(gen, findings(cppcheck(tmp_path), gen, tmp_path))
    assert set(rules) <= {"2.5", "8.7", "15.5"}


# ----------------------------------------------------------------------------- the rest of the matrix
def _matrix() -> list[tuple[str, str, str, str | None]]:
    cases = [(name, real, method, h_max) for name in ("abs-xbs4", "abs-adaptive2", "user")
             for real in REALS for method, h_max in STEPS]
    cases += [(kind, real, "rk4" if kind == "adaptive" else "euler", h_max) for kind in ("adaptive", "super-twisting", "vehicle-speed")
              for real in REALS for h_max in ((None, "1/50") if kind == "adaptive" else (None,))]
    return cases


@pytest.mark.slow
@pytest.mark.parametrize("name, real, method, h_max", _matrix())
def test_matrix_has_no_required_finding_and_its_advisory_ones_are_recorded(tmp_path, name, real, method, h_max):
    exe = cppcheck(tmp_path)
    if name == "user":
        gen = user(real, method, h_max)
    elif name == "adaptive":
        gen = adaptive(real, h_max)
    elif name == "super-twisting":
        gen = generate_super_twisting(400.0, 2000.0, real=real)
    elif name == "vehicle-speed":
        gen = generate_vehicle_speed(24.0, real=real)
    else:
        gen = builtin(name, real, method, h_max)
    rules = check(gen, findings(exe, gen, tmp_path))
    assert set(rules) <= {"2.5", "8.7", "15.5"}


# ----------------------------------------------------------------------------- the type model keeps every value
SPECIAL = (math.nan, math.inf, -math.inf, 0.0, -0.0, 1.0, -1.0, 2.5, 1e-30)


@pytest.mark.parametrize("real", REALS)
def test_boolean_temporaries_give_casadi_s_value_for_every_input(real):
    """The rewritten comparisons (<= and >= for == and !=, bool temporaries, a real tested for truth) give what
    casadi's own evaluation gives, on NaN, infinities and signed zeros too."""
    x = ca.SX.sym("x", 2)
    out = ca.vertcat(x[0] < x[1], x[0] <= x[1], x[0] == x[1], x[0] != x[1], ca.logic_not(x[0]),
                     ca.if_else(x[0], x[1], 3.0), ca.if_else(x[0] > x[1], x[0], -x[1]),
                     ca.if_else(x[0] == 0, 1.0, x[1]), (x[0] < x[1]) * x[1] + ca.logic_not(x[1]))
    k = kernel("k", [("x", x)], out, real=real, prefix="p")
    assert not re.search(r"[!=]=", k.body)
    source = (f"#include <math.h>\n#include <stdbool.h>\ntypedef {real} p_real;\n{k.body}\n"
              "void k_eval(const p_real *x, p_real *out);\n"
              "void k_eval(const p_real *x, p_real *out) { k(x, out); }\n")
    lib = ctypes.CDLL(str(compile_sources({"k.c": source}, ("k.c",), f"misra_bool_{real}",
                                          flags=("-std=c99", "-O2", "-fPIC", "-shared"))))
    ctype, dtype = (ctypes.c_double, np.float64) if real == "double" else (ctypes.c_float, np.float32)
    lib.k_eval.argtypes = [ctypes.POINTER(ctype), ctypes.POINTER(ctype)]
    fn = ca.Function("f", [x], [out])
    for a, b in itertools.product(SPECIAL, SPECIAL):
        xs = np.array([a, b], dtype=dtype)
        res = np.zeros(out.numel(), dtype=dtype)
        lib.k_eval(xs.ctypes.data_as(ctypes.POINTER(ctype)), res.ctypes.data_as(ctypes.POINTER(ctype)))
        ref = np.asarray(fn(xs.astype(float))).ravel().astype(dtype)
        assert np.array_equal(res, ref, equal_nan=True), (a, b, res, ref)
        assert np.array_equal(np.signbit(res), np.signbit(ref)), (a, b, res, ref)


# ----------------------------------------------------------------------------- clang-tidy narrowing, float
@pytest.mark.parametrize("name, method, h_max", [("abs-xbs3", "radau3", "1/100"), ("abs-xbs4", "rk4", None),
                                                 ("abs-adaptive2", "rk4", "1/50")])
def test_float_variants_have_no_narrowing_conversion_for_clang_tidy(tmp_path, name, method, h_max):
    """clang-tidy's narrowing checks (bugprone- and cppcoreguidelines-narrowing-conversions) on the float C."""
    exe = shutil.which("clang-tidy")
    if exe is None:
        message = ("!!! clang-tidy is NOT INSTALLED: the float C was NOT checked for narrowing conversions; "
                   "as root on Debian: apt-get install -y clang-tidy !!!")
        warnings.warn(message)
        pytest.skip(message)
    gen = adaptive("float", h_max) if name == "abs-adaptive2" else builtin(name, "float", method, h_max)
    gen.write(tmp_path)
    proc = subprocess.run([exe, "-checks=-*,bugprone-narrowing-conversions,cppcoreguidelines-narrowing-conversions",
                           "--warnings-as-errors=*", f"{gen.prefix}.c", "--", "-std=c99"], cwd=tmp_path,
                          capture_output=True, text=True, check=False, timeout=300)
    assert proc.returncode == 0 and "warning:" not in proc.stdout, proc.stdout + proc.stderr
