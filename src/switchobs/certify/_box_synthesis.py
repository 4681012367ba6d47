"""Joint synthesis of ``K_plus``, ``K_minus`` over a parameter box: polytopic LMIs, exact vertex checks.

The uncertain parameters ``theta`` enter ``A`` polynomially (:func:`model_terms`);
``{A(theta)}`` lies in the convex hull of the vertex matrices ``A_v`` (the box's
vertices when ``A`` is affine, monomial lifting otherwise,
:mod:`switchobs.certify._box_check`).  With ``Y_p = X_p K_p`` the conditions
(in the rescaled time, see :mod:`switchobs.certify._synthesis`)

    He(X_p A_p(v)) + 2 rate X_p <= 0,     He(X_p A_p(v)) + E'E <= 0,
    [[Z_p, Y_p'], [Y_p, X_p]] >= 0,       A_plus(v) = A_v - K_plus C,  A_minus(v) = -A_v + K_minus C,

are linear in ``(X_p, Y_p, Z_p)`` and affine in ``A_v``, so holding at every
vertex they hold for every ``theta`` of the box, also when ``theta`` varies in
time (Boyd et al. 1994, Sec. 5.1, quadratic stability of a polytope).

One ``X`` for both modes (``polytopic-strict``) needs ``C`` of rank n: with a
kernel, ``A_plus(v) + A_minus(v) = (K_minus - K_plus) C`` at every vertex and
the argument of :data:`STRICT_IMPOSSIBLE` applies.  So for one output each mode
gets its own ``X_p``, common to every vertex (``polytopic``); the Hespanha
construction of the nominal synthesis (``K_minus = K_plus - P^-1 C'``) is not
available because its ``P`` changes with ``theta`` (see :mod:`._box`).  Switching
between the modes is then certified by :func:`certify_box` (dwell time with
piecewise-linear Lyapunov matrices on the same box).
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..exceptions import ModelError
from ..model import Model
from ._box import ParameterBox, model_terms, parse_box
from ._box_check import evaluate_terms, vertex_matrices, vertex_values
from ._exact import fraction_matrix, rank
from ._lmi import DEFAULT_SOLVERS
from ._rounding import dyadic
from ._synthesis import (STRICT_IMPOSSIBLE, GainSynthesis, _floats, _lmi, check_synthesis_inputs, decay_holds,
                         noise_gain, state_rows)

__all__ = ["synthesize_box"]


def synthesize_box(model: Model, box: ParameterBox | Sequence[str] | Mapping[str, Any], *, decay_rate: Any,
                   noise_weight: float = 0.0, estimate: Sequence[str] | None = None,
                   values: Mapping[str, Any] | None = None, pieces: int = 2, strict: bool | None = None,
                   solvers: Sequence[str] = DEFAULT_SOLVERS) -> GainSynthesis:
    """``K_plus``, ``K_minus`` and Lyapunov matrices valid at every vertex of a parameter box, checked exactly.

    Parameters
    ----------
    model : Model
    box : ParameterBox, ``["a=150:230", ...]`` or ``{"a": (150, 230)}``
        Must contain the nominal point (the model's values overridden by ``values``).
    decay_rate : number
        Decay rate in the rescaled time, imposed on each mode at every parameter value of the box.
    noise_weight, estimate
        As in :func:`switchobs.certify.synthesize`; the H2 bound holds at every vertex, the reported
        ``noise_gain`` is the nominal point's.
    values : mapping, optional
        Nominal values overriding the model's.
    pieces : int
        Sub-boxes per parameter of degree > 1 (monomial lifting); unused when ``A`` is affine.
    strict : bool, optional
        One ``X`` for both modes; default iff ``C`` has rank n (otherwise impossible, reported infeasible).
    solvers : cvxpy solvers in order of preference

    Returns
    -------
    GainSynthesis
        ``formulation`` ``"polytopic"`` or ``"polytopic-strict"``, ``box`` and ``vertices`` set; feasible
        only if ``He(X_p A_p(v)) + 2 rate X_p < 0`` and ``X_p > 0`` hold exactly at every vertex.

    Raises
    ------
    ModelError, FreeSymbolError, DimensionError, SolverFailure

    References
    ----------
    Boyd, El Ghaoui, Feron, Balakrishnan (1994), Sec. 5.1 (polytopic LMIs) and 7.2 (Y = X K).
    """
    if not isinstance(box, ParameterBox):
        box = parse_box(box)
    if pieces < 1:
        raise ModelError(f"pieces must be a positive integer, got {pieces}")
    n = model.n
    rate, rows = check_synthesis_inputs(decay_rate, noise_weight, state_rows(model, estimate), n)
    terms, nominal, _ = model_terms(model, box, values)
    C = fraction_matrix(model.C, what="C", cols=n)
    monomials = [m for m, _ in terms]
    vertex_A = [evaluate_terms(terms, v) for v in vertex_values(monomials, box.intervals, pieces)]
    nominal_A = evaluate_terms(terms, [math.prod(x ** e for x, e in zip(nominal, m)) for m in monomials])
    full_rank = rank(C) == n
    use_strict = full_rank if strict is None else strict
    formulation = "polytopic-strict" if use_strict else "polytopic"

    def fail(detail: str, info: Any = None, solve_s: float = 0.0) -> GainSynthesis:
        return GainSynthesis(formulation, rate, noise_weight, rows, False, None, None, None, None, None,
                             float("inf"), {}, info, detail, solve_s, box=box, vertices=len(vertex_A))

    if use_strict and not full_rank:
        return fail(STRICT_IMPOSSIBLE)
    # imported here, not with the package: together about 1.5 s that certify and verify never need
    import cvxpy as cp
    import scipy.linalg

    sigma = float(rate)
    E = np.eye(n)[list(rows)]
    t0 = time.perf_counter()
    As, Cf, W = [_floats(A) / sigma for A in vertex_A], _floats(C), float(noise_weight) * sigma
    # Jacobi preconditioning: the states' scales differ by orders of magnitude (abs-xbs3: X spans 1e-4..1e2),
    # which makes the interior point fail on the polytope.  A Kalman filter of each mode at the nominal point
    # that decays at the (scaled) rate 1 -- the Riccati equation of A + I, unit intensities -- gives the scales:
    # z = D z~ with D = diag(X0)^(-1/2), X0 the sum of the inverse Riccati solutions, gives X~ = D X0 D a unit
    # diagonal.
    An = _floats(nominal_A) / sigma
    try:
        X0 = sum(np.linalg.inv(scipy.linalg.solve_continuous_are((sign * An + np.eye(n)).T, Cf.T, np.eye(n),
                                                                  np.eye(len(Cf))))
                 for sign in (1, -1))
        D = np.diag(1 / np.sqrt(np.abs(np.diag(X0))))
    except (np.linalg.LinAlgError, ValueError):
        D = np.eye(n)   # not detectable at the nominal point: the LMIs will say so
    v, info = _lmi([np.linalg.solve(D, A @ D) for A in As], Cf @ D, E @ D, 1.0, W, (1, -1), use_strict, solvers)
    solve_s = time.perf_counter() - t0
    if info.status == cp.INFEASIBLE or any(X.value is None for X in v["X"]):
        return fail(f"the polytopic LMIs are infeasible ({'; '.join(info.attempts)})", info, solve_s)
    t0 = time.perf_counter()
    Dinv = np.linalg.inv(D)
    X_nums = [Dinv @ np.asarray(X.value) @ Dinv for X in v["X"]] * (2 if use_strict else 1)
    K_plus, K_minus = (dyadic(D @ np.linalg.solve(np.asarray(X.value), np.asarray(Y.value)) * sigma, 40)
                       for X, Y in zip(v["X"] * (2 if use_strict else 1), v["Y"]))
    X_plus, X_minus = (dyadic((X + X.T) / 2) for X in X_nums)
    modes = vertex_matrices(terms, box.intervals, pieces, C, K_plus, K_minus)
    reason = ""
    for name, mats, X in zip(("A_plus", "A_minus"), modes, (X_plus, X_minus)):
        for i, A in enumerate(mats):
            if (why := decay_holds(A, X, rate)):
                reason = f"{name} at vertex {i + 1}: {why}"
                break
        if reason:
            break
    exact_s = time.perf_counter() - t0
    if reason:
        return fail(f"the rounded gains fail the exact vertex check: {reason}", info, solve_s)
    Af, Cf = _floats(nominal_A), _floats(C)
    Kp, Km = _floats(K_plus), _floats(K_minus)
    gains = {"A_plus": noise_gain(Af - Kp @ Cf, Kp, E), "A_minus": noise_gain(-Af + Km @ Cf, Km, E)}
    scaled = max(float(np.trace(X)) + (noise_weight * sigma) ** 2 * float(np.trace(Z.value))
                 for X, Z in zip(X_nums, v["Z"]))
    return GainSynthesis(formulation, rate, noise_weight, rows, True, K_plus, K_minus,
                         X_plus if use_strict else None, X_plus, X_minus, float(np.sqrt(max(scaled, 0.0) / sigma)),
                         gains, info, "", solve_s, exact_s, box=box, vertices=len(vertex_A))
