"""Numerical certification of switched error dynamics, re-checked in exact arithmetic.

cvxpy (Clarabel, then SCS) finds the matrices; every answer is rationalised
and re-checked exactly by an independent checker before it is called
certified; certificates are JSON documents that ``switchobs verify``
re-checks from their matrices alone.

Public API
----------
certify                   -- every applicable check on a family {A_p}, one verified certificate
certify_model             -- the same for a model's observer: A_plus = A - K_plus C, A_minus = -A + K_minus C
common_lyapunov           -- Hespanha's non-strict common Lyapunov condition (LMI + exact check)
strict_common_lyapunov    -- strict CQLF, or an exact dual proof that none exists
infeasibility_certificate -- the dual (theorem of alternatives) certificate alone
singular_sum              -- exact proof without an LMI that no strict CQLF exists (sum_p A_p singular)
dwell_time                -- Geromel–Colaneri dwell-time bound, bisected on tau, certified exactly
discrete_certificate      -- the sampled observer e+ = R(h A_pm) e for every step h = |s| dt (exact SOS proof
                             or exact refutation; rk4, euler, midpoint, radau3)
check_discrete            -- the exact re-check of a stored discrete section
certify_box               -- one certificate (strict common P or dwell time) for every parameter value of a box,
                             or the largest certified sub-box around the nominal point
classify_planar           -- Balde–Boscain–Mason cases i–iv with Gamma, det, tr(A1 A2) and R
verify_certificate        -- independent exact check of a certificate document
load_certificate          -- read a certificate JSON file
trajectory_conditions     -- Assumption 1 (PE, transversal zero crossings, dwell time in t and tau)
time_rescaling            -- tau(t) = ∫|s| dt
pe_level                  -- min over windows of ∫ y^2
zero_crossings            -- sign changes of y with their slopes
regressor_excitation      -- eigenvalues of windowed ∫ Psi'Psi (seed 001 Fig. 3.1)
admissible_constants      -- alpha (and dwell-time bounds for a beta) of Theorem 3, seed 004
as_family                 -- the validation gate for a family of matrices
plot_certification, plot_spectra, plot_dwell_margin, plot_planar
                          -- figures: spectra of the modes, dwell-time margin against T, planar level sets and
                             the worst-case trajectory (matplotlib Figures, ``ax=``)

Results: CertificationReport, LyapunovResult, DualCertificate, SingularSum, DwellTimeResult,
PlanarClassification, VerificationReport, TrajectoryReport, AdmissibleConstants, DiscreteCertificate,
DiscreteVerdict, BoxCertificate, ZeroCrossing, Family.

Moved, importable from here for one release: the gain synthesis (``synthesize``, ``synthesize_gains``,
``synthesize_box``, ``noise_gain``, ``noise_decay_front``, ``GainSynthesis``, ``FrontPoint``) to
:mod:`switchobs.synthesis`; ``ParameterBox`` and ``parse_box`` to :mod:`switchobs.model`.

Certificate schema (one frozen class per section, ``to_json`` / ``from_json``):
CertificateDocument, FamilySection, ObserverSection, LyapunovEntry, DualEntry,
SingularSumEntry, DwellTimeEntry, PlanarEntry, BoxSection, Verdict; enums CertificateKind, ArbitrarySwitching,
Existence; document_section registers a new optional section.
"""

# moved to switchobs.model and switchobs.synthesis; re-exported here for one release
from ..model import ParameterBox, parse_box
from ..synthesis import (FrontPoint, GainSynthesis, noise_decay_front, noise_gain, synthesize, synthesize_box,
                         synthesize_gains)
from ._box import BoxCertificate, certify_box
from ._certify import CertificationReport, certify, certify_model, verdict_text
from ._discrete import DiscreteCertificate, DiscreteVerdict, check_discrete, discrete_certificate
from ._dwell import DwellTimeResult, dwell_time
from ._family import Family, as_family
from ._lyapunov import (DEFAULT_EPS, DualCertificate, LyapunovResult, SingularSum, common_lyapunov,
                        infeasibility_certificate, singular_sum, strict_common_lyapunov)
from ._planar import PlanarClassification, classify_planar
from ._plot import plot_certification, plot_dwell_margin, plot_planar, plot_spectra
from ._schema import (ArbitrarySwitching, BoxSection, CertificateDocument, CertificateKind, DualEntry, DwellTimeEntry, Existence,
                      FamilySection, LyapunovEntry, ObserverSection, PlanarEntry, SingularSumEntry, Verdict,
                      document_section)
from ._trajectory import (AdmissibleConstants, TrajectoryReport, ZeroCrossing, admissible_constants, pe_level,
                          regressor_excitation, time_rescaling, trajectory_conditions, windowed_energy,
                          zero_crossings)
from ._verify import Check, VerificationReport, load_certificate, verify_certificate

__all__ = [
    "CertificationReport", "certify", "certify_model", "verdict_text",
    "BoxCertificate", "ParameterBox", "certify_box", "parse_box", "BoxSection",
    "FrontPoint", "GainSynthesis", "noise_decay_front", "noise_gain", "synthesize", "synthesize_gains",
    "synthesize_box",
    "DiscreteCertificate", "DiscreteVerdict", "check_discrete", "discrete_certificate",
    "DwellTimeResult", "dwell_time",
    "Family", "as_family",
    "DEFAULT_EPS", "DualCertificate", "LyapunovResult", "common_lyapunov", "infeasibility_certificate",
    "strict_common_lyapunov", "SingularSum", "singular_sum",
    "PlanarClassification", "classify_planar",
    "plot_certification", "plot_dwell_margin", "plot_planar", "plot_spectra",
    "ArbitrarySwitching", "CertificateDocument", "CertificateKind", "DualEntry", "DwellTimeEntry", "Existence",
    "FamilySection", "LyapunovEntry", "ObserverSection", "PlanarEntry", "SingularSumEntry", "Verdict",
    "document_section",
    "AdmissibleConstants", "TrajectoryReport", "ZeroCrossing", "admissible_constants", "pe_level",
    "regressor_excitation", "time_rescaling", "trajectory_conditions", "windowed_energy", "zero_crossings",
    "Check", "VerificationReport", "load_certificate", "verify_certificate",
]
