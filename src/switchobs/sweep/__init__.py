"""Design-space and robustness sweeps: thousands of braking and certification runs, on Dask or in-process.

A sweep is a set of cases, each a frozen, hashable, picklable spec of primitives
(:class:`BrakingCase`, :class:`CertifyCase`); :func:`run_case` builds everything from the spec where it
runs and returns metrics, never whole time series unless asked.  :func:`run_sweep` spreads the cases
in batches over a Dask cluster (a ``LocalCluster`` of one process per core, or an existing scheduler),
streams the rows to a JSON Lines file keyed by the case id, and resumes where a killed sweep stopped.

Public API
----------
BrakingCase, CertifyCase, CONTROLLERS, case_from_json -- case specs
run_case, CaseResult                                  -- one case, pure
grid, linspace, arange, certify_grid, a_of_load       -- cartesian grids and ranges
monte_carlo, monte_carlo_case, Uniform, Choice, Integers, RoadChanges
                                                      -- Monte-Carlo draws, per-case seeds from one root seed
run_sweep, SweepResult, read_results, dask_client     -- the engine (Dask or ``scheduler="none"``)
SweepSpec, load_sweep_spec                            -- sweep spec files (TOML)
summary_table, pareto_front, tune_betas, TunedDesign, check_tunable
                                                      -- tables and gain tuning
plot_heatmap, plot_pareto                             -- figures
LABELS, label                                         -- human names with units of case fields and metrics

Example::

    from switchobs.sweep import BrakingCase, grid, run_sweep
    cases = grid(BrakingCase(), road=["dry-asphalt", "snow"], speed_kmh=[60.0, 120.0])
    sweep = run_sweep(cases, path="rows.jsonl", scheduler="local")
    print(sweep)
"""

from ._analysis import TunedDesign, check_tunable, pareto_front, summary_table, tune_betas
from ._case import CONTROLLERS, BrakingCase, CertifyCase, case_from_json
from ._engine import SweepResult, dask_client, read_results, run_sweep
from ._grid import (Choice, Integers, RoadChanges, Uniform, a_of_load, arange, certify_grid, grid, linspace,
                    monte_carlo, monte_carlo_case)
from ._plots import LABELS, label, plot_heatmap, plot_pareto
from ._run import CaseResult, run_case
from ._spec import SweepSpec, load_sweep_spec

__all__ = ["BrakingCase", "CertifyCase", "CONTROLLERS", "case_from_json", "run_case", "CaseResult",
           "grid", "linspace", "arange", "certify_grid", "a_of_load", "monte_carlo", "monte_carlo_case",
           "Uniform", "Choice", "Integers", "RoadChanges", "run_sweep", "SweepResult", "read_results",
           "dask_client", "SweepSpec", "load_sweep_spec", "summary_table", "pareto_front", "tune_betas",
           "TunedDesign", "check_tunable", "plot_heatmap", "plot_pareto", "LABELS", "label"]
