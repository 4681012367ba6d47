"""switchobs transform: dz/dt = s(y)(Az + d(y)) + b(y)u found or checked from f, g, h (seed 004 Part III).

Every positive verdict is re-checked here independently: the model the result writes is read back with
Model.from_toml and dphi/dx (f + g u) = s(h)(A phi + d(h)) + b(h) u is simplified to zero in the states.
"""

import ast
import ctypes
import json
import pathlib
import re
import shlex
import subprocess

import pytest
import sympy as sp

from switchobs.cli.main import main
from switchobs.codegen import generate_observer
from switchobs.codegen._build import BUILD_FLAGS, compile_shared, find_compiler
from switchobs.design import design, design_gains
from switchobs.exceptions import DimensionError, ExpressionError, ModelError, TransformError
from switchobs.model import Model, builtin_model
from switchobs.transform import System, check_transformation, search_transformation
from switchobs.transform._lie import kappa

SYSTEMS = pathlib.Path(__file__).resolve().parents[1] / "examples" / "systems"
SEED000_PHI = ["x2", "c1*c2*exp(-c2*x1) - x3", "-c2*x3"]  # seed 000 Sec. III-B: z1 = x2, z2 = mu'(x1), z3 = -c2 c3


def system(name):
    return System.from_toml(SYSTEMS / f"{name}.toml")


def written_model(result, tmp_path):
    path = tmp_path / "model.toml"
    path.write_text(result.model_toml())
    return Model.from_toml(path)


def assert_normal_form(sys_, result, tmp_path):
    """Substitute z = phi(x) back: the transformed field equals s(y)(A z + d(y)) + b(y) u exactly."""
    assert result.exists, result.failing
    model = written_model(result, tmp_path)
    x = list(sys_.state_symbols)
    phi = sp.Matrix(result.phi)
    J = phi.jacobian(x)
    by_name = {**{str(s): s for s in sys_.symbols.values()}}
    to_sys = {s: by_name.get(str(s), s)
              for e in (*model.A, *model.d, *model.b, model.time_scale) for s in e.free_symbols}
    y = model.symbol(model.output)
    at_x = {**to_sys, y: sys_.h}
    s_x = model.time_scale.subs(at_x)
    assert model.C == sp.ImmutableMatrix([[1] + [0] * (sys_.n - 1)]) and sp.simplify(phi[0] - sys_.h) == 0
    u = sp.Matrix(sp.symbols(f"u1:{sys_.g.shape[1] + 1}"))
    left = J * sys_.f + (J * sys_.g * u if sys_.g.shape[1] else sp.zeros(sys_.n, 1))
    right = s_x * (model.A.subs(to_sys) * phi + model.d.subs(at_x))
    if sys_.g.shape[1]:
        right += model.b.subs(at_x) * u
    assert (left - right).applyfunc(sp.simplify) == sp.zeros(sys_.n, 1)
    assert sp.simplify(J.det()) != 0
    return model


# --------------------------------------------------------------------------- seed 000
@pytest.fixture(scope="module")
def wheel_search():
    return search_transformation(system("wheel-burckhardt"))


def test_seed000_search_finds_the_time_scale_of_eq7(wheel_search, tmp_path):
    sys_ = system("wheel-burckhardt")
    assert wheel_search.exists
    y, vx = sys_.output_symbol, sys_.symbols["vx"]
    assert sp.simplify(wheel_search.time_scale - y / vx) == 0            # s = z1/vx (seed 000 eq. (10)-(11))
    assert wheel_search.s_zeros == (0,)
    assert_normal_form(sys_, wheel_search, tmp_path)


