"""Joint synthesis of ``K_plus``, ``K_minus`` over a parameter box: polytopic LMIs, exact vertex checks.

The uncertain parameters ``theta`` enter ``A`` polynomially (:func:`model_terms`);
``{A(theta)}`` lies in the convex hull of the vertex matrices ``A_v`` (the box's
vertices when ``A`` is affine, monomial lifting otherwise,
:mod:`switchobs.certify._box_check`).  With ``Y_p = X_p K_p`` the conditions
(in the rescaled time, see :mod:`switchobs.synthesis._synthesis`)

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
from ..model import Model, ParameterBox, model_terms, parse_box
from ..exact import evaluate_terms, float_matrix, fraction_matrix, rank, vertex_matrices, vertex_values
from ..lmi import DEFAULT_SOLVERS
from ._synthesis import (STRICT_IMPOSSIBLE, GainSynthesis, _lmi, check_synthesis_inputs, decay_certificate,
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
        As in :func:`switchobs.synthesis.synthesize`; the H2 bound holds at every vertex, the reported
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
    sigma = float(rate)
    E = np.eye(n)[list(rows)]
    t0 = time.perf_counter()
    # solved in the coordinates of the modes' Kalman filters at the nominal point (riccati_scaling): the
    # states' scales differ by orders of magnitude (abs-xbs3: X spans 1e-4..1e2)
    point, info = _lmi([float_matrix(A) / sigma for A in vertex_A], float_matrix(C), E, float(noise_weight) * sigma,
                       (1, -1),
                       use_strict, solvers, nominal=float_matrix(nominal_A) / sigma)
    solve_s = time.perf_counter() - t0
    if point is None:
        return fail(f"the polytopic LMIs are infeasible ({'; '.join(info.attempts)})", info, solve_s)
    t0 = time.perf_counter()
    K_plus, K_minus = point.gain(0, rate), point.gain(1, rate)
    modes = vertex_matrices(terms, box.intervals, pieces, C, K_plus, K_minus)
    if use_strict:
        P, reason = decay_certificate(modes[0] + modes[1], rate, point.S[0], point.X_scaled[0], solvers)
        X_plus = X_minus = P
    else:
        (X_plus, why_plus), (X_minus, why_minus) = (
            decay_certificate(mats, rate, S, X, solvers) for mats, S, X in zip(modes, point.S, point.X_scaled))
        reason = f"A_plus: {why_plus}" if X_plus is None else f"A_minus: {why_minus}" if X_minus is None else ""
    exact_s = time.perf_counter() - t0
    if reason:
        return fail(f"the rounded gains fail the exact vertex check: {reason}", info, solve_s)
    Af, Cf = float_matrix(nominal_A), float_matrix(C)
    Kp, Km = float_matrix(K_plus), float_matrix(K_minus)
    gains = {"A_plus": noise_gain(Af - Kp @ Cf, Kp, E), "A_minus": noise_gain(-Af + Km @ Cf, Km, E)}
    scaled = max(tr_X + (noise_weight * sigma) ** 2 * tr_Z for tr_X, tr_Z in zip(point.trace_X, point.trace_Z))
    return GainSynthesis(formulation, rate, noise_weight, rows, True, K_plus, K_minus,
                         X_plus if use_strict else None, X_plus, X_minus, float(np.sqrt(max(scaled, 0.0) / sigma)),
                         gains, info, "", solve_s, exact_s, box=box, vertices=len(vertex_A))
