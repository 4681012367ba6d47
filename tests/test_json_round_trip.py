"""Every class with ``to_json`` reads its JSON back: ``type(x).from_json(json round trip of x.to_json())`` is ``x``.

Two checks keep this true as the package grows: an AST scan of the source finds every class that defines
or inherits ``to_json`` and asserts it also has ``from_json``, and :data:`SAMPLES` must hold a realistic
instance (from the real producer, kept small) of every public class with ``to_json``, which is written,
passed through ``json.dumps``/``json.loads`` and read back.
"""

from __future__ import annotations

import ast
import dataclasses
import functools
import importlib
import inspect
import json
import math
import pathlib
from collections.abc import Callable, Mapping
from fractions import Fraction
from typing import Any

import numpy as np
import pytest

import switchobs
from switchobs.exceptions import SwitchobsError

SRC = pathlib.Path(switchobs.__file__).parent
PACKAGES = ["exact", "model", "transform", "design", "spec", "lmi", "synthesis", "certify", "codegen", "observers",
            "plants", "sensors", "loop", "sweep", "report"]


# ------------------------------------------------------------------ every class with to_json has from_json
def _classes() -> dict[str, tuple[str, set[str], list[str]]]:
    """Every class of the source: name -> (file, methods it defines, names of its bases)."""
    out = {}
    for path in SRC.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ClassDef):
                methods = {n.name for n in node.body if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))}
                bases = [ast.unparse(b).split(".")[-1] for b in node.bases]
                assert node.name not in out or node.name.startswith("_"), f"two classes named {node.name}"
                out[node.name] = (str(path.relative_to(SRC)), methods, bases)
    return out


def _has(classes: dict[str, Any], name: str, method: str) -> bool:
    if name not in classes:
        return False
    _, methods, bases = classes[name]
    return method in methods or any(_has(classes, b, method) for b in bases)


def test_every_class_with_to_json_has_from_json():
    classes = _classes()
    writers = [name for name in classes if _has(classes, name, "to_json")]
    assert len(writers) > 80  # the scan sees the package
    missing = sorted(f"{classes[n][0]}: {n}" for n in writers if not _has(classes, n, "from_json"))
    assert not missing, f"classes with to_json but no from_json: {missing}"


def _public_writers() -> dict[str, type]:
    out = {}
    for pkg in PACKAGES:
        module = importlib.import_module(f"switchobs.{pkg}")
        for name in module.__all__:
            obj = getattr(module, name)
            if inspect.isclass(obj) and callable(getattr(obj, "to_json", None)):
                out[obj.__name__] = obj
    return out


# ------------------------------------------------------------------ equality
def same(a: Any, b: Any) -> bool:
    """Equal as values: dataclasses field by field (fields with ``compare=False`` skipped), arrays by shape,
    dtype kind and entries (NaN equal to NaN), floats with NaN equal to NaN, containers item by item, and
    the live objects (observers) by what they pickle as (their ``__reduce__`` arguments: spec, method...).

    ``==`` of a dataclass holding NaN or arrays is no test: ``nan != nan``, and arrays compare elementwise.
    """
    if type(a).__module__.startswith("switchobs") and not dataclasses.is_dataclass(a) and "__reduce__" in {
            k for klass in type(a).__mro__ if klass is not object for k in vars(klass)}:
        return type(a) is type(b) and same(a.__reduce__()[1], b.__reduce__()[1])
    if dataclasses.is_dataclass(a) and not isinstance(a, type):
        return type(a) is type(b) and all(same(getattr(a, f.name), getattr(b, f.name))
                                           for f in dataclasses.fields(a) if f.compare)
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        return a.shape == b.shape and a.dtype.kind == b.dtype.kind and bool(
            np.array_equal(a, b, equal_nan=a.dtype.kind == "f"))
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a):
        return math.isnan(b)
    if isinstance(a, Mapping):
        return isinstance(b, Mapping) and a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)):
        return type(a) is type(b) and len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    return type(a) is type(b) and a == b or (isinstance(a, Fraction) and a == b)


