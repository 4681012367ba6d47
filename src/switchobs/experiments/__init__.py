"""The seeds' experiments: their scenarios, settings and runs, below the report that renders them.

A Python user runs a seed experiment here without the report machinery; :mod:`switchobs.report` only turns
their results into pages and figures (``switchobs reproduce``).

Public API
----------
Runs              -- every run behind the reproduction pages, each made once on first use
fig67_scenario, HalfWindowLate, FIG67_*  -- seed 001 Figs. 6.7-6.9: the five-phase ABS closed on the encoder
SEC34_*, SEC36_*, sec36_estimators, StateRecorder, ParameterRecorder, Traced
                  -- seed 001 Secs. 3.4 and 3.6: the adaptive observer after road changes, on the two-axle car
fit_table61_encoder, EncoderFit, notch_from_zero, speed_spread, ...
                  -- seed 001 Table 6.1: the fitted encoder and the bounds behind its cells
quarter_car, step_halving, continuous_law, six_phase_roads, simulated_return, chain_braking, ChainBraking, ...
                  -- the set-ups and runs behind the measured numbers of the observer, ABS and encoder pages
msirdi_runs, msirdi_wheel, theorem3_reaching, equivalent_injection, identify_theta, MSIRDI_*
                  -- seed 003 Secs. III-B, IV, V: the vehicle-speed observer, the injections, theta_1 and theta_2
sec34_perturbed, Sec34Perturbed, eccentric_x2, SEC34_PERTURBED_*
                  -- seed 001 Sec. 3.4, Figs. 3.6-3.9: the observers on an eccentric wheel-speed sensor's x2
fig4_roads, Fig4Road, fig4_encoder_run, Fig4Encoder, noise_gains, NoiseGains, FIG4_*
                  -- seed 000 Fig. 4 and Sec. III-E: tracking and pressure per road, the estimate's noise by sign
encoder_comparison, EncoderComparison, two_axle_box_check, BoxRun
                  -- the evidence of docs/certify.md: synthesised gains on the encoder-fed demo braking, the box
                     certificate along the two-axle braking of seed 001 Sec. 3.6
target_runs, TargetRun, proof_runs, proved_observer, division_model, TARGET_ROWS, PROOF_ROWS, ...
                  -- the generated C on the emulated Cortex-M targets and its EVA proofs (docs/codegen.md)
fig47_runs, Fig47, FIG47_ROAD, FIG47_SPEED_KMH
                  -- seed 001 Fig. 4.7: the slip around its optimum with the two- and the five-phase ABS
"""
from ._target import (PROOF_ROWS, STATE_SIGNAL_RANGES, TARGET_ROWS, XBS3_RANGES, TargetRun, division_model,
                      parameter_ranges, proof_runs, proved_observer, qemu_version, target_runs)
from ._evidence import BoxRun, EncoderComparison, encoder_comparison, two_axle_box_check
from ._adaptive import (ParameterRecorder, SEC34_AUGMENTED_BETAS, SEC34_BETAS, SEC34_CHANGES, SEC34_FINE_H_MAX,
                        SEC34_GAINS, SEC34_GAMMAS, SEC34_H_MAX, SEC34_LARGE_GAMMA, SEC34_MAX_SUBSTEPS, SEC34_QUICK_S,
                        SEC34_WINDOWS, SEC36_ACTIVATION, SEC36_CROSSING_TOL_S, SEC36_FINE_STEP_S, SEC36_H_MAX,
                        SEC36_MAX_SUBSTEPS, SEC36_OBSERVER, SEC36_WINDOW_S, StateRecorder, Traced, bosch_sequence,
                        gram_eigenvalues, load_excursions, reconverged, psi_excitation, quick_reapproach, sec36_estimators,
                        sec36_late_excursions, sec36_settled, sec36_stays, segment_rms, upsilon_excitation)
from ._fig67 import (FIG67_BLOCKED_S, FIG67_ENCODER, FIG67_PHASES, FIG67_SMALL_ECCENTRICITY, FIG67_SPEEDS_KMH,
                     FIG67_SPLIT_M_S, HalfWindowLate, excursion, fast_cycles, fast_phase, fig67_open_loop,
                     fig67_scenario, locks, longest_stay)
from ._fig47 import FIG47_ROAD, FIG47_SPEED_KMH, Fig47, fig47_runs
from ._hoang_fig4 import (FIG4_NOISE_WINDOW, FIG4_OBSERVERS, FIG4_ROADS, FIG4_SETTLE_S, FIG4_TRACKING_PHASES,
                          Fig4Encoder, Fig4Road, NoiseGains, fig4_encoder_run, fig4_roads, noise_gains)
from ._layer_pages import (CHAIN_ABS_SCENARIOS, CHAIN_TSA_WINDOWS, ENCODER_COMMANDS, POINCARE_KPS, POINCARE_SETTING,
                           POINCARE_ZETAS, QUARTER_CAR_BETAS, QUARTER_CAR_OBSERVERS, QUARTER_CAR_STEPS,
                           STEP_HALVING_STEPS_S, TWO_PHASE_START, ChainBraking, chain_abs, chain_braking,
                           chain_tsa_windows, continuous_law, encoder_example, fig66_thresholds_run,
                           imperfection_encoders, imperfection_runs, no_stall_exit, plant_trajectory, quarter_car,
                           quarter_car_scenario, robustness_runs, simulated_return, six_phase_roads, step_halving,
                           step_halving_controllers, two_phase_start)
