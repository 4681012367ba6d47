"""Figures of braking runs, in the style of the seeds' plots (matplotlib ``Figure`` objects, no pyplot).

Each function returns the Figure and takes ``ax=``: the Axes to draw on, or
``None`` for a new Figure (:mod:`switchobs._figures`); save it with
``fig.savefig(path)``.
"""

from __future__ import annotations

import re
import textwrap
from typing import Any

import numpy as np

from .._figures import panels
from ._scenarios import Table41Result
from ._simulate import BrakingResult
from ._two_axle import TwoAxleResult

__all__ = ["plot_braking", "plot_table41", "plot_two_axle"]



_PYTHON_OBSERVER = re.compile(r"^(\w*Observer) of model '([^']+)' \((\w+)")
_C_OBSERVER = re.compile(r"generated C (\w+) observer \S+ for model '([^']+)' \((\w+), (\w+)")
_KINDS = {"SwitchedObserver": "switched observer", "AdaptiveSwitchedObserver": "adaptive observer"}



def _mark_road_changes(axes: Any, events: Any) -> None:
    """A dotted line at every road change on every panel, labelled with the new road on the top one."""
    for when, what in events:
        if what.startswith("road"):
            for a in axes:
                a.axvline(when, color="tab:red", lw=0.6, ls=":")
            road = what.split("-> ", 1)[-1].split(" (", 1)[0]
            axes[0].annotate(f"→ {road}", (when, 1.0), xycoords=("data", "axes fraction"), xytext=(2, -9),
                             textcoords="offset points", fontsize=7, color="tab:red")

def observer_title(description: str) -> str:
    """A run's observer as a figure title says it: ``switched observer of abs-xbs4 (radau3)`` for the line
    ``SwitchedObserver of model 'abs-xbs4' (radau3, ZOH signals y, vx, u)``; other descriptions unchanged.

    Examples
    --------
    >>> observer_title("SwitchedObserver of model 'abs-xbs4' (radau3, ZOH signals y, vx, u)")
    'switched observer of abs-xbs4 (radau3)'
    >>> observer_title("none")
    'no observer'
    """
    if description == "none":
        return "no observer"
    if (m := _C_OBSERVER.search(description)) is not None:
        return f"generated C {m.group(1)} observer of {m.group(2)} ({m.group(3)}, {m.group(4)})"
    if (m := _PYTHON_OBSERVER.match(description)) is not None:
        return f"{_KINDS.get(m.group(1), m.group(1))} of {m.group(2)} ({m.group(3)})"
    return f"observer {description}"

def plot_braking(result: BrakingResult, *, ax: Any = None) -> Any:
    """Time histories and phase planes of a run (seed 000 Figs. 3-4, seed 001 Figs. 3.4, 4.5-4.7).

    Left: speeds ``vx`` and ``R ω``, slip, ``x2`` with the controller phase,
    pressure, true and estimated XBS.  Right: the ``(lambda, x2)`` plane (seed
    001 Fig. 4.7) and the ``(z1, z2) = (x2, mu')`` plane (Figs. 4.4-4.6).

    Parameters
    ----------
    result : BrakingResult
    ax : sequence of 7 Axes, optional
        The five time histories, then the two planes; default a new Figure.

    Returns
    -------
    matplotlib.figure.Figure
    """
    s = result.series
    t = s["t"]
    if ax is None:
        from matplotlib.figure import Figure

        fig = Figure(figsize=(12, 10))
        grid = fig.add_gridspec(5, 2, width_ratios=(1.6, 1.0))
        axes = [fig.add_subplot(grid[i, 0]) for i in range(5)]
        for a in axes[1:]:
            a.sharex(axes[0])
        p1, p2 = fig.add_subplot(grid[0:2, 1]), fig.add_subplot(grid[2:5, 1])
    else:
        fig, given = panels(ax, 7, figsize=(12, 10), owner="plot_braking")
        axes, (p1, p2) = given[:5], given[5:]
    r = result.scenario.vehicle.radius_m
    axes[0].plot(t, s["vx"], label="vx")
    axes[0].plot(t, r * s["omega"], label="R ω")
    axes[0].set_ylabel("speed [m/s]")
    axes[0].legend(loc="upper right")
    axes[1].plot(t, s["lambda"])
    axes[1].set_ylabel("slip λ")
    axes[2].plot(t, s["x2"], lw=0.8)
    axes[2].set_ylabel("x2 [m/s²]")
    phase_ax = axes[2].twinx()
    phase_ax.step(t, s["phase"], where="post", color="tab:gray", lw=0.6, alpha=0.6)
    phase_ax.set_ylabel("phase")
    axes[3].plot(t, s["P_b"])
    axes[3].set_ylabel("P_b [bar]")
    axes[4].plot(t, s["xbs"], label="μ' (true)")
    has_estimate = not np.all(np.isnan(s["xbs_hat"]))
    if has_estimate:
        axes[4].plot(t, s["xbs_hat"], "--", label="μ' estimate")
    # the limits hold the true XBS of the ABS cycles, not its build-up before the first release (the 1-99
    # percentiles once the ABS is active; the estimate's transients after a road change may leave them), with
    # headroom above for the legend so that it covers no data
    active = s["phase"] >= 1
    cycled = s["xbs"][active & np.isfinite(s["xbs"])]
    lo, hi = (float(v) for v in np.percentile(cycled if cycled.size else s["xbs"][np.isfinite(s["xbs"])], [1, 99]))
    pad = 0.08 * (hi - lo or 1.0)
    axes[4].set_ylim(lo - pad, hi + pad + 0.45 * (hi - lo or 1.0))
    axes[4].set_ylabel("XBS")
    axes[4].set_xlabel("t [s]")
    axes[4].legend(loc="upper right", ncols=2, fontsize=8)
    _mark_road_changes(axes, result.events)
    p1.plot(s["lambda"][active], s["x2"][active], lw=0.6)
    p1.set_xlabel("slip λ")
    p1.set_ylabel("x2 [m/s²]")
    p1.set_title("(λ, x2) plane")
    p2.plot(s["x2"][active], s["xbs"][active], lw=0.8, label="true", zorder=3)
    z1 = s["x2"][active]
    z1 = z1[np.isfinite(z1)]
    if has_estimate:
        # the plane is the true trajectory's; estimate samples off it (transients after a road change) are left
        # out rather than drawn as lines running off the axes
        hat = np.where((s["xbs_hat"] >= lo - pad) & (s["xbs_hat"] <= hi + pad), s["xbs_hat"], np.nan)
        p2.plot(s["x2"][active], hat[active], lw=0.6, alpha=0.6, label="estimate (inside the plane)")
        p2.legend(loc="upper right", fontsize=8)
    z_pad = 0.05 * (float(z1.max() - z1.min()) or 1.0) if z1.size else 1.0
    if z1.size:
        p2.set_xlim(float(z1.min()) - z_pad, float(z1.max()) + z_pad)
    p2.set_ylim(lo - pad, hi + pad + 0.25 * (hi - lo or 1.0))
    p2.set_xlabel("z1 = x2 [m/s²]")
    p2.set_ylabel("z2 = μ'")
    p2.set_title("(z1, z2) plane")
    title = (f"{result.scenario.name}: {result.scenario.roads}, {result.scenario.speed_kmh:.0f} km/h, "
             f"{result.scenario.controller.name}, {observer_title(result.observer)}")
    fig.suptitle("\n".join(textwrap.wrap(title, 110)), fontsize=10)  # wrapped: never wider than the figure
    fig.set_layout_engine("constrained")
    return fig


