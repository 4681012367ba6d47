"""``switchobs codegen MODEL``: the designed observer as C (casadi), with a README for integrators."""

from __future__ import annotations

import argparse
import shlex
import sys
from typing import Any

import sympy as sp

from .._atomic import check_output_directory
from ..design import GainDesign, design
from ..exceptions import CodegenError, FreeSymbolError, PrerequisiteError, SpectrumError
from ..model import Model, load_model, rational_value
from ..spec import METHODS
from ._common import emit_json, parse_params

__all__ = ["register"]

#: Pseudo-model name of the super-twisting observer of seed 003 (not a switchobs model).
SUPER_TWISTING = "super-twisting"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("codegen",
                       description="Generate C for the switched observer of MODEL (built-in or TOML), the "
                                   "adaptive observer of seed 001 (3.4) with --unknown, or the super-twisting "
                                   f"observer of seed 003 with MODEL = {SUPER_TWISTING}.")
    p.add_argument("model", metavar="MODEL",
                   help="built-in model (abs-xbs3, abs-xbs4, abs-adaptive2, normal-form-N), a TOML file, "
                        f"or {SUPER_TWISTING}")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="default of a runtime parameter or value of a design symbol (repeatable), e.g. "
                        "--param beta1=40 --param c=24; for super-twisting: lam and alpha")
    target = p.add_mutually_exclusive_group()
    target.add_argument("--spectrum", help='poles of A_plus, e.g. "-40,-60,-60" or "-beta1,-beta2,-beta2" '
                        "(give the betas with --param)")
    target.add_argument("--charpoly", help='target det(sI - A_plus) in s, e.g. "s^3 + 6*s^2 + 11*s + 6"')
    target.add_argument("--gains-plus", help="K_plus entries, comma-separated")
    p.add_argument("--gains-minus", help="K_minus entries (default: the Theorem 1 choice)")
    p.add_argument("--unknown", help="parameters estimated by the adaptive observer of seed 001 (3.4), e.g. c,d")
    p.add_argument("--gamma", help="adaptation gain Gamma: its diagonal (\"50,20\") or rows (\"50,0;0,20\")")
    p.add_argument("--real", choices=("double", "float"), default="double", help="C real type (default double)")
    p.add_argument("--method", choices=METHODS, default=None,
                   help="discretisation, signals held over the step (default rk4; super-twisting: euler); "
                        "midpoint and radau3 are implicit and certified for every dt")
    p.add_argument("--h-max", metavar="auto|VALUE",
                   help="bound on the step |s|*dt in the rescaled time: a step beyond it is split into "
                        "sub-steps (H_MAX in the header, rounded down); VALUE is exact (0.01 or 1/100); auto "
                        "proves the discrete certificate of the design for --method: certified for every dt "
                        "(midpoint, radau3) needs no bound, no certificate (rk4, euler) exits 1 "
                        "(default: no sub-stepping)")
    p.add_argument("--max-substeps", type=int, metavar="N",
                   help="most sub-steps per step with --h-max, 1..16777216 (default 64); beyond: status SUBSTEP_LIMIT")
    p.add_argument("--range", action="append", default=[], metavar="NAME=LO:HI", dest="ranges",
                   help="declared range of a state, signal, parameter or dt (repeatable, or comma-separated; on "
                        "top of the model file's [ranges]), e.g. --range vx=1:70,dt=1e-4:1e-2: the step refuses a value outside (STATE_RANGE, also for a new "
                        "state, SIGNAL_RANGE, BAD_PARAM, BAD_DT); with a range for every one of them the files "
                        "include the Frama-C EVA proof driver <prefix>_proof.c")
    p.add_argument("--prove", action="store_true",
                   help="run the proof of no run-time errors (frama-c -eva, needs --range for every input) and "
                        "write its command and result to <prefix>_proof.md; exit 1 if EVA reports an alarm")
    p.add_argument("--prefix", help="C prefix (default switchobs_<model>, non-identifier characters as _)")
    p.add_argument("--out", required=True, metavar="DIR", help="directory for <prefix>.c, <prefix>.h, README.md")
    p.add_argument("--json", action="store_true", help="print the description as JSON")
    p.set_defaults(func=run)


def _command(args: argparse.Namespace) -> str:
    """The command line that regenerates the files (recorded in their comments)."""
    words = ["switchobs", "codegen", args.model]
    for opt in ("spectrum", "charpoly", "gains_plus", "gains_minus", "unknown", "gamma"):
        value = getattr(args, opt)
        if value is not None:
            words.append(f"--{opt.replace('_', '-')}={value}")
    words += [f"--param={item}" for item in args.param]
    words += [f"--real={args.real}"]
    if args.method:
        words.append(f"--method={args.method}")
    if args.h_max is not None:
        words.append(f"--h-max={args.h_max}")
    if args.max_substeps is not None:
        words.append(f"--max-substeps={args.max_substeps}")
    words += [f"--range={item}" for item in args.ranges]
    if args.prefix:
        words.append(f"--prefix={args.prefix}")
    words.append("--out=DIR")
    return shlex.join(words)


def _ranges(items: list[str]) -> dict[str, tuple[float, float]]:
    """``--range NAME=LO:HI`` options as a mapping (the generator checks the names and the bounds)."""
    out: dict[str, tuple[float, float]] = {}
    for item in (part for text in items for part in text.split(",") if part.strip()):
        name, eq, span = item.partition("=")
        lo, colon, hi = span.partition(":")
        try:
            if not (eq and colon and name.strip()):
                raise ValueError
            out[name.strip()] = (float(lo), float(hi))
        except ValueError:
            raise CodegenError(f"--range expects NAME=LO:HI with two numbers, e.g. vx=1:70, got {item!r}") from None
    return out


