"""Reading and writing measurement logs: ASAM MDF 4 (asammdf), Parquet (pyarrow) and CSV (standard library).

A log is read as named channels, each with its own time stamps (an MDF4 channel has its group's master; a
column of a table has the table's time column).  The file's size is checked before it is opened
(``MAX_LOG_BYTES``) and a channel's length before it is converted (``MAX_LOG_SAMPLES``), so a huge log is
refused by its size, never read whole.  Cells left empty (a null in Parquet, an empty field in CSV) are
kept as a mask: a column of encoder edges is shorter than the signals beside it in one table.

Channels are read piece by piece (:meth:`Log.pieces`): an MDF4 group fragment by fragment of its data
blocks (asammdf's ``iter_get``, :data:`MDF_FRAGMENT_BYTES` of records at a time, the file read through a
file object: asammdf maps a file it opens by name, and every page read would stay resident), a Parquet
table by batches of :data:`CHUNK_ROWS` rows (pyarrow's ``iter_batches``, the columns asked for only), a
CSV file row by row, handed on every :data:`CHUNK_ROWS` rows (only the columns asked for parsed, 8 bytes a
value).  Reading thus holds one piece, not the file's other channels or a decoded copy of the whole file;
:meth:`Log.channel` joins a channel's pieces (``tests/test_logs_memory.py`` measures the peak on a long
log, ``tests/test_replay_stream.py`` that of a streamed replay).

Logs are written by :class:`LogWriter` piece by piece and atomically (MDF4 by :mod:`._mdf4`, Parquet a row
group a piece, CSV row by row).
"""

from __future__ import annotations

import contextlib
import csv
import itertools
import math
from array import array
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from .._atomic import atomic_file
from .._limits import MAX_LOG_BYTES, MAX_LOG_SAMPLES
from ..exceptions import LogError, PrerequisiteError
from ._mdf4 import Mdf4Writer

__all__ = ["FORMATS", "Channel", "Log", "log_format", "read_log", "write_table", "write_mdf", "CHUNK_ROWS",
           "LogWriter"]

Array = npt.NDArray[np.float64]
Bools = npt.NDArray[np.bool_]

#: Rows of a table read at a time (module notes): 2 MB of float64 values a column.
CHUNK_ROWS = 262_144
#: Bytes of an MDF4 group's records asammdf decodes at a time (a fragment of its data blocks).
MDF_FRAGMENT_BYTES = 1 * 2**20

#: File name endings of each log format.
FORMATS: dict[str, tuple[str, ...]] = {"mdf": (".mf4", ".mdf"), "parquet": (".parquet", ".pq"), "csv": (".csv",)}


def log_format(path: str | Path, default: str | None = None) -> str:
    """The format of a log by its file name ending (``mdf``, ``parquet``, ``csv``); ``default`` if unknown."""
    suffix = Path(path).suffix.lower()
    for fmt, endings in FORMATS.items():
        if suffix in endings:
            return fmt
    if default is not None:
        return default
    known = ", ".join(e for endings in FORMATS.values() for e in endings)
    raise LogError(f"{str(path)!r}: unknown log format {suffix or '(no ending)'!r}; name it {known}")


def _missing(package: str, fmt: str) -> PrerequisiteError:
    return PrerequisiteError(f"{fmt} logs need {package}: pip install \"switchobs[logs]\" (or pip install {package})")


def _asammdf() -> Any:
    try:
        import asammdf
    except ImportError:
        raise _missing("asammdf", "MDF4") from None
    return asammdf


def _pyarrow() -> tuple[Any, Any]:
    try:
        import pyarrow
        import pyarrow.parquet
    except ImportError:
        raise _missing("pyarrow", "Parquet") from None
    return pyarrow, pyarrow.parquet


@dataclass(frozen=True, eq=False)
class Channel:
    """One channel of a log: time stamps [s], values in the file's unit, and which cells hold a value."""

    name: str
    t: Array
    values: Array
    present: npt.NDArray[np.bool_]
    unit: str


