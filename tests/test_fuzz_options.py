"""Fuzzing of the options of ``switchobs encoder``, ``switchobs simulate`` (issue 13) and ``switchobs sweep``
(issue 25).

Hypothesis draws command lines in which one or two options take hostile values (huge, tiny, negative,
NaN, infinite, not a number) and the others cheap ones.  Each runs in a child process whose address
space is capped (tests/option_worker.py) with a time bound, and must end with exit status 0, 1 or 2,
no traceback, and on failure one line naming the command (argparse's refusals too).  The number of examples per command is ``SWITCHOBS_FUZZ_EXAMPLES`` (``make fuzz`` raises it);
``make test`` runs a small, derandomised set.
"""

from __future__ import annotations

import json
import os
import re
import select
import subprocess
import sys
import uuid
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

EXAMPLES = int(os.environ.get("SWITCHOBS_FUZZ_EXAMPLES", "25"))
#: The address space of the child: the interpreter with numpy, scipy and cvxpy loaded (one BLAS thread)
#: maps about 0.45 GB, so this leaves about 1 GB for a run, the bound of issue 13.
MEMORY_BYTES = 1_500_000_000
#: Time bound of one run in the child: a refused option answers in milliseconds, a cheap run in about
#: 1 s, the longest accepted one (MAX_STEPS integration steps) in some 20 s on an idle machine.
RUN_SECONDS = 180.0

#: Hostile spellings: magnitudes past every limit, zero and signs, non-finite, not numbers at all.
EXTREMES = ("1e9", "1e300", "1e400", "-1", "0", "-0", "1e-9", "1e-300", "5e-324", "nan", "inf", "-inf",
            "abc", "", " ", "1,5", "0x10", "1_0", "10**9", "9" * 5000)
NUMBER = st.one_of(st.sampled_from(EXTREMES),
                   st.floats(allow_nan=True, allow_infinity=True).map(repr),
                   st.integers(-10**30, 10**30).map(str))

ENCODER_OPTIONS = ("--ppr", "--events", "--order", "--harmonics", "--rpm", "--duration", "--rate-hz", "--dnl",
                   "--eccentricity", "--clock-hz", "--seed", "--warmup")
SIMULATE_OPTIONS = ("--speed-kmh", "--duration", "--dt", "--delay", "--beta", "--gamma")


@st.composite
def encoder_argv(draw: st.DrawFn) -> list[str]:
    values = {"--duration": "1", "--warmup": "0.2"}
    for option in draw(st.lists(st.sampled_from(ENCODER_OPTIONS), min_size=1, max_size=2, unique=True)):
        values[option] = draw(NUMBER)
    argv = ["encoder", "--estimator", draw(st.sampled_from(("tsa", "notch", "three-stage"))),
            "--profile", draw(st.sampled_from(("constant", "varying", "braking")))]
    if draw(st.booleans()):
        argv.append("--both-edges")
    return argv + [f"{k}={v}" for k, v in values.items()]


@st.composite
def simulate_argv(draw: st.DrawFn) -> list[str]:
    values = {"--duration": "0.5"}
    for option in draw(st.lists(st.sampled_from(SIMULATE_OPTIONS), min_size=1, max_size=2, unique=True)):
        values[option] = draw(NUMBER)
    argv = ["simulate", "--observer", draw(st.sampled_from(("none", "xbs3", "xbs4", "adaptive"))),
            "--controller", draw(st.sampled_from(("five-phase", "two-phase")))]
    return argv + [f"{k}={v}" for k, v in values.items()]


@pytest.fixture(scope="module")
def worker():
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MPLBACKEND": "Agg"}
    proc = subprocess.Popen([sys.executable, str(Path(__file__).with_name("option_worker.py")),
                             str(MEMORY_BYTES), str(RUN_SECONDS)],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env)

    def run(argv: list[str]) -> dict:
        proc.stdin.write(json.dumps(argv) + "\n")
        proc.stdin.flush()
        # the child bounds each run itself; this only guards against a child that died or hangs in C code
        ready, _, _ = select.select([proc.stdout], [], [], RUN_SECONDS + 30.0)
        line = proc.stdout.readline() if ready else ""
        assert line, f"the worker died or hung on {argv} (exit status {proc.poll()})"
        return json.loads(line)

    yield run
    proc.stdin.close()
    proc.wait(timeout=30)


