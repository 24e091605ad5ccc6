"""An algorithm of one's own, registered by name (:func:`emaphm.optim.register`, issue 34),
works wherever a built-in name does: ``identify``, ``IdentificationConfig`` (and its JSON
round trip), a campaign spec and its store, a health history's inspection and the CLI's
``--algorithm`` within the process. A budget holds its polish back."""

from __future__ import annotations

import contextlib
import io
import json

import numpy as np
import pytest

from emaphm.identify import IdentificationConfig, identify
from emaphm.optim import register, registered, unregister
from emaphm.simulate import DEFAULT_SENSORS, simulate

BUDGET = 300


def coordinate_search(objective, bounds, rng):
    """Polls +-step along every axis from a random start, halving the step."""
    lo, hi = bounds
    x = lo + (hi - lo) * rng.random(lo.size)
    fx = objective(x[None])[0]
    step = 0.25 * (hi - lo)
    while np.max(step / (hi - lo)) > 1e-3:
        X = np.clip(np.vstack([x + np.diag(step), x - np.diag(step)]), lo, hi)
        f = objective(X)
        if f.min() < fx:
            x, fx = X[np.argmin(f)], f.min()
        else:
            step = step / 2
    return x


@pytest.fixture(scope="module")
def coord():
    register("coord", coordinate_search)
    yield "coord"
    unregister("coord")


@pytest.fixture(scope="module")
def trace():
    return simulate(scenario="friction-high", sensors=DEFAULT_SENSORS, seed=1)


def test_a_registered_function_identifies_by_name_and_round_trips(coord, trace):
    a = identify(trace, coord, seed=0, termination=BUDGET)
    b = identify(trace, coordinate_search, seed=0, termination=BUDGET)   # the object: its name
    assert a.algorithm == b.algorithm == "coord"
    np.testing.assert_array_equal(a.k, b.k)
    assert a.config.algorithm == "coord" and a.evaluations <= BUDGET
    assert a.polish_evaluations > 0                # the budget held the polish back
    config = IdentificationConfig.from_dict(json.loads(json.dumps(a.config.to_dict())))
    again = identify(trace, config, seed=0)
    np.testing.assert_array_equal(again.k, a.k)
    assert IdentificationConfig(coordinate_search).algorithm == "coord"


def test_an_unregistered_object_is_refused_where_a_name_is_stored(coord):
    from emaphm.campaign import CampaignSpec

    with pytest.raises(TypeError, match="register your function first"):
        IdentificationConfig(lambda objective, bounds, rng: bounds[0])
    with pytest.raises(TypeError, match="register your function first"):
        CampaignSpec(algorithms=["lsq", lambda objective, bounds, rng: bounds[0]])


def test_a_campaign_runs_a_registered_name_and_its_store_reads_back(coord, tmp_path):
    from emaphm.campaign import CampaignSpec, CampaignStore, SerialExecutor, run_campaign

    spec = CampaignSpec(scenarios=["friction-high"], algorithms=["coord"], runs=1,
                        budget=BUDGET, master_seed=3)
    assert CampaignSpec(scenarios=["friction-high"], algorithms=[coordinate_search], runs=1,
                        budget=BUDGET, master_seed=3) == spec
    summary = run_campaign(spec, tmp_path / "c.sqlite", SerialExecutor())
    assert summary.completed == 1 and summary.failed == 0
    with CampaignStore.open(tmp_path / "c.sqlite", readonly=True) as st:
        (result,) = st.results()
        assert st.spec == spec and result.algorithm == "coord"


def test_a_history_and_the_cli_take_a_registered_name(coord, trace, tmp_path):
    from emaphm.cli import main
    from emaphm.prognosis import HealthHistory, record_inspection

    with HealthHistory(tmp_path / "h.sqlite") as h:
        h.register("EMA-01")
        ins, _ = record_inspection(h, "EMA-01", trace, 1.0, seed=0,
                                   config=IdentificationConfig("coord", budget=BUDGET))
        assert ins.algorithm == "coord"
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        rc = main(["diagnose", "--scenario", "friction-high", "--seed", "1", "--algorithm",
                   "coord", "--budget", str(BUDGET), "--json", "--quiet"])
    assert rc == 0 and json.loads(buf.getvalue())["algorithm"] == "coord"
    assert "coord" in registered()
