"""``switchobs demo``: the main job (symbolic design of the built-in 3D ABS observer for now)."""

from __future__ import annotations

import argparse

from ..design import design
from ..model import builtin_model

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("demo", help="run the main job end to end")
    p.add_argument("--fast", action="store_true", help="shorter simulations (for CI)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    model = builtin_model("abs-xbs3")
    result = design(model, "-beta1,-beta2,-beta2")
    print(result)
    checks = result.verify()
    print("exact re-check:", ", ".join(f"{k}={'ok' if v else 'FAILED'}" for k, v in checks.items()))
    rig = result.numeric({"beta1": 40, "beta2": 60})
    print(f"TU Delft rig (a = 187.5, b = -4.375, c = 34), beta1 = 40, beta2 = 60:")
    print(f"  K_plus  = {rig['K_plus']}")
    print(f"  K_minus = {rig['K_minus']}")
    return 0 if all(checks.values()) else 1
