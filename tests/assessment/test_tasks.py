"""One unit's work: a trace the diagnosis refuses is an outcome, and the measures the
thresholds are tuned on are what each mode compares."""

from dataclasses import replace

import numpy as np

from emaphm.assessment.tasks import _examine, measures_of
from emaphm.identify import IdentificationConfig
from emaphm.modes import THRESHOLDS_BY_FAULT_MODEL
from emaphm.params import siemens_1fk7060
from emaphm.simulate import DEFAULT_SENSORS, simulate


def test_a_refused_trace_is_an_outcome_with_its_reason():
    tr = simulate(model="monitoring", sensors=DEFAULT_SENSORS, seed=1)
    wired = replace(tr, i_abc=np.asarray(tr.i_abc) * [1, 1, -1])      # a phase inverted
    ex, out = _examine(wired, siemens_1fk7060(), IdentificationConfig())
    assert ex is None and out["verdict"] == "refused" and not out["right"]
    assert "do not sum to zero" in out["reason"] and out["cpu_s"] >= 0


def test_the_measures_are_what_each_threshold_is_compared_with():
    params = siemens_1fk7060()
    tr = simulate([0.06, 0, 0, 0, 0, 0, 0.5, 0.5], model="monitoring", sensors=DEFAULT_SENSORS,
                  seed=2)
    ex, out = _examine(tr, params, IdentificationConfig(), expected=(("friction", None),))
    m = measures_of(ex, params)
    assert set(m) == set(THRESHOLDS_BY_FAULT_MODEL["physical"].__dataclass_fields__)
    assert abs(m["friction"] - ex.identification.k[0]) < 1e-12
    assert m["friction"] > 0.05 and m["short_circuit"] < 0.01
    assert m["gain_drift"] == abs(ex.identification.k[7] - 0.5)
    # a data sheet: the flux and the sensors read beyond their production tolerance
    assert m["demagnetization"] < 0 and m["current_sensor_gain"] < 0
    # the friction of 1.12x is below the default threshold: healthy, not the expected fault
    assert out["verdict"] == "healthy" and not out["right"]
