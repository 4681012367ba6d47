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

import re
import sys
from fractions import Fraction
from pathlib import Path

from .exceptions import SwitchobsError

__all__ = ["MAX_EXPRESSION_LENGTH", "MAX_EXPRESSION_DEPTH", "MAX_EXPRESSION_TERMS", "MAX_EXPONENT",
           "MAX_NUMBER_DIGITS", "MAX_CERTIFICATE_DIGITS", "MAX_CERTIFICATE_BYTES", "MAX_CERTIFICATE_DIMENSION",
           "MAX_DWELL_BITS", "MAX_BOX_VERTICES", "MAX_INPUT_FILE_BYTES", "MAX_PIL_ROWS",
           "MAX_LOG_BYTES", "MAX_LOG_SAMPLES", "MAX_SWEEP_CASES", "MAX_SWEEP_STEPS",
           "MAX_WORKERS_PER_CORE", "MAX_ROAD_CHANGES",
           "DOUBLE_MAX", "DOUBLE_MIN", "LIMITS", "decimal_fraction", "check_double", "digits", "read_text"]

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
#: Size of a certificate file.
MAX_CERTIFICATE_BYTES = 50_000_000
#: Size of a model, system or sweep file (TOML): a 64-state model of longest entries is about 8 MB.
MAX_INPUT_FILE_BYTES = 10_000_000
#: Rows of a processor-in-the-loop record: compiled into the harness, they and the states must fit the 4 MB code and
#: 4 MB data memories of the emulated MPS2 boards (20000 rows of 3 doubles are 480 kB).
MAX_PIL_ROWS = 20_000
#: Size of a measurement log replayed (MDF4, CSV, Parquet): refused by its size before it is opened, so a
#: huge file is never read whole.
MAX_LOG_BYTES = 1_000_000_000
#: Samples of one channel of a replayed log, and encoder edges: a one-hour log at 1 kHz (3.6 million) fits.  The
#: log is read whole, and the chain's arrays grow with it (a 10-minute log at 1 kHz with a 60-ppr encoder peaks
#: at about 0.5 GB: ``/usr/bin/time -f %M switchobs replay``), so an hour stays within about 2 GB.
MAX_LOG_SAMPLES = 4_000_000
#: Largest state dimension and number of modes in a certificate's family.
MAX_CERTIFICATE_DIMENSION = 100
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
    "MAX_CERTIFICATE_BYTES": MAX_CERTIFICATE_BYTES, "MAX_CERTIFICATE_DIMENSION": MAX_CERTIFICATE_DIMENSION,
    "MAX_DWELL_BITS": MAX_DWELL_BITS, "MAX_BOX_VERTICES": MAX_BOX_VERTICES,
    "MAX_INPUT_FILE_BYTES": MAX_INPUT_FILE_BYTES, "MAX_PIL_ROWS": MAX_PIL_ROWS,
    "MAX_LOG_BYTES": MAX_LOG_BYTES, "MAX_LOG_SAMPLES": MAX_LOG_SAMPLES, "MAX_SWEEP_CASES": MAX_SWEEP_CASES,
    "MAX_SWEEP_STEPS": MAX_SWEEP_STEPS, "MAX_WORKERS_PER_CORE": MAX_WORKERS_PER_CORE,
    "MAX_ROAD_CHANGES": MAX_ROAD_CHANGES,
}

_FRACTION = re.compile(r"^([+-]?)(\d+)\s*/\s*(\d+)$")
_DECIMAL = re.compile(r"^([+-]?)(\d*)(?:\.(\d*))?(?:[eE]([+-]?\d+))?$")


def read_text(path: str | Path, *, what: str, max_bytes: int, error: type[SwitchobsError]) -> tuple[str, str]:
    """The text of a user's file, ``"-"`` standard input, and the name to quote it by.

    The size is checked before the file is read (at most ``max_bytes + 1`` characters from standard input), so
    a huge input is refused in bounded memory.

    Raises
    ------
    SwitchobsError
        ``error``: the file cannot be read, is larger than ``max_bytes`` or is not UTF-8 text; the message names
        ``what`` and the file.
    """
    stdin = str(path) == "-"
    where = "<stdin>" if stdin else str(path)
    try:
        if stdin:
            text = sys.stdin.read(max_bytes + 1)
            size = len(text.encode("utf-8"))
        else:
            size = Path(path).stat().st_size
        if size > max_bytes:
            raise error(f"{what} {where!r} has {size} bytes (limit {max_bytes})")
        if not stdin:
            text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise error(f"cannot read {what} {where!r}: {exc.strerror}") from None
    except UnicodeDecodeError as exc:
        raise error(f"{what} {where!r} is not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    return text, where


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
