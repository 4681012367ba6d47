"""From dx/dt = f(x) + g(x) u, y = h(x) to the normal form dz/dt = s(y)(A z + d(y)) + b(y) u, y = C z.

Public API:

- :class:`System` -- a nonlinear system file (TOML, the safety rules of model files).
- :func:`check_transformation` -- check a candidate time scale ``s`` and coordinates ``phi``.
- :func:`search_transformation` -- find ``s`` and ``phi`` from ``f``, ``g``, ``h``, or name the failing condition.
- :class:`Transformation` -- the verdict, its derivation steps and the :class:`~switchobs.model.Model` it gives.
- :class:`Step` -- one step of the derivation.

Seed 004, Part III (the class); seed 000 eq. (4)-(7) and seed 001 eq. (2.6)
are the worked examples (``docs/transform.md``).
"""

from ._system import System
from ._transform import Step, Transformation, check_transformation, search_transformation

__all__ = ["System", "Step", "Transformation", "check_transformation", "search_transformation"]
