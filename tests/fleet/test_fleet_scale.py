"""A fleet site that grows: what a rebuild makes again and what it leaves alone, the
pages' SVG figures against the reference matplotlib plots, the pages made
by worker processes and on a Dask cluster, and the index of a large fleet.

The index of 10,000 actuators in a real browser is in ``test_fleet_browser.py``.
"""

from __future__ import annotations

import json
import re
import socket
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from emaphm.cli import main
from emaphm.diagnosis import diagnose
from emaphm.fleet.markup import page_stem
from emaphm.prognosis.history import HealthHistory


def _k(friction=0.0, short_a=0.0, ecc=0.0, gain=0.5):
    return [friction, 0.0, short_a, 0.0, 0.0, ecc, 0.5, gain]


def _add(h, aid, times, ks):
    for t, k in zip(times, ks):
        h.add(aid, float(t), k, diagnosis=diagnose(k, fault_model="paper").to_dict(),
              algorithm="pso", seed=0, fingerprint=f"{aid}-{t}")


T = np.linspace(0.0, 600.0, 5)
SERIES = {
    "EMA-PAST": [_k(friction=0.2 + 0.0006 * x) for x in T],
    "EMA-SOON": [_k(short_a=0.02 + 0.0004 * x) for x in T],
    "EMA-ECC": [_k(ecc=0.0005 * x) for x in T],
    "EMA-OK": [_k(friction=0.01) for _ in T],
}


@pytest.fixture()
def fleet(tmp_path):
    db = tmp_path / "fleet.sqlite"
    with HealthHistory(db) as h:
        for aid, ks in SERIES.items():
            h.register(aid, description=f"{aid.lower()} unit")
            _add(h, aid, T, ks)
        h.register("EMA-NEW")
        _add(h, "EMA-NEW", T[:1], [_k(short_a=0.05)])
    return db


def _mtimes(folder: Path) -> dict:
    return {p.relative_to(folder).as_posix(): p.stat().st_mtime_ns
            for p in folder.rglob("*") if p.is_file()}


# ----------------------------------------------------------------------------- rebuilds
def test_a_rebuild_with_nothing_changed_assesses_draws_and_writes_nothing(fleet, tmp_path,
                                                                          monkeypatch):
    from emaphm.fleet import status
    from emaphm.fleet.site import build_site

    out = tmp_path / "site"
    first = build_site(fleet, out, workers=0)
    assert first.drawn == 5 and first.written > 10
    before = _mtimes(out)
    assert {".figures.json", ".index-key"} <= {Path(p).name for p in before}

    def refuse(*args, **kwargs):
        raise AssertionError("an unchanged actuator was assessed again")

    monkeypatch.setattr(status, "assess", refuse)
    again = build_site(fleet, out, workers=0)
    assert (again.drawn, again.written, again.statuses) == (0, 0, ())
    assert _mtimes(out) == before                    # no page, figure, index or manifest
    assert again.rows == first.rows and set(again.pages) == set(first.pages)
    assert [r["id"] for r in again.rows] == [s.id for s in first.statuses]


def test_a_rebuild_reads_only_the_changed_actuators_records_from_the_history(fleet, tmp_path,
                                                                             monkeypatch):
    from emaphm.fleet.site import build_site

    out = tmp_path / "site"
    build_site(fleet, out, workers=0)
    read = []
    real = HealthHistory.data
    monkeypatch.setattr(HealthHistory, "data", lambda h, i: read.append(i) or real(h, i))
    assert build_site(fleet, out, workers=0).drawn == 0 and read == []
    with HealthHistory(fleet) as h:
        _add(h, "EMA-SOON", [700.0], [_k(short_a=0.3)])
    assert build_site(fleet, out, workers=0).drawn == 1 and read == ["EMA-SOON"]


def test_without_the_stored_records_the_actuators_are_keyed_by_what_the_history_returns(
        fleet, tmp_path, monkeypatch):
    from emaphm.fleet import site as fleet_site

    monkeypatch.setattr(HealthHistory, "record_digests", lambda self: None)
    out = tmp_path / "site"
    assert fleet_site.build_site(fleet, out, workers=0).drawn == 5
    assert fleet_site.build_site(fleet, out, workers=0).drawn == 0
    with HealthHistory(fleet) as h:
        _add(h, "EMA-SOON", [700.0], [_k(short_a=0.3)])
    site = fleet_site.build_site(fleet, out, workers=0)
    assert site.drawn == 1 and site.statuses[0].id == "EMA-SOON"


