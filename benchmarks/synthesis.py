"""What robustness and synthesis cost: box certificates and LMI gain synthesis beside the plain certificate.

For ``normal-form-N`` (``a_i = 0`` nominal, Theorem 1 gains for poles spread over ``[-1, -2]``, computed in
closed form: ``k_i^+`` the coefficients of the target polynomial, ``k_i^- = (-1)^i k_i^+``, seed 004), in one run:

* plain: ``certify_model`` without dwell-time bisection (strict LMI with its dual, Hespanha LMI, exact checks);
* box 2 / box 3: ``certify_box`` over ``a_1, a_2`` (and ``a_3``) in ``[-0.01, 0.01]`` (affine: 4 / 8 vertices
  per mode; the piecewise-linear dwell-time LMIs with bisection on tau and the exact vertex checks);
* synthesis: ``synthesize`` at decay rate 1/2, noise weight 0.1, all states weighted (LMI, rounding,
  exact Lyapunov P and decay checks);
* box synthesis: ``synthesize_box`` over the 2-parameter box, same rate and weight (polytopic LMIs,
  exact vertex checks; the box certificate of its pair is not included).

CPU seconds (``time.process_time`` in a child process), median [min-max] of ``--repeats`` runs (default
5).  Every measurement runs in its own process with a wall-clock limit (``--limit``); one that does not
finish is reported as such, with the limit, and ends that measurement's repeats.
Run: ``.venv/bin/python benchmarks/synthesis.py [--sizes 3 4 8 16] [--limit 300] [--quick]``.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import time
from fractions import Fraction

from _harness import Stats, publish

# imported here, in the parent: the forked children inherit the modules, so their CPU time leaves out the imports
# (cvxpy too, which the library imports only when it first solves an LMI)
import cvxpy  # noqa: F401
from switchobs.certify import certify_box, certify_model
from switchobs.synthesis import synthesize, synthesize_box
from switchobs.model import builtin_model

REPEATS = 5
HALF_WIDTH = "0.01"


def _theorem1_gains(n: int) -> tuple[list[Fraction], list[Fraction]]:
    coeffs = [Fraction(1)]
    for i in range(n):   # multiply by (s + 1 + i / (n - 1))
        root = 1 + Fraction(i, max(n - 1, 1))
        coeffs = [a + root * b for a, b in zip(coeffs + [Fraction(0)], [Fraction(0)] + coeffs)]
    k_plus = coeffs[1:]
    return k_plus, [(-1) ** (i + 1) * k for i, k in enumerate(k_plus)]


def _stage(kind: str, n: int) -> str:
    """Run one measurement; returns its verdict text."""
    model = builtin_model(f"normal-form-{n}")
    values = {f"a{i}": "0" for i in range(1, n + 1)}
    numeric = model.with_values(values)
    Kp, Km = _theorem1_gains(n)
    box2 = [f"a{i}=-{HALF_WIDTH}:{HALF_WIDTH}" for i in (1, 2)]
    if kind == "plain":
        rep = certify_model(numeric, K_plus=Kp, K_minus=Km, dwell=False)
        return "certified" if rep.certified else "not certified"
    if kind in ("box2", "box3"):
        box = [f"a{i}=-{HALF_WIDTH}:{HALF_WIDTH}" for i in range(1, int(kind[-1]) + 1)]
        r = certify_box(model, box, Kp, Km, values=values, search=False)
        return (f"{r.kind} tau_D {float(r.tau_D):.3g}" if r.tau_D is not None else r.kind) if r.certified \
            else f"not certified ({r.detail[:60]})"
    if kind == "synthesis":
        r = synthesize(numeric, decay_rate="1/2", noise_weight=0.1)
        return "certified" if r.feasible else f"failed: {r.detail[:60]}"
    r = synthesize_box(model, box2, decay_rate="1/2", noise_weight=0.1, values=values)
    return "checked at every vertex" if r.feasible else f"failed: {r.detail[:60]}"


def _child(kind: str, n: int, out: mp.Queue) -> None:
    t0 = time.process_time()
    verdict = _stage(kind, n)
    out.put((time.process_time() - t0, verdict))


def measure(kind: str, n: int, repeats: int, limit: float) -> tuple[Stats | None, str]:
    """CPU times of ``repeats`` runs, each in a fresh process stopped after ``limit`` s wall (then None)."""
    times, verdict = [], ""
    for _ in range(repeats):
        out: mp.Queue = mp.Queue()
        proc = mp.Process(target=_child, args=(kind, n, out))
        proc.start()
        proc.join(limit)
        if proc.is_alive():
            proc.terminate()
            proc.join()
            return None, f"not finished within {limit:g} s wall"
        if proc.exitcode != 0 or out.empty():
            return None, f"failed (exit code {proc.exitcode})"
        cpu, verdict = out.get()
        times.append(cpu)
    return Stats(tuple(times)), verdict


KINDS = (("plain", "plain certificate s"), ("box2", "box, 2 parameters s"), ("box3", "box, 3 parameters s"),
         ("synthesis", "synthesis s"), ("boxsyn", "box synthesis, 2 parameters s"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[3, 4, 8, 16])
    parser.add_argument("--repeats", type=int, default=REPEATS)
    parser.add_argument("--limit", type=float, default=300.0, help="wall-clock limit of one measurement [s]")
    parser.add_argument("--quick", action="store_true", help="n = 3 and 4, one repeat; printed, not written")
    args = parser.parse_args()
    sizes = [3, 4] if args.quick else args.sizes
    table = ["| n | " + " | ".join(title for _, title in KINDS) + " | box verdicts | synthesis | box synthesis |",
             "| ---: | " + " | ".join("---:" for _ in KINDS) + " | --- | --- | --- |"]
    for n in sizes:
        repeats = 1 if args.quick else args.repeats
        cells, verdicts = [], {}
        for kind, _ in KINDS:
            stats, verdicts[kind] = measure(kind, n, repeats, args.limit)
            cells.append("not finished" if stats is None and "not finished" in verdicts[kind] else
                         "failed" if stats is None else
                         stats.show() if len(stats.values) > 1 else f"{stats.values[0]:.3g}")
            print(f"n = {n}, {kind}: {cells[-1]} ({verdicts[kind]})", flush=True)
        box = f"2: {verdicts['box2']}; 3: {verdicts['box3']}"
        table.append(f"| {n} | " + " | ".join(cells) + f" | {box} | {verdicts['synthesis']} | {verdicts['boxsyn']} |")
    publish("synthesis",
            "`normal-form-N` ($a_i = 0$ nominal, Theorem 1 gains for poles spread over $[-1, -2]$); plain = "
            "`certify_model` without the dwell-time bisection (strict LMI with its dual, Hespanha, exact checks); "
            "box = `certify_box` over $a_1, a_2$ (and $a_3$) in $[-0.01, 0.01]$ (4 / 8 vertices per mode, "
            "piecewise-linear dwell-time LMIs bisected on $\\tau$, exact vertex checks); synthesis = `synthesize` "
            "at decay rate 1/2, $W = 0.1$, all states weighted (LMI, rounding, exact $P$, decay checks); box "
            "synthesis = `synthesize_box` over the 2-parameter box (polytopic LMIs, exact vertex checks). CPU "
            f"time in seconds of a child process per measurement, "
            + (f"median [min–max] of {args.repeats}" if args.repeats > 1 else
               "one run each (`--repeats N` gives the median [min–max] of N)")
            + f"; a measurement still running after {args.limit:g} s wall is stopped and reported as not finished.",
            [table], write=not args.quick)


if __name__ == "__main__":
    main()
