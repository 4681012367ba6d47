"""Entry point of the ``switchobs`` command.

Each sub-command lives in its own module ``switchobs.cli._<name>`` exposing
``register(subparsers)``, which adds its parser and sets ``func`` to a
callable ``func(args) -> int``.  What a failure prints and which exit status
it gives is the policy of :mod:`switchobs.cli._errors` (``docs/errors.md``).
"""

from __future__ import annotations

import argparse
import importlib
import math
import sys
import time
from collections.abc import Callable, Sequence

from .._progress import listening
from ..exceptions import PrerequisiteError
from ._errors import guarded

__all__ = ["main", "build_parser"]

#: Sub-command modules, in the order of ``switchobs --help``.
COMMANDS: tuple[str, ...] = ("design", "demo", "encoder", "codegen", "simulate", "certify", "synthesize", "verify",
                            "classify", "theory", "reproduce")


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The ``switchobs`` parser; with ``only``, just that sub-command (its module alone is imported)."""
    parser = argparse.ArgumentParser(
        prog="switchobs",
        description="Design, certify and export switched observers via singular time-rescaling.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name in COMMANDS:
        if only is not None and name != only:
            continue
        try:
            module = importlib.import_module(f"switchobs.cli._{name}")
        except ImportError as exc:  # a broken casadi/cvxpy must not take every command down
            _register_unavailable(sub, name, exc)
        else:
            module.register(sub)
    return parser


def _register_unavailable(sub: argparse._SubParsersAction, name: str, exc: ImportError) -> None:
    what = f"importing {exc.name} failed" if exc.name else "a dependency failed to import"
    message = (f"command {name!r} cannot run: {what} ({exc}); "
               "reinstall with `make install` (or pip install -e .)")

    def unavailable(args: argparse.Namespace) -> int:
        raise PrerequisiteError(message)

    p = sub.add_parser(name, help=f"(unavailable: {exc})", add_help=False)
    p.add_argument("rest", nargs=argparse.REMAINDER)
    p.set_defaults(func=unavailable)


#: Options whose value may start with "-" (a pole "-beta1", a gain "-2"); argparse would
#: take such a value for an option, so "--spectrum -1,-2" is rewritten "--spectrum=-1,-2".
VALUE_OPTIONS: frozenset[str] = frozenset({"--spectrum", "--charpoly", "--gains-plus", "--gains-minus"})


def _glue_option_values(argv: Sequence[str]) -> list[str]:
    out: list[str] = []
    it = iter(argv)
    for token in it:
        if token in VALUE_OPTIONS:
            value = next(it, None)
            out.append(token if value is None else f"{token}={value}")
        else:
            out.append(token)
    return out


#: Progress notes of the library are shown once a command has run this long (quick runs stay quiet), and at
#: most one a second (a bisection announces every solve).
PROGRESS_AFTER_S = 1.0
PROGRESS_EVERY_S = 1.0
#: Commands that print their own stage lines (the library notes would repeat them).
OWN_PROGRESS = frozenset({"demo"})


def stderr_progress(command: str, after_s: float = PROGRESS_AFTER_S,
                    every_s: float = PROGRESS_EVERY_S) -> Callable[[str], None]:
    """A progress listener printing ``switchobs CMD: [elapsed] stage (size)`` on stderr after ``after_s``."""
    start = time.perf_counter()
    last = [-math.inf]

    def show(text: str) -> None:
        now = time.perf_counter()
        if now - start >= after_s and now - last[0] >= every_s and command not in OWN_PROGRESS:
            last[0] = now
            print(f"switchobs {command}: [{now - start:6.1f} s] {text}", file=sys.stderr, flush=True)

    return show


def main(argv: Sequence[str] | None = None) -> int:
    argv = _glue_option_values(sys.argv[1:] if argv is None else argv)
    # Importing every command costs seconds (cvxpy, casadi, scipy.signal); a known command imports only its own.
    command = next((a for a in argv if not a.startswith("-")), None)
    parser = build_parser(command if command in COMMANDS else None)
    args = parser.parse_args(argv)

    def run() -> int:
        with listening(stderr_progress(args.command)):
            return args.func(args)
    return guarded(args.command, run)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
