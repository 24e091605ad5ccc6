"""The whole prognosis loop on a simulated degradation: simulate, diagnose, record, predict.

A fault grows along a chosen law (``emaphm.prognosis.DEGRADATION_SCENARIOS``); at
each inspection the reference model (switching PWM, 20 mA sensor noise) records a
trace, the identification (least squares by default, or the paper's PSO, DE, GWO:
``--algorithm``) finds k with an interval, the inspection goes into a health
history (SQLite), and the remaining useful life is predicted from the inspections
seen so far.

    python examples/degradation_demo.py [--scenario short-circuit-growth]
        [--inspections 8] [--algorithm lsq] [--budget N] [--seed 0] [--out-dir DIR]
        [--synthetic]

The identification's settings are one :class:`emaphm.identify.IdentificationConfig`
(its algorithm and budget: evaluations per identification, default the algorithm's own
stopping rule). ``--synthetic`` skips the simulations and identifications (the true k
plus identification-level noise), for a run of a second. Every random draw flows from
``--seed``. The same loop is ``emaphm demo-degradation``. The tests run it with
``--inspections 3 --budget 150`` (a budget that small identifies roughly; it shows the
loop, not its accuracy).
"""

from __future__ import annotations

import argparse
import math
import tempfile
from pathlib import Path

import numpy as np

from emaphm.identify import ALGORITHM_NAMES, DEFAULT_ALGORITHM, IdentificationConfig
from emaphm.prognosis import (DEGRADATION_SCENARIOS, HealthHistory, degradation_scenario,
                              inspection_times, prognose, record_inspection,
                              simulate_degradation, synthetic_k_history)
from emaphm.prognosis.metrics import alpha_lambda, coverage
from emaphm.prognosis.plots import plot_alpha_lambda, plot_history, plot_prognosis
from emaphm.prognosis.trends import MIN_INSPECTIONS, RULTrack


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scenario", default="short-circuit-growth", choices=list(DEGRADATION_SCENARIOS))
    ap.add_argument("--inspections", type=int, default=8)
    ap.add_argument("--algorithm", default=DEFAULT_ALGORITHM, choices=ALGORITHM_NAMES,
                    help="identification algorithm (default: least squares)")
    ap.add_argument("--budget", type=int, default=None,
                    help="evaluations per identification (default: the algorithm's own rule)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out-dir", help="write the history, prognosis and alpha-lambda figures here")
    ap.add_argument("--synthetic", action="store_true")
    args = ap.parse_args(argv)

    sc = degradation_scenario(args.scenario)
    times = inspection_times(sc.eol, args.inspections)
    with tempfile.TemporaryDirectory() as tmp:
        with HealthHistory(Path(tmp) / "history.sqlite") as history:
            history.register("EMA-DEMO", description=f"simulated {args.scenario}")
            if args.synthetic:                       # 1. the k an identification would give
                for t, k in zip(times, synthetic_k_history(sc, times, seed=args.seed)):
                    history.add("EMA-DEMO", float(t), k, spread_method="synthetic")
            else:                                    # 1. simulate, 2. diagnose and record
                config = IdentificationConfig(algorithm=args.algorithm, budget=args.budget)
                run = simulate_degradation(sc, times, seed=args.seed)
                for t, trace in zip(times, run.traces):
                    ins, _ = record_inspection(history, "EMA-DEMO", trace, float(t), seed=args.seed,
                                     config=config)
                    print(f"t = {t:6.0f} h  identified {sc.indicator} = "
                          f"{ins.k[_component(sc)]:.4f}  verdict "
                          f"{'healthy' if ins.healthy else 'FAULTY'}")
            data = history.data("EMA-DEMO")

    # 3. predict at every inspection from the third on, with what was known then
    preds = []
    for i in range(MIN_INSPECTIONS, data.n + 1):
        prog = prognose(data.times[:i], data.K[:i], seed=args.seed, indicators=(sc.indicator,),
                        actuator="EMA-DEMO")
        p = prog.predictions[sc.indicator]
        preds.append(p)
        print(f"after {i:2d} inspections (t = {p.t_now:6.0f} h): RUL median {p.median:7.0f} h, "
              f"90% [{p.lo:.0f}, {p.hi:.0f}], true {sc.eol - p.t_now:.0f} h")
    track = RULTrack(sc.indicator, sc.threshold, preds[0].level, times[MIN_INSPECTIONS - 1:],
                     np.arange(MIN_INSPECTIONS, data.n + 1), np.array([p.median for p in preds]),
                     np.array([p.lo for p in preds]), np.array([p.hi for p in preds]),
                     np.stack([p.samples for p in preds]))
    late = track.times >= 0.5 * sc.eol
    rul_true = sc.eol - track.times
    al = alpha_lambda(track.times, track.samples, sc.eol, alpha=0.2)
    result = {"scenario": args.scenario,
              "coverage_from_midlife": coverage(rul_true[late], track.lo[late], track.hi[late]),
              "abs_error": [float(abs(m - r)) if math.isfinite(m) else None
                            for m, r in zip(track.median, rul_true)],
              "alpha_lambda_passed": al.passed.tolist()}
    print(f"coverage of the true RUL from mid-life: {result['coverage_from_midlife']:.2f}; "
          f"alpha-lambda (alpha 0.2) passed at lambda = {al.lambdas[al.passed].tolist()}")
    if args.out_dir:
        out = Path(args.out_dir)
        plot_history(data, path=out / f"{args.scenario}-history.png")
        plot_prognosis(prog, indicators=(sc.indicator,), eol_true={sc.indicator: sc.eol},
                       path=out / f"{args.scenario}-prognosis.png")
        plot_alpha_lambda([track], sc.eol, title=args.scenario,
                          path=out / f"{args.scenario}-alpha-lambda.png")
        print(f"wrote the figures to {out}")
    return result


def _component(sc) -> int:
    from emaphm.prognosis.thresholds import INDICATOR_COMPONENT

    return INDICATOR_COMPONENT[sc.indicator]


if __name__ == "__main__":
    main()