class Log:
    """A log opened for reading: its channels by name (read when asked for).

    Parameters
    ----------
    path : str or Path
    time_channel : str
        The time column of a table (CSV, Parquet); an MDF4 channel has its group's master.
    time_factor : float
        Seconds per unit of the time column.
    """

    def __init__(self, path: str | Path, *, time_channel: str = "t", time_factor: float = 1.0):
        self.path = Path(path)
        self.format = log_format(path)
        try:
            size = self.path.stat().st_size
        except OSError as exc:
            raise LogError(f"cannot read the log {str(path)!r}: {exc.strerror}") from None
        if not self.path.is_file():
            raise LogError(f"the log {str(path)!r} is not a regular file")
        if size > MAX_LOG_BYTES:
            raise LogError(f"the log {str(path)!r} has {size} bytes (limit MAX_LOG_BYTES = {MAX_LOG_BYTES}); "
                           "cut it into shorter logs")
        self._time, self._factor = time_channel, time_factor
        self._parquet: Any = None
        self._mdf: Any = None
        self._file: Any = None
        if self.format == "mdf":
            asammdf = _asammdf()
            try:
                # from a file object, not by name: asammdf then reads it, where it would map a named file
                # into memory and every page read would stay resident (the whole log's size by the end)
                self._file = open(self.path, "rb")
                self._mdf = asammdf.MDF(self._file)
            except Exception as exc:  # asammdf raises many kinds for a file that is not MDF
                if self._file is not None:
                    self._file.close()
                raise LogError(f"the log {str(path)!r} is not a readable MDF file: {exc}") from None
            # pieces of a few MB: asammdf's default fragment (256 MB) would hold a long log's group whole
            self._mdf.configure(read_fragment_size=MDF_FRAGMENT_BYTES)
            # asammdf names each group's master "time"; a channel of the map is never the master
            self.names = sorted(n for n in self._mdf.channels_db if n != "time")
        elif self.format == "parquet":
            _, pq = _pyarrow()
            try:
                self._parquet = pq.ParquetFile(str(self.path))
                rows = self._parquet.metadata.num_rows
                columns = list(self._parquet.schema_arrow.names)
            except Exception as exc:
                raise LogError(f"the log {str(self.path)!r} is not a readable Parquet file: {exc}") from None
            if rows > MAX_LOG_SAMPLES:
                raise LogError(f"the log {str(self.path)!r} has {rows} rows (limit MAX_LOG_SAMPLES = "
                               f"{MAX_LOG_SAMPLES}); cut it into shorter logs")
            self._rows, self._all = int(rows), columns
            self.names = [n for n in columns if n != self._time]
        else:
            self._all = self._csv_header()
            self.names = [n for n in self._all if n != self._time]

    def _csv_header(self) -> list[str]:
        """The column names of a CSV log (its first row), checked."""
        try:
            with open(self.path, newline="", encoding="utf-8") as f:
                header = next(csv.reader(f), None)
        except UnicodeDecodeError as exc:
            raise LogError(f"the log {str(self.path)!r} is not UTF-8 text ({exc.reason} at byte {exc.start})") from None
        except OSError as exc:
            raise LogError(f"cannot read the log {str(self.path)!r}: {exc.strerror}") from None
        if not header:
            raise LogError(f"the log {str(self.path)!r} is empty; a CSV log starts with a header row")
        header = [h.strip() for h in header]
        dup = sorted({h for h in header if header.count(h) > 1})
        if dup:
            raise LogError(f"the log {str(self.path)!r} has the column {dup[0]!r} twice")
        return header

    # ------------------------------------------------------------------ pieces
    def time_base(self, name: str, *, what: str) -> int:
        """Which time stamps the channel ``name`` has: its MDF4 group, or 0 for every column of a table.

        Raises
        ------
        LogError
            The channel is not in the log (the message lists those that are), or in several groups of an MDF4.
        """
        if name not in self.names:
            shown = ", ".join(repr(n) for n in self.names[:30]) + (" ..." if len(self.names) > 30 else "")
            raise LogError(f"{what}: channel {name!r} is not in the log {str(self.path)!r}; it has {shown}")
        if self._mdf is None:
            return 0
        groups = sorted({g for g, _ in self._mdf.channels_db[name]})
        if len(groups) > 1:  # asammdf would ask for a group (and log to stderr): the map names channels only
            raise LogError(f"{what}: channel {name!r} is in {len(groups)} groups of {str(self.path)!r} (groups "
                           f"{', '.join(map(str, groups))}); the channel map cannot choose: give the log "
                           "unique channel names")
        return int(groups[0])

    def unit(self, name: str, *, what: str) -> str:
        """The unit the file records for the channel (MDF4; ``""`` for a table or none recorded)."""
        if self._mdf is None:
            return ""
        group = self.time_base(name, what=what)
        index = next(i for g, i in self._mdf.channels_db[name] if g == group)
        return str(self._mdf.groups[group].channels[index].unit or "")

    def pieces(self, names: Sequence[str], *, what: str) -> Iterator[tuple[Array, dict[str, tuple[Array, Bools]]]]:
        """The channels ``names`` of one time base (:meth:`time_base`) piece by piece, in order: their time
        stamps [s] and ``name -> (values, present)`` (module notes: an MDF4 group fragment by fragment, a
        table :data:`CHUNK_ROWS` rows at a time).

        Raises
        ------
        LogError
            A channel not in the log or not numeric, channels of different groups, a table without its time
            column, a damaged file or one that holds more samples than it declares.
        """
        bases = {self.time_base(n, what=what) for n in names}
        if len(bases) > 1:
            raise LogError(f"{what}: channels {', '.join(repr(n) for n in names)} are in different groups of "
                           f"{str(self.path)!r}; they must be recorded together")
        if self._mdf is not None:
            return self._mdf_pieces(list(names), bases.pop(), what)
        if self._time not in self._all:
            raise LogError(f"the time column {self._time!r} is not in the log {str(self.path)!r}; it has "
                           + ", ".join(repr(n) for n in self._all) + " (set [time] channel in the channel map)")
        rows = self._parquet_pieces(list(names)) if self.format == "parquet" else self._csv_pieces(list(names))
        return ((t * self._factor if self._factor != 1.0 else t, cols) for t, cols in rows)

    def channel(self, name: str, *, what: str) -> Channel:
        """The channel ``name`` whole (``what`` it is for, for the message): its pieces joined.

        Raises
        ------
        LogError
            As :meth:`pieces`.
        """
        ts, values, present = [], [], []
        for t, cols in self.pieces([name], what=what):
            ts.append(t)
            values.append(cols[name][0])
            present.append(cols[name][1])
        return Channel(name, join_pieces(ts, float), join_pieces(values, float), join_pieces(present, bool),
                       self.unit(name, what=what))

    def _parquet_pieces(self, names: list[str]) -> Iterator[tuple[Array, dict[str, tuple[Array, Bools]]]]:
        """The table's time column and ``names`` by batches of :data:`CHUNK_ROWS` rows."""
        columns = [self._time] + [n for n in names if n != self._time]
        at = 0
        batches = self._parquet.iter_batches(batch_size=CHUNK_ROWS, columns=columns, use_pandas_metadata=False)
        while True:
            try:
                batch = next(batches, None)
            except Exception as exc:   # pyarrow's own kinds for a damaged file
                raise LogError(f"columns {', '.join(repr(n) for n in columns)} of {str(self.path)!r} cannot be "
                               f"read: {exc}") from None
            if batch is None:
                break
            got = {}
            for i, name in enumerate(columns):
                col = batch.column(i)
                try:
                    got[name] = (np.asarray(col.to_numpy(zero_copy_only=False), dtype=float),
                                 ~np.asarray(col.is_null().to_numpy(zero_copy_only=False), dtype=bool))
                except (TypeError, ValueError, NotImplementedError):
                    raise LogError(f"column {name!r} of {str(self.path)!r} is not numeric ({col.type})") from None
            at += batch.num_rows
            yield got[self._time][0], {n: got[n] for n in names}
        if at != self._rows:
            raise LogError(f"the columns of {str(self.path)!r} have {at} rows, the file says {self._rows}")

    def _csv_pieces(self, names: list[str]) -> Iterator[tuple[Array, dict[str, tuple[Array, Bools]]]]:
        """The table's time column and ``names``, parsed row by row (every row's field count checked) and
        handed on every :data:`CHUNK_ROWS` rows."""
        header = self._all
        wanted = [self._time] + [n for n in names if n != self._time]
        picked = [header.index(n) for n in wanted]
        try:
            with open(self.path, newline="", encoding="utf-8") as f:
                reader = csv.reader(f)
                next(reader, None)
                line = 1
                while True:
                    # 8 bytes a value and 1 a flag (lists of floats would take 5 times that)
                    cols = [array("d") for _ in picked]
                    filled = [bytearray() for _ in picked]
                    for row in itertools.islice(reader, CHUNK_ROWS):
                        line += 1
                        if line - 1 > MAX_LOG_SAMPLES:
                            raise LogError(f"the log {str(self.path)!r} has more than {MAX_LOG_SAMPLES} rows "
                                           f"(limit MAX_LOG_SAMPLES); cut it into shorter logs")
                        if len(row) != len(header):
                            raise LogError(f"{str(self.path)!r} line {line}: {len(row)} fields, the header has "
                                           f"{len(header)}")
                        for c, fill, i in zip(cols, filled, picked):
                            cell = row[i].strip()
                            fill.append(1 if cell else 0)
                            try:
                                c.append(float(cell) if cell else math.nan)
                            except ValueError:
                                raise LogError(f"{str(self.path)!r} line {line}: {cell[:40]!r} is not a "
                                               "number") from None
                    if not filled[0]:
                        return
                    # an empty cell is a missing value; "nan" written out is a NaN sample (refused where a value
                    # is needed); the arrays are views of the buffers filled above (no second copy)
                    got = {n: (np.frombuffer(c, dtype=float), np.frombuffer(fl, dtype=np.bool_))
                           for n, c, fl in zip(wanted, cols, filled)}
                    yield got[self._time][0], {n: got[n] for n in names}
        except UnicodeDecodeError as exc:
            raise LogError(f"the log {str(self.path)!r} is not UTF-8 text ({exc.reason} at byte {exc.start})") from None
        except OSError as exc:
            raise LogError(f"cannot read the log {str(self.path)!r}: {exc.strerror}") from None

    def _mdf_pieces(self, names: list[str], group: int, what: str
                    ) -> Iterator[tuple[Array, dict[str, tuple[Array, Bools]]]]:
        """MDF4 channels of ``group`` fragment by fragment of the group's data blocks (asammdf's ``iter_get``,
        the channels side by side)."""
        total = int(self._mdf.groups[group].channel_group.cycles_nr)
        for name in names:
            if total > MAX_LOG_SAMPLES:
                raise LogError(f"{what}: channel {name!r} has {total} samples (limit MAX_LOG_SAMPLES = "
                               f"{MAX_LOG_SAMPLES})")
        index = {n: next(i for g, i in self._mdf.channels_db[n] if g == group) for n in names}
        fragments = zip(*(self._mdf.iter_get(n, group=group, index=index[n]) for n in names))
        at = 0
        while True:
            try:
                sigs = next(fragments, None)
            except Exception as exc:
                raise LogError(f"{what}: channel {names[0]!r} of {str(self.path)!r} cannot be read: {exc}") from None
            if sigs is None:
                break
            t = np.asarray(sigs[0].timestamps, dtype=float)
            if at + t.size > total:
                raise LogError(f"{what}: channel {names[0]!r} of {str(self.path)!r} holds more than the {total} "
                               "samples its group declares")
            cols = {}
            for name, sig in zip(names, sigs):
                samples = sig.samples
                try:
                    values = np.asarray(np.ma.getdata(samples), dtype=float)
                except (TypeError, ValueError):
                    raise LogError(f"{what}: channel {name!r} is not numeric ({samples.dtype})") from None
                present = ~np.ma.getmaskarray(samples) if isinstance(samples, np.ma.MaskedArray) else \
                    np.ones(t.size, dtype=bool)
                cols[name] = (values, present)
            at += t.size
            yield t, cols
        if at != total:
            raise LogError(f"{what}: channel {names[0]!r} of {str(self.path)!r} holds {at} of the {total} samples "
                           "its group declares")


