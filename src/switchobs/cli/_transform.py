"""``switchobs transform SYSTEM.toml``: the normal form of a nonlinear system, checked or searched."""

from __future__ import annotations

import argparse

from .._atomic import write_text
from ..exceptions import TransformError
from ..transform import System, check_transformation, search_transformation
from ._common import check_output, emit_json, output_file

__all__ = ["register", "split_top_level"]


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "transform",
        description="From dx/dt = f(x) + g(x) u, y = h(x) (a system file) to dz/dt = s(y)(A z + d(y)) + b(y) u, "
                    "y = C z (Pasillas-Lépine, Part III). Without --s/--phi, search s and phi from f, g, h alone; with "
                    "them, check the candidate. The derivation is printed step by step; exit 1 names the first "
                    "condition that fails.")
    p.add_argument("system", metavar="SYSTEM.toml", help="system file (docs/transform.md)")
    p.add_argument("--s", metavar="EXPR", help='candidate time scale in y, the parameters and external signals, '
                                                'e.g. "y/vx" (check mode, with --phi)')
    p.add_argument("--phi", metavar="EXPR,...", help='candidate coordinates z1,...,zn in the states, e.g. '
                                                      '"x2,c1*c2*exp(-c2*x1)-x3,-c2*x3" (check mode, with --s)')
    p.add_argument("--out", metavar="MODEL.toml", type=output_file,
                   help="write the normal form as a model file for `switchobs design`")
    p.add_argument("--theory", metavar="PATH", type=output_file,
                   help="write the derivation as a Markdown page with LaTeX")
    p.add_argument("--json", action="store_true", help="print the verdict, the model and the steps as JSON")
    p.set_defaults(func=run)


def split_top_level(text: str) -> list[str]:
    """``"x2, f(a, b), x3"`` -> ``["x2", "f(a, b)", "x3"]``: commas inside parentheses stay."""
    parts, depth, start = [], 0, 0
    for i, ch in enumerate(text):
        depth += {"(": 1, ")": -1}.get(ch, 0)
        if ch == "," and depth == 0:
            parts.append(text[start:i].strip())
            start = i + 1
    parts.append(text[start:].strip())
    return parts


def run(args: argparse.Namespace) -> int:
    if (args.s is None) != (args.phi is None):
        raise TransformError("check mode needs both --s and --phi (search mode: give neither)")
    check_output(args.out, what="the model", inputs=[args.system])
    check_output(args.theory, what="the derivation", inputs=[args.system])
    system = System.from_toml(args.system)
    if args.s is None:
        result = search_transformation(system)
    else:
        result = check_transformation(system, args.s, split_top_level(args.phi))
    if args.theory:
        write_text(args.theory, result.to_markdown(), what="the derivation")
    if args.out and result.exists:
        write_text(args.out, result.model_toml(), what="the model")
    if args.json:
        emit_json(result.to_json())
    else:
        print(result)
        for option, what in ((args.theory, "derivation"), (args.out if result.exists else None, "model")):
            if option:
                print(f"wrote {what} {option}")
        if args.out and not result.exists:
            print(f"{args.out} not written: no transformation exists")
    return 0 if result.exists else 1
