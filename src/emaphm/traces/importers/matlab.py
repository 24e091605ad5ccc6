"""MATLAB ``.mat`` exports: version 5 (read by ``scipy.io``) and version 7.3 (HDF5, read by
``h5py``, from the ``bench`` extra). A channel is a numeric vector at the top level, or a
field of a struct (its ``group``; a struct in a struct is the group ``Run.Messung``, as
MATLAB writes the path); scalars (a sample rate such as ``fs``) are listed by
``--inspect``, and so is what is not read (a struct array, a 2-D matrix), with the reason.
A version 7.3 file is read in slices; a version 5 file is read whole, one variable at a
time."""

from __future__ import annotations

import io
from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np

from ..container import TraceError
from .base import BLOCK_ROWS, Block, ChannelInfo, SourceInfo, as_float, cause, need, read_path
from .channel_map import SourceOptions
from .mat5 import check as check_v5

__all__ = ["MatSource"]


_HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


def _is_hdf5(path: Path) -> bool:
    """MATLAB 7.3 writes an HDF5 file behind a 512-byte header (or at offset 0)."""
    with open(path, "rb") as fh:
        head = fh.read(2048)
    return any(head[k:k + 8] == _HDF5_SIGNATURE for k in (0, 512, 1024))


def _hdf5_cut(path: Path) -> str:
    """Where an HDF5 file ends short of the end its superblock declares ("" when it does
    not, or where the superblock cannot tell)."""
    with open(path, "rb") as fh:
        head = fh.read(2048)
        size = fh.seek(0, 2)
    at = next(k for k in (0, 512, 1024) if head[k:k + 8] == _HDF5_SIGNATURE)
    version = head[at + 8] if len(head) > at + 8 else None
    if version in (0, 1):
        width, fields = head[at + 13:at + 14], at + (24 if version == 0 else 28)
    elif version in (2, 3):
        width, fields = head[at + 9:at + 10], at + 12
    else:
        return ""
    if width not in (b"\x04", b"\x08") or len(head) < fields + 4 * width[0]:
        return ""
    step = width[0]                 # the end of file is counted from the file's start,
    end = int.from_bytes(head[fields + 2 * step:fields + 3 * step], "little")  # header in
    if end <= size:
        return ""
    return (f"the file is truncated (or a length in it is damaged): its HDF5 header says it "
            f"ends at byte {end:,}, and it ends at byte {size:,} (a copy cut short, or a "
            "MATLAB session stopped mid-save?); copy or save it again")


#: How to save channels emaphm reads, said where a variable is not read.
_SAVE_AS = "save each channel as a vector, at the top level or in a struct"


def _matrix(label: str, shape: tuple[int, ...]) -> str:
    return (f"variable {label!r} is a {len(shape)}-D matrix of {' x '.join(map(str, shape))}, not "
            f"read; {_SAVE_AS}")


def _is_struct(value) -> bool:
    return hasattr(value, "_fieldnames")


def _vector_length(shape: tuple[int, ...]) -> int | None:
    if len(shape) == 1:
        return shape[0]
    if len(shape) == 2 and 1 in shape:
        return max(shape)
    return None


class _Upto(io.RawIOBase):
    """The first ``limit`` bytes of a file (the whole variables of a truncated one), as
    scipy reads a file object."""

    def __init__(self, path: Path, limit: int) -> None:
        self.fh = open(path, "rb")
        self.limit = limit

    def readable(self) -> bool:
        return True

    def seekable(self) -> bool:
        return True

    def readinto(self, b) -> int:
        left = max(0, self.limit - self.fh.tell())
        view = memoryview(b)[:left]
        return self.fh.readinto(view) if left else 0

    def seek(self, offset: int, whence: int = 0) -> int:
        if whence == 2:
            return self.fh.seek(self.limit + offset)
        return self.fh.seek(offset, whence)

    def tell(self) -> int:
        return self.fh.tell()

    def close(self) -> None:
        self.fh.close()
        super().close()


