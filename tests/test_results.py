"""Every result that has ``to_dict`` reads back with ``from_dict``, exactly, through JSON
(issue 34), and :mod:`emaphm.results` saves and loads each kind the one documented way.

Exact: ``from_dict(json(x.to_dict())).to_dict() == x.to_dict()``, and the arrays and
numbers of the result are the same bit for bit (JSON keeps every digit of a float).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from emaphm import results
from emaphm.calibration import CalibrationResult
from emaphm.diagnosis import Diagnosis
from emaphm.identify import Identification, IdentificationConfig, identify
from emaphm.params import load_params, siemens_1fk7060
from emaphm.prognosis import (IdentificationSpread, InspectionPolicy, KInterval, NextInspection,
                              Prognosis, RULPrediction, RULTrack, degradation_scenario,
                              identify_with_spread, inspection_times, next_inspection, rul_track,
                              synthetic_k_history)
from emaphm.simulate import DEFAULT_SENSORS, simulate
from emaphm.verdict import diagnose_identification


def through_json(obj):
    return json.loads(json.dumps(obj.to_dict()))


def assert_round_trip(obj, cls=None):
    cls = cls or type(obj)
    back = cls.from_dict(through_json(obj))
    assert type(back) is type(obj)
    assert json.dumps(back.to_dict(), sort_keys=True) == json.dumps(obj.to_dict(), sort_keys=True)
    return back


@pytest.fixture(scope="module")
def trace():
    return simulate(scenario="turn-short-15pct", sensors=DEFAULT_SENSORS, seed=3)


@pytest.fixture(scope="module")
def ident(trace):
    return identify(trace, IdentificationConfig("pso", budget=800), seed=0)


@pytest.fixture(scope="module")
def history():
    sc = degradation_scenario("friction-growth")
    times = inspection_times(sc.eol, 6)
    return times, synthetic_k_history(sc, times, seed=2)


@pytest.fixture(scope="module")
def planned(history):
    times, K = history
    return next_inspection(times, K, seed=1, policy=InspectionPolicy(risk=0.1), n_samples=500)


def test_identification(ident):
    back = assert_round_trip(ident)
    for name in ("k", "history", "k_raw", "k_true"):
        np.testing.assert_array_equal(getattr(back, name), getattr(ident, name))
    assert back.fitness == ident.fitness and back.config == ident.config
    assert back.params == ident.params and back.model_trace is None


def test_identification_config():
    c = IdentificationConfig("pso", options={"pop_size": 12}, budget="30s", nuisance=("R",))
    assert IdentificationConfig.from_dict(through_json(c)) == c


def test_diagnosis(trace, ident):
    diag = diagnose_identification(trace, ident)
    back = assert_round_trip(diag)
    np.testing.assert_array_equal(back.k, diag.k)
    assert back.verdict == diag.verdict and back.faults == diag.faults
    assert [f.details for f in back.faults] == [dict(f.details) for f in diag.faults]
    frame = diag.to_frame()
    assert list(frame["mode"]) == [f.mode for f in diag.faults] + [f.mode for f in diag.suspected]


def test_calibration_result():
    cal = siemens_1fk7060()
    from dataclasses import replace

    cal = replace(cal, calibration=replace(cal.calibration, date="2024-05-01T00:00:00+00:00",
                                           sources=("a.csv",)))
    res = CalibrationResult(params=cal, estimates={"R": {"value": 0.0123, "se": 0.001,
                                                         "lo95": 0.0103, "hi95": 0.0143,
                                                         "unit": "1"}},
                            fixed=("J",), correlated=(("flux", "J", 0.97),),
                            weak=(("K_c", 0.12),), fit_ratio={"a.csv": 1.07}, evaluations=321,
                            elapsed_s=1.5, params_source="trace")
    back = assert_round_trip(res)
    assert back == res


def test_spread_and_its_interval(trace):
    spread = identify_with_spread(trace, IdentificationConfig("pso", budget=600), seed=0)
    back = assert_round_trip(spread)
    np.testing.assert_array_equal(back.k, spread.k)
    np.testing.assert_array_equal(back.interval.lo, spread.interval.lo)
    assert_round_trip(spread.interval)
    frame = spread.to_frame()
    assert list(frame["component"]) == [f"k{i}" for i in range(1, 9)]
    np.testing.assert_array_equal(frame["hi"].to_numpy(), spread.interval.hi)


def test_prognosis_and_its_predictions(planned):
    prog, _ = planned
    back = assert_round_trip(prog)
    np.testing.assert_array_equal(back.times, prog.times)
    np.testing.assert_array_equal(back.K, prog.K)
    assert back.first.indicator == prog.first.indicator
    for name, p in prog.predictions.items():
        q = back.predictions[name]
        assert (q.median, q.lo, q.hi, q.p_reach) == (p.median, p.lo, p.hi, p.p_reach)
    full = Prognosis.from_dict(json.loads(json.dumps(prog.to_dict(samples=True))))
    p, q = prog.first, full.predictions[prog.first.indicator]
    np.testing.assert_array_equal(q.samples, p.samples)
    assert q.p_fail_within(100.0) == p.p_fail_within(100.0)
    frame = prog.to_frame()
    assert list(frame["indicator"]) == list(prog.predictions)
    assert_round_trip(p, RULPrediction)


def test_rul_track(history):
    times, K = history
    track = rul_track(times, K[:, 0], 0.5, seed=0, indicator="friction", n_samples=300)
    back = assert_round_trip(track)
    np.testing.assert_array_equal(back.median, track.median)
    assert list(track.to_frame()["time"]) == list(track.times)


def test_next_inspection_and_policy(planned):
    _, plan = planned
    back = assert_round_trip(plan)
    assert back == plan
    policy = InspectionPolicy(risk=0.02, max_interval=500.0)
    assert InspectionPolicy.from_dict(through_json(policy)) == policy
    never = NextInspection(at=10.0, risk=None, indicator=None, reason="x", rule="healthy",
                           target=0.05, t_now=1.0, t_last=1.0, intervals=plan.intervals,
                           t_star=math.inf)
    assert NextInspection.from_dict(through_json(never)).t_star == math.inf


def test_save_and_load_every_kind(tmp_path, ident, planned, trace):
    prog, plan = planned
    for i, obj in enumerate([ident, ident.config, prog, plan, siemens_1fk7060(),
                             prog.first, KInterval(np.zeros(8), np.zeros(8), np.ones(8), "seeds",
                                                   0.9, 3)]):
        path = results.save(obj, tmp_path / f"r{i}.json")
        back = results.load(path)
        assert type(back) is type(obj) and back.to_dict() == obj.to_dict()
    both = results.loads(results.dumps([ident, ident]))
    assert [b.to_dict() for b in both] == [ident.to_dict()] * 2
    with pytest.raises(TypeError, match="not an emaphm result"):
        results.dumps(trace)
    with pytest.raises(ValueError, match="not an emaphm result"):
        results.loads('{"emaphm_result": "mystery", "data": {}}')
    assert isinstance(results.load(results.save(load_params(
        results.Path(__file__).resolve().parents[1] / "examples/actuators/ema-270v-750w.toml"),
        tmp_path / "p.json")), type(siemens_1fk7060()))
    assert Identification.from_dict(ident.to_dict()).to_dict() == ident.to_dict()
    assert IdentificationSpread and Diagnosis        # the classes the kinds name


def test_a_history_record_and_the_alpha_lambda_metric(tmp_path, history, trace):
    from emaphm.prognosis import HealthHistory, Inspection, alpha_lambda

    with HealthHistory(tmp_path / "h.sqlite") as h:
        h.register("EMA-1")
        ins = h.add("EMA-1", 10.0, np.full(8, 0.1), diagnosis={"verdict": "healthy"},
                    extra={"fault_model": "physical", "x": [1, 2]})
    back = assert_round_trip(ins)
    np.testing.assert_array_equal(back.k, ins.k)
    assert back.fault_model == "physical" and back.extra == ins.extra
    assert Inspection.from_dict(ins.to_dict()).to_dict() == ins.to_dict()
    times, _ = history
    samples = np.tile(np.linspace(400.0, 600.0, 50), (len(times), 1))
    al = alpha_lambda(times, samples, eol=1000.0 + times[0])
    back = assert_round_trip(al)
    np.testing.assert_array_equal(back.passed, al.passed)
    assert back.score == al.score


def test_campaign_specs():
    from emaphm.campaign import AlgorithmSpec, CampaignSpec, ScenarioSpec

    custom = ScenarioSpec.custom("mine", [0.1] * 7 + [0.5], magnitude="x", fault_model="paper")
    spec = CampaignSpec(scenarios=("friction-low", "multiple", custom),
                        algorithms=(AlgorithmSpec("pso", "pso-30", {"pop_size": 30}, budget=500),
                                    "de"),
                        runs=2, master_seed=7, budget="30s", params=siemens_1fk7060(),
                        name="small")
    back = assert_round_trip(spec)
    assert back == spec and back.hash == spec.hash
    for s in spec.scenarios:
        assert assert_round_trip(s) == s
    for a in spec.algorithms:
        assert assert_round_trip(a) == a
    every_physical = CampaignSpec(fault_model="physical")
    assert assert_round_trip(every_physical) == every_physical


def test_run_result():
    from dataclasses import replace

    from emaphm.campaign import AlgorithmSpec, CampaignSpec, RunResult
    from emaphm.campaign.runner import execute_run

    spec = CampaignSpec(scenarios=("friction-high",), algorithms=(AlgorithmSpec("pso"),),
                        runs=1, budget=200, polish=False)
    run = spec.runs_list()[0]
    ok = execute_run(run)
    failed = execute_run(replace(run, k_true=(2.0,) * 8))
    assert ok.ok and failed.status == "failed" and failed.error_text
    for r in (ok, failed):
        back = assert_round_trip(r)
        assert back == r and back.outcome() == r.outcome()
    assert RunResult.from_dict(ok.to_dict()) == ok
    with pytest.raises(ValueError, match="unknown field"):
        RunResult.from_dict({**ok.to_dict(), "colour": "red"})
