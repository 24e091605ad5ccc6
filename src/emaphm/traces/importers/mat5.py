"""The layout of a MATLAB version 5 file, checked before scipy reads it: a 128-byte header,
then one element per variable (``miMATRIX``, or ``miCOMPRESSED``: a zlib stream holding
one), each made of tagged sub-elements (array flags, dimensions, name, data) whose
lengths must add up: numeric data of as many values as the dimensions say, a struct's
fields, a cell's cells, every one inside its variable. scipy trusts those lengths (a
flipped type or length byte can crash it); this walk refuses what does not add up, with
where, and finds where a truncated file stops being whole (:func:`check`).

Data are skipped, never held: a compressed variable is inflated in pieces and thrown
away, so the check holds a few kilobytes whatever the file's size.
"""

from __future__ import annotations

import math
import struct
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO

from ..container import TraceError

__all__ = ["Layout", "check"]

_HEADER = 128
_MATRIX, _COMPRESSED = 14, 15
#: bytes per value of each data type (miINT8 ... miUTF32)
_ITEM = {1: 1, 2: 1, 3: 2, 4: 2, 5: 4, 6: 4, 7: 4, 9: 8, 12: 8, 13: 8, 16: 1, 17: 2, 18: 4}
_NUMBER_TYPES = frozenset({1, 2, 3, 4, 5, 6, 7, 9, 12, 13})
_TEXT_TYPES = frozenset({1, 2, 3, 4, 16, 17, 18})
_CELL, _STRUCT, _OBJECT, _CHAR, _SPARSE = 1, 2, 3, 4, 5
_NUMERIC_CLASSES = frozenset(range(6, 16))
_DEPTH = 64
_CHUNK = 1 << 16


class _Bad(Exception):
    """A length, type or tag that does not add up (the message says which)."""


class _Short(Exception):
    """The bytes end before an element does."""


@dataclass(frozen=True)
class Layout:
    """What :func:`check` found: ``whole``, the bytes up to the end of the last whole
    variable (the file's size where none is cut), and ``damage``, a sentence on where
    a truncated file stops (empty when it is whole)."""

    whole: int
    variables: int
    damage: str = ""


class _Plain:
    """Bytes ``start`` to ``end`` of the file."""

    def __init__(self, fh: BinaryIO, start: int, end: int) -> None:
        self.fh, self.pos, self.end = fh, start, end
        fh.seek(start)

    def read(self, n: int) -> bytes:
        if self.pos + n > self.end:
            raise _Short
        data = self.fh.read(n)
        if len(data) < n:
            raise _Short
        self.pos += n
        return data

    def skip(self, n: int) -> None:
        if self.pos + n > self.end:
            raise _Short
        self.pos += n
        self.fh.seek(self.pos)


class _Inflated:
    """The inflated bytes of the zlib stream in bytes ``start`` to ``end`` of the file,
    read and skipped in pieces."""

    def __init__(self, fh: BinaryIO, start: int, end: int) -> None:
        self.fh, self.left = fh, end - start
        fh.seek(start)
        self.z = zlib.decompressobj()
        self.buf = b""
        self.pos = 0
        self.pending = b""

    def _more(self) -> bytes:
        try:
            if self.z.unconsumed_tail:
                return self.z.decompress(self.z.unconsumed_tail, _CHUNK)
            if self.left <= 0 or self.z.eof:
                return b""
            data = self.fh.read(min(self.left, _CHUNK))
            self.left -= len(data)
            if not data:
                self.left = 0
                return b""
            return self.z.decompress(data, _CHUNK)
        except zlib.error as exc:
            raise _Bad(f"its compressed data are damaged (zlib: {exc})") from None

    def _fill(self) -> bool:
        while True:
            out = self._more()
            if out:
                self.buf += out
                return True
            if self.left <= 0 or self.z.eof:
                return False

    def read(self, n: int) -> bytes:
        while len(self.buf) < n:
            if not self._fill():
                raise _Short
        data, self.buf = self.buf[:n], self.buf[n:]
        self.pos += n
        return data

    def skip(self, n: int) -> None:
        while n:
            if not self.buf and not self._fill():
                raise _Short
            k = min(n, len(self.buf))
            self.buf = self.buf[k:]
            self.pos += k
            n -= k

    def rest(self) -> int:
        """Bytes left after the element (to be none)."""
        total = len(self.buf)
        self.buf = b""
        while self._fill():
            total += len(self.buf)
            self.buf = b""
            if total > _CHUNK:
                break
        return total


