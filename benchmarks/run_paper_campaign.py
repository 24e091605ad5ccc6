"""Run the paper's campaign (DE, PSO, GWO x 11 scenarios x 10 runs = 330 identifications),
time it, and write its report.

    python benchmarks/run_paper_campaign.py                       # all cores, 330 runs
    python benchmarks/run_paper_campaign.py --runs 1 --scenarios friction-low,multiple \\
        --store /tmp/check.sqlite --out /tmp/check-report          # a quick check

Default settings throughout: each algorithm's own stopping rule, the polish of
``identify``, realistic sensor noise (``emaphm.simulate.DEFAULT_SENSORS``), master seed
2023. The store is resumable: if the script is stopped, run it again with the same
``--store`` (the wall time printed then covers only the second part; the timing line
says so).

At the end it prints a Markdown snippet for BENCHMARKS.md (wall time, machine, versions,
per-run times) and writes it to ``<out>/timing.md`` beside the report.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def main(argv: list[str] | None = None) -> int:
    from emaphm import __version__
    from emaphm.campaign import (CampaignStore, LocalExecutor, ProgressLine, paper_spec, run_campaign,
                                 write_report)
    from emaphm.campaign.runner import CampaignInterrupted
    from emaphm.campaign.spec import parse_scenarios

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--store", default=str(ROOT / "paper_campaign.sqlite"),
                    help="result store (default: paper_campaign.sqlite at the repository root)")
    ap.add_argument("--out", default=str(ROOT / "docs" / "results"), help="report folder (default docs/results)")
    ap.add_argument("--runs", type=int, default=10)
    ap.add_argument("--scenarios", default="paper", help="default: the paper's 11")
    ap.add_argument("--seed", type=int, default=2023, help="master seed (default 2023)")
    ap.add_argument("--workers", type=int, default=None, help="default: all cores")
    args = ap.parse_args(argv)

    spec = paper_spec(runs=args.runs, master_seed=args.seed, scenarios=parse_scenarios(args.scenarios))
    executor = LocalExecutor(args.workers)
    print(f"{spec.n_runs} runs on {executor.describe()}; store {args.store}", file=sys.stderr)
    t0 = time.perf_counter()
    try:
        summary = run_campaign(spec, args.store, executor, ProgressLine(sys.stderr))
    except CampaignInterrupted as exc:
        print(f"interrupted: {exc}; run the same command again to resume", file=sys.stderr)
        return 130
    wall = time.perf_counter() - t0
    if not summary.finished:
        print(f"{summary.missing} runs missing or failed; run again to retry them", file=sys.stderr)
        return 1

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    paths = write_report(args.store, out)
    with CampaignStore.open(args.store, readonly=True) as st:
        results = st.results()
    el = np.array([r.elapsed_s for r in results])
    by_alg = {a.label: np.array([r.elapsed_s for r in results if r.algorithm == a.label])
              for a in spec.algorithms}
    import numba
    import scipy

    complete = summary.skipped == 0
    lines = [
        f"## Paper campaign: {spec.n_runs} runs ({len(spec.scenarios)} scenarios x "
        f"{len(spec.algorithms)} algorithms x {spec.runs}) "
        f"({time.strftime('%Y-%m-%d %H:%M', time.gmtime())} UTC, `benchmarks/run_paper_campaign.py`)",
        "",
        f"- wall time: **{wall / 60:.1f} min** ({wall:.0f} s) on {executor.workers} worker processes"
        + ("" if complete else f" (resumed: {summary.skipped} runs were already stored; this is the "
                               "wall time of the last part only)"),
        f"- sum of the identification times: {el.sum() / 60:.1f} min; per run mean {el.mean():.2f} s, "
        f"median {np.median(el):.2f} s, max {el.max():.2f} s",
        "- per algorithm, mean time per run: "
        + ", ".join(f"{a} {v.mean():.2f} s" for a, v in by_alg.items()),
        f"- machine: {platform.processor() or platform.machine()}, {os.cpu_count()} logical cores, "
        f"{platform.system()} {platform.release()}",
        f"- software: emaphm {__version__}, Python {platform.python_version()}, numpy {np.__version__}, "
        f"numba {numba.__version__}, scipy {scipy.__version__}",
        f"- command: `python benchmarks/run_paper_campaign.py --runs {args.runs} --seed {args.seed}"
        + (f" --scenarios {args.scenarios}" if args.scenarios != "paper" else "") + "`",
        f"- report: {', '.join(p.name for p in paths)}",
        "",
    ]
    text = "\n".join(lines)
    (out / "timing.md").write_text(text, encoding="utf-8")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
