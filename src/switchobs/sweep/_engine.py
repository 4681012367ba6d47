"""The sweep engine: cases in batches on Dask (or serially in-process), rows streamed to JSON Lines.

Dask (``dask.distributed``, the optional extra ``switchobs[sweep]``) is imported only when a sweep
runs on it.  ``scheduler="local"`` starts a ``LocalCluster`` of one single-threaded worker process per
core; an address ``tcp://HOST:PORT`` or a ``distributed.Client`` uses an existing cluster, whose
workers need only the installed package (and a C compiler for ``impl = "c"``: each worker compiles
once through the cache of :mod:`switchobs.codegen`); ``scheduler="none"`` runs in this process.

Results survive: each finished case is one line of the results file, keyed by its case id, written as
soon as its batch returns (the file is created with the first row: a sweep that cannot start leaves no
file); ``resume=True`` skips the cases already there and refuses a file holding rows of cases that are not
in the sweep (another study's file); a case that fails is a row
with its error; when a worker dies, the scheduler re-runs its batches elsewhere (Dask's
``allowed-failures``), and a batch lost too often becomes ``lost`` rows that a resume re-runs.  Once
every case has its row, the file is rewritten in case order (atomically), so a sweep that was killed
and resumed ends with the same file as one that ran through.

A results path ending in ``.parquet`` (or ``.pq``) gets the same rows as a Parquet table (pyarrow, the
optional extra ``switchobs[logs]``): a Parquet file cannot grow row by row, so the rows stream to the journal
``<path>.rows.jsonl`` beside it (JSON Lines, as above: what a resume reads after a kill), and when every
case has its row the table is written atomically and the journal removed.  The table has one row per case:
``row`` holds the JSON Lines row (``read_results`` reads it back, equal to the JSON Lines file's), and
``case_id``, ``status``, ``error`` and the scalar fields of the case and the metrics as typed columns
``case.NAME`` and ``metrics.NAME`` (a list, or a name whose values mix types, as JSON text) for analysis.

Warm workers: before the first batch goes out, every worker imports the simulation stack (one task pinned to
each) while this process builds every C observer of the cases once, and every worker then takes them all
(``Client.run``), so no worker repeats a design before its first case.  The builds stay here: the first
takes most of a second (the symbolic design and sympy's first use), each further one some 70 ms, so spread
over the workers each of them would pay the first again after its imports, and the tuning of the study
(:func:`~switchobs.sweep.tune_betas`) needs the design in this process anyway.  What travels is each
observer's generated C source, never a binary: a worker compiles it into, or finds it verified in, its own
per-user compiled-code cache (:func:`switchobs.codegen.load_library`); a worker that joins later, or whose
warm-up fails, builds what its cases need itself.

A case's warnings (numpy's overflow in a diverging run) are not printed: its row reports the outcome
(non-finite numbers are null, the status says why).  In this process and on the local cluster, what C code
prints while a case runs (a solver's diagnostics) goes nowhere either, so that ``--json`` output stays
JSON; the local cluster's workers ignore Ctrl-C, which stops the sweep in this process, where the cluster
is closed.
"""

from __future__ import annotations

import json
import math
import os
import signal
import sys
import threading
import time
import warnings
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager, nullcontext
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from .._atomic import atomic_file, check_output_file
from .._json import fields_from_json
from .._limits import MAX_SWEEP_CASES, MAX_SWEEP_STEPS, MAX_WORKERS_PER_CORE
from .._progress import CountedProgress, progress
from .._validate import check_work
from ..exceptions import PrerequisiteError, SimulationError
from ._case import BrakingCase, Case
from ._grid import check_case_count
from ._run import STATUS_ERROR, STATUS_LOST, CaseResult, build_observers, observer_settings, run_case

__all__ = ["run_sweep", "SweepResult", "read_results", "SCHEDULER_NONE", "SCHEDULER_LOCAL", "dask_client",
           "check_sweep_size", "PARQUET_ENDINGS"]

