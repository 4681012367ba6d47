"""Independent exact checker of switchobs certificates (standard library only).

Only the link to the named model (:mod:`switchobs.certify._provenance`) reads
the model file, with the exact model layer; every inequality is decided here.

A certificate is a JSON document (format ``switchobs-certificate``, version 1,
sections in :mod:`switchobs.certify._schema`) holding the switched family
``{A_p}`` and, as rational strings, the matrices of one or more certificates.  :func:`verify_certificate` re-derives every
inequality from those matrices alone, decides each in exact rational
arithmetic (:mod:`switchobs.exact`), recomputes the verdict they
imply and compares it with the verdict the document claims.  It never looks
at margins, solver names or statuses: those are provenance, not evidence.

Certificate kinds and what they prove (``W_p(P) = A_p' P + P A_p``):

``strict-cqlf``
    ``P > 0`` and ``W_p(P) < 0`` for every p: uniform global exponential
    stability under arbitrary switching.
``hespanha``
    ``P > 0``, ``W_p(P) + C_p' C_p <= 0`` and ``(A_p, C_p)`` observable for every
    p (Hespanha 2004, Theorem 4, as used in seed 004 and seed 000 Appendix):
    uniform stability under arbitrary switching, uniform exponential stability
    under any positive dwell time.
``no-strict-cqlf``
    ``R_p >= 0``, not all zero, ``sum_p (A_p R_p + R_p A_p') >= 0``: no strict common
    quadratic Lyapunov function exists (theorem of alternatives: for such a P,
    ``0 <= <P, sum_p ...> = sum_p <W_p(P), R_p> < 0``).
``singular-sum``
    A rational ``v != 0`` with ``(sum_p A_p) v = 0``: no strict common quadratic
    Lyapunov function exists (for such a P, ``M = sum_p A_p`` has
    ``M' P + P M < 0``, yet ``v' (M' P + P M) v = 2 (M v)' P v = 0``).  It is the
    ``no-strict-cqlf`` alternative with ``R_p = v v'``, stored as ``v`` and checked
    in ``O(n^2)``; every observer pair has one (``A_plus + A_minus = (K_minus - K_plus) C``,
    ``v`` in the kernel of ``C``).
``no-common-lyapunov``
    Same with ``S = sum_p (A_p R_p + R_p A_p') >= 0`` and ``S != 0``: not even a
    non-strict ``P > 0`` with ``W_p(P) <= 0`` exists.
``dwell-time``
    ``P_p > 0``, ``W_p(P_p) < 0`` and ``exp(A_p' T) P_q exp(A_p T) - P_p < 0`` for
    ``p != q`` at ``T = tau_D`` (Geromel & Colaneri 2006): uniform exponential
    stability for every switching signal with dwell time ``>= tau_D``.  The
    exponential is enclosed rigorously (:func:`expm_enclosure`).
``planar``
    The Balde–Boscain–Mason case (seed 004), recomputed exactly from Gamma,
    the determinants and ``tr(A_1 A_2)``; cases i–iii are decided exactly,
    the R-test of case iv is not exact and is not part of the implied verdict.
"""

from __future__ import annotations

import json
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field, replace
from fractions import Fraction
from contextlib import contextmanager
from contextvars import ContextVar
from math import gcd
from pathlib import Path
from typing import Any

from .._limits import (MAX_CERTIFICATE_BYTES, MAX_CERTIFICATE_DIGITS, MAX_CERTIFICATE_WORK, MAX_DWELL_BITS,
                       digits, read_text)
from .._progress import progress
from ..exceptions import CertificateError, SwitchobsError
from ..exact import (Matrix, add, definiteness, expm_enclosure, fraction_matrix, inf_norm,
                     integer_form, is_zero, lyapunov_form, matmul, observable, product_work, scale, sqrt_upper,
                     to_fraction, transpose, arithmetic as _arithmetic)
from ._schema import (ANY_DWELL, ArbitrarySwitching, CertificateDocument, CertificateKind, Check, DualEntry,
                      DwellTimeEntry, Existence, FamilySection, LyapunovEntry, ObserverSection, SingularSumEntry,
                      Verdict)
