"""The fleet site in a real browser: headless Chromium from the operating system's packages,
driven by Selenium through Debian's chromium-driver (no browser or driver is downloaded:
both paths are given and Selenium Manager is kept offline).

On a machine without Chromium, its driver or Selenium the tests skip and say which is
missing; where ``EMAPHM_REQUIRE_BROWSER=1`` (set by ``.ci/run``) they fail instead.
"""

from __future__ import annotations

import contextlib
import io
import os
import shutil
import sys
import tempfile

import numpy as np
import pytest

from emaphm.diagnosis import diagnose
from emaphm.prognosis.history import HealthHistory

SCRIPT_ID = "<script>alert(1)</script>"
NASTY = "</script><img src=x onerror=alert(2)><script>alert(3)</script>"
CHROME_FLAGS = ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-quic",
                "--no-first-run", "--disable-background-networking",
                "--disable-component-update", "--disable-sync", "--disable-dev-shm-usage",
                "--hide-scrollbars", "--window-size=1280,900", "--force-device-scale-factor=1")


def _find(*names: str) -> str | None:
    for name in names:
        path = shutil.which(name) or (name if os.path.isabs(name) and os.access(name, os.X_OK)
                                      else None)
        if path:
            return path
    return None


def _browser() -> tuple[str, str]:
    """(chromium, chromedriver) paths, or skip (fail under EMAPHM_REQUIRE_BROWSER) naming
    what is missing and how to install it."""
    missing = []
    chromium = _find("chromium", "chromium-browser", "/usr/bin/chromium")
    driver = _find("chromedriver", "/usr/bin/chromedriver")
    if chromium is None:
        missing.append("chromium")
    if driver is None:
        missing.append("chromedriver")
    try:
        import selenium  # noqa: F401
    except ImportError:
        missing.append("selenium (pip install -e '.[test]')")
    if missing:
        why = (f"browser test needs {', '.join(missing)}: on Debian/Ubuntu "
               "apt-get install chromium chromium-driver")
        if os.environ.get("EMAPHM_REQUIRE_BROWSER"):
            pytest.fail(why + " (EMAPHM_REQUIRE_BROWSER is set: the browser test must run)")
        pytest.skip(why)
    return chromium, driver


def _k(friction=0.0, short_a=0.0, gain=0.5):
    return [friction, 0.0, short_a, 0.0, 0.0, 0.0, 0.5, gain]


#: The fleet and the order the index must show: past threshold, then by RUL median, then
#: the units without a predicted failure by how near their threshold they are.
EXPECTED_ORDER = ["EMA-PAST", "EMA-SOON", "EMA-LATER", "EMA-NEW", SCRIPT_ID, "EMA-OK"]


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    from emaphm.fleet.site import build_site

    tmp = tmp_path_factory.mktemp("fleet-browser")
    rng = np.random.default_rng(0)
    t = np.linspace(0.0, 600.0, 6)
    series = {
        "EMA-PAST": [_k(friction=0.2 + 0.0006 * x) for x in t],            # 0.56 > 0.5
        "EMA-SOON": [_k(short_a=0.02 + 0.0004 * x) for x in t],            # 0.3 near 700 h
        "EMA-LATER": [_k(friction=0.0003 * x) for x in t],                 # 0.5 near 1670 h
        "EMA-OK": [_k(friction=abs(e)) for e in rng.normal(0, 0.004, t.size)],
        "EMA-NEW": [_k(short_a=0.06)],
        SCRIPT_ID: [_k(gain=0.5 + 0.02 + e) for e in rng.normal(0, 0.002, 3)],
    }
    with HealthHistory(tmp / "fleet.sqlite") as h:
        for aid, ks in series.items():
            if aid == SCRIPT_ID:        # the registry refuses it; another tool wrote it
                h._con.execute("INSERT INTO actuators (id, description, time_unit, created_utc, "
                               "updated_utc) VALUES (?, ?, 'h', '2026-01-01', '2026-01-01')",
                               (aid, NASTY))
            else:
                h.register(aid, description=f"{aid.lower()} <b>unit</b>")
            for x, k in zip(t, ks):
                h.add(aid, float(x), k, diagnosis=diagnose(k, fault_model="paper").to_dict(),
                      algorithm="pso", fingerprint=f"{aid}{x}")
    return build_site(tmp / "fleet.sqlite", tmp / "site", workers=0)


