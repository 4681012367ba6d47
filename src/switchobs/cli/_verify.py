"""``switchobs verify CERT.json``: independent exact check of a certificate (``-``: from standard input),
saying what it is about."""

from __future__ import annotations

import argparse
import sys

from ..model import load_model
from ._common import emit_json

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("verify",
                       description="Re-check every inequality of a switchobs certificate in exact rational "
                                   "arithmetic, from its matrices alone, and compare the claimed verdict with "
                                   "the one they imply. Prints the model and gains the certificate is about and "
                                   "what could not be checked (e.g. no observer section: the model-gain link). "
                                   "Exit status 0 iff everything holds, 1 otherwise (with --strict, also when "
                                   "a link was not checked), 2 for a malformed file.")
    p.add_argument("certificate", metavar="CERT.json",
                   help="certificate written by switchobs certify --out, or - to read it from standard input")
    p.add_argument("--model", metavar="MODEL",
                   help="compare the observer's A and C with this model (built-in name or TOML file) at the "
                        "certificate's parameter values (default: the built-in model the certificate names)")
    p.add_argument("--strict", action="store_true",
                   help="fail (exit 1) when a section is missing or a link cannot be checked")
    p.add_argument("--arithmetic", choices=("exact", "interval"), default="exact",
                   help="kept for scripts: both names decide definiteness the same way, by an interval (arb) "
                        "enclosure that is a proof where it decides and the exact elimination elsewhere")
    p.add_argument("--json", action="store_true", help="print the report as JSON")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..certify import verify_certificate

    report = verify_certificate(args.certificate, model=load_model(args.model) if args.model else None,
                                arithmetic=args.arithmetic)
    if args.json:
        emit_json(report.to_json())
    else:
        print(report)
    if args.strict and report.unchecked:
        print(f"switchobs verify: --strict: {len(report.unchecked)} link(s) not checked: "
              f"{'; '.join(report.unchecked)}", file=sys.stderr)
        return 1
    return 0 if report.holds else 1
