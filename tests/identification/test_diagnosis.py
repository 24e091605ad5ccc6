"""From an identified fault vector to a verdict (:func:`emaphm.diagnosis.diagnose`).

Known answers: every scenario of the paper is read as exactly its fault mode (the short
circuit on its phase), with the physical numbers the mapping of ``k`` gives; the
thresholds are strict (a component at the threshold is healthy, just above it is not)
and validated.
"""

from __future__ import annotations

import dataclasses
from functools import partial
import json
import math

import numpy as np
import pytest
from support import k_with

from emaphm.diagnosis import DEFAULT_THRESHOLDS, FAULT_MODES, Diagnosis, Fault, Thresholds
from emaphm.diagnosis import diagnose as _diagnose
from emaphm.faults import K_NOMINAL, SCENARIOS, FaultVectorError

#: The rules under the paper's fault model unless a test says otherwise (as written for
#: emaphm 0.3, whose default it was; a bare k warns now, tests/identification/test_problem.py).
diagnose = partial(_diagnose, fault_model="paper")

SINGLE = {
    "friction-low": "friction", "friction-high": "friction",
    "backlash-low": "backlash", "backlash-high": "backlash",
    "short-circuit-low": "short_circuit", "short-circuit-high": "short_circuit",
    "eccentricity-low": "eccentricity", "eccentricity-high": "eccentricity",
    "gain-low": "gain_drift", "gain-high": "gain_drift",
}


_k = k_with      # nominal k with some components set, by 1-based index


# ----------------------------------------------------------------------------- verdicts
def test_nominal_is_healthy():
    d = diagnose(SCENARIOS["nominal"])
    assert isinstance(d, Diagnosis)
    assert d.healthy and d.faults == () and d.modes == ()
    assert d.summary().startswith("healthy")
    np.testing.assert_array_equal(d.k, K_NOMINAL)


def test_scenario_names_cover_every_mode():
    assert set(SINGLE) | {"nominal", "multiple", "turn-short-5pct", "turn-short-15pct"} \
        == set(SCENARIOS)
    from emaphm.modes import PAPER_MODES

    assert set(SINGLE.values()) == set(PAPER_MODES) and set(PAPER_MODES) < set(FAULT_MODES)


@pytest.mark.parametrize("name", sorted(SINGLE))
def test_single_fault_scenario_gives_exactly_its_mode(name):
    d = diagnose(SCENARIOS[name])
    assert not d.healthy
    assert d.modes == (SINGLE[name],)
    f = d.faults[0]
    assert isinstance(f, Fault)
    magnitude = 0.25 if name.endswith("-low") else 0.75
    if SINGLE[name] == "gain_drift":
        assert f.k == magnitude and f.component == "k8"
        assert f.severity == pytest.approx(0.5)          # |k8 - 0.5| / 0.5
    else:
        assert f.k == magnitude and f.severity == pytest.approx(magnitude)
    assert d.summary() == "faulty: " + f.reading


@pytest.mark.parametrize("j, phase", [(0, "A"), (1, "B"), (2, "C")])
def test_short_circuit_names_its_phase(j, phase):
    d = diagnose(_k(**{f"k{3 + j}": 0.25}))
    assert d.modes == ("short_circuit",)
    f = d.faults[0]
    assert f.phase == phase and f.component == f"k{3 + j}"
    assert f.reading.startswith(f"25% of phase {phase} turns shorted")
    for other in d.faults:
        assert other.phase == phase


def test_shorts_on_two_phases_are_two_faults():
    d = diagnose(_k(k3=0.5, k5=0.1))
    assert d.modes == ("short_circuit", "short_circuit")
    assert [f.phase for f in d.faults] == ["A", "C"]
    assert [f.k for f in d.faults] == [0.5, 0.1]


