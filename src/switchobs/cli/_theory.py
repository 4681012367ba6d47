"""``switchobs theory [--out DIR] [--check]``: write (or check) the theory documents generated from the code."""

from __future__ import annotations

import argparse
from pathlib import Path

from .._atomic import check_output_directory
from ..report import theory_documents, write_theory
from ._common import output_directory, write_or_check

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "theory",
        description="Generate the theory documents of the built-in models (abs-xbs3, abs-xbs4, abs-adaptive2) and "
                    "of the generic normal form (N = 3) from switchobs.design, as Markdown with LaTeX math. "
                    "The output is deterministic. With --check, write nothing and exit 1 if a file in DIR "
                    "differs from what the code generates now. Runs anywhere; the repository keeps its "
                    "documents in theory/ (the default DIR) and checks them with --check.")
    p.add_argument("--out", default="theory", metavar="DIR", type=output_directory,
                   help="output directory (default: theory)")
    p.add_argument("--check", action="store_true", help="compare DIR with the generated documents instead")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    out = Path(args.out) if args.check else check_output_directory(args.out, what="the theory documents into")

    def stale() -> list[Path]:
        return [out / doc.filename for doc in theory_documents()
                if not (out / doc.filename).is_file() or (out / doc.filename).read_text("utf-8") != doc.text]
    return write_or_check(args.check, stale, lambda: write_theory(out), f"switchobs theory --out {out}", out)
