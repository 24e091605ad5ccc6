"""The fleet's schedule (``emaphm fleet schedule``: CSV and iCalendar) and the site's
planning options (``emaphm fleet report``): full-precision numbers in the schedule, a site folder that is someone else's, the site
planned with the schedule's options, dates past 9999, deadlines rounded down, the index
sorted by the inspect-by time it shows, the console summary, stable calendar UIDs and
site URLs, and fleets timed in two units.
"""

from __future__ import annotations

import csv
import datetime as dt
import json
import math
import re

import numpy as np
import pytest

from emaphm.cli import main
from emaphm.fleet.markup import floor_deadline, fmt_deadline, page_stem, plain_number
from emaphm.prognosis.history import HealthHistory

import test_fleet
from test_fleet import _add_series, _k, _one_line_error, _unfold
from test_fleet_browser import driver  # noqa: F401  (its Chromium fixture, for one test)

small_site = test_fleet.small_site          # the fixture: a small fleet and its site


def _fleet(path, series, units=None):
    """A history of ``series`` (id -> (times, ks)); ``units``: id -> time unit."""
    with HealthHistory(path) as h:
        for aid, (times, ks) in series.items():
            h.register(aid, time_unit=(units or {}).get(aid, "h"))
            _add_series(h, aid, times, ks)
    return path


def _csv(path):
    return list(csv.DictReader(path.open(encoding="utf-8")))


# ----------------------------------------------------------------------------- 3: precision
def test_plain_number_keeps_every_digit_and_never_writes_an_exponent():
    for x, text in ((3456788.8, "3456788.8"), (2469134.5, "2469134.5"), (300.0, "300"),
                    (1e16, "10000000000000000"), (1e-5, "0.00001"), (0.0, "0"),
                    (-0.0, "0"), (299.99999999999994, "299.99999999999994")):
        assert plain_number(x) == text and float(text) == x


def test_the_schedule_writes_its_times_in_full_not_to_six_digits(tmp_path, capsys):
    db = _fleet(tmp_path / "big.sqlite", {"CYC-BIG": ([1234567.25, 2469134.5], [_k(), _k()])},
                units={"CYC-BIG": "cycles"})
    opts = ["--max-interval", "1000000", "--default-interval", "987654.3", "--min-interval",
            "1000"]
    out = tmp_path / "big.csv"
    assert main(["fleet", "schedule", "--db", str(db), "--out", str(out), *opts, "--json"]) == 0
    row = json.loads(capsys.readouterr().out)["rows"][0]
    assert row["inspect_by"] == 2469134.5 + 987654.3 and row["last_inspection"] == 2469134.5
    text = out.read_text(encoding="utf-8")
    assert "e+" not in text
    (cell,) = _csv(out)
    assert float(cell["inspect_by"]) == row["inspect_by"] and cell["inspect_by"] == "3456788.8"
    assert cell["last_inspection"] == "2469134.5" and cell["target_risk"] == "0.01"
    ics = tmp_path / "big.ics"
    assert main(["fleet", "schedule", "--db", str(db), "--out", str(ics), *opts, "--start",
                 "2026-12-01", "--per-day", "100000"]) == 0
    lines = _unfold(ics.read_bytes().decode("utf-8"))
    desc = next(line for line in lines if line.startswith("DESCRIPTION:"))
    assert "inspect by 3456788 cycles" in desc and "last inspection 2469134.5 cycles" in desc
    assert "e+" not in desc
    assert "by 3456788 cycles" in capsys.readouterr().out      # rounded down, not 3456789


# ----------------------------------------------------------------------------- 4: --out folder
def test_fleet_report_refuses_a_folder_that_holds_another_index(small_site, tmp_path, capsys):
    _, db = small_site
    mine = tmp_path / "o2"
    mine.mkdir()
    (mine / "index.html").write_text("<html>mine</html>\n")
    err = _one_line_error(capsys, ["fleet", "report", "--db", str(db), "--out", str(mine),
                                   "--quiet"], f"--out {mine} holds index.html",
                          "not of an emaphm fleet site", "give a new folder, one without them",
                          "earlier emaphm fleet report")
    assert err.startswith("emaphm fleet: error: ")
    assert (mine / "index.html").read_text() == "<html>mine</html>\n"
    assert sorted(p.name for p in mine.iterdir()) == ["index.html"]
    from emaphm.fleet.site import build_site

    with pytest.raises(ValueError, match="not of an emaphm fleet site"):
        build_site(db, mine, workers=0)
    assert sorted(p.name for p in mine.iterdir()) == ["index.html"]
    # a fresh clone of a pages branch: what the site does not write is left alone
    clone = tmp_path / "pages"
    (clone / ".git").mkdir(parents=True)
    (clone / "CNAME").write_text("fleet.example\n")
    build_site(db, clone, workers=0)
    assert (clone / "CNAME").read_text() == "fleet.example\n" and (clone / "index.html").is_file()


