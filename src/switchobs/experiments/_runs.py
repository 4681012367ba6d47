"""The runs behind the reproduction pages (``switchobs reproduce``), each made once, on first use, and shared by
the sections that quote them (``_repro_adaptive``, ``_repro_abs``, ``_repro_encoders``, ``_measured``,
``_reproductions`` of :mod:`switchobs.report`), the runs of the layer pages (:mod:`._layer_pages`) included."""

from __future__ import annotations

from dataclasses import replace
from functools import cached_property

import numpy as np

from ..loop import INITIAL_STATE, X2_MEASUREMENTS, EncoderX2, EstimatorSpec, xbs_estimator
from ..plants import (Accelerometer, BrakingResult, Table41Result, TwoAxleResult, TwoAxleScenario, aguado_sec36,
                      scenario, scenario_observer, scenario_observer_gains, simulate, simulate_two_axle, table41)
from ..plants import BrakingMetrics
from ..sensors import (TABLE61_ENCODER, TABLE61_PROFILES, ChainResult, ChainSettings, Encoder, EncoderEvents,
                       EstimatorComparison, compare_estimators, super_twisting, super_twisting_gains, varying_speed)
from . import _layer_pages as _pages
from ._fig67 import (FIG67_ENCODER, FIG67_PHASES, FIG67_SMALL_ECCENTRICITY, FIG67_SPEEDS_KMH, HalfWindowLate,
                         fig67_scenario)
from ._msirdi import MsirdiRuns, msirdi_runs
from ._adaptive import (SEC34_MAX_SUBSTEPS, SEC34_H_MAX, SEC36_FINE_STEP_S, SEC36_H_MAX, SEC36_MAX_SUBSTEPS,
                              SEC36_OBSERVER, ParameterRecorder, StateRecorder, Traced, sec36_estimators)
from ._fig47 import Fig47, fig47_runs
from ._hoang_fig4 import Fig4Encoder, fig4_encoder_run
from ._sec34_perturbed import Sec34Perturbed, sec34_perturbed

__all__ = ["Runs"]


