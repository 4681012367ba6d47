"""Certificates over parameter boxes: one Lyapunov certificate for every parameter value of a box.

The gains are fixed at the nominal design; the uncertain parameters
``theta`` (a box ``lo_i <= theta_i <= hi_i`` around the nominal values) enter
``A`` polynomially, so ``A_plus(theta) = A(theta) - K_plus C`` and
``A_minus(theta) = -A(theta) + K_minus C``.  The LMIs are posed at the
vertices of a polytope containing ``{A(theta)}`` (the box's vertices when
``A`` is affine in ``theta``; monomial lifting on sub-boxes otherwise, see
:mod:`switchobs.certify._box_check`), solved with margins, rounded to
rationals and re-checked exactly at every vertex.

Properties that can hold on a box:

* **strict common P** (UGES under arbitrary switching, for every ``theta`` and
  even for ``theta`` varying in time) -- impossible for a single output
  (``A_plus + A_minus = (K_minus - K_plus) C``), possible with two outputs;
* **dwell time** with piecewise-linear time-varying Lyapunov matrices
  (Allerhand & Shaked 2011): conditions affine in ``A``, so vertex checks are
  exact proofs for the box, no matrix exponential is needed;
* Hespanha's non-strict common P is *not* attempted: for one output every
  common non-strict P of the pair at ``theta`` is a multiple of the
  observability Gramian of ``(A_plus(theta), C)``, which changes direction
  with ``theta`` (for abs-xbs3 ``p_12 = c/a``, ``p_13 = 1/a``, seed 000 (24)),
  so no single P serves a box in ``a`` or ``c``.

When the whole box is not certified, :func:`certify_box` bisects on the scale
``rho`` of the box ``nominal + rho (box - nominal)`` for the largest
certified sub-box.

The smallest dwell time is bracketed on the nominal point first (its LMIs have
one matrix per mode instead of one per vertex, 10x cheaper at ``n = 16``): the
nominal ``A`` is a convex combination of the vertices', so the vertex LMIs'
margin never exceeds the nominal one and the bracket's lower end is infeasible
for the box too.  The vertex LMIs then start at its upper end.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # imported where an LMI is built (see _lmi)
    import cvxpy as cp

from ..exact import Matrix, dyadic, float_matrix, fraction_matrix, matrix_strings, to_fraction, vertex_matrices
from ..exceptions import ModelError
from ..lmi import DEFAULT_SOLVERS, SolveInfo, balance, primal_margin, solve
from ..model import Model, ParameterBox, matrix_rows, model_terms, parse_box
from ..model._box import bound_text
from ._box_check import check_dwell, check_strict
from ._dwell import _round_up
from ._lyapunov import DEFAULT_EPS, _reading

__all__ = ["BoxCertificate", "certify_box", "DEFAULT_SEGMENTS", "SEARCH_STEPS"]

#: Segments of the piecewise-linear Lyapunov matrices over the dwell time.
DEFAULT_SEGMENTS = 2
#: Bisection steps on the box scale (the scale is a multiple of 2^-SEARCH_STEPS).
SEARCH_STEPS = 6
#: Candidates ``tau * 1.1^k`` tried for the exact dwell-time certificate.
_CERTIFY_ATTEMPTS = 8
#: Relative width at which the bisection on the dwell time stops.
_REL_TOL = 0.02
#: Factor by which the box's dwell time grows from the nominal bracket until the vertex LMIs hold.
_GROWTH = 1.25


@dataclass(frozen=True)
class BoxCertificate:
    """Outcome of :func:`certify_box`.

    Attributes
    ----------
    requested : ParameterBox
        The box asked for.
    box : ParameterBox or None
        The box certified: the requested one, or the largest scaled sub-box found (None if none).
    scale : Fraction
        ``rho`` of the certified box ``nominal + rho (requested - nominal)`` (1: all of it; 0: none).
    kind : str
        ``"strict-cqlf"`` (UGES under arbitrary switching on the box) or ``"dwell-time"``; empty if none.
    tau_D : Fraction or None
        Certified dwell time (rescaled time) for ``"dwell-time"``.
    vertices : int
        Vertex matrices per mode of the certified box.
    inactive : tuple of str
        Box parameters that do not enter ``A`` (no effect on the certificate).
    data : dict or None
        The ``box`` section of the certificate document (what ``verify`` re-checks).
    detail : str
        Why the requested box (or any box) is not certified.
    timings : dict
        Wall time [s] of the stages.
    """

    requested: ParameterBox
    box: ParameterBox | None
    scale: Fraction
    kind: str
    tau_D: Fraction | None
    vertices: int
    inactive: tuple[str, ...]
    data: dict[str, Any] | None
    detail: str = ""
    timings: dict[str, float] = field(default_factory=dict)

    @property
    def certified(self) -> bool:
        """The whole requested box is certified."""
        return self.data is not None and self.scale == 1

    def to_json(self) -> dict[str, Any]:
        return {"requested": self.requested.to_json(), "box": None if self.box is None else self.box.to_json(),
                "scale": str(self.scale), "certified": self.certified, "kind": self.kind,
                "tau_D": None if self.tau_D is None else str(self.tau_D), "vertices": self.vertices,
                "inactive": list(self.inactive), "detail": self.detail, "timings": self.timings,
                "data": self.data}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> "BoxCertificate":
        """The certificate of :meth:`to_json` (boxes, scale and ``tau_D`` exact; ``data`` as stored).

        Raises
        ------
        CertificateError
            A missing key or a malformed box or number; the message names it.
        """
        with _reading("box certificate"):
            box = None if data["box"] is None else ParameterBox.from_json(data["box"])
            return cls(ParameterBox.from_json(data["requested"]), box, to_fraction(data["scale"], what="scale"),
                       str(data["kind"]), None if data["tau_D"] is None else to_fraction(data["tau_D"], what="tau_D"),
                       int(data["vertices"]), tuple(str(x) for x in data["inactive"]),
                       None if data["data"] is None else dict(data["data"]), str(data["detail"]),
                       {str(k): float(v) for k, v in data["timings"].items()})

    def __str__(self) -> str:
        if self.data is None or self.box is None:
            return f"box {self.requested}: nothing certified ({self.detail})"
        what = ("strict common P: UGES under arbitrary switching" if self.kind == "strict-cqlf" else
                f"dwell time tau_D = {self.tau_D} = {float(self.tau_D):.5g} (piecewise-linear Lyapunov)")
        head = (f"box {self.box}: certified exactly at {self.vertices} vertices per mode, {what}"
                if self.certified else
                f"box {self.requested}: NOT certified ({self.detail}); largest certified sub-box "
                f"(scale {bound_text(self.scale)}): {self.box}, {what}")
        if self.inactive:
            head += f"\n  {', '.join(self.inactive)} enter(s) only d or b, not the error dynamics: no effect"
        return head


# ----------------------------------------------------------------------------- LMIs
def pwl_margin(modes: Sequence[Sequence[np.ndarray]], T: float, segments: int, *,
               solvers: Sequence[str] = DEFAULT_SOLVERS) -> tuple[list[list[np.ndarray]], float, SolveInfo]:
    """Normalised margin of the piecewise-linear dwell-time LMIs at dwell time ``T`` (positive: feasible)."""
    import cvxpy as cp

    n = modes[0][0].shape[0]
    K = segments
    delta = T / K
    eye = np.eye(n)

    def fn() -> tuple[cp.Problem, dict]:
        Ps = [[cp.Variable((n, n), symmetric=True) for _ in range(K + 1)] for _ in modes]
        t = cp.Variable()
        cons = [sum(cp.trace(P) for seq in Ps for P in seq) == len(modes) * (K + 1) * n]
        cons += [P - t * eye >> 0 for seq in Ps for P in seq]
        for mats, seq in zip(modes, Ps):
            for A in mats:
                for k in range(K):
                    slope = (seq[k + 1] - seq[k]) / delta
                    for P in (seq[k], seq[k + 1]):
                        X = A.T @ P
                        cons.append(-(slope + X + X.T) - t * eye >> 0)
                X = A.T @ seq[K]
                cons.append(-(X + X.T) - t * eye >> 0)
        for p, q in ((0, 1), (1, 0)):
            cons.append(Ps[p][K] - Ps[q][0] - t * eye >> 0)
        return cp.Problem(cp.Maximize(t), cons), {"P": Ps, "t": t}

    v, info = solve(fn, solvers=solvers, what=f"piecewise-linear dwell-time LMI at T = {T:.6g}")
    Ps = [[(np.asarray(P.value) + np.asarray(P.value).T) / 2 for P in seq] for seq in v["P"]]
    return Ps, float(v["t"].value), info


@dataclass(frozen=True)
class _Attempt:
    kind: str
    certificate: dict[str, Any] | None
    tau_D: Fraction | None
    detail: str


class _BoxProblem:
    """The vertex LMIs of one model, gains and box family; ``attempt(rho)`` certifies one scaled box."""

    def __init__(self, terms: Sequence[tuple[list[int], Matrix]], nominal: Sequence[Fraction],
                 requested: ParameterBox, pieces: int, segments: int, C: Matrix, Kp: Matrix, Km: Matrix,
                 eps: float, solvers: Sequence[str], tau_max: float | None) -> None:
        self.terms, self.nominal, self.requested = terms, nominal, requested
        self.pieces, self.segments, self.C, self.Kp, self.Km = pieces, segments, C, Kp, Km
        self.eps, self.solvers, self.tau_max = eps, solvers, tau_max
        self.nominal_modes = [float_matrix(mats[0]) for mats in self.vertices(Fraction(0))]

    def vertices(self, rho: Fraction) -> tuple[list[Matrix], list[Matrix]]:
        return vertex_matrices(self.terms, self.requested.scaled(self.nominal, rho).intervals, self.pieces,
                               self.C, self.Kp, self.Km)

    def attempt(self, rho: Fraction, *, smallest_dwell: bool) -> _Attempt:
        modes = self.vertices(rho)
        numeric = [[float_matrix(A) for A in mats] for mats in modes]
        for name, mats in zip(("A_plus", "A_minus"), numeric):
            for i, A in enumerate(mats):
                if np.max(np.linalg.eigvals(A).real) >= 0:
                    return _Attempt("", None, None, f"{name} is not Hurwitz at vertex {i + 1} of the box")
        strict = self._strict(modes, numeric)
        if strict.certificate is not None:
            return strict
        return self._dwell(modes, numeric, smallest_dwell)

    def _strict(self, modes: list[list[Matrix]], numeric: list[list[np.ndarray]]) -> _Attempt:
        flat = numeric[0] + numeric[1]
        bal = balance(flat)
        P_b, t, _ = primal_margin(bal.matrices, [np.eye(flat[0].shape[0])] * len(flat), solvers=self.solvers,
                                  what="box strict CQLF LMI")
        if t <= self.eps:
            return _Attempt("", None, None, f"no strict common P (margin {t:.3g})")
        P = dyadic(P_b / np.outer(bal.d, bal.d))
        reason = check_strict(modes, P)
        if reason:
            return _Attempt("", None, None, f"strict common P rounded but not exact: {reason}")
        return _Attempt("strict-cqlf", {"kind": "strict-cqlf", "P": matrix_strings(P)}, None, "")

    def _dwell(self, modes: list[list[Matrix]], numeric: list[list[np.ndarray]], smallest: bool) -> _Attempt:
        bal = balance(numeric[0] + numeric[1])
        N = len(numeric[0])
        mats = [list(bal.matrices[:N]), list(bal.matrices[N:])]
        slow = min(float(np.min(-np.linalg.eigvals(A).real)) for A in bal.matrices)
        limit = self.tau_max * bal.sigma if self.tau_max is not None else 1000.0 / slow
        solved: dict[Fraction, tuple[list[list[np.ndarray]], float]] = {}

        def margin(tau: Fraction) -> float:
            """The box LMIs' margin at the dwell time ``tau`` (rescaled time), solved once per ``tau``."""
            if tau not in solved:
                Ps_b, t, _ = pwl_margin(mats, float(tau) * bal.sigma, self.segments, solvers=self.solvers)
                solved[tau] = (Ps_b, t)
            return solved[tau][1]

        hi_tau = _round_up(limit / bal.sigma)
        if smallest:
            # bracketed on the nominal point alone first (one vertex per mode instead of all of them, 10x
            # cheaper at n = 16): the nominal A is a convex combination of the vertices', so the vertex LMIs'
            # margin is at most the nominal one at every dwell time, and a dwell time infeasible there is
            # infeasible for the box
            nominal = [[(A * bal.d[None, :]) / bal.d[:, None] / bal.sigma] for A in self.nominal_modes]
            bracket = self._bisect(nominal, 1.0 / slow, limit)
            if bracket is None:
                return _Attempt("", None, None, f"the dwell-time LMIs are infeasible up to tau = "
                                                f"{limit / bal.sigma:.4g} (at the nominal point already)")
            lo, hi_tau = bracket[0] / bal.sigma, _round_up(bracket[1] / bal.sigma)
            while margin(hi_tau) <= self.eps:
                if float(hi_tau) * bal.sigma >= limit:
                    return _Attempt("", None, None, f"the dwell-time LMIs are infeasible up to tau = "
                                                    f"{float(hi_tau):.4g}")
                lo, hi_tau = float(hi_tau), _round_up(min(float(hi_tau) * _GROWTH, limit / bal.sigma))
            while float(hi_tau) - lo > _REL_TOL * float(hi_tau):
                mid = _round_up((lo + float(hi_tau)) / 2)
                if mid >= hi_tau:
                    break
                if margin(mid) > self.eps:
                    hi_tau = mid
                else:
                    lo = float(mid)
        detail = "the dwell-time LMIs are infeasible"
        for k in range(_CERTIFY_ATTEMPTS if smallest else 1):
            tau = hi_tau if k == 0 else _round_up(float(hi_tau) * 1.1 ** k)
            t = margin(tau)
            if t <= self.eps:
                detail = f"the dwell-time LMIs are infeasible at tau = {float(tau):.4g} (margin {t:.3g})"
                continue
            Ps = [[dyadic(P / np.outer(bal.d, bal.d), 52) for P in seq] for seq in solved[tau][0]]
            reason = check_dwell(modes, Ps, tau)
            if not reason:
                return _Attempt("dwell-time", {"kind": "dwell-time", "tau_D": str(tau), "segments": self.segments,
                                               "P_plus": [matrix_strings(P) for P in Ps[0]],
                                               "P_minus": [matrix_strings(P) for P in Ps[1]]}, tau, "")
            detail = f"rounded dwell-time matrices not exact at tau = {float(tau):.4g}: {reason}"
        return _Attempt("", None, None, detail)

    def _bisect(self, mats: list[list[np.ndarray]], start: float, limit: float) -> tuple[float, float] | None:
        """``(lo, hi)``: the dwell-time LMIs of ``mats`` infeasible at ``lo`` (or ``lo = 0``), feasible at
        ``hi``, ``hi - lo`` within :data:`_REL_TOL` of ``hi``; None if infeasible up to ``limit``."""
        lo, hi = 0.0, start
        while pwl_margin(mats, hi, self.segments, solvers=self.solvers)[1] <= self.eps:
            if hi >= limit:
                return None
            lo, hi = hi, min(4 * hi, limit)
        while hi - lo > _REL_TOL * hi:
            mid = (lo + hi) / 2
            if pwl_margin(mats, mid, self.segments, solvers=self.solvers)[1] > self.eps:
                hi = mid
            else:
                lo = mid
        return lo, hi