def _tag(s, order: str, end: int) -> tuple[int, int, bytes | None]:
    """A sub-element's ``(type, length, small data)`` (small data: the data of a small
    element, packed in its tag); the element must end by ``end``."""
    a, b = struct.unpack(order + "II", s.read(8))
    if a >> 16:
        n = a >> 16
        if n > 4:
            raise _Bad(f"a small element of {n} bytes (at most 4)")
        return a & 0xFFFF, n, struct.pack(order + "I", b)[:n]
    if s.pos + b > end:
        raise _Bad(f"an element of {b:,} bytes runs past the end of its variable")
    return a, b, None


def _data(s, order: str, end: int, types: frozenset[int], what: str) -> tuple[int, int, bytes | None]:
    kind, n, small = _tag(s, order, end)
    if kind not in types:
        raise _Bad(f"its {what} is of data type {kind}, which MATLAB does not write there")
    return kind, n, small


def _skip_data(s, n: int, small: bytes | None) -> None:
    if small is None:
        s.skip(n + (-n % 8))


def _count(dims: tuple[int, ...]) -> int:
    return math.prod(dims)


def _values(s, order: str, end: int, count: int, what: str) -> None:
    kind, n, small = _data(s, order, end, _NUMBER_TYPES, what)
    if n != count * _ITEM[kind]:
        raise _Bad(f"its {what} holds {n:,} bytes, not the {count:,} values x {_ITEM[kind]} "
                   "bytes its dimensions say")
    _skip_data(s, n, small)


def _matrix(s, order: str, end: int, depth: int) -> str:
    """Walk one miMATRIX's sub-elements (the stream just past its tag, ``end`` its end);
    its name."""
    if depth > _DEPTH:
        raise _Bad(f"it is nested more than {_DEPTH} deep")
    if s.pos == end:
        return ""                                   # an empty matrix
    kind, n, small = _tag(s, order, end)
    if kind != 6 or n != 8:
        raise _Bad("its array flags are not where they belong")
    flags = struct.unpack(order + "II", s.read(8))[0]
    cls, is_complex = flags & 0xFF, bool(flags & 0x800)
    if not 1 <= cls <= 17:
        raise _Bad(f"its class is {cls}, not one of MATLAB's (1 to 17)")
    kind, n, small = _tag(s, order, end)
    if kind != 5 or n < 8 or n % 4:
        raise _Bad("its dimensions are not where they belong")
    dims = struct.unpack(f"{order}{n // 4}i", small if small is not None else s.read(n))
    if min(dims) < 0:
        raise _Bad(f"its dimensions {dims} are negative")
    if small is None:
        s.skip(-n % 8)
    kind, n, small = _data(s, order, end, frozenset({1}), "name")
    name = small if small is not None else s.read(n)
    if small is None:
        s.skip(-n % 8)
    label = name.decode("latin-1")
    count = _count(dims)
    if cls in _NUMERIC_CLASSES:
        _values(s, order, end, count, "data")
        if is_complex:
            _values(s, order, end, count, "imaginary part")
    elif cls == _CHAR:
        kind, n, small = _data(s, order, end, _TEXT_TYPES, "text")
        if kind != 16 and n != count * _ITEM[kind]:
            raise _Bad(f"its text holds {n:,} bytes, not the {count:,} characters its "
                       "dimensions say")
        _skip_data(s, n, small)
    elif cls in (_CELL, _STRUCT, _OBJECT):
        _children(s, order, end, depth, cls, count)
    elif cls == _SPARSE:
        for what, types in (("row indices", frozenset({5})), ("column indices", frozenset({5})),
                            ("values", _NUMBER_TYPES)):
            _skip_data(s, *_data(s, order, end, types, what)[1:])
    if s.pos > end:
        raise _Bad("its parts run past its end")
    s.skip(end - s.pos)                             # padding, or what is not checked
    return label


def _children(s, order: str, end: int, depth: int, cls: int, count: int) -> None:
    """A cell's cells, a struct's (or an object's) fields, each an miMATRIX."""
    fields = 1
    if cls == _OBJECT:
        _skip_data(s, *_data(s, order, end, frozenset({1}), "class name")[1:])
    if cls in (_STRUCT, _OBJECT):
        kind, n, small = _tag(s, order, end)
        if kind != 5 or n != 4:
            raise _Bad("its field name length is not where it belongs")
        width = struct.unpack(order + "i", small if small is not None else s.read(4))[0]
        if small is None:
            s.skip(4)
        kind, n, small = _data(s, order, end, frozenset({1}), "field names")
        if width <= 0 or n % width:
            raise _Bad(f"its field names ({n:,} bytes) are not in lengths of {width}")
        fields = n // width
        _skip_data(s, n, small)
    total = count * fields
    if total * 8 > end - s.pos:
        raise _Bad(f"it says it holds {total:,} elements, more than fit in it")
    for _ in range(total):
        kind, n, _small = _tag(s, order, end)
        if kind != _MATRIX:
            raise _Bad(f"a part of it has data type {kind}, not a matrix")
        _matrix(s, order, s.pos + n, depth + 1)


