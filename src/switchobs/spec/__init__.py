"""The observer contract shared by the Python reference observers and the generated C.

Public API
----------
ObserverSpec        -- model, gains, estimated parameters and the affine split c = s d + b u (+ Psi theta),
                       checked once (linear in the unknowns, seed 001 eq. (3.2))
StepStatus          -- status codes 0-10 of one step (Python raises 1-5 and 8, C returns all)
STATUS_TEXT         -- one line per status code
REFERENCE_STATUSES  -- the codes a Python reference step can end with (0-5)
METHODS             -- discretisations: "rk4", "euler" (explicit), "midpoint", "radau3" (implicit)
DEFAULT_METHOD      -- "radau3", the step method when none is chosen (certified for every step length)
default_method      -- radau3 where it applies (affine right-hand side, n <= IMPLICIT_MAX_N), else rk4
CERTIFIED_METHODS   -- "midpoint", "radau3": the sampled observer is certified for every step length
uncertified_note    -- one line saying that a method is not certified (None for a certified one)
StepMethod          -- a method by its stability function R = N / D
STEP_METHODS        -- name -> StepMethod, for every name of METHODS
implicit_increment  -- D(Z)^-1 F(Z) f of one implicit step of an affine ODE (floats or casadi SX alike)
affine_jacobian     -- J = s A - g C, the state Jacobian of the switched observer
require_explicit    -- refuse an implicit method where the right-hand side is not affine in the state
Guard, domain_guards-- where the right-hand side is defined, with the status of each failing condition
SCALE               -- the symbol of the time scaling s in the split
"""

from ._methods import (CERTIFIED_METHODS, DEFAULT_METHOD, METHODS, STEP_METHODS, StepMethod, affine_jacobian,
                       default_method, implicit_increment, require_explicit, uncertified_note)
from ._spec import REFERENCE_STATUSES, SCALE, STATUS_TEXT, Guard, ObserverSpec, StepStatus, domain_guards

__all__ = ["CERTIFIED_METHODS", "DEFAULT_METHOD", "Guard", "METHODS", "ObserverSpec", "REFERENCE_STATUSES", "SCALE", "STATUS_TEXT", "STEP_METHODS",
           "StepMethod", "StepStatus", "affine_jacobian", "default_method", "domain_guards", "implicit_increment",
           "require_explicit", "uncertified_note"]
