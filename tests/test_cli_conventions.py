"""Command-line conventions: cheap --help, --version, -q/-v, - for stdin/stdout, the progress display."""

from __future__ import annotations

import ast
import importlib
import importlib.metadata
import io
import json
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

import switchobs
from switchobs._progress import listening, progress
from switchobs.cli import main as cli
from switchobs.cli._status import StatusLine
from switchobs.cli.main import COMMANDS, QUIET, VERBOSE, build_parser, main
from switchobs.plants import BrakingScenario, simulate, table41
from switchobs.sensors import compare_estimators, constant_speed

ROOT = Path(__file__).resolve().parents[1]
#: Packages that cost seconds to import: --help, --version and a mistyped command must not need them.
HEAVY = ("numpy", "scipy", "sympy", "cvxpy", "casadi", "matplotlib", "control", "clarabel", "scs", "mpmath")
#: A certificate small enough to write by hand (the docstring example of verify_certificate).
TINY_CERTIFICATE = {"format": "switchobs-certificate", "version": 1,
                    "family": {"names": ["A1"], "matrices": [[["-1"]]]},
                    "certificates": [{"kind": "strict-cqlf", "P": [["1"]]}],
                    "verdict": {"arbitrary_switching": "UGES", "dwell_time": "any", "strict_cqlf": "exists",
                                "common_lyapunov": "exists"}}


class Terminal(io.StringIO):
    """A stream that says it is a terminal."""

    def isatty(self) -> bool:
        return True


# ---------------------------------------------------------------- cheap entry points
@pytest.mark.parametrize("argv, code", [(["--help"], 0), (["--version"], 0), (["no-such-command"], 2), ([], 0)])
def test_help_version_and_a_wrong_command_import_no_heavy_package(argv, code):
    probe = ("import sys\nfrom switchobs.cli.main import main\n"
             f"try:\n    code = main({argv!r})\nexcept SystemExit as exc:\n    code = exc.code\n"
             f"heavy = sorted({{m.split('.')[0] for m in sys.modules}} & set({HEAVY!r}))\n"
             "print('HEAVY', code, heavy, file=sys.stderr)")
    proc = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120)
    assert proc.stderr.strip().splitlines()[-1] == f"HEAVY {code} []", proc.stderr


def test_help_lists_every_command_of_the_table_with_its_line(capsys, monkeypatch):
    monkeypatch.setenv("COLUMNS", "300")     # one line per command
    with pytest.raises(SystemExit) as exc:
        main(["--help"])
    assert exc.value.code == 0
    listing = [" ".join(line.split()) for line in capsys.readouterr().out.splitlines()]
    for name, text in COMMANDS.items():
        assert f"{name} {text}" in listing


@pytest.mark.parametrize("name", list(COMMANDS))
def test_every_command_of_the_table_has_a_module_that_registers_it(name):
    parser = build_parser(name)
    subparsers = next(a for a in parser._actions if a.dest == "command")
    assert list(subparsers.choices) == [name]
    assert hasattr(importlib.import_module(f"switchobs.cli._{name}"), "register")


#: What a chosen command's --help or argparse error must not import (numpy and sympy are cheap next to these).
SLOW_TO_IMPORT = ("scipy", "cvxpy", "casadi", "matplotlib", "control", "dask", "distributed")


def test_a_commands_help_and_its_argparse_errors_import_none_of_the_slow_packages():
    """Every command's module imports its heavy dependencies only when it runs (one process for all commands)."""
    probe = ("import sys\nfrom switchobs.cli.main import COMMANDS, main\n"
             f"slow = set({SLOW_TO_IMPORT!r})\n"
             "for name in COMMANDS:\n"
             "    for argv in ([name, '--help'], [name, '--no-such-option']):\n"
             "        try:\n            main(argv)\n        except SystemExit as exc:\n            code = exc.code\n"
             "        loaded = sorted({m.split('.')[0] for m in sys.modules} & slow)\n"
             "        print('SLOW', name, argv[1], code, loaded, file=sys.stderr)\n")
    proc = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=300)
    lines = [line for line in proc.stderr.splitlines() if line.startswith("SLOW ")]
    expected = [f"SLOW {name} {option} {code} []" for name in COMMANDS
                for option, code in (("--help", 0), ("--no-such-option", 2))]
    assert lines == expected, proc.stderr[-3000:]


