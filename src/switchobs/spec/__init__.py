"""The observer contract shared by the Python reference observers and the generated C.

Public API
----------
ObserverSpec        -- model, gains, estimated parameters and the affine split c = s d + b u (+ Psi theta),
                       checked once (linear in the unknowns, seed 001 eq. (3.2))
StepStatus          -- status codes 0-7 of one step (Python raises 1-5, C returns all)
STATUS_TEXT         -- one line per status code
REFERENCE_STATUSES  -- the codes a Python reference step can end with (0-5)
METHODS             -- discretisations: "rk4" (default), "euler"
Guard, domain_guards-- where the right-hand side is defined, with the status of each failing condition
SCALE               -- the symbol of the time scaling s in the split
"""

from ._spec import METHODS, REFERENCE_STATUSES, SCALE, STATUS_TEXT, Guard, ObserverSpec, StepStatus, domain_guards

__all__ = ["Guard", "METHODS", "ObserverSpec", "REFERENCE_STATUSES", "SCALE", "STATUS_TEXT", "StepStatus",
           "domain_guards"]
