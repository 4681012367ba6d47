"""``switchobs classify A1 A2``: Balde–Boscain–Mason case and verdict of a planar pair."""

from __future__ import annotations

import argparse
import json
import re
from typing import Any

from ..exceptions import DimensionError
from ._common import emit_json, figure_file

__all__ = ["register", "parse_matrix"]

_TOKEN = re.compile(r"[^\[\],\s]+")


def parse_matrix(text: str, *, name: str) -> list[list[str]]:
    """``"[[-1,2],[-3,-4]]"`` (entries may be ``1/2``, ``0.5``, ``1e-3``) -> rows of strings.

    Entries stay strings so that they are read exactly (``0.1`` is ``1/10``).
    """
    quoted = _TOKEN.sub(lambda m: json.dumps(m.group()), text.strip())
    try:
        data: Any = json.loads(quoted)
    except json.JSONDecodeError:
        raise DimensionError(f"{name} = {text!r} is not a matrix; write it as \"[[a, b], [c, d]]\"") from None
    if not isinstance(data, list) or not data or not all(isinstance(r, list) for r in data):
        raise DimensionError(f"{name} = {text!r} is not a list of rows; write it as \"[[a, b], [c, d]]\"")
    return data


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("classify",
                       description="Classify the planar switched system dx/dt = A_sigma x, sigma in {1, 2} "
                                   "(Balde, Boscain and Mason 2009, as stated in Pasillas-Lépine): Gamma, det, "
                                   "tr(A1 A2), R and the verdict. Rational entries are decided exactly.")
    p.add_argument("A1", help='first matrix, e.g. "[[-1,2],[-3,-4]]"')
    p.add_argument("A2", help="second matrix")
    p.add_argument("--json", action="store_true", help='JSON with fields "case" (i, ii, iii, iv) and "verdict"')
    p.add_argument("--plot", metavar="PATH", type=figure_file,
                   help="write a figure: level sets of each mode's Lyapunov function and "
                   "the worst-case trajectory")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..certify import classify_planar

    A1, A2 = parse_matrix(args.A1, name="A1"), parse_matrix(args.A2, name="A2")
    res = classify_planar(A1, A2)
    if args.plot:
        from .._figures import save_figure
        from ..certify import plot_planar

        save_figure(plot_planar(res, A1, A2), args.plot)
    if args.json:
        emit_json(res.to_json())
    else:
        print(res)
        if args.plot:
            print(f"figure written to {args.plot}")
    return 0
