"""Command and load profiles: shapes' known values, round trips, the diagnostic test's coverage."""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from emaphm.profiles import (PROFILES, Chirp, Constant, Profile, ProfileError, Ramp, Sine, Step,
                             Tabulated, Trapezoid, chirp, diagnostic, get_profile, read_profile,
                             sine)

T_S = 125e-6                     # the default control period
fine = st.floats(allow_nan=False, allow_infinity=False)


# --------------------------------------------------------------------------- shapes

def test_step_known_values():
    s = Step(t0=0.02, height=0.5)
    t = np.array([0.0, 0.019999, 0.02, 0.021, 1.0])
    assert s(t).tolist() == [0.0, 0.0, 0.5, 0.5, 0.5]


def test_ramp_known_values_and_slope():
    r = Ramp(t0=0.1, t1=0.25, height=3 * math.pi)
    t = np.arange(0.0, 0.4, T_S)
    y = r(t)
    assert np.all(y[t <= 0.1] == 0.0)
    assert np.allclose(y[t >= 0.25], 3 * math.pi, rtol=0, atol=1e-12)
    inside = (t > 0.1 + 2 * T_S) & (t < 0.25 - 2 * T_S)
    slope = np.gradient(y, t)[inside]
    assert slope == pytest.approx(3 * math.pi / 0.15, rel=1e-9)      # 62.8 rad/s
    assert r(np.array([0.175]))[0] == pytest.approx(1.5 * math.pi)


def test_sine_known_values():
    s = Sine(amplitude=2.0, frequency=5.0, t0=0.1, t1=0.3)
    t = np.array([0.0, 0.1, 0.15, 0.2, 0.25, 0.3, 0.4])
    np.testing.assert_allclose(s(t), [0.0, 0.0, 2.0, 0.0, -2.0, 0.0, 0.0], atol=1e-12)


def test_chirp_known_values_and_its_sweep():
    c = Chirp(amplitude=2.0, f0=1.0, f1=9.0, t0=0.5, t1=1.5)
    # phase 2 pi (f0 tau + (f1 - f0) tau^2 / (2 T)): the first crest is where
    # tau + 4 tau^2 = 1/4, tau = (sqrt(5) - 1) / 8, sooner than a quarter period of f0
    crest = 0.5 + (math.sqrt(5) - 1) / 8
    np.testing.assert_allclose(c(np.array([0.0, 0.5, crest, 1.5, 2.0])), [0, 0, 2.0, 0, 0],
                               atol=1e-12)
    # the instantaneous frequency rises linearly: zero crossings every half period
    t = np.arange(0.5, 1.5, 1e-6)
    y = c(t)
    cross = t[1:][np.sign(y[1:]) != np.sign(y[:-1])]
    f_inst = 0.5 / np.diff(cross)
    mid = 0.5 * (cross[1:] + cross[:-1])
    np.testing.assert_allclose(f_inst, 1.0 + 8.0 * (mid - 0.5), rtol=2e-3)


def test_sine_and_chirp_defaults_suit_a_diagnosis():
    """Like the diagnostic profile: a hold at rest first, more than one revolution of
    motion, reversals, and speeds and accelerations the preset follows easily."""
    from emaphm.params import siemens_1fk7060

    m = siemens_1fk7060()
    J = m.motor.J_m + m.load.J_l
    for p in (sine(), chirp()):
        t = p.grid(T_S)
        y = p.theta_ref(t)
        assert np.all(y[t < 0.02] == 0.0)                         # at rest first
        assert np.ptp(y) > 2 * math.pi * 1.2                        # > a revolution
        v = np.gradient(y, t)
        reversals = np.count_nonzero(np.diff(np.sign(v[np.abs(v) > 1.0])))
        assert reversals >= 2
        assert 0.5 <= p.duration <= 0.7                             # a diagnostic's length
        a = np.gradient(v, t)[t > 0.03]
        assert np.max(np.abs(v)) < 150.0                            # rad/s
        assert J * np.max(np.abs(a)) < 0.5 * m.motor.T_max           # N m of inertia torque
    assert chirp().command == (Chirp(4.0, 1.0, 5.0, 0.02, 0.62),)


