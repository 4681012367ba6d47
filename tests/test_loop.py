"""The closed loop: observer adapters, the estimator factory, the rules of the hybrid integrator, figures."""

from __future__ import annotations

import json
import pathlib
import shutil
from dataclasses import replace
from fractions import Fraction

import numpy as np
import pytest

import switchobs
from switchobs import loop
from switchobs.exceptions import DimensionError, ModelError, ObserverInputError, OutputError, SimulationError
from switchobs.loop import DEFAULT_BETA, INITIAL_STATE, EstimatorSpec, ObserverXbsEstimator, xbs_estimator
from switchobs.model import builtin_model
from switchobs.observers import ErrorCode, SwitchedObserver, xbs3_observer
from switchobs.plants import (MAX_CASCADE, BrakingScenario, FivePhaseABS, QuarterCar, TwoAxleScenario,
                              XbsEstimator, aguado_sec36, road, simulate, simulate_two_axle)


# --------------------------------------------------------------------------- adapter
def test_adapter_is_an_xbs_estimator_and_equals_run_with_mean_hold():
    obs = xbs3_observer(60.0, 60.0)
    est = ObserverXbsEstimator(obs, initial_state={"z2": 0.4, "z3": 20.0})
    assert isinstance(est, XbsEstimator)
    t = np.arange(0, 0.3, 1e-3)
    y, vx, u = 30 * np.sin(40 * t), 25 - 3 * t, 500 * np.cos(40 * t)
    est.reset(0.0, y[0], vx[0])
    np.testing.assert_array_equal(est.state, [y[0], 0.4, 20.0])
    assert est.estimate == 0.4
    out = [est.update(t[k], y[k], vx[k], u[k], 1e-3) for k in range(1, t.size)]
    rows = np.column_stack([(y[:-1] + y[1:]) / 2, (vx[:-1] + vx[1:]) / 2, u[1:]])
    traj = obs.run([y[0], 0.4, 20.0], rows, 1e-3)
    np.testing.assert_array_equal(out, traj[:, 1])
    before = est.state
    assert est.update(0.3, 5.0, 24.0, 0.0, 0.0) == out[-1]
    np.testing.assert_array_equal(est.state, before)
    assert est.describe() == "SwitchedObserver of model 'abs-xbs3' (radau3, ZOH signals y, vx, u)"   # the default
    with pytest.raises(ObserverInputError, match=r"vx = -1.0 must be > 0") as info:
        est.update(0.31, 5.0, -26.0, 0.0, 1e-3)      # the held (mean) speed is (24 - 26) / 2
    assert info.value.code == ErrorCode.UNDEFINED_TIME_SCALE


def test_adapter_refusals():
    with pytest.raises(DimensionError, match=r"\['mu'\], which are not observer states"):
        ObserverXbsEstimator(xbs3_observer(10.0, 10.0), initial_state={"mu": 0.1})
    nf = SwitchedObserver(builtin_model("normal-form-2"), [1, 2], [1, 2], params={"a1": -1, "a2": -2})
    with pytest.raises(ModelError, match=r"signals \(y, vx, u\), got \('y',\)"):
        ObserverXbsEstimator(nf)


# --------------------------------------------------------------------------- factory
def test_factory_flips_the_sign_of_b_for_the_models_of_seed_000_and_starts_from_the_initial_state():
    veh = QuarterCar.hoang2014()
    est = xbs_estimator(EstimatorSpec("xbs3", beta=80.0), veh, "hoang-dry")
    obs = est.observer
    # seed 000 writes b = -R gamma_b / I with +b u; QuarterCar.b is R gamma_b / J > 0 (seed 001)
    assert obs.values["b"] == pytest.approx(-veh.b) and obs.values["a"] == pytest.approx(veh.a)
    assert obs.values["c"] == pytest.approx(road("hoang-dry").c)
    est.reset(0.0, -3.0, 30.0)
    assert est.estimate == INITIAL_STATE["xbs3"]["z2"]
    same = ObserverXbsEstimator(xbs3_observer(80.0, 80.0, params={"a": veh.a, "b": -veh.b, "c": road("hoang-dry").c}),
                                initial_state={"z2": 0.5})
    same.reset(0.0, -3.0, 30.0)
    assert est.update(1e-3, -3.5, 29.99, 200.0, 1e-3) == same.update(1e-3, -3.5, 29.99, 200.0, 1e-3)
    adaptive = xbs_estimator("adaptive", veh, "hoang-dry").observer
    assert adaptive.values["b"] == pytest.approx(veh.b)          # seed 001's sign convention
    assert xbs_estimator("none", veh, "hoang-dry") is None
    assert str(EstimatorSpec("xbs4")) == f"xbs4 observer, beta {DEFAULT_BETA['xbs4']:g} (python)"


