"""Numeric models of any size through the command line (issue 12 benchmark).

For n = 4, 8, 16, 32, 64: a TOML model file per n (a chain of first-order lags
``x_i' = -d_i x_i + x_(i+1)``, ``d_i`` in 1, 3/2, 2, 5/2, seen through ``y = x_1``) and a
numeric spectrum (-2, -3, -5/2, -7/2 repeated).  Measured through the CLI, each in a
fresh process (``subprocess``, interpreter start-up and imports included):

* design  -- ``switchobs design MODEL --spectrum ... --json`` (exact K+, K-, Routh, P and re-check);
* certify -- ``switchobs certify MODEL --spectrum ... --out CERT`` (no strict CQLF by the exact
  singular-sum proof, Hespanha with the design's exact P, the document re-checked exactly; the
  Geromel-Colaneri bisection does not run, the Hespanha certificate gives every dwell time);
* verify  -- ``switchobs verify CERT`` (the independent exact checker);

beside what a user would write instead, on the same family ``A_plus, A_minus`` (floats) in the same run,
like for like (``_numeric_baseline.py``):

* the minimal cvxpy common-P LMI with a margin on the balanced family, with Clarabel and with SCS: a whole
  ``python`` process (imports included) beside the solve alone, in process;
* ``certify_model`` (the library call behind ``switchobs certify``) on the loaded model, in process;
* ``scipy.linalg.solve_continuous_lyapunov`` for ``A_plus`` (the floating-point floor, in process);
* the status of the plain ``P >= I, A_p' P + P A_p <= 0`` form (Clarabel, once): where it fails.

CPU time (``RUSAGE_CHILDREN`` for a whole process, ``time.process_time`` in process), median
[min–max] of 5 runs; every child runs with bytecode caching on (``PYTHONPYCACHEPREFIX`` in the run's
temporary directory, warmed by one untimed run), as an installed package has it.  The tables go to
``benchmarks/results/numeric_scaling.md`` and the log-log plot to docs/numeric_scaling.png.  Run with
``python benchmarks/numeric_scaling.py [--quick] [n ...]`` (``--quick``: n = 4 and 8, one run each with the
installation's bytecode caches and no warm-up run, printed only).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from _harness import MIN_REPEATS, Stats, publish, ratio, switchobs_exe

SIZES = (4, 8, 16, 32, 64)
QUICK_SIZES = (4, 8)
TIMEOUT_S = 900
ROOT = Path(__file__).resolve().parents[1]
BASELINE = Path(__file__).resolve().with_name("_numeric_baseline.py")
POLES = ("-2", "-3", "-5/2", "-7/2")
COMMANDS = ("design", "certify", "verify")
SOLVERS = ("CLARABEL", "SCS")
SOLVER_NAMES = {"CLARABEL": "Clarabel", "SCS": "SCS"}
GOAL_N, GOAL_RATIO = 32, 3.0


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


def child_env(tmp: Path, quick: bool) -> dict[str, str]:
    """The children's environment: bytecode cached under ``tmp`` (whatever PYTHONDONTWRITEBYTECODE says).

    A quick run keeps the installation's own bytecode caches instead: compiling every module the children
    import into a fresh cache would cost more than the quick run's few timed processes.
    """
    if quick:
        return dict(os.environ)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPYCACHEPREFIX"] = str(tmp / "pycache")
    return env


def run(argv: list[str], env: dict[str, str]) -> tuple[float, subprocess.CompletedProcess]:
    """CPU time (user + system) of the whole process ``argv``, and the process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run(argv, capture_output=True, text=True, timeout=TIMEOUT_S, cwd=str(ROOT), env=env)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(argv[:3])} ... exited {proc.returncode}: {proc.stderr[-400:]}")
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), proc


def timed(fn) -> float:
    c0 = time.process_time()
    fn()
    return time.process_time() - c0


def floats(design: dict) -> list[np.ndarray]:
    return [np.array([[eval_rational(x) for x in row] for row in design[k]]) for k in ("A_plus", "A_minus")]


def eval_rational(text: str) -> float:
    num, _, den = text.partition("/")
    return int(num) / int(den or 1)


