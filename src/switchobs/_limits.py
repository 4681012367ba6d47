"""Resource limits on user input, checked before any work (standard library only).

Exact arithmetic makes a short text expensive: ``"1e999999999"`` is a
billion-digit integer, ``9**9**9**9`` does not fit in memory.  Every number
and expression a user gives (model files, ``--param``, ``--spectrum``,
certificates) passes through here first, so that such input is refused in
milliseconds with a message naming the limit and the value.  The limits are
documented in ``docs/errors.md`` (a test keeps the page and these constants
in step).

The module imports nothing above the standard library and
:mod:`switchobs.exceptions`, so both the model layer and the independent
certificate checker use it.
"""

from __future__ import annotations

import os
import re
import select
import sys
from fractions import Fraction
from pathlib import Path

from .exceptions import SwitchobsError

__all__ = ["MAX_EXPRESSION_LENGTH", "MAX_EXPRESSION_DEPTH", "MAX_EXPRESSION_TERMS", "MAX_EXPONENT",
           "MAX_NUMBER_DIGITS", "MAX_CERTIFICATE_DIGITS", "MAX_CERTIFICATE_BYTES", "MAX_DIMENSION",
           "MAX_CERTIFICATE_WORK", "MAX_READ_WAIT_S", "MAX_NAME_LENGTH",
           "MAX_DWELL_BITS", "MAX_BOX_VERTICES", "MAX_INPUT_FILE_BYTES", "MAX_PIL_ROWS",
           "MAX_LOG_BYTES", "MAX_LOG_SAMPLES", "MAX_SWEEP_CASES", "MAX_SWEEP_STEPS",
           "MAX_WORKERS_PER_CORE", "MAX_ROAD_CHANGES",
           "DOUBLE_MAX", "DOUBLE_MIN", "LIMITS", "decimal_fraction", "check_double", "check_dimension", "digits",
           "read_text"]

