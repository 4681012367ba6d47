"""Figures without pyplot: the plot functions draw on ``matplotlib.figure.Figure`` objects.

No backend is selected and no global figure state is touched, so the plot
functions behave the same in a script, a test and a Jupyter notebook (where
the returned Figure displays itself).  Every plot function takes ``ax=``: the
Axes to draw on (a sequence of them for a figure with several panels) or
``None`` for a new Figure, and returns the Figure; whoever wants a file calls
:func:`save_figure`.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ._atomic import atomic_file
from .exceptions import SimulationError

__all__ = ["panels", "save_figure", "figure_format"]


def panels(ax: Any, count: int, *, figsize: tuple[float, float], owner: str, **subplots: Any
           ) -> tuple[Any, list[Any]]:
    """``(figure, axes)``: the ``count`` Axes given as ``ax``, or a new Figure with ``count`` subplots.

    Parameters
    ----------
    ax : Axes, sequence of Axes or None
    count : int
        Panels the plot draws.
    figsize : (float, float)
        Size of a new Figure [in].
    owner : str
        The plot function, for the error message.
    **subplots
        Passed to ``Figure.subplots`` for a new Figure (``nrows``, ``ncols``, ``sharex``, ...);
        default one column of ``count`` rows.

    Raises
    ------
    SimulationError
        If ``ax`` holds another number of Axes than ``count``.
    """
    if ax is None:
        from matplotlib.figure import Figure

        fig = Figure(figsize=figsize)
        subplots.setdefault("nrows", count)
        made = fig.subplots(squeeze=False, **subplots)
        return fig, list(np.ravel(made))
    axes = list(np.ravel(ax)) if isinstance(ax, (Sequence, np.ndarray)) else [ax]
    if len(axes) != count:
        raise SimulationError(f"{owner} draws {count} panel(s); give ax= {count} Axes or None, got {len(axes)}")
    return axes[0].figure, axes


def figure_format(path: str | Path) -> str:
    """The image format matplotlib writes ``path`` in, from its suffix (``"png"`` for ``x.png``).

    Checked before any work (the command line does it when it reads ``--plot``), so a typo costs nothing.

    Raises
    ------
    SimulationError
        A path without a suffix or with one matplotlib does not write; the message names the path.
    """
    from matplotlib.backend_bases import FigureCanvasBase

    supported = FigureCanvasBase.get_supported_filetypes()
    suffix = Path(path).suffix.lstrip(".").lower()
    if suffix not in supported:
        got = f"the suffix {suffix!r}" if suffix else "no suffix"
        raise SimulationError(f"cannot write the plot {str(path)!r}: {got}; give one of "
                              f"{', '.join('.' + k for k in sorted(supported))}")
    return suffix


def save_figure(fig: Any, path: str | Path, *, dpi: int = 110) -> Path:
    """Write ``fig`` to ``path`` (format from the suffix); the path.

    The file appears whole or not at all (:func:`switchobs._atomic.atomic_file`).

    Raises
    ------
    OutputError
        If the file cannot be written (missing directory, a directory in the way); the message names it.
    SimulationError
        For a suffix that is not an image format matplotlib writes.
    """
    path = Path(path)
    kind = figure_format(path)
    with atomic_file(path, what="the plot") as partial:
        fig.savefig(partial, dpi=dpi, format=kind)
    return path
