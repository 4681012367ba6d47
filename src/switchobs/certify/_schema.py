"""The certificate document, section by section: what ``certify`` writes and ``verify`` reads.

A certificate is a JSON object (format ``switchobs-certificate``, version 1)::

    {"format": ..., "version": 1,
     "family": FamilySection,
     "observer": ObserverSection,            optional sections, in registration order
     "certificates": [LyapunovEntry | DualEntry | SingularSumEntry | DwellTimeEntry | PlanarEntry, ...],
     "verdict": Verdict,
     "provenance": {...}}                    free-form: model, parameters, spectrum, producer

Each section is a frozen class with ``to_json`` / ``from_json``; the JSON is
exactly what earlier versions wrote (same keys, same order, same strings), so
existing certificates still verify.  Matrices stay as JSON (lists of rational
strings): the checker converts and checks them exactly, so a tampered entry
is a failed check with a reason, not a parse error.

A new optional top-level section is one class decorated with
:func:`document_section`: it gets a ``KEY``, ``to_json``, ``from_json`` and
``check(names, matrices) -> Check`` (its exact re-check, run by
``verify_certificate``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import MISSING, dataclass, field, fields
from enum import Enum
from typing import Any, ClassVar, Protocol

from .._limits import MAX_DIMENSION, check_dimension
from ..exceptions import CertificateError

__all__ = ["FORMAT", "VERSION", "CertificateKind", "ArbitrarySwitching", "Existence", "ANY_DWELL", "Verdict",
           "FamilySection", "ObserverSection", "LyapunovEntry", "DualEntry", "DwellTimeEntry", "PlanarEntry",
           "SingularSumEntry", "CertificateEntry", "CertificateDocument", "document_section", "Check",
           "DiscreteSection", "BoxSection"]

FORMAT = "switchobs-certificate"
VERSION = 1


class CertificateKind(str, Enum):
    """The ``kind`` of a certificate entry."""

    STRICT_CQLF = "strict-cqlf"
    HESPANHA = "hespanha"
    NO_STRICT_CQLF = "no-strict-cqlf"
    NO_COMMON_LYAPUNOV = "no-common-lyapunov"
    DWELL_TIME = "dwell-time"
    PLANAR = "planar"
    SINGULAR_SUM = "singular-sum"


class ArbitrarySwitching(str, Enum):
    """Stability under arbitrary switching, as the verified certificates imply it."""

    UGES = "UGES"
    UGS = "UGS"
    UGS_NOT_UGES = "UGS-not-UGES"
    UNBOUNDED = "unbounded"
    UNKNOWN = "unknown"


class Existence(str, Enum):
    """Whether a (strict) common quadratic Lyapunov function exists."""

    EXISTS = "exists"
    NONE = "none"
    UNKNOWN = "unknown"


#: ``Verdict.dwell_time`` when every positive dwell time works.
ANY_DWELL = "any"


@dataclass(frozen=True)
class Check:
    """One verified statement: ``name`` (which certificate), ``holds`` and the reason when it does not."""

    name: str
    holds: bool
    detail: str = ""

    def to_json(self) -> dict[str, Any]:
        return {"name": self.name, "holds": self.holds, "detail": self.detail}

    @classmethod
    def from_json(cls, data: Any) -> "Check":
        if not isinstance(data, Mapping) or not isinstance(data.get("holds"), bool):
            raise CertificateError(f"a check must be an object with 'name', 'holds' (true/false), 'detail'; got {data!r}")
        return cls(str(data["name"]), data["holds"], str(data.get("detail", "")))

    def __str__(self) -> str:
        return f"{self.name}: {'holds' if self.holds else 'FAILS'}{(' - ' + self.detail) if self.detail else ''}"


def _show(value: Any, limit: int = 80) -> str:
    """A JSON value for a message, shortened: a tampered file may hold megabytes."""
    text = repr(value)
    return text if len(text) <= limit else f"{text[:limit]}... ({type(value).__name__})"


def _enum(kind: type[Enum], value: Any, what: str) -> Any:
    try:
        return kind(value)
    except (ValueError, TypeError):
        raise CertificateError(f"{what} is {_show(value)}; expected one of {[k.value for k in kind]}") from None


@dataclass(frozen=True)
class Verdict:
    """What the certificates that hold imply.

    ``dwell_time`` is ``"any"`` (every positive dwell time), a rational string
    (the certified dwell time ``tau_D``) or None (nothing certified).
    """

    arbitrary_switching: ArbitrarySwitching
    dwell_time: str | None
    strict_cqlf: Existence
    common_lyapunov: Existence

    def to_json(self) -> dict[str, Any]:
        return {"arbitrary_switching": self.arbitrary_switching.value, "dwell_time": self.dwell_time,
                "strict_cqlf": self.strict_cqlf.value, "common_lyapunov": self.common_lyapunov.value}

    @classmethod
    def from_json(cls, data: Any) -> "Verdict":
        if not isinstance(data, Mapping):
            raise CertificateError(f"certificate 'verdict' must be an object, got {_show(data)}")
        keys = set(cls.__dataclass_fields__)
        if set(data) != keys:
            raise CertificateError(f"certificate 'verdict' must have the keys {sorted(keys)}, got {sorted(data)}")
        dwell = data["dwell_time"]
        if dwell is not None and not isinstance(dwell, str):
            raise CertificateError(f"verdict dwell_time is {dwell!r}; expected 'any', a rational string or null")
        return cls(_enum(ArbitrarySwitching, data["arbitrary_switching"], "verdict arbitrary_switching"), dwell,
                   _enum(Existence, data["strict_cqlf"], "verdict strict_cqlf"),
                   _enum(Existence, data["common_lyapunov"], "verdict common_lyapunov"))


# ----------------------------------------------------------------------------- sections
@dataclass(frozen=True)
class FamilySection:
    """The switched family ``{A_p}``: names and matrices (rows of rational strings)."""

    names: Sequence[Any]
    matrices: Sequence[Any]

    def to_json(self) -> dict[str, Any]:
        return {"names": list(self.names), "matrices": list(self.matrices)}

    @classmethod
    def from_json(cls, data: Any) -> "FamilySection":
        if not isinstance(data, Mapping) or "matrices" not in data:
            raise CertificateError("certificate has no 'family' with 'matrices'")
        mats = data["matrices"]
        if not isinstance(mats, list) or not mats:
            raise CertificateError(f"certificate 'family.matrices' must be a non-empty list of matrices, "
                                   f"got {_show(mats)}")
        if len(mats) > MAX_DIMENSION:
            raise CertificateError(f"certificate 'family.matrices' has {len(mats)} modes "
                                   f"(limit {MAX_DIMENSION})")
        for i, M in enumerate(mats):
            if not isinstance(M, list):
                raise CertificateError(f"certificate 'family.matrices[{i}]' must be a list of rows, got {_show(M)}")
            check_dimension(len(M), what=f"certificate 'family.matrices[{i}]'", error=CertificateError)
        names = data.get("names") or [f"A_{i + 1}" for i in range(len(mats))]
        if not isinstance(names, list) or not all(isinstance(nm, str) for nm in names):
            raise CertificateError(f"certificate 'family.names' must be a list of strings, got {_show(names)}")
        if len(names) != len(mats):
            raise CertificateError(f"'family.names' has {len(names)} names for {len(mats)} matrices")
        return cls(tuple(names), tuple(mats))


class OptionalSection(Protocol):
    """What a top-level section other than family, certificates, verdict and provenance provides."""

    KEY: ClassVar[str]

    def to_json(self) -> dict[str, Any]: ...

    @classmethod
    def from_json(cls, data: Any) -> "OptionalSection": ...

    def check(self, names: Sequence[str], matrices: Sequence[Any]) -> Check: ...


#: Optional top-level sections, by key, in the order they are written.
SECTIONS: dict[str, type[OptionalSection]] = {}


def document_section(cls: type) -> type:
    """Register an optional top-level section (written after ``family``, in registration order)."""
    SECTIONS[cls.KEY] = cls
    return cls


def _bits(M: Sequence[Sequence[Any]]) -> int:
    """Bits of the longest numerator plus the longest denominator of a Fraction matrix (its size over one
    common denominator when, as in ``T``, the denominators divide the longest)."""
    return max(x.numerator.bit_length() for row in M for x in row) + \
        max(x.denominator.bit_length() for row in M for x in row)


def _check_product_cost(pairs: Sequence[tuple[Any, Any]], *, what: str) -> None:
    """Refuse products ``X Y`` whose work exceeds :data:`~switchobs._limits.MAX_CERTIFICATE_WORK`, before any.

    Each nonzero entry of ``X`` meets a row of ``Y``; a product of a ``b``-bit and an ``s``-bit number (``b >= s``)
    is counted ``(b / 64 + 1) (s / 64 + 1) ** 0.5``, the unit of :func:`~switchobs.exact.elimination_work` for
    equal sizes.
    """
    from .._limits import MAX_CERTIFICATE_WORK

    work = 0.0
    for X, Y in pairs:
        big, small = sorted((_bits(X), _bits(Y)), reverse=True)
        nonzero = sum(1 for row in X for x in row if x)
        work += nonzero * len(Y[0]) * (big / 64 + 1) * (small / 64 + 1) ** 0.5
    if work > MAX_CERTIFICATE_WORK:
        raise CertificateError(f"certificate '{what}': its exact check would take too long (its products "
                               f"{work:.2g} > {MAX_CERTIFICATE_WORK:.2g} = MAX_CERTIFICATE_WORK); round the "
                               "certificate to fewer digits")


@document_section
@dataclass(frozen=True)
class ObserverSection:
    """The observer the family comes from: ``A``, ``C``, ``K_plus``, ``K_minus`` as rational strings.

    Its check re-derives ``A_plus = A - K_plus C`` and ``A_minus = -A + K_minus C``
    and compares them with the family.

    With ``T`` (a nonsingular matrix), the family and the gains are written in the coordinates ``z = T x``
    of the observer normal form: ``K_plus`` and ``K_minus`` are then ``T K_plus`` and ``T K_minus`` of the
    model's gains, and the check is ``T A - K_plus C = A_plus T`` and ``-T A + K_minus C = A_minus T`` with
    ``det T != 0``: the model's family ``T^-1 A_p T`` is similar to the certified one, so every stability
    certificate of one holds for the other.  A dense model's gains in its own coordinates need ``T``'s
    inverse and can be tens of thousands of digits long; in these coordinates they are not.
    """

    KEY: ClassVar[str] = "observer"
    A: Any
    C: Any
    K_plus: Any
    K_minus: Any
    T: Any = None

    def to_json(self) -> dict[str, Any]:
        out = {"A": self.A, "C": self.C, "K_plus": self.K_plus, "K_minus": self.K_minus}
        if self.T is not None:
            out["T"] = self.T
        return out

    @classmethod
    def from_json(cls, data: Any) -> "ObserverSection":
        if not isinstance(data, Mapping):
            raise CertificateError(f"certificate 'observer' must be an object, got {_show(data)}")
        for key in ("K_plus", "K_minus"):
            if not isinstance(data.get(key, []), list):
                raise CertificateError(f"certificate 'observer.{key}' must be a list of numbers, "
                                       f"got {_show(data.get(key))}")
        if "T" in data and not isinstance(data["T"], list):
            raise CertificateError(f"certificate 'observer.T' must be a list of rows, got {_show(data['T'])}")
        return cls(data.get("A"), data.get("C"), data.get("K_plus", []), data.get("K_minus", []), data.get("T"))

    def check(self, names: Sequence[str], matrices: Sequence[Any]) -> Check:
        from ..exact import add, fraction_matrix, matmul, nonsingular, scale, sub

        n = len(matrices[0])
        A = fraction_matrix(self.A, what="observer A", rows=n, cols=n)
        C = fraction_matrix(self.C, what="observer C", cols=n)
        Kp = fraction_matrix([[x] for x in self.K_plus], what="K_plus", rows=n, cols=1)
        Km = fraction_matrix([[x] for x in self.K_minus], what="K_minus", rows=n, cols=1)
        if self.T is None:
            expected = {"A_plus": sub(A, matmul(Kp, C)), "A_minus": add(scale(-1, A), matmul(Km, C))}
            for nm, M in zip(names, matrices):
                if nm in expected and expected[nm] != M:
                    which = "A - K_plus C" if nm == "A_plus" else "-A + K_minus C"
                    return Check("observer", False, f"{nm} in the family differs from {which} computed from the "
                                                    "observer's A, C and gains")
            return Check("observer", True)
        T = fraction_matrix(self.T, what="observer T", rows=n, cols=n)
        _check_product_cost([(T, A)] + [(M, T) for M in matrices], what="observer.T")
        if not nonsingular(T):
            return Check("observer", False, "the coordinates' matrix T is singular")
        TA = matmul(T, A)
        expected = {"A_plus": sub(TA, matmul(Kp, C)), "A_minus": add(scale(-1, TA), matmul(Km, C))}
        for nm, M in zip(names, matrices):
            if nm in expected and expected[nm] != matmul(M, T):
                which = "T A - K_plus C" if nm == "A_plus" else "-T A + K_minus C"
                return Check("observer", False, f"{nm} T in the family's coordinates differs from {which} computed "
                                                "from the observer's A, C, T and gains")
        return Check("observer", True)

    def model_gains(self) -> tuple[list[float], list[float]] | None:
        """``K_plus`` and ``K_minus`` in the model's coordinates (``T^-1`` of the stated ones) as the nearest
        doubles, or None without ``T`` (the stated gains are then the model's, exactly)."""
        from ..exact import fraction_matrix, solve_float

        if self.T is None:
            return None
        n = len(self.T)
        K = solve_float(fraction_matrix(self.T, what="observer T", rows=n, cols=n),
                        fraction_matrix([[p, m] for p, m in zip(self.K_plus, self.K_minus)], what="gains",
                                        rows=n, cols=2))
        return [row[0] for row in K], [row[1] for row in K]


@document_section
@dataclass(frozen=True)
class DiscreteSection:
    """The sampled observer: the step method's certificate for every ``h = |s| dt`` in ``(0, h_max]``.

    Written by ``switchobs certify --discrete METHOD``; the data is
    :meth:`switchobs.certify.DiscreteCertificate.to_json` (method, verdict,
    ``h_max`` as ``"inf"``, a rational string or ``"none"``, ``P_d``, ``C``
    and per mode an SOS decomposition or a refuting witness).  Its check
    re-derives the claim from the family's ``A_plus``, ``A_minus`` exactly.
    """

    KEY: ClassVar[str] = "discrete"
    data: Mapping[str, Any]

    def to_json(self) -> dict[str, Any]:
        return dict(self.data)

    @classmethod
    def from_json(cls, data: Any) -> "DiscreteSection":
        if not isinstance(data, Mapping):
            raise CertificateError(f"certificate 'discrete' must be an object, got {data!r}")
        for key, kind in (("method", str), ("verdict", str), ("h_max", str), ("strict", bool), ("P_d", list),
                          ("C", list), ("modes", list)):
            if not isinstance(data.get(key), kind):
                raise CertificateError(f"certificate 'discrete' needs {key!r} as a {kind.__name__}, "
                                       f"got {_show(data.get(key))}")
        return cls(dict(data))

    def check(self, names: Sequence[str], matrices: Sequence[Any]) -> Check:
        from ._discrete import check_discrete

        if list(names) != ["A_plus", "A_minus"]:
            return Check("discrete", False, f"the discrete section needs the family [A_plus, A_minus], got "
                                            f"{list(names)}")
        try:
            cert = check_discrete(matrices[0], matrices[1], self.data["C"], self.data["P_d"],
                                  self.data["method"], self.data)
        except CertificateError as exc:
            return Check("discrete", False, str(exc))
        return Check("discrete", True, f"{cert.method}: {cert.verdict.value}, h_max = {cert.h_max_text()}")


@document_section
@dataclass(frozen=True)
class BoxSection:
    """A certificate valid for every parameter value of a box (``switchobs certify --box``).

    The data is :attr:`switchobs.certify.BoxCertificate.data`: the parameters,
    nominal values, the certified box, ``A(theta)`` as one matrix per
    monomial, ``C``, the gains and the certificate (``strict-cqlf`` with ``P``
    or ``dwell-time`` with ``tau_D`` and the piecewise-linear ``P_plus``,
    ``P_minus``).  Its check rebuilds the vertex matrices and re-checks every
    inequality exactly (:mod:`switchobs.certify._box_check`).
    """

    KEY: ClassVar[str] = "box"
    data: Mapping[str, Any]

    def to_json(self) -> dict[str, Any]:
        return dict(self.data)

    @classmethod
    def from_json(cls, data: Any) -> "BoxSection":
        if not isinstance(data, Mapping):
            raise CertificateError(f"certificate 'box' must be an object, got {data!r}")
        for key, kind in (("parameters", list), ("nominal", Mapping), ("box", Mapping), ("A_terms", list),
                          ("C", list), ("K_plus", list), ("K_minus", list), ("certificate", Mapping)):
            if not isinstance(data.get(key), kind):
                raise CertificateError(f"certificate 'box' needs {key!r} as a {getattr(kind, '__name__', kind)}, "
                                       f"got {_show(data.get(key))}")
        return cls(dict(data))

    def check(self, names: Sequence[str], matrices: Sequence[Any]) -> Check:
        from ._box_check import check_box_data

        family = matrices if list(names) == ["A_plus", "A_minus"] else None
        try:
            reason = check_box_data(self.data, family)
        except (CertificateError, KeyError, TypeError, ValueError) as exc:
            return Check("box", False, f"malformed box section: {exc}")
        if reason:
            return Check("box", False, reason)
        cert = self.data["certificate"]
        what = "strict common P" if cert.get("kind") == "strict-cqlf" else f"dwell time {cert.get('tau_D')}"
        return Check("box", True, f"{what} on " + ", ".join(f"{p} in [{lo}, {hi}]" for p, (lo, hi) in
                                                             self.data["box"].items()))


# ----------------------------------------------------------------------------- certificate entries
class _Entry:
    """JSON of a certificate entry: ``kind`` first, then the fields in declaration order (the JSON keys)."""

    kind: CertificateKind

    def _writes(self, name: str) -> bool:
        return True

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"kind": self.kind.value}
        out.update({f.name: getattr(self, f.name) for f in fields(self) if f.name != "kind" and self._writes(f.name)})
        return out

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Any:
        values = {f.name: data.get(f.name, None if f.default is MISSING else f.default)
                  for f in fields(cls) if f.init}
        if "kind" in values:
            values["kind"] = CertificateKind(data["kind"])
        return cls(**values)


