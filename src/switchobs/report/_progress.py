"""Stage lines with elapsed times for the long steps of the demo, and the prerequisite check."""

from __future__ import annotations

import importlib
import sys
import time
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import TextIO

from .._papers import cite
from ..exceptions import CodegenError, PrerequisiteError, install_hint

__all__ = ["Progress", "Stage", "check_prerequisites"]


@dataclass(frozen=True)
class Stage:
    """A stage of a pipeline and what it needs before it can start.

    Attributes
    ----------
    name : str
    modules : tuple of str
        Python modules that must import (third-party packages and the switchobs layer).
    compiler : bool
        Whether a C compiler (``$CC``, ``gcc`` or ``cc`` on ``PATH``) is needed.
    """

    name: str
    modules: tuple[str, ...] = ()
    compiler: bool = False


def check_prerequisites(stages: Sequence[Stage]) -> None:
    """Check every stage's prerequisites before anything runs.

    Raises
    ------
    PrerequisiteError
        Naming the first stage that cannot run, what it misses and how to get it.

    Examples
    --------
    >>> check_prerequisites([Stage("design", ("sympy",))])      # nothing missing: returns None
    >>> check_prerequisites([Stage("plot", ("no_such_module",))])
    Traceback (most recent call last):
    ...
    switchobs.exceptions.PrerequisiteError: stage 'plot' cannot run: importing no_such_module failed (No module named 'no_such_module'); reinstall switchobs and its dependencies (pip install --force-reinstall "switchobs")
    """
    for stage in stages:
        for module in stage.modules:
            try:
                importlib.import_module(module)
            except ImportError as exc:
                raise PrerequisiteError(
                    f"stage {stage.name!r} cannot run: importing {module} failed ({exc}); "
                    f"{install_hint(getattr(exc, 'name', None) or module)}") from None
        if stage.compiler:
            from ..codegen import find_compiler  # importable without casadi: the generator alone needs it

            try:
                find_compiler()
            except CodegenError as exc:
                raise PrerequisiteError(f"stage {stage.name!r} cannot run: {exc}") from None


@dataclass
class Progress:
    """Prints ``[k/N] stage: what`` when a stage starts and its elapsed time when it ends.

    Parameters
    ----------
    total : int
        Number of stages.
    stream : text stream, optional
        Default ``sys.stderr``; ``None`` keeps quiet.

    Examples
    --------
    >>> import io
    >>> out = io.StringIO()
    >>> progress = Progress(1, stream=out)
    >>> with progress.stage("design", "symbolic gains"):
    ...     progress.note("abs-xbs3 done")
    >>> out.getvalue().splitlines()[:2]
    ['[1/1] design: symbolic gains', '      abs-xbs3 done']
    """

    total: int
    stream: TextIO | None = field(default_factory=lambda: sys.stderr)
    timings: dict[str, float] = field(default_factory=dict)
    _count: int = 0
    _t0: float = field(default_factory=time.perf_counter)

    def _say(self, text: str) -> None:
        if self.stream is not None:
            print(text, file=self.stream, flush=True)

    @contextmanager
    def stage(self, name: str, what: str) -> Iterator[None]:
        """Time one stage; on an exception say that it failed, then let the exception through."""
        self._count += 1
        self._say(f"[{self._count}/{self.total}] {name}: {cite(what)}")
        start = time.perf_counter()
        try:
            yield
        except BaseException:
            self._say(f"      {name} failed after {time.perf_counter() - start:.1f} s")
            raise
        self.timings[name] = time.perf_counter() - start
        self._say(f"      done in {self.timings[name]:.1f} s (total {time.perf_counter() - self._t0:.1f} s)")

    def note(self, text: str) -> None:
        """An indented line inside the current stage."""
        self._say(f"      {cite(text)}")

    def summary(self) -> Mapping[str, float]:
        return dict(self.timings)
