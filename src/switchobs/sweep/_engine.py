"""The sweep engine: cases in batches on Dask (or serially in-process), rows streamed to JSON Lines.

Dask (``dask.distributed``, the optional extra ``switchobs[sweep]``) is imported only when a sweep
runs on it.  ``scheduler="local"`` starts a ``LocalCluster`` of one single-threaded worker process per
core; an address ``tcp://HOST:PORT`` or a ``distributed.Client`` uses an existing cluster, whose
workers need only the installed package (and a C compiler for ``impl = "c"``: each worker compiles
once through the cache of :mod:`switchobs.codegen`); ``scheduler="none"`` runs in this process.

Results survive: each finished case is one line of the results file, keyed by its case id, written as
soon as its batch returns; ``resume=True`` skips the cases already there; a case that fails is a row
with its error; when a worker dies, the scheduler re-runs its batches elsewhere (Dask's
``allowed-failures``), and a batch lost too often becomes ``lost`` rows that a resume re-runs.  Once
every case has its row, the file is rewritten in case order (atomically), so a sweep that was killed
and resumed ends with the same file as one that ran through.
"""

from __future__ import annotations

import json
import math
import os
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from .._json import fields_from_json
from .._progress import CountedProgress, progress
from ..exceptions import PrerequisiteError, SimulationError
from ._case import Case
from ._run import STATUS_ERROR, STATUS_LOST, CaseResult, run_case

__all__ = ["run_sweep", "SweepResult", "read_results", "SCHEDULER_NONE", "SCHEDULER_LOCAL", "dask_client"]

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


def _run_batch(cases: Sequence[Case], series: bool) -> list[tuple[dict[str, Any], float]]:
    """Rows and wall times of a batch; any exception of a case becomes its error row (the batch goes on)."""
    out = []
    for case in cases:
        try:
            res = run_case(case, series=series)
        except Exception as exc:  # noqa: BLE001 - a bug in one case must not lose the others' results
            res = CaseResult(case, STATUS_ERROR, {}, error=f"{type(exc).__name__}: {exc}")
        out.append((res.to_json(), res.wall_time_s))
    return out


def read_results(path: str | Path) -> list[CaseResult]:
    """The rows of a results file; a last line cut short by a kill is left out."""
    rows, _ = _read_rows(Path(path))
    return [CaseResult.from_json(r) for r in rows]


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
            if not line.endswith(b"\n") or not isinstance(row, dict) or "case_id" not in row:
                raise ValueError("incomplete row")
        except ValueError:
            if good + len(line) == len(data):  # the last line, torn by a kill: re-run that case
                break
            raise SimulationError(f"{path}: line {number} is not a result row; is this a sweep results "
                                  f"file?") from None
        rows.append(row)
        good += len(line)
    return rows, good


def dask_client(scheduler: Any = SCHEDULER_LOCAL, *, workers: int | None = None) -> tuple[Any, Any, str]:
    """``(client, close, description)`` for a scheduler address, ``"local"`` or a Client.

    ``close()`` shuts down what this call started (a local cluster, a connection); a Client given
    by the caller stays open.

    Raises
    ------
    PrerequisiteError
        ``dask.distributed`` is not installed, or the scheduler cannot be reached.
    """
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

        n = workers or os.cpu_count() or 1
        cluster = distributed.LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                           dashboard_address=":0", silence_logs=logging.ERROR)
        client = distributed.Client(cluster)

        def close() -> None:
            client.close()
            cluster.close()
        return client, close, f"LocalCluster ({n} worker{'s' if n > 1 else ''})"
    try:
        client = distributed.Client(scheduler, timeout="20s")
    except (OSError, TimeoutError, ValueError) as exc:
        raise PrerequisiteError(f"cannot reach the Dask scheduler {scheduler!r}: {exc}; start one with "
                                "`dask scheduler` and `dask worker ADDRESS`, or use --scheduler local") from None
    return client, client.close, f"Dask scheduler {scheduler}"


def _batches(cases: Sequence[Case], workers: int, batch_size: int | None) -> list[list[Case]]:
    if batch_size is None:
        batch_size = max(1, min(MAX_BATCH, math.ceil(len(cases) / (BATCHES_PER_WORKER * max(workers, 1)))))
    elif not (isinstance(batch_size, int) and batch_size >= 1):
        raise SimulationError(f"batch_size must be an integer >= 1, got {batch_size!r}")
    return [list(cases[i:i + batch_size]) for i in range(0, len(cases), batch_size)]