SCHEDULER_NONE = "none"
SCHEDULER_LOCAL = "local"
#: Batches per worker a sweep aims at: enough to balance the load, few enough to amortise the scheduling.
BATCHES_PER_WORKER = 8
MAX_BATCH = 16  # an encoder-fed braking costs up to a second: a batch is also the loss of a kill and the tail


@dataclass(frozen=True, eq=False)
class SweepResult:
    """A finished sweep: one :class:`CaseResult` per case, in case order.

    Attributes
    ----------
    results : tuple of CaseResult
    path : Path or None
        The JSON Lines file.
    engine : str
        Where the cases ran (``in-process``, ``LocalCluster (2 workers)``, ``tcp://...``).
    resumed : int
        Cases found finished in the file and not re-run.
    wall_time_s : float
    """

    results: tuple[CaseResult, ...]
    path: Path | None
    engine: str
    resumed: int
    wall_time_s: float

    @property
    def failed(self) -> tuple[CaseResult, ...]:
        return tuple(r for r in self.results if not r.ok)

    def to_json(self) -> dict[str, Any]:
        return {"cases": len(self.results), "failed": len(self.failed), "resumed": self.resumed,
                "engine": self.engine, "path": None if self.path is None else str(self.path),
                "wall_time_s": self.wall_time_s, "rows": [r.to_json() for r in self.results]}

    @classmethod
    def from_json(cls, data: Any) -> SweepResult:
        """The sweep of :meth:`to_json` (its ``rows`` read by :meth:`CaseResult.from_json`).

        Raises
        ------
        SimulationError
            No ``rows`` or a malformed row or key.
        """
        if not isinstance(data, dict) or not isinstance(data.get("rows"), list):
            raise SimulationError(f"a sweep result JSON needs a list of 'rows', got {data!r:.80}")
        try:
            rows = tuple(CaseResult.from_json(r) for r in data["rows"])
        except (KeyError, TypeError) as exc:
            raise SimulationError(f"a sweep result JSON has a malformed row ({exc!r})") from None
        return fields_from_json(cls, data, error=SimulationError, what="sweep result", results=rows)

    def __str__(self) -> str:
        ran = len(self.results) - self.resumed
        rate = ran / self.wall_time_s if self.wall_time_s > 0 else math.inf
        text = (f"sweep: {len(self.results)} cases ({self.resumed} found finished, {ran} run on {self.engine} "
                f"in {self.wall_time_s:.1f} s, {rate:.3g} cases/s), {len(self.failed)} failed")
        if self.path is not None:
            text += f"; rows in {self.path}"
        return text


def _run_batch(cases: Sequence[Case], series: bool, quiet: bool = False) -> list[tuple[dict[str, Any], float]]:
    """Rows and wall times of a batch; any exception of a case becomes its error row (the batch goes on).

    ``quiet``: also silence what C code writes on the process's standard output and error (single-threaded
    places only: in-process, the local cluster's one-thread workers).
    """
    out = []
    with _silenced_fds() if quiet else nullcontext(), warnings.catch_warnings():
        # a case reports itself in its row; its numeric warnings would reach the user's terminal from any worker
        warnings.simplefilter("ignore")
        for case in cases:
            try:
                res = run_case(case, series=series)
            except Exception as exc:  # noqa: BLE001 - a bug in one case must not lose the others' results
                res = CaseResult(case, STATUS_ERROR, {}, error=f"{type(exc).__name__}: {exc}")
            out.append((res.to_json(), res.wall_time_s))
    return out


@contextmanager
def _silenced_fds() -> Iterator[None]:
    """File descriptors 1 and 2 on the null device for the block (C libraries print there, not via Python)."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (AttributeError, OSError, ValueError):
            pass
    try:
        saved = [os.dup(1), os.dup(2)]
    except OSError:  # no standard output or error to protect
        yield
        return
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, 1)
        os.dup2(null, 2)
        yield
    finally:
        _flush_c_streams()
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in (*saved, null):
            os.close(fd)


def _flush_c_streams() -> None:
    """``fflush(NULL)``: C's buffered output of the block goes where the block sent it, not after it."""
    import ctypes

    try:
        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError):  # no C library to ask (not a POSIX process)
        pass


