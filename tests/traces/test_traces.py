"""Tests of emaphm.traces: the Trace container, CSV/Parquet I/O, validation, resampling."""

from __future__ import annotations

import dataclasses
import json
import math
import os
import re
import tempfile
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from emaphm.traces import csv_format
from emaphm.traces import (
    COLUMNS,
    OPTIONAL_COLUMNS,
    UNITS,
    Trace,
    TraceError,
    read_trace,
    resample,
    validate,
    write_trace,
)

POLE_PAIRS = 4


def synthetic(
    duration: float = 0.5,
    dt: float = 1.25e-4,
    *,
    turns: float = 2.0,
    noise: float = 0.0,
    torque: bool = True,
    seed: int = 0,
) -> Trace:
    """A realistic healthy trace: smooth motion over ``turns`` revolutions, balanced currents."""
    t = np.arange(0.0, duration, dt)
    w = 2 * np.pi / duration
    amplitude = turns * 2 * np.pi
    theta = amplitude * (1 - np.cos(w * t)) / 2
    omega = amplitude * w * np.sin(w * t) / 2
    current = 2.0 + np.sin(3 * w * t)
    theta_el = POLE_PAIRS * theta
    i_abc = np.column_stack(
        [current * np.cos(theta_el - k * 2 * np.pi / 3) for k in range(3)]
    )
    if noise:
        i_abc = i_abc + np.random.default_rng(seed).normal(0.0, noise, i_abc.shape)
    return Trace(
        t=t,
        theta_ref=np.roll(theta, 8),
        theta_m=theta,
        omega_m=omega,
        i_abc=i_abc,
        torque=0.05 * current if torque else None,
        meta={"model": "synthetic", "k": np.zeros(8), "seed": np.int64(7),
              "profile": "diagnostic", "parameters": {"motor": {"p": POLE_PAIRS}}},
    )


@pytest.fixture
def trace() -> Trace:
    return synthetic()


def assert_same(a: Trace, b: Trace) -> None:
    """Bitwise equality of all arrays (NaN equal to NaN, -0.0 distinct from 0.0) and meta."""
    for name in ("t", "theta_ref", "theta_m", "omega_m", "i_abc", "torque"):
        x, y = getattr(a, name), getattr(b, name)
        if x is None or y is None:
            assert x is None and y is None, name
            continue
        assert x.shape == y.shape, name
        assert np.array_equal(np.isnan(x), np.isnan(y)), name
        keep = ~np.isnan(x)
        assert np.array_equal(x[keep].view(np.uint64), y[keep].view(np.uint64)), name
    assert json.dumps(a.meta) == json.dumps(b.meta)
    assert a == b


def write_bench_csv(path: Path, columns: dict[str, np.ndarray], *, delimiter: str = ",",
                    newline: str = "\n", header: list[str] | None = None,
                    units_row: list[str] | None = None, preamble: str = "") -> Path:
    names = list(columns)
    lines = [delimiter.join(header or names)]
    if units_row is not None:
        lines.append(delimiter.join(units_row))
    data = np.column_stack([np.asarray(v, dtype=object) for v in columns.values()])
    lines += [delimiter.join(str(x) for x in row) for row in data]
    path.write_bytes((preamble + newline.join(lines) + newline).encode())
    return path


# --------------------------------------------------------------------------------------
# Container
# --------------------------------------------------------------------------------------


def test_constants_describe_si_columns():
    assert COLUMNS == ("t", "theta_ref", "theta_m", "omega_m", "i_a", "i_b", "i_c")
    assert OPTIONAL_COLUMNS == ("torque", "v_a", "v_b", "v_c", "v_d", "v_q", "d_a", "d_b", "d_c",
                                "v_dc", "i_d_ref", "i_q_ref", "omega_ref")
    assert UNITS == {"t": "s", "theta_ref": "rad", "theta_m": "rad", "omega_m": "rad/s",
                     "i_a": "A", "i_b": "A", "i_c": "A", "torque": "N m",
                     "v_a": "V", "v_b": "V", "v_c": "V", "v_d": "V", "v_q": "V",
                     "d_a": "1", "d_b": "1", "d_c": "1", "v_dc": "V", "i_d_ref": "A",
                     "i_q_ref": "A", "omega_ref": "rad/s"}


def test_properties(trace):
    assert trace.n == 4000
    assert trace.dt == pytest.approx(1.25e-4, rel=1e-12)
    assert trace.duration == pytest.approx(0.5 - 1.25e-4, rel=1e-12)
    np.testing.assert_array_equal(trace.i_a, trace.i_abc[:, 0])
    np.testing.assert_array_equal(trace.i_b, trace.i_abc[:, 1])
    np.testing.assert_array_equal(trace.i_c, trace.i_abc[:, 2])
    assert list(trace.columns()) == list(COLUMNS) + ["torque"]
    assert list(synthetic(torque=False).columns()) == list(COLUMNS)
    assert "n=4000" in repr(trace)


