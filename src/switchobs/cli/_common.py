"""Helpers shared by the sub-commands: model loading with --param, JSON output, ``-`` for stdout, generated files."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any, TextIO

from .._atomic import check_output_file
from ..exceptions import ModelError, OutputError, SwitchobsError
from ..model import Model, builtin_names, load_model
from .main import QUIET

__all__ = ["add_model_arguments", "model_from_args", "parse_params", "emit_json", "write_or_check", "STDIO",
           "summary_stream", "write_certificate", "output_file", "output_directory", "figure_file", "check_output",
           "note_uncertified"]

#: The file name that means standard input (a model, a certificate) or standard output (``--out -``).
STDIO = "-"


def output_file(text: str) -> str:
    """``type=`` of an option naming an output file (``-``: standard output where the option says so): not empty."""
    if not text.strip():
        raise argparse.ArgumentTypeError("the path is empty; give a file name")
    return text


def output_directory(text: str) -> str:
    """``type=`` of an option naming an output directory: not empty and not ``-`` (several files go there)."""
    if not text.strip() or text == STDIO:
        raise argparse.ArgumentTypeError(f"{text!r} is not a directory name; give one (several files are written "
                                         "there, so standard output cannot take them)")
    return text


def figure_file(text: str) -> str:
    """``type=`` of ``--plot``: a path matplotlib can write (its suffix names the format), in a writable directory,
    checked when the command line is read, before any work."""
    from .._figures import figure_format

    output_file(text)
    try:
        figure_format(text)
        check_output_file(text, what="the plot")
    except SwitchobsError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text


def check_output(path: str | None, *, what: str, inputs: Iterable[str] = ()) -> None:
    """Before the work: ``path`` (unless absent or ``-``) can be written and is none of the command's ``inputs``
    (``certify model.toml --out model.toml`` would replace the model by its certificate)."""
    if path is None or path == STDIO:
        return
    target = check_output_file(path, what=what)
    for source in inputs:
        if source != STDIO and target.exists() and Path(source).exists() and target.samefile(source):
            raise OutputError(f"cannot write {what} {path!r}: it is the input {source!r}; give another path")


def add_model_arguments(parser: argparse.ArgumentParser) -> None:
    """MODEL positional and repeatable ``--param NAME=VALUE``."""
    parser.add_argument("model", metavar="MODEL",
                        help=f"built-in model ({', '.join(builtin_names())}), a TOML file, "
                             "or - for a TOML model on standard input")
    parser.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                        help="substitute a parameter value (repeatable), e.g. --param a=187.5")


def parse_params(items: list[str]) -> dict[str, str]:
    """``["a=187.5", "c=34"]`` -> ``{"a": "187.5", "c": "34"}`` with clear errors."""
    out: dict[str, str] = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name.strip() or not value.strip():
            raise ModelError(f"--param expects NAME=VALUE, got {item!r}")
        if name.strip() in out:
            raise ModelError(f"--param gives {name.strip()!r} twice")
        out[name.strip()] = value.strip()
    return out


def model_from_args(args: argparse.Namespace) -> Model:
    model = load_model(args.model)
    return model.with_values(parse_params(args.param))


def emit_json(data: Any) -> None:
    json.dump(data, sys.stdout, indent=2)
    sys.stdout.write("\n")


def summary_stream(args: argparse.Namespace) -> TextIO | None:
    """Where a command writing a certificate prints its summary: stdout, or stderr when the certificate goes
    to stdout (``--out -``), or nowhere then with ``--quiet``."""
    if getattr(args, "out", None) != STDIO:
        return sys.stdout
    return None if args.verbosity == QUIET else sys.stderr


def note_uncertified(args: argparse.Namespace, method: str) -> None:
    """One line on stderr when the switched observer's step ``method`` is not certified (not an error; nothing
    with ``--quiet``): the command goes on with it."""
    from ..spec import uncertified_note

    note = uncertified_note(method)
    if note is not None and args.verbosity != QUIET:
        print(f"switchobs {args.command}: note: {note}", file=sys.stderr)


def write_certificate(report: Any, out: str) -> None:
    """``--out``: the certificate into a file (``report.write``), or as JSON on standard output for ``-``."""
    if out == STDIO:
        emit_json(report.document)
    else:
        report.write(out)


def write_or_check(check: bool, stale: Callable[[], Iterable[Path]], write: Callable[[], Iterable[Path]],
                   regenerate: str, target: Path) -> int:
    """Generated files: list the ``stale`` ones and exit 1 (``check``), or ``write`` them and say so."""
    if check:
        paths = list(stale())
        for path in paths:
            print(f"{path}: differs from the generated text; run `{regenerate}`", file=sys.stderr)
        if not paths:
            print(f"{target}: up to date")
        return 1 if paths else 0
    for path in write():
        print(f"wrote {path}")
    return 0
