"""Damaged bench exports (issue 37, items 1-4): every binary reader (MATLAB 5, compressed
MATLAB 5, MATLAB 7.3, TDMS, MDF 4, Parquet) is fed thousands of seeded corruptions of a
small valid file: cut short, a length or an offset set to a boundary value, a tag or a
header byte changed, a byte flipped in the data and in the compressed streams. Each must
read as numbers or be refused with a TraceError of one line that names the file: no
other exception, no crash of the command (a reader that crashes does so in the sandbox,
:mod:`emaphm.traces.importers.sandbox`), and a file cut short is never read as whole.

Budget: :data:`CASES` (4,000) cases per format through one sandbox child, at most a minute
per format: measured on the shared 2-core Xeon, 4-9 s per format and 32 s for MDF 4 (the
slowest: 11 s on an idle core) beside another test run; every 250th case also runs
``emaphm import --inspect`` in-process. The sandbox itself is tested with readers that
crash and hang.
"""

from __future__ import annotations

import random
import struct
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from benchfiles import WRITERS
from emaphm.cli import main
from emaphm.traces import Trace, TraceError
from emaphm.traces.importers import open_source
from emaphm.traces.importers.channel_map import SourceOptions

CASES = 4000
BENCH_LIBS = ("h5py", "nptdms", "asammdf")
missing = [m for m in BENCH_LIBS if not __import__("importlib.util").util.find_spec(m)]
needs_bench = pytest.mark.skipif(bool(missing), reason=f"the bench extra is not installed "
                                 f"({', '.join(missing)}): pip install -e '.[bench]'")


def _trace(n: int = 200) -> Trace:
    t = np.arange(n) / 8000.0
    x = np.sin(2 * np.pi * 50 * t)
    return Trace(t=t, theta_ref=x, theta_m=0.9 * x, omega_m=np.cos(t),
                 i_abc=np.column_stack([x, -x / 2, -x / 2]), meta={})


def _seed(fmt: str, folder: Path) -> Path:
    """A small valid file of ``fmt``."""
    trace = _trace()
    if fmt == "mat5z":
        from scipy.io import savemat

        path = folder / "z.mat"
        savemat(path, {"fs": 8000.0, "pos": trace.theta_m, "i_a": trace.i_a,
                       "run": {"ref": trace.theta_ref, "i_b": trace.i_b}}, do_compression=True)
        return path
    if fmt == "parquet":
        import pyarrow as pa
        import pyarrow.parquet as pq

        path = folder / "bench.parquet"
        pq.write_table(pa.table({"t": trace.t, "ref": trace.theta_ref, "pos": trace.theta_m,
                                 "a": trace.i_a}), path, row_group_size=64)
        return path
    write, name = WRITERS[fmt]
    return write(trace, folder / name)[0]


# ----------------------------------------------------------------------------- mutations
_MARKS = (b"##", b"TDSm", b"PAR1", b"\x89HDF", b"HEAP", b"TREE", b"SNOD", b"OHDR", b"IM")
_BOUNDARY = (0, 1, 2, 7, 8, 0x7F, 0xFF, 0x7FFF_FFFF, 0xFFFF_FFFF)


def _fields(data: bytes) -> list[tuple[int, int, str]]:
    """``(offset, width, byte order)`` of the aligned integers of ``data`` that could be a
    length or an offset in it (1 to its size): the structure's fields, and a few others."""
    size = len(data)
    found = []
    for width, code in ((4, "I"), (8, "Q")):
        for order in "<>":
            for k in range(0, size - width + 1, width):
                v = struct.unpack_from(order + code, data, k)[0]
                if 0 < v <= size:
                    found.append((k, width, order))
    return found


def _marks(data: bytes) -> list[int]:
    out = []
    for mark in _MARKS:
        k = data.find(mark)
        while k >= 0 and len(out) < 400:
            out.append(k)
            k = data.find(mark, k + 1)
    return out or [0]