def test_multiple_fault_vector_gives_the_modes_above_threshold():
    # paper Eq. 8: k = [0.0133, 0.05, 0.003, 0, 0, 0.012, 0.5, 0.35]; with the default
    # (plant-tuned) thresholds the backlash (0.05 > 0.034) and the gain (|0.35 - 0.5| >
    # 0.015) stand out; friction, short circuit and eccentricity stay inside what the
    # plant's physics the model lacks read as them
    k = SCENARIOS["multiple"]
    d = diagnose(k)
    assert d.modes == ("backlash", "gain_drift")
    above = {"friction": k[0] > DEFAULT_THRESHOLDS.friction,
             "backlash": k[1] > DEFAULT_THRESHOLDS.backlash,
             "short_circuit": k[2:5].max() > DEFAULT_THRESHOLDS.short_circuit,
             "eccentricity": k[5] > DEFAULT_THRESHOLDS.eccentricity,
             "gain_drift": abs(k[7] - 0.5) > DEFAULT_THRESHOLDS.gain_drift}
    assert set(d.modes) == {m for m, hit in above.items() if hit}
    # with thresholds low enough every injected fault is named
    low = Thresholds(friction=0.01, backlash=0.01, short_circuit=0.002, eccentricity=0.01,
                     gain_drift=0.01)
    d = diagnose(k, thresholds=low)
    assert d.modes == ("friction", "backlash", "short_circuit", "eccentricity", "gain_drift")
    assert d.faults[2].phase == "A"
    assert d.thresholds is low


def test_eccentricity_phase_is_ignored_without_modulus():
    # k7 alone (phase of a zero eccentricity) is no fault
    assert diagnose(_k(k7=0.0)).healthy
    assert diagnose(_k(k7=1.0)).healthy


# ----------------------------------------------------------------------------- readings
def test_friction_reading():
    f = diagnose(_k(k1=0.75)).faults[0]
    assert "dry friction 2.50x nominal" in f.reading
    assert "dynamic 0.200 N m" in f.reading and "static 0.300 N m" in f.reading


def test_short_circuit_reading():
    f = diagnose(_k(k4=0.25)).faults[0]
    assert "25% of phase B turns shorted" in f.reading
    assert "R x0.75" in f.reading and "L x0.56" in f.reading


def test_gain_readings():
    low = diagnose(_k(k8=0.25)).faults[0]
    assert "proportional gain -25%" in low.reading
    assert "Kp 45.0 1/s instead of 60.0" in low.reading
    high = diagnose(_k(k8=0.75)).faults[0]
    assert "proportional gain +25%" in high.reading
    assert "Kp 75.0" in high.reading


def test_backlash_reading():
    f = diagnose(_k(k2=0.75)).faults[0]
    # 1 + 99 * 0.75 = 75.25 times 0.2 mrad
    assert "backlash 75.2x nominal" in f.reading and "15.05 mrad" in f.reading


@pytest.mark.parametrize("k7, deg", [(0.5, "+0 deg"), (0.75, "+90 deg"), (0.25, "-90 deg"),
                                     (0.0, "-180 deg")])
def test_eccentricity_reading(k7, deg):
    f = diagnose(_k(k6=0.5, k7=k7)).faults[0]
    assert f.mode == "eccentricity" and f.component == "k6,k7"
    assert f.reading == f"static eccentricity 50% of the air gap at {deg}"


def test_readings_use_the_given_params(nominal_params):
    tr = dataclasses.replace(nominal_params.transmission, FDJ=0.1, FSJ=0.2)
    p = dataclasses.replace(nominal_params, transmission=tr)
    f = diagnose(_k(k1=0.5), params=p).faults[0]
    assert "dynamic 0.200 N m" in f.reading and "static 0.400 N m" in f.reading


def test_to_dict_is_json():
    d = diagnose(_k(k1=0.75, k4=0.25, k8=0.25))
    out = json.loads(json.dumps(d.to_dict()))
    assert out["healthy"] is False
    assert [f["mode"] for f in out["faults"]] == ["friction", "short_circuit", "gain_drift"]
    assert out["faults"][1]["phase"] == "B"
    assert out["faults"][0]["reading"].startswith("dry friction 2.50x")
    assert out["thresholds"] == dataclasses.asdict(DEFAULT_THRESHOLDS)
    assert set(out["faults"][0]) == {"mode", "component", "k", "severity", "reading", "phase"}


