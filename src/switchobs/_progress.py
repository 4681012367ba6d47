"""Progress notes from long library steps: silent unless a caller listens.

Library code calls :func:`progress` with a stage and its size
(``"design: K_plus (n = 64)"``); nothing is printed unless the caller has
installed a listener with :func:`listening` (the command line prints the
notes on stderr).  The listener lives in a context variable, so library code
never changes global state and concurrent callers do not see each other's notes.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar

__all__ = ["progress", "listening"]

_LISTENER: ContextVar[Callable[[str], None] | None] = ContextVar("switchobs_progress", default=None)


def progress(text: str) -> None:
    """Report that a stage starts (``"certify: strict CQLF LMI (n = 64, 2 modes)"``).

    A loop that knows its length writes ``[k/N]`` in the note of step ``k``
    (``"simulate: Table 4.1 [3/30] two-phase, wet-asphalt, 120 km/h"``); the
    command line draws a bar from it.
    """
    listener = _LISTENER.get()
    if listener is not None:
        listener(text)


@contextmanager
def listening(listener: Callable[[str], None]) -> Iterator[None]:
    """Send the :func:`progress` notes of the enclosed calls to ``listener``.

    Examples
    --------
    >>> notes = []
    >>> with listening(notes.append):
    ...     progress("design: normal form (n = 3)")
    >>> progress("not heard")
    >>> notes
    ['design: normal form (n = 3)']
    """
    token = _LISTENER.set(listener)
    try:
        yield
    finally:
        _LISTENER.reset(token)
