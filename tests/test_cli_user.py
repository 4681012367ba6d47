"""A conventional command line: help without a command, the sub-command's usage for its own bad options, ASCII
terminals, complete MODEL lists."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from switchobs.cli.main import build_parser, main
from switchobs.model import builtin_names

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("argv", [[], ["-q"]])
def test_no_command_prints_the_help(argv, capsys):
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: switchobs") and "synthesize" in out and "transform" in out


def test_an_unknown_option_shows_the_usage_of_its_command(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["design", "abs-xbs3", "--bogus"])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("usage: switchobs design") and err.rstrip().endswith("unrecognized arguments: --bogus")


def test_an_ascii_terminal_gets_ascii_matrices_and_no_encoding_error(tmp_path):
    env = {**os.environ, "PYTHONIOENCODING": "ascii", "PYTHONPATH": str(ROOT / "src")}
    for argv in (["design", "abs-xbs3", "--spectrum=-beta1,-beta2,-beta2"], ["simulate", "--duration", "0.1"]):
        proc = subprocess.run([sys.executable, "-m", "switchobs", *argv], cwd=tmp_path, env=env, capture_output=True,
                              timeout=300)
        assert proc.returncode == 0, proc.stderr.decode("ascii", "replace")
        assert proc.stdout.isascii() and b"Error" not in proc.stderr
    assert b"K_plus =" in subprocess.run([sys.executable, "-m", "switchobs", "design", "abs-xbs3",
                                          "--spectrum=-1,-2,-3"], cwd=tmp_path, env=env, capture_output=True,
                                         timeout=300).stdout


@pytest.mark.parametrize("command", ["design", "certify", "codegen", "synthesize"])
def test_the_model_help_lists_every_built_in_model(command):
    text = " ".join(build_parser(command)._subparsers._group_actions[0].choices[command].format_help().split())
    assert all(name in text for name in builtin_names()), text
