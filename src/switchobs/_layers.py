"""The floors of the house, lowest first: a package imports only from its own floor or the floors below.

Each floor is a tuple of packages of equal rank (they may import one another's modules only one way; a test
finds circles).  ``tests/test_public_api.py`` checks every import against this table and ``docs/developer.md``
shows it as the map of the layers, each package with the first sentence of its docstring
(:func:`layer_map`).  Layer-free helpers (``switchobs._validate``, ``_limits``, ``_json``, ``_atomic``,
``_progress``, ``_display``, ``_figures``, ``_papers``, ``exceptions``) sit below every floor.
"""

from __future__ import annotations

__all__ = ["FLOORS", "RANK", "layer_map"]

FLOORS: tuple[tuple[str, ...], ...] = (
    ("exact",),
    ("model",),
    ("transform", "design"),
    ("spec", "lmi"),
    ("synthesis",),
    ("certify",),
    ("codegen",),
    ("observers",),
    ("plants",),
    ("sensors",),
    ("loop",),
    ("experiments", "sweep", "logs"),
    ("report",),
    ("cli",),
)
RANK: dict[str, int] = {name: rank for rank, floor in enumerate(FLOORS) for name in floor}


def layer_map() -> list[str]:
    """The map of ``docs/developer.md``: one line per package, lowest first, drawn from the packages' docstrings."""
    import importlib

    lines = []
    for rank, floor in enumerate(FLOORS):
        for name in floor:
            doc = (importlib.import_module(f"switchobs.{name}").__doc__ or "").strip()
            first = " ".join(doc.split("\n\n")[0].split())
            lines.append(f"{rank:>2}. `{name}`: {first}")
    return lines
