"""Numbers as a person reads them: exact rationals shortened for display, never in the results.

A design on a user's 6-digit spectrum has gains of 150-digit fractions, and a model entry typed as the
float ``-2.1`` is the binary fraction ``-4728779608739021/2251799813685248``.  The terminal output and the
notebook reprs print such a rational (longer than :data:`MAX_EXACT_CHARS` characters) to 6 significant
digits and say so; the results, ``--json``, the certificates and ``--exact`` keep every digit.
"""

from __future__ import annotations

import sys
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from fractions import Fraction
from typing import Any

import sympy as sp

__all__ = ["MAX_EXACT_CHARS", "ROUNDED_NOTE", "exact_display", "readable", "readable_number", "is_shortened",
           "unicode_output"]

#: A rational whose text is longer than this is displayed to 6 significant digits.
MAX_EXACT_CHARS = 20
#: The line that says so.
ROUNDED_NOTE = (f"(rationals longer than {MAX_EXACT_CHARS} characters shown to 6 significant digits; "
                "--exact or --json for the exact values)")

_EXACT: ContextVar[bool] = ContextVar("switchobs_exact_display", default=False)


@contextmanager
def exact_display(exact: bool = True) -> Iterator[None]:
    """Display every rational in full inside the block (the CLI's ``--exact``)."""
    token = _EXACT.set(exact)
    try:
        yield
    finally:
        _EXACT.reset(token)


def _long(r: sp.Rational) -> bool:
    return len(str(r)) > MAX_EXACT_CHARS


def readable(expr: Any) -> Any:
    """``expr`` (a sympy object, or a list of them) with every long rational as a 6-digit float."""
    if _EXACT.get():
        return expr
    if isinstance(expr, (list, tuple)):
        return type(expr)(readable(e) for e in expr)
    if not isinstance(expr, sp.Basic):
        return expr
    swap = {r: sp.Float(r, 6) for r in expr.atoms(sp.Rational) if _long(r)}
    return expr.xreplace(swap) if swap else expr


def is_shortened(expr: Any) -> bool:
    """Whether :func:`readable` changes ``expr``."""
    if _EXACT.get():
        return False
    if isinstance(expr, (list, tuple)):
        return any(is_shortened(e) for e in expr)
    return isinstance(expr, sp.Basic) and any(_long(r) for r in expr.atoms(sp.Rational))


def readable_number(text: str) -> str:
    """A rational written as text (``"p/q"``, as certificates store it) for display."""
    if _EXACT.get() or len(text) <= MAX_EXACT_CHARS:
        return text
    try:
        value = Fraction(text)
    except (ValueError, ZeroDivisionError):
        return text
    return sp.sstr(sp.Float(sp.Rational(value.numerator, value.denominator), 6))


#: Characters of sympy's Unicode pretty forms (brackets, rules, roots) and of the units the output prints.
_UNICODE_PROBE = "\u23a1\u23a4\u23a3\u23a6\u2500\u221a\u00b7\u00b2"


def unicode_output(stream: Any = None) -> bool:
    """Whether ``stream`` (default ``sys.stdout``) can print the Unicode pretty forms; else ASCII art is printed
    (``PYTHONIOENCODING=ascii``, a ``C`` locale), as sympy's own ``pprint`` decides from the terminal.

    Examples
    --------
    >>> import io
    >>> unicode_output(io.TextIOWrapper(io.BytesIO(), encoding="ascii"))
    False
    """
    encoding = getattr(sys.stdout if stream is None else stream, "encoding", None) or "ascii"
    try:
        _UNICODE_PROBE.encode(encoding)
    except (LookupError, UnicodeEncodeError):
        return False
    return True