def check(argv: list[str], result: dict) -> None:
    """Exit 0, 1 or 2; no traceback; a failure ends with one line naming the command."""
    assert result["crash"] is None, f"{argv}:\n{result['crash']}"
    code, command = result["code"], argv[0]
    assert code in (0, 1, 2), f"{argv}: exit status {code!r}\n{result['err']}"
    lines = [line for line in result["err"].splitlines() if not re.match(rf"switchobs {command}: \[", line)]
    assert "Traceback" not in result["err"], f"{argv}:\n{result['err']}"
    if code == 0:
        assert lines == [], f"{argv}: exit 0 with {lines}"
        return
    assert len(lines) == 1, f"{argv}: {len(lines)} lines on stderr\n{result['err']}"
    verb = "error" if code == 2 else "failed"
    assert lines[0].startswith(f"switchobs {command}: {verb}: "), f"{argv}: {lines[0]}"


SWEEP_OPTIONS = ("--workers", "--batch-size", "--max-cases", "--max-steps", "--scheduler", "--out", "--plots")
#: Schedulers that answer at once (an address that is not there waits 20 s for the connection; "local" starts
#: a cluster, drawn only with a number of workers beyond the limit, refused before any process starts).
SCHEDULERS = ("none", "bogus", "", "tcp://", "inproc://", "tls://127.0.0.1:1", "-1", "local")
PATHS = ("", "-", ".", "/", "/dev/full", "/dev/null", "/nonexistent/dir/x", "x\x00y", "a" * 300, "é/ü")
#: A sweep of two short brakings (about 0.3 s simulated each) and a table.
SWEEP_SPEC = """name = "fuzz"
[base]
speed_kmh = 10.0
[grid]
road = ["dry-asphalt", "snow"]
[[table]]
rows = ["road"]
column = "speed_kmh"
metric = "stop_time_s"
"""


@st.composite
def sweep_argv(draw: st.DrawFn) -> list[str]:
    values: dict[str, str] = {"--scheduler": "none"}
    for option in draw(st.lists(st.sampled_from(SWEEP_OPTIONS), min_size=1, max_size=2, unique=True)):
        values[option] = draw(st.sampled_from(SCHEDULERS) if option == "--scheduler" else
                              st.sampled_from(PATHS) if option in ("--out", "--plots") else NUMBER)
    if values["--scheduler"] == "local":
        values["--workers"] = draw(st.sampled_from(("100000", "0", "-1", "10**9", "1e9", "nan", "")))
    flags = draw(st.sampled_from(([], ["--json"], ["--resume"], ["-q"], ["--tune"])))
    return ["sweep", "SPEC", *flags, *(f"{k}={v}" for k, v in values.items())]


FUZZ = settings(max_examples=EXAMPLES, deadline=None, derandomize="SWITCHOBS_FUZZ_EXAMPLES" not in os.environ,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])


@FUZZ
@given(argv=encoder_argv())
def test_fuzzed_encoder_options_end_cleanly(worker, argv):
    check(argv, worker(argv))


@FUZZ
@given(argv=simulate_argv())
def test_fuzzed_simulate_options_end_cleanly(worker, argv):
    check(argv, worker(argv))


@pytest.fixture(scope="module")
def sweep_dir(tmp_path_factory):
    folder = tmp_path_factory.mktemp("sweep")
    (folder / "spec.toml").write_text(SWEEP_SPEC, encoding="utf-8")
    return folder


@FUZZ
@given(argv=sweep_argv())
def test_fuzzed_sweep_options_end_cleanly(worker, sweep_dir, argv):
    argv = [str(sweep_dir / "spec.toml") if a == "SPEC" else a for a in argv]
    if not any(a.startswith("--out=") for a in argv):  # a fresh results file per run, never in the source tree
        argv.append(f"--out={sweep_dir / uuid.uuid4().hex}.jsonl")
    before = set(os.listdir(Path.cwd()))
    check(argv, worker(argv))
    assert set(os.listdir(Path.cwd())) <= before, f"{argv}: wrote into the current directory"


#: The cases of issue 13, replayed under the memory cap (tests/test_resource_bounds.py checks the messages).
ISSUE_CASES = [["encoder", "--rpm", "1e9"], ["encoder", "--rate-hz", "1e9"], ["encoder", "--duration", "1e9"],
               ["encoder", "--harmonics", "1000"], ["encoder", "--events", "100000", "--duration", "2"],
               ["simulate", "--dt", "1e-9"], ["simulate", "--speed-kmh", "1e9"],
               ["simulate", "--observer", "xbs4", "--beta", "1e9", "--method", "rk4", "-q"]]   # radau3 stays bounded


@pytest.mark.parametrize("argv", ISSUE_CASES, ids=" ".join)
def test_issue_cases_end_cleanly_under_the_memory_cap(worker, argv):
    result = worker(argv)
    check(argv, result)
    assert result["code"] == (1 if "--beta" in argv else 2)
