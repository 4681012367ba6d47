"""cvxpy formulations of the Lyapunov LMIs and a solver driver with fallback.

Strict LMIs cannot be posed in floating point, so every problem maximises a
margin ``t`` under a normalisation that makes it bounded (``tr P = n``):

* primal: ``P >= t I`` and ``A_p' P + P A_p <= -t H_p`` (``H_p = I`` for the
  strict CQLF, ``H_p = C' C`` or 0 for Hespanha's non-strict condition);
* dual (theorem of alternatives): ``R_p >= 0``, ``sum tr R_p = 1`` and
  ``sum_p (A_p R_p + R_p A_p') >= s I``.

The matrices are first balanced by a diagonal similarity of powers of two
(exact, so the solution maps back without rounding) and scaled to unit norm.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # cvxpy is imported when a problem is solved: it costs about 1.5 s, and exact paths need none
    import cvxpy as cp

from ..exceptions import SolverFailure

__all__ = ["SolveInfo", "Balanced", "balance", "solve", "primal_margin", "dual_margin", "DEFAULT_SOLVERS",
           "SCS_FIRST_FROM_N", "by_size"]

DEFAULT_SOLVERS: tuple[str, ...] = ("CLARABEL", "SCS")
# The measured cross-over of benchmarks/certify_scaling.py: Clarabel (interior point, accurate) is faster up
# to n = 8 and SCS (first order) from n = 16 on, 3-7x at n = 32-64; the exact re-check of the rounded
# answer makes either rigorous, and the other solver is still tried when the first one fails.
SCS_FIRST_FROM_N = 16


def by_size(solvers: Sequence[str], n: int) -> tuple[str, ...]:
    """The default preference ordered for an ``n x n`` LMI (SCS first from :data:`SCS_FIRST_FROM_N`).

    An explicit choice other than :data:`DEFAULT_SOLVERS` is kept as given.
    """
    solvers = tuple(solvers)
    if solvers == DEFAULT_SOLVERS and n >= SCS_FIRST_FROM_N:
        return tuple(reversed(DEFAULT_SOLVERS))
    return solvers


@dataclass(frozen=True)
class SolveInfo:
    """How a cvxpy problem was solved.

    Attributes
    ----------
    solver : str
        The solver whose answer is used.
    status : str
        Its cvxpy status (``optimal``, ``optimal_inaccurate``...).
    attempts : tuple of str
        ``"SOLVER: status"`` for every solver tried, in order.
    build_s, solve_s : float
        Wall time of the cvxpy problem construction and compilation, and
        of the solver itself.
    """

    solver: str
    status: str
    attempts: tuple[str, ...]
    build_s: float
    solve_s: float

    def to_json(self) -> dict[str, Any]:
        return {"solver": self.solver, "status": self.status, "attempts": list(self.attempts),
                "build_s": self.build_s, "solve_s": self.solve_s}

    @classmethod
    def from_json(cls, data: Mapping[str, Any] | None) -> "SolveInfo | None":
        """The record of :meth:`to_json` (``None`` stays ``None``)."""
        if data is None:
            return None
        return cls(str(data["solver"]), str(data["status"]), tuple(str(a) for a in data["attempts"]),
                   float(data["build_s"]), float(data["solve_s"]))

    @property
    def accurate(self) -> bool:
        return self.status == "optimal"


@dataclass(frozen=True)
class Balanced:
    """Family after the similarity ``A_b = D^-1 A D / sigma`` (``D`` diagonal powers of two)."""

    matrices: tuple[np.ndarray, ...]
    d: np.ndarray
    sigma: float


def balance(matrices: Sequence[np.ndarray]) -> Balanced:
    """Balance the family jointly (LAPACK gebal on ``sum |A_p|``) and scale it to unit 2-norm."""
    import scipy.linalg  # about 0.4 s to import: only on the paths that solve an LMI

    total = sum(np.abs(A) for A in matrices)
    _, (d, _) = scipy.linalg.matrix_balance(total, permute=False, separate=True)
    d = np.asarray(d, dtype=float)
    mats = [(A * d[None, :]) / d[:, None] for A in matrices]
    sigma = max(np.linalg.norm(A, 2) for A in mats) or 1.0
    return Balanced(tuple(A / sigma for A in mats), d, float(sigma))


def solve(build: Callable[[], tuple[cp.Problem, dict]], *, solvers: Sequence[str] = DEFAULT_SOLVERS,
          what: str, infeasible_ok: bool = False) -> tuple[dict, SolveInfo]:
    """Solve the problem made by ``build`` with the first solver that returns an accurate optimum.

    ``build()`` returns ``(problem, variables)`` and is called afresh for each
    solver, so a failed attempt leaves no state behind.  An
    ``optimal_inaccurate`` answer is kept only if no later solver does better;
    the exact re-check decides anyway.  With ``infeasible_ok`` an accurate
    ``infeasible`` status is returned as an answer (the variables then hold
    no values); the callers prove infeasibility separately, exactly.

    Returns
    -------
    variables : dict
        The variables of the instance whose answer is used.
    info : SolveInfo

    Raises
    ------
    SolverFailure
        If no solver returns values; the message lists every attempt.
    """
    import cvxpy as cp

    attempts: list[str] = []
    fallback: tuple[dict, SolveInfo] | None = None
    for name in solvers:
        t0 = time.perf_counter()
        prob, variables = build()
        t1 = time.perf_counter()
        try:
            with warnings.catch_warnings():
                # cvxpy warns on inaccurate solutions; the status is recorded and the exact check decides
                warnings.simplefilter("ignore", UserWarning)
                prob.solve(solver=name)
        except (cp.SolverError, ValueError, ArithmeticError) as exc:
            attempts.append(f"{name}: error ({str(exc).splitlines()[0][:80] if str(exc) else type(exc).__name__})")
            continue
        wall = time.perf_counter() - t1
        stats = prob.solver_stats
        solve_s = float(stats.solve_time) if stats is not None and stats.solve_time is not None else wall
        compile_s = float(getattr(prob, "compilation_time", None) or max(wall - solve_s, 0.0))
        attempts.append(f"{name}: {prob.status}")
        info = SolveInfo(name, str(prob.status), tuple(attempts), (t1 - t0) + compile_s, solve_s)
        if prob.status == cp.OPTIMAL or (infeasible_ok and prob.status == cp.INFEASIBLE):
            return variables, info
        if prob.status == cp.OPTIMAL_INACCURATE and fallback is None:
            fallback = (variables, info)
    if fallback is not None:
        variables, info = fallback
        return variables, SolveInfo(info.solver, info.status, tuple(attempts), info.build_s, info.solve_s)
    raise SolverFailure(f"{what}: no solver returned a solution ({'; '.join(attempts)}); the problem may be "
                        "badly scaled - rescale the matrices or try another solver")


def _sym(M: cp.Expression) -> cp.Expression:
    return M + M.T


def primal_margin(mats: Sequence[np.ndarray], H: Sequence[np.ndarray | None], *,
                  solvers: Sequence[str] = DEFAULT_SOLVERS, what: str) -> tuple[np.ndarray, float, SolveInfo]:
    """Maximise ``t``: ``tr P = n``, ``P >= t I``, ``A_p' P + P A_p <= -t H_p`` (``H_p = None``: ``<= 0``).

    With some ``H_p = None`` the problem can be infeasible; ``t = -inf`` is then returned.
    """
    import cvxpy as cp

    n = mats[0].shape[0]
    eye = np.eye(n)

    def fn() -> tuple[cp.Problem, dict]:
        P = cp.Variable((n, n), symmetric=True)
        t = cp.Variable()
        cons = [cp.trace(P) == n, P - t * eye >> 0]
        for A, Hp in zip(mats, H):
            lhs = -_sym(A.T @ P)
            cons.append((lhs - t * Hp if Hp is not None else lhs) >> 0)
        return cp.Problem(cp.Maximize(t), cons), {"P": P, "t": t}

    v, info = solve(fn, solvers=by_size(solvers, n), what=what,
                    infeasible_ok=not all(Hp is not None for Hp in H))
    if info.status == "infeasible":
        return np.full((n, n), np.nan), -np.inf, info
    P = np.asarray(v["P"].value, dtype=float)
    return (P + P.T) / 2, float(v["t"].value), info


def dual_margin(mats: Sequence[np.ndarray], *, solvers: Sequence[str] = DEFAULT_SOLVERS, what: str
                ) -> tuple[list[np.ndarray], float, SolveInfo]:
    """Maximise ``s``: ``R_p >= 0``, ``sum tr R_p = 1``, ``sum_p (A_p R_p + R_p A_p') >= s I``."""
    import cvxpy as cp

    n = mats[0].shape[0]
    eye = np.eye(n)

    def fn() -> tuple[cp.Problem, dict]:
        Rs = [cp.Variable((n, n), PSD=True) for _ in mats]
        s = cp.Variable()
        S = sum(_sym(A @ R) for A, R in zip(mats, Rs))
        cons = [sum(cp.trace(R) for R in Rs) == 1, S - s * eye >> 0]
        return cp.Problem(cp.Maximize(s), cons), {"R": Rs, "s": s}

    v, info = solve(fn, solvers=by_size(solvers, n), what=what)
    Rs = [np.asarray(R.value, dtype=float) for R in v["R"]]
    return [(R + R.T) / 2 for R in Rs], float(v["s"].value), info