from ._provenance import model_link

__all__ = ["Check", "VerificationReport", "verify_certificate", "load_certificate", "implied_verdict",
           "planar_case_exact", "check_entry", "checked_once"]

#: The entry checks decided so far in one command (see :func:`checked_once`); None outside it.
_DECIDED: ContextVar[dict[tuple[Any, ...], Check] | None] = ContextVar("switchobs_decided_checks", default=None)


@dataclass(frozen=True)
class VerificationReport:
    """Result of :func:`verify_certificate`.

    Attributes
    ----------
    holds : bool
        Every certificate holds exactly and the claimed verdict is the implied one.
    checks : tuple of Check
    implied : Verdict
        The verdict the verified certificates imply.
    claimed : Verdict
        The verdict written in the document.
    model : str or None
        The model the document says it is about (``provenance.model``).
    parameters : mapping str -> str
        Its parameter values (``provenance.parameters``).
    gains : mapping str -> tuple of str
        ``K_plus`` and ``K_minus`` of the ``observer`` section (empty without one).
    unchecked : tuple of str
        The links the document does not let the checker verify (no ``observer`` section: the
        model-gain link; a model that is not built in: its A and C), one sentence each.
        ``switchobs verify --strict`` fails when there is any.
    arithmetic : str
        ``"exact"`` or ``"interval"``, as asked (both decide the same way).
    """

    holds: bool
    checks: tuple[Check, ...]
    implied: Verdict
    claimed: Verdict
    model: str | None = None
    parameters: Mapping[str, str] = field(default_factory=dict)
    gains: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    unchecked: tuple[str, ...] = ()
    arithmetic: str = "exact"

    def to_json(self) -> dict[str, Any]:
        return {"holds": self.holds, "checks": [c.to_json() for c in self.checks],
                "implied": self.implied.to_json(), "claimed": self.claimed.to_json(), "model": self.model,
                "parameters": dict(self.parameters), "gains": {k: list(v) for k, v in self.gains.items()},
                "unchecked": list(self.unchecked), "arithmetic": self.arithmetic}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> "VerificationReport":
        """The report of :meth:`to_json`."""
        if not isinstance(data, Mapping) or not isinstance(data.get("holds"), bool):
            raise CertificateError(f"not a verification report: {data!r}")
        return cls(data["holds"], tuple(Check.from_json(c) for c in data.get("checks", [])),
                   Verdict.from_json(data.get("implied")), Verdict.from_json(data.get("claimed")),
                   data.get("model"), dict(data.get("parameters", {})),
                   {k: tuple(v) for k, v in data.get("gains", {}).items()}, tuple(data.get("unchecked", ())),
                   data.get("arithmetic", "exact"))

    def __str__(self) -> str:
        values = ", ".join(f"{k} = {v}" for k, v in self.parameters.items())
        lines = [f"certificate about model {self.model}" + (f" ({values})" if values else "")
                 if self.model is not None else "certificate names no model (no provenance.model)"]
        lines += [f"  {k:<7} = [{', '.join(v)}]" for k, v in self.gains.items()]
        how = "exactly" if self.arithmetic == "exact" else "(interval arithmetic where it decides, else exactly)"
        lines.append(f"certificate holds {how}" if self.holds else "certificate does NOT hold")
        lines += [f"  {c}" for c in self.checks]
        lines.append("  implied verdict: " + ", ".join(f"{k} = {v}" for k, v in self.implied.to_json().items()))
        lines += [f"  not checked: {u}" for u in self.unchecked]
        return "\n".join(lines)


def load_certificate(path: str | Path) -> dict[str, Any]:
    """Read a certificate JSON file; ``"-"`` reads standard input.

    Raises
    ------
    CertificateError
        If the file cannot be read or is not JSON.
    """
    text, where = read_text(path, what="certificate", max_bytes=MAX_CERTIFICATE_BYTES, error=CertificateError)
    try:
        doc = json.loads(text, parse_int=_json_integer)
    except json.JSONDecodeError as exc:
        raise CertificateError(f"certificate {where!r} is not valid JSON: {exc}") from None
    except RecursionError:
        raise CertificateError(f"certificate {where!r} is nested too deeply to be a certificate") from None
    except CertificateError as exc:  # a number refused by _json_integer
        raise CertificateError(f"certificate {where!r}: {exc}") from None
    if not isinstance(doc, dict):
        raise CertificateError(f"certificate {where!r} must be a JSON object, got {type(doc).__name__}")
    return doc