def run_sweep(cases: Iterable[Case], *, path: str | Path | None = None, resume: bool = False,
              scheduler: Any = SCHEDULER_LOCAL, workers: int | None = None, batch_size: int | None = None,
              series: bool = False) -> SweepResult:
    """Run every case (each once: equal cases share a case id) and stream the rows to ``path``.

    Parameters
    ----------
    cases : iterable of BrakingCase or CertifyCase
    path : str or Path, optional
        JSON Lines file of the rows (one per case, keyed by ``case_id``).  An existing file needs
        ``resume=True``.
    resume : bool
        Keep the rows already in ``path`` (except ``lost`` ones) and run only the other cases.
    scheduler : "local", "none", "tcp://HOST:PORT" or distributed.Client
        Where the cases run (see the module notes).
    workers : int, optional
        Worker processes of the local cluster (default: one per core).
    batch_size : int, optional
        Cases per task (default: about :data:`BATCHES_PER_WORKER` batches per worker, at most
        :data:`MAX_BATCH` cases).
    series : bool
        Keep the time series of braking cases in the rows.

    Returns
    -------
    SweepResult

    Raises
    ------
    SimulationError
        ``path`` exists without ``resume``, or holds lines that are not result rows.
    PrerequisiteError
        Dask is needed and missing, or its scheduler cannot be reached.

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
    order = list(unique)
    done: dict[str, dict[str, Any]] = {}
    file = None if path is None else Path(path)
    good = 0
    if file is not None and file.exists():
        if not resume:
            raise SimulationError(f"the results file {str(file)!r} exists; resume it (--resume) or choose "
                                  f"another path")
        rows, good = _read_rows(file)
        for row in rows:
            if row.get("status") != STATUS_LOST:
                done[row["case_id"]] = row
    todo = [unique[k] for k in order if k not in done]
    resumed = len(order) - len(todo)
    counter = CountedProgress("sweep", total=len(order), done=resumed, unit="cases")
    engine = "in-process"
    walls: dict[str, float] = {}
    sink = None
    if file is not None:
        sink = open(file, "r+b" if file.exists() else "wb")
        sink.truncate(good)  # a torn last line goes
        sink.seek(good)

    def take(rows: list[tuple[dict[str, Any], float]]) -> None:
        for row, wall in rows:
            done[row["case_id"]] = row
            walls[row["case_id"]] = wall
            if sink is not None:
                sink.write((json.dumps(row, sort_keys=True) + "\n").encode("utf-8"))
        if sink is not None:
            sink.flush()
        counter.add(len(rows))

    try:
        if todo and scheduler in (SCHEDULER_NONE, None):
            progress(f"sweep: {len(todo)} cases in-process")
            for batch in _batches(todo, 1, batch_size or 1):
                take(_run_batch(batch, series))
        elif todo:
            engine = _run_on_dask(todo, take, scheduler=scheduler, workers=workers, batch_size=batch_size,
                                  series=series)
    finally:
        if sink is not None:
            sink.close()
    results = tuple(CaseResult.from_json(done[k]) for k in order)
    results = tuple(replace(r, wall_time_s=walls.get(k, 0.0)) for k, r in zip(order, results))
    if file is not None:
        _canonical(file, [done[k] for k in order], {k: done[k] for k in done if k not in unique})
    return SweepResult(results=results, path=file, engine=engine, resumed=resumed,
                       wall_time_s=time.perf_counter() - t0)


def _canonical(file: Path, rows: list[dict[str, Any]], foreign: dict[str, dict[str, Any]]) -> None:
    """Rewrite the file in case order (rows of other sweeps kept after them), atomically."""
    partial = file.with_name(f".{file.name}.partial")
    try:
        with open(partial, "w", encoding="utf-8") as fh:
            for row in [*rows, *foreign.values()]:
                fh.write(json.dumps(row, sort_keys=True) + "\n")
        os.replace(partial, file)
    finally:
        partial.unlink(missing_ok=True)


def _run_on_dask(todo: list[Case], take: Any, *, scheduler: Any, workers: int | None, batch_size: int | None,
                 series: bool) -> str:
    client, close, engine = dask_client(scheduler, workers=workers)
    from distributed import as_completed

    try:
        n = len(client.scheduler_info().get("workers", {})) or workers or 1
        batches = _batches(todo, n, batch_size)
        progress(f"sweep: {len(todo)} cases in {len(batches)} batches on {engine}")
        futures = client.map(_run_batch, batches, series=series, pure=False)
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
