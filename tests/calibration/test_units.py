"""Production units (emaphm.units) and the acquisition chain (emaphm.acquisition)."""

import numpy as np
import pytest

from emaphm.acquisition import Sensors
from emaphm.params import siemens_1fk7060
from emaphm.units import (DEFAULT_TOLERANCES, Tolerances, draw_unit, load_tolerances,
                          nominal_unit)

NOMINAL = siemens_1fk7060()


def test_same_seed_same_unit_other_seed_other_unit():
    a, b, c = draw_unit(NOMINAL, 3), draw_unit(NOMINAL, 3), draw_unit(NOMINAL, 4)
    assert a == b
    assert a.params != c.params


def test_drawn_units_stay_inside_their_tolerances():
    t = DEFAULT_TOLERANCES
    m0, tr0 = NOMINAL.motor, NOMINAL.transmission
    devs = []
    for seed in range(200):
        u = draw_unit(NOMINAL, seed)
        m = u.params.motor
        dJ = m.J_m / m0.J_m - 1
        assert t.J[0] <= dJ <= t.J[1]
        assert u.params.load.J_l / NOMINAL.load.J_l - 1 == pytest.approx(dJ)
        assert t.flux[0] <= m.c0[0] / m0.c0[0] - 1 <= t.flux[1]
        assert t.R[0] <= m.R[0] / m0.R[0] - 1 <= t.R[1]
        assert t.L[0] <= m.L[0] / m0.L[0] - 1 <= t.L[1]
        assert t.friction[0] <= u.params.transmission.FSJ / tr0.FSJ - 1 <= t.friction[1]
        assert all(t.sensor_gain[0] <= g - 1 <= t.sensor_gain[1] for g in u.sensor_gain)
        assert all(t.sensor_offset[0] <= o <= t.sensor_offset[1] for o in u.sensor_offset)
        assert t.load[0] <= u.load <= t.load[1]
        tr = u.params.transmission
        assert t.stiffness[0] <= tr.K_c / tr0.K_c - 1 <= t.stiffness[1]
        assert t.damping[0] <= tr.D_c / tr0.D_c - 1 <= t.damping[1]
        # the drive keeps its data-sheet torque constant: the firmware does not know the unit
        assert u.params.controller.resolved(NOMINAL.motor, NOMINAL.load) == \
            NOMINAL.controller.resolved(NOMINAL.motor, NOMINAL.load)
        devs.append(dJ)
    # uniform over the interval: the draws cover it
    assert min(devs) < -0.08 and max(devs) > 0.08


def test_the_nominal_unit_is_the_data_sheet():
    u = nominal_unit(NOMINAL)
    assert u.params == NOMINAL and u.load == 0 and u.sensor_gain == (1, 1, 1)


def test_tolerances_from_toml_and_bad_ones_named(tmp_path):
    p = tmp_path / "tol.toml"
    p.write_text("[tolerances]\nJ = [-0.02, 0.02]\nload = [0.0, 0.05]\n")
    t = load_tolerances(p)
    assert t.J == (-0.02, 0.02) and t.load == (0.0, 0.05) and t.R == DEFAULT_TOLERANCES.R
    p.write_text("[tolerances]\ninertia = [0, 1]\n")
    with pytest.raises(ValueError, match=r"unknown tolerance\(s\) \['inertia'\]"):
        load_tolerances(p)
    with pytest.raises(ValueError, match="relative deviation"):
        Tolerances(J=(-0.1, 10.0))
    with pytest.raises(ValueError, match="lo <= hi"):
        Tolerances(R=(0.2, 0.1))
    with pytest.raises(ValueError, match="give it in amperes"):
        Tolerances(sensor_offset=(-20.0, 20.0))
    with pytest.raises(ValueError, match="does not exist"):
        load_tolerances(tmp_path / "missing.toml")
    with pytest.raises(ValueError, match="unit seed must be a non-negative integer"):
        draw_unit(NOMINAL, -1)


def test_sensor_gain_and_offset_act_per_phase():
    i = np.tile([[1.0, -0.5, -0.5]], (4, 1))
    s = Sensors(gain=(1.03, 1.0, 0.97), offset=(0.01, 0.0, -0.02))
    _, out = s.apply(np.zeros(4), i, None)
    assert out[0] == pytest.approx([1.04, -0.5, -0.505])
    # ideal sensors leave the currents bit for bit
    _, same = Sensors().apply(np.zeros(4), i, None)
    assert np.array_equal(same, i)
    with pytest.raises(ValueError, match="Sensors.gain"):
        Sensors(gain=(1.0, 1.0))


