"""Compile a generated observer with the system C compiler and drive it from Python (ctypes).

The shared library is cached by the SHA-256 of its source, header, compiler
and flags in the user's own cache directory (``$SWITCHOBS_CODEGEN_CACHE``, by
default the platform's per-user cache: ``~/.cache/switchobs/codegen`` on Linux,
see :func:`cache_directory`), written atomically so that parallel test workers
can share it.  A library is code that runs in the user's process, so nothing is
loaded from a place another user can write: the directory is created 0700 and
refused when it, or a directory above it, is owned by another user or writable
by others (a sticky ``/tmp`` above is fine); a library is loaded only when it is
the user's, not writable by others, and its SHA-256 is the one recorded when it
was built, under the key of its source.  The cache keeps at most
:data:`CACHE_MAX_LIBRARIES` libraries and :data:`CACHE_MAX_BYTES` bytes, the
least recently used going first.  It is built
for the host's instruction set (:data:`HOST_FLAGS`, when the compiler accepts
them; the key then names the CPU too), as numba's JIT is: it only ever runs on
the machine that built it.  The files written for a target are unaffected.
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
import json
import math
import os
import platform
import shutil
import stat
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from .._validate import named_vector, signal_matrix
from ..exceptions import CodegenError, DimensionError, ModelError, ObserverInputError
from ._generate import BRANCH_HINTS, generate_observer
from ._observer import GeneratedObserver
from ..spec import STATUS_TEXT, StepStatus

__all__ = ["CObserver", "compile_observer", "compile_shared", "compile_sources", "cache_directory", "find_compiler",
           "load_library", "BUILD_FLAGS", "HOST_FLAGS", "CACHE_MAX_LIBRARIES", "CACHE_MAX_BYTES"]

#: Flags of the shared library the binding loads (the strict warning set is exercised by the tests); the
#: branch hints, which only clang reads, are wanted on the host (``_generate.BRANCH_HINTS``).
BUILD_FLAGS: tuple[str, ...] = ("-std=c99", "-O2", "-fPIC", "-shared", f"-D{BRANCH_HINTS}")
#: Added to the flags when the compiler accepts them (else the library is built without): the host's
#: instruction set (3-operand AVX instead of SSE2 moves on x86-64), and no contraction into fused
#: multiply-adds, so that every result equals the portable build's and the Python reference's.
HOST_FLAGS: tuple[str, ...] = ("-march=native", "-ffp-contract=off")

#: Largest n_steps of ``<prefix>_run`` (an int32_t, so that the API is the same on 16/32/64-bit targets).
_INT32_MAX = 2**31 - 1


#: The cache keeps at most this many compiled libraries ...
CACHE_MAX_LIBRARIES = 200
#: ... and this many bytes of them; beyond, the least recently used are removed after a build.
CACHE_MAX_BYTES = 256 * 2**20


def cache_directory() -> Path:
    """Where compiled observers are cached: ``$SWITCHOBS_CODEGEN_CACHE``, else the user's cache directory.

    The platform's per-user cache (platformdirs' ``user_cache_dir``): ``$XDG_CACHE_HOME/switchobs/codegen``
    or ``~/.cache/switchobs/codegen`` on Linux, ``~/Library/Caches/switchobs/codegen`` on macOS,
    ``%LOCALAPPDATA%\\switchobs\\Cache\\codegen`` on Windows.  Never a shared temporary directory: a
    predictable name there can be created first by another user, who then plants the libraries.
    """
    env = os.environ.get("SWITCHOBS_CODEGEN_CACHE")
    if env:
        return Path(env)
    import platformdirs

    return Path(platformdirs.user_cache_dir("switchobs", appauthor=False)) / "codegen"


def _refuse(path: Path, why: str) -> CodegenError:
    return CodegenError(f"refusing the compiled-code cache {str(path)!r}: {why}; compiled code is only loaded from "
                        "a directory that no other user can write (remove it, or set SWITCHOBS_CODEGEN_CACHE to "
                        "a directory of your own)")


def _check_owner(path: Path, st: os.stat_result, what: str) -> None:
    """Refuse ``path`` (with its stat ``st``) if another user owns it or may write it (POSIX; Windows ACLs are
    not inspected)."""
    if not hasattr(os, "getuid"):
        return
    if st.st_uid not in (os.getuid(), 0):
        raise _refuse(path, f"{what} is owned by user id {st.st_uid}, not by you ({os.getuid()})")
    # group write of the user's own primary group is the usual umask 002 of private user groups
    writers = stat.S_IWOTH | (0 if st.st_gid == os.getgid() else stat.S_IWGRP)
    if st.st_mode & writers and not (stat.S_ISDIR(st.st_mode) and st.st_mode & stat.S_ISVTX):
        raise _refuse(path, f"{what} is writable by other users (mode {stat.S_IMODE(st.st_mode):04o})")


def _secure_root(root: Path) -> Path:
    """``root`` created 0700 if missing, then checked: it and every directory above it are the user's (or
    root's) and not writable by others, except sticky directories such as ``/tmp`` (whose entries only their
    owner can rename)."""
    try:
        root.mkdir(mode=0o700, parents=True, exist_ok=True)
        real = root.resolve(strict=True)
        st = os.stat(real)
    except OSError as exc:
        raise CodegenError(f"cannot create the compiled-code cache {str(root)!r}: {exc.strerror}; "
                           "set SWITCHOBS_CODEGEN_CACHE to a writable directory of your own") from None
    if not stat.S_ISDIR(st.st_mode):
        raise _refuse(root, "it is not a directory")
    if hasattr(os, "getuid") and st.st_uid != os.getuid():
        raise _refuse(root, f"it is owned by user id {st.st_uid}, not by you ({os.getuid()})")
    if st.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        raise _refuse(root, f"other users may write it (mode {stat.S_IMODE(st.st_mode):04o}; it is created 0700)")
    for parent in real.parents:
        _check_owner(parent, os.stat(parent), f"the directory {str(parent)!r} above it")
    return real


def _manifest(library: Path) -> Path:
    return library.with_suffix(".json")


def _digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _verified(library: Path, key: str) -> bool:
    """Whether ``library`` is the one built for ``key``: the user's file, not writable by others, with the
    SHA-256 its manifest recorded at build time under that key.  A library without a matching manifest is not
    loaded (it is rebuilt); one owned by someone else or writable by others is refused."""
    try:
        fd = os.open(library, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0))
    except OSError:
        return False
    with os.fdopen(fd, "rb") as fh:
        st = os.fstat(fh.fileno())
        if not stat.S_ISREG(st.st_mode):
            raise _refuse(library, "it is not a regular file")
        _check_owner(library, st, "the library")
        data = fh.read()
    try:
        record = json.loads(_manifest(library).read_text("utf-8"))
    except (OSError, ValueError):
        return False
    return isinstance(record, dict) and record.get("key") == key and record.get("sha256") == _digest(data)


def _prune(root: Path, keep: Path) -> None:
    """Remove the least recently used libraries beyond :data:`CACHE_MAX_LIBRARIES` / :data:`CACHE_MAX_BYTES`."""
    entries = []
    for lib in root.glob("*.so"):
        try:
            st = lib.stat()
        except OSError:
            continue
        entries.append((st.st_mtime, st.st_size, lib))
    entries.sort(reverse=True)
    total = 0
    for count, (_, size, lib) in enumerate(entries, 1):
        total += size
        if lib != keep and (count > CACHE_MAX_LIBRARIES or total > CACHE_MAX_BYTES):
            for path in (lib, _manifest(lib)):
                try:
                    path.unlink()
                except OSError:
                    pass


_LIBRARIES_LOADED: dict[Path, ctypes.CDLL] = {}


def load_library(path: Path) -> ctypes.CDLL:
    """The library at ``path`` (as :func:`compile_sources` returns it), loaded once per process.

    Every compiled library of switchobs is loaded here, and only after :func:`compile_sources`
    verified it; a path it did not return is refused.
    """
    lib = _LIBRARIES_LOADED.get(path)
    if lib is None:
        if path not in _VERIFIED:
            raise CodegenError(f"refusing to load {str(path)!r}: not a library that switchobs built and verified")
        lib = ctypes.CDLL(str(path))
        _LIBRARIES_LOADED[path] = lib
    return lib


#: Libraries verified in this process (path -> key), the only ones :func:`load_library` loads.
_VERIFIED: dict[Path, str] = {}


def find_compiler(compiler: str | None = None) -> str:
    """The C compiler to use: ``compiler``, else ``$CC``, else ``gcc``, else ``cc``.

    Raises
    ------
    CodegenError
        If none is found on ``PATH``.
    """
    candidates = [compiler] if compiler else [c for c in (os.environ.get("CC"), "gcc", "cc") if c]
    for cand in candidates:
        path = shutil.which(cand)
        if path:
            return path
    raise CodegenError(f"no C compiler found (tried {', '.join(candidates)} on PATH); install gcc or set CC")


def compile_shared(gen: GeneratedObserver, *, compiler: str | None = None,
                   flags: Sequence[str] = BUILD_FLAGS, cache_dir: str | Path | None = None, host: bool = True) -> Path:
    """Compile ``gen`` into a shared library (cached); return its path (``host``: see :func:`compile_sources`).

    Raises
    ------
    CodegenError
        If the compiler fails; the message holds its first error lines.
    """
    return compile_sources(gen.files, (f"{gen.prefix}.c",), gen.prefix, compiler=compiler, flags=flags,
                           cache_dir=cache_dir, host=host)


@functools.lru_cache(maxsize=1)
def _host_cpu() -> str:
    """What ``-march=native`` compiles for: the machine and, where ``/proc/cpuinfo`` exists, the CPU model
    and its feature flags (a cache directory shared by different CPUs then holds one library per CPU)."""
    try:
        info = Path("/proc/cpuinfo").read_text(encoding="utf-8", errors="replace")
    except OSError:
        info = ""
    keys = {"model name", "flags", "Features", "CPU implementer", "CPU part"}
    lines = dict.fromkeys(line for line in info.splitlines() if line.split(":")[0].strip() in keys)
    return "\0".join([platform.system(), platform.machine(), *lines])


def compile_sources(files: Mapping[str, str], sources: Sequence[str], stem: str, *, compiler: str | None = None,
                    flags: Sequence[str] = BUILD_FLAGS, cache_dir: str | Path | None = None,
                    host: bool = True) -> Path:
    """Compile the C ``sources`` among ``files`` (name -> text) into one cached shared library ``<stem>-<key>.so``.

    The key is the SHA-256 of the files, the compiler, the flags and (``host``) the CPU; the
    library is written atomically, so parallel processes can share the cache.  With ``host``,
    :data:`HOST_FLAGS` are added to ``flags`` if the compiler accepts them.

    Raises
    ------
    CodegenError
        If the compiler fails; the message holds its first error lines.
    """
    cc = find_compiler(compiler)
    material = [f"{name}\0{files[name]}" for name in sorted(files)]
    tuning = [*HOST_FLAGS, _host_cpu()] if host else []
    key = hashlib.sha256("\0".join([*material, *sources, cc, *flags, *tuning]).encode()).hexdigest()[:20]
    root = _secure_root(Path(cache_dir) if cache_dir is not None else cache_directory())
    target = root / f"{stem}-{key}.so"
    if _verified(target, key):   # hashed on every call: a file changed since the last call is not loaded
        _VERIFIED[target] = key
        try:
            os.utime(target)   # recently used: pruned last
        except OSError:
            pass
        return target
    try:
        with tempfile.TemporaryDirectory(dir=root) as tmp:
            for name, text in files.items():
                (Path(tmp) / name).write_text(text, encoding="utf-8")
            out = Path(tmp) / "lib.so"
            args = ["-o", str(out), *(str(Path(tmp) / name) for name in sources), "-lm"]
            proc = subprocess.run([cc, *flags, *(HOST_FLAGS if host else ()), *args], capture_output=True,
                                  text=True, check=False)
            if proc.returncode != 0 and host:  # a compiler without -march=native: the portable build
                proc = subprocess.run([cc, *flags, *args], capture_output=True, text=True, check=False)
            if proc.returncode != 0:
                lines = (proc.stderr or proc.stdout).strip().splitlines()
                raise CodegenError(f"{cc} failed on the generated {', '.join(sources)}: " + " | ".join(lines[:4]))
            os.chmod(out, 0o700)
            record = Path(tmp) / "lib.json"
            record.write_text(json.dumps({"key": key, "sha256": _digest(out.read_bytes()), "compiler": cc,
                                          "python": sys.version.split()[0]}), encoding="utf-8")
            # the manifest last: a library is only loaded with its manifest, so a half-replaced pair is rebuilt
            os.replace(out, target)
            os.replace(record, _manifest(target))
    except OSError as exc:
        raise CodegenError(f"cannot build in the cache directory {str(root)!r}: {exc.strerror}; "
                           "set SWITCHOBS_CODEGEN_CACHE to a writable directory") from None
    # another process building the same key may be between its two renames: its pair is whole a moment later
    for _ in range(20):
        if _verified(target, key):
            break
        time.sleep(0.05)
    else:
        raise CodegenError(f"the library {str(target)!r} does not match its manifest after it was built; "
                           "another program is changing the compiled-code cache")
    _VERIFIED[target] = key
    _prune(root, target)
    return target


def _library(path: Path, gen: GeneratedObserver) -> ctypes.CDLL:
    lib = load_library(path)
    real = ctypes.c_float if gen.real == "float" else ctypes.c_double
    ptr = ctypes.POINTER(real)
    step = getattr(lib, f"{gen.prefix}_step")
    step.argtypes = [ptr, ptr, ptr, real]
    step.restype = ctypes.c_int32
    run = getattr(lib, f"{gen.prefix}_run")
    run.argtypes = [ptr, ptr, ctypes.c_int32, ptr, real, ptr]
    run.restype = ctypes.c_int32
    return lib


class CObserver:
    """A generated C observer, compiled and bound with ctypes.

    It has the interface of the Python reference observers
    (``switchobs.observers.SwitchedObserver``): ``step(xhat, signals, dt)``,
    ``run(xhat0, signal_rows, dt)``, ``readout(xhat)``, ``state_names``,
    ``signal_names``, ``size``, ``method``, and raises the same
    :class:`~switchobs.exceptions.ObserverInputError` codes, so either can be
    plugged into the simulations.  ``run_dt(xhat0, signal_rows, dt)`` runs the
    rows with a step length per row (``<prefix>_run_dt``).

    Parameters
    ----------
    generated : GeneratedObserver
    params : mapping name -> float, optional
        Runtime parameters replacing the defaults (model parameters, gains ``K_plus_<state>``...).
    readout : callable, optional
        ``readout(xhat)`` -> estimate (e.g. the reference observer's ``readout``).
    compiler : str, optional
    cache_dir : path, optional

    Notes
    -----
    In the float build, inputs are rounded to float32 before the call (a
    ``dt`` below the smallest float becomes 0 and is refused; values beyond
    3.4e38 become infinite and are refused as non-finite); results are
    returned as float64 arrays.
    """

    def __init__(self, generated: GeneratedObserver, *, params: Mapping[str, float] | None = None,
                 readout: Callable[[Any], Any] | None = None, compiler: str | None = None,
                 cache_dir: str | Path | None = None):
        self.generated = generated
        self._build_options = (compiler, cache_dir)
        self.library_path = compile_shared(generated, compiler=compiler, cache_dir=cache_dir)
        self._lib = _library(self.library_path, generated)
        self._dtype = np.float32 if generated.real == "float" else np.float64
        self._ctype = ctypes.c_float if generated.real == "float" else ctypes.c_double
        self._ptr = ctypes.POINTER(self._ctype)
        self.params = np.ascontiguousarray(generated.params_with(params), dtype=self._dtype)
        self._params_ptr = self.params.ctypes.data_as(self._ptr)
        self._x_type = self._ctype * generated.nx
        self._s_type = self._ctype * generated.ns
        self._step = getattr(self._lib, f"{generated.prefix}_step")
        self._run = getattr(self._lib, f"{generated.prefix}_run")
        # _run and _run_dt with untyped pointers: run() and run_dt() pass the arrays' addresses, without a
        # ctypes pointer object per argument (the per-call cost on short records)
        vp = ctypes.c_void_p
        self._run_addr = ctypes.CFUNCTYPE(ctypes.c_int32, vp, vp, ctypes.c_int32, vp, self._ctype, vp)(
            ctypes.cast(self._run, vp).value)
        self._run_dt_addr = ctypes.CFUNCTYPE(ctypes.c_int32, vp, vp, ctypes.c_int32, vp, vp, vp)(
            ctypes.cast(getattr(self._lib, f"{generated.prefix}_run_dt"), vp).value)
        self._params_addr = self.params.ctypes.data
        self._readout = readout

    # ------------------------------------------------------------------ construction
    @classmethod
    def _restore(cls, generated: GeneratedObserver, params: dict[str, float], readout: Callable[[Any], Any] | None,
                 compiler: str | None, cache_dir: str | Path | None) -> "CObserver":
        return cls(generated, params=params, readout=readout, compiler=compiler, cache_dir=cache_dir)

    def __reduce__(self):
        """Pickle as the generated files and the runtime parameters; unpickling recompiles (cached) and rebinds.

        The readout must be picklable itself (a reference observer's ``readout``
        is; a lambda is not).
        """
        params = dict(zip(self.generated.param_names, self.params.tolist()))
        return (type(self)._restore, (self.generated, params, self._readout, *self._build_options))

    @classmethod
    def like(cls, reference: Any, *, real: str = "double", prefix: str | None = None,
             compiler: str | None = None, cache_dir: str | Path | None = None) -> "CObserver":
        """The C twin of a Python reference observer (same model, gains, parameters, method, readout).

        ``reference`` is a ``switchobs.observers.SwitchedObserver`` or
        ``AdaptiveSwitchedObserver`` (read through its public attributes
        ``model``, ``K_plus``, ``K_minus``, ``values``, ``method``, ``unknown``,
        ``Gamma``, ``readout``, ``h_max``, ``max_substeps``).
        """
        unknown = tuple(getattr(reference, "unknown", ()))
        gen = generate_observer(reference.model, (reference.K_plus, reference.K_minus),
                                values=dict(reference.values), real=real, method=reference.method, prefix=prefix,
                                unknown=unknown, Gamma=reference.Gamma if unknown else None,
                                h_max=getattr(reference, "h_max", None),
                                max_substeps=getattr(reference, "max_substeps", None))
        has_readout = getattr(reference, "readout_expression", None) is not None
        return cls(gen, readout=reference.readout if has_readout else None, compiler=compiler, cache_dir=cache_dir)

    def with_params(self, params: Mapping[str, float]) -> "CObserver":
        """A copy with some runtime parameters changed (same compiled library)."""
        current = dict(zip(self.generated.param_names, self.params.tolist()))
        current.update(params)
        return CObserver(self.generated, params=current, readout=self._readout, cache_dir=self.library_path.parent)

    # ------------------------------------------------------------------ info
    @property
    def state_names(self) -> tuple[str, ...]:
        return self.generated.state_names

    @property
    def signal_names(self) -> tuple[str, ...]:
        return self.generated.signal_names

    @property
    def size(self) -> int:
        return self.generated.nx

    @property
    def method(self) -> str:
        return self.generated.method

    @property
    def real(self) -> str:
        return self.generated.real

    # ------------------------------------------------------------------ numerics
    def _vector(self, values: Any, names: Sequence[str], what: str) -> np.ndarray:
        arr = named_vector(values, names, what)
        if self._dtype is np.float64:
            return np.ascontiguousarray(arr)
        with np.errstate(over="ignore"):  # out-of-range doubles become inf, which the C checks refuse
            return np.ascontiguousarray(arr, dtype=self._dtype)

    def _dt(self, dt: Any) -> float:
        try:
            return float(dt)
        except (TypeError, ValueError):
            raise ObserverInputError(f"C observer step refused (BAD_DT, code 1): dt = {dt!r} is not a number",
                                     int(StepStatus.BAD_DT)) from None

    def _dt_ok(self, dt: float) -> bool:
        """dt passes the step's check: finite, > 0 and, when declared, within its range -- compared, as the C
        compares it, in the C real type (a double just below DT_MIN may round up to it in float)."""
        if not (math.isfinite(dt) and dt > 0.0):
            return False
        if "dt" not in self.generated.ranges:
            return True
        with np.errstate(over="ignore", under="ignore"):
            value = float(self._dtype(dt))
        lo, hi = self.generated.ranges["dt"]
        return lo <= value <= hi

    def _fail(self, code: int, x: np.ndarray, sig: np.ndarray, dt: float, row: int | None = None) -> ObserverInputError:
        status = StepStatus(code)
        where = f"row {row}: " if row is not None else ""
        named = lambda names, vals: ", ".join(f"{n} = {v!r}" for n, v in zip(names, vals.tolist()))  # noqa: E731
        ranged = lambda names: ", ".join(f"{n} in [{self.generated.ranges[n][0]!r}, "  # noqa: E731
                                         f"{self.generated.ranges[n][1]!r}]" for n in names if n in self.generated.ranges)
        detail = {
            StepStatus.BAD_DT: f"dt = {dt!r} must be finite and > 0 (seconds)" + (
                "" if "dt" not in self.generated.ranges else f", within its declared range: {ranged(['dt'])}"),
            StepStatus.NONFINITE_STATE: f"state {named(self.state_names, x)}; reset the observer",
            StepStatus.NONFINITE_SIGNAL: f"signals {named(self.signal_names, sig)}",
            StepStatus.UNDEFINED_TIME_SCALE: f"signals {named(self.signal_names, sig)}",
            StepStatus.NONFINITE_RESULT: f"signals {named(self.signal_names, sig)}; reduce dt or check the signals",
            StepStatus.BAD_PARAM: f"params {named(self.generated.param_names, self.params)}",
            StepStatus.BAD_ARGUMENT: "a NULL pointer or negative count reached the C code",
            StepStatus.STATE_RANGE: f"state {named(self.state_names, x)}; ranges {ranged(self.state_names)}",
            StepStatus.SIGNAL_RANGE: f"signals {named(self.signal_names, sig)}; ranges {ranged(self.signal_names)}",
            StepStatus.SUBSTEP_LIMIT: f"signals {named(self.signal_names, sig)}, dt = {dt!r}: |s|*dt needs more "
                                      f"than MAX_SUBSTEPS = {self.generated.max_substeps} sub-steps of H_MAX = "
                                      f"{self.generated.h_max_c!r}; reduce dt or regenerate with a larger "
                                      "max_substeps",
        }.get(status, "")
        return ObserverInputError(f"C observer step refused ({status.name}, code {int(status)}): {where}"
                                  f"{STATUS_TEXT[status]}: {detail}", int(status))

    def step(self, xhat: npt.ArrayLike, signals: npt.ArrayLike, dt: float) -> np.ndarray:
        """One step of ``<prefix>_step``; returns the new state (``xhat`` is not modified).

        Raises
        ------
        ObserverInputError
            With ``.code`` the status the C step returned.
        DimensionError
            If ``xhat`` or ``signals`` has the wrong length.
        """
        # ctypes arrays built straight from the sequences: the per-call cost is what an ABS loop pays
        try:
            if len(xhat) != self.size or len(signals) != len(self.signal_names):  # type: ignore[arg-type]
                raise TypeError
            xb = self._x_type(*xhat)  # type: ignore[misc]
            sb = self._s_type(*signals)  # type: ignore[misc]
        except (TypeError, ValueError, OverflowError):
            xb = self._x_type(*self._vector(xhat, self.state_names, "xhat").tolist())
            sb = self._s_type(*self._vector(signals, self.signal_names, "signals").tolist())
        dt_f = self._dt(dt)
        code = self._step(xb, sb, self._params_ptr, dt_f)
        x = np.frombuffer(xb, dtype=self._dtype).astype(float)
        if code != 0:
            raise self._fail(code, x, np.frombuffer(sb, dtype=self._dtype), dt_f)
        return x

    def run(self, xhat0: npt.ArrayLike, signal_rows: npt.ArrayLike, dt: float) -> np.ndarray:
        """All rows in one call of ``<prefix>_run``; row ``i`` is the state after row ``i`` of the signals.

        Raises
        ------
        ObserverInputError
            The status of the first failing step; the message names the row.
        """
        x, rows_c = self._start(xhat0, signal_rows, "_run")
        dt_f = self._dt(dt)
        k = rows_c.shape[0]
        if not self._dt_ok(dt_f) or not all(map(math.isfinite, x.tolist())):
            # the checks of the first step, also when there is no row (as the reference does); the state's
            # declared ranges are the C's to check (the same codes, STATE_RANGE with no row too)
            code = StepStatus.BAD_DT if not self._dt_ok(dt_f) else StepStatus.NONFINITE_STATE
            raise self._fail(int(code), x, rows_c[0] if k else np.zeros(0), dt_f, 0)
        return self._rows(xhat0, x, rows_c, lambda i: dt_f,
                          lambda x, traj: self._run_addr(x.ctypes.data, rows_c.ctypes.data, k, self._params_addr,
                                                         dt_f, traj.ctypes.data))

    def run_dt(self, xhat0: npt.ArrayLike, signal_rows: npt.ArrayLike, dt: npt.ArrayLike) -> np.ndarray:
        """All rows in one call of ``<prefix>_run_dt``: row ``i`` a step of ``dt[i]`` seconds (irregular sampling).

        The states equal those of :meth:`step` row after row, bit for bit.

        Raises
        ------
        ObserverInputError
            The status of the first failing step (``BAD_DT`` for a ``dt[i]`` not finite or ``<= 0``); the
            message names the row.
        DimensionError
            If ``dt`` is not one number per row.
        """
        x, rows_c = self._start(xhat0, signal_rows, "_run_dt")
        try:
            steps = np.asarray(dt, dtype=float)
        except (TypeError, ValueError):
            raise ObserverInputError(f"C observer step refused (BAD_DT, code 1): dt = {dt!r} is not a sequence of "
                                     "numbers (seconds, one per row)", int(StepStatus.BAD_DT)) from None
        k = rows_c.shape[0]
        if steps.shape != (k,):
            raise DimensionError(f"dt has shape {steps.shape} but signal_rows has {k} rows; give one step length "
                                 "per row")
        steps_c = self._reals(steps)
        return self._rows(xhat0, x, rows_c, lambda i: float(steps[i]),
                          lambda x, traj: self._run_dt_addr(x.ctypes.data, rows_c.ctypes.data, k, self._params_addr,
                                                            steps_c.ctypes.data, traj.ctypes.data))

    def _reals(self, values: np.ndarray) -> np.ndarray:
        """``values`` as a C-contiguous array of the C real type."""
        if self._dtype is np.float64:
            return np.ascontiguousarray(values, dtype=np.float64)
        with np.errstate(over="ignore"):  # out-of-range doubles become inf, which the C checks refuse
            return np.ascontiguousarray(values, dtype=self._dtype)

    def _start(self, xhat0: npt.ArrayLike, signal_rows: npt.ArrayLike, function: str
               ) -> tuple[np.ndarray, np.ndarray]:
        """The state the C ``function`` writes into (a copy) and the signal rows in the C real type."""
        x = np.array(self._vector(xhat0, self.state_names, "xhat0"))
        rows_c = self._reals(signal_matrix(signal_rows, self.signal_names))
        if rows_c.shape[0] > _INT32_MAX:
            raise DimensionError(f"signal_rows has {rows_c.shape[0]} rows; the C {function} takes at most "
                                 f"{_INT32_MAX} (int32_t) per call: split the record")
        return x, rows_c

    def _rows(self, xhat0: npt.ArrayLike, x: np.ndarray, rows_c: np.ndarray, dt_of: Callable[[int], float],
              call: Callable[[np.ndarray, np.ndarray], int]) -> np.ndarray:
        """The trajectory of ``call(x, trajectory)`` (``_run`` or ``_run_dt`` over ``rows_c`` from ``x``), or the
        refusal of its first failing row (``dt_of(row)``: that row's step length, for the message)."""
        k = rows_c.shape[0]
        traj = np.empty((k, self.size), dtype=self._dtype)
        code = call(x, traj)
        if code != 0:
            # rare path: run again from the start on a NaN-filled trajectory to find the first failing row (rows
            # before it are written, finite)
            x = np.array(self._vector(xhat0, self.state_names, "xhat0"))
            traj.fill(np.nan)
            call(x, traj)
            if not k:  # no row: the C refused the state (the zero-row checks of _run and _run_dt)
                raise self._fail(code, x, np.zeros(0), math.nan, 0)
            done = int(np.argmin(np.isfinite(traj).all(axis=1)))
            raise self._fail(code, x, rows_c[done], dt_of(done), done)
        return traj if traj.dtype == np.float64 else traj.astype(float)

    def readout(self, xhat: npt.ArrayLike) -> Any:
        """The readout given at construction (e.g. the XBS estimate) of a state or trajectory."""
        if self._readout is None:
            raise ModelError("this C observer has no readout; build it with CObserver.like(reference) or "
                             "readout=callable")
        return self._readout(xhat)

    @property
    def readout_code(self) -> str | None:
        """The readout of the reference observer as its printed expression in ``x0, x1, ...`` (None if unknown)."""
        return getattr(getattr(self._readout, "__self__", None), "readout_code", None)

    # ------------------------------------------------------------------ output
    def to_json(self, *, sources: bool = False) -> dict[str, Any]:
        """The library, the runtime parameters and what the C means (and, if ``sources``, the whole
        :meth:`GeneratedObserver.to_json` with the files: what :meth:`from_json` reads)."""
        out = {"kind": "CObserver", "library": str(self.library_path),
               "params": dict(zip(self.generated.param_names, self.params.tolist())),
               **{k: v for k, v in self.generated.to_json().items() if k != "parameters"}}
        if sources:
            out["generated"] = self.generated.to_json(sources=True)
        return out

    @classmethod
    def from_json(cls, data: Any, *, readout: Callable[[Any], Any] | None = None, compiler: str | None = None,
                  cache_dir: str | Path | None = None) -> "CObserver":
        """The observer of ``to_json(sources=True)``, compiled again (from the cache when it holds the library).

        A readout is a Python callable, not JSON: give it again as ``readout``.

        Raises
        ------
        ModelError
            Written without ``sources=True``, or a malformed part.
        CodegenError, PrerequisiteError
            As the constructor: the C does not compile, or there is no compiler.
        """
        if not isinstance(data, Mapping) or not isinstance(data.get("params"), Mapping) or "generated" not in data:
            raise ModelError("a CObserver JSON needs 'params' and 'generated'; write it with to_json(sources=True)")
        return cls(GeneratedObserver.from_json(data["generated"]), params=data["params"], readout=readout,
                   compiler=compiler, cache_dir=cache_dir)

    def __str__(self) -> str:
        return f"compiled {self.generated}\n  library: {self.library_path}"

    def __repr__(self) -> str:
        return f"<CObserver {self.generated.prefix} {self.real} {self.method} n={self.size}>"


def compile_observer(generated: GeneratedObserver, *, params: Mapping[str, float] | None = None,
                     readout: Callable[[Any], Any] | None = None, compiler: str | None = None,
                     cache_dir: str | Path | None = None) -> CObserver:
    """Compile ``generated`` (cached) and return the :class:`CObserver` bound to it.

    Examples
    --------
    >>> from switchobs.model import builtin_model
    >>> from switchobs.codegen import generate_observer
    >>> obs = compile_observer(generate_observer(builtin_model("abs-xbs3"),
    ...                                          ([84.0, -19.5, -21.3], [-16.0, -4.4, 21.3])))
    >>> obs.step([0.0, 0.5, 0.0], [10.0, 20.0, 0.0], 1e-3).round(6).tolist()
    [0.36948, 0.41203, -0.104526]
    """
    return CObserver(generated, params=params, readout=readout, compiler=compiler, cache_dir=cache_dir)