def test_tabulated_interpolates_and_holds_the_ends():
    tab = Tabulated(t=(0.0, 0.1, 0.3), values=(1.0, 2.0, 0.0))
    x = tab(np.array([-1.0, 0.0, 0.05, 0.1, 0.2, 0.3, 5.0]))
    np.testing.assert_allclose(x, [1.0, 1.0, 1.5, 2.0, 1.0, 0.0, 0.0], rtol=0, atol=1e-15)
    assert isinstance(Tabulated(t=np.array([0.0, 1.0]), values=[0, 1]).t, tuple)


def test_profile_from_samples_replays_a_recorded_command():
    rng = np.random.default_rng(0)
    t = 2.5 + np.arange(400) * T_S                    # a recording need not start at 0
    theta = np.cumsum(rng.normal(size=400)) * 1e-3
    load = rng.normal(size=400) * 0.1
    p = Profile.from_samples(t, theta, load)
    g = p.grid(T_S)
    assert g.size == 400
    np.testing.assert_allclose(g, t - t[0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(p.theta_ref(g), theta, rtol=0, atol=1e-12)
    np.testing.assert_allclose(p.load_torque(g), load, rtol=0, atol=1e-12)
    assert Profile.from_dict(json.loads(json.dumps(p.to_dict()))) == p


def test_constant():
    assert Constant(1.5)(np.zeros((4,))).tolist() == [1.5] * 4


@given(t0=st.floats(0.0, 0.1), height=st.floats(-20.0, 20.0).filter(lambda h: abs(h) > 1e-3),
       v_max=st.floats(1.0, 200.0), a_max=st.floats(100.0, 2e4))
def test_trapezoid_reaches_height_within_limits(t0, height, v_max, a_max):
    tr = Trapezoid(t0=t0, height=height, v_max=v_max, a_max=a_max)
    d = abs(height)
    v = min(v_max, math.sqrt(d * a_max))
    t_end = t0 + d / v + v / a_max                   # total move time
    dt = min(1e-4, (t_end - t0) / 2000)
    t = np.arange(0.0, t_end + 0.05, dt)
    y = tr(t)
    assert np.all(y[t <= t0] == 0.0)
    assert y[-1] == pytest.approx(height, rel=1e-9, abs=1e-12)
    assert tr(np.array([t_end + 1.0]))[0] == pytest.approx(height, rel=1e-9, abs=1e-12)
    # monotone towards the target
    assert np.all(np.diff(y) * math.copysign(1.0, height) >= -1e-12)
    speed = np.diff(y) / dt
    assert np.max(np.abs(speed)) <= v_max * (1 + 1e-9)
    acc = np.diff(speed) / dt
    assert np.max(np.abs(acc)) <= a_max * (1 + 1e-6) + 1e-9
    # the peak speed is the limit (trapezoid) or the triangle's peak
    assert np.max(np.abs(speed)) == pytest.approx(v, rel=0.02)


def test_trapezoid_is_exactly_zero_before_start():
    # regression: the triangular case's cruise time once rounded to -4e-17, which np.clip
    # turned into a -3.9e-17 rad command before t0
    tr = Trapezoid(t0=0.0, height=0.3125, v_max=6.0, a_max=100.0)   # triangular profile
    assert tr(np.array([0.0]))[0] == 0.0


def test_trapezoid_known_cruise():
    tr = Trapezoid(t0=0.0, height=10.0, v_max=50.0, a_max=1000.0)
    # 0.05 s up to speed (1.25 rad), 0.15 s cruise (7.5 rad), 0.05 s down
    assert tr(np.array([0.05, 0.2, 0.25]))[:].tolist() == pytest.approx([1.25, 8.75, 10.0])


@pytest.mark.parametrize("build, match", [
    (lambda: Step(float("nan"), 1.0), r"Step\.t0 must be finite"),
    (lambda: Ramp(0.2, 0.1, 1.0), r"Ramp needs t1 > t0"),
    (lambda: Sine(1.0, 0.0), r"Sine needs frequency > 0"),
    (lambda: Trapezoid(0.0, 1.0, -1.0, 10.0), r"Trapezoid needs v_max > 0"),
    (lambda: Constant(float("inf")), r"Constant\.value must be finite"),
    (lambda: Tabulated((0.0, 0.2, 0.1), (0.0, 1.0, 2.0)), r"strictly increasing times"),
    (lambda: Tabulated((0.0, 0.1), (0.0, 1.0, 2.0)), r"same length >= 2"),
    (lambda: Tabulated((0.0, 0.1), (0.0, float("nan"))), r"finite values"),
    (lambda: Profile(0.0), r"Profile\.duration \[s\] must be > 0"),
    (lambda: Profile.from_dict({"duration": 1.0, "command": [{"shape": "Spline"}]}),
     r"unknown profile shape 'Spline'"),
    (lambda: Profile.from_dict({"command": []}), r"cannot rebuild a profile without its duration"),
    (lambda: get_profile("spline"), r"unknown profile 'spline'; choose one of diagnostic, step, "
                                    r"ramp, sine, chirp, trapezoid, or a CSV file"),
    (lambda: Chirp(1.0, 0.0, 5.0, 0.0, 1.0), r"Chirp needs f0 > 0 and f1 > 0"),
    (lambda: Chirp(1.0, 1.0, 5.0, 0.5, 0.5), r"a finite t1 > t0"),
    (lambda: Chirp(1.0, 1.0, 5.0, 0.0, math.inf), r"Chirp\.t1 must be finite"),
])
def test_profile_errors(build, match):
    with pytest.raises(ProfileError, match=match):
        build()


# --------------------------------------------------------------------------- Profile

def test_profile_sums_shapes_and_grid():
    p = Profile(0.5, command=(Step(0.1, 1.0), Ramp(0.2, 0.3, 2.0)), load=(Constant(0.3), Step(0.4, -0.1)))
    t = p.grid(T_S)
    assert t.size == 4000 and t[0] == 0.0 and t[1] == pytest.approx(T_S) and t[-1] < 0.5
    assert p.theta_ref(np.array([0.05, 0.15, 0.25, 0.35])).tolist() == pytest.approx([0, 1, 2, 3])
    assert p.load_torque(np.array([0.0, 0.45])).tolist() == pytest.approx([0.3, 0.2])
    assert Profile(0.1).theta_ref(t).shape == t.shape and not Profile(0.1).theta_ref(t).any()


@pytest.mark.parametrize("profile", [diagnostic(), diagnostic(load_torque=0.5),
                                     *[f() for f in PROFILES.values()],
                                     Profile(1.0, (Sine(1.0, 2.0, 0.1, 0.9), Trapezoid(0.0, -2.0, 10.0, 100.0),
                                                   Chirp(0.5, 2.0, 1.0, 0.2, 0.8)),
                                             (Constant(0.1),), name="mix", description="all shapes"),
                                     Profile(0.2, (Tabulated((0.0, 0.1, 0.2), (0.0, 1.0, -1.0)),),
                                             (Tabulated((0.0, 0.2), (0.1, 0.3)),), name="tabulated")],
                         ids=lambda p: p.name)
def test_profile_dict_round_trip(profile):
    d = profile.to_dict()
    back = Profile.from_dict(d)
    assert back == profile
    assert back.description == profile.description
    # through JSON as well (trace metadata)
    assert Profile.from_dict(json.loads(json.dumps(d))) == profile
    t = profile.grid(T_S)
    np.testing.assert_array_equal(back.theta_ref(t), profile.theta_ref(t))
    np.testing.assert_array_equal(back.load_torque(t), profile.load_torque(t))


def test_builtin_profiles_by_name():
    for name in PROFILES:
        assert get_profile(name).name == name


# --------------------------------------------------------------------------- diagnostic

def test_diagnostic_profile_coverage():
    p = diagnostic()
    assert p.duration == 0.5 and p.name == "diagnostic"
    t = p.grid(T_S)
    y = p.theta_ref(t)
    v = np.diff(y) / T_S
    # more than one mechanical revolution (eccentricity follows the mechanical angle)
    assert y.max() - y.min() > 2 * math.pi
    assert np.sum(np.abs(np.diff(y))) > 2 * 2 * math.pi
    # a reversal: command speed of both signs (backlash shows only there)
    smooth = np.abs(np.diff(y)) < 0.1                  # leave out the steps
    assert np.any(v[smooth] > 10.0) and np.any(v[smooth] < -10.0)
    # holds: intervals of zero command speed of at least 20 ms, before and after motion
    still = np.abs(np.diff(y)) == 0.0
    runs, n = [], 0
    for s in still:
        n = n + 1 if s else 0
        runs.append(n)
    assert max(runs) * T_S >= 0.02
    assert np.all(still[(t[:-1] > 0.255) & (t[:-1] < 0.295)])      # hold after the ramp
    assert np.all(still[(t[:-1] > 0.021) & (t[:-1] < 0.099)])      # hold after the first step
    # steps: jumps of 0.5 rad within one sample (gain drift shows in step responses)
    jumps = np.flatnonzero(np.abs(np.diff(y)) > 0.4)
    assert len(jumps) == 2
    assert np.diff(y)[jumps].tolist() == pytest.approx([0.5, -0.5])
    # no load torque by default; a constant one on request
    assert not p.load_torque(t).any()
    assert diagnostic(0.3).load_torque(t) == pytest.approx(np.full(t.size, 0.3))


# --------------------------------------------------------------------------- from data
def _meta(**change):
    """The diagnostic profile's dict with ``change`` applied to its first command shape."""
    d = json.loads(json.dumps(diagnostic(load_torque=0.5).to_dict()))
    d["command"][0].update(change)
    return d


@pytest.mark.parametrize("data, match", [
    (_meta(height="abc"), r"^profile\.command\[0\]\.height: expected a number in rad, got the string 'abc'$"),
    (_meta(t0=[1, 2]), r"^profile\.command\[0\]\.t0: expected a number in s, got \[1, 2\]$"),
    (_meta(height=None), r"^profile\.command\[0\]\.height: expected a number in rad, got None$"),
    (_meta(height=True), r"expected a number in rad, got True"),
    (_meta(height=1e300), r"^profile\.command\[0\]\.height = 1e\+300 rad is beyond any actuator test "
                          r"\(at most 1e\+06 rad in magnitude\)"),
    (_meta(height=float("nan")), r"expected a finite number in rad, got nan"),
    (_meta(extra=1), r"^profile\.command\[0\]: unknown field\(s\) \['extra'\] of Step; its fields: t0, height$"),
    ({**_meta(), "command": [{"shape": "Step", "t0": 0.0}]}, r"profile\.command\[0\]: Step is missing height"),
    ({**_meta(), "load": [{"shape": "Constant", "value": 1e300}]},
     r"^profile\.load\[0\]\.value = 1e\+300 N m is beyond any actuator test"),
    ({**_meta(), "load": [{"shape": "Sine", "amplitude": "abc", "frequency": 2}]},
     r"^profile\.load\[0\]\.amplitude: expected a number in N m, got the string 'abc'$"),
    ({**_meta(), "load": [{"shape": "Sine", "amplitude": 1.0, "frequency": 1e9}]},
     r"profile\.load\[0\]\.frequency = 1e\+09 Hz is beyond"),
    ({**_meta(), "load": [{"shape": "Tabulated", "t": [0, 1], "values": [0, "x"]}]},
     r"profile\.load\[0\]\.values\[1\]: expected a number in N m, got the string 'x'"),
    ({**_meta(), "duration": "abc"}, r"^profile\.duration: expected a number in s, got the string 'abc'$"),
    ({**_meta(), "duration": -1.0}, r"Profile\.duration \[s\] must be > 0"),
    ({**_meta(), "command": "abc"}, r"^profile\.command: expected a list of shapes, got 'abc'$"),
    ({**_meta(), "command": [["Step", 0, 1]]}, r"^profile\.command\[0\]: expected an object such as"),
    ({**_meta(), "speed": 3}, r"^profile: unknown field\(s\) \['speed'\]"),
    ({**_meta(), "name": 5}, r"^profile\.name: expected text, got 5$"),
    ([1, 2], r"^profile: expected an object with duration, command and load, got \[1, 2\]$"),
    (_meta(height="x" * 100_000), r"got the string 'xxxx.*\.\.\.' \(100000 characters\)$"),
])
def test_a_profile_from_data_is_checked_field_by_field(data, match):
    # trace metadata is user input: each field named by its path, with the unit expected,
    # in our words (never "could not convert string to float"), and never echoed whole
    with pytest.raises(ProfileError, match=match) as info:
        Profile.from_dict(data)
    assert len(str(info.value)) < 300


def test_shapes_refuse_what_is_not_a_number():
    with pytest.raises(ProfileError, match=r"^Sine\.amplitude must be a number, got 'abc'$"):
        Sine("abc", 2.0)


# --------------------------------------------------------------------------- from a file
def test_read_profile_replays_a_csv_command(tmp_path):
    path = tmp_path / "mine.csv"
    path.write_text("t,theta_ref\n0,0\n0.1,1.0\n0.3,-2.0\n0.4,-2.0\n")
    p = read_profile(path)
    assert p.name == "mine" and p.duration == pytest.approx(0.4 + 0.4 / 3)   # a mean step after
    np.testing.assert_allclose(p.theta_ref(np.array([0.0, 0.05, 0.1, 0.2, 0.4, 0.45])),
                               [0.0, 0.5, 1.0, -0.5, -2.0, -2.0], atol=1e-12)
    assert not p.load_torque(np.array([0.1])).any()
    assert Profile.from_dict(json.loads(json.dumps(p.to_dict()))) == p   # into trace metadata


def test_read_profile_takes_the_trace_readers_conventions(tmp_path):
    """Comments, ';' between fields, names with their unit (converted), other columns
    ignored, a recording that starts later and elsewhere (replayed from 0, relative)."""
    path = tmp_path / "bench.csv"
    path.write_text("# exported by the bench\n# sample rate 10 Hz\n"
                    "t [ms];i_a [A];theta_ref [deg]\n1000;0.1;90\n1100;0.2;180\n1200;0.3;90\n")
    p = read_profile(path)
    np.testing.assert_allclose(p.theta_ref(np.array([0.0, 0.1, 0.2])),
                               [0.0, math.pi / 2, 0.0], atol=1e-12)
    units_row = tmp_path / "units.csv"
    units_row.write_text("t\ttheta_ref\n[s]\t[rev]\n0\t0\n0.5\t1\n")
    assert read_profile(units_row).theta_ref(np.array([0.5]))[0] == pytest.approx(2 * math.pi)


def test_a_trace_file_is_a_profile(tmp_path):
    from emaphm.traces import write_trace

    tr = simulate_trace()
    path = write_trace(tr, tmp_path / "recorded.csv")
    p = read_profile(path)
    g = p.grid(T_S)
    assert g.size == tr.n
    np.testing.assert_allclose(p.theta_ref(g), tr.theta_ref - tr.theta_ref[0], atol=1e-12)


def simulate_trace():
    from emaphm.simulate import simulate

    return simulate(model="monitoring", profile=sine(duration=0.1))


@pytest.mark.parametrize("text, match", [
    ("t,theta_ref\n0,0\n0.2,1\n0.1,2\n", r"time must increase strictly from row to row, but t "
                                          r"goes from 0\.2 to 0\.1 s at data row 3; sort the rows"),
    ("t,theta_ref\n0,0\n0.1,1\n0.1,2\n", r"time must increase strictly"),
    ("t,theta_ref\n0,0\n0.1,\n0.2,2\n", r"column theta_ref holds 1 empty or non-finite value\(s\), "
                                        r"the first in data row 2"),
    ("t,theta_ref\n0,0\nnan,1\n", r"column t holds 1 empty or non-finite"),
    ("t,theta_ref\n0,0\n", r"1 sample\(s\); a profile needs at least two rows"),
    ("time,position\n0,0\n1,1\n", r"no column t, theta_ref; the header must name t \[s\] and "
                                    r"theta_ref \[rad\] \(found time, position\)"),
    ("t [s],theta_ref [A]\n0,0\n1,1\n", r"column theta_ref: 'A' is a unit of current"),
    ("t,theta_ref\n0,0\n100,1\n", r"lasts 100 s, longer than 60 s \(is t in ms\? divide it by 1000\)"),
    ("t;theta_ref\n0;0\n0,1;1,5\n", r"decimal comma"),
    ("t,theta_ref\n0,0\n0.1,abc\n", r"profile file .*bad\.csv"),
])
def test_read_profile_refuses_in_one_line(tmp_path, text, match):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(ProfileError, match=match) as info:
        read_profile(path)
    assert "\n" not in str(info.value) and str(path) in str(info.value)


def test_read_profile_refuses_what_is_not_a_csv_file(tmp_path):
    with pytest.raises(ProfileError, match=r"does not exist"):
        read_profile(tmp_path / "missing.csv")
    (tmp_path / "dir.csv").mkdir()
    with pytest.raises(ProfileError, match=r"is not a file"):
        read_profile(tmp_path / "dir.csv")
    with pytest.raises(ProfileError, match=r"expected a \.csv file of columns t, theta_ref"):
        read_profile(tmp_path / "p.parquet")


def test_simulate_takes_a_profile_by_name_or_file(tmp_path, capsys):
    from emaphm.cli import main
    from emaphm.traces import read_trace

    out = tmp_path / "chirp.csv"
    assert main(["simulate", "--scenario", "nominal", "--model", "monitoring", "--profile",
                 "chirp", "--out", str(out)]) == 0
    tr = read_trace(out)
    assert Profile.from_dict(tr.meta["profile"]) == chirp()
    np.testing.assert_allclose(tr.theta_ref, chirp().theta_ref(tr.t), atol=1e-12)
    mine = tmp_path / "mine.csv"
    mine.write_text("t,theta_ref\n0,0\n0.2,8\n0.4,0\n")
    out2 = tmp_path / "mine-trace.csv"
    assert main(["simulate", "--scenario", "nominal", "--model", "monitoring", "--profile",
                 str(mine), "--out", str(out2)]) == 0
    assert np.max(read_trace(out2, min_rotation=0).theta_ref) == pytest.approx(8.0, abs=0.01)
    capsys.readouterr()
    mine.write_text("t,theta_ref\n0,0\n0.2,8\n0.2,0\n")
    for profile, said in ((str(mine), "--profile: profile file .*time must increase strictly"),
                          ("spline", "--profile 'spline': give a built-in profile \\(diagnostic, "
                                     "step, ramp, sine, chirp, trapezoid\\) or a CSV file")):
        assert main(["simulate", "--scenario", "nominal", "--profile", profile, "--out",
                     str(tmp_path / "x.csv")]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and re.search(said, err), err
    assert not (tmp_path / "x.csv").exists()