def test_arrays_are_float64_readonly_copies():
    t = np.arange(5)  # int input
    theta = np.zeros(5)
    tr = Trace(t, theta, theta, theta, np.zeros((5, 3)))
    assert all(a.dtype == np.float64 for a in tr.columns().values())
    for name in ("t", "theta_ref", "theta_m", "omega_m", "i_abc"):
        arr = getattr(tr, name)
        assert not arr.flags.writeable, name
        with pytest.raises(ValueError):
            arr[0] = 1.0
    theta[0] = 99.0  # the caller's array is not aliased
    assert tr.theta_m[0] == 0.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        tr.t = t  # type: ignore[misc]


@pytest.mark.parametrize(
    "change, match",
    [
        (dict(theta_m=np.zeros(4)), r"theta_m has 4 samples but t has 5"),
        (dict(omega_m=np.zeros((5, 1))), r"omega_m has shape \(5, 1\), expected \(n,\)"),
        (dict(i_abc=np.zeros((5, 2))), r"i_abc has shape \(5, 2\), expected \(5, 3\)"),
        (dict(i_abc=np.zeros(5)), r"i_abc has shape \(5,\), expected \(n, 3\)"),
        (dict(torque=np.zeros(6)), r"torque has 6 samples but t has 5"),
        (dict(t=["a"] * 5), r"Trace.t cannot be converted to a float64 array"),
        (dict(meta=[1, 2]), r"meta is a list, expected a dict"),
        (dict(meta={"rng": np.random.default_rng()}),
         r"meta\['rng'\] is a .*Generator.*plain data"),
        (dict(meta={1: "x"}), r"key 1 of type int; JSON metadata keys must be str"),
    ],
)
def test_construction_errors(change, match):
    z = np.zeros(5)
    kwargs = dict(t=np.arange(5.0), theta_ref=z, theta_m=z, omega_m=z, i_abc=np.zeros((5, 3)))
    kwargs.update(change)
    with pytest.raises(TraceError, match=match):
        Trace(**kwargs)


def test_meta_is_normalised_to_json_types(trace):
    @dataclasses.dataclass(frozen=True)
    class Motor:
        p: int
        r_s: float

    tr = trace.with_meta(
        k=np.arange(8) * 0.5,
        seed=np.int64(3),
        flag=np.bool_(True),
        params=Motor(p=4, r_s=np.float32(0.5)),
        nested={"shape": (1, 2), "path": Path("a/b")},
    )
    assert tr.meta["k"] == [0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5]
    assert type(tr.meta["seed"]) is int and type(tr.meta["flag"]) is bool
    assert tr.meta["params"] == {"p": 4, "r_s": 0.5}
    assert tr.meta["nested"] == {"shape": [1, 2], "path": os.fspath(Path("a/b"))}
    assert tr.meta["model"] == "synthetic"  # with_meta keeps the other keys
    assert trace.meta.get("flag") is None  # and leaves the original alone
    assert tr.t is trace.t  # arrays are shared, not copied


def test_from_columns_and_columns_roundtrip(trace):
    cols = dict(reversed(list(trace.columns().items())))
    cols["extra"] = np.ones(trace.n)
    assert Trace.from_columns(cols, meta=trace.meta) == trace
    del cols["i_b"], cols["t"]
    with pytest.raises(TraceError, match=r"missing column\(s\) \['t', 'i_b'\]; found .*'extra'.*"
                                         r"t \[s\], theta_ref \[rad\].*omega_m \[rad/s\]"):
        Trace.from_columns(cols)


def test_equality(trace):
    assert trace == synthetic()
    assert trace != trace.with_meta(model="other")
    assert trace.with_meta(a=1, b=2) == trace.with_meta(b=2, a=1)  # key order is irrelevant
    assert trace != synthetic(torque=False)
    assert trace != dataclasses.replace(trace, omega_m=trace.omega_m * 1.0000001)


# --------------------------------------------------------------------------------------
# File round trips
# --------------------------------------------------------------------------------------

FLOATS = st.floats(allow_nan=True, allow_infinity=True, allow_subnormal=True, width=64)
JSON_SCALARS = (
    st.none() | st.booleans() | st.integers(-(2**63), 2**63 - 1) | st.text(max_size=12)
    | st.floats(allow_nan=False, allow_infinity=True)
)
JSON = st.recursive(
    JSON_SCALARS,
    lambda inner: st.lists(inner, max_size=4)
    | st.dictionaries(st.text(max_size=8), inner, max_size=4),
    max_leaves=12,
)


