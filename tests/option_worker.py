"""Child process of tests/test_fuzz_options.py: runs ``switchobs`` command lines under a memory cap.

Started with ``python option_worker.py MEMORY_BYTES SECONDS``.  It caps its address space (so that an
allocation the limits of switchobs miss ends in MemoryError here, not in the OOM killer), imports the
CLI once, then reads one JSON argv per line on stdin and answers one JSON line per run on stdout:
``{"code": exit status or null, "out": stdout tail, "err": stderr, "crash": traceback or null}``.  A run
longer than SECONDS is interrupted and reported as a crash.
"""

from __future__ import annotations

import contextlib
import io
import json
import resource
import signal
import sys
import traceback


class Timeout(BaseException):
    """Raised by the alarm; a BaseException so that no ``except Exception`` of the library swallows it."""


def _alarm(signum, frame):
    raise Timeout


def main() -> None:
    memory, seconds = int(sys.argv[1]), float(sys.argv[2])
    resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
    from switchobs.cli.main import main as switchobs

    signal.signal(signal.SIGALRM, _alarm)
    reply = sys.stdout
    for line in sys.stdin:
        argv = json.loads(line)
        out, err = io.StringIO(), io.StringIO()
        code = crash = None
        signal.setitimer(signal.ITIMER_REAL, seconds)
        try:
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                try:
                    code = switchobs(argv)
                except SystemExit as exc:          # argparse: one error line, exit 2
                    code = exc.code
        except Timeout:
            crash = f"no answer within {seconds:g} s"
        except BaseException:                      # noqa: BLE001 - every escape is what the fuzzing looks for
            crash = traceback.format_exc()
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0.0)
        reply.write(json.dumps({"code": code, "out": out.getvalue()[-2000:], "err": err.getvalue(),
                                "crash": crash}) + "\n")
        reply.flush()


if __name__ == "__main__":
    main()
