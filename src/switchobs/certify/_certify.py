"""The full certification run: every applicable check, one JSON certificate, one verdict.

:func:`certify` runs, for a family ``{A_p}``: the strict CQLF LMI (with its
dual when infeasible), Hespanha's non-strict condition, the Geromel–Colaneri
dwell time (by default only when neither of them is certified, the one case
where it changes the verdict) and, for two ``2 x 2`` matrices,
the Balde–Boscain–Mason classification.  The certificates that hold exactly
are collected in a JSON document whose verdict is the one they imply, and
the document is passed through the independent checker before it is
returned.  :func:`certify_model` builds the family ``A_plus = A - K_plus C``,
``A_minus = -A + K_minus C`` of a model's switched observer first.
"""

from __future__ import annotations

import json
import math
import time
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import sympy as sp

from .._atomic import write_text
from .._progress import progress
from ..design import GainDesign
from ..exceptions import CertificateError, FreeSymbolError, SpectrumError, StructureLostWarning, SwitchobsError
from ..model import Model, is_statespace, statespace_matrices, user_matrix
from ._box import BoxCertificate, certify_box
from ..exact import (arithmetic as exact_arithmetic, fraction_matrix, is_zero, matmul, matrix_strings,
                     short_sqrt_lower)
from ._family import Family, FamilyLike, as_family
from ._discrete import DiscreteCertificate, discrete_certificate, stability_function
from ._dwell import DwellTimeResult, dwell_time
from ..lmi import DEFAULT_SOLVERS
from ._lyapunov import (DEFAULT_EPS, LyapunovResult, SingularSum, _reading, common_lyapunov,
                        infeasibility_certificate, strict_common_lyapunov)
from ._planar import PlanarClassification, classify_planar
from ._schema import (ANY_DWELL, ArbitrarySwitching, BoxSection, CertificateDocument, CertificateKind,
                      FamilySection, DiscreteSection, ObserverSection, PlanarEntry, Verdict)
from ._verify import VerificationReport, checked_once, implied_verdict, verify_certificate

__all__ = ["CertificationReport", "certify", "certify_model", "verdict_text"]


def verdict_text(verdict: Verdict, planar: PlanarClassification | None = None) -> str:
    """One sentence for an implied verdict (and the numerical planar case iv, if any)."""
    arb = verdict.arbitrary_switching
    dwell = verdict.dwell_time
    parts = []
    if arb is ArbitrarySwitching.UGES:
        parts.append("uniformly exponentially stable under arbitrary switching (strict common quadratic "
                     "Lyapunov function)")
    else:
        if dwell == ANY_DWELL:
            parts.append("uniformly exponentially stable for every switching signal with a positive dwell time "
                         "(Hespanha, non-strict common Lyapunov function)")
        elif dwell is not None:
            parts.append(f"uniformly exponentially stable for every switching signal with dwell time >= "
                         f"{dwell} = {float(Fraction(dwell)):.6g} (Geromel-Colaneri)")
        if arb is ArbitrarySwitching.UGS:
            parts.append("uniformly stable under arbitrary switching")
        elif arb is ArbitrarySwitching.UGS_NOT_UGES:
            parts.append("under arbitrary switching: uniformly stable but not exponentially (planar case ii)")
        elif arb is ArbitrarySwitching.UNBOUNDED:
            parts.append("some fast switching signal gives unbounded trajectories (planar case i)")
        elif planar is not None and planar.case == "iv":
            parts.append(f"under arbitrary switching: {planar.verdict} (planar case iv, R = {planar.R:.6g}, "
                         "computed numerically)")
        elif not parts:
            parts.append("nothing certified")
        if not any("arbitrary" in p for p in parts) and arb is ArbitrarySwitching.UNKNOWN and dwell is not None:
            parts.append("arbitrary switching not decided")
    return "; ".join(parts)


