"""The fleet layer: the order of attention, the state of one actuator, safe names and
markup, the static site's content, the demo fleet and the CLI's refusals.

The site's rendering in a real browser is tested in ``test_fleet_browser.py``.
"""

from __future__ import annotations

import json
import math
import re
import sqlite3
import tomllib
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from emaphm.cli import main
from emaphm.diagnosis import diagnose
from emaphm.fleet.markup import esc, page_stem, script_json, slug
from emaphm.fleet.status import (ActuatorStatus, assess, attention_key, growth_rate,
                                 order_fleet)
from emaphm.prognosis.history import Actuator, HealthHistory, HistoryData

SCRIPT_ID = "<script>alert(1)</script>"
NASTY = "</script><script>alert(2)</script><!-- & \"quotes\" 'apostrophes' \u2028"


# ----------------------------------------------------------------------------- helpers
def _k(friction=0.0, backlash=0.0, short_a=0.0, gain=0.5):
    return [friction, backlash, short_a, 0.0, 0.0, 0.0, 0.5, gain]


def _add_series(h, actuator, times, ks, **kw):
    for t, k in zip(times, ks):
        h.add(actuator, float(t), k, diagnosis=diagnose(k, fault_model="paper").to_dict(),
              algorithm="pso", seed=0, fingerprint=f"{actuator}-{t}", **kw)


def _register_raw(h, actuator_id, description=""):
    """An actuator the registry would refuse (a store written by another tool)."""
    h._con.execute("INSERT INTO actuators (id, description, time_unit, created_utc, updated_utc) "
                   "VALUES (?, ?, 'h', '2026-01-01T00:00:00', '2026-01-01T00:00:00')",
                   (actuator_id, description))


def _status(id_, *, past=False, ratio=0.5, rul=math.nan, lo=math.nan, no_growth=False,
            n=5, prognosis=True):
    act = Actuator(id=id_, description="", time_unit="h", created_utc="", n_inspections=n)
    data = HistoryData(actuator=act, times=np.arange(n, dtype=float), K=np.zeros((n, 8)),
                       K_lo=np.zeros((n, 8)), K_hi=np.zeros((n, 8)), inspections=())
    return ActuatorStatus(
        actuator=act, n_inspections=n, last_time=float(n - 1) if n else None,
        last_recorded_utc=None, verdict="healthy" if n else "not inspected", faults=(),
        worst="friction" if n else None, level=0.5 * ratio, threshold=0.5, rul_median=rul,
        rul_lo=lo, rul_hi=math.inf, rul_level=0.9, no_growth=no_growth, past_threshold=past,
        trend=0, growth=0.0, data=data, prognosis=object() if prognosis and n else None)


# ----------------------------------------------------------------------------- order
def test_the_fleet_is_ordered_past_threshold_first_then_by_rul_median():
    statuses = [
        _status("H-flat-far", ratio=0.1, no_growth=True),
        _status("A-past-a-bit", past=True, ratio=1.1, rul=0.0),
        _status("D-rul-200", rul=200.0, lo=150.0),
        _status("Z-never", n=0),
        _status("B-past-far", past=True, ratio=1.6, rul=0.0),
        _status("C-rul-50", rul=50.0, lo=40.0),
        _status("G-flat-near", ratio=0.8, rul=5e4, no_growth=True),
        _status("E-rul-200-lower-bound", rul=200.0, lo=100.0),
        _status("F-new", ratio=0.9, n=1, prognosis=False),
    ]
    got = [s.id for s in order_fleet(statuses)]
    assert got == ["B-past-far", "A-past-a-bit", "C-rul-50", "E-rul-200-lower-bound",
                   "D-rul-200", "F-new", "G-flat-near", "H-flat-far", "Z-never"]
    # ties by id, whatever the input order
    same = [_status(i, rul=10.0, lo=5.0) for i in ("b", "c", "a")]
    assert [s.id for s in order_fleet(same)] == ["a", "b", "c"]
    assert attention_key(same[0]) < attention_key(_status("x", rul=11.0, lo=1.0))


def _history(tmp_path, series, name="h.sqlite"):
    """``series``: id -> (times, ks); returns the HistoryData of each."""
    with HealthHistory(tmp_path / name) as h:
        for aid, (times, ks) in series.items():
            h.register(aid)
            _add_series(h, aid, times, ks)
        return {aid: h.data(aid) for aid in series}


def test_assess_names_the_growing_indicator_its_rul_and_a_rising_trend(tmp_path):
    rng = np.random.default_rng(1)
    t = np.linspace(0.0, 800.0, 8)
    friction = 0.0005 * t + rng.normal(0, 0.003, t.size)       # reaches 0.5 at t = 1000
    data = _history(tmp_path, {"EMA-1": (t, [_k(friction=max(f, 0.0)) for f in friction])})
    s = assess(data["EMA-1"], seed=0)
    assert s.worst == "friction" and s.trend == 1 and s.predicted and not s.past_threshold
    assert s.rul_state == "predicted" and s.verdict == "faulty" and s.faults == ("friction",)
    assert 120 < s.rul_median < 300 and s.rul_lo < s.rul_median < s.rul_hi   # truth: 200 h
    assert s.growth == pytest.approx(0.0005, rel=0.3)
    assert s.level == pytest.approx(friction[-1]) and s.threshold == 0.5
    assert s.n_inspections == 8 and s.last_time == 800.0