#: Characters in one expression string (a matrix entry, a pole, a gain).
MAX_EXPRESSION_LENGTH = 2000
#: Nesting depth of an expression's syntax tree (parentheses, unary signs, powers of powers).
MAX_EXPRESSION_DEPTH = 50
#: Numbers, names and calls in one expression (the operators between them are not counted).
MAX_EXPRESSION_TERMS = 500
#: Largest |exponent| of an exact power ``x**k`` (numerator and denominator of a rational ``k``).
MAX_EXPONENT = 64
#: Decimal digits of an exact number in a model: a literal, a value, or an exact power or product of them
#: (numerator and denominator each).
MAX_NUMBER_DIGITS = 1000
#: Decimal digits of one number in a certificate, counting a decimal exponent as that many digits (below
#: Python's own limit of 4300 digits for converting between integers and text).
MAX_CERTIFICATE_DIGITS = 4000
#: Size of a certificate file: the normal-form certificate of the dense 6-digit decimal 128-state model of
#: ``benchmarks/numeric_inputs.py`` is 52 MB (its ``T`` and ``P`` have 2000- and 4000-digit entries).
MAX_CERTIFICATE_BYTES = 100_000_000
#: Size of a model, system or sweep file (TOML): a 128-state model of longest entries is about 33 MB.
MAX_INPUT_FILE_BYTES = 40_000_000
#: Rows of a processor-in-the-loop record: compiled into the harness, they and the states must fit the 4 MB code and
#: 4 MB data memories of the emulated MPS2 boards (20000 rows of 3 doubles are 480 kB).
MAX_PIL_ROWS = 20_000
#: Size of a measurement log replayed (MDF4, CSV, Parquet): refused by its size before it is opened, so a
#: huge file is never read whole.
MAX_LOG_BYTES = 1_000_000_000
#: Samples of one channel of a replayed log, and encoder edges: a one-hour log at 1 kHz (3.6 million) fits.  Not
#: a memory bound: ``switchobs replay`` reads, runs and writes the log piece by piece, and its peak does not grow
#: with the log (about 0.24 GB for 10 minutes and for an hour at 1 kHz with a 60-ppr encoder, ``/usr/bin/time -f
#: %M``; ``benchmarks/replay_log.py``); ``log_signals`` and ``replay`` hold the whole arrays (they grow with the log).
MAX_LOG_SAMPLES = 4_000_000
#: States of a model (and of every file derived from one: a system, a certificate) and modes of a certificate's
#: family: the one dimension limit, checked before any work.
MAX_DIMENSION = 128
#: Seconds a read of a file or standard input may wait for data (a FIFO nobody writes to).
MAX_READ_WAIT_S = 10
#: Characters of a model's or system's name (one line of printable text).
MAX_NAME_LENGTH = 200
#: Work of a certificate's exact check, in the units of :func:`switchobs.exact.elimination_work` (entry updates
#: weighted by ``(bits / 64) ** 1.5``, about 5.5e7 a second on the 2-core test machine, within 15 % for dense
#: 16-64 state matrices of 100-4000 digits): checked for the products before any arithmetic
#: (:func:`switchobs.exact.product_work`: ``n**3`` products of a matrix's digits over one common denominator on
#: flint's integer matrices, scaled by the share of nonzero entries of the sparser factor) and counted by the
#: exact elimination as it goes, which stops at the bound, so no certificate costs much more than 7 s of
#: elimination.  The 128-state certificates of ``benchmarks/numeric_inputs.py`` need at most 2.1e7 for their
#: products (the normal-form ``P`` of the dense and decimal-chain models: 4000 digits, half of them zeros,
#: against companion matrices).
MAX_CERTIFICATE_WORK = 400_000_000
#: A dwell-time certificate is checked while ``||A_p||_inf * tau_D <= 2**MAX_DWELL_BITS`` (the enclosure of
#: ``exp(A_p tau_D)`` takes that many squarings); beyond, the check fails as undecidable in reasonable time.
MAX_DWELL_BITS = 64
#: Vertex matrices a box certificate may ask the checker to build (sub-boxes times monomial choices).
MAX_BOX_VERTICES = 65536
#: Cases of one sweep (grid points times Monte-Carlo draws), counted from the spec before any case is built;
#: ``switchobs sweep --max-cases`` raises it.  Every row is kept in memory until the sweep ends (a few kB each).
MAX_SWEEP_CASES = 100_000
#: Integration steps of a sweep's braking cases, each counted at its time bound over its step (an upper bound:
#: a braking to standstill stops earlier), checked before the first case runs; ``--max-steps`` raises it.
MAX_SWEEP_STEPS = 1_000_000_000
#: Worker processes of a local Dask cluster per core of the machine (``--workers``).
MAX_WORKERS_PER_CORE = 4
#: Road changes of one braking case (each is scored alone: its errors, re-convergence and recovery time).
MAX_ROAD_CHANGES = 100
#: The largest finite double and the smallest positive normal double: a number meant as a double lies in
#: ``[DOUBLE_MIN, DOUBLE_MAX]`` in magnitude, or is 0.
DOUBLE_MAX = sys.float_info.max
DOUBLE_MIN = sys.float_info.min

#: Every limit by name, for the documentation page and its test.
LIMITS: dict[str, int | float] = {
    "MAX_EXPRESSION_LENGTH": MAX_EXPRESSION_LENGTH, "MAX_EXPRESSION_DEPTH": MAX_EXPRESSION_DEPTH,
    "MAX_EXPRESSION_TERMS": MAX_EXPRESSION_TERMS, "MAX_EXPONENT": MAX_EXPONENT,
    "MAX_NUMBER_DIGITS": MAX_NUMBER_DIGITS, "MAX_CERTIFICATE_DIGITS": MAX_CERTIFICATE_DIGITS,
    "MAX_CERTIFICATE_BYTES": MAX_CERTIFICATE_BYTES, "MAX_DIMENSION": MAX_DIMENSION,
    "MAX_CERTIFICATE_WORK": MAX_CERTIFICATE_WORK,
    "MAX_DWELL_BITS": MAX_DWELL_BITS, "MAX_BOX_VERTICES": MAX_BOX_VERTICES,
    "MAX_INPUT_FILE_BYTES": MAX_INPUT_FILE_BYTES, "MAX_PIL_ROWS": MAX_PIL_ROWS,
    "MAX_LOG_BYTES": MAX_LOG_BYTES, "MAX_LOG_SAMPLES": MAX_LOG_SAMPLES, "MAX_SWEEP_CASES": MAX_SWEEP_CASES,
    "MAX_SWEEP_STEPS": MAX_SWEEP_STEPS, "MAX_WORKERS_PER_CORE": MAX_WORKERS_PER_CORE,
    "MAX_ROAD_CHANGES": MAX_ROAD_CHANGES, "MAX_READ_WAIT_S": MAX_READ_WAIT_S, "MAX_NAME_LENGTH": MAX_NAME_LENGTH,
}

