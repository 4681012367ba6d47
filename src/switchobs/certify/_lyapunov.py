"""Common quadratic Lyapunov functions: Hespanha's non-strict condition, strict CQLF, dual certificates.

Every numerical answer is turned into exact rational matrices and re-checked
by the independent checker before ``certified`` is set; the solver status is
reported but never decides anything.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np

from .._progress import progress
from ..exceptions import CertificateError
from ..model import user_matrix
from ..exact import (FACE_TOLERANCES, Matrix, dyadic, factor_rows, float_matrix, fraction_matrix, kernel_vector,
                     lyapunov_form, matrix_strings, normalise, project_dual, project_primal, psd_dyadic,
                     short_sqrt_lower)
from ._family import Family, FamilyLike, as_family
from ..lmi import DEFAULT_SOLVERS, SolveInfo, balance, dual_margin, primal_margin
from ._schema import CertificateKind, DualEntry, LyapunovEntry, SingularSumEntry
from ._verify import check_entry

__all__ = ["LyapunovResult", "DualCertificate", "SingularSum", "common_lyapunov", "strict_common_lyapunov",
           "infeasibility_certificate", "singular_sum", "DEFAULT_EPS"]

#: Numerical decision threshold on the normalised margin (``tr P = n``, family scaled to unit norm).
DEFAULT_EPS = 1e-7


def _fmt(M: Matrix | None) -> str:
    if M is None:
        return "    (none)"
    cells = [[str(x) for x in row] for row in M]
    w = max(len(c) for row in cells for c in row)
    return "\n".join("    [" + "  ".join(c.rjust(w) for c in row) + "]" for row in cells)


def _solver_text(info: SolveInfo | None) -> str:
    return "-" if info is None else f"{info.solver} ({info.status})"


def _matrices(data: Sequence[Any] | None) -> tuple[Matrix, ...] | None:
    return None if data is None else tuple(fraction_matrix(M) for M in data)


@contextmanager
def _reading(what: str) -> Iterator[None]:
    """Turn a missing key or a wrong type in a ``to_json`` document into a :class:`CertificateError`."""
    try:
        yield
    except (KeyError, TypeError, ValueError, IndexError) as exc:
        raise CertificateError(f"not a {what} JSON ({type(exc).__name__}: {exc})") from None


@dataclass(frozen=True)
class DualCertificate:
    """Exact proof that no (strict) common quadratic Lyapunov function exists.

    Attributes
    ----------
    kind : str
        ``"no-common-lyapunov"`` (``S != 0``: not even a non-strict P) or
        ``"no-strict-cqlf"`` (``S`` may vanish).  Empty when nothing was certified.
    certified : bool
    R : tuple of Matrix or None
        ``R_p >= 0`` with ``S = sum_p (A_p R_p + R_p A_p') >= 0``.
    margin : float
        Numerical optimum ``s`` of ``max s : sum tr R_p = 1, S >= s I``.
    solver : SolveInfo
    method : str
    exact_s : float
        Wall time of rounding and exact checking.
    detail : str
        Why nothing was certified, when that is the case.
    """

    kind: str
    certified: bool
    R: tuple[Matrix, ...] | None
    margin: float
    solver: SolveInfo | None
    method: str
    exact_s: float
    detail: str = ""

    def certificate(self) -> DualEntry | None:
        """The certificate entry of the document (``None`` unless certified)."""
        if not self.certified or self.R is None:
            return None
        return DualEntry(CertificateKind(self.kind), [matrix_strings(R) for R in self.R], self.margin, self.method,
                         _solver_text(self.solver))

    def to_json(self) -> dict[str, Any]:
        return {"kind": self.kind, "certified": self.certified,
                "R": None if self.R is None else [matrix_strings(R) for R in self.R],
                "margin": self.margin, "solver": _solver_text(self.solver), "method": self.method,
                "exact_s": self.exact_s, "detail": self.detail,
                "solve_info": None if self.solver is None else self.solver.to_json()}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> "DualCertificate":
        """The certificate of :meth:`to_json` (``R`` read back exactly)."""
        with _reading("dual certificate"):
            return cls(str(data["kind"]), bool(data["certified"]), _matrices(data["R"]), float(data["margin"]),
                       SolveInfo.from_json(data["solve_info"]), str(data["method"]), float(data["exact_s"]),
                       str(data["detail"]))

    def __str__(self) -> str:
        if not self.certified:
            return f"dual certificate: none ({self.detail})"
        what = "no strict CQLF" if self.kind == "no-strict-cqlf" else "no common (even non-strict) Lyapunov P"
        lines = [f"dual certificate [{self.kind}]: {what}, verified exactly ({self.method}; {_solver_text(self.solver)})"]
        for i, R in enumerate(self.R or ()):
            lines += [f"  R_{i + 1} =", _fmt(R)]
        return "\n".join(lines)


@dataclass(frozen=True)
class SingularSum:
    """Exact proof that no strict CQLF exists: ``(sum_p A_p) v = 0`` for a rational ``v != 0``.

    A strict ``P`` would give ``M' P + P M < 0`` for ``M = sum_p A_p`` (a sum of
    negative definite matrices), yet ``v' (M' P + P M) v = 2 (M v)' P v = 0``.
    It is the dual certificate ``R_p = v v'`` of :class:`DualCertificate`
    (``sum_p (A_p R_p + R_p A_p') = M v v' + v v' M' = 0``), found without an LMI.
    Every observer pair has one: ``A_plus + A_minus = (K_minus - K_plus) C`` vanishes on
    the kernel of ``C``.

    Attributes
    ----------
    v : tuple of Fraction
        The kernel vector (integers with no common factor).
    exact_s : float
        Wall time of finding and checking it.
    """

    v: tuple[Fraction, ...]
    exact_s: float
    method: str = "exact kernel of sum_p A_p"

    kind = "singular-sum"
    certified = True

    def certificate(self) -> SingularSumEntry:
        """The certificate entry of the document."""
        return SingularSumEntry([str(x) for x in self.v], self.method)

    def to_json(self) -> dict[str, Any]:
        return {"kind": self.kind, "certified": self.certified, "v": [str(x) for x in self.v],
                "method": self.method, "exact_s": self.exact_s}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> "SingularSum":
        """The proof of :meth:`to_json` (``v`` exact).

        Raises
        ------
        CertificateError
            A missing key or a malformed entry of ``v``.
        """
        with _reading("singular-sum proof"):
            return cls(tuple(Fraction(str(x)) for x in data["v"]), float(data["exact_s"]), str(data["method"]))

    def __str__(self) -> str:
        return (f"no strict CQLF [{self.kind}]: (sum_p A_p) v = 0 for v = [{', '.join(str(x) for x in self.v)}], "
                "verified exactly")


def _dual_from_json(data: Mapping[str, Any] | None) -> DualCertificate | SingularSum | None:
    """The ``dual`` of a :class:`LyapunovResult` JSON: a :class:`SingularSum` (``kind`` singular-sum) or a dual LMI."""
    if data is None:
        return None
    if isinstance(data, Mapping) and data.get("kind") == SingularSum.kind:
        return SingularSum.from_json(data)
    return DualCertificate.from_json(data)


def singular_sum(family: FamilyLike, *, names: Sequence[str] | None = None) -> SingularSum | None:
    """The exact :class:`SingularSum` proof that no strict CQLF exists, or None when ``sum_p A_p`` is nonsingular.

    Examples
    --------
    >>> singular_sum([[[-1, -1], [1, 0]], [[-1, 1], [-1, 0]]]).v
    (Fraction(0, 1), Fraction(1, 1))
    """
    fam = as_family(family, names)
    t0 = time.perf_counter()
    n = fam.n
    total = [[sum(A[i][j] for A in fam.exact) for j in range(n)] for i in range(n)]
    v = kernel_vector(total)
    if v is None:
        return None
    if not check_entry(fam.names, fam.exact, SingularSumEntry([str(x) for x in v])).holds:
        return None
    return SingularSum(tuple(v), time.perf_counter() - t0)


@dataclass(frozen=True)
class LyapunovResult:
    """Outcome of :func:`common_lyapunov` (Hespanha) or :func:`strict_common_lyapunov`.

    Attributes
    ----------
    kind : str
        ``"hespanha"`` or ``"strict-cqlf"``.
    family : Family
    feasible : bool
        The numerical decision: normalised margin above ``eps``.
    certified : bool
        The rational certificate holds exactly (the only verdict that counts).
    margin, eps : float
        Normalised margin ``t`` (``tr P = n``, ``P >= t I``, family of unit norm)
        and the threshold used.
    P : Matrix or None
    C : tuple of Matrix or None
        Output matrices ``C_p`` of Hespanha's condition
        (``A_p' P + P A_p <= -C_p' C_p``, ``(A_p, C_p)`` observable).
    solver : SolveInfo or None
    method : str
        ``"direct rounding"`` or ``"facial projection (face tol ...)"``.
    exact_s : float
        Wall time of rounding and exact re-checking.
    detail : str
        Why the result is not certified, when it is not.
    dual : DualCertificate, SingularSum or None
        When infeasible: the exact proof of infeasibility, if one was found.
    """

    kind: str
    family: Family
    feasible: bool
    certified: bool
    margin: float
    eps: float
    P: Matrix | None
    C: tuple[Matrix, ...] | None
    solver: SolveInfo | None
    method: str
    exact_s: float
    detail: str = ""
    dual: DualCertificate | SingularSum | None = None

    @property
    def P_float(self) -> np.ndarray | None:
        return None if self.P is None else np.array([[float(x) for x in r] for r in self.P])

    def certificate(self) -> LyapunovEntry | None:
        """The certificate entry of the document (``None`` unless certified)."""
        if not self.certified or self.P is None:
            return None
        kind = CertificateKind(self.kind)
        C = [matrix_strings(C) for C in (self.C or ())] if kind is CertificateKind.HESPANHA else None
        return LyapunovEntry(kind, matrix_strings(self.P), C, None if math.isnan(self.margin) else self.margin,
                             self.method, _solver_text(self.solver))

    def to_json(self) -> dict[str, Any]:
        return {"kind": self.kind, "feasible": self.feasible, "certified": self.certified,
                "margin": None if math.isnan(self.margin) else self.margin, "eps": self.eps,
                "P": None if self.P is None else matrix_strings(self.P),
                "C": None if self.C is None else [matrix_strings(C) for C in self.C],
                "solver": _solver_text(self.solver),
                "attempts": [] if self.solver is None else list(self.solver.attempts),
                "method": self.method, "exact_s": self.exact_s, "detail": self.detail,
                "dual": None if self.dual is None else self.dual.to_json(),
                "family": self.family.to_json(), "solve_info": None if self.solver is None else self.solver.to_json()}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> "LyapunovResult":
        """The result of :meth:`to_json`: ``P``, ``C`` and the family exact, a margin of ``None`` as NaN.

        ``family.numeric`` holds NumPy arrays, so compare two results by their :meth:`to_json`.
        """
        with _reading("Lyapunov result"):
            P = None if data["P"] is None else fraction_matrix(data["P"], what="P")
            return cls(str(data["kind"]), Family.from_json(data["family"]), bool(data["feasible"]),
                       bool(data["certified"]), math.nan if data["margin"] is None else float(data["margin"]),
                       float(data["eps"]), P, _matrices(data["C"]), SolveInfo.from_json(data["solve_info"]),
                       str(data["method"]), float(data["exact_s"]), str(data["detail"]),
                       _dual_from_json(data["dual"]))

    def __str__(self) -> str:
        title = {"hespanha": "Hespanha non-strict common Lyapunov P",
                 "strict-cqlf": "strict common quadratic Lyapunov P"}[self.kind]
        if self.certified:
            state = f"certified exactly ({self.method})"
        elif self.feasible:
            state = f"numerically feasible but NOT certified: {self.detail}"
        elif math.isnan(self.margin):
            state = f"none: {self.detail}"
        else:
            state = f"not found (margin {self.margin:.3g} <= eps {self.eps:g})"
        lines = [f"{title}: {state}", f"  margin {self.margin:.4g}, solver {_solver_text(self.solver)}"]
        if self.certified:
            lines += ["  P =", _fmt(self.P)]
            for nm, C in zip(self.family.names, self.C or ()):
                lines += [f"  C for {nm} =", _fmt(C)]
        if self.dual is not None:
            lines.append("  " + str(self.dual).replace("\n", "\n  "))
        return "\n".join(lines)


def _unbalance_P(P_b: np.ndarray, d: np.ndarray) -> np.ndarray:
    return P_b / np.outer(d, d)


def _output_weights(bal_d: np.ndarray, output: Any, n: int, count: int) -> list[np.ndarray]:
    """``H = C' C`` in balanced coordinates (identity without an output), normalised to unit norm."""
    if output is None:
        return [np.eye(n)] * count
    Cf = float_matrix(user_matrix(output, what="output C", part="C", cols=n))
    Cb = Cf * bal_d[None, :]
    H = Cb.T @ Cb
    return [H / (np.linalg.norm(H, 2) or 1.0)] * count


def _interior_outputs(fam: Family, P: Matrix, P_num: np.ndarray) -> list[Matrix] | None:
    """``C_p``: ``q I`` when ``W_p`` is numerically definite, else an exact factor of ``W_p``."""
    out = []
    for A, Af in zip(fam.exact, fam.numeric):
        W_num = -(Af.T @ P_num + P_num @ Af)
        w = np.linalg.eigvalsh((W_num + W_num.T) / 2)
        if w[0] > 1e-6 * max(w[-1], 1e-300):
            q = short_sqrt_lower(Fraction(float(w[0]) / 2))
            out.append([[q if i == j else Fraction(0) for j in range(fam.n)] for i in range(fam.n)])
        else:
            W = [[-x for x in row] for row in lyapunov_form(A, P)]
            C = factor_rows(W)
            if C is None:
                return None
            out.append(C)
    return out


def _factors(Ws: Sequence[Matrix]) -> list[Matrix] | None:
    outs = [factor_rows(W) for W in Ws]
    return None if any(C is None for C in outs) else outs


def common_lyapunov(family: FamilyLike, *, output: Any = None, names: Sequence[str] | None = None,
                    eps: float = DEFAULT_EPS, solvers: Sequence[str] = DEFAULT_SOLVERS,
                    dual: bool = True, candidate: tuple[Any, Sequence[Any]] | None = None) -> LyapunovResult:
    """Hespanha's non-strict common Lyapunov condition, solved by LMI and certified exactly.

    Find ``P = P' > 0`` and ``C_p`` with ``A_p' P + P A_p <= -C_p' C_p`` and every
    ``(A_p, C_p)`` observable.  With ``output`` (the model's ``C``) the LMI
    maximises ``t`` in ``P >= t I``, ``A_p' P + P A_p <= -t C' C`` (``tr P = n``), the
    structure of seed 000 eq. (24)-(28); without it, first the strict margin
    is tried and then the plain non-strict one (for Hurwitz ``A_p`` and
    ``P > 0``, ``(A_p, W_p)`` with ``W_p = -(A_p' P + P A_p) >= 0`` is automatically
    observable: an unobservable eigenvector ``v`` would give ``v* W_p v = -2 Re(lambda) v* P v = 0``).

    Parameters
    ----------
    family : sequence of matrices, mapping name -> matrix, or Family
    output : matrix, optional
        Output rows ``C`` (k x n) shared by the modes, e.g. the model's ``C``.
    names : names of the matrices (default ``A_1, A_2, ...``)
    eps : float
        Threshold on the normalised margin for the numerical decision.
    solvers : sequence of str
        cvxpy solvers in order of preference (default Clarabel, then SCS).
    dual : bool
        When infeasible, look for an exact certificate of infeasibility.
    candidate : (P, [C_p, ...]), optional
        An exact certificate known beforehand, e.g. the common ``P`` of a gain
        design (seed 004 Theorem 1: ``A_p' P + P A_p = -C' C``).  It is checked
        exactly first; the LMI runs only if it does not hold.  This is what
        makes large numeric observers cheap: no LMI, no rounding, no projection.

    Returns
    -------
    LyapunovResult

    Raises
    ------
    DimensionError, ModelError, NotHurwitzError, SolverFailure

    References
    ----------
    Hespanha (2004), Theorem 4; seed 004 (Hespanha's theorem and Theorem 1);
    seed 000 Sec. III-D and Appendix eq. (24)-(28).

    Examples
    --------
    >>> res = common_lyapunov([[[-1, -1], [1, 0]], [[-1, 1], [-1, 0]]], output=[[1, 0]])
    >>> res.certified
    True
    """
    fam = as_family(family, names)
    if candidate is not None:
        t0 = time.perf_counter()
        P = fraction_matrix(candidate[0], what="candidate P", rows=fam.n, cols=fam.n)
        Cs = [fraction_matrix(C, what="candidate C", cols=fam.n) for C in candidate[1]]
        if check_entry(fam.names, fam.exact, LyapunovEntry(CertificateKind.HESPANHA, P, Cs)).holds:
            return LyapunovResult("hespanha", fam, True, True, math.nan, eps, P, tuple(Cs), None,
                                  "exact P of the gain design", time.perf_counter() - t0)
    bal = balance(fam.numeric)
    n, N = fam.n, len(fam)
    stages = [_output_weights(bal.d, output, n, N), [None] * N]
    P_num = None
    info = None
    t = -np.inf
    for H in stages:
        P_b, t, info = primal_margin(bal.matrices, H, solvers=solvers, what="Hespanha LMI")
        if t > eps:
            P_num = _unbalance_P(P_b, bal.d)
            break
    t0 = time.perf_counter()
    if P_num is None:
        d = infeasibility_certificate(fam, eps=eps, solvers=solvers) if dual else None
        return LyapunovResult("hespanha", fam, False, False, float(t), eps, None, None, info, "",
                              time.perf_counter() - t0, "no common P found numerically", d)
    detail = ""
    P = dyadic(P_num)
    Cs = _interior_outputs(fam, P, P_num)
    if Cs is not None:
        check = check_entry(fam.names, fam.exact, LyapunovEntry(CertificateKind.HESPANHA, P, Cs))
        if check.holds:
            return LyapunovResult("hespanha", fam, True, True, float(t), eps, P, tuple(Cs), info,
                                  "direct rounding", time.perf_counter() - t0)
        detail = check.detail
    for tol in FACE_TOLERANCES:
        proj = project_primal(fam.exact, P_num, tol)
        if proj is None:
            continue
        P, *Ws = normalise(proj[0], *proj[1])
        Cs = _factors(Ws)
        if Cs is None:
            continue
        check = check_entry(fam.names, fam.exact, LyapunovEntry(CertificateKind.HESPANHA, P, Cs))
        if check.holds:
            return LyapunovResult("hespanha", fam, True, True, float(t), eps, P, tuple(Cs), info,
                                  f"facial projection (face tol {tol:g})", time.perf_counter() - t0)
        detail = check.detail
    detail = detail or "rounding broke the inequalities and no exact face projection succeeded"
    # a first-order solver's "optimal" (SCS, ~1e-4) can be too coarse to read the face from, where the
    # interior-point solver's "optimal_inaccurate" answer is not: the other solvers' answers get their turn
    others = tuple(name for name in solvers if name != (info.solver if info is not None else None))
    if info is not None and others and len(others) < len(solvers):
        retry = common_lyapunov(fam, output=output, names=names, eps=eps, solvers=others, dual=dual)
        if retry.certified:
            return retry
    return LyapunovResult("hespanha", fam, True, False, float(t), eps, None, None, info, "",
                          time.perf_counter() - t0, detail)


def strict_common_lyapunov(family: FamilyLike, *, names: Sequence[str] | None = None, eps: float = DEFAULT_EPS,
                           solvers: Sequence[str] = DEFAULT_SOLVERS, dual: bool = True) -> LyapunovResult:
    """Strict common quadratic Lyapunov function (arbitrary switching), or an exact proof that none exists.

    The LMI ``max t : tr P = n, P >= t I, A_p' P + P A_p <= -t I`` (family
    balanced and scaled to unit norm) decides numerically (``t > eps``); a
    positive answer is rounded to a rational ``P`` and ``P > 0``,
    ``A_p' P + P A_p < 0`` are re-checked exactly.  With ``dual``, a singular
    ``sum_p A_p`` is tried first: it proves exactly, without any LMI, that no
    strict P exists (:func:`singular_sum`).  Otherwise the dual problem
    gives ``R_p >= 0`` with ``sum_p (A_p R_p + R_p A_p') >= 0``, checked exactly:
    that is a proof of infeasibility, a solver status is not.

    Parameters
    ----------
    family, names, eps, solvers, dual
        As in :func:`common_lyapunov`.

    Returns
    -------
    LyapunovResult

    References
    ----------
    seed 004 (the 2D example has no strict CQLF, Balde-Boscain-Mason 2009);
    Boyd, El Ghaoui, Feron, Balakrishnan (1994), Sec. 2.2 (theorems of alternatives).

    Examples
    --------
    >>> strict_common_lyapunov([[[-1, 0], [0, -2]]]).certified
    True
    """
    fam = as_family(family, names)
    if dual:
        kernel = singular_sum(fam)
        if kernel is not None:  # decided exactly, no LMI needed
            return LyapunovResult("strict-cqlf", fam, False, False, math.nan, eps, None, None, None, "",
                                  kernel.exact_s, "no strict common P exists: sum_p A_p is singular", kernel)
    bal = balance(fam.numeric)
    P_b, t, info = primal_margin(bal.matrices, [np.eye(fam.n)] * len(fam), solvers=solvers,
                                 what="strict CQLF LMI")
    t0 = time.perf_counter()
    if t <= eps:
        if dual:
            progress(f"certify: no strict CQLF numerically; dual (infeasibility) LMI (n = {fam.n})")
        d = infeasibility_certificate(fam, eps=eps, solvers=solvers) if dual else None
        return LyapunovResult("strict-cqlf", fam, False, False, float(t), eps, None, None, info, "",
                              time.perf_counter() - t0, "no strict common P found numerically", d)
    P_num = _unbalance_P(P_b, bal.d)
    P = dyadic(P_num)
    check = check_entry(fam.names, fam.exact, LyapunovEntry(CertificateKind.STRICT_CQLF, P))
    if check.holds:
        return LyapunovResult("strict-cqlf", fam, True, True, float(t), eps, P, None, info, "direct rounding",
                              time.perf_counter() - t0)
    return LyapunovResult("strict-cqlf", fam, True, False, float(t), eps, None, None, info, "",
                          time.perf_counter() - t0, check.detail)


def infeasibility_certificate(family: FamilyLike, *, names: Sequence[str] | None = None, eps: float = DEFAULT_EPS,
                              solvers: Sequence[str] = DEFAULT_SOLVERS) -> DualCertificate:
    """The strongest exact certificate that no common quadratic Lyapunov function exists.

    Solves ``max s : R_p >= 0, sum tr R_p = 1, S = sum_p (A_p R_p + R_p A_p') >= s I``.
    ``s > eps``: ``R_p`` are rounded through dyadic factors (semidefinite by
    construction) and ``S > 0`` survives rounding: no non-strict common P
    either (``no-common-lyapunov``).  ``|s| <= eps``: the boundary case (seed
    004's planar example, where ``S = 0`` is forced); the face of the
    numerical solution is projected exactly (``no-strict-cqlf``, or
    ``no-common-lyapunov`` if the exact ``S`` is nonzero).

    Returns
    -------
    DualCertificate
        ``certified`` False with the reason if nothing could be proven.
    """
    fam = as_family(family, names)
    bal = balance(fam.numeric)
    R_b, s, info = dual_margin(bal.matrices, solvers=solvers, what="dual (infeasibility) LMI")
    t0 = time.perf_counter()
    R_num = [R * np.outer(bal.d, bal.d) for R in R_b]
    if s < -eps:
        return DualCertificate("", False, None, float(s), info, "", time.perf_counter() - t0,
                               f"the dual optimum {s:.3g} is negative: a strict common P is expected")
    detail = ""
    if s > eps:
        Rs = [psd_dyadic(R) for R in R_num]
        check = check_entry(fam.names, fam.exact, DualEntry(CertificateKind.NO_COMMON_LYAPUNOV, Rs))
        if check.holds:
            return DualCertificate("no-common-lyapunov", True, tuple(Rs), float(s), info, "direct rounding",
                                   time.perf_counter() - t0)
        detail = check.detail
    for tol in FACE_TOLERANCES:
        proj = project_dual(fam.exact, R_num, tol)
        if proj is None:
            continue
        Rs, S = proj
        top = max(R[i][i] for R in Rs for i in range(len(R)))
        if top > 0:  # the alternative is homogeneous: show R with largest diagonal entry 1
            Rs = [[[x / top for x in row] for row in R] for R in Rs]
            S = [[x / top for x in row] for row in S]
        kind = "no-strict-cqlf" if all(x == 0 for row in S for x in row) else "no-common-lyapunov"
        check = check_entry(fam.names, fam.exact, DualEntry(CertificateKind(kind), Rs))
        if check.holds:
            return DualCertificate(kind, True, tuple(Rs), float(s), info, f"facial projection (face tol {tol:g})",
                                   time.perf_counter() - t0)
        detail = check.detail
    return DualCertificate("", False, None, float(s), info, "", time.perf_counter() - t0,
                           detail or "no exact dual certificate could be extracted from the numerical solution")
