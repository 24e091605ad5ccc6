"""``emaphm params --datasheet`` (issue 22): catalogue units to emaphm's per-phase SI
parameters, the drive's gains derived as the preset's were; and the second actuator of our
design (examples/actuators/ema-270v-750w)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from emaphm.cli import main
from emaphm.datasheet import Nameplate, convert, load_nameplate
from emaphm.params import (ParameterError, derive_tuning, load_params,
                           siemens_1fk7060)

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "actuators"


def _plate(**fields) -> Nameplate:
    return Nameplate.from_dict({"datasheet": fields}, source="plate.toml")


def test_the_presets_nameplate_gives_the_presets_parameter_file():
    got = convert(load_nameplate(EXAMPLES / "siemens-1fk7060.nameplate.toml")).params.to_dict()
    want = siemens_1fk7060().to_dict()
    # the preset writes 10 A rms as 14.14 A peak; sqrt(2) x 10 is 14.1421
    assert got["motor"].pop("I_max") == pytest.approx(want["motor"].pop("I_max"), rel=2e-4)
    assert got == want


def test_derive_tuning_on_the_presets_own_motor_is_the_preset():
    p = siemens_1fk7060()
    tune = derive_tuning(p.motor, p.inverter.f_pwm, p.load.J_l)
    assert (tune.Kp_i, tune.Ki_i, tune.I_trip) == (p.inverter.Kp_i, p.inverter.Ki_i,
                                                   p.inverter.I_trip)
    assert (tune.Kp, tune.Kp_w, tune.Ki_w, tune.k_T) == (p.controller.Kp, p.controller.Kp_w,
                                                         p.controller.Ki_w, p.controller.k_T)


def test_tuning_keeps_the_loops_bandwidths():
    p = siemens_1fk7060()
    other = convert(_plate(poles=6, ke=57, r_ll="1.22 ohm", l_ll="8.4 mH", j_rotor="5.43 kg cm^2",
                           t_max="23 N m", i_max="30 A", f_pwm="16 kHz")).params
    # current loop crossover Kp_i / L and zero Ki_i / Kp_i against R / L, per control rate
    assert other.inverter.Kp_i / other.motor.L[0] / other.inverter.f_pwm == pytest.approx(
        p.inverter.Kp_i / p.motor.L[0] / p.inverter.f_pwm)
    assert other.inverter.Ki_i / other.motor.R[0] == pytest.approx(
        2 * p.inverter.Ki_i / p.motor.R[0])
    J, J0 = other.motor.J_m + other.load.J_l, p.motor.J_m + p.load.J_l
    assert other.controller.Kp_w / J == pytest.approx(2 * p.controller.Kp_w / J0)
    assert other.controller.Kp == 2 * p.controller.Kp


def test_a_catalogue_motor_converts_to_its_data_sheets_per_phase_values():
    # Siemens 1FT7044-AK7, Configuration Manual 1FT7 (PFT7S) 01/2009, 6SN1197-0AD13-0BP2,
    # Table 4-8: 2p = 6, k_T = 0.88 N m/A, k_E = 57 V/1000 rpm, R_ph = 0.61 ohm, L_D = 4.2 mH,
    # J = 5.43e-4 kg m^2, M_max = 23 N m, I_max = 30 A, T_el = 7 ms, T_mech = 1.3 ms. Given
    # here line to line, as most catalogues print them (twice the star's phase values).
    sheet = convert(_plate(name="1FT7044-AK7", poles=6, ke="57 V/krpm", kt="0.88 N m/A",
                           r_ll="1.22 ohm", l_ll="8.4 mH", j_rotor="5.43 kg cm^2",
                           t_max="23 N m", i_max="30 A", v_dc="600 V"))
    m = sheet.params.motor
    assert m.p == 3
    assert m.R[0] == pytest.approx(0.61, rel=0.01)
    assert m.L[0] == pytest.approx(4.2e-3, rel=0.01)
    assert m.J_m == pytest.approx(5.43e-4, rel=0.01)
    assert m.L[0] / m.R[0] == pytest.approx(7e-3, rel=0.02)                       # T_el
    assert 3 * m.R[0] * m.J_m / 0.88 ** 2 == pytest.approx(1.3e-3, rel=0.03)      # T_mech
    assert m.c0[0] == pytest.approx(math.sqrt(2) * 57 / math.sqrt(3) / (2 * math.pi * 1000 / 60))
    assert m.I_max == pytest.approx(30 * math.sqrt(2))
    # the catalogue's k_T (warm, 100 K) is 7 % under what its k_E (20 C) gives: said
    assert any("disagree by -6.7 %" in w for w in sheet.warnings), sheet.warnings


def test_per_phase_values_and_other_units_are_read():
    a = convert(_plate(poles=6, ke="57 mV/rpm", r_ph="0.61 ohm", l_ph="4.2 mH",
                       j_rotor="543 kg mm^2", t_max=23, i_max=30)).params.motor
    b = convert(_plate(poles=6, ke=f"{57 / (2000 * math.pi / 60)} V s/rad", r_ll=1.22,
                       l_ll=8.4e-3, j_rotor="5.43 kg cm^2", t_max="23 Nm", i_max="30 A")).params.motor
    for name in ("R", "L", "c0"):
        np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=1e-12)
    assert a.J_m == pytest.approx(b.J_m)


@pytest.mark.parametrize("fields, match", [
    (dict(poles=5), r"5 poles is odd; poles counts the magnet poles .*poles = 10"),
    (dict(r_ph=1.0), r"gives both r_ll \(line to line\) and r_ph \(per phase\); give one of "
                     r"them"),
    (dict(r_ll=None), r"missing r_ll \(or r_ph\)$"),
    (dict(ke="57 V/A"), r"unknown unit 'V/A' for a back-EMF constant"),
    (dict(j_rotor="1.1 kg"), r"unknown unit 'kg' for a inertia"),
    (dict(colour="red"), r"unknown field\(s\) \['colour'\]"),
    (dict(t_max=-1), r"t_max: expected a positive number"),
])
def test_nameplate_errors_name_the_field(fields, match):
    base = dict(poles=8, ke=135, r_ll=6.3, l_ll="44 mH", j_rotor="7.7 kg cm^2", t_max=18,
                i_max=10)
    with pytest.raises(ParameterError, match=match):
        _plate(**{k: v for k, v in {**base, **fields}.items() if v is not None})


def test_implausible_values_are_warned_about():
    sheet = convert(_plate(poles=8, ke=135, r_ll=6.3, l_ll="44 mH", j_rotor="7.7 kg cm^2",
                           t_max=60, i_max=10, n_max="6000 rpm"))
    text = " ".join(sheet.warnings)
    assert "t_max = 60 N m is more than the 22.3 N m that i_max = 10 A rms gives" in text
    assert "back-EMF at omega_max = 628.3 rad/s is 661.4 V peak per phase" in text


def test_a_bare_rotor_inertia_meant_in_kg_cm2_is_warned_about():
    """j_rotor = 0.45 (meant 0.45 kg cm^2) is 0.45 kg m^2, within 1e-7 to 1 kg m^2, but a
    3.6 N m motor would accelerate at 8 rad/s^2: said, with the unit to give. The two
    actuators we ship are far inside the range."""
    base = dict(poles=8, ke=135, r_ll=6.3, l_ll="44 mH", t_max=3.6, i_max=2)
    text = " ".join(convert(_plate(**base, j_rotor=0.45)).warnings)
    assert "t_max / j_rotor = 8 rad/s^2 is unlike a servo motor's (300 to 1e+06 rad/s^2)" in text
    assert 'catalogues print kg cm^2: give the unit, e.g. "1.3 kg cm^2"' in text
    assert not any("t_max / j_rotor" in w for w in
                   convert(_plate(**base, j_rotor="0.45 kg cm^2")).warnings)
    plate = load_nameplate(EXAMPLES / "ema-270v-750w.nameplate.toml")
    assert not any("t_max / j_rotor" in w for w in convert(plate).warnings)


def test_a_nameplate_given_as_parameters_says_to_convert_it(tmp_path):
    with pytest.raises(ParameterError, match=r"a \[datasheet\] table is a motor's catalogue "
                                             r"page, not parameters; convert it first: emaphm "
                                             r"params --datasheet FILE --out PARAMS.toml"):
        load_params(EXAMPLES / "ema-270v-750w.nameplate.toml")


def test_cli_writes_the_parameters_and_prints_the_warnings(tmp_path, capsys):
    (tmp_path / "m.toml").write_text('[datasheet]\nname = "x"\npoles = 6\nke = "57 V/krpm"\n'
                                     'kt = "0.88 N m/A"\nr_ll = "1.22 ohm"\nl_ll = "8.4 mH"\n'
                                     'j_rotor = "5.43 kg cm^2"\nt_max = "23 N m"\ni_max = "30 A"\n')
    assert main(["params", "--datasheet", str(tmp_path / "m.toml"), "--out",
                 str(tmp_path / "p.toml")]) == 0
    out, err = capsys.readouterr()
    assert "motor.R [ohm]                  0.61  line to line 1.22 ohm / 2" in out
    assert "emaphm params: warning: kt = 0.88 N m/A rms and ke = 57 V/krpm disagree" in err
    assert load_params(tmp_path / "p.toml").motor.p == 3


# ----------------------------------------------------------------------------- ema-270v-750w
def test_the_second_actuator_file_is_its_nameplates_conversion():
    plate = load_nameplate(EXAMPLES / "ema-270v-750w.nameplate.toml")
    assert load_params(EXAMPLES / "ema-270v-750w.toml") == convert(plate).params


def test_the_second_actuator_follows_the_diagnostic_profile():
    from emaphm.simulate import simulate

    params = load_params(EXAMPLES / "ema-270v-750w.toml")
    assert (params.motor.p, params.inverter.V_dc) == (5, 270.0)
    for model in ("monitoring", "reference"):
        tr = simulate(model=model, params=params)
        lag = tr.theta_ref - tr.theta_m
        assert abs(lag[-1]) < 0.02, model                 # settled at the end of the test
        assert np.max(np.abs(lag)) < 1.1, model            # ramps followed at Kp's lag
        assert np.max(np.abs(tr.i_abc)) < params.motor.I_max, model
        assert tr.meta["status"] == "ok" if "status" in tr.meta else True
