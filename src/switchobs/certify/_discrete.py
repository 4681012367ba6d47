"""Certificates of the sampled observer: the error map of one step, for every step length.

The generated C step (and the Python reference observer) advance the
observer by one step of a Runge-Kutta method with the signals held.  In the
rescaled time the error of mode ``sigma`` then obeys

    e+ = R(h A_sigma) e,        h = |s(y, t)| * dt,

where ``R`` is the method's stability function (``R(z) = N(z) / D(z)``) and
``h`` changes at every sample.  A *discrete certificate* is a matrix
``P_d > 0`` with ``R(h A_pm)' P_d R(h A_pm) <= P_d`` for **every** ``h`` in
``(0, h_max]`` and both modes, proved in exact rational arithmetic.

Two facts decide what can be certified (both checked exactly here):

* **Uniqueness.**  ``A_plus + A_minus = (K_minus - K_plus) C``, so for a single
  output every common (non-strict) Lyapunov matrix of the continuous pair
  has ``A_pm' P + P A_pm = -q_pm C'C`` and is therefore a multiple of the
  continuous ``P`` (seed 004, Theorem 1; seed 000 (24)).  Dividing the
  discrete decrease by ``h`` and letting ``h -> 0`` gives the continuous
  condition, so ``P_d`` must be ``P`` up to scale.
* **Order versus observability index.**  In observability coordinates
  ``w = O e`` scaled by ``diag(1, h, ..., h^(n-1))`` the decrease divided by
  ``h`` tends to a fixed matrix ``G(0)``.  For the exact flow it is a Gram
  matrix (positive definite); an explicit method of order ``p`` perturbs the
  entries of index ``j + k >= p``.  Euler (p = 1) breaks it for ``n >= 2`` and
  RK4 for ``n >= 3``: ``G(0)`` is then indefinite and the step *increases*
  ``V`` along a direction for every small ``h``, so no ``h_max > 0`` exists.
  Algebraically stable implicit methods keep the continuous certificate for
  every ``h``: the implicit midpoint rule (Gauss, order 2) with
  ``D'PD - N'PN = h Q`` and the 2-stage Radau IIA rule (order 3, L-stable)
  with ``D'PD - N'PN = h L'QL + h^3/12 A'QA + h^4/36 (A^2)'P A^2``, a strict
  decrease for every ``h > 0``.

Every proof is stored as data and re-checked by :func:`check_discrete`, which
uses only :mod:`switchobs.exact` (standard-library rationals).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from enum import Enum
from fractions import Fraction
from typing import Any

from ..exceptions import CertificateError, DimensionError
from ..spec import STEP_METHODS, StepMethod
from ..exact import (Matrix, add, definiteness, float_matrix, fraction_matrix, identity, is_zero, lyapunov_form, matmul,
                     matrix_strings, nullspace, observable, scale, solve, sub, to_fraction, transpose, zeros)

__all__ = ["StepMethod", "STEP_METHODS", "DiscreteVerdict", "DiscreteCertificate", "discrete_certificate",
           "check_discrete", "stability_function"]


def _method(name: str) -> StepMethod:
    try:
        return STEP_METHODS[name]
    except KeyError:
        raise CertificateError(f"unknown step method {name!r}; choose one of {', '.join(STEP_METHODS)}") from None


def stability_function(method: str) -> StepMethod:
    """The :class:`StepMethod` called ``method`` (one of :data:`STEP_METHODS`)."""
    return _method(method)


class DiscreteVerdict(str, Enum):
    """Outcome of a discrete certificate; the value is what the JSON stores."""

    CERTIFIED = "certified"          # a proof for every h in (0, h_max]
    IMPOSSIBLE = "impossible"        # no quadratic certificate for any h_max > 0 (exact witness)
    INCONCLUSIVE = "inconclusive"    # neither proved nor refuted by the checks here


# --------------------------------------------------------- matrix polynomials
MatPoly = list[Matrix]  # coefficient matrices of h^0, h^1, ...


def _powers(A: Matrix, k: int) -> list[Matrix]:
    out = [identity(len(A))]
    for _ in range(k):
        out.append(matmul(out[-1], A))
    return out


def _poly_of_A(coeffs: Sequence[Fraction], powers: Sequence[Matrix]) -> MatPoly:
    """``sum_j c_j (h A)^j`` as coefficient matrices of ``h^j``."""
    return [scale(c, powers[j]) for j, c in enumerate(coeffs)]


def _congruence(L: MatPoly, S: Matrix) -> MatPoly:
    """``L(h)' S L(h)`` for a matrix polynomial ``L``."""
    n = len(S)
    out = [zeros(n, n) for _ in range(2 * len(L) - 1)]
    SL = [matmul(S, Lk) for Lk in L]
    for j, Lj in enumerate(L):
        Ljt = transpose(Lj)
        for k, SLk in enumerate(SL):
            out[j + k] = add(out[j + k], matmul(Ljt, SLk))
    return out


