"""User text cannot inject code into the generated C (issue "Hostile input, round 2", security item 1).

Every text a model file carries into the generated files (name, description, references, the recorded
command line) is written through one escaper (``switchobs.codegen._text.c_comment``).  The test writes
hostile texts into a model file, generates the C through the CLI, compiles it and inspects the object:
every symbol is the generated observer's, its global symbols are exactly the API the header declares,
and there is no constructor section.
"""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

from switchobs.cli.main import main
from switchobs.codegen._text import c_comment

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "my_model.toml"

#: Texts that end, nest or splice a C comment, or smuggle a line break, if written as they are.
HOSTILE = [
    "x */ int injected = 1; /*",
    "x */ __attribute__((constructor)) static void injected(void) { } /*",
    "*/\n#define switchobs_my_wheel_step injected\n/*",
    "a *??/\n/ int injected = 2; /* trigraph splice",
    "b *\\\n/ int injected = 3; /* backslash splice",
    "c */\r int injected = 4; /* carriage return",
    "d \u2028*/ int injected = 5; /* unicode line separator",
    "e */ int injected = 6; // ` ``` `",
]


def _nm() -> str:
    tool = shutil.which("nm")
    if tool is None:
        pytest.skip("nm is not installed: the symbols of hostile generated C are NOT checked")
    return tool


def _toml_string(text: str) -> str:
    return '"' + "".join(ch if ch.isalnum() or ch in " */;(){}=#_.-,`?" else f"\\u{ord(ch):04X}" for ch in text) + '"'


def _hostile_model(tmp_path: Path, text: str) -> Path:
    source = EXAMPLE.read_text("utf-8")
    source = re.sub(r'^description = .*$', lambda _: f"description = {_toml_string(text)}", source, count=1,
                    flags=re.M)
    # a name is one line of printable ASCII (the model reader may refuse others); it still reaches the files
    name = re.sub(r"[^ -~]", " ", "w " + text)
    source = re.sub(r'^name = .*$', lambda _: f"name = {_toml_string(name)}", source, count=1, flags=re.M)
    source = source.replace('model = "Hoang', f"hostile = {_toml_string(text)}\nmodel = \"Hoang")
    path = tmp_path / "hostile.toml"
    path.write_text(source, "utf-8")
    return path


def _declared_api(header: str, prefix: str) -> set[str]:
    code = re.sub(r"/\*.*?\*/", " ", header, flags=re.S)
    code = "\n".join(line for line in code.splitlines() if not line.lstrip().startswith("#"))
    return set(re.findall(rf"\b({re.escape(prefix)}_\w+)\s*[\[(]", code))


@pytest.mark.parametrize("text", HOSTILE, ids=[f"hostile{i}" for i in range(len(HOSTILE))])
def test_hostile_model_text_cannot_add_a_symbol_or_constructor_to_the_generated_object(tmp_path, text, capsys):
    nm = _nm()
    model = _hostile_model(tmp_path, text)
    prefix = "safe_obs"
    out = tmp_path / "c"
    rc = main(["codegen", str(model), "--spectrum=-100,-100,-100", "--method", "radau3", "--prefix", prefix,
               "--out", str(out), "-q"])
    capsys.readouterr()
    assert rc == 0
    files = {p.name: p.read_text("utf-8") for p in out.iterdir()}
    assert all(body.isascii() for name, body in files.items() if name.endswith((".c", ".h")))
    obj = tmp_path / "obs.o"
    subprocess.run(["gcc", "-std=c99", "-c", str(out / f"{prefix}.c"), "-o", str(obj)], check=True,
                   capture_output=True)
    symbols = subprocess.run([nm, str(obj)], check=True, capture_output=True, text=True).stdout.split("\n")
    defined = [line.split() for line in symbols if len(line.split()) == 3]
    assert all(sym.startswith(prefix + "_") for _, _, sym in defined), defined
    exported = {sym for _, kind, sym in defined if kind.isupper()}
    assert exported == _declared_api(files[f"{prefix}.h"], prefix)
    sections = subprocess.run(["objdump", "-h", str(obj)], check=True, capture_output=True, text=True).stdout
    assert ".init_array" not in sections and ".ctors" not in sections


@pytest.mark.parametrize("text", HOSTILE, ids=[f"hostile{i}" for i in range(len(HOSTILE))])
def test_c_comment_leaves_no_comment_delimiter_splice_or_line_break(text):
    safe = c_comment(text)
    assert "*/" not in safe and "/*" not in safe and "??" not in safe and "\\" not in safe
    assert safe.isascii() and safe.isprintable() and "`" not in safe


def test_c_comment_keeps_plain_text_as_it_is():
    text = "3D XBS-like wheel model with a drift, the example of examples/design_my_model.py (eq. (7))"
    assert c_comment(text) == text


def test_c_comment_cites_the_papers_by_author_and_year_in_ascii():
    text = "the observer (seed 000 eq. (8)-(9), seed 004); seed 002 is not a paper"
    assert c_comment(text) == "the observer (Hoang et al. 2014 eq. (8)-(9), Pasillas-Lepine); seed 002 is not a paper"


def test_a_name_with_a_trailing_newline_is_refused_before_it_becomes_a_c_macro(tmp_path, capsys):
    # "^...$" admitted "z1\n": the macro line "#define P_X_Z1\n 0" would break the header
    source = EXAMPLE.read_text("utf-8").replace('states = ["z1", "z2", "z3"]', 'states = ["z1\\n", "z2", "z3"]')
    path = tmp_path / "newline.toml"
    path.write_text(source, "utf-8")
    rc = main(["codegen", str(path), "--spectrum=-1,-2,-3", "--out", str(tmp_path / "c"), "-q"])
    err = capsys.readouterr().err
    assert rc == 2 and "not a valid name" in err and err.count("\n") == 1
    assert not (tmp_path / "c").exists()
