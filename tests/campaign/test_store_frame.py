"""CampaignStore.frame (issue 22): a campaign store's runs as a pandas DataFrame."""

from __future__ import annotations

import numpy as np
import pytest
from support import small_spec

pd = pytest.importorskip("pandas", reason="pandas is not installed: pip install -e '.[pandas]'")


def test_campaign_store_frame(tmp_path):
    from emaphm.campaign import CampaignStore, RunResult

    def fake_result(run, status="ok"):
        if status != "ok":
            return RunResult.failure(run, "RuntimeError: boom")
        k = tuple(float(x) for x in np.linspace(0.1, 0.8, 8) + run.run * 0.01)
        return RunResult(key=run.key, index=run.index, scenario=run.scenario,
                         algorithm=run.algorithm, optimizer=run.optimizer, run=run.run,
                         seed=run.seed, noise_seed=run.noise_seed, spawn_key=run.spawn_key,
                         status="ok", k_true=run.k_true, k=k, fitness=1e-4, error_pct=0.5,
                         k_raw=k, history=(1.0, 0.5))

    spec = small_spec(scenarios="friction-low", runs=2, master_seed=3)
    with CampaignStore.open(tmp_path / "s.sqlite", spec) as st:
        runs = spec.runs_list()[:3]
        for run in runs:
            st.commit(fake_result(run))
        st.commit(fake_result(spec.runs_list()[3], status="failed"))
        df = st.frame()
        everything = st.frame(status=None)
    assert len(df) == 3 and len(everything) == 4
    assert set(df.index) == {r.key for r in runs}
    row = df.loc[runs[0].key]
    assert row["k_friction"] == pytest.approx(fake_result(runs[0]).k[0])
    assert row["k_true_friction"] == runs[0].k_true[0]
    assert np.isnan(everything.loc[spec.runs_list()[3].key, "k_friction"])