def measure(n: int, tmp: Path, repeats: int, env: dict[str, str], warm_up: bool) -> dict:
    model = tmp / f"chain-{n}.toml"
    model.write_text(chain_model(n), encoding="utf-8")
    cert = tmp / f"chain-{n}.json"
    family = tmp / f"chain-{n}.npz"
    exe, py = switchobs_exe(), sys.executable
    commands = {"design": [exe, "design", str(model), "--spectrum", spectrum(n), "--json"],
                "certify": [exe, "certify", str(model), "--spectrum", spectrum(n), "--out", str(cert)],
                "verify": [exe, "verify", str(cert)],
                "certify in process": [py, str(BASELINE), "certify", str(model), spectrum(n)],
                **{f"lmi {s}": [py, str(BASELINE), "lmi", str(family), s] for s in SOLVERS}}
    # "certify in process" is the time the child prints; an LMI child gives both its process and its solve
    runs: dict[str, list[float]] = {k: [] for k in (*commands, *(f"lmi {s} in process" for s in SOLVERS), "scipy")}
    status: dict[str, set[str]] = {s: set() for s in SOLVERS}
    mats: list[np.ndarray] = []
    for rep in range(repeats + warm_up):
        for name, argv in commands.items():
            cpu, proc = run(argv, env)
            if name == "design" and not mats:
                mats = floats(json.loads(proc.stdout))
                np.savez(family, A_plus=mats[0], A_minus=mats[1])
            if rep < warm_up:   # compiles the bytecode of every module the children import
                continue
            if name == "certify in process":
                out = json.loads(proc.stdout)
                if out["status"] != "certified":
                    raise SystemExit(f"n = {n}: certify_model did not certify the chain")
                runs[name].append(out["cpu"])
                continue
            runs[name].append(cpu)
            if name.startswith("lmi "):
                out = json.loads(proc.stdout)
                runs[f"{name} in process"].append(out["cpu"])
                status[name.removeprefix("lmi ")].add(out["status"])
        if rep >= warm_up:
            import scipy.linalg

            C = np.zeros((1, n))
            C[0, 0] = 1.0
            runs["scipy"].append(timed(lambda: scipy.linalg.solve_continuous_lyapunov(mats[0].T, -C.T @ C)))
    from _numeric_baseline import plain

    result: dict = {k: Stats(tuple(v)) for k, v in runs.items()}
    result["status"] = {s: sorted(v) for s, v in status.items()}
    result["plain"] = plain(mats, "CLARABEL")
    return result


def best_lmi(r: dict, suffix: str) -> tuple[str, float] | None:
    """The faster solver whose every run answered ``optimal``, and its median (``None``: none did)."""
    answered = [(r[f"lmi {s}{suffix}"].median, s) for s in SOLVERS if r["status"][s] == ["optimal"]]
    return (min(answered)[1], min(answered)[0]) if answered else None


def versus(ours: float, best: tuple[str, float] | None) -> str:
    return "no LMI answered" if best is None else f"{ratio(ours, best[1])} (vs {SOLVER_NAMES[best[0]]})"


def lmi_cell(r: dict, solver: str, suffix: str, scale: float = 1.0) -> str:
    bad = [s for s in r["status"][solver] if s != "optimal"]
    return r[f"lmi {solver}{suffix}"].show(scale) + (f" {'/'.join(bad)}" if bad else "")