@st.composite
def traces_st(draw) -> Trace:
    n = draw(st.integers(0, 40))
    col = hnp.arrays(np.float64, (n,), elements=FLOATS)
    torque = draw(st.none() | col)
    meta = draw(st.dictionaries(st.text(max_size=8), JSON, max_size=5))
    if draw(st.booleans()):  # numpy values are converted to JSON types
        meta["k"] = draw(hnp.arrays(np.float64, (8,), elements=st.floats(-1, 1)))
        meta["seed"] = np.int64(draw(st.integers(0, 2**32)))
    return Trace(
        t=draw(col), theta_ref=draw(col), theta_m=draw(col), omega_m=draw(col),
        i_abc=draw(hnp.arrays(np.float64, (n, 3), elements=FLOATS)), torque=torque,
        meta=meta,
    )


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
@settings(max_examples=60, deadline=None, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(tr=traces_st())
def test_roundtrip_is_exact(tmp_path, suffix, tr):
    with tempfile.TemporaryDirectory(dir=tmp_path) as d:
        path = write_trace(tr, Path(d) / f"trace{suffix}")
        assert path == Path(d) / f"trace{suffix}"
        back = read_trace(path, validate=False)
    assert_same(back, tr)


@pytest.mark.parametrize("suffix", [".csv", ".parquet", ".CSV"])
def test_roundtrip_realistic_trace_validates(tmp_path, trace, suffix):
    back = read_trace(write_trace(trace, tmp_path / f"run{suffix}"))
    assert_same(back, trace)
    assert back.meta == {"model": "synthetic", "k": [0.0] * 8, "seed": 7,
                         "profile": "diagnostic", "parameters": {"motor": {"p": 4}}}


def test_csv_layout(tmp_path, trace):
    path = write_trace(trace, tmp_path / "run.csv")
    lines = path.read_text().splitlines()
    assert lines[0].startswith("# emaphm-trace 1 {")
    assert json.loads(lines[0][len("# emaphm-trace 1 "):]) == trace.meta
    assert lines[1] == "t,theta_ref,theta_m,omega_m,i_a,i_b,i_c,torque"
    assert len(lines) == 2 + trace.n
    assert [float(x) for x in lines[2 + 5].split(",")] == [
        c[5] for c in trace.columns().values()
    ]


def test_parquet_layout(tmp_path, trace):
    import pyarrow.parquet as pq

    table = pq.read_table(write_trace(trace, tmp_path / "run.parquet"))
    assert table.column_names == list(COLUMNS) + ["torque"]
    assert all(str(f.type) == "double" for f in table.schema)
    assert json.loads(table.schema.metadata[b"emaphm"]) == trace.meta


def test_meta_with_nan_and_unicode_roundtrips(tmp_path, trace):
    tr = trace.with_meta(note="line1\nline2 \u2028 \u00b0 \U0001f600", x=math.nan,
                         y=[math.inf, -math.inf])
    for suffix in (".csv", ".parquet"):
        back = read_trace(write_trace(tr, tmp_path / f"m{suffix}"))
        assert back.meta["note"] == tr.meta["note"]
        assert math.isnan(back.meta["x"]) and back.meta["y"] == [math.inf, -math.inf]
        assert back == tr


def test_bench_csv_without_metadata_shuffled_with_extras(tmp_path, trace):
    cols = {
        "i_c": trace.i_c, "status": np.array(["ok"] * trace.n), "omega_m": trace.omega_m,
        "t": trace.t, "i_a": trace.i_a, "temperature": np.full(trace.n, 21.5),
        "theta_m": trace.theta_m, "i_b": trace.i_b, "theta_ref": trace.theta_ref,
    }
    cols = {k: (v if v.dtype.kind == "U" else np.array([repr(float(x)) for x in v]))
            for k, v in cols.items()}
    path = write_bench_csv(tmp_path / "bench.csv", cols, newline="\r\n",
                           preamble="# exported by bench rig 3\n")
    back = read_trace(path)
    assert back.torque is None
    assert back.meta == {}
    assert back == dataclasses.replace(trace, torque=None, meta={})


def test_bench_csv_semicolons_units_row_and_bracketed_names(tmp_path, trace):
    names = ["t [s]", "theta_ref [rad]", "theta_m (rad)", "omega_m", "i_a", "i_b", "i_c"]
    cols = {n: np.array([repr(float(x)) for x in v])
            for n, v in zip(names, list(trace.columns().values())[:7])}
    units = ["", "", "", "[rad/s]", "[A]", "[A]", "[A]"]
    path = write_bench_csv(tmp_path / "bench.csv", cols, delimiter=";", units_row=units)
    back = read_trace(path)
    assert back.meta["units"] == {"t": "s", "theta_ref": "rad", "theta_m": "rad",
                                  "omega_m": "rad/s", "i_a": "A", "i_b": "A", "i_c": "A"}
    assert dataclasses.replace(back, meta={}) == dataclasses.replace(trace, torque=None, meta={})


@pytest.mark.parametrize(
    "column, unit, match",
    [
        ("t", "[ms]", r"column 't' is in 'ms'.*multiply the column by 0.001 \(divide by 1000\)"),
        ("omega_m", "[rpm]", r"column 'omega_m' is in 'rpm'.*multiply the column by 2\*pi/60"),
        ("theta_m", "[deg]", r"column 'theta_m' is in 'deg'.*multiply the column by pi/180"),
        ("omega_m", "[deg/s]", r"column 'omega_m' is in 'deg/s'.*pi/180"),
        ("i_b", "[mA]", r"column 'i_b' is in 'mA'.*divide by 1000"),
        ("i_a", "[rad]",
         r"column 'i_a' has the unit 'rad' \(a unit of rad\), but 'i_a' must be in A"),
        ("t", "[fortnights]", r"column 't' has the unrecognised unit 'fortnights'"),
    ],
)
def test_non_si_units_row_is_rejected(tmp_path, trace, column, unit, match):
    cols = {n: np.array([repr(float(x)) for x in v])
            for n, v in list(trace.columns().items())[:7]}
    units = [unit if n == column else f"[{UNITS[n]}]" for n in cols]
    path = write_bench_csv(tmp_path / "bench.csv", cols, units_row=units)
    with pytest.raises(TraceError, match=match):
        read_trace(path)
    # not validated: readable, and the declared units are kept for a later validate()
    back = read_trace(path, validate=False)
    assert back.meta["units"][column] == unit.strip("[]")
    with pytest.raises(TraceError, match=match):
        validate(back)


def test_non_si_units_in_metadata_are_rejected(trace):
    with pytest.raises(TraceError, match=r"column 'omega_m' is in 'rpm'"):
        validate(trace.with_meta(units={"omega_m": "rpm"}))
    with pytest.raises(TraceError, match=r"column 'i_a' is in 'mA'"):
        validate(trace.with_meta(units={"i_abc": "mA"}))
    validate(trace.with_meta(units=dict(UNITS) | {"torque": "Nm", "omega_m": "rad/s"}))


def test_csv_metadata_units_conflicting_with_header(tmp_path, trace):
    path = write_trace(trace.with_meta(units={"t": "s"}), tmp_path / "run.csv")
    text = path.read_text().splitlines()
    text[1] = text[1].replace("t,", "t [ms],", 1)
    path.write_text("\n".join(text) + "\n")
    with pytest.raises(TraceError, match=r"'t' is declared in 's' by the metadata but in "
                                         r"'ms' by the header"):
        read_trace(path, validate=False)


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_missing_columns_in_file(tmp_path, trace, suffix):
    cols = {k: v for k, v in trace.columns().items() if k not in ("i_c", "omega_m")}
    if suffix == ".csv":
        path = write_bench_csv(tmp_path / "x.csv",
                               {k: np.array([repr(float(x)) for x in v]) for k, v in cols.items()})
    else:
        import pyarrow as pa
        import pyarrow.parquet as pq

        path = tmp_path / "x.parquet"
        pq.write_table(pa.table(cols), path)
    with pytest.raises(TraceError, match=rf"x{suffix}: missing column\(s\) \['omega_m', 'i_c'\]; "
                                         r"found \['t', 'theta_ref', 'theta_m', 'i_a', 'i_b', "
                                         r"'torque'\].*omega_m \[rad/s\]"):
        read_trace(path)


def test_foreign_parquet_without_metadata(tmp_path, trace):
    import pyarrow as pa
    import pyarrow.parquet as pq

    cols = dict(reversed(list(trace.columns().items())))
    cols["rpm_estimate"] = np.zeros(trace.n)
    pq.write_table(pa.table(cols), tmp_path / "foreign.parquet")
    back = read_trace(tmp_path / "foreign.parquet")
    assert back == dataclasses.replace(trace, meta={})


def test_csv_header_problems(tmp_path):
    (tmp_path / "numbers.csv").write_text("1,2,3\n4,5,6\n")
    with pytest.raises(TraceError, match=r"holds numbers, not column names; add a header row "
                                         r"'t,theta_ref,theta_m"):
        read_trace(tmp_path / "numbers.csv")
    (tmp_path / "empty.csv").write_text("# nothing\n\n")
    with pytest.raises(TraceError, match=r"no header row found"):
        read_trace(tmp_path / "empty.csv")
    (tmp_path / "dupe.csv").write_text("t,t,theta_ref,theta_m,omega_m,i_a,i_b,i_c\n")
    with pytest.raises(TraceError, match=r"\['t'\] appear more than once"):
        read_trace(tmp_path / "dupe.csv")
    (tmp_path / "newer.csv").write_text("# emaphm-trace 9 {}\nt\n")
    with pytest.raises(TraceError, match=r"format 9.*upgrade emaphm"):
        read_trace(tmp_path / "newer.csv")
    (tmp_path / "badjson.csv").write_text("# emaphm-trace 1 {oops\nt\n")
    with pytest.raises(TraceError, match=r"metadata is not valid JSON"):
        read_trace(tmp_path / "badjson.csv")


def test_csv_unparseable_value(tmp_path, trace):
    path = write_trace(trace, tmp_path / "run.csv")
    lines = path.read_text().splitlines()
    fields = lines[10].split(",")
    fields[3] = "oops"
    lines[10] = ",".join(fields)
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(TraceError, match=r"cannot read the data as numbers in data row 8, "
                                         r"column 'omega_m' \(.*'oops'"):
        read_trace(path)


@pytest.mark.parametrize("name", ["run.txt", "run.h5", "run", "run.csv.gz"])
def test_unsupported_suffix(tmp_path, trace, name):
    match = r"unsupported file type .*use one of \.csv, \.parquet"
    with pytest.raises(TraceError, match=match):
        write_trace(trace, tmp_path / name)
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(TraceError, match=match):
        read_trace(tmp_path / name)


def test_read_is_fast_for_1e5_rows(tmp_path):
    big = synthetic(duration=12.5)  # 100 000 rows
    assert big.n == 100_000
    for suffix in (".csv", ".parquet"):
        path = write_trace(big, tmp_path / f"big{suffix}")
        start = time.perf_counter()
        back = read_trace(path)
        elapsed = time.perf_counter() - start
        assert back == big
        assert elapsed < 5.0, f"{suffix}: reading 1e5 rows took {elapsed:.2f} s"


# --------------------------------------------------------------------------------------
# Atomic writes
# --------------------------------------------------------------------------------------


class Boom(RuntimeError):
    pass


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
@pytest.mark.parametrize("existing", [True, False])
def test_failed_write_keeps_old_file_and_leaves_no_temp(tmp_path, monkeypatch, trace, suffix,
                                                         existing):
    path = tmp_path / f"run{suffix}"
    if existing:
        write_trace(trace, path)
    before = path.read_bytes() if existing else None
    written = []

    def failing_fsync(fd):  # the temporary file is fully written when fsync is called
        written.append(os.fstat(fd).st_size)
        raise Boom("disk full")

    monkeypatch.setattr(os, "fsync", failing_fsync)
    with pytest.raises(Boom):
        write_trace(trace.with_meta(model="new"), path)
    assert written and written[0] > 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ([path.name] if existing else [])
    if existing:
        assert path.read_bytes() == before
        assert read_trace(path) == trace


def test_failure_mid_parquet_write_keeps_old_file(tmp_path, monkeypatch, trace):
    import pyarrow.parquet as pq

    path = write_trace(trace, tmp_path / "run.parquet")
    before = path.read_bytes()

    def half_write(table, where, **kwargs):
        where.write(b"PAR1 half a file")
        raise Boom("killed")

    monkeypatch.setattr(pq, "write_table", half_write)
    with pytest.raises(Boom):
        write_trace(trace.with_meta(model="new"), path)
    assert [p.name for p in tmp_path.iterdir()] == ["run.parquet"]
    assert path.read_bytes() == before


def test_failure_mid_csv_write_keeps_old_file(tmp_path, monkeypatch, trace):
    path = write_trace(trace, tmp_path / "run.csv")
    before = path.read_bytes()
    original = csv_format._csv_chunks

    def chunks_then_fail(tr, *args, **kwargs):
        for k, chunk in enumerate(original(tr, *args, **kwargs)):
            if k == 2:  # metadata line and header written, data not yet
                raise Boom("killed")
            yield chunk

    monkeypatch.setattr(csv_format, "_csv_chunks", chunks_then_fail)
    with pytest.raises(Boom):
        write_trace(trace.with_meta(model="new"), path)
    assert [p.name for p in tmp_path.iterdir()] == ["run.csv"]
    assert path.read_bytes() == before


def test_write_replaces_existing_file(tmp_path, trace):
    path = write_trace(trace, tmp_path / "run.csv")
    write_trace(trace.with_meta(model="second"), path)
    assert read_trace(path).meta["model"] == "second"
    assert [p.name for p in tmp_path.iterdir()] == ["run.csv"]


# --------------------------------------------------------------------------------------
# Validation
# --------------------------------------------------------------------------------------


def test_valid_traces_pass(trace):
    assert validate(trace) is trace
    validate(synthetic(torque=False))
    validate(synthetic(noise=0.3))  # noisy currents are not a wiring error
    validate(synthetic(noise=2.0))  # even when the noise is as large as the signal
    rng = np.random.default_rng(1)  # nor is pure sensor noise on unloaded phases
    validate(dataclasses.replace(trace, i_abc=rng.normal(0.0, 0.05, trace.i_abc.shape)))
    validate(dataclasses.replace(trace, i_abc=np.zeros((trace.n, 3))))
    # a filtered, slightly lagging speed estimate is accepted
    validate(dataclasses.replace(trace, omega_m=np.roll(trace.omega_m, 5)))


def replace(trace: Trace, **arrays) -> Trace:
    return dataclasses.replace(trace, **arrays)


def with_value(arr: np.ndarray, index, value) -> np.ndarray:
    out = np.array(arr)
    out[index] = value
    return out


@pytest.mark.parametrize("column", ["t", "theta_ref", "theta_m", "omega_m", "torque"])
@pytest.mark.parametrize("value, kind", [(np.nan, "NaN"), (np.inf, "inf"), (-np.inf, "inf")])
def test_non_finite_values(trace, column, value, kind):
    bad = replace(trace, **{column: with_value(getattr(trace, column), [123, 200], value)})
    where = r"row 123" if column == "t" else r"row 123 \(t = 0.015375 s\)"
    match = (rf"column '{column}' holds 2 non-finite value\(s\), "
             rf"the first \({kind}\) at {where}; remove or interpolate")
    with pytest.raises(TraceError, match=match):
        validate(bad)


def test_non_finite_current(trace):
    bad = replace(trace, i_abc=with_value(trace.i_abc, (321, 2), np.nan))
    match = r"column 'i_c' holds 1 non-finite.*row 321 \(t = 0.040125 s\)"
    with pytest.raises(TraceError, match=match):
        validate(bad)


def test_time_not_increasing(trace):
    bad = replace(trace, t=with_value(trace.t, 50, trace.t[49]))
    with pytest.raises(TraceError, match=r"'t' is not strictly increasing: t\[50\] = 0.00612+5 s "
                                         r"<= t\[49\].*sort the samples by time"):
        validate(bad)


def test_time_not_uniform_suggests_resample(trace):
    bad = replace(trace, t=with_value(trace.t, slice(1000, None), trace.t[1000:] + 0.3e-4))
    with pytest.raises(TraceError, match=r"'t' is not uniform.*ends at row 1000 .*"
                                         r"emaphm\.traces\.resample\(trace, numpy\.linspace"):
        validate(bad)
    validate(bad, rtol_dt=0.5)  # the tolerance is honoured
    fixed = resample(bad, np.linspace(bad.t[0], bad.t[-1], bad.n))
    validate(fixed)


def test_time_in_milliseconds(trace):
    with pytest.raises(TraceError, match=r"'t' looks like milliseconds.*mean step 0.125.*"
                                         r"divide t by 1000"):
        validate(replace(trace, t=trace.t * 1e3))


def test_duration_above_1000_s_says_both_readings():
    long = synthetic(duration=1080.0, dt=0.009, turns=50.0)
    with pytest.raises(TraceError, match=r"'t' spans 10\d\d.* with a mean step of 0.009: in "
                                         r"seconds the trace lasts 18 min.*in milliseconds it "
                                         r"lasts 1.08 s"):
        validate(long)


def test_an_hour_at_20_khz_is_long_not_milliseconds():
    from emaphm.traces.validation import _check_time_scale

    with pytest.raises(TraceError, match=r"^the trace lasts 1 h \(3600 s at 20000 Hz\), longer "
                                         r"than the 1000 s .*--window START:END") as info:
        _check_time_scale(5e-5, 3600.0)
    assert "millisecond" not in str(info.value)
    with pytest.raises(TraceError, match=r"looks like milliseconds"):
        _check_time_scale(0.125, 500.0)
    _check_time_scale(1.25e-4, 0.5)


def test_currents_in_milliamperes(trace):
    with pytest.raises(TraceError, match=r"column 'i_a' looks like mA, not A.*divide the phase "
                                         r"currents by 1000"):
        validate(replace(trace, i_abc=trace.i_abc * 1e3))
    only_c = trace.i_abc * [1, 1, 1e3]
    with pytest.raises(TraceError, match=r"column 'i_c' looks like mA"):
        validate(replace(trace, i_abc=only_c))


@pytest.mark.parametrize(
    "change, match",
    [
        (lambda tr: dict(omega_m=tr.omega_m * 60 / (2 * np.pi)),
         r"ratio omega_m / \(d theta_m/dt\) is 9\.549.*omega_m looks like rpm: multiply omega_m "
         r"by 2\*pi/60"),
        (lambda tr: dict(omega_m=np.degrees(tr.omega_m)),
         r"is 57\.3, expected 1, a units error; omega_m looks like deg/s: multiply omega_m by "
         r"pi/180"),
        (lambda tr: dict(theta_m=np.degrees(tr.theta_m), theta_ref=np.degrees(tr.theta_ref)),
         r"is 0\.01745.*theta_m looks like degrees: multiply theta_m and theta_ref by pi/180"),
        (lambda tr: dict(theta_m=tr.theta_m / (2 * np.pi)),
         r"theta_m looks like revolutions"),
        (lambda tr: dict(omega_m=-tr.omega_m),
         r"is -1, expected 1; omega_m has the opposite sign to d theta_m/dt: negate omega_m"),
        (lambda tr: dict(omega_m=tr.omega_m / 20),
         r"is 0\.05, expected 1\. Check that theta_m and omega_m are both motor-side"),
    ],
)
def test_speed_and_position_units(trace, change, match):
    with pytest.raises(TraceError, match=r"omega_m does not match the time derivative of "
                                         r"theta_m.*" + match):
        validate(replace(trace, **change(trace)))


def test_degrees_under_a_noisy_speed_are_found_by_the_integral():
    """Positions in degrees beside a speed in rad/s whose noise hides it from the derivative
    (a tachometer's noise, omega_m vs d theta_m/dt correlated only 0.7, and no speed beyond
    2000 rad/s): the change of theta_m is 57.3 times the integral of omega_m."""
    tr = synthetic(noise=0.02)
    rng = np.random.default_rng(1)
    noisy = tr.omega_m + rng.normal(0.0, np.std(tr.omega_m), tr.n)
    degrees = replace(tr, theta_m=np.degrees(tr.theta_m), theta_ref=np.degrees(tr.theta_ref),
                      omega_m=noisy)
    assert np.max(np.abs(noisy)) < 2000.0
    with pytest.raises(TraceError, match=r"^theta_m does not match the integral of omega_m: its "
                                         r"change is 5\d\.\d+ times .*positions look like degrees: "
                                         r"multiply theta_m and theta_ref by pi/180"):
        validate(degrees)
    validate(replace(tr, omega_m=noisy))                 # the same noise in rad: accepted
    revs = replace(tr, theta_m=tr.theta_m / (2 * np.pi), theta_ref=tr.theta_ref / (2 * np.pi),
                   omega_m=noisy)
    with pytest.raises(TraceError, match=r"theta_m looks like revolutions"):
        validate(revs, min_rotation=0)


def test_speed_check_survives_encoder_quantisation(trace):
    counts = 2 * np.pi / 4096
    quantised = np.round(trace.theta_m / counts) * counts
    validate(replace(trace, theta_m=quantised))


def test_too_few_samples(trace):
    short = Trace(trace.t[:99], trace.theta_ref[:99], trace.theta_m[:99], trace.omega_m[:99],
                  trace.i_abc[:99])
    with pytest.raises(TraceError, match=r"too short: 99 samples, at least 100.*"
                                         r"emaphm\.profiles\.diagnostic\(\)"):
        validate(short)


def test_rotation_below_one_revolution(trace):
    small = synthetic(turns=0.9)
    match = (r"max\(theta_m\) - min\(theta_m\) = 5\.655 rad is below min_rotation = 6\.283 rad; "
             r"eccentricity identification needs at least one full mechanical revolution.*"
             r"emaphm\.profiles\.diagnostic\(\).*min_rotation=0")
    with pytest.raises(TraceError, match=match):
        validate(small)
    validate(small, min_rotation=0)
    validate(small, min_rotation=5.0)
    with pytest.raises(TraceError, match=r"below min_rotation = 20"):
        validate(trace, min_rotation=20.0)


def test_rotation_check_on_read(tmp_path):
    path = write_trace(synthetic(turns=0.5), tmp_path / "short.parquet")
    with pytest.raises(TraceError, match=r"short\.parquet: .*full mechanical revolution"):
        read_trace(path)
    read_trace(path, min_rotation=0)
    read_trace(path, min_rotation=1.0)


@pytest.mark.parametrize(
    "change, match",
    [
        (lambda i: i * [1, 1, -1], r"do not sum to zero"),  # wrong sign on one phase
        (lambda i: i * [1, 1, 0], r"do not sum to zero.*i_c is constant throughout \(a missing "
                                  r"phase\?\).*set i_c = -\(i_a \+ i_b\)"),
        (lambda i: i[:, [0, 1, 1]], r"do not sum to zero"),  # phase b recorded twice
    ],
)
def test_star_connection(trace, change, match):
    with pytest.raises(TraceError, match=r"the phase currents ") as info:
        validate(replace(trace, i_abc=change(trace.i_abc)))
    assert re.search(match, str(info.value)), str(info.value)
    assert "Check for a swapped or missing phase, a wrong sign" in str(info.value)
    assert "no single current sensor's gain or offset explains it" in str(info.value)


@pytest.mark.parametrize("change", [lambda i: i + [0.3, 0.0, 0.0],          # an offset on a
                                    # an offset as large as the RMS current itself (was
                                    # refused as a wiring error beyond half of it)
                                    lambda i: i + [0.0, np.sqrt(np.mean(i * i)), 0.0],
                                    lambda i: i * [1.0, 0.8, 1.0],           # b reads 20 % low
                                    lambda i: i * [1.0, 1.0, 1.25] + [0, 0, -0.2]])
def test_a_sum_one_faulty_sensor_explains_is_read_for_the_diagnosis(trace, change):
    """What one current sensor's gain or offset explains is a sensor fault, diagnosed as
    such (emaphm.modes.current_sensor), not a file to refuse (issue 21)."""
    from emaphm.traces.zero_sum import best_fit

    bad = replace(trace, i_abc=change(trace.i_abc))
    validate(bad)
    fit = best_fit(bad.i_abc)
    assert fit.plausible and fit.residual < 0.01


def test_star_connection_with_noise(trace):
    noisy = synthetic(noise=1.0, seed=3)
    with pytest.raises(TraceError, match=r"do not sum to zero"):
        validate(replace(noisy, i_abc=noisy.i_abc * [1, 1, -1]))


def test_validate_argument_errors(trace):
    with pytest.raises(TypeError, match=r"needs a Trace"):
        validate(trace.columns())  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"min_rotation must be finite and >= 0"):
        validate(trace, min_rotation=-1.0)
    with pytest.raises(ValueError, match=r"rtol_dt must be finite and > 0"):
        validate(trace, rtol_dt=0.0)


