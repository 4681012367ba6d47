"""The generated observer as an FMU, checked by FMPy (a tool switchobs did not write).

Every FMU passes ``fmpy.validation.validate_fmu``; FMPy's slave classes step it over a record of the signals a
braking simulation (scenario hoang-fig3) fed its observer and get the C ``_run`` / ``_run_dt`` trajectory bit for
bit; ``fmpy.simulate_fmu`` runs it with the record as its input.  The matrix of every model (abs-xbs3, abs-xbs4,
a user model with d(y) and b(y)), method and real type in both FMI versions, sub-stepping and the adaptive
observer; four cases in the default run, the rest of the matrix marked slow.  One FMU per case and version per
module.
"""

from __future__ import annotations

import ctypes
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from _docs_blocks import assert_page_says, matches_with_elisions, shown_output

fmpy = pytest.importorskip("fmpy", reason="fmpy is not installed: the FMUs are NOT checked (pip install fmpy)")
from fmpy import extract, read_model_description, simulate_fmu  # noqa: E402
from fmpy import calloc, free  # noqa: E402
from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,  # noqa: E402
                       fmi2CallbackFunctions, fmi2CallbackLoggerTYPE, fmi2StepFinishedTYPE)
from fmpy.fmi3 import FMU3Slave  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

from switchobs.cli.main import main  # noqa: E402
from switchobs.codegen import METHODS, REALS, STATUS_TEXT, CObserver, StepStatus, generate_observer  # noqa: E402
from switchobs.codegen._fmu import fmi_headers, generate_fmu  # noqa: E402
from switchobs.design import design  # noqa: E402
from switchobs.exceptions import CodegenError  # noqa: E402
from switchobs.loop import ObserverXbsEstimator  # noqa: E402
from switchobs.model import builtin_model, load_model  # noqa: E402
from switchobs.observers import xbs3_observer  # noqa: E402
from switchobs.plants import scenario, simulate  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
#: Rows of the record the FMUs are stepped over (the first 1.2 s of the braking).
ROWS = 1200
DT = 1e-3

#: name -> (model, spectrum, real, method, h_max, unknown): abs-xbs3, abs-xbs4, a user model with d(y) and b(y)
#: (examples/my_model.toml), every method and real type, sub-stepping, the adaptive observer.
CASES = {
    "xbs3-rk4-substeps": ("abs-xbs3", "-40,-60,-60", "double", "rk4", "1/100", ()),
    "xbs4-euler-float": ("abs-xbs4", "-40,-60,-60,-60", "float", "euler", None, ()),
    "user-radau3": (str(ROOT / "examples" / "my_model.toml"), "-40,-60,-60", "double", "radau3", None, ()),
    "user-midpoint-float": (str(ROOT / "examples" / "my_model.toml"), "-40,-60,-60", "float", "midpoint", None, ()),
}


class _Recorder:
    """The observer of a simulation, recording the signals and step lengths of every step it makes."""

    def __init__(self, observer):
        self.observer, self.rows, self.dts = observer, [], []

    def __getattr__(self, name):
        return getattr(self.observer, name)

    def step(self, xhat, signals, dt):
        self.rows.append(np.array(signals, dtype=float))
        self.dts.append(float(dt))
        return self.observer.step(xhat, signals, dt)


@pytest.fixture(scope="module")
def record():
    """Signals (y, vx, u) and step lengths that the braking of hoang-fig3 gave its XBS observer (events make
    some steps shorter than 1 ms)."""
    rec = _Recorder(xbs3_observer(60.0, 60.0))
    simulate(scenario("hoang-fig3"), estimator=ObserverXbsEstimator(rec, initial_state={"z2": 0.5}))
    return np.array(rec.rows[:ROWS]), np.array(rec.dts[:ROWS])


def _generated(case: str):
    model_name, spectrum, real, method, h_max, unknown = CASES[case]
    m = load_model(model_name) if model_name.endswith(".toml") else builtin_model(model_name)
    return generate_observer(m, design(m, spectrum), real=real, method=method, h_max=h_max, unknown=unknown)


#: The full matrix of the issue: every model, method and real type (no sub-stepping), each in both FMI versions.
MODELS = {"xbs3": ("abs-xbs3", "-40,-60,-60"), "xbs4": ("abs-xbs4", "-40,-60,-60,-60"),
          "user": (str(ROOT / "examples" / "my_model.toml"), "-40,-60,-60")}
