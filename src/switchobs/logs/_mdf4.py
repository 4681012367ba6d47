"""Writing ASAM MDF 4.10 files directly, group by group and row block by row block.

A log written here is what a logger writes: each channel group one record layout (its master time, then
its channels, float64 or int64, little endian), its records in one uncompressed data block (``##DT``), no
conversions; the blocks before the data (identification, header, file history, data group, channel
group, channels, their names and units) are written first and the counts (the group's cycles, the data
block's length) patched in when the group ends.  Rows are appended as they come, so a result is written
piece by piece in the memory of one piece, and the file is one block per group to read back (asammdf
reads it fragment by fragment).  Writing through asammdf instead kept every appended block compressed
in its temporary storage and decompressed it to save: more work, and the whole result held at once.

Block layouts: ASAM MDF 4.1 (ID, HD, FH, MD, DG, CG, CN, TX, DT), each block 8-byte aligned, links are
file offsets, 0 for none.
"""

from __future__ import annotations

import struct
import time
from collections.abc import Mapping, Sequence
from typing import IO, Any

import numpy as np
import numpy.typing as npt

__all__ = ["Mdf4Writer"]

_COMMON = struct.Struct("<4s4xQQ")           # block id, reserved, length, link count
_DATA_TYPES = {"f": 4, "i": 2, "u": 0}      # IEEE 754 float, signed and unsigned integer, little endian
_CN_MASTER, _CN_VALUE, _SYNC_TIME = 2, 0, 1


def _block(kind: bytes, links: Sequence[int], data: bytes) -> bytes:
    return _COMMON.pack(kind, _COMMON.size + 8 * len(links) + len(data), len(links)) + \
        struct.pack(f"<{len(links)}Q", *links) + data


def _pad(raw: bytes) -> bytes:
    return raw + b"\0" * (-len(raw) % 8)


class Mdf4Writer:
    """An MDF 4.10 file written to the open binary file ``f``: :meth:`group` starts a channel group,
    :meth:`append` adds rows to it, :meth:`close` ends the file (the counts patched in).

    Parameters
    ----------
    f : binary file
        Opened for writing and reading back (``"w+b"``), at offset 0.
    """

    def __init__(self, f: IO[bytes]) -> None:
        self._f = f
        now = time.time_ns()
        ident = struct.pack("<8s8s8s4xH30x2H", b"MDF     ", b"4.10    ", b"switchob", 410, 0, 0)
        self._write(ident)
        hd_at = self._f.tell()
        hd = _block(b"##HD", [0, hd_at + 104, 0, 0, 0, 0], struct.pack("<Q2h4B2d", now, 0, 0, 0, 0, 0, 0, 0.0, 0.0))
        self._write(hd)
        fh_at = self._f.tell()
        comment = _pad(b"<FHcomment><TX>written by switchobs</TX><tool_id>switchobs</tool_id>"
                       b"<tool_vendor>switchobs</tool_vendor><tool_version>4</tool_version></FHcomment>\0")
        self._write(_block(b"##FH", [0, fh_at + 56], struct.pack("<Q2hB3x", now, 0, 0, 0)))
        self._write(_block(b"##MD", [], comment))
        self._first_dg_link = hd_at + _COMMON.size       # HD's first link: the first data group
        self._next_link = self._first_dg_link             # where the next data group's offset goes
        self._open: tuple[int, int, np.dtype[Any]] | None = None   # (CG offset, DT offset, record layout)
        self._rows = 0

    def _write(self, raw: bytes) -> None:
        self._f.write(_pad(raw))

    def _text(self, text: str) -> int:
        at = self._f.tell()
        self._write(_block(b"##TX", [], text.encode("utf-8") + b"\0"))
        return at

    def _patch(self, at: int, value: int) -> None:
        end = self._f.tell()
        self._f.seek(at)
        self._f.write(struct.pack("<Q", value))
        self._f.seek(end)

    def group(self, channels: Mapping[str, tuple[str, npt.DTypeLike]]) -> None:
        """Start a channel group (the previous one ends): its master ``time`` [s], then ``name -> (unit,
        dtype)`` (float or integer, 8 bytes), in this order."""
        self._end_group()
        layout = np.dtype([("time", "<f8")] + [(name, np.dtype(dtype).newbyteorder("<"))
                                               for name, (_, dtype) in channels.items()])
        for name in layout.names or ():
            if layout[name].itemsize != 8 or layout[name].kind not in _DATA_TYPES:
                raise ValueError(f"channel {name!r}: write 8-byte floats or integers, not {layout[name]}")
        dg_at = self._f.tell()
        self._patch(self._next_link, dg_at)
        self._next_link = dg_at + _COMMON.size
        cg_at = dg_at + 64
        cn_at = cg_at + 104
        specs = [("time", "s", _CN_MASTER, _SYNC_TIME)] + [(n, u, _CN_VALUE, 0) for n, (u, _) in channels.items()]
        # the texts go after the channels, so that every block's offset is known when it is written
        texts = cn_at + 160 * len(specs)
        names: list[tuple[int, int]] = []
        for name, unit, _, _ in specs:
            name_at = texts
            texts += len(_pad(_block(b"##TX", [], name.encode("utf-8") + b"\0")))
            unit_at = texts if unit else 0
            if unit:
                texts += len(_pad(_block(b"##TX", [], unit.encode("utf-8") + b"\0")))
            names.append((name_at, unit_at))
        dt_at = texts
        self._write(_block(b"##DG", [0, cg_at, dt_at, 0], struct.pack("<B7x", 0)))
        self._write(_block(b"##CG", [0, cn_at, 0, 0, 0, 0],
                           struct.pack("<QQHH4xII", 0, 0, 0, 0, layout.itemsize, 0)))
        offset = 0
        for i, ((name, _, kind, sync), (name_at, unit_at)) in enumerate(zip(specs, names)):
            field = layout[name]
            nxt = cn_at + 160 * (i + 1) if i + 1 < len(specs) else 0
            self._write(_block(b"##CN", [nxt, 0, name_at, 0, 0, 0, unit_at, 0],
                               struct.pack("<4B4I2BH6d", kind, sync, _DATA_TYPES[field.kind], 0, offset,
                                           8 * field.itemsize, 0, 0, 0, 0, 0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)))
            offset += field.itemsize
        for name, unit, _, _ in specs:
            self._text(name)
            if unit:
                self._text(unit)
        assert self._f.tell() == dt_at
        self._f.write(_COMMON.pack(b"##DT", _COMMON.size, 0))
        self._open, self._rows = (cg_at, dt_at, layout), 0

    def append(self, t: npt.ArrayLike, columns: Mapping[str, npt.ArrayLike]) -> None:
        """Rows of the open group: the master times and each channel's values (equal lengths)."""
        assert self._open is not None, "group() first"
        layout = self._open[2]
        tt = np.asarray(t, dtype=float)
        records = np.empty(tt.size, dtype=layout)
        records["time"] = tt
        for name in layout.names[1:]:
            records[name] = columns[name]
        self._f.write(records.data)
        self._rows += tt.size

    def _end_group(self) -> None:
        if self._open is None:
            return
        cg_at, dt_at, layout = self._open
        size = self._rows * layout.itemsize
        self._patch(dt_at + 8, _COMMON.size + size)          # the data block's length
        self._patch(cg_at + _COMMON.size + 6 * 8 + 8, self._rows)   # the group's cycle count
        self._f.write(b"\0" * (-size % 8))
        self._open = None

    def close(self) -> None:
        """End the last group (the file stays open: its owner closes it)."""
        self._end_group()