def test_the_records_left_out_are_named_on_every_build_even_with_nothing_changed(fleet,
                                                                                tmp_path,
                                                                                capsys):
    with HealthHistory(fleet) as h:             # a record an older emaphm let through
        h._con.execute("DROP TRIGGER inspections_time_forward")
        h._con.execute("INSERT INTO inspections (actuator, time, k, k_lo, k_hi, recorded_utc) "
                       "SELECT actuator, 1e308, k, k_lo, k_hi, recorded_utc FROM inspections "
                       "WHERE actuator = 'EMA-OK' AND time = 600")
    argv = ["fleet", "report", "--db", str(fleet), "--out", str(tmp_path / "site"),
            "--workers", "0", "--json", "--quiet"]
    for drawn in (5, 0):
        assert main(argv) == 0
        captured = capsys.readouterr()
        assert json.loads(captured.out)["drawn"] == drawn
        assert captured.err.count("\n") == 1 and "left out 1 stored inspection of EMA-OK" \
            in captured.err


def test_the_order_of_the_index_is_the_order_of_attention(fleet, tmp_path):
    from emaphm.fleet.site import build_site
    from emaphm.fleet.status import order_fleet

    site = build_site(fleet, tmp_path / "site", workers=0)
    assert [r["id"] for r in site.rows] == [s.id for s in order_fleet(site.statuses)]
    assert [r["rank"] for r in site.rows] == list(range(1, 6))
    assert site.rows[0]["id"] == "EMA-PAST"


def test_a_new_inspection_makes_that_actuators_page_and_figures_again_and_no_other(fleet,
                                                                                   tmp_path):
    from emaphm.fleet.site import build_site

    out = tmp_path / "site"
    build_site(fleet, out, workers=0)
    before = _mtimes(out)
    with HealthHistory(fleet) as h:
        _add(h, "EMA-OK", [700.0], [_k(friction=0.45)])       # now near its threshold
    site = build_site(fleet, out, workers=0)
    assert site.drawn == 1 and [s.id for s in site.statuses] == ["EMA-OK"]
    after = _mtimes(out)
    changed = sorted(n for n in after if after[n] != before.get(n))
    stem = page_stem("EMA-OK")
    assert changed == sorted([f"actuators/{stem}.html", f"actuators/{stem}-history.svg",
                              f"actuators/{stem}-prognosis.svg", "actuators/.figures.json",
                              "actuators/.index-key", "fleet.json", "index.html"])
    row = next(r for r in site.rows if r["id"] == "EMA-OK")
    assert row["n_inspections"] == 6 and row["last_time"] == 700.0
    index = (out / "index.html").read_text(encoding="utf-8")
    assert "EMA-OK" in index and json.loads((out / "fleet.json").read_text())["actuators"] \
        == [dict(r) for r in site.rows]
    # a calibration recorded for another actuator makes its page again (the page shows it)
    from emaphm.params import siemens_1fk7060

    with HealthHistory(fleet) as h:
        h.calibrate("EMA-NEW", 10.0, siemens_1fk7060(), sources=["/bench/h1.parquet"])
    site = build_site(fleet, out, workers=0)
    assert site.drawn == 1 and site.statuses[0].id == "EMA-NEW"
    assert "h1.parquet" in site.pages["EMA-NEW"].read_text(encoding="utf-8")


def test_other_settings_a_missing_or_cut_file_and_redraw_make_pages_again(fleet, tmp_path):
    from emaphm.fleet.site import build_site

    out = tmp_path / "site"
    build_site(fleet, out, workers=0)
    assert build_site(fleet, out, workers=0, seed=1).drawn == 5       # the RUL draws differ
    assert build_site(fleet, out, workers=0, seed=1).drawn == 0
    assert build_site(fleet, out, workers=0, seed=1, title="Other").drawn == 5
    stem = page_stem("EMA-SOON")
    fig = out / "actuators" / f"{stem}-prognosis.svg"
    fig.write_bytes(fig.read_bytes()[:100])                            # cut short
    (out / "actuators" / f"{page_stem('EMA-ECC')}.html").unlink()
    site = build_site(fleet, out, workers=0, seed=1, title="Other")
    assert sorted(s.id for s in site.statuses) == ["EMA-ECC", "EMA-SOON"]
    assert fig.stat().st_size > 1000
    (out / "index.html").unlink()
    site = build_site(fleet, out, workers=0, seed=1, title="Other")
    assert site.drawn == 0 and site.written == 2 and (out / "index.html").is_file()
    assert build_site(fleet, out, workers=0, seed=1, title="Other", redraw=True).drawn == 5


