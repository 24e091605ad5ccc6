"""The whole prognosis loop with real identifications: simulate a growing fault on the
reference model, identify k (PSO, small budget), record each inspection, predict the
remaining useful life; the same through the CLI; the spread methods; the example
script. Few inspections and small budgets keep it to seconds per identification."""

from __future__ import annotations

import importlib.util
import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from support import assert_png_of

from emaphm.cli import main
from emaphm.fitness import Eq4Objective
from emaphm.identify import IdentificationConfig
from emaphm.prognosis import (HealthHistory, degradation_scenario, identify_with_spread,
                              inspection_times, prognose, simulate_degradation)
from emaphm.prognosis import record_inspection as inspect
from emaphm.problem import IdentificationProblem
from emaphm.traces import write_trace

FAST = {"config": IdentificationConfig(budget=1500)}   # lsq needs a few hundred
ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def run():
    sc = degradation_scenario("friction-growth")
    return simulate_degradation(sc, inspection_times(sc.eol, 5), seed=7)


def test_simulate_identify_record_prognose(run, tmp_path):
    sc = run.scenario
    with HealthHistory(tmp_path / "h.sqlite") as h:
        h.register("EMA-E2E", description="friction growing linearly")
        for t, trace in zip(run.times, run.traces):
            ins, a = inspect(h, "EMA-E2E", trace, float(t), seed=0, **FAST)
            k_true = sc.k_at(t)
            # small budget: the friction/backlash trade-off costs up to 0.03 at one inspection,
            # and the plant's Stribeck friction reads up to 0.04 high (measured 0.041)
            assert abs(ins.k[0] - k_true[0]) < 0.06, (t, ins.k, k_true)
            assert ins.k_lo[0] <= ins.k[0] <= ins.k_hi[0]
            assert ins.fingerprint and ins.spread_method == "population"
            assert ins.extra["error_pct"] < 3.0       # on the plant: measured up to 2.07 %
        data = h.data("EMA-E2E")
        assert data.n == 5 and h.integrity_check() == "ok"
    assert [i.healthy for i in data.inspections][-1] is False
    prog = prognose(data.times, data.K, seed=0, actuator="EMA-E2E")
    assert prog.first.indicator == "friction"
    p = prog.predictions["friction"]
    rul_true = sc.eol - data.times[-1]                        # 50 h
    # the plant's Stribeck friction reads 0.04-0.05 high at this friction level (the
    # monitoring model has only Coulomb friction): at this growth (5e-4 per hour) that is
    # 80-100 h of life early, so the prediction errs on the safe side, never late
    assert p.lo <= p.median <= p.hi
    assert rul_true - 110 <= p.median <= rul_true + 10, (p.lo, p.median, p.hi)
    # the same history, predicted again with the same seed: the same numbers
    again = prognose(data.times, data.K, seed=0).predictions["friction"]
    assert (again.median, again.lo, again.hi) == (p.median, p.lo, p.hi)


def test_cli_loop(run, tmp_path, capsys):
    db = str(tmp_path / "cli.sqlite")
    assert main(["history", "register", "EMA-CLI", "--db", db, "--description", "bench"]) == 0
    for t, trace in list(zip(run.times, run.traces))[2:]:
        path = write_trace(trace, tmp_path / f"insp-{t:.0f}.csv")
        rc = main(["history", "add", "EMA-CLI", str(path), "--at", f"{t}", "--db", db,
                   "--budget", "1500", "--quiet"])
        assert rc == 0
    out, _ = capsys.readouterr()
    assert "recorded inspection of EMA-CLI" in out and "FAULTY" in out
    # the same file again is refused, and so is a time in the past
    assert main(["history", "add", "EMA-CLI", str(path), "--at", "2000", "--db", db, "--quiet"]) == 2
    assert "already recorded" in capsys.readouterr().err
    rc = main(["prognose", "EMA-CLI", "--db", db, "--plot", str(tmp_path / "p.png"),
               "--threshold", "friction=0.45"])
    out, _ = capsys.readouterr()
    assert rc == 0 and "first to fail: friction" in out
    assert "model discrepancy" in out and "friction 5.3 %" in out   # what the interval carries
    assert_png_of(tmp_path / "p.png", (10, 3.2 * 1 + 0.6))  # one growing indicator: friction
    rc = main(["prognose", "EMA-CLI", "--db", db, "--json", "--indicator", "friction"])
    d = json.loads(capsys.readouterr().out)
    assert rc == 0 and d["thresholds"]["friction"] == 0.5 and d["n_inspections"] == 3
    assert set(d["predictions"]) == {"friction"}
    assert d["predictions"]["friction"]["discrepancy"] == 0.053


