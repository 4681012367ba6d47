"""switchobs: design, certify and export switched observers via singular time-rescaling.

Systems ``dz/dt = s(y,t) (A z + d(y)) + b(y) u, y = C z`` whose time scaling
``s`` changes sign get an observer that switches between ``K_plus`` (s > 0) and
``K_minus`` (s < 0); in the rescaled time ``tau = ∫|s| dt`` its error obeys
``de/dtau = A_sigma e``, ``A_plus = A - K_plus C``, ``A_minus = -A + K_minus C``.

Public API (sub-packages follow the pipeline; each has its own ``__all__``)
---------------------------------------------------------------------------
Model, builtin_model, load_model            -- switchobs.model
design_gains, GainDesign, observer_normal_form -- switchobs.design (sympy, exact)
synthesize, synthesize_box                  -- switchobs.synthesis (gains by LMIs, exact decay certificates)
certify_model, common_lyapunov, strict_common_lyapunov, dwell_time,
classify_planar, verify_certificate, trajectory_conditions, discrete_certificate
                                            -- switchobs.certify (cvxpy + exact re-check; the sampled
                                               observer of each step method for every step length)
generate_observer, compile_observer, CObserver
                                            -- switchobs.codegen (casadi -> C)
SwitchedObserver, AdaptiveSwitchedObserver, xbs3_observer, xbs4_observer,
adaptive_xbs_observer                       -- switchobs.observers
simulate, BrakingScenario, scenario, table41, road, PoincareMap
                                            -- switchobs.plants (ABS)
Encoder, encoder_chain, ThreeStageEstimator, super_twisting
                                            -- switchobs.sensors (wheel encoders)
EstimatorSpec, xbs_estimator, ObserverXbsEstimator, EncoderLoopEstimator, demo_scenario
                                            -- switchobs.loop (observers in the ABS loop)
replay, replay_log                          -- switchobs.loop, switchobs.logs (measurement logs replayed)
run_demo, write_theory, theory_documents    -- switchobs.report (main job, theory/)

Example: the 4D XBS observer in the loop of a braking on dry asphalt::

    from switchobs import BrakingScenario, simulate, xbs_estimator
    sc = BrakingScenario("dry-asphalt", speed_m_s=30.0)
    res = simulate(sc, estimator=xbs_estimator("xbs4", sc.vehicle, sc.roads.initial))
    print(res.metrics)

Names are loaded on first use, so ``import switchobs`` stays cheap (cvxpy and
casadi are imported only by the layers that need them).  ``switchobs.<layer>``
is always the sub-package (``from switchobs import design`` gives the module
whatever was imported before; the design function is ``design_gains``).
"""

from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

_EXPORTS = {
    "switchobs.model": ("Model", "builtin_model", "load_model"),
    "switchobs.design": ("design_gains", "GainDesign", "observer_normal_form"),
    "switchobs.synthesis": ("synthesize", "synthesize_box"),
    "switchobs.certify": ("certify_model", "common_lyapunov", "strict_common_lyapunov", "dwell_time",
                          "classify_planar", "verify_certificate", "trajectory_conditions", "discrete_certificate"),
    "switchobs.codegen": ("generate_observer", "compile_observer", "CObserver"),
    "switchobs.observers": ("SwitchedObserver", "AdaptiveSwitchedObserver", "xbs3_observer", "xbs4_observer",
                            "adaptive_xbs_observer"),
    "switchobs.plants": ("simulate", "BrakingScenario", "scenario", "table41", "road", "PoincareMap"),
    "switchobs.sensors": ("Encoder", "encoder_chain", "ThreeStageEstimator", "super_twisting"),
    "switchobs.loop": ("EstimatorSpec", "xbs_estimator", "ObserverXbsEstimator", "EncoderLoopEstimator",
                       "demo_scenario", "replay"),
    "switchobs.logs": ("replay_log",),
    "switchobs.report": ("run_demo", "write_theory", "theory_documents"),
}
_WHERE = {name: module for module, names in _EXPORTS.items() for name in names}

__all__ = sorted(_WHERE)


#: The sub-packages, reachable as attributes before they are imported (``switchobs.design``).
_SUBPACKAGES = frozenset(module.split(".")[1] for module in _EXPORTS)


def __getattr__(name: str) -> Any:
    if name in _SUBPACKAGES:
        return importlib.import_module(f"switchobs.{name}")  # importing binds it in this namespace too
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module 'switchobs' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__) | _SUBPACKAGES)