#: Endings of a results path written as a Parquet table (module notes).
PARQUET_ENDINGS = (".parquet", ".pq")


def _is_parquet(path: Path) -> bool:
    return path.suffix.lower() in PARQUET_ENDINGS


def _journal(path: Path) -> Path:
    """Where the rows of a Parquet results file stream until the table is written (module notes)."""
    return path.with_name(path.name + ".rows.jsonl")


def _pyarrow() -> tuple[Any, Any]:
    try:
        import pyarrow
        import pyarrow.parquet
    except ImportError:
        raise PrerequisiteError("Parquet results need pyarrow: pip install \"switchobs[logs]\" (or pip install "
                                "pyarrow), or write JSON Lines (--out NAME.jsonl)") from None
    return pyarrow, pyarrow.parquet


def read_results(path: str | Path) -> list[CaseResult]:
    """The rows of a results file (JSON Lines, or a Parquet table: module notes); a last line cut short by a
    kill is left out."""
    file = Path(path)
    rows = _read_parquet(file) if _is_parquet(file) else _read_rows(file)[0]
    return [CaseResult.from_json(r) for r in rows]


def _read_parquet(path: Path) -> list[dict[str, Any]]:
    """The rows of a Parquet results file, from its ``row`` column."""
    _, pq = _pyarrow()
    try:
        names = pq.read_schema(str(path)).names
        table = pq.read_table(str(path), columns=["row"]) if "row" in names else None
    except Exception as exc:  # noqa: BLE001 - pyarrow raises its own kinds for a file that is not Parquet
        raise SimulationError(f"{path}: not a readable Parquet file ({exc}); is this a sweep results "
                              "file?") from None
    try:
        if table is None:
            raise KeyError("row")
        rows = [json.loads(text) for text in table.column("row").to_pylist()]
    except (KeyError, TypeError, ValueError) as exc:
        raise SimulationError(f"{path}: not a sweep results table (no JSON rows in a 'row' column: "
                              f"{type(exc).__name__}); is this a sweep results file?") from None
    bad = next((i for i, row in enumerate(rows, 1) if not _is_row(row)), None)
    if bad is not None:
        raise SimulationError(f"{path}: row {bad} is not a result row; is this a sweep results file?")
    return rows


def _flat_columns(rows: list[dict[str, Any]]) -> dict[str, list[Any]]:
    """``case.NAME`` and ``metrics.NAME`` columns of the rows' scalar fields (None where a row has none)."""
    # sorted: a row read back from JSON Lines has its keys sorted, a fresh one in field order
    names = sorted({(part, key) for row in rows for part in ("case", "metrics") for key in (row.get(part) or {})})
    return {f"{part}.{key}": [(row.get(part) or {}).get(key) for row in rows] for part, key in names}


def _write_parquet(path: Path, rows: list[dict[str, Any]]) -> None:
    """The rows as a Parquet table, atomically (module notes)."""
    pa, pq = _pyarrow()
    columns: dict[str, Any] = {
        "case_id": pa.array([r["case_id"] for r in rows], type=pa.string()),
        "status": pa.array([r["status"] for r in rows], type=pa.string()),
        "error": pa.array([r.get("error") for r in rows], type=pa.string())}
    for name, values in _flat_columns(rows).items():
        try:
            if any(isinstance(v, (list, dict)) for v in values):
                raise TypeError("not scalar")
            columns[name] = pa.array(values)
        except (TypeError, ValueError, pa.ArrowException):   # lists, or numbers beside text: as JSON text
            columns[name] = pa.array([None if v is None else json.dumps(v, sort_keys=True) for v in values],
                                     type=pa.string())
    columns["row"] = pa.array([json.dumps(r, sort_keys=True) for r in rows], type=pa.string())
    with atomic_file(path, what="the results file") as partial:
        pq.write_table(pa.table(columns), str(partial))


