"""The generated C on its targets: strict Cortex-M builds, hardware floating point, the build files, the sizes
and stack the README states, and the processor-in-the-loop run on qemu-system-arm over a braking record, bit
for bit against the host build and within the stated tolerance against the Python reference.

Each test needs a tool that `make cc-tools` installs (gcc-arm-none-eabi with newlib, qemu-system-arm, cmake
for one test); without it the test skips, saying loudly what was not checked.
"""

from __future__ import annotations

import functools
import re
import shutil
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from switchobs.codegen import (TARGETS, CObserver, GeneratedObserver, StepStatus, generate_observer, measure_footprint,
                               run_pil, target_build, target_real)
from switchobs.codegen._target import WARNING_FLAGS, build_files
from switchobs.design import design
from switchobs.exceptions import CodegenError
from switchobs.loop import PIL_SCENARIO, PIL_TOLERANCE, braking_record, compare_with_reference, reference_observer
from switchobs.model import builtin_model
from switchobs.observers import adaptive_xbs_observer, xbs3_observer, xbs4_observer

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = {"arm-none-eabi-gcc": "gcc-arm-none-eabi libnewlib-arm-none-eabi", "qemu-system-arm": "qemu-system-arm",
            "cmake": "cmake", "cppcheck": "cppcheck", "arm-none-eabi-nm": "gcc-arm-none-eabi", "newlib": "libnewlib-arm-none-eabi"}


def _missing(tool: str) -> bool:
    if tool == "newlib":  # the harness links newlib's libm: the cross compiler alone does not bring it
        return shutil.which("arm-none-eabi-gcc") is None or "/" not in subprocess.run(
            ["arm-none-eabi-gcc", "-print-file-name=libm.a"], capture_output=True, text=True, check=False).stdout
    return shutil.which(tool) is None


def need(*tools: str) -> None:
    """A loud skip when a tool is missing: the check is NOT made."""
    for tool in (*tools, *(("newlib",) if "qemu-system-arm" in tools else ())):
        if _missing(tool):
            message = (f"!!! {tool} is NOT INSTALLED: the generated C was NOT checked on its target; run `make "
                       f"cc-tools` (as root on Debian: apt-get install -y {PACKAGES.get(tool, tool)}) !!!")
            warnings.warn(message)
            pytest.skip(message)


#: The observers of the runs: (reference, real, target, initial state of the record).
CASES = {
    "abs-xbs3-radau3-float-m4f": (lambda: xbs3_observer(100.0, 100.0, method="radau3"), "float", "cortex-m4f",
                                  {"z2": 0.5}),
    "abs-xbs4-radau3-double-m7": (lambda: xbs4_observer(10.0, 20.0, method="radau3"), "double", "cortex-m7",
                                  {"z2": 0.5}),
    "abs-adaptive2-rk4-float-m4f": (lambda: adaptive_xbs_observer(100.0, [1e4, 1e4]), "float", "cortex-m4f",
                                    {"c": 30.0, "d": 15.0}),
    # sub-stepped: the step calls libm's ceilf on the M4F (newlib's), the host glibc's: both exact
    "abs-xbs3-rk4-substeps-float-m4f": (lambda: substepped_reference(), "float", "cortex-m4f", {"z2": 0.5}),
}


def substepped_reference():
    model = builtin_model("abs-xbs3")
    gen = generate_observer(model, design(model, "-100,-100,-100"), real="float", h_max="1/100")
    return reference_observer(model, gen)


@functools.cache
def case(name: str):
    make, real, target, initial = CASES[name]
    ref = make()
    gen = CObserver.like(ref, real=real).generated
    return ref, gen, target, initial


@functools.cache
def record(name: str):
    ref, _, _, initial = case(name)
    return braking_record(ref, initial_state=initial)


@functools.cache
def pil(name: str):
    _, gen, target, _ = case(name)
    rec = record(name)
    return run_pil(gen, target, rec.rows, rec.dt, rec.x0)


def cross_compile(gen: GeneratedObserver, target: str, flags: list[str], tmp: Path) -> subprocess.CompletedProcess:
    gen.write(tmp)
    cmd = ["arm-none-eabi-gcc", *TARGETS[target].flags, *flags, "-c", str(tmp / f"{gen.prefix}.c"), "-o",
           str(tmp / "obs.o")]
    return subprocess.run(cmd, capture_output=True, text=True, check=False)


# ----------------------------------------------------------------------------- builds
@pytest.mark.parametrize("name", sorted(CASES))
def test_cortex_m_build_is_clean_with_the_strict_warnings(tmp_path, name):
    # -Wfloat-equal included: the MISRA emitter writes casadi's truth tests as ordered comparisons
    need("arm-none-eabi-gcc")
    _, gen, target, _ = case(name)
    proc = cross_compile(gen, target, ["-Werror", *WARNING_FLAGS], tmp_path)
    assert proc.returncode == 0, proc.stderr


