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
from emaphm.recorded import MODELLED, RECORDED_VOLTAGES, drive_model_of
from emaphm.simulate import DEFAULT_SENSORS, simulate
from emaphm.traces import TraceError
from emaphm.verdict import examine

DATASHEET = siemens_1fk7060()
PLANT = replace(DATASHEET, plant=replace(DATASHEET.plant, dead_time=1e-6, device_drop=1.0))
SENSORS = replace(DEFAULT_SENSORS, encoder_counts=2 ** 17)

#: Firmwares that are not the data sheet's: two of emaphm's options, two foreign drives.
FIRMWARES = {
    "feed-forwards": dict(params=replace(PLANT, controller=replace(
        DATASHEET.controller, velocity_feedforward=1.0, torque_feedforward=1.0))),
    "speed filter 1 ms": dict(params=replace(PLANT, controller=replace(
        DATASHEET.controller, speed_filter_s=1e-3))),
    "observer-ip": dict(params=PLANT, drive="observer-ip"),
    "deadbeat": dict(params=PLANT, drive="deadbeat"),
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
