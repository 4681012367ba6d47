"""``switchobs sweep SPEC.toml``: a design-space or robustness sweep on Dask, its tables, figures and tuned gains.

The spec file (TOML, ``docs/sweeps.md``) lists the cases (a grid, Monte-Carlo draws per grid point) and
what to show of them.  Rows stream to ``--out`` (JSON Lines, one per case, keyed by its hash);
``--resume`` continues a killed sweep; ``--scheduler`` picks the engine: ``local`` (a LocalCluster, one
process per core), ``tcp://HOST:PORT`` (an existing Dask cluster) or ``none`` (serially, in-process).
Exit status 1 when a case failed (its row holds the error).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from .._figures import save_figure
from .._atomic import check_output_directory
from ..exceptions import SimulationError
from ..sweep import (check_tunable, load_sweep_spec, plot_heatmap, plot_pareto, run_sweep, summary_table, tune_betas)
from ._common import emit_json

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("sweep",
                       description="Run the cases of a sweep spec file on a Dask cluster (or in-process), stream "
                                   "one JSON line per case, print the summary tables, draw the heatmaps and, "
                                   "with --tune, pick the Pareto-optimal observer gains.")
    p.add_argument("spec", metavar="SPEC", help="sweep spec file (TOML; see docs/sweeps.md and examples/*.toml)")
    p.add_argument("--out", metavar="JSONL", help="results file (default: <spec name>.jsonl)")
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
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    if args.workers is not None and args.workers < 1:
        raise SimulationError(f"--workers must be >= 1, got {args.workers}")
    if args.batch_size is not None and args.batch_size < 1:
        raise SimulationError(f"--batch-size must be >= 1, got {args.batch_size}")
    if args.limit is not None and args.limit < 1:
        raise SimulationError(f"--limit must be >= 1, got {args.limit}")
    plots = None if args.plots is None else check_output_directory(args.plots, what="the plots into")
    spec = load_sweep_spec(args.spec)
    cases = spec.cases if args.limit is None else spec.cases[:args.limit]
    out = Path(args.out) if args.out else Path(f"{spec.name}.jsonl")
    if args.tune or spec.tune:
        check_tunable(cases)  # before the cases run, not after
    sweep = run_sweep(cases, path=out, resume=args.resume, scheduler=args.scheduler, workers=args.workers,
                      batch_size=args.batch_size)
    tables = [summary_table(sweep.results, rows=t.rows, column=t.column, metric=t.metric) for t in spec.tables]
    tuned = tune_betas(sweep.results) if (args.tune or spec.tune) else None
    written = []
    if plots is not None:
        plots.mkdir(parents=True, exist_ok=True)   # after the run: a failed sweep leaves no directory behind
        for h in spec.heatmaps:
            written.append(save_figure(plot_heatmap(sweep.results, x=h.x, y=h.y, metric=h.metric),
                                       plots / h.filename))
        if tuned is not None:
            written.append(save_figure(plot_pareto(tuned), plots / "pareto.png"))
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
    return 1 if sweep.failed else 0
