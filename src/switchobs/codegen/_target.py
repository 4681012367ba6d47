"""Targets of the generated C: build files, sizes and stack measured by building, processor-in-the-loop on qemu.

A :class:`Target` fixes what an ECU build fixes: the CPU and FPU flags, the real type (a Cortex-M4F has a
single-precision FPU only, so ``double`` there is refused: it would run in software floating point, tens of
times the instructions of the float step), and the flags every build uses (:data:`COMMON_FLAGS`: ``-ffp-contract=off`` so that no
multiply-add is fused and the target computes bit for bit what the host build and the Python reference
compute; ``-fno-math-errno`` so that ``sqrt`` is one FPU instruction, not a call into libm that sets
``errno``).  :func:`target_build` adds to a :class:`~switchobs.codegen.GeneratedObserver` a ``Makefile``
and a ``CMakeLists.txt`` that build the observer as a static library for the host and the target, and a
README section with the text, data and worst-case stack of every function measured by building it
(``arm-none-eabi-size``, ``-fstack-usage`` and ``-fcallgraph-info=su``) and the instructions of one step
counted on the emulator.

:func:`run_pil` is the processor-in-the-loop run: a bare-metal harness (``codegen/pil/``: vector table,
semihosting, a CMSDK timer) runs ``<prefix>_step`` over a record on ``qemu-system-arm`` (``mps2-an386``
with a Cortex-M4, ``mps2-an500`` with a Cortex-M7) and writes the status and the state of every row back;
the same harness built for the host (same flags but the CPU's, no ``-march=native``) gives the states to
compare bit for bit.  Instructions are counted with ``-icount shift=0`` (one instruction is one ns of
virtual time), read on timer 0 of the board (25 MHz: one tick per 40 instructions) around the whole record,
calibrated on a loop of known length, minus the same loop through an empty function.
"""

from __future__ import annotations

import dataclasses
import math
import re
import shutil
import subprocess
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from .._atomic import write_files
from .._json import JsonRecord
from .._limits import MAX_PIL_ROWS
from ..exceptions import CodegenError, DimensionError, PrerequisiteError
from ._observer import GeneratedObserver

__all__ = ["Target", "TARGETS", "COMMON_FLAGS", "WARNING_FLAGS", "TargetFootprint", "FunctionStack", "PilResult",
           "TargetBuild", "target_real", "build_files", "measure_footprint", "run_pil", "target_build"]

#: Flags of every build of the observer (library, harness, host and target).
COMMON_FLAGS: tuple[str, ...] = ("-std=c99", "-O2", "-ffp-contract=off", "-fno-math-errno")
#: The strict warnings the Cortex-M builds are checked with (``tests/test_codegen_target.py``).
WARNING_FLAGS: tuple[str, ...] = (
    "-Wall", "-Wextra", "-Wpedantic", "-Wconversion", "-Wsign-conversion", "-Wdouble-promotion", "-Wfloat-equal",
    "-Wshadow", "-Wundef", "-Wcast-qual", "-Wstrict-prototypes", "-Wmissing-prototypes")
_PIL_DIR = Path(__file__).resolve().parent / "pil"
#: Longest a harness may run on the emulator (a crashed one loops in its fault handler until then).
_QEMU_TIMEOUT_S = 120.0
#: Instructions of the calibration loop of ``pil_cortexm.c`` (1048576 iterations of subs + bne).
_CALIBRATION_INSTRUCTIONS = 2 * 1048576


@dataclass(frozen=True)
class Target:
    """A build target of the generated C.

    Attributes
    ----------
    name : str
        ``host``, ``cortex-m4f`` or ``cortex-m7``.
    description : str
    reals : tuple of str
        Real types the target computes in hardware; the first is its default.
    cpu_flags : tuple of str
        CPU, instruction set, FPU and float ABI flags (empty for the host: its default CPU, no
        ``-march=native``).
    compiler, size_tool : str
        The C compiler and the ``size`` of its binutils.
    machine, qemu_cpu : str or None
        The ``qemu-system-arm`` board and CPU of the processor-in-the-loop run (None: runs natively).
    refusal : str
        Why a real type outside ``reals`` is refused (one line).
    """

    name: str
    description: str
    reals: tuple[str, ...]
    cpu_flags: tuple[str, ...]
    compiler: str
    size_tool: str
    machine: str | None = None
    qemu_cpu: str | None = None
    refusal: str = ""

    @property
    def flags(self) -> tuple[str, ...]:
        """Every flag of the observer's build for this target."""
        return (*COMMON_FLAGS, *self.cpu_flags)

    @property
    def embedded(self) -> bool:
        return self.machine is not None