def test_same_is_strict_where_dataclass_equality_is_not():
    from switchobs.sensors import SpeedEstimate

    x = SpeedEstimate(np.arange(3.0), np.array([1.0, np.nan, 2.0]), np.zeros(3), "tsa")
    assert same(x, SpeedEstimate(np.arange(3.0), np.array([1.0, np.nan, 2.0]), np.zeros(3), "tsa"))
    assert not same(x, SpeedEstimate(np.arange(3.0), np.array([1.0, 0.0, 2.0]), np.zeros(3), "tsa"))
    assert not same(x, SpeedEstimate(np.arange(3), np.array([1.0, np.nan, 2.0]), np.zeros(3), "tsa"))
    assert not same((1.0,), [1.0]) and not same(1, 1.0) and same(math.nan, float("nan"))


# ------------------------------------------------------------------ realistic instances
@functools.cache
def _braking_run():
    from switchobs.loop import run_braking
    from switchobs.plants import RoadChange, RoadSchedule

    roads = RoadSchedule("dry-asphalt", [RoadChange("wet-asphalt", at_time_s=0.3)])
    return run_braking(roads, 40, observer="xbs3", duration_s=0.6, series=True, compiled=False)


@functools.cache
def _encoder_events():
    from switchobs.sensors import Encoder, varying_speed

    return Encoder(ppr=60, dnl_cycles=0.01, clock_hz=1e6, seed=2).events(varying_speed(1020.0, 0.3))


@functools.cache
def _comparison():
    from switchobs.sensors import ChainSettings, Encoder, compare_estimators, constant_speed

    return compare_estimators(constant_speed(1020.0, 0.4), Encoder(ppr=60, seed=1),
                              settings=ChainSettings(warmup_s=0.1), estimators=("tsa", "notch"))


@functools.cache
def _super_twisting():
    from switchobs.sensors import constant_speed, super_twisting, super_twisting_gains

    traj = constant_speed(600.0, 0.2)
    t = np.arange(0.0, 0.2, 1e-3)
    return super_twisting(t, traj.theta(t), gains=super_twisting_gains(400.0))


@functools.cache
def _sweep():
    from switchobs.sweep import BrakingCase, CertifyCase, run_sweep

    cases = [BrakingCase(road="wet-asphalt", speed_kmh=30.0, observer="xbs3", duration_s=0.4),
             CertifyCase(model="abs-xbs3", spectrum="-beta1,-beta2,-beta2", betas=(("beta1", 50.0), ("beta2", 60.0)),
                         dwell=False)]
    return run_sweep(cases, scheduler="none")


@functools.cache
def _c_observer():
    """The C twin of a reference observer, without its readout (a Python callable, not JSON)."""
    from switchobs.codegen import CObserver
    from switchobs.observers import xbs3_observer

    twin = CObserver.like(xbs3_observer(40.0, 60.0, method="radau3"))
    return CObserver(twin.generated, params={twin.generated.param_names[0]: 0.5})


@functools.cache
def _transformations():
    """One found by search, one refused in check mode (its candidate read back from its steps)."""
    from switchobs.transform import System, check_transformation, search_transformation

    systems = SRC.parents[1] / "examples" / "systems"
    found = search_transformation(System.from_toml(systems / "time-scaled.toml"))
    refused = check_transformation(System.from_toml(systems / "xbs-aguado.toml"), "y/vx", ["x2", "x1"])
    assert found.exists and not refused.exists
    return found, refused


def _demo_report():
    """By hand: the demo itself takes minutes (tests/test_demo.py runs it); the values are those it writes."""
    from switchobs.loop import BrakingSummary, DemoSettings, ErrorRow
    from switchobs.report import DemoReport, ModelResult

    rows = (ErrorRow("xbs4", "dry", 0.12, 0.05, 0.2, 0.03), ErrorRow("xbs4", "wet", 0.2, 0.1, 0.3, math.nan))
    braking = BrakingSummary("demo", "stopped", 3.9, 52.1, 50.3, 0.71, 0.42, 9, 0.11, rows,
                             {"xbs4": {"dry": 0.03, "wet": 0.05}}, 0.004, 3.1, 1830, 4, 2.5)
    model = ModelResult("abs-xbs3", "-beta1,-beta2,-beta2", ("beta1 + 2*beta2", "x"), ("y", "z"),
                        {"P > 0": True}, (300.0, -40.0), (-100.0, 2.0), "rk4", "h <= 1/100", "cert.json", True,
                        "certified", True, (("P", True), ("tau_D", True)), c_prefix="xbs3", c_files=("xbs3.c",))
    return DemoReport("out", DemoSettings(fast=True), (model,), braking, ("report.md",), {"design": 0.5})