# ----------------------------------------------------------------------------- thresholds
EPS = 1e-6


@pytest.mark.parametrize("field, component, healthy_value", [
    ("friction", "k1", 0.0), ("backlash", "k2", 0.0), ("short_circuit", "k3", 0.0),
    ("short_circuit", "k4", 0.0), ("short_circuit", "k5", 0.0), ("eccentricity", "k6", 0.0),
])
def test_component_just_below_and_above_its_threshold(field, component, healthy_value):
    th = getattr(DEFAULT_THRESHOLDS, field)
    assert diagnose(_k(**{component: th - EPS})).healthy
    assert diagnose(_k(**{component: th})).healthy               # strictly above raises
    d = diagnose(_k(**{component: th + EPS}))
    assert d.modes == (field,)
    assert d.faults[0].component.startswith(component)


@pytest.mark.parametrize("sign", [+1, -1])
def test_gain_drift_threshold_is_two_sided(sign):
    th = DEFAULT_THRESHOLDS.gain_drift
    assert diagnose(_k(k8=0.5 + sign * (th - EPS))).healthy
    d = diagnose(_k(k8=0.5 + sign * (th + EPS)))
    assert d.modes == ("gain_drift",)
    assert d.faults[0].severity == pytest.approx((th + EPS) / 0.5)


def test_custom_thresholds_move_the_decision():
    k = _k(k1=0.15)
    assert diagnose(k).modes == ("friction",)
    assert diagnose(k, thresholds=Thresholds(friction=0.2)).healthy


def test_default_thresholds_sit_below_the_low_fault_magnitude():
    for v in dataclasses.asdict(DEFAULT_THRESHOLDS).values():
        assert 0 < v < 0.25


@pytest.mark.parametrize("bad", [0.0, 1.0, -0.1, 1.5, math.nan, math.inf, "0.1", None])
@pytest.mark.parametrize("field", ["friction", "backlash", "short_circuit", "eccentricity",
                                   "gain_drift"])
def test_thresholds_are_validated(field, bad):
    with pytest.raises(ValueError, match=rf"Thresholds\.{field} must be in \(0, 1\), got"):
        Thresholds(**{field: bad})


def test_thresholds_are_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        DEFAULT_THRESHOLDS.friction = 0.5  # type: ignore[misc]


@pytest.mark.parametrize("bad, match", [
    ([0.0] * 7, "needs 8 components"),
    ([0, 0, 0, 0, 0, 0, 0.5, 1.2], "k8"),
    ([0, 0, 0, 0, 0, 0, 0.5, math.nan], "non-finite"),
])
def test_bad_fault_vector_raises(bad, match):
    with pytest.raises(FaultVectorError, match=match):
        diagnose(bad)


def test_accepts_a_comma_separated_string():
    assert diagnose("0.75,0,0,0,0,0,0.5,0.5").modes == ("friction",)


def test_physical_fault_model_reads_a_shorted_fraction_with_its_own_threshold():
    from emaphm.diagnosis import THRESHOLDS_BY_FAULT_MODEL

    k = K_NOMINAL.copy()
    k[3] = 0.08
    d = diagnose(k, fault_model="physical")
    assert d.fault_model == "physical" and d.thresholds == THRESHOLDS_BY_FAULT_MODEL["physical"]
    (f,) = d.faults
    assert f.mode == "short_circuit" and f.phase == "B"
    assert "8.0% of its turns" in f.reading and "fault resistance of 0.15 ohm" in f.reading
    assert "R x" not in f.reading                     # no turn removal under physical
    assert diagnose(k).faults[0].reading.startswith("8% of phase B turns shorted (R x0.92")
    assert d.to_dict()["fault_model"] == "physical"
    with pytest.raises(ValueError, match="unknown fault model"):
        diagnose(k, fault_model="electrical")


# ----------------------------------------------------------------------------- verdicts

