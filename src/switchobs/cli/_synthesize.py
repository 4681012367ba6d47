"""``switchobs synthesize MODEL --decay RATE``: K_plus, K_minus by LMIs, re-checked exactly, then certified."""

from __future__ import annotations

import argparse
import math
import sys
from typing import Any

from ..exceptions import ModelError
from ..model import load_model
from ._common import (STDIO, add_model_arguments, check_output, emit_json, output_file, parse_params, summary_stream,
                      write_certificate)
from .main import QUIET

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "synthesize",
        description="Find K_plus, K_minus by LMIs (Y = X K): every mode decays at RATE in the rescaled time and the "
                    "H2 gain from measurement noise (weight W against a unit process disturbance) to the error of "
                    "the chosen states is minimised. With one output a strict common Lyapunov function is "
                    "impossible, so the pair gets the non-strict common P (Hespanha) and per-mode decay "
                    "certificates. With --box the gains are synthesised jointly for the whole parameter box "
                    "(polytopic LMIs: each mode decays at RATE at every vertex, with one Lyapunov matrix per mode "
                    "common to all vertices). The gains are re-checked exactly, then certified like "
                    "`switchobs certify` (with --box, over the box). Exit status 0 if the synthesis and the "
                    "certificate hold, 1 if not, 2 on bad input.")
    add_model_arguments(p)
    p.add_argument("--decay", required=True, metavar="RATE", help="decay rate in the rescaled time, e.g. 99")
    p.add_argument("--noise-weight", type=float, default=0.0, metavar="W",
                   help="measurement-noise intensity relative to a unit process disturbance (default 0)")
    p.add_argument("--estimate", action="append", metavar="STATE",
                   help="state whose estimation error is weighted (repeatable; default all), e.g. z2")
    p.add_argument("--box", action="append", metavar="NAME=LOWER:UPPER",
                   help="synthesise the gains for every value of this parameter range (polytopic LMIs, exact vertex "
                        "checks) and certify them over it (repeatable), e.g. a=150:230")
    p.add_argument("--solver", choices=("CLARABEL", "SCS"), help="use only this cvxpy solver")
    p.add_argument("--json", action="store_true", help="print the synthesis and the certificate report as JSON")
    p.add_argument("--out", metavar="CERT.json", type=output_file,
                   help="write the certificate of the synthesised pair; - writes it "
                   "to standard output and the summary to stderr")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..certify import certify_model
    from ..synthesis import synthesize, synthesize_box

    if not (math.isfinite(args.noise_weight) and args.noise_weight >= 0):
        raise ModelError(f"--noise-weight must be a finite number >= 0, got {args.noise_weight!r}")
    if args.out == STDIO and args.json:
        raise ModelError("--out - writes the certificate to standard output; give --json or --out -, not both")
    check_output(args.out, what="the certificate", inputs=[args.model])
    model = load_model(args.model)
    values = parse_params(args.param)
    solvers = (args.solver,) if args.solver else ("CLARABEL", "SCS")
    common = dict(decay_rate=args.decay, noise_weight=args.noise_weight, estimate=args.estimate, values=values,
                  solvers=solvers)
    result = synthesize_box(model, args.box, **common) if args.box else synthesize(model, **common)
    report = None
    if result.feasible:
        K_plus, K_minus = result.gains()
        report = certify_model(model, values=values, K_plus=K_plus, K_minus=K_minus, solvers=solvers, box=args.box)
        if args.out:
            write_certificate(report, args.out)
    if args.json:
        emit_json({"synthesis": result.to_json(), "certification": None if report is None else report.to_json()})
    elif (stream := summary_stream(args)) is not None:
        print(result, file=stream)
        if report is not None:
            print(report, file=stream)
            if args.out and args.out != STDIO:
                print(f"certificate written to {args.out}", file=stream)
    if report is not None and args.verbosity != QUIET:
        _warn_fast_poles(report.family, float(args.decay), args.noise_weight)
    ok = report is not None and report.certified and (report.box is None or report.box.certified)
    return 0 if ok else 1


#: A pole this many times faster than the decay asked for means gains the decay alone does not bound.
FAST_POLE_RATIO = 1e3


def _warn_fast_poles(family: Any, decay: float, noise_weight: float) -> None:
    """One line on stderr when the synthesised poles are far faster than the decay rate asked for: the LMIs
    bound the decay from one side only, and without a noise weight nothing penalises large gains."""
    import numpy as np

    fastest = max(float(np.max(np.abs(np.linalg.eigvals(M)))) for M in family.numeric)
    if fastest > FAST_POLE_RATIO * decay:
        hint = ("give a noise weight to penalise them (e.g. --noise-weight 0.01)" if noise_weight == 0 else
                "give a larger --noise-weight or a smaller --decay")
        print(f"switchobs synthesize: warning: a pole at |lambda| = {fastest:.3g}, {fastest / decay:.3g} times the "
              f"decay rate {decay:g}: the gains are huge; {hint}", file=sys.stderr)
