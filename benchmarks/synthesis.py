"""What robustness and synthesis cost: box certificates and LMI gain synthesis beside the plain certificate.

For ``normal-form-N`` (``a_i = 0`` nominal, Theorem 1 gains for poles spread over ``[-1, -2]``, computed in
closed form: ``k_i^+`` the coefficients of the target polynomial, ``k_i^- = (-1)^i k_i^+``, seed 004), in one run:

* plain: ``certify_model`` without dwell-time bisection (strict LMI with its dual, Hespanha LMI, exact checks);
* box 2 / box 3: ``certify_box`` over ``a_1, a_2`` (and ``a_3``) in ``[-0.01, 0.01]`` (affine: 4 / 8 vertices
  per mode; the piecewise-linear dwell-time LMIs with bisection on tau and the exact vertex checks);
* synthesis: ``synthesize`` at decay rate 1/2, noise weight 0.1, all states weighted (LMI, rounding,
  exact Lyapunov P and decay checks).

CPU seconds (``time.process_time``), median [min-max] of ``REPEATS`` runs (1 for n = 16).
Run: ``.venv/bin/python benchmarks/synthesis.py [--quick | n ...]`` (``--quick``: n = 3, 4).
"""

from __future__ import annotations

import statistics
import sys
import time

import numpy as np

from switchobs.certify import certify_box, certify_model, synthesize
from fractions import Fraction
from switchobs.model import builtin_model

REPEATS = 3
SIZES = (3, 4) if "--quick" in sys.argv else tuple(int(x) for x in sys.argv[1:]) or (3, 4, 8, 16)
HALF_WIDTH = "0.01"


def _timed(fn, repeats):
    times, result = [], None
    for _ in range(repeats):
        t0 = time.process_time()
        result = fn()
        times.append(time.process_time() - t0)
    return times, result


def _cell(times):
    if len(times) == 1:
        return f"{times[0]:.3f}"
    return f"{statistics.median(times):.3f} [{min(times):.3f}-{max(times):.3f}]"


def _theorem1_gains(n: int) -> tuple[list[Fraction], list[Fraction]]:
    coeffs = [Fraction(1)]
    for i in range(n):   # multiply by (s + 1 + i / (n - 1))
        root = 1 + Fraction(i, max(n - 1, 1))
        coeffs = [a + root * b for a, b in zip(coeffs + [Fraction(0)], [Fraction(0)] + coeffs)]
    k_plus = coeffs[1:]
    return k_plus, [(-1) ** (i + 1) * k for i, k in enumerate(k_plus)]


def main() -> None:
    print("| n | plain certificate s | box, 2 parameters s | box, 3 parameters s | synthesis s | box verdicts | "
          "synthesis |")
    print("| ---: | ---: | ---: | ---: | ---: | --- | --- |")
    for n in SIZES:
        repeats = 1 if n >= 16 else REPEATS
        model = builtin_model(f"normal-form-{n}")
        values = {f"a{i}": "0" for i in range(1, n + 1)}
        numeric = model.with_values(values)
        Kp, Km = _theorem1_gains(n)
        plain_t, plain = _timed(lambda: certify_model(numeric, K_plus=Kp, K_minus=Km, dwell=False),
                                repeats)
        boxes = {}
        for count in (2, 3):
            box = [f"a{i}=-{HALF_WIDTH}:{HALF_WIDTH}" for i in range(1, count + 1)]
            boxes[count] = _timed(lambda: certify_box(model, box, Kp, Km, values=values, search=False), repeats)
        syn_t, syn = _timed(lambda: synthesize(numeric, decay_rate="1/2", noise_weight=0.1), repeats)
        verdicts = ", ".join(
            f"{k}: {r.kind or 'none'}" + (f" tau_D {float(r.tau_D):.3g}" if r.tau_D is not None else "")
            for k, (_, r) in boxes.items())
        assert plain.certified
        print(f"| {n} | {_cell(plain_t)} | {_cell(boxes[2][0])} | {_cell(boxes[3][0])} | {_cell(syn_t)} | "
              f"{verdicts} | {'certified' if syn.feasible else 'failed: ' + syn.detail[:40]} |", flush=True)


if __name__ == "__main__":
    np.set_printoptions(precision=4)
    main()
