"""The baselines of ``benchmarks/numeric_scaling.py``, each run in a fresh process (a helper, not a benchmark).

``python _numeric_baseline.py lmi FAMILY.npz SOLVER``
    What a user writes instead of ``switchobs certify``: numpy + scipy + cvxpy, the family balanced (LAPACK
    gebal on ``sum |A_p|``, a diagonal similarity, then scaled to unit 2-norm: the gains reach 1e23 at
    n = 32) and the minimal common-P LMI with a margin, ``max t: tr P = n, P >= t I,
    -(A_p' P + P A_p) >= t I`` (SOLVER: CLARABEL or SCS).  The margin form has an interior for every
    family; the plain ``P >= I, A_p' P + P A_p <= 0`` (:func:`plain`) has none when no strict common
    P exists (here ``A_plus + A_minus`` is singular), and the solvers fail on it.
``python _numeric_baseline.py certify MODEL SPECTRUM``
    The library call ``switchobs.certify.certify_model(model, spectrum=SPECTRUM)`` on the loaded model.

Each prints one JSON line ``{"cpu": s, "status": ...}``: the CPU time of the call alone
(``time.process_time``, the in-process figure); the caller measures the whole process (``RUSAGE_CHILDREN``).
"""

from __future__ import annotations

import json
import sys
import time
import warnings
from collections.abc import Sequence

import numpy as np


def balanced(mats: Sequence[np.ndarray]) -> list[np.ndarray]:
    """``D^-1 A_p D / sigma``: ``D`` from gebal on ``sum |A_p|``, ``sigma`` the largest 2-norm."""
    import scipy.linalg

    with np.errstate(invalid="ignore"):  # gebal's unused permutation vector is cast to int with NaNs at n = 64
        _, (d, _) = scipy.linalg.matrix_balance(sum(np.abs(A) for A in mats), permute=False, separate=True)
    out = [(A * d[None, :]) / d[:, None] for A in mats]
    sigma = max(np.linalg.norm(A, 2) for A in out)
    return [A / sigma for A in out]


def _solve(problem, solver: str) -> str:
    import cvxpy as cp

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)   # "solution may be inaccurate": the status says it
            problem.solve(solver=solver)
    except cp.SolverError:
        return "solver error"
    return problem.status


def lmi(mats: Sequence[np.ndarray], solver: str) -> str:
    """The margin LMI on the balanced family; its cvxpy status (``optimal`` when it answered)."""
    import cvxpy as cp

    mats = balanced(mats)
    n = mats[0].shape[0]
    P, t = cp.Variable((n, n), symmetric=True), cp.Variable()
    cons = [cp.trace(P) == n, P - t * np.eye(n) >> 0] + [-(A.T @ P + P @ A) - t * np.eye(n) >> 0 for A in mats]
    return _solve(cp.Problem(cp.Maximize(t), cons), solver)


def plain(mats: Sequence[np.ndarray], solver: str) -> str:
    """The plain feasibility form ``P >= I, A_p' P + P A_p <= 0`` on the balanced family; its status."""
    import cvxpy as cp

    mats = balanced(mats)
    n = mats[0].shape[0]
    P = cp.Variable((n, n), symmetric=True)
    cons = [P >> np.eye(n)] + [-(A.T @ P + P @ A) >> 0 for A in mats]
    return _solve(cp.Problem(cp.Minimize(0), cons), solver)


def main(argv: Sequence[str]) -> None:
    kind, *args = argv
    if kind == "lmi":
        import cvxpy  # noqa: F401  (imported before the clock starts: the whole process counts it)
        import scipy.linalg  # noqa: F401

        path, solver = args
        with np.load(path) as data:
            mats = [data["A_plus"], data["A_minus"]]
        c0 = time.process_time()
        status = lmi(mats, solver)
    elif kind == "certify":
        from switchobs.certify import certify_model
        from switchobs.model import load_model

        path, spectrum = args
        model = load_model(path)
        c0 = time.process_time()
        status = "certified" if certify_model(model, spectrum=spectrum).certified else "not certified"
    else:
        raise SystemExit(f"unknown baseline {kind!r}: lmi or certify")
    print(json.dumps({"cpu": time.process_time() - c0, "status": status}))


if __name__ == "__main__":
    main(sys.argv[1:])