_FRACTION = re.compile(r"^([+-]?)(\d+)\s*/\s*(\d+)$")
_DECIMAL = re.compile(r"^([+-]?)(\d*)(?:\.(\d*))?(?:[eE]([+-]?\d+))?$")


def read_text(path: str | Path, *, what: str, max_bytes: int, error: type[SwitchobsError],
              wait_s: float | None = None) -> tuple[str, str]:
    """The text of a user's file, ``"-"`` standard input, and the name to quote it by: the one reader of input.

    The size is enforced by reading, never by the file's ``stat`` (``/dev/zero`` and a pipe report 0 bytes):
    at most ``max_bytes + 1`` bytes are read, so a huge or endless input is refused in bounded memory.  A
    read that waits more than ``wait_s`` seconds for data (a FIFO nobody writes to) is refused too; only a
    terminal on standard input, where a person types, is waited for.

    Raises
    ------
    SwitchobsError
        ``error``: the file cannot be read (or standard input is closed), is larger than ``max_bytes``, waits
        longer than ``wait_s`` or is not UTF-8 text; the message names ``what`` and the file.
    """
    stdin = str(path) == "-"
    where = "<stdin>" if stdin else str(path)
    wait_s = MAX_READ_WAIT_S if wait_s is None else wait_s
    try:
        if stdin and sys.stdin is None:  # `<&-`: Python then has no sys.stdin
            raise error(f"cannot read {what} from standard input: it is closed; give a file instead of -")
        if stdin:
            fd = _stdin_fd()
            if fd is None:  # a stream in memory (an embedding program's, a test's): read as text, bounded too
                data = sys.stdin.read(max_bytes + 1).encode("utf-8", errors="surrogateescape")
            else:
                data = _read_bounded(fd, max_bytes, None if os.isatty(fd) else wait_s)
        else:
            # non-blocking open: opening a FIFO for reading would otherwise wait for a writer, unbounded
            fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
            try:
                data = _read_bounded(fd, max_bytes, wait_s)
            finally:
                os.close(fd)
    except TimeoutError:
        raise error(f"{what} {where!r} sent no data for {wait_s:g} s (limit MAX_READ_WAIT_S): a pipe or FIFO "
                    "nobody writes to?") from None
    except OSError as exc:
        raise error(f"cannot read {what} {where!r}: {exc.strerror or exc}") from None
    if len(data) > max_bytes:
        raise error(f"{what} {where!r} has more than {max_bytes} bytes (limit {max_bytes})")
    try:
        return data.decode("utf-8"), where
    except UnicodeDecodeError as exc:
        raise error(f"{what} {where!r} is not UTF-8 text ({exc.reason} at byte {exc.start})") from None


def _stdin_fd() -> int | None:
    """The descriptor of standard input, or None for a stream without one (``io.StringIO``)."""
    try:
        fd = sys.stdin.fileno()
    except (OSError, ValueError, AttributeError):
        return None
    os.fstat(fd)  # a descriptor closed under Python's feet: OSError, reported as unreadable
    return fd


def _read_bounded(fd: int, max_bytes: int, wait_s: float | None) -> bytes:
    """At most ``max_bytes + 1`` bytes of ``fd``; TimeoutError when no data comes for ``wait_s`` seconds."""
    chunks: list[bytes] = []
    left = max_bytes + 1
    poller = select.poll()  # poll, not select: any descriptor number
    poller.register(fd, select.POLLIN | select.POLLPRI)
    while left > 0:
        if wait_s is not None and not poller.poll(wait_s * 1000):
            raise TimeoutError
        try:
            chunk = os.read(fd, min(left, 1 << 20))
        except BlockingIOError:  # a FIFO whose writer has not written yet: wait again
            continue
        if not chunk:
            break
        chunks.append(chunk)
        left -= len(chunk)
    return b"".join(chunks)


