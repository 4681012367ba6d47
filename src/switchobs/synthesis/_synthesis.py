"""LMI synthesis of switched gain pairs ``K_plus``, ``K_minus`` with a decay rate and a noise bound.

Error dynamics in the rescaled time (seed 004; seed 000 eq. (13)), with
measurement noise ``v`` on ``y`` and a unit process disturbance ``w`` on
every state (the unknown ``z3`` of the XBS model is a random walk in
practice)::

    de/dtau = A_plus e + w - K_plus (W v),     A_plus  =  A - K_plus C
    de/dtau = A_minus e + w + K_minus (W v),   A_minus = -A + K_minus C

``W`` (``noise_weight``) is the noise intensity relative to the process
disturbance: the Kalman filter's trade-off.  ``W = 0`` designs for the decay
rate and the disturbance alone (high gains); a large ``W`` buys a small noise
gain with low gains.  The performance output is ``E e``, the estimation
error of the states the user cares about (the XBS ``z2``).

Two formulations, chosen by the kernel of ``C``:

**C of rank n (every state measured): strict, joint.**  Variables ``P``, ``Y_pm = P K_pm``,
``Z``: ``He(P A_pm) + 2 rate P <= 0`` for both modes (a strict common quadratic
Lyapunov function with decay ``rate`` under *arbitrary* switching) and the
H2 bound ``[[He(P A_p), P, -+W Y_p], [P, -I, 0], [-+W Y_p', 0, -I]] <= 0``,
``[[Z, E], [E', P]] >= 0``, minimising ``tr Z`` (the squared H2 bound of both
modes, with one storage function).  All are linear in ``(P, Y_pm, Z)``.

**C with a kernel (one output, or fewer independent outputs than states):
non-strict (Hespanha) with per-mode decay.**  A strict common P never
exists: ``A_plus + A_minus = (K_minus - K_plus) C``, so for a common P with
``Q_pm = -He(P A_pm) >= 0`` and ``v`` in ``ker C``, ``v'(Q_plus + Q_minus) v = 0``,
hence ``Q_pm v = 0``: no decay rate can be imposed on the common P, whatever
the gains.  The same argument forces ``Q_pm = C' S_pm C`` (``S_pm >= 0``), and
for one output ``P K_minus = P K_plus - ((q_plus + q_minus)/2) C'``.  The
choice ``K_minus = K_plus - P^-1 C'`` with ``He(P A_plus) = -C'C`` gives
``He(P A_minus) = -C'C`` and ``A_minus = P^-1 A_plus' P`` (for one output it is
Theorem 1 of seed 004): ``A_minus`` is similar to ``A_plus'``, so it has the
same spectrum and ``X_minus = P X_plus^-1 P`` proves the same decay rate.  The
synthesis therefore designs ``K_plus`` by the LMI in ``(X, Y = X K_plus, Z)``
with ``He(X A_plus) + 2 rate X <= 0`` and the H2 bound of the plus mode, then
sets ``K_minus`` from the exact ``P``: the pair has the non-strict common P
(Hespanha: UES for every positive dwell time) and each mode decays at
``rate``, all checked exactly.

Both formulations, and the polytopic ones of :mod:`._box_synthesis`, are
solved in the coordinates of the modes' Kalman filters
(:func:`riccati_scaling`, a change of variables that leaves the optimum
unchanged), and the decay certificates of the rounded gains come from
:func:`decay_certificate` (the LMI's point, else re-solved for the rounded
gains, else the exact Lyapunov solution).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # imported where an LMI is built (see _lmi)
    import cvxpy as cp

from .._json import JsonRecord, fields_from_json
from .._limits import check_double
from ..exact import (Matrix, add, definiteness, dyadic, float_matrix, fraction_matrix, identity, lyapunov_form,
                     lyapunov_solve, matmul, matrix_strings, observable, rank, scale, sub, to_fraction, transpose)
from ..exact import solve as solve_exact
from ..exceptions import CertificateError, DimensionError, ModelError, NotObservableError, SolverFailure
from ..lmi import DEFAULT_SOLVERS, SolveInfo, primal_margin, solve
from ..model import Model, ParameterBox, user_matrix


__all__ = ["GainSynthesis", "synthesize_gains", "synthesize", "noise_gain", "decay_holds", "decay_certificate",
           "riccati_scaling", "STRICT_IMPOSSIBLE", "RATE_MARGIN", "GAIN_BITS", "FrontPoint", "noise_decay_front"]

#: The LMI is solved at ``rate * (1 + RATE_MARGIN)`` so that the rounded matrices keep ``rate`` exactly.
RATE_MARGIN = 1e-2

STRICT_IMPOSSIBLE = ("a strict common Lyapunov function never exists when C has a kernel (here: fewer independent "
                     "outputs than states): A_plus + A_minus = (K_minus - K_plus) C, so for any common P with "
                     "-(A_pm' P + P A_pm) >= 0 both vanish on ker C, whatever the gains; use the non-strict "
                     "(Hespanha) formulation")


@dataclass(frozen=True)
class GainSynthesis:
    """Outcome of :func:`synthesize_gains`.

    Attributes
    ----------
    formulation : str
        ``"strict"`` (common P with decay; needs ``C`` of rank n), ``"hespanha"``
        (non-strict common P and per-mode decay certificates), or over a parameter box
        (:func:`switchobs.synthesis.synthesize_box`) ``"polytopic-strict"`` (one P for both modes and every
        vertex) and ``"polytopic"`` (one decay certificate per mode, common to every vertex).
    decay_rate : Fraction
        Requested decay rate in the rescaled time (``He(X A_p) + 2 rate X < 0`` exactly).
    noise_weight : float
    estimate : tuple of int
        Rows of ``E`` (0-based state indices) whose estimation error is weighted.
    feasible : bool
        The LMI was solved and the rounded gains passed every exact check.
    K_plus, K_minus : Matrix or None
        Exact gains (``n x k``).
    P : Matrix or None
        Common Lyapunov matrix: strict with decay, or (one output) ``He(P A_pm) = -C'C`` exactly;
        None for ``"polytopic"``.
    X_plus, X_minus : Matrix or None
        Per-mode decay certificates (for ``"strict"`` both are ``P``); over a box, valid at every vertex.
    noise_bound : float
        The LMI's H2 bound (``sqrt tr Z``) of the plus mode (both modes for ``"strict"``), W and w included.
    noise_gain : dict
        H2 norm from the measurement noise ``v`` to ``E e`` of each mode (float, from the exact gains;
        at the nominal point for a box).
    solver : SolveInfo or None
    detail : str
        Why the synthesis failed, when it did.
    solve_s, exact_s : float
    box : ParameterBox or None
        The parameter box of a polytopic synthesis.
    vertices : int
        Vertex matrices per mode at which the polytopic LMIs hold exactly.
    """

    formulation: str
    decay_rate: Fraction
    noise_weight: float
    estimate: tuple[int, ...]
    feasible: bool
    K_plus: Matrix | None
    K_minus: Matrix | None
    P: Matrix | None
    X_plus: Matrix | None
    X_minus: Matrix | None
    noise_bound: float
    noise_gain: dict[str, float]
    solver: SolveInfo | None
    detail: str = ""
    solve_s: float = 0.0
    exact_s: float = 0.0
    box: ParameterBox | None = None
    vertices: int = 0

    def gains(self) -> tuple[str, str]:
        """``K_plus`` and ``K_minus`` of a single output as the command line's ``"k1,k2,..."`` strings."""
        if self.K_plus is None or self.K_minus is None:
            raise CertificateError(f"no gains: {self.detail}")
        return (",".join(str(r[0]) for r in self.K_plus), ",".join(str(r[0]) for r in self.K_minus))

    def to_json(self) -> dict[str, Any]:
        def mat(M: Matrix | None) -> Any:
            return None if M is None else matrix_strings(M)

        return {"formulation": self.formulation, "decay_rate": str(self.decay_rate),
                "noise_weight": self.noise_weight, "estimate": list(self.estimate), "feasible": self.feasible,
                "K_plus": mat(self.K_plus), "K_minus": mat(self.K_minus), "P": mat(self.P),
                "X_plus": mat(self.X_plus), "X_minus": mat(self.X_minus), "noise_bound": self.noise_bound,
                "noise_gain": dict(self.noise_gain),
                "solver": None if self.solver is None else f"{self.solver.solver} ({self.solver.status})",
                "detail": self.detail, "solve_s": self.solve_s, "exact_s": self.exact_s,
                "box": None if self.box is None else self.box.to_json(), "vertices": self.vertices,
                "solve_info": None if self.solver is None else self.solver.to_json()}

    @classmethod
    def from_json(cls, data: Any) -> GainSynthesis:
        """The synthesis of :meth:`to_json`: gains, ``P`` and ``X`` exact, the solver record from ``solve_info``.

        Raises
        ------
        CertificateError
            A missing key or a malformed matrix or number; the message names it.
        """
        if not isinstance(data, Mapping) or "solve_info" not in data:
            raise CertificateError(f"a gain synthesis JSON needs 'solve_info', got {data!r:.80}")
        return fields_from_json(cls, data, error=CertificateError, what="gain synthesis",
                                solver=SolveInfo.from_json(data["solve_info"]))

    def __str__(self) -> str:
        head = f"LMI synthesis ({self.formulation}), decay rate {self.decay_rate} in tau, noise weight {self.noise_weight:g}"
        if self.box is not None:
            head += f", box {self.box}"
        if not self.feasible:
            return f"{head}: infeasible ({self.detail})"

        def col(M: Matrix) -> str:
            return "[" + "; ".join(", ".join(_short(x) for x in row) for row in M) + "]"

        what = {"strict": "strict common P with decay rate (UGES under arbitrary switching)",
                "hespanha": "per-mode decay certificates and the non-strict common P (Hespanha: UES for every "
                            "positive dwell time)",
                "polytopic-strict": f"one strict P with decay rate at all {self.vertices} vertices per mode (UGES "
                                    "under arbitrary switching, for every parameter value of the box)",
                "polytopic": f"one decay certificate per mode, common to all {self.vertices} vertices per mode "
                             "(each mode decays for every parameter value of the box, even time-varying; "
                             "switching: the box dwell-time certificate)"}[self.formulation]
        return "\n".join([
            head + ": feasible, checked exactly",
            f"  K_plus  = {col(self.K_plus)}",
            f"  K_minus = {col(self.K_minus)}",
            f"  certified: {what}",
            f"  noise gain (H2, v -> estimated states {list(self.estimate)}): "
            + ", ".join(f"{k} {v:.4g}" for k, v in self.noise_gain.items())
            + f"; LMI bound of the weighted H2 gain ([w; W v] -> E e) {self.noise_bound:.4g}"])


