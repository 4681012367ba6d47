"""Design and certify the switched observer of your own model (examples/my_model.toml).

Reproduces: seed 004 Theorem 1 on a user model -- A_plus = A - K_plus C and A_minus = -A + K_minus C
get the requested spectrum and one common Lyapunov matrix P; the numeric certificate is re-checked from
its JSON file exactly as `switchobs verify` does; the error decays in the rescaled time for an
arbitrary switching sequence while V = e'Pe never increases.
Run: python examples/design_my_model.py [OUT_DIR]   (SWITCHOBS_FAST=1 for a shorter run)
"""

import os
import sys
from pathlib import Path

import numpy as np
from scipy.linalg import expm

from switchobs.certify import certify_model, verify_certificate
from switchobs.design import design
from switchobs.model import load_model

FAST = os.environ.get("SWITCHOBS_FAST") == "1"
OUT = Path(sys.argv[1] if len(sys.argv) > 1 else os.environ.get("SWITCHOBS_EXAMPLES_OUT", "out/examples"))
OUT.mkdir(parents=True, exist_ok=True)

model = load_model(Path(__file__).with_name("my_model.toml"))
symbolic = design(model, "-beta1,-beta2,-beta2")              # gains as formulas in a, b, c, k, beta
print(f"{model}\n  K_plus  = {list(symbolic.K_plus)}\n  K_minus = {list(symbolic.K_minus)}  (Theorem 1)")
assert all(symbolic.verify().values()), "the exact re-check of the symbolic design failed"

spectrum = "-20,-30,-30"
report = certify_model(model, spectrum=spectrum, dwell=not FAST)
print(report)
report.write(OUT / "my_model_certificate.json")
check = verify_certificate(OUT / "my_model_certificate.json")
print(check)
assert report.certified and check.holds

numeric = design(model.numeric(), spectrum).numeric()
for name in ("A_plus", "A_minus"):
    eig = np.sort(np.linalg.eigvals(numeric[name]).real)
    assert np.allclose(eig, [-30, -30, -20], atol=1e-3), (name, eig)

# error dynamics de/dtau = A_sigma e under a random switching sequence, V = e'Pe
rng = np.random.default_rng(1)
A, P = {1: numeric["A_plus"], -1: numeric["A_minus"]}, numeric["P"]
e0 = np.array([1.0, -0.5, 20.0])
e, tau, rows, V = e0, 0.0, [(0.0, np.linalg.norm(e0))], [float(e0 @ P @ e0)]
for _ in range(15 if FAST else 60):
    dtau, sigma = rng.uniform(0.02, 0.2), rng.choice([1, -1])
    for h in np.linspace(0.0, dtau, 11)[1:]:
        x = expm(A[sigma] * h) @ e
        rows.append((tau + h, np.linalg.norm(x)))
        V.append(float(x @ P @ x))
    e, tau = x, tau + dtau
t_rows = np.array(rows)
print(f"|e| from {np.linalg.norm(e0):.3g} to {np.linalg.norm(e):.3g} over tau = {tau:.2f}; "
      f"V = e'Pe from {V[0]:.3g} to {V[-1]:.3g}, never increasing")
assert np.all(np.diff(V) <= 1e-12 * V[0]) and V[-1] < 1e-6 * V[0]

import matplotlib  # noqa: E402
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

fig, ax = plt.subplots(figsize=(7, 4))
ax.semilogy(t_rows[:, 0], t_rows[:, 1])
ax.set_xlabel("rescaled time τ")
ax.set_ylabel("|e(τ)|")
ax.set_title(f"{model.name}: observer error under random switching, spectrum {{{spectrum}}}")
fig.tight_layout()
fig.savefig(OUT / "design_my_model.png", dpi=100)
print(f"plot written to {OUT / 'design_my_model.png'}")
