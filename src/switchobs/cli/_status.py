"""The live progress display of the command line: one status line on a terminal, redrawn in place.

The library announces its stages with :func:`switchobs._progress.progress`
(``"certify: dwell time, bisection (n = 3, 2 modes)"``); a note that counts its
steps carries ``[k/N]`` (``"simulate: Table 4.1 [3/30] ..."``) and gets a bar,
which stays while the notes of the step itself (a design inside a theory
document) follow it.  :class:`StatusLine` shows them behind a spinner and the
elapsed time, ten times a second, so a long LMI solve that announces nothing still
shows that the command is alive.  Whatever the command prints meanwhile (its
result on stdout, its own stage lines on stderr) first erases the status line,
which comes back once the output has ended its line; when the command ends the
line is erased, leaving only the command's own output on the screen.
"""

from __future__ import annotations

import os
import re
import shutil
import sys
import threading
import time
from types import TracebackType
from typing import TextIO

__all__ = ["StatusLine", "is_terminal"]

#: A note that counts its steps: ``[k/N]``.
COUNT = re.compile(r"\[(\d+)/(\d+)\]")
SPINNER = "|/-\\"
BAR_WIDTH = 20


def is_terminal(stream: TextIO) -> bool:
    """Whether ``stream`` is an interactive terminal that understands carriage return and erase-line."""
    isatty = getattr(stream, "isatty", None)
    return bool(isatty and isatty()) and os.environ.get("TERM") != "dumb"


class _Erasing:
    """A text stream that erases the status line before each write (the command's own output)."""

    def __init__(self, status: StatusLine, stream: TextIO) -> None:
        self._status, self._stream = status, stream

    def write(self, text: str) -> int:
        return self._status._write_through(self._stream, text)

    def flush(self) -> None:
        self._stream.flush()

    def __getattr__(self, name: str):  # noqa: ANN204 - isatty, fileno, encoding, ... of the real stream
        return getattr(self._stream, name)


class StatusLine:
    """A progress listener drawing ``| switchobs CMD  12.3 s  [####....] note`` on a terminal.

    Parameters
    ----------
    command : str
        Sub-command name shown in the line.
    stream : text stream
        The terminal (``sys.stderr``).
    after_s : float
        Nothing is drawn before the command has run this long (quick commands leave no trace).
    refresh_s : float
        Redraw interval.

    Use as a context manager around the command: it starts the redraw thread and routes
    ``sys.stdout``/``sys.stderr`` through writers that erase the line first; on exit it stops,
    erases the line and restores both streams.  The instance itself is the listener
    (``status("certify: ...")``).
    """

    def __init__(self, command: str, stream: TextIO, *, after_s: float = 0.5, refresh_s: float = 0.1) -> None:
        self.command = command
        self._stream = stream
        self._after_s, self._refresh_s = after_s, refresh_s
        self._counted = ""   # the latest note with [k/N]
        self._text = ""      # the latest note after it
        self._start = time.perf_counter()
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._shown = False
        self._at_line_start = True
        self._thread = threading.Thread(target=self._run, name="switchobs-status", daemon=True)
        self._saved: tuple[TextIO, TextIO] | None = None

    def __call__(self, text: str) -> None:
        if COUNT.search(text):
            self._counted, self._text = text, ""
        else:
            self._text = text

    def render(self, elapsed_s: float, columns: int) -> str:
        """The status line after ``elapsed_s`` seconds, cut to ``columns - 1`` characters."""
        frame = SPINNER[int(elapsed_s / self._refresh_s) % len(SPINNER)]
        notes = [note for note in (self._counted, self._text) if note]
        count = COUNT.search(self._counted)
        if count is not None and int(count.group(2)) > 0:
            done = min(int(count.group(1)), int(count.group(2))) / int(count.group(2))
            filled = round(BAR_WIDTH * done)
            notes[0] = f"[{'#' * filled}{'.' * (BAR_WIDTH - filled)}] {notes[0]}"
        line = f"{frame} switchobs {self.command} {elapsed_s:6.1f} s  {' · '.join(notes)}".rstrip()
        return line[:max(columns - 1, 0)]

    # ------------------------------------------------------------ drawing
    def _draw(self) -> None:
        with self._lock:
            if not self._at_line_start:  # the command is half-way through a line of its own
                return
            if self._saved is not None:
                self._saved[0].flush()   # the command's stdout first, so the line stays below it
            columns = shutil.get_terminal_size().columns
            self._stream.write("\r" + self.render(time.perf_counter() - self._start, columns) + "\x1b[K")
            self._stream.flush()
            self._shown = True

    def _erase(self) -> None:
        if self._shown:
            self._stream.write("\r\x1b[K")
            self._stream.flush()
            self._shown = False

    def _write_through(self, stream: TextIO, text: str) -> int:
        with self._lock:
            self._erase()
            written = stream.write(text)
            if text:
                self._at_line_start = text.endswith("\n")
            return written

    def _run(self) -> None:
        while not self._stop.wait(self._refresh_s):
            if time.perf_counter() - self._start >= self._after_s:
                self._draw()

    # ------------------------------------------------------------ context
    def __enter__(self) -> StatusLine:
        self._saved = (sys.stdout, sys.stderr)
        if is_terminal(sys.stdout):  # the same screen: the result must not land on the status line
            sys.stdout = _Erasing(self, sys.stdout)  # type: ignore[assignment]
        sys.stderr = _Erasing(self, sys.stderr)  # type: ignore[assignment]
        self._thread.start()
        return self

    def __exit__(self, kind: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self._stop.set()
        self._thread.join()
        with self._lock:
            self._erase()
        if self._saved is not None:
            sys.stdout, sys.stderr = self._saved
            self._saved = None
