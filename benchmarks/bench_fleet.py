"""How long the fleet health site takes to build, and where the time goes.

Run: ``python benchmarks/bench_fleet.py [--db HISTORY] [--real] [--actuators 30]``
-> ``benchmarks/results/fleet.md`` and ``fleet.json`` (the table is printed too).

The fleet is the demo fleet of ``emaphm fleet demo`` (seed 0, 30 actuators, 136
inspections): by default recorded with ``--synthetic`` (seconds; the site draws the
same number of figures of the same kind either way), with ``--real`` diagnosed from
reference-plant traces first (minutes), or any existing history with ``--db``.

Each build runs ``emaphm fleet report`` in a fresh process, as a user would, and
reports its wall time and its CPU time together with every worker process it started
(``getrusage(RUSAGE_CHILDREN)``), beside the load average before and after:

* cold, ``--workers 0`` (in the one process), into an empty folder;
* cold, ``--workers N`` (default: every core), into an empty folder;
* a rebuild into the same folder with nothing changed (the figures are kept);
* a rebuild after one new inspection of one actuator (its figures are drawn again).

Then, in this process and on one core, the CPU time per actuator of each part of a
cold build: the prognosis (:func:`emaphm.fleet.status.assess`), building and saving
the history figure, building and saving the prognosis figure. On a shared machine the
wall time grows with the load; the CPU time is the measure of the code.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import io
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _machine import machine as _machine  # the scripts run from benchmarks/

ROOT = Path(__file__).resolve().parent


def machine() -> str:
    return _machine("matplotlib")


def _cli(*args: str) -> dict:
    """Run ``emaphm ARGS`` in a fresh process: wall and CPU seconds (with its workers)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    load0 = os.getloadavg()[0]
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-m", "emaphm.cli", *args], check=True,
                         capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"wall_s": wall, "cpu_s": cpu, "load_before": load0, "load_after": os.getloadavg()[0],
            "stdout": out.stdout.strip()}


