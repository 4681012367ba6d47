"""Helpers shared by the sub-commands: model loading with --param, JSON output, generated files."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

from ..exceptions import ModelError
from ..model import Model, load_model

__all__ = ["add_model_arguments", "model_from_args", "parse_params", "emit_json", "write_or_check"]


def add_model_arguments(parser: argparse.ArgumentParser) -> None:
    """MODEL positional and repeatable ``--param NAME=VALUE``."""
    parser.add_argument("model", metavar="MODEL",
                        help="built-in model (abs-xbs3, abs-xbs4, abs-adaptive2, normal-form-N) or a TOML file")
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