TARGETS: Mapping[str, Target] = {
    "host": Target("host", "the build machine (gcc, its default CPU)", ("double", "float"), (), "gcc", "size"),
    "cortex-m4f": Target(
        "cortex-m4f", "Arm Cortex-M4F, single-precision FPU (fpv4-sp-d16), hard-float ABI", ("float",),
        ("-mcpu=cortex-m4", "-mthumb", "-mfpu=fpv4-sp-d16", "-mfloat-abi=hard"), "arm-none-eabi-gcc",
        "arm-none-eabi-size", "mps2-an386", "cortex-m4",
        refusal="a Cortex-M4F has a single-precision FPU (fpv4-sp-d16): double would run in software floating "
                "point (tens of times the instructions of the float step, benchmarks/target.py); use --real "
                "float, or --target cortex-m7 for double"),
    "cortex-m7": Target(
        "cortex-m7", "Arm Cortex-M7, double-precision FPU (fpv5-d16), hard-float ABI", ("double", "float"),
        ("-mcpu=cortex-m7", "-mthumb", "-mfpu=fpv5-d16", "-mfloat-abi=hard"), "arm-none-eabi-gcc",
        "arm-none-eabi-size", "mps2-an500", "cortex-m7"),
}


def _target(target: Target | str) -> Target:
    if isinstance(target, Target):
        return target
    try:
        return TARGETS[target]
    except KeyError:
        raise CodegenError(f"unknown target {target!r}; choose one of {list(TARGETS)}") from None


def target_real(target: Target | str, real: str | None) -> str:
    """The real type of a build for ``target``: ``real``, or the target's default when None.

    Raises
    ------
    CodegenError
        ``real`` is not computed in hardware by the target (``double`` on a Cortex-M4F); the message says why
        and what to choose instead.

    Examples
    --------
    >>> target_real("cortex-m4f", None), target_real("cortex-m7", None), target_real("cortex-m7", "float")
    ('float', 'double', 'float')
    """
    t = _target(target)
    if real is None:
        return t.reals[0]
    if real not in t.reals:
        raise CodegenError(f"--real {real} is refused for --target {t.name}: {t.refusal}")
    return real


def _tool(name: str, package: str) -> str:
    path = shutil.which(name)
    if path is None:
        raise PrerequisiteError(f"{name} is not installed; install {package} (Debian: apt-get install {package}) "
                                "or build for --target host")
    return path


def _compiler(t: Target) -> str:
    return _tool(t.compiler, "gcc-arm-none-eabi libnewlib-arm-none-eabi" if t.embedded else "gcc")


def _run(cmd: Sequence[str], what: str, *, cwd: Path, timeout: float | None = None) -> str:
    try:
        proc = subprocess.run(list(cmd), cwd=cwd, capture_output=True, text=True, check=False, timeout=timeout)
    except subprocess.TimeoutExpired:
        raise CodegenError(f"{what} did not finish within {timeout:g} s ({' '.join(cmd[:3])} ...)") from None
    if proc.returncode != 0:
        lines = (proc.stderr or proc.stdout).strip().splitlines()
        raise CodegenError(f"{what} failed (exit {proc.returncode}): " + " | ".join(lines[:4]))
    return proc.stdout