def test_seed000_search_coordinates_are_eq7_up_to_the_documented_freedom(wheel_search):
    """z_seed = T z_search + psi(y), T constant: a linear change and an output-dependent shift (docs/transform.md)."""
    sys_ = system("wheel-burckhardt")
    x = sp.Matrix(sys_.state_symbols)
    seed = sp.Matrix([sys_.parse(e, what="phi") for e in SEED000_PHI])
    found = sp.Matrix(wheel_search.phi)
    T = (seed.jacobian(x) * found.jacobian(x).inv()).applyfunc(sp.simplify)
    assert not (T[:, 1:].free_symbols & set(x))
    psi = (seed - T[:, 1:] * found[1:, :]).applyfunc(sp.simplify)
    assert all(not (e.free_symbols & set(x) - {sys_.symbols["x2"]}) for e in psi)   # x2 = y
    assert T[:, 1:].rank() == sys_.n - 1


def test_seed000_check_mode_gives_eq7_and_the_sec3e_gains(tmp_path):
    sys_ = system("wheel-burckhardt")
    result = check_transformation(sys_, "y/vx", SEED000_PHI)
    model = assert_normal_form(sys_, result, tmp_path)
    seed = builtin_model("abs-xbs3")
    c2 = model.symbol("c2")
    rename = {c2: -seed.symbol("c"), model.symbol("a"): seed.symbol("a"), model.symbol("b"): seed.symbol("b")}
    assert model.A.subs(rename) == seed.A and model.b.subs(rename) == seed.b and model.d == seed.d
    assert sp.simplify(model.time_scale - seed.time_scale.subs(seed.symbol("vx"), model.symbol("vx"))) == 0
    mine = design_gains(model.numeric(), "-10,-20,-20")
    theirs = design_gains(seed.numeric(), "-10,-20,-20")
    assert mine.K_plus == theirs.K_plus and mine.K_minus == theirs.K_minus
    a, c, k1p, k1m = sp.Rational(375, 2), 34, 34 + 10 + 40, 34 - 10 - 40        # beta1 = 10, beta2 = 20, Sec. III-E
    assert list(mine.K_plus) == [k1p, -(400 + 400 + c * k1p) / a, -4000 / a]
    assert list(mine.K_minus) == [k1m, -(400 + 400 + c * k1m) / a, 4000 / a]


def test_seed000_a_wrong_candidate_names_the_failing_condition():
    sys_ = system("wheel-burckhardt")
    wrong_phi = check_transformation(sys_, "y/vx", ["x2", "x1", "x3"])
    assert not wrong_phi.exists and "is not constant" in wrong_phi.failing
    wrong_s = check_transformation(sys_, "1", SEED000_PHI)
    assert not wrong_s.exists and "not constant" in wrong_s.failing
    not_output = check_transformation(sys_, "y/vx", ["x1", "x2", "x3"])
    assert not not_output.exists and "is not the output" in not_output.failing


# --------------------------------------------------------------------------- seed 001
def test_seed001_xbs_model_2_6_from_the_wheel_dynamics(tmp_path):
    sys_ = system("xbs-aguado")
    found = search_transformation(sys_)
    assert sp.simplify(found.time_scale - sys_.output_symbol / sys_.symbols["vx"]) == 0
    assert_normal_form(sys_, found, tmp_path)
    checked = check_transformation(sys_, "y/vx", ["x2", "c1*c2*exp(-c2*x1) - c3"])   # z2 = mu'(x1)
    model = assert_normal_form(sys_, checked, tmp_path)
    a, b, c2, c3 = (model.symbol(k) for k in ("a", "b", "c2", "c3"))
    c, d = -c2, -c2 * c3                                                            # seed 001 below (2.6)
    assert model.A == sp.ImmutableMatrix([[0, -a], [0, c]]) and list(model.d) == [0, d]
    assert list(model.b) == [-b, 0]


