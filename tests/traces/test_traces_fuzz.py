"""Fuzzing the trace readers: whatever bytes a file holds, reading it gives a valid trace or
a TraceError naming the file, never another exception (2,000 generated files)."""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from emaphm.simulate import simulate
from emaphm.traces import TraceError, read_trace, write_trace


@pytest.fixture(scope="module")
def valid_files(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("fuzz-base")
    tr = simulate(model="monitoring")
    out = {}
    for suffix in (".csv", ".parquet"):
        p = tmp / f"base{suffix}"
        write_trace(tr, p)
        out[suffix] = p.read_bytes()
    return out


_META = [b"{", b"[" * 100_000, b'{"profile": {"kind": "x"}}', b'{"k": "abc"}', b"\xff\xfe",
         b'{"profile": 1e999}', b'{"parameters": {"motor": {"R": "3.15 ohm"}}}', b"null"]


@settings(max_examples=2000, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow,
                                 HealthCheck.data_too_large])
@given(data=st.data())
def test_a_malformed_trace_file_is_a_trace_error_or_a_trace(valid_files, tmp_path_factory, data):
    suffix = data.draw(st.sampled_from([".csv", ".parquet"]))
    raw = bytearray(valid_files[suffix])
    kind = data.draw(st.sampled_from(["flip", "truncate", "insert", "meta", "random"]))
    if kind == "flip":
        for _ in range(data.draw(st.integers(1, 20))):
            raw[data.draw(st.integers(0, len(raw) - 1))] = data.draw(st.integers(0, 255))
    elif kind == "truncate":
        raw = raw[: data.draw(st.integers(0, len(raw)))]
    elif kind == "insert":
        i = data.draw(st.integers(0, len(raw)))
        raw[i:i] = data.draw(st.binary(max_size=50))
    elif kind == "meta" and suffix == ".csv":
        end = raw.index(b"\n")
        raw[:end] = b"# emaphm " + data.draw(st.sampled_from(_META))
    else:
        raw = bytearray(data.draw(st.binary(max_size=500)))
    path = tmp_path_factory.mktemp("fuzz") / f"t{suffix}"
    path.write_bytes(bytes(raw))
    try:
        trace = read_trace(path)
    except TraceError as exc:
        assert str(path) in str(exc)
        return
    assert trace.n > 0                                   # a valid trace came back
    assert path.read_bytes() == bytes(raw)               # reading changed nothing


def test_a_folder_is_a_trace_error(tmp_path):
    d = tmp_path / "trace.csv"
    d.mkdir()
    with pytest.raises(TraceError, match="is a folder"):
        read_trace(d)