# ----------------------------------------------------------------------------- build files
def build_files(gen: GeneratedObserver, target: Target | str) -> dict[str, str]:
    """``Makefile`` and ``CMakeLists.txt`` building ``lib<prefix>.a`` for the host and for ``target``.

    ``make`` builds for the host, ``make TARGET=<name>`` for a Cortex-M target; ``cmake -B build`` for the
    host, ``cmake -B build -DSWITCHOBS_TARGET=<name>`` for a Cortex-M target (the compiler set from it).

    Examples
    --------
    >>> from switchobs.codegen import generate_observer
    >>> from switchobs.model import builtin_model
    >>> gen = generate_observer(builtin_model("abs-xbs3"), ([84.0, -19.5, -21.3], [-16.0, -4.4, 21.3]), real="float")
    >>> files = build_files(gen, "cortex-m4f")
    >>> sorted(files), "CPU_FLAGS = -mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 -mfloat-abi=hard" in files["Makefile"]
    (['CMakeLists.txt', 'Makefile'], True)
    """
    t = _target(target)
    p = gen.prefix
    embedded = {n: x for n, x in TARGETS.items() if x.embedded}
    make = [
        f"# Builds lib{p}.a (generated by switchobs for target {t.name}; do not edit, regenerate).",
        f"#   make                        for {t.name if t.embedded else 'the host'} (TARGET={t.name})",
        "#   make TARGET=host            the host (gcc)",
        *[f"#   make TARGET={n:<15} {x.description}" for n, x in embedded.items()],
        "# -ffp-contract=off: no fused multiply-add, so every target computes what the host and the Python",
        "# reference compute; -fno-math-errno: sqrt is one FPU instruction.  Never -ffast-math (refused by #error).",
        f"TARGET ?= {t.name if t.embedded else 'host'}",
        f"COMMON_FLAGS = {' '.join(COMMON_FLAGS)}",
        "ifeq ($(TARGET),host)",
        "CC = gcc",
        "AR = ar",
        "CPU_FLAGS =",
        *[line for n, x in embedded.items() for line in (
            f"else ifeq ($(TARGET),{n})",
            f"CC = {x.compiler}",
            f"AR = {x.compiler.replace('gcc', 'ar')}",
            f"CPU_FLAGS = {' '.join(x.cpu_flags)}")],
        "else",
        "$(error unknown TARGET $(TARGET): host, " + ", ".join(embedded) + ")",
        "endif",
        "CFLAGS ?=",
        "",
        f"lib{p}.a: {p}.o",
        "\t$(AR) rcs $@ $^",
        "",
        f"{p}.o: {p}.c {p}.h",
        "\t$(CC) $(COMMON_FLAGS) $(CPU_FLAGS) $(CFLAGS) -c $< -o $@",
        "",
        ".PHONY: clean",
        "clean:",
        f"\trm -f {p}.o lib{p}.a",
        "",
    ]
    cmake = [
        f"# Builds the static library {p} (generated by switchobs for target {t.name}; do not edit, regenerate).",
        f"#   cmake -B build && cmake --build build                                   {t.name}",
        "#   cmake -B build -DSWITCHOBS_TARGET=host && cmake --build build           the host",
        "#   cmake -B build -DSWITCHOBS_TARGET=cortex-m4f && cmake --build build     a Cortex-M target",
        "cmake_minimum_required(VERSION 3.13)",
        f'set(SWITCHOBS_TARGET "{t.name if t.embedded else "host"}" CACHE STRING "host, {", ".join(embedded)}")',
        *[line for i, (n, x) in enumerate(embedded.items()) for line in (
            f'{"if" if i == 0 else "elseif"}(SWITCHOBS_TARGET STREQUAL "{n}")',
            f'  set(SWITCHOBS_CPU_FLAGS {" ".join(x.cpu_flags)})')],
        'elseif(NOT SWITCHOBS_TARGET STREQUAL "host")',
        '  message(FATAL_ERROR "unknown SWITCHOBS_TARGET ${SWITCHOBS_TARGET}")',
        "endif()",
        'if(NOT SWITCHOBS_TARGET STREQUAL "host")',
        "  # bare metal: no executable can be linked while CMake probes the compiler",
        "  set(CMAKE_SYSTEM_NAME Generic)",
        "  set(CMAKE_SYSTEM_PROCESSOR arm)",
        "  set(CMAKE_C_COMPILER arm-none-eabi-gcc)",
        "  set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)",
        "endif()",
        f"project({p} C)",
        f"add_library({p} STATIC {p}.c)",
        f"target_include_directories({p} PUBLIC ${{CMAKE_CURRENT_SOURCE_DIR}})",
        f"target_compile_options({p} PRIVATE {' '.join(COMMON_FLAGS)} ${{SWITCHOBS_CPU_FLAGS}})",
        "",
    ]
    return {"Makefile": "\n".join(make), "CMakeLists.txt": "\n".join(cmake)}


# ----------------------------------------------------------------------------- footprint
@dataclass(frozen=True)
class FunctionStack(JsonRecord, error=CodegenError):
    """Stack of one function of the observer's object: its own frame and the worst chain of calls from it.

    ``calls_out`` names functions outside the object it calls (libm), whose stack is not counted.
    """

    function: str
    frame_bytes: int
    worst_bytes: int
    calls_out: tuple[str, ...] = ()

    def to_json(self) -> dict[str, Any]:
        return {"function": self.function, "frame_bytes": self.frame_bytes, "worst_bytes": self.worst_bytes,
                "calls_out": list(self.calls_out)}