def _short(x: Fraction) -> str:
    # a rounded gain is a dyadic rational: as a fraction only when that is short (3/8), else in decimal
    return str(x) if x.denominator <= 1000 and abs(x.numerator) < 10 ** 6 else f"{float(x):.8g}"


# ----------------------------------------------------------------------------- exact helpers
def decay_holds(A: Matrix, X: Matrix, rate: Fraction) -> str:
    """Empty string if ``X > 0`` and ``A' X + X A + 2 rate X < 0`` exactly; else the reason."""
    r = definiteness(X, strict=True)
    if not r.holds:
        return f"X > 0 fails: {r.reason}"
    r = definiteness(scale(-1, add(lyapunov_form(A, X), scale(2 * rate, X))), strict=True)
    return "" if r.holds else f"A' X + X A + 2 rate X < 0 fails: {r.reason}"


# ----------------------------------------------------------------------------- preconditioning
def riccati_scaling(A: np.ndarray, C: np.ndarray, signs: Sequence[int]) -> np.ndarray:
    """The change of coordinates ``z~ = S z`` in which the modes' Kalman filters have ``X~ = I``.

    The LMIs of an observer are badly conditioned in the model's coordinates, so the interior point stops
    early or reports infeasibility for problems that pole placement shows feasible: the states' scales
    differ by orders of magnitude (abs-xbs4 at decay rate 10: the eigenvalues of ``X`` span ``4e-4 .. 9e5``,
    the gain entries ``3e4 .. 3e7``), and the observability Gramian of a chain of integrators is nearly singular whatever
    the diagonal scaling (``normal-form-16``: condition number ``6e10``).  The Kalman filter of each mode
    ``sign * A - K C`` that decays at rate 1 (``A`` is given in the time scaled by the decay rate) -- the
    Riccati equation of ``sign * A + I`` with unit intensities, covariance ``Sigma_p`` -- is a feasible
    point of the decay LMI with ``X = Sigma_p^-1``; with ``X0 = sum_p Sigma_p^-1 = S' S`` (Cholesky),
    ``X~ = S^-T X S^-1`` is the identity there, a point deep inside the cone.  Float entries of ``S`` are
    exact dyadic rationals, so ``X = S' X~ S`` maps a rounded ``X~`` back exactly.

    Parameters
    ----------
    A : n x n float array
        The nominal ``A``, divided by the decay rate.
    C : k x n float array
    signs : ``+1`` for ``A - K_plus C``, ``-1`` for ``-A + K_minus C``

    Returns
    -------
    numpy.ndarray
        ``S``, upper triangular; the Jacobi part ``diag(X0)^(1/2)`` alone if ``X0`` is numerically not
        definite, the identity if a mode is not detectable (the LMIs will then say so).
    """
    import scipy.linalg  # about 0.4 s to import; certify and verify never get here

    n = len(A)
    try:
        X0 = sum(np.linalg.inv(scipy.linalg.solve_continuous_are((sign * A + np.eye(n)).T, C.T, np.eye(n),
                                                                  np.eye(len(C))))
                 for sign in signs)
    except (np.linalg.LinAlgError, ValueError):
        return np.eye(n)
    X0 = (X0 + X0.T) / 2
    if not np.all(np.isfinite(X0)):
        return np.eye(n)
    try:
        return np.linalg.cholesky(X0).T
    except np.linalg.LinAlgError:
        diag = np.abs(np.diag(X0))
        return np.diag(np.sqrt(diag)) if np.all(diag > 0) else np.eye(n)