def test_a_faster_recording_through_an_anti_alias_filter():
    from emaphm.simulate import DEFAULT_SENSORS, simulate

    s = Sensors(current_noise=0.02, current_lsb=DEFAULT_SENSORS.current_lsb, f_sample=20000.0,
                aa_order=2, aa_cutoff=4000.0)
    tr = simulate(scenario="friction-high", model="monitoring", sensors=s, seed=5)
    assert np.median(np.diff(tr.t)) == pytest.approx(5e-5)
    assert tr.t[-1] <= 0.5 and tr.meta["sensors"]["aa_cutoff"] == 4000.0
    # the filter makes the noise band-limited: neighbouring noise samples correlate
    clean = simulate(scenario="friction-high", model="monitoring",
                     sensors=Sensors(f_sample=20000.0, aa_order=2, aa_cutoff=4000.0))
    n = tr.i_abc - clean.i_abc
    rho = np.corrcoef(n[:-1, 0], n[1:, 0])[0, 1]
    assert rho > 0.5
    with pytest.raises(ValueError, match="aa_cutoff"):
        Sensors(f_sample=20000.0, aa_order=2, aa_cutoff=12000.0)
    with pytest.raises(ValueError, match="f_sample"):
        Sensors(f_sample=-1.0)


def test_band_limited_noise_is_not_read_as_misfit():
    # 20 kHz through a 2nd-order 4 kHz anti-alias filter: the noise floor is measured on
    # the model grid, where the band-limited noise is nearly white (before: 7x the floor,
    # flagged and restarted); measured ratio 1.10, error 0.45 %
    from emaphm.diagnosis import diagnose, fit_ratio_of
    from emaphm.identify import identify
    from emaphm.simulate import DEFAULT_SENSORS, simulate

    s = Sensors(current_noise=0.02, current_lsb=DEFAULT_SENSORS.current_lsb, f_sample=20000.0,
                aa_order=2, aa_cutoff=4000.0)
    tr = simulate(scenario="friction-high", model="monitoring", sensors=s, seed=5)
    ident = identify(tr, "pso", seed=0)
    assert ident.restarts == 0 and fit_ratio_of(ident) < 1.5
    assert ident.error_pct < 1.0
    d = diagnose(ident.k, fault_model=ident.fault_model, fit_ratio=fit_ratio_of(ident))
    assert d.verdict == "faulty" and d.modes == ("friction",)


def test_a_declared_anti_alias_filter_is_aligned_not_read_as_a_fault():
    # 20 kHz through a 2nd-order 2 kHz filter: its 112.5 us lag is misfit when unknown
    # (measured 2.82x, restarted, unexplained); declared in the parameters, the currents
    # are aligned by it (measured 1.97x, no restart, error 0.28 %)
    from dataclasses import replace

    from emaphm.diagnosis import diagnose, fit_ratio_of
    from emaphm.identify import identify
    from emaphm.params import CurrentSensors
    from emaphm.simulate import DEFAULT_SENSORS, simulate

    cs = CurrentSensors(aa_order=2, aa_cutoff=2000.0)
    assert cs.lag() == pytest.approx(np.sqrt(2) / (2 * np.pi * 2000.0))
    assert CurrentSensors(delay=1e-4).lag() == 1e-4 and CurrentSensors().lag() == 0.0
    s = Sensors(current_noise=0.02, current_lsb=DEFAULT_SENSORS.current_lsb, f_sample=20000.0,
                aa_order=2, aa_cutoff=2000.0)
    tr = simulate(scenario="friction-high", model="monitoring", sensors=s, seed=5)
    ident = identify(tr, "pso", seed=0, params=replace(NOMINAL, sensors=cs))
    assert ident.restarts == 0 and ident.error_pct < 1.0
    d = diagnose(ident.k, fault_model=ident.fault_model, fit_ratio=fit_ratio_of(ident))
    assert d.verdict == "faulty" and d.modes == ("friction",)


def test_the_contact_tolerances_drawn_last_leave_earlier_units_as_they_were():
    """The contact's stiffness and damping joined the tolerances after units had been
    drawn and benchmarked; they are drawn last, so a seed's other deviations are those
    it had before (unit seed 20001, recorded in benchmarks/results/commissioning.json)."""
    d = draw_unit(NOMINAL, 20001).deviations
    assert d["J"] == -0.09872156978281188 and d["load"] == 0.044326844431106516
    assert d["sensor_offset"][2] == 0.0192547318536198
    assert {"stiffness", "damping"} <= set(d)
