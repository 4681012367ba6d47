"""Figure of an estimator comparison (a matplotlib ``Figure``, no pyplot; see :mod:`switchobs._figures`)."""

from __future__ import annotations

from typing import Any

from .._figures import panels
from ._chain import EstimatorComparison

__all__ = ["plot_comparison"]


def plot_comparison(comparison: EstimatorComparison, *, ax: Any = None) -> Any:
    """Speed and acceleration of every estimator against the truth over one second after the warm-up.

    Parameters
    ----------
    comparison : EstimatorComparison
    ax : 2 Axes, optional
        Speed and acceleration panels; default a new Figure.

    Returns
    -------
    matplotlib.figure.Figure
    """
    first = comparison.results[0]
    t0 = first.t[0] + first.settings.warmup_s
    show = (first.t >= t0) & (first.t <= t0 + 1.0)
    fig, axes = panels(ax, 2, figsize=(9, 6), owner="plot_comparison", sharex=True)
    axes[0].plot(first.t[show], first.omega_true[show], "k", lw=2, label="truth")
    axes[1].plot(first.t[show], first.alpha_true[show], "k", lw=2, label="truth")
    for r in comparison.results:
        axes[0].plot(r.t[show], r.omega[show], lw=0.9, label=r.estimator)
        axes[1].plot(r.t[show], r.alpha[show], lw=0.9, label=r.estimator)
    axes[0].set_ylabel("omega [rad/s]")
    axes[1].set_ylabel("alpha [rad/s^2]")
    axes[1].set_xlabel("t [s]")
    axes[0].legend(loc="upper right", fontsize=8)
    axes[0].set_title(f"{comparison.trajectory}, {comparison.encoder.ppr}-ppr encoder")
    fig.tight_layout()
    return fig
