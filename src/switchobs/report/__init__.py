"""Reports: the end-to-end demo, the theory documents generated from the symbolic core, their figures.

Public API
----------
run_demo               -- the main job end to end (``switchobs demo``) -> DemoReport, writes out/demo/
DemoReport, DemoSettings, ModelResult, BrakingSummary, ErrorRow -- its results
demo_scenario          -- the braking scenario of the demo (dry -> wet -> snow, five-phase ABS with tracking)
EncoderLoopEstimator   -- XBS observers fed by a simulated encoder with three-stage compensation, in the ABS loop
EncoderLoopRecord      -- what the encoder chain and the observers saw
tracking_reference     -- the wheel-acceleration reference (21) a tracking five-phase ABS followed
theory_document(s)     -- the theory/*.md documents generated from switchobs.design (``switchobs theory``)
write_theory           -- write them into a directory
plot_demo, mark_road_changes -- figures of the demo
Progress, Stage, check_prerequisites -- stage lines with elapsed times; prerequisites of a pipeline
"""

from ._demo import DEMO_BETAS, DEMO_MODELS, STAGES, BrakingSummary, DemoReport, DemoSettings, ErrorRow, ModelResult, \
    demo_scenario, run_demo
from ._encoder_loop import EncoderLoopEstimator, EncoderLoopRecord
from ._plots import mark_road_changes, plot_demo
from ._progress import Progress, Stage, check_prerequisites
from ._reference import tracking_reference
from ._theory import THEORY_MODELS, TheoryDocument, theory_document, theory_documents, write_theory

__all__ = ["DEMO_BETAS", "DEMO_MODELS", "STAGES", "BrakingSummary", "DemoReport", "DemoSettings", "ErrorRow",
           "ModelResult", "demo_scenario", "run_demo", "EncoderLoopEstimator", "EncoderLoopRecord",
           "mark_road_changes", "plot_demo", "Progress", "Stage", "check_prerequisites", "tracking_reference",
           "THEORY_MODELS", "TheoryDocument", "theory_document", "theory_documents", "write_theory"]
