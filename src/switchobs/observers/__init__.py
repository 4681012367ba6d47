"""Reference switched observers (Python): generic, 3D / 4D XBS, switched adaptive.

Public API
----------
SwitchedObserver         -- dzhat/dt = s (A zhat + d + K(s)(y - C zhat)) + b u from any model (seed 000 (8)-(9))
AdaptiveSwitchedObserver -- switched adaptive observer of seed 001 eq. (3.4) for any linearly parametrised model
xbs3_observer            -- 3D known-road XBS observer (abs-xbs3, seed 000 Sec. III), gains from beta1, beta2
xbs4_observer            -- 4D unknown-road XBS observer (abs-xbs4, seed 000 Sec. IV), gains from beta1, beta2
adaptive_xbs_observer    -- switched adaptive XBS observer (abs-adaptive2, seed 001 Ch. 3), gains from beta, Gamma;
                            load_signal=True: a = R^2 Fz / J read each step (abs-adaptive2-load, Sec. 3.6)
xbs_gains                -- the beta-parametrised gain pairs of the built-in XBS models
ErrorCode                -- status codes of a refused step: switchobs.spec.StepStatus, shared with the generated C
METHODS                  -- discretisations: "radau3" (default of the switched observers), "midpoint" (certified,
                            switched only), "rk4" (default of the adaptive one), "euler"

Every observer has ``step(xhat, signals, dt)``, ``run(xhat0, signal_rows, dt)``,
``derivative(xhat, signals)`` and ``readout(xhat)``; signals are ordered as
``Model.signals`` (y, external signals, inputs) and held constant over a step.
To close an ABS loop on one, see :mod:`switchobs.loop`.
"""

from ._engine import METHODS, ErrorCode
from ._observer import AdaptiveSwitchedObserver, SwitchedObserver
from ._xbs import adaptive_xbs_observer, xbs3_observer, xbs4_observer, xbs_gains

__all__ = ["AdaptiveSwitchedObserver", "ErrorCode", "METHODS", "SwitchedObserver",
           "adaptive_xbs_observer", "xbs3_observer", "xbs4_observer", "xbs_gains"]