def _header(fh: BinaryIO, path: Path, size: int) -> str | None:
    """The byte order of a version 5 file ('<' or '>'), or None for another version."""
    head = fh.read(_HEADER)
    if len(head) < _HEADER:
        raise TraceError(f"{path}: the file is {size:,} bytes, shorter than the 128-byte header "
                         "of a MATLAB file: it is truncated or not a MATLAB file; export it again")
    if 0 in head[:4]:
        return None                                 # version 4: scipy's own check
    mark = head[126:128]
    if mark not in (b"IM", b"MI"):
        raise TraceError(f"{path}: not a readable MATLAB file: its header's byte order mark is "
                         f"{mark!r}, not 'IM' or 'MI'; the file is damaged: export it again")
    order = "<" if mark == b"IM" else ">"
    major = head[125] if order == "<" else head[124]
    if major != 1:
        what = ("7.3, but no HDF5 data follow its header" if major == 2
                else f"{major}, which MATLAB never wrote")
        raise TraceError(f"{path}: not a readable MATLAB file: its header says version {what}; "
                         "the file is damaged: export it again")
    return order


def check(path: str | Path) -> Layout:
    """Walk the MATLAB 5 file ``path``; a :class:`~emaphm.traces.TraceError` for a
    structure that does not add up, its :class:`Layout` otherwise (a truncated file's
    damage said there, with the part before it)."""
    path = Path(path)
    with open(path, "rb") as fh:
        size = fh.seek(0, 2)
        fh.seek(0)
        order = _header(fh, path, size)
        if order is None:
            return Layout(whole=size, variables=0)
        pos, k = _HEADER, 0
        while pos < size:
            k += 1
            n, cut = _variable(fh, path, order, pos, size, k)
            if cut:
                return Layout(whole=pos, variables=k - 1, damage=cut)
            pos += 8 + n
        return Layout(whole=size, variables=k)


def _variable(fh: BinaryIO, path: Path, order: str, pos: int, size: int,
              k: int) -> tuple[int, str]:
    """Check the variable ``k`` at ``pos``: its length and "" when whole, a sentence when
    cut by the end of the file, a TraceError when it does not add up."""
    whole = f"; the {k - 1} variable(s) before it are whole" if k > 1 else ""
    fh.seek(pos)
    tag = fh.read(8)
    if len(tag) < 8:
        return 0, (f"the file is truncated: it ends at byte {size:,}, inside the header of "
                   f"variable {k}{whole} (a copy cut short, or a logger stopped mid-write); copy "
                   "or export it again")
    kind, n = struct.unpack(order + "II", tag)
    where = f"{path}: not a readable MATLAB file: variable {k} (at byte {pos:,})"
    if kind not in (_MATRIX, _COMPRESSED):
        raise TraceError(f"{where} has data type {kind}, not a matrix; the file is damaged: "
                         "export it again")
    if pos + 8 + n > size:
        return n, (f"the file is truncated (or a length in it is damaged): variable {k} (at byte "
                   f"{pos:,}) needs {n:,} bytes, and the file ends {size - pos - 8:,} bytes "
                   f"in{whole} (a copy cut short, or a logger stopped mid-write?); copy or "
                   "export it again")
    try:
        if kind == _MATRIX:
            _matrix(_Plain(fh, pos + 8, pos + 8 + n), order, pos + 8 + n, 0)
        else:
            _compressed(fh, order, pos + 8, pos + 8 + n)
    except _Bad as exc:
        raise TraceError(f"{where}: {exc}; the file is damaged: export it again") from None
    except _Short:
        raise TraceError(f"{where}: its parts need more bytes than it holds; the file is "
                         "damaged: export it again") from None
    return n, ""


def _compressed(fh: BinaryIO, order: str, start: int, end: int) -> None:
    s = _Inflated(fh, start, end)
    kind, n = struct.unpack(order + "II", s.read(8))
    if kind != _MATRIX:
        raise _Bad(f"its compressed data hold data type {kind}, not a matrix")
    _matrix(s, order, 8 + n, 0)
    if s.rest():
        raise _Bad("its compressed data hold more than its matrix")