def test_trace_error_is_value_error():
    assert issubclass(TraceError, ValueError)


# --------------------------------------------------------------------------------------
# Resampling
# --------------------------------------------------------------------------------------


def linear_trace(t: np.ndarray, torque: bool = True) -> Trace:
    def lin(a, b):
        return a + b * t

    return Trace(t, lin(0.1, 2.0), lin(-1.0, 30.0), lin(30.0, 0.0),
                 np.column_stack([lin(1.0, -3.0), lin(-2.0, 5.0), lin(1.0, -2.0)]),
                 torque=lin(0.5, 0.25) if torque else None, meta={"model": "linear"})


def test_resample_is_exact_on_linear_signals():
    rng = np.random.default_rng(0)
    t = np.sort(rng.uniform(0.0, 1.0, 200))  # irregular source grid
    tr = linear_trace(t)
    t_new = np.linspace(t[0], t[-1], 333)
    out = resample(tr, t_new)
    expected = linear_trace(t_new)
    for name in ("theta_ref", "theta_m", "omega_m", "i_abc", "torque"):
        np.testing.assert_allclose(getattr(out, name), getattr(expected, name),
                                   rtol=1e-12, atol=1e-12, err_msg=name)
    np.testing.assert_array_equal(out.t, t_new)
    assert out.meta == tr.meta
    # the end points are reproduced bit for bit
    assert out.theta_m[0] == tr.theta_m[0] and out.theta_m[-1] == tr.theta_m[-1]