def join_pieces(parts: list[npt.NDArray[Any]], dtype: Any) -> npt.NDArray[Any]:
    """Pieces end to end (the one piece itself, no copy)."""
    return parts[0] if len(parts) == 1 else np.concatenate(parts) if parts else np.zeros(0, dtype=dtype)


def read_log(path: str | Path, *, time_channel: str = "t", time_factor: float = 1.0) -> Log:
    """Open a log for reading its channels (:class:`Log`)."""
    return Log(path, time_channel=time_channel, time_factor=time_factor)


class LogWriter:
    """A log of one table written piece by piece (:meth:`append`), atomically: the file appears when the
    ``with`` block ends without an error, and nothing does otherwise.

    MDF4: one channel group, the column ``time_column`` its master, the others its channels with their
    units (:class:`Mdf4Writer`); Parquet: one row group a piece (pyarrow's ``ParquetWriter``); CSV: the
    header, then a row per row.  Only the piece being written is held.

    Parameters
    ----------
    path : str or Path
    columns : mapping
        ``name -> (unit, dtype)`` of every column, in order (the time column first for MDF4).
    fmt : {"mdf", "parquet", "csv"}, optional
        Default by the ending of ``path``.
    time_column : str
        The MDF4 master.
    """

    def __init__(self, path: str | Path, columns: Mapping[str, tuple[str, npt.DTypeLike]], *,
                 fmt: str | None = None, time_column: str = "t") -> None:
        self.path, self.format = Path(path), fmt or log_format(path)
        if self.format not in FORMATS:
            raise LogError(f"unknown log format {self.format!r}; use {', '.join(FORMATS)}")
        self._columns, self._time = dict(columns), time_column
        self._stack = contextlib.ExitStack()
        self._sink: Any = None

    def __enter__(self) -> LogWriter:
        with contextlib.ExitStack() as stack:
            partial = stack.enter_context(atomic_file(self.path, what="the log"))
            if self.format == "parquet":
                pa, pq = _pyarrow()
                self._schema = pa.schema([(k, pa.from_numpy_dtype(np.dtype(d))) for k, (_, d) in self._columns.items()])
                # no dictionary encoding: measured signals seldom repeat a value, and trying it is most of the
                # writing's time (60000 rows of 10 columns: 24 ms with it, 4 ms without)
                self._sink = stack.enter_context(pq.ParquetWriter(str(partial), self._schema, use_dictionary=False))
            elif self.format == "mdf":
                self._sink = Mdf4Writer(stack.enter_context(open(partial, "w+b")))
                self._sink.group({k: v for k, v in self._columns.items() if k != self._time})
                stack.callback(self._sink.close)
            else:
                self._sink = csv.writer(stack.enter_context(open(partial, "w", newline="", encoding="utf-8")))
                self._sink.writerow(list(self._columns))
            self._stack = stack.pop_all()
        return self

    def append(self, columns: Mapping[str, npt.ArrayLike], *, empty: Mapping[str, npt.NDArray[np.bool_]] | None = None
               ) -> None:
        """Rows: every column's values (equal lengths); ``empty`` marks cells left empty (a null in Parquet,
        an empty field in CSV; MDF4 has no empty cells)."""
        arrays = {k: np.asarray(columns[k]) for k in self._columns}
        empty = empty or {}
        if self.format == "mdf":
            self._sink.append(arrays[self._time], {k: v for k, v in arrays.items() if k != self._time})
        elif self.format == "parquet":
            pa = _pyarrow()[0]
            self._sink.write_table(pa.table([pa.array(a, mask=empty.get(k)) for k, a in arrays.items()],
                                            schema=self._schema))
        else:
            cols = [a.tolist() for a in arrays.values()]
            gaps = [empty[k].tolist() if k in empty else None for k in arrays]
            self._sink.writerows([_cell(c[i]) if g is None or not g[i] else "" for c, g in zip(cols, gaps)]
                                 for i in range(len(cols[0]) if cols else 0))

    def __exit__(self, *exc: object) -> None:
        # on an error the partial file is removed unnamed (atomic_file); the sink is closed first either way
        self._stack.__exit__(*exc)