def _footprint():
    from switchobs.codegen import FunctionStack, TargetFootprint

    return TargetFootprint("cortex-m4f", "float", ("-O2", "-mcpu=cortex-m4"), "arm-none-eabi-gcc 12.2.1", 2232, 0, 0,
                           (FunctionStack("p_step", 16, 104), FunctionStack("p_rows", 88, 88, ("ceilf",))))


def _pil_result():
    from switchobs.codegen import PilResult

    states = ((0.5, 0.25, 0.0), (0.5, 0.25, 0.0))
    return PilResult("cortex-m4f", "float", "p", "mps2-an386", 2, (0, 3), (0, 3), states, states, 351.0, 40.0)


def normal_form_design() -> Any:
    """A Theorem 1 design in normal-form coordinates of a dense 3-state model with decimal entries."""
    from switchobs.design import normal_form_design
    from switchobs.model import Model

    model = Model.from_dict({"name": "dense-3", "states": ["x1", "x2", "x3"], "output": "y", "time_scale": "y",
                             "A": [["-0.5", "0.31", "0"], ["0.2", "-1.25", "0.7"], ["0.1", "0", "-2.5"]],
                             "C": ["1.5", "0.25", "0"]})
    return normal_form_design(model, "-1,-1.5,-2.25")


def _samples() -> dict[str, Callable[[], tuple[Any, dict[str, Any]]]]:
    """Class name -> a function returning an instance and the ``to_json`` options that keep everything."""
    from switchobs import certify, loop, plants, report, sensors, sweep
    from switchobs.observers import xbs4_observer
    from switchobs.sweep._spec import sweep_spec_from_dict

    def series(x):
        return x, {"include_series": True}

    def arrays(x):
        return x, {"arrays": True}

    def plain(x):
        return x, {}

    def poincare():
        r = plants.road("dry-asphalt")
        return plants.PoincareMap.from_abs(kp=10.0, z_ref=8.0, chi_a=-0.1, chi_b=0.1, c=r.c, d=r.d)

    def trajectory():
        t = np.linspace(0.0, 2.0, 401)
        return certify.trajectory_conditions(t, np.sin(3 * t) + 0.2, window=1.0, vx=np.full_like(t, 20.0))

    def front():
        from switchobs.model import builtin_model
        return certify.noise_decay_front(builtin_model("abs-xbs3").numeric(), [1], noise_weights=(0.0,))[0]

    def synthesis():
        return certify.synthesize_gains([[0, 1], [-2, -1]], [[1, 0]], decay_rate=1, noise_weight=0.1)

    def admissible():
        from switchobs.model import builtin_model
        return certify.admissible_constants(builtin_model("abs-adaptive2").numeric(),
                                            bounds={"w1": (-50, 50), "w2": (-20, 30), "vx": (5, 40)}, epsilon=2.0)

    def tsa():
        ev = _encoder_events()
        return sensors.time_stamping(ev.times, ev.angles, np.arange(0.01, 0.3, 1e-3), order=2, window=15)

    def stiffness():
        st = _super_twisting()
        speed = 20.0 + 0.0 * st.t
        return sensors.identify_stiffness(st.t, st.z2 + 1.0, st.x2_hat + 60.0, speed, inertia_kg_m2=1.2,
                                          start_s=0.05)

    def vehicle_speed():
        t = np.arange(0.0, 0.5, 1e-3)
        return sensors.vehicle_speed_observer(t, 30.0 - 5.0 * t, gain=sensors.vehicle_speed_gain(6.0), x3_0=31.0)

    def speed_parameters():
        run = vehicle_speed()
        return sensors.identify_speed_parameters(run.t, run.z3 - 6.0, 100.0 + 0.0 * run.t, 30.0 - 5.0 * run.t,
                                                 mass_kg=290.0, start_s=0.1)

    def summary():
        rows = _sweep().results
        return sweep.summary_table([r for r in rows if r.case.kind == "braking"], rows=("road",),
                                   column="speed_kmh", metric="braking_distance_m")

    def theory():
        from switchobs.model import builtin_model
        return report.theory_document(builtin_model("abs-xbs3"), "-beta1,-beta2,-beta2", "seed 000 Sec. III-E")

    def encoder_loop():
        from dataclasses import replace
        sc = replace(loop.demo_scenario(loop.DemoSettings()), duration_s=0.3)
        obs = xbs4_observer(100.0, 100.0, method="radau3")
        est = loop.EncoderLoopEstimator([("xbs4", obs, {"z2": 0.5})], encoder=sensors.Encoder(ppr=60, seed=1),
                                        radius_m=sc.vehicle.radius_m,
                                        beside=[("exact", loop.ObserverXbsEstimator(obs, initial_state={"z2": 0.5}))])
        plants.simulate(sc, estimator=est)
        return est.record()

    def encoder_measurements():  # a locked start makes NaN samples (TSA window not full yet)
        t = np.linspace(0.0, 0.3, 301)
        return loop.encoder_measurements(t, -30.0 * np.exp(-t / 0.1), 20.0 - 2.0 * t, np.full(300, 100.0),
                                         encoder=sensors.Encoder(ppr=60, seed=1), radius_m=0.3)

    def replayed():  # free rolling from edges of an ideal 60-ppr wheel: the chain's warm-up leaves NaN samples
        t = np.linspace(0.0, 0.2, 201)
        stamps, teeth = loop.edges_from_wheel_speed(t, np.full(t.size, 20.0 / 0.3), loop.ideal_encoder(60))
        return loop.replay(loop.LogSignals(t, np.full(t.size, 20.0), np.zeros(t.size), stamps, teeth, ppr=60))

    def observer():
        return xbs4_observer(100.0, 60.0, method="radau3")

    def adaptive():
        from switchobs.observers import adaptive_xbs_observer
        return adaptive_xbs_observer(50.0, [[2.0, 0.0], [0.0, 3.0]])

    def normal_form():  # a model not in normal form already: T is not the identity
        from switchobs.design import observer_normal_form
        from switchobs.model import Model
        return observer_normal_form(Model.from_dict({"name": "chain", "states": ["z1", "z2"], "parameters": ["k"],
                                                     "positive": ["k"], "A": [[0, "k"], [1, 0]],
                                                     "C": [1, 1], "time_scale": "y"}))

    def tuned():
        def row(b1, b2, rec, noise):
            return sweep.CaseResult(sweep.BrakingCase(observer="xbs4", beta1=b1, beta2=b2), "stopped",
                                    {"recovery_max_s": rec, "xbs_rms_settled": noise})
        return sweep.tune_betas([row(25, 25, 1.0, 0.1), row(50, 50, 0.5, 0.2), row(200, 200, None, 0.05)])

    return {
        # design, spec, observers, codegen, transform
        "ObserverNormalForm": lambda: plain(normal_form()),
        "NormalFormDesign": lambda: plain(normal_form_design()),
        "ObserverSpec": lambda: plain(adaptive().spec),
        "Guard": lambda: plain(_c_observer().generated.guards[0]),
        "SwitchedObserver": lambda: plain(observer()),
        "AdaptiveSwitchedObserver": lambda: plain(adaptive()),
        "GeneratedObserver": lambda: (_c_observer().generated, {"sources": True}),
        "CObserver": lambda: (_c_observer(), {"sources": True}),
        "ProofResult": lambda: plain(__import__("switchobs.codegen", fromlist=["ProofResult"]).ProofResult(
            "switchobs_abs_xbs3", "frama-c -eva a.c a_proof.c", "25.0 (Manganese)", 1, 5, 9.7,
            ("a.c:12: non-finite double value. assert \\is_finite(x);",))),
        "Transformation": lambda: plain(_transformations()[0]),
        # the target runs need the cross compiler and qemu (tests/test_codegen_target.py): their shapes
        "FunctionStack": lambda: plain(_footprint().stack[0]),
        "TargetFootprint": lambda: plain(_footprint()),
        "PilResult": lambda: plain(_pil_result()),
        "PilRecord": lambda: plain(loop.PilRecord(np.array([[0.5, 20.0, 10.0], [math.nan, 19.9, 10.0]]),
                                                  np.array([1e-3, 1e-3]), np.array([0.5, 0.0, 0.0]), "two rows")),
        "PilComparison": lambda: plain(loop.PilComparison(2, 2, True, 2.5e-7, 1e-4)),
        # plants
        "FivePhaseABS": lambda: plain(plants.FivePhaseABS(tracking=True, stall_timeout_s=None)),
        "SixPhaseABS": lambda: plain(plants.SixPhaseABS(slip_threshold=0.08, hold_timeout_s=0.2)),
        "TwoPhaseABS": lambda: plain(plants.TwoPhaseABS(start_decel_m_s2=None)),
        "ContinuousXbsControl": lambda: plain(plants.ContinuousXbsControl(c=1.2, d=0.5)),
        "Burckhardt": lambda: plain(plants.road("snow")),
        "ExponentialTyre": lambda: plain(plants.fit_exponential("wet-asphalt", points=21)),
        "QuarterCar": lambda: plain(plants.QuarterCar(mass_kg=400.0)),
        "BrakeActuator": lambda: plain(plants.BrakeActuator(delay_s=0.002)),
        "PrescribedSpeed": lambda: plain(plants.PrescribedSpeed(3.0)),
        "RoadChange": lambda: plain(plants.RoadChange("wet-asphalt", at_position_m=12.5)),
        "PoincareMap": lambda: plain(poincare()),
        "PoincareFixedPoint": lambda: plain(poincare().fixed_point()),
        "Assumption1Status": lambda: plain(_braking_run().metrics.assumption1),
        "Reconvergence": lambda: plain(_braking_run().metrics.reconvergence[0]),
        # certify
        "FrontPoint": lambda: plain(front()),
        "GainSynthesis": lambda: plain(synthesis()),
        "TrajectoryReport": lambda: plain(trajectory()),
        "ZeroCrossing": lambda: plain(trajectory().crossings[0]),
        "AdmissibleConstants": lambda: plain(admissible()),
        # loop
        "EstimatorSpec": lambda: plain(loop.EstimatorSpec("xbs4", beta=80.0, beta2=60.0, method="radau3")),
        "BrakingRun": lambda: series(_braking_run()),
        "EncoderLoopRecord": lambda: plain(encoder_loop()),
        "EncoderMeasurements": lambda: plain(encoder_measurements()),
        "EncoderSamples": lambda: plain(loop.EncoderSamples(**encoder_measurements().signals())),
        "ReplayResult": lambda: plain(replayed()),
        "ReplaySummary": lambda: plain(replayed().summary),
        "DemoSettings": lambda: plain(loop.DemoSettings(fast=True)),
        "ErrorRow": lambda: plain(_demo_report().braking.errors[1]),
        "BrakingSummary": lambda: plain(_demo_report().braking),
        # sensors
        "EncoderEvents": lambda: arrays(_encoder_events()),
        "TsaEstimate": lambda: arrays(tsa()),
        "SpeedEstimate": lambda: plain(sensors.SpeedEstimate(np.arange(4.0), np.array([np.nan, 1.0, 2.0, 3.0]),
                                                             np.array([np.nan, np.nan, 1.0, 1.0]), "tsa")),
        "SuperTwistingGains": lambda: plain(_super_twisting().gains),
        "SuperTwistingRun": lambda: arrays(_super_twisting()),
        "StiffnessEstimate": lambda: arrays(stiffness()),
        "VehicleSpeedGain": lambda: plain(vehicle_speed().gain),
        "VehicleSpeedRun": lambda: arrays(vehicle_speed()),
        "SpeedParameterEstimate": lambda: arrays(speed_parameters()),
        "EstimatorComparison": lambda: arrays(_comparison()),
        # sweep
        "BrakingCase": lambda: plain(_sweep().results[0].case),
        "CertifyCase": lambda: plain(_sweep().results[1].case),
        "SweepResult": lambda: plain(_sweep()),
        "SweepSpec": lambda: (sweep_spec_from_dict({"name": "t", "base": {"observer": "xbs3"},
                                                          "grid": {"speed_kmh": [30, 60]},
                                                          "table": [{"rows": ["road"], "column": "speed_kmh",
                                                                     "metric": "braking_distance_m"}]}),
                              {"include_cases": True}),
        "SummaryTable": lambda: plain(summary()),
        "TunedDesign": lambda: plain(tuned()),
        # report
        "ModelResult": lambda: plain(_demo_report().models[0]),
        "DemoReport": lambda: plain(_demo_report()),
        # report: the evidence runs take seconds (tests/test_report_evidence.py), these are their shapes
        "EncoderComparison": lambda: plain(report.EncoderComparison(
            ("xbs3", "synthesised"), {"xbs3": ("[1, 2]", "[3, 4]")}, {"xbs3": {"dry": 0.1, "wet": math.nan}},
            {"xbs3": 0.4}, {"xbs3": 0.01}, {"xbs3": 0.002})),
        "BoxRun": lambda: plain(report.BoxRun("a=250:450", "dwell-time", None, (296.5, 401.2), 297.0, True, 0.002,
                                              0.01, 0.5, 1.0, 1e-3, 2.45)),
        "ReproductionPage": lambda: plain(report.ReproductionPage("docs/x.md", "# x\n\n| a |\n")),
        "TheoryDocument": lambda: plain(theory()),
    }