def _pcombine(op: Any, A: MatPoly, B: MatPoly) -> MatPoly:
    """``op`` (``add`` or ``sub``) coefficient by coefficient, the shorter polynomial padded with zeros."""
    n = len(A[0]) if A else len(B[0])
    size = max(len(A), len(B))
    pad = lambda X: X + [zeros(n, n)] * (size - len(X))  # noqa: E731
    return [op(X, Y) for X, Y in zip(pad(A), pad(B))]


def _trim(W: MatPoly) -> MatPoly:
    while len(W) > 1 and is_zero(W[-1]):
        W = W[:-1]
    return W


def decrease_polynomial(A: Matrix, P: Matrix, method: StepMethod) -> MatPoly:
    """``W(h) = D(hA)' P D(hA) - N(hA)' P N(hA)``: ``V(e) - V(e+) = (D^-1 e)' W (D^-1 e)``."""
    deg = max(len(method.numerator), len(method.denominator)) - 1
    powers = _powers(A, deg)
    return _trim(_pcombine(sub, _congruence(_poly_of_A(method.denominator, powers), P),
                           _congruence(_poly_of_A(method.numerator, powers), P)))


# ------------------------------------------------------------------- the SOS proof
@dataclass(frozen=True)
class SosTerm:
    """One term ``h^power L(h)' S L(h)`` of a decomposition of ``W(h)``; ``S`` is checked ``>= 0``."""

    power: int
    factor: tuple[Matrix, ...]  # L(h) = sum_j factor[j] h^j
    middle: Matrix

    def to_json(self) -> dict[str, Any]:
        return {"power": self.power, "factor": [matrix_strings(L) for L in self.factor],
                "middle": matrix_strings(self.middle)}

    @classmethod
    def from_json(cls, data: Mapping[str, Any], n: int) -> SosTerm:
        power = data.get("power")
        if not isinstance(power, int) or isinstance(power, bool) or not 1 <= power <= 16:
            raise CertificateError(f"SOS term power must be an integer in 1..16, got {power!r}")
        factor = data.get("factor")
        if not isinstance(factor, list) or not 1 <= len(factor) <= 8:
            raise CertificateError("SOS term factor must be a list of 1 to 8 matrices")
        return cls(power, tuple(fraction_matrix(L, what="SOS factor", rows=n, cols=n) for L in factor),
                   fraction_matrix(data.get("middle"), what="SOS middle", rows=n, cols=n))


def _sos_terms(A: Matrix, P: Matrix, Q: Matrix, method: StepMethod) -> tuple[SosTerm, ...] | None:
    """Closed-form decompositions of ``W(h)`` for the algebraically stable methods (derived in the module doc)."""
    n = len(A)
    I = identity(n)
    if method.name == "midpoint":
        return (SosTerm(1, (I,), Q),)
    if method.name == "radau3":
        A2 = matmul(A, A)
        return (SosTerm(1, (I, scale(Fraction(-1, 6), A)), Q),
                SosTerm(3, (A,), scale(Fraction(1, 12), Q)),
                SosTerm(4, (A2,), scale(Fraction(1, 36), P)))
    return None


def _sos_expand(terms: Sequence[SosTerm], n: int) -> MatPoly:
    total: MatPoly = [zeros(n, n)]
    for t in terms:
        part = [zeros(n, n)] * t.power + _congruence(list(t.factor), t.middle)
        total = _pcombine(add, total, part)
    return _trim(total)