def test_the_spec_sub_stepping_bound_reaches_the_observer_its_c_twin_and_the_json():
    """EstimatorSpec.h_max / max_substeps: the observer splits a step with |s| dt above h_max, as its C build does."""
    veh = QuarterCar()
    spec = EstimatorSpec("xbs4", h_max=1e-3, max_substeps=50)
    obs = xbs_estimator(spec, veh, "dry-asphalt").observer
    assert (obs.h_max, obs.max_substeps) == (Fraction(1, 1000), 50)
    assert xbs_estimator("xbs4", veh, "dry-asphalt").observer.h_max is None
    # the reference observer sub-steps: a step of |s| dt = 0.05 differs from the unbounded one
    plain = xbs_estimator("xbs4", veh, "dry-asphalt")
    bounded = xbs_estimator(spec, veh, "dry-asphalt")
    for est in (plain, bounded):
        est.reset(0.0, -3.0, 20.0)
    assert plain.update(0.1, -4.0, 20.0, 100.0, 0.1) != bounded.update(0.1, -4.0, 20.0, 100.0, 0.1)
    assert "|s| dt <= 0.001 in at most 50 sub-steps" in str(spec)
    assert EstimatorSpec.from_json(json.loads(json.dumps(spec.to_json()))) == spec
    with pytest.raises(SimulationError, match="max_substeps = 5 has no effect without h_max"):
        EstimatorSpec("xbs3", max_substeps=5)
    with pytest.raises(SimulationError, match="h_max = -1.0 must be > 0"):
        EstimatorSpec("adaptive", h_max=-1.0)
    pytest.importorskip("casadi", reason="casadi is not installed: the C twin's H_MAX is NOT checked")
    if shutil.which("gcc") is None and shutil.which("cc") is None:
        pytest.skip("no C compiler is installed: the C twin's H_MAX is NOT checked")
    twin = xbs_estimator(EstimatorSpec("xbs4", impl="c", h_max=1e-3, max_substeps=50), veh, "dry-asphalt").observer
    assert (twin.generated.h_max, twin.generated.max_substeps) == (Fraction(1, 1000), 50)


def test_factory_refusals():
    with pytest.raises(SimulationError, match="unknown observer 'xbs5'; choose one of xbs3, xbs4, adaptive, none"):
        EstimatorSpec("xbs5")
    with pytest.raises(SimulationError, match="unknown observer implementation 'rust'"):
        EstimatorSpec("xbs4", impl="rust")
    with pytest.raises(SimulationError, match="needs an EstimatorSpec or an observer kind"):
        xbs_estimator(4, QuarterCar(), "dry-asphalt")


def test_public_names_of_the_loop_are_exported_at_the_top():
    top = {name for name, module in switchobs._WHERE.items() if module == "switchobs.loop"}
    assert top and top <= set(loop.__all__)
    assert switchobs.xbs_estimator is loop.xbs_estimator


# --------------------------------------------------------------------------- one integrator, one set of rules
class _Refusing:
    """An estimator that refuses its n-th step, as an observer whose state left its domain would."""

    def __init__(self, n: int):
        self.n = n

    def reset(self, t0, y0, vx0):
        self.k = 0

    def update(self, t, y, vx, u, dt):
        self.k += 1
        if self.k >= self.n:
            raise ObserverInputError(f"refused step {self.k}", code=ErrorCode.NONFINITE_STATE)
        return 0.3


def test_an_observer_failure_stops_both_loops_with_status_observer_failed():
    one = simulate(BrakingScenario("dry-asphalt", speed_m_s=20.0, duration_s=1.0), estimator=_Refusing(50))
    assert one.status == "observer-failed" and one.message.startswith("refused step 50")
    assert one.steps == 50 and one.series["t"].size == 51          # the refused step is recorded
    sc = replace(aguado_sec36(), duration_s=1.0)
    two = simulate_two_axle(sc, estimators=(None, _Refusing(400)))
    assert two.status == "observer-failed" and two.message.startswith("rear observer: refused step 400")
    assert two.steps == 400 and two.metrics["rear"]["observer_failure"].endswith("refused step 400")
    assert "observer-failed (rear observer" in str(two)


