"""``switchobs codegen ... --fmu / --a2l``: the integration artefacts written beside the generated C."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from ..exceptions import CodegenError

if TYPE_CHECKING:  # the codegen package imports casadi: not at --help
    from ..codegen import GeneratedObserver

__all__ = ["add_integration_arguments", "integration_files"]


def add_integration_arguments(p: argparse.ArgumentParser) -> None:
    """``--fmu``, ``--fmi-version`` and ``--a2l`` of ``switchobs codegen``."""
    p.add_argument("--fmu", action="store_true",
                   help="also write <prefix>.fmu: a co-simulation FMU with a binary for this platform "
                        "(needs fmpy for the FMI headers)")
    # checked in integration_files (one line, exit 2), not by argparse choices (usage text)
    p.add_argument("--fmi-version", default=None, metavar="{2,3}",
                   help="FMI version of --fmu: 3 (FMI 3.0, default) or 2 (FMI 2.0)")
    p.add_argument("--a2l", action="store_true",
                   help="also write <prefix>.a2l (ASAP2 1.71) and <prefix>_calibration.c/.h, the calibration "
                        "object it describes (addresses 0 with SYMBOL_LINKs, for the linker-map tool)")


def integration_files(gen: "GeneratedObserver", args: argparse.Namespace) -> dict[str, str | bytes]:
    """File name -> content of the artefacts the options ask for (built before anything is written)."""
    if args.fmi_version is not None and not args.fmu:
        raise CodegenError(f"--fmi-version {args.fmi_version} chooses the FMI version of --fmu; give --fmu too")
    if args.fmi_version not in (None, "2", "3"):
        raise CodegenError(f"--fmi-version must be 2 (FMI 2.0) or 3 (FMI 3.0), got {args.fmi_version!r}")
    out: dict[str, str | bytes] = {}
    if args.fmu:
        from ..codegen import generate_fmu
        fmu = generate_fmu(gen, fmi_version=int(args.fmi_version or 3))
        out[fmu.file_name] = fmu.data
    if args.a2l:
        from ..codegen import calibration_files, generate_a2l
        out.update(calibration_files(gen))
        out[f"{gen.prefix}.a2l"] = generate_a2l(gen)
    return out