@dataclass(frozen=True)
class CertificationReport:
    """Everything :func:`certify` found, the JSON certificate and its independent check.

    Attributes
    ----------
    family : Family
    strict : LyapunovResult
    hespanha : LyapunovResult
    dwell : DwellTimeResult or None
        Run as ``certify(..., dwell=...)`` asks.
    planar : PlanarClassification or None
        For two 2 x 2 matrices.
    document : dict
        The certificate (JSON types only); write it with :meth:`write`.
    verification : VerificationReport
        The independent exact check of ``document``.
    verdict : Verdict
        The verdict implied by the certificates that hold.
    text : str
        The verdict in one sentence.
    timings : dict
        Wall time [s] of each check.
    discrete : DiscreteCertificate or None
        The sampled observer's certificate (``certify(..., discrete=METHOD)``);
        None when not asked for or when no continuous common ``P`` is certified.
    discrete_method : str or None
        The step method asked for.
    box : BoxCertificate or None
        The certificate over a parameter box (``certify_model(..., box=...)``).
    """

    family: Family
    strict: LyapunovResult
    hespanha: LyapunovResult
    dwell: DwellTimeResult | None
    planar: PlanarClassification | None
    document: dict[str, Any]
    verification: VerificationReport
    verdict: Verdict
    text: str
    timings: dict[str, float] = field(default_factory=dict)
    discrete: DiscreteCertificate | None = None
    discrete_method: str | None = None
    box: BoxCertificate | None = None

    @property
    def discrete_certified(self) -> bool | None:
        """The sampled observer's certificate holds (None when it was not asked for)."""
        if self.discrete_method is None:
            return None
        return self.discrete is not None and self.discrete.certified and self.verification.holds

    @property
    def certified(self) -> bool:
        """Some stability certificate (strict, Hespanha or dwell time) holds and the document checks out."""
        kinds = {c["kind"] for c in self.document["certificates"]}
        stable = {CertificateKind.STRICT_CQLF, CertificateKind.HESPANHA, CertificateKind.DWELL_TIME}
        return self.verification.holds and bool(kinds & stable)

    def write(self, path: str | Path) -> None:
        """Write the certificate whole or not at all (:func:`switchobs._atomic.write_text`).

        Raises
        ------
        OutputError
            If ``path`` cannot be written; the message names it.
        """
        write_text(path, json.dumps(self.document, indent=2) + "\n", what="the certificate")

    def to_json(self) -> dict[str, Any]:
        return {"verdict": self.verdict.to_json(), "text": self.text, "certified": self.certified,
                "strict": self.strict.to_json(), "hespanha": self.hespanha.to_json(),
                "dwell_time": None if self.dwell is None else self.dwell.to_json(),
                "planar": None if self.planar is None else self.planar.to_json(),
                "verification": self.verification.to_json(), "timings": self.timings,
                "discrete": None if self.discrete is None else self.discrete.to_json(),
                "box": None if self.box is None else self.box.to_json(),
                "spectra": self.family.spectra(),
                "certificate": self.document, "discrete_method": self.discrete_method}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> "CertificationReport":
        """The report of :meth:`to_json`; the family is the one the strict check ran on.

        The family holds NumPy arrays, so compare two reports by their
        :meth:`to_json` (the exact family, certificates, document and check
        are all in it).  ``certified`` and ``spectra`` are derived, not read.

        Raises
        ------
        CertificateError
            A missing key or a malformed part; the message names the part.
        """
        if not isinstance(data, Mapping):
            raise CertificateError(f"a certification report must be an object, got {type(data).__name__}")
        with _reading("certification report"):
            strict = LyapunovResult.from_json(data["strict"])
            document = data["certificate"]
            if not isinstance(document, Mapping):
                raise CertificateError(f"a certification report's 'certificate' must be an object, got {document!r}")
            return cls(strict.family, strict, LyapunovResult.from_json(data["hespanha"]),
                       None if data["dwell_time"] is None else DwellTimeResult.from_json(data["dwell_time"]),
                       None if data["planar"] is None else PlanarClassification.from_json(data["planar"]),
                       dict(document), VerificationReport.from_json(data["verification"]),
                       Verdict.from_json(data["verdict"]), str(data["text"]),
                       {str(k): float(v) for k, v in data["timings"].items()},
                       None if data["discrete"] is None else DiscreteCertificate.from_json(data["discrete"]),
                       data.get("discrete_method"),
                       None if data["box"] is None else BoxCertificate.from_json(data["box"]))

    def __repr__(self) -> str:
        return (f"<CertificationReport: {self.family}, certified={self.certified}, "
                f"verification {'holds' if self.verification.holds else 'FAILS'}>")

    def _repr_markdown_(self) -> str:
        """The report in a notebook: spectra, the table of checks and the verdict."""
        rows = self._rows()
        table = ["| " + " | ".join(rows[0]) + " |", "|" + "---|" * len(rows[0])]
        table += ["| " + " | ".join(r) + " |" for r in rows[1:]]
        spectra = "; ".join(f"${nm.replace('_plus', '^+').replace('_minus', '^-')}$: {text}"
                            for nm, text in self.family.spectra().items())
        tail = [f"**verdict**: {self.text}",
                f"independent exact check of the certificate: **{'holds' if self.verification.holds else 'FAILS'}**"]
        if self.discrete is not None:
            tail.insert(1, f"sampled observer: {self.discrete}")
        if self.box is not None:
            tail.insert(1, str(self.box))
        return "\n".join([f"**Certification** of the {self.family} (spectra: {spectra})", "", *table, "",
                          *[t + "\n" for t in tail]])

    def to_numpy(self) -> dict[str, np.ndarray]:
        """The family's matrices by name and the certified common ``P`` (if any) as float arrays."""
        out = dict(zip(self.family.names, self.family.numeric))
        common = self.hespanha if self.hespanha.certified else self.strict if self.strict.certified else None
        if common is not None:
            out["P"] = common.P_float
        return out

    def _rows(self) -> list[tuple[str, ...]]:
        """The table of checks: (check, result, margin, solver, exact), header first."""
        rows = [("check", "result", "margin", "solver", "exact")]
        s = self.strict
        if s.certified:
            strict_res = "exists"
        elif s.dual is not None and s.dual.certified:
            strict_res = {"no-strict-cqlf": "none (dual certificate)",
                          "singular-sum": "none (A_plus + A_minus singular)" if list(self.family.names) == [
                              "A_plus", "A_minus"] else "none (sum of the A_p singular)"}.get(
                s.dual.kind, "none (not even non-strict)")
        else:
            strict_res = "not found" if not s.feasible else "feasible, not certified"
        rows.append(("strict common P", strict_res, "-" if math.isnan(s.margin) else f"{s.margin:.3g}", _solver(s),
                     _exact_col(s.certified or (s.dual is not None and s.dual.certified))))
        h = self.hespanha
        h_res = "certified" if h.certified else ("not found" if not h.feasible else "feasible, not certified")
        rows.append(("Hespanha non-strict P", h_res, "-" if math.isnan(h.margin) else f"{h.margin:.3g}", _solver(h),
                     _exact_col(h.certified)))
        if self.dwell is not None:
            d = self.dwell
            d_res = f"tau_D = {float(d.tau_D):.5g}" if d.certified and d.tau_D is not None else "not certified"
            rows.append(("dwell time (Geromel-Colaneri)", d_res, f"{d.margin:.3g}",
                         "-" if d.solver is None else d.solver.solver, _exact_col(d.certified)))
        if self.planar is not None:
            p = self.planar
            rows.append(("planar (Balde-Boscain-Mason)", f"case {p.case}: {p.stability}",
                         "-" if p.R is None else f"R={p.R:.4g}", "-", "exact" if p.case != "iv" else "R numeric"))
        return rows

    def __str__(self) -> str:
        rows = self._rows()
        widths = [max(len(r[i]) for r in rows) for i in range(5)]
        lines = ["  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in rows]
        lines.insert(1, "  ".join("-" * w for w in widths))
        head = [f"{self.family} (spectra: " + "; ".join(f"{nm} {text}" for nm, text in self.family.spectra().items())
                + ")"]
        tail = [f"verdict: {self.text}"]
        if self.box is not None:
            tail.append(str(self.box))
        if self.discrete is not None:
            tail.append(str(self.discrete))
        elif self.discrete_method is not None:
            tail.append(f"discrete certificate ({self.discrete_method}): not attempted, no continuous common "
                        "Lyapunov matrix is certified")
        tail += [
                f"independent exact check of the certificate: {'holds' if self.verification.holds else 'FAILS'}"]
        if not self.verification.holds:
            tail += [f"  {c}" for c in self.verification.checks if not c.holds]
        return "\n".join(head + lines + tail)


def _solver(r: LyapunovResult) -> str:
    return "-" if r.solver is None else r.solver.solver


def _exact_col(ok: bool) -> str:
    return "holds" if ok else "-"


def certify(family: FamilyLike, *, names: Sequence[str] | None = None, output: Any = None,
            dwell: bool | str = "auto", eps: float = DEFAULT_EPS, solvers: Sequence[str] = DEFAULT_SOLVERS,
            observer: ObserverSection | None = None, provenance: Mapping[str, Any] | None = None,
            discrete: str | None = None, box: BoxCertificate | None = None,
            candidate: tuple[Any, Sequence[Any]] | None = None, arithmetic: str = "exact") -> CertificationReport:
    """Run every applicable check on a switched family and return the verified certificate.

    Parameters
    ----------
    family : matrices, mapping name -> matrix, or Family (all Hurwitz)
    names : names of the matrices
    output : matrix, optional
        Output rows for Hespanha's LMI (the model's ``C`` for an observer).
    dwell : {"auto", True, False}
        Compute the Geromel–Colaneri dwell time: ``"auto"`` when neither a strict
        CQLF nor a Hespanha certificate holds (a Hespanha certificate already gives
        every positive dwell time, and the bisection's LMIs are ill-conditioned and
        slow for large observers), True whenever no strict CQLF is certified (the
        number itself, e.g. to compare designs), False never.
    eps : float
        Numerical margin threshold.
    solvers : cvxpy solvers in order of preference
    observer : ObserverSection, optional
        ``A``, ``C``, ``K_plus``, ``K_minus`` (rational strings): the checker then
        also re-derives ``A_plus``, ``A_minus`` from them.
    provenance : mapping, optional
        Free-form information stored in the document (model, values, spectrum).
    discrete : {"rk4", "euler", "midpoint", "radau3"}, optional
        Also certify the sampled observer of this step method for every step
        length (:func:`~switchobs.certify.discrete_certificate`, with the
        certified common ``P``); needs the family ``[A_plus, A_minus]`` and ``output``.
    box : BoxCertificate, optional
        A certificate over a parameter box (:func:`~switchobs.certify.certify_box`); when it certified a
        box, it becomes the document's ``box`` section, re-checked by ``verify``.
    candidate : (P, [C_p, ...]), optional
        An exact Hespanha certificate known beforehand (the design's common P),
        checked exactly before any LMI (see :func:`common_lyapunov`).
    arithmetic : {"exact", "interval"}
        Recorded in the document's provenance; both decide the same way (see
        :data:`switchobs.exact.ARITHMETICS`): an LDL' in arb balls with outward rounding
        first, a proof where it decides, and the exact elimination elsewhere.

    Returns
    -------
    CertificationReport

    Raises
    ------
    DimensionError, ModelError, NotHurwitzError, SolverFailure
    CertificateError
        An unknown ``discrete`` method, or ``discrete`` without ``output``; an unknown ``dwell``
        or ``arithmetic``.

    Warns
    -----
    StructureLostWarning
        The family is a float ``StateSpace`` pair exported by :meth:`GainDesign.to_statespace` whose
        rounding broke ``A_plus + A_minus = (K_minus - K_plus) C`` (seed 004 Theorem 1) and no Hespanha
        certificate holds: the verdict is the rounded pair's; certify the design itself for the design's.

    Examples
    --------
    >>> rep = certify([[[-1, -1], [1, 0]], [[-1, 1], [-1, 0]]], output=[[1, 0]])
    >>> rep.verdict.dwell_time, rep.planar.case
    ('any', 'ii')
    """
    fam = as_family(family, names)
    if dwell not in ("auto", True, False):
        raise CertificateError(f"dwell must be 'auto', True or False, got {dwell!r}")
    with exact_arithmetic(arithmetic), checked_once():  # each entry checked once: candidates and document
        report = _certify(fam, output, dwell, eps, solvers, observer, provenance, discrete, box, candidate,
                          arithmetic)
    lost = _rounded_observer_pair(family) if not report.hespanha.certified else ""
    if lost:
        warnings.warn(StructureLostWarning(lost), stacklevel=2)
    return report


def _rounded_observer_pair(family: Any) -> str:
    """The warning for a float ``StateSpace`` pair exported by :meth:`GainDesign.to_statespace`, or ``""``.

    ``to_statespace`` writes ``B = -K_plus`` for ``A_plus`` and ``B = K_minus`` for ``A_minus``, so the pair
    of a Theorem 1 design (seed 004) satisfies ``A_plus + A_minus = (K_minus - K_plus) C = (B_plus + B_minus) C``
    exactly, the structure its exact common P rests on.  Floats rounded it away when the identity fails exactly
    but holds to rounding error (relative 1e-9): then the weaker verdict is the rounding's, not the design's.
    """
    if isinstance(family, Mapping):
        family = list(family.values())
    if not isinstance(family, (list, tuple)) or len(family) != 2 or not all(map(is_statespace, family)):
        return ""
    try:
        (Ap, Bp, Cp, _), (Am, Bm, Cm, _) = (statespace_matrices(sys) for sys in family)
    except SwitchobsError:
        return ""
    if Bp.shape != (len(Ap), 1) or Bm.shape != Bp.shape or not np.array_equal(Cp, Cm):
        return ""
    scale = max(np.max(np.abs(Ap)), np.max(np.abs(Am)), np.max(np.abs((Bp + Bm) @ Cp)), 1e-300)
    exact = [fraction_matrix(M) for M in (Ap, Am, Bp + Bm, Cp)]
    residual = [[a + b - c for a, b, c in zip(ra, rb, rc)]
                for ra, rb, rc in zip(exact[0], exact[1], matmul(exact[2], exact[3]))]
    gap = float(max(abs(x) for row in residual for x in row)) / scale
    if is_zero(residual) or gap > 1e-9:
        return ""
    return ("the StateSpace pair looks like GainDesign.to_statespace's export of a Theorem 1 design, but float "
            f"rounding broke A_plus + A_minus = (K_minus - K_plus) C (off by {gap:.1e} relative), the structure "
            "of the design's exact common Lyapunov P, and no Hespanha certificate holds for the rounded pair: its "
            "verdict is not the design's; certify the design itself "
            "(certify_model(model, gains=design)) for the design's verdict")


def _certify(fam: Family, output: Any, dwell: bool | str, eps: float, solvers: Sequence[str],
             observer: ObserverSection | None, provenance: Mapping[str, Any] | None, discrete: str | None,
             box: BoxCertificate | None, candidate: tuple[Any, Sequence[Any]] | None,
             arithmetic: str) -> CertificationReport:
    if discrete is not None:
        stability_function(discrete)
        if output is None or list(fam.names) != ["A_plus", "A_minus"]:
            raise CertificateError("the discrete certificate needs the observer's family [A_plus, A_minus] and "
                                   f"its output C; got {list(fam.names)} and output {output!r}")
    size = f"n = {fam.n}, {len(fam)} modes"
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    progress(f"certify: strict common quadratic Lyapunov LMI and exact re-check ({size})")
    strict = strict_common_lyapunov(fam, eps=eps, solvers=solvers)
    timings["strict"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    progress(f"certify: Hespanha non-strict common Lyapunov LMI and exact re-check ({size})")
    hesp = common_lyapunov(fam, output=output, eps=eps, solvers=solvers, dual=False, candidate=candidate)
    timings["hespanha"] = time.perf_counter() - t0
    if not hesp.certified and isinstance(strict.dual, SingularSum):
        # the singular sum excludes a strict P only; the LMI dual may exclude every common P
        t0 = time.perf_counter()
        progress(f"certify: dual (infeasibility) LMI: is there any common Lyapunov P? ({size})")
        wider = infeasibility_certificate(fam, eps=eps, solvers=solvers)
        if wider.certified and wider.kind == CertificateKind.NO_COMMON_LYAPUNOV:
            strict = replace(strict, dual=wider)
        timings["dual"] = time.perf_counter() - t0
    dw = None
    if (dwell is True or (dwell == "auto" and not hesp.certified)) and not strict.certified:
        t0 = time.perf_counter()
        progress(f"certify: Geromel-Colaneri dwell time, bisection ({size})")
        dw = dwell_time(fam, eps=eps, solvers=solvers)
        timings["dwell_time"] = time.perf_counter() - t0
    planar = None
    if len(fam) == 2 and fam.n == 2:
        t0 = time.perf_counter()
        planar = classify_planar(fam.exact[0], fam.exact[1], names=fam.names)
        timings["planar"] = time.perf_counter() - t0
    certs = [c for c in (strict.certificate(), hesp.certificate(),
                         strict.dual.certificate() if strict.dual is not None else None,
                         dw.certificate() if dw is not None else None) if c is not None]
    if planar is not None:
        certs.append(PlanarEntry(planar.case, str(planar.gamma), planar.R, planar.verdict))
    sections: dict[str, Any] = {} if observer is None else {ObserverSection.KEY: observer}
    disc = None
    common = hesp if hesp.certified else strict if strict.certified else None
    if discrete is not None and common is not None:
        t0 = time.perf_counter()
        disc = discrete_certificate(fam.exact[0], fam.exact[1], user_matrix(output, what="output C", part="C"), common.P,
                                    method=discrete)
        sections[DiscreteSection.KEY] = DiscreteSection(disc.to_json(reasons=False))
        timings["discrete"] = time.perf_counter() - t0
    if box is not None and box.data is not None:
        sections[BoxSection.KEY] = BoxSection(box.data)
    holding = [c.kind for c in certs if c.kind is not CertificateKind.PLANAR]
    tau = [Fraction(c.tau_D) for c in certs if c.kind is CertificateKind.DWELL_TIME]
    verdict = implied_verdict(holding, planar.case if planar is not None else None, tau)
    document = CertificateDocument(FamilySection(**fam.to_json()), tuple(certs), verdict,
                                   {**(provenance or {}), "produced_by": "switchobs certify",
                                    "arithmetic": arithmetic}, sections)
    doc = document.to_json()
    t0 = time.perf_counter()
    if certs:
        progress(f"certify: independent exact check of the certificate ({size})")
        check = verify_certificate(doc, arithmetic=arithmetic)
    else:
        check = VerificationReport(False, (), verdict, verdict, arithmetic)
    timings["verify"] = time.perf_counter() - t0
    return CertificationReport(fam, strict, hesp, dw, planar, doc, check, verdict, verdict_text(verdict, planar),
                               timings, disc, discrete, box)


def certify_model(model: Model, *, values: Mapping[str, Any] | None = None, spectrum: str | Sequence | None = None,
                  gains: GainDesign | None = None, K_plus: Any = None, K_minus: Any = None,
                  dwell: bool | str = "auto",
                  eps: float = DEFAULT_EPS, solvers: Sequence[str] = DEFAULT_SOLVERS,
                  discrete: str | None = None, box: Any = None, arithmetic: str = "exact") -> CertificationReport:
    """Certify the switched observer of a numeric model (seed 004; seed 000 eq. (13)).

    The error dynamics in the rescaled time are ``A_plus = A - K_plus C`` and
    ``A_minus = -A + K_minus C``.  Give one of ``gains`` (a design, evaluated
    with :meth:`GainDesign.at`), ``spectrum`` (gains by
    :func:`switchobs.design.design_gains`, Theorem 1 of seed 004) or
    ``K_plus`` (and optionally any ``K_minus``; omitted, the Theorem 1 choice).

    Parameters
    ----------
    model : Model
        Parameters take the model's stored ``[values]``, overridden by ``values``.
    values : mapping name -> number, optional
        Parameter values, exact (``"187.5"`` is ``375/2``).
    spectrum : str or sequence, optional
        Poles of ``A_plus``, e.g. ``"-10,-20,-20"``.
    gains : GainDesign, optional
        The designed gains; a design still holding parameters is evaluated at
        the model's values (its design symbols must have values already).
    K_plus, K_minus : str or sequence, optional
        Numeric gains, e.g. ``"84,-7312/375,-64/3"`` (the command line's form).
    dwell, eps, solvers, discrete, arithmetic
        As in :func:`certify`.
    box : ParameterBox, ``["a=150:230", ...]`` or mapping, optional
        Also certify the gains for every parameter value of this box
        (:func:`~switchobs.certify.certify_box`; the largest certified sub-box when not all of it).

    Returns
    -------
    CertificationReport

    Raises
    ------
    SpectrumError
        Not exactly one of a spectrum, a design or gains.
    FreeSymbolError
        A parameter or design symbol has no value.
    ModelError
        The design is for another model (other states).
    NotHurwitzError
        ``A_plus`` or ``A_minus`` is not Hurwitz (named, with its spectrum).
    """
    from ..design import design_gains, normal_form_statement, observer_normal_form, parse_gains, theorem1_K_minus

    if K_minus is not None and K_plus is None:
        raise SpectrumError("K_minus needs K_plus (alone, K_minus is the Theorem 1 choice)")
    if sum(x is not None for x in (spectrum, gains, K_plus)) != 1:
        raise SpectrumError("give either a spectrum, a gain design or the gains K_plus [and K_minus]")
    used = {k: str(v) for k, v in model.values.items()}
    used.update({k: str(v) for k, v in (values or {}).items()})
    if gains is not None:
        if not isinstance(gains, GainDesign):
            raise SpectrumError(f"gains must be a GainDesign, got {type(gains).__name__}; give numbers as K_plus")
        gains.check_model(model)
        if not gains.is_numeric:
            gains = gains.at({k: v for k, v in used.items() if k in gains.model.parameters})
    parametric, model = model, model.with_values(dict(values or {})).numeric()
    provenance = {"model": model.name, "parameters": used,
                  "spectrum": None if spectrum is None else (spectrum if isinstance(spectrum, str)
                                                             else [str(p) for p in spectrum]),
                  "references": dict(model.references)}
    normal = normal_form_statement(model, spectrum) if spectrum is not None and box is None else None
    if normal is not None:
        observer = ObserverSection(A=matrix_strings(fraction_matrix(model.A, what="A")),
                                   C=matrix_strings(fraction_matrix(model.C, what="C")),
                                   K_plus=[str(k) for k in normal.k_plus], K_minus=[str(k) for k in normal.k_minus],
                                   T=matrix_strings(normal.T))
        # Hurwitz by construction: both modes have the characteristic polynomial prod (s - p) of the poles
        family = as_family([normal.A_plus, normal.A_minus], ["A_plus", "A_minus"], hurwitz=False)
        poles = tuple(complex(p) for p in normal.spectrum)
        return certify(replace(family, poles=(poles, poles), hurwitz=True), output=normal.C, dwell=dwell,
                       eps=eps, solvers=solvers, observer=observer, provenance=provenance, discrete=discrete,
                       candidate=(normal.P, [normal.C, normal.C]), arithmetic=arithmetic)
    design: GainDesign | None = gains
    if gains is not None:
        Kp, Km = gains.K_plus, gains.K_minus
    elif spectrum is not None:
        progress(f"certify: gains for the spectrum (n = {model.n})")
        design = design_gains(model, spectrum)
        Kp, Km = design.K_plus, design.K_minus
    else:
        Kp = parse_gains(K_plus, model, what="K_plus")
        Km = parse_gains(K_minus, model, what="K_minus") if K_minus is not None else \
            theorem1_K_minus(observer_normal_form(model), Kp)
        if not (Kp.free_symbols or Km.free_symbols):
            try:  # gains in the Hoang family come with their exact common P
                design = design_gains(model, K_plus=Kp, K_minus=None if K_minus is None else Km)
            except CertificateError:
                design = None
    A_plus = sp.Matrix(model.A - Kp * model.C)
    A_minus = sp.Matrix(-model.A + Km * model.C)
    free = sorted({str(s) for M in (A_plus, A_minus) for s in M.free_symbols})
    if free:
        raise FreeSymbolError(f"the error matrices still depend on {free}; give their values "
                              "(or a numeric spectrum, or a design evaluated with GainDesign.at)")
    observer = ObserverSection(A=matrix_strings(fraction_matrix(model.A, what="A")),
                               C=matrix_strings(fraction_matrix(model.C, what="C")),
                               K_plus=[str(x[0]) for x in fraction_matrix([[e] for e in Kp], what="K_plus")],
                               K_minus=[str(x[0]) for x in fraction_matrix([[e] for e in Km], what="K_minus")])
    robust = None if box is None else certify_box(parametric, box, Kp, Km, values=values, eps=eps, solvers=solvers)
    return certify([A_plus, A_minus], names=["A_plus", "A_minus"], output=model.C, dwell=dwell, eps=eps,
                   solvers=solvers, observer=observer, provenance=provenance, discrete=discrete, box=robust,
                   candidate=_design_candidate(design), arithmetic=arithmetic)


def _design_candidate(design: GainDesign | None) -> tuple[Any, list[Any]] | None:
    """The design's exact common P with rational outputs ``C_p``, as a Hespanha candidate.

    ``A_minus' P + P A_minus = -C_minus' C_minus`` with ``C_minus = sqrt(r) C``; for a
    Hoang-family gain ``sqrt(r)`` may be irrational, and a rational ``q <= sqrt(r)``
    keeps the (non-strict) inequality.
    """
    if design is None or design.conditional or not design.is_numeric:
        return None
    outputs = []
    for C in (design.C_plus, design.C_minus):
        scale = sp.sympify(C[0] / design.model.C[0]) if design.model.C[0] != 0 else None
        if all(sp.sympify(x).is_Rational for x in C):
            outputs.append([[sp.Rational(x) for x in C]])
        elif scale is not None and scale.is_positive and (scale**2).is_Rational:
            q = short_sqrt_lower(Fraction(str(scale**2)))
            outputs.append([[q * Fraction(str(x)) for x in design.model.C]])
        else:
            return None
    return design.P, outputs
