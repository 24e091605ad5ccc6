"""Files named on the command line: the one way emaphm reads them and the one way it writes them.

* :func:`regular_file`: every file argument (a trace, ``--params``, ``--map``, a bench
  export, ``--tolerances``, ``--spec``, a nameplate, an existing store) is checked to be a
  regular file, after following its links, before it is opened: a FIFO would block the
  command forever, a link to ``/dev/zero`` would be read without end, and a link loop is
  not a missing file;
* :func:`folder_problem`: whether a file can be created in a folder (tried, as the
  operating system decides, root included);
* :func:`atomic_write`: an output file is written atomically, through an unpredictable
  temporary sibling opened with ``O_EXCL`` (a planted file or symlink of a predictable
  name cannot be followed), then :func:`os.replace`;
* :class:`StagedWrites`: many files written as one (each so staged, all renamed into
  place together once every one is on disk).
"""

from __future__ import annotations

import errno
import os
import secrets
import stat
import tempfile
from pathlib import Path
from typing import IO, Callable, Sequence

__all__ = ["atomic_write", "atomic_write_text", "StagedWrites", "regular_file", "file_kind",
           "folder_problem"]

_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
          (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
          (stat.S_ISSOCK, "a socket"))


def file_kind(mode: int) -> str:
    """What an ``st_mode`` is, in words: ``"a regular file"``, ``"a folder"``, ``"a FIFO
    (named pipe)"``, ``"a character device"``..."""
    for test, kind in _KINDS:
        if test(mode):
            return kind
    return "a regular file" if stat.S_ISREG(mode) else "not a regular file"


def regular_file(path: str | os.PathLike[str], what: str, *, give: str = "a file",
                 error: type[Exception] = ValueError,
                 missing: type[Exception] = FileNotFoundError) -> Path:
    """``path`` as a :class:`~pathlib.Path` if it is, after following its links, a regular
    file; else ``error`` (``missing`` when nothing is there) with one sentence that names
    ``what`` (e.g. ``"trace file"``), the path, what it is instead and the fix (``give``,
    e.g. ``"a TOML file"``).

    Checked before the file is opened: a FIFO blocks the reader until a writer comes, a
    device such as ``/dev/zero`` never ends, a folder is not a file, and a link loop or a
    link to nothing is not "missing" to the user who sees the link.
    """
    p = Path(path)
    label = f"{what} {p}" if what else str(p)
    try:
        st = os.stat(p)
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise error(f"{label} is a symbolic link loop (following its links leads back to "
                        f"it); point the link at a file or give {give}") from None
        if exc.errno in (errno.ENOENT, errno.ENOTDIR):
            if os.path.islink(p):
                raise missing(f"{label} is a link to {os.readlink(p)}, which does not exist; "
                              f"give {give}") from None
            raise missing(f"{label} does not exist") from None
        if exc.errno == errno.EACCES:
            raise error(f"{label} cannot be read (permission denied); give {give} you can "
                        "read") from None
        if exc.errno == errno.ENAMETOOLONG:
            raise error(f"{what + ' ' if what else ''}path is too long for this system "
                        f"({len(str(p))} characters); give {give}") from None
        raise error(f"{label} cannot be read ({exc.strerror or exc}); give {give}") from None
    if stat.S_ISREG(st.st_mode):
        return p
    kind = file_kind(st.st_mode)
    if os.path.islink(p):
        target = os.path.realpath(p)
        if stat.S_ISDIR(st.st_mode):
            raise error(f"{label} is a link to {target}, a folder; give {give}")
        raise error(f"{label} is a link to {target}, {kind}, not a regular file; give {give}")
    if stat.S_ISDIR(st.st_mode):
        raise error(f"{label} is a folder; give {give}")
    raise error(f"{label} is {kind}, not a regular file; give {give}")


def folder_problem(folder: str | os.PathLike[str]) -> str | None:
    """Why no file can be created in ``folder`` (``"it does not exist"``, ``"it is a
    file"``, ``"Permission denied"``, ``"Read-only file system"``...), or None when one can.
    Tried with an anonymous temporary file, which leaves nothing behind: the operating
    system decides, for root as for anyone."""
    f = Path(folder)
    if not f.exists():
        return "it does not exist"
    if not f.is_dir():
        return "it is a file, not a folder"
    try:
        with tempfile.TemporaryFile(dir=f):
            pass
    except OSError as exc:
        return str(exc.strerror or exc)
    return None


def atomic_write(path: str | os.PathLike[str], write: Callable[[IO[bytes]], None]) -> Path:
    """Write ``path`` through ``write(binary file)`` on a temporary sibling and a rename.

    On any failure the temporary file is removed and an existing file at ``path`` is
    left untouched.
    """
    path = Path(path)
    directory = path.parent
    tmp = directory / f".{path.name}.{secrets.token_hex(6)}.tmp"
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0), 0o666)
    try:
        with os.fdopen(fd, "wb") as fh:
            write(fh)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
    try:  # make the rename itself durable where the platform allows it
        dir_fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return path
    try:
        os.fsync(dir_fd)
    except OSError:
        pass
    finally:
        os.close(dir_fd)
    return path


def atomic_write_text(path: str | os.PathLike[str], text: str) -> Path:
    """:func:`atomic_write` of a UTF-8 text."""
    data = text.encode("utf-8")
    return atomic_write(path, lambda fh: fh.write(data))


class StagedWrites:
    """Files written as one: each written whole beside its place under an unpredictable
    temporary name (``O_EXCL``, as :func:`atomic_write`), then renamed into place all
    together (:meth:`commit`) once every one is written and flushed; a writer that fails
    on the way (a full disk, a crash) removes them (:meth:`discard`) and leaves the
    files as they were, never half new and half old (the fleet site's build). A rename
    needs no room on the disk, and replaces a link in the file's place (never writing
    through it)."""

    def __init__(self) -> None:
        self.moves: list[tuple[Path, Path]] = []
        self.removals: list[Path] = []

    def write(self, path: Path, payload: bytes) -> None:
        tmp = Path(path).parent / f".{Path(path).name}.{secrets.token_hex(6)}.tmp"
        try:
            with open(tmp, "xb") as fh:
                fh.write(payload)
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise
        self.moves.append((tmp, Path(path)))

    def remove(self, path: Path) -> None:
        self.removals.append(path)

    def commit(self) -> None:
        if self.moves:
            _sync_all([tmp for tmp, _ in self.moves])
        for tmp, path in self.moves:
            os.replace(tmp, path)
        self.moves = []
        for path in self.removals:
            path.unlink(missing_ok=True)

    def discard(self) -> None:
        for tmp, _ in self.moves:
            tmp.unlink(missing_ok=True)
        self.moves = []


def _sync_all(paths: Sequence[Path]) -> None:
    """Flush ``paths`` to disk: the whole system's buffers at once where the platform can
    (``os.sync``), else each file."""
    if hasattr(os, "sync"):
        os.sync()
        return
    for path in paths:                          # pragma: no cover - Windows
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_BINARY", 0))
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
