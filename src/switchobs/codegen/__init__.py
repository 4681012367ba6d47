"""Generated C observers (casadi): exact translation, strict C99 API, and a ctypes binding.

Public API
----------
generate_observer   -- model + gains -> GeneratedObserver (``<prefix>.h``, ``<prefix>.c``, README); switched
                       observer (seed 000 (8)-(9)) or, with ``unknown``, the adaptive observer (seed 001 (3.4))
generate_super_twisting -- the super-twisting observer of seed 003 (8)-(9), Euler scheme (13)
generate_vehicle_speed -- the sliding-mode observer of the vehicle speed of seed 003 (15), forward Euler
GeneratedObserver   -- the generated files and what they mean (names, defaults, checks, stack)
compile_observer    -- compile with the system C compiler (cached) and bind with ctypes
CObserver           -- the compiled observer: ``step`` / ``run`` like the Python reference observers, ``run_dt``
                       with a step length per row
compile_sources     -- compile C files into one cached shared library (the observers' and the braking loop's)
load_library        -- load a library that compile_sources built and verified (nothing else is loaded)
cache_directory     -- where compiled libraries are cached: the user's own cache directory
StepStatus          -- status codes of ``<prefix>_step`` / ``<prefix>_run`` / ``<prefix>_run_dt``
default_prefix      -- ``switchobs_<model>`` with non-identifier characters as ``_``
TARGETS, Target, target_real -- build targets (host, cortex-m4f, cortex-m7): flags, real type, emulator
target_build, TargetBuild -- the files for a target: Makefile, CMakeLists.txt, README with measured sizes,
                       stack per function and instructions per step on the emulator
measure_footprint, TargetFootprint, FunctionStack -- text/data/bss and worst-case stack, measured by building
run_pil, PilResult  -- processor in the loop: the step over a record on qemu-system-arm and on the host
generate_fmu        -- the observer as an FMI 3.0 / 2.0 co-simulation FMU (GeneratedFMU), binary for this platform
build_fmu, FMUVariable -- the archive of any rendered FMI wrapper (the quarter car's plant FMU uses it)
generate_a2l        -- ASAP2 1.71 description of the calibration object of ``calibration_files``
calibration_files   -- ``<prefix>_calibration.c/.h``: the named parameter array a calibration tool writes
elf_symbols         -- symbol addresses of a linked program (``nm``), for ``generate_a2l(addresses=...)``
prove, ProofResult  -- Frama-C EVA proof that the step has no run-time errors over its declared ranges
proof_driver, proof_record -- the EVA driver ``<prefix>_proof.c`` and the record ``<prefix>_proof.md``
proof_command, loop_unroll -- the Frama-C command of the proof and its ``-eva-auto-loop-unroll``
divisor_gaps        -- the model's divisors that the declared ranges do not keep away from 0
fuzz_harness        -- a libFuzzer harness of the C API with the API contract as its oracle
"""

from ..spec import METHODS, STATUS_TEXT, Guard, StepStatus, domain_guards
from ._a2l import a2l_symbols, calibration_files, elf_symbols, generate_a2l
from ._build import CObserver, cache_directory, compile_observer, compile_sources, find_compiler, load_library
from ._fmu import (FMI_VERSIONS, FMUVariable, GeneratedFMU, build_fmu, fmi3_common, fmi_headers, fmu_token,
                   generate_fmu)
from ._generate import (REALS, default_prefix, generate_observer, generate_super_twisting,
                        generate_vehicle_speed)
from ._observer import GeneratedObserver, divisor_gaps, loop_unroll, proof_command, proof_driver
from ._fuzz import fuzz_harness
from ._proof import ProofResult, proof_record, prove
from ._target import (TARGETS, FunctionStack, PilResult, Target, TargetBuild, TargetFootprint, measure_footprint,
                      run_pil, target_build, target_real)

__all__ = ["CObserver", "FMI_VERSIONS", "FMUVariable", "GeneratedFMU", "build_fmu", "fmi3_common", "fmi_headers",
           "fmu_token", "GeneratedObserver", "a2l_symbols", "calibration_files",
           "elf_symbols", "generate_a2l", "generate_fmu", "Guard", "METHODS", "REALS", "STATUS_TEXT", "StepStatus",
           "cache_directory", "compile_observer", "compile_sources", "find_compiler", "default_prefix", "domain_guards",
           "generate_observer", "generate_super_twisting", "generate_vehicle_speed", "load_library", "TARGETS", "Target", "target_real",
           "target_build", "TargetBuild", "measure_footprint", "TargetFootprint", "FunctionStack", "run_pil",
           "PilResult", "ProofResult", "divisor_gaps", "fuzz_harness", "loop_unroll", "proof_command", "proof_driver",
           "proof_record", "prove"]
