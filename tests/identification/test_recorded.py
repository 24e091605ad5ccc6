"""Identification from the drive's recorded voltages (:mod:`emaphm.recorded`): the drive's
firmware is not modelled, so drives that are not emaphm's are diagnosed as emaphm's is.

Every plant here has an inverter with dead time and device drops, an encoder of 2^17
counts and the data sheet's parameters (never the drive's: ``[controller]`` describes
emaphm's plain cascade, not the firmware the plant runs).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from emaphm.identify import IdentificationConfig, identify
from emaphm.params import siemens_1fk7060
from emaphm.problem import IdentificationProblem
from emaphm.recorded import (MODELLED, RECORDED_CURRENT_REFERENCES, RECORDED_SPEED_REFERENCE,
                             RECORDED_VOLTAGES, drive_model_of)
from emaphm.simulate import DEFAULT_SENSORS, simulate
from emaphm.traces import TraceError
from emaphm.verdict import examine

DATASHEET = siemens_1fk7060()
PLANT = replace(DATASHEET, inverter=replace(DATASHEET.inverter, dead_time=1e-6, device_drop=1.0))
SENSORS = replace(DEFAULT_SENSORS, encoder_counts=2 ** 17)

#: Firmwares that are not the data sheet's: two of emaphm's options, three foreign drives.
FIRMWARES = {
    "feed-forwards": dict(params=replace(PLANT, controller=replace(
        DATASHEET.controller, velocity_feedforward=1.0, torque_feedforward=1.0))),
    "speed filter 1 ms": dict(params=replace(PLANT, controller=replace(
        DATASHEET.controller, speed_filter_s=1e-3))),
    "observer-ip": dict(params=PLANT, drive="observer-ip"),
    "deadbeat": dict(params=PLANT, drive="deadbeat"),
    "stationary-pi": dict(params=PLANT, drive="stationary-pi"),
}


def _trace(firmware, faults=(), seed=3, **kw):
    return simulate(sensors=SENSORS, seed=seed, drive_signals=True, faults=list(faults),
                    **FIRMWARES[firmware], **kw)


def test_the_drive_model_follows_what_the_trace_carries():
    with_v = _trace("deadbeat")
    bare = simulate(sensors=SENSORS, seed=3)
    assert drive_model_of(with_v) == RECORDED_VOLTAGES and drive_model_of(bare) == MODELLED
    assert drive_model_of(with_v, MODELLED) == MODELLED
    with pytest.raises(TraceError, match="needs the drive's voltage commands"):
        drive_model_of(bare, RECORDED_VOLTAGES)
    with pytest.raises(ValueError, match="unknown drive model"):
        drive_model_of(bare, "telepathy")
    # the most the drive recorded: voltages, else current references, else speed reference
    refs = replace(with_v, drive={n: with_v.drive[n] for n in ("i_q_ref", "omega_ref")})
    speed = replace(with_v, drive={"omega_ref": with_v.drive["omega_ref"]})
    assert drive_model_of(refs) == RECORDED_CURRENT_REFERENCES
    assert drive_model_of(speed) == RECORDED_SPEED_REFERENCE
    assert drive_model_of(refs, RECORDED_SPEED_REFERENCE) == RECORDED_SPEED_REFERENCE
    with pytest.raises(TraceError, match="needs the drive's current reference i_q_ref.*"
                                         "'recorded speed reference'"):
        drive_model_of(speed, RECORDED_CURRENT_REFERENCES)


def test_the_drives_own_gain_is_not_observable_without_its_controller():
    ident = identify(_trace("deadbeat", seed=4), seed=0, params=DATASHEET)
    assert ident.drive_model == RECORDED_VOLTAGES
    assert ident.not_observable == ("gain_drift",)
    assert ident.k[7] == 0.5
    assert set(ident.nuisance) >= {"V_dt", "angle"}
    # the plant's legs lose V_dc t_d / T_s + 1 V = 5.8 V: the fit finds it
    assert ident.nuisance["V_dt"] == pytest.approx(5.8, abs=0.6)
    d = ident.to_dict()
    assert d["drive_model"] == "recorded voltages" and d["not_observable"] == ["gain_drift"]


@pytest.mark.slow
@pytest.mark.parametrize("firmware", list(FIRMWARES))
def test_drives_that_are_not_emaphms_are_diagnosed_from_their_voltages(firmware):
    """Healthy reads healthy; friction x2, a 10 % short of phase A through 0.15 ohm, a magnet
    15 % weaker and phase B's sensor 10 % low are each named right and alone. The modelled
    controller, which does not describe this firmware, explains none of them."""
    cases = {(): set(), ("friction:2",): {("friction", None)},
             ("short_circuit:a:0.1:0.15",): {("short_circuit", "A")},
             ("demagnetization:0.15",): {("demagnetization", None)},
             ("current_sensor:b:gain:0.9",): {("current_sensor", "B")}}
    for faults, named in cases.items():
        tr = _trace(firmware, faults)
        ex = examine(tr, params=DATASHEET, seed=0)
        assert ex.identification.drive_model == RECORDED_VOLTAGES
        got = {(f.mode, f.phase) for f in ex.diagnosis.faults}
        assert ex.diagnosis.verdict == ("faulty" if named else "healthy"), (faults, ex.diagnosis)
        assert got == named, (faults, got)
    modelled = examine(_trace(firmware), params=DATASHEET, seed=0,
                       config=IdentificationConfig(drive_model=MODELLED))
    assert modelled.diagnosis.verdict == "unexplained"


def test_the_problem_refuses_what_the_path_cannot_do():
    tr = _trace("deadbeat", seed=5)
    with pytest.raises(ValueError, match="mode 'phases', n_sub 1"):
        IdentificationProblem(tr, mode="equivalent")
    thin = tr.with_meta(voltage_delay_periods=3)
    with pytest.raises(TraceError, match="voltage_delay_periods = 3"):
        IdentificationProblem(thin)


# ------------------------------------------------- the drive's references, its inner loops modelled

#: emaphm's cascade with options the data sheet's ``[controller]`` does not describe, outside
#: the current loop (whose gains the data sheet's are).
OUTER = ("feed-forwards", "speed filter 1 ms")


def _references(trace, names):
    return replace(trace, drive={n: trace.drive[n] for n in names})


@pytest.mark.slow
@pytest.mark.parametrize("firmware", OUTER)
def test_drives_are_diagnosed_from_their_current_references(firmware):
    """The current references alone (no voltages): the current loop is modelled from
    ``[controller]``, the position and speed loops are not, so options outside the current
    loop that the parameters do not describe change nothing. Healthy reads healthy; the
    four faults are named right and alone."""
    cases = {(): set(), ("friction:2",): {("friction", None)},
             ("short_circuit:a:0.1:0.15",): {("short_circuit", "A")},
             ("demagnetization:0.15",): {("demagnetization", None)},
             ("current_sensor:b:gain:0.9",): {("current_sensor", "B")}}
    for faults, named in cases.items():
        tr = _references(_trace(firmware, faults), ("i_d_ref", "i_q_ref"))
        ex = examine(tr, params=DATASHEET, seed=0)
        assert ex.identification.drive_model == RECORDED_CURRENT_REFERENCES
        assert ex.identification.not_observable == ("gain_drift",)
        got = {(f.mode, f.phase) for f in ex.diagnosis.faults}
        assert ex.diagnosis.verdict == ("faulty" if named else "healthy"), (faults, ex.diagnosis)
        assert got == named, (faults, got)


@pytest.mark.slow
def test_a_described_speed_loop_is_diagnosed_from_its_speed_reference():
    """The speed reference alone: the speed loop as ``[controller]`` describes it (here a
    1 ms speed filter and a 2-DOF weight, described) rebuilds the current references.
    Healthy reads healthy, friction x2 and the short are named."""
    ctl = replace(DATASHEET.controller, speed_filter_s=1e-3, speed_reference_weight=0.8)
    described = replace(DATASHEET, controller=ctl)
    plant = replace(PLANT, controller=ctl)
    for faults, named in {(): set(), ("friction:2",): {("friction", None)},
                          ("short_circuit:a:0.1:0.15",): {("short_circuit", "A")}}.items():
        tr = _references(simulate(params=plant, sensors=SENSORS, seed=6, drive_signals=True,
                                  faults=list(faults)), ("omega_ref",))
        ex = examine(tr, params=described, seed=0)
        assert ex.identification.drive_model == RECORDED_SPEED_REFERENCE
        assert {(f.mode, f.phase) for f in ex.diagnosis.faults} == named, (faults, ex.diagnosis)
        assert ex.diagnosis.verdict == ("faulty" if named else "healthy")


def test_references_in_other_units_are_refused():
    tr = _trace("deadbeat", seed=5)
    milli = replace(tr, drive={"i_q_ref": tr.drive["i_q_ref"] * 1000.0})
    with pytest.raises(TraceError, match="current references reach .* A.*not mA"):
        IdentificationProblem(milli, params=DATASHEET)
    rpm = replace(tr, drive={"omega_ref": tr.drive["omega_ref"] * 60 / (2 * np.pi)})
    with pytest.raises(TraceError, match="speed reference reaches .*not rpm"):
        IdentificationProblem(rpm, params=DATASHEET)


# ------------------------------------------------------------------ a drive not described


@pytest.mark.slow
def test_a_drive_lag_the_description_lacks_is_not_read_as_a_fault():
    """A 0.25 ms filter on the speed feedback of a healthy unit's drive, its parameters the
    data sheet's: the modelled controller once read it as backlash at about 2x the noise
    floor. The refit with the drive's likeliest deviations explains it as well, so no fault
    is named; and where the fit stays a misfit, the hint points at the drive."""
    plant = replace(DATASHEET, controller=replace(DATASHEET.controller, speed_filter_s=2.5e-4))
    verdicts = []
    for seed in (1, 2, 3):
        ex = examine(simulate(params=plant, sensors=DEFAULT_SENSORS, seed=seed), params=DATASHEET,
                     seed=0)
        verdicts.append(ex.diagnosis.verdict)
        if ex.diagnosis.unexplained is not None and ex.diagnosis.unexplained.reason == "drive":
            assert "speed-feedback filter the drive's description lacks" in \
                ex.diagnosis.unexplained.hint
    assert "faulty" not in verdicts
    lag = replace(DATASHEET, controller=replace(DATASHEET.controller, speed_filter_s=1e-3))
    ex = examine(simulate(params=lag, sensors=DEFAULT_SENSORS, seed=1), params=DATASHEET, seed=0)
    assert ex.diagnosis.verdict == "unexplained"
    assert "the drive's control likely differs from [controller]" in ex.diagnosis.unexplained.hint


def test_the_drive_check_refits_only_the_deviations_that_could_explain_a_fault(monkeypatch):
    """The check's cost: a deviation far off (fitting k and the healthy actuator both more
    than DRIVE_SCREEN times worse) is not refitted, and faults of one phase are not checked
    at all; the verdicts are those of the check that refits every deviation."""
    import emaphm.identify as identify_mod
    import emaphm.verdict as verdict

    calls = []
    real = identify_mod.minimize

    def counting(problem, *a, **kw):
        calls.append(problem.params.controller)
        return real(problem, *a, **kw)

    monkeypatch.setattr(identify_mod, "minimize", counting)
    cases = {"friction-high": simulate(scenario="friction-high", sensors=DEFAULT_SENSORS, seed=1),
             "short": simulate(faults=["short_circuit:a:0.1:0.15"], sensors=DEFAULT_SENSORS,
                               seed=1)}
    screened = {}
    for name, tr in cases.items():
        calls.clear()
        ex = examine(tr, seed=0)
        screened[name] = (ex.diagnosis.verdict, [(f.mode, f.phase) for f in ex.diagnosis.faults])
        deviations = [c for c in calls if c != DATASHEET.controller]
        if name == "short":
            assert deviations == []                       # one phase's fault: not checked
        else:
            assert 0 < len(deviations) < len(verdict.DRIVE_DEVIATIONS)   # some screened out
    assert screened == {"friction-high": ("faulty", [("friction", None)]),
                        "short": ("faulty", [("short_circuit", "A")])}
    # every deviation refitted: the same verdict on the friction trace
    monkeypatch.setattr(verdict, "DRIVE_SCREEN", np.inf)
    calls.clear()
    ex = examine(cases["friction-high"], seed=0)
    assert len([c for c in calls if c != DATASHEET.controller]) == len(verdict.DRIVE_DEVIATIONS)
    assert (ex.diagnosis.verdict, [(f.mode, f.phase) for f in ex.diagnosis.faults]) == \
        screened["friction-high"]


@pytest.mark.slow
def test_calibration_refuses_to_absorb_a_drive_it_does_not_describe():
    from emaphm.calibration import CalibrationError, calibrate

    for tau, words in ((2.5e-4, "outside what a unit of this design spreads over"),
                       (1e-3, "the drive's control likely differs from [controller]")):
        plant = replace(DATASHEET, controller=replace(DATASHEET.controller, speed_filter_s=tau))
        traces = [simulate(params=plant, sensors=DEFAULT_SENSORS, seed=s, unit_seed=3)
                  for s in (1, 2)]
        with pytest.raises(CalibrationError, match=words.replace("[", "\\[").replace("]", "\\]")):
            calibrate(traces, DATASHEET)


def test_a_parameter_at_the_end_of_its_range_is_said():
    """A winding 45 % above its data sheet, searched within -10..+30 %: the fit ends at the
    bound, and the result says so."""
    hot = replace(DATASHEET, motor=replace(DATASHEET.motor, R=tuple(1.45 * r for r in DATASHEET.motor.R)))
    tr = simulate(params=hot, sensors=DEFAULT_SENSORS, seed=2, drive_signals=True)
    ident = identify(IdentificationProblem(tr, params=DATASHEET, nuisance=("R",)), seed=0)
    assert "R" in ident.at_bounds and ident.nuisance["R"] == pytest.approx(0.3, abs=1e-3)
    from emaphm.verdict import diagnose_identification

    notes = diagnose_identification(tr, ident, params=DATASHEET).notes
    assert any("winding resistance +30.0 % at the end of its range" in n for n in notes)
