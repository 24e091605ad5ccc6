"""The health-history store (:mod:`emaphm.prognosis.history`).

What a maintenance engineer relies on: every committed inspection survives a crash
(SIGKILL of the writer between or during inspections, an exception inside the
transaction); an inspection of an unknown actuator, a time that does not move
forward, a trace already recorded or a trace that fails validation is refused with
a message that says what to do, and leaves the history exactly as it was. Files go
to ``tmp_path`` only.
"""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest
from support import assert_png_of, legend_texts, mm_trace  # noqa: F401  (mm_trace: a fixture)

from emaphm.cli import EXIT_USAGE, main
from emaphm.faults import K_NOMINAL
from emaphm.prognosis import history as hist
from emaphm.prognosis.history import (DuplicateInspectionError, HealthHistory, HistoryError,
                                      TimeOrderError, UnknownActuatorError, trace_fingerprint)
from emaphm.prognosis.workflow import record_inspection as inspect
from emaphm.simulate import simulate
from emaphm.traces import Trace, TraceError, write_trace

K1 = np.array([0.1, 0, 0, 0, 0, 0, 0.5, 0.5])


def _snapshot(h: HealthHistory):
    """Everything a user can read from the store."""
    return ([a.to_dict() for a in h.actuators()],
            {a.id: [i.to_dict() for i in h.inspections(a.id)] for a in h.actuators()})


@pytest.fixture()
def store(tmp_path):
    with HealthHistory(tmp_path / "h.sqlite") as h:
        h.register("EMA-1", description="left aileron")
        h.add("EMA-1", 10.0, K1, fingerprint="f10")
        h.add("EMA-1", 20.0, K1 + [0.01, 0, 0, 0, 0, 0, 0, 0], fingerprint="f20")
        yield h


def test_round_trip_and_arrays(store):
    a = store.actuator("EMA-1")
    assert (a.n_inspections, a.last_time, a.time_unit, a.description) == (2, 20.0, "h", "left aileron")
    data = store.data("EMA-1")
    assert data.times.tolist() == [10.0, 20.0]
    assert data.K.shape == (2, 8) and data.K[1, 0] == pytest.approx(0.11)
    np.testing.assert_array_equal(data.K_lo, data.K)          # no interval given: k itself
    assert store.journal_mode == "wal"
    assert store.integrity_check() == "ok"


def test_interval_and_diagnosis_are_stored(store):
    lo, hi = K1 - 0.005, K1 + 0.005
    ins = store.add("EMA-1", 30.0, K1, k_lo=np.clip(lo, 0, 1), k_hi=hi, spread_method="population",
                    level=0.9, diagnosis={"healthy": False, "faults": [{"mode": "friction"}]},
                    algorithm="pso", seed=3, fitness=1e-4, evaluations=100, source="x.csv",
                    extra={"note": "gate check"})
    back = store.inspections("EMA-1")[-1]
    assert back.to_dict() == ins.to_dict()
    assert back.healthy is False and back.extra == {"note": "gate check"}
    np.testing.assert_allclose(back.k_hi, hi)


@pytest.mark.parametrize("bad, error, match", [
    (lambda h: h.add("EMA-9", 30.0, K1), UnknownActuatorError, "emaphm history register EMA-9"),
    (lambda h: h.add("EMA-1", 20.0, K1), TimeOrderError, "is not after its last inspection at 20"),
    (lambda h: h.add("EMA-1", 15.0, K1), TimeOrderError, "times must increase"),
    (lambda h: h.add("EMA-1", -1.0, K1), HistoryError, "finite number >= 0"),
    (lambda h: h.add("EMA-1", float("nan"), K1), HistoryError, "finite number >= 0"),
    (lambda h: h.add("EMA-1", 30.0, K1, fingerprint="f10"), DuplicateInspectionError,
     "already recorded for 'EMA-1' at 10"),
    (lambda h: h.add("EMA-1", 30.0, [1.5, 0, 0, 0, 0, 0, 0.5, 0.5]), HistoryError, "outside [0, 1]"),
    (lambda h: h.add("EMA-1", 30.0, K1, k_lo=K1 + 0.1), HistoryError, "must contain k"),
    (lambda h: h.add("EMA-1", 30.0, K1, extra={"x": object()}), HistoryError, "not JSON"),
    (lambda h: h.register("EMA-1"), HistoryError, "already registered"),
    (lambda h: h.register("bad id!"), HistoryError, "letters, digits"),
    (lambda h: h.register("EMA-2", time_unit="days"), HistoryError, "flight hours or cycles"),
])
def test_refused_operations_leave_the_store_unchanged(store, bad, error, match):
    before = _snapshot(store)
    with pytest.raises(error, match=match.replace("[", r"\[").replace("]", r"\]")):
        bad(store)
    assert _snapshot(store) == before
    assert issubclass(error, ValueError)      # the CLI turns it into exit status 2
    store.add("EMA-1", 30.0, K1)              # and the store still takes a good inspection
    assert store.actuator("EMA-1").n_inspections == 3