MATRIX = {f"{short}-{method}-{real}": (model, spectrum, real, method, None, ())
          for short, (model, spectrum) in MODELS.items() for real in REALS for method in METHODS}
CASES.update({name: case for name, case in MATRIX.items() if case not in CASES.values()})
#: The cases of the default run (the rest of the matrix is marked slow).
DEFAULT = ("xbs3-rk4-substeps", "xbs4-euler-float", "user-radau3", "user-midpoint-float")


class _FMUs(dict):
    """Case and FMI version -> (generated, FMU, path, unzipped directory, initial state), built on first use
    (the generated observer once per case) and kept for the module."""

    def __init__(self, root):
        super().__init__()
        self.root, self.generated = root, {}

    def __missing__(self, key):
        case, version = key
        if case not in self.generated:
            self.generated[case] = _generated(case)
        gen = self.generated[case]
        x0 = {name: 0.1 * (i + 1) for i, name in enumerate(gen.state_names)}
        fmu = generate_fmu(gen, fmi_version=version, initial_state=x0)
        path = fmu.write(self.root / f"{case}-{version}.fmu")
        self[key] = (gen, fmu, path, extract(str(path), unzipdir=str(self.root / f"{case}-{version}")), x0)
        return self[key]


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    """Every case and FMI version, generated, written and extracted once (on first use)."""
    return _FMUs(tmp_path_factory.mktemp("fmus"))


PARAMS = [pytest.param(case, version, marks=() if case in DEFAULT else pytest.mark.slow)
          for case in CASES for version in (3, 2)]


def _slave(fmu, path, unzipped, name="instance", **instantiate):
    md = read_model_description(str(path))
    cls = FMU3Slave if fmu.fmi_version == 3 else FMU2Slave
    slave = cls(guid=md.guid if fmu.fmi_version == 2 else md.instantiationToken, unzipDirectory=unzipped,
                modelIdentifier=fmu.prefix, instanceName=name)
    slave.instantiate(**instantiate)
    if fmu.fmi_version == 2:
        slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    return slave


def _names(gen, prefix):
    return [f"{prefix}{n}" for n in gen.state_names]


def _step_over(fmu, slave, gen, rows, dts):
    vr = fmu.value_references
    sig = [vr[n] for n in gen.signal_names]
    out = [vr[n] for n in _names(gen, "xhat_")]
    traj, t = [], 0.0
    for row, h in zip(rows, dts):
        slave.setReal(sig, list(row)) if fmu.fmi_version == 2 else slave.setFloat64(sig, list(row))
        slave.doStep(currentCommunicationPoint=t, communicationStepSize=h)
        t += h
        traj.append(slave.getReal(out) if fmu.fmi_version == 2 else slave.getFloat64(out))
    return np.array(traj)


def _exit(slave, fmu, x0, gen):
    vr = fmu.value_references
    refs = [vr[n] for n in _names(gen, "xhat0_")]
    values = [x0[n] for n in gen.state_names]
    slave.setReal(refs, values) if fmu.fmi_version == 2 else slave.setFloat64(refs, values)
    slave.exitInitializationMode()


@pytest.mark.parametrize("case,version", PARAMS)
def test_fmpy_validation_finds_no_problem(fmus, case, version):
    gen, fmu, path, _, _ = fmus[case, version]
    assert validate_fmu(str(path)) == []
    md = read_model_description(str(path))
    assert md.fmiVersion == f"{version}.0" and md.coSimulation.modelIdentifier == gen.prefix
    causality = {v.name: v.causality for v in md.modelVariables}
    assert [n for n in gen.signal_names if causality[n] == "input"] == list(gen.signal_names)
    assert all(causality[n] == "parameter" for n in (*gen.param_names, *_names(gen, "xhat0_")))
    assert all(causality[n] == "output" for n in (*_names(gen, "xhat_"), "status"))
    tunable = {v.name for v in md.modelVariables if v.variability == "tunable"}
    assert tunable == set(gen.param_names)   # the model values and K_plus / K_minus
    starts = {v.name: float(v.start) for v in md.modelVariables if v.name in gen.param_names}
    assert [starts[n] for n in gen.param_names] == list(gen.default_params)


