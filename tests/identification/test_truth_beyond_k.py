"""Faults beyond the paper in the results (issue 34, item 9): the injected faults as data
in the trace's metadata, their true values beside k, and an error measure that covers them
(Eq. 9 extended), for the identification and for what the verdict was read on."""

from __future__ import annotations

import math

import numpy as np
import pytest

from emaphm.faults import K_NOMINAL, error_pct
from emaphm.problem import error_all_pct, true_nuisance
from emaphm.simulate import DEFAULT_SENSORS, simulate
from emaphm.verdict import examine


@pytest.fixture(scope="module")
def demag():
    return simulate(faults=["demagnetization:0.3"], sensors=DEFAULT_SENSORS, seed=1)


def test_the_injected_faults_are_data_in_the_metadata():
    t = simulate(faults=["current_sensor:b:gain:0.9", "short_circuit:a:0.1:0.05",
                         "demagnetization:0.2"], model="monitoring")
    a, b, c = t.meta["injected"]
    assert a == {"spec": "current_sensor:b:gain:0.9", "mode": "current_sensor", "k": {},
                 "plant": False, "sensor": {"phase": "B", "gain": 0.9, "offset_a": 0.0}}
    assert b["k"] == {"k3": 0.1} and b["plant"] and c["mode"] == "demagnetization"
    truth = true_nuisance(t)
    assert set(truth) == {"demag", "Rf_a"} and truth["demag"] == pytest.approx(-0.2)
    assert "truth" not in simulate(scenario="nominal", model="monitoring").meta


def test_the_error_covers_the_parameters_beside_k():
    k = K_NOMINAL.copy()
    assert error_all_pct(k, k, {}, {}) == 0.0
    assert error_all_pct(k, k, {"demag": -0.3}, {"demag": -0.3}) == 0.0
    # a lost flux not found: 0.3 of demag's range of 0.52, over sqrt(7.5)
    assert error_all_pct(k, k, {}, {"demag": -0.3}) == pytest.approx(100 * 0.3 / 0.52 / math.sqrt(7.5))
    k2 = k.copy()
    k2[0] = 0.1
    assert error_all_pct(k2, k, {}, {}) == pytest.approx(error_pct(k2, k))


def test_a_demagnetized_trace_reads_its_truth_and_the_verdict_its_error(demag):
    exam = examine(demag, seed=0)
    ident = exam.identification
    assert ident.nuisance_true == pytest.approx({"demag": -0.3})
    assert ident.error_all_pct is not None and ident.error_all_pct > ident.error_pct - 1e-9
    assert "demagnetization" in exam.diagnosis.modes
    assert exam.nuisance["demag"] == pytest.approx(-0.3, abs=0.02)   # the refit read it
    assert exam.error_all_pct < 3.0 < ident.error_all_pct
    np.testing.assert_array_equal(exam.k, exam.diagnosis.refit.k)
    d = ident.to_dict()
    assert d["nuisance_true"] == ident.nuisance_true and d["error_all_pct"] == ident.error_all_pct
