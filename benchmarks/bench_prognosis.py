"""RUL statistics of the prognosis layer, and the figures of ``docs/prognosis.md``.

Two kinds of degradation histories, each with 10 inspections evenly spaced from
t = 0 to 95 % of the life (true end of life 1000 h), predictions made at every
inspection from the third on with the inspections seen so far:

* **synthetic** (``--synthetic-histories``, default 200 per scenario): the true
  k plus Gaussian noise of 0.007 per component (the identification's error
  level), no identification: statistics of the trend and RUL maths;
* **real** (``--real-histories``, default 3 per scenario): reference-plant
  traces (switching PWM, Stribeck friction, 20 mA current noise, 12-bit ADC), the
  unit first calibrated on two healthy traces (``history calibrate``; off with
  ``--no-commission``), each inspection identified by the default pipeline and
  recorded in a health history: the whole loop.

Reported per scenario and inspection: coverage of the true RUL by the 90 %
interval, median |RUL error|, alpha-lambda (alpha 0.2, beta 0.5) pass rate, and
the prognostic horizon (alpha 0.1). ``--calibrate`` also measures the
per-component identification error behind
:data:`emaphm.prognosis.uncertainty.IDENTIFICATION_ERROR_P90`.

Run: ``python benchmarks/bench_prognosis.py [--workers 2] [--calibrate]``
-> ``benchmarks/results/prognosis.md``, ``prognosis.json`` and
``docs/figures/prognosis/*.png``.
"""

from __future__ import annotations

import os

for _v in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import datetime as _dt  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from concurrent.futures import ProcessPoolExecutor  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
FIGURES = ROOT / "docs" / "figures" / "prognosis"
SCENARIOS = ("friction-growth", "short-circuit-growth", "gain-drift", "friction-power")
REAL_SCENARIOS = ("friction-growth", "short-circuit-growth", "gain-drift")
N_INSPECTIONS = 10


def _track_stats(sc, tracks) -> dict:
    """Per prediction time: coverage, median |error|, alpha-lambda pass rate; and PH."""
    from emaphm.prognosis import metrics

    times = tracks[0].times
    rul_true = sc.eol - times
    inside = np.array([(tr.lo <= rul_true) & (rul_true <= tr.hi) for tr in tracks])
    err = np.abs(np.array([tr.median for tr in tracks]) - rul_true)
    al = np.array([metrics.alpha_lambda(tr.times, tr.samples, sc.eol, alpha=0.2,
                                        lambdas=(0.5, 0.6, 0.7, 0.8, 0.9)).passed for tr in tracks])
    ph = np.array([metrics.prognostic_horizon(tr.times, tr.samples, sc.eol, alpha=0.1)
                   for tr in tracks])
    late = times >= 0.5 * sc.eol
    return {"times": times.tolist(), "n_used": tracks[0].n_used.tolist(),
            "coverage": inside.mean(axis=0).tolist(),
            "median_abs_error": np.median(err, axis=0).tolist(),
            "coverage_from_midlife": float(inside[:, late].mean()),
            # a cone that never reaches the threshold (lo = hi = inf) is infinitely wide
            "width_from_midlife": float(np.median(np.nan_to_num(
                np.array([tr.hi - tr.lo for tr in tracks])[:, late], nan=np.inf))),
            "alpha_lambda_pass": dict(zip(["0.5", "0.6", "0.7", "0.8", "0.9"], al.mean(axis=0).tolist())),
            "prognostic_horizon_median": float(np.nanmedian(ph)) if np.isfinite(ph).any() else None,
            "prognostic_horizon_found": float(np.mean(np.isfinite(ph))),
            "n_histories": len(tracks)}


def synthetic(name: str, n: int) -> tuple[dict, list]:
    from emaphm.prognosis import degradation_scenario, inspection_times, rul_track, synthetic_k_history
    from emaphm.prognosis.trends import indicator_series

    sc = degradation_scenario(name)
    t = inspection_times(sc.eol, N_INSPECTIONS)
    tracks = []
    for h in range(n):
        y = indicator_series(synthetic_k_history(sc, t, seed=10_000 + h))[sc.indicator]
        tracks.append(rul_track(t, y, sc.threshold, seed=h, n_samples=2000))
    return _track_stats(sc, tracks), tracks


