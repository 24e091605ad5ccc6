"""Actuator parameters: preset values, validation messages, TOML round trips, immutability."""

from __future__ import annotations

import dataclasses
import math
import re

import pytest

from emaphm.params import (ActuatorParams, Controller, Inverter, Load, Motor, ParameterError,
                           Transmission, load_params, save_params, siemens_1fk7060)

# k_E = 135 V per 1000 rpm, line-to-line RMS -> peak per-phase V s/rad (motor-defaults.md)
C0_DATASHEET = math.sqrt(2.0) * 135.0 / math.sqrt(3.0) / 104.72


# --------------------------------------------------------------------------- preset

def test_preset_back_emf_coefficient_from_voltage_constant():
    m = siemens_1fk7060().motor
    # 104.72 rad/s is 1000 rpm rounded; the preset uses 1000*2*pi/60 exactly
    for c in m.c0:
        assert c == pytest.approx(C0_DATASHEET, rel=5e-6)
        assert c == pytest.approx(math.sqrt(2.0) * 135.0 / math.sqrt(3.0) / (1000 * 2 * math.pi / 60),
                                  rel=1e-14)
    # = 1.05259 V s/rad (the docs round it to "about 1.05"; 1.0527 is the bare Motor() default)
    assert m.c0[0] == pytest.approx(1.0526, abs=1e-4)


def test_preset_motor_and_drive_values():
    p = siemens_1fk7060()
    m, ctl = p.motor, p.controller
    assert m.p == 4
    assert m.R == (3.15, 3.15, 3.15)
    assert m.L == (22e-3, 22e-3, 22e-3)
    assert m.J_m == 7.7e-4
    assert m.T_max == 18.0
    assert m.I_max == pytest.approx(10.0 * math.sqrt(2.0), rel=1e-3)   # 10 A RMS, peak
    assert m.ecc == 0.0 and m.ecc_phase == 0.0
    # the drive's torque constant is the healthy motor's 1.5*c0 (peak amperes)
    assert ctl.k_T == pytest.approx(1.5 * m.c0[0], rel=1e-14)
    assert m.k_T == pytest.approx(1.5 * m.c0[0], rel=1e-14)
    # k_T in N m per A RMS is about 2.2 (data sheet class)
    assert m.k_T * math.sqrt(2.0) == pytest.approx(2.23, abs=0.02)
    # electrical time constant about 7 ms
    assert m.L[0] / m.R[0] == pytest.approx(7e-3, rel=0.01)
    # friction levels: dynamic below static
    tr = p.transmission
    assert 0 < tr.FDJ <= tr.FSJ
    assert p.inverter.T_s == pytest.approx(1.0 / p.inverter.f_pwm)
    assert p.name == "siemens-1fk7060-2ac71"


def test_scalar_is_broadcast_to_three_phases():
    m = Motor(R=2.0, L=0.01, c0=1.0)
    assert m.R == (2.0, 2.0, 2.0)
    assert m.L == (0.01, 0.01, 0.01)
    assert m.c0 == (1.0, 1.0, 1.0)
    assert all(isinstance(x, float) for x in m.R)


# --------------------------------------------------------------------------- validation