def test_a_rebuild_with_nothing_changed_imports_neither_scipy_nor_matplotlib(fleet, tmp_path):
    from emaphm.fleet.site import build_site

    out = tmp_path / "site"
    build_site(fleet, out, workers=0)
    code = ("import sys; from emaphm.fleet.site import build_site; "
            f"s = build_site({str(fleet)!r}, {str(out)!r}, workers=0); "
            "print(s.drawn, s.written, sorted(m for m in ('scipy', 'matplotlib') "
            "if m in sys.modules))")
    out_text = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True,
                              text=True).stdout.split()
    assert out_text == ["0", "0", "[]"]
    # a cold build draws its figures without matplotlib
    code = code.replace(repr(str(out)), repr(str(tmp_path / "cold")))
    out_text = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True,
                              text=True).stdout.split()
    assert out_text[0] == "5" and out_text[2:] == ["['scipy']"]


def test_an_index_longer_than_a_page_holds_the_first_rows_and_all_the_data(fleet, tmp_path,
                                                                            monkeypatch):
    from emaphm.fleet import pages as fleet_pages, site as fleet_site

    monkeypatch.setattr(fleet_pages, "PAGE_ROWS", 2)
    site = fleet_site.build_site(fleet, tmp_path / "site", workers=0)
    html = site.index.read_text(encoding="utf-8")
    assert re.findall(r"<tr data-i=\"(\d+)\"", html) == ["0", "1"]
    assert "The first 2 of 5 actuators" in html and "2 of 5 shown" in html
    block = re.search(r'<script type="application/json" id="fleet-data">(.*?)</script>', html,
                      re.S).group(1)
    data = json.loads(block)
    assert data["page_rows"] == 2 and [r["id"] for r in data["actuators"]] == \
        [r["id"] for r in site.rows]
    for r in data["actuators"]:              # each row carries its table row, escaped
        assert r["html"].startswith(f"<tr data-i=\"{r['rank'] - 1}\"")
        assert f">{r['id']}</a>" in r["html"]


def test_worker_processes_make_the_same_site(fleet, tmp_path):
    from emaphm.fleet.site import build_site

    serial = build_site(fleet, tmp_path / "serial", workers=0)
    pool = build_site(fleet, tmp_path / "pool", workers=2)
    assert pool.workers == 2 and pool.drawn == 5 and pool.statuses == ()
    assert _same_files(tmp_path / "serial", tmp_path / "pool")
    assert serial.rows == pool.rows


def _same_files(a: Path, b: Path) -> bool:
    """The two sites hold the same files with the same bytes, but for the index's build
    time (and so the index's digest that actuators/.index-key keeps)."""
    names = sorted(p.relative_to(a).as_posix() for p in a.rglob("*") if p.is_file())
    assert names == sorted(p.relative_to(b).as_posix() for p in b.rglob("*") if p.is_file())
    for name in names:
        x, y = (a / name).read_bytes(), (b / name).read_bytes()
        if name == "index.html":
            x, y = (re.sub(rb"built [0-9: -]+UTC", b"", v) for v in (x, y))
        if name == "actuators/.index-key":
            x, y = (re.sub(rb'"index.html": "[0-9a-f]+"', b"", v) for v in (x, y))
        assert x == y, name
    return True


# ----------------------------------------------------------------------------- figures
def _reference_points(fig, label):
    """{axes title: sorted (x, y) of the reference figure's lines labelled ``label``}."""
    out = {}
    for ax in fig.axes:
        pts = [tuple(p) for line in ax.get_lines() if line.get_label() == label
               for p in np.asarray(line.get_xydata(), dtype=float)]
        if ax.get_visible():
            out[ax.get_title()] = sorted(pts)
    return out


