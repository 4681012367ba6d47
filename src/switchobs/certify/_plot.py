"""Figures of a certification: spectra of the modes, the dwell-time margin, planar level sets and trajectories.

Plot functions draw on matplotlib Figures without pyplot (:mod:`switchobs._figures`), take ``ax=`` and
return the Figure; ``switchobs certify --plot`` and ``switchobs classify --plot`` write them.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .._figures import panels
from ..exceptions import CertificateError
from ._certify import CertificationReport
from ._dwell import gc_margin
from ._family import as_family
from ..lmi import balance
from ._planar import PlanarClassification

__all__ = ["plot_certification", "plot_spectra", "plot_dwell_margin", "plot_planar"]

_COLOURS = ("tab:blue", "tab:red", "tab:green", "tab:purple")


def plot_spectra(report: CertificationReport, *, ax: Any = None) -> Any:
    """Eigenvalues of every mode (``A_plus``, ``A_minus``) in the complex plane; all left of the axis is Hurwitz."""
    fig, (a,) = panels(ax, 1, figsize=(5.0, 4.0), owner="plot_spectra")
    for k, (nm, M) in enumerate(zip(report.family.names, report.family.numeric)):
        eig = np.linalg.eigvals(M)
        a.scatter(eig.real, eig.imag, marker="ox+s"[k % 4], s=46, facecolors="none" if k % 4 == 0 else None,
                  color=_COLOURS[k % 4], label=nm, zorder=3)
    a.axvline(0.0, color="0.4", lw=0.8)
    a.axhline(0.0, color="0.8", lw=0.6)
    a.set_xlabel("Re λ")
    a.set_ylabel("Im λ")
    a.set_title("spectra of the modes (rescaled time τ)", fontsize=10)
    a.legend(fontsize=8, loc="best")
    return fig


def plot_dwell_margin(report: CertificationReport, *, ax: Any = None, points: int = 12) -> Any:
    """The Geromel–Colaneri LMI margin against the dwell time ``T``, with the certified ``tau_D`` marked.

    The margin is the normalised optimum of the LMIs the bisection of
    :func:`~switchobs.certify.dwell_time` solves (positive: feasible at ``T``); ``points``
    LMI solves on a logarithmic grid around ``tau_D``.  Needs a report with a dwell-time result.
    """
    from matplotlib.ticker import NullFormatter  # matplotlib only when a figure is drawn

    fig, (a,) = panels(ax, 1, figsize=(5.0, 4.0), owner="plot_dwell_margin")
    d = report.dwell
    if d is None:
        raise CertificateError("the report has no dwell-time result (a strict common P made it unnecessary); "
                               "plot_certification shows the spectra alone then")
    bal = balance(report.family.numeric)
    ref = float(d.tau_D) if d.tau_D is not None else max(d.tau_numeric, 1e-9)
    grid = np.geomspace(ref / 8, ref * 4, points)
    margins = [gc_margin(bal.matrices, T * bal.sigma)[1] for T in grid]
    a.semilogx(grid, margins, "o-", color="tab:blue", ms=4, label="LMI margin")
    a.axhline(0.0, color="0.4", lw=0.8)
    if d.certified and d.tau_D is not None:
        a.axvline(float(d.tau_D), color="tab:red", ls="--", label=f"certified τ_D = {float(d.tau_D):.4g}")
    a.set_xlabel("dwell time T (rescaled time τ)")
    a.set_ylabel("Geromel–Colaneri margin")
    a.xaxis.set_minor_formatter(NullFormatter())  # decade labels only: minor labels collide on a short range
    a.set_title("dwell-time LMI margin (feasible above 0)", fontsize=10)
    a.legend(fontsize=8, loc="upper left")
    return fig


def plot_certification(report: CertificationReport, *, ax: Any = None) -> Any:
    """The spectra of the modes and, when the verdict rests on a dwell time, its LMI margin against ``T``."""
    count = 1 if report.dwell is None else 2
    fig, axes = panels(ax, count, figsize=(5.0 * count, 4.0), owner="plot_certification", nrows=1, ncols=count)
    plot_spectra(report, ax=axes[0])
    if count == 2:
        plot_dwell_margin(report, ax=axes[1])
    fig.set_layout_engine("constrained")
    return fig


def _lyapunov(A: np.ndarray) -> np.ndarray:
    """``P`` with ``A' P + P A = -I``."""
    import scipy.linalg  # with the figure only, like matplotlib

    return scipy.linalg.solve_continuous_lyapunov(A.T, -np.eye(A.shape[0]))