def _unscale(M: Matrix, S: np.ndarray) -> Matrix:
    """``S' M S`` exactly: a matrix of the coordinates ``z~ = S z`` back in the model's."""
    S_ex = [[Fraction(float(x)) for x in row] for row in S]
    return matmul(matmul(transpose(S_ex), M), S_ex)


def decay_certificate(mats: Sequence[Matrix], rate: Fraction, S: np.ndarray, start: np.ndarray | None,
                      solvers: Sequence[str] = DEFAULT_SOLVERS) -> tuple[Matrix | None, str]:
    """A rational ``X > 0`` with ``A' X + X A + 2 rate X < 0`` exactly for every ``A`` of ``mats``.

    ``mats`` are exact matrices of the rounded gains: one mode, the vertices of one mode, or both modes
    for a common ``P``.  Candidates, each rounded in the coordinates ``z~ = S z`` of
    :func:`riccati_scaling` (where it is well conditioned), mapped back exactly and checked exactly; the
    first that holds is returned:

    1. ``start``, the LMI's point ``X~``;
    2. re-solved for the rounded gains: the Lyapunov equation ``He(X~ (A~ + rate I)) = -I`` (one matrix),
       else the margin LMI of :func:`switchobs.lmi.primal_margin` on the shifted matrices;
    3. one matrix: the exact solution of ``He(X (A + rate I)) = -S' S``, which holds whenever
       ``A + rate I`` is Hurwitz.

    Returns
    -------
    X : Matrix or None
    reason : str
        Why the last candidate failed (empty with ``X``).
    """
    import scipy.linalg

    n = len(mats[0])
    scaled = [S @ np.linalg.solve(S.T, (float_matrix(A) + float(rate) * np.eye(n)).T).T for A in mats]
    reason = "no candidate"

    def check(X: Matrix) -> bool:
        nonlocal reason
        reason = next((why for A in mats if (why := decay_holds(A, X, rate))), "")
        return not reason

    def rounded(X_scaled: np.ndarray) -> Matrix:
        return _unscale(dyadic((X_scaled + X_scaled.T) / 2), S)

    if start is not None and check(rounded(start)):
        return rounded(start), ""
    try:
        if len(mats) == 1:
            with warnings.catch_warnings():
                # A + rate I close to singular (the rate at the abscissa): the exact check rejects the answer
                warnings.simplefilter("ignore", RuntimeWarning)
                X_num = scipy.linalg.solve_continuous_lyapunov(scaled[0].T, -np.eye(n))
        else:
            norm = max(np.linalg.norm(M, 2) for M in scaled) or 1.0
            X_num, _, _ = primal_margin([M / norm for M in scaled], [np.eye(n)] * len(scaled), solvers=solvers,
                                        what="decay certificate for the rounded gains")
        if np.all(np.isfinite(X_num)) and check(X := rounded(X_num)):
            return X, ""
    except (np.linalg.LinAlgError, ValueError, SolverFailure):
        pass
    if len(mats) == 1:
        try:
            X = lyapunov_solve(add(mats[0], scale(rate, identity(n))), _unscale(identity(n), S))
        except DimensionError:
            return None, "A + rate I is singular"
        if check(X):
            return X, ""
    return None, reason