@pytest.mark.parametrize("name", ["abs-xbs3-radau3-float-m4f", "abs-xbs4-radau3-double-m7"])
def test_the_step_uses_the_fpu_not_software_floating_point(tmp_path, name):
    """No call of the run-time library's soft-float routines (__aeabi_dmul...): every operation is an FPU one."""
    need("arm-none-eabi-gcc", "arm-none-eabi-nm")
    _, gen, target, _ = case(name)
    assert cross_compile(gen, target, [], tmp_path).returncode == 0
    undefined = subprocess.run(["arm-none-eabi-nm", "-u", str(tmp_path / "obs.o")], capture_output=True, text=True,
                               check=True).stdout.split()
    soft_float = re.compile(r"__aeabi_(?:d|f|[iul]+2[fd])")
    assert not [s for s in undefined if soft_float.match(s)], undefined
    # the same observer in double on the Cortex-M4F calls them: the reason the target refuses double
    double = CObserver.like(case(name)[0], real="double").generated
    (tmp_path / "dbl").mkdir()
    assert cross_compile(double, "cortex-m4f", [], tmp_path / "dbl").returncode == 0
    soft = subprocess.run(["arm-none-eabi-nm", "-u", str(tmp_path / "dbl" / "obs.o")], capture_output=True,
                          text=True, check=True).stdout
    assert "__aeabi_dmul" in soft and "__aeabi_dadd" in soft


def test_double_is_refused_on_the_single_precision_fpu():
    assert target_real("cortex-m4f", None) == "float" and target_real("cortex-m7", None) == "double"
    assert target_real("cortex-m7", "float") == "float" and target_real("host", "double") == "double"
    with pytest.raises(CodegenError, match=r"single-precision FPU.*software floating point.*--real float"):
        target_real("cortex-m4f", "double")
    proc = subprocess.run([sys.executable, "-m", "switchobs.cli.main", "codegen", "abs-xbs3", "--spectrum",
                           "-40,-60,-60", "--target", "cortex-m4f", "--real", "double", "--out", "unused"],
                          capture_output=True, text=True, check=False, cwd=ROOT)
    assert proc.returncode == 2 and len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    assert "--real double is refused for --target cortex-m4f" in proc.stderr and not (ROOT / "unused").exists()


def test_readme_states_the_sizes_and_stack_measured_by_building(tmp_path):
    """The README's figures are those of an independent build of the same file (size, -fstack-usage)."""
    need("arm-none-eabi-gcc", "qemu-system-arm")
    _, gen, target, _ = case("abs-xbs3-radau3-float-m4f")
    build = target_build(gen, target)
    assert cross_compile(gen, target, ["-fstack-usage"], tmp_path).returncode == 0
    text, data, bss = map(int, subprocess.run(["arm-none-eabi-size", str(tmp_path / "obs.o")], capture_output=True,
                                              text=True, check=True).stdout.splitlines()[1].split()[:3])
    frames = {line.split("\t")[0].rsplit(":", 1)[-1]: int(line.split("\t")[1])
              for line in (tmp_path / "obs.su").read_text().splitlines()}
    f = build.footprint
    assert (f.text_bytes, f.data_bytes, f.bss_bytes) == (text, data, bss) and data == bss == 0
    p = gen.prefix
    assert f.worst("_step") == frames[f"{p}_step"] + frames[f"{p}_rows"] > frames[f"{p}_rows"]
    assert f"text {text} B" in build.readme and f"| `{p}_step` | {frames[f'{p}_step']} | {f.worst('_step')} |" \
        in build.readme
    assert f"**{build.pil.instructions_per_step:.0f}**" in build.readme and "## On the target: cortex-m4f" in build.readme
    assert 100 < build.pil.instructions_per_step < 2000 and build.pil.instructions_per_tick == 40.0
    assert set(build.files) == {*gen.files, "Makefile", "CMakeLists.txt"}


