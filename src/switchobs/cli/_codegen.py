"""``switchobs codegen MODEL``: the designed observer as C (casadi), with a README for integrators."""

from __future__ import annotations

import argparse
import io
import shlex
import sys
import warnings
from pathlib import Path
from typing import Any

import sympy as sp

from .._atomic import check_output_directory, staged_directory, write_files
from .._limits import MAX_INPUT_FILE_BYTES, read_text
from ..design import GainDesign, NormalFormDesign, design, normal_form_statement
from ..exceptions import CodegenError, FreeSymbolError, PrerequisiteError, SpectrumError
from ..model import Model, builtin_names, load_model, rational_value
from ..spec import METHODS, default_method
from ._common import emit_json, note_uncertified, output_directory, parse_params
from ._errors import flush_stdout
from ._integration import add_integration_arguments, integration_files

__all__ = ["register"]

#: Pseudo-model names of the sliding-mode observers of seed 003 (not switchobs models).
SUPER_TWISTING = "super-twisting"
VEHICLE_SPEED = "vehicle-speed"
#: Their runtime gains, the rule those follow and the equation of their Euler scheme.
SLIDING_MODE = {SUPER_TWISTING: (("lam", "alpha"), "seed 003 (9), rule (12)", "13"),
                VEHICLE_SPEED: (("beta",), "seed 003 (15), Theorem 3: beta > eta", "15")}
#: The names of ``switchobs.codegen.TARGETS`` (listed here so that ``--help`` imports no numpy).
TARGET_NAMES = ("host", "cortex-m4f", "cortex-m7")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("codegen",
                       description="Generate C for the switched observer of MODEL (built-in or TOML), the "
                                   "adaptive observer of Aguado-Rojas 2020 (3.4) with --unknown, or the super-twisting "
                                   f"observer of M'Sirdi et al. 2008 with MODEL = {SUPER_TWISTING} (its vehicle-speed "
                                   f"observer (15): MODEL = {VEHICLE_SPEED}).")
    p.add_argument("model", metavar="MODEL",
                   help=f"built-in model ({', '.join(builtin_names())}), a TOML file, "
                        f"{SUPER_TWISTING} or {VEHICLE_SPEED}")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="default of a runtime parameter or value of a design symbol (repeatable), e.g. "
                        "--param beta1=40 --param c=24; for super-twisting: lam and alpha; for vehicle-speed: beta")
    target = p.add_mutually_exclusive_group()
    target.add_argument("--spectrum", help='poles of A_plus, e.g. "-40,-60,-60" or "-beta1,-beta2,-beta2" '
                        "(give the betas with --param)")
    target.add_argument("--charpoly", help='target det(sI - A_plus) in s, e.g. "s^3 + 6*s^2 + 11*s + 6"')
    target.add_argument("--gains-plus", help="K_plus entries, comma-separated")
    p.add_argument("--gains-minus", help="K_minus entries (default: the Theorem 1 choice)")
    p.add_argument("--unknown", help="parameters estimated by the adaptive observer of Aguado-Rojas 2020 (3.4), e.g. c,d")
    p.add_argument("--gamma", help="adaptation gain Gamma: its diagonal (\"50,20\") or rows (\"50,0;0,20\")")
    p.add_argument("--real", choices=("double", "float"), default=None,
                   help="C real type (default double; with --target the target's: float on cortex-m4f, whose "
                        "single-precision FPU refuses double)")
    p.add_argument("--target", choices=TARGET_NAMES, default=None,
                   help="build target: writes a Makefile and a CMakeLists.txt (static library for the host and the "
                        "target) and states in the README the text, data and worst-case stack per function, "
                        "measured by building, and the instructions per step counted on qemu-system-arm "
                        "(cortex-m4f: mps2-an386, cortex-m7: mps2-an500)")
    p.add_argument("--pil", action="store_true",
                   help="with a Cortex-M --target: processor in the loop, the step over a record on qemu-system-arm "
                        "compared bit for bit with the host build and within a tolerance with the Python reference "
                        "(exit 1 when it differs); the record is --record, else for signals (y, vx, u) a braking "
                        "simulation with a road change and a sensor dropout, else constant signals")
    p.add_argument("--record", metavar="CSV",
                   help="with --pil: rows of signals, a header naming them (and an optional dt column, seconds; "
                        "default 0.001); the state starts at 0")
    p.add_argument("--method", choices=METHODS, default=None,
                   help="discretisation, signals held over the step (default radau3; rk4 with --unknown, as the "
                        "adaptive observer takes explicit steps only, and beyond 12 states; super-twisting and vehicle-speed: euler); midpoint and radau3 "
                        "are implicit and certified for every dt, rk4 and euler are not (a note says so)")
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
                        "top of the model file's [ranges]), e.g. --range vx=1:70,dt=1e-4:1e-2: the step refuses a "
                        "value outside (STATE_RANGE, also for a new state, SIGNAL_RANGE, BAD_PARAM, BAD_DT); with a "
                        "range for every one of them the files "
                        "include the Frama-C EVA proof driver <prefix>_proof.c")
    p.add_argument("--prove", action="store_true",
                   help="run the proof of no run-time errors (frama-c -eva, needs --range for every input) and "
                        "write its command and result to <prefix>_proof.md; exit 1 if EVA reports an alarm")
    p.add_argument("--prefix", help="C prefix (default switchobs_<model>, non-identifier characters as _)")
    p.add_argument("--out", required=True, metavar="DIR", type=output_directory,
                   help="directory for <prefix>.c, <prefix>.h, README.md and <prefix>_misra.md (the MISRA C:2012 "
                        "deviation record)")
    p.add_argument("--json", action="store_true", help="print the description as JSON")
    add_integration_arguments(p)
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
    if args.target:
        words.append(f"--target={args.target}")
    if args.method:
        words.append(f"--method={args.method}")
    if args.h_max is not None:
        words.append(f"--h-max={args.h_max}")
    if args.max_substeps is not None:
        words.append(f"--max-substeps={args.max_substeps}")
    words += [f"--range={item}" for item in args.ranges]
    if args.prefix is not None:
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