def test_a_fit_far_above_what_the_model_reaches_is_unexplained_not_faulty():
    from emaphm.fitness import misfit_limit, misfit_p_value

    k = K_NOMINAL.copy()
    k[0] = 0.5                                     # friction would be named
    lim = misfit_limit()
    assert 2.0 < lim < 4.0                         # 2.70 with the tuned lognormal
    ok = diagnose(k, fit_ratio=0.9 * lim)
    assert ok.verdict == "faulty" and ok.modes == ("friction",) and ok.unexplained is None
    bad = diagnose(k, fit_ratio=1.2 * lim)
    assert bad.verdict == "unexplained" and not bad.healthy and bad.faults == ()
    assert bad.unexplained.reason == "misfit"
    assert bad.unexplained.p_value == pytest.approx(misfit_p_value(1.2 * lim))
    assert bad.unexplained.p_value < 1e-4 < misfit_p_value(0.9 * lim)
    assert "emaphm calibrate" in bad.unexplained.hint
    assert "measured on the preset" not in bad.unexplained.hint       # the preset's own limit
    from emaphm.params import siemens_1fk7060

    other = dataclasses.replace(siemens_1fk7060(), name="my-ema")
    hint = diagnose(k, fit_ratio=1.2 * lim, params=other).unexplained.hint
    assert "the limit was measured on the preset, not on my-ema" in hint and "emaphm assess" in hint
    assert [f.mode for f in bad.suspected] == ["friction"]
    d = bad.to_dict()
    assert d["verdict"] == "unexplained" and d["healthy"] is False and d["faults"] == []
    assert set(d["unexplained"]) == {"reason", "statistic", "p_value", "hint"}
    # healthy stays a boolean true only for the healthy verdict
    h = diagnose(K_NOMINAL, fit_ratio=1.3)
    assert h.verdict == "healthy" and h.to_dict()["healthy"] is True
    assert misfit_p_value(float("inf")) == 0.0 and misfit_p_value(1.0) > 0.9


def test_a_balanced_change_on_all_three_phases_is_a_calibration_mismatch():
    k = K_NOMINAL.copy()
    k[2:5] = [0.06, 0.08, 0.07]
    d = diagnose(k, fault_model="physical")
    assert d.verdict == "unexplained" and d.unexplained.reason == "balanced-phases"
    assert d.unexplained.p_value is None and "calibrate" in d.unexplained.hint
    assert {f.phase for f in d.suspected} == {"A", "B", "C"}
    # one phase clearly dominant: a real short circuit, named
    k[2:5] = [0.2, 0.03, 0.03]
    d = diagnose(k, fault_model="physical")
    assert d.verdict == "faulty" and {f.phase for f in d.faults} == {"A", "B", "C"}


def test_backlash_reads_from_zero_on_a_transmission_without_any():
    """A data sheet with no backlash (a harmonic drive): k2 is an absolute width from zero,
    not a multiple of nothing (it read 'backlash 99.9x nominal (0.00 mrad)')."""
    from dataclasses import replace as _replace

    from emaphm.faults import BACKLASH_FROM_ZERO, apply_faults
    from emaphm.params import siemens_1fk7060

    p = siemens_1fk7060()
    zero = _replace(p, transmission=_replace(p.transmission, backlash=0.0))
    k = [0, 0.5, 0, 0, 0, 0, 0.5, 0.5]
    assert apply_faults(zero, k, "physical").transmission.backlash == pytest.approx(
        0.5 * BACKLASH_FROM_ZERO)
    assert apply_faults(p, k, "physical").transmission.backlash == pytest.approx(
        p.transmission.backlash * 50.5)
    reading = diagnose(k, params=zero, fault_model="physical").faults[0].reading
    assert "10.00 mrad where the data sheet states none" in reading
    assert "x nominal" in diagnose(k, params=p, fault_model="physical").faults[0].reading
    from emaphm.models.layout import C_BACKLASH, pack_population

    _, CP = pack_population(zero, np.array([k]), fault_model="physical")
    assert CP[0, C_BACKLASH] == pytest.approx(0.5 * BACKLASH_FROM_ZERO)
