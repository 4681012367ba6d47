"""Noise gain against decay rate: Theorem 1 (beta) designs beside the LMI-synthesised gain pairs.

Reproduces: for abs-xbs3 at the TU Delft values (seed 000 Fig. 2), the H2 gain from encoder noise on y to
the XBS error z2 (rescaled time) of the Theorem 1 designs with every pole at -beta (seed 000 Sec. III-E;
beta = 100 is the demo's design) and of `switchobs synthesize` at the same requested decay rates and
noise weights; every LMI pair passes the exact decay and common-P checks. The plot is the front of the
issue: noise gain against the decay rate achieved (both modes have the same spectrum).
Run: python examples/noise_decay_front.py [OUT_DIR]   (SWITCHOBS_FAST=1: fewer rates)
"""

import os
import sys
from pathlib import Path

from switchobs.certify import noise_decay_front
from switchobs.model import builtin_model

FAST = os.environ.get("SWITCHOBS_FAST") == "1"
OUT = Path(sys.argv[1] if len(sys.argv) > 1 else os.environ.get("SWITCHOBS_EXAMPLES_OUT", "out/examples"))
OUT.mkdir(parents=True, exist_ok=True)

RATES = (50, 100) if FAST else (25, 50, 100, 200, 400)
WEIGHTS = (0.0, 0.001, 0.1)
points = noise_decay_front(builtin_model("abs-xbs3"), RATES, noise_weights=WEIGHTS, estimate=("z2",))
print(f"{'design':>12} {'decay rate':>10} {'noise A_plus':>12} {'noise A_minus':>13}")
for p in points:
    print(f"{p.design:>12} {p.decay_rate:10.1f} {p.noise_gain['A_plus']:12.4g} {p.noise_gain['A_minus']:13.4g}")
beta = {round(p.decay_rate): p for p in points if p.design == "beta"}
assert sorted(beta) == sorted(RATES), "a beta design decays exactly at beta"
for p in points:
    if p.design.startswith("lmi"):
        requested = min(r for r in RATES if r * 0.999 <= p.decay_rate)
        assert p.decay_rate >= requested * 0.999, "an LMI pair decays at least at the requested rate"

import matplotlib  # noqa: E402
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

fig, ax = plt.subplots(figsize=(6.5, 4.5))
for design in ["beta"] + [f"lmi W={w:g}" for w in WEIGHTS]:
    pts = sorted((p for p in points if p.design == design), key=lambda p: p.decay_rate)
    ax.plot([p.decay_rate for p in pts], [p.worst_noise_gain for p in pts], "o-" if design == "beta" else "s--",
            label="Theorem 1, all poles at -beta" if design == "beta" else f"LMI synthesis, {design[4:]}")
demo = beta[100]
ax.plot(demo.decay_rate, demo.worst_noise_gain, "r*", ms=14, label="beta = 100 (demo design)")
ax.set_xscale("log")
ax.set_yscale("log")
ax.set_xlabel("decay rate in tau (both modes)")
ax.set_ylabel("H2 gain, noise on y -> error of z2 (worse mode)")
ax.set_title("abs-xbs3: noise gain against decay rate")
ax.legend(fontsize=8)
fig.tight_layout()
fig.savefig(OUT / "noise_decay_front.png", dpi=100)
print(f"plot written to {OUT / 'noise_decay_front.png'}")
