"""A batch of traces on worker processes against the same calls in a row (issue 34, item 6).

Eight plant traces (scenarios and seeds of their own), each identified by PSO on a budget
sized for at least a second of work; the same identifications

1. in a row in this process (warm: one identification before the clock starts),
2. as one batch on ``--workers`` processes: this one and ``workers - 1`` started for it
   (``identify(traces, workers=2)``,
   the pool's start and the workers' warm-up included), and
3. as a second batch on the same, warm, workers,

then (1) again; the serial time is the mean of its two runs. Each batch must give the
serial results bit for bit (checked). Target (issue 34): the first batch in at most 0.6x
the serial wall time.

Run: ``python benchmarks/bench_batch.py [--traces 8] [--workers 2] [--budget 15000]``
-> ``benchmarks/results/batch_identify.md`` (then ``python benchmarks/collect.py``).
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import time
from pathlib import Path

import numpy as np

from _machine import machine

SCENARIOS = ("friction-high", "backlash-high", "short-circuit-low", "eccentricity-high",
             "gain-low", "nominal", "friction-low", "multiple")
OUT = Path(__file__).parent / "results" / "batch_identify.md"


def _same(a: list, b: list) -> bool:
    return all(np.array_equal(x.k, y.k) and x.fitness == y.fitness and x.evaluations == y.evaluations
               for x, y in zip(a, b))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--traces", type=int, default=8)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--budget", type=int, default=15000, help="PSO evaluations per trace")
    ap.add_argument("--out", type=Path, default=OUT)
    args = ap.parse_args()

    from emaphm import batch
    from emaphm.identify import IdentificationConfig, identify
    from emaphm.simulate import DEFAULT_SENSORS, simulate

    traces = [simulate(scenario=SCENARIOS[i % len(SCENARIOS)], sensors=DEFAULT_SENSORS, seed=i + 1)
              for i in range(args.traces)]
    config = IdentificationConfig("pso", budget=args.budget)
    identify(traces[0], config, seed=0)                       # this process warm
    load0 = os.getloadavg()

    def serial() -> tuple[float, list]:
        t0 = time.perf_counter()
        out = [identify(t, config, seed=0) for t in traces]
        return time.perf_counter() - t0, out

    s1, ref = serial()
    batch.close_pools()
    t0 = time.perf_counter()
    cold = identify(traces, config, seed=0, workers=args.workers)
    t_cold = time.perf_counter() - t0
    t0 = time.perf_counter()
    warm = identify(traces, config, seed=0, workers=args.workers)
    t_warm = time.perf_counter() - t0
    batch.close_pools()
    s2, again = serial()
    load1 = os.getloadavg()
    t_serial = 0.5 * (s1 + s2)
    per = t_serial / len(traces)
    same = _same(cold, ref) and _same(warm, ref) and _same(again, ref)
    when = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    lines = [
        "## Batches of traces on worker processes (`benchmarks/bench_batch.py`)",
        "",
        f"Run {when} on {machine('numba')}; load average {load0[0]:.2f} before, {load1[0]:.2f} "
        f"after (the machine is shared). {len(traces)} plant traces, PSO on a budget of "
        f"{args.budget} evaluations each ({per:.2f} s of work a trace in a row); "
        f"`identify(traces, workers={args.workers})`. Target (issue 34): the first batch, the "
        "pool's start and warm-up included, in at most 0.6x the calls in a row. Results the "
        f"same bit for bit as in a row: {'yes' if same else 'NO'}.",
        "",
        "| how | wall [s] | against in a row |",
        "|---|---|---|",
        f"| {len(traces)} calls in a row (mean of {s1:.2f} and {s2:.2f}) | {t_serial:.2f} | 1.00 |",
        f"| one batch, this process and {args.workers - 1} worker(s) started for it | {t_cold:.2f} | "
        f"{t_cold / t_serial:.2f} |",
        f"| the next batch, the same warm worker(s) | {t_warm:.2f} | {t_warm / t_serial:.2f} |",
        "",
    ]
    text = "\n".join(lines)
    print(text)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
