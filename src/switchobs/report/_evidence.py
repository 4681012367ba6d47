"""The simulation evidence block of ``docs/certify.md``: the runs of :mod:`switchobs.experiments` rendered."""

from __future__ import annotations

from ..experiments import encoder_comparison, two_axle_box_check

__all__ = ["synthesis_evidence"]


def synthesis_evidence() -> str:
    """The generated block of ``docs/certify.md``: :func:`encoder_comparison` (fast demo), :func:`two_axle_box_check`."""
    return encoder_comparison().table() + "\n\n" + two_axle_box_check().text()
