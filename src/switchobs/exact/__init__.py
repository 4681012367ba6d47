"""Exact and interval linear algebra: the one room for rational matrix work.

Rationals (:class:`fractions.Fraction`, the type of the certificates' JSON), integer kernels on
python-flint's GMP integers, definiteness by fraction-free symmetric elimination (Sylvester's
criterion) with an ``arb`` interval first try, rank, kernels and solutions, observability, rigorous
enclosures of matrix exponentials, and the rationalisation of floating-point LMI solutions (dyadic
rounding, facial projection).  Design, synthesis, certify and the independent verifier use it; the
verifier's reasoning stays its own (it shares this arithmetic, not the producers' logic).

Public API
----------
Matrix, to_fraction, fraction_matrix, matrix_strings, identity, zeros, transpose, matmul, add, sub, scale,
lyapunov_form, integer_form, is_zero, inf_norm, float_matrix, product_work -- exact matrices as lists of rows (products on flint)
Definiteness, definiteness, ldl_psd, ARITHMETICS, arithmetic -- M > 0 / M >= 0, decided exactly; M = L D L'
rank, nullspace, solve, lyapunov_solve, observable, nonsingular, charpoly -- exact elimination (fmpq_mat, nmod_mat)
solve_float                                                   -- a solve to double precision from an enclosure
expm_enclosure, sqrt_lower, sqrt_upper                        -- rigorous bounds
dyadic, psd_dyadic, factor_rows, range_basis, project_primal, project_dual, kernel_vector,
normalise, short_sqrt_lower, MAX_PROJECTION_UNKNOWNS, FACE_TOLERANCES  -- floats to exact candidates
Interval, monomial_range, box_pieces, vertex_values, evaluate_terms, observer_pair, vertex_matrices
                                                              -- polytopes of matrices over parameter boxes
"""

from ._exact import (elimination_work, ARITHMETICS, Definiteness, Matrix, add, arithmetic, charpoly, definiteness,
                     expm_enclosure, float_matrix, fraction_matrix, identity, inf_norm, integer_form, is_zero, ldl_psd,
                     lyapunov_form, lyapunov_solve, matmul, matrix_strings, nonsingular, nullspace, observable,
                     product_work, rank, scale, solve, solve_float, sqrt_lower, sqrt_upper, sub,
                     to_fraction, transpose, zeros)
from ._polytope import (Interval, box_pieces, evaluate_terms, monomial_range, observer_pair, vertex_matrices,
                        vertex_values)
from ._rounding import (FACE_TOLERANCES, MAX_PROJECTION_UNKNOWNS, dyadic, factor_rows, kernel_vector, normalise,
                        project_dual, project_primal, psd_dyadic, range_basis, short_sqrt_lower)

__all__ = ["ARITHMETICS", "Definiteness", "Matrix", "add", "arithmetic", "charpoly", "definiteness", "elimination_work", "expm_enclosure",
           "float_matrix", "fraction_matrix", "identity", "inf_norm", "integer_form", "is_zero", "ldl_psd",
           "lyapunov_form", "lyapunov_solve", "matmul", "matrix_strings", "nonsingular", "nullspace", "observable",
           "product_work", "solve_float", "rank", "scale",
           "solve", "sqrt_lower", "sqrt_upper", "sub", "to_fraction", "transpose", "zeros", "FACE_TOLERANCES",
           "MAX_PROJECTION_UNKNOWNS", "dyadic", "factor_rows", "kernel_vector", "normalise", "project_dual",
           "project_primal", "psd_dyadic", "range_basis", "short_sqrt_lower", "Interval", "box_pieces",
           "evaluate_terms", "monomial_range", "observer_pair", "vertex_matrices", "vertex_values"]
