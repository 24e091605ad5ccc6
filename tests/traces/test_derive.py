"""One derivation of the channels a recording may lack (issue 34): the speed from the
position, the third current from two (:mod:`emaphm.traces.derive`), the same in ``emaphm
import`` and in ``Trace.from_pandas``; the metadata says what was derived."""

from __future__ import annotations

import numpy as np
import pytest

from emaphm.simulate import DEFAULT_SENSORS, simulate
from emaphm.traces import Trace, TraceError
from emaphm.traces.derive import SPEED_NOTE, THIRD_CURRENT_NOTE, derive_missing
from emaphm.traces.importers import ChannelMap, import_trace

pd = pytest.importorskip("pandas")

MAP = """
[channels]
t = { name = "t", unit = "s" }
theta_ref = { name = "theta_ref", unit = "rad" }
theta_m = { name = "theta_m", unit = "rad" }
i_a = { name = "i_a", unit = "A" }
i_b = { name = "i_b", unit = "A" }
"""


@pytest.fixture(scope="module")
def trace():
    return simulate(scenario="nominal", sensors=DEFAULT_SENSORS, seed=4)


def test_a_frame_with_two_currents_and_no_speed_is_a_trace(trace):
    df = pd.DataFrame({c: trace.columns()[c] for c in ("t", "theta_ref", "theta_m", "i_a", "i_b")})
    got = Trace.from_pandas(df, meta={"scenario": "x"})
    np.testing.assert_array_equal(got.i_c, -(trace.i_a + trace.i_b))
    np.testing.assert_array_equal(got.omega_m, np.gradient(trace.theta_m, trace.t))
    assert got.meta == {"scenario": "x", "currents_measured": 2,
                        "derived": {"omega_m": SPEED_NOTE, "i_c": THIRD_CURRENT_NOTE}}
    whole = Trace.from_pandas(trace.to_pandas())             # nothing to derive: as it was
    assert "derived" not in whole.meta and whole == trace


def test_the_importer_and_from_pandas_derive_alike(trace, tmp_path):
    import tomllib

    cols = {c: trace.columns()[c] for c in ("t", "theta_ref", "theta_m", "i_a", "i_b")}
    lines = [",".join(cols)] + [",".join(repr(float(v)) for v in row)
                                for row in zip(*cols.values())]
    (tmp_path / "bench.csv").write_text("\n".join(lines) + "\n")
    imported = import_trace(tmp_path / "bench.csv",
                            ChannelMap.from_dict(tomllib.loads(MAP), source="map.toml"))
    framed = Trace.from_pandas(pd.DataFrame(cols))
    np.testing.assert_array_equal(imported.omega_m, framed.omega_m)
    np.testing.assert_array_equal(imported.i_c, framed.i_c)
    assert imported.meta["derived"] == framed.meta["derived"]
    assert imported.meta["currents_measured"] == framed.meta["currents_measured"] == 2


def test_what_cannot_be_derived_is_named():
    with pytest.raises(TraceError, match=r"\['theta_m', 'omega_m'\].*may be left out"):
        Trace.from_columns({"t": [0.0, 1.0], "theta_ref": [0, 0], "i_a": [0, 0], "i_b": [0, 0],
                            "i_c": [0, 0]})
    with pytest.raises(TraceError, match=r"missing column\(s\) \['i_b', 'i_c'\]"):
        Trace.from_pandas(pd.DataFrame({"t": [0.0], "theta_ref": [0.0], "theta_m": [0.0],
                                        "omega_m": [0.0], "i_a": [0.0]}))
    cols, notes = derive_missing({"t": np.array([0.0]), "theta_m": np.array([1.0]),
                                  "i_a": np.array([1.0]), "i_b": np.array([2.0])}, np.array([0.0]))
    assert cols["omega_m"].tolist() == [0.0] and cols["i_c"].tolist() == [-3.0]
    assert set(notes) == {"omega_m", "i_c"}
