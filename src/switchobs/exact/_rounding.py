"""From a floating-point LMI solution to exact rational certificate candidates.

Two routes, tried in this order by the callers:

1. **Direct rounding** (interior solutions): round the matrices to dyadic
   rationals (40 significant bits); positive semidefinite unknowns are rounded
   through a factor ``F F'`` so that they stay semidefinite exactly.  Works
   whenever the numerical solution has slack.
2. **Facial projection** (boundary solutions, Peyrl & Parrilo 2008): when an
   inequality is active (``A_+' P + P A_+ = -c^2 C' C`` for the observers of
   seed 004 Theorem 1, or ``sum (A_p R_p + R_p A_p') = 0`` in the dual of the
   planar example), rounding breaks it.  The face is read off the numerical
   solution (range of each semidefinite block, snapped to a rational basis),
   the blocks are re-parametrised as ``U X U'``, the linear equations of the
   LMI are written exactly in the unknowns ``(P, X)`` or ``(X, Y)``, and the
   rounded point is projected exactly onto their solution space.  Positivity
   of the projected blocks is then decided exactly.

Both return plain exact matrices; whether they form a certificate is decided
by the independent checker (:mod:`switchobs.certify._verify`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from fractions import Fraction
from typing import Any

import numpy as np
from ._exact import Matrix, definiteness, float_matrix, ldl_psd, matmul, nullspace, solve, sqrt_lower, transpose

__all__ = ["dyadic", "psd_dyadic", "factor_rows", "range_basis", "project_primal", "project_dual",
           "kernel_vector", "MAX_PROJECTION_UNKNOWNS", "FACE_TOLERANCES", "short_sqrt_lower", "normalise"]

#: Projection is exact rational elimination; beyond this many unknowns it is skipped (too slow).
MAX_PROJECTION_UNKNOWNS = 240
#: Relative eigenvalue thresholds tried to read the face of a semidefinite block.
FACE_TOLERANCES: tuple[float, ...] = (1e-5, 1e-7, 1e-3)


def dyadic(M: np.ndarray, bits: int = 40) -> Matrix:
    """Round to dyadic rationals with ``bits`` significant bits relative to the largest entry."""
    M = np.atleast_2d(np.asarray(M, dtype=float))
    top = float(np.max(np.abs(M))) if M.size else 0.0
    if top == 0.0:
        return [[Fraction(0)] * M.shape[1] for _ in range(M.shape[0])]
    e = bits - math.frexp(top)[1]
    return [[Fraction(round(math.ldexp(x, e))) / Fraction(2) ** e if e >= 0
             else Fraction(round(math.ldexp(x, e)) * 2 ** (-e)) for x in row] for row in M]


def psd_dyadic(R: np.ndarray, bits: int = 40, rel_tol: float = 1e-10) -> Matrix:
    """Round a numerically PSD matrix through a dyadic factor, so the result is PSD exactly."""
    w, V = np.linalg.eigh((R + R.T) / 2)
    keep = w > rel_tol * max(float(np.max(np.abs(w))), 1e-300)
    F = dyadic(V[:, keep] * np.sqrt(w[keep]), bits) if np.any(keep) else [[Fraction(0)] for _ in range(len(R))]
    return matmul(F, transpose(F))


def normalise(P: Matrix, *others: Matrix) -> tuple[Matrix, ...]:
    """Divide ``P`` (and ``others``) by the largest diagonal entry of ``P``: the certificate is homogeneous."""
    c = max(P[i][i] for i in range(len(P)))
    if c <= 0:
        return (P, *others)
    return tuple([[x / c for x in row] for row in M] for M in (P, *others))


def short_sqrt_lower(x: Fraction, bits: int = 20) -> Fraction:
    """A positive dyadic ``q <= sqrt(x)`` with about ``bits`` significant bits (short certificates)."""
    q = sqrt_lower(x, max(64, x.denominator.bit_length()))
    k = bits - (q.numerator.bit_length() - q.denominator.bit_length())
    return Fraction(math.floor(q * 2 ** k), 2 ** k) if k >= 0 else Fraction(math.floor(q / 2 ** -k) * 2 ** -k)


def factor_rows(M: Sequence[Sequence[Fraction]]) -> Matrix | None:
    """A rational ``C`` with ``C' C <= M`` exactly and ``row space(C) = range(M)``.

    ``M = L D L'`` exactly; ``C = diag(q) L'`` over the positive pivots with
    ``0 < q_k <= sqrt(d_k)`` rational, so ``M - C' C = L diag(d - q^2) L' >= 0``.
    Observability of ``(A, C)`` is then that of ``(A, M)``.
    """
    f = ldl_psd(M)
    if f is None:
        return None
    L, d = f
    rows = []
    for k, dk in enumerate(d):
        if dk > 0:
            q = short_sqrt_lower(dk)
            rows.append([q * L[i][k] for i in range(len(L))])
    return rows


def _snap(x: float, tol: float) -> Fraction:
    f = Fraction(x).limit_denominator(64)
    return f if abs(float(f) - x) <= tol else Fraction(x).limit_denominator(2 ** 40)


def range_basis(M: np.ndarray, rel_tol: float) -> Matrix:
    """Rational basis (columns, ``n x r``) of the numerical range of a PSD matrix.

    The eigenvectors of the eigenvalues above ``rel_tol`` times the largest
    are brought to reduced row-echelon form by full pivoting (pivot entries
    1) and every other entry is snapped to a rational of denominator at most
    64 when within ``sqrt(rel_tol)`` of it: an interior-point solution near a
    face of the semidefinite cone is off the face by about the square root of
    its accuracy, so coordinate faces such as ``span(e1)`` come out exact.
    Wrong snaps are harmless: the exact re-check rejects them.
    """
    w, V = np.linalg.eigh((M + M.T) / 2)
    top = float(np.max(np.abs(w))) if w.size else 0.0
    keep = w > rel_tol * top if top > 0 else np.zeros_like(w, dtype=bool)
    B = V[:, keep].T.copy()  # r x n rows spanning the range
    r, n = B.shape
    pivcols: list[int] = []
    for row in range(r):
        sub = np.abs(B[row:, :])
        sub[:, pivcols] = -1.0
        i, c = np.unravel_index(int(np.argmax(sub)), sub.shape)
        i += row
        B[[row, i]] = B[[i, row]]
        B[row] /= B[row, c]
        for k in range(r):
            if k != row:
                B[k] -= B[k, c] * B[row]
        pivcols.append(int(c))
    tol = max(1e-6, float(np.sqrt(rel_tol)))
    rows = [[_snap(float(x), tol) for x in B[i]] for i in range(r)]
    for i in range(r):
        for k, c in enumerate(pivcols):
            rows[i][c] = Fraction(int(i == k))
    return transpose(rows) if rows else [[] for _ in range(n)]


def _sym_units(r: int) -> list[tuple[int, int]]:
    return [(a, b) for a in range(r) for b in range(a, r)]


def _unit_image(U: Matrix, a: int, b: int, X: Matrix | None = None) -> Matrix:
    """``X E_ab U'`` for the symmetric unit ``E_ab`` (``X = U`` by default): ``O(n^2)``, no matrix product."""
    X = U if X is None else X
    n = len(U)
    xa = [X[i][a] for i in range(n)]
    xb = [X[i][b] for i in range(n)]
    ua = [U[i][a] for i in range(n)]
    ub = [U[i][b] for i in range(n)]
    if a == b:
        return [[xa[i] * ua[j] for j in range(n)] for i in range(n)]
    return [[xa[i] * ub[j] + xb[i] * ua[j] for j in range(n)] for i in range(n)]