def test_fleet_report_builds_into_an_empty_folder_and_updates_its_own_site(small_site,
                                                                          tmp_path, capsys):
    _, db = small_site
    out = tmp_path / "empty"
    out.mkdir()
    argv = ["fleet", "report", "--db", str(db), "--out", str(out), "--workers", "0", "--json",
            "--quiet"]
    assert main(argv) == 0 and json.loads(capsys.readouterr().out)["drawn"] == 5
    assert (out / "actuators" / ".figures.json").is_file()
    assert main(argv) == 0                          # our own site: updated, nothing to make
    assert json.loads(capsys.readouterr().out)["drawn"] == 0
    text = ["fleet", "report", "--db", str(db), "--out", str(out), "--workers", "0"]
    assert main(text) == 0                          # said as it is: nothing was written
    assert capsys.readouterr().out.startswith(f"up to date, nothing written: {out}")
    # a site written by an older build: recognised by its index key alone
    (out / "actuators" / ".figures.json").unlink()
    assert main(argv) == 0 and json.loads(capsys.readouterr().out)["drawn"] == 5


def test_a_new_site_folder_is_marked_before_its_first_page_is_written(small_site, tmp_path,
                                                                      monkeypatch):
    """An interrupted first build leaves a folder the next build takes up again."""
    from emaphm.fleet import site as fleet_site

    _, db = small_site

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(fleet_site, "_make", interrupted)
    with pytest.raises(KeyboardInterrupt):
        fleet_site.build_site(db, tmp_path / "s", workers=0)
    monkeypatch.undo()
    assert fleet_site.build_site(db, tmp_path / "s", workers=0).drawn == 5


