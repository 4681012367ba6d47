"""Generated C observers (casadi): exact translation, strict C99 API, and a ctypes binding.

Public API
----------
generate_observer   -- model + gains -> GeneratedObserver (``<prefix>.h``, ``<prefix>.c``, README); switched
                       observer (seed 000 (8)-(9)) or, with ``unknown``, the adaptive observer (seed 001 (3.4))
generate_super_twisting -- the super-twisting observer of seed 003 (8)-(9), Euler scheme (13)
GeneratedObserver   -- the generated files and what they mean (names, defaults, checks, stack)
compile_observer    -- compile with the system C compiler (cached) and bind with ctypes
CObserver           -- the compiled observer: ``step`` / ``run`` like the Python reference observers, ``run_dt``
                       with a step length per row
compile_sources     -- compile C files into one cached shared library (the observers' and the braking loop's)
StepStatus          -- status codes of ``<prefix>_step`` / ``<prefix>_run`` / ``<prefix>_run_dt``
default_prefix      -- ``switchobs_<model>`` with non-identifier characters as ``_``
prove, ProofResult  -- Frama-C EVA proof that the step has no run-time errors over its declared ranges
proof_driver, proof_record -- the EVA driver ``<prefix>_proof.c`` and the record ``<prefix>_proof.md``
fuzz_harness        -- a libFuzzer harness of the C API with the API contract as its oracle
"""

from ..spec import METHODS, STATUS_TEXT, Guard, StepStatus, domain_guards
from ._build import CObserver, cache_directory, compile_observer, compile_sources, find_compiler
from ._generate import REALS, GeneratedObserver, default_prefix, generate_observer, generate_super_twisting
from ._fuzz import fuzz_harness
from ._proof import ProofResult, proof_driver, proof_record, prove

__all__ = ["CObserver", "GeneratedObserver", "Guard", "METHODS", "REALS", "STATUS_TEXT", "StepStatus",
           "cache_directory", "compile_observer", "compile_sources", "find_compiler", "default_prefix", "domain_guards", "generate_observer",
           "generate_super_twisting", "ProofResult", "fuzz_harness", "proof_driver", "proof_record", "prove"]