def test_certify_and_verify_without_an_lmi_import_neither_cvxpy_nor_scipy(tmp_path):
    """A family proved by the singular sum and the design's exact P solves no LMI: no solver import (1.5 s)."""
    model = tmp_path / "chain.toml"
    model.write_text('name = "chain-4"\nstates = ["x1", "x2", "x3", "x4"]\noutput = "y"\n'
                     'A = [["-1", "1", "0", "0"], ["0", "-3/2", "1", "0"], ["0", "0", "-2", "1"], '
                     '["0", "0", "0", "-5/2"]]\nC = ["1", "0", "0", "0"]\ntime_scale = "y"\n', encoding="utf-8")
    cert = tmp_path / "chain.json"
    probe = ("import sys\nfrom switchobs.cli.main import main\n"
             f"codes = [main(['certify', {str(model)!r}, '--spectrum=-2,-3,-5/2,-7/2', '--out', {str(cert)!r}]),\n"
             f"         main(['verify', {str(cert)!r}])]\n"
             "loaded = sorted({m.split('.')[0] for m in sys.modules} & {'cvxpy', 'scipy', 'matplotlib', 'casadi'})\n"
             "print('LOADED', codes, loaded, file=sys.stderr)")
    proc = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=300)
    assert proc.stderr.strip().splitlines()[-1] == "LOADED [0, 0] []", proc.stderr[-3000:]


def test_design_of_a_small_model_imports_no_plant_loop_sensor_or_solver(tmp_path):
    """``design`` only prints stage lines from switchobs.report: not its demo's plants, loop and sensors (0.3 s)."""
    model = tmp_path / "chain.toml"
    model.write_text('name = "chain-4"\nstates = ["x1", "x2", "x3", "x4"]\noutput = "y"\n'
                     'A = [["-1", "1", "0", "0"], ["0", "-3/2", "1", "0"], ["0", "0", "-2", "1"], '
                     '["0", "0", "0", "-5/2"]]\nC = ["1", "0", "0", "0"]\ntime_scale = "y"\n', encoding="utf-8")
    probe = ("import sys\nfrom switchobs.cli.main import main\n"
             f"code = main(['design', {str(model)!r}, '--spectrum=-2,-3,-5/2,-7/2'])\n"
             "loaded = sorted({'.'.join(m.split('.')[:2]) for m in sys.modules}\n"
             "                & {'switchobs.plants', 'switchobs.loop', 'switchobs.sensors', 'cvxpy', 'casadi',"
             " 'matplotlib'})\n"
             "print('LOADED', code, loaded, file=sys.stderr)")
    proc = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=300)
    assert proc.stderr.strip().splitlines()[-1] == "LOADED 0 []", proc.stderr[-3000:]


def test_version_is_single_sourced(capsys):
    with pytest.raises(SystemExit):
        main(["--version"])
    assert capsys.readouterr().out.strip() == f"switchobs {switchobs.__version__}"
    assert importlib.metadata.version("switchobs") == switchobs.__version__
    project = tomllib.loads((ROOT / "pyproject.toml").read_text("utf-8"))["project"]
    assert "version" in project["dynamic"] and "version" not in project


