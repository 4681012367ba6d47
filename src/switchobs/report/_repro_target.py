"""The "On the target" and proof sections of docs/codegen.md: the runs of :mod:`switchobs.experiments`'s target
experiments (sizes, stack, instructions per step, processor in the loop, MISRA; the EVA proofs) rendered.

The counts are exact for a given compiler, qemu and Frama-C (the sections name them), so
``switchobs reproduce --check`` compares them with a fresh run like every generated section.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

# the set-ups moved to switchobs.experiments; named here too for the tests that import them from this module
from ..experiments import (PROOF_ROWS, STATE_SIGNAL_RANGES, XBS3_RANGES, division_model, parameter_ranges,
                           proof_runs, proved_observer, qemu_version, target_runs)
from ._markdown import md_table

if TYPE_CHECKING:
    from ..experiments import Runs

__all__ = ["TARGET_SECTIONS", "XBS3_RANGES", "STATE_SIGNAL_RANGES", "PROOF_ROWS", "division_model",
           "parameter_ranges", "proved_observer"]


def _on_the_target_section(runs: Runs) -> list[str]:  # noqa: ARG001 - the runs of the other sections
    from ..codegen import TARGETS
    from ..codegen._misra import CPPCHECK_COMMAND

    done = target_runs()
    table = [[r.model, r.method, r.real, r.target, r.footprint.text_bytes,
              r.footprint.data_bytes + r.footprint.bss_bytes, r.footprint.worst("_step"), r.footprint.worst("_run"),
              f"{r.pil.instructions_per_step:.0f}", f"{r.pil.identical_rows}/{r.pil.rows}",
              f"{r.reference.max_relative_error:.1e} (≤ {r.reference.tolerance:g})",
              " / ".join(str(r.misra.get(k, 0)) for k in ("Mandatory", "Required", "Advisory"))
              + (f" (and {r.misra['other']} other cppcheck findings)" if r.misra.get("other") else "")]
             for r in done]
    m4f = next(r for r in done if r.model == "abs-xbs3" and r.target == "cortex-m4f")
    stack_lines = [f"`{s.function}` {s.frame_bytes} B own, {s.worst_bytes} B worst" for s in m4f.footprint.stack]
    flags = {n: " ".join(t.flags) for n, t in TARGETS.items() if t.embedded}
    return [
        f"Measured with `{done[-1].footprint.compiler}` and `{qemu_version()}`, flags "
        + "; ".join(f"{n}: `{v}`" for n, v in flags.items()) + ".  The record: " + done[-1].record + ".",
        "",
        md_table(["model", "method", "real", "target", "text B", "data + bss B", "stack `_step` B", "stack `_run` B",
                  "instructions per step", "rows bit-identical to the host", "vs Python reference",
                  "MISRA mandatory / required / advisory"], table),
        "",
        "MISRA: findings of cppcheck's misra addon (`" + CPPCHECK_COMMAND.format(source="<prefix>.c")
        + "`) on the generated files; every advisory one is listed with its reason in `<prefix>_misra.md` "
        "(see [MISRA C:2012](#misra-c2012)).",
        "",
        "Per function (abs-xbs3, float, cortex-m4f): " + "; ".join(stack_lines) + ".",
    ]


def _proof_status_section(runs: Runs) -> list[str]:  # noqa: ARG001 - the runs of the other sections
    done = proof_runs()
    proofs = [[gen.model_name, gen.kind, gen.method, gen.real, len(gen.ranges), result.alarms, result.proved,
               "**proved**" if result.ok else "not proved"] for gen, result in done]
    return [
        f"Proof of no run-time errors (Frama-C {done[-1][1].frama_c_version}, `switchobs codegen --prove`): the "
        "ranged build of each observer, a declared range of every state, signal, parameter and `dt` (ours: see "
        "[Proof of no run-time errors](#proof-of-no-run-time-errors)), EVA over every finite input of every "
        "public function.",
        "",
        md_table(["model", "observer", "method", "real", "declared ranges", "EVA alarms", "properties valid",
                  "status"], proofs),
    ]


#: (name, page, generator) of the sections of this module.
TARGET_SECTIONS = (("on_the_target", "docs/codegen.md", _on_the_target_section),
                   ("proof_status", "docs/codegen.md", _proof_status_section))