@dataclass(frozen=True)
class TargetFootprint(JsonRecord, error=CodegenError):
    """Sizes and stack of the observer's object file built for a target (``size``, ``-fstack-usage``).

    Attributes
    ----------
    target, real : str
    flags : tuple of str
        The flags of the build.
    compiler : str
        The compiler's ``--version`` first line.
    text_bytes, data_bytes, bss_bytes : int
        ``size`` of ``<prefix>.o`` (text includes the constant tables: default parameters, status texts).
    stack : tuple of FunctionStack
        Every function of the object (not inlined ones), in file order.
    """

    target: str
    real: str
    flags: tuple[str, ...]
    compiler: str
    text_bytes: int
    data_bytes: int
    bss_bytes: int
    stack: tuple[FunctionStack, ...]

    def worst(self, function: str) -> int:
        """Worst-case stack in bytes of a call of ``function`` (a suffix such as ``_step`` is enough)."""
        for f in self.stack:
            if f.function == function or f.function.endswith(function):
                return f.worst_bytes
        raise CodegenError(f"no function {function!r} in the object (functions: {[f.function for f in self.stack]})")

    def to_json(self) -> dict[str, Any]:
        out = {k: getattr(self, k) for k in ("target", "real", "compiler", "text_bytes", "data_bytes", "bss_bytes")}
        return {**out, "flags": list(self.flags), "stack": [s.to_json() for s in self.stack]}

    def __str__(self) -> str:
        return (f"{self.target} ({self.real}): text {self.text_bytes} B, data {self.data_bytes} B, bss "
                f"{self.bss_bytes} B; worst-case stack " +
                ", ".join(f"{f.function} {f.worst_bytes} B" for f in self.stack))


def _stack(su: str, ci: str) -> tuple[FunctionStack, ...]:
    """Frames from the ``.su`` file, worst chains from the call graph of ``-fcallgraph-info=su``."""
    frames: dict[str, int] = {}
    order: list[str] = []
    for line in su.splitlines():
        parts = line.split("\t")
        if len(parts) < 3:
            continue
        name = parts[0].rsplit(":", 1)[-1]
        if parts[2].strip() != "static":
            raise CodegenError(f"the frame of {name} is {parts[2].strip()} (not static): no bound can be stated")
        frames[name] = int(parts[1])
        order.append(name)
    edges: dict[str, set[str]] = {}
    title = lambda t: t.rsplit(":", 1)[-1]  # noqa: E731 - 'file.c:name' for static functions
    for m in re.finditer(r'edge: \{ sourcename: "([^"]+)" targetname: "([^"]+)"', ci):
        edges.setdefault(title(m.group(1)), set()).add(title(m.group(2)))

    def worst(name: str, seen: frozenset[str]) -> tuple[int, set[str]]:
        if name not in frames:
            return 0, {name}
        if name in seen:
            raise CodegenError(f"{name} is recursive: no stack bound")
        best, outside = 0, set()
        for callee in edges.get(name, ()):
            w, o = worst(callee, seen | {name})
            best = max(best, w)
            outside |= o
        return frames[name] + best, outside

    out = []
    for name in order:
        w, outside = worst(name, frozenset())
        out.append(FunctionStack(name, frames[name], w, tuple(sorted(outside))))
    return tuple(out)


def measure_footprint(gen: GeneratedObserver, target: Target | str, *,
                      step: tuple[str, str] | None = None) -> TargetFootprint:
    """Build ``<prefix>.c`` for ``target`` and measure text, data, bss and the stack of every function.

    ``step = (name, C text)`` measures that file instead (a step written by hand with the generated header's
    types, as ``benchmarks/target.py`` compares).

    Raises
    ------
    CodegenError
        The real type is not the target's (:func:`target_real`), or the build fails.
    PrerequisiteError
        The target's compiler or ``size`` is not installed.
    """
    t = _target(target)
    target_real(t, gen.real)
    cc, size = _compiler(t), _tool(t.size_tool, "binutils")
    with tempfile.TemporaryDirectory(prefix="switchobs-target-") as tmp:
        d = Path(tmp)
        files = {**gen.files, **({} if step is None else {"step.c": step[1]})}
        for name, text in files.items():
            (d / name).write_text(text, encoding="utf-8")
        source = f"{gen.prefix}.c" if step is None else "step.c"
        _run([cc, *t.flags, "-fstack-usage", "-fcallgraph-info=su", "-c", source, "-o", "obs.o"],
             f"{t.compiler} on {source}", cwd=d)
        sizes = _run([size, "obs.o"], t.size_tool, cwd=d).splitlines()[1].split()
        stack = _stack((d / "obs.su").read_text(), (d / "obs.ci").read_text())
        version = _run([cc, "--version"], t.compiler, cwd=d).splitlines()[0]
    return TargetFootprint(target=t.name, real=gen.real, flags=t.flags, compiler=version, text_bytes=int(sizes[0]),
                           data_bytes=int(sizes[1]), bss_bytes=int(sizes[2]), stack=stack)