def _discrete_certificate(model: Model, gains: GainDesign | NormalFormDesign, values: dict[str, str], method: str):
    """The discrete certificate of the exact A_plus, A_minus, C and P of the design at the given values (for a
    normal-form design, in its coordinates: a step of ``h A`` maps ``T``-similar families to similar ones)."""
    try:
        from ..certify import discrete_certificate
    except ImportError as exc:
        raise PrerequisiteError(f"--h-max auto needs switchobs.certify.discrete_certificate, which is not "
                                f"available ({exc}); give --h-max VALUE") from None
    if isinstance(gains, NormalFormDesign):
        return discrete_certificate(gains.A_plus, gains.A_minus, gains.C, gains.P, method=method)
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
    from ..codegen import generate_observer, generate_super_twisting, generate_vehicle_speed

    from ..codegen import target_real

    if args.pil and args.target in (None, "host"):
        raise CodegenError("--pil runs the step on an emulated Cortex-M: give --target cortex-m4f or cortex-m7")
    if args.record and not args.pil:
        raise CodegenError("--record is the record of the processor-in-the-loop run: give --pil too")
    args.real = target_real(args.target, args.real) if args.target else (args.real or "double")
    values = parse_params(args.param)
    command = _command(args)
    model, unknown = None, []
    if args.model in SLIDING_MODE:
        names, rule, eq = SLIDING_MODE[args.model]
        extra = sorted(set(values) - set(names))
        missing = [k for k in names if k not in values]
        if extra or missing:
            raise CodegenError(f"{args.model} takes " + " and ".join(f"--param {k}=..." for k in names)
                               + f" ({rule}); missing {missing}, unexpected {extra}")
        if args.spectrum or args.charpoly or args.gains_plus or args.gains_minus or args.unknown or args.gamma:
            raise CodegenError(f"{args.model} has no gain design or unknowns; give only {' and '.join(names)}")
        if args.method not in (None, "euler"):
            raise CodegenError(f"{args.model} is discretised by the Euler scheme of seed 003 ({eq}); "
                               f"--method {args.method} is not available")
        if args.h_max is not None or args.max_substeps is not None:
            raise CodegenError(f"{args.model} has no rescaled-time certificate; --h-max and --max-substeps "
                               "apply to the switched observers")
        try:
            gains = [float(values[k]) for k in names]
        except ValueError:
            raise CodegenError(f"{' and '.join(names)} must be numbers, got "
                               + ", ".join(repr(values[k]) for k in names)) from None
        generate = generate_super_twisting if args.model == SUPER_TWISTING else generate_vehicle_speed
        gen = generate(*gains, real=args.real, command=command, ranges=_ranges(args.ranges),
                       prefix=f"switchobs_{args.model.replace('-', '_')}" if args.prefix is None else args.prefix)
    else:
        if not (args.spectrum or args.charpoly or args.gains_plus):
            raise SpectrumError("give the gains with --spectrum, --charpoly or --gains-plus")
        model = load_model(args.model)
        # a dense rational model: the design in its normal form's coordinates, the C gets K's doubles from it
        normal = normal_form_statement(model, args.spectrum) if args.spectrum else None
        gains = normal if normal is not None else design(
            model, args.spectrum, characteristic_polynomial=args.charpoly, K_plus=args.gains_plus,
            K_minus=args.gains_minus)
        unknown = [u.strip() for u in args.unknown.split(",")] if args.unknown else []
        if args.gamma and not unknown:
            raise CodegenError("--gamma is the adaptation gain of the adaptive observer; give --unknown too")
        method = args.method or default_method(model.n, affine=not unknown)
        # the adaptive observer has explicit steps only and no discrete certificate at all; --h-max auto
        # proves or refutes the certificate itself (exit 1 with its own line)
        if not unknown and args.h_max != "auto":
            note_uncertified(args, method)
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
        gen = generate_observer(model, gains.gains() if normal is not None else gains, values=values,
                                real=args.real, method=method,
                                prefix=args.prefix, unknown=unknown,
                                Gamma=_gamma(args.gamma) if args.gamma else None, h_max=h_max,
                                max_substeps=args.max_substeps, certificate=certificate, command=command,
                                ranges=_ranges(args.ranges))
    from ..codegen import target_build

    record = _record(args, gen, model, tuple(unknown)) if args.pil else None
    build = None if not args.target else target_build(
        gen, args.target, record=None if record is None else (record.rows, record.dt, record.x0),
        record_description=None if record is None else record.description)
    proof = None
    if args.prove:
        from ..codegen import proof_record, prove

        proof = prove(gen)
    comparison = None
    if record is not None and build is not None and build.pil is not None and model is not None:
        from ..loop import compare_with_reference, reference_observer

        comparison = compare_with_reference(build.pil, reference_observer(model, gen, unknown=tuple(unknown)),
                                            record.rows, record.dt, record.x0)
    files = {**(build or gen).files, **integration_files(gen, args),
             **({} if proof is None else {f"{gen.prefix}_proof.md": proof_record(gen, proof)})}
    # The files and the report on standard output succeed together: a report that cannot be written (a full
    # disk, /dev/full) removes the files and any directory made for them (the one cleanup of staged_directory).
    with staged_directory(args.out, what="the generated C into") as work:
        write_files(work, files, what="the generated C into")
        paths = [Path(args.out) / name for name in files]
        if args.json:
            data = gen.to_json()
            if build is not None:
                data["target"] = {"name": build.target, "footprint": build.footprint.to_json(),
                                  "record": build.record,
                                  "instructions_per_step": None if build.pil is None else build.pil.instructions_per_step}
            if comparison is not None:
                data["pil"] = {**comparison.to_json(), "passed": comparison.passed}
            data["written"] = [str(p) for p in paths]
            emit_json(data)
        else:
            print(build or gen)
            print(f"  wrote {', '.join(str(p) for p in paths)}")
            if record is not None and build is not None and build.pil is not None:
                print(f"  {build.pil}")
                print(f"  record: {record}")
                print(f"  {comparison}" if comparison is not None else "  (no Python reference for this observer)")
        if proof is not None:
            print(proof, file=sys.stderr if args.json else sys.stdout)
        flush_stdout()
    passed = True
    if build is not None and build.pil is not None and record is not None:
        passed = comparison.passed if comparison is not None else build.pil.bit_identical
    if proof is not None:
        passed = passed and proof.ok
    return 0 if passed else 1


