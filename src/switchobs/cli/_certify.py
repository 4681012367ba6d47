"""``switchobs certify MODEL``: numerical verdict on the switched observer, certified exactly."""

from __future__ import annotations

import argparse
import math

from .._display import ROUNDED_NOTE, exact_display, readable_number
from ..spec import STEP_METHODS
from ..exceptions import CertificateError, SpectrumError
from ..model import load_model
from ._common import (STDIO, add_model_arguments, check_output, emit_json, figure_file, output_file, parse_params,
                      summary_stream, write_certificate)

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "certify",
        description="Build A_plus = A - K_plus C and A_minus = -A + K_minus C for MODEL with numeric values, "
                    "run the strict and Hespanha common-Lyapunov LMIs, the Geromel-Colaneri dwell time (when needed) and "
                    "(n = 2) the Balde-Boscain-Mason classification, re-check every certificate in exact "
                    "arithmetic and print the verdict. With --discrete METHOD, also certify the sampled "
                    "observer that runs in C (one METHOD step per sample, h = |s|*dt) for every step length. "
                    "With --box NAME=LOWER:UPPER (repeatable), also certify the same gains for every parameter "
                    "value of the box (or find the largest certified sub-box around the nominal point). "
                    "Exit status 0 if a stability certificate holds (and, with --discrete, the sampled one too, and "
                    "with --box, the whole box), "
                    "1 if none does, 2 on bad input.")
    add_model_arguments(p)
    p.add_argument("--spectrum", help='poles of A_plus, e.g. "-10,-20,-20" (gains by Theorem 1, Pasillas-Lépine)')
    p.add_argument("--gains-plus", help='K_plus entries, e.g. "84,-7312/375,-64/3"')
    p.add_argument("--gains-minus", help="K_minus entries (default: the Theorem 1 choice)")
    p.add_argument("--solver", choices=("CLARABEL", "SCS"), help="use only this cvxpy solver "
                   "(default: CLARABEL, then SCS as fallback)")
    dwell = p.add_mutually_exclusive_group()
    dwell.add_argument("--dwell", action="store_true",
                       help="always run the Geromel-Colaneri dwell-time bisection when no strict common P is "
                            "certified (by default it runs only when the Hespanha certificate does not hold either: "
                            "that one already gives every positive dwell time)")
    dwell.add_argument("--no-dwell", action="store_true", help="skip the dwell-time bisection")
    p.add_argument("--discrete", choices=tuple(STEP_METHODS), metavar="METHOD",
                   help=f"also certify the sampled observer of this step method ({', '.join(STEP_METHODS)}): "
                        "adds a 'discrete' section to the certificate")
    p.add_argument("--rate-hz", type=float, default=1000.0,
                   help="sample rate used to state the discrete certificate in the user's units (default 1000)")
    p.add_argument("--box", action="append", metavar="NAME=LOWER:UPPER",
                   help="uncertain parameter range, e.g. a=150:230 (repeatable): adds a 'box' section, valid for "
                        "every value in the box, even varying in time")
    p.add_argument("--arithmetic", choices=("exact", "interval"), default="exact",
                   help="kept for scripts: both names decide definiteness the same way, by an interval (arb) "
                        "enclosure that is a proof where it decides and the exact elimination elsewhere; "
                        "recorded in the certificate's provenance")
    p.add_argument("--json", action="store_true", help="print the full report as JSON")
    p.add_argument("--exact", action="store_true",
                   help="print the gains in full (default: rationals longer than 20 characters to 6 digits)")
    p.add_argument("--out", metavar="CERT.json", type=output_file,
                   help="write the certificate (checkable with switchobs verify); "
                   "- writes it to standard output and the summary to stderr")
    p.add_argument("--plot", metavar="PATH", type=figure_file,
                   help="write a figure: the spectra of A_plus and A_minus and, when the "
                   "verdict rests on a dwell time, the Geromel-Colaneri LMI margin against T with tau_D marked")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..certify import ObserverSection, certify_model

    if args.gains_minus is not None and args.gains_plus is None:
        raise SpectrumError("--gains-minus needs --gains-plus")
    if (args.spectrum is None) == (args.gains_plus is None):
        raise SpectrumError("give either a spectrum (--spectrum) or the gains (--gains-plus [--gains-minus])")
    if not (math.isfinite(args.rate_hz) and args.rate_hz > 0):
        raise CertificateError(f"--rate-hz must be a positive number of samples per second, got {args.rate_hz!r}")
    if args.out == STDIO and args.json:
        raise CertificateError("--out - writes the certificate to standard output; give --json or --out -, not both")
    check_output(args.out, what="the certificate", inputs=[args.model])
    model = load_model(args.model)
    solvers = (args.solver,) if args.solver else ("CLARABEL", "SCS")
    dwell = True if args.dwell else False if args.no_dwell else "auto"
    report = certify_model(model, values=parse_params(args.param), spectrum=args.spectrum,
                           K_plus=args.gains_plus, K_minus=args.gains_minus, dwell=dwell, solvers=solvers,
                           discrete=args.discrete, box=args.box, arithmetic=args.arithmetic)
    if args.out:
        write_certificate(report, args.out)
    if args.plot:
        from .._figures import save_figure
        from ..certify import plot_certification

        save_figure(plot_certification(report), args.plot)
    if args.json:
        emit_json(report.to_json())
    elif (stream := summary_stream(args)) is not None:
        prov = report.document.get("provenance", {})
        obs = report.document.get("observer", {})
        values = ", ".join(f"{k} = {v}" for k, v in prov.get("parameters", {}).items())
        print(f"switchobs certify: model {prov.get('model')}{' (' + values + ')' if values else ''}", file=stream)
        model_gains = ObserverSection.from_json(obs).model_gains() if "T" in obs else None
        if model_gains is not None:  # the exact gains are in the normal form's coordinates: show the model's
            for name, K in zip(("K_plus ", "K_minus"), model_gains):
                print(f"  {name} = [{', '.join(f'{k:.6g}' for k in K)}]", file=stream)
            print("  (the nearest doubles of T^-1 k, 6 significant digits: the certificate states the observer in "
                  "its normal form's coordinates z = T x, exactly, with k = T K; --json for them)", file=stream)
        else:
            with exact_display(args.exact):
                shown = {k: [readable_number(v) for v in obs.get(k, [])] for k in ("K_plus", "K_minus")}
            print(f"  K_plus  = [{', '.join(shown['K_plus'])}]", file=stream)
            print(f"  K_minus = [{', '.join(shown['K_minus'])}]", file=stream)
            if any(shown[k] != obs.get(k, []) for k in shown):
                print(f"  {ROUNDED_NOTE}", file=stream)
        print(report, file=stream)
        if report.discrete is not None:
            from ..report import sampled_lines

            for line in sampled_lines(model, report.discrete, rate_hz=args.rate_hz):
                print(line, file=stream)
        if args.out and args.out != STDIO:
            print(f"certificate written to {args.out}", file=stream)
        if args.plot:
            print(f"figure written to {args.plot}", file=stream)
    box_ok = report.box is None or report.box.certified
    return 0 if report.certified and report.discrete_certified is not False and box_ok else 1
