"""Figures of the demo: XBS, wheel acceleration, switching, encoder compensation.

Matplotlib ``Figure`` objects (no pyplot, no backend switch); each plot
function takes ``ax=`` (its Axes, or ``None`` for a new Figure) and returns the
Figure; :func:`demo_figures` gives them all by file name, the demo writes them.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from .._figures import panels

__all__ = ["demo_figures", "mark_road_changes", "plot_xbs", "plot_wheel_acceleration", "plot_switching",
           "plot_encoder"]

Array = npt.NDArray[np.float64]


def mark_road_changes(axes: Sequence[Any], scenario: Any, *, label: bool = True) -> None:
    """Dashed vertical lines at the road changes of a scenario, the road names on the first axes."""
    starts = [0.0] + [c.at_time_s for c in scenario.roads.changes]
    names = [scenario.roads.initial.name] + [c.road.name for c in scenario.roads.changes]
    for ax in axes:
        for t in starts[1:]:
            ax.axvline(t, color="k", ls="--", lw=0.8, alpha=0.6)
    if label:
        ax0 = axes[0]
        for t, name in zip(starts, names):
            ax0.annotate(name, (t, 1.0), xycoords=("data", "axes fraction"), xytext=(3, -12),
                         textcoords="offset points", fontsize=8)


def _clip_limits(ax: Any, truth: Array, margin: float = 0.6) -> None:
    lo, hi = float(np.nanmin(truth)), float(np.nanmax(truth))
    span = hi - lo
    ax.set_ylim(lo - margin * span, hi + margin * span)


def plot_xbs(scenario: Any, result: Any, record: Any, *, ax: Any = None) -> Any:
    """True vs estimated XBS: exact-x2 observer (top), encoder-fed observers (bottom); road changes marked.

    ``ax``: 2 Axes or ``None``; returns the Figure (as the other demo plots).
    """
    s = result.series
    fig, axes = panels(ax, 2, figsize=(11, 7), owner="plot_xbs", sharex=True)
    for ax in axes:
        ax.plot(s["t"], s["xbs"], color="k", lw=1.2, label="true XBS μ'(λ)")
    for label, est in record.beside.items():
        axes[0].plot(record.steps_t, est, lw=0.9, label=label)
    for label, est in record.estimates.items():
        axes[1].plot(record.t, est, lw=0.8, alpha=0.9, label=label)
    for ax in axes:
        _clip_limits(ax, s["xbs"])
        ax.set_ylabel("XBS [-]")
        ax.legend(loc="upper right", fontsize=8)
        ax.grid(alpha=0.3)
    axes[0].set_title("extended braking stiffness: true and estimated (estimates clipped to the plot)")
    axes[1].set_xlabel("t [s]")
    return _finish(fig, axes, scenario)


def plot_wheel_acceleration(scenario: Any, result: Any, record: Any, *, ax: Any = None) -> Any:
    """x2 and the tracking reference (21) the controller recorded, the encoder measurement, pressure and phase."""
    s = result.series
    fig, axes = panels(ax, 2, figsize=(11, 7), owner="plot_wheel_acceleration", sharex=True,
                       gridspec_kw={"height_ratios": (2, 1)})
    axes[0].plot(s["t"], s["x2"], color="k", lw=1.0, label="x2 = R dω/dt - a_x (plant)")
    axes[0].plot(s["t"], s["x2_ref"], color="tab:red", lw=1.4, label="reference x2* (21) in phases 1, 3, 4")
    axes[0].plot(record.t_measured, record.x2_measured, color="tab:blue", lw=0.6, alpha=0.8,
                 label="x2 measured (encoder, three-stage), at its time")
    axes[0].set_ylabel("wheel acceleration [m/s²]")
    axes[0].legend(loc="lower right", fontsize=8)
    axes[0].grid(alpha=0.3)
    axes[1].plot(s["t"], s["P_b"], color="tab:green", label="brake pressure P_b")
    axes[1].set_ylabel("P_b [bar]")
    ph = axes[1].twinx()
    ph.step(s["t"], s["phase"], where="post", color="tab:gray", lw=0.6)
    ph.set_ylabel("ABS phase")
    axes[1].set_xlabel("t [s]")
    axes[0].set_title("closed-loop wheel-acceleration control (Hoang et al. 2014 (21)-(22)) on the C observer's XBS")
    return _finish(fig, axes, scenario)


def plot_switching(scenario: Any, result: Any, record: Any, *, ax: Any = None) -> Any:
    """The switching signal sign(s), s = y / vx, and the rescaled time tau = ∫|s| dt (seed 004); 3 Axes."""
    from ..certify import time_rescaling

    s = result.series
    keep = np.concatenate([[True], np.diff(s["t"]) > 0])
    t, s_true = s["t"][keep], (s["x2"] / s["vx"])[keep]
    ok = np.isfinite(record.x2_measured)
    tm, s_meas = record.t[ok], (record.x2_measured / record.vx)[ok]
    fig, axes = panels(ax, 3, figsize=(11, 7), owner="plot_switching", sharex=True,
                       gridspec_kw={"height_ratios": (1, 1, 1.4)})
    axes[0].step(t, np.sign(s_true), where="post", lw=0.6, color="k")
    axes[0].set_ylabel("σ(t) exact")
    axes[1].step(tm, np.sign(s_meas), where="post", lw=0.6, color="tab:blue")
    axes[1].set_ylabel("σ(t) measured")
    for ax in axes[:2]:
        ax.set_yticks([-1, 1], ["K−", "K+"])
    axes[2].plot(t, time_rescaling(t, s_true), color="k", label="τ(t) from the plant's y/vx")
    axes[2].plot(tm, time_rescaling(tm, s_meas), color="tab:blue", label="τ(t) from the measured y/vx")
    axes[2].set_ylabel("τ = ∫|s| dt")
    axes[2].set_xlabel("t [s]")
    axes[2].legend(loc="upper left", fontsize=8)
    axes[0].set_title("switching signal: K_plus when s = y/vx > 0, K_minus when s < 0; rescaled time τ")
    return _finish(fig, axes, scenario)


def plot_encoder(scenario: Any, result: Any, record: Any, *, ax: Any = None) -> Any:
    """Encoder compensation: speed and x2 errors of the raw TSA and of the three-stage estimate; 2 Axes."""
    s = result.series
    ok = np.isfinite(record.t_measured)
    t, tm = record.t[ok], record.t_measured[ok]
    omega_now = np.interp(t, s["t"], s["omega"])
    x2_then = np.interp(tm, s["t"], s["x2"])
    fig, axes = panels(ax, 2, figsize=(11, 7), owner="plot_encoder", sharex=True)
    axes[0].plot(t, record.omega_tsa[ok] - omega_now, lw=0.6, label="raw TSA")
    axes[0].plot(t, record.omega_measured[ok] - omega_now, lw=0.6, label="three-stage")
    axes[0].set_ylabel("ω error [rad/s]")
    axes[1].plot(t, record.x2_tsa[ok] - x2_then, lw=0.6, label="raw TSA")
    axes[1].plot(t, record.x2_measured[ok] - x2_then, lw=0.6, label="three-stage")
    axes[1].set_ylabel("x2 error at the window centre [m/s²]")
    axes[1].set_xlabel("t [s]")
    for ax in axes:
        ax.legend(loc="upper right", fontsize=8)
        ax.grid(alpha=0.3)
    axes[0].set_title(f"{scenario.vehicle.radius_m:g} m wheel, 60-ppr encoder: harmonic compensation "
                      "(Aguado-Rojas 2020 Ch. 6)")
    return _finish(fig, axes, scenario)


def demo_figures(scenario: Any, result: Any, record: Any) -> dict[str, Any]:
    """All figures of the demo, by file name (``xbs.png``, ``wheel_acceleration.png``, ...)."""
    from ..plants import plot_braking

    return {"xbs.png": plot_xbs(scenario, result, record),
            "wheel_acceleration.png": plot_wheel_acceleration(scenario, result, record),
            "switching.png": plot_switching(scenario, result, record),
            "encoder.png": plot_encoder(scenario, result, record),
            "braking.png": plot_braking(result)}


def _finish(fig: Any, axes: Any, scenario: Any) -> Any:
    """Mark the road changes and lay the figure out (every demo plot ends this way)."""
    mark_road_changes(axes, scenario)
    fig.tight_layout()
    return fig
