"""Entry point of the ``switchobs`` command.

Each sub-command lives in its own module ``switchobs.cli._<name>`` exposing
``register(subparsers)``, which adds its parser and sets ``func`` to a
callable ``func(args) -> int``.  Only the module of the command being run is
imported: ``switchobs --help`` lists the commands from :data:`COMMANDS`
without importing any (cvxpy, casadi and scipy.signal take seconds).  Errors
raised on purpose by switchobs (all subclasses of
:class:`switchobs.exceptions.SwitchobsError`) become one line on stderr and
exit status 2.  What a failure prints and which exit status it gives is the
policy of :mod:`switchobs.cli._errors` (``docs/errors.md``).

Global options (before or after the command): ``--version``, ``-q/--quiet``
(nothing on stderr but errors), ``-v/--verbose`` (every progress note as a
timestamped line).  Progress: by default a live status line on a terminal
(:class:`switchobs.cli._status.StatusLine`), nothing when stderr is a pipe or
a file; the stage lines of ``design`` (n > 4) and ``demo`` are the commands'
own output and are printed unless ``--quiet``.
"""

from __future__ import annotations

import argparse
import importlib
import math
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import NoReturn

from .. import __version__
from .._progress import listening
from ..exceptions import PrerequisiteError
from ._errors import EXIT_BAD_INPUT, guarded, unavailable_message
from ._status import StatusLine, is_terminal

__all__ = ["main", "build_parser"]

#: Sub-commands in the order of ``switchobs --help``: name -> the one-line help listed there.
COMMANDS: dict[str, str] = {
    "design": "design K_plus/K_minus, Routh conditions and the common P (sympy, exact)",
    "demo": "run the main job end to end (design, certify, C, braking with the C observer, report)",
    "encoder": "wheel-encoder chain: TSA, notch, three-stage and super-twisting RMS errors",
    "codegen": "generate the observer as strict C99 (casadi): <prefix>.c/.h and a README",
    "simulate": "ABS braking simulation (quarter car, five/two-phase ABS, XBS observers)",
    "certify": "certify the switched error dynamics (LMIs, dwell time, planar case) exactly",
    "synthesize": "synthesise a gain pair by LMIs (decay rate, noise gain) and certify it",
    "verify": "re-check a certificate exactly (exit 0 iff it holds)",
    "classify": "Balde-Boscain-Mason case (i)-(iv) of two Hurwitz 2x2 matrices",
    "theory": "write theory/*.md (model, normal form, gains, Routh, P, coupling) from the symbolic core",
    "reproduce": "regenerate docs/reproductions.md and the Table 4.1 / 6.1 sections from runs",
    "sweep": "design-space and robustness sweeps on Dask (tables, heatmaps, gain tuning)",
    "transform": "find (or check) s(y) and z = phi(x) putting dx/dt = f + g u, y = h into the normal form",
    "replay": "replay a measurement log (MDF4, CSV, Parquet) through the encoder chain and an XBS observer",
}

#: Verbosity levels (``args.verbosity``).
QUIET, NORMAL, VERBOSE = 0, 1, 2


def _add_verbosity(parser: argparse.ArgumentParser, default: object) -> None:
    group = parser.add_mutually_exclusive_group()
    group.add_argument("-q", "--quiet", dest="verbosity", action="store_const", const=QUIET, default=default,
                       help="print nothing on stderr but errors (no progress, no stage lines)")
    group.add_argument("-v", "--verbose", dest="verbosity", action="store_const", const=VERBOSE, default=default,
                       help="print every progress note as a line with its elapsed time (also into a pipe or file)")


class _Parser(argparse.ArgumentParser):
    """argparse with the failure policy of every other refusal: one line ``switchobs CMD: error: ...``, exit 2.

    argparse's own format (the usage, wrapped over several lines, then the error) would make a refused option
    the one failure that is not one line; ``--help`` still shows the usage.
    """

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