def noise_gain(A_mode: np.ndarray, K: np.ndarray, E: np.ndarray) -> float:
    """H2 norm of ``v -> E e`` for ``de/dtau = A_mode e + K v`` (``inf`` if ``A_mode`` is not Hurwitz)."""
    if np.max(np.linalg.eigvals(A_mode).real) >= 0:
        return float("inf")
    import scipy.linalg

    Wc = scipy.linalg.solve_continuous_lyapunov(A_mode, -K @ K.T)
    return float(np.sqrt(max(np.trace(E @ Wc @ E.T), 0.0)))


# ----------------------------------------------------------------------------- the LMIs
def _he(M: cp.Expression) -> cp.Expression:
    return M + M.T


#: Significant bits of each rounded gain entry.  Per entry, because the entries span orders of magnitude
#: (abs-xbs4 at rate 40, W = 0: 3e7 .. 2e11); short, because the rate margin absorbs the rounding and short
#: rationals keep the exact checks and the independent certify path (its face projection) robust: at 40
#: bits relative to the largest entry one random pair of the tests lost its Hespanha certificate.
GAIN_BITS = 24

#: Weight on every state added to ``E'E`` in the LMI: keeps ``X`` definite (a decay certificate must be).
STATE_REGULARISATION = 1e-3


@dataclass(frozen=True)
class LmiPoint:
    """The synthesis LMI's solution; ``X`` kept in the coordinates ``z~ = S z`` of :func:`riccati_scaling`.

    Attributes
    ----------
    S : tuple of numpy.ndarray
        The change of coordinates of each mode's ``X`` (the same for a shared ``X``; float entries taken
        exactly).
    X_scaled : tuple of numpy.ndarray
        ``X~_p = S_p^-T X_p S_p^-1`` per mode (up to a positive factor: the certificates are homogeneous).
    K : tuple of numpy.ndarray
        ``K_p`` in the model's coordinates and the time scaled by the decay rate.
    trace_X, trace_Z : tuple of float
        ``tr X_p`` (the model's coordinates) and ``tr Z_p`` of the H2 bound.
    """

    S: tuple[np.ndarray, ...]
    X_scaled: tuple[np.ndarray, ...]
    K: tuple[np.ndarray, ...]
    trace_X: tuple[float, ...]
    trace_Z: tuple[float, ...]

    def gain(self, i: int, rate: Fraction) -> Matrix:
        """The ``i``-th gain in ``tau``, each entry rounded to :data:`GAIN_BITS` significant bits."""
        return [[dyadic(np.array([[x]]), GAIN_BITS)[0][0] for x in row] for row in self.K[i] * float(rate)]


