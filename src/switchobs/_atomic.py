"""Outputs that appear whole or not at all (standard library only).

Every file switchobs writes goes through here: it is written under a
temporary name in the directory it belongs to, then renamed into place, so
an interrupted or failed command leaves no half-written file; a command that
writes a folder of files stages them in a temporary folder and moves them in
only when it succeeds.  The ``check_*`` functions test an output path before
a command starts its long work (a certification, the demo), so a typo in
``--out`` costs milliseconds, not minutes.  Every failure is an
:class:`~switchobs.exceptions.OutputError` naming the path.
"""

from __future__ import annotations

import os
import re
import secrets
import shutil
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path

from .exceptions import OutputError

__all__ = ["check_output_file", "check_output_directory", "atomic_file", "write_text", "staged_directory",
           "write_files", "safe_file_name", "MAX_NAME_LENGTH"]

#: Characters kept of a name from a file when it becomes a file name (the suffix is added after).
MAX_NAME_LENGTH = 100
_UNSAFE = re.compile(r"[^A-Za-z0-9._-]+")


def _fail(path: Path, what: str, reason: str) -> OutputError:
    return OutputError(f"cannot write {what} {str(path)!r}: {reason}")


def _target(path: str | os.PathLike, what: str) -> Path:
    target = Path(path)
    if "\x00" in str(target):  # no system call takes it: refused here, not as an internal error later
        raise _fail(target, what, "a path cannot hold a NUL character")
    return target


def _probe(directory: Path, target: Path, what: str) -> None:
    """Create and remove a file in ``directory``: the one sure test (read-only file systems, root, quotas)."""
    probe = directory / f".switchobs-probe-{secrets.token_hex(4)}"
    try:
        os.close(os.open(probe, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600))
        os.unlink(probe)
    except OSError as exc:
        raise _fail(target, what, f"the directory {str(directory)!r} is not writable ({exc.strerror})") from None


def check_output_file(path: str | os.PathLike, *, what: str = "the file") -> Path:
    """``path`` as a Path if a file can be written there, else :class:`OutputError` saying why.

    The directory must exist and be writable; the path must not be a
    directory or a special file (``/dev/full``, a pipe): the file is replaced
    by a rename, which would replace a device node.
    """
    target = _target(path, what)
    if target.is_dir():
        raise _fail(target, what, "it is a directory; give a file name")
    if target.exists() and not target.is_file():
        raise _fail(target, what, "it exists and is not a regular file (a device or a pipe); give a file path")
    parent = target.parent
    if not parent.exists():
        raise _fail(target, what, f"the directory {str(parent)!r} does not exist; create it first")
    if not parent.is_dir():
        raise _fail(target, what, f"{str(parent)!r} is not a directory")
    _probe(parent, target, what)
    return target


def _nearest_existing(path: Path) -> Path:
    probe = path
    while not probe.exists() and probe != probe.parent:
        probe = probe.parent
    return probe


def check_output_directory(path: str | os.PathLike, *, what: str = "the directory") -> Path:
    """``path`` as a Path if files can be written into it (created if missing), else :class:`OutputError`."""
    target = _target(path, what)
    if target.exists() and not target.is_dir():
        raise _fail(target, what, "it exists and is not a directory")
    base = _nearest_existing(target)
    if not base.is_dir():
        raise _fail(target, what, f"{str(base)!r} is not a directory")
    _probe(base, target, what)
    return target


@contextmanager
def atomic_file(path: str | os.PathLike, *, what: str = "the file") -> Iterator[Path]:
    """A temporary path next to ``path`` (same suffix); renamed to ``path`` when the block succeeds.

    On any failure the temporary file is removed and ``path`` is untouched.
    """
    target = check_output_file(path, what=what)
    partial = target.with_name(f".{target.stem}.partial-{secrets.token_hex(4)}{target.suffix}")
    try:
        yield partial
        os.replace(partial, target)
    except OutputError:
        raise
    except OSError as exc:
        raise _fail(target, what, exc.strerror or str(exc)) from None
    finally:
        partial.unlink(missing_ok=True)