@pytest.mark.parametrize("case,version", PARAMS)
def test_slave_steps_equal_the_c_run_bit_for_bit(fmus, record, case, version):
    """One doStep per row with the row's signals held equals _run (fixed 1 ms) and _run_dt (the recorded,
    irregular step lengths) of the same C, bit for bit."""
    gen, fmu, path, unzipped, x0 = fmus[case, version]
    rows, dts = record
    c = CObserver(gen)
    start = [x0[n] for n in gen.state_names]
    for steps in (np.full(len(rows), DT), dts):
        slave = _slave(fmu, path, unzipped)
        _exit(slave, fmu, x0, gen)
        got = _step_over(fmu, slave, gen, rows, steps)
        status = slave.getInteger([fmu.value_references["status"]]) if version == 2 else \
            slave.getInt32([fmu.value_references["status"]])
        slave.terminate()
        slave.freeInstance()
        want = c.run(start, rows, DT) if steps is not dts else c.run_dt(start, rows, dts)
        assert np.array_equal(got, want)
        assert list(status) == [0]


@pytest.mark.parametrize("version", (3, 2))
def test_simulate_fmu_runs_the_record_as_input(fmus, record, version):
    """fmpy.simulate_fmu with the record as a piecewise-constant input: the C _run of the same rows."""
    gen, fmu, path, _, x0 = fmus["xbs3-rk4-substeps", version]
    rows, _ = record
    n = 400
    t = np.arange(n) * DT
    signal = np.zeros(n, dtype=[("time", float)] + [(s, float) for s in gen.signal_names])
    signal["time"] = t
    for j, s in enumerate(gen.signal_names):
        signal[s] = rows[:n, j]
    outputs = _names(gen, "xhat_")
    result = simulate_fmu(str(path), start_time=0.0, stop_time=t[-1], step_size=DT, input=signal,
                          output=outputs + ["status"], start_values={f"xhat0_{k}": v for k, v in x0.items()})
    got = np.column_stack([result[o] for o in outputs])
    want = CObserver(gen).run([x0[s] for s in gen.state_names], rows[:n - 1], DT)
    assert got.shape == (n, gen.nx)
    np.testing.assert_array_equal(got[0], [x0[s] for s in gen.state_names])   # the start values
    # FMPy interpolates the input linearly between its samples at t_k, the times the steps start: the values
    # it sets are the rows up to the rounding of its time grid
    np.testing.assert_allclose(got[1:], want, rtol=1e-9, atol=1e-9 * np.abs(want).max())
    assert np.all(result["status"] == 0)


@pytest.mark.parametrize("version", (3, 2))
def test_refused_step_is_discarded_with_the_status_logged_and_the_state_kept(fmus, version):
    gen, fmu, path, unzipped, x0 = fmus["xbs3-rk4-substeps", version]
    messages = []
    if version == 3:
        def log3(env, status, category, message):
            messages.append((status, message.decode()))
        slave = _slave(fmu, path, unzipped, logMessage=log3)
    else:
        def log2(env, name, status, category, message, *args):
            messages.append((status, message.decode()))
        callbacks = fmi2CallbackFunctions(logger=fmi2CallbackLoggerTYPE(log2),
                                          allocateMemory=fmi2CallbackAllocateMemoryTYPE(calloc),
                                          freeMemory=fmi2CallbackFreeMemoryTYPE(free),
                                          stepFinished=fmi2StepFinishedTYPE(), componentEnvironment=None)
        slave = _slave(fmu, path, unzipped, callbacks=callbacks)
    _exit(slave, fmu, x0, gen)
    vr = fmu.value_references
    set_real = slave.setReal if version == 2 else slave.setFloat64
    get_real = slave.getReal if version == 2 else slave.getFloat64
    set_real([vr["y"], vr["vx"], vr["u"]], [1.0, -3.0, 0.0])   # vx must be > 0
    before = get_real([vr[n] for n in _names(gen, "xhat_")])
    with pytest.raises(Exception, match="Discard|discard|status 2"):
        slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=DT)
    status = (slave.getInteger if version == 2 else slave.getInt32)([vr["status"]])
    code = int(StepStatus.UNDEFINED_TIME_SCALE)   # what _step returns for vx <= 0 (a guard of s = y / vx)
    assert list(status) == [code]
    assert get_real([vr[n] for n in _names(gen, "xhat_")]) == before
    text = STATUS_TEXT[StepStatus(code)]
    logged = [m for s, m in messages if s == 2 and f"status {code} ({text})" in m]
    assert len(logged) == 1, messages
    assert_page_says("codegen.md", f"`{logged[0]}`")
    # the next step with admissible signals is made as usual
    set_real([vr["vx"]], [3.0])
    slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=DT)
    assert list((slave.getInteger if version == 2 else slave.getInt32)([vr["status"]])) == [0]
    slave.terminate()
    slave.freeInstance()


