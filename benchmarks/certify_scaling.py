"""Wall time of the strict common-Lyapunov certificate versus the state dimension (issue 3 benchmark).

For n = 2, 4, 8, 16, 32: a random pair with a planted common P (A_p = P^-1 (S_p - Q_p / 2),
S_p skew, Q_p > 0, integer data, so A_p' P + P A_p = -Q_p), then for Clarabel and SCS:

* build  -- cvxpy problem construction and compilation (canonicalisation);
* solve  -- the solver's own time;
* exact  -- dyadic rounding of P and the exact re-check (fraction-free Bareiss on integers);
* total  -- the complete certificate, ``strict_common_lyapunov`` end to end (wall);
* verify -- the independent checker on the JSON certificate (parse + exact re-check);

next to ``scipy.linalg.solve_continuous_lyapunov`` for one mode (the floating-point floor).
Prints a markdown table; run with ``python benchmarks/certify_scaling.py``.
"""

from __future__ import annotations

import statistics
import time

import numpy as np
import scipy.linalg

from switchobs.certify import as_family, strict_common_lyapunov, verify_certificate
from switchobs.certify._lmi import balance, primal_margin
from switchobs.certify._rounding import dyadic
from switchobs.certify._verify import _check_strict

SIZES = (2, 4, 8, 16, 32)
SOLVERS = ("CLARABEL", "SCS")


def planted_pair(n: int, seed: int) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    G = rng.integers(-3, 4, (n, n))
    P = G @ G.T + n * np.eye(n)
    mats = []
    for _ in range(2):
        S = rng.integers(-4, 5, (n, n))
        Q = rng.integers(-2, 3, (n, n))
        Q = Q @ Q.T + np.eye(n)
        mats.append(np.linalg.solve(P, (S - S.T) - Q / 2))
    return mats


def measure(n: int, solver: str, repeats: int) -> dict[str, float]:
    fam = as_family(planted_pair(n, 1000 + n))
    rows: dict[str, list[float]] = {k: [] for k in ("build", "solve", "exact", "total", "verify", "floor")}
    for _ in range(repeats):
        bal = balance(fam.numeric)
        P_b, t, info = primal_margin(bal.matrices, [np.eye(n)] * 2, solvers=(solver,), what="bench")
        t0 = time.perf_counter()
        P = dyadic(P_b / np.outer(bal.d, bal.d))
        ok = _check_strict(fam.names, fam.exact, {"P": P}).holds
        rows["exact"].append(time.perf_counter() - t0)
        rows["build"].append(info.build_s)
        rows["solve"].append(info.solve_s)
        t0 = time.perf_counter()
        res = strict_common_lyapunov(fam, solvers=(solver,), dual=False)
        rows["total"].append(time.perf_counter() - t0)
        if not (ok and res.certified):
            raise SystemExit(f"n = {n}, {solver}: the planted pair was not certified ({res.detail})")
        doc = {"format": "switchobs-certificate", "version": 1, "family": fam.to_json(),
               "certificates": [res.certificate()],
               "verdict": {"arbitrary_switching": "UGES", "dwell_time": "any", "strict_cqlf": "exists",
                           "common_lyapunov": "exists"}}
        t0 = time.perf_counter()
        if not verify_certificate(doc).holds:
            raise SystemExit(f"n = {n}, {solver}: the certificate does not verify")
        rows["verify"].append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        scipy.linalg.solve_continuous_lyapunov(fam.numeric[0].T, -np.eye(n))
        rows["floor"].append(time.perf_counter() - t0)
    return {k: statistics.median(v) for k, v in rows.items()}


def main() -> None:
    print("| n | solver | build [s] | solve [s] | exact re-check [s] | complete certificate [s] | "
          "independent verify [s] | scipy Lyapunov floor [s] |")
    print("|---|---|---|---|---|---|---|---|")
    for n in SIZES:
        for solver in SOLVERS:
            r = measure(n, solver, repeats=3 if n <= 16 else 1)
            print(f"| {n} | {solver} | {r['build']:.4f} | {r['solve']:.4f} | {r['exact']:.4f} | {r['total']:.4f} | "
                  f"{r['verify']:.4f} | {r['floor']:.6f} |", flush=True)


if __name__ == "__main__":
    main()
