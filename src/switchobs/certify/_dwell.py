"""Dwell-time bound by the Geromel–Colaneri LMIs, bisected on tau and certified exactly.

For a dwell time ``T`` the conditions are (Geromel & Colaneri 2006, Theorem 1)

    P_p > 0,   A_p' P_p + P_p A_p < 0,   exp(A_p' T) P_q exp(A_p T) - P_p < 0   (p != q).

``V(x) = x' P_sigma x`` then decreases along each mode and, if the mode lasted
at least ``T``, across the switch (for ``D >= T``,
``exp(A_p' D) P_q exp(A_p D) < exp(A_p'(D-T)) P_p exp(A_p (D-T)) <= P_p``), so
every switching signal with dwell time ``>= T`` gives uniform exponential
stability.  Feasibility is monotone in ``T`` for the same reason, which
justifies the bisection.  In floating point the strict inequalities become a
margin: ``max t`` with ``sum tr P_p = N n``, ``P_p >= t I`` and both
inequalities ``<= -t I``.  The returned ``tau_D`` is a rational upper rounding of
the bisection's feasible end, and the rounded ``P_p`` are re-checked exactly
with a rigorous enclosure of the matrix exponential.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np

from .._progress import progress
from ..exact import Matrix, dyadic, matrix_strings
from ._family import Family, FamilyLike, as_family
from ._lyapunov import _matrices, _reading
from ..lmi import DEFAULT_SOLVERS, SolveInfo, balance, solve
from ._schema import DwellTimeEntry
from ._verify import check_entry

__all__ = ["DwellTimeResult", "dwell_time", "gc_margin", "CERTIFY_ATTEMPTS"]

#: Candidates ``tau_numeric * 1.1^k`` tried for the exact certificate (up to a factor of about 6.7).
CERTIFY_ATTEMPTS = 20


@dataclass(frozen=True)
class DwellTimeResult:
    """Outcome of :func:`dwell_time`.

    Attributes
    ----------
    family : Family
    tau_D : Fraction or None
        Certified dwell time (in the switched system's own time, ``tau`` for the
        observers): every switching signal with dwell time ``>= tau_D`` gives UES.
    certified : bool
    tau_lower : float
        Largest ``T`` found infeasible by the bisection (the LMI bound cannot go below it).
    tau_numeric : float
        Smallest ``T`` found feasible by the bisection (numerical LMI bound).  ``tau_D``
        is the first of ``tau_numeric * 1.1^k`` (rounded up to 4 digits) whose rounded
        ``P_p`` pass the exact check: near ``tau_numeric`` the margin is at the
        solver's accuracy and rounding may break it.
    P : tuple of Matrix or None
        The exact ``P_p``.
    margin : float
        Normalised LMI margin at ``tau_D``.
    solver : SolveInfo or None
    iterations : int
        LMI solves of the bisection.
    solve_s, exact_s : float
    detail : str
    """

    family: Family
    tau_D: Fraction | None
    certified: bool
    tau_lower: float
    tau_numeric: float
    P: tuple[Matrix, ...] | None
    margin: float
    solver: SolveInfo | None
    iterations: int
    solve_s: float
    exact_s: float
    detail: str = ""

    def certificate(self) -> DwellTimeEntry | None:
        """The certificate entry of the document (``None`` unless certified)."""
        if not self.certified or self.P is None or self.tau_D is None:
            return None
        return DwellTimeEntry(str(self.tau_D), [matrix_strings(P) for P in self.P], self.margin,
                              "Geromel-Colaneri LMI, bisection",
                              "-" if self.solver is None else f"{self.solver.solver} ({self.solver.status})")

    def to_json(self) -> dict[str, Any]:
        return {"tau_D": None if self.tau_D is None else str(self.tau_D),
                "tau_D_float": None if self.tau_D is None else float(self.tau_D),
                "certified": self.certified, "tau_lower": self.tau_lower, "tau_numeric": self.tau_numeric,
                "P": None if self.P is None else [matrix_strings(P) for P in self.P],
                "margin": self.margin, "iterations": self.iterations, "solve_s": self.solve_s,
                "exact_s": self.exact_s, "detail": self.detail,
                "solver": None if self.solver is None else f"{self.solver.solver} ({self.solver.status})",
                "family": self.family.to_json(), "solve_info": None if self.solver is None else self.solver.to_json()}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> "DwellTimeResult":
        """The result of :meth:`to_json`: ``tau_D``, the ``P_p`` and the family exact.

        ``family.numeric`` holds NumPy arrays, so compare two results by their :meth:`to_json`.
        """
        with _reading("dwell-time result"):
            return cls(Family.from_json(data["family"]), None if data["tau_D"] is None else Fraction(data["tau_D"]),
                       bool(data["certified"]), float(data["tau_lower"]), float(data["tau_numeric"]),
                       _matrices(data["P"]), float(data["margin"]), SolveInfo.from_json(data["solve_info"]),
                       int(data["iterations"]), float(data["solve_s"]), float(data["exact_s"]), str(data["detail"]))

    def __str__(self) -> str:
        if self.certified and self.tau_D is not None:
            return (f"dwell time (Geromel-Colaneri): tau_D = {self.tau_D} = {float(self.tau_D):.6g} certified exactly "
                    f"(LMI bound {self.tau_numeric:.6g}, infeasible at {self.tau_lower:.6g}; "
                    f"{self.iterations} LMI solves)")
        return f"dwell time (Geromel-Colaneri): not certified ({self.detail})"


def gc_margin(mats: Sequence[np.ndarray], T: float, *, solvers: Sequence[str] = DEFAULT_SOLVERS
              ) -> tuple[list[np.ndarray], float, SolveInfo]:
    """Normalised margin of the Geromel–Colaneri LMIs at dwell time ``T`` (positive: feasible)."""
    import cvxpy as cp
    import scipy.linalg

    n = mats[0].shape[0]
    N = len(mats)
    eye = np.eye(n)
    Es = [scipy.linalg.expm(A * T) for A in mats]

    def fn() -> tuple[cp.Problem, dict]:
        Ps = [cp.Variable((n, n), symmetric=True) for _ in mats]
        t = cp.Variable()
        cons = [sum(cp.trace(P) for P in Ps) == N * n]
        for p, (A, E, P) in enumerate(zip(mats, Es, Ps)):
            AP = A.T @ P
            cons += [P - t * eye >> 0, -(AP + AP.T) - t * eye >> 0]
            for q, Pq in enumerate(Ps):
                if q != p:
                    J = E.T @ Pq @ E
                    cons.append(P - (J + J.T) / 2 - t * eye >> 0)
        return cp.Problem(cp.Maximize(t), cons), {"P": Ps, "t": t}

    v, info = solve(fn, solvers=solvers, what=f"Geromel-Colaneri LMI at T = {T:.6g}")
    Ps = [np.asarray(P.value, dtype=float) for P in v["P"]]
    return [(P + P.T) / 2 for P in Ps], float(v["t"].value), info


def _round_up(x: float, digits: int = 4) -> Fraction:
    """A rational ``>= x`` with ``digits`` significant decimal digits."""
    e = math.floor(math.log10(x)) - digits + 1
    q = Fraction(10) ** e
    return math.ceil(Fraction(x) / q) * q


def dwell_time(family: FamilyLike, *, names: Sequence[str] | None = None, eps: float = 1e-7,
               rel_tol: float = 1e-3, tau_max: float | None = None,
               solvers: Sequence[str] = DEFAULT_SOLVERS) -> DwellTimeResult:
    """Smallest dwell time certified by the Geromel–Colaneri LMIs (bisection), with exact re-check.

    Parameters
    ----------
    family : matrices (Hurwitz), mapping or Family
    names : names of the matrices
    eps : float
        Threshold on the normalised LMI margin.
    rel_tol : float
        Relative width at which the bisection stops.
    tau_max : float, optional
        Largest dwell time tried (default ``1000 / min |Re lambda|``).
    solvers : cvxpy solvers in order of preference

    Returns
    -------
    DwellTimeResult
        ``tau_D`` is in the time of the switched system (the rescaled time
        ``tau`` for the observers of seed 004).

    Raises
    ------
    DimensionError, ModelError, NotHurwitzError, SolverFailure

    References
    ----------
    Geromel & Colaneri (2006), SIAM J. Control Optim. 45(5), Theorem 1;
    seed 004, 'Why asking for dwell-time?'; seed 000 Sec. III-D.

    Examples
    --------
    >>> A1 = [["-0.1", -1], [2, "-0.1"]]; A2 = [["-0.1", -2], [1, "-0.1"]]
    >>> dwell_time([A1, A2]).certified
    True
    """
    fam = as_family(family, names)
    bal = balance(fam.numeric)
    mats = bal.matrices  # time is scaled by sigma: T_b = sigma T
    slow = min(float(np.min(-np.linalg.eigvals(A).real)) for A in mats)
    hi = 1.0 / slow
    limit = (tau_max * bal.sigma) if tau_max is not None else 1000.0 / slow
    iterations = 0
    solve_s = 0.0
    last: tuple[list[np.ndarray], float, SolveInfo] | None = None
    while True:
        res = gc_margin(mats, hi, solvers=solvers)
        iterations += 1
        solve_s += res[2].solve_s
        if res[1] > eps:
            last = res
            break
        if hi >= limit:
            return DwellTimeResult(fam, None, False, hi / bal.sigma, np.inf, None, res[1], res[2], iterations,
                                   solve_s, 0.0, f"the LMIs are infeasible up to tau = {hi / bal.sigma:.4g}")
        hi = min(2 * hi, limit)
    lo = 0.0
    while hi - lo > rel_tol * hi and hi > 1e-9:
        progress(f"certify: dwell time in [{lo / bal.sigma:.4g}, {hi / bal.sigma:.4g}] (n = {fam.n}, "
                 f"LMI solve {iterations + 1})")
        mid = (lo + hi) / 2
        res = gc_margin(mats, mid, solvers=solvers)
        iterations += 1
        solve_s += res[2].solve_s
        if res[1] > eps:
            hi, last = mid, res
        else:
            lo = mid
    t0 = time.perf_counter()
    detail = ""
    for k in range(CERTIFY_ATTEMPTS):
        tau = _round_up(hi / bal.sigma * 1.1 ** k)
        Ps_b, t, info = gc_margin(mats, float(tau) * bal.sigma, solvers=solvers)
        iterations += 1
        if t <= eps:
            continue
        Ps = [dyadic(P / np.outer(bal.d, bal.d), 52) for P in Ps_b]
        check = check_entry(fam.names, fam.exact, DwellTimeEntry(str(tau), Ps))
        if check.holds:
            return DwellTimeResult(fam, tau, True, lo / bal.sigma, hi / bal.sigma, tuple(Ps), t, info, iterations,
                                   solve_s, time.perf_counter() - t0)
        detail = check.detail
    return DwellTimeResult(fam, None, False, lo / bal.sigma, hi / bal.sigma, None, 0.0,
                           last[2] if last else None, iterations, solve_s, time.perf_counter() - t0,
                           f"no rounded P_p passed the exact check up to tau = {float(tau):.4g} ({detail})")
