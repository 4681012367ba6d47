"""Numeric models of any size through the command line (issue 12 benchmark).

For n = 4, 8, 16, 32 (64 on request): a TOML model file per n (a chain of first-order lags
``x_i' = -d_i x_i + x_(i+1)``, ``d_i`` in 1, 3/2, 2, 5/2, seen through ``y = x_1``) and a
numeric spectrum (-2, -3, -5/2, -7/2 repeated).  Measured through the CLI, each in a
fresh process (``subprocess``, import time included):

* design  -- ``switchobs design MODEL --spectrum ... --json`` (exact K+, K-, Routh, P and re-check);
* certify -- ``switchobs certify MODEL --spectrum ... --no-dwell --out CERT`` (strict CQLF LMI with its
  dual, Hespanha with the design's exact P, every certificate re-checked exactly);
* verify  -- ``switchobs verify CERT`` (the independent exact checker);

beside what a user would write instead, measured in the same run on the same family
``A_plus, A_minus`` (floats, in process):

* cvxpy   -- a minimal common-P LMI: ``P >= I``, ``A_p' P + P A_p <= 0``, Clarabel;
* scipy   -- ``scipy.linalg.solve_continuous_lyapunov`` for ``A_plus`` (the floating-point floor).

Wall and CPU time (CPU of the child process for the CLI rows), median of REPEATS with
min-max.  Prints a markdown table and saves the log-log plot docs/numeric_scaling.png.
Run with ``python benchmarks/numeric_scaling.py [n ...]``.
"""

from __future__ import annotations

import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

#: n = 64 is left out: certify does not finish there in minutes (docs/certify.md); `python
#: benchmarks/numeric_scaling.py 64` tries it.
SIZES = (4, 8, 16, 32)
REPEATS = 3
TIMEOUT_S = 600
ROOT = Path(__file__).resolve().parents[1]
SWITCHOBS = [sys.executable, "-m", "switchobs"]
POLES = ("-2", "-3", "-5/2", "-7/2")


def chain_model(n: int) -> str:
    lags = ("1", "3/2", "2", "5/2")
    rows = []
    for i in range(n):
        row = ["0"] * n
        row[i] = f"-{lags[i % 4]}"
        if i < n - 1:
            row[i + 1] = "1"
        rows.append("[" + ", ".join(f'"{x}"' for x in row) + "]")
    states = ", ".join(f'"x{i + 1}"' for i in range(n))
    C = ", ".join(f'"{int(i == 0)}"' for i in range(n))
    return (f'name = "chain-{n}"\nstates = [{states}]\noutput = "y"\nA = [{", ".join(rows)}]\n'
            f'C = [{C}]\ntime_scale = "y"\n')


def spectrum(n: int) -> str:
    return ",".join(POLES[i % 4] for i in range(n))


def run_cli(args: list[str]) -> tuple[float, float, subprocess.CompletedProcess]:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(SWITCHOBS + args, capture_output=True, text=True, timeout=TIMEOUT_S, cwd=str(ROOT))
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, proc


def timed(fn) -> tuple[float, float]:
    t0, c0 = time.perf_counter(), time.process_time()
    fn()
    return time.perf_counter() - t0, time.process_time() - c0


def baselines(design: dict, failures: set[str]) -> dict[str, tuple[float, float]]:
    import cvxpy as cp
    import scipy.linalg

    mats = [np.array([[float(eval_rational(x)) for x in row] for row in design[k]]) for k in ("A_plus", "A_minus")]
    C = np.array([[float(eval_rational(x)) for x in design["C"]]])
    n = mats[0].shape[0]

    def lmi() -> None:
        P = cp.Variable((n, n), symmetric=True)
        cons = [P >> np.eye(n)] + [-(A.T @ P + P @ A) >> 0 for A in mats]
        problem = cp.Problem(cp.Minimize(0), cons)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", UserWarning)
                problem.solve(solver="CLARABEL")
        except cp.SolverError:
            failures.add("solver error")
            return
        if problem.status != cp.OPTIMAL:
            failures.add(problem.status)

    return {"cvxpy": timed(lmi),
            "scipy": timed(lambda: scipy.linalg.solve_continuous_lyapunov(mats[0].T, -C.T @ C))}