def _json_integer(text: str) -> int:
    """A JSON integer, refused before conversion when it has more digits than a certificate number may."""
    if len(text.lstrip("-")) > MAX_CERTIFICATE_DIGITS:
        raise CertificateError(f"a JSON integer of {len(text.lstrip('-'))} digits (limit {MAX_CERTIFICATE_DIGITS}): "
                               f"{text[:20]}...")
    return int(text)


# ------------------------------------------------------------------ family
def _family(fam: FamilySection) -> tuple[list[str], list[Matrix]]:
    names = fam.names
    As = [fraction_matrix(M, what=str(nm)) for M, nm in zip(fam.matrices, names)]
    n = len(As[0])
    for nm, M in zip(names, As):
        if len(M) != len(M[0]):
            raise CertificateError(f"{nm} is not square ({len(M)}x{len(M[0])})")
        if len(M) != n:
            raise CertificateError(f"{nm} is {len(M)}x{len(M)} but {names[0]} is {n}x{n}")
    return [str(x) for x in names], As


def _per_mode(items: Any, kind: str, key: str, names: Sequence[str], n: int) -> list[Matrix]:
    if not isinstance(items, (list, tuple)) or len(items) != len(names):
        raise CertificateError(f"{kind}: '{key}' must list one matrix per mode ({len(names)})")
    return [fraction_matrix(M, what=f"{key}[{nm}]", rows=n, cols=n) for M, nm in zip(items, names)]


def _defin(M: Matrix, *, strict: bool, negate: bool = False) -> Any:
    r = definiteness(scale(-1, M) if negate else M, strict=strict)
    if negate and not r.holds:
        return type(r)(r.holds, r.index, r.reason + " (of the negated left-hand side)")
    return r


def _out_name(nm: str) -> str:
    return "C_" + nm[2:] if nm.startswith("A_") else f"C_{nm}"


def _fail(name: str, claim: str, res: Any) -> Check:
    return Check(name, False, f"{claim} fails: {res.reason}")


# ------------------------------------------------------------- certificate kinds
def _check_strict(names: Sequence[str], As: Sequence[Matrix], cert: LyapunovEntry) -> Check:
    n = len(As[0])
    P = fraction_matrix(cert.P, what="P", rows=n, cols=n)
    r = _defin(P, strict=True)
    if not r.holds:
        return _fail("strict-cqlf", "P > 0", r)
    for nm, A in zip(names, As):
        r = _defin(lyapunov_form(A, P), strict=True, negate=True)
        if not r.holds:
            return _fail("strict-cqlf", f"{nm}' P + P {nm} < 0", r)
    return Check("strict-cqlf", True)


def _check_hespanha(names: Sequence[str], As: Sequence[Matrix], cert: LyapunovEntry) -> Check:
    n = len(As[0])
    P = fraction_matrix(cert.P, what="P", rows=n, cols=n)
    Cs = cert.C
    if not isinstance(Cs, (list, tuple)) or len(Cs) != len(As):
        raise CertificateError(f"hespanha: 'C' must list one output matrix per mode ({len(As)})")
    r = _defin(P, strict=True)
    if not r.holds:
        return _fail("hespanha", "P > 0", r)
    for nm, A, Craw in zip(names, As, Cs):
        C = fraction_matrix(Craw, what=f"C[{nm}]", cols=n)
        M = add(lyapunov_form(A, P), matmul(transpose(C), C))
        r = _defin(M, strict=False, negate=True)
        cn = _out_name(nm)
        if not r.holds:
            return _fail("hespanha", f"{nm}' P + P {nm} + {cn}' {cn} <= 0", r)
        obs, dim = observable(A, C)
        if not obs:
            return Check("hespanha", False, f"({nm}, {cn}) is not observable: the observable subspace has "
                                            f"dimension {dim} < {n}")
    return Check("hespanha", True)