def write_table(path: str | Path, columns: Mapping[str, npt.ArrayLike], *, fmt: str | None = None) -> Path:
    """Write columns as a CSV or Parquet table, atomically; a column shorter than the first is padded with
    empty cells (nulls), as a column of encoder edges beside the signals is."""
    fmt = fmt or log_format(path)
    if fmt not in ("parquet", "csv"):
        raise LogError(f"write_table writes csv or parquet, not {fmt!r} (use write_mdf)")
    arrays = {k: np.asarray(v) for k, v in columns.items()}
    rows = max((a.size for a in arrays.values()), default=0)
    with LogWriter(path, {k: ("", a.dtype) for k, a in arrays.items()}, fmt=fmt) as out:
        out.append({k: np.concatenate([a, np.zeros(rows - a.size, dtype=a.dtype)]) for k, a in arrays.items()},
                   empty={k: np.arange(rows) >= a.size for k, a in arrays.items() if a.size < rows})
    return Path(path)


def _cell(v: Any) -> str:
    if isinstance(v, float):
        return "" if math.isnan(v) else repr(v)
    return str(v)


def write_mdf(path: str | Path, groups: Sequence[tuple[npt.ArrayLike, Mapping[str, tuple[npt.ArrayLike, str]]]]
              ) -> Path:
    """Write an ASAM MDF 4 file atomically (:class:`Mdf4Writer`): each group a master time [s] and its channels
    ``name -> (values, unit)`` (floats, or integers as 64-bit integers)."""
    with atomic_file(path, what="the log") as partial, open(partial, "w+b") as f:
        mdf = Mdf4Writer(f)
        for t, channels in groups:
            arrays = {name: (_mdf_values(v), unit) for name, (v, unit) in channels.items()}
            mdf.group({name: (unit, a.dtype) for name, (a, unit) in arrays.items()})
            mdf.append(t, {name: a for name, (a, _) in arrays.items()})
        mdf.close()
    return Path(path)


def _mdf_values(values: npt.ArrayLike) -> npt.NDArray[Any]:
    """A channel's values as MDF4 stores them here: 8-byte floats or signed integers."""
    a = np.asarray(values)
    return a.astype(np.int64) if a.dtype.kind in "iub" else a.astype(float)
