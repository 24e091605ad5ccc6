"""The cost of identifying from recorded voltages, beside today's identification of the
same traces at a base revision (issue 32: "no slower than today's identification, at
216ed3d, of the same actuator's traces on emaphm's own firmware").

The traces: the paper's scenarios the versions benchmark times (friction-high,
backlash-low, turn-short-15pct, gain-low, eccentricity-high, multiple) and a healthy one,
simulated on the reference plant with the drive's log (emaphm's own firmware, the preset,
seed 1), written to Parquet once. Each round identifies every trace with ``lsq`` (seed 0)
once in a fresh process of the base revision (its ``src/`` extracted with ``git archive``:
the modelled controller, which ignores the drive's columns) and once in one of the working
tree (the recorded voltages, the default for a trace that has them), alternating, after a
warm-up identification of another trace in each process; CPU time (``time.process_time``),
single-threaded. Reported: the median over the rounds of each trace's CPU time and the
ratio now / base, and the sum over the traces.

Run: ``python benchmarks/bench_drive_cost.py [--base 216ed3d] [--rounds 5]`` ->
``benchmarks/results/drive_cost.md``.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import machine  # noqa: E402
from bench_versions import _extract  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "drive_cost.md"
SCENARIOS = ("nominal", "friction-high", "backlash-low", "turn-short-15pct", "gain-low",
             "eccentricity-high", "multiple")

WORKLOAD = r'''
import json, sys, time
from emaphm.identify import identify
from emaphm.traces import read_trace
folder, names = sys.argv[1], sys.argv[2].split(",")
traces = {n: read_trace(f"{folder}/{n}.parquet") for n in names + ["warm"]}
identify(traces["warm"], "lsq", seed=0)
out = {}
for n in names:
    t = time.process_time(); r = identify(traces[n], "lsq", seed=0)
    out[n] = time.process_time() - t
    out[n + " evaluations"] = int(r.evaluations)
    out[n + " path"] = getattr(r, "drive_model", "modelled controller")
json.dump(out, sys.stdout)
'''


def _run(src: Path, folder: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=str(src), OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1",
               NUMBA_NUM_THREADS="1")
    r = subprocess.run([sys.executable, "-c", WORKLOAD, str(folder), ",".join(SCENARIOS)],
                       env=env, capture_output=True, text=True, timeout=1800, check=False)
    if r.returncode != 0:
        raise RuntimeError(f"workload on {src} failed:\n{r.stderr[-3000:]}")
    return json.loads(r.stdout)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", default="216ed3d")
    ap.add_argument("--rounds", type=int, default=5)
    args = ap.parse_args()
    from emaphm.simulate import DEFAULT_SENSORS, simulate
    from emaphm.traces import write_trace

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "traces"
        folder.mkdir()
        for name in SCENARIOS:
            write_trace(simulate(scenario=name, sensors=DEFAULT_SENSORS, seed=1, drive_signals=True),
                        folder / f"{name}.parquet")
        write_trace(simulate(scenario="nominal", sensors=DEFAULT_SENSORS, seed=2, drive_signals=True),
                    folder / "warm.parquet")
        base_src = _extract(args.base, Path(tmp))
        now_src = ROOT / "src"
        _run(base_src, folder), _run(now_src, folder)          # compile both caches
        rounds: dict[str, list[dict]] = {"base": [], "now": []}
        for i in range(args.rounds):
            for name, src in (("base", base_src), ("now", now_src)):
                rounds[name].append(_run(src, folder))
            print(f"round {i + 1}/{args.rounds}", flush=True)
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                          text=True).stdout.strip()
    lines = [f"## Identification from recorded voltages beside {args.base}'s of the same traces\n",
             f"Machine: {machine('numba')}; load average {os.getloadavg()[0]:.2f} at the end; "
             f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC; {head}. "
             f"{args.rounds} rounds, each every trace once on each version in a fresh process, "
             "alternating; medians of the rounds; CPU time, one thread "
             "(`benchmarks/bench_drive_cost.py`).\n",
             f"| trace | {args.base}: modelled controller | now: recorded voltages | now / base "
             "| evaluations (base, now) |", "|---|---|---|---|---|"]
    total_b = total_n = 0.0
    for name in SCENARIOS:
        b = float(np.median([r[name] for r in rounds["base"]]))
        n = float(np.median([r[name] for r in rounds["now"]]))
        total_b += b
        total_n += n
        lines.append(f"| {name} | {b:.3f} s | {n:.3f} s | {n / b:.2f} | "
                     f"{rounds['base'][0][name + ' evaluations']}, "
                     f"{rounds['now'][0][name + ' evaluations']} |")
    lines.append(f"| all seven | {total_b:.3f} s | {total_n:.3f} s | {total_n / total_b:.2f} | |")
    paths = {rounds["now"][0][n + " path"] for n in SCENARIOS}
    lines.append(f"\nPath of the working tree: {', '.join(sorted(paths))}.")
    RESULTS.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