class MatSource:
    """A ``.mat`` file of either version. A version 5 file's layout is checked first
    (:mod:`.mat5`): scipy reads only one that adds up, and only the whole variables of a
    truncated one (whose damage ``info`` says)."""

    def __init__(self, path: str | Path, options: SourceOptions = SourceOptions()) -> None:
        self.path = read_path(path)
        self.v73 = _is_hdf5(self.path)
        self.scalars: dict[str, float] = {}
        self.skipped: list[str] = []
        self.whole: int | None = None
        self.info = self._inspect_v73() if self.v73 else self._inspect_v5()

    # ------------------------------------------------------------------ version 5
    def _scipy(self, read, **kwargs):
        """``read`` (scipy's whosmat or loadmat) of the file, or of the whole part of a
        truncated one."""
        if self.whole is None:
            return read(self.path, **kwargs)
        with _Upto(self.path, self.whole) as fh:
            return read(fh, **kwargs)

    def _inspect_v5(self) -> SourceInfo:
        from scipy import io as sio

        layout = check_v5(self.path)
        if layout.damage:
            self.whole = layout.whole
        try:
            listing = self._scipy(sio.whosmat)
            data = self._scipy(sio.loadmat, squeeze_me=True, struct_as_record=False,
                               variable_names=[n for n, shape, cls in listing
                                               if cls == "struct" or np.prod(shape) == 1])
        except (ValueError, TypeError, OSError, NotImplementedError) as exc:
            raise TraceError(f"{self.path}: not a readable MATLAB file ({cause(exc)})") from None
        chans = []
        for name, shape, cls in listing:
            n = _vector_length(tuple(shape))
            if cls == "struct":
                chans += self._struct_fields(name, data.get(name))
            elif n is not None and n > 1 and cls not in ("char", "cell", "sparse"):
                chans.append(ChannelInfo(name=name, samples=n))
            elif int(np.prod(shape)) == 1 and np.ndim(data.get(name)) == 0:
                try:
                    self.scalars[name] = float(data[name])
                except (TypeError, ValueError):
                    pass
            elif len(shape) >= 2 and cls not in ("char", "cell", "sparse", "object"):
                self.skipped.append(_matrix(name, tuple(shape)))
        return SourceInfo(path=self.path, format="mat", channels=tuple(chans),
                          notes=("MATLAB version 5",) + self._scalar_note(),
                          skipped=tuple(self.skipped), damage=layout.damage)

    def _struct_fields(self, name: str, value) -> list[ChannelInfo]:
        """The vectors of the struct ``value`` (the group ``name``) and of the structs in
        it (the group ``name.field``)."""
        if isinstance(value, np.ndarray) and value.size > 1 and all(map(_is_struct, value.flat)):
            self.skipped.append(f"variable {name!r} is a struct array of {value.size}, not read; "
                                f"{_SAVE_AS} (one struct per run, or one file per run)")
            return []
        out = []
        for field in getattr(value, "_fieldnames", None) or []:
            x = getattr(value, field)
            if _is_struct(x) or (isinstance(x, np.ndarray) and x.dtype == object):
                out += self._struct_fields(f"{name}.{field}", x)
                continue
            x = np.asarray(x)
            n = _vector_length(x.shape)
            if x.dtype.kind not in "biuf":
                continue
            if n and n > 1:
                out.append(ChannelInfo(name=field, group=name, samples=n))
            elif x.size == 1:
                self.scalars[f"{name}.{field}"] = float(x.reshape(()))
            elif x.ndim >= 2:
                self.skipped.append(_matrix(f"{name}.{field}", x.shape))
        return out

    def _scalar_note(self) -> tuple[str, ...]:
        if not self.scalars:
            return ()
        shown = ", ".join(f"{k} = {v:g}" for k, v in list(self.scalars.items())[:10])
        return (f"scalars: {shown}",)

    # ------------------------------------------------------------------ version 7.3
    def _inspect_v73(self) -> SourceInfo:
        h5py = need("h5py", "MATLAB 7.3 files")
        cut = _hdf5_cut(self.path)
        if cut:
            raise TraceError(f"{self.path}: {cut}")
        try:
            self.h5 = h5py.File(self.path, "r")
        except OSError as exc:
            raise TraceError(f"{self.path}: not a readable MATLAB 7.3 (HDF5) file "
                             f"({cause(exc)})") from None
        chans = []

        def visit(name: str, obj) -> None:
            if not isinstance(obj, h5py.Dataset) or name.startswith("#"):
                return
            if obj.dtype.kind not in "biuf":
                return
            group, _, leaf = name.rpartition("/")
            n = _vector_length(obj.shape)
            if n is not None and n > 1:
                # a struct in a struct is written as MATLAB writes its path: Run.Messung
                chans.append(ChannelInfo(name=leaf, group=group.replace("/", ".") or None,
                                         samples=n))
            elif obj.size == 1:
                self.scalars[name.replace("/", ".")] = float(np.asarray(obj[()]).reshape(()))
            elif len(obj.shape) >= 2:
                self.skipped.append(_matrix(name.replace("/", "."), obj.shape))

        self.h5.visititems(visit)
        return SourceInfo(path=self.path, format="mat", channels=tuple(chans),
                          notes=("MATLAB version 7.3 (HDF5)",) + self._scalar_note(),
                          skipped=tuple(self.skipped))

    # ------------------------------------------------------------------ reading
    def blocks(self, channels: Sequence[ChannelInfo], first: int = 0,
               stop: int | None = None) -> Iterator[Block]:
        n = min(c.samples or 0 for c in channels)
        stop = n if stop is None else min(stop, n)
        if self.v73:
            sets = [self.h5[f"{c.group.replace('.', '/')}/{c.name}" if c.group else c.name]
                    for c in channels]
            for a in range(first, stop, BLOCK_ROWS):
                b = min(a + BLOCK_ROWS, stop)
                yield Block(start=a, columns=tuple(_slice(ds, a, b) for ds in sets))
            return
        from scipy import io as sio

        cols = []
        for c in channels:
            path = c.group.split(".") + [c.name] if c.group else [c.name]
            value = self._scipy(sio.loadmat, squeeze_me=True, struct_as_record=False,
                                variable_names=[path[0]])[path[0]]
            for field in path[1:]:
                value = getattr(value, field)
            cols.append(as_float(value, f"{self.path}: {c.label}")[first:stop])
        yield Block(start=first, columns=tuple(cols))

    def close(self) -> None:
        if self.v73:
            self.h5.close()


def _slice(ds, a: int, b: int) -> np.ndarray:
    """Samples ``a:b`` of a vector dataset stored as (n,), (1, n) or (n, 1)."""
    shape = ds.shape
    if len(shape) == 1:
        x = ds[a:b]
    elif shape[0] == 1:
        x = ds[0, a:b]
    else:
        x = ds[a:b, 0]
    return np.asarray(x, dtype=np.float64)