def _symmetrised(M: Matrix) -> Matrix:
    """``M + M'``."""
    return [[M[i][j] + M[j][i] for j in range(len(M))] for i in range(len(M))]


def _q(M: Sequence[Sequence[Any]]) -> list[list[Any]]:
    """Entries as python-flint's ``fmpq``: the coefficient loops below in C arithmetic."""
    import flint

    return [[flint.fmpq(int(x.numerator), int(x.denominator)) for x in row] for row in M]


def kernel_vector(M: Sequence[Sequence[Any]]) -> list[Fraction] | None:
    """A nonzero integer vector ``v`` (no common factor) with ``M v = 0`` for a square rational ``M``, or None."""
    N = nullspace(M)
    if not N:
        return None
    row = N[0]
    den = math.lcm(*(x.denominator for x in row))
    ints = [int(x * den) for x in row]
    g = math.gcd(*ints)
    return [Fraction(x // g) for x in ints]


def _vech_coords(X: np.ndarray, r: int) -> list[float]:
    return [float(X[a, b]) for a, b in _sym_units(r)]


def _assemble(units: Sequence[tuple[int, int]], z: Sequence[Fraction], r: int) -> Matrix:
    X = [[Fraction(0)] * r for _ in range(r)]
    for (a, b), v in zip(units, z):
        X[a][b] = v
        X[b][a] = v
    return X


def _project(columns: list[list[Matrix]], start: Sequence[Fraction]) -> list[Fraction] | None:
    """Exact orthogonal projection of ``start`` onto ``{z : sum_m z_m E_m^(e) = 0 for every equation block e}``.

    ``columns[m]`` lists, for unknown ``m``, its coefficient matrix in each
    matrix equation; only the upper triangles are equations (all blocks are symmetric).
    """
    k = len(columns)
    n_eq = len(columns[0])
    n = len(columns[0][0])
    rows = []
    for e in range(n_eq):
        for i in range(n):
            for j in range(i, n):
                rows.append([columns[m][e][i][j] for m in range(k)])
    # The projection is unique, whichever basis of the solution space the rows of N are
    N = nullspace(rows, k)
    if not N:
        return None
    # z = N' (N N')^-1 N start
    Nt = transpose(N)
    y = solve(matmul(N, Nt), matmul(N, [[x] for x in start]))
    return [row[0] for row in matmul(Nt, y)]


def project_primal(As: Sequence[Matrix], P_num: np.ndarray, rel_tol: float
                   ) -> tuple[Matrix, list[Matrix]] | None:
    """Exact ``(P, W_p)`` with ``A_p' P + P A_p = -W_p``, ``W_p`` on the numerical face; ``None`` if it fails.

    ``P > 0`` and ``W_p >= 0`` are checked exactly; the caller still verifies
    the certificate built from them.
    """
    n = len(As[0])
    Af = [float_matrix(A) for A in As]
    W_nums = [-(A.T @ P_num + P_num @ A) for A in Af]
    faces = [range_basis(W, rel_tol) for W in W_nums]
    ranks = [len(U[0]) if U and U[0] else 0 for U in faces]
    p_units = _sym_units(n)
    n_unknown = len(p_units) + sum(r * (r + 1) // 2 for r in ranks)
    if n_unknown > MAX_PROJECTION_UNKNOWNS:
        return None
    zero = [[Fraction(0)] * n for _ in range(n)]
    columns: list[list[Matrix]] = []
    eye = _q([[Fraction(int(i == j)) for j in range(n)] for i in range(n)])
    As_t = [transpose(_q(A)) for A in As]
    for a, b in p_units:  # A' E_ab + E_ab A
        columns.append([_symmetrised(_unit_image(eye, a, b, At)) for At in As_t])
    start = [Fraction(float(P_num[a, b])) for a, b in p_units]
    for p, (U, r) in enumerate(zip(faces, ranks)):
        if r == 0:
            continue
        start += _face_start(U, W_nums[p], r)
        Uq = _q(U)
        for a, b in _sym_units(r):
            img = _unit_image(Uq, a, b)
            columns.append([img if q == p else zero for q in range(len(As))])
    z = _project(columns, start)
    if z is None:
        return None
    P = _assemble(p_units, z[:len(p_units)], n)
    if not definiteness(P, strict=True).holds:
        return None
    Ws, _ = _face_matrices(faces, ranks, z, len(p_units), n)
    if Ws is None:
        return None
    return P, Ws


def project_dual(As: Sequence[Matrix], R_nums: Sequence[np.ndarray], rel_tol: float
                 ) -> tuple[list[Matrix], Matrix] | None:
    """Exact ``(R_p, S)`` with ``sum_p (A_p R_p + R_p A_p') = S``, all on their numerical faces.

    Returns ``None`` if the projected blocks are not semidefinite or all ``R_p`` vanish.
    """
    n = len(As[0])
    Af = [float_matrix(A) for A in As]
    S_num = sum(A @ R + R @ A.T for A, R in zip(Af, R_nums))
    if not all(np.all(np.isfinite(M)) for M in (*R_nums, S_num)):  # a solver answer beyond double range
        return None
    scale_R = max(float(np.max(np.abs(R))) for R in R_nums)
    faces = [range_basis(R, rel_tol) for R in R_nums]
    ranks = [len(U[0]) if U and U[0] else 0 for U in faces]
    s_top = float(np.max(np.abs(np.linalg.eigvalsh(S_num))))
    norm_A = max(float(np.linalg.norm(A, 2)) for A in Af)
    S_face = range_basis(S_num, rel_tol) if s_top > rel_tol * scale_R * norm_A else [[] for _ in range(n)]
    s_rank = len(S_face[0]) if S_face and S_face[0] else 0
    n_unknown = sum(r * (r + 1) // 2 for r in ranks) + s_rank * (s_rank + 1) // 2
    if n_unknown == 0 or n_unknown > MAX_PROJECTION_UNKNOWNS:
        return None
    columns: list[list[Matrix]] = []
    start: list[Fraction] = []
    for U, r, R in zip(faces, ranks, R_nums):
        if r == 0:
            continue
        start += _face_start(U, R, r)
    for A, U, r in zip(As, faces, ranks):
        Uq = _q(U)
        AU = _q(matmul(A, U)) if r else Uq
        for a, b in _sym_units(r):  # A U E_ab U' + (A U E_ab U')'
            columns.append([_symmetrised(_unit_image(Uq, a, b, AU))])
    if s_rank:
        start += _face_start(S_face, S_num, s_rank)
        Sq = _q(S_face)
        for a, b in _sym_units(s_rank):
            img = _unit_image(Sq, a, b)
            columns.append([[[-x for x in row] for row in img]])
    z = _project(columns, start)
    if z is None:
        return None
    Rs, pos = _face_matrices(faces, ranks, z, 0, n)
    if Rs is None:
        return None
    S = [[Fraction(0)] * n for _ in range(n)]
    if s_rank:
        Y = _assemble(_sym_units(s_rank), z[pos:], s_rank)
        if not definiteness(Y, strict=False).holds:
            return None
        S = matmul(matmul(S_face, Y), transpose(S_face))
    return Rs, S


def _face_start(U: Matrix, W: np.ndarray, r: int) -> list[Fraction]:
    """Coordinates of the numeric matrix ``W`` on the face spanned by ``U`` (the projection's start point)."""
    pinv = np.linalg.pinv(float_matrix(U))
    return [Fraction(x) for x in _vech_coords(pinv @ W @ pinv.T, r)]


def _face_matrices(faces: Sequence[Matrix], ranks: Sequence[int], z: Sequence[Fraction], pos: int,
                   n: int) -> tuple[list[Matrix] | None, int]:
    """``U X U'`` for each face from the projected coordinates ``z[pos:]``; None if an ``X`` is not PSD."""
    out = []
    for U, r in zip(faces, ranks):
        if r == 0:
            out.append([[Fraction(0)] * n for _ in range(n)])
            continue
        m = r * (r + 1) // 2
        X = _assemble(_sym_units(r), z[pos:pos + m], r)
        pos += m
        if not definiteness(X, strict=False).holds:
            return None, pos
        out.append(matmul(matmul(U, X), transpose(U)))
    return out, pos
