"""The closed ABS loop: observers and measurement chains wired to the plant simulations.

:mod:`switchobs.plants` holds the physics and the brake controllers and calls
an estimator through its port :class:`switchobs.plants.XbsEstimator`
(``reset(t0, y0, vx0)``, ``update(t, y, vx, u, dt) -> mu_hat``);
:mod:`switchobs.observers` holds generic switched observers; this package
turns the latter into the former and sets them up for a vehicle.

Public API
----------
EstimatorSpec, xbs_estimator -- an observer kind (xbs3, xbs4, adaptive, none), gains and implementation
                               (python | c) -> an estimator for a vehicle (sign conventions, initial state)
OBSERVER_KINDS, DEFAULT_BETA, DEFAULT_GAMMA, INITIAL_STATE -- the factory's choices and defaults
default_method              -- the step method of a kind when none is chosen (radau3; rk4 for the adaptive one)
ObserverXbsEstimator        -- any observer with step/readout as an estimator (mean-hold of the signals)
LoadXbsEstimator            -- the same for an observer that reads the wheel load a = R^2 Fz / J as a signal
                               (seed 001 Sec. 3.6; the two-axle vehicle feeds it the load (3.36))
SteppingObserver            -- what it needs (Python reference observers and compiled C observers qualify)
EncoderLoopEstimator        -- XBS observers fed by a simulated encoder with three-stage compensation
EncoderSamples              -- the one measurement record: the chain's signals at the controller samples;
                            EncoderLoopRecord, EncoderMeasurements and ReplayResult are subclasses of it (its
                            fields first, then what their producer adds), kept under their names
EncoderLoopRecord           -- what the encoder chain and the observers saw
EncoderX2, X2_MEASUREMENTS  -- the chain's measured x2 (TSA, notch, three-stage) as the controller's input
encoder_measurements, EncoderMeasurements -- the same chain over a whole recorded run at once (after the plant,
                            when the controller does not read the estimate), with the observer's steps
run_braking, BrakingRun, CONTROLLER_NAMES -- one braking case from plain values (road, speed, controller,
                            observer), compiled to C when possible, metrics back (what a sweep calls)
LogSignals, replay, ReplayResult, ReplaySummary -- recorded data in: a log's edges, speed and pressure (SI
                            units) through the encoder chain and an XBS observer (``switchobs replay``)
stream_replay, ReplayStream, REPLAY_CHUNK, SignalPiece, SignalSource -- the same piece by piece, each piece's
                            result handed out as it is decided, the chain's and the observer's state carried
                            across (bit for bit the same)
RateIntegral, SpeedIntegral, CounterEdges, WheelSpeedEdges -- those helpers fed in pieces (their state carried)
zero_order_hold, pressure_from_rate, speed_from_acceleration, edges_from_counts, edges_from_wheel_speed,
measurements_signals, ideal_encoder -- from what loggers record to LogSignals; a simulated run's chain inputs as one
DemoSettings, demo_scenario, demo_braking -- the braking of ``switchobs demo``
braking_record, PilRecord, reference_run, reference_observer, compare_with_reference, PilComparison, PIL_SCENARIO, PIL_TOLERANCE
                            -- the record of a processor-in-the-loop run of the generated C (a braking with a
                            road change and a sensor dropout) and its comparison with the Python reference
road_segments, segment_errors, ErrorRow, summarise_braking, BrakingSummary, SETTLE_S
                            -- estimation errors per road segment and the demo's braking summary

Example
-------
>>> from switchobs.loop import xbs_estimator
>>> from switchobs.plants import BrakingScenario, simulate
>>> sc = BrakingScenario("dry-asphalt", speed_m_s=20.0, duration_s=0.5)
>>> res = simulate(sc, estimator=xbs_estimator("xbs4", sc.vehicle, sc.roads.initial))
>>> res.observer
"SwitchedObserver of model 'abs-xbs4' (radau3, ZOH signals y, vx, u)"
"""

from ._adapter import LoadXbsEstimator, ObserverXbsEstimator, SteppingObserver
from ._braking import CONTROLLER_NAMES, BrakingRun, run_braking
from ._demo import (SETTLE_S, BrakingSummary, DemoSettings, ErrorRow, demo_braking, demo_scenario, road_segments,
                    segment_errors, summarise_braking)
from ._encoder_batch import EncoderMeasurements, EncoderSamples, encoder_measurements
from ._encoder_loop import X2_MEASUREMENTS, EncoderLoopEstimator, EncoderLoopRecord, EncoderX2
from ._pil import (PIL_SCENARIO, PIL_TOLERANCE, PilComparison, PilRecord, braking_record, compare_with_reference,
                   reference_observer, reference_run)
from ._replay import (REPLAY_CHUNK, CounterEdges, LogSignals, RateIntegral, ReplayResult, ReplayStream, ReplaySummary,
                      SignalPiece, SignalSource, SpeedIntegral, WheelSpeedEdges, edges_from_counts,
                      edges_from_wheel_speed, ideal_encoder, measurements_signals, pressure_from_rate, replay,
                      speed_from_acceleration, stream_replay, zero_order_hold)
from ._factory import (DEFAULT_BETA, DEFAULT_GAMMA, INITIAL_STATE, OBSERVER_KINDS, EstimatorSpec, compiled_observers,
                       default_method, install_observers, xbs_estimator)

__all__ = ["EstimatorSpec", "xbs_estimator", "default_method", "OBSERVER_KINDS", "DEFAULT_BETA", "DEFAULT_GAMMA", "INITIAL_STATE",
           "ObserverXbsEstimator", "LoadXbsEstimator", "SteppingObserver", "run_braking", "BrakingRun", "CONTROLLER_NAMES", "EncoderLoopEstimator", "EncoderLoopRecord",
           "EncoderX2", "X2_MEASUREMENTS", "encoder_measurements", "EncoderMeasurements", "EncoderSamples",
           "DemoSettings", "demo_scenario", "demo_braking", "road_segments", "segment_errors", "ErrorRow",
           "summarise_braking", "BrakingSummary", "SETTLE_S", "braking_record", "PilRecord", "reference_run", "reference_observer",
           "compare_with_reference", "PilComparison", "PIL_SCENARIO", "PIL_TOLERANCE",
           "LogSignals", "replay", "ReplayResult", "ReplaySummary", "stream_replay", "ReplayStream", "REPLAY_CHUNK",
           "SignalPiece", "SignalSource", "RateIntegral", "SpeedIntegral", "CounterEdges", "WheelSpeedEdges",
           "zero_order_hold", "pressure_from_rate", "speed_from_acceleration", "edges_from_counts",
           "edges_from_wheel_speed", "measurements_signals", "ideal_encoder", "compiled_observers",
           "install_observers"]