# ----------------------------------------------------------------------------- processor in the loop
def _c_real(v: float, real: str) -> str:
    """An exact C literal of ``v`` (already of the real type): hexadecimal, or the math.h macro."""
    if math.isnan(v):
        return "NAN"
    if math.isinf(v):
        return "INFINITY" if v > 0 else "-INFINITY"
    return float(v).hex() + ("f" if real == "float" else "")


def _pil_sources(gen: GeneratedObserver, rows: np.ndarray, dts: np.ndarray, x0: np.ndarray,
                 step: tuple[str, str] | None) -> dict[str, str]:
    p, P = gen.prefix, gen.prefix.upper()
    step_name = f"{p}_step" if step is None else step[0]
    config = "\n".join([
        "/* The observer and the record of this processor-in-the-loop run (generated by switchobs). */",
        "#ifndef PIL_CONFIG_H", "#define PIL_CONFIG_H", f'#include "{p}.h"',
        f"typedef {p}_real pil_real;", f"#define PIL_NX {P}_NX", f"#define PIL_NS {P}_NS",
        f"#define PIL_ROWS {rows.shape[0]}", f"#define PIL_STEP {step_name}",
        f"int32_t {step_name}(pil_real *xhat, const pil_real *signals, const pil_real *params, pil_real dt);",
        "extern const pil_real pil_signals[PIL_ROWS * PIL_NS];", "extern const pil_real pil_dt[PIL_ROWS];",
        "extern const pil_real pil_x0[PIL_NX];", "#endif", ""])

    def array(name: str, size: str, values: np.ndarray) -> str:
        body = ",\n".join("    " + ", ".join(_c_real(float(v), gen.real) for v in values[i:i + 4])
                          for i in range(0, values.size, 4))
        return f"const pil_real {name}[{size}] = {{\n{body}\n}};"

    record = "\n".join(['#include <math.h>', '#include "pil_config.h"', "",
                        array("pil_signals", "PIL_ROWS * PIL_NS", rows.ravel()), array("pil_dt", "PIL_ROWS", dts),
                        array("pil_x0", "PIL_NX", x0), ""])
    harness = {name: (_PIL_DIR / name).read_text(encoding="utf-8")
               for name in ("pil_main.c", "pil_empty.c", "pil_host.c", "pil_cortexm.c", "pil_mps2.ld")}
    return {**gen.files, **harness, "pil_config.h": config, "pil_record.c": record,
            **({} if step is None else {"step.c": step[1]})}


def _parse_pil(text: str, gen: GeneratedObserver, n: int) -> tuple[np.ndarray, np.ndarray, dict[str, int]]:
    dtype = np.float32 if gen.real == "float" else np.float64
    counts: dict[str, int] = {}
    statuses, states = [], []
    for line in text.splitlines():
        parts = line.split()
        if not parts:
            continue
        if parts[0] in ("CAL", "RUN", "BASE"):
            counts[parts[0]] = int(parts[1], 16)
        elif parts[0] == "R":
            statuses.append(int(parts[1], 16) - (1 << 32 if int(parts[1], 16) >= 1 << 31 else 0))
            states.append(np.frombuffer(bytes.fromhex(parts[2]), dtype=dtype))
        elif parts[0] == "FAULT":
            raise CodegenError("the harness faulted on the target (a HardFault or UsageFault handler ran)")
    if len(states) != n or "END" not in text:
        raise CodegenError(f"the harness wrote {len(states)} of {n} rows; its output ends with {text[-200:]!r}")
    return np.array(statuses, dtype=np.int32), np.array(states).astype(np.float64), counts


