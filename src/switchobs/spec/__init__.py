"""The observer contract shared by the Python reference observers and the generated C.

Public API
----------
ObserverSpec        -- model, gains, estimated parameters and the affine split c = s d + b u (+ Psi theta),
                       checked once (linear in the unknowns, seed 001 eq. (3.2))
StepStatus          -- status codes 0-10 of one step (Python raises 1-5 and 8, C returns all)
STATUS_TEXT         -- one line per status code
REFERENCE_STATUSES  -- the codes a Python reference step can end with (0-5)
METHODS             -- discretisations: "rk4" (default), "euler" (explicit), "midpoint", "radau3" (implicit)
StepMethod          -- a method by its stability function R = N / D
STEP_METHODS        -- name -> StepMethod, for every name of METHODS
implicit_increment  -- D(Z)^-1 F(Z) f of one implicit step of an affine ODE (floats or casadi SX alike)
affine_jacobian     -- J = s A - g C, the state Jacobian of the switched observer
require_explicit    -- refuse an implicit method where the right-hand side is not affine in the state
Guard, domain_guards-- where the right-hand side is defined, with the status of each failing condition
SCALE               -- the symbol of the time scaling s in the split
"""

from ._methods import METHODS, STEP_METHODS, StepMethod, affine_jacobian, implicit_increment, require_explicit
from ._spec import REFERENCE_STATUSES, SCALE, STATUS_TEXT, Guard, ObserverSpec, StepStatus, domain_guards

__all__ = ["Guard", "METHODS", "ObserverSpec", "REFERENCE_STATUSES", "SCALE", "STATUS_TEXT", "STEP_METHODS",
           "StepMethod", "StepStatus", "affine_jacobian", "domain_guards", "implicit_increment",
           "require_explicit"]