def test_assess_past_threshold_falling_flat_new_and_never_inspected(tmp_path):
    rng = np.random.default_rng(2)
    t = np.linspace(0.0, 500.0, 6)
    series = {
        "PAST": (t, [_k(friction=0.1 + 0.0009 * x) for x in t]),            # 0.55 at the end
        "FALL": (t, [_k(gain=0.5 - (0.2 - 0.0003 * x)) for x in t]),        # drift recedes
        "FLAT": (t, [_k(backlash=0.01 + e) for e in rng.normal(0, 0.002, t.size)]),
        "NEW": (t[:1], [_k(short_a=0.02)]),
        "NONE": ((), ()),
    }
    data = _history(tmp_path, series)
    past = assess(data["PAST"], seed=0)
    assert past.past_threshold and past.worst == "friction" and past.rul_state == "past threshold"
    assert past.ratio == pytest.approx(0.55 / 0.5)
    fall = assess(data["FALL"], seed=0)
    assert fall.worst == "gain_drift" and fall.trend == -1 and not fall.predicted
    assert fall.rul_state == "no growth"
    flat = assess(data["FLAT"], seed=0)
    assert flat.trend == 0 and flat.rul_state == "no growth" and flat.verdict == "healthy"
    new = assess(data["NEW"], seed=0)
    assert new.prognosis is None and new.rul_state == "no prediction" and new.trend is None
    assert new.worst == "short_circuit_a" and math.isnan(new.rul_median)
    none = assess(data["NONE"], seed=0)
    assert none.worst is None and none.verdict == "not inspected" and none.n_inspections == 0
    assert [s.id for s in order_fleet([none, new, flat, fall, past])] == \
        ["PAST", "FALL", "NEW", "FLAT", "NONE"]


def test_a_trend_within_the_noise_is_not_a_predicted_failure(tmp_path):
    """A healthy demo unit's short-circuit k scatters at zero; the exponential fitted to the
    scatter crosses 0.3 at a finite median (prognose), but the growth is not beyond the
    noise, so the fleet does not list it among the failing units."""
    from emaphm.fleet.demo import _synthetic, demo_fleet

    unit = demo_fleet(30, seed=0)[8]
    assert unit.scenario is None
    t = np.array(unit.times)
    data = _history(tmp_path, {unit.id: (t, _synthetic(unit))})
    s = assess(data[unit.id], seed=0)
    p = s.prognosis.predictions["short_circuit_b"]
    span = t[-1] - t[0]
    assert math.isfinite(p.median) and not p.no_growth(span)       # prognose sees a crossing
    assert s.rul_state == "no growth" and not s.predicted and s.trend == 0


def test_growth_rate_is_the_trend_derivative_at_the_last_inspection():
    from emaphm.prognosis.trends import fit_trend

    t = np.linspace(0.0, 100.0, 8)
    lin = fit_trend(t, 0.1 + 0.002 * t + np.array([0, 1, -1, 0, 1, -1, 0, 0]) * 1e-3, "linear")
    rate, se = growth_rate(lin)
    assert rate == pytest.approx(lin.theta[1]) and se == pytest.approx(math.sqrt(lin.cov[1, 1]))
    exp = fit_trend(t, 0.01 * np.exp(0.02 * t), "exponential")
    rate, _ = growth_rate(exp)
    h = 1e-4
    numeric = (exp.value(t[-1] + h)[0] - exp.value(t[-1] - h)[0]) / (2 * h)
    assert rate == pytest.approx(numeric, rel=1e-5)


# ----------------------------------------------------------------------------- markup
def test_page_stems_are_safe_distinct_and_stable():
    stems = {i: page_stem(i) for i in ("EMA-1", "ema-1", "EMA/1", "EMA:1", "EMA.1", SCRIPT_ID,
                                       "..", "-", "A" * 64)}
    assert len(set(stems.values())) == len(stems)
    for aid, stem in stems.items():
        assert re.fullmatch(r"[a-z0-9-]{1,40}-[0-9a-f]{10}", stem), stem
    assert stems[SCRIPT_ID].startswith("script-alert-1-script-")
    assert stems[".."].startswith("actuator-") and len(stems["A" * 64]) == 40 + 11
    assert page_stem("EMA-0042") == "ema-0042-2afaeebfeb"          # pinned: links must not move
    assert slug("Left Aileron #2") == "left-aileron-2" and page_stem("x", digits=64)[-65] == "-"


def test_script_json_cannot_end_its_script_element_and_round_trips():
    payload = {"id": SCRIPT_ID, "description": NASTY, "n": [1, 2.5, None]}
    text = script_json(payload)
    assert not re.search("[<>&\u2028\u2029]", text)
    assert "</script" not in text.lower() and "<!--" not in text
    assert json.loads(text) == payload
    with pytest.raises(ValueError):
        script_json({"x": math.inf})


def test_esc_escapes_text_and_both_quotes():
    assert esc(SCRIPT_ID) == "&lt;script&gt;alert(1)&lt;/script&gt;"
    assert esc("a\"b'c&") == "a&quot;b&#x27;c&amp;"


