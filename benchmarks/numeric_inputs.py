"""Users' numbers at the sizes of issue 28: small integers against 6-significant-digit decimals, once each.

Three kinds of model file, each a TOML file written for the run:

* integer chain -- the chain of ``numeric_scaling.py`` (``x_i' = -d_i x_i + x_(i+1)``, ``d_i`` in 1, 3/2, 2,
  5/2, ``y = x_1``) with its spectrum -2, -3, -5/2, -7/2 repeated;
* decimal chain -- the same chain with ``d_i`` drawn in [1, 3] and written with 6 significant digits, and the
  spectrum spread over [-2, -1] as a user types it (``-1,-1.03226,-1.06452,...``);
* dense decimal -- a dense random observable model (``A = G / sqrt(n) - I / 2``, ``C`` random, normal ``G``,
  fixed seed), every entry and pole with 6 significant digits.

Measured through the CLI as whole processes (interpreter start-up and imports included): ``switchobs design
--json`` at n = 64 and 128, ``switchobs certify --out`` at n = 32, 64 and 128, ``switchobs verify`` of that
certificate at n = 64, and the minimal cvxpy LMI a user would write instead (``_numeric_baseline.py lmi``:
balanced family, common P with a margin, SCS) at n = 64 on the design's family.  Each command runs once (the
machine is shared and the large ones take minutes): its CPU time (user + system) and peak resident memory come
from ``os.wait4`` on that process alone.  A command that fails shows its exit status and the first words of
its error line; one still running after ``TIMEOUT_S`` is stopped.  Results go to
``benchmarks/results/numeric_inputs.md``.  Run with ``python benchmarks/numeric_inputs.py [--quick]``
(``--quick``: n = 8 only, printed, not written).
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
import tomllib
from fractions import Fraction
from pathlib import Path

import numpy as np
from _harness import number, publish, switchobs_exe
from numeric_scaling import chain_model
from numeric_scaling import spectrum as integer_spectrum

ROOT = Path(__file__).resolve().parents[1]
BASELINE = Path(__file__).resolve().with_name("_numeric_baseline.py")
TIMEOUT_S = 150
KINDS = ("integer chain", "decimal chain", "dense decimal")
#: command -> the sizes it runs at (issue 28's goals)
SIZES = {"design": (64, 128), "certify": (32, 64, 128), "verify": (64,), "lmi": (64,)}
QUICK_SIZES = {"design": (8,), "certify": (8,), "verify": (8,), "lmi": (8,)}
#: command -> {n: goal in CPU seconds} (issue 28, "Done when")
GOALS = {"certify": {32: 2.0, 64: 10.0, 128: 60.0}, "verify": {64: 5.0}, "design": {64: 5.0, 128: 30.0}}
GOAL_MEMORY_MB = 2048
GOAL_RATIO_N, GOAL_RATIO = 64, 3.0


def six(x: float) -> str:
    """``x`` with 6 significant digits, as a user types it."""
    return f"{float(f'{x:.6g}'):.6g}"


def toml(name: str, A: list[list[str]], C: list[str]) -> str:
    n = len(A)
    states = ", ".join(f'"x{i + 1}"' for i in range(n))
    rows = ", ".join("[" + ", ".join(f'"{x}"' for x in row) + "]" for row in A)
    return (f'name = "{name}"\nstates = [{states}]\noutput = "y"\nA = [{rows}]\n'
            f'C = [{", ".join(f"{chr(34)}{c}{chr(34)}" for c in C)}]\ntime_scale = "y"\n')


def model_text(kind: str, n: int) -> tuple[str, str]:
    """The TOML text and the spectrum of the model of ``kind`` with ``n`` states."""
    if kind == "integer chain":
        return chain_model(n), integer_spectrum(n)
    rng = np.random.default_rng(n)
    poles = ",".join(six(-1 - k / max(n - 1, 1)) for k in range(n))
    if kind == "decimal chain":
        d = [six(v) for v in rng.uniform(1, 3, n)]
        A = [["0"] * n for _ in range(n)]
        for i in range(n):
            A[i][i] = f"-{d[i]}"
            if i < n - 1:
                A[i][i + 1] = "1"
        return toml(f"decimal-chain-{n}", A, ["1"] + ["0"] * (n - 1)), poles
    G = rng.normal(size=(n, n)) / np.sqrt(n) - 0.5 * np.eye(n)
    return toml(f"dense-{n}", [[six(x) for x in row] for row in G], [six(x) for x in rng.normal(size=n)]), poles


def run(argv: list[str]) -> dict:
    """CPU seconds and peak memory [MB] of the process ``argv`` alone, its exit status, output and error line."""
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        proc = subprocess.Popen(argv, stdout=out, stderr=err, cwd=str(ROOT), start_new_session=True)
        start = time.monotonic()
        while True:
            pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
            if pid:
                break
            if time.monotonic() - start > TIMEOUT_S:
                os.killpg(proc.pid, signal.SIGKILL)
                pid, status, usage = os.wait4(proc.pid, 0)
                return {"cpu": usage.ru_utime + usage.ru_stime, "mb": usage.ru_maxrss / 1024, "rc": None,
                        "stdout": "", "error": f"stopped after {TIMEOUT_S} s"}
            time.sleep(0.05)
        proc.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        lines = [line for line in err.read().decode(errors="replace").splitlines() if "error" in line]
        return {"cpu": usage.ru_utime + usage.ru_stime, "mb": usage.ru_maxrss / 1024, "rc": proc.returncode,
                "stdout": out.read().decode(errors="replace"), "error": lines[-1] if lines else ""}


def cell(r: dict | None) -> str:
    if r is None:
        return "—"
    shown = f"{number(r['cpu'])} s, {r['mb']:.0f} MB"
    if r["rc"] == 0:
        return shown
    reason = r["error"].split("error: ", 1)[-1]
    reason = reason if len(reason) <= 90 else reason[:87] + "..."
    status = "stopped" if r["rc"] is None else f"exit {r['rc']}"
    # a table cell of Markdown: "A_plus[1][1]" would be read as a reference link
    return f"{shown}, **{status}**: {reason}".replace("|", "\\|").replace("[", "\\[").replace("]", "\\]")


def measure(kind: str, n: int, sizes: dict, tmp: Path) -> dict[str, dict]:
    text, poles = model_text(kind, n)
    model = tmp / f"{kind.replace(' ', '-')}-{n}.toml"
    model.write_text(text, encoding="utf-8")
    cert = model.with_suffix(".json")
    exe = switchobs_exe()
    out: dict[str, dict] = {}
    if n in sizes["design"] or n in sizes["lmi"]:
        out["design"] = run([exe, "design", str(model), "--spectrum", poles, "--json"])
    if n in sizes["certify"]:
        out["certify"] = run([exe, "certify", str(model), "--spectrum", poles, "--out", str(cert)])
    if n in sizes["verify"] and cert.exists():
        out["verify"] = run([exe, "verify", str(cert)])
    if n in sizes["lmi"] and out["design"]["rc"] == 0:
        design = json.loads(out["design"]["stdout"])
        family = model.with_suffix(".npz")
        # what a user holds: the model and the gains as doubles (a normal-form design gives them as doubles)
        data = tomllib.loads(text)
        A = np.array([[float(Fraction(x)) for x in row] for row in data["A"]])
        C = np.array([[float(Fraction(x)) for x in data["C"]]])
        K = {k: np.array([float(Fraction(x)) for x in design[k]]).reshape(-1, 1) for k in ("K_plus", "K_minus")}
        np.savez(family, A_plus=A - K["K_plus"] @ C, A_minus=-A + K["K_minus"] @ C)
        lmi = run([sys.executable, str(BASELINE), "lmi", str(family), "SCS"])
        status = json.loads(lmi["stdout"])["status"] if lmi["rc"] == 0 else ""
        if status != "optimal" and lmi["rc"] == 0:
            lmi["error"] = f"error: cvxpy status {status}"
        out["lmi"] = lmi
    if n not in sizes["design"]:
        out.pop("design", None)
    for r in out.values():   # the run's temporary directory is noise in a published error line
        r["error"] = r["error"].replace(f"{tmp}/", "")
    return out


def verdicts(results: dict, sizes: dict) -> list[str]:
    """One line per goal of issue 28: the figures of this run against it."""
    lines = []
    for command, goals in GOALS.items():
        for n, goal in goals.items():
            if n not in sizes[command]:
                continue
            shown = []
            for kind in KINDS:
                r = results[kind].get(n, {}).get(command)
                if r is None:
                    continue
                ok = r["rc"] == 0 and r["cpu"] <= goal and r["mb"] <= GOAL_MEMORY_MB
                state = f"{number(r['cpu'])} s" if r["rc"] == 0 else ("stopped" if r["rc"] is None else
                                                                       f"exit {r['rc']}")
                shown.append(f"{kind} {state} ({'met' if ok else 'not met'})")
            lines.append(f"`{command}` n = {n} ≤ {goal:g} s: " + "; ".join(shown))
    n = GOAL_RATIO_N
    if n in sizes["lmi"]:
        shown = []
        for kind in KINDS:
            r = results[kind].get(n, {})
            if "lmi" in r and "certify" in r and r["lmi"]["rc"] == 0 and r["certify"]["rc"] == 0:
                q = r["certify"]["cpu"] / r["lmi"]["cpu"]
                shown.append(f"{kind} {q:.2g}× ({'met' if q <= GOAL_RATIO else 'not met'})")
            elif "lmi" in r:
                shown.append(f"{kind}: not compared (certify or the LMI failed)")
        lines.append(f"`certify` at most {GOAL_RATIO:g}× the SCS LMI at n = {n}, whole processes: " + "; ".join(shown))
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="n = 8 only, printed, not written")
    args = parser.parse_args()
    sizes = QUICK_SIZES if args.quick else SIZES
    all_n = sorted({n for ns in sizes.values() for n in ns})
    results: dict[str, dict[int, dict]] = {kind: {} for kind in KINDS}
    with tempfile.TemporaryDirectory() as tmp:
        for kind in KINDS:
            for n in all_n:
                results[kind][n] = measure(kind, n, sizes, Path(tmp))
                print(f"{kind}, n = {n} done", file=sys.stderr, flush=True)
    table = ["| model | n | design | certify | verify | cvxpy LMI, SCS |", "|---|---:|---|---|---|---|"]
    for kind in KINDS:
        for n in all_n:
            r = results[kind][n]
            table.append(f"| {kind} | {n} | " + " | ".join(cell(r.get(c)) for c in ("design", "certify", "verify",
                                                                                    "lmi")) + " |")
    method = ("Whole processes through the CLI, each run once: CPU time (user + system) and peak resident memory "
              "of that process (`os.wait4`), interpreter start-up and imports included. *integer chain*: "
              "$\\dot x_i = -d_ix_i + x_{i+1}$, $d_i \\in \\{1, 3/2, 2, 5/2\\}$, $y = x_1$, spectrum "
              "$-2, -3, -5/2, -7/2$ repeated (the chain of the table above); *decimal chain*: the same chain with "
              "$d_i \\in [1, 3]$ written with 6 significant digits and the spectrum spread over $[-2, -1]$ "
              "(`-1,-1.03226,...`); *dense decimal*: a dense random observable model, every entry of $A$, $C$ and "
              "every pole with 6 significant digits. `switchobs design --json`, `switchobs certify --out`, "
              "`switchobs verify` of that certificate, and the minimal cvxpy common-$P$ LMI with a margin "
              "(balanced family, SCS) on the design's float family as a whole `python` process. A failing "
              "command shows its exit status and error line, one running longer than "
              f"{TIMEOUT_S} s is stopped; — marks sizes not run for that command.")
    publish("numeric_inputs", method, [table], ["Goals of issue 28 (this run): " + " — ".join(verdicts(results, sizes))
                                                + "."], write=not args.quick)


if __name__ == "__main__":
    main()
