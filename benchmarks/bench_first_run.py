"""The quick start's first run (issue 36): ``emaphm diagnose --scenario friction-high`` in a
fresh process with an empty kernel cache, then again with the cache it left.

Each round runs, alternating, the command with the kernels compiled as the job needs them
and in child processes on the other core (``emaphm.models.warm``, the default) and with
``EMAPHM_PREFETCH=0`` (one process compiles everything it runs), each into its own empty
``EMAPHM_CACHE_DIR``; then the command once more on the filled cache (a later process).
Wall time of the whole command (imports, the reference plant's simulation, the
identification, the verdict and the figure included) and the CPU time of it and its
children.

Run: ``python benchmarks/bench_first_run.py [--rounds 2]`` ->
``benchmarks/results/first_run.md``.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _machine import machine

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(__file__).parent / "results"
COMMAND = ["diagnose", "--scenario", "friction-high", "--plot"]


def run(cache: Path, prefetch: bool, plot: Path) -> tuple[float, float]:
    """``(wall s, CPU s of the command and its children)``."""
    env = dict(os.environ, EMAPHM_CACHE_DIR=str(cache), EMAPHM_PREFETCH="1" if prefetch else "0")
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    done = subprocess.run([str(Path(sys.executable).with_name("emaphm")), *COMMAND, str(plot)], env=env,
                          capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SystemExit(f"the command failed: {done.stderr[-2000:]}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rounds", type=int, default=2)
    args = ap.parse_args()
    rows: dict[str, list[tuple[float, float]]] = {}
    with tempfile.TemporaryDirectory(prefix="emaphm-first-run-") as tmp:
        plot = Path(tmp) / "diagnosis.png"
        for r in range(args.rounds):
            for prefetch in (True, False):
                cache = Path(tmp) / f"cache-{r}-{int(prefetch)}"
                shutil.rmtree(cache, ignore_errors=True)
                cache.mkdir()
                label = "children compile ahead" if prefetch else "one process (EMAPHM_PREFETCH=0)"
                rows.setdefault(f"first run, {label}", []).append(run(cache, prefetch, plot))
                rows.setdefault(f"next run, {label}", []).append(run(cache, prefetch, plot))
                print(r, label, rows[f"first run, {label}"][-1], rows[f"next run, {label}"][-1],
                      flush=True)
    load = os.getloadavg()[0]
    out = ["## The quick start's first run (`benchmarks/bench_first_run.py`)", "",
           f"Machine: {machine('numba')}; load average {load:.2f} at the end; "
           f"{_dt.datetime.now(_dt.timezone.utc):%Y-%m-%d %H:%M} UTC. `emaphm "
           f"{' '.join(COMMAND)} diagnosis.png` in a fresh process, {args.rounds} rounds "
           "alternating the two settings, each first run on an empty kernel cache of its own "
           "and the next run on the cache it left; medians (wall time of the whole command; "
           "CPU time of it and its child processes).", "",
           "| run | wall s | CPU s |", "|---|---|---|"]
    for label, xs in rows.items():
        out.append(f"| {label} | {statistics.median(w for w, _ in xs):.1f} | "
                   f"{statistics.median(c for _, c in xs):.1f} |")
    text = "\n".join(out) + "\n"
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "first_run.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
