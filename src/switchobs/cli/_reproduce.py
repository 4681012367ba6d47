"""``switchobs reproduce [--root DIR] [--check]``: write (or check) the reproduction pages generated from runs."""

from __future__ import annotations

import argparse
from pathlib import Path

from .._atomic import check_output_directory
from ..report import GENERATED_SECTIONS, stale_pages, write_reproductions
from ._common import write_or_check

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "reproduce",
        description="Run the seed reproductions (Table 4.1, Table 6.1, the ABS on the encoder of Figs. 6.7-6.9, the "
                    "seeds' scenarios, Appendix C, the "
                    "Poincaré map, the super-twisting orders) and write docs/reproductions.md and the generated "
                    f"sections of {', '.join(sorted({path for path, _ in GENERATED_SECTIONS}))}. About a minute. With --check, write nothing and "
                    "exit 1 if a committed page differs from the fresh run. A repository command: it needs a checkout of "
                    "the switchobs repository (its docs/), not an installed package alone.")
    p.add_argument("--root", default=".", metavar="DIR", help="repository root holding docs/ (default: .)")
    p.add_argument("--check", action="store_true", help="compare the committed pages with a fresh run instead")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    root = Path(args.root) if args.check else check_output_directory(args.root, what="the reproduction pages under")
    return write_or_check(args.check, lambda: [root / path for path in stale_pages(root)],
                          lambda: write_reproductions(root), f"switchobs reproduce --root {root}", root)