@dataclass(frozen=True)
class _Scaled:
    """One ``X`` variable's coordinates: ``S``, ``A~ = S A S^-1``, ``C~ = C S^-1``, the weight and ``S S'``."""

    S: np.ndarray
    mats: list[np.ndarray]
    C: np.ndarray
    weight: np.ndarray
    c: float
    gram: np.ndarray

    @classmethod
    def of(cls, S: np.ndarray, As: Sequence[np.ndarray], C: np.ndarray, weight: np.ndarray) -> "_Scaled":
        def tilde(M: np.ndarray) -> np.ndarray:   # M S^-1
            return np.linalg.solve(S.T, M.T).T

        w = np.linalg.solve(S.T, tilde(weight))
        c = float(np.exp2(np.round(np.log2(np.max(np.abs(w))))))
        return cls(S, [S @ tilde(A) for A in As], tilde(C), (w + w.T) / (2 * c), c, S @ S.T)


def _lmi(As: Sequence[np.ndarray], C: np.ndarray, E: np.ndarray, W: float, signs: Sequence[int], shared: bool,
         solvers: Sequence[str], nominal: np.ndarray) -> tuple[LmiPoint | None, SolveInfo]:
    """The LMIs in the time scaled by the decay rate (``As`` divided by it, ``W`` multiplied: the decay
    rate becomes 1), solved in the coordinates of :func:`riccati_scaling` at ``nominal``; ``None`` if the
    solver proves them infeasible.

    One gain ``Y_p = X_p K_p`` per mode sign in ``signs`` (``+1``: ``A - K_plus C``, ``-1``:
    ``-A + K_minus C``), every inequality posed at every matrix of ``As`` (the nominal ``A``, or the
    vertices of a parameter box: the polytopic LMIs of Boyd et al. 1994, Sec. 5.1); ``shared``: one
    ``X`` for all modes (the strict common P), else one per mode.  H2 by the observability Gramian:
    ``||G_p||_2^2 <= tr X + W^2 tr(K_p' X K_p)`` when ``He(X A_p) + E'E <= 0``; with
    ``[[Z_p, Y_p'], [Y_p, X]] >= 0`` all is linear.

    The scaling is a change of variables, not of the problem: ``X = c S' X~ S``, ``Y = c S' Y~``,
    ``Z = c Z~``, ``A~ = S A S^-1``, ``C~ = C S^-1``, the weight ``S^-T (E'E + rI) S^-1 / c`` and the
    objective ``tr X = c tr(X~ S S')``; ``c`` (a power of two, the largest entry of the scaled weight) is
    the homogeneity of the LMIs in ``(X, Y, Z)`` and brings the weight to unit size.  A shared ``X`` gets
    the ``S`` of all modes' filters; separate ones each their own (the modes' LMIs are then coupled only
    through the objective, a sum, so each mode's part may be scaled on its own)."""
    import cvxpy as cp

    n, k = As[0].shape[0], C.shape[0]
    lam = 1 + RATE_MARGIN
    weight = E.T @ E + STATE_REGULARISATION * np.eye(n)
    groups = [tuple(signs)] if shared else [(sign,) for sign in signs]
    coords = [_Scaled.of(riccati_scaling(nominal, C, g), As, C, weight) for g in groups]

    def fn() -> tuple[cp.Problem, dict]:
        Xs = [cp.Variable((n, n), symmetric=True) for _ in coords]
        Ys = [cp.Variable((n, k)) for _ in signs]
        Zs = [cp.Variable((k, k), symmetric=True) for _ in signs]
        cons = [X >> 0 for X in Xs]
        objective = 0
        for i, (sign, Y, Z) in enumerate(zip(signs, Ys, Zs)):
            j = 0 if shared else i
            X, sc = Xs[j], coords[j]
            for A in sc.mats:
                HeA = sign * (_he(X @ A) - _he(Y @ sc.C))
                cons += [-(HeA + 2 * lam * X) >> 0, -(HeA + sc.weight) >> 0]
            cons.append(cp.bmat([[Z, Y.T], [Y, X]]) >> 0)
            # normalised so that the objective stays of unit size whatever W and S
            objective += ((cp.sum(cp.multiply(sc.gram, X)) if i == j else 0) + W ** 2 * cp.trace(Z)) \
                / (float(np.max(np.abs(sc.gram))) + W ** 2)
        return cp.Problem(cp.Minimize(objective), cons), {"X": Xs, "Y": Ys, "Z": Zs}

    v, info = solve(fn, solvers=solvers, what="gain synthesis LMI", infeasible_ok=True)
    if info.status == cp.INFEASIBLE or any(X.value is None for X in v["X"]):
        return None, info
    per_mode = [coords[0 if shared else i] for i in range(len(signs))]
    X_of = [np.asarray(v["X"][0 if shared else i].value) for i in range(len(signs))]
    # K = X^-1 Y = S^-1 X~^-1 Y~
    Ks = tuple(np.linalg.solve(sc.S, np.linalg.solve(X, np.asarray(Y.value)))
               for sc, X, Y in zip(per_mode, X_of, v["Y"]))
    return LmiPoint(tuple(sc.S for sc in per_mode), tuple(X_of), Ks,
                    tuple(sc.c * float(np.sum(sc.gram * X)) for sc, X in zip(per_mode, X_of)),
                    tuple(sc.c * float(np.trace(Z.value)) for sc, Z in zip(per_mode, v["Z"]))), info