def _gamma(text: str) -> list[list[float]] | list[float]:
    try:
        if ";" in text:
            return [[float(v) for v in row.split(",")] for row in text.split(";")]
        return [float(v) for v in text.split(",")]
    except ValueError:
        raise CodegenError(f"--gamma expects numbers like \"50,20\" or \"50,0;0,20\", got {text!r}") from None


def _discrete_certificate(model: Model, gains: GainDesign, values: dict[str, str], method: str):
    """The discrete certificate of the exact A_plus, A_minus, C and P of the design at the given values."""
    try:
        from ..certify import discrete_certificate
    except ImportError as exc:
        raise PrerequisiteError(f"--h-max auto needs switchobs.certify.discrete_certificate, which is not "
                                f"available ({exc}); give --h-max VALUE") from None
    merged: dict[str, Any] = {**model.values, **{k: rational_value(v, what=k) for k, v in values.items()}}

    def exact(M: sp.MatrixBase, name: str) -> sp.ImmutableMatrix:
        free = sorted(str(x) for x in M.free_symbols if str(x) not in merged)
        if free:
            raise FreeSymbolError(f"{name} depends on {free}; give their values with --param")
        return sp.ImmutableMatrix(M.xreplace({x: merged[str(x)] for x in M.free_symbols}))

    return discrete_certificate(exact(gains.A_plus, "A_plus"), exact(gains.A_minus, "A_minus"),
                                exact(model.C, "C"), exact(gains.P, "P"), method=method)


def run(args: argparse.Namespace) -> int:
    check_output_directory(args.out, what="the generated C into")
    from ..codegen import generate_observer, generate_super_twisting

    values = parse_params(args.param)
    command = _command(args)
    if args.model == SUPER_TWISTING:
        extra = sorted(set(values) - {"lam", "alpha"})
        missing = [k for k in ("lam", "alpha") if k not in values]
        if extra or missing:
            raise CodegenError(f"{SUPER_TWISTING} takes --param lam=... and --param alpha=... (seed 003 (9), rule "
                               f"(12)); missing {missing}, unexpected {extra}")
        if args.spectrum or args.charpoly or args.gains_plus or args.gains_minus or args.unknown or args.gamma:
            raise CodegenError(f"{SUPER_TWISTING} has no gain design or unknowns; give only lam and alpha")
        if args.method not in (None, "euler"):
            raise CodegenError(f"{SUPER_TWISTING} is discretised by the Euler scheme of seed 003 (13); "
                               f"--method {args.method} is not available")
        if args.h_max is not None or args.max_substeps is not None:
            raise CodegenError(f"{SUPER_TWISTING} has no rescaled-time certificate; --h-max and --max-substeps "
                               "apply to the switched observers")
        try:
            lam, alpha = float(values["lam"]), float(values["alpha"])
        except ValueError:
            raise CodegenError(f"lam and alpha must be numbers, got {values['lam']!r}, {values['alpha']!r}") from None
        gen = generate_super_twisting(lam, alpha, real=args.real,
                                      prefix=args.prefix or "switchobs_super_twisting", command=command)
    else:
        if not (args.spectrum or args.charpoly or args.gains_plus):
            raise SpectrumError("give the gains with --spectrum, --charpoly or --gains-plus")
        model = load_model(args.model)
        gains = design(model, args.spectrum, characteristic_polynomial=args.charpoly,
                       K_plus=args.gains_plus, K_minus=args.gains_minus)
        unknown = [u.strip() for u in args.unknown.split(",")] if args.unknown else []
        if args.gamma and not unknown:
            raise CodegenError("--gamma is the adaptation gain of the adaptive observer; give --unknown too")
        method = args.method or "rk4"
        if args.h_max == "auto" and unknown:
            raise CodegenError("--h-max auto certifies the switched observer's error dynamics (A_plus, A_minus); "
                               "the adaptive observer's error also has the parameter estimates: give --h-max VALUE")
        h_max, certificate = args.h_max, None
        if args.h_max == "auto":
            cert = _discrete_certificate(model, gains, values, method)
            if not cert.certified:
                print(f"switchobs codegen: method {method} has no discrete certificate for this design "
                      f"({cert.verdict.value}); use --method radau3 (certified for every dt), or --h-max VALUE "
                      "(uncertified, but it bounds the step)", file=sys.stderr)
                return 1
            h_max, certificate = cert.h_max, cert.statement
        gen = generate_observer(model, gains, values=values, real=args.real, method=method,
                                prefix=args.prefix, unknown=unknown,
                                Gamma=_gamma(args.gamma) if args.gamma else None, h_max=h_max,
                                max_substeps=args.max_substeps, certificate=certificate, command=command,
                                ranges=_ranges(args.ranges))
    proof = None
    if args.prove:
        from ..codegen import proof_record, prove

        proof = prove(gen)
        paths = gen.write(args.out, extra={f"{gen.prefix}_proof.md": proof_record(gen, proof)})
    else:
        paths = gen.write(args.out)
    if args.json:
        data = gen.to_json()
        data["written"] = [str(p) for p in paths]
        emit_json(data)
    else:
        print(gen)
        print(f"  wrote {', '.join(str(p) for p in paths)}")
    if proof is not None:
        print(proof, file=sys.stderr if args.json else sys.stdout)
        return 0 if proof.ok else 1
    return 0