@pytest.mark.parametrize("build, match", [
    (lambda: Motor(R=-1.0), r"Motor\.R \[ohm\] must be > 0, got -1"),
    (lambda: Motor(L=(0.02, 0.0, 0.02)), r"Motor\.L \[H\] must be > 0, got 0"),
    (lambda: Motor(R=(1.0, 2.0)), r"Motor\.R \[ohm\] needs 3 per-phase values"),
    (lambda: Motor(c0="x"), r"Motor\.c0 \[V s/rad\]"),
    (lambda: Motor(p=0), r"Motor\.p \[pole pairs, integer\]"),
    (lambda: Motor(p=4.0), r"Motor\.p \[pole pairs, integer\]"),
    (lambda: Motor(ecc=1.5), r"Motor\.ecc \[-, 0\.\.1\] must be <= 1"),
    (lambda: Motor(J_m=float("nan")), r"Motor\.J_m \[kg m\^2\] must be finite"),
    (lambda: Motor(C_m=-1e-3), r"Motor\.C_m \[N m s/rad\] must be >= 0"),
    (lambda: Inverter(V_dc=-600.0), r"Inverter\.V_dc \[V\] must be > 0"),
    (lambda: Inverter(f_pwm=0.0), r"Inverter\.f_pwm \[Hz\] must be > 0"),
    (lambda: Controller(Kp=-60.0), r"Controller\.Kp \[1/s\] must be > 0"),
    (lambda: Controller(k_T=True), r"Controller\.k_T \[N m/A peak\]: expected a number in N m/A peak, got True"),
    (lambda: Motor(R="3.15 ohm"), r"Motor\.R \[ohm\]: expected a number in ohm or 3 per-phase numbers "
                                  r"\(a, b, c\), got the string '3\.15 ohm'; write R = 3\.15 \(a bare number in ohm\)"),
    (lambda: Motor(L="22 mH"), r"got the string '22 mH'; write L = 0\.022 \(a bare number in H\)"),
    (lambda: Inverter(V_dc="six hundred"), r"Inverter\.V_dc \[V\]: expected a number in V, got the string "
                                            r"'six hundred'; write V_dc as a bare number in V"),
    (lambda: Transmission(FSJ=-0.1), r"Transmission\.FSJ \[N m\] must be >= 0"),
    (lambda: Transmission(backlash=-1e-4), r"Transmission\.backlash \[rad\] must be >= 0"),
    (lambda: Transmission(FSJ=0.1, FDJ=0.2),
     r"Transmission\.FDJ \[N m\] = 0\.2 exceeds Transmission\.FSJ \[N m\] = 0\.1"),
    (lambda: Load(J_l=0.0), r"Load\.J_l \[kg m\^2\] must be > 0"),
    (lambda: ActuatorParams(motor="not a motor"), r"ActuatorParams\.motor must be a Motor"),
])
def test_invalid_values_name_field_and_unit(build, match):
    with pytest.raises(ParameterError, match=match):
        build()


def test_parameter_error_is_a_value_error():
    assert issubclass(ParameterError, ValueError)


@pytest.mark.parametrize("obj, attr, value", [
    (Motor(), "R", (1.0, 1.0, 1.0)),
    (Inverter(), "V_dc", 1.0),
    (Controller(), "Kp", 1.0),
    (Transmission(), "FSJ", 1.0),
    (Load(), "J_l", 1.0),
    (siemens_1fk7060(), "motor", Motor()),
])
def test_frozen(obj, attr, value):
    with pytest.raises(dataclasses.FrozenInstanceError):
        setattr(obj, attr, value)


# --------------------------------------------------------------------------- dicts and TOML

def _faulty_looking():
    """A parameter set with unequal phases and every section changed."""
    return ActuatorParams(
        motor=Motor(p=3, R=(1.0, 2.0, 3.0), L=(1e-3, 2e-3, 3e-3), c0=(0.5, 0.6, 0.7), ecc=0.3,
                    ecc_phase=-1.2, J_m=1e-3, C_m=1e-4, T_max=10.0, I_max=12.0),
        inverter=Inverter(V_dc=300.0, f_pwm=10000.0, Kp_i=20.0, Ki_i=3000.0),
        controller=Controller(Kp=40.0, Ki=1.0, Kd=0.01, omega_max=150.0, Kp_w=0.3, Ki_w=5.0, k_T=0.9),
        transmission=Transmission(FSJ=0.2, FDJ=0.1, backlash=1e-3),
        load=Load(J_l=2e-3, C_l=1e-3),
        name="bench-b",
    )


@pytest.mark.parametrize("params", [siemens_1fk7060(), _faulty_looking()], ids=["preset", "custom"])
def test_dict_round_trip(params):
    d = params.to_dict()
    assert d["motor"]["R"] == list(params.motor.R)
    assert ActuatorParams.from_dict(d) == params