@pytest.fixture(scope="module")
def driver():
    chromium, chromedriver = _browser()
    offline = os.environ.get("SE_OFFLINE")
    os.environ["SE_OFFLINE"] = "true"                 # Selenium Manager must not download
    from selenium import webdriver
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service

    profile = tempfile.mkdtemp(prefix="emaphm-chromium-")
    opts = Options()
    opts.binary_location = chromium
    for flag in CHROME_FLAGS:
        opts.add_argument(flag)
    opts.add_argument(f"--user-data-dir={profile}")
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    d = webdriver.Chrome(service=Service(chromedriver), options=opts)
    d.set_page_load_timeout(60)
    try:
        yield d
    finally:
        d.quit()
        shutil.rmtree(profile, ignore_errors=True)
        if offline is None:
            os.environ.pop("SE_OFFLINE", None)
        else:
            os.environ["SE_OFFLINE"] = offline


def _open(driver, path):
    from selenium.webdriver.support.ui import WebDriverWait

    driver.get(path.as_uri())
    WebDriverWait(driver, 20).until(
        lambda d: d.execute_script("return document.readyState") == "complete")


def _visible_ids(driver):
    return driver.execute_script(
        "return Array.from(document.querySelectorAll('#fleet tbody tr'))"
        ".filter(r => !r.hidden).map(r => r.querySelector('td.c-id a').textContent)")


def _severe(driver):
    return [e for e in driver.get_log("browser") if e.get("level") == "SEVERE"]


def _no_alert(driver):
    from selenium.common.exceptions import NoAlertPresentException

    with pytest.raises(NoAlertPresentException):
        driver.switch_to.alert.text


def _screenshot_pixels(driver):
    from PIL import Image

    img = Image.open(io.BytesIO(driver.get_screenshot_as_png())).convert("RGB")
    return np.asarray(img, dtype=float)


def test_the_index_renders_sorted_and_filters(site, driver):
    _open(driver, site.index)
    assert driver.execute_script("return document.documentElement.classList.contains('js')")
    assert driver.find_element("css selector", "#fleet tbody").is_displayed()
    assert len(driver.find_elements("css selector", "#fleet tbody tr")) == 6
    assert _visible_ids(driver) == EXPECTED_ORDER
    # the ids and descriptions are text: nothing of theirs ran or became an element
    _no_alert(driver)
    assert driver.execute_script("return document.querySelectorAll('#fleet img, #fleet b, "
                                 "#fleet script').length") == 0
    link_texts = [a.text for a in driver.find_elements("css selector", "#fleet td.c-id a")]
    assert SCRIPT_ID in link_texts
    assert NASTY in driver.find_element("css selector", "#fleet").text

    # sort by id (click), then the other way (click again)
    button = driver.find_element("css selector", "thead button[data-key=id]")
    button.click()
    assert _visible_ids(driver) == sorted(EXPECTED_ORDER, key=str.lower)
    th = driver.find_element("css selector", "thead th[data-key=id]")
    assert th.get_attribute("aria-sort") == "ascending"
    button.click()
    assert _visible_ids(driver) == sorted(EXPECTED_ORDER, key=str.lower, reverse=True)
    assert th.get_attribute("aria-sort") == "descending"
    # most inspections first, the order of attention between equals
    driver.find_element("css selector", "thead button[data-key=n]").click()
    assert _visible_ids(driver) == ["EMA-PAST", "EMA-SOON", "EMA-LATER", "EMA-OK", SCRIPT_ID,
                                    "EMA-NEW"]
    # back to the order of attention through the sort menu
    from selenium.webdriver.support.ui import Select

    Select(driver.find_element("id", "sort")).select_by_value("rank")
    assert _visible_ids(driver) == EXPECTED_ORDER

    # a text filter, then a state filter
    box = driver.find_element("id", "filter")
    box.send_keys("ema-s")
    assert _visible_ids(driver) == ["EMA-SOON"]
    assert driver.find_element("id", "shown").text == "1 of 6 shown"
    box.clear()
    box.send_keys("script")
    assert _visible_ids(driver) == [SCRIPT_ID]
    box.clear()
    box.send_keys(" ")                                   # whitespace filters nothing
    assert _visible_ids(driver) == EXPECTED_ORDER
    box.clear()
    Select(driver.find_element("id", "show")).select_by_value("past threshold")
    assert _visible_ids(driver) == ["EMA-PAST"]
    Select(driver.find_element("id", "show")).select_by_value("predicted")
    assert _visible_ids(driver) == ["EMA-SOON", "EMA-LATER"]
    box.send_keys("no such actuator")
    assert _visible_ids(driver) == [] and driver.find_element("id", "empty").is_displayed()
    assert _severe(driver) == []