def test_build_files_build_the_static_library_for_host_and_target(tmp_path):
    need("arm-none-eabi-gcc", "cmake")
    _, gen, target, _ = case("abs-xbs4-radau3-double-m7")
    gen.write(tmp_path)
    for name, text in build_files(gen, target).items():
        (tmp_path / name).write_text(text)
    lib = f"lib{gen.prefix}.a"
    for make_target in ("host", "cortex-m7"):
        subprocess.run(["make", "-s", "clean"], cwd=tmp_path, check=True)
        proc = subprocess.run(["make", "-s", f"TARGET={make_target}"], cwd=tmp_path, capture_output=True, text=True,
                              check=False)
        assert proc.returncode == 0 and (tmp_path / lib).exists(), proc.stderr
        kind = subprocess.run(["file", "-b", str(tmp_path / f"{gen.prefix}.o")], capture_output=True, text=True,
                              check=False).stdout if shutil.which("file") else ""
        assert not kind or ("ARM" in kind) == (make_target != "host"), kind
    attrs = subprocess.run(["arm-none-eabi-readelf", "-A", str(tmp_path / f"{gen.prefix}.o")], capture_output=True,
                           text=True, check=True).stdout
    assert "Tag_ABI_VFP_args: VFP registers" in attrs and "FPv5/FP-D16" in attrs, attrs
    build = tmp_path / "cmake-build"
    for cmd in (["cmake", "-S", str(tmp_path), "-B", str(build), "-DSWITCHOBS_TARGET=cortex-m4f"],
                ["cmake", "--build", str(build)]):
        proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
        assert proc.returncode == 0, proc.stdout + proc.stderr
    assert (build / lib).exists()


# ----------------------------------------------------------------------------- processor in the loop
def test_the_record_comes_from_a_braking_with_both_signs_a_road_change_and_a_refused_step():
    rec = record("abs-xbs3-radau3-float-m4f")
    y = rec.rows[:, 0]
    t = np.cumsum(rec.dt)
    change = PIL_SCENARIO.roads.changes[0].at_time_s
    assert np.sum(y > 0) > 100 and np.sum(y < 0) > 100
    assert t[0] < change < t[-1] and np.all(rec.rows[:, 1] > 0)
    assert np.sum(np.isnan(y)) == 1


@pytest.mark.parametrize("name", sorted(CASES))
def test_pil_on_qemu_is_bit_identical_to_the_host_build_and_close_to_the_reference(name):
    """qemu-system-arm (mps2-an386 Cortex-M4 / mps2-an500 Cortex-M7) against gcc on the host, same source, same
    flags but the CPU's (-ffp-contract=off, no -march=native), and against the Python reference in double."""
    need("arm-none-eabi-gcc", "qemu-system-arm")
    ref, gen, target, _ = case(name)
    rec, res = record(name), pil(name)
    assert res.rows == rec.rows.shape[0] and res.bit_identical, f"{res.identical_rows}/{res.rows} rows"
    dropout = int(np.flatnonzero(np.isnan(rec.rows[:, 0]))[0])
    assert res.target_status[dropout] == StepStatus.NONFINITE_SIGNAL and res.refused_rows == 1
    assert res.target_states[dropout] == res.target_states[dropout - 1]  # the refused step left the state
    cmp = compare_with_reference(res, ref, rec.rows, rec.dt, rec.x0)
    assert cmp.status_equal and cmp.max_relative_error <= PIL_TOLERANCE[gen.real], cmp
    assert cmp.passed
    # the states are not trivially equal: the observer moved through the record
    states = np.array(res.target_states)
    assert np.ptp(states[:, 0]) > 1.0 and np.all(np.isfinite(states))
    assert 100 < res.instructions_per_step < 3000
    if gen.h_max is not None:  # some rows of the record take sub-steps, and the step calls ceilf
        assert any(abs(r[0] / r[1]) * h > gen.h_max_c for r, h in zip(rec.rows, rec.dt) if np.isfinite(r[0]))
        step = [f for f in measure_footprint(gen, target).stack if f.function.endswith("_step")][0]
        assert step.calls_out == ("ceilf",) and step.worst_bytes > step.frame_bytes


def test_a_host_state_that_differs_in_one_bit_is_seen():
    """The bit-for-bit comparison is of the bits: one ulp in one row is a difference."""
    need("arm-none-eabi-gcc", "qemu-system-arm")
    res = pil("abs-xbs3-radau3-float-m4f")
    states = [list(r) for r in res.host_states]
    x = np.float32(states[10][1])
    states[10][1] = float(np.nextafter(x, np.float32(np.inf)))
    tweaked = type(res)(**{**res.__dict__, "host_states": tuple(map(tuple, states))})
    assert tweaked.identical_rows == res.rows - 1 and not tweaked.bit_identical