@settings(max_examples=50, deadline=None, database=None)
@given(
    n=st.integers(2, 50),
    m=st.integers(1, 50),
    coef=st.tuples(st.floats(-1e3, 1e3), st.floats(-1e3, 1e3)),
)
def test_resample_linear_property(n, m, coef):
    t = np.linspace(0.0, 1.0, n)
    a, b = coef
    tr = Trace(t, a + b * t, a + b * t, a + b * t, np.column_stack([a + b * t] * 3))
    t_new = np.linspace(0.0, 1.0, m + 1)[1:] if m > 1 else np.array([0.5])
    out = resample(tr, t_new)
    np.testing.assert_allclose(out.theta_m, a + b * t_new, rtol=1e-9, atol=1e-9 * (abs(a) + abs(b)))
    assert out.torque is None


def test_resample_nodes_are_exact(trace):
    out = resample(trace, trace.t[::7])
    np.testing.assert_array_equal(out.i_abc, trace.i_abc[::7])
    np.testing.assert_array_equal(out.torque, trace.torque[::7])


def test_resample_bounds(trace):
    half = 0.5 * trace.dt
    out = resample(linear_trace(trace.t), np.array([trace.t[0] - 0.99 * half,
                                                    trace.t[-1] + 0.99 * half]))
    # inside the half-step margin the end segments are extended linearly
    np.testing.assert_allclose(out.theta_m, -1.0 + 30.0 * out.t, rtol=1e-12)
    with pytest.raises(TraceError, match=r"outside the trace .*tolerance half a step"):
        resample(trace, np.array([trace.t[0] - 1.01 * half, 0.1]))
    with pytest.raises(TraceError, match=r"outside the trace"):
        resample(trace, np.array([0.1, trace.t[-1] + 1.01 * half]))


@pytest.mark.parametrize(
    "t_new, match",
    [
        (np.array([0.2, 0.1]), r"t_new must be finite and strictly increasing"),
        (np.array([0.1, np.nan]), r"t_new must be finite and strictly increasing"),
        (np.zeros((2, 2)), r"t_new must be a non-empty 1-D array"),
        (np.array([]), r"t_new must be a non-empty 1-D array"),
    ],
)
def test_resample_bad_grid(trace, t_new, match):
    with pytest.raises(TraceError, match=match):
        resample(trace, t_new)


def test_resample_needs_increasing_source(trace):
    bad = replace(trace, t=with_value(trace.t, 10, trace.t[9]))
    with pytest.raises(TraceError, match=r"trace\.t must be finite and strictly increasing"):
        resample(bad, trace.t)