# ----------------------------------------------------------------------------- the site
def _calibrated_params():
    from emaphm.params import Calibration, siemens_1fk7060

    return replace(siemens_1fk7060(), calibration=Calibration(
        date="2026-01-02", sources=("healthy1.parquet", "healthy2.parquet"),
        estimates=(("R", 0.12, 0.01), ("offset_a", 0.03, 0.002)), fixed=("L",)))


@pytest.fixture(scope="module")
def small_site(tmp_path_factory):
    """A small fleet built through the history API (and one id the registry refuses)."""
    from emaphm.fleet.site import build_site

    tmp = tmp_path_factory.mktemp("fleet")
    db = tmp / "fleet.sqlite"
    t = np.linspace(0.0, 600.0, 5)
    with HealthHistory(db) as h:
        h.register("EMA-SOON", description="left aileron " + NASTY)
        _add_series(h, "EMA-SOON", t, [_k(friction=0.05 + 0.0007 * x) for x in t])
        h.register("EMA-PAST")
        _add_series(h, "EMA-PAST", t, [_k(short_a=0.01 + 0.0005 * x) for x in t])
        h.register("EMA-CAL", description="calibrated")
        params = _calibrated_params()
        h.calibrate("EMA-CAL", 0.0, params, sources=["/bench/healthy1.parquet"])
        _add_series(h, "EMA-CAL", t, [_k(backlash=0.01) for _ in t],
                    extra={"calibrated_at": 0.0, "parameters": params.to_dict(),
                           "fault_model": "physical", "nuisance": {"R": 0.01}})
        h.register("EMA-NEW")
        _add_series(h, "EMA-NEW", t[:1], [_k()])
        _register_raw(h, SCRIPT_ID, NASTY)
        _add_series(h, SCRIPT_ID, t[:3], [_k(gain=0.5 + 0.0001 * x) for x in t[:3]])
    site = build_site(db, tmp / "site", workers=0)
    return site, db


def _svg_size(path: Path) -> tuple[int, int]:
    import xml.etree.ElementTree as ET

    root = ET.fromstring(path.read_bytes())
    assert root.tag == "{http://www.w3.org/2000/svg}svg"
    return int(root.get("width")), int(root.get("height"))


def test_the_index_lists_every_actuator_in_attention_order(small_site):
    site, _ = small_site
    html = site.index.read_text(encoding="utf-8")
    order = [s.id for s in site.statuses]
    assert order[:2] == ["EMA-PAST", "EMA-SOON"] and set(order) == {
        "EMA-SOON", "EMA-PAST", "EMA-CAL", "EMA-NEW", SCRIPT_ID}
    rows = re.findall(r"<tr data-i=\"(\d+)\"", html)
    assert rows == [str(i) for i in range(5)]
    links = re.findall(r"<td class=\"c-id\"[^>]*><div><a href=\"([^\"]+)\">([^<]+)</a>", html)
    assert [text for _, text in links] == [esc(i) for i in order]
    for href, _ in links:
        assert (site.out / href).is_file()
    data = json.loads((site.out / "fleet.json").read_text())
    assert [r["id"] for r in data["actuators"]] == order
    past = data["actuators"][0]
    assert past["rul_state"] == "past threshold" and past["worst"] == "short_circuit_a"
    soon = data["actuators"][1]
    assert soon["rul_state"] == "predicted" and soon["trend"] == 1 and soon["rul_median"] > 0
    assert soon["rul_lo"] <= soon["rul_median"] <= (soon["rul_hi"] or math.inf)
    for name in ("fleet.css", "fleet.js"):
        shipped = Path(__import__("emaphm.fleet", fromlist=["x"]).__file__).parent / "assets" / name
        assert (site.out / "assets" / name).read_bytes() == shipped.read_bytes()
    assert not list(site.out.rglob("*.tmp"))


def test_user_text_is_escaped_everywhere_and_the_inline_json_is_intact(small_site):
    site, _ = small_site
    html = site.index.read_text(encoding="utf-8")
    assert "<script>alert" not in html and "<!-- &" not in html
    assert esc(SCRIPT_ID) in html and esc(NASTY) in html
    # exactly the two script elements we wrote: the shipped script and the data block
    assert html.count("<script") == 2 and html.count("</script>") == 2
    block = re.search(r'<script type="application/json" id="fleet-data">(.*?)</script>', html,
                      re.S).group(1)
    rows = json.loads(block)["actuators"]
    assert {r["id"] for r in rows} >= {SCRIPT_ID} and NASTY in [r["description"] for r in rows]
    page = site.pages[SCRIPT_ID]
    assert page.name.startswith("script-alert-1-script-")
    text = page.read_text(encoding="utf-8")
    assert f"<h1>{esc(SCRIPT_ID)}</h1>" in text and "<script>alert" not in text
    assert text.count("<script") == 1                      # only the shipped fleet.js


