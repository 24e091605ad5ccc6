"""HealthHistory.frame (issue 22): an actuator's inspections as a pandas DataFrame."""

from __future__ import annotations

import pytest

pd = pytest.importorskip("pandas", reason="pandas is not installed: pip install -e '.[pandas]'")


def test_history_frame(tmp_path):
    from emaphm.prognosis.history import HealthHistory

    with HealthHistory(tmp_path / "h.sqlite") as h:
        h.register("EMA-1", time_unit="h")
        for t, k1 in ((0.0, 0.1), (100.0, 0.3)):
            h.add("EMA-1", t, [k1, 0, 0, 0, 0, 0, 0.5, 0.5], k_lo=[k1 - 0.01] + [0] * 7,
                  k_hi=[k1 + 0.01] + [1] * 7, algorithm="lsq", seed=0, fitness=1e-4)
        df = h.frame("EMA-1")
    assert list(df["time"]) == [0.0, 100.0]
    assert list(df["k_friction"]) == [0.1, 0.3]
    assert df["k_hi_friction"].iloc[1] == pytest.approx(0.31)
    assert df.attrs["actuator"]["id"] == "EMA-1" and df.index.name == "id"