def plot_table41(result: Table41Result, *, ax: Any = None) -> Any:
    """Bar chart of the braking distances of Table 4.1, ours beside the seed's; one panel per speed.

    ``ax``: one Axes per speed of the result, or ``None`` for a new Figure; returns the Figure.
    """
    speeds = sorted({r.speed_kmh for r in result.rows})
    fig, axes = panels(ax, len(speeds), figsize=(4.5 * len(speeds), 4.5), owner="plot_table41", nrows=1,
                       ncols=len(speeds))
    for ax, v in zip(axes, speeds):
        rows = [r for r in result.rows if r.speed_kmh == v]
        x = np.arange(len(rows))
        w = 0.2
        ax.bar(x - 1.5 * w, [r.five_phase_m for r in rows], w, label="five-phase (ours)")
        ax.bar(x - 0.5 * w, [r.seed_five_phase_m or np.nan for r in rows], w, label="five-phase (seed)", alpha=0.5)
        ax.bar(x + 0.5 * w, [r.two_phase_m for r in rows], w, label="two-phase (ours)")
        ax.bar(x + 1.5 * w, [r.seed_two_phase_m or np.nan for r in rows], w, label="two-phase (seed)", alpha=0.5)
        ax.set_xticks(x, [r.road.replace("-", "\n") for r in rows], fontsize=8)
        ax.set_title(f"{v:.0f} km/h")
        ax.set_ylabel("braking distance [m]")
    axes[0].legend(fontsize=8)
    fig.suptitle("Aguado-Rojas 2020 Table 4.1: braking distance vx(0)²/(2 g μ̄)")
    fig.tight_layout()
    return fig


def plot_two_axle(result: TwoAxleResult, *, ax: Any = None) -> Any:
    """Speeds and speed estimate, slips, pressures, loads and XBS of both axles (seed 001 Figs. 3.15-3.19).

    ``ax``: 5 Axes, or ``None`` for a new Figure; returns the Figure.
    """
    s = result.series
    t = s["t"]
    r = result.scenario.vehicle.radius_m
    fig, axes = panels(ax, 5, figsize=(10, 12), owner="plot_two_axle", sharex=True)
    axes[0].plot(t, s["vx"], label="vx")
    axes[0].plot(t, s["vx_hat"], "--", label="vx estimate")
    axes[0].plot(t, r * s["omega_f"], lw=0.8, label="R ω front")
    axes[0].plot(t, r * s["omega_r"], lw=0.8, label="R ω rear")
    axes[0].set_ylabel("speed [m/s]")
    axes[1].plot(t, s["lambda_f"], label="front")
    axes[1].plot(t, s["lambda_r"], label="rear")
    axes[1].set_ylabel("slip λ")
    axes[2].plot(t, s["P_f"], label="front")
    axes[2].plot(t, s["P_r"], label="rear")
    axes[2].set_ylabel("P_b [bar]")
    axes[3].plot(t, s["Fz_f"], label="front (3.36)")
    axes[3].plot(t, s["Fz_r"], label="rear (3.36)")
    axes[3].set_ylabel("Fz [N]")
    axes[4].plot(t, s["xbs_f"], label="μ' front")
    axes[4].plot(t, s["xbs_r"], label="μ' rear")
    for key, label in (("xbs_hat_f", "estimate front"), ("xbs_hat_r", "estimate rear")):
        if not np.all(np.isnan(s[key])):
            axes[4].plot(t, s[key], "--", lw=0.8, label=label)
    axes[4].set_ylim(-1.0, 4.0)
    axes[4].set_ylabel("XBS")
    axes[4].set_xlabel("t [s]")
    for ax in axes:
        ax.legend(loc="upper right", fontsize=7)
    _mark_road_changes(axes, result.events)
    fig.suptitle("\n".join(textwrap.wrap(str(result.scenario), 110)), fontsize=9)  # wrapped: never wider than the figure
    fig.tight_layout()
    return fig
