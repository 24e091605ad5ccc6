"""The linked lists of an ASAM MDF 4 file, walked before asammdf reads it: data groups,
their channel groups and channels, their data blocks, each a chain of links to the next.
asammdf follows these chains as they are, so a link that points back into its own chain
(one corrupted address) sends it round forever, and it believes a channel group's count
of records (a corrupted count has it read empty records for minutes). :func:`check`
refuses a link that points outside the file, at a block of another kind or back into
its chain, a block that runs past the end of the file (the file is truncated), and a
data group whose channel groups count more records than its data hold."""

from __future__ import annotations

import struct
from pathlib import Path
from typing import BinaryIO

from ..container import TraceError

__all__ = ["check"]

#: Data blocks a data group's data link may point at, and those whose bytes are counted.
_DATA = ("DT", "DV", "DZ", "DL", "HL", "LD", "SD", "RD", "RV", "DI", "RI")
#: The most blocks a walk visits (a bound on the work, whatever the links say).
_MAX_BLOCKS = 1_000_000


class _Bad(Exception):
    pass


class _Truncated(_Bad):
    pass


class _Walk:
    """A walk of one file: every block read once, counted."""

    def __init__(self, fh: BinaryIO, size: int) -> None:
        self.fh, self.size, self.visited = fh, size, 0

    def block(self, addr: int, kinds: tuple[str, ...], what: str) -> tuple[str, list[int], bytes]:
        """The kind, the links and the first bytes of the data of the block at ``addr``
        (one of ``kinds``)."""
        self.visited += 1
        if self.visited > _MAX_BLOCKS:
            raise _Bad(f"it has more than {_MAX_BLOCKS:,} blocks")
        if addr < 64:
            raise _Bad(f"the link to its {what} points at byte {addr:,}, inside the file's "
                       "identification block")
        if addr + 24 > self.size:
            raise _Truncated(f"the link to its {what} points at byte {addr:,}, past the end of "
                             f"the file ({self.size:,} bytes)")
        self.fh.seek(addr)
        head = self.fh.read(24)
        kind = head[2:4].decode("latin-1")
        length, count = struct.unpack("<QQ", head[8:24])
        if head[:2] != b"##" or kind not in kinds:
            raise _Bad(f"its {what} at byte {addr:,} is a {head[:4]!r} block, not "
                       f"{' or '.join('##' + k for k in kinds)}")
        if length < 24 + 8 * count:
            raise _Bad(f"its {what} at byte {addr:,} says {length:,} bytes for {count:,} links")
        if addr + length > self.size:
            raise _Truncated(f"its {what} at byte {addr:,} needs {length:,} bytes, and the file "
                             f"ends {self.size - addr:,} bytes in")
        links = list(struct.unpack(f"<{count}Q", self.fh.read(8 * count))) if count else []
        data = self.fh.read(min(length - 24 - 8 * count, 64))
        return kind, links, data

    def chain(self, first: int, kinds: tuple[str, ...], what: str):
        """``(kind, links, data)`` of every block of the chain from ``first`` (the next is
        each block's first link)."""
        seen: set[int] = set()
        addr = first
        while addr:
            if addr in seen:
                raise _Bad(f"the chain of its {what}s links back to the one at byte {addr:,}")
            seen.add(addr)
            kind, links, data = self.block(addr, kinds, what)
            yield kind, links, data
            addr = links[0] if links else 0

    def data_bytes(self, addr: int) -> int | None:
        """The bytes of records a data group's data link holds (None: a kind not counted)."""
        if not addr:
            return 0
        kind, links, data = self.block(addr, _DATA, "data block")
        if kind == "DT":
            return self._length(addr) - 24 - 8 * len(links)
        if kind == "DZ" and len(data) >= 16:
            return struct.unpack_from("<Q", data, 8)[0]
        if kind == "HL":
            return self.data_bytes(links[0]) if links else 0
        if kind == "DL":
            total = 0
            for _, dl_links, _ in self.chain(addr, ("DL",), "data list"):
                for link in dl_links[1:]:
                    part = self.data_bytes(link) if link else 0
                    if part is None:
                        return None
                    total += part
            return total
        return None

    def _length(self, addr: int) -> int:
        self.fh.seek(addr + 8)
        return struct.unpack("<Q", self.fh.read(8))[0]


def _group(walk: _Walk, k: int, links: list[int], data: bytes) -> None:
    """Data group ``k``: its channel groups' channels, and their records against its data."""
    if len(links) < 3 or not data:
        raise _Bad(f"its data group {k} has {len(links)} links and {len(data)} bytes of data, "
                   "fewer than a data group has")
    rec_id = data[0]
    need = 0
    for j, (_, cg_links, cg) in enumerate(walk.chain(links[1], ("CG",), "channel group"), 1):
        if len(cg_links) < 2 or len(cg) < 32:
            raise _Bad(f"channel group {j} of data group {k} is shorter than a channel group")
        for _ in walk.chain(cg_links[1], ("CN",), "channel"):
            pass
        cycles, flags = struct.unpack_from("<QH", cg, 8)
        data_bytes, inval = struct.unpack_from("<II", cg, 24)
        if not flags & 1:                               # not a variable-length group
            need += cycles * (rec_id + data_bytes + inval)
    held = walk.data_bytes(links[2])
    if held is not None and need > held:
        raise _Bad(f"the channel groups of data group {k} count {need:,} bytes of records, and "
                   f"its data hold {held:,}")


def check(path: str | Path) -> None:
    """Walk the MDF 4 file ``path`` (an MDF 3 file, or what is no MDF file, is left to
    asammdf); a TraceError naming what does not add up, or where a truncated file is
    cut."""
    path = Path(path)
    with open(path, "rb") as fh:
        size = fh.seek(0, 2)
        fh.seek(0)
        ident = fh.read(64)
        if len(ident) < 64 or not ident.startswith(b"MDF") or ident[8:9] != b"4":
            return
        walk = _Walk(fh, size)
        try:
            _, links, _ = walk.block(64, ("HD",), "header block")
            for k, (_, dg_links, dg) in enumerate(walk.chain(links[0] if links else 0, ("DG",),
                                                             "data group"), 1):
                _group(walk, k, dg_links, dg)
        except _Truncated as exc:
            raise TraceError(f"{path}: the file is truncated (or a length in it is damaged): "
                             f"{exc} (a copy cut short, or a logger stopped mid-write?); copy or "
                             "export it again") from None
        except _Bad as exc:
            raise TraceError(f"{path}: not a readable MDF file: {exc}; the file is damaged: "
                             "export it again") from None
