"""Run many ``switchobs`` command lines in one process under a memory cap (used by the hostile-input tests).

Reads one JSON object per line on stdin: ``{"argv": [...], "files": {name: text}}`` (the files are
written into a fresh folder, the current directory of the run); prints one JSON object per line:
``{"rc": int, "stderr": str, "stdout_lines": int, "seconds": float}``.  The address space is capped
at ``SWITCHOBS_BATCH_MEMORY`` bytes (default 1 GiB) with ``resource.setrlimit``, so an input that
would exhaust memory fails here instead of taking the machine down.  A command that hangs makes the
caller's timeout fire; the results printed so far name the inputs that finished.
"""

from __future__ import annotations

import contextlib
import functools
import io
import json
import os
import resource
import sys
import tempfile
import time
from pathlib import Path


def main() -> None:
    limit = int(os.environ.get("SWITCHOBS_BATCH_MEMORY", str(1 << 30)))
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    from switchobs.cli.main import main as switchobs

    home = Path.cwd()
    for line in sys.stdin:
        case = json.loads(line)
        with tempfile.TemporaryDirectory() as tmp:
            for name, text in case.get("files", {}).items():
                Path(tmp, name).write_text(text, encoding="utf-8")
            os.chdir(tmp)
            out, err = io.StringIO(), io.StringIO()
            start = time.perf_counter()
            try:
                with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                    rc = switchobs(case["argv"])
            except SystemExit as exc:  # argparse usage errors
                rc = exc.code if isinstance(exc.code, int) else 2
            finally:
                os.chdir(home)
            seconds = time.perf_counter() - start
        print(json.dumps({"rc": rc, "stderr": err.getvalue(), "stdout_lines": out.getvalue().count("\n"),
                          "seconds": seconds}), flush=True)


def run_batch(cases: list[dict], *, timeout: float, memory: int = 1 << 30) -> list[dict]:
    """Run ``cases`` in one subprocess (see the module docstring); the results of those that finished."""
    import subprocess

    env = {**os.environ, "SWITCHOBS_BATCH_MEMORY": str(memory), "OPENBLAS_NUM_THREADS": "1",
           "OMP_NUM_THREADS": "1", "MPLBACKEND": "Agg"}
    stdin = "".join(json.dumps(case) + "\n" for case in cases)
    try:
        proc = subprocess.run([sys.executable, __file__], input=stdin, capture_output=True, text=True,
                              timeout=timeout, env=env)
        stdout = proc.stdout
    except subprocess.TimeoutExpired as exc:
        stdout = exc.stdout.decode() if isinstance(exc.stdout, bytes) else (exc.stdout or "")
    return [json.loads(line) for line in stdout.splitlines() if line.startswith("{")]


@functools.lru_cache(maxsize=1)
def valid_certificate() -> str:
    """A certificate of abs-xbs3 with every kind certify writes for it (Hespanha, singular sum, dwell time), as JSON
    text."""
    from switchobs.certify import certify_model
    from switchobs.model import builtin_model

    # dwell=True: the dwell-time entry is written only on request once a Hespanha certificate holds
    report = certify_model(builtin_model("abs-xbs3"), spectrum="-10,-20,-20", dwell=True)
    return json.dumps(report.document, indent=2) + "\n"


if __name__ == "__main__":
    main()
