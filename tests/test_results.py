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


# ----------------------------------------------------------------------------- the rest of item 5
@pytest.fixture(scope="module")
def examined(trace):
    from emaphm.verdict import examine

    return examine(trace, config=IdentificationConfig("pso", budget=400), seed=0, loops=False)


def test_examination(examined):
    from emaphm.traces import fingerprint
    from emaphm.verdict import Examination

    back = assert_round_trip(examined)
    assert back.trace is None and back.trace_fingerprint == fingerprint(examined.trace)
    np.testing.assert_array_equal(back.identification.k, examined.identification.k)
    np.testing.assert_array_equal(back.k, examined.k)
    assert back.diagnosis.verdict == examined.diagnosis.verdict
    assert back.diagnosis.faults == examined.diagnosis.faults
    assert back.sensor == examined.sensor
    assert back.nuisance == examined.nuisance and back.error_all_pct == examined.error_all_pct
    again = Examination.from_dict(back.to_dict())      # read back twice: the same fingerprint
    assert again.to_dict() == examined.to_dict()


def test_sensor_finding(examined, trace):
    from dataclasses import replace

    from emaphm.modes import DEFAULT_THRESHOLDS
    from emaphm.modes.current_sensor import SensorFinding, screen
    from emaphm.traces.zero_sum import best_fit

    assert examined.sensor.fit is not None
    assert assert_round_trip(examined.sensor) == examined.sensor
    faulty = replace(trace, i_abc=trace.i_abc * np.array([1.0, 0.8, 1.0]))    # B reads 0.8
    found = screen(faulty, None, DEFAULT_THRESHOLDS)
    assert found.gain_fault and found.phase == 1 and assert_round_trip(found) == found
    placed = SensorFinding(True, best_fit(trace.i_abc), False, True).placed(2)
    assert assert_round_trip(placed) == placed
    assert assert_round_trip(SensorFinding(observable=False)) == SensorFinding(observable=False)
    old = {k: v for k, v in placed.to_dict().items() if k != "fit"}      # an older record
    assert SensorFinding.from_dict(old).fit is None


def test_unit():
    from emaphm.units import Unit, draw_unit, nominal_unit

    for unit in (draw_unit(siemens_1fk7060(), 5), nominal_unit(siemens_1fk7060(), load=0.3)):
        back = Unit.from_dict(json.loads(json.dumps(unit.to_dict(params=True))))
        assert back == unit and back.to_dict(params=True) == unit.to_dict(params=True)
        assert Unit.from_dict(through_json(unit), params=unit.params) == unit
    with pytest.raises(ValueError, match="without its parameters"):
        Unit.from_dict(through_json(unit))


def test_history_records(tmp_path):
    from emaphm.prognosis import HealthHistory
    from emaphm.prognosis.history import Actuator, RemovedInspection, SkippedInspection

    with HealthHistory(tmp_path / "h.sqlite") as h:
        act = h.register("EMA-1", description="left aileron", time_unit="cycles")
        h.add("EMA-1", 10.0, np.full(8, 0.1), diagnosis={"verdict": "healthy"})
        h.add("EMA-1", 20.0, np.full(8, 0.2), diagnosis={"verdict": "healthy"})
        listed = h.actuator("EMA-1")
        removed = h.remove("EMA-1", at=20.0)
    for a in (act, listed):
        assert assert_round_trip(a) == a
    assert listed.n_inspections == 2 and listed.last_time == 20.0
    assert assert_round_trip(removed) == removed and removed.verdict == "healthy"
    skipped = SkippedInspection(3, "EMA-1", math.nan, None, "its time is not a number")
    back = assert_round_trip(skipped)
    assert math.isnan(back.time) and back.reason == skipped.reason
    assert RemovedInspection and Actuator


def test_policy_run():
    from emaphm.prognosis import DegradationLaw, DegradationScenario
    from emaphm.prognosis.inspection import PolicyRun, simulate_policy

    law = DegradationLaw.reaching("linear", 0.5, 1000.0, onset=100.0)
    sc = DegradationScenario("friction", law)
    run = simulate_policy(sc, InspectionPolicy(risk=0.1), seed=4, discrepancy={})
    healthy = simulate_policy(None, InspectionPolicy(risk=0.1), seed=4, horizon=600.0)
    assert run.flagged_at is not None and healthy.eol == math.inf
    for r in (run, healthy):
        back = assert_round_trip(r)
        np.testing.assert_array_equal(back.times, r.times)
        assert (back.rules, back.risks, back.flagged_at, back.missed, back.planned, back.eol) \
            == (r.rules, r.risks, r.flagged_at, r.missed, r.planned, r.eol)
        assert back.expected_misses == r.expected_misses
    assert PolicyRun.from_dict(run.to_dict()).to_dict() == run.to_dict()


def test_degradation_scenario_and_law():
    from emaphm.prognosis import DEGRADATION_SCENARIOS, DegradationLaw, DegradationScenario
    from emaphm.prognosis.thresholds import FailureThresholds

    for sc in DEGRADATION_SCENARIOS.values():
        assert assert_round_trip(sc) == sc and assert_round_trip(sc.law) == sc.law
    own = DegradationScenario("short_circuit_b", DegradationLaw("power", 1e-7, 0.01, 2.5, 40.0),
                              k_base=[0.1] + [0.0] * 5 + [0.5, 0.5], name="own",
                              thresholds=FailureThresholds(short_circuit=0.2, friction=0.4))
    back = assert_round_trip(own)
    assert back == own and back.eol == own.eol
    assert "thresholds" not in DEGRADATION_SCENARIOS["gain-drift"].to_dict()


