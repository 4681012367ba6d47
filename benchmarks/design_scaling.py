"""Time to the complete symbolic certificate of normal-form-N versus a naive sympy solve.

For N = 2..8, fully symbolic coefficients a_1..a_N and gains k_1..k_N:
``design(model, K_plus=...)`` computes K_minus (Theorem 1), the Routh–Hurwitz
conditions of A_plus and A_minus, the common P and the Hoang-family coupling
constraints.  The baseline solves the n(n+1)/2 Lyapunov unknowns of
``A_plus' P + P A_plus = -C' C`` with ``sympy.linsolve`` (P only!), in the same
run, with a time limit.  Each design time is the median of fresh-process
runs so that the per-dimension caches are part of what is measured.

Run: ``.venv/bin/python benchmarks/design_scaling.py [--max-n 8] [--repeats 3] [--baseline-limit 120]``
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import statistics
import time


def _design_time(n: int, queue) -> None:
    import sympy as sp

    from switchobs.design import design
    from switchobs.model import builtin_model

    model = builtin_model(f"normal-form-{n}")
    gains = sp.symbols(" ".join(f"k{i}" for i in range(1, n + 1)), real=True)
    start = time.perf_counter()
    result = design(model, K_plus=list(gains))
    elapsed = time.perf_counter() - start
    verify_s = None
    if n <= 6:
        start = time.perf_counter()
        ok = all(result.verify().values())
        verify_s = time.perf_counter() - start if ok else float("nan")
    queue.put((elapsed, verify_s, None))


def _p_only_time(n: int, queue) -> None:
    """The common P alone by the structured solve (cold cache), for a like-for-like ratio."""
    import sympy as sp

    from switchobs.design import observer_form_gramian, observer_normal_form, plus_coefficients
    from switchobs.model import builtin_model

    model = builtin_model(f"normal-form-{n}")
    gains = sp.Matrix(sp.symbols(" ".join(f"k{i}" for i in range(1, n + 1)), real=True))
    start = time.perf_counter()
    observer_form_gramian(plus_coefficients(observer_normal_form(model), gains))
    queue.put((time.perf_counter() - start, None, None))


def _naive_time(n: int, queue) -> None:
    import sympy as sp

    from switchobs.design import naive_lyapunov
    from switchobs.model import builtin_model

    model = builtin_model(f"normal-form-{n}")
    gains = sp.Matrix(sp.symbols(" ".join(f"k{i}" for i in range(1, n + 1)), real=True))
    A_plus = model.A - gains * model.C
    start = time.perf_counter()
    naive_lyapunov(A_plus, model.C.T * model.C)
    queue.put((time.perf_counter() - start, None, None))


def _timed(target, n: int, limit: float) -> tuple:
    queue = mp.Queue()
    proc = mp.Process(target=target, args=(n, queue))
    proc.start()
    proc.join(limit)
    if proc.is_alive():
        proc.terminate()
        proc.join()
        return None, None, None
    return queue.get()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-n", type=int, default=8)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--baseline-limit", type=float, default=120.0)
    args = parser.parse_args()
    print(f"{'N':>2} | {'P only [s]':>10} | {'full design [s]':>15} | {'exact re-check [s]':>18} | "
          f"{'naive P [s]':>11} | {'P speed-up':>10} | {'design speed-up':>15}")
    print("---|---:|---:|---:|---:|---:|---:")
    naive_done = True
    for n in range(2, args.max_n + 1):
        runs = [_timed(_design_time, n, 600) for _ in range(args.repeats)]
        design_s = statistics.median(r[0] for r in runs)
        p_s = statistics.median(_timed(_p_only_time, n, 600)[0] for _ in range(args.repeats))
        verify = [r[1] for r in runs if r[1] is not None]
        verify_s = f"{statistics.median(verify):.3f}" if verify else "-"
        naive = None
        if naive_done:
            naive, _, _ = _timed(_naive_time, n, args.baseline_limit)
            naive_done = naive is not None
        naive_s = f"{naive:.3f}" if naive is not None else f"> {args.baseline_limit:.0f}"
        def ratio(ours: float) -> str:
            return f"{naive / ours:.1f}x" if naive is not None else f"> {args.baseline_limit / ours:.0f}x"

        print(f"{n:>2} | {p_s:10.4f} | {design_s:15.3f} | {verify_s:>18} | {naive_s:>11} | {ratio(p_s):>10} | "
              f"{ratio(design_s):>15}", flush=True)


if __name__ == "__main__":
    main()
