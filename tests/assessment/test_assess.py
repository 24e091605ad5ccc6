"""``emaphm assess`` end to end on the reference plant (a few units, two grids): its files,
the figures its JSON lets a reader recompute, resuming, the assessed parameters honoured by
``diagnose``, the prediction checked on fresh units, and its refusals."""

from __future__ import annotations

import dataclasses
import json
import os
import re
from collections import Counter
from pathlib import Path

import pytest

from emaphm.assessment import AssessmentSpec, assess
from emaphm.assessment.stats import wilson
from emaphm.cli import main
from emaphm.params import load_params, siemens_1fk7060

FAST = ["--units", "3", "--healthy", "2", "--healthy-datasheet", "1",
        "--grids", "friction,short_circuit", "--severities", "friction=1.5",
        "--severities", "short_circuit=0.1", "--workers", "0", "--quiet"]


@pytest.fixture(scope="module")
def assessed(tmp_path_factory):
    out = tmp_path_factory.mktemp("assess") / "preset"
    assert main(["assess", "--out", str(out), "--tune-units", "3", *FAST]) == 0
    return out


def test_it_writes_the_whole_assessment_and_nothing_beside(assessed):
    names = sorted(os.listdir(assessed))
    assert names == ["assessment.json", "params.toml", "pod_friction.png",
                     "pod_short_circuit.png", "report.md", "units.sqlite"]
    # the work folder of the resumable run is gone once the folder is written
    assert sorted(os.listdir(assessed.parent)) == ["preset"]
    for png in ("pod_friction.png", "pod_short_circuit.png"):
        assert (assessed / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_json_is_strict_json_a_missing_number_null(assessed, tmp_path):
    """JSON has no NaN: a reader that keeps to the standard refuses one (a threshold no
    other fault moved had 'crosstalk': NaN)."""
    from emaphm.assessment.report import _finite, write_outputs

    def strict(text):
        return json.loads(text, parse_constant=lambda c: pytest.fail(f"{c} in the JSON"))

    strict((assessed / "assessment.json").read_text())
    a = strict((assessed / "assessment.json").read_text())
    name = next(iter(a["thresholds"]["tuning"]))
    a["thresholds"]["tuning"][name]["crosstalk"] = float("nan")
    assert _finite({"x": [1.0, float("inf"), {"y": float("nan")}]}) == {"x": [1.0, None,
                                                                              {"y": None}]}
    write_outputs(a, tmp_path)
    assert strict((tmp_path / "assessment.json").read_text())["thresholds"]["tuning"][name][
        "crosstalk"] is None
    assert not re.search(r"\bnan\b", (tmp_path / "report.md").read_text())


def test_every_figure_of_the_json_can_be_recomputed_from_its_runs(assessed):
    a = json.loads((assessed / "assessment.json").read_text())
    assert a["schema_version"] == 1 and a["emaphm_version"]
    runs = a["runs"]
    # 3 units: 2 healthy after calibration, 1 on the data sheet, 2 faults
    assert len(runs) == 3 * (2 + 1 + 2)
    for path in ("calibrated", "datasheet"):
        fa = a["false_alarm"][path]
        rs = [r for r in runs if r["case"] == "healthy" and r["path"] == path]
        v = Counter(r["verdict"] for r in rs)
        assert (fa["n"], fa["faulty"], fa["unexplained"], fa["healthy"]) == \
            (len(rs), v["faulty"], v["unexplained"], v["healthy"])
        assert fa["rate"] == v["faulty"] / len(rs)
        assert (fa["lo"], fa["hi"]) == pytest.approx(wilson(v["faulty"], len(rs)))
        assert fa["interval"] == "wilson"
    for grid in ("friction", "short_circuit"):
        (row,) = a["pod"][grid]
        rs = [r for r in runs if r["case"] == grid and r["path"] == "calibrated"]
        assert row["n"] == len(rs) == 3
        assert row["pci"] == sum(r["right"] for r in rs) / 3
        assert row["pod"] == sum(r["verdict"] == "faulty" for r in rs) / 3
        assert (row["lo"], row["hi"]) == pytest.approx(wilson(round(3 * row["pci"]), 3))
        # 3 units can never put the lower bound of a proportion at 0.9
        assert a["min_detectable"][grid] is None
    assert a["pod"]["friction"][0]["severity_unit"] == "x nominal friction"
    assert sum(sum(row.values()) for row in a["confusion"].values()) == \
        sum(r["path"] == "calibrated" for r in runs)
    assert len(a["seeds"]["unit_seeds"]) == len(a["seeds"]["tune_unit_seeds"]) == 3
    assert a["cpu_s"]["total"] > 0 and a["tracking"]["ratio"] < 0.15


def test_the_short_and_the_friction_are_named_after_calibration(assessed):
    a = json.loads((assessed / "assessment.json").read_text())
    assert a["pod"]["short_circuit"][0]["pci"] == 1.0
    assert a["pod"]["friction"][0]["pci"] == 1.0
    assert a["false_alarm"]["calibrated"]["faulty"] == 0


def test_the_assessed_parameters_carry_the_tuned_thresholds(assessed, tmp_path, capsys,
                                                            monkeypatch):
    from emaphm.modes import THRESHOLDS_BY_FAULT_MODEL

    a = json.loads((assessed / "assessment.json").read_text())
    params = load_params(assessed / "params.toml")
    tuned = a["thresholds"]["values"]
    assert dict(params.thresholds) == pytest.approx(tuned)
    assert a["thresholds"]["tuned"] and set(a["thresholds"]["tuning"]) == set(tuned)
    # everything else is the data sheet's
    assert params.to_dict() | {"thresholds": None} == siemens_1fk7060().to_dict() | {"thresholds": None}
    # emaphm calibrate keeps them, and diagnose reads a calibrated unit with them; on the
    # data sheet they only raise the defaults
    monkeypatch.chdir(tmp_path)
    toml = str(assessed / "params.toml")
    for s in (1, 2, 3):
        assert main(["simulate", "--k", "0,0,0,0,0,0,0.5,0.5", "--model", "monitoring", "--params",
                     toml, "--seed", str(s),
                     "--out", f"h{s}.parquet"]) == 0
    assert main(["calibrate", "h1.parquet", "h2.parquet", "--params", toml, "--out", "unit.toml",
                 "--quiet"]) == 0
    assert dict(load_params("unit.toml").thresholds) == pytest.approx(tuned)
    capsys.readouterr()
    assert main(["diagnose", "h3.parquet", "--params", "unit.toml", "--json", "--quiet"]) == 0
    unit = json.loads(capsys.readouterr().out)["thresholds"]
    assert main(["diagnose", "h3.parquet", "--params", toml, "--json", "--quiet"]) == 0
    sheet = json.loads(capsys.readouterr().out)["thresholds"]
    default = dataclasses.asdict(THRESHOLDS_BY_FAULT_MODEL["physical"])
    for name, value in tuned.items():
        assert unit[name] == pytest.approx(value), name
        assert sheet[name] == pytest.approx(max(value, default[name])), name


def test_the_report_reads_in_words_with_its_figures(assessed):
    md = (assessed / "report.md").read_text()
    assert "## Conclusions" in md and "called faulty 0 times in 6" in md
    assert "![friction](pod_friction.png)" in md
    # 3 of 3: 9 in 10 on the runs, but 3 runs do not bound it there (interval from 44 %)
    assert ("Dry friction: named right 9 times in 10 or more in the runs tried (too few to "
            "bound it there) from 1.5 (x nominal friction) on, 3 times in 3 there") in md
    assert "min_detectable needs `--units 35` or more" in md


def test_the_prediction_holds_on_fresh_units(assessed, tmp_path):
    """The assessed parameters on units of another seed, thresholds kept: each rate lies in
    the assessed interval, allowing for the fresh units' own sampling error."""
    fresh = tmp_path / "fresh"
    assert main(["assess", "--params", str(assessed / "params.toml"), "--no-tune", "--seed", "1",
                 "--out", str(fresh), *FAST]) == 0
    a = json.loads((assessed / "assessment.json").read_text())
    b = json.loads((fresh / "assessment.json").read_text())
    assert b["thresholds"]["values"] == pytest.approx(a["thresholds"]["values"])
    assert not set(a["seeds"]["unit_seeds"]) & set(b["seeds"]["unit_seeds"])

    def overlap(x, y):
        return x[0] <= y[1] and y[0] <= x[1]

    fa, fb = a["false_alarm"]["calibrated"], b["false_alarm"]["calibrated"]
    assert overlap((fa["lo"], fa["hi"]), wilson(fb["faulty"], fb["n"]))
    for grid in ("friction", "short_circuit"):
        (ra,), (rb,) = a["pod"][grid], b["pod"][grid]
        assert overlap((ra["lo"], ra["hi"]), wilson(rb["right"], rb["n"]))


def test_an_interrupted_assessment_resumes_to_the_same_numbers(tmp_path):
    spec = AssessmentSpec(siemens_1fk7060().to_dict(), units=2, tune_units=1, healthy=1,
                          healthy_datasheet=0, tune_healthy=1, grids=("friction",),
                          severities={"friction": (2.0,)})
    whole = assess(spec, tmp_path / "whole")

    class Interrupting:
        """Runs one unit, then Ctrl-C."""
        workers = 0

        def map_unordered(self, fn, items):
            for item in items:
                yield item, fn(item)
                raise KeyboardInterrupt

    out = tmp_path / "resumed"
    with pytest.raises(KeyboardInterrupt):
        assess(spec, out, executor=Interrupting())
    assert not out.exists() and (tmp_path / ".resumed.assessing" / "units.sqlite").exists()
    resumed = assess(spec, out)
    assert resumed.resumed == 1 and resumed.ran == 2
    strip = lambda rs: [{k: v for k, v in r.items() if k != "cpu_s"} for r in rs]  # noqa: E731
    assert strip(resumed.summary["runs"]) == strip(whole.summary["runs"])
    assert resumed.summary["thresholds"] == whole.summary["thresholds"]
    # another spec into the same work folder is refused, with the differences
    (tmp_path / ".again.assessing").mkdir()
    assess_other = AssessmentSpec(siemens_1fk7060().to_dict(), units=3, tune_units=1, healthy=1,
                                  healthy_datasheet=0, tune_healthy=1, grids=("friction",),
                                  severities={"friction": (2.0,)})
    with pytest.raises(KeyboardInterrupt):
        assess(spec, tmp_path / "again", executor=Interrupting())
    with pytest.raises(ValueError, match="units: 3 here, 2 there"):
        assess(assess_other, tmp_path / "again")


def _fails(argv, capsys, match):
    try:
        rc = main(argv)
    except SystemExit as exc:           # refused by the parser
        rc = exc.code
    assert rc == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "Traceback" not in err[0], err
    assert match in err[0], err[0]


def test_bad_input_is_one_line_and_writes_nothing(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    Path("tol.toml").write_text("[tolerances]\nJJ = [0, 1]\n")
    _fails(["assess", "--out", "o", "--tolerances", "tol.toml"], capsys, "unknown tolerance(s) ['JJ']")
    _fails(["assess", "--out", "o", "--units", "0"], capsys, "--units")
    _fails(["assess", "--out", "nowhere/o"], capsys, "does not exist")
    Path("exists").mkdir()
    _fails(["assess", "--out", "exists"], capsys, "exists; give a new folder")
    Path("file").write_text("x")
    _fails(["assess", "--out", "file/o"], capsys, "--out")
    weak = siemens_1fk7060().to_dict()
    weak["motor"]["T_max"] = 0.5
    from emaphm.params import ActuatorParams, save_params

    save_params(ActuatorParams.from_dict(weak), "weak.toml")
    _fails(["assess", "--params", "weak.toml", "--out", "o"], capsys,
           "does not track the diagnostic profile")
    _fails(["assess", "--out", "o", "--grids", "friction,wear"], capsys, "unknown assessment grid")
    _fails(["assess", "--out", "o", "--severities", "friction"], capsys, "GRID=S1,S2")
    _fails(["assess", "--out", "o", "--target-far", "1"], capsys, "--target-far")
    assert sorted(os.listdir(tmp_path)) == ["exists", "file", "tol.toml", "weak.toml"]
    assert os.listdir("exists") == []


def test_a_dask_cluster_gives_the_serial_numbers(tmp_path, capsys):
    distributed = pytest.importorskip("distributed")
    from emaphm.campaign.executors import DaskExecutor

    spec = AssessmentSpec(siemens_1fk7060().to_dict(), units=1, tune_units=1, healthy=1,
                          healthy_datasheet=0, tune_healthy=1, grids=("friction",),
                          severities={"friction": (2.0,)}, seed=5)
    here = assess(spec, tmp_path / "here").summary
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  dashboard_address=None, silence_logs=40) as cluster:
        there = assess(spec, tmp_path / "there",
                       executor=DaskExecutor(cluster.scheduler_address)).summary
    strip = lambda rs: [{k: v for k, v in r.items() if k != "cpu_s"} for r in rs]  # noqa: E731
    assert strip(there["runs"]) == strip(here["runs"]) and len(here["runs"]) == 2
    # a scheduler that does not answer: one line, exit 2, nothing written
    _fails(["assess", "--out", str(tmp_path / "nowhere"), "--scheduler", "tcp://127.0.0.1:9",
            "--units", "1"], capsys, "scheduler")
    assert not (tmp_path / "nowhere").exists()


def test_a_lost_unit_is_retried_and_nothing_is_written_until_every_unit_is_in(tmp_path):
    from emaphm.assessment.runner import AssessmentIncomplete

    spec = AssessmentSpec(siemens_1fk7060().to_dict(), units=2, tune_units=0, healthy=1,
                          healthy_datasheet=0, grids=("friction",), severities={"friction": (2.0,)})

    class LosesUnitOne:
        """A pool whose worker dies on the second unit."""
        workers = 0

        def map_unordered(self, fn, items):
            for item in items:
                yield item, (RuntimeError("worker lost") if item.index == 1 else fn(item))

    out = tmp_path / "a"
    with pytest.raises(AssessmentIncomplete, match=r"1 unit\(s\) failed .*assess/1.*worker lost"):
        assess(spec, out, executor=LosesUnitOne())
    assert not out.exists()
    again = assess(spec, out)
    assert again.ran == 1 and again.resumed == 1 and not again.summary["failures"]
    assert sorted({r["unit"] for r in again.summary["runs"]}) == [0, 1]


# ----------------------------------------------------------------------------- issue 37
TINY = ["--units", "2", "--no-tune", "--grids", "friction", "--severities", "friction=2",
        "--healthy", "1", "--healthy-datasheet", "0", "--workers", "0", "--quiet"]


def test_a_full_disk_is_one_line_the_units_done_are_kept_and_the_rerun_completes(
        tmp_path, capsys, monkeypatch):
    """SQLite's "database or disk is full" on the second unit's commit (it was a
    traceback): one line that says so, the first unit kept, nothing in --out; the same
    command, with room again, resumes from the unit kept and writes the assessment."""
    import sqlite3

    import emaphm.assessment.store as store_module

    real_connect = sqlite3.connect
    commits = []

    class FullDisk:
        def __init__(self, conn):
            self.conn = conn

        def execute(self, sql, *args):
            if sql.startswith("INSERT OR REPLACE INTO units"):
                commits.append(sql)
                if len(commits) == 2:
                    raise sqlite3.OperationalError("database or disk is full")
            return self.conn.execute(sql, *args)

        def __getattr__(self, name):
            return getattr(self.conn, name)

    monkeypatch.setattr(store_module.sqlite3, "connect",
                        lambda *a, **kw: FullDisk(real_connect(*a, **kw)))
    out = tmp_path / "a"
    assert main(["assess", "--out", str(out), *TINY]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert "units.sqlite: cannot write the assessment's store: the disk is full (SQLite: " \
           "database or disk is full); the units done are kept in" in err
    assert "run the same command again to resume" in err
    assert not out.exists()
    monkeypatch.undo()
    kept = real_connect(tmp_path / ".a.assessing" / "units.sqlite")
    assert kept.execute("SELECT count(*) FROM units").fetchone()[0] == 1
    kept.close()
    assert main(["assess", "--out", str(out), *TINY[:-1]]) == 0
    assert "2 units" in capsys.readouterr().err
    runs = json.loads((out / "assessment.json").read_text())["runs"]
    assert sorted({r["unit"] for r in runs}) == [0, 1]
    assert not (tmp_path / ".a.assessing").exists()


def test_a_second_assessment_into_the_same_folder_is_refused_at_once(tmp_path, capsys):
    """Two runs into one --out: the second is refused before its work (it failed at the
    end of it, when the first had written --out)."""
    import fcntl

    work = tmp_path / ".a.assessing"
    work.mkdir()
    with open(work / "lock", "a+b") as held:
        fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)
        _fails(["assess", "--out", str(tmp_path / "a"), *TINY], capsys,
               f"--out {tmp_path / 'a'}: another emaphm assess is running into it")
    assert sorted(p.name for p in work.iterdir()) == ["lock"]


def test_a_second_assessment_started_as_the_first_writes_its_outputs_is_refused(
        tmp_path, capsys, monkeypatch):
    """The first run let its lock go before it wrote --out: a second run started then ran
    (every unit resumed), wrote --out and removed the work folder, and the first failed at
    its end. Now the second is refused at once and the first writes its assessment."""
    import emaphm.assessment.report as report

    out = tmp_path / "a"
    real = report.write_outputs
    second = []

    def write_then_start_another(summary, folder):
        second.append(main(["assess", "--out", str(out), *TINY]))
        second.append(capsys.readouterr().err)
        return real(summary, folder)

    monkeypatch.setattr(report, "write_outputs", write_then_start_another)
    assert main(["assess", "--out", str(out), *TINY]) == 0
    rc, err = second
    assert rc == 2 and err.count("\n") == 1, err
    assert f"--out {out}: another emaphm assess is running into it" in err
    assert (out / "assessment.json").is_file() and not (tmp_path / ".a.assessing").exists()


def test_an_actuator_whose_simulation_diverges_is_not_said_to_have_a_nan_error(monkeypatch):
    import numpy as np

    import emaphm.simulate
    from emaphm.assessment import AssessmentError
    from emaphm.assessment.runner import check_tracking

    good = emaphm.simulate.simulate(model="monitoring")
    nan = dataclasses.replace(good, theta_m=np.full(good.n, np.nan))
    monkeypatch.setattr(emaphm.simulate, "simulate", lambda **kw: nan)
    with pytest.raises(AssessmentError, match=r"the simulation of the healthy actuator diverged "
                                              r"\(its position is not a finite number\)") as info:
        check_tracking(siemens_1fk7060())
    assert "nan" not in str(info.value)
