"""Entry point of the ``switchobs`` command.

Each sub-command lives in its own module ``switchobs.cli._<name>`` exposing
``register(subparsers)``, which adds its parser and sets ``func`` to a
callable ``func(args) -> int``.  Errors raised on purpose by switchobs (all
subclasses of :class:`switchobs.exceptions.SwitchobsError`) become one line on
stderr and exit status 2; nothing else is caught, so a real bug still shows
its traceback.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from ..exceptions import SwitchobsError

__all__ = ["main", "build_parser"]

#: Sub-command modules, in the order of ``switchobs --help``.
COMMANDS: tuple[str, ...] = ("design", "demo")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="switchobs",
        description="Design, certify and export switched observers via singular time-rescaling.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name in COMMANDS:
        importlib.import_module(f"switchobs.cli._{name}").register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except SwitchobsError as exc:
        print(f"switchobs {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"switchobs {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