# ------------------------------------------------------ observability scaling
def _scaled(A: Matrix, C: Matrix, W: MatPoly) -> list[Matrix]:
    """``O^-T W_m O^-1`` for each coefficient: the decrease in observability coordinates ``w = O e``."""
    n = len(A)
    O = [C[0]]
    for _ in range(n - 1):
        O.append(matmul([O[-1]], A)[0])
    try:
        Oi = solve(O, identity(n))
    except DimensionError:
        raise CertificateError("(A, C) is not observable: the observability matrix is singular") from None
    Oit = transpose(Oi)
    return [matmul(Oit, matmul(Wk, Oi)) for Wk in W]


def _leading_term(Mw: list[Matrix], u: Sequence[Fraction]) -> tuple[int, Fraction] | None:
    """Lowest-order term ``(power, coefficient)`` of ``p(h) = u' G(h) u``, ``G_jk = Mw_jk(h) / h^(j+k+1)``."""
    terms: dict[int, Fraction] = {}
    idx = [j for j, x in enumerate(u) if x != 0]
    for m, M in enumerate(Mw):
        for j in idx:
            for k in idx:
                if M[j][k] != 0:
                    power = m - j - k - 1
                    terms[power] = terms.get(power, Fraction(0)) + u[j] * u[k] * M[j][k]
    nonzero = sorted(p for p, c in terms.items() if c != 0)
    return (nonzero[0], terms[nonzero[0]]) if nonzero else None


def _witness(Mw: list[Matrix], n: int) -> list[Fraction] | None:
    """A rational ``u`` whose ``p(h) = u' G(h) u`` has a negative lowest-order coefficient, if one is found.

    Candidates: the unit vectors (a diagonal entry of ``G`` whose lowest
    power has a negative coefficient, Euler's obstruction) and a negative
    direction of ``G(0)`` on the largest leading block free of negative
    powers (RK4's obstruction for ``n >= 3``).
    """
    for j in range(n):
        u = [Fraction(int(i == j)) for i in range(n)]
        lead = _leading_term(Mw, u)
        if lead is not None and lead[1] < 0:
            return u
    r = n
    while r > 0 and any(Mw[m][j][k] != 0 for j in range(r) for k in range(r) for m in range(min(j + k + 1, len(Mw)))):
        r -= 1
    G0 = [[Mw[j + k + 1][j][k] if j + k + 1 < len(Mw) else Fraction(0) for k in range(r)] for j in range(r)]
    if not r or definiteness(G0, strict=False).holds:
        return None
    import numpy as np  # the search only; the claim is checked exactly by the caller

    _, V = np.linalg.eigh(float_matrix(G0))
    for den in (10**3, 10**6, 10**9, 10**12):
        u = [Fraction(float(x)).limit_denominator(den) for x in V[:, 0]] + [Fraction(0)] * (n - r)
        lead = _leading_term(Mw, u)
        if lead is not None and lead[1] < 0:
            return u
    return None


# ------------------------------------------------------------ h_rho (numeric)
def spectral_bound(A: Matrix, method: StepMethod) -> float | None:
    """Smallest ``h > 0`` where the spectral radius of ``R(h A)`` reaches 1 (None: never, A-stable method).

    Numeric (numpy roots of ``|N(h lam)|^2 - |D(h lam)|^2``); reported for
    orientation, never used in a proof.
    """
    import numpy as np

    lams = np.linalg.eigvals(float_matrix(A))
    best: float | None = None
    for lam in lams:
        num = np.polynomial.Polynomial([float(c) * lam**k for k, c in enumerate(method.numerator)])
        den = np.polynomial.Polynomial([float(c) * lam**k for k, c in enumerate(method.denominator)])
        conj = lambda p: np.polynomial.Polynomial(np.conj(p.coef))  # noqa: E731
        diff = num * conj(num) - den * conj(den)
        coef = np.real(diff.coef)
        coef[0] = 0.0  # |R(0)| = 1 exactly
        roots = np.polynomial.Polynomial(coef[1:]).roots() if np.any(coef[1:]) else []
        for r in roots:
            if abs(r.imag) <= 1e-9 * max(1.0, abs(r.real)) and r.real > 1e-12:
                best = float(r.real) if best is None else min(best, float(r.real))
    return best