def test_a_guard_cascade_raises_in_both_loops_naming_the_guard():
    # a controller whose every phase is left at once: the phase changes never let time pass
    class Endless(FivePhaseABS):
        def runtime(self, plant, actuator):
            rt = super().runtime(plant, actuator)
            rt.table = tuple(((1.0, -1e9, (p + 1) % 6),) for p in range(6))   # every guard always positive
            return rt
    with pytest.raises(SimulationError, match=rf"changed phase {MAX_CASCADE} times at t = 0.000000 s .*guard 0"):
        simulate(BrakingScenario("dry-asphalt", speed_m_s=20.0, controller=Endless(), duration_s=0.1))
    with pytest.raises(SimulationError, match=rf"front controller changed phase {MAX_CASCADE} times"):
        simulate_two_axle(TwoAxleScenario("dry-asphalt", speed_m_s=20.0, front=Endless(), duration_s=0.5))


def test_the_wheel_of_the_sensors_runs_on_the_same_integrator_and_stops_at_a_located_lock():
    from switchobs.sensors import burckhardt_tyre, simulate_wheel

    veh = QuarterCar()
    tyre = burckhardt_tyre("dry-asphalt", veh.load_n)
    run = simulate_wheel(lambda t: -300.0, tyre, speed0_m_s=20.0, duration_s=0.5, vehicle=veh)
    np.testing.assert_allclose(run.t, np.linspace(0.0, 0.5, 5001), rtol=0, atol=1e-15)   # on the sample grid
    # omega integrates alpha: the trapezoid of the recorded alpha gives the recorded omega
    np.testing.assert_allclose(run.omega[-1] - run.omega[0], np.trapezoid(run.alpha, run.t), rtol=1e-4)
    with pytest.raises(SimulationError, match=r"the wheel locked or the car stopped at t = 0\.\d+ s \(< 2 s\)"):
        simulate_wheel(lambda t: -3000.0, tyre, speed0_m_s=20.0, duration_s=2.0, vehicle=veh)


def test_series_carry_the_tracked_reference_by_name():
    sc = BrakingScenario("dry-asphalt", speed_m_s=30.0, duration_s=1.0, controller=FivePhaseABS(tracking=True))
    s = simulate(sc, estimator="true").series
    tracked = np.isin(s["phase"], (1, 3, 4))
    assert np.all(np.isfinite(s["x2_ref"][tracked])) and np.all(np.isnan(s["x2_ref"][~tracked]))
    assert np.all(np.isnan(simulate(replace(sc, controller=FivePhaseABS())).series["x2_ref"]))


# --------------------------------------------------------------------------- figures
def test_plots_return_figures_and_draw_on_given_axes(tmp_path):
    from matplotlib.figure import Figure

    from switchobs._figures import save_figure
    from switchobs.plants import plot_braking, plot_two_axle

    res = simulate(BrakingScenario("dry-asphalt", speed_m_s=15.0, duration_s=0.5))
    fig = plot_braking(res)
    assert isinstance(fig, Figure) and len(fig.axes) == 8              # 5 histories (one twin) + 2 planes
    host = Figure(figsize=(12, 14))
    axes = host.subplots(7)
    assert plot_braking(res, ax=axes) is host
    with pytest.raises(SimulationError, match="plot_braking draws 7 panel"):
        plot_braking(res, ax=axes[:3])
    path = save_figure(fig, tmp_path / "b.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(OutputError, match="cannot write the plot"):
        save_figure(fig, tmp_path / "missing" / "b.png")
    two = simulate_two_axle(replace(aguado_sec36(), duration_s=0.5))
    assert isinstance(plot_two_axle(two), Figure)


def test_library_code_never_selects_a_matplotlib_backend():
    root = pathlib.Path(switchobs.__file__).parent
    offenders = [str(p.relative_to(root)) for p in root.rglob("*.py")
                 if "matplotlib.use(" in p.read_text() or "import matplotlib.pyplot" in p.read_text()]
    assert offenders == []


@pytest.mark.parametrize("module", ["switchobs.loop", "switchobs.loop._factory", "switchobs.loop._adapter",
                                    "switchobs.loop._braking", "switchobs.loop._encoder_batch"])
def test_loop_docstring_examples(module):
    import doctest
    import importlib

    result = doctest.testmod(importlib.import_module(module), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0
