"""Seed 001 (Aguado-Rojas) Sec. 4.3: Poincaré map of the two-phase XBS ABS.

Reproduces: the closed-form return map P (4.13)-(4.14) on the section z2 = chi_a agrees with the map
measured by integrating the closed loop (4.5); its fixed point zeta° in (-1, 0) is a stable limit cycle,
|P'(zeta°)| < 1, with P' the product of the four factors (4.15)-(4.18); the sufficient condition
alpha > (delta_up + 1) / kappa of Sec. 4.3.3 holds for the larger gains.
Dry asphalt (Table 2.1), z_ref = 8 m/s², chi_a = -0.1, chi_b = 0.1.
Run: python examples/poincare_two_phase.py [OUT_DIR]   (SWITCHOBS_FAST=1: fewer gains)
"""

import math
import os
import sys
from pathlib import Path

import numpy as np

from switchobs.plants import PoincareMap, road, simulate_return_map

FAST = os.environ.get("SWITCHOBS_FAST") == "1"
OUT = Path(sys.argv[1] if len(sys.argv) > 1 else os.environ.get("SWITCHOBS_EXAMPLES_OUT", "out/examples"))
OUT.mkdir(parents=True, exist_ok=True)

dry = road("dry-asphalt")
settings = dict(z_ref=8.0, chi_a=-0.1, chi_b=0.1, c=dry.c, d=dry.d)
print(f"{'kp':>6} {'zeta°':>10} {'P(zeta°)':>10} {'|P′|':>10} {'bound':>8}  analytic vs simulated P(-0.5)")
maps = {}
for kp in ((10.0, 300.0) if FAST else (10.0, 50.0, 100.0, 300.0, 3000.0)):
    P = PoincareMap.from_abs(kp=kp, **settings)
    fp = P.fixed_point()
    z_ref = settings["z_ref"]
    _, simulated = simulate_return_map(-0.5 * z_ref, kp=kp, **settings)
    rel = abs(P(-0.5) - simulated / z_ref) / abs(P(-0.5))
    print(f"{kp:6g} {fp.zeta:10.6f} {P(fp.zeta):10.6f} {abs(fp.derivative):10.4g} {fp.alpha_bound:8.2f}  {rel:.1e}")
    assert -1.0 < fp.zeta < 0.0 and math.isclose(P(fp.zeta), fp.zeta, abs_tol=1e-9)
    assert abs(fp.derivative) < 1.0, "the limit cycle should be stable"
    assert math.isclose(fp.derivative, math.prod(fp.factors), rel_tol=1e-9)
    assert rel < 1e-6, "the closed-form map (4.13) should match the integrated loop (4.5)"
    if kp > fp.alpha_bound:
        print(f"       kp = {kp:g} > {fp.alpha_bound:.2f}: sufficient condition of Sec. 4.3.3 holds")
    maps[kp] = (P, fp)

import matplotlib  # noqa: E402
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

zeta = np.linspace(-0.999, -0.01, 300)
fig, ax = plt.subplots(figsize=(6, 5))
ax.plot(zeta, zeta, "k--", lw=0.8, label="identity")
for kp, (P, fp) in maps.items():
    ax.plot(zeta, [P(z) for z in zeta], label=f"P(ζ), kp = {kp:g}")
    ax.plot(fp.zeta, fp.zeta, "o", color=ax.lines[-1].get_color())
ax.set_xlabel("ζ1° = z1 / z_ref at the start of phase 1")
ax.set_ylabel("P(ζ1°)")
ax.set_title("Aguado-Rojas 2020 (4.13): Poincaré map of the two-phase ABS, dry asphalt")
ax.legend(fontsize=8)
fig.tight_layout()
fig.savefig(OUT / "poincare_two_phase.png", dpi=100)
print(f"plot written to {OUT / 'poincare_two_phase.png'}")