# ----------------------------------------------------------------------------- 5: planning options
def test_fleet_report_plans_with_the_schedules_options_and_says_the_risk(small_site, tmp_path,
                                                                         capsys):
    _, db = small_site
    out = tmp_path / "site"
    assert main(["fleet", "report", "--db", str(db), "--out", str(out), "--workers", "0",
                 "--risk", "0.05", "--max-interval", "500", "--quiet", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["risk"] == 0.05
    assert main(["fleet", "schedule", "--db", str(db), "--out", str(tmp_path / "plan.csv"),
                 "--risk", "0.05", "--max-interval", "500", "--site", str(out), "--json"]) == 0
    planned = {r["actuator"]: r for r in json.loads(capsys.readouterr().out)["rows"]}
    site = json.loads((out / "fleet.json").read_text())
    assert site["inspection_policy"] == {"risk": 0.05, "max_interval": 500.0,
                                         "min_interval": None, "default_interval": None}
    for row in site["actuators"]:                    # the page a row links to shows its time
        p = planned[row["id"]]
        assert (row["inspect_by"], row["inspect_target"]) == (p["inspect_by"], 0.05), row["id"]
        page = (out / row["page"]).read_text(encoding="utf-8")
        assert "planned at risk 0.05" in page
        if not p["due_now"]:
            assert f">{fmt_deadline(p['inspect_by'], 'h')}</span>" in page
    cal = next(r for r in site["actuators"] if r["id"] == "EMA-CAL")
    assert cal["inspect_by"] == 600.0 + 300.0 and cal["inspect_rule"] == "healthy"
    index = (out / "index.html").read_text(encoding="utf-8")
    assert 'inspections planned at risk <b id="risk">0.05</b>' in index
    assert "maximum 500 h" in index


def test_fleet_report_refuses_bad_planning_options_as_fleet_schedule_does(small_site, tmp_path,
                                                                          capsys):
    _, db = small_site
    base = ["fleet", "report", "--db", str(db), "--out", str(tmp_path / "site")]
    _one_line_error(capsys, [*base, "--min-interval", "900"], "must be below the maximum",
                    "--min-interval")
    _one_line_error(capsys, [*base, "--min-interval", "700", "--max-interval", "600"],
                    "--min-interval 700 must be below --max-interval 600")
    for argv, needle in ((["--risk", "1.5"], "risk must be a probability in (0, 1)"),
                         (["--risk", "0.00001"], "risk"),
                         (["--default-interval", "0"], "interval must be a finite number > 0")):
        try:
            rc = main([*base, *argv])
        except SystemExit as exc:
            rc = exc.code
        err = capsys.readouterr().err
        assert rc == 2 and err.count("\n") == 1 and needle in err, err
    assert not (tmp_path / "site").exists()


def test_a_change_of_planning_options_makes_the_pages_again_and_nothing_else_does(
        small_site, tmp_path, monkeypatch):
    from emaphm.fleet import status
    from emaphm.fleet.site import build_site
    from emaphm.prognosis.inspection import InspectionPolicy

    _, db = small_site
    out = tmp_path / "site"
    assert build_site(db, out, workers=0).drawn == 5
    same = build_site(db, out, workers=0, policy=InspectionPolicy(risk=0.01))
    assert (same.drawn, same.written) == (0, 0)            # the default, said or not
    wider = build_site(db, out, workers=0, policy=InspectionPolicy(risk=0.01,
                                                                   default_interval=200))
    assert wider.drawn == 5
    rows = {r["id"]: r for r in wider.rows}
    assert rows["EMA-CAL"]["inspect_by"] == 600.0 + 200.0
    assert rows["EMA-NEW"]["inspect_by"] == 0.0 + 200.0
    riskier = build_site(db, out, workers=0, policy=InspectionPolicy(risk=0.05))
    assert riskier.drawn == 5 and {r["inspect_target"] for r in riskier.rows} == {0.05}
    assert "planned at risk 0.05" in riskier.pages["EMA-SOON"].read_text(encoding="utf-8")

    def refuse(*args, **kwargs):
        raise AssertionError("an unchanged actuator was assessed again")

    monkeypatch.setattr(status, "assess", refuse)
    again = build_site(db, out, workers=0, policy=InspectionPolicy(risk=0.05))
    assert (again.drawn, again.written) == (0, 0) and again.rows == riskier.rows
    with pytest.raises(ValueError, match="InspectionPolicy"):
        build_site(db, out, workers=0, policy={"risk": 0.05})


# ----------------------------------------------------------------------------- 6: past 9999
def test_dates_past_9999_are_refused_in_one_line_and_nothing_is_written(small_site, tmp_path,
                                                                        capsys):
    _, db = small_site
    base = ["fleet", "schedule", "--db", str(db)]
    for out, start, per_day in (("p.csv", "2026-12-01", "0.0001"),
                                ("p.ics", "9999-12-01", "0.001")):
        err = _one_line_error(capsys, [*base, "--out", str(tmp_path / out), "--start", start,
                                       "--per-day", per_day],
                              f"days after {start}, past 9999-12-31", "--per-day", "--start")
        assert "the next inspection of " in err and "after its last, would fall" in err
    assert not list(tmp_path.iterdir())


def test_an_event_on_the_last_date_there_is_is_refused_before_the_file_is_written(tmp_path):
    from emaphm.fleet.schedule import Calendar, DateRangeError, ScheduleRow, write_ics

    cal = Calendar(start=dt.date(9999, 12, 30), per_day=8.0)
    assert cal.date_of(108.0, 100.0) == dt.date(9999, 12, 31)
    with pytest.raises(DateRangeError, match=r"2 days after 9999-12-30, past 9999-12-31"):
        cal.date_of(116.0, 100.0)
    # an hour a day of 1e-300: an infinite count of days is said as what it is, not raised
    with pytest.raises(DateRangeError, match=r"^more than 2,921,939 days after 2000-01-01, past 9999-12-31"):
        Calendar(start=dt.date(2000, 1, 1), per_day=1e-300).date_of(1e10, 0.0)
    row = ScheduleRow(actuator="EMA-1", description="", inspect_by=108.0, time_unit="h",
                      date=dt.date.max, due_now=False, rule="healthy", indicator=None,
                      risk=None, target_risk=0.01, reason="r", last_inspection=100.0,
                      inspections=3, link="x.html")
    with pytest.raises(ValueError, match="EMA-1 falls on 9999-12-31"):
        write_ics([row], tmp_path / "p.ics")
    assert not list(tmp_path.iterdir())


# ----------------------------------------------------------------------------- 7: rounded down
def test_deadlines_are_shown_rounded_down_float_noise_aside():
    for x, text in ((1879.7, "1879 h"), (745.8, "745 h"), (1247.8, "1247 h"), (300.0, "300 h"),
                    (299.99999999999994, "300 h"), (300.00000000000006, "300 h"),
                    (7.46, "7.4 h"), (9.99, "9.9 h"), (0.0, "0 h"), (3456788.8, "3456788 h"),
                    (1e16, "10000000000000000 h")):
        assert fmt_deadline(x, "h") == text, x
        assert floor_deadline(x)[0] <= x or math.isclose(floor_deadline(x)[0], x)
    assert fmt_deadline(None, "h") == "\u2013" and fmt_deadline(math.inf, "h") == "\u221e"


def test_the_site_the_calendar_and_the_console_show_a_deadline_rounded_down(tmp_path, capsys):
    from emaphm.fleet.site import build_site

    db = _fleet(tmp_path / "h.sqlite", {"EMA-1": ([445.8], [_k()])})     # due at 745.8 h
    site = build_site(db, tmp_path / "site", workers=0)
    assert site.rows[0]["inspect_by"] == pytest.approx(745.8)
    for text in (site.index.read_text(encoding="utf-8"),
                 site.pages["EMA-1"].read_text(encoding="utf-8")):
        assert ">745 h</span>" in text and "746 h" not in text
    ics = tmp_path / "p.ics"
    assert main(["fleet", "schedule", "--db", str(db), "--out", str(ics), "--start",
                 "2026-12-01", "--per-day", "8"]) == 0
    assert "by 745 h (2027-01-07)" in capsys.readouterr().out
    lines = _unfold(ics.read_bytes().decode("utf-8"))
    assert any("inspect by 745 h" in line for line in lines)


# ----------------------------------------------------------------------------- 8: sort by it
def _unit_fleet(tmp_path):
    """Times chosen so that the order of the inspect-by times is not that of the intervals,
    with a float-noise tie and a fleet in two units."""
    series = {
        "A-LATE": ([1000.0], [_k()]),                  # 1300 h, 300 h ahead
        "B-EARLY": ([100.0, 150.0], [_k(), _k()]),      # 450 h, 300 h ahead
        "Z-EXACT": ([0.0], [_k()]),                     # 300 h
        "M-NOISE": ([3e-14], [_k()]),                   # 300.00000000000006 h: shown 300 h
        "C-CYC": ([10.0], [_k()]),                      # 310 cycles: after every hour
        "P-PAST": (np.linspace(0.0, 600.0, 5), [_k(friction=0.2 + 0.0006 * x)
                                                 for x in np.linspace(0.0, 600.0, 5)]),
    }
    return _fleet(tmp_path / "u.sqlite", series, units={"C-CYC": "cycles"})


def test_the_inspect_by_column_sorts_by_the_time_left_per_unit_ties_by_id(tmp_path):
    from emaphm.fleet.site import build_site

    site = build_site(_unit_fleet(tmp_path), tmp_path / "site", workers=0)
    rows = sorted(site.rows, key=lambda r: r["sort"]["inspect"])
    # due first; then the time left (300 h each, float noise too: ties by id); cycles last
    assert [r["id"] for r in rows] == ["P-PAST", "A-LATE", "B-EARLY", "M-NOISE", "Z-EXACT",
                                       "C-CYC"]
    assert sorted(r["sort"]["inspect"] for r in site.rows) == list(range(1, 7))
    data = json.loads(re.search(r'<script type="application/json" id="fleet-data">(.*?)'
                                r'</script>', site.index.read_text(encoding="utf-8"),
                                re.S).group(1))
    assert {r["id"]: r["sort"]["inspect"] for r in data["actuators"]} == \
        {r["id"]: r["sort"]["inspect"] for r in site.rows}


def test_the_inspect_by_column_is_the_schedules_order_never_inspected_first(tmp_path):
    """Never inspected first of all (it sorted by id among the due ones), then past due,
    then the time left (a default interval each: by id), as fleet schedule orders the same
    history."""
    from emaphm.fleet.schedule import assess_fleet
    from emaphm.fleet.site import build_site
    from emaphm.fleet.status import inspect_key

    db = _fleet(tmp_path / "o.sqlite", {
        "A-PAST": (np.linspace(0.0, 600.0, 5), [_k(friction=0.2 + 0.0006 * x)
                                                 for x in np.linspace(0.0, 600.0, 5)]),
        "B-LATE": ([0.7], [_k()]), "C-SOON": ([0.2], [_k()]), "Z-NEW": ([], [])})
    site = build_site(db, tmp_path / "site", workers=0)
    shown = [r["id"] for r in sorted(site.rows, key=lambda r: r["sort"]["inspect"])]
    assert shown == ["Z-NEW", "A-PAST", "B-LATE", "C-SOON"]
    assert shown == [s.id for s in sorted(assess_fleet(db), key=inspect_key)]


def test_the_browser_sorts_the_inspect_by_column_as_the_schedule_does(tmp_path, driver):
    """As test_fleet_browser.py drives it (its driver: skips without Chromium, fails instead
    where EMAPHM_REQUIRE_BROWSER is set)."""
    from test_fleet_browser import _open, _visible_ids

    from emaphm.fleet.site import build_site

    site = build_site(_unit_fleet(tmp_path), tmp_path / "site", workers=0)
    _open(driver, site.index)
    driver.find_element("css selector", "thead button[data-key=inspect]").click()
    assert _visible_ids(driver) == ["P-PAST", "A-LATE", "B-EARLY", "M-NOISE", "Z-EXACT", "C-CYC"]
    shown = driver.execute_script(
        "return Array.from(document.querySelectorAll('#fleet tbody td.c-inspect span'))"
        ".map(s => s.textContent + ' ' + s.nextSibling.textContent)")
    assert shown == ["1300 h in 300 h \u00b7 default interval",
                     "450 h in 300 h \u00b7 default interval",
                     "300 h in 300 h \u00b7 default interval",
                     "300 h in 300 h \u00b7 default interval",
                     "310 cycles in 300 cycles \u00b7 default interval"]


# ----------------------------------------------------------------------------- 9: the summary
def test_the_schedule_summary_says_how_many_more_it_does_not_list(small_site, tmp_path, capsys):
    _, db = small_site
    out = tmp_path / "plan.csv"
    assert main(["fleet", "schedule", "--db", str(db), "--out", str(out)]) == 0
    lines = capsys.readouterr().out.splitlines()
    due = int(re.search(r"(\d+) due now", lines[0]).group(1))
    listed = lines[1:4]
    assert len(listed) == 3 and lines[4].startswith("  and 2 more")
    more_due = due - sum(": now, " in line for line in listed)
    assert (f"({more_due} of them due now)" in lines[4]) == (more_due > 0)
    assert lines[4].endswith(f": see {out}") and len(lines) == 5


# ----------------------------------------------------------------------------- 11: calendar
def _events(path):
    lines = _unfold(path.read_bytes().decode("utf-8"))
    events, cur = {}, None
    for line in lines:
        if line == "BEGIN:VEVENT":
            cur = {}
        elif line == "END:VEVENT":
            events[cur["DESCRIPTION"].split(":", 1)[0].split(" (")[0]] = cur
            cur = None
        elif cur is not None:
            key, _, value = line.partition(":")
            cur[key.split(";")[0]] = value
    return events


def test_an_updated_plan_keeps_each_events_uid_and_tells_the_calendar_it_is_newer(tmp_path):
    from emaphm.fleet.schedule import Calendar, schedule, write_ics

    t = np.linspace(0.0, 600.0, 7)
    db = _fleet(tmp_path / "h.sqlite", {
        "EMA-1": (t, [_k(friction=0.02 + 0.0004 * x + 0.003 * math.sin(x)) for x in t]),
        "EMA-2": (t[:2], [_k(), _k()])})
    cal = Calendar(start=dt.date(2026, 12, 1), per_day=8.0)
    from emaphm.prognosis.inspection import InspectionPolicy

    old = write_ics(schedule(db, calendar=cal), tmp_path / "old.ics", source=str(db),
                    now=dt.datetime(2026, 12, 1, 8, 0, tzinfo=dt.timezone.utc))
    new = write_ics(schedule(db, calendar=cal, policy=InspectionPolicy(risk=0.05,
                                                                      default_interval=200)),
                    tmp_path / "new.ics", source=str(db),
                    now=dt.datetime(2026, 12, 2, 8, 0, tzinfo=dt.timezone.utc))
    a, b = _events(old), _events(new)
    assert set(a) == set(b) == {"EMA-1", "EMA-2"}
    assert a["EMA-2"]["DTSTART"] != b["EMA-2"]["DTSTART"]          # the event moved
    for aid in a:
        assert a[aid]["UID"] == b[aid]["UID"]
        assert a[aid]["UID"].startswith(page_stem(aid, digits=64)) and \
            a[aid]["UID"].endswith("@emaphm")
        assert int(b[aid]["SEQUENCE"]) - int(a[aid]["SEQUENCE"]) == 86400
        assert (a[aid]["DTSTAMP"], b[aid]["DTSTAMP"]) == ("20261201T080000Z", "20261202T080000Z")
    other = write_ics(schedule(db, calendar=cal), tmp_path / "other.ics", source="/else.sqlite")
    assert _events(other)["EMA-1"]["UID"] != a["EMA-1"]["UID"]       # another history's


def test_a_site_url_with_a_space_and_a_query_makes_working_links(tmp_path, capsys):
    from emaphm.fleet.schedule import page_links

    stem = page_stem("EMA-1")
    assert page_links(["EMA-1"], "https://ops.example/fleet site?x=1&y=2") == {
        "EMA-1": f"https://ops.example/fleet%20site/actuators/{stem}.html?x=1&y=2"}
    assert page_links(["EMA-1"], "https://ops.example/a%20b/") == {
        "EMA-1": f"https://ops.example/a%20b/actuators/{stem}.html"}
    assert page_links(["EMA-1"], "https://ops.example") == {
        "EMA-1": f"https://ops.example/actuators/{stem}.html"}
    assert page_links(["EMA-1"], "my site") == {"EMA-1": f"my site/actuators/{stem}.html"}
    db = _fleet(tmp_path / "h.sqlite", {"EMA-1": ([0.0], [_k()])})
    ics = tmp_path / "p.ics"
    assert main(["fleet", "schedule", "--db", str(db), "--out", str(ics), "--start",
                 "2026-12-01", "--per-day", "8", "--site",
                 "https://ops.example/fleet site?x=1&y=2"]) == 0
    url = f"https://ops.example/fleet%20site/actuators/{stem}.html?x=1&y=2"
    assert _events(ics)["EMA-1"]["URL"] == url


# ----------------------------------------------------------------------------- 14: two units
def test_dates_for_a_fleet_in_two_units_are_refused_and_one_unit_is_planned(tmp_path, capsys):
    db = _unit_fleet(tmp_path)
    base = ["fleet", "schedule", "--db", str(db), "--start", "2026-12-01", "--per-day", "8"]
    _one_line_error(capsys, [*base, "--out", str(tmp_path / "p.ics")],
                    "timed in 2 units (5 in h and 1 in cycles)", "--actuator ID",
                    "leave out --start and --per-day")
    assert not (tmp_path / "p.ics").exists()
    assert main([*base, "--out", str(tmp_path / "c.ics"), "--actuator", "C-CYC"]) == 0
    assert main([*base, "--out", str(tmp_path / "h.csv"), "--actuator", "A-LATE",
                 "--actuator", "Z-EXACT"]) == 0
    from emaphm.fleet.schedule import Calendar, schedule

    with pytest.raises(ValueError, match="5 in h and 1 in cycles"):
        schedule(db, calendar=Calendar(start=dt.date(2026, 12, 1), per_day=8.0))


def test_without_dates_the_schedule_is_due_now_first_then_grouped_by_unit(tmp_path, capsys):
    out = tmp_path / "p.csv"
    assert main(["fleet", "schedule", "--db", str(_unit_fleet(tmp_path)), "--out",
                 str(out)]) == 0
    table = _csv(out)
    assert [r["actuator"] for r in table] == ["P-PAST", "A-LATE", "B-EARLY", "M-NOISE",
                                              "Z-EXACT", "C-CYC"]
    assert [r["time_unit"] for r in table] == ["h"] * 5 + ["cycles"]
    assert table[0]["due_now"] == "yes" and {r["due_now"] for r in table[1:]} == {"no"}