def test_an_actuator_page_loads_with_its_figures(site, driver):
    _open(driver, site.index)
    driver.find_element("link text", "EMA-SOON").click()
    assert driver.current_url == site.pages["EMA-SOON"].as_uri()
    imgs = driver.execute_script(
        "return Array.from(document.images).map(i => [i.getAttribute('src'), i.complete, "
        "i.naturalWidth, i.naturalHeight])")
    assert len(imgs) == 2, imgs
    assert all(ok and w > 0 and h > 0 for _, ok, w, h in imgs), imgs
    assert driver.find_element("css selector", "h1").text == "EMA-SOON"
    px = _screenshot_pixels(driver)
    assert px.shape[:2] == (driver.execute_script("return window.innerHeight"),
                            driver.execute_script("return window.innerWidth"))
    assert px.std() > 20                                 # not a blank (one-colour) page
    assert len(np.unique(px.reshape(-1, 3)[::7], axis=0)) > 50
    assert _severe(driver) == []


def test_the_script_id_has_a_page_of_its_own_that_renders_it_as_text(site, driver):
    _open(driver, site.index)
    driver.find_element("link text", SCRIPT_ID).click()
    _no_alert(driver)
    assert driver.current_url == site.pages[SCRIPT_ID].as_uri()
    assert driver.find_element("css selector", "h1").text == SCRIPT_ID
    assert driver.find_element("css selector", "p.desc").text == NASTY
    assert driver.execute_script("return document.scripts.length") == 1   # fleet.js alone
    imgs = driver.execute_script("return Array.from(document.images).map(i => i.naturalWidth)")
    assert len(imgs) == 2 and min(imgs) > 0
    assert _severe(driver) == []


@contextlib.contextmanager
def _phone(driver):
    """The page as a 375 px wide phone shows it, for the ``with`` block."""
    driver.execute_cdp_cmd("Emulation.setDeviceMetricsOverride",
                           {"width": 375, "height": 812, "deviceScaleFactor": 1, "mobile": True})
    try:
        yield
    finally:
        driver.execute_cdp_cmd("Emulation.clearDeviceMetricsOverride", {})


def test_a_phone_shows_the_index_without_horizontal_scrolling(site, driver):
    with _phone(driver):
        _open(driver, site.index)
        assert driver.execute_script("return window.innerWidth") == 375
        assert driver.execute_script("return document.documentElement.scrollWidth") <= 375
        # every actuator is there, one card each, none wider than the screen
        widths = driver.execute_script(
            "return Array.from(document.querySelectorAll('#fleet tbody tr'))"
            ".map(r => r.getBoundingClientRect().right)")
        assert len(widths) == 6 and max(widths) <= 375
        assert driver.execute_script(      # the headings are for screen readers only
            "return document.querySelector('#fleet thead').getBoundingClientRect().height") <= 1
        px = _screenshot_pixels(driver)
        assert px.shape[1] == 375 and px.std() > 20


def test_printing_drops_the_controls_and_keeps_the_table(site, driver):
    _open(driver, site.index)
    driver.execute_cdp_cmd("Emulation.setEmulatedMedia", {"media": "print"})
    try:
        assert driver.execute_script(
            "return getComputedStyle(document.getElementById('controls')).display") == "none"
        assert driver.execute_script(
            "return getComputedStyle(document.querySelector('#fleet tbody tr')).display") \
            == "table-row"
    finally:
        driver.execute_cdp_cmd("Emulation.setEmulatedMedia", {"media": ""})
    import base64

    from selenium.webdriver.common.print_page_options import PrintOptions

    pdf = base64.b64decode(driver.print_page(PrintOptions()))
    assert pdf[:5] == b"%PDF-" and len(pdf) > 10_000


def test_without_a_browser_the_test_skips_and_says_why_unless_ci_requires_it(monkeypatch):
    monkeypatch.setattr(sys.modules[__name__], "_find", lambda *names: None)
    monkeypatch.delenv("EMAPHM_REQUIRE_BROWSER", raising=False)
    with pytest.raises(pytest.skip.Exception, match="chromium, chromedriver.*apt-get install"):
        _browser()
    monkeypatch.setenv("EMAPHM_REQUIRE_BROWSER", "1")
    with pytest.raises(pytest.fail.Exception, match="EMAPHM_REQUIRE_BROWSER is set"):
        _browser()


# ----------------------------------------------------------------------------- a large fleet
BIG = 10_000
POSITIONS = ("aileron", "elevator", "rudder", "spoiler", "flap")