def real_history(task: tuple[str, int, bool]) -> dict:
    """One simulated history, identified and recorded; returns the k history. With
    ``commission``, the unit is first calibrated on two healthy traces (``history
    calibrate`` at t = 0), so every inspection is diagnosed with its calibration."""
    from emaphm.calibration import calibrate
    from emaphm.faults import K_NOMINAL
    from emaphm.params import siemens_1fk7060
    from emaphm.prognosis import (HealthHistory, inspect, inspection_times,
                                  simulate_degradation)
    from emaphm.simulate import DEFAULT_SENSORS, simulate

    name, h, commission = task
    sc = _scenario(name)
    times = inspection_times(sc.eol, N_INSPECTIONS)
    t0 = time.perf_counter()
    run = simulate_degradation(sc, times, seed=h)
    with tempfile.TemporaryDirectory() as tmp, HealthHistory(Path(tmp) / "h.sqlite") as store:
        store.register("EMA")
        calibration = None
        if commission:          # two healthy traces of the unit, noise seeds apart from the run's
            healthy = [simulate(K_NOMINAL, sensors=DEFAULT_SENSORS, seed=50_000 + 2 * h + j)
                       for j in range(2)]
            cal = calibrate(healthy, siemens_1fk7060())
            store.calibrate("EMA", 0.0, cal.params, sources=("healthy-1", "healthy-2"))
            calibration = {n: e["value"] for n, e in cal.estimates.items()}
        for t, trace in zip(times, run.traces):
            inspect(store, "EMA", trace, float(t), seed=h)
        data = store.data("EMA")
    return {"scenario": name, "history": h, "times": data.times.tolist(), "K": data.K.tolist(),
            "K_lo": data.K_lo.tolist(), "K_hi": data.K_hi.tolist(), "k_true": run.k_true.tolist(),
            "error_pct": [i.extra.get("error_pct") for i in data.inspections],
            "calibration": calibration,
            "elapsed_s": time.perf_counter() - t0}


def _backlash_growth():
    from emaphm.prognosis import DegradationLaw, DegradationScenario
    from emaphm.prognosis.thresholds import DEFAULT_FAILURE_THRESHOLDS as thr

    return DegradationScenario("backlash", DegradationLaw.reaching("linear", thr.backlash, 1000.0),
                               name="backlash-growth")


def _eccentricity_growth():
    from emaphm.prognosis import DegradationLaw, DegradationScenario
    from emaphm.prognosis.thresholds import DEFAULT_FAILURE_THRESHOLDS as thr

    return DegradationScenario("eccentricity",
                               DegradationLaw.reaching("linear", thr.eccentricity, 1000.0),
                               name="eccentricity-growth")


#: Histories only the discrepancy tuning runs (no preset: the RUL tables do not report them).
TUNE_SCENARIOS = {"backlash-growth": _backlash_growth, "eccentricity-growth": _eccentricity_growth}
TUNE_SEED0 = 100


def _scenario(name: str):
    """A preset degradation scenario, or one only the discrepancy tuning runs."""
    from emaphm.prognosis import degradation_scenario

    return TUNE_SCENARIOS[name]() if name in TUNE_SCENARIOS else degradation_scenario(name)
#: Share of its failure threshold from which a true indicator counts in the discrepancy.
TUNE_FROM = 0.25


def relative_errors(rows: list[dict]) -> dict[str, list[float]]:
    """``(identified - true) / true`` of each history's degrading indicator, at the
    inspections where the true value is at least :data:`TUNE_FROM` of its threshold."""
    from emaphm.prognosis.trends import indicator_series

    out: dict[str, list[float]] = {}
    for r in rows:
        name = r["scenario"]
        sc = _scenario(name)
        y = indicator_series(np.array(r["K"]))[sc.indicator]
        y_true = indicator_series(np.array(r["k_true"]))[sc.indicator]
        y, y_true = abs(y), abs(y_true)              # gain drift: signed by its own direction
        m = y_true >= TUNE_FROM * sc.threshold
        out.setdefault(sc.indicator, []).extend(((y[m] - y_true[m]) / y_true[m]).tolist())
    return out


def calibrate_one(task: tuple[int | None, float, int]) -> dict:
    from emaphm.faults import K_NOMINAL
    from emaphm.identify import identify
    from emaphm.simulate import DEFAULT_SENSORS, simulate

    idx, v, s = task
    k = K_NOMINAL.copy()
    if idx is not None:
        k[idx] = v
    tr = simulate(k, sensors=DEFAULT_SENSORS, seed=300 + s)
    r = identify(tr, seed=s)
    return {"k_true": k.tolist(), "k": r.k.tolist(), "error_pct": r.error_pct}