@dataclass(frozen=True)
class PilResult(JsonRecord, error=CodegenError):
    """A processor-in-the-loop run: the record stepped on the emulated target and on the host.

    Attributes
    ----------
    target, real, prefix, machine : str
        The target, the real type, the observer and the emulated board (``qemu-system-arm -M``).
    rows : int
        Rows of the record (one ``<prefix>_step`` call each).
    target_status, host_status : tuple of int
        Status of every row on the target and on the host.
    target_states, host_states : tuple of tuple of float
        State after every row (the real type's values as float64; a refused row repeats the previous state).
    instructions_per_step : float
        Mean instructions of one ``_step`` call over the record on the emulator, beyond those of a call of an
        empty function of the same signature (``-icount shift=0``; resolution 40 instructions / rows).
    instructions_per_tick : float
        The calibrated ratio of instructions to timer ticks (40 on the MPS2 boards' 25 MHz timer).
    """

    target: str
    real: str
    prefix: str
    machine: str
    rows: int
    target_status: tuple[int, ...]
    host_status: tuple[int, ...]
    target_states: tuple[tuple[float, ...], ...]
    host_states: tuple[tuple[float, ...], ...]
    instructions_per_step: float
    instructions_per_tick: float

    @property
    def identical_rows(self) -> int:
        """Rows where target and host give the same status and the same state, bit for bit (NaN equals NaN)."""
        t, h = np.array(self.target_states), np.array(self.host_states)
        same = (t.view(np.uint64) == h.view(np.uint64)).all(axis=1)
        return int(np.sum(same & (np.array(self.target_status) == np.array(self.host_status))))

    @property
    def bit_identical(self) -> bool:
        return self.identical_rows == self.rows

    @property
    def refused_rows(self) -> int:
        return int(np.sum(np.array(self.target_status) != 0))

    def to_json(self) -> dict[str, Any]:
        return {k: [list(r) for r in v] if k.endswith("_states") else list(v) if isinstance(v, tuple) else v
                for k, v in dataclasses.asdict(self).items()}

    def __str__(self) -> str:
        return (f"processor in the loop: {self.prefix} ({self.real}) on {self.target} (qemu {self.machine}), "
                f"{self.rows} rows ({self.refused_rows} refused): {self.identical_rows}/{self.rows} rows "
                f"bit-identical to the host build; {self.instructions_per_step:.0f} instructions per step")


