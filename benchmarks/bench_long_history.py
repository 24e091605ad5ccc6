"""Time and memory of the prognosis of one actuator as its history grows (issue 37, item 9).

Run: ``python benchmarks/bench_long_history.py [--sizes 100,300,1000,3000,10000]
[--base REV] [--base-max 3000]`` -> ``benchmarks/results/long_history.md`` and
``long_history.json`` (the table is printed too).

Each history is one actuator inspected every 24 h: friction growing linearly from 0.05 to
0.35 (k1) with identification-sized noise (0.007 per component of k), and one inspection
in 200 landed in a wrong basin (k1 + 0.2, k2 + 0.1), which the prognosis's outlier screen
leaves out. For each size, in a fresh process as a user would run them:

* ``emaphm prognose EMA-1 --json`` (every indicator of every registered fault mode, the
  next inspection's plan);
* ``emaphm fleet report --workers 0`` into a new folder (the prognosis, the figures and
  the pages of the actuator).

Each row gives the wall and CPU time and the peak resident memory of that process
(``os.wait4``), beside the load average before and after (the machine is shared).
``--base REV`` runs the same commands with emaphm at git revision ``REV`` (its ``src/``
extracted by ``git archive``), alternating with this tree's, on the sizes up to
``--base-max`` (the quadratic code passed 3 GB at 10,000).
"""

from __future__ import annotations

import argparse
import datetime as _dt
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _machine import machine as _machine  # the scripts run from benchmarks/
from _versions import extract_src

ROOT = Path(__file__).resolve().parent
#: The commit before the prognosis became linear in the inspections.
BASE = "c9a96f0"


def _history(db: Path, n: int, seed: int = 0) -> None:
    import numpy as np

    from emaphm.prognosis.history import HealthHistory

    rng = np.random.default_rng(seed)
    with HealthHistory(db) as h:
        h.register("EMA-1")
        for i in range(n):
            k = np.array([0.05 + 0.3 * i / n, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5, 0.5])
            k += rng.normal(0.0, 0.007, 8) * np.r_[1, 1, 1, 1, 1, 1, 0, 1]
            if rng.random() < 0.005:
                k[0] += 0.2
                k[1] += 0.1
            h.add("EMA-1", 24.0 * i, np.clip(k, 0.0, 1.0))


def _run(args: list[str], src: Path | None = None) -> dict:
    """``emaphm ARGS`` in a fresh process: wall and CPU seconds, peak memory [MB] (its own
    and its children's), the load average around it."""
    env = dict(os.environ)
    if src is not None:
        env["PYTHONPATH"] = str(src)
    load0 = os.getloadavg()[0]
    t0 = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-m", "emaphm.cli", *args], env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    err = proc.stderr.read().decode() if proc.stderr else ""
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode != 0:
        raise RuntimeError(f"emaphm {' '.join(args)} failed ({proc.returncode}): {err[-500:]}")
    return {"wall_s": wall, "cpu_s": usage.ru_utime + usage.ru_stime,
            "rss_mb": usage.ru_maxrss / 1024.0, "load_before": load0,
            "load_after": os.getloadavg()[0]}


def measure(sizes: list[int], base: str | None, base_max: int) -> list[dict]:
    rows = []
    with tempfile.TemporaryDirectory(prefix="emaphm-long-history-") as tmp:
        tmp = Path(tmp)
        src = extract_src(base, tmp) if base else None
        for n in sizes:
            db = tmp / f"h{n}.sqlite"
            t0 = time.perf_counter()
            _history(db, n)
            record_s = time.perf_counter() - t0
            trees = [("this tree", None)] + ([(f"emaphm {base}", src)]
                                             if src is not None and n <= base_max else [])
            for name, code in trees:
                for what, args in (
                        ("prognose", ["prognose", "EMA-1", "--db", str(db), "--json"]),
                        ("fleet report", ["fleet", "report", "--db", str(db), "--out",
                                          str(tmp / f"site{n}-{len(rows)}"), "--workers", "0",
                                          "--quiet"])):
                    r = _run(args, code)
                    rows.append({"inspections": n, "code": name, "command": what,
                                 "record_s": record_s, **r})
                    print(f"{n:>6} {name:>16} {what:>12}: {r['wall_s']:.2f} s wall, "
                          f"{r['cpu_s']:.2f} s CPU, {r['rss_mb']:.0f} MB", flush=True)
    return rows


def write(rows: list[dict], started: str, base: str | None) -> str:
    lines = [f"## Prognosis of one actuator as its history grows (`benchmarks/bench_long_history.py`)",
             "",
             f"Run {started} on {_machine('scipy')}. One actuator inspected every 24 h, "
             "friction growing (k1 0.05 to 0.35, noise 0.007 per component, one inspection "
             "in 200 in a wrong basin); each command in a fresh process, `fleet report "
             "--workers 0`. Peak memory is the process's resident set (`os.wait4`). Target "
             "(issue 37 item 9): 10,000 inspections in under 10 s and 500 MB."
             + (f" `emaphm {base}` is the code before (a leave-one-out refit per inspection "
                "and an onset regressor matrix of (2n, n)), run alternately on the same "
                "histories." if base else ""),
             "",
             "| inspections | code | command | wall [s] | CPU [s] | peak memory [MB] | "
             "load before / after |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['inspections']:,} | {r['code']} | {r['command']} | {r['wall_s']:.2f} "
                     f"| {r['cpu_s']:.2f} | {r['rss_mb']:.0f} | {r['load_before']:.2f} / "
                     f"{r['load_after']:.2f} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", default="100,300,1000,3000,10000")
    ap.add_argument("--base", default=None, help=f"git revision to compare with (e.g. {BASE})")
    ap.add_argument("--base-max", type=int, default=3000)
    args = ap.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    started = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    rows = measure(sizes, args.base, args.base_max)
    out = ROOT / "results"
    (out / "long_history.json").write_text(json.dumps(
        {"started": started, "machine": _machine("scipy"), "base": args.base, "rows": rows},
        indent=1) + "\n")
    text = write(rows, started, args.base)
    (out / "long_history.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
