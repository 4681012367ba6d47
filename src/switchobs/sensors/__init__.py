"""Wheel-encoder measurement chain: from the teeth to the wheel speed, acceleration and ``x2``.

Seed 001 Chapters 5-6 and Appendix C (time-stamping algorithm, encoder
imperfections, three-stage harmonic compensation, notch baseline) and seed 003
(super-twisting observer, equivalent output injection, stiffness and radius
identification).

Trajectories
    AngleTrajectory, constant_speed, varying_speed, trapezoid_speed, rpm_to_rad_s
Encoder
    Encoder, EncoderEvents
Time-stamping algorithm
    time_stamping, TsaEstimate, tsa_condition_number, controller_times, TimeStamper
Harmonic compensation
    ThreeStageEstimator, three_stage, NotchFilter, notch, notch_series, SpeedEstimate
Super-twisting observer and identification
    SuperTwistingGains, super_twisting_gains, SuperTwistingObserver, super_twisting,
    SuperTwistingRun, low_pass, StiffnessEstimate, identify_stiffness
Sliding-mode observer of the vehicle speed and identification of theta_2 (seed 003 Secs. III-B, V-B)
    VehicleSpeedGain, vehicle_speed_gain, VehicleSpeedObserver, vehicle_speed_observer, VehicleSpeedRun,
    SpeedParameterEstimate, identify_speed_parameters
Torque-driven quarter car (vehicle and roads of switchobs.plants)
    WheelRun, simulate_wheel, braking_trajectory, linear_tyre, burckhardt_tyre
Chain
    encoder_chain, compare_estimators, ChainSettings, ChainResult, EstimatorComparison,
    ESTIMATORS, rms_error, estimate_lag, plot_comparison (a matplotlib Figure)
Seed 001 Table 6.1
    TABLE61_SEED, TABLE61_ENCODER, TABLE61_PROFILES, ROBUSTNESS_PROFILES (300-1500 rpm)
"""

from ._chain import (ESTIMATORS, ROBUSTNESS_PROFILES, TABLE61_ENCODER, TABLE61_PROFILES, TABLE61_SEED, ChainResult, ChainSettings,
                     EstimatorComparison, compare_estimators, encoder_chain)
from ._encoder import Encoder, EncoderEvents
from ._identify import SpeedParameterEstimate, StiffnessEstimate, identify_speed_parameters, identify_stiffness
from ._plot import plot_comparison
from ._quarter_car import WheelRun, braking_trajectory, burckhardt_tyre, linear_tyre, simulate_wheel
from ._series import SpeedEstimate, estimate_lag, rms_error
from ._super_twisting import (SuperTwistingGains, SuperTwistingObserver, SuperTwistingRun, low_pass,
                              super_twisting, super_twisting_gains)
from ._three_stage import NotchFilter, ThreeStageEstimator, notch, notch_series, three_stage
from ._trajectory import AngleTrajectory, constant_speed, rpm_to_rad_s, trapezoid_speed, varying_speed
from ._vehicle_speed import (VehicleSpeedGain, VehicleSpeedObserver, VehicleSpeedRun, vehicle_speed_gain,
                             vehicle_speed_observer)
from ._tsa import TimeStamper, TsaEstimate, controller_times, time_stamping, tsa_condition_number

__all__ = [
    "AngleTrajectory", "constant_speed", "varying_speed", "trapezoid_speed", "rpm_to_rad_s",
    "Encoder", "EncoderEvents",
    "time_stamping", "TsaEstimate", "tsa_condition_number", "controller_times", "TimeStamper",
    "ThreeStageEstimator", "three_stage", "NotchFilter", "notch", "notch_series", "SpeedEstimate",
    "SuperTwistingGains", "super_twisting_gains", "SuperTwistingObserver", "super_twisting",
    "SuperTwistingRun", "low_pass", "StiffnessEstimate", "identify_stiffness",
    "VehicleSpeedGain", "vehicle_speed_gain", "VehicleSpeedObserver", "vehicle_speed_observer", "VehicleSpeedRun",
    "SpeedParameterEstimate", "identify_speed_parameters",
    "WheelRun", "simulate_wheel", "braking_trajectory", "linear_tyre", "burckhardt_tyre",
    "encoder_chain", "compare_estimators", "ChainSettings", "ChainResult", "EstimatorComparison",
    "ESTIMATORS", "TABLE61_SEED", "TABLE61_ENCODER", "TABLE61_PROFILES", "ROBUSTNESS_PROFILES",
    "rms_error", "estimate_lag", "plot_comparison",
]