# ------------------------------------------------------------ results
@dataclass(frozen=True)
class ModeProof:
    """The proof (or refutation) for one mode ``A_sigma``."""

    name: str
    h_rho: float | None
    sos: tuple[SosTerm, ...] = ()
    witness: tuple[Fraction, ...] = ()      # u: p(h) = u' G(h) u has a negative lowest-order coefficient
    witness_power: int = 0                  # that lowest power of h
    witness_value: Fraction | None = None   # that coefficient

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"name": self.name, "h_rho": self.h_rho}
        if self.sos:
            out["sos"] = [t.to_json() for t in self.sos]
        if self.witness:
            out["witness"] = {"u": [str(x) for x in self.witness], "power": self.witness_power,
                              "coefficient": str(self.witness_value)}
        return out

    @classmethod
    def from_json(cls, data: Mapping[str, Any], n: int) -> ModeProof:
        """The proof of :meth:`to_json` for a model with ``n`` states (SOS terms and witness exact).

        Raises
        ------
        CertificateError
            A missing key or a malformed term, witness or ``h_rho``.
        """
        if not isinstance(data, Mapping) or not isinstance(data.get("name"), str):
            raise CertificateError(f"a discrete mode proof needs a 'name', got {data!r}")
        rho = data.get("h_rho")
        if rho is not None and (isinstance(rho, bool) or not isinstance(rho, (int, float))):
            raise CertificateError(f"{data['name']}: h_rho must be a number or null, got {rho!r}")
        sos = tuple(SosTerm.from_json(t, n) for t in data.get("sos", ()))
        witness = data.get("witness")
        if witness is None:
            return cls(data["name"], None if rho is None else float(rho), sos)
        try:
            u = tuple(to_fraction(x, what="witness entry") for x in witness["u"])
            power, value = witness["power"], to_fraction(witness["coefficient"], what="witness coefficient")
        except (KeyError, TypeError) as exc:
            raise CertificateError(f"{data['name']}: malformed witness ({type(exc).__name__}: {exc})") from None
        if not isinstance(power, int) or isinstance(power, bool):
            raise CertificateError(f"{data['name']}: witness power must be an integer, got {power!r}")
        return cls(data["name"], None if rho is None else float(rho), sos, u, power, value)