def test_tunable_parameters_and_independent_instances(fmus, record):
    """Two instances of one FMU, interleaved: one with its gains retuned in step mode, each equal to the C _run
    with its own parameters (no state shared between instances)."""
    gen, fmu, path, unzipped, x0 = fmus["xbs3-rk4-substeps", 3]
    rows, _ = record
    rows = rows[:300]
    tuned = {"K_plus_z1": 150.0, "K_minus_z1": -100.0, "c": 30.0}
    vr = fmu.value_references
    a, b = _slave(fmu, path, unzipped, "a"), _slave(fmu, path, unzipped, "b")
    _exit(a, fmu, x0, gen)
    _exit(b, fmu, x0, gen)
    b.setFloat64([vr[k] for k in tuned], list(tuned.values()))   # tunable: set in step mode
    sig, out = [vr[n] for n in gen.signal_names], [vr[n] for n in _names(gen, "xhat_")]
    got_a, got_b = [], []
    for k, row in enumerate(rows):
        for slave, got in ((a, got_a), (b, got_b)):
            slave.setFloat64(sig, list(row))
            slave.doStep(currentCommunicationPoint=k * DT, communicationStepSize=DT)
            got.append(slave.getFloat64(out))
    start = [x0[n] for n in gen.state_names]
    np.testing.assert_array_equal(got_a, CObserver(gen).run(start, rows, DT))
    np.testing.assert_array_equal(got_b, CObserver(gen, params=tuned).run(start, rows, DT))
    assert not np.array_equal(got_a, got_b)
    for slave in (a, b):
        slave.terminate()
        slave.freeInstance()


def test_fmi2_instance_is_the_only_allocation_through_the_environment(fmus, record):
    """FMI 2.0: the FMU allocates through the environment's allocateMemory, once per instance, freed once."""
    gen, fmu, path, unzipped, x0 = fmus["xbs3-rk4-substeps", 2]
    calls = []

    def allocate(n, size):
        calls.append(("allocate", n * size))
        return calloc(n, size)

    def release(pointer):
        calls.append(("free", pointer))
        free(pointer)
    callbacks = fmi2CallbackFunctions(logger=fmi2CallbackLoggerTYPE(lambda *a: None),
                                      allocateMemory=fmi2CallbackAllocateMemoryTYPE(allocate),
                                      freeMemory=fmi2CallbackFreeMemoryTYPE(release),
                                      stepFinished=fmi2StepFinishedTYPE(), componentEnvironment=None)
    slave = _slave(fmu, path, unzipped, callbacks=callbacks)
    _exit(slave, fmu, x0, gen)
    _step_over(fmu, slave, gen, record[0][:100], np.full(100, DT))
    slave.terminate()
    assert [c[0] for c in calls] == ["allocate"]
    slave.freeInstance()
    assert [c[0] for c in calls] == ["allocate", "free"]