def _record(args: argparse.Namespace, gen: Any, model: Model | None, unknown: tuple[str, ...]) -> Any:
    """The record of the run: the --record file, a braking simulation (signals y, vx, u), or constant signals."""
    import numpy as np

    from ..codegen._target import default_record
    from ..loop import PilRecord, braking_record, reference_observer

    if args.record:
        text, _ = read_text(args.record, what="the --record file", max_bytes=MAX_INPUT_FILE_BYTES, error=CodegenError)
        try:
            with warnings.catch_warnings():  # a ragged row is an error here, not a warning
                warnings.simplefilter("error")
                table = np.genfromtxt(io.StringIO(text), delimiter=",", names=True, dtype=float)
        except (ValueError, UserWarning) as exc:
            raise CodegenError(f"--record {args.record!r} cannot be read as CSV with a header: {exc}") from None
        names = table.dtype.names or ()
        missing = [n for n in gen.signal_names if n not in names]
        if missing or table.size == 0:
            raise CodegenError(f"--record {args.record!r} needs a header row and columns {list(gen.signal_names)} "
                               f"(and optionally dt); missing {missing}, has {list(names)}")
        table = np.atleast_1d(table)
        rows = np.column_stack([table[n] for n in gen.signal_names])
        dt = table["dt"] if "dt" in names else np.full(rows.shape[0], 1e-3)
        return PilRecord(rows, dt, np.zeros(gen.nx), f"{rows.shape[0]} rows of {Path(args.record).name!r}")
    if model is not None and tuple(gen.signal_names)[1:] == ("vx", "u"):
        return braking_record(reference_observer(model, gen, unknown=unknown))
    rows, dt, x0 = default_record(gen)
    return PilRecord(rows, np.full(rows.shape[0], dt), x0, f"{rows.shape[0]} rows of constant signals, the sign of "
                     "the measured output alternating")


