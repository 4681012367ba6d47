"""From a python-control model to a certified, simulated and plotted switched observer (notebook cells).

Reproduces: seed 004 Theorem 1 from the python-control side -- a `control.StateSpace` becomes a
switchobs model whose dynamics are scaled by a measured signal v(t) that changes sign,
dz/dt = v (A z) + B u, y = C z; the gains are placed from a NumPy spectrum, the error systems of both
modes come back as `control.StateSpace` objects with the requested poles, the pair is certified
exactly (one common Lyapunov matrix P), the plant is simulated with `control.input_output_response`
and the observer error decays in the rescaled time tau = ∫|v| dt although v keeps crossing zero.
The cells (`# %%`) run in Jupyter, VS Code or as a script.
Run: python examples/python_control_notebook.py [OUT_DIR]   (SWITCHOBS_FAST=1 for a shorter run)
"""

# %% set-up
import os
import sys
from pathlib import Path

import control
import numpy as np

from switchobs.certify import certify_model
from switchobs.design import design_gains
from switchobs.model import Model
from switchobs.observers import SwitchedObserver

FAST = os.environ.get("SWITCHOBS_FAST") == "1"
OUT = Path(sys.argv[1] if len(sys.argv) > 1 and not sys.argv[1].startswith("-") else
           os.environ.get("SWITCHOBS_EXAMPLES_OUT", "out/examples"))
OUT.mkdir(parents=True, exist_ok=True)

# %% a python-control model; its drift is scaled by the measured signal v (the singular time scaling)
A = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, -2.0, -2.0]])
B = np.array([[0.0], [0.0], [1.0]])
C = np.array([[1.0, 0.0, 0.0]])
plant_lti = control.ss(A, B, C, 0)
model = Model.from_statespace(plant_lti, time_scale="v", external=["v"], name="chain3")
print(model)
assert model.signals == ("y", "v", "u1")

# %% gains from a NumPy spectrum (seed 004 Theorem 1); the error systems come back as StateSpace objects
spectrum = np.array([-2.0, -3.0, -4.0])
gains = design_gains(model, spectrum)
print(repr(gains))
for sign in ("plus", "minus"):
    err = gains.to_statespace(sign)
    poles = np.sort(control.poles(err).real)
    print(f"A_{sign} poles: {poles}")
    assert np.allclose(poles, np.sort(spectrum)), (sign, poles)

# %% exact certificate: one common Lyapunov matrix P for both modes (Hespanha, re-checked in rationals)
report = certify_model(model, gains=gains, dwell=not FAST)
print(report.text)
assert report.certified and report.verification.holds

# %% simulate the plant with python-control: dz/dt = v(t) A z + B u, v(t) = cos(t) crosses zero
T_end = 12.0 if FAST else 30.0
dt = 1e-3
t = np.arange(0.0, T_end, dt)
v = np.cos(t)
u = 0.5 * np.sin(0.7 * t)
plant = control.nlsys(lambda tt, x, uu, params: uu[0] * (A @ x) + B[:, 0] * uu[1],
                      lambda tt, x, uu, params: C @ x, inputs=["v", "u"], outputs=["y"], states=3)
z = control.input_output_response(plant, t, np.vstack([v, u]), X0=[1.0, -1.0, 0.5],
                                  solve_ivp_kwargs={"max_step": dt, "rtol": 1e-9, "atol": 1e-12}).states
y = C @ z

# %% the switched observer (K_plus while v > 0, K_minus while v < 0), started at zero
observer = SwitchedObserver(model, gains)
zhat = observer.run(np.zeros(3), np.column_stack([y[0], v, u]), dt)
error = np.linalg.norm(z[:, 1:] - zhat[:-1].T, axis=0)
tau = np.concatenate([[0.0], np.cumsum(np.abs(v[:-1]) * dt)])[1:]
print(f"|e| from {error[0]:.3g} to {error[-1]:.3g} over tau = {tau[-1]:.1f} (t = {T_end:g} s)")
assert error[-1] < 1e-2 * error[0] and np.all(np.isfinite(zhat))

# %% plot: the time scaling and the error (it levels off at the discretisation error of the 1 ms steps)
from matplotlib.figure import Figure  # noqa: E402  (no pyplot: the Figure displays itself in a notebook)

fig = Figure(figsize=(8, 5.5), layout="constrained")
ax_v, ax_e = fig.subplots(2, sharex=True)
ax_v.plot(t, v, label="v(t) = s, the time scaling")
ax_v.axhline(0.0, color="k", lw=0.6)
ax_v.legend(loc="upper right", fontsize=8)
ax_e.semilogy(t[1:], error, label="|z - ẑ|")
ax_e.set_xlabel("t [s]")
ax_e.set_ylabel("observer error")
ax_e.legend(loc="lower left", fontsize=8)
ax_v.set_title(f"{model.name}: python-control plant, switchobs observer, spectrum {spectrum.tolist()}", fontsize=9)
path = OUT / "python_control_notebook.png"
fig.savefig(path, dpi=100)
print(f"plot written to {path}")
