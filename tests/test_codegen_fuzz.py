"""libFuzzer on every public function of the generated C API, the API contract as the oracle.

The harness (``switchobs.codegen.fuzz_harness``) aborts when a status is outside ``StepStatus``, a refused
step changed the state, an OK step left a non-finite (or out-of-range) state, or ``_run`` / ``_run_dt``
differ from a loop of ``_step`` (status, first failing row, state, trajectory rows); clang's
``-fsanitize=fuzzer,address,undefined`` makes every memory error and undefined behaviour a crash too.
``make test`` fuzzes each variant for ``SWITCHOBS_FUZZ_C_SECONDS`` (default 10) seconds; ``make fuzz`` longer.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess

import pytest

from switchobs.codegen import fuzz_harness, generate_observer
from switchobs.design import design
from switchobs.model import builtin_model

from test_codegen_proof import xbs3

SECONDS = int(os.environ.get("SWITCHOBS_FUZZ_C_SECONDS", "10"))
FLAGS = ["-std=c99", "-g", "-O1", "-fsanitize=fuzzer,address,undefined", "-fno-sanitize-recover=all",
         "-fsanitize=float-divide-by-zero"]


def _libfuzzer(tmp_path) -> str:
    clang = shutil.which("clang")
    if clang is None:
        pytest.skip("clang is not installed (make cc-tools): the generated C API is NOT fuzzed")
    probe = tmp_path / "probe.c"
    probe.write_text("#include <stdint.h>\n#include <stddef.h>\n"
                     "int LLVMFuzzerTestOneInput(const uint8_t *d, size_t n) { (void)d; (void)n; return 0; }\n")
    proc = subprocess.run([clang, "-fsanitize=fuzzer", str(probe), "-o", str(tmp_path / "probe")],
                          capture_output=True, text=True)
    if proc.returncode != 0:
        pytest.skip("clang has no libFuzzer runtime (-fsanitize=fuzzer fails: "
                    f"{proc.stderr.strip().splitlines()[-1:]}): the generated C API is NOT fuzzed")
    return clang


def _xbs4_float_substeps():
    m = builtin_model("abs-xbs4")
    gains = design(m, "-beta1,-beta1,-beta2,-beta2")
    return generate_observer(m, gains, values={"beta1": 10, "beta2": 20}, real="float", h_max="1/100",
                             max_substeps=8)


def _adaptive():
    m = builtin_model("abs-adaptive2")
    return generate_observer(m, ([8.0, -0.08], [-3.0, -0.04]), unknown=["c", "d"], Gamma=[50, 20])


VARIANTS = {
    "abs-xbs3 radau3 double, ranged": lambda: xbs3("radau3"),
    "abs-xbs4 rk4 float, h_max 1/100": _xbs4_float_substeps,
    "abs-adaptive2 adaptive rk4 double": _adaptive,
}


@pytest.mark.parametrize("name", sorted(VARIANTS))
def test_libfuzzer_finds_no_contract_violation(name, tmp_path):
    clang = _libfuzzer(tmp_path)
    gen = VARIANTS[name]()
    for fname, text in gen.files.items():
        (tmp_path / fname).write_text(text)
    harness = tmp_path / f"{gen.prefix}_fuzz.c"
    harness.write_text(fuzz_harness(gen))
    exe = tmp_path / "fuzz"
    proc = subprocess.run([clang, *FLAGS, str(harness), str(tmp_path / f"{gen.prefix}.c"), "-lm", "-o", str(exe)],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    corpus = tmp_path / "corpus"
    corpus.mkdir()
    run = subprocess.run([str(exe), f"-max_total_time={SECONDS}", "-seed=1", "-max_len=512", "-timeout=10",
                          "-rss_limit_mb=1024", str(corpus)], capture_output=True, text=True, cwd=tmp_path,
                         timeout=SECONDS + 120)
    assert run.returncode == 0, run.stderr[-3000:]
    done = re.search(r"Done (\d+) runs", run.stderr)
    assert done and int(done.group(1)) > 1000, run.stderr[-500:]


def test_the_harness_catches_a_broken_contract(tmp_path):
    """The oracle is not vacuous: a step that writes its state before a refusal is caught."""
    clang = _libfuzzer(tmp_path)
    gen = xbs3("rk4")
    for fname, text in gen.files.items():
        (tmp_path / fname).write_text(text)
    # the mutant moves the state of a refused single step
    end = f"    return status;\n}}\n\nint32_t {gen.prefix}_run("
    source = gen.source.replace(end, "    if (status != 0 && n_steps == 1) { xhat[0] += 1.0; }\n" + end)
    assert source != gen.source
    (tmp_path / f"{gen.prefix}.c").write_text(source)
    harness = tmp_path / "h.c"
    harness.write_text(fuzz_harness(gen))
    exe = tmp_path / "fuzz"
    subprocess.run([clang, *FLAGS, str(harness), str(tmp_path / f"{gen.prefix}.c"), "-lm", "-o", str(exe)],
                   check=True, capture_output=True)
    run = subprocess.run([str(exe), "-max_total_time=20", "-seed=1", "-max_len=512"], capture_output=True,
                         text=True, cwd=tmp_path, timeout=140)
    assert run.returncode != 0 and "contract violated: a refused step changed xhat" in run.stderr, run.stderr[-2000:]
