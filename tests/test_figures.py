"""Certification plots (issue 16 item 5): `certify --plot`, `classify --plot`, the figure generator of the docs."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import numpy as np
import pytest
from _docs_blocks import matches_with_elisions, shown_output

from switchobs._figures import save_figure
from switchobs.certify import as_family, certify, classify_planar, plot_certification, plot_planar
from switchobs.cli.main import main
from switchobs.exceptions import OutputError, SimulationError

ROOT = Path(__file__).resolve().parents[1]
A1, A2 = [["-0.1", -1], [2, "-0.1"]], [["-0.1", -2], [1, "-0.1"]]  # planar case iv, R = 1.604 (docs/certify.md)


def _figure_commands() -> list[str]:
    """The `switchobs ...` lines of the Makefile's `figures` target."""
    text = (ROOT / "Makefile").read_text("utf-8")
    block = re.search(r"^figures:.*\n((?:\t.*\n)+)", text, re.M).group(1)
    return [line.strip().removeprefix("$(VENV)/bin/") for line in block.splitlines() if "switchobs" in line]


def _draw(line: str, pages: str, tmp_path: Path) -> tuple[str, Path]:
    """Run a figure line of the Makefile with its figure written under ``tmp_path``, after checking that the
    committed figure exists and ``pages`` use it; return the target and the figure drawn."""
    argv = shlex.split(line)[1:]
    target = argv[argv.index("--plot") + 1]
    assert f"({target.removeprefix('docs/')})" in pages and (ROOT / target).is_file()
    out = tmp_path / Path(target).name
    argv[argv.index("--plot") + 1] = str(out)
    assert main(argv) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    return target, out


def test_the_docs_figure_generator_runs_prints_what_the_page_shows_and_its_figures_are_used(tmp_path, capsys):
    commands = [line for line in _figure_commands() if line.split()[1] in ("certify", "classify")]
    assert len(commands) == 2
    docs = (ROOT / "docs" / "certify.md").read_text("utf-8")
    for line in commands:
        target, out = _draw(line, docs, tmp_path)
        printed = capsys.readouterr().out
        assert f"figure written to {out}\n" in printed
        # the page shows the same command without --plot: the same output less the figure's line
        shown = shown_output("certify.md", line.replace(f" --plot {target}", ""))
        assert matches_with_elisions(shown, printed.replace(f"figure written to {out}\n", "")), printed
    assert not list(tmp_path.glob(".*partial*"))


def test_the_braking_and_encoder_figures_are_drawn_by_the_figure_generator(tmp_path):
    """The braking and encoder figures of docs/abs.md and docs/encoders.md come from `make figures` (their numbers
    from `switchobs reproduce`)."""
    commands = [line for line in _figure_commands() if line.split()[1] in ("simulate", "encoder")]
    assert len(commands) == 5
    pages = (ROOT / "docs" / "abs.md").read_text("utf-8") + (ROOT / "docs" / "encoders.md").read_text("utf-8")
    for line in commands:
        _draw(line, pages, tmp_path)


def test_worst_trajectory_grows_by_R_per_half_turn():
    c = classify_planar(A1, A2)
    fig = plot_planar(c, A1, A2, turns=2)
    (ax,) = fig.axes
    path = next(line for line in ax.lines if line.get_label().startswith("worst switching")).get_xydata()
    growth = np.linalg.norm(path[-1]) / np.linalg.norm(path[0])
    assert growth == pytest.approx(c.R ** 2, rel=0.05)
    assert ax.get_title() == "planar case (iv): unbounded"


def test_certification_figure_marks_tau_D_and_plots_every_eigenvalue():
    rep = certify([[[-1, 0], [0, -2]], [[-2, 0], [0, -1]]])  # strict common P: no dwell time, one panel
    assert rep.dwell is None and len(plot_certification(rep).axes) == 1
    rep = certify(as_family([A1, A2]))
    assert rep.dwell is not None and rep.dwell.certified
    fig = plot_certification(rep)
    assert sum(len(c.get_offsets()) for c in fig.axes[0].collections) == 4
    tau = [line for line in fig.axes[1].lines if line.get_label().startswith("certified")]
    assert tau and tau[0].get_xdata()[0] == pytest.approx(float(rep.dwell.tau_D))


def test_save_figure_is_atomic(tmp_path):
    fig = plot_planar(classify_planar(A1, A2), A1, A2)
    with pytest.raises(OutputError, match="cannot write the plot .*missing.* does not exist"):
        save_figure(fig, tmp_path / "missing" / "x.png")
    with pytest.raises(SimulationError, match="cannot write"):
        save_figure(fig, tmp_path / "x.unknownformat")
    assert list(tmp_path.iterdir()) == []


def test_braking_figure_title_fits_and_legend_sits_above_the_xbs_data():
    from switchobs.plants import BrakingScenario, plot_braking, simulate

    res = simulate(BrakingScenario("dry-asphalt", speed_m_s=15.0, duration_s=0.5))
    fig = plot_braking(res)
    assert all(len(line) <= 110 for line in fig._suptitle.get_text().splitlines())
    xbs = fig.axes[4]
    # the limits are those of the ABS cycles (phase >= 1), not of the build-up's large XBS at small slip
    true = res.series["xbs"][res.series["phase"] >= 1]
    top = np.percentile(true[np.isfinite(true)], 99)
    assert xbs.get_ylim()[1] > top + 0.4 * (top - np.percentile(true[np.isfinite(true)], 1))  # legend headroom
    assert xbs.get_ylim()[1] < np.nanmax(res.series["xbs"])
