"""``switchobs design MODEL``: symbolic gain pair and exact common Lyapunov certificate."""

from __future__ import annotations

import argparse
import sys

from .._display import exact_display
from ..design import design_gains, normal_form_statement
from ..exceptions import NotHurwitzError, NotObservableError, SpectrumError
from ..report import Progress
from ._common import add_model_arguments, emit_json, model_from_args
from .main import QUIET

__all__ = ["register"]

#: What ``design --json`` gives of the design at the model's values (``at_values``), besides the values.
AT_VALUES_KEYS = ("K_plus", "K_minus", "hurwitz_plus", "hurwitz_minus", "P")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("design",
                       description="Design the switched observer gains of MODEL and their exact certificate.")
    add_model_arguments(p)
    target = p.add_mutually_exclusive_group()
    target.add_argument("--spectrum", help='poles of A_plus, comma-separated, e.g. "-beta1,-beta2,-beta2" '
                        "(new names are positive design symbols)")
    target.add_argument("--charpoly", help='target det(sI - A_plus) in s, e.g. "s^3 + 6*s^2 + 11*s + 6"')
    target.add_argument("--gains-plus", help='K_plus entries, comma-separated (numbers, expressions or new '
                        'symbols, e.g. "k1,k2,k3")')
    p.add_argument("--gains-minus", help="K_minus entries (default: the Theorem 1 choice)")
    p.add_argument("--json", action="store_true", help="print the certificate as JSON (full matrices)")
    p.add_argument("--full", action="store_true",
                   help="print full matrices also for n > 4 (default there: gains as lists, P by its n free entries)")
    p.add_argument("--exact", action="store_true",
                   help="print every rational in full (default: those longer than 20 characters to 6 digits)")
    p.add_argument("--no-verify", action="store_true",
                   help="skip the exact re-check of the Lyapunov equations (for large symbolic models)")
    p.add_argument("--symbolic", action="store_true",
                   help="show the symbolic design only (default: when the model has [values], also the gains, "
                        "Routh–Hurwitz conditions and P at those values, as certify uses them)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    if not (args.spectrum or args.charpoly or args.gains_plus):
        raise SpectrumError("give the target with --spectrum, --charpoly or --gains-plus")
    model = model_from_args(args)
    # progress on stderr for the symbolic stages that take seconds from n = 5 on
    quiet = model.n <= 4 or args.verbosity == QUIET
    progress = Progress(1 if args.no_verify else 2, stream=None if quiet else sys.stderr)
    what = f"gains, Routh–Hurwitz conditions and the common P of {model.name} (n = {model.n})"
    with progress.stage("design", what):
        # a rational model whose gains are long in its own coordinates is designed in its normal form's
        normal = normal_form_statement(model, args.spectrum) if args.spectrum else None
        result = normal if normal is not None else design_gains(
            model, args.spectrum, characteristic_polynomial=args.charpoly, K_plus=args.gains_plus,
            K_minus=args.gains_minus)
    checks = None
    if not args.no_verify:
        with progress.stage("re-check", "exact re-check of the certificate"):
            checks = result.verify()
    if normal is not None:
        if args.json:
            emit_json({**normal.to_json(), "verified": checks})
        else:
            print(normal)
            _print_checks(checks)
        return 0 if checks is None or all(checks.values()) else 1
    # one rule with certify: a model's [values] are used; the symbolic result comes first, then the same design
    # at those values (a substitution: the re-check above covers it)
    at_values = not args.symbolic and bool(result.stored_values)
    failed = None
    if at_values:
        try:
            evaluated = result.at()
        except (NotHurwitzError, NotObservableError) as exc:
            failed = str(exc)
    if args.json:
        data = result.to_json()
        data["verified"] = checks
        if at_values:
            data["at_values"] = {"values": {k: str(v) for k, v in result.stored_values.items()},
                                 **({"error": failed} if failed else
                                    {k: evaluated.to_json()[k] for k in AT_VALUES_KEYS})}
        emit_json(data)
    else:
        with exact_display(args.exact):
            print(result.describe(full=True) if args.full else result)
        _print_checks(checks)
        if at_values:
            with exact_display(args.exact):
                print(f"at the model's values: {failed}" if failed else
                      result.describe_at_values(full=True if args.full else None))
    ok = (checks is None or all(checks.values())) and failed is None
    return 0 if ok else 1


def _print_checks(checks: dict[str, bool] | None) -> None:
    if checks is not None:
        status = "all hold exactly" if all(checks.values()) else "FAILED: " + ", ".join(
            k for k, v in checks.items() if not v)
        print(f"  exact re-check ({', '.join(checks)}): {status}")
