"""``switchobs reproduce [--root DIR] [--check]``: write (or check) the reproduction pages generated from runs."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..report import GENERATED_SECTIONS, stale_pages, write_reproductions

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "reproduce", help="regenerate docs/reproductions.md and the Table 4.1 / 6.1 sections from runs",
        description="Run the seed reproductions (Table 4.1, Table 6.1, the seeds' scenarios, Appendix C, the "
                    "Poincaré map, the super-twisting orders) and write docs/reproductions.md and the generated "
                    f"sections of {', '.join(sorted({path for path, _ in GENERATED_SECTIONS}))}. About a minute. With --check, write nothing and "
                    "exit 1 if a committed page differs from the fresh run.")
    p.add_argument("--root", default=".", metavar="DIR", help="repository root holding docs/ (default: .)")
    p.add_argument("--check", action="store_true", help="compare the committed pages with a fresh run instead")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    root = Path(args.root)
    if args.check:
        stale = stale_pages(root)
        for path in stale:
            print(f"{root / path}: differs from a fresh run; run `switchobs reproduce --root {root}`",
                  file=sys.stderr)
        if not stale:
            print(f"{root}: reproduction pages up to date")
        return 1 if stale else 0
    for path in write_reproductions(root):
        print(f"wrote {path}")
    return 0