def _parts(db: Path) -> dict:
    """CPU seconds per actuator of each part of a cold build, in this process."""
    import matplotlib

    matplotlib.use("Agg")
    from emaphm.fleet.site import FIGURE_DPI
    from emaphm.fleet.status import assess
    from emaphm.prognosis.history import HealthHistory
    from emaphm.prognosis.plots import (interesting_indicators, moved_components, plot_history,
                                        plot_prognosis)
    from emaphm.prognosis.thresholds import INDICATOR_COMPONENT

    with HealthHistory(db, create=False) as h:
        datas = [h.data(a.id) for a in h.actuators()]
    plot_history(datas[0]).savefig(io.BytesIO(), format="png", dpi=FIGURE_DPI)   # fonts, caches
    parts = {"prognosis (assess)": 0.0, "history figure: build": 0.0,
             "history figure: draw and save PNG": 0.0, "prognosis figure: build": 0.0,
             "prognosis figure: draw and save PNG": 0.0}
    n_prog = 0
    for d in datas:
        c = time.process_time()
        s = assess(d, seed=0)
        parts["prognosis (assess)"] += time.process_time() - c
        c = time.process_time()
        always = [INDICATOR_COMPONENT[s.worst]] if s.worst in INDICATOR_COMPONENT else []
        fig = plot_history(d, components=moved_components(d, always=always))   # as the site
        parts["history figure: build"] += time.process_time() - c
        c = time.process_time()
        fig.savefig(io.BytesIO(), format="png", dpi=FIGURE_DPI)
        parts["history figure: draw and save PNG"] += time.process_time() - c
        if s.prognosis is not None:
            n_prog += 1
            p = s.prognosis
            span = float(p.times[-1] - p.times[0])
            names = [s.worst] + [n for n in interesting_indicators(p) if n != s.worst
                                 and not p.predictions[n].no_growth(span)]
            c = time.process_time()
            fig = plot_prognosis(p, indicators=names[:3])
            parts["prognosis figure: build"] += time.process_time() - c
            c = time.process_time()
            fig.savefig(io.BytesIO(), format="png", dpi=FIGURE_DPI)
            parts["prognosis figure: draw and save PNG"] += time.process_time() - c
    return {"n_actuators": len(datas), "n_prognoses": n_prog,
            "per_actuator_cpu_s": {k: v / len(datas) for k, v in parts.items()}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--db", help="an existing health history (default: record the demo fleet)")
    ap.add_argument("--real", action="store_true",
                    help="record the demo fleet from reference-plant traces (minutes)")
    ap.add_argument("--actuators", type=int, default=30)
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--out", default=str(ROOT / "results"), help="folder of fleet.md/json")
    args = ap.parse_args()

    tmp = Path(tempfile.mkdtemp(prefix="emaphm-bench-fleet-"))
    try:
        if args.db:
            db = tmp / "history.sqlite"
            shutil.copy(args.db, db)
            fleet = f"the history {Path(args.db).name}"
        else:
            db = tmp / "demo.sqlite"
            demo = ["fleet", "demo", "--db", str(db), "--actuators", str(args.actuators),
                    "--quiet"] + ([] if args.real else ["--synthetic"])
            rec = _cli(*demo)
            fleet = (f"the demo fleet (seed 0, {args.actuators} actuators) recorded "
                     + ("from reference-plant traces, diagnosed" if args.real else
                        "--synthetic (true k plus noise)")
                     + f" in {rec['wall_s']:.1f} s ({rec['cpu_s']:.1f} s CPU)")
        from emaphm.prognosis.history import HealthHistory

        with HealthHistory(db, create=False) as h:
            acts = h.actuators()
        n_act, n_ins = len(acts), sum(a.n_inspections for a in acts)
        report = ["fleet", "report", "--db", str(db), "--quiet", "--json"]
        rows = {}
        rows["cold, --workers 0 (one process)"] = _cli(*report, "--out", str(tmp / "s0"),
                                                      "--workers", "0")
        rows[f"cold, --workers {args.workers}"] = _cli(*report, "--out", str(tmp / "s1"),
                                                       "--workers", str(args.workers))
        rows["rebuild, nothing changed"] = _cli(*report, "--out", str(tmp / "s1"),
                                                "--workers", str(args.workers))
        last = max(acts, key=lambda a: a.n_inspections)
        with HealthHistory(db) as h:
            ins = h.inspections(last.id)[-1]
            h.add(last.id, ins.time + 50.0, ins.k, k_lo=ins.k_lo, k_hi=ins.k_hi,
                  diagnosis=ins.diagnosis, source="bench_fleet: one more inspection")
        rows["rebuild, one actuator with a new inspection"] = _cli(
            *report, "--out", str(tmp / "s1"), "--workers", str(args.workers))
        for r in rows.values():
            r["drawn"] = json.loads(r.pop("stdout"))["drawn"]
        parts = _parts(db)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)

    when = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    lines = ["## Fleet health site: build time (`benchmarks/bench_fleet.py`)", "",
             f"Run {when} on {machine()}. Fleet: {fleet}; {n_act} actuators, {n_ins} "
             f"inspections. Each build is `emaphm fleet report` in a fresh process; CPU "
             f"includes its worker processes. Load average before and after each build "
             f"shown: the machine is shared, so wall times grow with the load, CPU times "
             f"do not. Target (issue 12): the site of a 30-actuator demo fleet builds in "
             f"under 10 s.", "",
             "| build | wall [s] | CPU [s] | actuators drawn | load before / after |",
             "|---|---|---|---|---|"]
    for name, r in rows.items():
        lines.append(f"| {name} | {r['wall_s']:.1f} | {r['cpu_s']:.1f} | {r['drawn']} | "
                     f"{r['load_before']:.2f} / {r['load_after']:.2f} |")
    lines += ["", f"CPU per actuator of a cold build, one core, in one process "
              f"({parts['n_actuators']} actuators, {parts['n_prognoses']} with a prognosis):", "",
              "| part | CPU per actuator [s] |", "|---|---|"]
    total = 0.0
    for name, v in parts["per_actuator_cpu_s"].items():
        lines.append(f"| {name} | {v:.3f} |")
        total += v
    lines.append(f"| total | {total:.3f} |")
    text = "\n".join(lines) + "\n"
    print(text)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "fleet.md").write_text(text)
    (out / "fleet.json").write_text(json.dumps(
        {"date": when, "machine": machine(), "fleet": fleet, "actuators": n_act,
         "inspections": n_ins, "builds": rows, "parts": parts}, indent=1) + "\n")


if __name__ == "__main__":
    main()