class _Completion(argparse.Action):
    """``--completion bash``: print the script and exit (the commands' modules are imported only then)."""

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace, values: object,
                 option_string: str | None = None) -> None:
        from ._completion import bash_completion

        sys.stdout.write(bash_completion())
        parser.exit()


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The ``switchobs`` parser; with ``only``, the parser of that sub-command (its module alone is imported).

    Without ``only`` the sub-commands are listed from :data:`COMMANDS` and none is importable: this parser
    answers ``--help``, ``--version`` and an unknown command.
    """
    parser = _Parser(
        prog="switchobs",
        description="Design, certify and export switched observers via singular time-rescaling.")
    parser.add_argument("--version", action="version", version=f"switchobs {__version__}")
    parser.add_argument("--completion", action=_Completion, choices=("bash",), metavar="SHELL",
                        help="print a completion script for SHELL (bash), generated from the commands' parsers")
    _add_verbosity(parser, NORMAL)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name, text in COMMANDS.items():
        if only is None:
            sub.add_parser(name, help=text, add_help=False)
            continue
        if name != only:
            continue
        try:
            module = importlib.import_module(f"switchobs.cli._{name}")
        except ImportError as exc:  # a broken casadi/cvxpy must not take every command down
            _register_unavailable(sub, name, exc)
        else:
            module.register(sub)
        # after the command too ("switchobs certify ... -q"); SUPPRESS keeps a value given before it
        _add_verbosity(sub.choices[name], argparse.SUPPRESS)
    return parser


def _register_unavailable(sub: argparse._SubParsersAction, name: str, exc: ImportError) -> None:
    message = unavailable_message(name, exc)

    def unavailable(args: argparse.Namespace) -> int:
        raise PrerequisiteError(message)

    p = sub.add_parser(name, add_help=False)
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


#: With --verbose, progress notes are printed at most one a second (a bisection announces every solve).
PROGRESS_AFTER_S = 0.0
PROGRESS_EVERY_S = 1.0
#: Commands that print their own stage lines (the library notes, as lines, would repeat them).
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


@contextmanager
def progress_display(command: str, verbosity: int) -> Iterator[None]:
    """Where the library's progress notes go while ``command`` runs (see the module docstring)."""
    if verbosity == VERBOSE:
        with listening(stderr_progress(command)):
            yield
    elif verbosity == NORMAL and is_terminal(sys.stderr):
        with StatusLine(command, sys.stderr) as status, listening(status):
            yield
    else:
        yield


def _ascii_safe_streams() -> None:
    """On streams that cannot encode Unicode (``PYTHONIOENCODING=ascii``, a ``C`` locale) a character
    without an ASCII form (``m/s²``) is escaped instead of failing the command; matrices print as ASCII art."""
    from .._display import unicode_output

    for stream in (sys.stdout, sys.stderr):
        if not unicode_output(stream) and hasattr(stream, "reconfigure"):
            stream.reconfigure(errors="backslashreplace")


def main(argv: Sequence[str] | None = None) -> int:
    argv = _glue_option_values(sys.argv[1:] if argv is None else argv)
    # Importing every command costs seconds (cvxpy, casadi, scipy.signal); a known command imports only its own.
    command = next((a for a in argv if not a.startswith("-")), None)
    parser = build_parser(command if command in COMMANDS else None)
    if command is None and not {"-h", "--help", "--version", "--completion"} & {a.split("=")[0] for a in argv}:
        parser.print_help()     # no command: what there is to run
        return 0
    args, unknown = parser.parse_known_args(argv)
    if unknown:   # the usage of the command they belong to, not the top-level one
        commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        commands.choices[args.command].error(f"unrecognized arguments: {' '.join(unknown)}")
    _ascii_safe_streams()   # a command runs: it has imported what it prints with

    def run() -> int:
        with progress_display(args.command, args.verbosity):
            return args.func(args)
    return guarded(args.command, run)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
