"""``emaphm assess`` on two actuators (issue 23): its time on two cores and where it goes,
and whether its prediction holds on fresh units.

For each actuator (the preset and ``examples/actuators/ema-270v-750w.toml``, a 270 V,
10-pole design never tuned on):

1. **The assessment** at its defaults (20 units, thresholds tuned on 20 others for a 1 %
   false-alarm target, every grid, 10 healthy traces per unit after calibration and 2 on
   the data sheet), seed 0, on a local pool of ``--workers`` processes: wall and CPU time,
   and the CPU by what it was spent on (calibration, diagnoses, simulation and the rest).
2. **Fresh units**: 10 new units (seed 1, so none of the assessed or tuning units), each
   calibrated with the assessed ``params.toml`` (its thresholds kept: ``--no-tune``); the
   measured false-alarm rate (10 healthy traces per unit), a 10 % short named right and a
   friction x1.5 named right, each against the assessed 95 % interval: "holds" when the
   fresh units' own Wilson interval (the 10-unit sampling error) overlaps it; the fresh
   point estimate inside the assessed interval is reported too.

Run: ``python benchmarks/bench_assess.py [--workers 2] [--units 20] [--fresh 10]`` (or
``--render``: the tables again from ``assess.json``, nothing run) ->
``benchmarks/results/assess.md`` and ``assess.json``.
"""

from __future__ import annotations

import os

for _v in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import datetime as _dt  # noqa: E402
import json  # noqa: E402
import shutil  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

from _actuators import ACTUATORS, datasheet  # noqa: E402
from _machine import machine  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(__file__).parent / "results"
CHECKS = (("short_circuit", 0.1, "10 % short named right"), ("friction", 1.5, "friction x1.5 named right"))


def run(name: str, workers: int, units: int, fresh: int, work: Path) -> dict:
    from emaphm.assessment import AssessmentSpec, assess
    from emaphm.campaign.executors import make_executor
    from emaphm.params import load_params

    executor = make_executor(workers)
    spec = AssessmentSpec(datasheet(name).to_dict(), units=units, seed=0)
    t0 = time.perf_counter()
    out = assess(spec, work / name, executor=executor)
    wall = time.perf_counter() - t0
    a = out.summary
    assessed = load_params(work / name / "params.toml")
    fspec = AssessmentSpec(assessed.to_dict(), units=fresh, tune_units=0, seed=1,
                           healthy=10, healthy_datasheet=0,
                           grids=tuple(g for g, _, _ in CHECKS),
                           severities={g: (s,) for g, s, _ in CHECKS})
    t1 = time.perf_counter()
    b = assess(fspec, work / f"{name}-fresh", executor=executor).summary
    fresh_wall = time.perf_counter() - t1
    return {"actuator": name, "wall_s": wall, "load_end": os.getloadavg()[0], "summary": a,
            "fresh": b, "fresh_wall_s": fresh_wall, "workers": workers,
            "date": _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
            "machine": machine("numba")}


def _holds(lo: float, hi: float, k: int, n: int) -> tuple[bool, bool, tuple[float, float]]:
    from emaphm.assessment.stats import wilson

    w = wilson(k, n)
    return (w[0] <= hi and lo <= w[1]), (lo <= k / n <= hi if n else False), w


def _min_detectable(least: float | None, rows: list[dict]) -> str:
    """The smallest severity detected at a 95 % lower bound of 90 %, or why there is none."""
    if least is not None:
        return f"{least:g}"
    n = max(r["n"] for r in rows)
    return f"none ({n}/{n} bounds it at {100 * rows[0]['lo']:.0f} %, under 90 %)" \
        if all(r["right"] == r["n"] for r in rows) else f"none at {n} units"


#: The table's words for a POD fit without an a90, by :attr:`PODFit.status`.
_NO_A90 = {"every run a hit": "every run a hit: below the sizes tried",
           "no hit": "no hit at any size", "separated": "hits and misses do not overlap in size",
           "too few sizes": "fewer than two sizes tried",
           "not growing": "the fitted POD does not grow with size"}


def _fit(fit: dict) -> str:
    from emaphm.assessment.stats import PODFit

    f = PODFit.from_dict(fit)
    if f.a90 is not None:
        return f"{f.a90:.3g}" + ("" if f.a90_95 is None else f" ({f.a90_95:.3g})")
    if f.status == "not recorded":          # a result stored before the status: its note
        return f.note
    return _NO_A90[f.status]


