"""``switchobs sweep SPEC.toml``: a design-space or robustness sweep on Dask, its tables, figures and tuned gains.

The spec file (TOML, ``docs/sweeps.md``) lists the cases (a grid, Monte-Carlo draws per grid point) and
what to show of them.  Rows stream to ``--out`` (JSON Lines, one per case, keyed by its hash; a ``.parquet``
ending: the same rows as a Parquet table, streamed to a journal beside it until the table is written);
``--resume`` continues a killed sweep; ``--scheduler`` picks the engine: ``local`` (a LocalCluster, one
process per core), ``tcp://HOST:PORT`` (an existing Dask cluster) or ``none`` (serially, in-process).
The whole spec and the sweep's size (``--max-cases``, ``--max-steps``: :data:`switchobs._limits.MAX_SWEEP_CASES`,
:data:`switchobs._limits.MAX_SWEEP_STEPS`) are checked before any case runs; the default ``--out`` is the spec's
name reduced to a plain file name in the current directory.
Exit status 1 when a case failed (its row holds the error; one ``failed:`` line on stderr says how many).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from .._atomic import check_output_directory, staged_directory
from .._figures import save_figure
from .._limits import MAX_SWEEP_CASES, MAX_SWEEP_STEPS
from ..exceptions import SimulationError
from ..sweep import (check_tunable, load_sweep_spec, plot_heatmap, plot_pareto, run_sweep, summary_table, tune_betas)
from ._common import STDIO, emit_json

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("sweep",
                       description="Run the cases of a sweep spec file on a Dask cluster (or in-process), stream "
                                   "one JSON line per case, print the summary tables, draw the heatmaps and, "
                                   "with --tune, pick the Pareto-optimal observer gains.")
    p.add_argument("spec", metavar="SPEC", help="sweep spec file (TOML; see docs/sweeps.md and examples/*.toml)")
    p.add_argument("--out", metavar="RESULTS", help="results file: JSON Lines, or a Parquet table for a .parquet "
                                                    "ending (needs pyarrow) (default: <spec name>.jsonl)")
    p.add_argument("--resume", action="store_true", help="keep the rows already in --out and run the rest")
    p.add_argument("--scheduler", default="local", metavar="WHERE",
                   help="local (LocalCluster, default), tcp://HOST:PORT (an existing Dask scheduler) or none "
                        "(serially in this process)")
    p.add_argument("--workers", type=int, help="worker processes of the local cluster (default: one per core)")
    p.add_argument("--batch-size", type=int, help="cases per Dask task (default: about 4 batches per worker)")
    p.add_argument("--limit", type=int, metavar="N",
                   help="run only the first N cases of the spec (a quick try of a large spec)")
    p.add_argument("--plots", metavar="DIR",
                   help="write the heatmaps (and pareto.png with --tune) here (created if missing)")
    p.add_argument("--tune", action="store_true",
                   help="pick the Pareto-optimal (beta1, beta2) of the grid and print its design command")
    p.add_argument("--json", action="store_true", help="print the summary, tables and tuned design as JSON")
    p.add_argument("--max-cases", type=_limit("--max-cases"), default=MAX_SWEEP_CASES, metavar="N",
                   help=f"refuse a sweep of more cases, before any runs (default {MAX_SWEEP_CASES})")
    p.add_argument("--max-steps", type=_limit("--max-steps"), default=MAX_SWEEP_STEPS, metavar="N",
                   help=f"refuse a sweep whose braking cases take more integration steps, each case counted at "
                        f"duration_s / dt_s (default {MAX_SWEEP_STEPS:.0e})")
    p.set_defaults(func=run)


def _limit(option: str):  # type: ignore[no-untyped-def]
    """An argparse type: a whole number >= 1, also written 1e6."""
    def parse(text: str) -> int:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{option} needs a whole number >= 1, got {text!r}") from None
        if not (math.isfinite(value) and value >= 1 and value == int(value)):
            raise argparse.ArgumentTypeError(f"{option} needs a whole number >= 1, got {text!r}")
        return int(value)
    return parse


def run(args: argparse.Namespace) -> int:
    if args.workers is not None and args.workers < 1:
        raise SimulationError(f"--workers must be >= 1, got {args.workers}")
    if args.batch_size is not None and args.batch_size < 1:
        raise SimulationError(f"--batch-size must be >= 1, got {args.batch_size}")
    if args.limit is not None and args.limit < 1:
        raise SimulationError(f"--limit must be >= 1, got {args.limit}")
    for option, value in (("--out", args.out), ("--plots", args.plots)):
        if value is not None and not value.strip():
            raise SimulationError(f"{option} {value!r}: give a file or directory name")
    if args.out == STDIO:
        raise SimulationError("--out -: the results file of a sweep is rewritten in case order and resumed, so it "
                              "cannot be standard output; give a file name (--json prints the summary)")
    plots = None if args.plots is None else check_output_directory(args.plots, what="the --plots directory")
    spec = load_sweep_spec(args.spec, max_cases=args.max_cases)  # every case, table and heatmap checked
    # the spec's name is reduced to a plain file name in the current directory: never a path from a file
    out = Path(args.out) if args.out is not None else Path(spec.results_file)
    cases = spec.cases if args.limit is None else spec.cases[:args.limit]
    if args.tune:
        check_tunable(cases)  # before the cases run, not after
    sweep = run_sweep(cases, path=out, resume=args.resume, scheduler=args.scheduler, workers=args.workers,
                      batch_size=args.batch_size, max_cases=args.max_cases, max_steps=args.max_steps)
    tables = [summary_table(sweep.results, rows=t.rows, column=t.column, metric=t.metric) for t in spec.tables]
    tuned = tune_betas(sweep.results) if (args.tune or spec.tune) else None
    written = []
    # every case failed: no figure to draw, and the failure is reported below (not as an error of the figures)
    if plots is not None and (spec.heatmaps or tuned is not None) and any(r.ok for r in sweep.results):
        figures = [(h.filename, lambda h=h: plot_heatmap(sweep.results, x=h.x, y=h.y, metric=h.metric))
                   for h in spec.heatmaps]
        if tuned is not None:
            figures.append(("pareto.png", lambda: plot_pareto(tuned)))
        with staged_directory(plots, what="the --plots directory") as work:  # all the figures or none
            for name, draw in figures:
                save_figure(draw(), work / name)
        written = [plots / name for name, _ in figures]
    if args.json:
        emit_json({"spec": spec.to_json(), "sweep": {k: v for k, v in sweep.to_json().items() if k != "rows"},
                   "tables": [t.to_json() for t in tables], "tuned": None if tuned is None else tuned.to_json(),
                   "plots": [str(p) for p in written],
                   "failed": [r.to_json() for r in sweep.failed]})
    else:
        print(spec)
        print(sweep)
        for r in sweep.failed[:10]:
            print(f"  FAILED {r.case_id}: {r}")
        for t in tables:
            print()
            print(t)
        if tuned is not None:
            print()
            print(tuned)
        for p in written:
            print(f"wrote {p}")
    if not sweep.failed:
        return 0
    # a failed run's one line on stderr (docs/errors.md), after the results
    print(f"switchobs sweep: failed: {len(sweep.failed)} of {len(sweep.results)} cases failed (their rows in "
          f"{sweep.path or 'the results'} hold the errors)", file=sys.stderr)
    return 1