def test_seed001_adaptive_model_3_2_in_w_coordinates(tmp_path):
    sys_ = system("xbs-aguado")
    w2 = "c1*c2*exp(-c2*x1) - c3 - (c2/a)*x2"                    # w2 = z2 + (c/a) z1, seed 001 below (3.1)
    checked = check_transformation(sys_, "y/vx", ["x2", w2])
    model = assert_normal_form(sys_, checked, tmp_path)
    seed = builtin_model("abs-adaptive2")
    c2, c3 = model.symbol("c2"), model.symbol("c3")
    to_seed = {c2: -seed.symbol("c"), c3: seed.symbol("d") / seed.symbol("c"),
               model.symbol("a"): seed.symbol("a"), model.symbol("b"): seed.symbol("b")}
    assert model.A.subs(to_seed) == seed.A
    d_seed = seed.d.subs(seed.symbol("y"), model.symbol("y"))
    assert (model.d.subs(to_seed) - d_seed).applyfunc(sp.simplify) == sp.zeros(2, 1)
    assert (model.b.subs(to_seed) - seed.b).applyfunc(sp.simplify) == sp.zeros(2, 1)


# --------------------------------------------------------------------------- textbook cases
def test_output_injection_without_time_scaling(tmp_path):
    sys_ = system("oi-linearisable")
    result = search_transformation(sys_)
    assert result.time_scale == 1 and result.s_zeros == ()
    model = assert_normal_form(sys_, result, tmp_path)
    assert model.inputs == () and model.b.shape == (2, 0)


def test_a_system_that_needs_a_nontrivial_time_scale(tmp_path):
    sys_ = system("time-scaled")
    result = search_transformation(sys_)
    assert result.time_scale == sys_.output_symbol and result.s_zeros == (0,)
    assert_normal_form(sys_, result, tmp_path)
    z1, z2 = sp.symbols("z1 z2", real=True)
    assert result.phi_inverse == (z1, z1**2 + z2)                     # x = phi^-1(z), explicit


def test_no_time_scale_exists_for_rayleighs_oscillator():
    result = search_transformation(system("no-normal-form"))
    assert not result.exists and result.model is None
    assert "s'(y)/s(y) = 3*e*x2 is not a function of the output" in result.failing
    with pytest.raises(TransformError, match="no transformation exists"):
        result.model_toml()


def test_no_commuting_frame_in_dimension_three():
    result = search_transformation(system("no-normal-form-3"))
    assert not result.exists and "[ad^1 tau~, ad^2 tau~] = [0, 0, -2] != 0" in result.failing


def test_an_unobservable_system_fails_the_rank_condition():
    sys_ = System.from_dict({"name": "decoupled", "states": ["x1", "x2"], "f": ["x1", "x2"], "h": "x1"})
    result = search_transformation(sys_)
    assert not result.exists and "observability rank condition" in result.failing


def test_an_input_that_is_not_output_dependent_is_named():
    sys_ = System.from_dict({"name": "bad-input", "states": ["x1", "x2"], "f": ["x2", "0"], "g": ["x2", "0"],
                             "h": "x1", "inputs": ["u"]})
    result = search_transformation(sys_)
    assert not result.exists and "[ad^0 tau~, g_1]" in result.failing


def test_a_polynomial_system_with_parameters(tmp_path):
    """poly2 has the property of poly3 and poly4 (symbolic k, q; s = 1 + y^2) at a fraction of the time; the larger
    ones are timed in benchmarks/transform.py."""
    sys_ = system("poly2")
    result = search_transformation(sys_)
    assert sp.expand(result.time_scale - (1 + sys_.output_symbol ** 2)) == 0
    assert_normal_form(sys_, result, tmp_path)


def test_several_inputs_each_output_dependent_in_z(tmp_path):
    """g = dphi^-1 b(y) for b = [[0, 1], [1, y]] in the coordinates of time-scaled.toml (x2 = z2 + z1^2)."""
    sys_ = System.from_dict({"name": "two-inputs", "states": ["x1", "x2"],
                             "f": ["x1*(x2 - x1^2)", "-x1^2 + 2*x1^2*(x2 - x1^2)"],
                             "g": [["0", "1"], ["1", "3*x1"]], "h": "x1", "inputs": ["u1", "u2"]})
    result = search_transformation(sys_)
    model = assert_normal_form(sys_, result, tmp_path)
    assert model.inputs == ("u1", "u2") and model.b == sp.ImmutableMatrix([[0, 1], [1, model.symbol("y")]])
    assert result.time_scale == sys_.output_symbol