SAMPLES = _samples()


def test_every_public_class_with_to_json_has_a_round_trip_sample():
    writers = _public_writers()
    missing = sorted(set(writers) - set(SAMPLES) - EXISTING)
    assert not missing, f"public classes with to_json but no round-trip sample here: {missing}"


#: Classes whose round trip has its own test elsewhere (tests/test_notebook.py and the layers' tests).
EXISTING = {"Model", "GainDesign", "CaseResult", "ChainSettings", "ChainResult", "BrakingMetrics", "TwoAxleVehicle",
            "TwoAxleScenario", "TwoAxleResult", "BrakingScenario", "BrakingResult", "RoadSchedule", "Table41Row",
            "Table41Result", "CertificationReport", "Family", "PlanarClassification", "ParameterBox",
            "BoxCertificate", "SolveInfo", "VerificationReport", "CertificateDocument", "DwellTimeResult",
            "DualCertificate", "SingularSum", "LyapunovResult", "DiscreteCertificate",
            # the sections and entries of a certificate file, read back by CertificateDocument.from_json
            "Check", "Verdict", "FamilySection", "ObserverSection", "DiscreteSection", "BoxSection", "LyapunovEntry",
            "DualEntry", "DwellTimeEntry", "PlanarEntry", "SingularSumEntry"}


