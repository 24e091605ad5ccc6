"""The drive's own signals in a trace: kept whole, written and read back, and read as the
phase voltages the drive applied (:mod:`emaphm.traces.drive_signals`)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from emaphm.simulate import simulate
from emaphm.traces import DRIVE_COLUMNS, Trace, TraceError, fingerprint, read_trace, resample, write_trace
from emaphm.traces.drive_signals import (applied_voltages, check_commands, control_samples,
                                         delay_periods, voltage_form)

T_S = 1.25e-4
N = 400


def _trace(drive=None, dt=T_S, n=N, meta=None):
    t = np.arange(n) * dt
    theta = 20.0 * t
    i = np.column_stack([np.sin(4 * theta), np.sin(4 * theta - 2.1), np.sin(4 * theta + 2.1)])
    return Trace(t=t, theta_ref=theta, theta_m=theta, omega_m=np.full(n, 20.0), i_abc=i,
                 meta=meta or {}, drive=drive or {})


@pytest.fixture(scope="module")
def plant():
    """A plant trace with its drive's log (emaphm's drive, the preset, noise-free)."""
    return simulate(scenario="friction-low", drive_signals=True)


def test_a_group_comes_whole_or_not_at_all():
    n = N
    with pytest.raises(TraceError, match="phase voltages come together .* without v_c"):
        _trace({"v_a": np.zeros(n), "v_b": np.zeros(n)})
    with pytest.raises(TraceError, match="duty cycles come together .* without v_dc"):
        _trace({"d_a": np.zeros(n), "d_b": np.zeros(n), "d_c": np.zeros(n)})
    with pytest.raises(TraceError, match="i_d_ref without i_q_ref"):
        _trace({"i_d_ref": np.zeros(n)})
    with pytest.raises(TraceError, match="unknown signal"):
        _trace({"v_x": np.zeros(n)})
    with pytest.raises(TraceError, match="has 3 samples but t has"):
        _trace({"omega_ref": np.zeros(3)})
    # v_dc alone, i_q_ref alone and omega_ref alone are whole
    tr = _trace({"v_dc": np.full(n, 600.0), "i_q_ref": np.zeros(n), "omega_ref": np.zeros(n)})
    assert sorted(tr.drive) == ["i_q_ref", "omega_ref", "v_dc"]
    assert voltage_form(tr) is None


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_drive_signals_round_trip_through_emaphms_files(plant, tmp_path, suffix):
    path = write_trace(plant, tmp_path / f"t{suffix}")
    back = read_trace(path)
    assert back == plant
    assert list(back.drive) == ["v_a", "v_b", "v_c", "i_d_ref", "i_q_ref", "omega_ref"]
    assert back.meta["voltage_delay_periods"] == 0


def test_drive_signals_in_frames_resampling_and_the_fingerprint(plant):
    pytest.importorskip("pandas")
    df = plant.to_pandas()
    assert {"v_a", "i_q_ref", "omega_ref"} <= set(df.columns)
    assert Trace.from_pandas(df) == plant
    half = resample(plant, plant.t[:-1] + 0.5 * T_S)
    np.testing.assert_allclose(half.drive["i_q_ref"],
                               0.5 * (plant.drive["i_q_ref"][:-1] + plant.drive["i_q_ref"][1:]))
    # a trace's fingerprint covers its drive signals; one without any keeps its old one
    bare = Trace(plant.t, plant.theta_ref, plant.theta_m, plant.omega_m, plant.i_abc,
                 meta=plant.meta)
    assert fingerprint(bare) != fingerprint(plant)
    assert fingerprint(bare) == fingerprint(Trace(plant.t, plant.theta_ref, plant.theta_m,
                                                  plant.omega_m, plant.i_abc))
    assert set(DRIVE_COLUMNS) >= set(plant.drive)


def test_the_three_forms_of_command_give_the_same_phase_voltages(plant):
    """A plant's logged phase voltages, the same as dq voltages at the sampled angle and as
    duty cycles on a 600 V link, read back as the same applied phase voltages."""
    p = 4
    idx = control_samples(plant, T_S)
    v = applied_voltages(plant, idx, p)
    theta_e = p * plant.theta_m
    v_a, v_b, v_c = (plant.drive[x] for x in ("v_a", "v_b", "v_c"))
    al = (2 * v_a - v_b - v_c) / 3
    be = (v_b - v_c) / math.sqrt(3)
    v_d = -(al * np.cos(theta_e) + be * np.sin(theta_e))
    v_q = al * np.sin(theta_e) - be * np.cos(theta_e)
    dq = Trace(plant.t, plant.theta_ref, plant.theta_m, plant.omega_m, plant.i_abc,
               drive={"v_d": v_d, "v_q": v_q})
    np.testing.assert_allclose(applied_voltages(dq, idx, p), v, atol=1e-9)
    duties = {f"d_{x}": 0.5 + plant.drive[f"v_{x}"] / 600.0 for x in "abc"}
    dc = Trace(plant.t, plant.theta_ref, plant.theta_m, plant.omega_m, plant.i_abc,
               drive={**duties, "v_dc": np.full(plant.n, 600.0)})
    np.testing.assert_allclose(applied_voltages(dc, idx, p), v, atol=1e-9)
    assert voltage_form(dq) == "dq voltages" and voltage_form(dc) == "duty cycles"
    np.testing.assert_allclose(v.sum(axis=1), 0.0, atol=1e-9)   # star-referenced


def test_a_period_of_delay_shifts_the_commands():
    n = N
    ramp = np.arange(n, dtype=float)
    tr = _trace({"v_a": ramp, "v_b": -ramp, "v_c": np.zeros(n)}, meta={"voltage_delay_periods": 1})
    assert delay_periods(tr) == 1
    v = applied_voltages(tr, control_samples(tr, T_S), 4)
    assert v[0, 0] == pytest.approx(0.0) and v[5, 0] == pytest.approx(4.0)
    bad = _trace({"v_a": ramp, "v_b": -ramp, "v_c": np.zeros(n)}, meta={"voltage_delay_periods": 2})
    with pytest.raises(TraceError, match="voltage_delay_periods = 2.*give 0 or 1"):
        delay_periods(bad)


def test_commands_come_once_per_control_period_or_a_whole_fraction_of_it():
    z = {"v_a": np.zeros(N), "v_b": np.zeros(N), "v_c": np.zeros(N)}
    np.testing.assert_array_equal(control_samples(_trace(z), T_S), np.arange(N))
    np.testing.assert_array_equal(control_samples(_trace(z, dt=T_S / 4), T_S)[:3], [0, 4, 8])
    with pytest.raises(TraceError, match="decimated log"):
        control_samples(_trace(z, dt=2 * T_S), T_S)
    with pytest.raises(TraceError, match="no whole fraction of the control period"):
        control_samples(_trace(z, dt=T_S / 1.5), T_S)


def test_commands_no_inverter_applies_are_refused():
    n = N
    v = np.column_stack([np.full(n, 700.0), np.full(n, -350.0), np.full(n, -350.0)])
    tr = _trace({"v_a": v[:, 0], "v_b": v[:, 1], "v_c": v[:, 2]})
    with pytest.raises(TraceError, match="beyond the DC link of 600 V"):
        check_commands(tr, v, 600.0)
    duty = {"d_a": np.full(n, 50.0), "d_b": np.zeros(n), "d_c": np.zeros(n),
            "v_dc": np.full(n, 600.0)}
    with pytest.raises(TraceError, match="outside \\[0, 1\\].*not percent"):
        check_commands(_trace(duty), np.zeros((n, 3)), 600.0)
    dead = {**duty, "d_a": np.zeros(n), "v_dc": np.zeros(n)}
    with pytest.raises(TraceError, match="v_dc is 0 V"):
        check_commands(_trace(dead), np.zeros((n, 3)), 600.0)


def test_a_bench_export_maps_the_drives_channels_like_any(plant, tmp_path):
    """A logger's CSV in its own units (ms, deg, mV for the voltages, percent duties would be
    refused later): the map names the drive's channels and the log's delay; the import puts
    them in the trace in SI, and the recorded-voltage path reads them."""
    from emaphm.traces.importers import ChannelMap, import_trace
    import tomllib

    t_ms = plant.t * 1e3
    cols = {"time_ms": t_ms, "cmd_deg": np.degrees(plant.theta_ref),
            "pos_deg": np.degrees(plant.theta_m), "ia": plant.i_abc[:, 0], "ib": plant.i_abc[:, 1],
            "ua_mV": plant.drive["v_a"] * 1e3, "ub_mV": plant.drive["v_b"] * 1e3,
            "uc_mV": plant.drive["v_c"] * 1e3, "iq_set": plant.drive["i_q_ref"]}
    path = tmp_path / "rig.csv"
    with path.open("w") as f:
        f.write(",".join(cols) + "\n")
        for row in np.column_stack(list(cols.values())):
            f.write(",".join(repr(float(x)) for x in row) + "\n")
    cmap = ChannelMap.from_dict(tomllib.loads('''
[source]
voltage_delay_periods = 0
[channels]
t = { name = "time_ms", unit = "ms" }
theta_ref = { name = "cmd_deg", unit = "deg" }
theta_m = { name = "pos_deg", unit = "deg" }
i_a = { name = "ia", unit = "A" }
i_b = { name = "ib", unit = "A" }
v_a = { name = "ua_mV", unit = "mV" }
v_b = { name = "ub_mV", unit = "mV" }
v_c = { name = "uc_mV", unit = "mV" }
i_q_ref = { name = "iq_set", unit = "A" }
'''), source="map.toml")
    tr = import_trace(path, cmap)
    assert tr.meta["voltage_delay_periods"] == 0
    np.testing.assert_allclose(tr.drive["v_a"], plant.drive["v_a"], rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(tr.drive["i_q_ref"], plant.drive["i_q_ref"], atol=1e-12)
    assert voltage_form(tr) == "phase voltages"
    bad = ChannelMap.from_dict
    with pytest.raises(TraceError, match="voltage_delay_periods = 2"):
        bad(tomllib.loads('[source]\nvoltage_delay_periods = 2\n[channels]\ntheta_ref = "a"\n'
                          'theta_m = "b"\ni_a = "c"\ni_b = "d"\n'), source="map.toml")