def test_an_output_that_is_not_a_single_state(tmp_path):
    """y = x1 + x2: the normal form z1' = z2 + z1^2, z2' = -z1 with x1 = z1 - z2, x2 = z2."""
    sys_ = System.from_dict({"name": "sum-output", "states": ["x1", "x2"],
                             "f": ["x2 + (x1 + x2)^2 + x1 + x2", "-(x1 + x2)"], "h": "x1 + x2"})
    result = search_transformation(sys_)
    model = assert_normal_form(sys_, result, tmp_path)
    y = model.symbol("y")
    assert result.time_scale == 1 and list(model.d) == [y**2, -y]
    back = dict(zip(sys_.state_symbols, (e for _, e in model.original)))          # x = phi^-1(z), substituted
    assert [sp.simplify(e.subs(back)) for e in result.phi] == [model.symbol(z) for z in model.states]


def test_kappa_is_the_coefficient_of_the_time_scale_equation():
    assert [kappa(n) for n in (2, 3, 4)] == [-2, 4, -7]


# --------------------------------------------------------------------------- system files
@pytest.mark.parametrize("change, error, match", [
    ({"f": ["x2"]}, DimensionError, "'f' must be a flat list of 2"),
    ({"f": ["x2", "__import__('os')"]}, ExpressionError, "call of '__import__' is not allowed"),
    ({"h": "vx"}, ExpressionError, "unknown name 'vx'"),
    ({"color": "red"}, ModelError, "unknown key"),
    ({"g": ["0"], "inputs": ["u"]}, DimensionError, "'g' must hold 2 rows of 1"),
    ({"h": "k"}, ModelError, "does not depend on the states"),
    ({"positive": ["u"], "inputs": ["u"]}, ModelError, "not states, parameters or external"),
    ({"states": ["x1"], "f": ["x1"], "h": "x1"}, ModelError, "at least 2 states"),
])
def test_bad_system_files_are_one_clear_error(change, error, match):
    base = {"name": "bad", "states": ["x1", "x2"], "f": ["x2", "-k*x1"], "h": "x1", "parameters": ["k"]}
    with pytest.raises(error, match=match):
        System.from_dict({**base, **change})


def test_a_candidate_of_the_wrong_length_is_an_input_error():
    with pytest.raises(TransformError, match="phi has 2 component"):
        check_transformation(system("wheel-burckhardt"), "y/vx", ["x2", "x1"])


def test_the_transform_package_does_not_import_design():
    root = pathlib.Path(__file__).resolve().parents[1] / "src" / "switchobs" / "transform"
    for path in root.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module:
                assert node.module.split(".")[0] not in {"design", "certify", "codegen", "report", "cli"}, path


