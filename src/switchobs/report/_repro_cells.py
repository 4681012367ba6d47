"""Table cells and phrases shared by the generated reproduction sections: a Markdown table row, a deviation in
percent, a time in seconds."""

from __future__ import annotations

def _pct(ours: float, seed: float) -> str:
    return f"{100.0 * (ours / seed - 1.0):+.1f} %"


def _row(*cells: object) -> str:
    return "| " + " | ".join(str(c) for c in cells) + " |"


def _fmt_s(v: float | None) -> str:
    return "never (outside the band at the end)" if v is None else f"{v:.3f} s"
