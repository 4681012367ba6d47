"""``switchobs demo [--fast] [--out DIR]``: the main job end to end (see ``switchobs.report.run_demo``)."""

from __future__ import annotations

import argparse

from ..report import STAGES, Progress, run_demo
from ._common import output_directory
from .main import QUIET

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "demo",
        description="On abs-xbs3 and abs-xbs4 with the TU Delft rig of Hoang et al. 2014: symbolic design of K+/K-, "
                    "exact and numeric certification (the certificate re-verified from its file), C generation "
                    "and compilation, an emergency braking dry -> wet -> snow with the generated C observer in "
                    "the loop fed by a 60-ppr encoder with three-stage compensation, and a report with figures. "
                    "Stage lines go to stderr (none with --quiet). Exit status 0 when every check holds, 1 when a "
                    "check fails, 2 when a stage cannot run (the message names it).")
    p.add_argument("--fast", action="store_true", help="shorter braking and timing (for CI, well under a minute)")
    p.add_argument("--out", default="out/demo", metavar="DIR", type=output_directory,
                   help="output directory (default: out/demo)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    quiet = Progress(len(STAGES), stream=None) if args.verbosity == QUIET else None
    report = run_demo(args.out, fast=args.fast, progress=quiet)
    print(report)
    return 0 if report.ok else 1