# --------------------------------------------------------------------------- command line and pipeline
def test_cli_search_writes_model_and_theory_and_the_model_goes_to_c(tmp_path, capsys):
    out, theory = tmp_path / "m.toml", tmp_path / "derivation.md"
    assert main(["transform", str(SYSTEMS / "time-scaled.toml"), "--out", str(out), "--theory", str(theory)]) == 0
    text = capsys.readouterr().out
    assert "Lie derivatives" in text and "s(y) = y" in text and f"wrote model {out}" in text
    assert "## 4. Time scale" in theory.read_text() and "\\tau" in theory.read_text()
    assert main(["design", str(out), "--spectrum=-1,-2", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["K_plus"]
    assert main(["certify", str(out), "--spectrum=-1,-2", "--no-dwell"]) == 0
    capsys.readouterr()
    assert main(["codegen", str(out), "--spectrum=-1,-2", "--out", str(tmp_path / "c")]) == 0
    source = next((tmp_path / "c").glob("*.c"))
    cc = subprocess.run([find_compiler(), "-std=c99", "-Wall", "-Werror", "-c", str(source), "-o",
                         str(tmp_path / "o.o")], capture_output=True, text=True)
    assert cc.returncode == 0, cc.stderr


STRICT = ("-Wall", "-Wextra", "-Wpedantic", "-Wconversion", "-Wfloat-conversion", "-Wdouble-promotion", "-Werror")


def test_the_generated_c_reads_the_estimate_back_in_the_original_coordinates(wheel_search, tmp_path):
    """Seed 000's wheel: <prefix>_original(z) = phi^-1(z) = x on points phi(x), an error code outside the domain."""
    model = written_model(wheel_search, tmp_path)
    assert [k for k, _ in model.original] == ["x1", "x2", "x3"]
    gen = generate_observer(model, design(model.numeric(), "-10,-20,-20"))
    assert gen.original_names == ("x1", "x2", "x3") and f"{gen.prefix}_original(" in gen.readme
    lib = ctypes.CDLL(str(compile_shared(gen, flags=(*BUILD_FLAGS, *STRICT))))
    original = getattr(lib, f"{gen.prefix}_original")
    vec = ctypes.POINTER(ctypes.c_double)
    original.argtypes, original.restype = [vec, vec, vec, vec], ctypes.c_int32

    def call(z, params=None, signals=(1.0, 20.0, 0.0)):
        arr = lambda v: None if v is None else (ctypes.c_double * len(v))(*v)  # noqa: E731
        out = (ctypes.c_double * 3)(7.0, 7.0, 7.0)
        return original(arr(z), arr(signals), arr(params), out), list(out)

    sys_ = system("wheel-burckhardt")
    values = {sys_.symbols[k]: v for k, v in sys_.values.items()}
    phi = [e.subs(values) for e in wheel_search.phi]
    numeric = model.numeric()
    zs = [model.symbol(z) for z in model.states]
    inverse = sp.lambdify(zs, [e for _, e in numeric.original], "math")     # phi^-1 in Python, from the file
    for x in [(0.05, -3.0, 0.4), (0.2, 1.5, 0.1), (0.01, 0.0, 1.0)]:
        z = [float(e.subs(dict(zip(sys_.state_symbols, map(sp.Rational, x))))) for e in phi]
        status, out = call(z)
        assert status == 0
        assert out == pytest.approx(inverse(*z), rel=1e-12, abs=1e-12) and out == pytest.approx(x, abs=1e-9)
    c2 = -34.0
    assert call([0.0, 1.0, c2]) == (5, [7.0] * 3)            # c2^2 z1 - c2 z2 + z3 = 0: NONFINITE_RESULT, x unchanged
    assert call([0.0, 1.0, 0.0])[0] == 5                      # log of a negative number (a c1 c2^2 < 0)
    assert call([0.0, float("nan"), 0.0])[0] == 2             # NONFINITE_STATE
    bad_a = list(gen.params_with({"a": -1.0}))
    assert call(z, params=bad_a)[0] == 6                      # a is declared positive: BAD_PARAM
    assert original(None, None, None, None) == 7              # BAD_ARGUMENT


@pytest.mark.parametrize("original, error, match", [
    ({"states": ["x1", "x2"], "inverse": ["z1"]}, DimensionError, "needs 2 states and 2 inverse"),
    ({"states": ["x1", "x2"], "inverse": ["z1", "__import__('os')"]}, ExpressionError, "not allowed"),
    ({"states": ["x1", "x2"], "inverse": ["z1", "u + z2"]}, ExpressionError, "unknown name 'u'"),
    ({"states": ["x1", "x2"], "inverse": ["z1", "t"]}, ExpressionError, "unknown name 't'"),
    ({"states": ["x1", "z2"], "inverse": ["z1", "z2"]}, ModelError, "clash with the model's names"),
    ({"states": ["x1", "x2"]}, ModelError, "exactly the keys 'states' and 'inverse'"),
])
def test_the_original_table_of_a_model_file_is_validated(original, error, match):
    base = {"name": "m", "states": ["z1", "z2"], "A": [["0", "1"], ["0", "0"]], "C": ["1", "0"], "time_scale": "y",
            "inputs": ["u"], "parameters": ["k"], "external": ["vx"]}
    with pytest.raises(error, match=match):
        Model.from_dict({**base, "original": original})
    ok = Model.from_dict({**base, "original": {"states": ["x1", "x2"], "inverse": ["z1/vx", "k*z2 + y"]}})
    assert Model.from_json(ok.to_json()) == ok and ok.with_values({"k": 2}).original[1][1] == 2 * ok.symbol("z2") + \
        ok.symbol("y")


def test_cli_check_mode_json_and_negative_verdict(tmp_path, capsys):
    wheel = str(SYSTEMS / "wheel-burckhardt.toml")
    assert main(["transform", wheel, "--s", "y/vx", "--phi", ",".join(SEED000_PHI), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["exists"] and data["model"]["A"] == [["0", "-a", "0"], ["0", "-c2", "1"], ["0", "0", "0"]]
    out = tmp_path / "none.toml"
    assert main(["transform", str(SYSTEMS / "no-normal-form.toml"), "--out", str(out)]) == 1
    text = capsys.readouterr().out
    assert "no transformation: s'(y)/s(y)" in text and not out.exists()


@pytest.mark.parametrize("argv, match", [
    (["--s", "y/vx"], "needs both --s and --phi"),
    (["--s", "y/vx", "--phi", "x2,x1"], "phi has 2 component"),
    (["--s", "y/vx", "--phi", "x2,x1,nope"], "unknown name 'nope'"),
    (["--out", "/nonexistent/dir/m.toml"], "does not exist"),
    (["--phi", "x2"], "needs both --s and --phi"),
])
def test_cli_bad_input_is_one_line_and_exit_2(argv, match, capsys):
    assert main(["transform", str(SYSTEMS / "wheel-burckhardt.toml"), *argv]) == 2
    err = capsys.readouterr().err
    assert match in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err


@pytest.mark.parametrize("command", [
    'switchobs transform examples/systems/wheel-burckhardt.toml --s y/vx --phi "x2, c1*c2*exp(-c2*x1) - x3, -c2*x3"',
    "switchobs transform examples/systems/time-scaled.toml",
    "switchobs transform examples/systems/no-normal-form.toml",
])
def test_the_derivations_shown_in_the_docs_are_what_the_command_prints(command, capsys, monkeypatch):
    root = SYSTEMS.parents[1]
    page = (root / "docs" / "transform.md").read_text("utf-8")
    block = re.search(r"^\$ " + re.escape(command) + r"\n```text\n(.*?)\n```", page, re.S | re.M)
    assert block, f"docs/transform.md shows no output of `{command}`"
    monkeypatch.chdir(root)
    main(shlex.split(command)[1:])
    assert capsys.readouterr().out.rstrip("\n") == block.group(1)


def test_states_named_like_the_normal_form_coordinates_do_not_clash(tmp_path):
    sys_ = System.from_dict({"name": "z-named", "states": ["z1", "z2"], "f": ["z2 + z1^2", "-z1"], "h": "z1"})
    result = search_transformation(sys_)
    model = assert_normal_form(sys_, result, tmp_path)
    assert model.states == ("w1", "w2") and list(model.d) == [model.symbol("y") ** 2, -model.symbol("y")]


def test_cli_a_missing_system_file_is_exit_2(tmp_path, capsys):
    assert main(["transform", str(tmp_path / "nope.toml")]) == 2
    assert "cannot read system file" in capsys.readouterr().err