def _dual_sum(As: Sequence[Matrix], Rs: Sequence[Matrix]) -> Matrix:
    n = len(As[0])
    S = [[Fraction(0)] * n for _ in range(n)]
    for A, R in zip(As, Rs):
        AR = matmul(A, R)
        S = add(S, [[AR[i][j] + AR[j][i] for j in range(n)] for i in range(n)])
    return S


def _check_dual(names: Sequence[str], As: Sequence[Matrix], cert: DualEntry) -> Check:
    n = len(As[0])
    kind = cert.kind.value
    Rs = _per_mode(cert.R, kind, "R", names, n)
    for nm, R in zip(names, Rs):
        r = _defin(R, strict=False)
        if not r.holds:
            return _fail(kind, f"R_{nm} >= 0", r)
    if all(is_zero(R) for R in Rs):
        return Check(kind, False, "all R_p are zero (the alternative needs a nonzero R_p)")
    S = _dual_sum(As, Rs)
    r = _defin(S, strict=False)
    if not r.holds:
        return _fail(kind, "sum_p (A_p R_p + R_p A_p') >= 0", r)
    if kind == "no-common-lyapunov" and is_zero(S):
        return Check(kind, False, "sum_p (A_p R_p + R_p A_p') is zero; it must be nonzero to exclude a "
                                  "non-strict common P")
    return Check(kind, True)


def _check_singular_sum(names: Sequence[str], As: Sequence[Matrix], cert: SingularSumEntry) -> Check:
    n = len(As[0])
    v = fraction_matrix([cert.v], what="singular-sum v", rows=1, cols=n)[0]
    if all(x == 0 for x in v):
        return Check("singular-sum", False, "v is zero (the kernel vector must be nonzero)")
    for i in range(n):
        if sum(A[i][j] * v[j] for A in As for j in range(n) if v[j]) != 0:
            return Check("singular-sum", False, f"(sum_p A_p) v = 0 fails: entry {i + 1} is nonzero")
    return Check("singular-sum", True)


def _check_dwell(names: Sequence[str], As: Sequence[Matrix], cert: DwellTimeEntry) -> Check:
    n = len(As[0])
    T = to_fraction(cert.tau_D, what="dwell-time tau_D")
    if T <= 0:
        return Check("dwell-time", False, f"tau_D = {T} must be positive")
    if max(inf_norm(A) for A in As) * T > 2 ** MAX_DWELL_BITS:
        return Check("dwell-time", False, f"||A_p||_inf * tau_D exceeds 2^{MAX_DWELL_BITS} (limit "
                                          "MAX_DWELL_BITS): exp(A_p tau_D) is not enclosed; certify a smaller tau_D")
    Ps = _per_mode(cert.P, "dwell-time", "P", names, n)
    for nm, A, P in zip(names, As, Ps):
        r = _defin(P, strict=True)
        if not r.holds:
            return _fail("dwell-time", f"P_{nm} > 0", r)
        r = _defin(lyapunov_form(A, P), strict=True, negate=True)
        if not r.holds:
            return _fail("dwell-time", f"{nm}' P_{nm} + P_{nm} {nm} < 0", r)
    for p, (nm, A, P) in enumerate(zip(names, As, Ps)):
        for q, (nq, Pq) in enumerate(zip(names, Ps)):
            if p == q:
                continue
            claim = f"exp({nm}' tau_D) P_{nq} exp({nm} tau_D) - P_{nm} < 0"
            ok, reason = _jump_condition(A, T, Pq, P)
            if not ok:
                return Check("dwell-time", False, f"{claim} fails: {reason}")
    return Check("dwell-time", True)


