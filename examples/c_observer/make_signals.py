"""Record the signals an ABS controller would give the observer: t, y = x2, vx, u = dP_b/dt, true XBS.

Usage: python make_signals.py OUT.csv [DURATION_S]. The five-phase ABS brakes on the drum of seed 000
Fig. 3 (dry -> wet at 3 s); u is the mean pressure rate over each step, (P(t) - P(t - dt)) / dt.
"""

import sys
from dataclasses import replace

import numpy as np

from switchobs.plants import scenario, simulate

path, duration = sys.argv[1], float(sys.argv[2]) if len(sys.argv) > 2 else 6.0
s = simulate(replace(scenario("hoang-fig3"), duration_s=duration)).series
keep = np.concatenate([[True], np.diff(s["t"]) > 0])          # event-located steps repeat a time
t, P = s["t"][keep], s["P_b"][keep]
u = np.concatenate([[0.0], np.diff(P) / np.diff(t)])
np.savetxt(path, np.column_stack([t, s["x2"][keep], s["vx"][keep], u, s["xbs"][keep]]), delimiter=",",
           header="t,y,vx,u,xbs", comments="", fmt="%.17g")
print(f"wrote {t.size} samples to {path}")
