"""Copy the benchmark results (``benchmarks/results/*.md``) into the documentation pages.

A page shows a result between ``<!-- bench:NAME -->`` and ``<!-- /bench:NAME -->`` (NAME the script's stem);
everything between the markers is replaced by the file ``results/NAME.md`` as the script last wrote it.
``make bench`` runs this after the scripts; ``tests/test_docs.py`` checks that the pages hold the files.
Run: ``python benchmarks/render_docs.py [--check]`` (``--check``: exit 1 if a page is out of date).
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
BLOCK = re.compile(r"(<!-- bench:([\w-]+) -->\n)(.*?)(<!-- /bench:\2 -->)", re.S)


def render(text: str) -> str:
    """``text`` with every marked block replaced by its results file."""
    def fill(m: re.Match) -> str:
        path = RESULTS / f"{m.group(2)}.md"
        if not path.is_file():
            raise SystemExit(f"no {path.relative_to(ROOT)}: run benchmarks/{m.group(2)}.py first")
        return m.group(1) + path.read_text(encoding="utf-8") + m.group(4)
    return BLOCK.sub(fill, text)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="only report pages that are out of date")
    args = parser.parse_args()
    stale = []
    for page in sorted((ROOT / "docs").glob("*.md")):
        text = page.read_text(encoding="utf-8")
        new = render(text)
        if new != text:
            stale.append(page.name)
            if not args.check:
                page.write_text(new, encoding="utf-8")
    verb = "out of date" if args.check else "updated"
    print(f"{verb}: {', '.join(stale)}" if stale else "all benchmark tables in docs/ are up to date")
    return 1 if args.check and stale else 0


if __name__ == "__main__":
    sys.exit(main())