@pytest.mark.parametrize("params", [siemens_1fk7060(), _faulty_looking()], ids=["preset", "custom"])
def test_toml_round_trip(tmp_path, params):
    path = save_params(params, tmp_path / "actuator.toml")
    assert path.exists()
    assert load_params(path) == params
    assert load_params(path, partial=True) == params
    # atomic write leaves no temporary file behind
    assert sorted(x.name for x in tmp_path.iterdir()) == ["actuator.toml"]


def test_partial_file_fills_defaults(tmp_path):
    path = tmp_path / "partial.toml"
    path.write_text('name = "mine"\n[motor]\nR = 4.0\n[transmission]\nbacklash = 1e-3\n')
    p = load_params(path, partial=True)
    d = siemens_1fk7060()
    assert p.motor.R == (4.0, 4.0, 4.0)
    assert p.transmission.backlash == 1e-3
    assert p.name == "mine"
    # everything else from the preset
    assert p.motor.L == d.motor.L and p.motor.c0 == d.motor.c0
    assert p.transmission.FSJ == d.transmission.FSJ
    assert p.inverter == d.inverter and p.controller == d.controller and p.load == d.load


def test_partial_file_is_still_validated(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text("[transmission]\nFDJ = 1.0\n")          # above the preset FSJ
    with pytest.raises(ParameterError, match=r"Transmission\.FDJ \[N m\].*exceeds"):
        load_params(path, partial=True)


def test_missing_field_is_named_with_unit(tmp_path):
    d = siemens_1fk7060().to_dict()
    del d["motor"]["L"]
    with pytest.raises(ParameterError, match=r"\[motor\] is missing L \[H\]"):
        ActuatorParams.from_dict(d)
    # through a file: the path is in the message
    import tomli_w
    path = tmp_path / "missing.toml"
    path.write_bytes(tomli_w.dumps(d).encode())
    with pytest.raises(ParameterError, match=r"missing\.toml: \[motor\] is missing L \[H\]"):
        load_params(path)


def test_missing_section_lists_its_fields():
    d = siemens_1fk7060().to_dict()
    del d["load"]
    with pytest.raises(ParameterError, match=r"missing section \[load\] with fields J_l \[kg m\^2\]"):
        ActuatorParams.from_dict(d)


def test_unknown_field_and_section_are_errors(tmp_path):
    d = siemens_1fk7060().to_dict()
    d["motor"]["Rs"] = 3.0
    with pytest.raises(ParameterError, match=r"unknown field\(s\) \['Rs'\] in \[motor\]; known fields:.*R \[ohm\]"):
        ActuatorParams.from_dict(d)
    d = siemens_1fk7060().to_dict()
    d["gearbox"] = {"ratio": 10}
    with pytest.raises(ParameterError, match=r"unknown section\(s\) \['gearbox'\]"):
        ActuatorParams.from_dict(d)
    path = tmp_path / "typo.toml"
    path.write_text("[motor]\nRr = 3.0\n")
    with pytest.raises(ParameterError, match=r"unknown field\(s\) \['Rr'\] in \[motor\]"):
        load_params(path, partial=True)


def test_negative_value_in_file(tmp_path):
    path = tmp_path / "neg.toml"
    path.write_text("[load]\nJ_l = -1e-3\n")
    with pytest.raises(ParameterError, match=r"Load\.J_l \[kg m\^2\] must be > 0, got -0\.001"):
        load_params(path, partial=True)


def test_unreadable_files(tmp_path):
    with pytest.raises(ParameterError, match="does not exist"):
        load_params(tmp_path / "nope.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[motor\nR = ")
    with pytest.raises(ParameterError, match="not valid TOML"):
        load_params(bad)


def test_a_parameter_path_that_is_a_folder_or_binary_is_refused_by_name(tmp_path):
    from emaphm.params import ParameterError, load_params

    with pytest.raises(ParameterError, match=r"parameter file .* is a folder; give a TOML file"):
        load_params(tmp_path)
    bad = tmp_path / "bin.toml"
    bad.write_bytes(b"\xff\xfe\x00binary")
    with pytest.raises(ParameterError, match=r"parameter file .*bin.toml is not"):
        load_params(bad)


def test_saved_parameters_carry_each_fields_unit_as_a_comment(tmp_path):
    from emaphm.params import load_params, save_params, siemens_1fk7060

    p = tmp_path / "m.toml"
    save_params(siemens_1fk7060(), p)
    lines = p.read_text().splitlines()
    for key, unit in (("R", "ohm"), ("J_m", "kg m^2"), ("Kp", "1/s"), ("K_c", "N m/rad"),
                      ("offset", "A, per phase")):
        i = next(n for n, line in enumerate(lines) if line.startswith(f"{key} = "))
        assert lines[i - 1] == f"# {key} [{unit}]"
    assert load_params(p) == siemens_1fk7060()          # the comments read back as nothing


def test_outputs_go_through_one_atomic_writer_that_does_not_follow_a_planted_link(tmp_path):
    import os

    from emaphm._files import atomic_write_text
    from emaphm.params import save_params, siemens_1fk7060

    victim = tmp_path / "victim.txt"
    victim.write_text("keep me")
    # the predictable temporary names the writers used before: a planted symlink there
    # is never written through
    for name in (f".m.toml.tmp-{os.getpid()}", ".m.toml.tmp"):
        (tmp_path / name).symlink_to(victim)
    out = save_params(siemens_1fk7060(), tmp_path / "m.toml")
    assert victim.read_text() == "keep me" and out.read_text().startswith("# emaphm")
    # a failure leaves the old file and no temporary file
    p = tmp_path / "t.txt"
    atomic_write_text(p, "one")
    before = sorted(x.name for x in tmp_path.iterdir())

    class Boom(Exception):
        pass

    from emaphm._files import atomic_write

    def half(fh):
        fh.write(b"half")
        raise Boom

    with pytest.raises(Boom):
        atomic_write(p, half)
    assert p.read_text() == "one" and sorted(x.name for x in tmp_path.iterdir()) == before


@pytest.mark.parametrize("section, changes, words", [
    ("inverter", {"f_pwm": 1e9}, r"inverter.f_pwm \[Hz\] = 1e\+09 is outside 500 Hz"),
    ("inverter", {"f_pwm": 10}, "is outside 500 Hz to 100 kHz"),
    ("motor", {"R": 3150.0}, r"give ohms \(3.15 ohm, not 3150 milliohm\)"),
    ("motor", {"L": 22.0}, r"give henries \(22 mH = 0.022\)"),
    ("motor", {"L": 1e-6}, "electrical time constant L/R of phase a"),
])
def test_implausible_parameter_files_are_refused_with_the_unit_slip(tmp_path, section, changes,
                                                                     words):
    from emaphm.params import ParameterError, load_params, save_params, siemens_1fk7060

    p = tmp_path / "bad.toml"
    save_params(siemens_1fk7060(), p)
    text = p.read_text()
    import tomllib

    import tomli_w

    data = tomllib.loads(text)
    data[section].update(changes)
    p.write_text(tomli_w.dumps(data))
    with pytest.raises(ParameterError, match=words):
        load_params(p)


def test_a_file_from_before_0_3_with_the_contact_under_plant_reads_it_into_transmission(tmp_path):
    """Files written before the monitoring model had the backlash contact kept ``K_c`` and
    ``D_c`` in ``[plant]``; they load, with the values in ``[transmission]``, and are
    written back the new way."""
    d = siemens_1fk7060().to_dict()
    for key in ("K_c", "D_c"):
        del d["transmission"][key]
    d["plant"].update(K_c=2500.0, D_c=0.3)
    p = ActuatorParams.from_dict(d)
    assert (p.transmission.K_c, p.transmission.D_c) == (2500.0, 0.3)
    assert "K_c" not in p.to_dict()["plant"]
    # a partial file the same, and [transmission]'s own value wins over a stale [plant] one
    path = tmp_path / "old.toml"
    path.write_text("[plant]\nomega_s = 2.0\nK_c = 3000.0\n[transmission]\nD_c = 0.7\n")
    q = load_params(path, partial=True)
    assert (q.plant.omega_s, q.transmission.K_c, q.transmission.D_c) == (2.0, 3000.0, 0.7)
    path.write_text("[plant]\nK_c = 3000.0\n[transmission]\nK_c = 3500.0\n")
    assert load_params(path, partial=True).transmission.K_c == 3500.0


# ----------------------------------------------------------------------------- [thresholds]

def test_an_actuators_own_thresholds_round_trip_through_its_file(tmp_path):
    from emaphm.modes import THRESHOLDS_BY_FAULT_MODEL, thresholds_for
    from emaphm.params import Calibration

    own = dataclasses.replace(siemens_1fk7060(), thresholds=(("short_circuit", 0.011),
                                                             ("friction", 0.06),
                                                             ("backlash", 0.05)))
    path = save_params(own, tmp_path / "own.toml")
    assert "[thresholds]" in path.read_text()
    table = path.read_text().split("[thresholds]")[1]
    assert "[rad]" not in table and "dimensionless" in table     # not the backlash's radians
    back = load_params(path)
    assert back.thresholds == (("backlash", 0.05), ("friction", 0.06), ("short_circuit", 0.011))
    default = THRESHOLDS_BY_FAULT_MODEL["physical"]
    # tuned for a calibrated unit: there they apply as they are
    unit = dataclasses.replace(back, calibration=Calibration(date="2026-11-26T00:00:00+00:00"))
    t = thresholds_for("physical", unit)
    assert (t.friction, t.short_circuit, t.backlash) == (0.06, 0.011, 0.05)
    assert t.eccentricity == default.eccentricity
    # on the data sheet only where they raise the defaults
    t = thresholds_for("physical", back)
    assert (t.friction, t.short_circuit, t.backlash) == (default.friction, default.short_circuit,
                                                         0.05)
    # the paper's turn removal keeps its own short-circuit threshold (k3..k5 read another
    # way there); the other modes' tuned thresholds hold under it too (they were ignored)
    t = thresholds_for("paper", unit)
    assert t.short_circuit == THRESHOLDS_BY_FAULT_MODEL["paper"].short_circuit
    assert (t.friction, t.backlash) == (0.06, 0.05)
    assert t == dataclasses.replace(THRESHOLDS_BY_FAULT_MODEL["paper"], friction=0.06,
                                    backlash=0.05)
    # a data sheet without the table keeps the defaults
    assert thresholds_for("physical", siemens_1fk7060()) == default
    # a file without the table writes none
    assert "[thresholds]" not in save_params(siemens_1fk7060(), tmp_path / "p.toml").read_text()


@pytest.mark.parametrize("table,message", [
    ("frictio = 0.1", "unknown threshold 'frictio'; known: backlash"),
    ("friction = 1.5", "friction = 1.5 must be a number in (0, 1)"),
    ("friction = 'high'", "must be a number in (0, 1)"),
])
def test_a_bad_thresholds_table_is_refused_with_the_file_and_the_fix(tmp_path, table, message):
    path = save_params(siemens_1fk7060(), tmp_path / "p.toml")
    path.write_text(path.read_text() + f"\n[thresholds]\n{table}\n")
    with pytest.raises(ParameterError, match=re.escape(f"{path}: [thresholds] ") + ".*"
                       + re.escape(message)):
        load_params(path)


def test_a_diagnosis_and_a_calibration_keep_the_actuators_thresholds():
    from emaphm.diagnosis import diagnose
    from emaphm.modes import DEFAULT_THRESHOLDS
    from emaphm.params import Calibration
    from support import k_with

    sheet = dataclasses.replace(siemens_1fk7060(), thresholds=(("friction", 0.05),))
    unit = dataclasses.replace(sheet, calibration=Calibration(date="2026-11-26T00:00:00+00:00"))
    k = k_with(k1=0.07)
    assert [f.mode for f in diagnose(k, params=unit, fault_model="physical").faults] == ["friction"]
    # on the data sheet the lowered threshold does not apply; without the table neither
    assert not diagnose(k, params=sheet, fault_model="physical").faults
    assert not diagnose(k, params=siemens_1fk7060(), fault_model="physical").faults
    # explicit thresholds still win
    assert not diagnose(k, params=unit, fault_model="physical", thresholds=DEFAULT_THRESHOLDS).faults
    # emaphm calibrate writes the unit with the thresholds of the file it was given
    from emaphm.calibration import calibrate
    from emaphm.simulate import DEFAULT_SENSORS, simulate

    traces = [simulate(model="monitoring", params=sheet, sensors=DEFAULT_SENSORS, seed=s)
              for s in (1, 2)]
    calibrated = calibrate(traces, sheet).params
    assert calibrated.calibration.date and calibrated.thresholds == sheet.thresholds
    assert [f.mode for f in diagnose(k, params=calibrated, fault_model="physical").faults] == \
        ["friction"]


# --------------------------------------------------------------------------- issue 37: bounds
def _from_preset(changes: dict) -> ActuatorParams:
    data = siemens_1fk7060().to_dict()
    for (sec, name), value in changes.items():
        data[sec][name] = value
    return ActuatorParams.from_dict(data, source="p.toml")


def test_the_preset_and_the_examples_are_well_inside_every_bound():
    import warnings
    from pathlib import Path

    from emaphm.params import PlausibilityWarning, check_plausible

    examples = Path(__file__).resolve().parents[1] / "examples" / "actuators"
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlausibilityWarning)
        check_plausible(siemens_1fk7060())
        check_plausible(load_params(examples / "ema-270v-750w.toml"))