def _is_row(row: Any) -> bool:
    return (isinstance(row, dict) and isinstance(row.get("case_id"), str) and isinstance(row.get("case"), dict)
            and isinstance(row.get("status"), str) and isinstance(row.get("metrics", {}), (dict, type(None))))


def _read_rows(path: Path) -> tuple[list[dict[str, Any]], int]:
    """Rows and the byte length of the complete lines (a torn last line is not part of the file)."""
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise SimulationError(f"cannot read the results file {str(path)!r}: {exc.strerror}") from None
    rows, good = [], 0
    for number, line in enumerate(data.splitlines(keepends=True), 1):
        try:
            row = json.loads(line)
            if not line.endswith(b"\n") or not _is_row(row):
                raise ValueError("incomplete row")
        except ValueError:
            if good + len(line) == len(data):  # the last line, torn by a kill: re-run that case
                break
            raise SimulationError(f"{path}: line {number} is not a result row; is this a sweep results "
                                  f"file?") from None
        rows.append(row)
        good += len(line)
    return rows, good


def _local_workers(workers: int | None) -> int:
    """The worker processes of a local cluster: ``workers`` (default one per core), at most
    :data:`switchobs._limits.MAX_WORKERS_PER_CORE` per core."""
    cores = os.cpu_count() or 1
    if workers is None:
        return cores
    if isinstance(workers, bool) or not (isinstance(workers, int) and workers >= 1):
        raise SimulationError(f"workers must be an integer >= 1, got {workers!r}")
    check_work(f"worker processes of the local cluster ({cores} core{'s' if cores > 1 else ''})", workers,
               MAX_WORKERS_PER_CORE * cores, f"give at most {MAX_WORKERS_PER_CORE} per core (MAX_WORKERS_PER_CORE)",
               error=SimulationError)
    return workers


def dask_client(scheduler: Any = SCHEDULER_LOCAL, *, workers: int | None = None) -> tuple[Any, Any, str]:
    """``(client, close, description)`` for a scheduler address, ``"local"`` or a Client.

    ``close()`` shuts down what this call started (a local cluster, a connection); a Client given
    by the caller stays open.  The workers of a local cluster ignore Ctrl-C (SIGINT, which a terminal sends
    to every process of the command): the interrupt stops the sweep here, and ``close()`` stops them.

    Raises
    ------
    PrerequisiteError
        ``dask.distributed`` is not installed, the local cluster cannot start, or the scheduler cannot be
        reached.
    SimulationError
        More ``workers`` than :data:`switchobs._limits.MAX_WORKERS_PER_CORE` per core.
    """
    n = _local_workers(workers) if scheduler == SCHEDULER_LOCAL else 0
    try:
        import distributed
    except ImportError as exc:
        raise PrerequisiteError(f"sweeps on Dask need dask.distributed ({exc}); install the extra with "
                                "pip install \"switchobs[sweep]\", or run serially with "
                                "--scheduler none") from None
    if isinstance(scheduler, distributed.Client):
        return scheduler, lambda: None, f"Dask client {scheduler.scheduler.address}"
    if scheduler == SCHEDULER_LOCAL:
        import logging

        try:
            with _workers_ignore_interrupts():
                cluster = distributed.LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                                   dashboard_address=":0", silence_logs=logging.ERROR)
        except (OSError, RuntimeError, TimeoutError, ValueError) as exc:
            raise PrerequisiteError(f"cannot start a local Dask cluster of {n} worker{'s' if n > 1 else ''} "
                                    f"({type(exc).__name__}: {exc}); try fewer --workers or --scheduler none") \
                from None
        client = distributed.Client(cluster)

        def close() -> None:
            client.close()
            cluster.close()
        return client, close, f"LocalCluster ({n} worker{'s' if n > 1 else ''})"
    _check_address(scheduler)
    try:
        client = distributed.Client(scheduler, timeout="20s")
    except (OSError, TimeoutError, ValueError, TypeError) as exc:
        raise PrerequisiteError(f"cannot reach the Dask scheduler {scheduler!r}: {exc}; start one with "
                                "`dask scheduler` and `dask worker ADDRESS`, or use --scheduler local") from None
    return client, client.close, f"Dask scheduler {scheduler}"


