"""The failure policy of the ``switchobs`` command: one line on stderr and a documented exit status.

=====  ==========================================================================
 0     success (a certificate holds, files written, a run finished)
 1     a negative verdict or a failed run (no certificate holds, an observer diverged)
 2     bad input or environment (a malformed model or certificate, a limit exceeded,
       an output that cannot be written, a missing compiler), and internal errors
 130   interrupted (Ctrl-C)
=====  ==========================================================================

Nothing else reaches the user: errors raised on purpose
(:class:`switchobs.exceptions.SwitchobsError`) print their message; input that
exhausts the interpreter (``RecursionError``, ``MemoryError``,
``OverflowError``) and a failed write (``OSError``, naming the path) print
what happened; any other exception is a bug, printed as one line asking for a
report (with the traceback when ``SWITCHOBS_DEBUG=1``).  ``docs/errors.md``
states the same policy.
"""

from __future__ import annotations

import os
import sys
import traceback
import warnings
from collections.abc import Callable
from typing import Any

from .._papers import cite
from ..exceptions import EXTRAS, FreeSymbolError, OutputError, SwitchobsError, install_hint

__all__ = ["EXIT_OK", "EXIT_FAILED", "EXIT_BAD_INPUT", "EXIT_INTERRUPTED", "DEBUG_ENV", "EXTRAS", "guarded",
           "install_hint", "unavailable_message", "flush_stdout"]

EXIT_OK = 0
EXIT_FAILED = 1
EXIT_BAD_INPUT = 2
EXIT_INTERRUPTED = 130
#: Environment variable: when set to a non-empty value other than 0, an internal error also prints its traceback.
DEBUG_ENV = "SWITCHOBS_DEBUG"


def unavailable_message(command: str, exc: ImportError) -> str:
    """Why ``command`` cannot run when a third-party package it imports is missing or broken."""
    what = f"importing {exc.name} failed" if exc.name else "a dependency failed to import"
    return f"command {command!r} cannot run: {what} ({exc}); {install_hint(exc.name)}"


def _one_line(text: str, limit: int = 500) -> str:
    line = " ".join(str(text).split())
    return line if len(line) <= limit else line[:limit] + " ..."


def _message(exc: BaseException, command: str) -> str:
    """The one line for an exception that escaped a command, without the ``switchobs CMD: error:`` prefix."""
    if isinstance(exc, SwitchobsError):
        # The library names what has no value; only here is the way to give it a command-line flag.
        hint = "; give values with --param NAME=VALUE" if isinstance(exc, FreeSymbolError) else ""
        return f"{exc}{hint}"
    # A command imports cvxpy, casadi, scipy or matplotlib when it runs, not when it is registered (so that
    # its --help and argparse errors stay fast): a missing or broken one surfaces here.  An import error of
    # switchobs itself is a bug, reported as one below.
    top = (getattr(exc, "name", None) or "").split(".")[0]
    if isinstance(exc, ModuleNotFoundError) and top in EXTRAS:
        return f"this needs {exc.name}, which is not installed; {install_hint(exc.name)}"
    if isinstance(exc, ImportError) and top != "switchobs":
        return unavailable_message(command, exc)
    if isinstance(exc, RecursionError):
        return "the input is nested too deeply to process (RecursionError); simplify it"
    if isinstance(exc, MemoryError):
        return "out of memory: the input or the options ask for more than this machine has; make them smaller"
    if isinstance(exc, RuntimeWarning):
        return (f"a numeric computation overflowed or became undefined ({exc}); the values or options are beyond "
                "what double precision handles: make them smaller")
    if isinstance(exc, OverflowError):
        return f"a number is too large to process ({exc}); check the values and options"
    if isinstance(exc, OSError):
        where = f" {exc.filename!r}" if exc.filename else ""
        return f"cannot access{where}: {exc.strerror or exc}"
    return (f"internal error {type(exc).__name__}: {exc} (a bug in switchobs: please report it with the command "
            f"line; {DEBUG_ENV}=1 shows the traceback)")


class _CheckedStdout:
    """Standard output whose failed writes are :class:`OutputError` (exit 2): a full disk or ``/dev/full`` loses
    the output, which is a failure, not a success reported by no one.  A closed pipe stays BrokenPipeError."""

    def __init__(self, stream: Any):
        self._stream = stream

    def _failed(self, exc: OSError) -> OutputError:
        try:  # what is still buffered goes nowhere, so that the interpreter's own flush at exit does not fail again
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, self._stream.fileno())
            os.close(devnull)
        except (OSError, ValueError, AttributeError):
            pass
        return OutputError(f"cannot write to standard output: {exc.strerror or exc}")

    def write(self, text: str) -> int:
        try:
            return self._stream.write(text)
        except BrokenPipeError:
            raise
        except OSError as exc:
            raise self._failed(exc) from None

    def flush(self) -> None:
        try:
            self._stream.flush()
        except BrokenPipeError:
            raise
        except OSError as exc:
            raise self._failed(exc) from None

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)


#: The messages of numpy's floating-point warnings (``np.seterr``), also as scipy passes them on.
_FLOATING_POINT_WARNINGS = r".*(overflow|invalid value|divide by zero|underflow) encountered"


def flush_stdout() -> None:
    """Push what the command printed to standard output; :class:`OutputError` if it cannot take it."""
    sys.stdout.flush()


def guarded(command: str, run: Callable[[], int | None]) -> int:
    """Run one sub-command under the policy: its exit status, or one line on stderr and 1, 2 or 130.

    Standard output must be open (``>&-`` would lose every result) and take all that was printed.
    """
    stdout = sys.stdout
    try:
        if stdout is None:
            raise OutputError("standard output is closed: the results would be lost; redirect it to a file or "
                              "/dev/null")
        sys.stdout = _CheckedStdout(stdout)
        with warnings.catch_warnings():
            # numpy's floating-point warnings would print several lines (also with -q) and let a run go on with
            # inf or NaN: they end it as bad input.  Code that overflows on purpose says so with np.errstate.
            warnings.filterwarnings("error", message=_FLOATING_POINT_WARNINGS, category=RuntimeWarning)
            code = int(run() or EXIT_OK)
        flush_stdout()
        return code
    except BrokenPipeError:  # output piped into `head`: not an error of ours
        sys.stdout = open(os.devnull, "w")
        return EXIT_OK
    except KeyboardInterrupt:
        print(f"switchobs {command}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Exception as exc:
        if os.environ.get(DEBUG_ENV, "") not in ("", "0"):
            traceback.print_exc()
        print(f"switchobs {command}: error: {_one_line(cite(_message(exc, command)))}", file=sys.stderr)
        return EXIT_BAD_INPUT
    finally:
        if isinstance(sys.stdout, _CheckedStdout):
            sys.stdout = stdout
