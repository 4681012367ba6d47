"""Figures of a sweep: a heatmap of a metric over two case fields, the Pareto front of the gains."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from .._figures import panels
from ..exceptions import SimulationError
from ._analysis import TunedDesign, summary_table
from ._run import CaseResult

__all__ = ["plot_heatmap", "plot_pareto", "LABELS", "label"]

#: Human names, with units, of the case fields and metrics a figure shows (any other name is shown as it is).
LABELS: dict[str, str] = {
    "speed_kmh": "initial speed [km/h]", "road": "road", "controller": "ABS algorithm", "observer": "observer",
    "beta1": "observer rate beta1", "beta2": "observer rate beta2", "gamma": "adaptation gain gamma",
    "load_n": "wheel load Fz [N]", "dt_s": "integration step [s]", "encoder_ppr": "encoder pulses per revolution",
    "braking_distance_m": "braking distance (Table 4.1 definition) [m]",
    "stopping_distance_m": "distance travelled [m]", "stop_time_s": "stop time [s]",
    "mean_friction": "mean friction", "abs_activation_s": "ABS activation time [s]", "abs_cycles": "ABS cycles",
    "slip_mean": "mean slip", "efficiency": "friction used / peak friction", "xbs_rms": "XBS error RMS",
    "xbs_rms_settled": "settled XBS error RMS", "reconvergence_max_s": "worst re-convergence (10 %) after a road change [s]",
    "recovery_max_s": "worst recovery to the noise floor after a road change [s]", "simulated_s": "simulated time [s]",
}


def label(name: str) -> str:
    """The human name of a case field or metric (:data:`LABELS`), else ``name``.

    Examples
    --------
    >>> label("speed_kmh"), label("no_such_field")
    ('initial speed [km/h]', 'no_such_field')
    """
    return LABELS.get(name, name)


def plot_heatmap(results: Sequence[CaseResult], *, x: str, y: str, metric: str, ax: Any = None,
                 title: str | None = None) -> Any:
    """The mean of ``metric`` per (``y``, ``x``) cell, each cell annotated (e.g. road × speed of the braking distance).

    Returns
    -------
    matplotlib.figure.Figure
    """
    table = summary_table(results, rows=[y], column=x, metric=metric)
    if not table.row_keys:
        raise SimulationError(f"no finished case to draw {metric} over {y} x {x}")
    data = np.array([[math.nan if v is None else v for v in row] for row in table.cells], dtype=float)
    fig, (axis,) = panels(ax, 1, figsize=(1.2 + 1.0 * len(table.column_keys), 1.2 + 0.45 * len(table.row_keys)),
                          owner="plot_heatmap")
    image = axis.imshow(np.ma.masked_invalid(data), aspect="auto", cmap="viridis")
    axis.set_xticks(range(len(table.column_keys)), [f"{c:g}" if isinstance(c, float) else str(c)
                                                    for c in table.column_keys])
    axis.set_yticks(range(len(table.row_keys)), [f"{k[0]:g}" if isinstance(k[0], float) else str(k[0])
                                                 for k in table.row_keys])
    axis.set_xlabel(label(x))
    axis.set_ylabel(label(y))
    finite = data[np.isfinite(data)]
    middle = float(np.mean([finite.min(), finite.max()])) if finite.size else 0.0
    for (i, j), v in np.ndenumerate(data):
        if math.isfinite(v):
            axis.text(j, i, f"{v:.3g}", ha="center", va="center", fontsize=7,
                      color="white" if v < middle else "black")
    fig.colorbar(image, ax=axis, label=label(metric))
    axis.set_title(title or f"mean {label(metric)}")
    fig.tight_layout()
    return fig


def plot_pareto(tuned: TunedDesign, *, ax: Any = None) -> Any:
    """Every gain pair's costs, the Pareto front, and the chosen design marked.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, (axis,) = panels(ax, 1, figsize=(6.0, 4.2), owner="plot_pareto")
    finite = [p for p in tuned.pairs if math.isfinite(p[2]) and math.isfinite(p[3])]
    axis.scatter([p[2] for p in finite], [p[3] for p in finite], s=18, color="0.6", label="gain pairs")
    front = [tuned.pairs[i] for i in tuned.front]
    axis.plot([p[2] for p in front], [p[3] for p in front], "o-", color="C0", label="Pareto front")
    # neighbours on the front alternate above and below it, so that their labels do not overprint
    for k, (b1, b2, r, n, _) in enumerate(front):
        axis.annotate(f"{b1:g}/{b2:g}", (r, n), textcoords="offset points", xytext=(4, 4 if k % 2 == 0 else -11),
                      fontsize=7)
    axis.plot([tuned.reconvergence_s], [tuned.noise_rms], "*", color="C3", markersize=14,
              label=f"chosen: beta {tuned.beta1:g}/{tuned.beta2:g}")
    axis.set_xlabel(label("recovery_max_s"))
    axis.set_ylabel(label("xbs_rms_settled"))
    axis.set_title(f"{tuned.observer} gains: re-convergence vs noise")
    axis.legend(fontsize=8)
    fig.tight_layout()
    return fig