@dataclass(frozen=True)
class LyapunovEntry(_Entry):
    """``strict-cqlf`` (``P``) or ``hespanha`` (``P`` and one output matrix ``C_p`` per mode)."""

    kind: CertificateKind
    P: Any
    C: Any = None
    margin: float | None = None
    method: str = ""
    solver: str = ""

    def _writes(self, name: str) -> bool:
        return name != "C" or self.kind is CertificateKind.HESPANHA


@dataclass(frozen=True)
class DualEntry(_Entry):
    """``no-strict-cqlf`` or ``no-common-lyapunov``: one ``R_p >= 0`` per mode."""

    kind: CertificateKind
    R: Any
    margin: float | None = None
    method: str = ""
    solver: str = ""


@dataclass(frozen=True)
class DwellTimeEntry(_Entry):
    """``dwell-time``: ``tau_D`` (a rational string) and one ``P_p`` per mode (Geromel–Colaneri)."""

    tau_D: Any
    P: Any
    margin: float | None = None
    method: str = ""
    solver: str = ""
    kind: CertificateKind = field(default=CertificateKind.DWELL_TIME, init=False)


@dataclass(frozen=True)
class PlanarEntry(_Entry):
    """``planar``: the Balde–Boscain–Mason case, ``Gamma``, the numeric ``R`` of case iv and its verdict."""

    case: Any
    Gamma: str = ""
    R: float | None = None
    verdict: str = ""
    kind: CertificateKind = field(default=CertificateKind.PLANAR, init=False)


