"""``switchobs verify CERT.json``: independent exact check of a certificate (``-``: from standard input)."""

from __future__ import annotations

import argparse

from ._common import emit_json

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("verify",
                       description="Re-check every inequality of a switchobs certificate in exact rational "
                                   "arithmetic, from its matrices alone, and compare the claimed verdict with "
                                   "the one they imply. Exit status 0 iff everything holds, 1 otherwise, "
                                   "2 for a malformed file.")
    p.add_argument("certificate", metavar="CERT.json",
                   help="certificate written by switchobs certify --out, or - to read it from standard input")
    p.add_argument("--json", action="store_true", help="print the report as JSON")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..certify import verify_certificate

    report = verify_certificate(args.certificate)
    if args.json:
        emit_json(report.to_json())
    else:
        print(report)
    return 0 if report.holds else 1