@dataclass(frozen=True)
class DiscreteCertificate:
    """A discrete certificate of the sampled error dynamics ``e+ = R(h A_pm) e``.

    Attributes
    ----------
    method : str
        Step method (a key of :data:`STEP_METHODS`).
    verdict : DiscreteVerdict
    h_max : Fraction or None
        Certified while ``|s(y, t)| * dt <= h_max``; ``None`` with a
        certified verdict means every step length (``h_max = inf``).
    strict : bool
        ``V`` decreases strictly at every step with ``h > 0`` (otherwise
        non-strictly, with a decrease observable along the sampled pair).
    P_d : Matrix
        The Lyapunov matrix (the continuous common ``P``: see the uniqueness lemma).
    modes : tuple of ModeProof
    statement : str
        The claim in plain words.
    reasons : tuple of str
        Why a verdict is what it is (the uniqueness lemma, what was not attempted).
    C : Matrix
        The output row the refutation's observability coordinates use.
    """

    method: str
    verdict: DiscreteVerdict
    h_max: Fraction | None
    strict: bool
    P_d: Matrix
    modes: tuple[ModeProof, ...]
    statement: str
    reasons: tuple[str, ...] = field(default=())
    C: Matrix = field(default_factory=list)

    @property
    def certified(self) -> bool:
        return self.verdict is DiscreteVerdict.CERTIFIED

    @property
    def h_rho(self) -> float | None:
        """The per-mode bound: the smallest ``h`` where a mode's step map stops contracting its spectrum."""
        values = [m.h_rho for m in self.modes if m.h_rho is not None]
        return min(values) if values else None

    def h_max_text(self) -> str:
        if not self.certified:
            return "none"
        return "inf" if self.h_max is None else str(self.h_max)

    def to_json(self, *, reasons: bool = True) -> dict[str, Any]:
        """The certificate as JSON types; ``reasons=False`` leaves out ``reasons`` (the document's section)."""
        out = {"method": self.method, "verdict": self.verdict.value, "h_max": self.h_max_text(),
               "strict": self.strict, "statement": self.statement, "P_d": matrix_strings(self.P_d),
               "C": matrix_strings(self.C), "modes": [m.to_json() for m in self.modes]}
        if reasons:
            out["reasons"] = list(self.reasons)
        return out

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> DiscreteCertificate:
        """The certificate of :meth:`to_json`, exact (nothing re-checked: :func:`check_discrete` does that).

        A document's ``discrete`` section (no ``reasons``) reads back with ``reasons = ()``.

        Raises
        ------
        CertificateError
            A missing key, an unknown method or verdict, or a malformed matrix, ``h_max`` or mode.
        """
        if not isinstance(data, Mapping):
            raise CertificateError(f"a discrete certificate must be an object, got {data!r}")
        for key, kind in (("method", str), ("verdict", str), ("h_max", str), ("strict", bool), ("statement", str),
                          ("P_d", list), ("C", list), ("modes", list)):
            if not isinstance(data.get(key), kind):
                raise CertificateError(f"a discrete certificate needs {key!r} as a {kind.__name__}, "
                                       f"got {data.get(key)!r}")
        method = _method(data["method"]).name
        try:
            verdict = DiscreteVerdict(data["verdict"])
        except ValueError:
            raise CertificateError(f"unknown discrete verdict {data['verdict']!r}; choose one of "
                                   f"{', '.join(v.value for v in DiscreteVerdict)}") from None
        h_max = None if data["h_max"] in ("inf", "none") else to_fraction(data["h_max"], what="h_max")
        P_d = fraction_matrix(data["P_d"], what="P_d")
        C = fraction_matrix(data["C"], what="C", cols=len(P_d)) if data["C"] else []
        reasons = data.get("reasons", [])
        if not isinstance(reasons, list) or not all(isinstance(r, str) for r in reasons):
            raise CertificateError(f"a discrete certificate's 'reasons' must be a list of strings, got {reasons!r}")
        return cls(method, verdict, h_max, data["strict"], P_d,
                   tuple(ModeProof.from_json(m, len(P_d)) for m in data["modes"]), data["statement"],
                   tuple(reasons), C)

    def __str__(self) -> str:
        rho = self.h_rho
        lines = [f"discrete certificate ({STEP_METHODS[self.method].description}): {self.verdict.value}",
                 f"  {self.statement}",
                 f"  per-mode bound h_rho (spectral radius of R(h A) reaches 1): "
                 f"{'none (A-stable)' if rho is None else f'{rho:.6g}'}"]
        for m in self.modes:
            if m.witness:
                lines.append(f"  {m.name}: along e = O^-1 diag(1, h, ..., h^(n-1))^-1 u, u = "
                             f"[{', '.join(map(str, m.witness))}], V(e+) - V(e) = "
                             f"{-m.witness_value} h^{m.witness_power + 1} + O(h^{m.witness_power + 2}) > 0")
        lines += [f"  {r}" for r in self.reasons]
        return "\n".join(lines)


# ------------------------------------------------------------ the analysis
def _uniqueness(A_plus: Matrix, A_minus: Matrix, C: Matrix) -> str | None:
    """None when every common Lyapunov matrix is a multiple of P (single output, A_+ + A_- = K C); else why not."""
    if len(C) != 1:
        return f"the uniqueness lemma needs one output, the model has {len(C)}"
    kernel = nullspace(C, len(A_plus))
    S = add(A_plus, A_minus)
    if kernel and not is_zero(matmul(S, transpose(kernel))):
        return "A_plus + A_minus does not vanish on ker C"
    for name, A in (("A_plus", A_plus), ("A_minus", A_minus)):
        if not observable(A, C)[0]:
            return f"({name}, C) is not observable"
    return None


