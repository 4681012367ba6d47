"""Exact re-check of a parameter-box certificate (standard library only).

The error matrices depend on the uncertain parameters ``theta`` polynomially,
``A(theta) = sum_m theta^m M_m`` (one rational matrix ``M_m`` per monomial
``m``), and ``A_plus = A - K_plus C``, ``A_minus = -A + K_minus C`` with the
gains fixed at their nominal values.  Every condition checked here is
*affine* in ``A``, so it holds on the whole box once it holds at the
vertices of a polytope containing ``{A(theta)}``:

* affine dependence: the box's own vertices;
* polynomial dependence (monomial lifting): each monomial ``theta^m`` is
  treated as a parameter of its own, ranging over its exact interval on a
  sub-box; the vertices of the lifted box of every sub-box (``pieces`` per
  parameter of degree > 1) contain the image.  Sound and conservative.

Because the conditions hold pointwise in ``A(theta)``, they also hold when
the parameters vary in time inside the box (load transfer during braking).

Kinds (``He(X) = X + X'``):

``strict-cqlf``
    ``P > 0`` and ``He(P A_p(v)) < 0`` for every vertex ``v`` and mode ``p``.
``dwell-time``
    Piecewise-linear time-varying Lyapunov matrices (Allerhand & Shaked 2011,
    Theorem 1): ``P_{p,0..K} > 0``, ``delta = tau_D / K``, for every vertex
    ``(P_{p,k+1} - P_{p,k}) / delta + He(P_{p,j} A_p(v)) < 0`` for ``j = k, k+1``,
    ``He(P_{p,K} A_p(v)) < 0``, and ``P_{p,K} - P_{q,0} >= 0`` for ``p != q``:
    ``V = e' P_sigma(time since the switch) e`` decreases along every mode and
    does not increase at a switch after a dwell of at least ``tau_D``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from fractions import Fraction
from typing import Any

from .._limits import MAX_BOX_VERTICES, MAX_EXPONENT
from ..exceptions import CertificateError
from ..exact import (Interval, Matrix, add, definiteness, evaluate_terms, fraction_matrix, lyapunov_form,
                     observer_pair, scale, sub, to_fraction, vertex_matrices)

__all__ = ["check_box_data", "check_strict", "check_dwell"]

def _neg_definite(M: Matrix) -> Any:
    return definiteness(scale(-1, M), strict=True)


def check_strict(modes: Sequence[Sequence[Matrix]], P: Matrix) -> str:
    """Empty string if ``P > 0`` and ``He(P A) < 0`` at every vertex matrix; else the reason."""
    r = definiteness(P, strict=True)
    if not r.holds:
        return f"P > 0 fails: {r.reason}"
    for name, mats in zip(("A_plus", "A_minus"), modes):
        for i, A in enumerate(mats):
            r = _neg_definite(lyapunov_form(A, P))
            if not r.holds:
                return f"{name}' P + P {name} < 0 fails at vertex {i + 1}: {r.reason}"
    return ""


def check_dwell(modes: Sequence[Sequence[Matrix]], Ps: Sequence[Sequence[Matrix]], tau: Fraction) -> str:
    """Empty string if the piecewise-linear dwell-time conditions hold at every vertex; else the reason."""
    if tau <= 0:
        return f"tau_D = {tau} must be positive"
    K = len(Ps[0]) - 1
    if K < 1 or any(len(seq) != K + 1 for seq in Ps):
        return "every mode needs the same number (at least 2) of matrices P_0..P_K"
    delta = tau / K
    for name, mats, seq in zip(("A_plus", "A_minus"), modes, Ps):
        for k, P in enumerate(seq):
            r = definiteness(P, strict=True)
            if not r.holds:
                return f"P_{name},{k} > 0 fails: {r.reason}"
        for i, A in enumerate(mats):
            for k in range(K):
                slope = scale(1 / delta, sub(seq[k + 1], seq[k]))
                for j in (k, k + 1):
                    r = _neg_definite(add(slope, lyapunov_form(A, seq[j])))
                    if not r.holds:
                        return (f"(P_{name},{k + 1} - P_{name},{k}) / delta + He(P_{name},{j} {name}) < 0 fails "
                                f"at vertex {i + 1}: {r.reason}")
            r = _neg_definite(lyapunov_form(A, seq[K]))
            if not r.holds:
                return f"He(P_{name},{K} {name}) < 0 fails at vertex {i + 1}: {r.reason}"
    for p, q in ((0, 1), (1, 0)):
        r = definiteness(sub(Ps[p][K], Ps[q][0]), strict=False)
        if not r.holds:
            names = ("A_plus", "A_minus")
            return f"P_{names[p]},{K} - P_{names[q]},0 >= 0 fails: {r.reason}"
    return ""


def _interval(value: Any, what: str) -> Interval:
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise CertificateError(f"{what} must be [lower, upper], got {value!r}")
    lo, hi = (to_fraction(x, what=what) for x in value)
    if lo > hi:
        raise CertificateError(f"{what} = [{lo}, {hi}] is empty (lower > upper)")
    return lo, hi


def check_box_data(data: Mapping[str, Any], family: Sequence[Matrix] | None = None) -> str:
    """Re-check a ``box`` section exactly; empty string if it holds, else the reason.

    ``family`` (``[A_plus, A_minus]`` of the document) must be the pair at the nominal point.
    """
    params = list(data["parameters"])
    box = [_interval(data["box"].get(p), f"box[{p}]") for p in params]
    nominal = [to_fraction(data["nominal"].get(p), what=f"nominal[{p}]") for p in params]
    for p, (lo, hi), v in zip(params, box, nominal):
        if not lo <= v <= hi:
            return f"the nominal {p} = {v} is outside the box [{lo}, {hi}]"
    terms = []
    for t in data["A_terms"]:
        mono = [int(e) for e in t["monomial"]]
        if len(mono) != len(params) or min(mono, default=0) < 0 or max(mono, default=0) > MAX_EXPONENT:
            raise CertificateError(f"box A_terms monomial {str(mono)[:60]} does not match the parameters {params} "
                                   f"(exponents 0..{MAX_EXPONENT})")
        terms.append((mono, fraction_matrix(t["matrix"], what="box A_terms matrix")))
    n = len(terms[0][1])
    C = fraction_matrix(data["C"], what="box C", cols=n)
    Kp = fraction_matrix(data["K_plus"], what="box K_plus", rows=n, cols=len(C))
    Km = fraction_matrix(data["K_minus"], what="box K_minus", rows=n, cols=len(C))
    pieces = int(data.get("pieces", 1))
    if pieces < 1:
        raise CertificateError(f"box pieces must be a positive integer, got {pieces}")
    cut = sum(1 for i in range(len(params)) if max((m[i] for m, _ in terms), default=0) > 1)
    if cut * math.log2(pieces) + len(terms) > math.log2(MAX_BOX_VERTICES):
        raise CertificateError(f"box: {pieces} pieces on {cut} parameter(s) with {len(terms)} monomials may need "
                               f"more than {MAX_BOX_VERTICES} vertex matrices (limit MAX_BOX_VERTICES)")
    if family is not None:
        values = [Fraction(1)] * len(terms)
        for i, (mono, _) in enumerate(terms):
            for e, v in zip(mono, nominal):
                values[i] *= v ** e
        expected = observer_pair(evaluate_terms(terms, values), C, Kp, Km)
        if [list(map(list, M)) for M in expected] != [list(map(list, M)) for M in family]:
            return "the box's A(theta) at the nominal point and its gains do not give the family's A_plus, A_minus"
    modes = vertex_matrices(terms, box, pieces, C, Kp, Km)
    cert = data.get("certificate")
    if not isinstance(cert, Mapping):
        raise CertificateError("box section has no 'certificate' object")
    kind = cert.get("kind")
    if kind == "strict-cqlf":
        return check_strict(modes, fraction_matrix(cert["P"], what="box P", rows=n, cols=n))
    if kind == "dwell-time":
        Ps = [[fraction_matrix(P, what=f"box P_{m}", rows=n, cols=n) for P in cert[f"P_{m}"]]
              for m in ("plus", "minus")]
        return check_dwell(modes, Ps, to_fraction(cert["tau_D"], what="box tau_D"))
    raise CertificateError(f"box certificate kind is {kind!r}; expected 'strict-cqlf' or 'dwell-time'")
