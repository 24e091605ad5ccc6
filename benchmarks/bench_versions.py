"""The same workload on two versions of emaphm, side by side: kernel and identification CPU.

Used to check that a refactor keeps the speed (issue 20: the monitoring model's kernel
within 3 %, an identification's CPU time within 5 % of before). The base version's
``src/`` is extracted from git (``git archive``) into a temporary folder; each round runs
the workload once on the base and once on the working tree, in fresh processes (the
kernels of each are compiled once into their own cache first), alternating, so that both
see the same machine load. Reported: the median CPU time of each measurement over the
rounds and the ratio now / base.

Workload (fixed, seeded): the SIMD kernel's fitness of 48 candidates on the diagnostic
profile (ns per candidate-step), the scalar kernel on one candidate (a least-squares
residual), identifications of reference-plant traces (friction-high, backlash-low,
turn-short-15pct, gain-low, eccentricity-high, multiple; seed 1) with ``lsq`` and, on two
of them, with the paper's PSO at its defaults, and ``emaphm diagnose`` of five healthy
plant traces in the process (the whole verdict: on a healthy trace no fault mode's
hypothesis runs; "same k" compares the last verdict). Every measured trace is identified
once after a warm-up on another trace: 967ef73 kept each thread's last objectives in a
hidden cache (removed by issue 20), so a trace seen before is a cache hit there and not
here, which is not the cost of one identification.

Run: ``python benchmarks/bench_versions.py [--base REV] [--rounds N]``; writes
``benchmarks/results/versions.md``.
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
RESULTS = ROOT / "benchmarks" / "results" / "versions.md"

#: The commit the identification golden file was recorded at, before the renovation.
BASE = "967ef73"

WORKLOAD = r'''
import json, sys, time
import numpy as np
from emaphm.identify import identify
from emaphm.models.monitoring import MonitoringModel
from emaphm.simulate import simulate, DEFAULT_SENSORS

out = {}
mm = MonitoringModel(fault_model="physical")
K = np.random.default_rng(0).random((48, 8)) * np.array([1, 1, 0.1, 0.1, 0.1, 1, 1, 1])
K[:, 6:] = np.clip(K[:, 6:], 0.2, 0.8)
target = mm.simulate_population(K[:1]).i_abc[0]
w = np.full_like(target, 1e-4)
mm.weighted_sse(K, target, w)
ts = []
for _ in range(7):
    t = time.process_time(); mm.weighted_sse(K, target, w); ts.append(time.process_time() - t)
out["simd_ns_per_candidate_step"] = float(np.median(ts)) / (48 * mm.t.size) * 1e9
one = K[:1]
mm.weighted_sse(one, target, w)
ts = []
for _ in range(15):
    t = time.process_time(); mm.weighted_sse(one, target, w); ts.append(time.process_time() - t)
out["scalar_ns_per_step"] = float(np.median(ts)) / mm.t.size * 1e9
traces = {s: simulate(scenario=s, sensors=DEFAULT_SENSORS, seed=1)
          for s in ("friction-high", "backlash-low", "turn-short-15pct", "gain-low",
                    "eccentricity-high", "multiple")}
# warm up on a trace that is not measured: 967ef73 kept each thread's last objectives
# (identify's hidden cache, removed by issue 20), so a measured trace it had seen before
# would be a cache hit there and a fresh build here
warm = simulate(scenario="nominal", sensors=DEFAULT_SENSORS, seed=2)
identify(warm, "lsq", seed=0); identify(warm, "pso", seed=0)
for s, tr in traces.items():
    t = time.process_time(); r = identify(tr, "lsq", seed=0)
    out[f"lsq {s}"] = time.process_time() - t
    out[f"lsq {s} k"] = [float(x) for x in r.k]
for s in ("friction-high", "gain-low"):
    t = time.process_time(); r = identify(traces[s], "pso", seed=0)
    out[f"pso {s}"] = time.process_time() - t
    out[f"pso {s} k"] = [float(x) for x in r.k]
# emaphm diagnose of a healthy plant trace, in this process: the whole verdict's cost
import contextlib, io, os, tempfile
from emaphm.cli import main
from emaphm.traces import write_trace
with tempfile.TemporaryDirectory() as tmp:
    paths = [os.path.join(tmp, f"healthy{seed}.parquet") for seed in range(7, 13)]
    for seed, path in zip(range(7, 13), paths):
        write_trace(simulate(scenario="nominal", sensors=DEFAULT_SENSORS, seed=seed), path)
    with contextlib.redirect_stdout(io.StringIO()):
        main(["diagnose", paths[0], "--json", "--quiet"])             # warm-up, not measured
    ts = []
    for path in paths[1:]:                  # each trace once: no cache of 967ef73's can hit
        with contextlib.redirect_stdout(io.StringIO()) as buf:
            t = time.process_time(); main(["diagnose", path, "--json", "--quiet"])
            ts.append(time.process_time() - t)
    out["diagnose healthy (CLI, in process)"] = float(np.median(ts))
    out["diagnose healthy (CLI, in process) k"] = json.loads(buf.getvalue())["verdict"]
json.dump(out, sys.stdout)
'''


def _run(src: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=str(src), OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    r = subprocess.run([sys.executable, "-c", WORKLOAD], env=env, capture_output=True, text=True,
                       timeout=1800, check=False)
    if r.returncode != 0:
        raise RuntimeError(f"workload on {src} failed:\n{r.stderr[-3000:]}")
    return json.loads(r.stdout)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", default=BASE, help=f"git revision to compare with (default {BASE})")
    ap.add_argument("--rounds", type=int, default=5)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        base_src = extract_src(args.base, Path(tmp))
        now_src = ROOT / "src"
        _run(base_src), _run(now_src)                       # compile both kernel caches
        rounds = {"base": [], "now": []}
        for i in range(args.rounds):
            for name, src in (("base", base_src), ("now", now_src)):
                rounds[name].append(_run(src))
            print(f"round {i + 1}/{args.rounds}", flush=True)
    keys = [k for k in rounds["now"][0] if not k.endswith(" k")]
    rows = []
    for k in keys:
        b = float(np.median([r[k] for r in rounds["base"]]))
        n = float(np.median([r[k] for r in rounds["now"]]))
        same = "" if k.startswith("simd") or k.startswith("scalar") else (
            "yes" if rounds["base"][0][k + " k"] == rounds["now"][0][k + " k"] else "NO")
        rows.append((k, b, n, n / b, same))
    lsq = [r for r in rows if r[0].startswith("lsq")]
    total_b, total_n = sum(r[1] for r in lsq), sum(r[2] for r in lsq)
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                          text=True).stdout.strip()
    lines = [f"## Two versions side by side: {args.base} and {head}\n",
             f"Machine: {machine('numba')}; load average {os.getloadavg()[0]:.2f} at the end; "
             f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC. {args.rounds} rounds, each the workload once on each version "
             "in a fresh process, alternating; medians of the rounds; CPU time "
             "(`benchmarks/bench_versions.py`).\n",
             "| measurement | base | now | now / base | same k |", "|---|---|---|---|---|"]
    for k, b, n, ratio, same in rows:
        unit = "ns" if k.startswith(("simd", "scalar")) else "s"
        fmt = (lambda x: f"{x:.1f} {unit}") if unit == "ns" else (lambda x: f"{x:.3f} {unit}")
        lines.append(f"| {k} | {fmt(b)} | {fmt(n)} | {ratio:.3f} | {same} |")
    lines.append(f"| lsq, the six traces together | {total_b:.3f} s | {total_n:.3f} s | "
                 f"{total_n / total_b:.3f} | |")
    RESULTS.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