def test_the_page_figures_draw_what_the_reference_plots_draw(fleet):
    """The pages' SVG figures are drawn from panels of data; the panels hold the points,
    thresholds, RUL bars and medians the reference matplotlib plots draw, and their titles."""
    from emaphm.fleet.figures import PageFigures
    from emaphm.fleet.status import assess
    from emaphm.prognosis.plots import plot_history, plot_prognosis

    figs = PageFigures()
    with HealthHistory(fleet, readonly=True) as h:
        data = {aid: h.data(aid) for aid in SERIES}
    drawn = {"identified": 0, "median": 0, "rul": 0}
    for aid, d in data.items():
        shown = [0, 2, 5, 6, 7]
        mine = figs.history_panels(d, components=shown)
        ref = plot_history(d, components=shown)
        assert [p.title for p in mine] == [ax.get_title() for ax in ref.axes
                                           if ax.get_visible()][:len(shown)]
        for state in ("healthy", "faulty", "unexplained"):
            want = _reference_points(ref, state)
            got = {p.title: sorted(zip(p.layers[state].x, p.layers[state].y)) for p in mine}
            assert got == {k: v for k, v in want.items() if k in got}, (aid, state)
        hollow = _reference_points(ref, "no eccentricity: phase meaningless")
        ecc = mine[3].layers["hollow"]
        assert sorted(zip(ecc.x, ecc.y)) == hollow.get("k7: eccentricity phase", [])
        thr = {ax.get_title(): [line.get_ydata()[0] for line in ax.get_lines()
                                if line.get_linestyle() == "--"] for ax in ref.axes}
        for p in mine:
            assert list(p.layers["threshold"].y) == thr[p.title]
        s = assess(d, seed=0)
        names = [s.worst] + [n for n in s.prognosis.predictions if n != s.worst][:1]
        mine = figs.prognosis_panels(s.prognosis, indicators=names)
        ref = plot_prognosis(s.prognosis, indicators=names)
        for panel, ax in zip(mine, ref.axes):
            assert panel.title == ax.get_title()
            # the cone and its median over every trend draw, as the reference's
            p = s.prognosis.predictions[panel.title.partition(":")[0]]
            cone = panel.layers["cone"]
            np.testing.assert_array_equal(np.vstack([cone.y, panel.layers["trend"].y, cone.y2]),
                                          p.band(cone.x, (0.05, 0.5, 0.95)))
            for label in ("identified", "median"):
                want = [np.asarray(x.get_xydata()) for x in ax.get_lines()
                        if x.get_label() == label]
                layer = panel.layers.get(label)
                got = (np.column_stack([layer.x, layer.y]) if layer is not None
                       else np.empty((0, 2)))
                assert (got.size == 0 and not want) or np.allclose(got, want[0])
                drawn[label] += got.size > 0
            want = [x.get_xydata() for x in ax.get_lines() if x.get_label().startswith("RUL ")]
            bar = panel.layers.get("rul")
            assert (not want and bar is None) or np.allclose(
                np.column_stack([bar.x, bar.y]), want[0])
            drawn["rul"] += bool(want)
            assert panel.layers["threshold"].y[0] == pytest.approx(
                next(x.get_ydata()[0] for x in ax.get_lines() if x.get_linestyle() == "--"))
        assert figs.prognosis_title(s.prognosis) == ref.get_suptitle()
    assert drawn["median"] >= 2 and drawn["rul"] >= 2 and drawn["identified"] == 8


def test_a_page_figure_is_a_pure_function_of_its_data_and_valid_svg(fleet):
    import xml.etree.ElementTree as ET

    from emaphm.fleet.figures import PageFigures
    from emaphm.fleet.status import assess

    with HealthHistory(fleet, readonly=True) as h:
        past, ecc, new = (h.data(a) for a in ("EMA-PAST", "EMA-ECC", "EMA-NEW"))
    figs = PageFigures()
    first = figs.history(past, components=[0, 7])
    prog = figs.prognosis(assess(past, seed=0).prognosis, indicators=["friction"])
    figs.history(ecc, components=[5, 6])                 # the same layout, other data
    figs.history(new, components=[2])
    figs.prognosis(assess(ecc, seed=0).prognosis, indicators=["eccentricity"])
    assert figs.history(past, components=[0, 7]) == first
    assert figs.prognosis(assess(past, seed=0).prognosis, indicators=["friction"]) == prog
    assert PageFigures().history(past, components=[0, 7]) == first
    assert first[1:] == (1100, 345) and prog[1:] == (1000, 380)
    for svg, w, h in (first, prog):
        root = ET.fromstring(svg)                        # well-formed XML
        assert root.tag == "{http://www.w3.org/2000/svg}svg"
        assert (root.get("width"), root.get("height")) == (str(w), str(h))
    texts = [t.text for t in ET.fromstring(first[0]).iter("{http://www.w3.org/2000/svg}text")]
    from emaphm.faults import K_LABELS

    assert f"k1: {K_LABELS[0]}" in texts and f"k8: {K_LABELS[7]}" in texts
    assert any(t.startswith("health history of EMA-PAST") for t in texts)
    with pytest.raises(ValueError, match="indices of k"):
        figs.history(past, components=[8])
    with pytest.raises(ValueError, match="no prediction for indicator 'x'"):
        figs.prognosis(assess(past, seed=0).prognosis, indicators=["x"])


