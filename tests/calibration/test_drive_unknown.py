"""Drive settings a user does not know, estimated by the calibration
(``calibrate(drive_unknown=...)``, ``emaphm calibrate --drive-unknown``)."""

from __future__ import annotations

import tomllib
import warnings
from dataclasses import replace

import pytest

from emaphm.calibration import DRIVE_SETTINGS, CalibrationError, calibrate, drive_bounds
from emaphm.cli import main
from emaphm.params import CalibrationWarning, load_params, save_params, siemens_1fk7060
from emaphm.simulate import DEFAULT_SENSORS, simulate
from emaphm.traces import write_trace
from emaphm.verdict import examine

DATASHEET = siemens_1fk7060()
#: a drive with a 1 ms low-pass on its speed feedback that the data sheet does not state
LAGGED = replace(DATASHEET, controller=replace(DATASHEET.controller, speed_filter_s=1e-3))


@pytest.fixture(scope="module")
def healthy():
    return [simulate(params=LAGGED, sensors=DEFAULT_SENSORS, seed=s) for s in (21, 22)]


@pytest.fixture(scope="module")
def estimated(healthy):
    return calibrate(healthy, DATASHEET, drive_unknown=["speed_filter_s"])


def test_the_bounds_start_from_the_stated_value():
    b = drive_bounds(DATASHEET, ["velocity_feedforward", "speed_filter_s", "Kp_w"])
    assert b["velocity_feedforward"] == (0.0, 1.5, 0.0)
    assert b["speed_filter_s"] == (0.0, 5e-3, 2.5e-4)       # a filter's search starts off zero
    assert b["Kp_w"] == (-0.5, 1.0, 0.0)                       # relative to the stated gain
    stated = replace(DATASHEET, controller=replace(DATASHEET.controller, speed_filter_s=5e-4))
    lo, hi, x0 = drive_bounds(stated, ["speed_filter_s"])["speed_filter_s"]
    assert (lo, hi, x0) == pytest.approx((-5e-4, 4.5e-3, 0.0))
    assert set(DRIVE_SETTINGS) >= {"torque_feedforward", "Kp_i", "Ki_i"}


def test_an_unknown_speed_filter_is_estimated_not_absorbed(healthy, estimated):
    """Without the setting the calibration refuses (the drive is not described); with it
    the filter reads 1 ms, the unit fits at its noise floor, and a diagnosis on the
    calibrated parameters reads healthy and names friction."""
    with pytest.raises(CalibrationError, match="drive's control likely differs"):
        calibrate(healthy, DATASHEET)
    e = estimated.estimates["speed_filter_s"]
    assert e["unit"] == "s" and e["value"] == pytest.approx(1e-3, rel=0.05)
    assert estimated.params.controller.speed_filter_s == pytest.approx(e["value"])
    assert max(estimated.fit_ratio.values()) < 1.5
    assert "speed_filter_s" in estimated.summary()
    for faults, named in (((), set()), (("friction:2",), {"friction"})):
        tr = simulate(params=LAGGED, sensors=DEFAULT_SENSORS, seed=23, faults=list(faults))
        ex = examine(tr, params=estimated.params, seed=0)
        assert {f.mode for f in ex.diagnosis.faults} == named
        assert ex.diagnosis.verdict == ("faulty" if named else "healthy")


def test_the_digest_covers_the_estimated_setting(estimated, tmp_path):
    path = tmp_path / "unit.toml"
    save_params(estimated.params, path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        back = load_params(path)                    # the file as written: no warning
    assert back.controller.speed_filter_s == estimated.params.controller.speed_filter_s
    value = tomllib.loads(path.read_text())["controller"]["speed_filter_s"]
    edited = tmp_path / "edited.toml"
    edited.write_text(path.read_text().replace(f"speed_filter_s = {value!r}",
                                               f"speed_filter_s = {value * 2!r}"))
    with pytest.warns(CalibrationWarning, match="does not match its digest"):
        load_params(edited)


def test_the_command_line_refuses_a_setting_it_cannot_estimate(healthy, tmp_path, capsys):
    paths = []
    for j, tr in enumerate(healthy):
        paths.append(str(tmp_path / f"h{j}.parquet"))
        write_trace(tr, paths[-1])
    out = tmp_path / "unit.toml"
    assert main(["calibrate", *paths, "--out", str(out), "--drive-unknown",
                 "speed_filter_s,delay_periods", "--quiet"]) == 2
    assert not out.exists()
    err = capsys.readouterr().err.strip()
    assert "--drive-unknown delay_periods" in err and "describe the others" in err
    assert len(err.splitlines()) == 1