@dataclass(frozen=True)
class SingularSumEntry(_Entry):
    """``singular-sum``: a nonzero rational ``v`` with ``(sum_p A_p) v = 0``: no strict CQLF.

    The compact form of the ``no-strict-cqlf`` alternative with ``R_p = v v'`` for every p
    (then ``sum_p (A_p R_p + R_p A_p') = M v v' + v v' M' = 0``, ``M = sum_p A_p``).
    """

    v: Any
    method: str = ""
    kind: CertificateKind = field(default=CertificateKind.SINGULAR_SUM, init=False)


CertificateEntry = LyapunovEntry | DualEntry | DwellTimeEntry | PlanarEntry | SingularSumEntry

_ENTRIES: dict[CertificateKind, Callable[[Mapping[str, Any]], CertificateEntry]] = {
    CertificateKind.STRICT_CQLF: LyapunovEntry.from_json,
    CertificateKind.HESPANHA: LyapunovEntry.from_json,
    CertificateKind.NO_STRICT_CQLF: DualEntry.from_json,
    CertificateKind.NO_COMMON_LYAPUNOV: DualEntry.from_json,
    CertificateKind.DWELL_TIME: DwellTimeEntry.from_json,
    CertificateKind.PLANAR: PlanarEntry.from_json,
    CertificateKind.SINGULAR_SUM: SingularSumEntry.from_json,
}


