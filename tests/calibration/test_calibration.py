"""Commissioning (emaphm.calibration): known answers on twin traces, refusals, the CLI."""

from dataclasses import replace

import pytest
from support import assert_png_of

from emaphm.acquisition import Sensors
from emaphm.calibration import (DRIVE_PARAMETERS, DRIVE_SETTINGS, PARAMETERS, CalibrationError,
                                apply_deviations, calibrate)
from emaphm.cli import main
from emaphm.params import load_params, siemens_1fk7060
from emaphm.simulate import DEFAULT_SENSORS, simulate
from emaphm.traces import write_trace

NOMINAL = siemens_1fk7060()
TRUE = {"J": 0.06, "R": 0.12, "friction": -0.15, "gain_a": 0.02, "gain_b": -0.01,
        "offset_c": 0.03}


def _unit_traces(seeds, dev=TRUE, k=None):
    unit = apply_deviations(NOMINAL, dev)
    s = unit.sensors
    sensors = Sensors(current_noise=0.02, current_lsb=DEFAULT_SENSORS.current_lsb,
                      gain=s.gain, offset=s.offset)
    # the monitoring model's own physics (a twin): calibration must find the truth
    return [simulate(k, model="monitoring", params=replace(unit, sensors=type(s)()),
                     sensors=sensors, seed=seed, fault_model="physical") for seed in seeds]


@pytest.fixture(scope="module")
def twin_result():
    return calibrate(_unit_traces([1, 2]), NOMINAL, sources=["a", "b"],
                     free=["J", "R", "L", "friction", "gain_a", "gain_b", "offset_c"])


def test_twin_calibration_recovers_the_unit(twin_result):
    r = twin_result
    # measured on these seeds: |error| J 0.002, R 0.006, L 0.006, friction 0.012, gains
    # 0.003-0.004, offset 0.0006; the bounds allow about twice that
    tol = {"J": 0.005, "R": 0.03, "L": 0.015, "friction": 0.03, "gain_a": 0.008,
           "gain_b": 0.008, "offset_c": 0.002}
    for name, e in r.estimates.items():
        assert e["value"] == pytest.approx(TRUE.get(name, 0.0), abs=tol[name]), name
        assert e["lo95"] < e["value"] < e["hi95"] and e["se"] >= e["se_stat"] > 0
    # the current loop hides resistance and inductance: a typical deviation moves the fit
    # less than the identifiability limit, so they stay at the data sheet, and say so
    assert {"R", "L"} <= {n for n, _ in r.weak} and {"R", "L"} <= set(r.fixed)
    assert all(effect < 0.1 for _, effect in r.weak)
    # and the fit is at the noise floor without them
    assert {"J", "friction", "gain_a", "gain_b", "offset_c"} <= set(r.estimates)
    # calibrated: the fit is at the noise floor (the floor's own estimate scatters ~20 %)
    assert all(0.8 < x < 1.3 for x in r.fit_ratio.values())
    # the calibrated parameters carry their provenance
    cal = r.params.calibration
    assert cal.sources == ("a", "b") and {n for n, _, _ in cal.estimates} == set(r.estimates)


def test_the_calibration_figure_shows_the_fit_and_its_residual(twin_result, tmp_path):
    import numpy as np
    from support import legend_texts

    from emaphm.plots import plot_calibration

    fig = plot_calibration(twin_result, source=1, path=tmp_path / "cal.png")
    assert_png_of(tmp_path / "cal.png", fig)
    t, meas, model = twin_result.fits[1]
    axes = fig.axes
    assert [ax.get_ylabel() for ax in axes] == ["i_a [A]", "i_b [A]", "i_c [A]",
                                                "measured - model [A]"]
    assert axes[-1].get_xlabel() == "time [s]"
    for j, ax in enumerate(axes[:3]):           # measured under the calibrated model
        assert len(ax.lines) == 2 and legend_texts(ax) == ["measured", "calibrated model"]
        np.testing.assert_array_equal(ax.lines[0].get_ydata(), meas[:, j])
        np.testing.assert_array_equal(ax.lines[1].get_ydata(), model[:, j])
        y0, y1 = ax.get_ylim()
        assert y0 <= meas[:, j].min() and y1 >= meas[:, j].max()
    assert len(axes[3].lines) == 3 and legend_texts(axes[3]) == ["i_a", "i_b", "i_c"]
    for j in range(3):
        np.testing.assert_array_equal(axes[3].lines[j].get_ydata(), meas[:, j] - model[:, j])
    x0, x1 = axes[3].get_xlim()
    assert x0 <= t[0] and x1 >= t[-1]
    title = fig._suptitle.get_text()
    assert title.startswith(f"calibration on b: fit {twin_result.fit_ratio['b']:.2f}x the noise floor")
    assert all(name in title for name in twin_result.estimates)