def test_every_parameter_beyond_its_bound_is_refused_by_name():
    """Each bound of emaphm.params.PLAUSIBLE, ten times beyond it: refused, the field named
    (by its bound or by an earlier check of the same field, e.g. L above 1 H)."""
    from emaphm.params import PLAUSIBLE

    checked = 0
    for (sec, name), (lo, _, _, hi, _) in PLAUSIBLE.items():
        for bad in ([hi * 10] if hi is not None else []) + ([lo / 10 if lo > 0 else lo * 10]
                                                          if lo is not None else []):
            value = int(bad) if name == "p" else bad
            with pytest.raises(ParameterError, match=rf"(?i){sec}\.{name}\b"):
                _from_preset({(sec, name): value})
            checked += 1
    assert checked == 42


@pytest.mark.parametrize("changes, words", [
    ({("motor", "J_m"): 1e-30}, r"motor.J_m \[kg m\^2\] = 1e-30 is beyond what any servo actuator "
                                r"has \(1e-09 to 100\): give kg m\^2"),
    ({("motor", "p"): 10 ** 12}, r"motor.p \[pole pairs, integer\] = 1e\+12 is beyond"),
    ({("motor", "c0"): 7.8e305}, r"motor.c0 \[V s/rad\] = 7.8e\+305 is beyond"),
    ({("motor", "J_m"): 1e-7}, r"controller.Kp_w = 0.6 N m s/rad on motor.J_m = 1e-07 kg m\^2 is a "
                               r"speed loop gain of 750 per period"),
    ({("motor", "L"): 1e-3}, r"current loop gain of 5.22 per period \(Kp_i T_s / L\), above the 2 "
                             r"where a sampled loop diverges"),
])
def test_absurd_motors_are_refused(changes, words):
    with pytest.raises(ParameterError, match=words):
        _from_preset(changes)


def test_a_value_near_the_edge_is_used_with_one_warning():
    from emaphm.params import PlausibilityWarning

    with pytest.warns(PlausibilityWarning, match=r"p.toml: controller.omega_max \[rad/s\] = 20000 "
                                                 r"is unlike a servo actuator's \(usually 1 to "
                                                 r"10000\)"):
        p = _from_preset({("controller", "omega_max"): 2e4})
    assert p.controller.omega_max == 2e4
    with pytest.warns(PlausibilityWarning, match=r"speed loop gain of 3.75 per period, above the "
                                                 r"2 of a stable loop"):
        _from_preset({("motor", "J_m"): 2e-5})