CALIBRATION_CASES = ([(None, 0.0)] + [(0, v) for v in (0.05, 0.2, 0.45)]
                     + [(2, v) for v in (0.05, 0.15, 0.28)] + [(7, v) for v in (0.45, 0.35, 0.27)]
                     + [(1, 0.2), (5, 0.3)])


def figures(syn_tracks: dict, real: list[dict], stats: dict) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    from emaphm.plots import save_figure
    from emaphm.prognosis import degradation_scenario, prognose, rul_track
    from emaphm.prognosis.history import Actuator, HistoryData
    from emaphm.prognosis.plots import plot_alpha_lambda, plot_history, plot_prognosis
    from emaphm.prognosis.trends import MODEL_DISCREPANCY, indicator_series

    FIGURES.mkdir(parents=True, exist_ok=True)
    written = []
    # 1. a recorded history (real identifications)
    r0 = next(r for r in real if r["scenario"] == "short-circuit-growth")
    from emaphm.prognosis.history import Inspection

    ins = tuple(Inspection(id=i, actuator="EMA", time=t, k=np.array(k), k_lo=np.array(lo),
                           k_hi=np.array(hi), spread_method="population", level=0.9,
                           healthy=bool(k[2] <= 0.03), diagnosis=None, fingerprint=None,
                           algorithm="pso", seed=0, fitness=None, evaluations=None, source=None,
                           recorded_utc="")
                for i, (t, k, lo, hi) in enumerate(zip(r0["times"], r0["K"], r0["K_lo"], r0["K_hi"])))
    data = HistoryData(actuator=Actuator("EMA-SC", "simulated short-circuit growth, phase A", "h", ""),
                       times=np.array(r0["times"]), K=np.array(r0["K"]), K_lo=np.array(r0["K_lo"]),
                       K_hi=np.array(r0["K_hi"]), inspections=ins)
    p = FIGURES / "history-short-circuit.png"
    plot_history(data, path=p)
    written.append(p)
    # 2. prediction cones at mid-life and near the end (real identifications)
    for name in REAL_SCENARIOS:
        r = next(x for x in real if x["scenario"] == name)
        sc = degradation_scenario(name)
        for i, tag in ((6, "midlife"), (10, "late")):
            prog = prognose(np.array(r["times"][:i]), np.array(r["K"][:i]), seed=0,
                            actuator=f"simulated {name}")
            p = FIGURES / f"prognosis-{name}-{tag}.png"
            plot_prognosis(prog, indicators=(sc.indicator,), eol_true={sc.indicator: sc.eol},
                           path=p, title=f"{name}: prognosis after {i} inspections "
                                         f"(real identifications)")
            written.append(p)
    # 3. alpha-lambda: real tracks per scenario, and synthetic tracks
    fig = Figure(figsize=(15, 4.6), layout="constrained")
    axes = fig.subplots(1, 3, sharey=True)
    for ax, name in zip(axes, REAL_SCENARIOS):
        sc = degradation_scenario(name)
        tracks = []
        for r in (x for x in real if x["scenario"] == name):
            y = indicator_series(np.array(r["K"]))[sc.indicator]
            tracks.append(rul_track(np.array(r["times"]), y, sc.threshold, seed=r["history"],
                                    discrepancy=MODEL_DISCREPANCY[sc.indicator]))
        plot_alpha_lambda(tracks, sc.eol, ax=ax, labels=[f"history {i}" for i in range(len(tracks))],
                          title=f"{name} (real identifications)")
    p = FIGURES / "alpha-lambda-real.png"
    save_figure(fig, p)
    written.append(p)
    fig = Figure(figsize=(20, 4.6), layout="constrained")
    axes = fig.subplots(1, 4, sharey=True)
    for ax, name in zip(axes, SCENARIOS):
        sc = degradation_scenario(name)
        plot_alpha_lambda(syn_tracks[name][:25], sc.eol, ax=ax,
                          title=f"{name} (25 synthetic histories)")
    p = FIGURES / "alpha-lambda-synthetic.png"
    save_figure(fig, p)
    written.append(p)
    # 4. coverage and median error against the share of life
    fig = Figure(figsize=(11, 4.2), layout="constrained")
    a1, a2 = fig.subplots(1, 2)
    for i, name in enumerate(SCENARIOS):
        s = stats["synthetic"][name]
        x = np.array(s["times"]) / 1000.0
        a1.plot(x, s["coverage"], "o-", color=f"C{i}", label=f"{name} (synthetic)")
        a2.semilogy(x, np.array(s["median_abs_error"]), "o-", color=f"C{i}", label=name)
        if name in stats["real"]:
            sr = stats["real"][name]
            a1.plot(np.array(sr["times"]) / 1000.0, sr["coverage"], "s--", color=f"C{i}", mfc="none",
                    label=f"{name} (real, {sr['n_histories']} histories)")
            a2.semilogy(np.array(sr["times"]) / 1000.0, sr["median_abs_error"], "s--",
                        color=f"C{i}", mfc="none")
    a1.axhline(0.9, color="k", lw=0.8, ls=":")
    a1.axvline(0.5, color="C3", lw=0.8, ls=":")
    a1.set_xlabel("share of life at the prediction")
    a1.set_ylabel("coverage of the true RUL (90 % interval)")
    a1.set_ylim(0, 1.05)
    a1.legend(fontsize=7, loc="lower right")
    a2.axvline(0.5, color="C3", lw=0.8, ls=":")
    a2.set_xlabel("share of life at the prediction")
    a2.set_ylabel("median |RUL error| [h]")
    a2.legend(fontsize=7)
    for a in (a1, a2):
        a.grid(True, alpha=0.3, which="both")
    p = FIGURES / "coverage-and-error.png"
    save_figure(fig, p)
    written.append(p)
    return [str(x.relative_to(ROOT)) for x in written]


