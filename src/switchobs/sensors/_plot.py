"""Figure of an estimator comparison (a matplotlib ``Figure``, no pyplot; see :mod:`switchobs._figures`)."""

from __future__ import annotations

from typing import Any

from .._figures import panels
from ._chain import EstimatorComparison

__all__ = ["plot_comparison"]


def plot_comparison(comparison: EstimatorComparison, *, ax: Any = None) -> Any:
    """Estimation errors of every estimator (speed and acceleration) over one second after the warm-up.

    The errors ``estimate - truth`` are drawn, not the estimates over the truth: the estimators differ
    by far less than the signal, so only the errors show which one is better.

    Parameters
    ----------
    comparison : EstimatorComparison
    ax : 2 Axes, optional
        Speed-error and acceleration-error panels; default a new Figure.

    Returns
    -------
    matplotlib.figure.Figure
    """
    first = comparison.results[0]
    t0 = first.t[0] + first.settings.warmup_s
    show = (first.t >= t0) & (first.t <= t0 + 1.0)
    fig, axes = panels(ax, 2, figsize=(9, 6), owner="plot_comparison", sharex=True)
    for r in comparison.results:
        axes[0].plot(r.t[show], (r.omega - r.omega_true)[show], lw=0.9, label=r.estimator)
        axes[1].plot(r.t[show], (r.alpha - r.alpha_true)[show], lw=0.9, label=r.estimator)
    for a in axes:
        a.axhline(0.0, color="k", lw=0.6)
    axes[0].set_ylabel("speed error [rad/s]")
    axes[1].set_ylabel("acceleration error [rad/s^2]")
    axes[1].set_xlabel("t [s]")
    axes[0].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)  # outside: the errors fill the panel
    axes[0].set_title(f"estimation errors, {comparison.trajectory}, {comparison.encoder.ppr}-ppr encoder")
    fig.tight_layout()
    return fig
