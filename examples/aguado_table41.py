"""Seed 001 (Aguado-Rojas) Table 4.1: the two-phase XBS ABS brakes shorter than the five-phase ABS.

Reproduces: braking distance vx(0)^2 / (2 g mean friction) of the free quarter car to 2.5 km/h on the five
roads of Table 2.1 at 60, 120 and 180 km/h, both algorithms; the two-phase ABS is shorter on every road
and speed, and our distances are those of the seed within a few per cent.
Run: python examples/aguado_table41.py [OUT_DIR]   (SWITCHOBS_FAST=1: 60 and 120 km/h only)
"""

import os
import sys
from pathlib import Path

from switchobs.plants import plot_table41, table41

FAST = os.environ.get("SWITCHOBS_FAST") == "1"
OUT = Path(sys.argv[1] if len(sys.argv) > 1 else os.environ.get("SWITCHOBS_EXAMPLES_OUT", "out/examples"))
OUT.mkdir(parents=True, exist_ok=True)

result = table41(speeds_kmh=(60.0, 120.0) if FAST else (60.0, 120.0, 180.0))   # two-phase on the true XBS
print(result)
assert result.two_phase_always_shorter, "the two-phase ABS should brake shorter on every road and speed"
worst = max(abs(r.two_phase_m / r.seed_two_phase_m - 1) for r in result.rows)
print(f"largest relative difference to the seed's two-phase distances: {100 * worst:.1f} %")
assert worst < 0.05
plot_table41(result).savefig(OUT / "aguado_table41.png", dpi=110)
print(f"plot written to {OUT / 'aguado_table41.png'}")
