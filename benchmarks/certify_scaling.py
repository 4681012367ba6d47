"""CPU time of the strict common-Lyapunov certificate versus a minimal cvxpy LMI, by state dimension.

For each n: a random pair with a planted common P (A_p = P^-1 (S_p - Q_p / 2), S_p skew, Q_p > 0,
integer data, so A_p' P + P A_p = -Q_p).  For Clarabel and SCS:

* baseline -- what a user would write: ``P >> I``, ``A_p' P + P A_p << -I`` in cvxpy, solved (float P,
  no check);
* certificate -- ``strict_common_lyapunov`` end to end (balancing, margin LMI, dyadic rounding, exact
  re-check), with the exact re-check also timed alone;
* verify -- the independent checker on the JSON certificate (parse + exact re-check);

and the default solver order (``solvers`` left out: Clarabel first below n = 16, SCS first from it, see
``lmi/_lmi.py``).  Run: ``python benchmarks/certify_scaling.py [--quick] [--max-n 64] [--repeats 5]``.
"""

from __future__ import annotations

import argparse

import cvxpy as cp
import numpy as np
from _harness import MIN_REPEATS, cpu, publish, ratio

from switchobs.certify import as_family, strict_common_lyapunov, verify_certificate
from switchobs.lmi import DEFAULT_SOLVERS, SCS_FIRST_FROM_N, balance, by_size, primal_margin
from switchobs.exact import dyadic
from switchobs.certify._schema import CertificateKind, LyapunovEntry
from switchobs.certify._verify import _check_strict

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


def cvxpy_common_p(mats: list[np.ndarray], solver: str) -> None:
    """The minimal common-P LMI a cvxpy user writes (feasibility, float answer)."""
    n = mats[0].shape[0]
    P = cp.Variable((n, n), symmetric=True)
    cons = [P >> np.eye(n)] + [A.T @ P + P @ A << -np.eye(n) for A in mats]
    prob = cp.Problem(cp.Minimize(0), cons)
    prob.solve(solver=solver)
    if prob.status not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE):
        raise SystemExit(f"cvxpy baseline with {solver}: {prob.status}")


def certificate_document(fam, res) -> dict:
    return {"format": "switchobs-certificate", "version": 1, "family": fam.to_json(),
            "certificates": [res.certificate().to_json()],
            "verdict": {"arbitrary_switching": "UGES", "dwell_time": "any", "strict_cqlf": "exists",
                        "common_lyapunov": "exists"}}


def measure(n: int, solver: str | None, repeats: int) -> dict:
    fam = as_family(planted_pair(n, 1000 + n))
    solvers = DEFAULT_SOLVERS if solver is None else (solver,)
    results = []
    total = cpu(lambda: results.append(strict_common_lyapunov(fam, solvers=solvers, dual=False)), repeats)
    res = results[-1]
    if not res.certified:
        raise SystemExit(f"n = {n}, {solver or 'default'}: the planted pair was not certified ({res.detail})")
    row = {"total": total}
    if solver is None:
        return row
    bal = balance(fam.numeric)
    P_b, _, _ = primal_margin(bal.matrices, [np.eye(n)] * 2, solvers=solvers, what="bench")
    P = dyadic(P_b / np.outer(bal.d, bal.d))
    entry = LyapunovEntry(CertificateKind.STRICT_CQLF, P)
    row["exact"] = cpu(lambda: _check_strict(fam.names, fam.exact, entry), repeats)
    doc = certificate_document(fam, res)
    row["verify"] = cpu(lambda: verify_certificate(doc), repeats)
    if not verify_certificate(doc).holds:
        raise SystemExit(f"n = {n}, {solver}: the certificate does not verify")
    row["baseline"] = cpu(lambda: cvxpy_common_p(fam.numeric, solver), repeats)
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="smoke run: n up to 16 only; printed, not written to benchmarks/results")
    parser.add_argument("--max-n", type=int, default=32)
    parser.add_argument("--repeats", type=int, default=MIN_REPEATS)
    args = parser.parse_args()
    sizes = [n for n in (2, 4, 8, 16, 32, 64) if n <= (16 if args.quick else args.max_n)]
    table = ["| n | solver | cvxpy common-P LMI [ms] | complete certificate [ms] | vs cvxpy | exact re-check [ms] "
             "| share of the certificate | independent verify [ms] |",
             "|---:|---|---:|---:|---|---:|---:|---:|"]
    default = ["| n | solvers tried first | complete certificate [ms] | vs the best single solver |",
               "|---:|---|---:|---|"]
    for n in sizes:
        best = None
        for solver in SOLVERS:
            r = measure(n, solver, args.repeats)
            best = r["total"] if best is None or r["total"].median < best.median else best
            share = r["exact"].median / r["total"].median
            table.append(f"| {n} | {solver} | {r['baseline'].show(1e3)} | {r['total'].show(1e3)} | "
                         f"{ratio(r['total'].median, r['baseline'].median)} | {r['exact'].show(1e3)} | "
                         f"{100 * share:.0f} % | {r['verify'].show(1e3)} |")
            print(table[-1], flush=True)
        r = measure(n, None, args.repeats)
        default.append(f"| {n} | {by_size(DEFAULT_SOLVERS, n)[0]} | {r['total'].show(1e3)} | "
                       f"{ratio(r['total'].median, best.median)} |")
        print(default[-1], flush=True)
    publish("certify_scaling",
            f"Strict common-$P$ certificate of a random pair with a planted common $P$ against the minimal cvxpy "
            f"LMI (`P >> I`, `A' P + P A << -I`, float answer, no check), per solver; CPU time "
            f"(`time.process_time`), median [min–max] of {args.repeats} runs, in ms. *vs cvxpy*: how much "
            f"slower or faster the complete certificate (balancing, margin LMI, rounding, exact re-check) is "
            f"than the bare LMI. The second table is the default solver order (SCS first from "
            f"n = {SCS_FIRST_FROM_N}), against the faster single solver of the first table.",
            [table, default], write=not args.quick)


if __name__ == "__main__":
    main()