def report(rows: list[dict]) -> list[str]:
    when = rows[-1].get("date", "date not recorded")
    lines = [f"## `emaphm assess` on two actuators ({when})", "",
             f"Machine: {rows[-1].get('machine', machine('numba'))}; "
             f"{rows[-1].get('workers', 2)} worker processes. "
             "`benchmarks/bench_assess.py`: the assessment at its defaults (20 units, "
             "thresholds tuned on 20 others for a 1 % false-alarm target, all 8 grids), then "
             "10 fresh units (another seed) calibrated with the assessed `params.toml`. Wall "
             "time depends on the machine's load (shown); CPU time is the sum over the "
             "workers.", "",
             "| actuator | wall [min] | load at the end | CPU [s] | calibration | diagnoses "
             "| simulation and the rest | diagnoses run | false alarms after calibration (Wilson 95 %) "
             "| on the data sheet: faulty / unexplained |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        a = r["summary"]
        c = a["cpu_s"]
        fa, fs = a["false_alarm"]["calibrated"], a["false_alarm"]["datasheet"]
        lines.append(
            f"| {r['actuator']} | {r['wall_s'] / 60:.1f} | {r['load_end']:.2f} | {c['total']:.0f} "
            f"| {c['calibrate']:.0f} s ({100 * c['calibrate'] / c['total']:.0f} %) "
            f"| {c['diagnose']:.0f} s ({100 * c['diagnose'] / c['total']:.0f} %) "
            f"| {c['simulate_and_rest']:.0f} s ({100 * c['simulate_and_rest'] / c['total']:.0f} %) "
            f"| {len(a['runs'])} | {fa['faulty']}/{fa['n']} ({100 * fa['lo']:.1f}-{100 * fa['hi']:.1f} %) "
            f"| {fs['faulty']} / {fs['unexplained']} of {fs['n']} |")
    lines += ["", "Probability of correct identification after calibration (the right mode, "
              "and phase, named alone; `n` per severity = units), by grid and severity:", ""]
    for r in rows:
        a = r["summary"]
        lines += [f"**{r['actuator']}**: thresholds "
                  + ", ".join(f"{n} {v:.3g}" for n, v in a["thresholds"]["values"].items()), "",
                  "| grid | " + " | ".join(f"s{i + 1}" for i in range(4)) + " | min_detectable | a90 (a90/95) |",
                  "|---|---|---|---|---|---|---|"]
        for grid, rs in a["pod"].items():
            fit = a["pod_fit"][grid]
            cells = [f"{x['severity']:g}: {x['right']}/{x['n']}" for x in rs]
            cells += [""] * (4 - len(cells))
            lines.append(f"| {grid} | " + " | ".join(cells)
                         + f" | {_min_detectable(a['min_detectable'][grid], rs)} | {_fit(fit)} |")
        lines.append("")
    lines += ["The prediction on fresh units (10 new units each, seed 1, thresholds from the "
              "assessed `params.toml`): the assessed 95 % interval, the fresh rate with its "
              "own Wilson interval; **holds** when the two intervals overlap (the fresh "
              "units' sampling error allowed for).", "",
              "| actuator | quantity | assessed | fresh | fresh rate inside the assessed interval | holds |",
              "|---|---|---|---|---|---|"]
    for r in rows:
        a, b = r["summary"], r["fresh"]
        fa, fb = a["false_alarm"]["calibrated"], b["false_alarm"]["calibrated"]
        ok, inside, w = _holds(fa["lo"], fa["hi"], fb["faulty"], fb["n"])
        lines.append(f"| {r['actuator']} | false-alarm rate | {fa['faulty']}/{fa['n']} "
                     f"[{100 * fa['lo']:.1f}, {100 * fa['hi']:.1f}] % | {fb['faulty']}/{fb['n']} "
                     f"[{100 * w[0]:.1f}, {100 * w[1]:.1f}] % | {'yes' if inside else 'no'} "
                     f"| {'yes' if ok else 'NO'} |")
        for grid, s, label in CHECKS:
            (ra,) = [x for x in a["pod"][grid] if abs(x["severity"] - s) < 1e-12]
            (rb,) = b["pod"][grid]
            ok, inside, w = _holds(ra["lo"], ra["hi"], rb["right"], rb["n"])
            lines.append(f"| {r['actuator']} | {label} | {ra['right']}/{ra['n']} "
                         f"[{100 * ra['lo']:.0f}, {100 * ra['hi']:.0f}] % | {rb['right']}/{rb['n']} "
                         f"[{100 * w[0]:.0f}, {100 * w[1]:.0f}] % | {'yes' if inside else 'no'} "
                         f"| {'yes' if ok else 'NO'} |")
    lines.append("")
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--units", type=int, default=20)
    ap.add_argument("--fresh", type=int, default=10)
    ap.add_argument("--actuators", default=",".join(ACTUATORS))
    ap.add_argument("--render", action="store_true",
                    help="write assess.md again from assess.json, running nothing")
    args = ap.parse_args()
    if args.render:
        rows = [{**r, "summary": {**r["summary"], "runs": r["runs"]}}
                for r in json.loads((RESULTS / "assess.json").read_text())]
        lines = report(rows)
        (RESULTS / "assess.md").write_text("\n".join(lines) + "\n")
        print("\n".join(lines))
        return
    work = Path(tempfile.mkdtemp(prefix="bench-assess-"))
    try:
        rows = [run(name, args.workers, args.units, args.fresh, work)
                for name in args.actuators.split(",")]
    finally:
        shutil.rmtree(work, ignore_errors=True)
    lines = report(rows)
    (RESULTS / "assess.md").write_text("\n".join(lines) + "\n")
    slim = [{**r, "summary": {k: v for k, v in r["summary"].items() if k != "runs"},
             "runs": r["summary"]["runs"], "fresh": r["fresh"]} for r in rows]
    (RESULTS / "assess.json").write_text(json.dumps(slim, indent=1) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
