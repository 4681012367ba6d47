"""One failure policy (docs/errors.md): hostile input ends with one line and exit 0, 1, 2 or 130 (issue 13).

Every case listed in issue 13 under "Tracebacks or wrong exit codes" and "Hangs" for model
expressions, values, certificates and outputs is replayed here; the ones that used to hang or exhaust
memory run in one subprocess capped at 1 GiB, whose timeout fails the test if any of them hangs again.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from _cli_batch import run_batch, valid_certificate
from switchobs import _limits
from switchobs._atomic import atomic_file, staged_directory, write_files
from switchobs.cli._errors import guarded
from switchobs.cli.main import COMMANDS, main
from switchobs.exceptions import ExpressionError, ModelError, OutputError
from switchobs.model import parse_expression, rational_value

ROOT = Path(__file__).resolve().parents[1]
MODEL = (ROOT / "examples" / "my_model.toml").read_text("utf-8")
SPECTRUM = "--spectrum=-10,-20,-20"


def _model(a12: str | None = None, a_value: str | None = None) -> str:
    text = MODEL
    if a12 is not None:
        text = text.replace('["0", "-a", "0"]', f'["0", {json.dumps(a12)}, "0"]')
    if a_value is not None:
        text = text.replace('a = "187.5"', f"a = {json.dumps(a_value)}")
    return text


def _one_line(result: dict) -> bool:
    err = result["stderr"]
    return err.count("\n") == 1 and err.startswith("switchobs ") and "Traceback" not in err


# ---------------------------------------------------------------------------------------- the policy
@pytest.mark.parametrize("exc, status, words", [
    (ModelError("bad value"), 2, "bad value"),
    (RecursionError("deep"), 2, "nested too deeply"),
    (MemoryError(), 2, "out of memory"),
    (OverflowError("int too large"), 2, "too large"),
    (FileNotFoundError(2, "No such file or directory", "x/y.json"), 2, "'x/y.json'"),
    (RuntimeError("oops"), 2, "internal error RuntimeError: oops"),
    (KeyboardInterrupt(), 130, "interrupted"),
])
def test_every_exception_is_one_line_and_a_documented_status(capsys, monkeypatch, exc, status, words):
    monkeypatch.delenv("SWITCHOBS_DEBUG", raising=False)

    def fail() -> int:
        raise exc
    assert guarded("design", fail) == status
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err and err.startswith("switchobs design: ")


def test_an_internal_error_shows_its_traceback_only_with_switchobs_debug(capsys, monkeypatch):
    monkeypatch.setenv("SWITCHOBS_DEBUG", "1")

    def fail() -> int:
        raise RuntimeError("oops")
    assert guarded("design", fail) == 2
    err = capsys.readouterr().err
    assert "Traceback" in err and err.splitlines()[-1].startswith("switchobs design: error: internal error")


# ---------------------------------------------------------------------------------------- expressions
@pytest.mark.parametrize("text, match", [
    ("1e400", "beyond the largest double"),
    ("1e-400", "below the smallest normal double"),
    ("10**100000", "10**100000 has more than 1000 digits"),
    ("2**1000000", "2**1000000 has more than 1000 digits"),
    ("9**9**9**9", "9**387420489 has more than 1000 digits"),
    ("2**(1/100)", "exponent 1/100 is larger than 64"),
    ("a**(10**10)", "exponent 10000000000 is larger than 64"),
    ("a**b", "not a number"),
    ("+".join(["a"] * 100_000), "199999 characters"),
    ("-" * 5000 + "a", "5001 characters"),
    ("-" * 1500 + "a", "nested more than 50 levels"),
    ("(1+" * 60 + "a" + ")" * 60, "nested more than 50 levels"),
    ("(" * 250 + "a" + ")" * 250, "too many nested parentheses"),
    ("+".join(["a"] * 600), "more than 500 terms"),
    ("1" * 1500, "more than 1000 digits"),
    ("(10**60)**60", "more than 1000 digits"),
])
def test_expressions_are_bounded_before_they_are_built(text, match):
    import sympy as sp

    with pytest.raises(ExpressionError, match=re.escape(match)):
        parse_expression(text, {"a": sp.Symbol("a"), "b": sp.Symbol("b")}, what="A[1][2]")


def test_bounded_expressions_still_parse_exactly():
    import sympy as sp

    a = sp.Symbol("a")
    assert parse_expression("0.1*a^2 + 10**300 - 2**64", {"a": a}) == a**2 / 10 + 10**300 - 2**64
    assert parse_expression("1e308", {}) == 10**308 and parse_expression("2.5e-308", {}) == sp.Rational(1, 4 * 10**307)


def test_an_expanded_polynomial_is_counted_by_its_operands_not_its_operators():
    import sympy as sp

    # 60 monomials: 300 numbers and names, but 600 syntax nodes with the operators (cf. examples/systems/poly4.toml)
    a, b = sp.symbols("a b")
    text = " + ".join(f"{i}*a^{i % 7 + 1}*b^{i % 5 + 1}" for i in range(1, 61))
    assert parse_expression(text, {"a": a, "b": b}) == sum(i * a**(i % 7 + 1) * b**(i % 5 + 1) for i in range(1, 61))


@pytest.mark.parametrize("value, match", [
    ("1e400", "beyond the largest double"), ("1e-400", "below the smallest normal double"),
    ("1e999999999", "more than 1000 digits"), ("1e-999999999", "more than 1000 digits"),
    (float("inf"), "is not finite"), ("abc", "not a finite number"), (10**2000, "more than 1000 digits"),
])
def test_values_must_be_doubles(value, match):
    with pytest.raises(ModelError, match=re.escape(match)):
        rational_value(value, what="values.a")


def test_substituted_values_cannot_make_a_number_explode():
    from switchobs.model import Model

    data = {"name": "m", "states": ["z"], "A": [["-a**64"]], "C": ["1"], "time_scale": "1", "parameters": ["a"]}
    with pytest.raises(ModelError, match="'A' holds an exact number of about 19201 digits"):
        Model.from_dict(data).with_values({"a": "1e300"})


# ---------------------------------------------------------------------------------------- certificates
def _certificate(change) -> str:
    doc = json.loads(valid_certificate())
    change(doc)
    return json.dumps(doc)


def _set_dwell(doc: dict, value: str) -> None:
    next(c for c in doc["certificates"] if c["kind"] == "dwell-time")["tau_D"] = value


CERTIFICATE_CASES = [
    ("5001-digit integer", lambda d: None, lambda text: text.replace('"163/6000"', "1" * 5001, 1),
     "JSON integer of 5001 digits"),
    ("verdict list", lambda d: d.__setitem__("verdict", [1, 2]), None, "'verdict' must be an object"),
    ("verdict string", lambda d: d.__setitem__("verdict", "UGS"), None, "'verdict' must be an object"),
    ("observer string", lambda d: d.__setitem__("observer", "x"), None, "'observer' must be an object"),
    ("names 5", lambda d: d["family"].__setitem__("names", 5), None, "'family.names' must be a list of strings"),
    ("kind list", lambda d: d["certificates"][0].__setitem__("kind", ["x"]), None, "unknown certificate kind"),
    ("provenance string", lambda d: d.__setitem__("provenance", "x"), None, "'provenance' must be an object"),
    ("P huge", lambda d: d["certificates"][0]["P"][0].__setitem__(0, "1e999999999"), None, "more than 4000 digits"),
    ("P tiny", lambda d: d["certificates"][0]["P"][0].__setitem__(0, "1e-999999999"), None, "more than 4000 digits"),
    ("tau huge", lambda d: _set_dwell(d, "1e999999999"), None, "tau_D: '1e999999999' has more than 4000 digits"),
    ("tau tiny", lambda d: _set_dwell(d, "1e-999999999"), None, "tau_D: '1e-999999999' has more than 4000 digits"),
]


def _model_cases() -> list[tuple[str, str, list[str], str]]:
    """(name, model file text, extra arguments, words of the message) of the expression and value cases."""
    return [
        ("1e400", _model("-1e400"), [], "beyond the largest double"),
        ("10**100000", _model("-10**100000"), [], "more than 1000 digits"),
        ("2**1000000", _model("-2**1000000"), [], "more than 1000 digits"),
        ("values 1e400", _model(a_value="1e400"), [], "values.a: 1e400 is beyond the largest double"),
        ("values 1e-400", _model(a_value="1e-400"), [], "values.a: 1e-400 is below the smallest normal double"),
        ("100000-term sum", _model("+".join(["a"] * 100_000)), [], "characters (limit 2000)"),
        ("5000 minuses", _model("-" * 5000 + "a"), [], "characters (limit 2000)"),
        ("9**9**9**9", _model("9**9**9**9"), [], "more than 1000 digits"),
        ("a**(10**10), a = 2", _model("-a**(10**10)", a_value="2"), [], "larger than 64"),
        ("--param 1e400", MODEL, ["--param", "c=1e400"], "parameter 'c': 1e400 is beyond the largest double"),
        ("spectrum 1e400", MODEL, ["--spectrum=-1e400,-2,-3"], "beyond the largest double"),
    ]


def test_hostile_models_and_certificates_end_in_one_line_and_exit_2():
    cases, expected = [], []
    for name, text, extra, words in _model_cases():
        spectrum = [] if any(a.startswith("--spectrum") for a in extra) else [SPECTRUM]
        cases.append({"argv": ["certify", "m.toml", *spectrum, *extra], "files": {"m.toml": text}})
        expected.append((name, words))
    for name, change, rewrite, words in CERTIFICATE_CASES:
        text = _certificate(change)
        cases.append({"argv": ["verify", "c.json"], "files": {"c.json": rewrite(text) if rewrite else text}})
        expected.append((name, words))
    results = run_batch(cases, timeout=20 + 5 * len(cases))
    assert len(results) == len(cases), f"hung or crashed after {expected[len(results)][0]!r}: {results[-1:]}"
    for (name, words), result in zip(expected, results):
        assert result["rc"] == 2 and _one_line(result) and words in result["stderr"], (name, result)


# ---------------------------------------------------------------------------------------- verify reports
def test_verify_says_which_model_and_gains_and_what_was_not_checked(tmp_path, capsys):
    good = tmp_path / "good.json"
    good.write_text(valid_certificate(), "utf-8")
    assert main(["verify", str(good)]) == 0
    out = capsys.readouterr().out
    assert out.startswith("certificate about model abs-xbs3 (a = 375/2, b = -35/8, c = 34)")
    assert "K_plus  = [84, -7312/375, -64/3]" in out and "model: holds" in out and "not checked" not in out
    bare = tmp_path / "bare.json"
    bare.write_text(_certificate(lambda d: d.pop("observer")), "utf-8")
    assert main(["verify", str(bare)]) == 0
    assert "not checked: observer section absent: the model-gain link" in capsys.readouterr().out
    assert main(["verify", "--strict", str(bare)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--strict: 2 link(s) not checked" in err


def test_verify_detects_a_changed_model_or_says_it_cannot(tmp_path, capsys):
    renamed = tmp_path / "renamed.json"
    renamed.write_text(_certificate(lambda d: d["provenance"].__setitem__("model", "abs-xbs4")), "utf-8")
    assert main(["verify", str(renamed)]) == 1
    out = capsys.readouterr().out
    assert "certificate does NOT hold" in out and "model: FAILS - the observer has 3 states, model 'abs-xbs4' has 4" in out
    other = tmp_path / "other.json"
    other.write_text(_certificate(lambda d: d["provenance"].__setitem__("model", "normal-form-3")), "utf-8")
    assert main(["verify", str(other)]) == 0
    assert "not checked: model 'normal-form-3': the certificate does not record ['a1', 'a2', 'a3']" in \
        capsys.readouterr().out
    assert main(["verify", "--strict", str(other)]) == 1


# ---------------------------------------------------------------------------------------- outputs
@pytest.mark.parametrize("target, words", [
    ("missing/cert.json", "the directory 'missing' does not exist"),
    (".", "it is a directory"),
    ("/dev/full", "not a regular file"),
    ("/proc/cert.json", "is not writable"),
])
def test_certify_refuses_an_unwritable_out_before_solving(tmp_path, capsys, monkeypatch, target, words):
    monkeypatch.chdir(tmp_path)
    assert main(["certify", "abs-xbs3", SPECTRUM, "--out", target]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1 and words in captured.err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("argv", [["demo", "--fast", "--out", "/dev/full"], ["theory", "--out", "/dev/full"],
                                  ["theory", "--out", "/proc/theory"]])
def test_directory_outputs_are_checked_first(capsys, argv):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"'{argv[-1]}'" in err


def test_codegen_with_a_directory_in_the_way_leaves_nothing_and_names_it(tmp_path, capsys):
    out = tmp_path / "c"
    (out / "switchobs_abs_xbs3.h").mkdir(parents=True)
    assert main(["codegen", "abs-xbs3", SPECTRUM, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"'{out / 'switchobs_abs_xbs3.h'}'" in err
    assert sorted(p.name for p in out.rglob("*")) == ["switchobs_abs_xbs3.h"]


def test_staged_files_appear_together_or_not_at_all(tmp_path):
    target = tmp_path / "new" / "deeper"
    with pytest.raises(RuntimeError):
        with staged_directory(target) as work:
            (work / "a.txt").write_text("a")
            raise RuntimeError("stage failed")
    assert list(tmp_path.iterdir()) == []               # the folders created for the output are gone too
    assert write_files(target, {"a.txt": "a", "sub/b.txt": "b"}) == (target / "a.txt", target / "sub/b.txt")
    assert (target / "sub" / "b.txt").read_text() == "b"
    assert sorted(p.name for p in target.iterdir()) == ["a.txt", "sub"]


def test_an_atomic_file_keeps_the_old_content_when_the_write_fails(tmp_path):
    path = tmp_path / "cert.json"
    path.write_text("old")
    with pytest.raises(ValueError):
        with atomic_file(path) as partial:
            partial.write_text("half")
            raise ValueError("interrupted")
    assert path.read_text() == "old" and [p.name for p in tmp_path.iterdir()] == ["cert.json"]
    with pytest.raises(OutputError, match="it is a directory"):
        with atomic_file(tmp_path):
            pass


# ---------------------------------------------------------------------------------------- the page
def _table(page: str, heading: str) -> list[list[str]]:
    section = page.split(f"## {heading}\n", 1)[1].split("\n## ", 1)[0]
    rows = [line for line in section.splitlines() if line.startswith("|")]
    return [[cell.strip() for cell in row.strip("|").split("|")] for row in rows[2:]]


def test_the_limits_page_states_the_code_s_limits():
    page = (ROOT / "docs" / "errors.md").read_text("utf-8")
    stated = {row[0].strip("`"): row[1] for row in _table(page, "Limits")}
    assert stated == {name: str(value) for name, value in _limits.LIMITS.items()}


def test_the_page_gives_the_exit_status_of_every_command():
    page = (ROOT / "docs" / "errors.md").read_text("utf-8")
    listed = [row[0].strip("`") for row in _table(page, "Exit status per command")]
    assert sorted(listed) == sorted(COMMANDS)
    assert "errors.md" in (ROOT / "mkdocs.yml").read_text("utf-8")
    assert re.search(r"\| 130 \| interrupted", page)