def _jump_condition(A: Matrix, T: Fraction, Pq: Matrix, Pp: Matrix) -> tuple[bool, str]:
    """``exp(A'T) Pq exp(AT) - Pp < 0`` with a rigorous enclosure, refining the precision twice.

    With ``E = Ê / 2^w + Delta`` and ``||Delta||_inf <= err``:
    ``E' Pq E <= Ê' Pq Ê / 4^w + eta I`` where
    ``eta = 2 ||Ê||_2 ||Pq||_2 d + ||Pq||_2 d^2``, ``d = sqrt(n) err`` bounds ``||Delta||_2``,
    ``||Ê||_2 <= (||Ê||_1 + ||Ê||_inf) / 2`` and ``||Pq||_2 <= ||Pq||_inf``.  All
    products are done on integers (``Pq = Nq / dq``, ``Pp = Np / dp``).
    """
    n = len(A)
    Nq, dq = integer_form(Pq)
    Np, dp = integer_form(Pp)
    p2 = inf_norm(Pq)
    reason = ""
    for bits in (128, 256, 512):
        E_int, w, err = expm_enclosure(A, T, bits)
        # 4^w dq dp (Ê'PqÊ/4^w - Pp) = dp Ê' Nq Ê - 4^w dq Np
        core = matmul(matmul(transpose(E_int), Nq), E_int)
        big = (1 << (2 * w)) * dq
        nominal = [[dp * core[i][j] - big * Np[i][j] for j in range(n)] for i in range(n)]
        r = definiteness([[-x for x in row] for row in nominal], strict=True)
        if not r.holds:
            return False, r.reason
        d2 = sqrt_upper(Fraction(n)) * err
        e2 = Fraction(inf_norm(transpose(E_int)) + inf_norm(E_int), 2 << w)
        eta = 2 * e2 * p2 * d2 + p2 * d2 * d2
        shift = -((-eta * big * dp).numerator // (eta * big * dp).denominator)  # ceil: eta I, same scaling
        r = definiteness([[-nominal[i][j] - (shift if i == j else 0) for j in range(n)] for i in range(n)],
                         strict=True)
        if r.holds:
            return True, ""
        reason = (f"the nominal inequality holds but the enclosure of exp(A tau_D) (error about "
                  f"2^{err.numerator.bit_length() - err.denominator.bit_length()}) "
                  f"is too wide to decide it ({r.reason})")
    return False, reason


def planar_case_exact(A1: Matrix, A2: Matrix) -> str:
    """Balde–Boscain–Mason case (``"i"``..``"iv"``) of a Hurwitz 2x2 pair, decided in exact arithmetic.

    ``Gamma = (tr A1 tr A2 - tr(A1 A2)) / 2`` is compared with
    ``-sqrt(det A1 det A2)`` and ``tr(A1 A2)`` with ``-2 sqrt(det A1 det A2)``
    by comparing squares, so no square root is ever taken.
    """
    tr1 = A1[0][0] + A1[1][1]
    tr2 = A2[0][0] + A2[1][1]
    d1 = A1[0][0] * A1[1][1] - A1[0][1] * A1[1][0]
    d2 = A2[0][0] * A2[1][1] - A2[0][1] * A2[1][0]
    P = matmul(A1, A2)
    t12 = P[0][0] + P[1][1]
    if not (tr1 < 0 < d1 and tr2 < 0 < d2):
        raise CertificateError("planar classification needs two Hurwitz 2x2 matrices "
                               f"(tr, det) = ({tr1}, {d1}) and ({tr2}, {d2})")
    gamma = (tr1 * tr2 - t12) / 2
    dd = d1 * d2
    if gamma < 0 and gamma * gamma > dd:
        return "i"
    if gamma < 0 and gamma * gamma == dd:
        return "ii"
    if t12 >= 0 or t12 * t12 < 4 * dd:
        return "iii"
    return "iv"


# ------------------------------------------------------------------- verdict
def implied_verdict(holding: Sequence[str], planar_case: str | None = None,
                    dwell: Sequence[Fraction] = ()) -> Verdict:
    """The verdict implied by the certificate kinds that hold (and the exact planar case, if any)."""
    strict = CertificateKind.STRICT_CQLF in holding or planar_case == "iii"
    hesp = CertificateKind.HESPANHA in holding
    if strict:
        arbitrary = ArbitrarySwitching.UGES
    elif planar_case == "ii":
        arbitrary = ArbitrarySwitching.UGS_NOT_UGES
    elif planar_case == "i":
        arbitrary = ArbitrarySwitching.UNBOUNDED
    elif hesp:
        arbitrary = ArbitrarySwitching.UGS
    else:
        arbitrary = ArbitrarySwitching.UNKNOWN
    if strict or hesp:
        dwell_time = ANY_DWELL
    elif dwell:
        dwell_time = str(min(dwell))
    else:
        dwell_time = None
    if strict:
        cqlf = Existence.EXISTS
    elif {CertificateKind.NO_STRICT_CQLF, CertificateKind.NO_COMMON_LYAPUNOV, CertificateKind.SINGULAR_SUM} \
            & set(holding) \
            or planar_case in ("i", "ii", "iv"):
        cqlf = Existence.NONE
    else:
        cqlf = Existence.UNKNOWN
    if strict or hesp:
        common = Existence.EXISTS
    elif CertificateKind.NO_COMMON_LYAPUNOV in holding or planar_case == "i":
        common = Existence.NONE
    else:
        common = Existence.UNKNOWN
    return Verdict(arbitrary, dwell_time, cqlf, common)


def verify_certificate(doc: Mapping[str, Any] | str | Path, *, model: Any = None,
                       arithmetic: str = "exact") -> VerificationReport:
    """Re-check a certificate exactly, from its matrices alone.

    Parameters
    ----------
    doc : mapping, or path of a JSON file
    model : Model, optional
        The model the certificate should be about; its ``A`` and ``C`` at the
        recorded parameter values are compared with the ``observer`` section.
        By default the built-in model named in ``provenance.model`` (if any).
    arithmetic : {"exact", "interval"}
        Both decide the same way (see :data:`switchobs.exact.ARITHMETICS`): definiteness by
        an LDL' in arb balls (outward rounding), a proof where it decides, and the exact
        elimination elsewhere.  The name is shown in the report.

    Returns
    -------
    VerificationReport
        ``holds`` is True iff every certificate in the document holds exactly,
        the claimed ``verdict`` equals the verdict they imply, and the observer
        is the model's (when that can be checked); ``unchecked`` lists the
        links that could not be checked.

    Raises
    ------
    CertificateError
        If the document is malformed (unknown kind, wrong shapes, entries
        that are not rational numbers).

    Examples
    --------
    >>> doc = {"format": "switchobs-certificate", "version": 1,
    ...        "family": {"names": ["A1"], "matrices": [[["-1"]]]},
    ...        "certificates": [{"kind": "strict-cqlf", "P": [["1"]]}],
    ...        "verdict": {"arbitrary_switching": "UGES", "dwell_time": "any",
    ...                    "strict_cqlf": "exists", "common_lyapunov": "exists"}}
    >>> verify_certificate(doc).holds
    True
    """
    with _arithmetic(arithmetic):
        return _verify(doc, arithmetic, model)


def _verify(doc: Mapping[str, Any] | str | Path, how: str, model: Any) -> VerificationReport:
    if not isinstance(doc, Mapping):
        doc = load_certificate(doc)
    document = CertificateDocument.from_json(doc)
    _check_cost(doc, len(document.family.matrices[0]))
    names, As = _family(document.family)
    checks = [section.check(names, As) for section in document.sections.values()]
    link, unchecked = model_link(document, model)
    if link is not None:
        checks.append(link)
    holding: list[str] = []
    dwell: list[Fraction] = []
    planar: str | None = None
    for cert in document.certificates:
        kind = cert.kind
        progress(f"verify: {kind.value} certificate (n = {len(As[0])}, {len(As)} modes)")
        if kind is not CertificateKind.PLANAR:
            c = check_entry(names, As, cert)
            if kind is CertificateKind.DWELL_TIME and c.holds:
                dwell.append(to_fraction(cert.tau_D, what="dwell-time tau_D"))
        else:
            if len(As) != 2 or len(As[0]) != 2:
                c = Check("planar", False, "the planar classification needs exactly two 2x2 matrices")
            else:
                case = planar_case_exact(As[0], As[1])
                claimed = cert.case
                c = Check("planar", case == claimed,
                          "" if case == claimed else f"claimed case {claimed!r} but the exact case is {case!r}")
                if c.holds:
                    planar = case
        checks.append(c)
        if c.holds:
            holding.append(kind)
    implied = implied_verdict(holding, planar, dwell)
    claimed = document.verdict
    if claimed != implied:
        diff = [k for k, v in implied.to_json().items() if claimed.to_json()[k] != v]
        checks.append(Check("verdict", False, "the claimed verdict differs from the one the certificates imply "
                            f"in {sorted(diff)}: claimed {claimed.to_json()}, implied {implied.to_json()}"))
    else:
        checks.append(Check("verdict", True))
    observer = document.sections.get(ObserverSection.KEY)
    gains = {} if observer is None else {k: tuple(_text(x) for x in getattr(observer, k))
                                         for k in ("K_plus", "K_minus")}
    parameters = document.provenance.get("parameters")
    return VerificationReport(holds=all(c.holds for c in checks), checks=tuple(checks), implied=implied,
                              claimed=claimed, model=_text(document.provenance.get("model"), none=True),
                              parameters={_text(k): _text(v) for k, v in parameters.items()}
                              if isinstance(parameters, Mapping) else {},
                              gains=gains, unchecked=unchecked, arithmetic=how)


@contextmanager
def checked_once() -> Iterator[None]:
    """Inside the block every certificate entry is checked once: :func:`check_entry` records its verdicts.

    ``certify`` decides its candidates with :func:`check_entry` (the verifier's own checks, not a
    producer's copy of them) and then verifies the document it wrote: an entry of that document
    equal to a candidate already decided (the same family and the same rationals) is
    not eliminated again.  Everything else (the verdict, the sections, the model link) is checked
    by :func:`verify_certificate` as always; ``switchobs verify`` and a call outside this block
    decide every entry afresh.
    """
    token = _DECIDED.set({})
    try:
        yield
    finally:
        _DECIDED.reset(token)


#: The fields each kind of entry is checked from (margins, methods and solver names are not).
_CHECKED_FIELDS = {CertificateKind.STRICT_CQLF: ("P",), CertificateKind.HESPANHA: ("P", "C"),
                   CertificateKind.NO_STRICT_CQLF: ("R",), CertificateKind.NO_COMMON_LYAPUNOV: ("R",),
                   CertificateKind.SINGULAR_SUM: ("v",), CertificateKind.DWELL_TIME: ("tau_D", "P")}


def check_entry(names: Sequence[str], As: Sequence[Matrix], cert: Any) -> Check:
    """Check one certificate entry (any kind but ``planar``) exactly against the family ``As``.

    Inside :func:`checked_once` an entry already decided against the same family is not checked again.
    """
    check = {CertificateKind.STRICT_CQLF: _check_strict, CertificateKind.HESPANHA: _check_hespanha,
             CertificateKind.NO_STRICT_CQLF: _check_dual, CertificateKind.NO_COMMON_LYAPUNOV: _check_dual,
             CertificateKind.SINGULAR_SUM: _check_singular_sum, CertificateKind.DWELL_TIME: _check_dwell}[cert.kind]
    decided = _DECIDED.get()
    if decided is None:
        return check(names, As, cert)
    try:   # the rationals themselves (parsed once, then checked as parsed): a cheap hash, whatever their notation
        parsed = {f: _parsed(getattr(cert, f)) for f in _CHECKED_FIELDS[cert.kind]}
    except (SwitchobsError, TypeError, ValueError):
        return check(names, As, cert)   # malformed: the check itself names the problem
    cert = replace(cert, **parsed)
    key = (cert.kind, tuple(names), _frozen(As), *(_frozen(v) for v in parsed.values()))
    if key not in decided:
        decided[key] = check(names, As, cert)
    return decided[key]


def _parsed(value: Any) -> Any:
    """``value`` with every number an exact Fraction (nested lists kept as lists)."""
    if isinstance(value, (list, tuple)):
        return [_parsed(x) for x in value]
    if value is None or isinstance(value, Mapping):
        raise TypeError("not a number")
    return to_fraction(value)


def _frozen(value: Any) -> Any:
    return tuple(_frozen(x) for x in value) if isinstance(value, (list, tuple)) else value


def _check_cost(doc: Mapping[str, Any], n: int) -> None:
    """Refuse a certificate whose exact products would take too long, before any of them: ``n**3`` products of
    entries of ``D`` digits (``D`` those of the matrix over one common denominator), counted by
    :func:`~switchobs.exact.product_work`, against :data:`~switchobs._limits.MAX_CERTIFICATE_WORK`.
    A product skips the zeros of its sparser factor, so a family matrix's products are scaled by the share of
    its nonzero entries and a certificate matrix's (multiplied only with the family) by that of the densest
    family matrix, when smaller than its own: the normal-form matrices of a large observer have ``2n - 1``
    nonzero entries of ``n**2``.  The observer section's coordinates are costed by their own check
    (:meth:`~switchobs.certify._schema.ObserverSection.check`).  The elimination then counts its own work as it
    goes (:func:`~switchobs.exact.definiteness`): the minors it forms grow with every pivot, which no estimate
    made before it can bound tightly.
    """
    family = doc.get("family") if isinstance(doc.get("family"), Mapping) else {}
    matrices = family.get("matrices") if isinstance(family.get("matrices"), list) else []
    partner = max((_density(M) for M in matrices if isinstance(M, list)), default=1.0)
    for where, rows in _matrices(doc):
        if where.startswith("observer."):
            continue
        size = _common_digits(rows, MAX_CERTIFICATE_DIGITS * 2)
        share = _density(rows) if where.startswith("family.") else min(_density(rows), partner)
        work = product_work(n, round(size * _BITS_PER_DIGIT)) * share
        if work > MAX_CERTIFICATE_WORK:
            raise CertificateError(f"certificate '{where}': its exact check would take too long (n = {n} states, "
                                   f"a matrix of at least {size} digits over one common denominator: its products "
                                   f"alone {work:.2g} > {MAX_CERTIFICATE_WORK:.2g} = MAX_CERTIFICATE_WORK); round "
                                   "the certificate to fewer digits")


def _density(rows: Any) -> float:
    """The share of nonzero entries of a JSON matrix (1 for anything that is not a non-empty list of rows)."""
    if not (isinstance(rows, list) and rows and all(isinstance(r, list) for r in rows)):
        return 1.0
    total = sum(len(r) for r in rows)
    zeros = sum(1 for r in rows for x in r if x in ("0", 0, "-0"))
    return (total - zeros) / total if total else 1.0


#: log2(10): the bits of a decimal digit.
_BITS_PER_DIGIT = 3.3219280948873626


def _matrices(data: Any, where: str = "") -> Any:
    """``(key path, rows)`` of every matrix (a list of rows) and vector (a row) in a JSON value, provenance aside."""
    if isinstance(data, Mapping):
        for key, value in data.items():
            if key != "provenance":
                yield from _matrices(value, f"{where}.{key}" if where else str(key))
    elif isinstance(data, list):
        if data and all(isinstance(x, (str, int)) and not isinstance(x, bool) for x in data):
            yield where, [data]
        elif data and all(isinstance(r, list) and all(isinstance(x, (str, int)) for x in r) for r in data):
            yield where, data
        else:
            for i, value in enumerate(data):
                yield from _matrices(value, f"{where}[{i}]")


def _common_digits(rows: Sequence[Sequence[Any]], cap: int) -> int:
    """Digits of ``rows`` over one common denominator (an upper bound; stops once above ``cap``)."""
    common, top = 1, 0
    for row in rows:
        for entry in row:
            try:
                value = to_fraction(entry)
            except SwitchobsError:
                continue  # not a number: the check itself names it
            shared = gcd(common, value.denominator)
            if shared != value.denominator:  # a denominator the common one holds already costs one gcd, no division
                common *= value.denominator // shared
            top = max(top, digits(value.numerator))
            if digits(common) + top > cap:
                return digits(common) + top
    return digits(common) + top


def _text(value: Any, *, none: bool = False) -> Any:
    """A free-form provenance value as short text (a tampered file may hold anything there)."""
    if value is None and none:
        return None
    text = value if isinstance(value, str) else str(value)
    return text if len(text) <= 80 else text[:77] + "..."