@pytest.mark.parametrize("version", (3, 2))
def test_wrapper_compiles_without_warnings_in_strict_c99(fmus, tmp_path, version):
    gen, fmu, _, _, _ = fmus["user-midpoint-float", version]
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler is installed: the wrapper's warnings are NOT checked")
    files = {**gen.files, f"{gen.prefix}_fmi{version}.c": fmu.wrapper, **fmi_headers(version)}
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    proc = subprocess.run([cc, "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", "-Wconversion",
                           "-Wno-sign-conversion", "-c", f"{gen.prefix}_fmi{version}.c"], cwd=tmp_path,
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr


def test_adaptive_observer_fmu_steps_like_its_c(tmp_path, record):
    """The adaptive observer of seed 001 (3.4) (state w, theta_hat, Upsilon) as an FMU, FMI 3.0."""
    m = builtin_model("abs-adaptive2")
    gen = generate_observer(m, design(m, "-40,-60"), unknown=["c"], Gamma=[50.0])
    fmu = generate_fmu(gen)
    path = fmu.write(tmp_path / "adaptive.fmu")
    assert validate_fmu(str(path)) == []
    x0 = {n: 0.0 for n in gen.state_names}
    slave = _slave(fmu, path, extract(str(path), unzipdir=str(tmp_path / "adaptive")))
    _exit(slave, fmu, x0, gen)
    rows = record[0][:300]
    got = _step_over(fmu, slave, gen, rows, np.full(len(rows), DT))
    slave.terminate()
    slave.freeInstance()
    np.testing.assert_array_equal(got, CObserver(gen).run(np.zeros(gen.nx), rows, DT))


def test_the_page_shows_what_the_command_prints_and_the_archive_holds(tmp_path, monkeypatch, capsys):
    command = "switchobs codegen abs-xbs3 --spectrum=-40,-60,-60 --fmu --a2l --out gen"
    monkeypatch.chdir(tmp_path)
    assert main(command.split()[1:]) == 0
    printed = capsys.readouterr().out
    assert matches_with_elisions(shown_output("codegen.md", command), printed), printed
    import zipfile
    with zipfile.ZipFile(tmp_path / "gen" / "switchobs_abs_xbs3.fmu") as zf:
        names = sorted(zf.namelist())
    assert names == ["binaries/x86_64-linux/switchobs_abs_xbs3.so", "documentation/README.md",
                     "modelDescription.xml", "sources/buildDescription.xml", "sources/switchobs_abs_xbs3.c",
                     "sources/switchobs_abs_xbs3.h", "sources/switchobs_abs_xbs3_fmi3.c"] or \
        not names[0].startswith("binaries/x86_64-linux/")   # the page names the x86-64 Linux layout
    for name in names[1:]:
        assert_page_says("codegen.md", f"`{name}`")
    assert_page_says("codegen.md", f"over {ROWS} rows of the hoang-fig3 braking")


def test_cli_writes_the_fmu_and_refuses_bad_options_in_one_line(tmp_path, capsys):
    out = tmp_path / "c"
    assert main(["codegen", "abs-xbs3", "--spectrum=-40,-60,-60", "--fmu", "--fmi-version", "2",
                 "--out", str(out)]) == 0
    path = out / "switchobs_abs_xbs3.fmu"
    assert validate_fmu(str(path)) == [] and read_model_description(str(path)).fmiVersion == "2.0"
    capsys.readouterr()
    for bad, says in ((["--fmu", "--fmi-version", "4"], "--fmi-version must be 2"),
                      (["--fmi-version", "3"], "give --fmu too")):
        target = tmp_path / "bad"
        assert main(["codegen", "abs-xbs3", "--spectrum=-40,-60,-60", *bad, "--out", str(target)]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and says in err, err
        assert not target.exists()   # nothing written


def test_generate_fmu_refuses_an_unknown_version_and_state(fmus):
    gen = fmus["xbs3-rk4-substeps", 3][0]
    with pytest.raises(CodegenError, match=r"FMI version must be one of \[2, 3\], got 1"):
        generate_fmu(gen, fmi_version=1)
    with pytest.raises(CodegenError, match=r"initial_state names \['z9'\]"):
        generate_fmu(gen, initial_state={"z9": 1.0})


def test_original_coordinates_are_outputs_of_the_fmu(tmp_path, record):
    """A model with an [original] table (as switchobs transform writes it): the FMU's x_<name> outputs are
    phi^-1(xhat) of its state outputs at every step, here x1 = z1, x2 = z2 / a, x3 = log(vx) * z3."""
    text = (ROOT / "examples" / "my_model.toml").read_text()
    text = text.replace("[values]", '[original]\nstates = ["x1", "x2", "x3"]\n'
                                    'inverse = ["z1", "z2 / a", "log(vx) * z3"]\n\n[values]')
    path = tmp_path / "with_original.toml"
    path.write_text(text)
    m = load_model(str(path))
    gen = generate_observer(m, design(m, "-40,-60,-60"))
    assert gen.original_names == ("x1", "x2", "x3")
    for version in (3, 2):
        fmu = generate_fmu(gen, fmi_version=version)
        fmu_path = fmu.write(tmp_path / f"original{version}.fmu")
        assert validate_fmu(str(fmu_path)) == []
        slave = _slave(fmu, fmu_path, extract(str(fmu_path), unzipdir=str(tmp_path / f"original{version}")))
        _exit(slave, fmu, {n: 0.0 for n in gen.state_names}, gen)
        vr = fmu.value_references
        get = slave.getReal if version == 2 else slave.getFloat64
        assert get([vr["x_x3"]]) == [0.0]                    # phi^-1 of the start state at the start signals
        rows = record[0][:200]
        states = _step_over(fmu, slave, gen, rows, np.full(len(rows), DT))
        originals = np.array(get([vr[f"x_{n}"] for n in gen.original_names]))
        slave.terminate()
        slave.freeInstance()
        z, vx = states[-1], rows[-1, 1]
        a = float(m.values["a"])
        np.testing.assert_allclose(originals, [z[0], z[1] / a, np.log(vx) * z[2]], rtol=1e-15, atol=0)


def test_without_fmpy_the_fmu_is_refused_in_one_line(tmp_path, monkeypatch, capsys):
    import sys

    monkeypatch.setitem(sys.modules, "fmpy", None)   # import fmpy raises ImportError
    target = tmp_path / "out"
    assert main(["codegen", "abs-xbs3", "--spectrum=-40,-60,-60", "--fmu", "--out", str(target)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "pip install 'switchobs[fmu]'" in err, err
    assert not target.exists()


@pytest.mark.slow
@pytest.mark.parametrize("version", (3, 2))
def test_fmpy_builds_the_binary_from_the_shipped_sources(fmus, record, tmp_path, version):
    """The sources are complete: FMPy's build_platform_binary (CMake, from buildDescription.xml or the FMI 2.0
    <SourceFiles>) builds a binary that steps like the shipped one."""
    if shutil.which("cmake") is None:
        pytest.skip("cmake is not installed: building the FMU from its sources is NOT checked")
    from fmpy.build import build_platform_binary

    gen, fmu, path, _, x0 = fmus["xbs3-rk4-substeps", version]
    unzipped = tmp_path / "fmu"
    shutil.unpack_archive(str(path), str(unzipped), format="zip")
    shutil.rmtree(unzipped / "binaries")
    (tmp_path / "build").mkdir()
    build_platform_binary(str(unzipped.resolve()), build_dir=str(tmp_path / "build"))
    assert (unzipped / "binaries" / fmu.platform / f"{gen.prefix}.so").is_file()
    slave = _slave(fmu, path, str(unzipped))
    _exit(slave, fmu, x0, gen)
    rows = record[0][:300]
    got = _step_over(fmu, slave, gen, rows, np.full(len(rows), DT))
    slave.terminate()
    slave.freeInstance()
    np.testing.assert_array_equal(got, CObserver(gen).run([x0[n] for n in gen.state_names], rows, DT))


def test_super_twisting_fmu_is_valid(tmp_path):
    """The super-twisting observer of seed 003 (signals x1, f1) exports too."""
    from switchobs.codegen import generate_super_twisting

    fmu = generate_fmu(generate_super_twisting(10.0, 20.0), fmi_version=2)
    assert validate_fmu(str(fmu.write(tmp_path / "st.fmu"))) == []
    assert {"x1", "f1", "lam", "alpha", "status"} <= set(fmu.value_references)


def test_a_parameter_named_like_an_output_is_refused_before_compiling(tmp_path, capsys):
    model = tmp_path / "clash.toml"
    model.write_text('name = "clash"\nstates = ["z1", "z2"]\nA = [["0", "1"], ["-status", "-3"]]\nC = ["1", "0"]\n'
                     'time_scale = "y"\nparameters = ["status"]\n[values]\nstatus = "2"\n')
    assert main(["codegen", str(model), "--spectrum=-2,-3", "--fmu", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "FMU variable names ['status'] occur twice" in err, err