def check_synthesis_inputs(decay_rate: Any, noise_weight: float, estimate: Sequence[int] | None,
                           n: int) -> tuple[Fraction, tuple[int, ...]]:
    """The validated decay rate (exact, > 0) and weighted state indices; raises on a bad value."""
    rate = check_double(to_fraction(decay_rate, what="decay_rate"), what="decay_rate", error=ModelError,
                        text=str(decay_rate))
    if rate <= 0:
        raise ModelError(f"decay_rate must be positive, got {rate}")
    if not (noise_weight >= 0 and np.isfinite(noise_weight)):
        raise ModelError(f"noise_weight must be a finite number >= 0, got {noise_weight!r}")
    rows = tuple(range(n)) if estimate is None else tuple(int(i) for i in estimate)
    if not rows or any(i < 0 or i >= n for i in rows):
        raise DimensionError(f"estimate must list state indices in 0..{n - 1}, got {list(rows)}")
    return rate, rows


def synthesize_gains(A: Any, C: Any, *, decay_rate: Any, noise_weight: float = 0.0,
                     estimate: Sequence[int] | None = None, strict: bool | None = None,
                     solvers: Sequence[str] = DEFAULT_SOLVERS) -> GainSynthesis:
    """Synthesise ``K_plus``, ``K_minus`` by LMIs (``Y = P K``), round them and re-check exactly.

    Parameters
    ----------
    A : n x n matrix
        The model's ``A`` (numeric, exact rationals or floats taken exactly).
    C : k x n matrix
        Output rows (one or more).
    decay_rate : number
        Decay rate in the rescaled time ``tau`` (``He(X A_p) + 2 rate X < 0``), > 0.
    noise_weight : float
        ``W >= 0``: measurement-noise intensity relative to the unit process disturbance.
    estimate : sequence of int, optional
        0-based indices of the states whose estimation error is weighted (default all).
    strict : bool, optional
        Force the formulation; default strict iff ``C`` has rank ``n`` (no kernel).  Strict with a
        kernel is reported infeasible with the reason (:data:`STRICT_IMPOSSIBLE`).
    solvers : cvxpy solvers in order of preference

    Returns
    -------
    GainSynthesis

    Raises
    ------
    DimensionError, ModelError, SolverFailure

    References
    ----------
    Boyd, El Ghaoui, Feron, Balakrishnan (1994), Sec. 5.2 and 7.2 (observer LMIs with Y = P K);
    seed 004, Theorem 1 and the Hespanha argument.
    """
    A_ex = user_matrix(A, what="A")
    n = len(A_ex)
    if len(A_ex[0]) != n:
        raise DimensionError(f"A must be square, got {n}x{len(A_ex[0])}")
    C_ex = user_matrix(C, what="C", part="C", cols=n)
    rate, rows = check_synthesis_inputs(decay_rate, noise_weight, estimate, n)
    # no gain makes an unobservable mode decay: bad input, as design and certify say, not an infeasible LMI
    obs, dim = observable(A_ex, C_ex)
    if not obs:
        raise NotObservableError(f"the pair (A, C) is not observable: the observable subspace has dimension {dim} "
                                 f"< {n}; change C or A so that every state shows up in the output")
    full_rank = rank(C_ex) == n
    use_strict = full_rank if strict is None else strict
    formulation = "strict" if use_strict else "hespanha"

    def fail(detail: str, info: SolveInfo | None = None, solve_s: float = 0.0) -> GainSynthesis:
        return GainSynthesis(formulation, rate, noise_weight, rows, False, None, None, None, None, None,
                             float("inf"), {}, info, detail, solve_s)

    if use_strict and not full_rank:
        return fail(STRICT_IMPOSSIBLE)
    Af, Cf = float_matrix(A_ex), float_matrix(C_ex)
    E = np.eye(n)[list(rows)]
    sigma = float(rate)
    t0 = time.perf_counter()
    point, info = _lmi([Af / sigma], Cf, E, float(noise_weight) * sigma, (1, -1) if use_strict else (1,), True,
                       solvers, nominal=Af / sigma)
    solve_s = time.perf_counter() - t0
    if point is None:
        return fail(f"the LMI is infeasible ({'; '.join(info.attempts)})", info, solve_s)
    t0 = time.perf_counter()
    K_plus = point.gain(0, rate)
    A_plus = sub(A_ex, matmul(K_plus, C_ex))
    if use_strict:
        K_minus = point.gain(1, rate)
        A_minus = add(scale(-1, A_ex), matmul(K_minus, C_ex))
        P, why = decay_certificate([A_plus, A_minus], rate, point.S[0], point.X_scaled[0], solvers)
        reason = f"no exact common decay certificate ({why})" if P is None else ""
        X_plus = X_minus = P
    else:
        try:
            P = lyapunov_solve(A_plus, matmul(transpose(C_ex), C_ex))
            K_minus = sub(K_plus, solve_exact(P, transpose(C_ex)))
        except DimensionError:
            return fail("A_plus of the rounded gain is singular for the Lyapunov equation", info, solve_s)
        A_minus = add(scale(-1, A_ex), matmul(K_minus, C_ex))
        X_plus, why = decay_certificate([A_plus], rate, point.S[0], point.X_scaled[0], solvers)
        # A_minus = P^-1 A_plus' P, so X_minus = P X_plus^-1 P proves the same decay rate
        X_minus = None if X_plus is None else matmul(matmul(P, solve_exact(X_plus, identity(n))), P)
        reason = (f"no exact decay certificate for A_plus ({why})" if X_minus is None else
                  decay_holds(A_minus, X_minus, rate) or hespanha_pair_holds(A_plus, A_minus, P, C_ex))
    exact_s = time.perf_counter() - t0
    if reason:
        return fail(f"the rounded gains fail the exact check: {reason}", info, solve_s)
    fl = [float_matrix(M) for M in (A_plus, A_minus, K_plus, K_minus)]
    gains = {"A_plus": noise_gain(fl[0], fl[2], E), "A_minus": noise_gain(fl[1], fl[3], E)}
    # H2^2 in the scaled time is sigma times H2^2 in tau
    scaled = point.trace_X[0] + (noise_weight * sigma) ** 2 * max(point.trace_Z)
    bound = float(np.sqrt(max(scaled, 0.0) / sigma))
    return GainSynthesis(formulation, rate, noise_weight, rows, True, K_plus, K_minus, P, X_plus, X_minus, bound,
                         gains, info, "", solve_s, exact_s)


