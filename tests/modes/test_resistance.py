"""A high-resistance connection of one phase (emaphm.modes.resistance): the mode added in
modes/ as the proof of one vocabulary (issue 33), read on the recorded-voltage path."""

from dataclasses import replace

import numpy as np
import pytest

from emaphm import modes
from emaphm.calibration import calibrate
from emaphm.modes import resistance
from emaphm.params import siemens_1fk7060
from emaphm.problem import apply_extra
from emaphm.simulate import DEFAULT_SENSORS, simulate
from emaphm.verdict import _problem_of, examine

DATASHEET = siemens_1fk7060()
PLANT = replace(DATASHEET, inverter=replace(DATASHEET.inverter, dead_time=1e-6, device_drop=1.0))
SENSORS = replace(DEFAULT_SENSORS, encoder_counts=2 ** 17)


def test_the_mode_is_registered_with_its_indicators_and_threshold():
    m = modes.mode("resistance")
    assert m.per_phase and m.hypothesis is resistance.hypothesis
    assert [i.name for i in m.indicators] == ["resistance_a", "resistance_b", "resistance_c"]
    assert modes.DEFAULT_THRESHOLDS.resistance == 0.1
    inj = modes.parse_fault("resistance:b:1.3")
    p = inj.plant(DATASHEET)
    assert p.motor.R == pytest.approx((DATASHEET.motor.R[0], 1.3 * DATASHEET.motor.R[1],
                                       DATASHEET.motor.R[2]))
    with pytest.raises(ValueError, match="1 to 5 x"):
        modes.parse_fault("resistance:a:0.5")
    # the per-phase deviations searched beside k apply to one phase each
    q = apply_extra(DATASHEET, ("R", "R_c"), [0.1, 0.5])
    assert q.motor.R[2] == pytest.approx(DATASHEET.motor.R[2] * 1.1 * 1.5)
    assert q.motor.R[0] == pytest.approx(DATASHEET.motor.R[0] * 1.1)


def test_the_imbalance_is_each_phase_above_the_median():
    assert resistance.imbalance({"R_a": 0.35, "R_b": 0.05, "R_c": 0.02}) == \
        pytest.approx((0.30, 0.0, -0.03))
    assert resistance.imbalance({"R": 0.1}) is None
    read = modes.indicator_readings(
        {"hypothesis_check": {"mode": "resistance", "nuisance": {"R_a": 0.0, "R_b": 0.31,
                                                                  "R_c": 0.01}}}, {})
    assert read["resistance_b"] == pytest.approx(0.30) and read["resistance_a"] == \
        pytest.approx(-0.01)
    assert modes.indicator_readings({}, {"nuisance": {"flux": -0.01}})["resistance_a"] is None


@pytest.fixture(scope="module")
def unit():
    """A production unit on a foreign drive (deadbeat), its voltage commands recorded,
    calibrated on two healthy traces."""
    kw = dict(params=PLANT, sensors=SENSORS, unit_seed=90_001, drive_signals=True,
              drive="deadbeat")
    cal = calibrate([simulate(seed=1, **kw), simulate(seed=2, **kw)], DATASHEET)
    return kw, cal.params


def test_a_phase_at_1_3x_is_named_alone_and_a_short_is_not_a_connection(unit):
    kw, params = unit
    ex = examine(simulate(seed=14, faults=["resistance:b:1.3"], **kw), params=params, seed=0)
    d = ex.diagnosis
    assert [(f.mode, f.phase) for f in d.faults] == [("resistance", "B")]
    assert d.refit.mode == "resistance"
    assert d.faults[0].k == pytest.approx(0.30, abs=0.03)
    assert "high-resistance connection in phase B" in d.faults[0].reading
    short = examine(simulate(seed=12, faults=["short_circuit:a:0.1:0.15"], **kw), params=params,
                    seed=0).diagnosis
    assert [(f.mode, f.phase) for f in short.faults] == [("short_circuit", "A")]


def test_the_screen_spares_the_refit_where_no_phase_asks(unit):
    """Seven evaluations tell a phase at 1.3x (a gain of about 0.2) from healthy, friction
    and a weaker magnet (about 0.002), so that those cost no refit."""
    kw, params = unit
    gains = {}
    for label, faults in (("healthy", []), ("friction", ["friction:2"]),
                          ("connection", ["resistance:b:1.3"])):
        tr = simulate(seed=20, faults=faults, **kw)
        ident = examine(tr, params=params, seed=0).identification
        gains[label] = resistance.screened_gain(_problem_of(tr, ident, params), ident)
    assert gains["connection"] > 0.1
    assert max(gains["healthy"], gains["friction"]) < resistance.SCREEN_GAIN
    assert np.isfinite(list(gains.values())).all()
