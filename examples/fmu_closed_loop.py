"""Close the braking loop between two FMUs in FMPy: the quarter car with its ABS, and the XBS observer.

Reproduces: `switchobs simulate hoang-fig4 --observer-impl c` (seed 000 Fig. 4: the five-phase ABS with
wheel-acceleration tracking, fed by the 4D observer of Sec. IV) as a co-simulation of the plant FMU
(`switchobs.plants.generate_plant_fmu`) and the observer FMU (`switchobs.codegen.generate_fmu`), both FMI 3.0,
stepped by FMPy's `FMU3Slave` in a loop of 1 ms communication steps.  Per step the master sets the plant's input
`xbs_hat`, steps the plant (early return allowed: a step that ends at an event or a breakpoint returns there),
feeds the observer the mean of the two samples bounding the step of `x2` and `vx` and the plant's `u_mean`, steps
it by the plant's `dt`, and reads its estimate back.  Every sample of the co-simulation equals the simulation's
bit for bit: the same integrator steps, the same observer steps, the same transitions.
SCENARIO `two-phase`: the two-phase ABS of seed 001 on the 3D observer, from 60 km/h on dry asphalt to the stop
(the shorter steps below the low speed, the stop located inside a step).
Run: python examples/fmu_closed_loop.py [OUT_DIR] [SCENARIO]   (needs fmpy and a C compiler;
SWITCHOBS_FAST=1: the first 2 s)
"""

import os
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Slave

from switchobs.codegen import generate_fmu
from switchobs.loop import EstimatorSpec, xbs_estimator
from switchobs.plants import (BrakingScenario, TwoPhaseABS, scenario, scenario_observer, scenario_observer_gains,
                              simulate)

FAST = os.environ.get("SWITCHOBS_FAST") == "1"
SHOWN = sys.argv[1] if len(sys.argv) > 1 else os.environ.get("SWITCHOBS_EXAMPLES_OUT", "out/examples")
OUT = Path(SHOWN).resolve()   # FMPy loads the binaries by absolute path
NAME = sys.argv[2] if len(sys.argv) > 2 else "hoang-fig4"
OUT.mkdir(parents=True, exist_ok=True)

if NAME == "two-phase":
    sc = BrakingScenario("dry-asphalt", speed_m_s=60 / 3.6, controller=TwoPhaseABS(), name=NAME)
    spec = EstimatorSpec("xbs3", impl="c")
else:
    sc = scenario(NAME)
    gains = scenario_observer_gains(NAME)
    spec = EstimatorSpec(scenario_observer(NAME), beta=gains.get("beta"), gamma=gains.get("gamma"), impl="c")
if FAST and NAME != "two-phase":
    sc = replace(sc, duration_s=2.0)


def estimator():
    return xbs_estimator(spec, sc.vehicle, sc.roads.initial)


# what `switchobs simulate NAME --observer-impl c` runs: the compiled loop with the generated C observer
reference = simulate(sc, estimator=estimator())

# the two FMUs
from switchobs.plants import generate_plant_fmu  # noqa: E402

est = estimator()
plant_fmu = generate_plant_fmu(sc).write(OUT / "switchobs_quarter_car.fmu")
obs_gen = est.observer.generated
obs_fmu = generate_fmu(obs_gen).write(OUT / f"{obs_gen.prefix}.fmu")


def slave(path, name, **options):
    md = read_model_description(str(path))
    s = FMU3Slave(guid=md.instantiationToken, unzipDirectory=extract(str(path), unzipdir=str(OUT / name)),
                  modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
    s.instantiate(**options)
    s.enterInitializationMode()
    return s, {v.name: v.valueReference for v in md.modelVariables}


plant, pv = slave(plant_fmu, "plant", earlyReturnAllowed=True)
plant.exitInitializationMode()
observer, ov = slave(obs_fmu, "observer")
y, vx = plant.getFloat64([pv["x2"], pv["vx"]])
est.reset(0.0, y, vx)                       # the observer's start: the first measurement in z1
x0 = est.state
observer.setFloat64([ov[f"xhat0_{n}"] for n in obs_gen.state_names], list(x0))
observer.exitInitializationMode()

SIG = [ov[n] for n in obs_gen.signal_names]
XHAT = [ov[f"xhat_{n}"] for n in obs_gen.state_names]
OUTS = [pv[n] for n in ("vx", "P_b", "x2", "xbs", "u_mean", "dt")]
t, rows = 0.0, [(0.0, vx, 0.0, y, plant.getFloat64([pv["xbs"]])[0], float("nan"),
                 plant.getInt32([pv["phase"]])[0])]
hat = est.estimate
while True:
    plant.setFloat64([pv["xbs_hat"]], [hat])
    _, terminate, _, t_new = plant.doStep(currentCommunicationPoint=t, communicationStepSize=sc.dt_s)
    if t_new == t:                          # the braking ended at the previous step
        break
    vx_new, p_b, y_new, xbs, u_mean, dt = plant.getFloat64(OUTS)
    # the observer's zero-order hold: the mean of the samples bounding the step, the step's mean pressure rate
    observer.setFloat64(SIG, [0.5 * (y + y_new), 0.5 * (vx + vx_new), u_mean])
    observer.doStep(currentCommunicationPoint=t, communicationStepSize=dt)
    hat = est.observer.readout(np.array(observer.getFloat64(XHAT)))
    t, y, vx = t_new, y_new, vx_new
    rows.append((t, vx, p_b, y, xbs, hat, plant.getInt32([pv["phase"]])[0]))
    if terminate:
        break
for s in (plant, observer):
    s.terminate()
    s.freeInstance()

co = np.array(rows)
ref = reference.series
names = ("t", "vx", "P_b", "x2", "xbs", "xbs_hat", "phase")
print(f"{NAME}: {len(co) - 1} communication steps over {co[-1, 0]:.3f} s; simulate made {reference.steps} steps "
      f"({reference.status})")
assert co.shape[0] == ref["t"].size, (co.shape, ref["t"].size)
for j, name in enumerate(names):
    if name == "xbs_hat":                   # the run's first sample has no estimate yet (NaN)
        same = np.array_equal(co[1:, j], ref[name][1:])
    else:
        same = np.array_equal(co[:, j], ref[name])
    print(f"  {name:8s} equal to simulate's bit for bit: {same}")
    assert same, name
print(f"FMUs written to {SHOWN}: {plant_fmu.name}, {obs_fmu.name}")