def test_schema_refuses_time_going_backwards_even_bypassing_python(store):
    import sqlite3

    with pytest.raises(sqlite3.IntegrityError, match="after the last inspection"):
        store._con.execute("INSERT INTO inspections (actuator, time, k, k_lo, k_hi, recorded_utc) "
                           "VALUES ('EMA-1', 5, '[]', '[]', '[]', 'now')")
    with pytest.raises(sqlite3.IntegrityError):
        store._con.execute("INSERT INTO inspections (actuator, time, k, k_lo, k_hi, recorded_utc) "
                           "VALUES ('nobody', 50, '[]', '[]', '[]', 'now')")
    assert store.actuator("EMA-1").n_inspections == 2


def test_exception_inside_the_transaction_rolls_back(store, monkeypatch):
    before = _snapshot(store)

    def boom(self, con, actuator_id):
        raise RuntimeError("power cut between the two statements")

    monkeypatch.setattr(HealthHistory, "_touch", boom)
    with pytest.raises(RuntimeError, match="power cut"):
        store.add("EMA-1", 30.0, K1)
    assert _snapshot(store) == before
    monkeypatch.undo()
    store.add("EMA-1", 30.0, K1)
    assert store.data("EMA-1").times.tolist() == [10.0, 20.0, 30.0]


_WRITER = textwrap.dedent("""
    import sys
    import numpy as np
    from emaphm.prognosis.history import HealthHistory
    h = HealthHistory(sys.argv[1])
    h.register("EMA-K")
    k = np.array([0.0, 0, 0, 0, 0, 0, 0.5, 0.5])
    i = 0
    while True:
        i += 1
        k[0] = min(0.001 * i, 1.0)
        h.add("EMA-K", float(i), k, extra={"pad": "x" * 2000})
        print(i, flush=True)
""")