def test_each_actuator_page_has_its_figures_calibration_and_inspections(small_site):
    site, db = small_site
    for status in site.statuses:
        text = site.pages[status.id].read_text(encoding="utf-8")
        imgs = re.findall(r'<img src="([^"]+)" width="(\d+)" height="(\d+)"', text)
        expected = (1 if status.n_inspections else 0) + (status.prognosis is not None)
        assert len(imgs) == expected, status.id
        for src, w, h in imgs:
            assert _svg_size(site.pages[status.id].parent / src) == (int(w), int(h))
        assert 'href="../index.html"' in text and 'href="../assets/fleet.css"' in text
    cal = site.pages["EMA-CAL"].read_text(encoding="utf-8")
    assert "calibration of 0 h" in cal and "Calibrations recorded" in cal
    assert "healthy1.parquet" in cal and "+12.00 %" in cal and "R +1.0 %" in cal
    assert "Kept at the data sheet: L" in cal
    soon = site.pages["EMA-SOON"].read_text(encoding="utf-8")
    assert "data sheet" in soon and "No calibration recorded" in soon
    assert soon.count("<tr><th scope=\"row\">") >= 5            # five inspections
    assert "EMA-SOON-600" in soon and "pso" in soon             # fingerprint, algorithm
    assert "0.470<small>[0.470, 0.470]</small>" in soon         # k1 with its interval
    new = site.pages["EMA-NEW"].read_text(encoding="utf-8")
    assert "needs 3 inspections" in new or "a degradation trend needs at least 3" in new


def test_workers_draw_the_same_site_and_a_rebuild_draws_only_what_changed(tmp_path):
    from emaphm.fleet.site import build_site

    db = tmp_path / "f.sqlite"
    t = np.linspace(0.0, 300.0, 3)
    with HealthHistory(db) as h:                 # B has a prognosis, A and C do not yet
        for aid, f, n in (("A", 0.0005, 2), ("B", 0.0002, 3), ("C", 0.0, 2)):
            h.register(aid)
            _add_series(h, aid, t[:n], [_k(friction=0.01 + f * x) for x in t[:n]])
    serial = build_site(db, tmp_path / "serial", workers=0)
    parallel = build_site(db, tmp_path / "parallel", workers=2)
    assert (serial.workers, parallel.workers) == (0, 2) and serial.drawn == parallel.drawn == 3
    a, b = (json.loads((s.out / "fleet.json").read_text()) for s in (serial, parallel))
    assert a == b and [r["id"] for r in a["actuators"]] == ["B", "A", "C"]
    figs = sorted(p.name for p in (tmp_path / "serial" / "actuators").glob("*.svg"))
    assert figs == sorted(p.name for p in (tmp_path / "parallel" / "actuators").glob("*.svg"))
    assert len(figs) == 4
    # rebuild after one new inspection of B: only B's figures are drawn again
    before = {p.name: p.stat().st_mtime_ns for p in (tmp_path / "serial" / "actuators").glob("*.svg")}
    with HealthHistory(db) as h:
        _add_series(h, "B", [400.0], [_k(friction=0.2)])
    again = build_site(db, tmp_path / "serial", workers=0)
    assert again.drawn == 1
    after = {p.name: p.stat().st_mtime_ns for p in (tmp_path / "serial" / "actuators").glob("*.svg")}
    changed = sorted(n for n in after if after[n] != before[n])
    assert changed == sorted(f"{page_stem('B')}-{k}.svg" for k in ("history", "prognosis"))
    assert build_site(db, tmp_path / "serial", workers=0, actuators=["A"], redraw=True).drawn == 1
    # a deleted figure is drawn again
    (tmp_path / "serial" / "actuators" / f"{page_stem('C')}-history.svg").unlink()
    assert build_site(db, tmp_path / "serial", workers=0).drawn == 1
    assert (tmp_path / "serial" / "actuators" / f"{page_stem('C')}-history.svg").is_file()


# ----------------------------------------------------------------------------- the demo
def test_the_demo_fleet_is_varied_and_every_unit_flows_from_the_seed():
    from emaphm.fleet.demo import FAULT_KINDS, demo_fleet

    units = demo_fleet(30, seed=0)
    assert [u.id for u in units] == [f"EMA-{i:03d}" for i in range(1, 31)]
    assert demo_fleet(30, seed=0) == units and demo_fleet(3, seed=0) == units[:3]
    assert demo_fleet(30, seed=1) != units
    indicators = {u.scenario.indicator for u in units if u.scenario is not None}
    assert len(indicators) >= 6 and sum(u.scenario is None for u in units) == 9
    laws = {u.scenario.law.kind for u in units if u.scenario is not None}
    assert laws == {"linear", "exponential", "power"}
    ages = [u.times[-1] / u.eol for u in units if u.scenario is not None]
    assert min(ages) < 0.3 and max(ages) >= 1.0                     # young ones, and failed ones
    counts = [len(u.times) for u in units]
    assert min(counts) == 1 and max(counts) <= 10
    for u in units:
        assert np.all(np.diff(u.times) > 0) and u.times[0] >= 0
        K = u.k_true()
        assert K.shape == (len(u.times), 8) and K.min() >= 0 and K.max() <= 1
    assert len(FAULT_KINDS) == 10
    with pytest.raises(ValueError, match="1 to 500"):
        demo_fleet(0)


