"""Readings a drive path could not see are left out of the trends (issue 32, item 2).

Identified from recorded voltages or current references, no position loop is modelled
and k8 (the drive's own gain drift) stays at its placeholder 0.5: the history keeps the
record (``extra["not_observable"]``), and the prognosis must not read the placeholders as
healthy readings that flatten a growing drift.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from emaphm.cli import main
from emaphm.faults import K_NOMINAL
from emaphm.prognosis.history import HealthHistory
from emaphm.prognosis.trends import Prognosis, prognose

TIMES = np.arange(8) * 100.0
#: k8 drifts from 0.5 to 0.78 over the history; inspections 2, 4 and 6 ran on recorded
#: voltages, where k8 is the placeholder 0.5
DRIFT = 0.5 + 0.04 * np.arange(8)
BLIND = (2, 4, 6)


def _K(placeholders: bool) -> np.ndarray:
    K = np.tile(K_NOMINAL, (TIMES.size, 1))
    K[:, 7] = DRIFT
    if placeholders:
        K[list(BLIND), 7] = 0.5
    return K


@pytest.fixture()
def db(tmp_path):
    path = tmp_path / "h.sqlite"
    with HealthHistory(path) as h:
        h.register("EMA-1")
        for i, (t, k) in enumerate(zip(TIMES, _K(placeholders=True))):
            blind = ["gain_drift"] if i in BLIND else []
            h.add("EMA-1", float(t), k, fingerprint=f"f{i}",
                  extra={"drive_model": "recorded voltages" if blind else "modelled controller",
                         "not_observable": blind})
    return path


def test_history_says_which_inspections_saw_each_mode(db):
    with HealthHistory(db, readonly=True) as h:
        data = h.data("EMA-1")
    obs = data.observed
    assert obs["gain_drift"].tolist() == [i not in BLIND for i in range(8)]
    assert all(obs[n].all() for n in obs if n != "gain_drift")


def test_trend_uses_the_readings_that_saw_the_mode(db):
    with HealthHistory(db, readonly=True) as h:
        data = h.data("EMA-1")
    masked = prognose(data.times, data.K, seed=3, observed=data.observed)
    clean = prognose(TIMES[[0, 1, 3, 5, 7]], _K(False)[[0, 1, 3, 5, 7]], seed=3)
    naive = prognose(data.times, data.K, seed=3)
    p, q = masked.predictions["gain_drift"], clean.predictions["gain_drift"]
    # the same readings give the same trend: the placeholders are not in it
    assert p.median == pytest.approx(q.median, rel=1e-9)
    assert p.model == q.model
    # the placeholders read as healthy would pull the drift down and push its failure out
    assert naive.predictions["gain_drift"].median > 1.2 * p.median
    # other indicators see every inspection
    np.testing.assert_array_equal(masked.predictions["friction"].samples,
                                  naive.predictions["friction"].samples)
    assert masked.unobserved == {"gain_drift": BLIND}
    t, y = masked.readings("gain_drift")
    assert t.tolist() == TIMES[[0, 1, 3, 5, 7]].tolist()
    np.testing.assert_allclose(y, DRIFT[[0, 1, 3, 5, 7]] - 0.5)


def test_too_few_seen_gives_no_prediction_and_round_trips():
    obs = {"gain_drift": np.array([True, False, False, True, False, False, False, False])}
    prog = prognose(TIMES, _K(False), seed=0, observed=obs)
    assert "gain_drift" not in prog.predictions and "friction" in prog.predictions
    back = Prognosis.from_dict(json.loads(json.dumps(prog.to_dict())))
    assert back.unobserved == prog.unobserved
    assert back.observed("gain_drift").tolist() == obs["gain_drift"].tolist()


@pytest.mark.parametrize("observed, match", [
    ({"gain": np.ones(8, bool)}, "unknown health indicator 'gain'"),
    ({"gain_drift": np.ones(5, bool)}, r"one entry per inspection \(8\)")])
def test_bad_masks_are_refused(observed, match):
    with pytest.raises(ValueError, match=match):
        prognose(TIMES, _K(False), seed=0, observed=observed)


def test_cli_says_what_it_left_out(db, capsys):
    assert main(["prognose", "EMA-1", "--db", str(db), "--seed", "1"]) == 0
    out = capsys.readouterr().out
    assert "gain_drift: not observable on 3 of 8 inspections" in out
    assert "trended on the other 5" in out
    assert main(["prognose", "EMA-1", "--db", str(db), "--seed", "1", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    # the flux was searched at none of them (data sheet's units): no demagnetization
    # series, which the table says only when it is asked for
    assert data["unobserved"] == {"gain_drift": list(BLIND)}
    assert "demagnetization" not in out
    assert main(["prognose", "EMA-1", "--db", str(db), "--indicator", "demagnetization"]) == 0
    assert "demagnetization: not measured at any of the 8 inspections" in capsys.readouterr().out


def test_the_level_now_is_the_last_reading_that_saw_the_mode(db):
    from emaphm.prognosis.thresholds import latest_values

    with HealthHistory(db, readonly=True) as h:
        data = h.data("EMA-1")
    now = latest_values(data.K, data.observed)
    assert now["gain_drift"] == pytest.approx(DRIFT[7] - 0.5)
    blind_last = {**data.observed, "gain_drift": np.array([True] * 3 + [False] * 5)}
    assert latest_values(data.K, blind_last)["gain_drift"] == pytest.approx(0.0)  # k8 = 0.5 at 2
    assert latest_values(data.K, {"gain_drift": np.zeros(8, bool)})["gain_drift"] == 0.0
    assert latest_values(data.K)["friction"] == 0.0