@pytest.mark.slow
def test_cli_pil_for_a_user_model_prints_the_comparison_and_the_instructions(tmp_path):
    """A user's own model (examples/my_model.toml: a drift d(y) = k y and b(y)) through `switchobs codegen
    --target cortex-m4f --pil`, on the braking record and on a CSV record of the user's."""
    need("arm-none-eabi-gcc", "qemu-system-arm")
    base = [sys.executable, "-m", "switchobs.cli.main", "codegen", str(ROOT / "examples" / "my_model.toml"),
            "--spectrum", "-40,-60,-60", "--method", "radau3", "--target", "cortex-m4f", "--pil"]
    proc = subprocess.run([*base, "--out", str(tmp_path / "a")], capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr
    out = proc.stdout
    assert re.search(r"(\d+)/\1 rows bit-identical to the host build", out), out
    assert "statuses equal to the Python reference's" in out and "PASSED" in out
    assert re.search(r"\d+ instructions per step", out) and "sensor dropout" in out
    readme = (tmp_path / "a" / "README.md").read_text()
    assert "## On the target: cortex-m4f" in readme and "braking" in readme
    csv = tmp_path / "rec.csv"
    csv.write_text("vx,y,u,dt\n" + "".join(f"{20 - k * 0.01},{(-1) ** k * 2.0},{50.0},0.001\n" for k in range(50))
                   + "0,1,1,0.001\n")
    proc = subprocess.run([*base, "--record", str(csv), "--json", "--out", str(tmp_path / "b")],
                          capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr
    data = __import__("json").loads(proc.stdout)
    assert data["pil"]["rows"] == data["pil"]["identical_rows"] == 51 and data["pil"]["status_equal"]
    assert data["pil"]["passed"] and data["target"]["instructions_per_step"] > 100
    assert data["target"]["footprint"]["text_bytes"] > 1000 and "51 rows of 'rec.csv'" in data["target"]["record"]
    bad = tmp_path / "bad.csv"
    bad.write_text("y,u\n1,2\n")
    proc = subprocess.run([*base, "--record", str(bad), "--out", str(tmp_path / "c")], capture_output=True,
                          text=True, check=False)
    assert proc.returncode == 2 and "missing ['vx']" in proc.stderr and not (tmp_path / "c").exists()


def test_pil_needs_a_cortex_m_target_and_a_record_of_the_right_shape():
    _, gen, _, _ = case("abs-xbs3-radau3-float-m4f")
    with pytest.raises(CodegenError, match="needs a Cortex-M target"):
        run_pil(gen, "host", np.ones((3, 3)), 1e-3, np.zeros(3))
    with pytest.raises(CodegenError, match="unknown target 'cortex-a53'"):
        run_pil(gen, "cortex-a53", np.ones((3, 3)), 1e-3, np.zeros(3))
    need("arm-none-eabi-gcc", "qemu-system-arm")
    with pytest.raises(Exception, match="rows of 3 signals"):
        run_pil(gen, "cortex-m4f", np.ones((3, 2)), 1e-3, np.zeros(3))
    with pytest.raises(CodegenError, match="single-precision FPU"):
        measure_footprint(CObserver.like(case("abs-xbs3-radau3-float-m4f")[0]).generated, "cortex-m4f")


@pytest.mark.slow
def test_docs_on_the_target_section_equals_a_fresh_run():
    """docs/codegen.md "On the target" (sizes, stack, instructions, PIL, MISRA) is what the runs give today."""
    need("arm-none-eabi-gcc", "qemu-system-arm", "cppcheck")
    from switchobs.experiments import Runs
    from switchobs.report._repro_target import TARGET_SECTIONS

    (name, page, section), = [s for s in TARGET_SECTIONS if s[0] == "on_the_target"]  # proof_status: its own
    text = (ROOT / page).read_text("utf-8")
    begin, end = f"<!-- begin generated: {name} (switchobs reproduce) -->", f"<!-- end generated: {name} -->"
    committed = text[text.index(begin):text.index(end)]
    fresh = "\n".join(section(Runs()))
    assert fresh in committed, "docs/codegen.md 'On the target' differs from a fresh run: run `switchobs reproduce`"
    assert "| abs-xbs3 | radau3 | float | cortex-m4f |" in fresh and "1510/1510" in fresh
    assert fresh.count(" | 0 / 0 / ") == 4  # no mandatory or required MISRA finding on any row


def test_a_step_that_faults_on_the_target_is_reported_not_hung():
    """A store to an address the board does not decode: the fault handler reports it, qemu exits, one error."""
    need("arm-none-eabi-gcc", "qemu-system-arm")
    _, gen, _, _ = case("abs-xbs3-radau3-float-m4f")
    bad = ("bad_step", f'#include <stdint.h>\n#include "{gen.prefix}.h"\n'
           "int32_t bad_step(float *x, const float *s, const float *p, float dt);\n"
           "int32_t bad_step(float *x, const float *s, const float *p, float dt)\n"
           "{ (void)x; (void)s; (void)p; (void)dt; *(volatile uint32_t *)0xF0000000u = 1u; return 0; }\n")
    with pytest.raises(CodegenError, match="the harness faulted on cortex-m4f"):
        run_pil(gen, "cortex-m4f", np.ones((4, 3)), 1e-3, np.zeros(3), step=bad)