def test_a_synthetic_demo_is_recorded_and_says_so(tmp_path):
    from emaphm.fleet.demo import demo_fleet, record_demo_fleet

    units = demo_fleet(4, seed=3)
    res = record_demo_fleet(tmp_path / "d.sqlite", units, synthetic=True)
    assert [r["id"] for r in res] == [u.id for u in units]
    with HealthHistory(tmp_path / "d.sqlite", create=False) as h:
        assert [a.id for a in h.actuators()] == [u.id for u in units]
        for u in units:
            ins = h.inspections(u.id)
            assert [i.time for i in ins] == list(u.times)
            assert all("synthetic" in i.source and i.extra["synthetic"] for i in ins)
            assert np.allclose(ins[-1].extra["k_true"], u.k_true()[-1])
            assert all(i.diagnosis["verdict"] in ("healthy", "faulty") for i in ins)
    with pytest.raises(ValueError, match="exists"):
        record_demo_fleet(tmp_path / "d.sqlite", units, synthetic=True)


def test_a_real_demo_unit_is_simulated_and_diagnosed(tmp_path):
    from emaphm.fleet.demo import demo_fleet, record_demo_fleet

    unit = demo_fleet(3, seed=0)[2]                        # healthy, two inspections
    assert unit.scenario is None and len(unit.times) == 2
    res = record_demo_fleet(tmp_path / "r.sqlite", [unit], workers=0, budget=600)
    assert res[0]["verdicts"] and len(res[0]["verdicts"]) == 2
    with HealthHistory(tmp_path / "r.sqlite", create=False) as h:
        ins = h.inspections(unit.id)
    assert len({i.fingerprint for i in ins}) == 2 and all(i.algorithm == "lsq" for i in ins)
    assert all("reference plant" in i.source for i in ins)
    assert all(i.extra["k_true"] == [0, 0, 0, 0, 0, 0, 0.5, 0.5] for i in ins)


# ----------------------------------------------------------------------------- the CLI
def _one_line_error(capsys, argv, *needles):
    rc = main(argv)
    err = capsys.readouterr().err
    assert rc == 2, err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    for n in needles:
        assert n in err, err
    return err


def test_fleet_report_refuses_bad_input_in_one_line(tmp_path, capsys, small_site):
    _, db = small_site
    out = str(tmp_path / "site")
    _one_line_error(capsys, ["fleet", "report", "--db", str(tmp_path / "none.sqlite"),
                             "--out", out], "no health history")
    bad = tmp_path / "bad.sqlite"
    bad.write_bytes(b"not a database at all" * 100)
    _one_line_error(capsys, ["fleet", "report", "--db", str(bad), "--out", out],
                    "not an emaphm health history")
    _one_line_error(capsys, ["fleet", "report", "--db", str(db), "--out", out,
                             "--actuator", "EMA-404"], "'EMA-404' is not registered")
    _one_line_error(capsys, ["fleet", "report", "--db", str(db), "--out", str(bad)],
                    "is a file, not a folder")
    _one_line_error(capsys, ["fleet", "report", "--db", str(db), "--out", out,
                             "--threshold", "friction=2"], "--threshold")
    _one_line_error(capsys, ["fleet", "report", "--db", str(db), "--out", out, "--level", "1.5"],
                    "--level")
    with HealthHistory(tmp_path / "empty.sqlite"):
        pass
    _one_line_error(capsys, ["fleet", "report", "--db", str(tmp_path / "empty.sqlite"),
                             "--out", out], "has no actuators")
    sql = tmp_path / "other.sqlite"
    with sqlite3.connect(sql) as con:
        con.execute("CREATE TABLE t (x)")
    _one_line_error(capsys, ["fleet", "report", "--db", str(sql), "--out", out],
                    "not an emaphm health history")
    assert not (tmp_path / "site").exists()              # nothing written on refusal


def test_fleet_demo_refuses_bad_input_in_one_line(tmp_path, capsys, small_site):
    _, db = small_site
    _one_line_error(capsys, ["fleet", "demo", "--db", str(db)], "exists")
    _one_line_error(capsys, ["fleet", "demo", "--db", str(tmp_path / "no" / "d.sqlite")],
                    "does not exist")
    _one_line_error(capsys, ["fleet", "demo", "--db", str(tmp_path / "d.sqlite"),
                             "--actuators", "0"], "--actuators")
    _one_line_error(capsys, ["fleet", "demo", "--db", str(tmp_path / "d.sqlite"),
                             "--budget", "0"], "--budget")
    assert not (tmp_path / "d.sqlite").exists()