def check_dimension(size: int, *, what: str, error: type[Exception]) -> None:
    """Refuse ``size`` states (or modes) above :data:`MAX_DIMENSION`, before anything of that size is built.

    The one dimension check of models, systems and certificates, so that every model that can be read can be
    certified and its certificate read back.
    """
    if size > MAX_DIMENSION:
        raise error(f"{what} has {size} states (limit {MAX_DIMENSION} = MAX_DIMENSION: the exact design and "
                    "certificate checks grow steeply with n); reduce the model")


def _shorten(text: str, keep: int = 40) -> str:
    return text if len(text) <= keep else f"{text[:keep // 2]}...{text[-keep // 2:]} ({len(text)} characters)"


def digits(value: int) -> int:
    """Decimal digits of ``|value|`` (an upper bound, exact within one, from the bit length: no conversion)."""
    return max(1, (abs(value).bit_length() * 30103) // 100000 + 1)


def decimal_fraction(text: str, *, what: str, error: type[Exception], max_digits: int = MAX_NUMBER_DIGITS) -> Fraction:
    """The exact rational a decimal (``"-3.5e-2"``) or fraction (``"375/2"``) string spells, size-checked first.

    Parameters
    ----------
    text : str
    what : str
        Where the number comes from, for the message.
    error : exception class
        Raised for a malformed or too large number (the caller's layer's error).
    max_digits : int
        Most decimal digits of the result's numerator and denominator; a decimal
        exponent counts as that many digits, so ``"1e999999999"`` is refused
        before it is expanded.

    Raises
    ------
    error
        Naming ``what``, the value and the limit.
    """
    s = text.strip().replace("_", "")
    m = _FRACTION.match(s)
    if m:
        size = max(len(m.group(2)), len(m.group(3)))
    else:
        m = _DECIMAL.match(s)
        if not m or not (m.group(2) or m.group(3)):
            raise error(f"{what}: {_shorten(text)!r} is not a finite number (write e.g. 187.5, 375/2 or -3e-2)")
        exponent = m.group(4) or "0"
        if len(exponent.lstrip("+-")) > 12:
            size = max_digits + 1
        else:
            size = len(m.group(2)) + len(m.group(3) or "") + abs(int(exponent))
    if size > max_digits:
        raise error(f"{what}: {_shorten(text)!r} has more than {max_digits} digits (limit {max_digits}, "
                    "counting the decimal exponent); write a shorter number")
    try:
        # the forms certificates are written in ("-375/2", "42") are read from the groups matched above: Fraction's
        # own parser would run a second regular expression over every digit
        if m.re is _FRACTION and len(m.group(1)) + len(m.group(2)) + len(m.group(3)) + 1 == len(s):  # no spaces
            return Fraction(int(m.group(1) + m.group(2)), int(m.group(3)))
        if m.re is _DECIMAL and m.group(2) and m.group(3) is None and m.group(4) is None:
            return Fraction(int(s))
        return Fraction(s)
    except (ValueError, ZeroDivisionError):
        raise error(f"{what}: {_shorten(text)!r} is not a finite number (a zero denominator?)") from None


def check_double(value: Fraction, *, what: str, error: type[Exception], text: str | None = None) -> Fraction:
    """``value`` unchanged if it is 0 or a normal double in magnitude; else ``error`` naming the range.

    A number meant as a double (a parameter value, a literal in an expression) must be one: ``1e400``
    overflows to infinity and ``1e-400`` underflows to zero, which would silently change the model.
    """
    shown = _shorten(text if text is not None else str(value))
    size = abs(value)
    if size > DOUBLE_MAX:
        raise error(f"{what}: {shown} is beyond the largest double ({DOUBLE_MAX:.4g}); give a smaller value")
    if 0 < size < DOUBLE_MIN:
        raise error(f"{what}: {shown} is below the smallest normal double ({DOUBLE_MIN:.4g}) and would "
                    "round to 0; write 0 if you mean it, or rescale the model")
    return value