def _statement(method: StepMethod, verdict: DiscreteVerdict, h_max: Fraction | None, strict: bool) -> str:
    if verdict is DiscreteVerdict.CERTIFIED:
        bound = "for every dt (no bound on |s(y,t)|*dt)" if h_max is None else f"while |s(y,t)|*dt <= {h_max}"
        kind = "strictly decreases" if strict else "never increases (decrease observable along the sampled pair)"
        return f"certified {bound}: V(e) = e'P_d e {kind} at every {method.name} step of either mode"
    if verdict is DiscreteVerdict.IMPOSSIBLE:
        return (f"no quadratic Lyapunov function decreases along the sampled {method.name} error dynamics of both "
                f"modes on (0, h_max] for any h_max > 0 (exact witness below); use an algebraically stable method "
                "(midpoint, radau3)")
    return f"not certified: the {method.name} step is neither proved nor refuted by these checks"


def check_discrete(A_plus: Any, A_minus: Any, C: Any, P: Any, method: str, data: Mapping[str, Any] | None = None
                   ) -> DiscreteCertificate:
    """Analyse (``data=None``) or re-check (``data`` = a stored ``discrete`` section) a discrete certificate.

    Everything is exact.  With ``data`` the stored claim must be reproduced:
    the same verdict and ``h_max``, each SOS term's middle ``>= 0`` and the
    terms summing to ``W(h)`` coefficient by coefficient, each witness giving
    ``u' G0 u < 0``.

    Raises
    ------
    CertificateError
        When a stored section does not check (tampered ``h_max``, ``P_d``, method, terms or witness).
    """
    m = _method(method)
    Ap = fraction_matrix(A_plus, what="A_plus")
    n = len(Ap)
    Am = fraction_matrix(A_minus, what="A_minus", rows=n, cols=n)
    Cm = fraction_matrix(C, what="C", cols=n)
    Pm = fraction_matrix(P, what="P_d", rows=n, cols=n)
    if not definiteness(Pm, strict=True).holds:
        raise CertificateError("P_d is not positive definite")
    reasons: list[str] = []
    modes: list[ModeProof] = []
    stored = {md.get("name"): md for md in (data or {}).get("modes", []) if isinstance(md, Mapping)}
    verdicts: list[DiscreteVerdict] = []
    strict_all = True
    for name, A in (("A_plus", Ap), ("A_minus", Am)):
        W = decrease_polynomial(A, Pm, m)
        Q = [[-x for x in row] for row in lyapunov_form(A, Pm)]
        claim = stored.get(name, {}) if data is not None else {}
        # h_rho is orientation, not part of the proof: the re-check keeps the stored value (no floating point)
        stored_rho = claim.get("h_rho")
        rho = spectral_bound(A, m) if data is None else (
            float(stored_rho) if isinstance(stored_rho, (int, float)) and not isinstance(stored_rho, bool) else None)
        if not definiteness(Q, strict=False).holds:
            raise CertificateError(f"P_d is not a continuous Lyapunov matrix of {name}: "
                                   f"-({name}' P_d + P_d {name}) is not >= 0")
        if "sos" in claim:
            terms = tuple(SosTerm.from_json(t, n) for t in claim["sos"])
        else:
            terms = _sos_terms(A, Pm, Q, m) or ()
        if terms:
            for t in terms:
                if not definiteness(t.middle, strict=False).holds:
                    raise CertificateError(f"{name}: an SOS middle matrix (power {t.power}) is not >= 0")
            if not all(is_zero(X) for X in _pcombine(sub, _sos_expand(terms, n), W)):
                raise CertificateError(f"{name}: the SOS terms do not add up to D'P_dD - N'P_dN for method "
                                       f"{m.name}")
            # one term h^k L' S L with S > 0 and L constant and invertible makes W(h) > 0 for every h > 0
            strict = any(len(t.factor) == 1 and _invertible(t.factor[0]) and definiteness(t.middle, strict=True).holds
                         for t in terms)
            strict_all &= strict
            modes.append(ModeProof(name, rho, sos=terms))
            verdicts.append(DiscreteVerdict.CERTIFIED)
            continue
        Mw = _scaled(A, Cm, W)
        if "witness" in claim:
            try:
                u = [to_fraction(x, what="witness entry") for x in claim["witness"]["u"]]
            except (KeyError, TypeError) as exc:
                raise CertificateError(f"{name}: malformed witness ({exc})") from None
            if len(u) != n:
                raise CertificateError(f"{name}: the witness has {len(u)} entries, the model has n = {n}")
        else:
            u = _witness(Mw, n)
        lead = _leading_term(Mw, u) if u is not None else None
        if lead is not None and lead[1] < 0:
            modes.append(ModeProof(name, rho, witness=tuple(u), witness_power=lead[0], witness_value=lead[1]))
            verdicts.append(DiscreteVerdict.IMPOSSIBLE)
        else:
            if "witness" in claim:
                raise CertificateError(f"{name}: the stored witness does not make V increase for small h")
            modes.append(ModeProof(name, rho))
            verdicts.append(DiscreteVerdict.INCONCLUSIVE)
            reasons.append(f"{name}: no direction found along which V increases for small h, and a certified "
                           "h_max for an explicit method needs an interval proof, which this version does not attempt")
    if DiscreteVerdict.IMPOSSIBLE in verdicts:
        why = _uniqueness(Ap, Am, Cm)
        if why is None:
            verdict = DiscreteVerdict.IMPOSSIBLE
            reasons.append("every common Lyapunov matrix of the pair is a multiple of P (A_plus + A_minus = "
                           "(K_minus - K_plus) C, one output), so the witness refutes every P_d")
        else:
            verdict = DiscreteVerdict.INCONCLUSIVE
            reasons.append(f"the witness refutes this P_d only: {why}")
    elif all(v is DiscreteVerdict.CERTIFIED for v in verdicts):
        verdict = DiscreteVerdict.CERTIFIED
    else:
        verdict = DiscreteVerdict.INCONCLUSIVE
    h_max = None  # the proofs here are for every step length; a finite bound would need an interval proof
    cert = DiscreteCertificate(m.name, verdict, h_max, verdict is DiscreteVerdict.CERTIFIED and strict_all, Pm,
                               tuple(modes), _statement(m, verdict, h_max, strict_all), tuple(reasons), Cm)
    if data is not None:
        _compare(cert, data)
    return cert


