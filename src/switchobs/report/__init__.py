"""Reports: the end-to-end demo, the theory documents generated from the symbolic core, their figures.

Public API
----------
run_demo               -- the main job end to end (``switchobs demo``) -> DemoReport, writes out/demo/
DemoReport, ModelResult -- its results (the braking part: switchobs.loop.BrakingSummary)
DEMO_BETAS, DEMO_MODELS, STAGES -- the demo's gains, models and stages
theory_document(s)     -- the theory/*.md documents generated from switchobs.design (``switchobs theory``)
write_theory           -- write them into a directory
reproduction_pages, write_reproductions, stale_pages, ReproductionPage, GENERATED_SECTIONS -- the reproduction
                       pages generated from runs (``switchobs reproduce``)
demo_figures, mark_road_changes -- figures of the demo (matplotlib Figure objects)
Progress, Stage, check_prerequisites -- stage lines with elapsed times; prerequisites of a pipeline
sampled_lines, sampled_observer_table, speed_table -- the sampled observer's certificate in sample rate and vehicle speed
synthesis_evidence -- the evidence block of docs/certify.md; its runs (encoder_comparison, two_axle_box_check,
    EncoderComparison, BoxRun) live in switchobs.experiments, re-exported here for one release -- the seed's beta design
                       against the synthesised pair on the demo braking (60-ppr encoder), and the box certificate
                       against a two-axle braking whose load varies
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # for type checkers and the API reference, which read the source; __getattr__ binds them at run time
    from ._demo import DEMO_BETAS, DEMO_MODELS, STAGES, DemoReport, ModelResult, run_demo
    from ..experiments import BoxRun, EncoderComparison, encoder_comparison, two_axle_box_check
    from ._evidence import synthesis_evidence
    from ._plots import demo_figures, mark_road_changes
    from ._progress import Progress, Stage, check_prerequisites
    from ._reproductions import (GENERATED_SECTIONS, ReproductionPage, reproduction_pages, stale_pages,
                                 write_reproductions)
    from ._sampled import sampled_lines, sampled_observer_table, speed_table
    from ._theory import THEORY_MODELS, TheoryDocument, theory_document, theory_documents, write_theory

# Loaded on first use: the demo, evidence and plot modules import the plants, the loop and the sensors
# (~0.3 s), which a command that only wants Progress (``switchobs design``) must not pay for.
_EXPORTS = {
    "._demo": ("DEMO_BETAS", "DEMO_MODELS", "STAGES", "DemoReport", "ModelResult", "run_demo"),
    "._evidence": ("synthesis_evidence",),
    # moved to switchobs.experiments (the runs); re-exported here for one release
    "..experiments": ("BoxRun", "EncoderComparison", "encoder_comparison", "two_axle_box_check"),
    "._plots": ("demo_figures", "mark_road_changes"),
    "._progress": ("Progress", "Stage", "check_prerequisites"),
    "._reproductions": ("GENERATED_SECTIONS", "ReproductionPage", "reproduction_pages", "stale_pages",
                        "write_reproductions"),
    "._sampled": ("sampled_lines", "sampled_observer_table", "speed_table"),
    "._theory": ("THEORY_MODELS", "TheoryDocument", "theory_document", "theory_documents", "write_theory"),
}
_WHERE = {name: module for module, names in _EXPORTS.items() for name in names}

__all__ = ["DEMO_BETAS", "DEMO_MODELS", "STAGES", "DemoReport", "ModelResult", "run_demo", "mark_road_changes",
           "demo_figures", "Progress", "Stage", "check_prerequisites", "THEORY_MODELS", "TheoryDocument",
           "theory_document", "theory_documents", "write_theory", "sampled_lines", "sampled_observer_table", "speed_table",
           "GENERATED_SECTIONS", "ReproductionPage", "reproduction_pages", "stale_pages", "write_reproductions",
           "BoxRun", "EncoderComparison", "encoder_comparison", "synthesis_evidence", "two_axle_box_check"]


def __getattr__(name: str) -> Any:
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module 'switchobs.report' has no attribute {name!r}")
    value = getattr(importlib.import_module(module, __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
