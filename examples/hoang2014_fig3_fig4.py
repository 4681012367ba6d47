"""Seed 000 (Hoang et al. 2014) Figs. 3 and 4: the 4D XBS observer through road changes.

Reproduces: Fig. 3 -- dry -> wet at 3 s, five-phase ABS, the observer beside the loop: the estimate is
"highly perturbed by the swift road transition" and converges again "in a fraction of a second";
Fig. 4 -- dry 3 s, wet 1 s, then snow, five-phase ABS with wheel-acceleration tracking (21)-(22) fed by
the observer's XBS (in the loop): the ABS keeps cycling on all three roads.
Run: python examples/hoang2014_fig3_fig4.py [OUT_DIR]   (SWITCHOBS_FAST=1: Fig. 3 shortened to 4.5 s)
"""

import os
import sys
from dataclasses import replace
from pathlib import Path

from switchobs.loop import ObserverXbsEstimator
from switchobs.observers import xbs4_observer
from switchobs.plants import plot_braking, scenario, simulate

FAST = os.environ.get("SWITCHOBS_FAST") == "1"
OUT = Path(sys.argv[1] if len(sys.argv) > 1 else os.environ.get("SWITCHOBS_EXAMPLES_OUT", "out/examples"))
OUT.mkdir(parents=True, exist_ok=True)


def observer() -> ObserverXbsEstimator:
    # beta1 = beta2 = 100 (docs/observers.md); the XBS estimate starts at 0.5
    return ObserverXbsEstimator(xbs4_observer(100.0, 100.0), initial_state={"z2": 0.5})


fig3 = scenario("hoang-fig3")
if FAST:
    fig3 = replace(fig3, duration_s=4.5)
res3 = simulate(fig3, estimator=observer(), observer_in_loop=False)
print("Hoang et al. 2014 Fig. 3:", res3, sep="\n")
after = [r for r in res3.metrics.reconvergence if r.label == "-> hoang-wet"][0]
print(f"re-converged within 10 % {after.time_s:.3f} s after the change to the wet road (seed: a fraction of a second)")
assert res3.status == "duration" and after.time_s is not None and after.time_s < 0.5
plot_braking(res3).savefig(OUT / "hoang2014_fig3.png", dpi=110)

fig4 = scenario("hoang-fig4")
res4 = simulate(fig4, estimator=observer(), observer_in_loop=True)
print("Hoang et al. 2014 Fig. 4:", res4, sep="\n")
s = res4.series
for name, (a, b) in {"dry": (0.5, 3.0), "wet": (3.0, 4.0), "snow": (4.0, 7.0)}.items():
    sel = (s["t"] >= a) & (s["t"] < b)
    cycles = int(((s["phase"][sel][1:] == 1) & (s["phase"][sel][:-1] != 1)).sum())
    print(f"  {name}: {cycles} ABS cycles, slip {s['lambda'][sel].mean():.3f}")
    assert cycles >= 2, f"the tracking ABS stopped cycling on the {name} road"
assert all(r.time_s is not None and r.time_s < 0.5 for r in res4.metrics.reconvergence if r.label != "initial")
plot_braking(res4).savefig(OUT / "hoang2014_fig4.png", dpi=110)
print(f"plots written to {OUT / 'hoang2014_fig3.png'} and {OUT / 'hoang2014_fig4.png'}")
