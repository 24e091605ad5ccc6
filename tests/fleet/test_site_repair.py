"""``emaphm fleet report`` over a damaged site, into links, and on a full disk (issue 37,
bad item 8 and partial items): a rebuild repairs what it finds damaged, never writes
through a link out of its folder, and a build that fails leaves the site as it was."""

from __future__ import annotations

import errno
import hashlib
import os
import re
from pathlib import Path

import numpy as np
import pytest

from emaphm.cli import main
from emaphm.prognosis.history import HealthHistory

from test_fleet import _add_series, _k, _one_line_error


@pytest.fixture()
def fleet(tmp_path):
    """A history of three actuators and its site."""
    db = tmp_path / "fleet.sqlite"
    t = np.linspace(0.0, 400.0, 4)
    with HealthHistory(db) as h:
        for n, slope in enumerate((0.0005, 0.0008, 0.0001)):
            h.register(f"EMA-{n}")
            _add_series(h, f"EMA-{n}", t, [_k(friction=0.05 + slope * x) for x in t])
    site = tmp_path / "site"
    assert main(["fleet", "report", "--db", str(db), "--out", str(site), "--workers", "0",
                 "--quiet"]) == 0
    return db, site


def _report(db: Path, site: Path, *extra: str) -> int:
    return main(["fleet", "report", "--db", str(db), "--out", str(site), "--workers", "0",
                 "--quiet", *extra])


def _files(site: Path) -> dict[str, str]:
    """Every path under ``site``: a file's SHA-256 (the index without its build time), a
    link's target."""
    out = {}
    for p in sorted(site.rglob("*")):
        rel = p.relative_to(site).as_posix()
        if p.is_symlink():
            out[rel] = f"link to {os.readlink(p)}"
        elif p.is_file():
            data = p.read_bytes()
            if p.name == "index.html":
                data = re.sub(rb"built [0-9: -]+UTC", b"", data)
            if p.name == ".index-key":
                data = re.sub(rb'"index.html": "[0-9a-f]+"', b"", data)
            out[rel] = hashlib.sha256(data).hexdigest()
    return out


@pytest.mark.parametrize("redraw", [True, False])
def test_an_emptied_index_and_fleet_json_are_written_again(fleet, capsys, redraw):
    """It printed "wrote site/index.html" and left both at 0 bytes (with --redraw)."""
    db, site = fleet
    whole = _files(site)
    for name in ("index.html", "fleet.json"):
        (site / name).write_bytes(b"")
    capsys.readouterr()
    assert _report(db, site, *(["--redraw"] if redraw else [])) == 0
    assert _files(site) == whole
    assert (site / "index.html").stat().st_size > 1000


def test_a_fleet_json_replaced_by_a_link_is_replaced_and_its_target_untouched(fleet, tmp_path):
    db, site = fleet
    whole = _files(site)
    elsewhere = tmp_path / "elsewhere.json"
    elsewhere.write_bytes((site / "fleet.json").read_bytes())
    (site / "fleet.json").unlink()
    (site / "fleet.json").symlink_to(elsewhere)
    before = elsewhere.read_bytes()
    assert _report(db, site) == 0
    assert not (site / "fleet.json").is_symlink() and _files(site) == whole
    assert elsewhere.read_bytes() == before


def test_a_page_replaced_by_a_link_is_drawn_again(fleet, tmp_path):
    db, site = fleet
    whole = _files(site)
    page = next((site / "actuators").glob("*.html"))
    copy = tmp_path / "copy.html"
    copy.write_bytes(page.read_bytes())
    page.unlink()
    page.symlink_to(copy)
    assert _report(db, site) == 0
    assert not page.is_symlink() and _files(site) == whole


def test_a_linked_assets_folder_is_not_written_through(fleet, tmp_path):
    """fleet.css and fleet.js were written through a symlinked assets/ into a folder
    outside --out."""
    db, site = fleet
    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / "mine.txt").write_text("not the site's")
    for p in (site / "assets").iterdir():
        p.unlink()
    (site / "assets").rmdir()
    (site / "assets").symlink_to(outside, target_is_directory=True)
    assert _report(db, site) == 0
    assert sorted(p.name for p in outside.iterdir()) == ["mine.txt"]
    assert (site / "assets").is_dir() and not (site / "assets").is_symlink()
    assert sorted(p.name for p in (site / "assets").iterdir()) == ["fleet.css", "fleet.js"]


def test_a_linked_actuators_folder_is_refused(fleet, tmp_path, capsys):
    db, site = fleet
    outside = tmp_path / "pages"
    (site / "actuators").rename(outside)
    (site / "actuators").symlink_to(outside, target_is_directory=True)
    before = {p.name: p.read_bytes() for p in outside.iterdir()}
    _one_line_error(capsys, ["fleet", "report", "--db", str(db), "--out", str(site),
                             "--workers", "0"], "its actuators/ is a link to",
                    "a site writes only inside its folder")
    assert {p.name: p.read_bytes() for p in outside.iterdir()} == before


def test_a_full_disk_leaves_the_old_site_whole(fleet, capsys, monkeypatch):
    """No space for the third file of a rebuild: one line, every file as it was, no
    temporary file left (it left the site half new, half old)."""
    from emaphm.fleet import site as site_module

    db, site = fleet
    with HealthHistory(db) as h:                 # every page and the index change
        for n in range(3):
            _add_series(h, f"EMA-{n}", [500.0], [_k(friction=0.5)])
    whole = _files(site)
    real = site_module.StagedWrites.write
    count = []

    def full(self, path, payload):
        count.append(path)
        if len(count) == 3:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))
        return real(self, path, payload)

    monkeypatch.setattr(site_module.StagedWrites, "write", full)
    capsys.readouterr()
    err = _one_line_error(capsys, ["fleet", "report", "--db", str(db), "--out", str(site),
                                   "--workers", "0", "--quiet"], "No space left on device",
                          f"the site in {site} was left as it was")
    assert "Traceback" not in err
    assert _files(site) == whole
    monkeypatch.undo()
    assert _report(db, site) == 0
    assert _files(site) != whole and not list(site.rglob("*.tmp"))
