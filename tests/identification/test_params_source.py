"""Which actuator a trace is identified on (issue 34): parameters given, then a history's
calibration of the unit, then the trace's own (its metadata's ``"parameters"``), then the
preset (:func:`emaphm.params.resolve_params`); the result says which, and parameters
given for a trace of another actuator warn.

A trace simulated with the preset carries the preset's parameters: identified with them by
default, its numbers are those of an identification with the preset given, bit for bit
(the same :class:`ActuatorParams`, so the golden file of ``test_golden.py`` holds).
"""

from __future__ import annotations

import json
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from emaphm.identify import identify
from emaphm.params import (ActuatorMismatchWarning, ActuatorParams, ParameterError, as_params,
                           load_params, resolve_params, siemens_1fk7060)
from emaphm.problem import IdentificationProblem
from emaphm.simulate import DEFAULT_SENSORS, simulate
from emaphm.verdict import diagnose_identification

ROOT = Path(__file__).resolve().parents[2]
EMA270 = ROOT / "examples" / "actuators" / "ema-270v-750w.toml"


@pytest.fixture(scope="module")
def ema270():
    return load_params(EMA270)


@pytest.fixture(scope="module")
def trace270(ema270):
    """Dry friction x2 on the 270 V design (the issue's case)."""
    return simulate(scenario="friction-high", params=ema270, sensors=DEFAULT_SENSORS, seed=1)


@pytest.fixture(scope="module")
def preset_trace():
    return simulate(scenario="backlash-high", sensors=DEFAULT_SENSORS, seed=2)


def test_the_order_is_given_then_the_traces_own_then_the_preset(trace270, ema270):
    assert resolve_params(None, trace270) == (ema270, "trace")
    p = siemens_1fk7060()
    with pytest.warns(ActuatorMismatchWarning, match="ema-270v-750w"):
        assert resolve_params(p, trace270) == (p, "given")
    bare = replace(trace270, meta={k: v for k, v in trace270.meta.items() if k != "parameters"})
    assert resolve_params(None, bare) == (p, "preset")
    assert resolve_params(None, None) == (p, "preset")


def test_a_calibration_of_the_traces_own_actuator_does_not_warn(trace270, ema270):
    cal = replace(ema270, calibration=replace(ema270.calibration, date="2024-05-01T00:00:00+00:00"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert resolve_params(cal, trace270) == (cal, "given")
        assert resolve_params(ema270, trace270) == (ema270, "given")     # the same: no warning


def test_traces_of_two_actuators_need_the_parameters_given(trace270, preset_trace):
    with pytest.raises(ValueError, match="different actuators"):
        resolve_params(None, [trace270, preset_trace])


def test_unreadable_parameters_in_the_metadata_say_what_to_do(trace270):
    bad = replace(trace270, meta={**trace270.meta, "parameters": {"motor": 3}})
    with pytest.raises(ParameterError, match="give the actuator's parameters"):
        resolve_params(None, bad)


def test_parameters_as_an_object_a_dict_or_a_toml_path(ema270, tmp_path):
    assert as_params(ema270) is ema270
    assert as_params(ema270.to_dict()) == ema270
    assert as_params(json.loads(json.dumps(ema270.to_dict()))) == ema270
    assert as_params(str(EMA270)) == ema270 and as_params(EMA270) == ema270
    assert as_params({"name": "mine", "load": {"J_l": 0.01, "C_l": 0.0}}).motor == siemens_1fk7060().motor
    with pytest.raises(TypeError, match="params must be an ActuatorParams, a dict"):
        as_params(3.0)


def test_identify_uses_the_traces_own_actuator(trace270, ema270):
    own = identify(trace270, seed=0)
    assert own.params_source == "trace" and own.params == ema270
    given = identify(trace270, seed=0, params=ema270)
    assert given.params_source == "given"
    np.testing.assert_array_equal(own.k, given.k)
    assert own.fitness == given.fitness and own.evaluations == given.evaluations
    assert own.k[0] > 0.5                     # the friction, not the preset's misreading
    d = own.to_dict()
    assert d["params_source"] == "trace" and d["parameters"]["name"] == "ema-270v-750w"
    # the verdict reads k on the actuator the identification used
    v = diagnose_identification(trace270, own, check=False)
    assert v.to_dict() == diagnose_identification(trace270, own, params=ema270,
                                                  check=False).to_dict()


def test_a_preset_trace_gives_the_numbers_of_the_preset_given(preset_trace):
    p = siemens_1fk7060()
    assert ActuatorParams.from_dict(preset_trace.meta["parameters"]) == p
    own = identify(preset_trace, "pso", seed=3, termination=600)
    given = identify(preset_trace, "pso", seed=3, termination=600, params=p)
    assert (own.params_source, given.params_source) == ("trace", "given")
    np.testing.assert_array_equal(own.k, given.k)
    np.testing.assert_array_equal(own.history, given.history)
    assert own.fitness == given.fitness and own.evaluations == given.evaluations


def test_the_problem_takes_a_dict_or_a_path_and_says_where_they_came_from(trace270, ema270):
    a = IdentificationProblem(trace270)
    b = IdentificationProblem(trace270, params=str(EMA270))
    c = IdentificationProblem(trace270, params=ema270.to_dict())
    assert a.params == b.params == c.params == ema270
    assert (a.params_source, b.params_source, c.params_source) == ("trace", "given", "given")
    assert replace(a, n_sub=1).params_source == "trace"
    with pytest.raises(ValueError, match="params_source must be one of"):
        IdentificationProblem(trace270, params_source="mine")


def test_calibrate_works_around_the_traces_own_actuator(ema270):
    from emaphm.calibration import CalibrationResult, calibrate

    healthy = simulate(scenario="nominal", params=ema270, unit_seed=7, sensors=DEFAULT_SENSORS,
                       seed=1)
    cal = calibrate([healthy])
    assert cal.params_source == "trace" and cal.params.name == "ema-270v-750w"
    assert cal.params.calibration.date                    # a calibration of its own
    back = CalibrationResult.from_dict(json.loads(json.dumps(cal.to_dict())))
    assert back.to_dict() == cal.to_dict() and back.params == cal.params
    with warnings.catch_warnings():                       # its own calibration: no warning
        warnings.simplefilter("error")
        assert resolve_params(cal.params, healthy) == (cal.params, "given")
