"""Model layer: built-ins, TOML files, safe expression parsing and its errors."""

import pytest
import sympy as sp

from switchobs.exceptions import DimensionError, ExpressionError, FreeSymbolError, ModelError, NotRealError
from switchobs.model import Model, builtin_model, load_model, numeric, parse_expression

XBS3_TOML = """
name = "my-xbs3"
states = ["z1", "z2", "z3"]
A = [["0", "-a", "0"], ["0", "c", "1"], ["0", "0", "0"]]
C = ["1", "0", "0"]
time_scale = "y/vx"
b = ["b", "0", "0"]
parameters = ["a", "b", "c"]
external = ["vx"]
inputs = ["u"]
positive = ["a", "vx"]
[values]
a = 187.5
b = -4.375
c = 34
"""


def write(tmp_path, text, name="m.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_hoang2014_eq7_builtin_matches_toml_user_model(tmp_path):
    builtin = builtin_model("abs-xbs3")
    user = load_model(write(tmp_path, XBS3_TOML))
    assert (builtin.A - user.A).is_zero_matrix and builtin.C == user.C
    assert user.values["a"] == sp.Rational(375, 2) and user.values["b"] == sp.Rational(-35, 8)
    assert sp.simplify(user.time_scale - user.symbols["y"] / user.symbols["vx"]) == 0
    assert user.signals == ("y", "vx", "u")


def test_aguado2020_eq33_adaptive2_w_coordinates():
    m = builtin_model("abs-adaptive2")
    a, b, c, d, y = (m.symbols[k] for k in ("a", "b", "c", "d", "y"))
    assert m.A == sp.Matrix([[0, -a], [0, 0]])
    assert (m.d - sp.Matrix([c * y, d])).is_zero_matrix
    assert (m.b - sp.Matrix([-b, -b * c / a])).is_zero_matrix


@pytest.mark.parametrize("n", [1, 2, 7])
def test_normal_form_builtin_structure(n):
    m = builtin_model(f"normal-form-{n}")
    assert m.n == n and list(m.C) == [1] + [0] * (n - 1)
    assert all(m.A[i, i + 1] == 1 for i in range(n - 1))


def test_with_values_is_exact_and_removes_parameters():
    m = builtin_model("abs-xbs3").with_values({"a": "187.5"})
    assert "a" not in m.parameters and m.A[0, 1] == sp.Rational(-375, 2)


def test_numeric_gate_names_free_symbols():
    m = builtin_model("abs-xbs3")
    with pytest.raises(FreeSymbolError, match=r"\['a', 'c'\]"):
        numeric(m.A)
    assert numeric(m.A, {"a": 2, "c": 3})[1, 1] == 3.0


def test_numeric_gate_refuses_a_complex_value_as_not_real():
    """A complex value has no free symbol left: it is NotRealError, and no message names a CLI flag."""
    with pytest.raises(NotRealError, match="K is not real") as info:
        numeric(sp.sqrt(sp.Symbol("q")), {"q": -4}, what="K")
    assert not isinstance(info.value, FreeSymbolError)
    with pytest.raises(FreeSymbolError) as free:
        numeric(builtin_model("abs-xbs3").A)
    with pytest.raises(ModelError) as bad:
        builtin_model("abs-xbs3").with_values({"a": "x/0"})
    assert "--param" not in str(free.value) and "--param" not in str(bad.value)


@pytest.mark.parametrize("text, match", [
    ("__import__('os')", "call of '__import__' is not allowed"),
    ("__import__('os').system('true')", "call of .*system.* is not allowed"),
    ("a.__class__", "unsupported syntax 'Attribute'"),
    ("lambda: 1", "unsupported syntax 'Lambda'"),
    ("open('x')", "call of 'open' is not allowed"),
    ("q + 1", "unknown name 'q'"),
    ("a +", "cannot parse"),
    ("[1, 2]", "unsupported syntax 'List'"),
])
def test_parse_expression_rejects_unsafe_or_unknown(text, match):
    with pytest.raises(ExpressionError, match=match):
        parse_expression(text, {"a": sp.Symbol("a")}, what="A[1][1]")


def test_parse_expression_exact_decimals_and_caret_power():
    x = sp.Symbol("x")
    assert parse_expression("0.1*x^2", {"x": x}) == sp.Rational(1, 10) * x**2


@pytest.mark.parametrize("change, error, match", [
    (("A", [["0", "1"], ["0", "0"]]), DimensionError, "'A' has the wrong number of rows; expected 3 instead of 2"),
    (("A", [["0", "1", "0"], ["0", "0"], ["0", "0", "0"]]), DimensionError, "row 2 has the wrong number of entries"),
    (("C", [["1", "0", "0"], ["0", "1", "0"]]), DimensionError, "'C' must be one row"),
    (("C", "1"), DimensionError, "'C' must be a row"),
    (("C", ["1", "0"]), DimensionError, "expected 3 instead of 2"),
    (("b", ["b", "0"]), DimensionError, "'b' has the wrong length; expected 3 instead of 2"),
    (("A", [["0", "-a", "0"], ["0", "zz", "1"], ["0", "0", "0"]]), ExpressionError, "unknown name 'zz'"),
    (("A", [["0", "-a", "0"], ["0", "z1", "1"], ["0", "0", "0"]]), ExpressionError, "unknown name 'z1'"),
    (("states", ["z1", "z1", "z3"]), ModelError, "repeats the name"),
    (("values", {"q": 1}), ModelError, "'values' gives 'q', which is not a parameter"),
    (("values", {"a": -1}), ModelError, "'a' is declared positive but was given the value -1"),
    (("values", {"a": "abc"}), ModelError, "is not a finite number"),
    (("time_scale", "0"), ModelError, "identically zero"),
    (("bogus", 1), ModelError, "unknown key"),
])
def test_bad_model_definitions(tmp_path, change, error, match):
    import tomllib

    data = tomllib.loads(XBS3_TOML)
    data[change[0]] = change[1]
    with pytest.raises(error, match=match):
        Model.from_dict(data)


def test_malformed_toml_and_missing_file(tmp_path):
    with pytest.raises(ModelError, match="is not valid TOML"):
        load_model(write(tmp_path, "name = [unclosed"))
    with pytest.raises(ModelError, match="cannot read model file"):
        load_model(tmp_path / "absent.toml")
    with pytest.raises(ModelError, match="missing required key 'A'"):
        load_model(write(tmp_path, 'name = "x"\nstates = ["z"]\nC = ["1"]\ntime_scale = "y"'))


def test_model_file_not_utf8_or_too_large_is_refused_before_parsing(tmp_path):
    from switchobs._limits import MAX_INPUT_FILE_BYTES

    bad = tmp_path / "latin1.toml"
    bad.write_bytes('name = "r\u00e9sum\u00e9"'.encode("latin-1"))
    with pytest.raises(ModelError, match=r"model file '.*latin1.toml' is not UTF-8 text"):
        load_model(bad)
    big = tmp_path / "big.toml"
    with big.open("wb") as f:  # sparse: refused after reading the limit plus one byte, never trusting stat
        f.truncate(MAX_INPUT_FILE_BYTES + 1)
    with pytest.raises(ModelError,
                       match=rf"has more than {MAX_INPUT_FILE_BYTES} bytes \(limit {MAX_INPUT_FILE_BYTES}\)"):
        load_model(big)


def test_unknown_builtin_lists_known_names():
    with pytest.raises(ModelError, match="abs-xbs3, abs-xbs4, abs-adaptive2, abs-adaptive2-load, normal-form-N"):
        builtin_model("abs-xbs5")
