"""Balde–Boscain–Mason classification of planar switched linear systems (seed 004).

For two Hurwitz ``2 x 2`` matrices, with
``Gamma = (tr A1 tr A2 - tr(A1 A2)) / 2`` and ``delta = sqrt(det A1 det A2)``:

(i)   ``Gamma < -delta``: some switching signal gives an unbounded trajectory;
(ii)  ``Gamma = -delta``: uniformly stable (UGS) but not UGES;
(iii) ``Gamma > -delta`` and ``tr(A1 A2) > -2 delta``: a strict common quadratic
      Lyapunov function exists (UGES);
(iv)  ``Gamma > -delta`` and ``tr(A1 A2) <= -2 delta``: UGES if ``R < 1``, UGS if
      ``R = 1``, unbounded trajectories if ``R > 1``.

Cases i–iii are decided exactly (squares are compared, no square root is
taken).  The seed gives no formula for ``R`` and the paper was not available
to us, so ``R`` is computed by the worst-case trajectory construction the
invariant stands for: ``A1 x`` and ``A2 x`` are collinear on the lines where
``det(A1 x, A2 x) = 0`` (eigenvectors of ``A2^-1 A1``, real and positive in
case iv since ``Gamma > delta`` there); between two such lines the trajectory
that gains most radius per angle follows one field only, and a half-turn of
it multiplies the norm by

    R = exp( sum over the sectors of a half-turn of  ∫ (e' A_i e) / |e_perp' A_i e| dtheta ),

``e = (cos theta, sin theta)``, with ``A_i`` the field of largest
``d ln r / d theta`` among those turning in the chosen direction (both
directions are tried; fields that stop turning inside a sector block that
direction).  Convex combinations are never worse (a linear-fractional
function of the weight is monotone) and, since every convex combination is
Hurwitz when ``Gamma > -delta``, back-and-forth motion only contracts.  ``R`` is
thus the growth per half-turn of the worst trajectory; ``R`` and the paper's
invariant agree on the side of 1 they fall, which is all the verdict uses.
The worst switching signal is periodic, and the product of its matrix
exponentials over a half-turn has the eigenvalue ``-R`` (a check used in the
tests).  ``R`` is computed with mpmath at 40 digits; ``R = 1`` is declared when
``|ln R| < 1e-25``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

import mpmath
import numpy as np

from ..exceptions import CertificateError, DimensionError, NotHurwitzError
from ..exact import Matrix, matmul
from ._family import as_family, format_spectrum

__all__ = ["PlanarClassification", "classify_planar", "VERDICTS"]

VERDICTS = {
    "i": "unbounded trajectory exists for some switching signal",
    "ii": "UGS but not UGES",
    "iii": "UGES: a strict common quadratic Lyapunov function exists",
    "iv<": "UGES (R < 1), although no strict common quadratic Lyapunov function exists",
    "iv=": "UGS but not UGES (R = 1)",
    "iv>": "unbounded trajectory exists for some switching signal (R > 1)",
}


@dataclass(frozen=True)
class PlanarClassification:
    """Balde–Boscain–Mason case of a planar pair and its verdict.

    Attributes
    ----------
    case : str
        ``"i"``, ``"ii"``, ``"iii"`` or ``"iv"``.
    verdict : str
    stability : str
        ``"UGES"``, ``"UGS-not-UGES"`` or ``"unbounded"``.
    gamma, det1, det2, trace_product : Fraction
        ``Gamma(A1, A2)``, ``det A1``, ``det A2``, ``tr(A1 A2)`` (exact for rational input).
    delta : float
        ``sqrt(det A1 det A2)``.
    R : float or None
        Worst-case growth per half-turn (cases iii and iv; None otherwise).
    worst_switching : tuple of (str, float)
        For ``R``: the matrices and durations of the worst switching signal
        over one half-turn (empty when no trajectory can turn).
    names : tuple of str
    """

    case: str
    verdict: str
    stability: str
    gamma: Fraction
    det1: Fraction
    det2: Fraction
    trace_product: Fraction
    delta: float
    R: float | None
    worst_switching: tuple[tuple[str, float], ...] = field(default=())
    names: tuple[str, str] = ("A1", "A2")

    @property
    def strict_cqlf_exists(self) -> bool:
        return self.case == "iii"

    def half_turn_product(self, matrices: Sequence[np.ndarray]) -> np.ndarray:
        """``prod exp(A_i t_i)`` over the worst switching signal of one half-turn."""
        import scipy.linalg

        index = {nm: i for i, nm in enumerate(self.names)}
        Phi = np.eye(2)
        for nm, dt in self.worst_switching:
            Phi = scipy.linalg.expm(np.asarray(matrices[index[nm]], dtype=float) * dt) @ Phi
        return Phi

    def to_json(self) -> dict[str, Any]:
        return {"case": self.case, "verdict": self.verdict, "stability": self.stability,
                "Gamma": str(self.gamma), "det1": str(self.det1), "det2": str(self.det2),
                "tr_A1A2": str(self.trace_product), "sqrt_det_product": self.delta,
                "R": self.R, "worst_switching": [[nm, dt] for nm, dt in self.worst_switching],
                "names": list(self.names)}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> "PlanarClassification":
        """The classification of :meth:`to_json` (exact fields read back as fractions)."""
        try:
            return cls(data["case"], data["verdict"], data["stability"], Fraction(data["Gamma"]),
                       Fraction(data["det1"]), Fraction(data["det2"]), Fraction(data["tr_A1A2"]),
                       float(data["sqrt_det_product"]), None if data["R"] is None else float(data["R"]),
                       tuple((str(nm), float(dt)) for nm, dt in data["worst_switching"]),
                       (str(data["names"][0]), str(data["names"][1])))
        except (KeyError, TypeError, ValueError, IndexError) as exc:
            raise CertificateError(f"not a planar classification JSON ({type(exc).__name__}: {exc})") from None

    def __str__(self) -> str:
        a, b = self.names
        lines = [f"planar case ({self.case}): {self.verdict}",
                 f"  Gamma({a},{b}) = {self.gamma} = {float(self.gamma):.6g}",
                 f"  det {a} = {self.det1}, det {b} = {self.det2}, sqrt(det {a} det {b}) = {self.delta:.6g}",
                 f"  tr({a} {b}) = {self.trace_product} = {float(self.trace_product):.6g}"]
        if self.R is not None:
            lines.append(f"  R (worst growth per half-turn) = {self.R:.12g}")
        return "\n".join(lines)


def _trig(A: Matrix) -> tuple[mpmath.mpf, ...]:
    """``e_perp' A e = alpha + beta cos 2t + gamma sin 2t`` and ``e' A e = a0 + a1 cos 2t + a2 sin 2t``."""
    a11, a12, a21, a22 = (mpmath.mpf(x.numerator) / x.denominator for x in (A[0][0], A[0][1], A[1][0], A[1][1]))
    rot = ((a21 - a12) / 2, (a21 + a12) / 2, (a22 - a11) / 2)
    rad = ((a11 + a22) / 2, (a11 - a22) / 2, (a12 + a21) / 2)
    return rot + rad


def _eval(c: Sequence[mpmath.mpf], t: mpmath.mpf) -> mpmath.mpf:
    return c[0] + c[1] * mpmath.cos(2 * t) + c[2] * mpmath.sin(2 * t)


def _min_on(c: Sequence[mpmath.mpf], a: mpmath.mpf, b: mpmath.mpf) -> mpmath.mpf:
    pts = [a, b]
    phase = mpmath.atan2(c[2], c[1]) / 2
    k0 = int(mpmath.floor((a - phase) / (mpmath.pi / 2))) - 1
    for k in range(k0, k0 + 6):
        t = phase + k * mpmath.pi / 2
        if a < t < b:
            pts.append(t)
    return min(_eval(c, t) for t in pts)


def _collinear_angles(A1: Matrix, A2: Matrix) -> list[mpmath.mpf]:
    """Angles in ``[0, pi)`` where ``A1 x`` and ``A2 x`` are parallel: roots of ``x' sym(A1' J A2) x``."""
    J = [[Fraction(0), Fraction(1)], [Fraction(-1), Fraction(0)]]
    K = matmul(matmul([[A1[0][0], A1[1][0]], [A1[0][1], A1[1][1]]], J), A2)
    m11, m22, m12 = K[0][0], K[1][1], (K[0][1] + K[1][0]) / 2
    disc = m12 * m12 - m11 * m22
    if disc < 0:
        return []

    def mp(x: Fraction) -> mpmath.mpf:
        return mpmath.mpf(x.numerator) / x.denominator

    if m22 != 0:
        # m22 u^2 + 2 m12 u + m11 = 0 with u = tan(theta)
        sq = mpmath.sqrt(mp(disc))
        roots = [mpmath.atan((-mp(m12) + sgn * sq) / mp(m22)) % mpmath.pi for sgn in (1, -1)]
    else:
        # cos(theta) (m11 cos + 2 m12 sin) = 0
        roots = [mpmath.pi / 2] + ([mpmath.atan(-mp(m11) / (2 * mp(m12))) % mpmath.pi] if m12 != 0 else [])
    out: list[mpmath.mpf] = []
    for r in sorted(roots):
        if not out or abs(r - out[-1]) > mpmath.mpf(10) ** (-30):
            out.append(r)
    return out


def _worst_growth(A1: Matrix, A2: Matrix, names: tuple[str, str]
                  ) -> tuple[mpmath.mpf, tuple[tuple[str, float], ...]]:
    coeffs = [_trig(A1), _trig(A2)]
    lines = _collinear_angles(A1, A2)
    pi = mpmath.pi
    bounds = lines + [lines[0] + pi] if lines else [mpmath.mpf(0), pi]
    best = (mpmath.mpf(0), ())
    for sign in (1, -1):
        total = mpmath.mpf(0)
        plan: list[tuple[str, float]] = []
        ok = True
        for a, b in zip(bounds[:-1], bounds[1:]):
            mid = (a + b) / 2
            cands = []
            for i, c in enumerate(coeffs):
                rot = sign * _eval(c[:3], mid)
                if rot > 0:
                    cands.append((_eval(c[3:], mid) / rot, i))
            if not cands:
                ok = False
                break
            _, i = max(cands)
            rot_c = [sign * x for x in coeffs[i][:3]]
            if _min_on(rot_c, a, b) <= 0:
                ok = False
                break
            c = coeffs[i]
            total += mpmath.quad(lambda t, c=c: _eval(c[3:], t) / (sign * _eval(c[:3], t)), [a, b])
            dt = mpmath.quad(lambda t, c=c: 1 / (sign * _eval(c[:3], t)), [a, b])
            plan.append((names[i], float(dt)))
        if ok:
            R = mpmath.exp(total)
            if R > best[0]:
                best = (R, tuple(plan) if sign == 1 else tuple(plan[::-1]))
    return best


def classify_planar(A1: Any, A2: Any, *, names: Sequence[str] = ("A1", "A2")) -> PlanarClassification:
    """Classify a pair of Hurwitz ``2 x 2`` matrices (Balde, Boscain & Mason 2009, as stated in seed 004).

    Parameters
    ----------
    A1, A2 : array-like (2 x 2)
        Entries as ints, fraction/decimal strings, sympy Rationals or floats
        (taken at their exact binary value).  Cases i–iii are then decided exactly.
    names : pair of str

    Returns
    -------
    PlanarClassification

    Raises
    ------
    DimensionError
        If a matrix is not 2 x 2.
    NotHurwitzError
        If a matrix is not Hurwitz (the classification assumes both are).

    References
    ----------
    seed 004, 'Classification of planar switched systems' and 'The Theorem of
    Balde, Boscain, and Mason (2009)'.

    Examples
    --------
    >>> classify_planar([[-1, -1], [1, 0]], [[-1, 1], [-1, 0]]).case
    'ii'
    """
    fam = as_family([A1, A2], list(names), hurwitz=False)
    if fam.n != 2:
        raise DimensionError(f"the planar classification needs 2x2 matrices, got {fam.n}x{fam.n}")
    E1, E2 = fam.exact
    for nm, M, Mf in zip(fam.names, fam.exact, fam.numeric):
        tr = M[0][0] + M[1][1]
        det = M[0][0] * M[1][1] - M[0][1] * M[1][0]
        if not (tr < 0 < det):
            raise NotHurwitzError(f"{nm} is not Hurwitz (trace {tr}, determinant {det}; spectrum "
                                  f"{format_spectrum(Mf)}); the Balde-Boscain-Mason classification assumes "
                                  "two Hurwitz matrices")
    tr1 = E1[0][0] + E1[1][1]
    tr2 = E2[0][0] + E2[1][1]
    d1 = E1[0][0] * E1[1][1] - E1[0][1] * E1[1][0]
    d2 = E2[0][0] * E2[1][1] - E2[0][1] * E2[1][0]
    prod = matmul(E1, E2)
    t12 = prod[0][0] + prod[1][1]
    gamma = (tr1 * tr2 - t12) / 2
    dd = d1 * d2
    delta = float(mpmath.sqrt(mpmath.mpf(dd.numerator) / dd.denominator))
    nm = (fam.names[0], fam.names[1])
    if gamma < 0 and gamma * gamma > dd:
        return PlanarClassification("i", VERDICTS["i"], "unbounded", gamma, d1, d2, t12, delta, None, (), nm)
    if gamma < 0 and gamma * gamma == dd:
        return PlanarClassification("ii", VERDICTS["ii"], "UGS-not-UGES", gamma, d1, d2, t12, delta, None, (), nm)
    with mpmath.workdps(40):
        R, plan = _worst_growth(E1, E2, nm)
        logR = mpmath.log(R) if R > 0 else mpmath.mpf("-inf")
    case = "iii" if (t12 >= 0 or t12 * t12 < 4 * dd) else "iv"
    if case == "iii":
        return PlanarClassification("iii", VERDICTS["iii"], "UGES", gamma, d1, d2, t12, delta, float(R), plan, nm)
    if abs(logR) < mpmath.mpf("1e-25"):
        key, stab = "iv=", "UGS-not-UGES"
    elif logR < 0:
        key, stab = "iv<", "UGES"
    else:
        key, stab = "iv>", "unbounded"
    return PlanarClassification("iv", VERDICTS[key], stab, gamma, d1, d2, t12, delta, float(R), plan, nm)