def _entry(data: Any) -> CertificateEntry:
    kind = data.get("kind") if isinstance(data, Mapping) else None
    if not isinstance(kind, str) or kind not in {k.value for k in CertificateKind}:
        raise CertificateError(f"unknown certificate kind {kind!r}; known kinds: "
                               f"{', '.join(k.value for k in CertificateKind)}")
    return _ENTRIES[CertificateKind(kind)](data)


# ----------------------------------------------------------------------------- document
@dataclass(frozen=True)
class CertificateDocument:
    """A whole certificate: the family, optional sections, the entries, the claimed verdict, provenance."""

    family: FamilySection
    certificates: tuple[CertificateEntry, ...]
    verdict: Verdict
    provenance: Mapping[str, Any] = field(default_factory=dict)
    sections: Mapping[str, OptionalSection] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"format": FORMAT, "version": VERSION, "family": self.family.to_json()}
        out.update({key: self.sections[key].to_json() for key in SECTIONS if key in self.sections})
        out["certificates"] = [c.to_json() for c in self.certificates]
        out["verdict"] = self.verdict.to_json()
        out["provenance"] = dict(self.provenance)
        return out

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> "CertificateDocument":
        """Read a document; raises :class:`CertificateError` for a wrong format, version or structure."""
        if data.get("format") != FORMAT:
            raise CertificateError(f"not a switchobs certificate: format is {data.get('format')!r}, "
                                   f"expected {FORMAT!r}")
        version = data.get("version")
        if type(version) is not int or version != VERSION:  # JSON true and 1.0 equal 1 to Python
            raise CertificateError(f"unsupported certificate version {data.get('version')!r} "
                                   f"(this checker reads {VERSION})")
        family = FamilySection.from_json(data.get("family"))
        certs = data.get("certificates")
        if not isinstance(certs, list) or not certs:
            raise CertificateError("certificate has no 'certificates' list")
        sections = {key: SECTIONS[key].from_json(data[key]) for key in SECTIONS if data.get(key) is not None}
        provenance = data.get("provenance") or {}
        if not isinstance(provenance, Mapping):
            raise CertificateError(f"certificate 'provenance' must be an object, got {_show(provenance)}")
        # free-form, but the keys the model link reads must have their type: a wrong one is no link at all
        for key, kind, what in (("model", str, "a model name (text)"), ("parameters", Mapping, "an object")):
            if provenance.get(key) is not None and not isinstance(provenance[key], kind):
                raise CertificateError(f"certificate 'provenance.{key}' must be {what}, got {_show(provenance[key])}")
        return cls(family, tuple(_entry(c) for c in certs), Verdict.from_json(data.get("verdict")),
                   dict(provenance), sections)