def test_spread_methods(run):
    trace = run.traces[2]
    obj = Eq4Objective.from_trace(trace)
    problem = IdentificationProblem(trace, objective=obj)     # the trace set up once
    PSO = IdentificationConfig("pso", options={"pop_size": 20})
    res = {}
    for method in ("population", "seeds", "bootstrap"):
        # budget 900: at 600 one of the two seeds' PSO runs stops above the misfit limit
        # (1.74x the floor) and "seeds" drops it
        a = identify_with_spread(problem, replace(PSO, budget=900), seed=1, method=method,
                                 n_runs=2)
        iv = a.interval
        assert np.all(iv.lo <= iv.k) and np.all(iv.k <= iv.hi)
        assert iv.details["n_eff"] > 0 and iv.method == method
        res[method] = a
    assert len(res["population"].runs) == 1
    assert len(res["seeds"].runs) == 2 and len(res["bootstrap"].runs) == 3
    assert res["bootstrap"].evaluations > res["population"].evaluations
    # the floor alone makes each interval at least as wide as the identification's error
    from emaphm.prognosis.uncertainty import IDENTIFICATION_ERROR_P90

    assert res["population"].interval.half_width[0] >= IDENTIFICATION_ERROR_P90[0] - 1e-12
    bare = identify_with_spread(problem, replace(PSO, budget=600), seed=1, error_floor=0.0)
    assert bare.interval.half_width[0] < res["population"].interval.half_width[0] + 1e-12
    ks = np.array(res["seeds"].interval.details["k_runs"])
    np.testing.assert_allclose(res["seeds"].k, np.median(ks, axis=0))
    assert np.all(res["seeds"].interval.lo <= ks.min(axis=0) + 1e-12)
    # an identification far above the trace's noise level is run again with a new seed
    assert 0.3 < res["population"].identification.fitness / obj.noise_floor() < 3.0
    weak = identify_with_spread(problem, IdentificationConfig("pso", options={"pop_size": 10},
                                                              budget=20, polish=False),
                                seed=1, retries=1)
    assert weak.interval.details["retries"] == 1 and len(weak.runs) == 1
    assert weak.interval.details["fitness_ratio"] > 5 and weak.interval.details["suspect"]
    with pytest.raises(ValueError, match="suspect_ratio"):
        identify_with_spread(trace, IdentificationConfig(suspect_ratio=0.5), seed=1)
    # the 0.3 keywords still work for one release, with a warning
    with pytest.warns(DeprecationWarning, match="0.3 spelling"), \
            pytest.raises(ValueError, match="suspect_ratio"):
        identify_with_spread(trace, seed=1, suspect_ratio=0.5)
    with pytest.raises(ValueError, match="unknown spread method"):
        identify_with_spread(trace, seed=1, method="jackknife")
    with pytest.raises(ValueError, match="explicit seed"):
        identify_with_spread(trace, seed=None)


