"""Write ``docs/fleet.png``, the README's picture of the fleet health site: the index of
the demo fleet as headless Chromium renders it.

Run: ``python docs/fleet_screenshot.py [--db demo.sqlite] [--out docs/fleet.png]``.
Without ``--db`` it records the demo fleet first (``emaphm fleet demo``: reference-plant
traces, diagnosed; a few minutes). Needs Chromium and its driver from the operating
system (``apt-get install chromium chromium-driver``) and Selenium (the ``test`` extra);
nothing is downloaded.
"""

from __future__ import annotations

import argparse
import io
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
FLAGS = ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--hide-scrollbars", "--force-device-scale-factor=1")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--db", help="a health history (default: record the demo fleet)")
    ap.add_argument("--out", default=str(HERE / "fleet.png"))
    ap.add_argument("--width", type=int, default=1280)
    ap.add_argument("--height", type=int, default=820)
    args = ap.parse_args()
    os.environ["SE_OFFLINE"] = "true"
    from PIL import Image
    from selenium import webdriver
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service

    from emaphm.fleet.site import build_site

    tmp = Path(tempfile.mkdtemp(prefix="emaphm-fleet-shot-"))
    try:
        db = Path(args.db) if args.db else tmp / "demo.sqlite"
        if not args.db:
            subprocess.run([sys.executable, "-m", "emaphm.cli", "fleet", "demo", "--db", str(db)],
                           check=True)
        site = build_site(db, tmp / "site")
        opts = Options()
        opts.binary_location = shutil.which("chromium") or "/usr/bin/chromium"
        for flag in FLAGS + (f"--user-data-dir={tmp / 'profile'}",
                             f"--window-size={args.width},{args.height}"):
            opts.add_argument(flag)
        driver = webdriver.Chrome(service=Service(shutil.which("chromedriver")
                                                  or "/usr/bin/chromedriver"), options=opts)
        try:
            driver.get(site.index.as_uri())
            png = driver.get_screenshot_as_png()
        finally:
            driver.quit()
        img = Image.open(io.BytesIO(png)).convert("RGB")
        # a 256-colour palette keeps the picture small; the page has few colours
        img.quantize(colors=256, method=Image.Quantize.MEDIANCUT).save(args.out, optimize=True)
        print(f"wrote {args.out} ({Path(args.out).stat().st_size / 1024:.0f} kB)")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