def _invertible(M: Matrix) -> bool:
    return not nullspace(M, len(M))


def _compare(cert: DiscreteCertificate, data: Mapping[str, Any]) -> None:
    """A stored section must claim exactly what the re-check establishes."""
    claims = {"method": cert.method, "verdict": cert.verdict.value, "h_max": cert.h_max_text(),
              "strict": cert.strict}
    for key, value in claims.items():
        if data.get(key) != value:
            raise CertificateError(f"discrete section claims {key} = {data.get(key)!r}, the exact re-check gives "
                                   f"{value!r}")


def discrete_certificate(A_plus: Any, A_minus: Any, C: Any, P: Any, *, method: str = "rk4"
                         ) -> DiscreteCertificate:
    """Certify (or refute) the sampled observer ``e+ = R(h A_pm) e`` for every step length ``h``.

    Parameters
    ----------
    A_plus, A_minus : matrix-like (rational)
        The error matrices ``A - K_plus C`` and ``-A + K_minus C`` (seed 000 (13)).
    C : matrix-like
        Output matrix (one row).
    P : matrix-like
        The continuous common Lyapunov matrix (Hespanha, seed 004; seed 000 (24)).
    method : {"rk4", "euler", "midpoint", "radau3"}
        The step of the generated C / Python observer.

    Returns
    -------
    DiscreteCertificate
        ``certified`` with ``h_max`` (``None`` = any step) for midpoint and
        radau3; ``impossible`` with an exact witness for euler (``n >= 2``) and
        rk4 (``n >= 3``); ``inconclusive`` otherwise.

    Examples
    --------
    >>> A_plus = [[-2, 1], [-1, 0]]; A_minus = [[-2, -1], [1, 0]]
    >>> cert = discrete_certificate(A_plus, A_minus, [[1, 0]], [[1, 0], [0, 1]], method="radau3")
    >>> cert.verdict.value, cert.h_max, cert.strict
    ('certified', None, True)
    """
    from ..model import user_matrix  # the user's boundary (NumPy, sympy); the checker itself stays stdlib-only

    return check_discrete(*(user_matrix(M, what=nm, part=part) for M, nm, part in
                            ((A_plus, "A_plus", "A"), (A_minus, "A_minus", "A"), (C, "C", "C"), (P, "P", "A"))), method)