def mutate(data: bytes, fields, marks, rng: random.Random) -> tuple[str, bytes]:
    """One seeded corruption of ``data``: ``(kind, bytes)``."""
    d = bytearray(data)
    kind = rng.choices(["truncate", "length", "tag", "header", "flip", "twice"],
                       weights=[20, 30, 15, 15, 15, 5])[0]
    if kind == "truncate":
        return kind, bytes(d[:rng.randrange(len(d))])
    if kind == "twice":
        _, once = mutate(data, fields, marks, rng)
        if len(once) < len(data):
            return "truncate", once
        return "twice", mutate(once, fields, marks, rng)[1]
    if kind == "length":
        k, width, order = rng.choice(fields)
        v = struct.unpack_from(order + "IQ"[width // 8], d, k)[0]
        new = rng.choice(_BOUNDARY + (v - 1, v + 1, v + 8, 2 * v, len(d), len(d) + 1,
                                      (1 << (8 * width)) - 1, rng.getrandbits(8 * width)))
        struct.pack_into(order + "IQ"[width // 8], d, k, new % (1 << (8 * width)))
    elif kind == "tag":
        k = min(len(d) - 1, rng.choice(marks) + rng.randrange(16))
        d[k] = rng.randrange(256)
    elif kind == "header":
        k = rng.randrange(min(len(d), 1024))
        d[k:k + 4] = rng.choice([b"\0" * 4, b"\xff" * 4, rng.randbytes(4)])
    else:
        k = rng.randrange(len(d))
        d[k] ^= 1 << rng.randrange(8)
    return kind, bytes(d[:len(data)])


def _read_all(path: Path, fmt: str) -> str:
    """Read every channel of ``path``: "ok", "damaged" (a truncated file listed) or the
    TraceError's message."""
    options = SourceOptions(format="mat") if path.suffix == ".mat" else SourceOptions()
    try:
        with open_source(path, options) as source:
            chans = [c for c in source.info.channels if c.samples]
            if chans:
                for block in source.blocks(chans):
                    assert all(c.dtype == np.float64 for c in block.columns)
            return "damaged" if source.info.damage else "ok"
    except TraceError as exc:
        return str(exc)


FORMATS = ["mat5", "mat5z", "mat73", "tdms", "mdf4", "parquet"]


@pytest.mark.parametrize("fmt", FORMATS)
def test_corrupt_files_are_read_or_refused_in_one_line(fmt, tmp_path, capsys, monkeypatch):
    from emaphm.traces.importers import sandbox

    if fmt in ("mat73", "tdms", "mdf4") and missing:
        pytest.skip(f"the bench extra is not installed ({', '.join(missing)})")
    monkeypatch.setattr(sandbox, "READ_TIMEOUT", 20.0)      # a reader sent round forever
    seed = _seed(fmt, tmp_path)
    data = seed.read_bytes()
    assert _read_all(seed, fmt) == "ok"
    fields, marks = _fields(data), _marks(data)
    rng = random.Random(f"issue 37 {fmt}")
    case = tmp_path / f"case{seed.suffix}"
    seen: dict[str, int] = {}
    for k in range(CASES):
        kind, bad = mutate(data, fields, marks, rng)
        case.write_bytes(bad)
        got = _read_all(case, fmt)
        outcome = got if got in ("ok", "damaged") else "refused"
        seen[outcome] = seen.get(outcome, 0) + 1
        where = f"case {k} ({kind}, {len(bad)} of {len(data)} bytes)"
        if outcome == "refused":
            assert "\n" not in got and str(case) in got, (where, got)
            assert "Traceback" not in got and len(got) < 1200, (where, got)
        if kind == "truncate":
            assert outcome != "ok", f"{where}: a file cut short was read as whole"
        if k % 250 == 0:
            rc = main(["import", str(case), "--inspect"])
            err = capsys.readouterr().err
            assert rc in (0, 2) and "Traceback" not in err, (where, err)
            assert rc == 0 or err.count("\n") == 1, (where, err)
    # the corruptions reach past the first checks: some read, some refused
    assert seen.get("refused", 0) > CASES // 10 and seen.get("ok", 0) > 0, seen


# ----------------------------------------------------------------------------- the sandbox
def _reader_module(folder: Path, body: str) -> None:
    (folder / "hostile_reader.py").write_text(textwrap.dedent(f"""
        import os, signal, time
        from emaphm.traces.importers.base import SourceInfo, Block

        class Reader:
            def __init__(self, path, options):
                self.path = path
                {body}
                self.info = SourceInfo(path=path, format="x", channels=())

            def blocks(self, channels, first=0, stop=None):
                return iter(())

            def close(self):
                pass
        """))


@pytest.mark.parametrize("body, words", [
    ("os.kill(os.getpid(), signal.SIGSEGV)", "crashed the reader (SIGSEGV)"),
    ("os.abort()", "crashed the reader (SIGABRT)"),
    ("os._exit(3)", "crashed the reader (it stopped)"),
    ("time.sleep(60)", "took more than 1 s and was stopped"),
    ("raise RuntimeError('Object visitation failed')",
     "it is damaged or is not one (RuntimeError: Object visitation failed)"),
])
def test_a_reader_that_crashes_or_hangs_is_a_refusal_and_the_next_file_reads(
        body, words, tmp_path, monkeypatch):
    from emaphm.traces.importers.sandbox import ReaderProcess, SandboxedSource

    _reader_module(tmp_path, body)
    monkeypatch.setenv("PYTHONPATH", str(tmp_path))
    (tmp_path / "x.bin").write_bytes(b"\0" * 64)
    process = ReaderProcess(timeout=1.0)
    try:
        with pytest.raises(TraceError) as err:
            SandboxedSource(tmp_path / "x.bin", "hostile_reader", "Reader", "an X file",
                            process=process)
        assert str(err.value).startswith(f"{tmp_path / 'x.bin'}: ") and words in str(err.value)
        assert "\n" not in str(err.value)
        # the same process reads the next file: a fresh child where the last one died
        seed = _seed("mat5z", tmp_path)
        source = SandboxedSource(seed, "emaphm.traces.importers.matlab", "MatSource", "a MATLAB file", process=process)
        assert [c.name for c in source.info.channels] == ["pos", "i_a", "ref", "i_b"]
        blocks = list(source.blocks(source.info.channels[:1]))
        source.close()
        assert blocks[0].n == 200
    finally:
        process.stop()


def test_the_sandbox_is_one_child_for_many_files(tmp_path):
    from emaphm.traces.importers.sandbox import reader_process

    seed = _seed("mat5z", tmp_path)
    with open_source(seed) as source:
        list(source.blocks(source.info.channels))
    first = reader_process().proc.pid
    for _ in range(20):
        with open_source(seed) as source:
            list(source.blocks(source.info.channels))
    assert reader_process().proc.pid == first


def test_the_sandbox_child_ends_with_its_parent(tmp_path):
    """A parent killed outright leaves no reader behind: the child reads end of file on
    its pipe and exits."""
    import signal
    import subprocess
    import time

    seed = _seed("mat5z", tmp_path)
    code = ("import sys, time\nfrom emaphm.traces.importers import inspect_source\n"
            "from emaphm.traces.importers.sandbox import reader_process\n"
            f"inspect_source({str(seed)!r})\nprint(reader_process().proc.pid, flush=True)\n"
            "time.sleep(60)\n")
    parent = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    child = int(parent.stdout.readline())
    parent.send_signal(signal.SIGKILL)
    parent.wait()
    status = Path(f"/proc/{child}/status")
    for _ in range(100):
        try:
            state = status.read_text().split("State:")[1].split()[0]
        except (FileNotFoundError, ProcessLookupError):
            break
        if state in ("Z", "X"):                      # exited, not yet reaped by init
            break
        time.sleep(0.05)
    else:
        pytest.fail(f"the sandbox child {child} outlived its parent")
