"""The command output a docs page shows, and the rule by which it may leave lines out."""

import re
from pathlib import Path

DOCS = Path(__file__).resolve().parents[1] / "docs"


def shown_output(page: str, command: str) -> str:
    """The lines ``docs/page`` shows after ``$ command``, up to the next prompt or the end of the block."""
    text = (DOCS / page).read_text("utf-8")
    block = re.search(r"^\$ " + re.escape(command) + r"\n(.*?)(?=\n\$ |\n```)", text, re.S | re.M)
    assert block, f"docs/{page} shows no output of `{command}`"
    return block.group(1).rstrip("\n")


def matches_with_elisions(shown: str, printed: str) -> bool:
    """``shown`` is ``printed`` with runs of lines left out where a line is ``...`` and line ends left out
    where a line ends in ``...``."""
    pattern = []
    for line in shown.splitlines():
        if line.strip() == "...":
            pattern.append(r"(?:.*\n)*?")
        elif line.endswith("..."):
            pattern.append(re.escape(line[:-3]) + r".*\n")
        else:
            pattern.append(re.escape(line) + r"\n")
    return re.fullmatch("".join(pattern), printed.rstrip("\n") + "\n") is not None


def assert_page_says(page: str, fragment: str) -> None:
    """``docs/page`` quotes ``fragment`` (a number of a fresh run, formatted as the page shows it)."""
    assert fragment in (DOCS / page).read_text("utf-8"), f"docs/{page} does not say {fragment!r} (a fresh run)"


def page_number(page: str, pattern: str) -> float:
    """The number ``docs/page`` gives where ``pattern`` (a regular expression with one group) matches."""
    found = re.search(pattern, (DOCS / page).read_text("utf-8"))
    assert found, f"docs/{page} has no {pattern!r}"
    return float(found.group(1))
