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

The working tree runs each trace twice: with its whole log (the recorded voltages) and
with its current references alone (``i_d_ref, i_q_ref``: the recorded current references).

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
from _versions import extract_src  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "drive_cost.md"
SCENARIOS = ("nominal", "friction-high", "backlash-low", "turn-short-15pct", "gain-low",
             "eccentricity-high", "multiple")

WORKLOAD = r'''
import json, sys, time
from dataclasses import replace
from emaphm.identify import identify
from emaphm.traces import read_trace
folder, names, keep = sys.argv[1], sys.argv[2].split(","), sys.argv[3]
traces = {n: read_trace(f"{folder}/{n}.parquet") for n in names + ["warm"]}
if keep:                                     # the drive's log reduced to these signals
    traces = {n: replace(t, drive={c: t.drive[c] for c in keep.split(",")})
              for n, t in traces.items()}
identify(traces["warm"], "lsq", seed=0)
out = {}
for n in names:
    t = time.process_time(); r = identify(traces[n], "lsq", seed=0)
    out[n] = time.process_time() - t
    out[n + " evaluations"] = int(r.evaluations)
    out[n + " path"] = getattr(r, "drive_model", "modelled controller")
json.dump(out, sys.stdout)
'''


#: The working tree's drive paths, by the drive signals each trace keeps ("": all of them).
PATHS = {"now": "", "now-refs": "i_d_ref,i_q_ref"}


def _run(src: Path, folder: Path, keep: str = "") -> dict:
    env = dict(os.environ, PYTHONPATH=str(src), OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1",
               NUMBA_NUM_THREADS="1")
    r = subprocess.run([sys.executable, "-c", WORKLOAD, str(folder), ",".join(SCENARIOS), keep],
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
        base_src = extract_src(args.base, Path(tmp))
        now_src = ROOT / "src"
        _run(base_src, folder), _run(now_src, folder)          # compile both caches
        rounds: dict[str, list[dict]] = {"base": [], **{p: [] for p in PATHS}}
        for i in range(args.rounds):
            rounds["base"].append(_run(base_src, folder))
            for name, keep in PATHS.items():
                rounds[name].append(_run(now_src, folder, keep))
            print(f"round {i + 1}/{args.rounds}", flush=True)
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                          text=True).stdout.strip()
    lines = [f"## Identification from what the drive recorded beside {args.base}'s of the same "
             "traces\n",
             f"Machine: {machine('numba')}; load average {os.getloadavg()[0]:.2f} at the end; "
             f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC; {head}. "
             f"{args.rounds} rounds, each every trace once on each version in a fresh process, "
             "alternating; medians of the rounds; CPU time, one thread "
             "(`benchmarks/bench_drive_cost.py`).\n",
             f"| trace | {args.base}: modelled controller | now: recorded voltages | now / base "
             "| now: recorded current references | now / base | evaluations (base, voltages, "
             "references) |", "|---|---|---|---|---|---|---|"]
    med = {p: {n: float(np.median([r[n] for r in rounds[p]])) for n in SCENARIOS} for p in rounds}
    for name in SCENARIOS:
        b, n, c = med["base"][name], med["now"][name], med["now-refs"][name]
        lines.append(f"| {name} | {b:.3f} s | {n:.3f} s | {n / b:.2f} | {c:.3f} s | {c / b:.2f} | "
                     + ", ".join(str(rounds[p][0][name + " evaluations"]) for p in rounds) + " |")
    tot = {p: sum(med[p].values()) for p in med}
    lines.append(f"| all seven | {tot['base']:.3f} s | {tot['now']:.3f} s | "
                 f"{tot['now'] / tot['base']:.2f} | {tot['now-refs']:.3f} s | "
                 f"{tot['now-refs'] / tot['base']:.2f} | |")
    paths = {rounds[p][0][n + " path"] for p in PATHS for n in SCENARIOS}
    lines.append(f"\nPaths of the working tree: {', '.join(sorted(paths))}.")
    RESULTS.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