def write_text(path: str | os.PathLike, text: str, *, what: str = "the file") -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically; the path."""
    with atomic_file(path, what=what) as partial:
        partial.write_text(text, encoding="utf-8")
    return Path(path)


@contextmanager
def staged_directory(path: str | os.PathLike, *, what: str = "the directory") -> Iterator[Path]:
    """A fresh folder whose files appear in ``path`` (created if missing) only when the block succeeds.

    On success every file of the folder is moved into ``path`` (replacing
    files of the same name, keeping the others); on failure the folder, and
    any directory created for ``path``, is removed.  A file of the folder
    whose place in ``path`` is taken by a directory fails the whole move
    before anything is moved.
    """
    target = check_output_directory(path, what=what)
    created: list[Path] = []
    for ancestor in reversed([target, *target.parents]):
        if not ancestor.exists():
            try:
                ancestor.mkdir()
            except OSError as exc:
                _remove_created(created)
                raise _fail(target, what, f"cannot create {str(ancestor)!r} ({exc.strerror})") from None
            created.append(ancestor)
    work = target / f".switchobs-partial-{secrets.token_hex(4)}"
    try:
        work.mkdir()
        yield work
        files = sorted(p for p in work.rglob("*") if not p.is_dir())
        for source in files:
            dest = target / source.relative_to(work)
            if dest.is_dir() or (dest.exists() and not dest.is_file()):
                raise _fail(dest, "the file", "it is a directory or a special file; remove it or choose "
                                              "another output directory")
        for source in files:
            dest = target / source.relative_to(work)
            dest.parent.mkdir(parents=True, exist_ok=True)
            os.replace(source, dest)
    except OutputError:
        _remove_created(created)
        raise
    except OSError as exc:
        _remove_created(created)
        raise _fail(Path(exc.filename) if getattr(exc, "filename", None) else target, what,
                    exc.strerror or str(exc)) from None
    except BaseException:
        _remove_created(created)
        raise
    finally:
        shutil.rmtree(work, ignore_errors=True)


def _remove_created(created: list[Path]) -> None:
    for directory in reversed(created):
        shutil.rmtree(directory, ignore_errors=True)


def write_files(directory: str | os.PathLike, files: Mapping[str, str | bytes], *,
                what: str = "the directory") -> tuple[Path, ...]:
    """Write ``{relative path: text (UTF-8) or bytes}`` into ``directory`` all together or not at all; the
    paths written."""
    with staged_directory(directory, what=what) as work:
        for name, content in files.items():
            path = work / name
            path.parent.mkdir(parents=True, exist_ok=True)
            if isinstance(content, bytes):
                path.write_bytes(content)
            else:
                path.write_text(content, encoding="utf-8")
    return tuple(Path(directory) / name for name in files)


def safe_file_name(text: str, *, suffix: str = "", fallback: str = "output") -> str:
    """A plain file name made of ``text`` (a name read from a user's file), ending in ``suffix``.

    A name from a file is not a path: every run of characters other than ASCII letters, digits, ``.``, ``_``
    and ``-`` (a ``/``, a ``\\``, a NUL, a space, non-ASCII) becomes one ``_``, leading dots, dashes and
    underscores go (no ``..``, no hidden file, no option-like name), and the rest is cut to
    :data:`MAX_NAME_LENGTH` characters; an empty result is ``fallback``.  The result names a file in the
    current directory, never elsewhere.

    Examples
    --------
    >>> safe_file_name("../../evil", suffix=".jsonl"), safe_file_name("/tmp/x y", suffix=".png")
    ('evil.jsonl', 'tmp_x_y.png')
    """
    name = _UNSAFE.sub("_", str(text)).lstrip("._-")[:MAX_NAME_LENGTH].rstrip(".")
    return (name or fallback) + suffix