def plot(results: dict[int, dict], path: Path) -> None:
    import matplotlib
    from matplotlib.figure import Figure
    from matplotlib.ticker import NullFormatter

    matplotlib.rcParams["svg.hashsalt"] = "switchobs"
    fig = Figure(figsize=(10, 4.2))
    sizes = sorted(results)
    panels = (("whole processes (the CLI, a python script)", (*COMMANDS, *(f"lmi {s}" for s in SOLVERS))),
              ("in process", ("certify in process", *(f"lmi {s} in process" for s in SOLVERS), "scipy")))
    axes = fig.subplots(1, 2, sharey=True)
    for ax, (title, names) in zip(axes, panels):
        for name in names:
            label = name.replace(" in process", "").replace("lmi CLARABEL", "cvxpy LMI, Clarabel") \
                .replace("lmi SCS", "cvxpy LMI, SCS").replace("scipy", "scipy Lyapunov")
            ax.loglog(sizes, [results[n][name].median for n in sizes], "o-", label=label)
        ax.set_xlabel("state dimension n")
        ax.set_xticks(sizes, [str(n) for n in sizes])
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize="small")
        ax.set_title(title, fontsize="medium")
    axes[0].set_ylabel("CPU time [s] (median)")
    fig.suptitle("numeric chain models: switchobs against the minimal cvxpy LMI")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sizes", nargs="*", type=int, help=f"state dimensions (default {list(SIZES)})")
    parser.add_argument("--quick", action="store_true",
                        help=f"n = {', '.join(map(str, QUICK_SIZES))}, one run, no warm-up; print, do not publish or plot")
    parser.add_argument("--repeats", type=int, help=f"runs per measurement (default {MIN_REPEATS}, 1 with --quick)")
    args = parser.parse_args()
    sizes = tuple(args.sizes) or (QUICK_SIZES if args.quick else SIZES)
    args.repeats = args.repeats or (1 if args.quick else MIN_REPEATS)
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        env = child_env(Path(tmp), args.quick)
        for k, n in enumerate(sizes):
            results[n] = measure(n, Path(tmp), args.repeats, env, warm_up=k == 0 and not args.quick)
            print(f"n = {n} done", file=sys.stderr, flush=True)
    whole = ["| n | design [s] | certify [s] | verify [s] "
             "| cvxpy LMI, Clarabel [s] | cvxpy LMI, SCS [s] | certify vs LMI |",
             "|---:|---:|---:|---:|---:|---:|---|"]
    inproc = ["| n | `certify_model` [s] | cvxpy LMI, Clarabel [s] | cvxpy LMI, SCS [s] | scipy Lyapunov [ms] "
              "| certify vs LMI | plain LMI, Clarabel |",
              "|---:|---:|---:|---:|---:|---|---|"]
    for n in sizes:
        r = results[n]
        whole.append(f"| {n} | " + " | ".join(r[k].show() for k in COMMANDS)
                     + "".join(f" | {lmi_cell(r, s, '')}" for s in SOLVERS)
                     + f" | {versus(r['certify'].median, best_lmi(r, ''))} |")
        inproc.append(f"| {n} | {r['certify in process'].show()}"
                      + "".join(f" | {lmi_cell(r, s, ' in process')}" for s in SOLVERS)
                      + f" | {r['scipy'].show(1e3)} | {versus(r['certify in process'].median, best_lmi(r, ' in process'))}"
                      f" | {r['plain']} |")
    method = ("Chain models $\\dot x_i = -d_ix_i + x_{i+1}$, $d_i \\in \\{1, 3/2, 2, 5/2\\}$, $y = x_1$, from TOML "
              "files, spectrum $-2, -3, -5/2, -7/2$ repeated. CPU time, median [min–max] of "
              f"{args.repeats} runs. First table: whole processes (interpreter start-up and imports included, "
              "`RUSAGE_CHILDREN`): `switchobs design --json` (exact gains, Routh array, $P$, re-check); "
              "`switchobs certify --out` (no strict CQLF by the exact singular-sum proof, Hespanha from the "
              "design's exact $P$, the document re-checked exactly); `switchobs verify`; "
              "and what a user writes instead, a `python` script (numpy, scipy, cvxpy) "
              "that balances the float family $A_\\pm$ (a diagonal similarity by LAPACK gebal, scaled to unit "
              "norm: the entries of $A_-$ reach $10^{23}$ at $n = 32$) and solves the minimal common-$P$ LMI "
              "with a margin, $\\max t$: $\\operatorname{tr} P = n$, $P \\succeq tI$, "
              "$-(A_p^\\top P + PA_p) \\succeq tI$ (its cvxpy status when not `optimal`). Second table: the same "
              "work in process (`time.process_time`, the first call in a fresh process after its imports): "
              "`switchobs.certify.certify_model` on the loaded model (what `certify` runs, without writing the "
              "file), the balancing and LMI solve alone, and `scipy.linalg.solve_continuous_lyapunov` for $A_+$. "
              "*certify vs LMI* compares with the faster solver that answered `optimal` in every run. *plain "
              "LMI*: the status of $P \\succeq I$, $A_p^\\top P + PA_p \\preceq 0$ (balanced, Clarabel, once), "
              "the form without a margin: it has no interior point here (no strict common $P$ exists, "
              "$A_+ + A_-$ is singular) and the solvers fail on it as $n$ grows. Every child process runs with "
              "bytecode caching on (`PYTHONPYCACHEPREFIX` in a temporary directory, one untimed warm-up run), as "
              "an installed package has it.")
    largest = max(sizes)
    goal = "not run"
    if GOAL_N in results:
        r = results[GOAL_N]
        parts = []
        for label, ours, suffix in (("whole process", r["certify"].median, ""),
                                    ("in process", r["certify in process"].median, " in process")):
            best = best_lmi(r, suffix)
            parts.append(f"{label} {ours:.2g} s against {best[1]:.2g} s ({SOLVER_NAMES[best[0]]}), "
                         f"{ours / best[1]:.2g}×" if best else f"{label}: no LMI answered")
        ok = all(best_lmi(r, s) and ours / best_lmi(r, s)[1] <= GOAL_RATIO
                 for ours, s in ((r["certify"].median, ""), (r["certify in process"].median, " in process")))
        goal = "; ".join(parts) + (": **met**" if ok else ": **not met**")
    notes = [f"Goals of issue 12 (this run): certify at n = 32 below 5 s: "
             + (f"{results[32]['certify'].median:.2g} s CPU" if 32 in results else "not run")
             + f"; certify at n = 64 below 60 s: "
             + (f"{results[64]['certify'].median:.2g} s CPU" if 64 in results else "not run")
             + f"; design at n = 64 below 5 s: "
             + (f"{results[64]['design'].median:.2g} s CPU" if 64 in results else "not run")
             + f"; certify within {GOAL_RATIO:.0f}× the minimal cvxpy LMI at n = {GOAL_N}, like for like: {goal}."
             + f" The largest size run is n = {largest}."]
    publish("numeric_scaling", method, [whole, inproc], notes, write=not args.quick)
    if not args.quick and len(sizes) > 1:
        plot(results, ROOT / "docs" / "numeric_scaling.png")


if __name__ == "__main__":
    main()
