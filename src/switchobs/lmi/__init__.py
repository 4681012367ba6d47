"""Linear matrix inequalities in floating point: cvxpy formulations and a solver driver with fallback.

The numeric half of every certificate and of the gain synthesis: the margins found here are only
candidates, rationalised and decided exactly by :mod:`switchobs.exact` and the certify layer's checker.

Public API
----------
balance, Balanced      -- a diagonal similarity by powers of two (exact) and scaling to unit norm
solve, SolveInfo       -- run a cvxpy problem with solver fallback; what the solver reported
primal_margin          -- max t: P >= t I, A_p' P + P A_p <= -t H_p, tr P = n
dual_margin            -- the theorem of alternatives of the common-P LMI
DEFAULT_SOLVERS, SCS_FIRST_FROM_N, by_size  -- which solvers are tried, in which order
"""

from ._lmi import (DEFAULT_SOLVERS, SCS_FIRST_FROM_N, Balanced, SolveInfo, balance, by_size, dual_margin,
                   primal_margin, solve)

__all__ = ["DEFAULT_SOLVERS", "SCS_FIRST_FROM_N", "Balanced", "SolveInfo", "balance", "by_size", "dual_margin",
           "primal_margin", "solve"]