def test_every_third_party_import_of_the_package_is_declared():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text("utf-8"))["project"]
    # import name -> distribution name where they differ
    distribution = {"flint": "python-flint"}
    declared = {req.split(">")[0].split("[")[0].split("=")[0].strip().lower()
                for req in project["dependencies"] + project["optional-dependencies"]["codegen"]
                + project["optional-dependencies"]["sweep"] + project["optional-dependencies"]["fmu"]
                + project["optional-dependencies"]["logs"]}
    imported = set()
    for path in (ROOT / "src" / "switchobs").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text("utf-8"))):
            if isinstance(node, ast.Import):
                imported |= {alias.name.split(".")[0] for alias in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                imported.add(node.module.split(".")[0])
    third_party = {distribution.get(m, m) for m in imported - set(sys.stdlib_module_names)
                   if m not in ("switchobs", "__future__")}
    assert third_party and third_party <= declared, sorted(third_party - declared)
    assert project["license"] == "MIT" and (ROOT / "LICENSE").read_text("utf-8").startswith("MIT License")


@pytest.mark.parametrize("argv, verbosity", [
    (["-q", "verify", "c.json"], QUIET), (["verify", "c.json", "--quiet"], QUIET),
    (["--verbose", "verify", "c.json"], VERBOSE), (["verify", "-v", "c.json"], VERBOSE),
    (["verify", "c.json"], 1),
])
def test_quiet_and_verbose_go_before_or_after_the_command(argv, verbosity):
    assert build_parser("verify").parse_args(argv).verbosity == verbosity


@pytest.mark.parametrize("module, hint", [("casadi", 'pip install "switchobs[codegen]"'),
                                          ("distributed", 'pip install "switchobs[sweep]"'),
                                          ("matplotlib", 'pip install --force-reinstall "switchobs"')])
def test_a_missing_optional_package_names_its_extra(monkeypatch, capsys, module, hint):
    def needs(args):
        raise ModuleNotFoundError(f"No module named {module!r}", name=module)

    monkeypatch.setattr("switchobs.cli._classify.run", needs)
    assert main(["classify", "[[-1]]", "[[-2]]"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and hint in err and module in err
    assert "make install" not in err and "-e ." not in err     # an installed user has no repository


# ---------------------------------------------------------------- - for standard input and output
def test_verify_reads_the_certificate_from_standard_input(monkeypatch, capsys):
    monkeypatch.setattr("sys.stdin", io.StringIO(json.dumps(TINY_CERTIFICATE)))
    assert main(["verify", "-"]) == 0
    assert "\ncertificate holds exactly\n" in capsys.readouterr().out
    monkeypatch.setattr("sys.stdin", io.StringIO("not json"))
    assert main(["verify", "-"]) == 2
    assert "certificate '<stdin>' is not valid JSON" in capsys.readouterr().err


def test_certify_reads_the_model_from_stdin_and_writes_the_certificate_to_stdout(monkeypatch, capsys):
    model = (ROOT / "examples" / "my_model.toml").read_text("utf-8")
    monkeypatch.setattr("sys.stdin", io.StringIO(model))
    argv = ["certify", "-", "--spectrum", "-40,-60,-60", "--no-dwell", "--out", "-"]
    params = ["--param", "a=187.5", "--param", "b=-1", "--param", "c=34", "--param", "k=1"]
    assert main(argv + params) == 0
    out, err = capsys.readouterr()
    document = json.loads(out)                          # stdout holds the certificate alone
    assert document["provenance"]["model"] == "my-wheel"
    assert err.startswith("switchobs certify: model my-wheel") and "certificate written" not in err
    monkeypatch.setattr("sys.stdin", io.StringIO(out))
    assert main(["verify", "-"]) == 0
    assert "\ncertificate holds exactly\n" in capsys.readouterr().out
    assert main(["certify", "abs-xbs3", "--spectrum", "-40,-60,-60", "--out", "-", "--json"]) == 2
    assert "not both" in capsys.readouterr().err


# ---------------------------------------------------------------- progress
def test_long_library_loops_count_their_steps():
    notes: list[str] = []
    with listening(notes.append):
        table41(roads=("dry-asphalt",), speeds_kmh=(60.0,))
        compare_estimators(constant_speed(600.0, 1.2), estimators=("tsa", "notch"))
    table = [n for n in notes if n.startswith("simulate: Table 4.1")]   # the Python loop adds its own notes
    assert table == ["simulate: Table 4.1 [1/2] five-phase, dry-asphalt, 60 km/h",
                     "simulate: Table 4.1 [2/2] two-phase, dry-asphalt, 60 km/h"]
    assert [n for n in notes if n.startswith("encoder: [")] == [
        "encoder: [1/2] tsa estimator" + notes[-2].split("tsa estimator")[1],
        "encoder: [2/2] notch estimator" + notes[-1].split("notch estimator")[1]]



def test_the_python_simulation_loop_counts_tenths_of_its_time_bound():
    notes: list[str] = []
    with listening(notes.append):
        simulate(BrakingScenario("dry-asphalt", speed_m_s=15.0, duration_s=0.2), compiled=False)
    assert [n.split(" t = ")[0] for n in notes] == [f"simulate: braking [{k}/10]" for k in range(1, 11)]
    assert notes[-1].endswith("t = 0.2 s of 0.2 s")

def test_the_status_line_draws_a_bar_keeps_it_for_the_steps_notes_and_fits_the_terminal():
    status = StatusLine("simulate", Terminal())
    status("simulate: Table 4.1 [3/4] two-phase, wet-asphalt, 120 km/h")
    line = status.render(12.34, 200)
    assert line.endswith("  12.3 s  [###############.....] simulate: Table 4.1 [3/4] two-phase, wet-asphalt, 120 km/h")
    status("design: common Lyapunov matrix P (n = 3)")
    assert status.render(12.34, 200).endswith("120 km/h · design: common Lyapunov matrix P (n = 3)")
    assert len(status.render(12.34, 40)) == 39
    status("simulate: Table 4.1 [4/4] five-phase, snow, 60 km/h")
    assert "[####################] simulate: Table 4.1 [4/4]" in status.render(1.0, 200)


def test_the_status_line_gives_way_to_the_commands_output_and_leaves_nothing_behind(monkeypatch):
    terminal = Terminal()
    monkeypatch.setattr("sys.stderr", terminal)
    monkeypatch.setenv("COLUMNS", "200")
    with StatusLine("certify", terminal, after_s=60.0) as status:   # the test draws, not the clock
        status("certify: strict common quadratic Lyapunov LMI (n = 3, 2 modes)")
        status._draw()
        assert terminal.getvalue().startswith("\r") and terminal.getvalue().endswith("(n = 3, 2 modes)\x1b[K")
        print("[1/2] design: gains", file=sys.stderr)        # the command's own stage line
        status._draw()
    text = terminal.getvalue()
    assert "\x1b[K\r\x1b[K[1/2] design: gains\n\r" in text    # erased first, drawn again below it
    assert text.endswith("\r\x1b[K") and sys.stderr is terminal


def test_main_shows_the_status_line_on_a_terminal_only_and_lines_with_verbose(monkeypatch, capsys):
    class Drawing(StatusLine):   # draws at each note, so the test does not depend on the clock
        def __call__(self, text: str) -> None:
            super().__call__(text)
            self._draw()

    monkeypatch.setattr(cli, "StatusLine", Drawing)

    def noisy(args):
        progress("verify: [1/1] strict-cqlf certificate")
        print("result")
        return 0

    monkeypatch.setattr("switchobs.cli._verify.run", noisy)
    terminal = Terminal()
    monkeypatch.setattr("sys.stderr", terminal)
    assert main(["verify", "x.json"]) == 0
    assert "switchobs verify" in terminal.getvalue() and "[####################] verify: [1/1]" in terminal.getvalue()
    assert terminal.getvalue().endswith("\r\x1b[K") and capsys.readouterr().out == "result\n"
    for argv, expected in ((["-q", "verify", "x.json"], ""),
                           (["-v", "verify", "x.json"], "switchobs verify: [")):
        terminal = Terminal()
        monkeypatch.setattr("sys.stderr", terminal)
        assert main(argv) == 0
        assert terminal.getvalue().startswith(expected) and (expected or terminal.getvalue() == "")
    pipe = io.StringIO()                                    # not a terminal: silent
    monkeypatch.setattr("sys.stderr", pipe)
    assert main(["verify", "x.json"]) == 0
    assert pipe.getvalue() == ""
