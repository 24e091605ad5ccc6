"""The fault-mode registry and the modes beyond the paper's k (issue 21).

Layers: the registry's contract (every mode reads, simulates, has its thresholds); the
sum of three currents on synthetic currents (known answers); and plant traces diagnosed
as ``emaphm diagnose`` does (:func:`emaphm.verdict.examine`): a faulty sensor named alone
on its phase, a demagnetized rotor named with its flux ratio, a short's fault loop read
within the plant's own, a short never called a sensor fault.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from emaphm.cli import main
from emaphm.modes import (DEFAULT_THRESHOLDS, FAULT_MODES, MODES, PAPER_MODES, Thresholds,
                          fault_specs, parse_fault)
from emaphm.modes.current_sensor import UNOBSERVABLE_NOTE
from emaphm.simulate import DEFAULT_SENSORS, simulate
from emaphm.traces.zero_sum import best_fit, single_sensor_fits, two_currents
from emaphm.verdict import examine


# ----------------------------------------------------------------------------- registry
def test_every_mode_reads_simulates_and_has_thresholds():
    assert set(PAPER_MODES) == {"friction", "backlash", "short_circuit", "eccentricity",
                                "gain_drift"}
    assert {"demagnetization", "current_sensor"} <= set(FAULT_MODES)
    fields = set(DEFAULT_THRESHOLDS.__dataclass_fields__)
    for name, m in MODES.items():
        assert m.name == name and callable(m.read) and m.inject is not None
        assert set(m.fields()) <= fields and m.severity_unit and m.grid
        assert 0 < m.threshold < 1
    with pytest.raises(ValueError, match="current_sensor_gain must be in"):
        Thresholds(current_sensor_gain=0.0)


@pytest.mark.parametrize("spec, k, sensor", [
    ("friction:2.5", {0: 0.75}, None),
    ("backlash:10", {1: 9 / 99}, None),
    ("short_circuit:b:0.2", {3: 0.2}, None),
    ("eccentricity:0.1", {5: 0.1, 6: 0.5}, None),
    ("gain_drift:0.9", {7: 0.4}, None),
    ("demagnetization:0.15", {}, None),
    ("current_sensor:a:gain:0.9", {}, (0, 0.9, 0.0)),
    ("current_sensor:c:offset:0.2", {}, (2, 1.0, 0.2)),
])
def test_fault_specs_parse_into_injections(spec, k, sensor):
    inj = parse_fault(spec)
    assert {j: pytest.approx(v) for j, v in inj.k.items()} == k
    assert inj.sensor == sensor


def test_a_short_with_its_fault_resistance_and_a_demagnetization_change_the_plant(nominal_params):
    inj = parse_fault("short_circuit:a:0.3:0.05")
    assert inj.k == {2: 0.3} and inj.plant(nominal_params).motor.R_f == (0.05, 0.15, 0.15)
    demag = parse_fault("demagnetization:0.15").plant(nominal_params)
    np.testing.assert_allclose(demag.motor.c0, np.array(nominal_params.motor.c0) * 0.85)
    assert demag.controller.k_T == nominal_params.controller.k_T     # the drive keeps its k_T


@pytest.mark.parametrize("spec, match", [
    ("friction:9", "1 to 3 x nominal"), ("short_circuit:x:0.3", "short_circuit:PHASE"),
    ("current_sensor:a:bias:0.1", "current_sensor:PHASE:gain"), ("nonsense:1", "unknown fault mode"),
    ("demagnetization:abc", "not a number"), ("", "MODE:FIELDS"),
])
def test_bad_fault_specs_say_what_to_write(spec, match):
    with pytest.raises(ValueError, match=match):
        parse_fault(spec)
    assert "current_sensor:PHASE:gain:GAIN" in fault_specs()


def test_simulate_fault_on_the_command_line(tmp_path, capsys):
    out = tmp_path / "d.parquet"
    assert main(["simulate", "--fault", "demagnetization:0.1", "--fault", "friction:1.5",
                 "--seed", "1", "--out", str(out)]) == 0
    from emaphm.traces import read_trace

    t = read_trace(out)
    assert t.meta["faults"] == ["demagnetization:0.1", "friction:1.5"]
    assert t.meta["k"][0] == pytest.approx(0.25)
    assert main(["simulate", "--fault", "friction:9", "--out", str(out)]) == 2
    assert "friction is 1 to 3 x nominal" in capsys.readouterr().err


# ----------------------------------------------------------------------------- the sum
def _currents(n: int = 2000, amp: float = 3.0) -> np.ndarray:
    t = np.linspace(0.0, 0.5, n)
    th = 2 * np.pi * 7 * t
    i = np.stack([amp * np.sin(th - j * 2 * np.pi / 3) for j in range(3)], axis=1)
    i[:, 0] += 0.5 * np.sin(2 * np.pi * 3 * t)            # a harmonic the phases share less
    i[:, 1] -= 0.5 * np.sin(2 * np.pi * 3 * t)
    return i


@pytest.mark.parametrize("j, g, o", [(0, 0.9, 0.0), (1, 1.2, 0.0), (2, 1.0, 0.25),
                                     (1, 0.85, -0.1)])
def test_one_faulty_sensor_is_read_from_the_sum(j, g, o):
    i = _currents()
    m = i.copy()
    m[:, j] = g * i[:, j] + o
    fit = best_fit(m)
    assert fit.plausible and fit.residual < 1e-6
    assert fit.gain == pytest.approx(g, abs=1e-9) and fit.offset == pytest.approx(o, abs=1e-9)
    if g != 1.0:
        assert fit.phase == j            # a gain follows its phase's waveform
    assert all(f.sum_ratio > 0.0 for f in single_sensor_fits(m))


def test_two_measured_currents_make_sensors_unobservable():
    i = _currents()
    i[:, 2] = -(i[:, 0] + i[:, 1])
    assert two_currents(i) and two_currents(_currents(), {"currents_measured": 2})
    assert not two_currents(_currents() + [0.0, 0.0, 0.01])


# ----------------------------------------------------------------------------- plant traces
@pytest.fixture(scope="module")
def plant():
    """Plant traces of the nominal unit (data sheet exact), one fault each, seed 4."""
    specs = {"gain": "current_sensor:b:gain:0.9", "offset": "current_sensor:c:offset:0.2",
             "short": "short_circuit:a:0.1", "severe": "short_circuit:a:0.3:0.5",
             "demag": "demagnetization:0.15"}
    return {name: simulate(faults=[s], sensors=DEFAULT_SENSORS, seed=4)
            for name, s in specs.items()}


def _named(diag):
    return [(f.mode, f.phase) for f in diag.faults]


def test_a_sensor_gain_is_named_alone_on_its_phase(plant):
    ex = examine(plant["gain"], seed=0)
    assert _named(ex.diagnosis) == [("current_sensor", "B")]
    f = ex.diagnosis.faults[0]
    assert f.details["kind"] == "gain" and f.details["value"] == pytest.approx(0.9, abs=0.01)
    assert ex.trace.meta["corrected_sensor"]["phase"] == "B"


def test_a_sensor_offset_is_placed_by_the_model(plant):
    ex = examine(plant["offset"], seed=0)
    assert _named(ex.diagnosis) == [("current_sensor", "C")]
    assert ex.diagnosis.faults[0].details["value"] == pytest.approx(0.2, abs=0.02)


def test_an_offsets_phase_is_scored_before_it_is_identified(plant):
    """The three corrections scored at the healthy actuator: the right one stands out (a
    wrong one leaves the offset in two currents), so one identification places it; without
    a score all three are identified, to the same phase."""
    from emaphm.faults import K_NOMINAL
    from emaphm.identify import identify
    from emaphm.modes.current_sensor import correct, resolve, screen
    from emaphm.problem import IdentificationProblem

    trace = plant["offset"]
    finding = screen(trace, None, DEFAULT_THRESHOLDS)
    assert finding.needs_phase
    calls = []

    def run(t):
        calls.append(t)
        return identify(t, seed=0, fault_model="physical")

    def score(t):
        return IdentificationProblem(t, fault_model="physical").fitness_at(K_NOMINAL)

    scores = [score(correct(trace, finding, j)) for j in range(3)]
    assert min(scores) * 10 < sorted(scores)[1]          # the right phase stands out
    placed, fixed, ident = resolve(trace, finding, run, score)
    assert placed.phase == 2 and len(calls) == 1 and ident.fitness > 0
    calls.clear()
    again, _, ident3 = resolve(trace, finding, run)
    assert again.phase == 2 and len(calls) == 3 and ident3.fitness == ident.fitness


def test_a_short_is_never_a_sensor_fault_and_carries_its_fault_loop(plant):
    ex = examine(plant["short"], seed=0)
    assert not ex.sensor.faulty
    assert _named(ex.diagnosis) == [("short_circuit", "A")]
    d = ex.diagnosis.to_dict()["faults"][0]
    truth = plant["short"].meta["plant"]
    assert d["fault_current_a_rms"] == pytest.approx(truth["fault_current_a_rms"][0], rel=0.25)
    for q, iv in (("fault_current_a_rms", "fault_current_interval"),
                  ("fault_power_w", "fault_power_interval"),
                  ("fault_mmf_a_rms", "fault_mmf_interval")):
        lo, hi = d[iv]
        assert 0 < lo <= d[q] <= hi
    assert d["fault_mmf_a_rms"] == pytest.approx(truth["fault_mmf_a_rms"][0], rel=0.25)
    assert d["mu"] == pytest.approx(0.1, abs=0.02)
    json.dumps(ex.diagnosis.to_dict())


def test_the_loop_report_of_known_currents():
    """RMS, power R_f i^2 and ampere-turns mu i from a mean square (known answers)."""
    from emaphm.faults import loop_report

    r = loop_report([4.0, 0.0, 9.0], [0.5, 0.15, 2.0], [0.1, 0.0, 0.3])
    assert r["fault_current_a_rms"] == [2.0, 0.0, 3.0]
    assert r["fault_power_w"] == [2.0, 0.0, 18.0]
    assert r["fault_mmf_a_rms"] == pytest.approx([0.2, 0.0, 0.9])
    assert r["R_f_ohm"] == [0.5, 0.15, 2.0]


def test_a_severe_short_is_read_with_its_fault_resistance(plant):
    """30 % of phase A through 0.5 ohm (3.3x the parameters' bridge): the fixed-bridge fit
    reads 24 % at 1.95x the noise floor; the refit with the bridge searched fits at 1.1x
    with 0.88 ohm, and its fault current is within 25 % of the plant's."""
    ex = examine(plant["severe"], seed=0)
    d = ex.diagnosis
    assert _named(d) == [("short_circuit", "A")] and d.refit.mode == "short_circuit"
    f = d.faults[0].details
    assert f["R_f_ohm"] > 0.3 and f["mu"] > 0.25
    truth = plant["severe"].meta["plant"]["fault_current_a_rms"][0]
    assert f["fault_current_a_rms"] == pytest.approx(truth, rel=0.25)


def test_a_demagnetized_rotor_is_named_with_its_flux_ratio(plant):
    ex = examine(plant["demag"], seed=0)
    assert _named(ex.diagnosis) == [("demagnetization", None)]
    assert ex.diagnosis.faults[0].details["flux_ratio"] == pytest.approx(0.85, abs=0.02)
    assert ex.diagnosis.refit.mode == "demagnetization"


def test_healthy_traces_cost_no_hypothesis_and_name_nothing():
    tr = simulate(sensors=DEFAULT_SENSORS, seed=5)
    ex = examine(tr, seed=0)
    assert ex.diagnosis.verdict == "healthy" and ex.diagnosis.refit is None
    assert ex.sensor.observable and not ex.sensor.faulty


def test_two_currents_say_sensor_faults_are_not_observable(plant):
    from dataclasses import replace

    tr = plant["short"]
    i = tr.i_abc.copy()
    i[:, 2] = -(i[:, 0] + i[:, 1])
    two = replace(tr, i_abc=i, meta={**tr.meta, "currents_measured": 2})
    ex = examine(two, seed=0)
    assert UNOBSERVABLE_NOTE in ex.diagnosis.notes and not ex.sensor.observable
    assert ("current_sensor", "A") not in _named(ex.diagnosis)


def test_a_sum_no_sensor_explains_is_refused_with_the_closest_sensor(tmp_path, capsys):
    from dataclasses import replace

    from emaphm.traces import write_trace

    tr = simulate(sensors=DEFAULT_SENSORS, seed=6)
    swapped = replace(tr, i_abc=tr.i_abc[:, [0, 1, 1]])          # phase b recorded twice
    write_trace(swapped, tmp_path / "bad.csv")
    assert main(["diagnose", str(tmp_path / "bad.csv"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "no single current sensor's gain or offset explains it" in err and "\n" == err[-1]
    assert err.count("\n") == 1
    assert math.isfinite(best_fit(swapped.i_abc).residual)