@pytest.mark.parametrize("name", sorted(SAMPLES))
def test_round_trip(name):
    x, options = SAMPLES[name]()
    cls = type(x)
    assert cls.__name__ == name
    text = json.dumps(x.to_json(**options))
    back = cls.from_json(json.loads(text))
    assert same(back, x), f"{name}: {back!r} != {x!r}"
    assert json.dumps(back.to_json(**options)) == text


def _through_json(x: Any, **options: Any) -> Any:
    return json.loads(json.dumps(x.to_json(**options)))


def test_a_refused_candidate_and_a_c_observer_with_its_readout_round_trip():
    from switchobs.codegen import CObserver
    from switchobs.exceptions import TransformError
    from switchobs.observers import xbs3_observer
    from switchobs.transform import Transformation

    refused = _transformations()[1]
    assert same(Transformation.from_json(_through_json(refused)), refused)
    edited = {**_through_json(refused), "failing": "nothing"}
    with pytest.raises(TransformError, match="differs from the stored one"):
        Transformation.from_json(edited)
    ref = xbs3_observer(40.0, 60.0, method="radau3")
    twin = CObserver.like(ref)
    back = CObserver.from_json(_through_json(twin, sources=True), readout=ref.readout)
    assert same(back, twin) and back.readout(np.array([0.1, 0.2, 0.3])) == ref.readout(np.array([0.1, 0.2, 0.3]))