def test_demo_degradation_into_a_history_says_so_and_refuses_a_repeat(capsys, tmp_path):
    """--db of a history that holds other actuators: the demo's is added, and said; the same
    demo again is refused before any work, with a fix that works (it said 'already
    registered: record its inspections with emaphm history add')."""
    from emaphm.prognosis.history import HealthHistory

    db = tmp_path / "fleet.sqlite"
    with HealthHistory(db) as h:
        h.register("EMA-1")
    argv = ["demo-degradation", "--scenario", "gain-drift", "--synthetic", "--inspections", "5",
            "--db", str(db), "--json"]
    assert main(argv) == 0
    assert f"adding demo-gain-drift-0 to {db}, beside its 1 actuator(s)" in capsys.readouterr().err
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "holds demo-gain-drift-0 already" in err and "--seed" in err
    assert main(argv + ["--seed", "1"]) == 0
    with HealthHistory(db, readonly=True) as h:
        assert [a.id for a in h.actuators()] == ["EMA-1", "demo-gain-drift-0", "demo-gain-drift-1"]
    (tmp_path / "empty.sqlite").touch()                  # mktemp's: a new history, not refused
    assert main(argv[:-3] + ["--db", str(tmp_path / "empty.sqlite"), "--json"]) == 0


def test_demo_degradation_cli_synthetic(capsys, tmp_path):
    out = tmp_path / "new" / "figures"          # created where missing
    rc = main(["demo-degradation", "--scenario", "gain-drift", "--synthetic", "--inspections", "10",
               "--json", "--plot-dir", str(out)])
    d = json.loads(capsys.readouterr().out)
    assert rc == 0 and d[0]["coverage_from_midlife"] >= 0.8
    assert sorted(p.name for p in out.iterdir()) == ["gain-drift-alpha-lambda.png",
                                                   "gain-drift-prognosis.png"]
    assert_png_of(out / "gain-drift-alpha-lambda.png", (7, 4.5))
    assert_png_of(out / "gain-drift-prognosis.png", (10, 3.8))
    assert main(["demo-degradation", "--scenario", "rust"]) == 2
    (tmp_path / "afile").write_text("x")
    assert main(["demo-degradation", "--synthetic", "--plot-dir", str(tmp_path / "afile")]) == 2
    assert "is a file, not a folder" in capsys.readouterr().err


def test_example_script_runs(tmp_path):
    spec = importlib.util.spec_from_file_location("degradation_demo",
                                                  ROOT / "examples" / "degradation_demo.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    result = mod.main(["--synthetic", "--inspections", "10", "--out-dir", str(tmp_path),
                       "--scenario", "short-circuit-growth"])
    assert result["coverage_from_midlife"] >= 0.6
    errs = [e for e in result["abs_error"] if e is not None and math.isfinite(e)]
    assert errs[-1] < errs[0]
    assert len(list(tmp_path.glob("*.png"))) == 3


def test_the_table_says_when_a_trend_is_read_beyond_k_1(tmp_path, capsys):
    """``emaphm prognose --at`` far past the inspections reads a friction trend at a k
    above 1: the row stays, and a line under the table says it is extrapolated."""
    db = str(tmp_path / "h.sqlite")
    with HealthHistory(db) as h:
        h.register("EMA-X")
        for t in (0.0, 100.0, 200.0, 300.0, 400.0, 500.0):
            h.add("EMA-X", t, [8e-4 * t + 0.002 * (t % 200 == 0), 0, 0, 0, 0, 0, 0.5, 0.5])
    assert main(["prognose", "EMA-X", "--db", db, "--indicator", "friction"]) == 0
    assert "extrapolated" not in capsys.readouterr().out
    assert main(["prognose", "EMA-X", "--db", db, "--indicator", "friction", "--at", "1500",
                 "--json"]) == 0
    d = json.loads(capsys.readouterr().out)["predictions"]["friction"]
    assert d["current"] > 1.1 and d["extrapolated"].startswith("extrapolated beyond k = 1")
    assert main(["prognose", "EMA-X", "--db", db, "--indicator", "friction", "--at", "1500"]) == 0
    out = capsys.readouterr().out
    assert f"friction: extrapolated beyond k = 1: the trend is at {d['current']:.3g} at 1500" in out