def _worst_path(mats: Sequence[np.ndarray], x0: np.ndarray, sign: int, half_turns: int) -> np.ndarray | None:
    """The worst switching of Balde–Boscain–Mason as a feedback, turning in the direction ``sign``.

    At each point the mode that turns ``x`` in that direction with the largest growth of ``|x|`` per
    unit angle (``x' A x / (sign x × A x)``) is followed; ``None`` when at some point no mode turns
    that way (cases i and ii, where no trajectory turns around the origin).
    """
    import scipy.linalg

    dt = 0.02 / max(float(np.max(np.abs(np.linalg.eigvals(A)))) for A in mats)
    Es = [scipy.linalg.expm(A * dt) for A in mats]
    x, path, angle = x0, [x0], 0.0
    while angle < half_turns * np.pi:
        best = None
        for k, A in enumerate(mats):
            v = A @ x
            rot = sign * (x[0] * v[1] - x[1] * v[0])
            if rot > 0 and (best is None or x @ v / rot > best[0]):
                best = (float(x @ v / rot), k)
        if best is None or len(path) > 200_000:  # no mode turns that way, or one barely turns: no worst path
            return None
        new = Es[best[1]] @ x
        angle += sign * float(np.arctan2(x[0] * new[1] - x[1] * new[0], x @ new))  # signed angle of the step
        x = new
        path.append(x)
    return np.array(path)


def _greedy(mats: Sequence[np.ndarray], x0: np.ndarray, t_end: float, steps: int) -> np.ndarray:
    """The switching that always picks the mode along which ``|x|`` grows fastest (or decays slowest)."""
    import scipy.linalg

    dt = t_end / steps
    Es = [scipy.linalg.expm(A * dt) for A in mats]
    x, path = x0, [x0]
    for _ in range(steps):
        i = max(range(len(mats)), key=lambda k: float(x @ (mats[k] + mats[k].T) @ x))
        x = Es[i] @ x
        path.append(x)
    return np.array(path)


def plot_planar(classification: PlanarClassification, A1: Any, A2: Any, *, ax: Any = None, turns: int = 3) -> Any:
    """Level sets of each mode's Lyapunov function and a worst-case trajectory of the planar pair.

    The level sets are those of ``V_i = x' P_i x`` with ``A_i' P_i + P_i A_i = -I``.  The
    trajectory follows the worst switching of Balde–Boscain–Mason (the mode with the largest growth
    of ``|x|`` per unit angle, as :func:`~switchobs.certify.classify_planar` integrates for ``R``)
    for ``turns`` half-turns, so that ``|x|`` grows by about ``R`` per half-turn; when no trajectory
    turns around the origin, the switching that always picks the mode along which ``|x|`` grows fastest.
    """
    fig, (a,) = panels(ax, 1, figsize=(5.0, 4.6), owner="plot_planar")
    mats = list(as_family([A1, A2], list(classification.names), hurwitz=False).numeric)
    x0 = np.array([1.0, 0.0])
    paths = [p for p in (_worst_path(mats, x0, sign, turns) for sign in (1, -1)) if p is not None]
    if paths:
        path = max(paths, key=lambda p: float(np.linalg.norm(p[-1])))
        label = f"worst switching, {turns} half-turns" + (f" (R = {classification.R:.4g} each)"
                                                          if classification.R is not None else "")
    else:
        scale = min(float(np.min(-np.linalg.eigvals(A).real)) for A in mats)
        path = _greedy(mats, x0, 6.0 / scale, 600)
        label = "switching to the mode of fastest growth of |x|"
    span = 1.15 * max(1.0, float(np.max(np.abs(path))))
    g = np.linspace(-span, span, 161)
    X, Y = np.meshgrid(g, g)
    for k, (nm, A) in enumerate(zip(classification.names, mats)):
        P = _lyapunov(A)
        V = P[0, 0] * X ** 2 + 2 * P[0, 1] * X * Y + P[1, 1] * Y ** 2
        levels = float(x0 @ P @ x0) * np.array([0.25, 1.0, 4.0])
        a.contour(X, Y, V, levels=levels, colors=_COLOURS[k], linewidths=0.9,
                  linestyles="solid" if k == 0 else "dashed")
        a.plot([], [], color=_COLOURS[k], ls="solid" if k == 0 else "dashed", label=f"level sets of V for {nm}")
    a.plot(path[:, 0], path[:, 1], color="black", lw=1.3, label=label)
    a.plot(*x0, "ko", ms=4)
    a.set_aspect("equal")
    a.set_xlim(-span, span)
    a.set_ylim(-span, span)
    a.set_xlabel("x1")
    a.set_ylabel("x2")
    a.set_title(f"planar case ({classification.case}): {classification.stability}", fontsize=10)
    a.legend(fontsize=7, loc="upper left", framealpha=0.85)
    return fig