def certify_box(model: Model, box: ParameterBox | Sequence[str] | Mapping[str, Any], K_plus: Any, K_minus: Any,
                *, values: Mapping[str, Any] | None = None, pieces: int = 2, segments: int = DEFAULT_SEGMENTS,
                tau_max: float | None = None, search: bool = True, eps: float = DEFAULT_EPS,
                solvers: Sequence[str] = DEFAULT_SOLVERS) -> BoxCertificate:
    """One certificate for every parameter value of a box (gains fixed at the nominal design).

    Parameters
    ----------
    model : Model
    box : ParameterBox, ``["a=150:230", ...]`` or ``{"a": (150, 230)}``
        Must contain the nominal point (the model's values overridden by ``values``).
    K_plus, K_minus : matrices (n x k) or columns
        The nominal gains, exact.
    values : mapping, optional
        Nominal values overriding the model's.
    pieces : int
        Sub-boxes per parameter of degree > 1 (monomial lifting); unused when ``A`` is affine.
    segments : int
        Segments of the piecewise-linear Lyapunov matrices over the dwell time.
    tau_max : float, optional
        Largest dwell time (rescaled time) accepted; default ``1000 / slowest decay`` of the vertices.
    search : bool
        When the box is not certified, bisect on its scale for the largest certified sub-box.
    eps, solvers
        As in :func:`switchobs.certify.certify`.

    Returns
    -------
    BoxCertificate

    Raises
    ------
    ModelError, FreeSymbolError, DimensionError, SolverFailure

    References
    ----------
    Boyd, El Ghaoui, Feron, Balakrishnan (1994), Sec. 5.1 (polytopic LMIs);
    Allerhand & Shaked (2011), IEEE TAC 56(2), Theorem 1 (dwell time by piecewise-linear P).
    """
    if not isinstance(box, ParameterBox):
        box = parse_box(box)
    if pieces < 1 or segments < 1:
        raise ModelError(f"pieces and segments must be positive integers, got {pieces} and {segments}")
    t_start = time.perf_counter()
    terms, nominal, inactive = model_terms(model, box, values)
    n = model.n
    C = fraction_matrix(model.C, what="C", cols=n)
    Kp, Km = (_column_gain(K, n, what) for K, what in ((K_plus, "K_plus"), (K_minus, "K_minus")))
    problem = _BoxProblem(terms, nominal, box, pieces, segments, C, Kp, Km, eps, solvers, tau_max)
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    full = problem.attempt(Fraction(1), smallest_dwell=True)
    timings["box"] = time.perf_counter() - t0
    rho, best = Fraction(1), full
    if full.certificate is None:
        rho, best = Fraction(0), None
        if search:
            t0 = time.perf_counter()
            lo, hi = Fraction(0), Fraction(1)
            for _ in range(SEARCH_STEPS):
                mid = (lo + hi) / 2
                if problem.attempt(mid, smallest_dwell=False).certificate is not None:
                    lo = mid
                else:
                    hi = mid
            if lo > 0:
                best = problem.attempt(lo, smallest_dwell=True)
                rho = lo if best.certificate is not None else Fraction(0)
            timings["search"] = time.perf_counter() - t0
    timings["total"] = time.perf_counter() - t_start
    certified_box = None if best is None or best.certificate is None else box.scaled(nominal, rho)
    data = None
    vertices = 0
    if certified_box is not None and best is not None:
        vertices = len(problem.vertices(rho)[0])
        data = {"parameters": list(box.names), "nominal": {nm: str(v) for nm, v in zip(box.names, nominal)},
                "box": certified_box.to_json(), "requested": box.to_json(), "scale": str(rho), "pieces": pieces,
                "A_terms": [{"monomial": m, "matrix": matrix_strings(M)} for m, M in terms],
                "C": matrix_strings(C), "K_plus": matrix_strings(Kp), "K_minus": matrix_strings(Km),
                "certificate": best.certificate}
    return BoxCertificate(box, certified_box, rho, best.kind if best else "", best.tau_D if best else None,
                          vertices, inactive, data, "" if full.certificate is not None else full.detail, timings)


def _column_gain(K: Any, n: int, what: str) -> Matrix:
    rows = matrix_rows(K, name=what)
    if rows and not isinstance(rows[0], (list, tuple)):
        rows = [[x] for x in rows]
    return fraction_matrix(rows, what=what, rows=n)
