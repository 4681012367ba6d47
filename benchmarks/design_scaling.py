"""CPU time of the symbolic design of normal-form-N against a naive sympy solve, and through the CLI.

For N = 2..8 and fully symbolic coefficients a_1..a_N and gains k_1..k_N:

* P only -- the structured solve of the common P (``observer_form_gramian``), cold: the per-dimension
  cache and sympy's cache are cleared before each run;
* naive P -- the strongest naive baseline: ``sympy.linsolve`` on the n(n+1)/2 entries of P for the
  observer form with one symbol per characteristic-polynomial coefficient (what the structured solve
  also uses; 2N symbols a_i, k_i make it hundreds of times slower), stopped after ``--baseline-limit``;
* design, re-check, text -- ``design(model, K_plus=...)``, ``GainDesign.verify()`` and ``str()``, cold;
* CLI -- the whole ``switchobs design normal-form-N --gains-plus k1,..,kN`` process (interpreter,
  imports, design, the default exact re-check, printing).

Each N runs in a fresh process.  Run: ``python benchmarks/design_scaling.py [--quick] [--max-n 8]
[--repeats 5] [--baseline-limit 20]``; without ``--quick`` it also times the CLI goals of issue 18
(gains N = 8 < 10 s and N = 10 < 60 s, symbolic spectrum N = 8 < 30 s): CPU and wall time of
``--repeats`` whole processes each.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import queue as queue_module
import time

from _harness import MIN_REPEATS, Stats, cli_cpu, cpu, number, publish, ratio


def _clear_caches() -> None:
    from sympy.core.cache import clear_cache

    from switchobs.design._lyapunov import _generic_solution
    from switchobs.design._recheck import _generic_identities_hold

    clear_cache()
    _generic_solution.cache_clear()
    _generic_identities_hold.cache_clear()


def _in_process(n: int, repeats: int) -> dict:
    import sympy as sp

    from switchobs.design import design, observer_form_gramian
    from switchobs.model import builtin_model

    model = builtin_model(f"normal-form-{n}")
    gains = list(sp.symbols(" ".join(f"k{i}" for i in range(1, n + 1)), real=True))
    alpha = sp.symbols(f"c1:{n + 1}")
    warm = design(builtin_model("normal-form-2"), K_plus=list(sp.symbols("w1 w2")))  # code paths, not timed
    warm.verify()
    str(warm)
    results = []
    p_only = cpu(lambda: observer_form_gramian(alpha), repeats, setup=_clear_caches)
    full = cpu(lambda: results.append(design(model, K_plus=gains)), repeats, setup=_clear_caches)
    checks = []
    recheck = cpu(lambda: checks.append(results[-1].verify()), repeats, setup=_clear_caches)
    if not all(checks[-1].values()):
        raise SystemExit(f"N = {n}: the exact re-check failed: {checks[-1]}")
    text = cpu(lambda: str(results[-1]), repeats)
    return {"p": p_only, "design": full, "recheck": recheck, "text": text, "chars": len(str(results[-1]))}


def _naive(n: int, repeats: int, queue) -> None:
    """Puts the CPU time of each of ``repeats`` cold naive solves as soon as it is done."""
    import time

    import sympy as sp
    from sympy.core.cache import clear_cache

    from switchobs.design import naive_lyapunov, normal_form_matrix

    alpha = sp.symbols(f"c1:{n + 1}")
    F = normal_form_matrix([-c for c in alpha])  # the observer form, det(sI - F) = s^n + c1 s^(n-1) + ...
    E = sp.zeros(n, n)
    E[0, 0] = 1
    naive_lyapunov(sp.Matrix([[-alpha[0]]]), sp.Matrix([[1]]))  # loads linsolve's code paths, not timed
    for _ in range(repeats):
        clear_cache()
        t0 = time.process_time()
        naive_lyapunov(F, E)
        queue.put(time.process_time() - t0)


def _in_child(n: int, repeats: int, queue) -> None:
    queue.put(_in_process(n, repeats))


def _naive_times(n: int, repeats: int, limit: float) -> list[float] | None:
    """The naive solves in one fresh process; None as soon as one takes longer than ``limit`` seconds."""
    queue = mp.Queue()
    proc = mp.Process(target=_naive, args=(n, repeats, queue))
    proc.start()
    times = []
    try:
        for _ in range(repeats):
            times.append(queue.get(timeout=limit + 30))  # + the start-up of the child
            if times[-1] > limit:
                return None
    except queue_module.Empty:
        return None
    finally:
        proc.terminate()
        proc.join()
    return times


def _goal(args: list[str], repeats: int) -> tuple[Stats, Stats]:
    """CPU and wall time of ``repeats`` whole ``switchobs ARGS`` processes."""
    cpu_s, wall_s = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        cpu_s += cli_cpu(args, 1).values
        wall_s.append(time.perf_counter() - t0)
    return Stats(tuple(cpu_s)), Stats(tuple(wall_s))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="smoke run: N up to 4, 2 runs, the CLI at N = 4 once, no goals; printed, not written "
                             "to benchmarks/results")
    parser.add_argument("--max-n", type=int, default=8)
    parser.add_argument("--repeats", type=int, default=MIN_REPEATS)
    parser.add_argument("--baseline-limit", type=float, default=20.0)
    args = parser.parse_args()
    max_n = min(args.max_n, 4) if args.quick else args.max_n
    if args.quick:
        args.repeats = 2
    table = ["| N | P only [ms] | naive P [ms] | P vs naive | design [ms] | exact re-check [ms] | text [ms] "
             "| text [kB] | CLI process [s] |",
             "|---:|---:|---:|---|---:|---:|---:|---:|---:|"]
    naive_on = True
    for n in range(2, max_n + 1):
        queue = mp.Queue()
        proc = mp.Process(target=_in_child, args=(n, args.repeats, queue))
        proc.start()
        r = queue.get()
        proc.join()
        naive = _naive_times(n, args.repeats, args.baseline_limit) if naive_on else None
        naive_on = naive is not None
        if naive_on:
            naive_s, versus = Stats(tuple(naive)).show(1e3), ratio(r["p"].median, Stats(tuple(naive)).median)
        else:
            naive_s = f"> {args.baseline_limit:.0f} s"
            versus = f"> {number(args.baseline_limit / r['p'].median)}× faster"
        gains = ",".join(f"k{i}" for i in range(1, n + 1))
        # whole processes cost seconds each: every other N keeps `make bench` to a few minutes
        cli = cli_cpu(["design", f"normal-form-{n}", "--gains-plus", gains], 1 if args.quick else args.repeats).show() \
            if (n % 2 == 0 and not args.quick) or n == max_n else "–"
        table.append(f"| {n} | {r['p'].show(1e3)} | {naive_s} | {versus} | {r['design'].show(1e3)} | "
                     f"{r['recheck'].show(1e3)} | {r['text'].show(1e3)} | {number(r['chars'] / 1e3)} | {cli} |")
        print(table[-1], flush=True)
    tables = [table]
    if not args.quick:
        goals = [f"| command (whole process, default exact re-check; {args.repeats} runs) | CPU [s] | wall [s] "
                 "| goal [s] | CPU within goal |", "|---|---:|---:|---:|---|"]
        for n, target, goal in ((8, "gains", 10), (10, "gains", 60), (8, "spectrum", 30)):
            if target == "gains":
                argv = ["--gains-plus", ",".join(f"k{i}" for i in range(1, n + 1))]
            else:
                argv = ["--spectrum", ",".join(f"-l{i}" for i in range(1, n + 1))]
            t, wall = _goal(["design", f"normal-form-{n}", *argv], args.repeats)
            goals.append(f"| `switchobs design normal-form-{n} {argv[0]} {argv[1]}` | {t.show()} | {wall.show()} | "
                         f"{goal} | {'yes' if t.max < goal else 'no'} |")
            print(goals[-1], flush=True)
        tables.append(goals)
    publish("design_scaling",
            f"`normal-form-N` with fully symbolic $a_i$ and $k_i$; CPU time (`time.process_time`, and "
            f"`RUSAGE_CHILDREN` for the whole CLI process), median [min–max] of {args.repeats} cold runs "
            f"(caches cleared), each N in a fresh process. *P only*: the structured solve of the common $P$; "
            f"*naive P*: `sympy.linsolve` on the $N(N+1)/2$ entries of $P$ for the observer form with one "
            f"symbol per characteristic-polynomial coefficient (stopped after {args.baseline_limit:.0f} s); "
            f"*design*: gains, $K_-$, Routh–Hurwitz conditions, $P$ and the coupling constraints; *exact "
            f"re-check*: `GainDesign.verify()`; *text*: `str()` of the design (compact past N = 4); *CLI "
            f"process*: `switchobs design normal-form-N --gains-plus k1,...,kN` end to end with the default "
            f"exact re-check (even N and the last N only: each run costs seconds). Goals: wall time is CPU "
            f"time stretched by the machine's load (stated above); the goals hold if the CPU time does.",
            tables, write=not args.quick)


if __name__ == "__main__":
    main()