def _table(stats: dict, kind: str) -> list[str]:
    lines = ["| scenario | histories | inspections used | 3 | 4 | 5 | 6 | 7 | 8 | 9 | 10 |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for name, s in stats.items():
        cov = " | ".join(f"{c:.2f}" for c in s["coverage"])
        err = " | ".join(f"{e:.0f}" for e in s["median_abs_error"])
        lines.append(f"| {name} | {s['n_histories']} | coverage | {cov} |")
        lines.append(f"| | | median abs error [h] | {err} |")
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--synthetic-histories", type=int, default=200)
    ap.add_argument("--real-histories", type=int, default=3)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--calibrate", action="store_true")
    ap.add_argument("--tune-discrepancy", type=int, default=0, metavar="N",
                    help="only measure each indicator's model discrepancy on N commissioned "
                         "histories per scenario (seeds 100+) and print it "
                         "(-> results/prognosis_tuning.json)")
    ap.add_argument("--no-commission", dest="commission", action="store_false",
                    help="diagnose the real histories with the data sheet (no emaphm calibrate "
                         "on healthy traces first)")
    args = ap.parse_args()
    t0 = time.perf_counter()
    if args.tune_discrepancy:
        names = list(REAL_SCENARIOS) + list(TUNE_SCENARIOS)
        tasks = [(n, TUNE_SEED0 + h, args.commission) for n in names
                 for h in range(args.tune_discrepancy)]
        with ProcessPoolExecutor(max_workers=args.workers) as ex:
            rows = list(ex.map(real_history, tasks))
        errors = relative_errors(rows)
        summary = {n: {"rms": float(np.sqrt(np.mean(np.square(e)))), "mean": float(np.mean(e)),
                       "n": len(e)} for n, e in errors.items()}
        RESULTS.mkdir(parents=True, exist_ok=True)
        (RESULTS / "prognosis_tuning.json").write_text(json.dumps(
            {"discrepancy": summary, "rows": rows}, indent=1))
        print(json.dumps(summary, indent=1))
        print(f"{time.perf_counter() - t0:.0f} s")
        return
    stats: dict = {"synthetic": {}, "real": {}}
    syn_tracks = {}
    for name in SCENARIOS:
        stats["synthetic"][name], syn_tracks[name] = synthetic(name, args.synthetic_histories)
        print(f"synthetic {name}: coverage from mid-life "
              f"{stats['synthetic'][name]['coverage_from_midlife']:.3f}", flush=True)
    tasks = [(n, h, args.commission) for n in REAL_SCENARIOS for h in range(args.real_histories)]
    with ProcessPoolExecutor(max_workers=args.workers) as ex:
        real = list(ex.map(real_history, tasks))
        calib = list(ex.map(calibrate_one, [(i, v, s) for i, v in CALIBRATION_CASES for s in (0, 1)])) \
            if args.calibrate else None
    from emaphm.prognosis import degradation_scenario, rul_track
    from emaphm.prognosis.trends import indicator_series

    from emaphm.prognosis.trends import MODEL_DISCREPANCY

    for name in REAL_SCENARIOS:
        sc = degradation_scenario(name)
        tracks = []
        for r in (x for x in real if x["scenario"] == name):
            y = indicator_series(np.array(r["K"]))[sc.indicator]
            tracks.append(rul_track(np.array(r["times"]), y, sc.threshold, seed=r["history"],
                                    n_samples=2000,
                                    discrepancy=MODEL_DISCREPANCY[sc.indicator]))
        stats["real"][name] = _track_stats(sc, tracks)
        ind_err = [np.abs(np.array(r["K"]) - np.array(r["k_true"])).max(axis=0).tolist()
                   for r in real if r["scenario"] == name]
        stats["real"][name]["max_component_error"] = np.max(ind_err, axis=0).tolist()
        stats["real"][name]["identification_error_pct_median"] = float(np.median(
            [e for r in real if r["scenario"] == name for e in r["error_pct"]]))
        print(f"real {name}: coverage from mid-life {stats['real'][name]['coverage_from_midlife']:.3f}",
              flush=True)
    if calib is not None:
        E = np.abs(np.array([c["k"] for c in calib]) - np.array([c["k_true"] for c in calib]))
        stats["calibration"] = {"n": len(calib), "p50": np.quantile(E, 0.5, axis=0).tolist(),
                                "p90": np.quantile(E, 0.9, axis=0).tolist(),
                                "max": E.max(axis=0).tolist()}
    figs = figures(syn_tracks, real, stats)
    meta = {"date": _dt.date.today().isoformat(), "python": platform.python_version(),
            "machine": platform.machine(), "processor": platform.processor() or platform.machine(),
            "cpus": os.cpu_count(), "workers": args.workers, "elapsed_s": time.perf_counter() - t0,
            "inspections": N_INSPECTIONS, "figures": figs}
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / "prognosis.json").write_text(json.dumps({"meta": meta, "stats": stats, "real": real},
                                                       indent=1))
    from emaphm.prognosis.trends import DEFAULT_MODELS

    md = [f"## Prognosis: RUL statistics ({meta['date']}, {meta['cpus']} CPUs, "
          f"{meta['elapsed_s']:.0f} s)", "",
          f"{N_INSPECTIONS} inspections from 0 to 950 h, true end of life 1000 h; a prediction at "
          "every inspection from the 3rd on. 90 % intervals (trend models "
          f"{', '.join(DEFAULT_MODELS)} mixed by Akaike weight; Monte Carlo over the fit; for "
          "real identifications "
          "also over each indicator's model discrepancy, `emaphm.prognosis.trends."
          "MODEL_DISCREPANCY`, measured with `--tune-discrepancy` on seeds 100+).", "",
          "### Synthetic k histories (true k + N(0, 0.007) per component, no identification)", ""]
    md += _table(stats["synthetic"], "synthetic")
    md += ["", "### Real identifications (reference plant with sensor noise, the default "
           "pipeline; " + ("each unit calibrated first on two healthy traces, `history calibrate`"
                           if args.commission else "data-sheet parameters, no calibration")
           + ")", ""]
    md += _table(stats["real"], "real")
    md += ["", "### From mid-life on", "",
           "| scenario | kind | coverage | median interval width [h] | alpha-lambda pass at 0.5 / 0.7 / 0.9 | PH (alpha 0.1) median h, share found |",
           "|---|---|---|---|---|---|"]
    for kind in ("synthetic", "real"):
        for name, s in stats[kind].items():
            al = s["alpha_lambda_pass"]
            ph = s["prognostic_horizon_median"]
            md.append(f"| {name} | {kind} | {s['coverage_from_midlife']:.3f} | "
                      f"{s['width_from_midlife']:.0f} | "
                      f"{al['0.5']:.2f} / {al['0.7']:.2f} / {al['0.9']:.2f} | "
                      f"{'-' if ph is None else f'{ph:.0f}'}, {s['prognostic_horizon_found']:.2f} |")
    if calib is not None:
        c = stats["calibration"]
        md += ["", f"### Identification error per component ({c['n']} traces, PSO default budget)", "",
               "| | " + " | ".join(f"k{i + 1}" for i in range(8)) + " |",
               "|---|" + "---|" * 8]
        for q in ("p50", "p90", "max"):
            md.append(f"| {q} | " + " | ".join(f"{x:.4f}" for x in c[q]) + " |")
    (RESULTS / "prognosis.md").write_text("\n".join(md) + "\n")
    print("\n".join(md))


if __name__ == "__main__":
    main()