def _check_address(scheduler: Any) -> None:
    """Refuse what is not ``tcp://HOST:PORT`` before a Client is made: a Client whose constructor fails is
    closed by the garbage collector later, which can block for a minute and print a traceback."""
    from distributed.comm.addressing import parse_address, parse_host_port

    if not isinstance(scheduler, str):
        raise SimulationError(f"scheduler must be 'local', 'none', an address or a distributed.Client, got "
                              f"{scheduler!r:.80}")
    try:
        scheme, location = parse_address(scheduler)
        port = parse_host_port(location)[1]
    except (ValueError, TypeError) as exc:
        raise SimulationError(f"--scheduler {scheduler!r} is not 'local', 'none' or a scheduler address "
                              f"tcp://HOST:PORT ({exc})") from None
    if scheme != "tcp" or not 0 < port < 65536:
        raise SimulationError(f"--scheduler {scheduler!r}: give the address of a Dask scheduler as tcp://HOST:PORT "
                              "(a port in 1-65535), or 'local' or 'none'")


@contextmanager
def _workers_ignore_interrupts() -> Iterator[None]:
    """SIGINT ignored while the cluster starts its worker processes, which inherit that (and only that)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _batch_size(batch_size: int | None) -> None:
    if batch_size is not None and (isinstance(batch_size, bool) or not (isinstance(batch_size, int)
                                                                         and batch_size >= 1)):
        raise SimulationError(f"batch_size must be an integer >= 1, got {batch_size!r}")


def _batches(cases: Sequence[Case], workers: int, batch_size: int | None) -> list[list[Case]]:
    _batch_size(batch_size)
    if batch_size is None:
        batch_size = max(1, min(MAX_BATCH, math.ceil(len(cases) / (BATCHES_PER_WORKER * max(workers, 1)))))
    return [list(cases[i:i + batch_size]) for i in range(0, len(cases), batch_size)]


def check_sweep_size(cases: Sequence[Case], *, max_cases: int = MAX_SWEEP_CASES,
                     max_steps: float = MAX_SWEEP_STEPS) -> None:
    """Refuse a sweep of more than ``max_cases`` cases, or whose braking cases take more than ``max_steps``
    integration steps, each counted at its time bound over its step (an upper bound), before any case runs.

    Raises
    ------
    SimulationError
        Naming the count or the steps and the limit (:data:`switchobs._limits.MAX_SWEEP_CASES`,
        :data:`switchobs._limits.MAX_SWEEP_STEPS`).
    """
    check_case_count(len(cases), "cases of the sweep", max_cases=max_cases)
    steps = sum(c.duration_s / c.dt_s for c in cases if isinstance(c, BrakingCase))
    check_work(f"integration steps of the {sum(isinstance(c, BrakingCase) for c in cases)} braking cases (each "
               "at its time bound duration_s over its step dt_s)", steps, max_steps,
               "shorten duration_s, use a larger dt_s or fewer cases, or raise the limit (--max-steps)",
               error=SimulationError)


def run_sweep(cases: Iterable[Case], *, path: str | Path | None = None, resume: bool = False,
              scheduler: Any = SCHEDULER_LOCAL, workers: int | None = None, batch_size: int | None = None,
              series: bool = False, max_cases: int = MAX_SWEEP_CASES,
              max_steps: float = MAX_SWEEP_STEPS) -> SweepResult:
    """Run every case (each once: equal cases share a case id) and stream the rows to ``path``.

    Parameters
    ----------
    cases : iterable of BrakingCase or CertifyCase
    path : str or Path, optional
        JSON Lines file of the rows (one per case, keyed by ``case_id``), created with the first row, or a
        Parquet table (``.parquet``, ``.pq``: module notes).  An existing file needs ``resume=True``.
    resume : bool
        Keep the rows already in ``path`` (except ``lost`` ones) and run only the other cases.
    scheduler : "local", "none", "tcp://HOST:PORT" or distributed.Client
        Where the cases run (see the module notes).
    workers : int, optional
        Worker processes of the local cluster (default: one per core; at most
        :data:`switchobs._limits.MAX_WORKERS_PER_CORE` per core, and no more than the cases to run).
    batch_size : int, optional
        Cases per task (default: about :data:`BATCHES_PER_WORKER` batches per worker, at most
        :data:`MAX_BATCH` cases).
    series : bool
        Keep the time series of braking cases in the rows.
    max_cases, max_steps
        Limits of :func:`check_sweep_size`, checked before any case runs.

    Returns
    -------
    SweepResult

    Raises
    ------
    SimulationError
        ``path`` exists without ``resume``, holds lines that are not result rows or rows of cases that are
        not in this sweep; the sweep is larger than the limits; bad ``workers`` or ``batch_size``.
    OutputError
        ``path`` cannot be written (checked before any case runs).
    PrerequisiteError
        Dask is needed and missing, or its scheduler cannot be reached; pyarrow for a Parquet ``path``.

    Examples
    --------
    >>> from switchobs.sweep import BrakingCase, grid
    >>> sweep = run_sweep(grid(BrakingCase(), speed_kmh=[40.0, 60.0]), scheduler="none")
    >>> [r.status for r in sweep.results]
    ['stopped', 'stopped']
    """
    t0 = time.perf_counter()
    unique: dict[str, Case] = {}
    for case in cases:
        unique.setdefault(case.case_id, case)
        if len(unique) > max_cases:  # an endless iterable ends here
            check_case_count(len(unique), "cases of the sweep", max_cases=max_cases)
    order = list(unique)
    check_sweep_size(list(unique.values()), max_cases=max_cases, max_steps=max_steps)
    _batch_size(batch_size)
    local = scheduler == SCHEDULER_LOCAL
    if local:
        _local_workers(workers)
    done: dict[str, dict[str, Any]] = {}
    target = None if path is None else check_output_file(path, what="the results file")
    table = target is not None and _is_parquet(target)
    if table:
        _pyarrow()                                   # before any case runs
    # the file the rows stream to: the results file, or the journal of a Parquet table
    file = _journal(target) if table and target is not None else target
    if file is not None and table:
        check_output_file(file, what="the results journal")
    good = 0
    existed = file is not None and file.exists()
    tabled = table and target is not None and target.exists()
    if target is not None and (existed or tabled):
        if not resume:
            found = file if existed else target
            raise SimulationError(f"the results file {str(found)!r} exists; resume it (--resume) or choose "
                                  f"another path")
        rows, good = _read_rows(file) if existed and file is not None else ([], 0)
        if tabled:
            rows = _read_parquet(target) + rows      # a journal's rows are newer than the table's
        foreign = [row for row in rows if row["case_id"] not in unique]
        if foreign:
            raise SimulationError(f"the results file {str(file)!r} holds {len(foreign)} row(s) of cases that are "
                                  f"not in this sweep (the first: case {foreign[0]['case_id']}); it is another "
                                  "study's file: give this sweep a results file of its own")
        for row in rows:
            if row.get("status") != STATUS_LOST:
                done[row["case_id"]] = row
    todo = [unique[k] for k in order if k not in done]
    resumed = len(order) - len(todo)
    counter = CountedProgress("sweep", total=len(order), done=resumed, unit="cases")
    engine = "in-process"
    walls: dict[str, float] = {}
    sink: list[Any] = []

    def take(rows: list[tuple[dict[str, Any], float]]) -> None:
        if file is not None and not sink:  # the file appears with the first row, never empty
            sink.append(open(file, "r+b" if existed else "wb"))
            sink[0].truncate(good)  # a torn last line goes
            sink[0].seek(good)
        for row, wall in rows:
            done[row["case_id"]] = row
            walls[row["case_id"]] = wall
            if sink:
                sink[0].write((json.dumps(row, sort_keys=True) + "\n").encode("utf-8"))
        if sink:
            sink[0].flush()
        counter.add(len(rows))

    try:
        if todo and scheduler in (SCHEDULER_NONE, None):
            progress(f"sweep: {len(todo)} cases in-process")
            for batch in _batches(todo, 1, batch_size or 1):
                take(_run_batch(batch, series, quiet=True))
        elif todo:
            engine = _run_on_dask(todo, take, scheduler=scheduler, workers=workers, batch_size=batch_size,
                                  series=series)
    finally:
        if sink:
            sink[0].close()
    results = tuple(CaseResult.from_json(done[k]) for k in order)
    results = tuple(replace(r, wall_time_s=walls.get(k, 0.0)) for k, r in zip(order, results))
    if table and target is not None:
        _write_parquet(target, [done[k] for k in order])
        if file is not None:
            file.unlink(missing_ok=True)
    elif target is not None:
        _canonical(target, [done[k] for k in order])
    return SweepResult(results=results, path=target, engine=engine, resumed=resumed,
                       wall_time_s=time.perf_counter() - t0)


def _canonical(file: Path, rows: list[dict[str, Any]]) -> None:
    """Rewrite the file in case order, atomically."""
    with atomic_file(file, what="the results file") as partial:
        with open(partial, "w", encoding="utf-8") as fh:
            for row in rows:
                fh.write(json.dumps(row, sort_keys=True) + "\n")


def _run_on_dask(todo: list[Case], take: Any, *, scheduler: Any, workers: int | None, batch_size: int | None,
                 series: bool) -> str:
    local = scheduler == SCHEDULER_LOCAL
    # no more workers than cases: each costs a process start and a share of the memory
    client, close, engine = dask_client(scheduler, workers=min(_local_workers(workers), len(todo)) if local
                                        else workers)
    from distributed import as_completed

    try:
        n = len(client.scheduler_info().get("workers", {})) or workers or 1
        batches = _batches(todo, n, batch_size)
        _warm_workers(client, todo)
        progress(f"sweep: {len(todo)} cases in {len(batches)} batches on {engine}")
        # the local cluster's workers run one case at a time: their C output can be silenced (module notes)
        futures = client.map(_run_batch, batches, series=series, quiet=local, pure=False)
        index = {f.key: b for f, b in zip(futures, batches)}
        for future in as_completed(futures):
            try:
                rows = future.result()
            except Exception as exc:  # noqa: BLE001 - e.g. KilledWorker: the batch is lost, not the sweep
                rows = [(CaseResult(case, STATUS_LOST, {}, error=f"{type(exc).__name__}: {exc}").to_json(), 0.0)
                        for case in index[future.key]]
            take(rows)
            future.release()
    finally:
        close()
    return engine


def _warm_workers(client: Any, cases: Sequence[Case]) -> None:
    """Every worker imports the simulation stack (one task pinned to each) while this process builds the cases'
    C observers, which every worker then takes (module notes).  A build that fails is left out, a warm-up
    that fails is given up: the cases concerned build what they need."""
    settings = observer_settings(cases)
    if not settings:
        return
    progress(f"sweep: warming the workers ({len(settings)} C observer{'s' if len(settings) != 1 else ''})")
    imports: list[Any] = []
    try:
        imports = [client.submit(_warm_worker, {}, workers=[w], pure=False)
                   for w in client.scheduler_info().get("workers", {})]
        built = build_observers(settings)
        if built:
            client.run(_warm_worker, built, on_error="return")
    except Exception:  # noqa: BLE001 - a warm-up that cannot be sent costs time, not results
        pass
    finally:
        for future in imports:   # released, never awaited: a worker that left must not hold the sweep
            future.release()


def _warm_worker(built: dict[Any, Any]) -> int:
    """On a worker: the simulation stack imported and the observers ``built`` installed (their number)."""
    from .. import codegen  # noqa: F401 - what unpickling a C observer imports (casadi)
    from ..loop import install_observers
    from ..plants import simulate  # noqa: F401 - the import a first case would pay

    return install_observers(built)