@pytest.fixture(scope="module")
def big_site(tmp_path_factory):
    """10,000 actuators: ten with three inspections (a failure predicted or past), the
    others registered and never inspected, so that the site builds in seconds."""
    from emaphm.fleet.site import build_site

    tmp = tmp_path_factory.mktemp("fleet-big")
    db = tmp / "big.sqlite"
    with HealthHistory(db) as h:
        h._con.execute("BEGIN")              # one transaction: a commit each took minutes
        h._con.executemany(
            "INSERT INTO actuators (id, description, time_unit, created_utc, updated_utc) "
            "VALUES (?, ?, 'h', '2026-01-01T00:00:00', '2026-01-01T00:00:00')",
            [(f"EMA-{i:05d}", f"{POSITIONS[i % 5]}, aircraft {100 + i // 10}")
             for i in range(1, BIG + 1)])
        h._con.execute("COMMIT")
        for i in range(1, BIG + 1, 1000):
            for t in (0.0, 300.0, 600.0):
                k = _k(friction=0.0008 * t) if i % 3 == 1 else _k(short_a=0.0004 * t)
                h.add(f"EMA-{i:05d}", t, k, diagnosis=diagnose(k, fault_model="paper").to_dict())
    return build_site(db, tmp / "site", workers=0)


def _page_text(driver):
    return driver.execute_script(
        "var p = document.getElementById('pager'); "
        "return p.hidden ? null : document.getElementById('page').textContent")


def test_an_index_of_ten_thousand_actuators_pages_sorts_and_filters(big_site, driver):
    from selenium.webdriver.support.ui import Select

    order = [r["id"] for r in big_site.rows]
    assert len(order) == BIG and order[0] == "EMA-00001"          # past its threshold
    _open(driver, big_site.index)
    assert driver.find_element("id", "shown").text == f"{BIG} of {BIG} shown"
    assert _visible_ids(driver) == order[:100]                     # the order of attention
    assert _page_text(driver) == "page 1 of 100 (1\u2013100)"
    assert not driver.find_element("id", "more").is_displayed()    # the note for no script
    nxt, prev = driver.find_element("id", "next"), driver.find_element("id", "prev")
    assert not prev.is_enabled()
    nxt.click()
    assert _visible_ids(driver) == order[100:200]
    assert _page_text(driver) == "page 2 of 100 (101\u2013200)" and prev.is_enabled()
    prev.click()
    assert _visible_ids(driver) == order[:100]

    box = driver.find_element("id", "filter")
    box.send_keys("ema-07777")
    assert _visible_ids(driver) == ["EMA-07777"]
    assert driver.find_element("id", "shown").text == f"1 of {BIG} shown"
    assert _page_text(driver) is None                              # one page: no pager
    box.clear()
    box.send_keys("aircraft 1000")
    want = [r["id"] for r in big_site.rows              # every word somewhere in its text
            if "aircraft" in r["text"] and "1000" in r["text"]]
    assert len(want) == 12 and _visible_ids(driver) == want   # aircraft 1000; EMA-(0)1000
    box.clear()
    button = driver.find_element("css selector", "thead button[data-key=id]")
    button.click()
    button.click()                                                 # descending
    assert _visible_ids(driver)[:3] == ["EMA-10000", "EMA-09999", "EMA-09998"]
    assert _page_text(driver) == "page 1 of 100 (1\u2013100)"
    box.send_keys("rudder")                                        # 2,000: twenty pages
    assert _page_text(driver) == "page 1 of 20 (1\u2013100)"
    for _ in range(19):
        nxt.click()
    assert _page_text(driver) == "page 20 of 20 (1901\u20132000)" and not nxt.is_enabled()
    assert _visible_ids(driver)[-1] == "EMA-00002"
    box.clear()
    Select(driver.find_element("id", "show")).select_by_value("attention")
    want = sorted((r["id"] for r in big_site.rows if "attention" in r["tags"]), reverse=True)
    assert len(want) == 10 and _visible_ids(driver) == want
    assert _severe(driver) == []


def test_a_phone_pages_the_large_index_without_horizontal_scrolling(big_site, driver):
    with _phone(driver):
        _open(driver, big_site.index)
        assert driver.execute_script("return window.innerWidth") == 375
        assert driver.find_element("id", "pager").is_displayed()
        assert len(driver.find_elements("css selector", "#fleet tbody tr")) == 100
        driver.find_element("id", "next").click()
        assert _visible_ids(driver) == [r["id"] for r in big_site.rows[100:200]]
        assert driver.execute_script("return document.documentElement.scrollWidth") <= 375
        right = driver.execute_script(
            "return Math.max(...Array.from(document.querySelectorAll('#fleet tbody tr, "
            "#pager')).map(e => e.getBoundingClientRect().right))")
        assert right <= 375
