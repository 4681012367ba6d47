"""Symbolic design core (sympy): normal form, K_plus / K_minus, Routh–Hurwitz, common Lyapunov P.

Public API
----------
design_gains            -- the whole design and its exact certificate (GainDesign); also named ``design``
observer_normal_form    -- T, a_i and observability conditions of (A, C)
is_rational             -- a matrix of rational numbers only (the exact fast paths' test)
normal_form_design      -- the Theorem 1 design of a rational model in normal-form coordinates (NormalFormDesign)
normal_form_statement   -- that design when its coordinates are the better statement (NORMAL_FORM_DIGITS), else None
theorem1_K_minus        -- the unique K_minus of Theorem 1 (seed 004)
hoang_family_constraints-- coupling constraints of the Hoang family (seed 000 eq. (17))
hurwitz_conditions      -- Routh–Hurwitz / Liénard–Chipart conditions
routh_first_column      -- numeric Routh array of a rational characteristic polynomial
observer_form_gramian   -- structured exact solution of the observer-form Lyapunov equation
parse_spectrum          -- validated target spectrum
"""

from ._design import (GainDesign, NormalFormDesign, design, design_gains, hoang_family_constraints, minus_coefficients,
                      NORMAL_FORM_DIGITS, normal_form_design, normal_form_statement, parse_gains, plus_coefficients, theorem1_K_minus)
from ._lyapunov import naive_lyapunov, observer_form_gramian
from ._normal_form import ObserverNormalForm, is_rational, normal_form_matrix, observer_normal_form
from ._routh import hurwitz_conditions, hurwitz_determinants, is_hurwitz_exact, readable_condition, routh_first_column
from ._spectrum import LAPLACE, parse_spectrum, polynomial_coefficients, spectrum_coefficients

__all__ = [
    "GainDesign", "NormalFormDesign", "NORMAL_FORM_DIGITS", "design", "design_gains", "normal_form_design",
    "normal_form_statement", "hoang_family_constraints", "minus_coefficients", "parse_gains", "plus_coefficients",
    "theorem1_K_minus", "naive_lyapunov", "observer_form_gramian", "ObserverNormalForm", "is_rational", "normal_form_matrix",
    "observer_normal_form", "hurwitz_conditions", "hurwitz_determinants", "is_hurwitz_exact",
    "readable_condition", "routh_first_column", "LAPLACE", "parse_spectrum", "polynomial_coefficients", "spectrum_coefficients",
]
