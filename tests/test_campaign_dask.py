"""A campaign on a real Dask cluster gives the local executor's results: the same runs,
seeds and counts exactly, the floats to 1e-12 (:func:`agreement.assert_same_outcome` says
why not bit for bit).

The test starts its own ``LocalCluster`` (two worker processes, one thread each) and
reaches it by address, as ``emaphm campaign --scheduler tcp://HOST:PORT`` does.
"""

from __future__ import annotations

import pytest
from agreement import assert_same_outcome

distributed = pytest.importorskip("distributed")

from emaphm.campaign import (CampaignStore, DaskExecutor, SerialExecutor, paper_spec,  # noqa: E402
                             run_campaign)
from emaphm.campaign.spec import parse_algorithms, parse_scenarios  # noqa: E402
from emaphm.cli import main  # noqa: E402


def spec():
    return paper_spec(runs=2, master_seed=99, budget=600, name="dask",
                      scenarios=parse_scenarios("backlash-high,short-circuit-low"),
                      algorithms=parse_algorithms("pso,gwo"))


def outcomes(path):
    with CampaignStore.open(path, readonly=True) as st:
        return {r.key: r.outcome() for r in st.results()}


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None, silence_logs=40) as c:
        yield c


def test_dask_cluster_gives_the_local_results(tmp_path, cluster):
    local = tmp_path / "local.sqlite"
    remote = tmp_path / "dask.sqlite"
    a = run_campaign(spec(), local, SerialExecutor())
    b = run_campaign(spec(), remote, DaskExecutor(cluster.scheduler_address))
    assert a.finished and b.finished and b.completed == 8 and b.failed == 0
    got, want = outcomes(remote), outcomes(local)
    assert got.keys() == want.keys() and len(got) == 8
    for key in want:
        assert_same_outcome(got[key], want[key], key)
    with CampaignStore.open(remote, readonly=True) as st:
        workers = {r.worker for r in st.results()}
    assert len(workers) == 2, "both workers should have taken runs"


def test_cli_scheduler_option_and_a_client_object(tmp_path, cluster, capsys):
    store = tmp_path / "cli.sqlite"
    rc = main(["campaign", "--scenarios", "gain-low", "--algorithms", "pso", "--runs", "1",
               "--budget", "300", "--store", str(store), "--scheduler", cluster.scheduler_address,
               "--quiet"])
    assert rc == 0, capsys.readouterr().err
    # a Client given by the caller is used and left open
    with distributed.Client(cluster) as client:
        s = paper_spec(runs=2, master_seed=0, budget=300, scenarios=parse_scenarios("gain-low"),
                       algorithms=parse_algorithms("pso"))
        summary = run_campaign(s, store.with_name("client.sqlite"), DaskExecutor(client))
        assert summary.completed == 2 and client.status == "running"
    assert outcomes(store)["gain-low/pso/0"] != {}
