"""Table cells and phrases shared by the generated reproduction sections: a Markdown table row, a deviation in
percent, a time in seconds, and what a row is (fitted or predicted) or what our runs say of a seed's claim
(contradicted)."""

from __future__ import annotations

def _pct(ours: float, seed: float) -> str:
    return f"{100.0 * (ours / seed - 1.0):+.1f} %"


def _row(*cells: object) -> str:
    return "| " + " | ".join(str(c) for c in cells) + " |"


def _fmt_s(v: float | None) -> str:
    return "never (outside the band at the end)" if v is None else f"{v:.3f} s"


#: The header of the column that says, on every row with a seed's value beside ours, whether ours was fitted
#: (a value we chose was chosen to match the seed there) or predicted (nothing was chosen on it).
ROLE = "fitted or predicted"
#: A row on which nothing was chosen to match the seed.
PREDICTED = "predicted"


def _fitted(why: str) -> str:
    """The role of a row whose value we chose to match the seed's, and what was chosen: its difference from the
    seed measures the fit, not the model, so such a row shows no deviation."""
    return f"**fitted**: {why}"


def _contradicted(claim: str, evidence: str) -> str:
    """A seed statement our runs contradict, flagged as such (not only explained)."""
    return f"**Contradicted by our runs:** the seed's \"{claim}\": {evidence}."