def test_sigkill_between_inspections_loses_nothing_committed(tmp_path):
    db = tmp_path / "crash.sqlite"
    script = tmp_path / "writer.py"
    script.write_text(_WRITER)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    proc = subprocess.Popen([sys.executable, str(script), str(db)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env)
    committed = 0
    deadline = time.monotonic() + 60
    try:
        while committed < 40 and time.monotonic() < deadline:
            line = proc.stdout.readline()
            if not line:
                break
            committed = int(line)
    finally:
        os.kill(proc.pid, signal.SIGKILL)        # mid-stream: between or during an inspection
        proc.wait()
    # the writer may have run ahead of this reader (a loaded machine): what it reported
    # before the kill is in the pipe still
    reported = [int(x) for x in proc.stdout.read().split()]
    committed = max([committed, *reported])
    assert committed >= 40, proc.stderr.read()
    with HealthHistory(db, create=False) as h:
        assert h.integrity_check() == "ok"
        times = h.data("EMA-K").times
        # every inspection reported as committed is there, at most one more got through
        assert committed <= times.size <= committed + 1
        assert times.tolist() == [float(i) for i in range(1, times.size + 1)]
        h.add("EMA-K", float(times.size + 1), K1)   # and the store goes on


def test_opening(tmp_path):
    with pytest.raises(HistoryError, match="no health history .* register an actuator first"):
        HealthHistory(tmp_path / "missing.sqlite", create=False)
    assert not (tmp_path / "missing.sqlite").exists()
    with pytest.raises(HistoryError, match="does not exist; create it first"):
        HealthHistory(tmp_path / "nope" / "h.sqlite")
    import sqlite3

    other = tmp_path / "other.sqlite"
    con = sqlite3.connect(other)
    con.execute("CREATE TABLE t (x)")
    con.commit()
    con.close()
    with pytest.raises(HistoryError, match="not an emaphm health history"):
        HealthHistory(other)
    (tmp_path / "junk.sqlite").write_bytes(b"not a database at all" * 100)
    with pytest.raises(HistoryError, match="not an emaphm health history"):
        HealthHistory(tmp_path / "junk.sqlite")
    # two handles on one file see each other's commits
    with HealthHistory(tmp_path / "a.sqlite") as h1, HealthHistory(tmp_path / "a.sqlite") as h2:
        h1.register("EMA-1")
        h2.add("EMA-1", 1.0, K1)
        assert h1.actuator("EMA-1").n_inspections == 1


# ----------------------------------------------------------------------------- inspect()
def _no_identification(monkeypatch):
    import emaphm.prognosis.uncertainty as unc

    def fail(*a, **k):
        raise AssertionError("identification must not run for a refused inspection")

    monkeypatch.setattr(unc, "identify_with_spread", fail)


def test_inspect_refuses_before_identifying(store, mm_trace, monkeypatch):
    _no_identification(monkeypatch)
    before = _snapshot(store)
    with pytest.raises(UnknownActuatorError, match="register it first"):
        inspect(store, "EMA-7", mm_trace, 30.0, seed=0)
    with pytest.raises(TimeOrderError):
        inspect(store, "EMA-1", mm_trace, 20.0, seed=0)
    t = mm_trace.t
    bad = Trace(t=t, theta_ref=mm_trace.theta_ref, theta_m=mm_trace.theta_m, omega_m=mm_trace.omega_m,
                i_abc=np.where(t[:, None] > 0.2, np.nan, mm_trace.i_abc))
    with pytest.raises(TraceError, match="non-finite"):
        inspect(store, "EMA-1", bad, 30.0, seed=0)
    assert _snapshot(store) == before


def test_fingerprint_is_content_based(mm_trace, tmp_path):
    from emaphm.traces import read_trace

    fp = trace_fingerprint(mm_trace)
    p = write_trace(mm_trace, tmp_path / "x.parquet")
    assert trace_fingerprint(read_trace(p, validate=False)) == fp
    assert trace_fingerprint(mm_trace.with_meta(note="other meta")) == fp
    other = simulate(K_NOMINAL, model="monitoring")
    assert trace_fingerprint(other) != fp


# ----------------------------------------------------------------------------- CLI
def _run(argv, capsys):
    rc = main(argv)
    out, err = capsys.readouterr()
    return rc, out, err


def test_cli_errors_leave_history_unchanged(tmp_path, capsys, mm_trace, monkeypatch):
    _no_identification(monkeypatch)
    db = str(tmp_path / "h.sqlite")
    good = write_trace(mm_trace, tmp_path / "good.csv")
    short = write_trace(Trace(t=mm_trace.t[:20], theta_ref=mm_trace.theta_ref[:20],
                              theta_m=mm_trace.theta_m[:20], omega_m=mm_trace.omega_m[:20],
                              i_abc=mm_trace.i_abc[:20]), tmp_path / "short.csv")
    rc, _, err = _run(["history", "add", "EMA-1", str(good), "--at", "5", "--db", db], capsys)
    assert rc == EXIT_USAGE and "no health history" in err
    assert _run(["history", "register", "EMA-1", "--db", db, "--unit", "cycles"], capsys)[0] == 0
    with HealthHistory(db) as h:
        h.add("EMA-1", 100.0, K1, fingerprint="x")
        before = _snapshot(h)
    cases = [
        (["history", "add", "EMA-2", str(good), "--at", "200"], "register it first"),
        (["history", "add", "EMA-1", str(good), "--at", "50"], "not after its last inspection"),
        (["history", "add", "EMA-1", str(short), "--at", "200"], "too short"),
        (["history", "add", "EMA-1", str(tmp_path / "nope.csv"), "--at", "200"], "does not exist"),
        (["history", "register", "EMA-1"], "already registered"),
        (["history", "show", "EMA-3"], "not registered"),
        (["prognose", "EMA-1"], "a trend needs at least 3"),
        (["prognose", "EMA-1", "--threshold", "friction"], "MODE=VALUE"),
        (["prognose", "EMA-1", "--threshold", "wear=0.3"], "unknown fault mode"),
        # times as given, every digit: 100.0000001 is not the inspection at 100
        (["history", "remove", "EMA-1", "--at", "100.0000001"],
         "no inspection at 100.0000001 cycles"),
    ]
    for argv, match in cases:
        rc, _, err = _run(argv + ["--db", db], capsys)
        assert rc == EXIT_USAGE, (argv, err)
        assert match in err, (argv, err)
        assert err.startswith("emaphm ") and "error:" in err
    with HealthHistory(db) as h:
        assert _snapshot(h) == before


def test_cli_show_and_list(store, capsys, tmp_path):
    db = str(store.path)
    rc, out, _ = _run(["history", "show", "EMA-1", "--db", db, "--plot", str(tmp_path / "h.png")], capsys)
    assert rc == 0 and "2 inspections" in out and "friction" in out
    assert_png_of(tmp_path / "h.png", (11, 9))             # plot_history's figure
    rc, out, _ = _run(["history", "list", "--db", db], capsys)
    assert rc == 0 and "EMA-1" in out and "left aileron" in out
    rc, out, _ = _run(["history", "show", "EMA-1", "--db", db, "--json"], capsys)
    import json

    assert len(json.loads(out)["inspections"]) == 2


def test_cli_list_keeps_one_row_per_actuator(tmp_path, capsys):
    db = str(tmp_path / "h.sqlite")
    with HealthHistory(db) as h:
        h.register("EMA-1", description="left aileron\nline 2\tbay 3")
        h.register("EMA-2")
    rc, out, _ = _run(["history", "list", "--db", db], capsys)
    rows = out.splitlines()
    assert rc == 0 and len(rows) == 3 and rows[1].endswith("left aileron line 2 bay 3")


def test_default_db_from_environment(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("EMAPHM_HISTORY", str(tmp_path / "env.sqlite"))
    assert _run(["history", "register", "EMA-E"], capsys)[0] == 0
    assert (tmp_path / "env.sqlite").exists()
    assert hist.DEFAULT_DB == "emaphm-history.sqlite"


# ----------------------------------------------------------------------------- calibrations

def test_a_recalibration_is_an_event_and_later_inspections_use_it(tmp_path):
    import sqlite3
    from dataclasses import replace

    from emaphm.params import Calibration, siemens_1fk7060

    p = siemens_1fk7060()
    cal = replace(p, motor=replace(p.motor, J_m=8.0e-4),
                  calibration=Calibration(date="2026-11-23", sources=("h1.csv",)))
    with HealthHistory(tmp_path / "h.sqlite") as h:
        h.register("EMA-C")
        assert h.calibration("EMA-C") is None
        h.calibrate("EMA-C", 100.0, cal, sources=["h1.csv"])
        h.calibrate("EMA-C", 300.0, replace(cal, motor=replace(cal.motor, J_m=9.0e-4)))
        assert h.calibration("EMA-C", at=50.0) is None
        t, got = h.calibration("EMA-C", at=200.0)
        assert t == 100.0 and got == cal
        assert h.calibration("EMA-C")[1].motor.J_m == 9.0e-4
        recs = h.calibrations("EMA-C")                 # every one, in time order
        assert [(r.time, r.sources, r.actuator) for r in recs] == [
            (100.0, ("h1.csv",), "EMA-C"), (300.0, (), "EMA-C")]
        assert recs[0].params == cal and recs[1].params.motor.J_m == 9.0e-4
        assert recs[0].recorded_utc <= recs[1].recorded_utc
        with pytest.raises(HistoryError, match="register"):
            h.calibrations("EMA-X")
        with pytest.raises(HistoryError, match="register"):
            h.calibrate("EMA-X", 1.0, cal)
        with pytest.raises(HistoryError, match="finite number"):
            h.calibrate("EMA-C", float("nan"), cal)
    # a store of schema 1 (before calibrations) gains the table when opened
    old = tmp_path / "old.sqlite"
    with HealthHistory(old) as h:
        h.register("EMA-O")
    con = sqlite3.connect(old)
    con.execute("DROP TABLE calibrations")
    con.execute("ALTER TABLE inspections DROP COLUMN readings")
    con.execute("PRAGMA user_version = 1")
    con.commit()
    con.close()
    with HealthHistory(old) as h:
        assert h.calibration("EMA-O") is None
        h.calibrate("EMA-O", 1.0, cal)
        assert h.calibration("EMA-O")[1] == cal


def test_cli_history_calibrate_then_add_diagnoses_with_the_calibration(tmp_path, capsys):
    import json

    from emaphm.cli import main
    from emaphm.simulate import DEFAULT_SENSORS, simulate
    from emaphm.traces import write_trace

    paths = []
    for seed, k in ((1, None), (2, None), (3, [0, 0, 0.15, 0, 0, 0, 0.5, 0.5])):
        tr = simulate(k, model="monitoring", sensors=DEFAULT_SENSORS, seed=seed,
                      fault_model="physical")
        paths.append(str(tmp_path / f"t{seed}.csv"))
        write_trace(tr, paths[-1])
    db = str(tmp_path / "h.sqlite")
    assert main(["history", "register", "EMA-7", "--db", db]) == 0
    assert main(["history", "calibrate", "EMA-7", paths[0], paths[1], "--at", "10",
                 "--db", db, "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["at"] == 10.0
    assert main(["history", "calibrate", "EMA-7", str(tmp_path / "none.csv"), "--at", "11",
                 "--db", db]) == 2
    assert main(["history", "add", "EMA-7", paths[2], "--at", "20", "--db", db, "--json",
                 "--quiet", "--budget", "3000"]) == 0
    ins = json.loads(capsys.readouterr().out)
    assert ins["extra"]["calibrated_at"] == 10.0
    assert set(ins["extra"]["nuisance"]) == {"R", "flux"}      # calibrated: drift searched
    assert ins["fault_model"] == "physical"
    assert ins["extra"]["parameters"]["calibration"]["sources"] == ["t1.csv", "t2.csv"]


def test_history_plot_colours_each_component_by_its_own_verdict(tmp_path):
    from matplotlib.colors import to_rgba

    from emaphm.diagnosis import diagnose
    from emaphm.prognosis.plots import component_status, plot_history
    from emaphm.prognosis.thresholds import DEFAULT_FAILURE_THRESHOLDS, INDICATOR_COMPONENT

    with HealthHistory(tmp_path / "h.sqlite") as h:
        h.register("EMA-P")
        ks = [[0.0, 0.01, 0, 0, 0, 0.0, 0.5, 0.5], [0.5, 0.01, 0, 0, 0, 0.0, 0.8, 0.5],
              [0.6, 0.02, 0, 0, 0, 0.2, 0.3, 0.5]]
        for t, k in zip((10.0, 20.0, 30.0), ks):
            d = diagnose(k, fit_ratio=10.0 if t == 30.0 else 1.2, fault_model="paper").to_dict()
            h.add("EMA-P", t, k, diagnosis=d)
        data = h.data("EMA-P")
    st = component_status(data)
    assert list(st[:, 0]) == ["healthy", "faulty", "unexplained"]       # friction
    assert list(st[:2, 1]) == ["healthy", "healthy"]                    # backlash never named
    fig = plot_history(data)
    axes = fig.axes

    def points(ax, color):
        return [tuple(line.get_xdata()) for line in ax.lines
                if line.get_marker() == "o" and line.get_mfc() != "none"
                and to_rgba(line.get_color()) == to_rgba(color)]

    assert points(axes[0], "C2") == [(10.0,)] and points(axes[0], "C3") == [(20.0,)]
    assert points(axes[0], "0.5") == [(30.0,)]
    assert points(axes[1], "C3") == []                     # backlash 0.01 is not painted faulty
    # k7 without eccentricity: hollow points, no trend line
    hollow = [line for line in axes[6].lines if line.get_mfc() == "none"]
    assert len(hollow) == 1 and tuple(hollow[0].get_xdata()) == (10.0, 20.0, 30.0)
    assert [ax.get_ylabel() for ax in axes] == [f"k{j} [-]" for j in range(1, 9)]
    assert [ax.get_xlabel() for ax in axes[-2:]] == ["time [flight hours]"] * 2
    # each component's failure threshold (k8: the band around nominal 0.5)
    thr = {INDICATOR_COMPONENT[n]: DEFAULT_FAILURE_THRESHOLDS.for_indicator(n)
           for n in INDICATOR_COMPONENT}
    for j, ax in enumerate(axes):
        flat = sorted(ln.get_ydata()[0] for ln in ax.lines if ln.get_linestyle() == "--")
        want = [] if j not in thr else [0.5 - thr[j], 0.5 + thr[j]] if j == 7 else [thr[j]]
        assert flat == pytest.approx(want), j
        # every point is inside the axes, with its interval
        y0, y1 = ax.get_ylim()
        assert y0 <= data.K_lo[:, j].min() and y1 >= data.K_hi[:, j].max()
        x0, x1 = ax.get_xlim()
        assert x0 < 10.0 and x1 > 30.0
    assert legend_texts(axes[0]) == ["healthy", "faulty", "unexplained", "failure threshold"]
    assert legend_texts(axes[6])[0] == "no eccentricity: phase meaningless"


def test_a_damaged_history_is_refused_unchanged(tmp_path):
    import random

    p = tmp_path / "h.sqlite"
    with HealthHistory(p) as h:
        h.register("EMA-D")
        h.add("EMA-D", 1.0, [0, 0, 0, 0, 0, 0, 0.5, 0.5])
    data = bytearray(p.read_bytes())
    rnd = random.Random(1)
    for i in range(200, len(data)):
        data[i] = rnd.randrange(256)
    p.write_bytes(bytes(data))
    before = p.read_bytes()
    with pytest.raises(HistoryError, match="damaged|not an emaphm health history"):
        HealthHistory(p, create=False)
    assert p.read_bytes() == before


def test_history_plot_of_the_components_that_moved(tmp_path):
    """``moved_components``: what reached a quarter of its threshold or was named faulty
    (the eccentricity phase beside its modulus); ``plot_history(components=...)`` draws
    just those panels, says how many it left out, and refuses indices outside k."""
    from emaphm.diagnosis import diagnose
    from emaphm.prognosis.plots import MOVED_SHARE, moved_components, plot_history
    from emaphm.prognosis.thresholds import DEFAULT_FAILURE_THRESHOLDS

    thr_f = DEFAULT_FAILURE_THRESHOLDS.for_indicator("friction")
    with HealthHistory(tmp_path / "h.sqlite") as h:
        h.register("EMA-M")
        ks = [[0.0, 0.0, 0, 0, 0, 0.0, 0.5, 0.5],
              [0.5 * thr_f, 0.0, 0, 0, 0, 0.3, 0.2, 0.5],
              [1.1 * MOVED_SHARE * thr_f, 0.0, 0, 0, 0, 0.3, 0.2, 0.5]]
        for t, k in zip((1.0, 2.0, 3.0), ks):
            h.add("EMA-M", t, k,
                  diagnosis=diagnose(k, fit_ratio=1.2, fault_model="paper").to_dict())
        data = h.data("EMA-M")
        h.register("EMA-Q")
        h.add("EMA-Q", 1.0, [0, 0, 0, 0, 0, 0, 0.5, 0.5])
        quiet = h.data("EMA-Q")
    assert moved_components(data) == [0, 5, 6]             # friction, eccentricity and its phase
    assert moved_components(data, always=[3]) == [0, 3, 5, 6]
    assert moved_components(quiet) == [0]                  # nothing moved: friction alone
    fig = plot_history(data, components=moved_components(data))
    shown = [ax for ax in fig.axes if ax.get_visible()]
    assert [ax.get_ylabel() for ax in shown] == ["k1 [-]", "k6 [-]", "k7 [-]"]
    assert len(fig.axes) == 4 and not fig.axes[3].get_visible()     # 2 x 2, one cell empty
    assert tuple(fig.get_size_inches()) == pytest.approx((11, 1.2 + 1.95 * 2))
    assert "5 other components not shown" in fig._suptitle.get_text()
    assert [ax.get_xlabel() for ax in shown[-2:]] == ["time [flight hours]"] * 2
    assert tuple(plot_history(data).get_size_inches()) == pytest.approx((11, 9))
    with pytest.raises(ValueError, match="indices of k in 0..7"):
        plot_history(data, components=[8])


# ----------------------------------------------------------------------------- issue 25 items 3, 4, 12
def _files(folder):
    """Every file in ``folder`` with the SHA-256 of its bytes (journal files included)."""
    import hashlib

    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.iterdir()) if p.is_file()}


def _history(path, times=(10.0, 20.0, 30.0, 40.0)):
    """A closed history of EMA-R with a growing friction, one inspection per time."""
    with HealthHistory(path) as h:
        h.register("EMA-R", description="ro")
        for i, t in enumerate(times):
            h.add("EMA-R", t, K1 + [0.05 * i, 0, 0, 0, 0, 0, 0, 0],
                  diagnosis={"healthy": True, "verdict": "healthy", "faults": []})
    return path


def test_reading_commands_leave_the_history_byte_identical(tmp_path, capsys):
    folder = tmp_path / "db"
    folder.mkdir()
    db = str(_history(folder / "h.sqlite"))
    before = _files(folder)
    assert set(before) == {"h.sqlite"}
    for argv in (["history", "show", "EMA-R", "--plot", str(tmp_path / "h.png")],
                 ["history", "show", "EMA-R", "--json"], ["history", "list"],
                 ["prognose", "EMA-R"], ["prognose", "EMA-R", "--json"],
                 ["fleet", "report", "--out", str(tmp_path / "site"), "--workers", "0",
                  "--quiet"]):
        rc, out, err = _run(argv + ["--db", db], capsys)
        assert rc == 0, (argv, err)
        assert _files(folder) == before, argv           # no byte changed, no -wal/-shm left
    with HealthHistory(db, readonly=True) as h:         # and a reading handle cannot write
        assert h.journal_mode == "wal" and h.data("EMA-R").n == 4
        with pytest.raises(HistoryError, match="opened read-only"):
            h.register("EMA-S")
    assert _files(folder) == before


def test_a_read_only_open_refuses_what_is_not_a_history_and_creates_nothing(tmp_path):
    with pytest.raises(HistoryError, match="no health history at"):
        HealthHistory(tmp_path / "missing.sqlite", readonly=True)
    (tmp_path / "empty.sqlite").write_bytes(b"")
    for kw in ({"readonly": True}, {"create": False}):
        with pytest.raises(HistoryError, match="is an empty file, not a health history; it was "
                                               "not changed"):
            HealthHistory(tmp_path / "empty.sqlite", **kw)
    with HealthHistory(tmp_path / "empty.sqlite") as h:      # register turns it into one
        h.register("EMA-1")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["empty.sqlite"]
    for name in ("", ":memory:"):
        with pytest.raises(HistoryError, match="give the path of a health history file"):
            HealthHistory(name)


def test_a_version_1_history_is_read_as_it_is(tmp_path):
    import sqlite3

    old = _history(tmp_path / "old.sqlite")
    con = sqlite3.connect(old)
    con.execute("DROP TABLE calibrations")
    con.execute("ALTER TABLE inspections DROP COLUMN readings")
    con.execute("PRAGMA user_version = 1")
    con.commit()
    con.close()
    before = _files(tmp_path)
    with HealthHistory(old, readonly=True) as h:
        assert h.data("EMA-R").n == 4
        assert h.calibration("EMA-R") is None and h.calibrations("EMA-R") == []
    assert _files(tmp_path) == before                   # read, not migrated
    with HealthHistory(old) as h:                       # a writing open migrates it
        assert h.calibrations("EMA-R") == []
    assert sqlite3.connect(old).execute("PRAGMA user_version").fetchone()[0] == hist.SCHEMA_VERSION


def test_sqlite_refusing_a_write_is_reported_with_the_file_and_the_permission(tmp_path):
    """As root no permission bites (the CLI corpus runs that case without the capability
    that overrides them): here SQLite's own refusal, from a read-only connection."""
    import sqlite3
    import urllib.parse

    db = _history(tmp_path / "h.sqlite")
    with HealthHistory(db) as h:
        h._con.close()
        h._con = sqlite3.connect(f"file:{urllib.parse.quote(str(db))}?mode=ro", uri=True,
                                 isolation_level=None)
        with pytest.raises(hist.ReadOnlyHistoryError,
                           match=r"cannot write the health history .*h\.sqlite: attempt to write "
                                 r"a readonly database; it was not changed\. Make it writable"):
            h.add("EMA-R", 50.0, K1)


def test_a_read_only_file_is_refused_before_any_work(tmp_path, monkeypatch):
    db = _history(tmp_path / "h.sqlite")
    monkeypatch.setattr(hist, "write_problem", lambda p: "the file is read-only (Permission denied)")
    with pytest.raises(hist.ReadOnlyHistoryError, match=r"cannot write the health history .*h\.sqlite: "
                                                        r"the file is read-only \(Permission denied\)"):
        HealthHistory(db, create=False)
    with HealthHistory(db, readonly=True) as h:          # reading it is fine
        assert h.data("EMA-R").n == 4


@pytest.mark.parametrize("unit, ok, bad", [("h", 1e6, 1.0000001e6), ("cycles", 1e9, 2e9)])
def test_times_are_bounded_by_the_unit(tmp_path, unit, ok, bad):
    with HealthHistory(tmp_path / "h.sqlite") as h:
        h.register("EMA-T", time_unit=unit)
        for t in (bad, 1e308, float("inf")):
            with pytest.raises(HistoryError, match="beyond|finite number"):
                h.add("EMA-T", t, K1)
            with pytest.raises(HistoryError, match="beyond|finite number"):
                h.calibrate("EMA-T", t, None)
        assert h.actuator("EMA-T").n_inspections == 0
        h.add("EMA-T", ok, K1)
        assert h.data("EMA-T").times.tolist() == [ok]
    assert hist.MAX_TIME == {"h": 1e6, "cycles": 1e9}


def _raw(db, **columns):
    """An inspection row written as another program (or an older emaphm) could have."""
    import sqlite3

    row = {"actuator": "EMA-R", "k": "[0.1,0,0,0,0,0,0.5,0.5]", "k_lo": "[0.1,0,0,0,0,0,0.5,0.5]",
           "k_hi": "[0.1,0,0,0,0,0,0.5,0.5]", "recorded_utc": "2020-01-01T00:00:00", **columns}
    con = sqlite3.connect(db)
    con.execute("DROP TRIGGER inspections_time_forward")
    con.execute(f"INSERT INTO inspections ({', '.join(row)}) VALUES ({', '.join('?' * len(row))})",
                tuple(row.values()))
    con.commit()
    con.close()


BAD_RECORDS = {
    "time 1e308": dict(time=1e308),
    "time infinite": dict(time=float("inf")),
    "time as text": dict(time="abc"),
    "k NaN": dict(time=25.0, k="[NaN,0,0,0,0,0,0.5,0.5]"),
    "k 1e308": dict(time=25.0, k="[1e308,0,0,0,0,0,0.5,0.5]"),
    "k of 3": dict(time=25.0, k="[0.1,0,0]"),
    "k not JSON": dict(time=25.0, k="[0.1,"),
    "diagnosis a list": dict(time=25.0, diagnosis="[1, 2]"),
    "faults not objects": dict(time=25.0, diagnosis='{"healthy": false, "faults": ["x"]}'),
    "extra a string": dict(time=25.0, extra='"x"'),
}


@pytest.mark.parametrize("name", list(BAD_RECORDS))
def test_any_stored_record_is_left_out_with_one_warning_not_a_crash(tmp_path, capsys, name):
    db = _history(tmp_path / "h.sqlite")
    _raw(db, **BAD_RECORDS[name])
    with HealthHistory(db, readonly=True) as h:
        data = h.data("EMA-R")
        assert data.n == 4 and len(data.skipped) == 1 and data.times.tolist() == [10, 20, 30, 40]
        assert len(h.inspections("EMA-R")) == 4 and h.actuators()[0].n_inspections == 5
        bad_id = data.skipped[0].id
    for argv in (["history", "show", "EMA-R", "--plot", str(tmp_path / "h.png")],
                 ["history", "list"], ["prognose", "EMA-R", "--plot", str(tmp_path / "p.png")],
                 ["fleet", "report", "--out", str(tmp_path / "site"), "--workers", "0"]):
        rc, out, err = _run(argv + ["--db", str(db)], capsys)
        assert rc == 0, (argv, err)
        assert "Traceback" not in err
        warnings = [ln for ln in err.splitlines() if ": warning: " in ln]
        if argv[1] != "list":
            assert len(warnings) == 1, err
            assert f"left out 1 stored inspection of EMA-R that cannot be used (id {bad_id} " \
                   in warnings[0]
            assert f"emaphm history remove EMA-R --id {bad_id}" in warnings[0]
    # and it can be taken back
    rc, out, err = _run(["history", "remove", "EMA-R", "--id", str(bad_id), "--db", str(db)], capsys)
    assert rc == 0 and out.startswith(f"removed inspection {bad_id} of EMA-R at "), err
    with HealthHistory(db, readonly=True) as h:
        assert h.data("EMA-R").skipped == () and h.actuators()[0].n_inspections == 4


def test_an_inspection_is_taken_back_by_its_time_or_its_id(tmp_path, capsys):
    db = _history(tmp_path / "h.sqlite")
    _raw(db, time=1e308, source="typo.csv")
    with HealthHistory(db) as h:
        with pytest.raises(TimeOrderError, match=r"take that inspection back with emaphm history "
                                                 r"remove EMA-R --at 1e\+308"):
            h.add("EMA-R", 50.0, K1)
        before = _snapshot(h)
        with pytest.raises(HistoryError, match=r"EMA-R has no inspection at 15 h; nothing was "
                                               r"removed \(its inspections: id 1 at 10, id 2 at 20"):
            h.remove("EMA-R", at=15.0)
        with pytest.raises(HistoryError, match="no inspection with id 99"):
            h.remove("EMA-R", inspection_id=99)
        with pytest.raises(HistoryError, match="its time .* or its id"):
            h.remove("EMA-R")
        with pytest.raises(UnknownActuatorError):
            h.remove("EMA-X", at=10.0)
        assert _snapshot(h) == before
    rc, out, err = _run(["history", "remove", "EMA-R", "--at", "1e308", "--db", str(db)], capsys)
    assert rc == 0, err
    assert out == "removed inspection 5 of EMA-R at 1e+308 h, recorded 2020-01-01 00:00:00 UTC " \
                  "from typo.csv\n"
    with HealthHistory(db) as h:
        gone = h.remove("EMA-R", inspection_id=2)
        assert (gone.id, gone.time, gone.verdict) == (2, 20.0, "healthy")
        assert h.data("EMA-R").times.tolist() == [10.0, 30.0, 40.0]
        h.add("EMA-R", 50.0, K1)                          # the record goes on
    rc, out, _ = _run(["history", "remove", "EMA-R", "--at", "50", "--json", "--db", str(db)], capsys)
    import json

    assert rc == 0 and json.loads(out)["time"] == 50.0


def test_history_add_quiet_prints_the_record_in_one_line(tmp_path, capsys, mm_trace, monkeypatch):
    """--quiet: no progress and no k table, the record in one line on stdout (as fleet demo
    and the other commands' --quiet keep only their result line)."""
    import emaphm.prognosis.workflow as wf
    from emaphm.prognosis.uncertainty import KInterval

    def fake_inspect(h, actuator, trace, t, **kw):
        diag = {"healthy": False, "verdict": "faulty", "faults": [{"mode": "friction",
                                                                   "reading": "k1 0.3"}]}
        ins = h.add(actuator, t, K1, diagnosis=diag)
        interval = KInterval(k=K1, lo=K1, hi=K1, method="population", level=0.9, n=1)
        return ins, type("A", (), {"interval": interval, "evaluations": 7, "elapsed_s": 0.1})()

    monkeypatch.setattr(wf, "record_inspection", fake_inspect)
    db = str(_history(tmp_path / "h.sqlite"))
    trace = str(write_trace(mm_trace, tmp_path / "t.csv"))
    rc, out, err = _run(["history", "add", "EMA-R", trace, "--at", "50", "--quiet", "--db", db],
                        capsys)
    assert rc == 0 and err == ""
    assert out == "recorded inspection of EMA-R at 50 h: FAULTY (friction)\n"
    rc, out, _ = _run(["history", "add", "EMA-R", trace + "", "--at", "60", "--db", db], capsys)
    assert rc == 0 and out.count("\n") > 3 and "friction" in out       # the table without it


def test_a_skipped_inspection_round_trips_through_its_dict():
    from emaphm.prognosis.history import SkippedInspection

    for t in (12.5, math.nan):
        s = SkippedInspection(3, "EMA-1", t, "2026-11-26T20:00:00", "time out of range")
        back = SkippedInspection.from_dict(json.loads(json.dumps(s.to_dict())))
        assert back.to_dict() == s.to_dict()
    with pytest.raises(KeyError):
        SkippedInspection.from_dict({"id": 1, "actuator": "A", "time": 1.0})


def test_record_digests_change_with_an_actuators_records_only(tmp_path):
    """What the fleet site's cache reads of the store (through HealthHistory, never its
    tables by name): one digest per actuator, which moves when its records do."""
    db = tmp_path / "d.sqlite"
    with HealthHistory(db) as h:
        for a in ("EMA-1", "EMA-2"):
            h.register(a)
            h.add(a, 1.0, K1)
        before = h.record_digests()
        h.add("EMA-2", 2.0, K1)
        after = h.record_digests()
    assert set(before) == {"EMA-1", "EMA-2"}
    assert after["EMA-1"] == before["EMA-1"] and after["EMA-2"] != before["EMA-2"]
    with HealthHistory(db, readonly=True) as h:
        assert h.record_digests() == after
