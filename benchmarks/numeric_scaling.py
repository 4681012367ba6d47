"""Numeric models of any size through the command line (issue 12 benchmark).

For n = 4, 8, 16, 32, 64: a TOML model file per n (a chain of first-order lags
``x_i' = -d_i x_i + x_(i+1)``, ``d_i`` in 1, 3/2, 2, 5/2, seen through ``y = x_1``) and a
numeric spectrum (-2, -3, -5/2, -7/2 repeated).  Measured through the CLI, each in a
fresh process (``subprocess``, import time included):

* design  -- ``switchobs design MODEL --spectrum ... --json`` (exact K+, K-, Routh, P and re-check);
* certify -- ``switchobs certify MODEL --spectrum ... --out CERT`` (no strict CQLF by the exact
  singular-sum proof, Hespanha with the design's exact P, the document re-checked exactly; the
  Geromel-Colaneri bisection does not run, the Hespanha certificate gives every dwell time);
* verify  -- ``switchobs verify CERT`` (the independent exact checker);
* the same two with ``--arithmetic interval`` (strict definiteness by arb balls);

beside what a user would write instead, measured in the same run on the same family
``A_plus, A_minus`` (floats, in process):

* cvxpy   -- a minimal common-P LMI: ``P >= I``, ``A_p' P + P A_p <= 0``, Clarabel;
* scipy   -- ``scipy.linalg.solve_continuous_lyapunov`` for ``A_plus`` (the floating-point floor).

CPU time (``RUSAGE_CHILDREN`` for the CLI processes, ``time.process_time`` in process), median
[min–max] of 5 runs; the table goes to ``benchmarks/results/numeric_scaling.md`` and the log-log plot
to docs/numeric_scaling.png.  Run with ``python benchmarks/numeric_scaling.py [--quick] [n ...]``
(``--quick``: n <= 16, printed only).
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
from _harness import MIN_REPEATS, Stats, publish, ratio, switchobs_exe

SIZES = (4, 8, 16, 32, 64)
TIMEOUT_S = 900
ROOT = Path(__file__).resolve().parents[1]
POLES = ("-2", "-3", "-5/2", "-7/2")
COMMANDS = ("design", "certify", "verify", "certify interval", "verify interval")


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


def run_cli(args: list[str]) -> tuple[float, subprocess.CompletedProcess]:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run([switchobs_exe(), *args], capture_output=True, text=True, timeout=TIMEOUT_S,
                          cwd=str(ROOT))
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), proc


def timed(fn) -> float:
    c0 = time.process_time()
    fn()
    return time.process_time() - c0


def baselines(design: dict, failures: set[str]) -> dict[str, float]:
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


def measure(n: int, tmp: Path, repeats: int) -> dict:
    model = tmp / f"chain-{n}.toml"
    model.write_text(chain_model(n), encoding="utf-8")
    cert = tmp / f"chain-{n}.json"
    cert_interval = tmp / f"chain-{n}-interval.json"
    runs: dict[str, list[float]] = {k: [] for k in (*COMMANDS, "cvxpy", "scipy")}
    design = None
    failures: set[str] = set()
    commands = {"design": ["design", str(model), "--spectrum", spectrum(n), "--json"],
                "certify": ["certify", str(model), "--spectrum", spectrum(n), "--out", str(cert)],
                "verify": ["verify", str(cert)],
                "certify interval": ["certify", str(model), "--spectrum", spectrum(n), "--arithmetic", "interval",
                                     "--out", str(cert_interval)],
                "verify interval": ["verify", str(cert_interval), "--arithmetic", "interval"]}
    for _ in range(repeats):
        for name in COMMANDS:
            cpu, proc = run_cli(commands[name])
            if proc.returncode != 0:
                raise SystemExit(f"n = {n}: switchobs {name} exited {proc.returncode}: {proc.stderr[-400:]}")
            runs[name].append(cpu)
            if name == "design":
                design = json.loads(proc.stdout)
        for name, cpu in baselines(design, failures).items():
            runs[name].append(cpu)
    out = {k: Stats(tuple(v)) for k, v in runs.items()}
    out["cvxpy status"] = sorted(failures)
    return out


def plot(results: dict[int, dict], path: Path) -> None:
    import matplotlib
    from matplotlib.figure import Figure
    from matplotlib.ticker import NullFormatter

    matplotlib.rcParams["svg.hashsalt"] = "switchobs"
    fig = Figure(figsize=(6, 4))
    ax = fig.add_subplot()
    sizes = sorted(results)
    for name in (*COMMANDS, "cvxpy", "scipy"):
        ax.loglog(sizes, [results[n][name].median for n in sizes], "o-", label=name)
    ax.set_xlabel("state dimension n")
    ax.set_ylabel("CPU time [s] (median)")
    ax.set_xticks(sizes, [str(n) for n in sizes])
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    ax.set_title("numeric chain models through the CLI")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sizes", nargs="*", type=int, help=f"state dimensions (default {list(SIZES)})")
    parser.add_argument("--quick", action="store_true", help="n <= 16; print, do not publish or plot")
    parser.add_argument("--repeats", type=int, default=MIN_REPEATS)
    args = parser.parse_args()
    sizes = tuple(args.sizes) or tuple(n for n in SIZES if n <= 16 or not args.quick)
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for n in sizes:
            results[n] = measure(n, Path(tmp), args.repeats)
            print(f"n = {n} done", file=sys.stderr, flush=True)
    table = ["| n | design [s] | certify [s] | verify [s] | certify, interval [s] | verify, interval [s] "
             "| cvxpy LMI [s] | scipy Lyapunov [ms] | certify vs cvxpy |",
             "|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
    for n in sizes:
        r = results[n]
        status = " " + "/".join(r["cvxpy status"]) if r["cvxpy status"] else ""
        table.append(f"| {n} | " + " | ".join(r[k].show() for k in COMMANDS)
                     + f" | {r['cvxpy'].show()}{status} | {r['scipy'].show(1e3)} "
                       f"| {ratio(r['certify'].median, r['cvxpy'].median)} |")
    method = ("Chain models $\\dot x_i = -d_ix_i + x_{i+1}$, $d_i \\in \\{1, 3/2, 2, 5/2\\}$, $y = x_1$, from TOML "
              "files, spectrum $-2, -3, -5/2, -7/2$ repeated. Each command is a whole `switchobs` process "
              "(interpreter and imports included), CPU time (`RUSAGE_CHILDREN`), median [min–max] of "
              f"{args.repeats} runs, in s: `design --json` (exact gains, Routh array, $P$, re-check); `certify --out` "
              "(no strict CQLF by the exact singular-sum proof, Hespanha from the design's exact $P$, the "
              "document re-checked exactly); `verify`; the same two with `--arithmetic interval`. Baselines in "
              "the same run, in process (`time.process_time`): a minimal cvxpy common-$P$ LMI ($P \\succeq I$, "
              "$A_p^\\top P + PA_p \\preceq 0$, Clarabel; its status when it fails) and "
              "`scipy.linalg.solve_continuous_lyapunov` for $A_+$.")
    largest = max(sizes)
    notes = [f"Goals of issue 12 (this run): certify at n = 32 below 5 s: "
             + (f"{results[32]['certify'].median:.2g} s CPU" if 32 in results else "not run")
             + f"; certify at n = 64 below 60 s: "
             + (f"{results[64]['certify'].median:.2g} s CPU exact, {results[64]['certify interval'].median:.2g} s "
                "interval" if 64 in results else "not run")
             + f"; design at n = 64 below 5 s: "
             + (f"{results[64]['design'].median:.2g} s CPU" if 64 in results else "not run")
             + f". The largest size run is n = {largest}."]
    publish("numeric_scaling", method, [table], notes, write=not args.quick)
    if not args.quick and len(sizes) > 1:
        plot(results, ROOT / "docs" / "numeric_scaling.png")


if __name__ == "__main__":
    main()
