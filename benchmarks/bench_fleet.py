"""How long the fleet health site takes to build as the fleet grows, and where the time goes.

Run: ``python benchmarks/bench_fleet.py [--sizes 30,300,1000,10000] [--base REV] [--dask]``
-> ``benchmarks/results/fleet.md`` and ``fleet.json`` (the table is printed too);
``--append`` adds the sizes it measures to the ``fleet.json`` there (a 10,000-actuator
fleet's recording and cold build take about 5 minutes on two shared cores: run it apart),
each run's date in the table.

Each fleet is the demo fleet of ``emaphm fleet demo --synthetic`` (seed 0; true k plus
identification-sized noise: the site draws the same kind of figures as for a diagnosed
fleet). For each size, ``emaphm fleet report`` runs in a fresh process, as a user would:

* cold, ``--workers N`` (default: every core), into an empty folder;
* a rebuild into the same folder with nothing changed;
* a rebuild after one new inspection of one actuator.

Each row reports the wall time and the CPU time of the process with every worker process
it started (``getrusage(RUSAGE_CHILDREN)``), beside the load average before and after: on
a shared machine the wall time grows with the load, the CPU time much less.

``--base REV`` builds the 300-actuator fleet's site with emaphm at git revision ``REV``
as well (its ``src/`` extracted by ``git archive``), cold and rebuilt with nothing
changed, alternating with this tree's builds, so that both see the same load; ``--dask``
adds a cold build of that fleet on a local Dask cluster of N worker processes
(``--scheduler``). Then, in this process and on one core, the CPU time per actuator of
each part of a cold build on the first 60 actuators of that fleet: the prognosis
(:func:`emaphm.fleet.status.assess`), the two figures as the site draws them
(:class:`emaphm.fleet.figures.PageFigures`) and as the reference plots draw them
(:func:`emaphm.prognosis.plots.plot_history`, ``plot_prognosis``, saved at the site's
resolution).
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
from _versions import extract_src

ROOT = Path(__file__).resolve().parent

#: The commit before the fleet site learnt to grow (issue 24 item 6).
BASE = "17bc857"


def machine() -> str:
    return _machine("matplotlib")


def _cli(*args: str, src: Path | None = None) -> dict:
    """Run ``emaphm ARGS`` in a fresh process (emaphm from ``src`` if given): wall and CPU
    seconds with its workers, the load average around it and its JSON answer if any."""
    env = dict(os.environ)
    if src is not None:
        env["PYTHONPATH"] = str(src)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    load0 = os.getloadavg()[0]
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-m", "emaphm.cli", *args], check=True,
                         capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    try:
        answer = json.loads(out.stdout)
    except ValueError:
        answer = {}
    return {"wall_s": wall, "cpu_s": cpu, "load_before": load0, "load_after": os.getloadavg()[0],
            "drawn": answer.get("drawn"), "written": answer.get("written")}


def _add_inspection(db: Path) -> str:
    """One more inspection of the actuator with the most: its last k again, 50 h later."""
    from emaphm.prognosis.history import HealthHistory

    with HealthHistory(db) as h:
        last = max(h.actuators(), key=lambda a: (a.n_inspections, a.id))
        ins = h.inspections(last.id)[-1]
        h.add(last.id, ins.time + 50.0, ins.k, k_lo=ins.k_lo, k_hi=ins.k_hi,
              diagnosis=ins.diagnosis, source="bench_fleet: one more inspection")
    return last.id


def _fleet(n: int, tmp: Path, workers: int, base: Path | None, dask: bool,
           rev: str = BASE) -> dict:
    db = tmp / f"demo{n}.sqlite"
    rec = _cli("fleet", "demo", "--db", str(db), "--actuators", str(n), "--synthetic", "--quiet")
    db_base = tmp / f"demo{n}-{rev}.sqlite"
    if base is not None:   # the same demo fleet, recorded by the base in its own schema (an
        # older emaphm refuses a history a newer one wrote)
        _cli("fleet", "demo", "--db", str(db_base), "--actuators", str(n), "--synthetic",
             "--quiet", src=base)
    from emaphm.prognosis.history import HealthHistory

    with HealthHistory(db, readonly=True) as h:
        n_ins = sum(a.n_inspections for a in h.actuators())
    report = ["fleet", "report", "--db", str(db), "--quiet", "--json"]
    report_base = ["fleet", "report", "--db", str(db_base), "--quiet", "--json"]
    out, out_base = tmp / f"site{n}", tmp / f"base{n}"
    w = ["--workers", str(workers)]
    rows = {}
    rows["cold"] = _cli(*report, "--out", str(out), *w)
    if base is not None:
        rows[f"cold, emaphm {rev}"] = _cli(*report_base, "--out", str(out_base), *w, src=base)
    rows["rebuild, nothing changed"] = _cli(*report, "--out", str(out), *w)
    if base is not None:
        rows[f"rebuild, nothing changed, emaphm {rev}"] = _cli(*report_base, "--out",
                                                               str(out_base), *w, src=base)
    _add_inspection(db)
    rows["rebuild, one actuator with a new inspection"] = _cli(*report, "--out", str(out), *w)
    if dask:
        from distributed import LocalCluster

        with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                          dashboard_address=None, silence_logs=40) as cluster:
            rows[f"cold, --scheduler (local Dask cluster, {workers} worker processes)"] = _cli(
                *report, "--out", str(tmp / f"dask{n}"), "--scheduler", cluster.scheduler_address)
    return {"actuators": n, "inspections": n_ins, "record": rec, "builds": rows}


def _parts(db: Path, n: int = 60) -> dict:
    """CPU seconds per actuator of each part of a cold build, in this process."""
    import matplotlib

    matplotlib.use("Agg")
    from emaphm.fleet.figures import PageFigures
    from emaphm.fleet.site import FIGURE_DPI
    from emaphm.fleet.status import assess
    from emaphm.prognosis.history import HealthHistory
    from emaphm.prognosis.plots import (interesting_indicators, moved_components, plot_history,
                                        plot_prognosis)
    from emaphm.prognosis.thresholds import INDICATOR_COMPONENT

    with HealthHistory(db, readonly=True) as h:
        datas = [h.data(a.id) for a in h.actuators()[:n]]
    figs = PageFigures(px_per_inch=FIGURE_DPI)
    names = ("prognosis (assess, with the next inspection's plan)",
             "history figure, as the site draws it (SVG)",
             "prognosis figure, as the site draws it (SVG)",
             "history figure, reference plot_history", "prognosis figure, reference plot_prognosis")
    parts = dict.fromkeys(names, 0.0)

    def timed(name, fn):
        c = time.process_time()
        value = fn()
        parts[name] += time.process_time() - c
        return value

    def png(fig):
        fig.savefig(io.BytesIO(), format="png", dpi=FIGURE_DPI)

    plot_history(datas[0]).savefig(io.BytesIO(), format="png")              # fonts, caches
    n_prog = 0
    for i, d in enumerate(datas):
        s = timed(names[0], lambda: assess(d, seed=0))
        always = [INDICATOR_COMPONENT[s.worst]] if s.worst in INDICATOR_COMPONENT else []
        shown = moved_components(d, always=always)
        if i == 0:
            figs.history(d, components=shown)                                # its first layout
        timed(names[1], lambda: figs.history(d, components=shown))
        timed(names[3], lambda: png(plot_history(d, components=shown)))
        if s.prognosis is not None:
            n_prog += 1
            p = s.prognosis
            span = float(p.times[-1] - p.times[0])
            ind = ([s.worst] + [x for x in interesting_indicators(p) if x != s.worst
                                and not p.predictions[x].no_growth(span)])[:3]
            timed(names[2], lambda: figs.prognosis(p, indicators=ind))
            timed(names[4], lambda: png(plot_prognosis(p, indicators=ind)))
    return {"n_actuators": len(datas), "n_prognoses": n_prog,
            "per_actuator_cpu_s": {k: v / len(datas) for k, v in parts.items()}}


def _table(fleets: list[dict], parts: dict, when: str, base: str | None, workers: int) -> str:
    runs = sorted({f.get("date", when) for f in fleets})
    lines = ["## Fleet health site: build time as the fleet grows (`benchmarks/bench_fleet.py`)",
             "", f"Run {' and '.join(runs)} on {machine()}. Fleets: the demo fleet (seed 0) "
             "recorded by `emaphm fleet demo --synthetic` (true k plus identification-sized "
             f"noise). Each build is `emaphm fleet report --workers {workers}` in a fresh "
             "process; CPU includes its worker processes (on a Dask cluster: this process "
             "only, the cluster's workers are not its children). Load average (1 min) before "
             "and after each build shown: the machine is shared, so wall times grow with the "
             "load. Targets (issue 24 item 6): 300 actuators in at most 15 s on 2 cores, at "
             "most 1 s when nothing changed, linear up to 10,000."
             + (f" `emaphm {base}` is the code before the site learnt to grow, run "
                "alternately with this tree on the same fleet." if base else ""), "",
             "| fleet | build | wall [s] | CPU [s] | CPU per actuator [ms] | pages made | "
             "files written | load before / after |", "|---|---|---|---|---|---|---|---|"]
    many = len(runs) > 1
    for f in fleets:
        n = f["actuators"]
        rec = f["record"]
        lines.append(f"| {n:,} ({f['inspections']:,} inspections"
                     + (f", run {f['date']}" if many else "") + ") | recording it (`fleet demo "
                     f"--synthetic`) | {rec['wall_s']:.1f} | {rec['cpu_s']:.1f} | "
                     f"{1000 * rec['cpu_s'] / n:.1f} | | | {rec['load_before']:.2f} / "
                     f"{rec['load_after']:.2f} |")
        for name, r in f["builds"].items():
            fmt = (lambda v: "" if v is None else f"{v:,}")
            lines.append(f"| {n:,} | {name} | {r['wall_s']:.2f} | {r['cpu_s']:.2f} | "
                         f"{1000 * r['cpu_s'] / n:.1f} | {fmt(r['drawn'])} | {fmt(r['written'])} "
                         f"| {r['load_before']:.2f} / {r['load_after']:.2f} |")
    if parts:
        lines += ["", f"CPU per actuator of the parts of a cold build, one core, in one process "
                  f"(the first {parts['n_actuators']} actuators of the 300-actuator fleet, "
                  f"{parts['n_prognoses']} with a prognosis; a figure's time includes writing its "
                  "file: SVG text for the site's, a PNG at the site's size for matplotlib's):",
                  "", "| part | CPU per actuator [ms] |", "|---|---|"]
        for name, v in parts["per_actuator_cpu_s"].items():
            lines.append(f"| {name} | {1000 * v:.1f} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", default="30,300,1000,10000",
                    help="fleet sizes, comma-separated (default 30,300,1000,10000)")
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--base", nargs="?", const=BASE, default=None,
                    help=f"also build the 300-actuator site with emaphm at this revision "
                         f"(default {BASE})")
    ap.add_argument("--dask", action="store_true", help="a cold build on a local Dask cluster")
    ap.add_argument("--out", default=str(ROOT / "results"), help="folder of fleet.md/json")
    ap.add_argument("--append", action="store_true",
                    help="add these sizes to the fleet.json in --out (same machine)")
    args = ap.parse_args()
    sizes = [int(x) for x in args.sizes.split(",")]

    tmp = Path(tempfile.mkdtemp(prefix="emaphm-bench-fleet-"))
    try:
        base = extract_src(args.base, tmp) if args.base else None
        fleets, parts = [], {}
        for n in sizes:
            fleets.append(_fleet(n, tmp, args.workers, base if n == 300 else None,
                                 args.dask and n == 300, rev=args.base or BASE))
            print(json.dumps(fleets[-1]), file=sys.stderr, flush=True)
            if n == 300:
                parts = _parts(tmp / "demo300.sqlite")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)

    when = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    for f in fleets:
        f["date"] = when
    out = Path(args.out)
    if args.append:
        old = json.loads((out / "fleet.json").read_text())
        if old["machine"] != machine() or old["workers"] != args.workers:
            raise SystemExit(f"--append: {out / 'fleet.json'} was measured on {old['machine']} "
                             f"with {old['workers']} workers; run all sizes again here")
        measured = {f["actuators"] for f in fleets}
        fleets = sorted([f for f in old["fleets"] if f["actuators"] not in measured] + fleets,
                        key=lambda f: f["actuators"])
        parts = parts or old["parts"]
        args.base = args.base or old["base"]
    text = _table(fleets, parts, when, args.base, args.workers)
    print(text)
    out.mkdir(parents=True, exist_ok=True)
    (out / "fleet.md").write_text(text)
    (out / "fleet.json").write_text(json.dumps(
        {"date": when, "machine": machine(), "workers": args.workers, "base": args.base,
         "fleets": fleets, "parts": parts}, indent=1) + "\n")


if __name__ == "__main__":
    main()
