"""Progress notes from long library steps: silent unless a caller listens.

Library code calls :func:`progress` with a stage and its size
(``"design: K_plus (n = 64)"``); nothing is printed unless the caller has
installed a listener with :func:`listening` (the command line prints the
notes on stderr).  The listener lives in a context variable, so library code
never changes global state and concurrent callers do not see each other's notes.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar

__all__ = ["progress", "listening", "CountedProgress"]

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


class CountedProgress:
    """Counted work with its rate and the estimated time left, announced through :func:`progress`.

    ``done`` may start above 0 (work found finished, e.g. a resumed sweep): the rate counts only what
    is done from now on.

    Examples
    --------
    >>> notes = []
    >>> with listening(notes.append):
    ...     counter = CountedProgress("sweep", total=4, done=1, unit="cases")
    ...     counter.add(3)
    >>> notes[-1].startswith("sweep: 4/4 cases (100 %)")
    True
    """

    def __init__(self, label: str, *, total: int, done: int = 0, unit: str = "items"):
        self.label, self.total, self.done, self.unit = label, int(total), int(done), unit
        self._start_done = self.done
        self._start = time.perf_counter()

    @property
    def rate(self) -> float:
        """Items per second since the start (0 before the first)."""
        elapsed = time.perf_counter() - self._start
        return (self.done - self._start_done) / elapsed if elapsed > 0 else 0.0

    def text(self) -> str:
        rate = self.rate
        left = self.total - self.done
        eta = f"{left / rate:.0f} s left" if rate > 0 else "time left unknown"
        share = 100.0 * self.done / self.total if self.total else 100.0
        return f"{self.label}: {self.done}/{self.total} {self.unit} ({share:.0f} %), {rate:.3g}/s, {eta}"

    def add(self, count: int = 1) -> None:
        """Count ``count`` more items done and announce the new state."""
        self.done += count
        progress(self.text())