def test_inertia_and_flux_cannot_be_told_apart_on_the_profile():
    r = calibrate(_unit_traces([3]), NOMINAL, free=["J", "flux", "offset_a"])
    assert ("J", "flux") in {(a, b) for a, b, _ in r.correlated}
    assert len(r.fixed) == 1 and r.fixed[0] in ("J", "flux")
    assert r.fixed[0] not in r.estimates


def test_a_faulty_unit_is_refused():
    k = [0.75, 0, 0, 0, 0, 0, 0.5, 0.5]     # friction x2.5
    traces = _unit_traces([4], dev={}, k=k)
    with pytest.raises(CalibrationError, match="does not look healthy after calibration"):
        calibrate(traces, NOMINAL, free=["J", "R", "gain_a"])


def test_the_same_recording_twice_is_refused_before_any_fit():
    """A copy weighs one recording twice and narrows the intervals it has not earned."""
    (trace,) = _unit_traces([4], dev={})
    with pytest.raises(CalibrationError, match=r"^b.parquet is the same recording as "
                                               r"a.csv; give each trace of the healthy unit "
                                               r"once"):
        calibrate([trace, trace], NOMINAL, sources=["a.csv", "b.parquet"],
                  progress=lambda n: pytest.fail("fitted"))


def test_a_trace_without_noise_or_of_unknown_parameters_is_refused():
    clean = simulate(model="monitoring", fault_model="physical")
    with pytest.raises(CalibrationError, match="carry no measurement noise"):
        calibrate([clean], NOMINAL)
    with pytest.raises(ValueError, match="unknown calibration parameter"):
        calibrate(_unit_traces([1]), NOMINAL, free=["inertia"])
    with pytest.raises(CalibrationError, match="at least one trace"):
        calibrate([], NOMINAL)


def test_apply_deviations_scales_what_it_says():
    p = apply_deviations(NOMINAL, {"J": 0.1, "flux": -0.05, "load": 0.2, "gain_b": 0.03})
    assert p.motor.J_m == pytest.approx(NOMINAL.motor.J_m * 1.1)
    assert p.load.J_l == pytest.approx(NOMINAL.load.J_l * 1.1)
    assert p.motor.c0[1] == pytest.approx(NOMINAL.motor.c0[1] * 0.95)
    assert p.load.T_0 == pytest.approx(0.2)
    assert p.sensors.gain == pytest.approx((1.0, 1.03, 1.0))
    # the drive keeps its data-sheet settings (k_T, the feed-forward's inertia)
    assert p.controller.resolved(NOMINAL.motor, NOMINAL.load) == \
        NOMINAL.controller.resolved(NOMINAL.motor, NOMINAL.load)
    assert set(PARAMETERS) >= {"J", "flux", "R", "L", "friction", "viscous", "load"}