def _record(gen: GeneratedObserver, signal_rows: npt.ArrayLike, dt: npt.ArrayLike | float,
            x0: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    dtype = np.float32 if gen.real == "float" else np.float64
    rows = np.asarray(signal_rows, dtype=float)
    if rows.ndim != 2 or rows.shape[1] != gen.ns or rows.shape[0] == 0:
        raise DimensionError(f"the record must have rows of {gen.ns} signals ({', '.join(gen.signal_names)}), got "
                             f"shape {rows.shape}")
    if rows.shape[0] > MAX_PIL_ROWS:
        raise DimensionError(f"the record has {rows.shape[0]} rows (limit MAX_PIL_ROWS = {MAX_PIL_ROWS}: the harness "
                             "holds it in the board's memory); split it")
    try:
        dts = np.broadcast_to(np.asarray(dt, dtype=float), (rows.shape[0],))
    except ValueError:
        raise DimensionError(f"dt must be one number or one per row ({rows.shape[0]}), got shape "
                             f"{np.shape(dt)}") from None
    x = np.asarray(x0, dtype=float).reshape(-1)
    if x.shape != (gen.nx,):
        raise DimensionError(f"x0 must have {gen.nx} entries ({', '.join(gen.state_names)}), got {x.size}")
    with np.errstate(over="ignore"):  # out-of-range doubles become inf, which the step refuses
        return rows.astype(dtype), dts.astype(dtype), x.astype(dtype)


def qemu_arguments(target: Target | str) -> list[str]:
    """The ``qemu-system-arm`` options of the run (board, CPU, no display or monitor, one ns per instruction)."""
    t = _target(target)
    return ["-M", str(t.machine), "-cpu", str(t.qemu_cpu), "-display", "none", "-monitor", "none", "-serial", "none",
            "-icount", "shift=0"]


def run_pil(gen: GeneratedObserver, target: Target | str, signal_rows: npt.ArrayLike, dt: npt.ArrayLike | float,
            x0: npt.ArrayLike, *, step: tuple[str, str] | None = None) -> PilResult:
    """Run ``<prefix>_step`` over a record on the emulated target and on the host; return both.

    Parameters
    ----------
    gen : GeneratedObserver
    target : Target or str
        A Cortex-M target (:data:`TARGETS`).
    signal_rows : (N, NS) array
        One row of signals per step (rounded to the real type).
    dt : float or (N,) array
        Step length of every row in seconds.
    x0 : (NX,) array
        Initial state.
    step : (name, C text), optional
        Run that function instead of ``<prefix>_step`` (same signature; a step written by hand, compiled with
        the generated files, as ``benchmarks/target.py`` compares).

    Returns
    -------
    PilResult

    Raises
    ------
    CodegenError
        Not a Cortex-M target, the real type refused there, a build that fails, or a harness that faults or
        does not finish.
    PrerequisiteError
        ``arm-none-eabi-gcc``, ``gcc`` or ``qemu-system-arm`` is not installed.
    DimensionError
        Rows, ``dt`` or ``x0`` of the wrong shape.
    """
    t = _target(target)
    if not t.embedded:
        raise CodegenError(f"the processor-in-the-loop run needs a Cortex-M target ({[n for n in TARGETS if n != 'host']}), "
                           f"got {t.name!r}")
    target_real(t, gen.real)
    rows, dts, x = _record(gen, signal_rows, dt, x0)
    cc, host_cc = _compiler(t), _tool("gcc", "gcc")
    qemu = _tool("qemu-system-arm", "qemu-system-arm")
    n = rows.shape[0]
    with tempfile.TemporaryDirectory(prefix="switchobs-pil-") as tmp:
        d = Path(tmp)
        for name, text in _pil_sources(gen, rows, dts, x, step).items():
            (d / name).write_text(text, encoding="utf-8")
        common = ["pil_main.c", "pil_empty.c", "pil_record.c", f"{gen.prefix}.c", *([] if step is None else ["step.c"])]
        _run([cc, *t.flags, "-Wall", "-Wextra", "-Werror", "-nostartfiles", "-T", "pil_mps2.ld", "-Wl,--gc-sections",
              *common, "pil_cortexm.c", "-lm", "-o", "pil.elf"], f"{t.compiler} (harness)", cwd=d)
        _run([host_cc, *COMMON_FLAGS, "-Wall", "-Wextra", "-Werror", *common, "pil_host.c", "-lm", "-o", "pil_host"],
             "gcc (host harness)", cwd=d)
        # the semihosting console into a file: qemu writes it to stderr or stdout depending on what they are
        try:
            _run([qemu, *qemu_arguments(t), "-chardev", "file,id=pil,path=pil.out", "-semihosting-config",
                  "enable=on,target=native,chardev=pil", "-kernel", "pil.elf"], f"qemu-system-arm -M {t.machine}",
                 cwd=d, timeout=_QEMU_TIMEOUT_S)
        finally:
            out = (d / "pil.out").read_text(encoding="ascii", errors="replace") if (d / "pil.out").exists() else ""
            if "FAULT" in out:
                raise CodegenError(f"the harness faulted on {t.name} (qemu {t.machine}): a HardFault, MemManage, "
                                   "BusFault or UsageFault handler ran after "
                                   f"{out.count(chr(10) + 'R ')} rows were written") from None
        host = _run([str(d / "pil_host")], "the host harness", cwd=d, timeout=_QEMU_TIMEOUT_S)
    t_status, t_states, counts = _parse_pil(out, gen, n)
    h_status, h_states, _ = _parse_pil(host, gen, n)
    # the tick count of the calibration loop is truncated: 2^21 instructions in 52429 ticks is 39.9998
    per_tick = round(_CALIBRATION_INSTRUCTIONS / counts["CAL"], 2)
    return PilResult(target=t.name, real=gen.real, prefix=gen.prefix, machine=str(t.machine), rows=n,
                     target_status=tuple(map(int, t_status)), host_status=tuple(map(int, h_status)),
                     target_states=tuple(map(tuple, t_states.tolist())), host_states=tuple(map(tuple, h_states.tolist())),
                     instructions_per_step=(counts["RUN"] - counts["BASE"]) * per_tick / n,
                     instructions_per_tick=per_tick)


# ----------------------------------------------------------------------------- the files for a target
def default_record(gen: GeneratedObserver, *, rows: int = 200) -> tuple[np.ndarray, float, np.ndarray]:
    """Signals for counting instructions when no record is given: ``rows`` rows alternating the sign of the
    measured output (both gains), the other signals 1 (-1 where declared negative), ``dt`` 1 ms, state 0.

    The step is straight-line code but for its checks, the gain switch and sub-steps, so the count hardly
    depends on the values; a record of your own gives the figure for your signals (:func:`run_pil`).
    """
    signs = [-1.0 if any(g.expr.is_Symbol and g.expr.name == s and g.kind == "negative" for g in gen.guards)
             else 1.0 for s in gen.signal_names]
    out = np.tile(np.array(signs), (rows, 1))
    out[:, 0] = np.where(np.arange(rows) % 2 == 0, 0.5, -0.5)
    return out, 1e-3, np.zeros(gen.nx)


@dataclass(frozen=True)
class TargetBuild:
    """The generated observer for one target: its files, the build files, the README with the measured figures.

    Attributes
    ----------
    generated : GeneratedObserver
    target : str
    footprint : TargetFootprint
    pil : PilResult or None
        The run that counted the instructions (Cortex-M targets).
    record : str
        What the instructions were counted over.
    """

    generated: GeneratedObserver
    target: str
    footprint: TargetFootprint
    pil: PilResult | None = None
    record: str = ""

    @property
    def readme(self) -> str:
        return self.generated.readme.rstrip("\n") + "\n\n" + "\n".join(target_section(self)) + "\n"

    @property
    def files(self) -> dict[str, str]:
        return {**self.generated.files, **build_files(self.generated, self.target), "README.md": self.readme}

    def write(self, directory: str | Path) -> tuple[Path, ...]:
        """Write every file into ``directory``: all or none (:func:`switchobs._atomic.write_files`)."""
        return write_files(directory, self.files, what="the generated C into")

    def __str__(self) -> str:
        lines = [str(self.generated), f"  target: {self.footprint}"]
        if self.pil is not None:
            lines.append(f"  instructions per step on qemu {self.pil.machine}: {self.pil.instructions_per_step:.0f} "
                         f"({self.record})")
        return "\n".join(lines)


def target_section(build: TargetBuild) -> list[str]:
    """The README section "On the target": flags, sizes, stack per function, instructions per step."""
    t, f, p = TARGETS[build.target], build.footprint, build.generated.prefix
    out = [f"## On the target: {t.name}", "",
           f"{t.description}; real type `{f.real}`.  Built with `{f.compiler}`:", "",
           "```sh", f"{t.compiler} {' '.join(t.flags)} -c {p}.c", "```", "",
           "`make` / `make TARGET=<target>` or `cmake` (the `Makefile` and `CMakeLists.txt` next to this file) build "
           f"`lib{p}.a` the same way.  `-ffp-contract=off` keeps every multiply-add unfused, so the target computes "
           "what the host build and the Python reference compute; `-fno-math-errno` makes `sqrt` one FPU "
           "instruction (the step never reads `errno`).", "",
           f"Measured by building `{p}.c` (`{t.size_tool}`, `-fstack-usage`, `-fcallgraph-info=su`): text "
           f"{f.text_bytes} B (code and constant tables), data {f.data_bytes} B, bss {f.bss_bytes} B.", "",
           "| function | own frame B | worst-case stack of a call B |", "| --- | ---: | ---: |",
           *[f"| `{s.function}` | {s.frame_bytes} | {s.worst_bytes}"
             + (f" + {', '.join(f'`{c}`' for c in s.calls_out)} (libm)" if s.calls_out else "") + " |"
             for s in f.stack], ""]
    if build.pil is not None:
        out += [f"Instructions per `{p}_step` call on `qemu-system-arm -M {build.pil.machine} -cpu {t.qemu_cpu} "
                f"-icount shift=0`: **{build.pil.instructions_per_step:.0f}** (mean over {build.record}; beyond a "
                "call of an empty function; qemu counts instructions, not cycles).", ""]
    elif t.embedded:
        out += ["Instructions per step: not counted (no emulator run).", ""]
    else:
        out += ["Instructions per step: counted only on the emulated Cortex-M targets.", ""]
    return out


def target_build(gen: GeneratedObserver, target: Target | str, *, count_instructions: bool = True,
                 record: tuple[npt.ArrayLike, npt.ArrayLike | float, npt.ArrayLike] | None = None,
                 record_description: str | None = None) -> TargetBuild:
    """The files of ``gen`` for ``target``: build files and the README section with the measured figures.

    Parameters
    ----------
    gen : GeneratedObserver
        Generated with the target's real type (:func:`target_real`).
    target : Target or str
    count_instructions : bool
        Count the instructions of a step on the emulator (Cortex-M targets; needs ``qemu-system-arm``).
    record : (signal_rows, dt, x0), optional
        What to count over; default :func:`default_record`.
    record_description : str, optional
        Says what the record is, in the README.

    Raises
    ------
    CodegenError, PrerequisiteError
        As :func:`measure_footprint` and :func:`run_pil`.
    """
    t = _target(target)
    footprint = measure_footprint(gen, t)
    pil, described = None, ""
    if t.embedded and count_instructions:
        rec = record if record is not None else default_record(gen)
        pil = run_pil(gen, t, *rec)
        described = record_description or (f"{pil.rows} rows" + ("" if record is not None else
                                                                   " of constant signals, the sign of y alternating"))
    return TargetBuild(gen, t.name, footprint, pil, described)
