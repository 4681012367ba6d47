"""Figure of a replayed log (a matplotlib ``Figure``, no pyplot; see :mod:`switchobs._figures`)."""

from __future__ import annotations

from typing import Any

import numpy as np

from .._figures import panels
from ..loop import ReplayResult

__all__ = ["plot_replay"]


def plot_replay(result: ReplayResult, *, ax: Any = None) -> Any:
    """The chain's wheel speed and ``x2`` and the observer's XBS estimate over a replayed log.

    Parameters
    ----------
    result : ReplayResult
    ax : 3 Axes, optional
        Wheel-speed, ``x2`` and XBS panels; default a new Figure.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axes = panels(ax, 3, figsize=(9, 7), owner="plot_replay", sharex=True)
    t = result.t
    axes[0].plot(t, result.omega_tsa, lw=0.7, label="TSA")
    axes[0].plot(t, result.omega_measured, lw=0.9, label="three-stage")
    axes[0].set_ylabel("wheel speed [rad/s]")
    for name, label in (("x2_tsa", "TSA"), ("x2_notch", "TSA + notch"), ("x2_measured", "three-stage")):
        axes[1].plot(t, getattr(result, name), lw=0.7, label=label)
    axes[1].set_ylabel("x2 = R dω/dt - a_x [m/s²]")
    axes[2].plot(t, result.xbs_hat, lw=1.0, color="C3", label=result.summary.observer)
    refused = np.flatnonzero(result.status != 0)
    if refused.size:
        axes[2].axvline(float(t[refused[0]]), color="k", ls="--", lw=0.8, label="step refused")
    axes[2].set_ylabel("XBS estimate")
    axes[2].set_xlabel("t [s]")
    for a in axes:
        a.legend(loc="upper right", fontsize=8)
    axes[0].set_title(f"replay of {result.summary.source}")
    fig.tight_layout()
    return fig
