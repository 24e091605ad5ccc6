"""The health indicators as the fault modes declare them (emaphm.modes.Indicator): the
prognosis layer reads them from the registry, an indicator beyond k is stored with each
inspection (NULL where not measured), and older names keep working with a warning."""

import json
import sqlite3
import warnings

import numpy as np
import pytest

from emaphm import modes
from emaphm.prognosis import history as hist
from emaphm.prognosis.history import HealthHistory
from emaphm.prognosis.thresholds import (DEFAULT_FAILURE_THRESHOLDS, INDICATOR_COMPONENT,
                                         INDICATORS, FailureThresholds, latest_values)
from emaphm.prognosis.trends import INDICATOR_BOUNDS, MODEL_DISCREPANCY, prognose

K0 = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5, 0.5]


def test_the_prognosis_vocabulary_is_the_registry_s():
    assert INDICATORS == tuple(modes.INDICATORS)
    # the paper's k first, in its order, so that each indicator's seed (spawned in this
    # order) is what it was before the indicators beyond k came
    assert INDICATORS[:7] == ("friction", "backlash", "short_circuit_a", "short_circuit_b",
                              "short_circuit_c", "eccentricity", "gain_drift")
    for name, ind in modes.INDICATORS.items():
        assert modes.INDICATOR_MODE[name] in modes.MODES
        assert ind in modes.MODES[modes.INDICATOR_MODE[name]].indicators
        assert DEFAULT_FAILURE_THRESHOLDS.for_indicator(name) == ind.failure
        assert MODEL_DISCREPANCY[name] == ind.discrepancy > 0
        assert INDICATOR_BOUNDS[name] == ind.bounds
    # every mode a prognosis can fail on has a field, none more
    assert set(FailureThresholds.__dataclass_fields__) == {
        i.threshold for i in modes.INDICATORS.values()}
    assert INDICATOR_COMPONENT == {n: i.component for n, i in modes.INDICATORS.items()
                                   if i.component is not None}


