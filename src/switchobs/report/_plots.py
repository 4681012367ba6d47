"""Figures of the demo (matplotlib, Agg backend): XBS, wheel acceleration, switching, encoder compensation."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

__all__ = ["plot_demo", "mark_road_changes"]

Array = npt.NDArray[np.float64]


def _pyplot() -> Any:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


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


def plot_xbs(path: Path, scenario: Any, result: Any, record: Any) -> Path:
    """True vs estimated XBS: exact-x2 observer (top), encoder-fed observers (bottom); road changes marked."""
    plt = _pyplot()
    s = result.series
    fig, axes = plt.subplots(2, 1, figsize=(11, 7), sharex=True)
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
    return _save(fig, axes, scenario, path)


def plot_wheel_acceleration(path: Path, scenario: Any, result: Any, record: Any) -> Path:
    """x2 and its tracking reference (21), the encoder measurement, the pressure and the ABS phase."""
    from ._reference import tracking_reference

    plt = _pyplot()
    s = result.series
    ref, _ = tracking_reference(result)
    fig, axes = plt.subplots(2, 1, figsize=(11, 7), sharex=True, gridspec_kw={"height_ratios": (2, 1)})
    axes[0].plot(s["t"], s["x2"], color="k", lw=1.0, label="x2 = R dω/dt - a_x (plant)")
    axes[0].plot(s["t"], ref, color="tab:red", lw=1.4, label="reference x2* (21) in phases 1, 3, 4")
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
    axes[0].set_title("closed-loop wheel-acceleration control (seed 000 (21)-(22)) on the C observer's XBS")
    return _save(fig, axes, scenario, path)


def plot_switching(path: Path, scenario: Any, result: Any, record: Any) -> Path:
    """The switching signal sign(s), s = y / vx, and the rescaled time tau = ∫|s| dt (seed 004)."""
    from ..certify import time_rescaling

    plt = _pyplot()
    s = result.series
    keep = np.concatenate([[True], np.diff(s["t"]) > 0])
    t, s_true = s["t"][keep], (s["x2"] / s["vx"])[keep]
    ok = np.isfinite(record.x2_measured)
    tm, s_meas = record.t[ok], (record.x2_measured / record.vx)[ok]
    fig, axes = plt.subplots(3, 1, figsize=(11, 7), sharex=True, gridspec_kw={"height_ratios": (1, 1, 1.4)})
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
    return _save(fig, axes, scenario, path)


def plot_encoder(path: Path, scenario: Any, result: Any, record: Any) -> Path:
    """Encoder compensation: speed and x2 errors of the raw TSA and of the three-stage estimate."""
    plt = _pyplot()
    s = result.series
    ok = np.isfinite(record.t_measured)
    t, tm = record.t[ok], record.t_measured[ok]
    omega_now = np.interp(t, s["t"], s["omega"])
    x2_then = np.interp(tm, s["t"], s["x2"])
    fig, axes = plt.subplots(2, 1, figsize=(11, 7), sharex=True)
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
                      "(seed 001 Ch. 6)")
    return _save(fig, axes, scenario, path)


def plot_demo(out: Path, scenario: Any, result: Any, record: Any) -> list[Path]:
    """All figures of the demo into ``out``; returns their paths."""
    from ..plants import plot_braking

    return [plot_xbs(out / "xbs.png", scenario, result, record),
            plot_wheel_acceleration(out / "wheel_acceleration.png", scenario, result, record),
            plot_switching(out / "switching.png", scenario, result, record),
            plot_encoder(out / "encoder.png", scenario, result, record),
            plot_braking(result, out / "braking.png")]


def _save(fig: Any, axes: Any, scenario: Any, path: Path) -> Path:
    """Mark the road changes, write the figure and free it (every demo plot ends this way)."""
    mark_road_changes(axes, scenario)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    _pyplot().close(fig)
    return path