def hespanha_pair_holds(A_plus: Matrix, A_minus: Matrix, P: Matrix, C: Matrix) -> str:
    """Empty string if ``P > 0`` and ``He(P A_pm) = -C'C`` exactly (the non-strict common P); else the reason."""
    r = definiteness(P, strict=True)
    if not r.holds:
        return f"P > 0 fails: {r.reason}"
    CtC = matmul(transpose(C), C)
    for name, A in (("A_plus", A_plus), ("A_minus", A_minus)):
        if add(lyapunov_form(A, P), CtC) != [[Fraction(0)] * len(P) for _ in P]:
            return f"{name}' P + P {name} = -C'C fails"
    return ""


def synthesize(model: Model, *, decay_rate: Any, noise_weight: float = 0.0, estimate: Sequence[str] | None = None,
               values: Mapping[str, Any] | None = None, strict: bool | None = None,
               solvers: Sequence[str] = DEFAULT_SOLVERS) -> GainSynthesis:
    """:func:`synthesize_gains` for a model at its numeric values; ``estimate`` names states (``["z2"]``)."""
    numeric = model.with_values(dict(values or {})).numeric()
    rows = state_rows(model, estimate)
    A = fraction_matrix(numeric.A, what="A")
    C = fraction_matrix(numeric.C, what="C")
    return synthesize_gains(A, C, decay_rate=decay_rate, noise_weight=noise_weight, estimate=rows, strict=strict,
                            solvers=solvers)