def test_demo_unit():
    from emaphm.fleet.demo import demo_fleet

    units = demo_fleet(4, seed=0, synthetic=True)
    assert any(u.scenario is None for u in units) and any(u.scenario for u in units)
    for u in units:
        back = assert_round_trip(u)
        assert back == u and back.eol == u.eol
        np.testing.assert_array_equal(back.k_true(), u.k_true())


def test_schedule_row(tmp_path):
    import datetime as dt

    from emaphm.fleet.demo import demo_fleet, record_demo_fleet
    from emaphm.fleet.schedule import Calendar, schedule

    record_demo_fleet(tmp_path / "h.sqlite", demo_fleet(4, seed=0, synthetic=True),
                      synthetic=True)
    dated = schedule(tmp_path / "h.sqlite", calendar=Calendar(dt.date(2026, 1, 5), 8.0))
    plain = schedule(tmp_path / "h.sqlite")
    assert dated[0].date is not None and plain[0].date is None
    for row in dated + plain:
        assert assert_round_trip(row) == row


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


def test_save_and_load_the_other_kinds(tmp_path, examined):
    from emaphm.campaign import AlgorithmSpec, CampaignSpec, RunResult, ScenarioSpec
    import datetime as dt

    from emaphm.fleet.demo import demo_fleet
    from emaphm.fleet.schedule import ScheduleRow
    from emaphm.prognosis import DEGRADATION_SCENARIOS
    from emaphm.prognosis.history import Actuator, RemovedInspection, SkippedInspection
    from emaphm.prognosis.inspection import simulate_policy
    from emaphm.units import draw_unit

    sc = DEGRADATION_SCENARIOS["friction-growth"]
    spec = CampaignSpec(scenarios=("gain-low",), algorithms=("pso",), runs=1)
    run = RunResult.failure(spec.runs_list()[0], "ValueError: a test")
    objs = [examined, examined.sensor, draw_unit(siemens_1fk7060(), 1),
            Actuator("EMA-1", "", "h", "2026-01-01T00:00:00+00:00", 2, 20.0),
            SkippedInspection(1, "EMA-1", 5.0, None, "k is not finite"),
            RemovedInspection(2, "EMA-1", 20.0, None, "healthy", "a.csv"),
            simulate_policy(None, InspectionPolicy(risk=0.1), seed=0, horizon=600.0),
            sc, sc.law, demo_fleet(1, seed=0, synthetic=True)[0], spec,
            ScenarioSpec.named("gain-low"), AlgorithmSpec("de", "de-20", {"pop_size": 20}), run,
            ScheduleRow("EMA-1", "rudder", 320.5, "h", dt.date(2026, 2, 1), False, "risk",
                        "friction", 0.05, 0.05, "the risk", 300.0, 4, "actuators/x.html")]
    for i, obj in enumerate(objs):
        back = results.load(results.save(obj, tmp_path / f"r{i}.json"))
        assert type(back) is type(obj) and back.to_dict() == obj.to_dict(), type(obj).__name__
    unit = objs[2]
    assert results.load(tmp_path / "r2.json") == unit          # saved with its parameters
    assert results.loads(results.dumps([unit, unit])) == [unit, unit]
    assert {results.kind_of(o) for o in objs} == {
        "examination", "sensor_finding", "unit", "actuator", "skipped_inspection",
        "removed_inspection", "policy_run", "degradation_scenario", "degradation_law",
        "demo_unit", "campaign_spec", "scenario_spec", "algorithm_spec", "run_result",
        "schedule_row"}


def test_sensors_and_the_assessments_records(trace):
    from emaphm.acquisition import Sensors
    from emaphm.assessment.spec import AssessmentSpec, Case, cases
    from emaphm.assessment.stats import Proportion, proportion
    from emaphm.assessment.tuning import TunedThreshold, tune_thresholds
    from emaphm.modes import DEFAULT_THRESHOLDS

    recorded = Sensors.from_dict(trace.meta["sensors"])        # as the trace was recorded
    assert recorded == DEFAULT_SENSORS and assert_round_trip(recorded) == recorded
    chain = Sensors(0.01, 0.005, 4096, (1.0, 0.97, 1.0), (0.0, 0.02, 0.0), 20e3, 2, 4e3)
    assert assert_round_trip(chain) == chain
    assert assert_round_trip(proportion(3, 10)) == proportion(3, 10)
    assert math.isnan(assert_round_trip(proportion(0, 0)).rate)
    spec = AssessmentSpec(siemens_1fk7060().to_dict(), units=1, tune_units=1, healthy=2)
    made = cases(spec, 0)
    assert made
    for case in made:
        assert assert_round_trip(case) == case
    rng = np.random.default_rng(0)
    readings = [{"friction": float(x)} for x in rng.normal(0.02, 0.01, 200)]
    for tuned in tune_thresholds(readings, 0.01, DEFAULT_THRESHOLDS).values():
        back = assert_round_trip(tuned)
        assert back.to_dict().keys() == tuned.to_dict().keys() and type(back) is TunedThreshold
    for obj in (chain, proportion(3, 10), made[0], tuned):     # NaN where no unit was tuned
        assert results.dumps(results.loads(results.dumps(obj))) == results.dumps(obj)
    assert Proportion and Case