def test_cli_calibrate_writes_parameters_diagnose_reads(tmp_path, capsys):
    paths = []
    for i, tr in enumerate(_unit_traces([5, 6])):
        p = tmp_path / f"h{i}.csv"
        write_trace(tr, p)
        paths.append(str(p))
    out = tmp_path / "unit.toml"
    assert main(["calibrate", *paths, "--out", str(out), "--json", "--quiet",
                 "--plot", str(tmp_path / "cal.png")]) == 0
    import json

    d = json.loads(capsys.readouterr().out)
    assert "estimates" in d and d["fit_ratio"]
    p = load_params(out)
    assert p.calibration.sources == ("h0.csv", "h1.csv")
    # the common mode of the gains trades with inertia and flux (all scale the current);
    # their differences are separable: 1.02 / 0.99 (measured 0.0305)
    assert p.sensors.gain[0] / p.sensors.gain[1] == pytest.approx(1.02 / 0.99, abs=0.005)
    assert_png_of(tmp_path / "cal.png", (10, 9))        # plot_calibration's size
    # a missing trace is refused with the reason
    assert main(["calibrate", str(tmp_path / "nope.csv"), "--out", str(out)]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_an_estimate_the_others_predict_together_is_kept_at_the_data_sheet():
    """Production unit 20003 on the plant: flux, inertia, friction, load and the sensor
    gains scale its currents jointly. Without the multiple-correlation rule it calibrated
    to flux and inertia both +17 % (truth -4.5 %, -1.2 %) at a good fit, every pair below
    the pairwise limit; with it the flux is kept and the inertia reads the ratio the
    currents can see, (1 + dJ) / (1 + dflux) - 1 = +3.4 %, inside its interval. Measured
    on the two-level friction of the paper's parameters; with the Stribeck drop estimated
    too (the default) the pair J ~ flux is past the pairwise limit, with the same outcome."""
    from emaphm.calibration import MULTIPLE_CORRELATION_LIMIT
    from emaphm.units import draw_unit

    unit = draw_unit(NOMINAL, 20003)
    traces = [simulate(unit=unit, sensors=DEFAULT_SENSORS, seed=s, fault_model="physical")
              for s in (1, 2)]
    dev = unit.deviations
    visible = (1 + dev["J"]) / (1 + dev["flux"]) - 1
    two_level = [n for n in PARAMETERS if n not in DRIVE_PARAMETERS and n not in DRIVE_SETTINGS]
    r = calibrate(traces, NOMINAL, free=two_level)
    assert "flux" in r.fixed and "flux" not in r.estimates
    flux, partner, rho = next(c for c in r.correlated if c[0] == "flux")
    assert "J" in partner.split("+") and rho > MULTIPLE_CORRELATION_LIMIT
    e = r.estimates["J"]
    assert e["lo95"] <= visible <= e["hi95"]
    assert "not separable" in r.summary() and "flux ~ J" in r.summary()
    default = calibrate(traces, NOMINAL)
    assert "flux" in default.fixed and "stribeck" in default.estimates
    e = default.estimates["J"]
    assert e["lo95"] <= visible <= e["hi95"]
    # the old rule alone (no multiple-correlation limit) estimates the flux far off, outside
    # what a unit of the design spreads over: refused, naming it
    from emaphm.calibration import CalibrationError

    with pytest.raises(CalibrationError, match=r"flux \+1\d[.\d]* % \(95 % interval .* tolerance -5 to \+5 %\)"):
        calibrate(traces, NOMINAL, multiple_limit=1.0, free=two_level)


# ----------------------------------------------------------------------------- provenance
def _file_of(params, tmp_path, name="unit.toml"):
    from emaphm.params import save_params

    return save_params(params, tmp_path / name)


def test_a_calibration_records_its_provenance(twin_result):
    from emaphm import __version__
    from emaphm.calibration import trace_digest
    from emaphm.params import calibration_digest

    cal = twin_result.params.calibration
    assert cal.emaphm_version == __version__ and cal.date
    assert cal.trace_sha256 == tuple(trace_digest(t) for t in _unit_traces([1, 2]))
    assert len(set(cal.trace_sha256)) == 2 and all(len(d) == 64 for d in cal.trace_sha256)
    assert cal.digest == calibration_digest(twin_result.params) and cal.digest.startswith("sha256:")


def test_the_trace_digest_is_the_historys_fingerprint():
    from emaphm.calibration import trace_digest
    from emaphm.prognosis.history import trace_fingerprint

    tr = _unit_traces([7])[0]
    assert trace_digest(tr) == trace_fingerprint(tr)


def test_a_calibrate_written_file_loads_silently(twin_result, tmp_path):
    import warnings

    path = _file_of(twin_result.params, tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        back = load_params(path)
        load_params(path, partial=True)
        load_params(_file_of(NOMINAL, tmp_path, "sheet.toml"))      # a data sheet: nothing
    assert back.calibration == twin_result.params.calibration


def _edited(path, old, new):
    text = path.read_text()
    assert text.count(old) == 1, old
    path.write_text(text.replace(old, new))
    return path


def test_an_edited_estimate_or_calibrated_value_warns_in_one_line(twin_result, tmp_path):
    import tomllib

    from emaphm.params import CalibrationWarning

    path = _file_of(twin_result.params, tmp_path)
    data = tomllib.loads(path.read_text())
    name, value, _ = data["calibration"]["estimates"][0]
    # an estimate changed by hand
    est = _edited(_file_of(twin_result.params, tmp_path, "est.toml"), repr(value),
                  repr(value + 0.1))
    # a calibrated value changed by hand (the friction)
    fsj = data["transmission"]["FSJ"]
    val = _edited(_file_of(twin_result.params, tmp_path, "val.toml"), f"FSJ = {fsj!r}",
                  f"FSJ = {fsj * 1.5!r}")
    for p in (est, val):
        with pytest.warns(CalibrationWarning, match=r"does not match its digest: the estimates or "
                                                    r"the calibrated parameters .* were edited "
                                                    r"after emaphm calibrate") as rec:
            load_params(p)
        assert len(rec) == 1 and "\n" not in str(rec[0].message) and str(p) in str(rec[0].message)
    # what the calibration did not set is not its business (the drive's tuning, the name)
    kp = data["controller"]["Kp"]
    other = _edited(_file_of(twin_result.params, tmp_path, "other.toml"), f"Kp = {kp!r}",
                    f"Kp = {kp * 2!r}")
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        load_params(other)


def test_a_calibration_block_without_provenance_warns(tmp_path):
    from emaphm.params import Calibration, CalibrationWarning

    by_hand = replace(NOMINAL, calibration=Calibration(date="2026-01-01", sources=("h1.csv",),
                                                       estimates=(("J", 0.05, 0.01),)))
    path = _file_of(by_hand, tmp_path)
    with pytest.warns(CalibrationWarning, match=r"has no provenance \(no digest of what emaphm "
                                                r"calibrate wrote\)"):
        p = load_params(path)
    assert p.calibration.date == "2026-01-01"        # still read: a warning, not a refusal
    # a file of an older emaphm, without the provenance fields at all
    text = "\n".join(ln for ln in path.read_text().splitlines()
                     if not ln.startswith(("digest", "emaphm_version", "trace_sha256", "# digest",
                                           "# emaphm_version", "# trace_sha256")))
    old = tmp_path / "old.toml"
    old.write_text(text)
    with pytest.warns(CalibrationWarning, match="no provenance"):
        load_params(old)


def test_the_command_line_says_the_warning_in_one_line(twin_result, tmp_path, capsys):
    data = twin_result.params.calibration.estimates[0][1]
    path = _edited(_file_of(twin_result.params, tmp_path), repr(data), repr(data + 0.1))
    assert main(["simulate", "--scenario", "nominal", "--model", "monitoring", "--params",
                 str(path), "--out", str(tmp_path / "x.csv")]) == 0
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if "warning" in ln]
    assert lines == [f"emaphm simulate: warning: {path}: its [calibration] block does not match "
                     f"its digest: the estimates or the calibrated parameters (motor, friction, "
                     f"load, sensors) were edited after emaphm calibrate wrote them; calibrate "
                     f"the unit again, or remove the block to use the values as a data sheet"]


def test_the_digest_covers_every_value_a_calibration_sets():
    """apply_deviations changes only CALIBRATED_FIELDS: a value the calibration sets that
    the digest missed could be edited unnoticed."""
    from emaphm.calibration import DRIVE_SETTINGS
    from emaphm.params import CALIBRATED_DRIVE_FIELDS, CALIBRATED_FIELDS

    def changed(dev):
        a, b = NOMINAL.to_dict(), apply_deviations(NOMINAL, dev).to_dict()
        return {(sec, k) for sec in a if isinstance(a[sec], dict)
                for k in a[sec] if a[sec][k] != b[sec][k]}

    assert changed({n: 0.1 for n in PARAMETERS if n not in DRIVE_SETTINGS
                    and n != "stribeck"}) == set(CALIBRATED_FIELDS)
    # the Stribeck speed it estimates: [transmission] omega_s, which the digest covers
    # where the block names it (a file calibrated before it was estimated keeps its digest)
    assert changed({"stribeck": 0.8}) == {("transmission", "omega_s")}
    from emaphm.params import Calibration, calibration_digest

    unit = apply_deviations(NOMINAL, {"stribeck": 0.8})
    named = replace(unit, calibration=Calibration(date="2026-11-28",
                                                  estimates=(("stribeck", 0.8, 0.05),)))
    edited = replace(named, transmission=replace(named.transmission, omega_s=0.9))
    assert calibration_digest(named) != calibration_digest(edited)
    older = replace(named, calibration=Calibration(date="2026-11-28"))
    assert calibration_digest(older) == calibration_digest(
        replace(older, transmission=replace(older.transmission, omega_s=0.0)))
    # a drive setting it estimates (--drive-unknown): that one, which the digest covers
    # where the block names it
    for n in DRIVE_SETTINGS:
        step = -0.1 if n == "speed_reference_weight" else 0.1       # 1, its upper bound
        assert changed({n: step}) == {(CALIBRATED_DRIVE_FIELDS[n], n)}, n


def test_an_inertia_read_per_flux_is_checked_against_both_tolerances():
    """With the flux kept at the data sheet (not separable on the profile), the inertia
    estimate is J / flux of the unit: a unit of inertia +9 % and flux -5 % (both within
    their tolerances) reads J +14.7 %, which the check must accept; J +25 % it refuses."""
    from emaphm.calibration import _check_tolerances
    from emaphm.units import DEFAULT_TOLERANCES as tol

    ratio = 1.09 / 0.95 - 1.0
    est = {"J": {"value": ratio, "lo95": ratio - 0.02, "hi95": ratio + 0.02, "unit": ""}}
    assert ratio - 0.02 > tol.J[1]                      # outside the inertia's own tolerance
    _check_tolerances(est, None, fixed=("flux",))
    with pytest.raises(CalibrationError, match=r"J \+14\.7 %"):
        _check_tolerances(est, None)                    # with the flux estimated beside it
    far = {"J": {"value": 0.25, "lo95": 0.23, "hi95": 0.27, "unit": ""}}
    with pytest.raises(CalibrationError, match=r"tolerance -14\.\d to \+15\.\d %"):
        _check_tolerances(far, None, fixed=("flux",))


def test_a_calibration_estimates_the_stribeck_drop_the_plant_has():
    """ema-270v-750w unit 1 (friction -4 % of its data sheet, the plant's Stribeck speed
    1 rad/s): with the two-level friction alone its calibration put the friction at +37 %
    and was refused; with the drop estimated (switched on where it improves the fit,
    calibration.SWITCHED) the speed reads near the plant's, the friction inside its
    tolerance, the fit closer to the noise floor, and the calibrated file states it."""
    from pathlib import Path

    from emaphm.units import draw_unit

    sheet = load_params(Path(__file__).resolve().parents[2] / "examples" / "actuators"
                        / "ema-270v-750w.toml")
    unit = draw_unit(sheet, 1)
    traces = [simulate(unit=unit, params=sheet, sensors=DEFAULT_SENSORS, seed=s)
              for s in (100, 101)]
    two_level = [n for n in PARAMETERS if n not in DRIVE_PARAMETERS and n not in DRIVE_SETTINGS]
    with pytest.raises(CalibrationError, match=r"friction \+3\d"):
        calibrate(traces, sheet, free=two_level)
    r = calibrate(traces, sheet)
    e = r.estimates["stribeck"]
    assert 0.7 < e["value"] < 1.4 and e["unit"] == "rad/s"
    assert abs(r.estimates["friction"]["value"] - unit.deviations["friction"]) < 0.2
    assert max(r.fit_ratio.values()) < 1.5
    assert r.params.transmission.omega_s == pytest.approx(e["value"])
