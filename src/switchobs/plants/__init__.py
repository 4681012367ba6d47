"""ABS plants, brake controllers and braking simulations (Hoang et al. 2014 Secs. II, V; Aguado-Rojas 2020 Chs. 2-4).

Tyres and roads
    :class:`Burckhardt`, :data:`ROADS`, :func:`road`, :func:`road_names`,
    :class:`ExponentialTyre`, :func:`fit_exponential`, :func:`relation19_alphas`,
    :class:`RoadChange`, :class:`RoadSchedule`
Vehicle
    :class:`QuarterCar`, :class:`BrakeActuator`, :class:`PrescribedSpeed`
Controllers
    :class:`FivePhaseABS`, :class:`SixPhaseABS` (the Bosch cycle), :class:`TwoPhaseABS`, :class:`ContinuousXbsControl`
Observer port
    :class:`XbsEstimator` (the protocol the simulations call; observers are wired to it
    by :mod:`switchobs.loop`), :class:`LoadInput` (an estimator that also reads the wheel load, fed by the
    two-axle vehicle, seed 001 Sec. 3.6), :class:`TrueXbs` (oracle), :class:`X2Measurement` (a measured ``x2``
    the controller reads, seed 001 Figs. 6.7-6.9), :class:`CompiledEstimator` and
    :class:`CompiledObserver` (an estimator's C step, run by the compiled braking loop),
    :class:`ReplayEstimator`, :data:`Replay` and :func:`replay_updates` (an estimator beside the loop,
    run over the recorded run afterwards)
Hybrid integrator (every simulated plant: quarter car, two-axle vehicle, the wheel of :mod:`switchobs.sensors`)
    :func:`integrate`, :class:`HybridPlant` (protocol), :class:`HybridRun`, :class:`Crossing`,
    :data:`MAX_CASCADE`
Simulation
    :class:`BrakingScenario`, :func:`simulate`, :class:`BrakingResult`,
    :func:`generate_plant_fmu` (the quarter car with its ABS as an FMI 3.0 co-simulation FMU),
    :class:`BrakingMetrics`, :class:`Assumption1Status`, :func:`assumption1`, :func:`distance_label` (what the
    travelled distance is called: stopping distance or distance travelled)
Two-axle vehicle (seed 001 Sec. 3.6)
    :class:`TwoAxleVehicle`, :class:`Accelerometer`, :class:`TwoAxleScenario`,
    :func:`simulate_two_axle`, :class:`TwoAxleResult`
Scenarios and figures
    :func:`scenario`, :func:`scenario_names`, :func:`scenario_observer_gains`, :func:`aguado_sec36`, :func:`table41`
    (seed 001 Table 4.1), :func:`plot_braking`, :func:`plot_two_axle`, :func:`plot_table41`
Limit cycle of the two-phase ABS
    :class:`PoincareMap` (seed 001 eqs. (4.13)-(4.14)), :func:`simulate_return_map`
"""

from ._compiled import CompiledEstimator, CompiledObserver
from ._controllers import ContinuousXbsControl, FivePhaseABS, SixPhaseABS, TwoPhaseABS
from ._fmu import PLANT_OUTPUTS, generate_plant_fmu
from ._estimator import LoadInput, Replay, ReplayEstimator, TrueXbs, X2Measurement, XbsEstimator, replay_updates
from ._hybrid import MAX_CASCADE, Crossing, HybridPlant, HybridRun, integrate
from ._plot import plot_braking, plot_table41, plot_two_axle
from ._poincare import PoincareFixedPoint, PoincareMap, simulate_return_map
from ._two_axle import Accelerometer, TwoAxleResult, TwoAxleScenario, TwoAxleVehicle, simulate_two_axle
from ._scenarios import (TABLE41_ROADS, aguado_sec36, TABLE41_SEED, TABLE41_SPEEDS_KMH, Table41Result, Table41Row, scenario,
                         scenario_description, scenario_names, scenario_observer, scenario_observer_gains, table41)
from ._metrics import Assumption1Status, BrakingMetrics, Reconvergence, assumption1, distance_label
from ._road import RoadChange, RoadSchedule
from ._simulate import SERIES, BrakingResult, BrakingScenario, simulate
from ._tyre import (D1_HOANG, D2_HOANG, ROADS, Burckhardt, ExponentialTyre, fit_exponential, relation19_alphas,
                    road, road_names)
from ._vehicle import GRAVITY, BrakeActuator, PrescribedSpeed, QuarterCar

__all__ = [
    "Burckhardt", "ROADS", "road", "road_names", "ExponentialTyre", "fit_exponential", "relation19_alphas",
    "D1_HOANG", "D2_HOANG", "RoadChange", "RoadSchedule",
    "QuarterCar", "BrakeActuator", "PrescribedSpeed", "GRAVITY", "distance_label",
    "FivePhaseABS", "SixPhaseABS", "TwoPhaseABS", "ContinuousXbsControl",
    "XbsEstimator", "LoadInput", "TrueXbs", "X2Measurement", "CompiledEstimator", "CompiledObserver",
    "ReplayEstimator", "Replay", "replay_updates", "integrate", "HybridPlant", "HybridRun", "Crossing", "MAX_CASCADE",
    "BrakingScenario", "BrakingResult", "simulate", "SERIES", "generate_plant_fmu", "PLANT_OUTPUTS",
    "BrakingMetrics", "Assumption1Status", "Reconvergence", "assumption1",
    "scenario", "scenario_names", "scenario_observer", "scenario_observer_gains", "scenario_description", "table41", "Table41Result",
    "Table41Row", "TABLE41_SEED", "TABLE41_ROADS", "TABLE41_SPEEDS_KMH", "plot_braking", "plot_table41",
    "PoincareMap", "PoincareFixedPoint", "simulate_return_map",
    "TwoAxleVehicle", "Accelerometer", "TwoAxleScenario", "TwoAxleResult", "simulate_two_axle", "aguado_sec36",
    "plot_two_axle",
]