from ._msirdi import (MSIRDI_COARSE_STEP_S, MSIRDI_DURATION_S, MSIRDI_REACHING_STEP_S, MSIRDI_F_PLUS, MSIRDI_ID_STEP_S, MSIRDI_ID_TAU_S, MSIRDI_INITIAL_ERROR_M_S,
                      MSIRDI_INJECTION_STEPS, MSIRDI_MARGINS, MSIRDI_SPEED0_M_S, MSIRDI_START_S, MSIRDI_STIFFNESS_N,
                      Identification, InjectionRow, ReachingRow, equivalent_injection, identify_theta, msirdi_torque,
                      msirdi_wheel, theorem3_reaching, MsirdiRuns, msirdi_runs)
from ._runs import (Runs)
from ._sec34_perturbed import (SEC34_PERTURBED_ENCODER, SEC34_PERTURBED_OBSERVERS, Sec34Perturbed, eccentric_x2,
                               sec34_perturbed)
from ._table61 import (EncoderFit, NOTCH_RAMPS_S, TABLE61_FIT_UNITS, constant_cells,
                       fit_table61_encoder, notch_from_zero, notch_to_tsa_ratios, reference_1024,
                       seed_speed_spread, speed_exponents, speed_spread, tooth_error_bound, trapezoid_spread_bound,
                       tsa_orders)

__all__ = ["PROOF_ROWS", "STATE_SIGNAL_RANGES", "TARGET_ROWS", "XBS3_RANGES", "TargetRun", "division_model",
           "parameter_ranges", "proof_runs", "proved_observer", "qemu_version", "target_runs", "BoxRun", "EncoderComparison", "encoder_comparison", "two_axle_box_check", "CHAIN_ABS_SCENARIOS", "CHAIN_TSA_WINDOWS", "ChainBraking", "ENCODER_COMMANDS", "EncoderFit",
           "FIG67_BLOCKED_S", "FIG67_ENCODER", "FIG67_PHASES", "FIG67_SMALL_ECCENTRICITY", "FIG67_SPEEDS_KMH",
           "FIG67_SPLIT_M_S", "HalfWindowLate", "NOTCH_RAMPS_S", "POINCARE_KPS", "POINCARE_SETTING",
           "POINCARE_ZETAS", "ParameterRecorder", "QUARTER_CAR_BETAS", "QUARTER_CAR_OBSERVERS", "QUARTER_CAR_STEPS",
           "Runs", "SEC34_AUGMENTED_BETAS", "SEC34_BETAS", "SEC34_CHANGES", "SEC34_FINE_H_MAX", "SEC34_GAINS",
           "SEC34_GAMMAS", "SEC34_H_MAX", "SEC34_LARGE_GAMMA", "SEC34_MAX_SUBSTEPS", "SEC34_QUICK_S",
           "SEC34_WINDOWS", "SEC36_ACTIVATION", "SEC36_CROSSING_TOL_S", "SEC36_FINE_STEP_S", "SEC36_H_MAX",
           "Identification", "InjectionRow", "MSIRDI_COARSE_STEP_S", "MSIRDI_DURATION_S", "MSIRDI_F_PLUS",
           "MSIRDI_ID_STEP_S", "MSIRDI_ID_TAU_S", "MSIRDI_INITIAL_ERROR_M_S", "MSIRDI_INJECTION_STEPS",
           "MSIRDI_MARGINS", "MSIRDI_REACHING_STEP_S", "MSIRDI_SPEED0_M_S", "MSIRDI_START_S", "MSIRDI_STIFFNESS_N",
           "MsirdiRuns", "ReachingRow", "SEC36_MAX_SUBSTEPS", "SEC36_OBSERVER", "SEC36_WINDOW_S",
           "STEP_HALVING_STEPS_S", "StateRecorder", "TABLE61_FIT_UNITS", "TWO_PHASE_START", "Traced", "bosch_sequence",
           "chain_abs", "chain_braking", "chain_tsa_windows", "constant_cells", "continuous_law", "encoder_example",
           "equivalent_injection", "excursion", "fast_cycles", "fast_phase", "fig66_thresholds_run", "fig67_open_loop",
           "fig67_scenario", "fit_table61_encoder", "gram_eigenvalues", "identify_theta", "imperfection_encoders",
           "imperfection_runs", "load_excursions", "locks", "longest_stay", "msirdi_runs", "msirdi_torque",
           "msirdi_wheel", "no_stall_exit", "notch_from_zero", "notch_to_tsa_ratios", "plant_trajectory",
           "psi_excitation", "quarter_car", "quarter_car_scenario", "quick_reapproach", "reconverged",
           "reference_1024", "robustness_runs", "sec36_estimators", "sec36_late_excursions", "sec36_settled",
           "sec36_stays", "seed_speed_spread", "segment_rms", "simulated_return", "six_phase_roads", "speed_exponents",
           "speed_spread", "step_halving", "step_halving_controllers", "theorem3_reaching", "tooth_error_bound",
           "trapezoid_spread_bound", "tsa_orders", "two_phase_start", "upsilon_excitation",
           "SEC34_PERTURBED_ENCODER", "SEC34_PERTURBED_OBSERVERS", "Sec34Perturbed", "eccentric_x2", "sec34_perturbed",
           "FIG4_NOISE_WINDOW", "FIG4_OBSERVERS", "FIG4_ROADS", "FIG4_SETTLE_S", "FIG4_TRACKING_PHASES",
           "Fig4Encoder", "Fig4Road", "NoiseGains", "fig4_encoder_run", "fig4_roads", "noise_gains",
           "FIG47_ROAD", "FIG47_SPEED_KMH", "Fig47", "fig47_runs"]