def test_a_json_without_its_parts_or_of_another_class_is_refused_by_name():
    """What to_json leaves out by default is asked for by name; one class's JSON is not read as another's."""
    from switchobs.codegen import GeneratedObserver
    from switchobs.plants import FivePhaseABS, TwoPhaseABS
    from switchobs.sensors import EncoderEvents
    from switchobs.sweep import BrakingCase, SweepSpec

    with pytest.raises(SwitchobsError, match=r"EncoderEvents JSON needs 'times'; write it with to_json\(arrays=True\)"):
        EncoderEvents.from_json(_encoder_events().to_json())
    with pytest.raises(SwitchobsError, match=r"to_json\(sources=True\)"):
        GeneratedObserver.from_json(_c_observer().generated.to_json())
    x, options = SAMPLES["SweepSpec"]()
    with pytest.raises(SwitchobsError, match=r"to_json\(include_cases=True\)"):
        SweepSpec.from_json(x.to_json())
    with pytest.raises(SwitchobsError, match="has name 'five-phase', got 'two-phase'"):
        FivePhaseABS.from_json(TwoPhaseABS().to_json())
    with pytest.raises(SwitchobsError, match="needs kind 'braking', got 'certify'"):
        BrakingCase.from_json(_sweep().results[1].case.to_json())
    with pytest.raises(SwitchobsError, match="needs 6 thresholds"):  # the class judges the values
        FivePhaseABS.from_json({**FivePhaseABS().to_json(), "eps": "fast"})
