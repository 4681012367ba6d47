"""The "On the target" section of docs/codegen.md: the generated C built and run on the emulated Cortex-M targets.

Sizes, worst-case stack and instructions per step are measured, not estimated: the observer of the
processor-in-the-loop tests is built with each target's flags (``switchobs.codegen.TARGETS``) and stepped
over the braking record of ``switchobs.loop.braking_record`` on ``qemu-system-arm`` and on the host.  The
counts are exact for a given compiler and qemu (the section names both), so ``switchobs reproduce --check``
compares them with a fresh run like every generated section.
"""

from __future__ import annotations

import shutil
import subprocess
from typing import TYPE_CHECKING

from ..loop import braking_record, compare_with_reference
from ._markdown import md_table

if TYPE_CHECKING:
    from ..experiments import Runs

__all__ = ["TARGET_SECTIONS"]

#: (model, method, beta1, beta2, real, target) of the rows: the observers of tests/test_codegen_target.py.
ROWS = (("abs-xbs3", "radau3", 100.0, 100.0, "float", "cortex-m4f"),
        ("abs-xbs3", "radau3", 100.0, 100.0, "double", "cortex-m7"),
        ("abs-xbs4", "radau3", 10.0, 20.0, "float", "cortex-m4f"),
        ("abs-xbs4", "radau3", 10.0, 20.0, "double", "cortex-m7"))


def _on_the_target_section(runs: Runs) -> list[str]:  # noqa: ARG001 - the runs of the other sections
    from ..codegen import TARGETS, CObserver, measure_footprint, run_pil   # casadi: not for `reproduce --help`
    from ..observers import xbs3_observer, xbs4_observer

    make = {"abs-xbs3": xbs3_observer, "abs-xbs4": xbs4_observer}
    table, compiler, stack_lines, described = [], "", [], ""
    for model, method, b1, b2, real, target in ROWS:
        ref = make[model](b1, b2, method=method)
        rec = braking_record(ref, initial_state={"z2": 0.5})
        described = rec.description
        gen = CObserver.like(ref, real=real).generated
        f, pil = measure_footprint(gen, target), run_pil(gen, target, rec.rows, rec.dt, rec.x0)
        cmp = compare_with_reference(pil, ref, rec.rows, rec.dt, rec.x0)
        compiler = f.compiler
        table.append([model, method, real, target, f.text_bytes, f.data_bytes + f.bss_bytes, f.worst("_step"),
                      f.worst("_run"), f"{pil.instructions_per_step:.0f}", f"{pil.identical_rows}/{pil.rows}",
                      f"{cmp.max_relative_error:.1e} (≤ {cmp.tolerance:g})"])
        if model == "abs-xbs3" and target == "cortex-m4f":
            stack_lines = [f"`{s.function}` {s.frame_bytes} B own, {s.worst_bytes} B worst" for s in f.stack]
    qemu = subprocess.run([str(shutil.which("qemu-system-arm")), "--version"], capture_output=True, text=True,
                          check=False).stdout.splitlines()[0]
    flags = {n: " ".join(t.flags) for n, t in TARGETS.items() if t.embedded}
    return [
        f"Measured with `{compiler}` and `{qemu}`, flags "
        + "; ".join(f"{n}: `{v}`" for n, v in flags.items()) + ".  The record: " + described + ".",
        "",
        md_table(["model", "method", "real", "target", "text B", "data + bss B", "stack `_step` B", "stack `_run` B",
                  "instructions per step", "rows bit-identical to the host", "vs Python reference"], table),
        "",
        "Per function (abs-xbs3, float, cortex-m4f): " + "; ".join(stack_lines) + ".",
    ]


#: (name, page, generator) of the sections of this module.
TARGET_SECTIONS = (("on_the_target", "docs/codegen.md", _on_the_target_section),)