def eval_rational(text: str) -> float:
    num, _, den = text.partition("/")
    return int(num) / int(den or 1)


def stats(values: list[float]) -> str:
    return f"{statistics.median(values):.3g} ({min(values):.3g}–{max(values):.3g})"


def measure(n: int, tmp: Path) -> dict[str, dict[str, list]]:
    model = tmp / f"chain-{n}.toml"
    model.write_text(chain_model(n), encoding="utf-8")
    cert = tmp / f"chain-{n}.json"
    rows: dict[str, dict[str, list]] = {k: {"wall": [], "cpu": []}
                                               for k in ("design", "certify", "verify", "cvxpy", "scipy")}
    design = None
    failures: set[str] = set()
    for _ in range(REPEATS):
        for name, args in (("design", ["design", str(model), "--spectrum", spectrum(n), "--json"]),
                           ("certify", ["certify", str(model), "--spectrum", spectrum(n), "--no-dwell",
                                        "--out", str(cert)]),
                           ("verify", ["verify", str(cert)])):
            wall, cpu, proc = run_cli(args)
            if proc.returncode != 0:
                raise SystemExit(f"n = {n}: switchobs {name} exited {proc.returncode}: {proc.stderr[-400:]}")
            rows[name]["wall"].append(wall)
            rows[name]["cpu"].append(cpu)
            if name == "design":
                design = json.loads(proc.stdout)
        for name, (wall, cpu) in baselines(design, failures).items():
            rows[name]["wall"].append(wall)
            rows[name]["cpu"].append(cpu)
    rows["cvxpy"]["status"] = sorted(failures)
    return rows


def plot(results: dict[int, dict], path: Path) -> None:
    import matplotlib
    from matplotlib.figure import Figure
    from matplotlib.ticker import NullFormatter

    matplotlib.rcParams["svg.hashsalt"] = "switchobs"
    fig = Figure(figsize=(6, 4))
    ax = fig.add_subplot()
    sizes = sorted(results)
    for name in ("design", "certify", "verify", "cvxpy", "scipy"):
        ax.loglog(sizes, [statistics.median(results[n][name]["wall"]) for n in sizes], "o-", label=name)
    ax.set_xlabel("state dimension n")
    ax.set_ylabel("wall time [s] (median)")
    ax.set_xticks(sizes, [str(n) for n in sizes])
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    ax.set_title("numeric chain models through the CLI")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main() -> None:
    sizes = tuple(int(a) for a in sys.argv[1:]) or SIZES
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for n in sizes:
            results[n] = measure(n, Path(tmp))
            print(f"n = {n} done", file=sys.stderr, flush=True)
    print(f"n | design wall [s] | certify wall [s] | verify wall [s] | cvxpy LMI wall [s] | scipy Lyapunov wall [s] "
          f"| certify CPU [s] | certify / cvxpy\n---|---:|---:|---:|---:|---:|---:|---:")
    for n in sizes:
        r = results[n]
        ratio = statistics.median(r["certify"]["wall"]) / statistics.median(r["cvxpy"]["wall"])
        print(f"{n} | {stats(r['design']['wall'])} | {stats(r['certify']['wall'])} | {stats(r['verify']['wall'])} "
              f"| {stats(r['cvxpy']['wall'])}{' ' + '/'.join(r['cvxpy']['status']) if r['cvxpy']['status'] else ''} "
              f"| {stats(r['scipy']['wall'])} | {stats(r['certify']['cpu'])} "
              f"| {ratio:.0f}x")
    if os.environ.get("SWITCHOBS_BENCH_PLOT", "1") == "1" and len(sizes) > 1:
        plot(results, ROOT / "docs" / "numeric_scaling.png")


if __name__ == "__main__":
    main()