def state_rows(model: Model, estimate: Sequence[str] | None) -> list[int] | None:
    """0-based indices of the named states (None: all); raises on a name that is not a state."""
    names = list(model.states)
    unknown = [s for s in (estimate or ()) if s not in names]
    if unknown:
        raise ModelError(f"estimate names {unknown}, which are not states of {model.name!r} (states: {names})")
    return None if not estimate else [names.index(s) for s in estimate]


@dataclass(frozen=True)
class FrontPoint(JsonRecord, error=CertificateError):
    """One design on the noise-gain / decay-rate plane (:func:`noise_decay_front`).

    Attributes
    ----------
    design : str
        ``"beta"`` (Theorem 1 with every pole at ``-beta``) or ``"lmi W=<weight>"``.
    decay_rate : float
        Spectral abscissa of ``A_plus`` (both modes: equal spectra) with the sign flipped, in ``tau``.
    noise_gain : dict
        H2 gain from the measurement noise to the weighted error, per mode.
    K_plus, K_minus : tuple of str
        The exact gains (one output).
    """

    design: str
    decay_rate: float
    noise_gain: dict[str, float]
    K_plus: tuple[str, ...]
    K_minus: tuple[str, ...]

    @property
    def worst_noise_gain(self) -> float:
        return max(self.noise_gain.values())

    def to_json(self) -> dict[str, Any]:
        return {"design": self.design, "decay_rate": self.decay_rate, "noise_gain": dict(self.noise_gain),
                "K_plus": list(self.K_plus), "K_minus": list(self.K_minus)}

    def __str__(self) -> str:
        return (f"{self.design}: decay rate {self.decay_rate:.4g}, noise gain "
                + ", ".join(f"{k} {v:.4g}" for k, v in self.noise_gain.items()))


def noise_decay_front(model: Model, rates: Sequence[Any], *, noise_weights: Sequence[float] = (0.0, 1e-2),
                      estimate: Sequence[str] = ("z2",), values: Mapping[str, Any] | None = None,
                      solvers: Sequence[str] = DEFAULT_SOLVERS) -> tuple[FrontPoint, ...]:
    """Theorem 1 designs with all poles at ``-rate`` beside the LMI designs at each rate and noise weight.

    The comparison of the issue's Pareto front: noise gain (H2, measurement noise on ``y`` to the error
    of ``estimate``) against the decay rate achieved, for a single-output model.
    """
    from ..design import design_gains

    numeric = model.with_values(dict(values or {})).numeric()
    names = list(model.states)
    E = np.eye(model.n)[[names.index(s) for s in estimate]]
    A = np.array(numeric.A.tolist(), dtype=float)
    C = np.array(numeric.C.tolist(), dtype=float)
    points = []

    def point(design: str, Kp: np.ndarray, Km: np.ndarray, texts: tuple[tuple[str, ...], tuple[str, ...]]) -> None:
        Ap, Am = A - Kp @ C, -A + Km @ C
        rate = -max(float(np.max(np.linalg.eigvals(M).real)) for M in (Ap, Am))
        points.append(FrontPoint(design, rate, {"A_plus": noise_gain(Ap, Kp, E), "A_minus": noise_gain(Am, Km, E)},
                                 *texts))

    for r in rates:
        beta = design_gains(numeric, ",".join([f"-{r}"] * model.n))
        Kp, Km = (np.array(K.tolist(), dtype=float) for K in (beta.K_plus, beta.K_minus))
        point("beta", Kp, Km, (tuple(str(x) for x in beta.K_plus), tuple(str(x) for x in beta.K_minus)))
        for W in noise_weights:
            res = synthesize(model, decay_rate=r, noise_weight=W, estimate=estimate, values=values, solvers=solvers)
            if res.feasible:
                point(f"lmi W={W:g}", float_matrix(res.K_plus), float_matrix(res.K_minus),
                      tuple(tuple(",".join(str(x) for x in row) for row in M) for M in (res.K_plus, res.K_minus)))
    return tuple(points)