def test_fleet_demo_then_report_from_the_command_line(tmp_path, capsys):
    db = tmp_path / "demo.sqlite"
    assert main(["fleet", "demo", "--db", str(db), "--actuators", "3", "--synthetic",
                 "--json"]) == 0
    demo = json.loads(capsys.readouterr().out)
    assert [a["id"] for a in demo["actuators"]] == ["EMA-001", "EMA-002", "EMA-003"]
    assert main(["fleet", "report", "--db", str(db), "--out", str(tmp_path / "new" / "site"),
                 "--workers", "0", "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["actuators"] == 3 and Path(rep["index"]).is_file()
    assert sorted(rep["pages"]) == ["EMA-001", "EMA-002", "EMA-003"]


def test_the_site_assets_are_package_data():
    """An install from a clean clone carries the stylesheet and the script."""
    root = Path(__file__).resolve().parents[2]
    cfg = tomllib.loads((root / "pyproject.toml").read_text())
    patterns = cfg["tool"]["setuptools"]["package-data"]["emaphm.fleet"]
    assets = root / "src" / "emaphm" / "fleet" / "assets"
    shipped = {p.relative_to(assets.parent).as_posix() for pat in patterns
               for p in assets.parent.glob(pat)}
    on_disk = {p.relative_to(assets.parent).as_posix() for p in assets.iterdir()}
    assert on_disk and on_disk <= shipped
    from emaphm.fleet.site import ASSETS

    assert {f"assets/{a}" for a in ASSETS} == on_disk


def test_a_site_rebuilt_from_another_history_drops_the_pages_it_no_longer_has(tmp_path):
    from emaphm.fleet.site import build_site

    t = np.linspace(0.0, 300.0, 3)
    first, second = tmp_path / "1.sqlite", tmp_path / "2.sqlite"
    with HealthHistory(first) as h:
        for aid in ("A", "GONE"):
            h.register(aid)
            _add_series(h, aid, t, [_k(friction=0.01 + 0.0004 * x) for x in t])
    with HealthHistory(second) as h:
        h.register("A")
        _add_series(h, "A", t, [_k(friction=0.01 + 0.0004 * x) for x in t])
    out = tmp_path / "site"
    build_site(first, out, workers=0)
    gone = page_stem("GONE")
    assert (out / "actuators" / f"{gone}.html").is_file()
    assert (out / "actuators" / f"{gone}-prognosis.svg").is_file()
    # a subset keeps the others' pages; the whole of another history does not
    build_site(first, out, workers=0, actuators=["A"])
    assert (out / "actuators" / f"{gone}.html").is_file()
    site = build_site(second, out, workers=0)
    assert set(site.pages) == {"A"}
    left = sorted(p.name for p in (out / "actuators").iterdir())
    assert not [n for n in left if n.startswith(gone)]
    manifest = json.loads((out / "actuators" / ".figures.json").read_text())
    assert set(manifest) == {page_stem("A")}


def test_a_site_is_built_around_a_stored_record_it_cannot_use(tmp_path, capsys):
    """A record an older emaphm let through (--at 1e308) made the whole report fail
    ('SVD did not converge'): the site leaves it out, and the command says so in one
    warning line; the history is read, never written (its bytes are the same)."""
    import hashlib

    from emaphm.fleet.site import build_site

    db = tmp_path / "fleet.sqlite"
    t = np.linspace(0.0, 600.0, 5)
    with HealthHistory(db) as h:
        h.register("EMA-TYPO")
        _add_series(h, "EMA-TYPO", t, [_k(friction=0.05 + 0.0007 * x) for x in t])
        h.register("EMA-OK")
        _add_series(h, "EMA-OK", t, [_k(backlash=0.01) for _ in t])
        h._con.execute("DROP TRIGGER inspections_time_forward")
        h._con.execute("INSERT INTO inspections (actuator, time, k, k_lo, k_hi, recorded_utc) "
                       "SELECT actuator, 1e308, k, k_lo, k_hi, recorded_utc FROM inspections "
                       "WHERE actuator = 'EMA-TYPO' AND time = 600")
    before = hashlib.sha256(db.read_bytes()).hexdigest()
    site = build_site(db, tmp_path / "site", workers=0)
    typo = next(s for s in site.statuses if s.id == "EMA-TYPO")
    assert typo.n_inspections == 5 and typo.last_time == 600.0 and typo.prognosis is not None
    assert [x.time for x in typo.data.skipped] == [1e308]
    assert main(["fleet", "report", "--db", str(db), "--out", str(tmp_path / "site"),
                 "--workers", "0", "--quiet"]) == 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("emaphm fleet report: warning: left out 1 "
                                                   "stored inspection of EMA-TYPO")
    assert "emaphm history remove EMA-TYPO --id 11" in err
    assert hashlib.sha256(db.read_bytes()).hexdigest() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fleet.sqlite", "site"]


# ----------------------------------------------------------------------------- when to look next
def test_assess_plans_each_actuators_next_inspection(tmp_path):
    from emaphm.prognosis.inspection import INTERVAL_DEFAULTS, InspectionPolicy

    t = np.linspace(0.0, 600.0, 7)
    series = {
        "GROW": (t, [_k(friction=0.02 + 0.0004 * x + 0.003 * math.sin(x)) for x in t]),
        "PAST": (t, [_k(friction=0.1 + 0.0009 * x) for x in t]),
        "FLAT": (t, [_k(backlash=0.004 * abs(math.sin(x))) for x in t]),
        "NEW": (t[:1], [_k()]),
        "NONE": ((), ()),
    }
    data = _history(tmp_path, series)
    dflt = INTERVAL_DEFAULTS["h"]
    grow = assess(data["GROW"], seed=0).plan
    assert grow.indicator == "friction" and grow.rule in ("risk", "max interval")
    assert 600.0 + dflt.min <= grow.at <= 600.0 + dflt.max and grow.target == 0.01
    assert assess(data["PAST"], seed=0).plan.rule == "act now"
    flat = assess(data["FLAT"], seed=0).plan
    assert (flat.rule, flat.at) == ("healthy", 600.0 + dflt.default)
    assert assess(data["NEW"], seed=0).plan.rule == "too few inspections"
    assert assess(data["NONE"], seed=0).plan.rule == "never inspected"
    assert assess(data["GROW"], seed=0, policy=None).plan is None
    # a smaller risk plans sooner, with more draws behind it; the RUL stays the RUL
    strict = assess(data["GROW"], seed=0, policy=InspectionPolicy(risk=0.002))
    assert strict.plan.at <= grow.at and strict.prognosis.predictions["friction"].samples.size \
        == 20_000


def _unfold(ics: str) -> list[str]:
    """RFC 5545 content lines: every physical line ends in CRLF, is at most 75 octets, and
    a line that starts with a space continues the one before."""
    assert ics.endswith("\r\n") and "\n" not in ics.replace("\r\n", "")
    physical = ics.split("\r\n")[:-1]
    assert all(len(line.encode("utf-8")) <= 75 for line in physical)
    lines: list[str] = []
    for line in physical:
        if line.startswith(" "):
            lines[-1] += line[1:]
        else:
            lines.append(line)
    return lines


def test_fleet_schedule_writes_one_row_per_actuator_soonest_first_linked_to_its_page(
        small_site, tmp_path, capsys):
    site, db = small_site
    out = tmp_path / "plan.csv"
    assert main(["fleet", "schedule", "--db", str(db), "--out", str(out), "--site",
                 str(site.out), "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)["rows"]
    import csv

    table = list(csv.DictReader(out.open(encoding="utf-8")))
    assert [r["actuator"] for r in table] == [r["actuator"] for r in rows]
    assert len(table) == 5 and table[0]["due_now"] == "yes"
    assert table[0]["actuator"] == "EMA-PAST" and table[0]["rule"] == "act now"
    assert table[0]["indicator"] == "short_circuit_a"
    due = [r["inspect_by"] - (r["last_inspection"] or 0.0) for r in rows]
    assert due == sorted(due)
    soon = next(r for r in table if r["actuator"] == "EMA-SOON")     # 0.47 of 0.5, growing
    assert (soon["indicator"], soon["rule"], soon["due_now"]) == ("friction", "act now", "yes")
    assert float(soon["risk"]) > 0.01 and "friction" in soon["reason"]
    cal = next(r for r in table if r["actuator"] == "EMA-CAL")       # flat backlash at 0.01
    assert (cal["rule"], float(cal["inspect_by"])) == ("healthy", 600.0 + 300.0)
    for r in table:                                  # each link is the page fleet report wrote
        assert Path(r["link"]).is_file(), r["link"]
        assert r["reason"] and r["time_unit"] == "h" and r["date"] == ""


def test_fleet_schedule_as_a_calendar_maps_operating_hours_onto_dates(tmp_path, capsys):
    import datetime as dt

    t = np.linspace(0.0, 600.0, 7)
    with HealthHistory(tmp_path / "h.sqlite") as h:
        h.register("EMA-1", description="left aileron, A320; MSN 1234")
        _add_series(h, "EMA-1", t, [_k(friction=0.02 + 0.0004 * x + 0.003 * math.sin(x))
                                    for x in t])
        h.register("EMA-2")
        _add_series(h, "EMA-2", t[:2], [_k(), _k()])
        _register_raw(h, "=HYPERLINK(\"x\")")
    out = tmp_path / "plan.ics"
    assert main(["fleet", "schedule", "--db", str(tmp_path / "h.sqlite"), "--out", str(out),
                 "--start", "2026-12-01", "--per-day", "8", "--site",
                 "https://ops.example/fleet", "--risk", "0.05", "--json"]) == 0
    rows = {r["actuator"]: r for r in json.loads(capsys.readouterr().out)["rows"]}
    lines = _unfold(out.read_bytes().decode("utf-8"))
    assert lines[0] == "BEGIN:VCALENDAR" and lines[-1] == "END:VCALENDAR"
    events = [i for i, line in enumerate(lines) if line == "BEGIN:VEVENT"]
    assert len(events) == 3 and lines.count("END:VEVENT") == 3
    start = dt.date(2026, 12, 1)
    for r in rows.values():
        days = 0 if r["due_now"] else math.floor((r["inspect_by"] - r["last_inspection"]) / 8)
        assert r["date"] == (start + dt.timedelta(days=days)).isoformat()
        assert f"DTSTART;VALUE=DATE:{r['date'].replace('-', '')}" in lines
        assert f"URL:{r['link']}" in lines and r["link"].startswith("https://ops.example/fleet/")
    assert rows["EMA-2"]["inspect_by"] == 100.0 + 300.0 and rows["EMA-2"]["date"] == "2027-01-07"
    desc = next(line for line in lines if line.startswith("DESCRIPTION:EMA-1"))
    assert "left aileron\\, A320\\; MSN 1234" in desc and "\\n" in desc
    # the csv of an id that reads as a formula starts it with a quote
    assert main(["fleet", "schedule", "--db", str(tmp_path / "h.sqlite"), "--out",
                 str(tmp_path / "plan.csv")]) == 0
    assert "'=HYPERLINK" in (tmp_path / "plan.csv").read_text(encoding="utf-8")


def test_fleet_schedule_refuses_bad_input_in_one_line(small_site, tmp_path, capsys):
    _, db = small_site
    base = ["fleet", "schedule", "--db", str(db)]
    ics = str(tmp_path / "p.ics")
    _one_line_error(capsys, [*base, "--out", ics], "calendar events need dates",
                    "--start DATE", "--per-day H")
    _one_line_error(capsys, [*base, "--out", ics, "--start", "2026-12-01"],
                    "give both, e.g. --start 2026-12-01 --per-day 8")
    _one_line_error(capsys, [*base, "--out", ics, "--start", "1.12.2026", "--per-day", "8"],
                    "write it as YYYY-MM-DD")
    _one_line_error(capsys, [*base, "--out", str(tmp_path / "p.txt")], "must end in .csv or .ics")
    _one_line_error(capsys, [*base, "--out", str(tmp_path / "p.csv"), "--actuator", "EMA-9"],
                    "'EMA-9' is not registered")
    _one_line_error(capsys, [*base, "--out", str(tmp_path / "p.csv"), "--risk", "0.01",
                             "--min-interval", "900"], "must be below the maximum")
    for argv, needle in ((["--risk", "1.5"], "risk must be a probability in (0, 1)"),
                         (["--max-interval", "0"], "interval must be a finite number > 0"),
                         (["--per-day", "-8"], "operating time per day must be a number")):
        with pytest.raises(SystemExit) as exc:
            main([*base, "--out", str(tmp_path / "p.csv"), *argv])
        err = capsys.readouterr().err
        assert exc.value.code == 2 and err.count("\n") == 1 and needle in err, err
    assert not list(tmp_path.iterdir())                       # nothing written


def test_the_index_shows_when_to_inspect_each_actuator_sortable_and_due_in_red(small_site):
    site, _ = small_site
    data = json.loads((site.out / "fleet.json").read_text())
    rows = {r["id"]: r for r in data["actuators"]}
    past, soon, cal = rows["EMA-PAST"], rows["EMA-SOON"], rows["EMA-CAL"]
    assert past["inspect_now"] and past["inspect_rule"] == "act now"
    assert past["inspect_indicator"] == "short_circuit_a" and past["inspect_by"] == 600.0
    assert soon["inspect_indicator"] == "friction" and soon["inspect_reason"]
    assert (cal["inspect_rule"], cal["inspect_by"], cal["inspect_now"]) == ("healthy", 900.0, False)
    assert rows["EMA-NEW"]["inspect_rule"] == "too few inspections"
    assert all(r["inspect_target"] == 0.01 for r in rows.values())
    # the script sorts the column by how far each is from due: the due ones first
    keys = sorted(rows.values(), key=lambda r: r["sort"]["inspect"])
    assert [r["inspect_now"] for r in keys] == sorted((r["inspect_now"] for r in keys),
                                                      reverse=True)
    assert {r["id"] for r in keys[-2:]} == {"EMA-CAL", "EMA-NEW"}   # a default interval ahead
    assert keys[-1]["inspect_left"] == keys[-2]["inspect_left"] == 300.0
    assert sorted(r["sort"]["inspect"] for r in keys) == [1, 2, 3, 4, 5]  # places, as shown
    html = site.index.read_text(encoding="utf-8")
    assert '<button type="button" data-key="inspect">Inspect by</button>' in html
    assert '<option value="inspect">Inspect by</option>' in html
    assert html.count('class="c-inspect"') == 5 + 1           # each row and the heading
    due = re.findall(r'<td class="c-inspect"[^>]*><div><strong class="due" title="([^"]*)">'
                     r'act now</strong><small>([^<]*)</small>', html)
    assert ("short_circuit_a" in {ind for _, ind in due}) and all(t for t, _ in due)
    assert re.search(r'<td class="c-inspect"[^>]*><div><span title="[^"]*">900 h</span>'
                     r'<small>in 300 h \u00b7 default interval</small>', html)
    assert ".due { color: var(--red); }" in (site.out / "assets" / "fleet.css").read_text()
    page = site.pages["EMA-CAL"].read_text(encoding="utf-8")
    assert "<dt>Inspect by</dt>" in page and "every indicator at its healthy level" in page


def test_a_demagnetizing_unit_is_trended_and_shown_on_the_site(tmp_path, capsys):
    """The flux lost, read at each inspection (a calibrated unit's flux drift), is an
    indicator like the components of k: its row on the unit's page, its level and
    remaining life in the index, the next inspection planned before its crossing."""
    db = tmp_path / "h.sqlite"
    t = np.arange(6) * 150.0
    loss = 0.2 * t / 1500.0 + np.array([0.002, -0.001, 0.001, -0.002, 0.0, 0.001])
    with HealthHistory(db) as h:
        h.register("EMA-DM")
        for ti, x in zip(t, loss):     # the readings as record_inspection stores them
            h.add("EMA-DM", float(ti), _k(), readings={"demagnetization": float(x)},
                  diagnosis=diagnose(_k(), fault_model="paper").to_dict())
        from emaphm.prognosis.inspection import InspectionPolicy

        s = assess(h.data("EMA-DM"), seed=0, policy=InspectionPolicy(risk=0.01))
    assert s.worst == "demagnetization" and s.level == pytest.approx(loss[-1])
    assert s.predicted and 750 * 0.8 < s.rul_median < 750 * 1.2      # 0.2 at 1500 h
    assert s.plan.at < 1500.0
    out = tmp_path / "site"
    assert main(["fleet", "report", "--db", str(db), "--out", str(out), "--workers", "0",
                 "--quiet"]) == 0
    page = next(out.rglob(f"{page_stem('EMA-DM')}.html")).read_text(encoding="utf-8")
    assert "demagnetization (flux lost)" in page