def test_an_older_indicator_name_works_with_a_deprecation_warning():
    with pytest.warns(DeprecationWarning, match="short_circuit_a"):
        assert modes.indicator_name("short_a") == "short_circuit_a"
    with pytest.warns(DeprecationWarning):
        assert DEFAULT_FAILURE_THRESHOLDS.for_indicator("short_b") == 0.3
    with pytest.warns(DeprecationWarning):
        assert FailureThresholds().with_updates({"short_c": 0.2}).short_circuit == 0.2
    t = np.arange(5.0) * 100
    K = np.tile(K0, (5, 1))
    K[:, 2] = 0.02 * np.arange(5)
    with pytest.warns(DeprecationWarning):
        p = prognose(t, K, seed=1, indicators=["short_a"])
    assert list(p.predictions) == ["short_circuit_a"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        new = prognose(t, K, seed=1, indicators=["short_circuit_a"])
    assert new.predictions["short_circuit_a"].median == p.predictions["short_circuit_a"].median
    # a prognosis written before the rename reads back under the new name
    d = new.to_dict()
    d["predictions"] = {"short_a": {**d["predictions"]["short_circuit_a"], "indicator": "short_a"}}
    with pytest.warns(DeprecationWarning):
        back = type(new).from_dict(d)
    assert back.predictions["short_circuit_a"].indicator == "short_circuit_a"
    with pytest.raises(ValueError, match="unknown health indicator 'short_d'"):
        modes.indicator_name("short_d")


def test_a_reading_beyond_k_is_trended_over_the_inspections_that_measured_it():
    t = np.arange(8.0) * 100.0
    K = np.tile(K0, (8, 1))
    loss = 0.02 + 0.02 * np.arange(8)                 # 2 % of the flux more every 100 h
    loss[[1, 4]] = np.nan                             # two inspections did not measure it
    p = prognose(t, K, seed=3, readings={"demagnetization": loss})
    pred = p.predictions["demagnetization"]
    assert p.unobserved["demagnetization"] == (1, 4)
    # the straight line crosses 0.2 at t = 900 h: 200 h after the last inspection
    assert 150 < pred.median < 260 and pred.lo < 200 < pred.hi
    tt, yy = p.readings("demagnetization")
    assert tt.tolist() == [0, 200, 300, 500, 600, 700] and np.allclose(yy, loss[np.isfinite(loss)])
    # without readings it has no prediction; the others are unchanged by it
    q = prognose(t, K, seed=3)
    assert "demagnetization" not in q.predictions
    assert q.predictions["friction"].median == p.predictions["friction"].median
    back = type(p).from_dict(json.loads(json.dumps(p.to_dict())))
    assert np.array_equal(np.isnan(back.beyond_k["demagnetization"]), np.isnan(loss))
    assert latest_values(K, readings={"demagnetization": loss})["demagnetization"] == loss[-1]
    with pytest.raises(ValueError, match="read from k"):
        prognose(t, K, seed=3, readings={"friction": loss})
    with pytest.raises(ValueError, match="one entry per inspection"):
        prognose(t, K, seed=3, readings={"demagnetization": loss[:3]})


def _diag(nuisance=None, refit=None):
    return {"healthy": True, "verdict": "healthy", "faults": [],
            "hypothesis_check": None if refit is None else {
                "mode": "demagnetization", "k": K0, "nuisance": refit, "fit_ratio": 1.1}}


def test_the_flux_loss_is_read_from_the_refit_or_the_identification_s_drift():
    def read(d, e):
        return modes.indicator_readings(d, e)["demagnetization"]

    assert read(_diag(), {"nuisance": {"R": 0.01, "flux": -0.03}}) == 0.03
    assert read(_diag(refit={"R": 0.0, "demag": -0.12}), {"nuisance": {"flux": -0.06}}) == 0.12
    # a data sheet's unit searched no flux: not measured, which is not healthy
    assert read(_diag(), {"nuisance": {}}) is None
    assert read(None, None) is None
    assert read({"hypothesis_check": "garbage"}, {"nuisance": {"flux": "x"}}) is None
    # every indicator beyond k has its entry, None where not measured
    assert set(modes.indicator_readings(None, None)) == {
        n for n, i in modes.INDICATORS.items() if i.reading is not None}


def _store(path, n=4):
    with HealthHistory(path) as h:
        h.register("EMA-D")
        for i in range(n):
            h.add("EMA-D", 100.0 * i, K0, diagnosis=_diag(),
                  extra={"nuisance": {"flux": -0.01 * i}} if i != 2 else {})
    return path


def test_the_history_stores_the_readings_and_null_where_none_was_measured(tmp_path):
    db = _store(tmp_path / "h.sqlite")
    con = sqlite3.connect(db)
    stored = [json.loads(r[0]) for r in con.execute("SELECT readings FROM inspections ORDER BY time")]
    con.close()
    assert [r["demagnetization"] for r in stored] == [0.0, 0.01, None, 0.03]
    assert stored[0]["current_sensor_gain_a"] is None          # NULL: not measured
    with HealthHistory(db, readonly=True) as h:
        data = h.data("EMA-D")
        assert h.inspections("EMA-D")[3].readings["demagnetization"] == 0.03
    # a series for each indicator measured once at least
    assert list(data.readings) == ["demagnetization"]
    r = data.readings["demagnetization"]
    assert np.isnan(r[2]) and np.allclose(r[[0, 1, 3]], [0.0, 0.01, 0.03])
    with HealthHistory(db) as h:
        with pytest.raises(hist.HistoryError, match="beyond k"):
            h.add("EMA-D", 500.0, K0, readings={"friction": 0.1})
        with pytest.raises(hist.HistoryError, match="finite number or None"):
            h.add("EMA-D", 500.0, K0, readings={"demagnetization": float("nan")})
        assert h.add("EMA-D", 500.0, K0, readings={"demagnetization": 0.05}).readings == \
            {"demagnetization": 0.05}


def test_a_schema_2_history_is_read_and_migrated_with_its_readings(tmp_path):
    db = _store(tmp_path / "old.sqlite")
    con = sqlite3.connect(db)
    con.execute("ALTER TABLE inspections DROP COLUMN readings")
    con.execute("PRAGMA user_version = 2")
    con.commit()
    con.close()
    with HealthHistory(db, readonly=True) as h:         # read as it is: from the diagnoses
        r = h.data("EMA-D").readings["demagnetization"]
    assert np.isnan(r[2]) and np.allclose(r[[0, 1, 3]], [0.0, 0.01, 0.03])
    assert sqlite3.connect(db).execute("PRAGMA user_version").fetchone()[0] == 2
    with HealthHistory(db) as h:                        # a writing open migrates it
        assert np.allclose(h.data("EMA-D").readings["demagnetization"], r, equal_nan=True)
    con = sqlite3.connect(db)
    assert con.execute("PRAGMA user_version").fetchone()[0] == hist.SCHEMA_VERSION == 3
    assert json.loads(con.execute("SELECT readings FROM inspections WHERE time = 200")
                      .fetchone()[0])["demagnetization"] is None
    con.close()


def test_the_cli_takes_an_older_indicator_name_and_says_so(tmp_path, capsys):
    from emaphm.cli import main

    db = tmp_path / "h.sqlite"
    with HealthHistory(db) as h:
        h.register("EMA-S")
        for i in range(4):
            h.add("EMA-S", 100.0 * i, [0, 0, 0.03 * i, 0, 0, 0, 0.5, 0.5])
    assert main(["prognose", "EMA-S", "--indicator", "short_a", "--json", "--db", str(db)]) == 0
    out, err = capsys.readouterr()
    assert "now called short_circuit_a" in err
    assert list(json.loads(out)["predictions"]) == ["short_circuit_a"]
    with pytest.raises(SystemExit):
        main(["prognose", "EMA-S", "--indicator", "short_d", "--db", str(db)])
    assert "demagnetization" in capsys.readouterr().err
