"""pandas interop (issue 22): a trace as a DataFrame and back; pandas is optional and
imported only when a frame is asked for (the history's and the campaign store's frames are
tested beside them)."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from emaphm.simulate import simulate
from emaphm.traces import Trace, TraceError

pd = pytest.importorskip("pandas", reason="pandas is not installed: pip install -e '.[pandas]'")


def test_trace_round_trips_through_a_dataframe():
    tr = simulate(scenario="friction-high", model="monitoring")
    df = tr.to_pandas()
    assert list(df.columns) == ["t", "theta_ref", "theta_m", "omega_m", "i_a", "i_b", "i_c",
                                "torque"]
    assert df.attrs["emaphm"]["scenario" if "scenario" in tr.meta else "model"]
    np.testing.assert_array_equal(df["i_b"].to_numpy(), tr.i_b)
    assert Trace.from_pandas(df) == tr
    df2 = df.drop(columns="torque").assign(temperature=21.0)
    back = Trace.from_pandas(df2, meta={"source": "bench"})
    assert back.torque is None and back.meta == {"source": "bench"}
    # issue 34: a third current left out is derived, as emaphm import derives it
    assert Trace.from_pandas(df.drop(columns="i_c")).meta["currents_measured"] == 2
    with pytest.raises(TraceError, match=r"DataFrame: missing column\(s\) \['i_b', 'i_c'\]"):
        Trace.from_pandas(df.drop(columns=["i_b", "i_c"]))


def test_emaphm_does_not_import_pandas_until_a_frame_is_asked_for():
    code = ("import sys, emaphm.cli, emaphm.traces, emaphm.prognosis.history, emaphm.campaign; "
            "emaphm.cli.build_parser(); print('pandas' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