class Runs:
    """The runs behind the pages, each made once on first use."""

    @cached_property
    def table41(self) -> Table41Result:
        return table41()

    @cached_property
    def table41_adaptive(self) -> Table41Result:
        return table41(estimator_factory=lambda sc: xbs_estimator("adaptive", sc.vehicle, sc.roads.initial),
                       observer="adaptive")

    def __init__(self) -> None:
        self._brakings: dict[tuple[str, EstimatorSpec], BrakingResult] = {}
        self._sec34: dict[tuple[float, float, float], Traced] = {}
        self._quarter_car: dict[tuple[float, str | None, float | None, float | None], BrakingResult] = {}

    def braking(self, name: str, kind: str | EstimatorSpec) -> BrakingResult:
        """The built-in scenario ``name`` with the observer ``kind`` in the loop."""
        spec = kind if isinstance(kind, EstimatorSpec) else EstimatorSpec(kind)
        if (name, spec) not in self._brakings:
            sc = scenario(name)
            self._brakings[name, spec] = simulate(sc, estimator=xbs_estimator(spec, sc.vehicle, sc.roads.initial))
        return self._brakings[name, spec]

    def default_run(self, name: str) -> BrakingResult:
        """``switchobs simulate NAME``: the built-in scenario with its default observer and the gains the
        scenario chose for it."""
        return self.braking(name, EstimatorSpec(scenario_observer(name), **scenario_observer_gains(name)))

    def sec34(self, beta: float, gamma: float, h_max: float | None = None) -> Traced:
        """Seed 001 Sec. 3.4 with the adaptive observer ``(beta, Gamma = gamma I)`` sub-stepped to ``|s| dt <=
        h_max`` (default :data:`SEC34_H_MAX`), and its states after every sample."""
        h_max = SEC34_H_MAX if h_max is None else h_max
        key = (beta, gamma, h_max)
        if key not in self._sec34:
            sc = scenario("aguado-sec34")
            spec = EstimatorSpec("adaptive", beta=beta, gamma=gamma, h_max=h_max, max_substeps=SEC34_MAX_SUBSTEPS)
            obs = xbs_estimator(spec, sc.vehicle, sc.roads.initial).observer
            est = StateRecorder(obs, initial_state=INITIAL_STATE["adaptive"])
            with np.errstate(over="ignore", invalid="ignore"):
                res = simulate(sc, estimator=est)
            self._sec34[key] = Traced(res, tuple(obs.state_names), np.array(est.states))
        return self._sec34[key]

    @cached_property
    def sec34_perturbed(self) -> Sec34Perturbed:
        """Seed 001 Sec. 3.4's perturbed scenario (Figs. 3.6-3.9): the observers on the exact and the eccentric
        sensor's ``x2``."""
        return sec34_perturbed()

    @cached_property
    def fig4_encoder(self) -> Fig4Encoder:
        """Seed 000 Fig. 4 with the encoder chain feeding the 4D observer in the loop and the 3D one beside."""
        return fig4_encoder_run()

    @cached_property
    def fig47(self) -> Fig47:
        """Seed 001 Fig. 4.7: the five- and two-phase ABS on wet asphalt from 120 km/h."""
        return fig47_runs()

    @cached_property
    def two_axle_default(self) -> TwoAxleResult:
        """``switchobs simulate aguado-sec36``: the scenario with its default observer per wheel (the
        ``estimated`` run of :attr:`sec36` while that is the default)."""
        kind = scenario_observer("aguado-sec36")
        sc, spec = aguado_sec36(), EstimatorSpec(kind, **scenario_observer_gains("aguado-sec36"))
        if kind == "adaptive" and spec == SEC36_OBSERVER:
            return self._sec36_estimated[0]
        return simulate_two_axle(sc, estimators=sec36_estimators(sc, spec, load_signal=kind == "adaptive"))

    @cached_property
    def _sec36_estimated(self) -> tuple[TwoAxleResult, dict[str, np.ndarray]]:
        """The ``estimated`` run of :attr:`sec36`, and each wheel's estimate ``c_hat`` after every update (rows
        ``t``, ``c_hat``) recorded along it."""
        sc = aguado_sec36()
        recorders = tuple(ParameterRecorder(e, "c") for e in sec36_estimators(sc, SEC36_OBSERVER))
        result = simulate_two_axle(sc, estimators=recorders)
        return result, {k: np.array(r.rows) for k, r in zip("fr", recorders)}

    @cached_property
    def sec36(self) -> dict[str, TwoAxleResult]:
        """Seed 001 Sec. 3.6: the six-phase ABS with the adaptive observer per wheel, its ``a`` from the loads
        (3.36) with the measured acceleration, fed by the estimated speed and the biased accelerometer
        (``estimated``) or by the true signals (``true``, Fig. 3.18); the same with the static-load ``a``
        (``static-load``); the first second with the default ``Gamma`` at 1 ms (``gamma-default``, it
        diverges), at 0.5 ms (``gamma-default-fine``), with ours at 1 ms (``gamma-half``), and the whole run
        with the default ``Gamma`` and the observer sub-stepped (``gamma-default-substeps``)."""
        sc = aguado_sec36()
        true = replace(sc, accelerometer=Accelerometer(bias_m_s2=0.0, drift_m_s2_per_sqrt_s=0.0),
                       speed_from_filter=False)

        def run(s: TwoAxleScenario, spec: EstimatorSpec, load_signal: bool = True) -> TwoAxleResult:
            return simulate_two_axle(s, estimators=sec36_estimators(s, spec, load_signal=load_signal))

        first = replace(sc, duration_s=1.0)
        with np.errstate(over="ignore", invalid="ignore"):    # the default-Gamma run overflows on purpose
            return {"estimated": self._sec36_estimated[0], "true": run(true, SEC36_OBSERVER),
                    "static-load": run(sc, SEC36_OBSERVER, load_signal=False),
                    "gamma-default": run(first, EstimatorSpec("adaptive")),
                    "gamma-default-fine": run(replace(first, dt_s=SEC36_FINE_STEP_S), EstimatorSpec("adaptive")),
                    "gamma-default-substeps": run(sc, EstimatorSpec("adaptive", h_max=SEC36_H_MAX,
                                                                    max_substeps=SEC36_MAX_SUBSTEPS)),
                    "gamma-half": run(first, SEC36_OBSERVER)}

    @property
    def sec36_c_hat(self) -> dict[str, np.ndarray]:
        """Each wheel's ``c_hat`` along the ``estimated`` run of :attr:`sec36` (rows ``t``, ``c_hat``): the
        parameter the strict re-approach on snow waits for."""
        return self._sec36_estimated[1]

    @cached_property
    def fig67(self) -> dict[str, BrakingResult]:
        """Seed 001 Sec. 6.4: the Fig. 6.6 ABS on dry concrete from 130 km/h, reading the exact ``x2``, the
        encoder's (TSA, notch, three-stage: Figs. 6.7-6.9) and, to find what limits them, a perfect encoder's
        TSA, the exact ``x2`` read half a TSA window late and the TSA with a smaller eccentricity."""
        sc = fig67_scenario()
        radius = sc.vehicle.radius_m
        return {"exact": simulate(sc),
                **{kind: simulate(sc, x2_source=EncoderX2(kind, encoder=FIG67_ENCODER, radius_m=radius))
                   for kind in X2_MEASUREMENTS},
                "tsa-ideal": simulate(sc, x2_source=EncoderX2("tsa", encoder=Encoder(ppr=60), radius_m=radius)),
                "half-window": simulate(sc, x2_source=HalfWindowLate(radius)),
                "tsa-small": simulate(sc, x2_source=EncoderX2("tsa", radius_m=radius, encoder=replace(
                    FIG67_ENCODER, eccentricity=FIG67_SMALL_ECCENTRICITY)))}

    @cached_property
    def fig67_robust(self) -> dict[str, list[BrakingResult]]:
        """The runs of Figs. 6.7-6.9 (130 km/h, phase 0 first) with the other eccentricity phases and
        initial speeds of :data:`FIG67_PHASES` and :data:`FIG67_SPEEDS_KMH`."""
        base = fig67_scenario()
        others = [(base, phase) for phase in FIG67_PHASES[1:]]
        others += [(replace(base, speed_m_s=v / 3.6), FIG67_PHASES[0]) for v in FIG67_SPEEDS_KMH]
        return {kind: [self.fig67[kind], *(simulate(sc, x2_source=EncoderX2(
            kind, encoder=replace(FIG67_ENCODER, eccentricity_phase_rad=phase), radius_m=sc.vehicle.radius_m))
                                             for sc, phase in others)] for kind in X2_MEASUREMENTS}

    @cached_property
    def table61(self) -> dict[str, EstimatorComparison]:
        return {name: compare_estimators(build(10.0), TABLE61_ENCODER) for name, (_, build) in TABLE61_PROFILES.items()}

    @cached_property
    def table61_seed_stage1(self) -> dict[str, EstimatorComparison]:
        """The three-stage estimator as the seed runs it: stage 1 a 1 Hz high-pass (Sec. 6.2)."""
        return {name: compare_estimators(build(10.0), TABLE61_ENCODER, estimators=("three-stage",),
                                         settings=ChainSettings(highpass_hz=1.0))
                for name, (_, build) in TABLE61_PROFILES.items()}

    @cached_property
    def msirdi(self) -> MsirdiRuns:
        """Seed 003 Secs. III-B, IV, V on the quarter car: Theorem 3, the injections (20)-(21), theta_1, theta_2."""
        return msirdi_runs()

    @cached_property
    def super_twisting(self) -> tuple[list[float], list[float], list[float], list[float]]:
        """Seed 003 Theorems 1-2 on the exact angle of the varying profile: arrival times, bands, max errors."""
        traj = varying_speed(1020.0, 1.0)
        steps = [4e-4, 2e-4, 1e-4, 5e-5]
        arrivals, bands, e1, e2 = [], [], [], []
        for dt in steps:
            t = np.arange(0.0, 1.0, dt)
            run = super_twisting(t, traj.theta(t), gains=super_twisting_gains(400.0))
            err1, err2 = np.abs(traj.theta(t) - run.x1_hat), np.abs(traj.omega(t) - run.x2_hat)
            e1.append(float(err1[t > 0.5].max()))
            e2.append(float(err2[t > 0.5].max()))
            band = 2.0 * e2[-1]
            arrivals.append(float(t[np.flatnonzero(err2 > band)[-1] + 1]))
            bands.append(band)
        return steps, arrivals, e1, e2

    # ---------------------------------------------------------------- the layer pages (._layer_pages)

    def quarter_car(self, dt_s: float, kind: str | None = None, gamma: float | None = None,
                    beta: float | None = None) -> BrakingResult:
        """:func:`~switchobs.experiments.quarter_car`, made once per argument set."""
        key = (dt_s, kind, gamma, beta)
        if key not in self._quarter_car:
            self._quarter_car[key] = _pages.quarter_car(dt_s, kind, gamma, beta)
        return self._quarter_car[key]

    @cached_property
    def step_halving(self) -> dict[str, tuple[BrakingMetrics, ...]]:
        return _pages.step_halving()

    @cached_property
    def no_stall_exit(self) -> BrakingResult:
        """``hoang-fig4`` without the stall exit."""
        return _pages.no_stall_exit("hoang-fig4")

    @cached_property
    def continuous_law(self) -> dict[str, BrakingResult]:
        return _pages.continuous_law()

    @cached_property
    def fig66_thresholds(self) -> BrakingResult:
        return _pages.fig66_thresholds_run()

    @cached_property
    def two_phase_start(self) -> BrakingResult:
        return _pages.two_phase_start()

    @cached_property
    def six_phase_roads(self) -> dict[str, BrakingResult]:
        return _pages.six_phase_roads()

    @cached_property
    def return_maps(self) -> dict[tuple[float, float], float]:
        """:func:`~switchobs.experiments.simulated_return` at every gain and start of the Poincare table."""
        return {(kp, zeta): _pages.simulated_return(kp, zeta) for kp in _pages.POINCARE_KPS
                for zeta in _pages.POINCARE_ZETAS}

    @cached_property
    def encoder_cli(self) -> list[tuple[str, EstimatorComparison]]:
        """What each command of :data:`~switchobs.experiments.ENCODER_COMMANDS` compares."""
        return [(command, compare_estimators(build(), TABLE61_ENCODER)) for command, build in _pages.ENCODER_COMMANDS]

    @cached_property
    def encoder_example(self) -> tuple[EncoderEvents, ChainResult]:
        return _pages.encoder_example()

    @cached_property
    def imperfections(self) -> list[tuple[str, EstimatorComparison]]:
        return _pages.imperfection_runs()

    @cached_property
    def robustness(self) -> list[tuple[str, EstimatorComparison, EstimatorComparison]]:
        return _pages.robustness_runs()

    @cached_property
    def chain_braking(self) -> _pages.ChainBraking:
        return _pages.chain_braking()

    @cached_property
    def chain_abs(self) -> dict[str, EstimatorComparison]:
        """The open-loop chain on the closed-loop brakings of :data:`~switchobs.experiments.CHAIN_ABS_SCENARIOS`
        (their plant trajectories, no observer)."""
        return _pages.chain_abs({name: _pages.plant_trajectory(self.braking(name, "none"))
                                 for name in _pages.CHAIN_ABS_SCENARIOS})

    @cached_property
    def chain_tsa_windows(self) -> dict[str, tuple[float, ...]]:
        """The TSA window on ``hoang-fig3``'s plant trajectory."""
        return _pages.chain_tsa_windows(_pages.plant_trajectory(self.braking("hoang-fig3", "none")))