# ----------------------------------------------------------------------------- the demo
def test_a_synthetic_demo_fleet_grows_to_twenty_thousand_and_its_units_do_not_change(tmp_path,
                                                                                      capsys):
    from emaphm.fleet.demo import MAX_SYNTHETIC, demo_fleet, record_demo_fleet

    big = demo_fleet(10_000, seed=0, synthetic=True)
    assert len(big) == 10_000 and big[:30] == demo_fleet(30, seed=0)
    assert big[-1].id == "EMA-10000" and len({u.id for u in big}) == 10_000
    with pytest.raises(ValueError, match="1 to 500 actuators \\(1 to 20000 synthetic\\)"):
        demo_fleet(600)
    with pytest.raises(ValueError, match="1 to 20000 synthetic"):
        demo_fleet(MAX_SYNTHETIC + 1, synthetic=True)
    with pytest.raises(ValueError, match="at most 500 actuators.*synthetic=True"):
        record_demo_fleet(tmp_path / "real.sqlite", big[:501])
    assert not (tmp_path / "real.sqlite").exists()
    rc = main(["fleet", "demo", "--db", str(tmp_path / "d.sqlite"), "--actuators", "600"])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1
    assert "--actuators must be 1 to 500, got 600 (20000 with --synthetic)" in err
    assert main(["fleet", "demo", "--db", str(tmp_path / "d.sqlite"), "--actuators", "600",
                 "--synthetic", "--quiet"]) == 0
    with HealthHistory(tmp_path / "d.sqlite", readonly=True) as h:
        acts = h.actuators()
    assert len(acts) == 600 and sum(a.n_inspections for a in acts) == \
        sum(len(u.times) for u in big[:600])


# ----------------------------------------------------------------------------- Dask
def test_fleet_report_refuses_a_bad_scheduler_in_one_line_before_any_work(fleet, tmp_path,
                                                                           capsys):
    pytest.importorskip("distributed")
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()                                   # bound, never listened: refused
    out = tmp_path / "site"
    for argv, words in (
            (["--scheduler", f"127.0.0.1:{port}"],
             f"cannot reach a Dask scheduler at tcp://127.0.0.1:{port} (Connection refused)"),
            (["--scheduler", "inproc://x"], "scheme inproc:// is not supported"),
            (["--scheduler", "tcp://10.0.0.1"], "is not HOST:PORT after tcp://"),
            (["--scheduler", f"127.0.0.1:{port}", "--workers", "2"],
             "give either --workers (local processes) or --scheduler (Dask cluster), not both")):
        rc = main(["fleet", "report", "--db", str(fleet), "--out", str(out), *argv])
        err = capsys.readouterr().err
        assert rc == 2 and err.count("\n") == 1 and "Traceback" not in err, err
        assert words in err, err
    assert not out.exists()
    from emaphm.fleet.site import build_site

    with pytest.raises(ValueError, match="executor must have a map_unordered"):
        build_site(fleet, out, executor=object())


def test_a_dask_cluster_makes_the_same_site(fleet, tmp_path, capsys):
    distributed = pytest.importorskip("distributed")
    from emaphm.campaign.executors import DaskExecutor
    from emaphm.fleet.site import build_site

    build_site(fleet, tmp_path / "serial", workers=0)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None, silence_logs=40) as cluster:
        site = build_site(fleet, tmp_path / "dask",
                          executor=DaskExecutor(cluster.scheduler_address, warm=False))
        assert (site.drawn, site.workers, site.statuses) == (5, 0, ())
        assert _same_files(tmp_path / "serial", tmp_path / "dask")
        argv = ["fleet", "report", "--db", str(fleet), "--out", str(tmp_path / "cli"),
                "--scheduler", cluster.scheduler_address, "--quiet", "--json"]
        assert main(argv) == 0
        assert json.loads(capsys.readouterr().out)["drawn"] == 5
        assert _same_files(tmp_path / "serial", tmp_path / "cli")
        assert main(argv) == 0                     # nothing changed: nothing sent, written
        rep = json.loads(capsys.readouterr().out)
        assert (rep["drawn"], rep["written"]) == (0, 0)


def test_a_figure_the_page_no_longer_has_is_removed(fleet, tmp_path):
    from emaphm.fleet.site import build_site

    out = tmp_path / "site"
    build_site(fleet, out, workers=0)
    prog = out / "actuators" / f"{page_stem('EMA-OK')}-prognosis.svg"
    assert prog.is_file()
    with HealthHistory(fleet) as h:            # three of its five inspections taken back:
        for t in T[-3:]:                        # too few for a trend
            h.remove("EMA-OK", at=float(t))
    site = build_site(fleet, out, workers=0)
    assert site.drawn == 1 and not prog.exists()
    page = site.pages["EMA-OK"].read_text(encoding="utf-8")
    assert "-prognosis.svg" not in page and "-history.svg" in page
