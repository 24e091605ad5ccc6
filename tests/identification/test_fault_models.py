"""The fault model setting end to end: traces, identification, campaigns, history, CLI."""

import json

import numpy as np
import pytest
from support import mm_trace  # noqa: F401  (a fixture)

from emaphm.campaign.spec import CampaignSpec, ScenarioSpec
from emaphm.cli import main
from emaphm.fitness import trace_fault_model
from emaphm.simulate import simulate
from emaphm.traces import Trace, read_trace


def _bare(trace, **meta):
    return Trace(t=trace.t, theta_ref=trace.theta_ref, theta_m=trace.theta_m,
                 omega_m=trace.omega_m, i_abc=trace.i_abc, meta=meta)


def test_a_trace_is_diagnosed_with_its_own_fault_model(mm_trace):
    assert mm_trace.meta["fault_model"] == "physical"
    assert trace_fault_model(mm_trace) == "physical"
    # written by emaphm before fault models existed: the paper's
    assert trace_fault_model(_bare(mm_trace, model="reference")) == "paper"
    # a bench trace: physical
    assert trace_fault_model(_bare(mm_trace)) == "physical"
    with pytest.raises(ValueError, match="unknown fault model"):
        trace_fault_model(_bare(mm_trace, fault_model="magic"))


def test_scenarios_keep_their_fault_model_and_a_bare_k_is_physical():
    assert simulate(scenario="short-circuit-high", model="monitoring").meta["fault_model"] == "paper"
    assert simulate([0, 0, 0.1, 0, 0, 0, 0.5, 0.5], model="monitoring").meta["fault_model"] \
        == "physical"
    t = simulate(scenario="short-circuit-high", model="monitoring", fault_model="physical")
    assert t.meta["fault_model"] == "physical"


def test_campaign_specs_carry_the_fault_model_and_old_stores_read_as_paper():
    spec = CampaignSpec(scenarios=("short-circuit-high", "turn-short-5pct"), runs=1)
    assert [s.fault_model for s in spec.scenarios] == ["paper", "physical"]
    assert {r.scenario: r.fault_model for r in spec.runs_list()} == {
        "short-circuit-high": "paper", "turn-short-5pct": "physical"}
    over = CampaignSpec(scenarios=("short-circuit-high",), runs=1, fault_model="physical")
    assert over.scenarios[0].fault_model == "physical" and over.hash != spec.hash
    # a user's custom scenario without a fault model is physical
    user = CampaignSpec.from_dict({"scenarios": [{"name": "mine", "k": [0, 0, 0.1, 0, 0, 0, 0.5, 0.5]}]})
    assert user.scenarios[0].fault_model == "physical"
    # a stored spec written before fault models existed: its scenarios are the paper's
    d = spec.to_dict()
    for s in d["scenarios"]:
        s.pop("fault_model")
    old = CampaignSpec.from_json(json.dumps(d))
    assert [s.fault_model for s in old.scenarios] == ["paper", "paper"]
    with pytest.raises(ValueError, match="unknown fault_model"):
        CampaignSpec(scenarios=("nominal",), fault_model="ideal")
    assert ScenarioSpec.named("turn-short-15pct").to_dict()["fault_model"] == "physical"


def test_inspections_record_their_fault_model_old_ones_read_as_paper():
    from emaphm.prognosis.history import Inspection

    base = dict(id=1, actuator="a", time=1.0, k=np.zeros(8), k_lo=np.zeros(8), k_hi=np.zeros(8),
                spread_method=None, level=None, healthy=True, diagnosis=None, fingerprint=None,
                algorithm="pso", seed=0, fitness=None, evaluations=None, source=None,
                recorded_utc="")
    assert Inspection(**base).fault_model == "paper"
    ins = Inspection(**base, extra={"fault_model": "physical"})
    assert ins.fault_model == "physical" and ins.to_dict()["fault_model"] == "physical"


def test_cli_simulate_records_fault_model_and_unit(tmp_path, capsys):
    out = tmp_path / "u.csv"
    assert main(["simulate", "--scenario", "nominal", "--unit-seed", "4", "--seed", "1",
                 "--unreported-load", "0.05", "--out", str(out)]) == 0
    tr = read_trace(out)
    assert tr.meta["fault_model"] == "paper" and tr.meta["unit"]["seed"] == 4
    assert tr.meta["unit"]["unreported_load"] == 0.05
    assert tr.meta["profile"]["load"] == simulate(model="monitoring").meta["profile"]["load"]
    # the unit options describe the plant: refused with the monitoring model or a trace file
    assert main(["simulate", "--scenario", "nominal", "--unit-seed", "4", "--model",
                 "monitoring", "--out", str(out)]) == 2
    assert "use them with --model reference" in capsys.readouterr().err
    assert main(["diagnose", str(out), "--unit-seed", "3"]) == 2
    assert "not with a trace file" in capsys.readouterr().err
    assert main(["simulate", "--scenario", "nominal", "--tolerances", "t.toml",
                 "--out", str(out)]) == 2
    assert "--tolerances needs --unit-seed" in capsys.readouterr().err


def test_cli_nuisance_option_is_checked(tmp_path, capsys):
    out = tmp_path / "t.csv"
    assert main(["simulate", "--scenario", "nominal", "--model", "monitoring", "--seed", "1",
                 "--out", str(out)]) == 0
    assert main(["diagnose", str(out), "--nuisance", "J", "--quiet"]) == 2
    assert "give none or a comma-separated subset of R, flux" in capsys.readouterr().err
    assert main(["diagnose", str(out), "--nuisance", "R,R", "--quiet"]) == 2
    assert main(["diagnose", str(out), "--nuisance", "R", "--budget", "400", "--quiet",
                 "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert set(d["nuisance"]) == {"R"} and d["verdict"] in ("healthy", "faulty", "unexplained")
