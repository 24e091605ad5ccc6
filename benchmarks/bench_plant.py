"""Fault detection and identification on plant traces, beside twin traces.

The *plant* is emaphm's reference model as a real actuator stand-in: switching
PWM, phase self and mutual inductance with leakage, physical inter-turn fault
loops, Stribeck friction, a compliant backlash contact and the acquisition
chain (20 mA rms noise, 12-bit ADC). The monitoring model has none of that
but the fault loop. *Twin* traces are the monitoring model's own currents with
the same acquisition chain: the inverse crime, reported second.

Cases (each run draws its own noise seed; thresholds are set on one set of seeds
and reported on another, disjoint one):

* ``short``: physical inter-turn short circuits, ``mu`` in {5, 10, 20, 30} % of one
  phase's turns (A, B, C in turn) through a fault resistance ``R_f`` in {0.05, 0.15,
  0.5} ohm (the monitoring model assumes 0.15 ohm); 40 runs;
* ``modes``: friction x2.5 (k1 = 0.75), backlash, eccentricity and gain drift at
  the paper's magnitudes (0.25 and 0.75), nominal unit;
* ``healthy``: the nominal plant, 100 seeds.

``--tune`` runs the same cases on the tuning seeds (10000+) and prints the
detection thresholds it suggests (:func:`suggest`: 1.25x the largest deviation of
each component where it is not at fault, at least 0.015) and the lognormal of
the fit ratios the misfit test uses; the library's thresholds
(:data:`emaphm.diagnosis.THRESHOLDS_BY_FAULT_MODEL`) are what every other case
uses, on the test seeds (0+).

Run: ``python benchmarks/bench_plant.py [--workers 2] [--healthy 100]`` ->
``benchmarks/results/plant.md`` and ``plant.json``; ``--tune`` first.
"""

from __future__ import annotations

import os

for _v in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import datetime as _dt  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402
from concurrent.futures import ProcessPoolExecutor  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from bench_identification import _warm, machine  # noqa: E402  (shared: warm-up, machine line)

RESULTS = Path(__file__).parent / "results"
MUS = (0.05, 0.10, 0.20, 0.30)
RFS = (0.05, 0.15, 0.5)
MODE_CASES = {"friction x2.5": (0, 0.75), "backlash-low": (1, 0.25), "backlash-high": (1, 0.75),
              "eccentricity-low": (5, 0.25), "eccentricity-high": (5, 0.75),
              "gain-low": (7, 0.25), "gain-high": (7, 0.75)}
MODE_OF = {0: "friction", 1: "backlash", 5: "eccentricity", 7: "gain_drift"}
TEST_SEED0 = 0
TUNE_SEED0 = 10_000


def _k(index=None, value=None):
    from emaphm.faults import K_NOMINAL

    k = K_NOMINAL.copy()
    if index is not None:
        k[index] = value
    return k


def run_one(task: dict) -> dict:
    from dataclasses import replace

    from emaphm.identify import IdentificationConfig, identify
    from emaphm.verdict import examine
    from emaphm.params import siemens_1fk7060
    from emaphm.simulate import DEFAULT_SENSORS, simulate

    nominal = siemens_1fk7060()
    plant = nominal
    if task.get("R_f") is not None:
        plant = replace(nominal, motor=replace(nominal.motor, R_f=(task["R_f"],) * 3))
    k = np.asarray(task["k"])
    t0 = time.process_time()
    trace = simulate(k, model=task["model"], params=plant, sensors=DEFAULT_SENSORS,
                     seed=task["seed"], fault_model="physical")
    sim_cpu = time.process_time() - t0
    # the monitoring model assumes the data sheet, and its own fault resistance
    t0 = time.process_time()
    ident = identify(trace, ALGORITHM, seed=task["seed"], params=nominal)
    cpu = time.process_time() - t0
    # the verdict as `emaphm diagnose` gives it (the sensors from the currents' sum, the
    # same identification, the checks and the modes' hypotheses); the check's CPU is
    # what it costs beyond the identification
    t0 = time.process_time()
    diag = examine(trace, params=nominal, config=IdentificationConfig(ALGORITHM),
                   seed=task["seed"]).diagnosis
    check_cpu = max(0.0, time.process_time() - t0 - cpu)
    return {**task, "k_id": ident.k.tolist(), "error_pct": ident.error_pct,
            "faults": [(f.mode, f.phase) for f in diag.faults], "verdict": diag.verdict,
            "mismatch_checked": diag.mismatch is not None,
            "unexplained_reason": None if diag.unexplained is None else diag.unexplained.reason,
            "fitness": ident.fitness,
            "noise_floor": ident.noise_floor, "restarts": ident.restarts,
            "suspect": ident.suspect, "cpu_s": cpu, "sim_cpu_s": sim_cpu,
            "check_cpu_s": check_cpu}


def tasks(case: str, model: str, seed0: int, n_healthy: int) -> list[dict]:
    out = []
    if case == "short":
        i = 0
        for mu in MUS:
            for rf in RFS:
                for ph in range(3):
                    if i >= 40:
                        break
                    out.append({"case": "short", "model": model, "mu": mu, "R_f": rf,
                                "phase": "ABC"[ph], "k": _k(2 + ph, mu).tolist(),
                                "seed": seed0 + i})
                    i += 1
        # fill to 40 with phase A at the middle fault resistance
        while len(out) < 40:
            mu = MUS[len(out) % len(MUS)]
            out.append({"case": "short", "model": model, "mu": mu, "R_f": 0.15, "phase": "A",
                        "k": _k(2, mu).tolist(), "seed": seed0 + len(out)})
    elif case == "modes":
        for name, (idx, val) in MODE_CASES.items():
            for s in range(5):
                out.append({"case": "modes", "model": model, "name": name, "index": idx,
                            "k": _k(idx, val).tolist(), "seed": seed0 + 100 + 10 * idx + s})
    elif case == "healthy":
        for s in range(n_healthy):
            out.append({"case": "healthy", "model": model, "k": _k().tolist(),
                        "seed": seed0 + 1000 + s})
    return out


def summarise(rows: list[dict]) -> dict:
    res: dict = {}
    for model in ("reference", "monitoring"):
        rs = [r for r in rows if r["model"] == model]
        if not rs:
            continue
        sh = [r for r in rs if r["case"] == "short"]
        ok = [r for r in sh if r["faults"] == [("short_circuit", r["phase"])]]
        mono = {}
        for rf in RFS:
            sev = []
            for mu in MUS:
                v = [r["k_id"][2 + "ABC".index(r["phase"])] for r in sh if r["mu"] == mu and r["R_f"] == rf]
                sev.append(float(np.mean(v)) if v else float("nan"))
            mono[rf] = sev
        md = [r for r in rs if r["case"] == "modes"]
        md_ok = [r for r in md if [m for m, _ in r["faults"]] == [MODE_OF[r["index"]]]]
        he = [r for r in rs if r["case"] == "healthy"]
        res[model] = {
            "short_runs": len(sh), "short_right_alone": len(ok),
            "short_severity_by_Rf": mono,
            "modes_runs": len(md), "modes_right_alone": len(md_ok),
            "modes_mean_error": float(np.mean([r["error_pct"] for r in md])) if md else None,
            "modes_error_by_case": {n: float(np.mean([r["error_pct"] for r in md if r["name"] == n]))
                                    for n in MODE_CASES if any(r["name"] == n for r in md)},
            "healthy_runs": len(he), "healthy_false_alarms": sum(1 for r in he if r["faults"]),
            "healthy_unexplained": sum(1 for r in he if r["verdict"] == "unexplained"),
            "unexplained": sum(1 for r in sh + md if r["verdict"] == "unexplained"),
            "healthy_fit_ratio_p95": float(np.percentile([r["fitness"] / r["noise_floor"]
                                                          for r in he], 95)) if he else None,
            "median_cpu_s": float(np.median([r["cpu_s"] for r in rs])),
            "checked": sum(1 for r in rs if r.get("mismatch_checked")),
            "check_median_cpu_s": float(np.median([r["check_cpu_s"] for r in rs
                                                   if r.get("mismatch_checked")]))
            if any(r.get("mismatch_checked") for r in rs) else None,
            "explained_by_mismatch": sum(1 for r in rs if r.get("unexplained_reason") == "mismatch"),
            "failures": [(r["case"], r.get("name") or f"mu={r.get('mu')} Rf={r.get('R_f')} "
                          f"{r.get('phase')}", r["faults"]) for r in sh + md
                         if r not in ok and r not in md_ok],
        }
    return res


#: The k components each detection threshold reads (``gain_drift``: ``|k8 - 0.5|``).
THRESHOLD_COMPONENTS = {"friction": (0,), "backlash": (1,), "short_circuit": (2, 3, 4),
                        "eccentricity": (5,), "gain_drift": (7,)}


def largest_deviations(runs) -> dict[str, float]:
    """Each threshold's largest deviation from healthy over ``runs``, pairs ``(k, faulted)``
    (``faulted``: the index of the component at fault, or None), leaving out the component
    at fault: what a threshold must stay above."""
    out = dict.fromkeys(THRESHOLD_COMPONENTS, 0.0)
    for k, faulted in runs:
        k = np.asarray(k)
        for comp, idx in THRESHOLD_COMPONENTS.items():
            for j in idx:
                if j != faulted:
                    out[comp] = max(out[comp], abs(k[j] - 0.5) if comp == "gain_drift" else k[j])
    return {comp: float(v) for comp, v in out.items()}


def suggest(rows: list[dict]) -> dict:
    """Thresholds from the tuning runs: each component's largest deviation from healthy
    in runs where that component is not at fault (healthy units, and every other fault:
    cross-talk), times 1.25, at least 0.015; and the lognormal of the fit ratios of the
    runs the model explains (wrong basins, fit > 10x, left out)."""
    from emaphm.diagnosis import THRESHOLDS_BY_FAULT_MODEL

    def faulted(r):
        if r["case"] == "short":
            return 2 + "ABC".index(r["phase"])
        return r["index"] if r["case"] == "modes" else None

    largest = largest_deviations((r["k_id"], faulted(r)) for r in rows)
    cur = THRESHOLDS_BY_FAULT_MODEL["physical"]
    out = {}
    for comp, v in largest.items():
        out[comp] = {"max_not_at_fault": float(v), "suggested": float(max(1.25 * v, 0.015)),
                     "current": getattr(cur, comp)}
    ratios = np.array([r["fitness"] / r["noise_floor"] for r in rows])
    ok = np.log(ratios[ratios < 10])
    out["fit_ratio"] = {"log_mean": float(ok.mean()), "log_std": float(ok.std(ddof=1)),
                        "n": int(ok.size), "wrong_basins": int(np.sum(ratios >= 10)),
                        "p50_p99_max": np.percentile(ratios, [50, 99, 100]).round(3).tolist()}
    return out


def report(summary: dict, wall: float, workers: int) -> str:
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    now = _dt.datetime.now(_dt.timezone.utc)
    out = [f"## Plant traces beside twin traces ({now:%Y-%m-%d %H:%M} UTC)", "",
           f"Machine: {machine()}; "
           f"load average {load:.2f} at the end; {wall / 60:.1f} min wall on {workers} workers. "
           f"Algorithm: {ALGORITHM} with identify's defaults, fault model physical; "
           "the monitoring model assumes the data sheet and R_f = 0.15 ohm. Test seeds (0+), "
           "disjoint from the tuning seeds (10000+) the thresholds were set on.", "",
           "| | plant | twin |", "|---|---|---|"]
    p, t = summary.get("reference", {}), summary.get("monitoring", {})

    def cell(d, key, fmt="{}"):
        return fmt.format(d[key]) if d and d.get(key) is not None else "-"

    out.append(f"| inter-turn short (mu 5-30 %, R_f 0.05-0.5 ohm): right phase alone | "
               f"{cell(p, 'short_right_alone')}/{cell(p, 'short_runs')} | "
               f"{cell(t, 'short_right_alone')}/{cell(t, 'short_runs')} |")
    out.append(f"| friction, backlash, eccentricity, gain: right mode alone | "
               f"{cell(p, 'modes_right_alone')}/{cell(p, 'modes_runs')} | "
               f"{cell(t, 'modes_right_alone')}/{cell(t, 'modes_runs')} |")
    out.append(f"| ... mean Eq. 9 error [%] | {cell(p, 'modes_mean_error', '{:.2f}')} | "
               f"{cell(t, 'modes_mean_error', '{:.2f}')} |")
    out.append(f"| healthy nominal unit: false alarms | {cell(p, 'healthy_false_alarms')}/"
               f"{cell(p, 'healthy_runs')} | {cell(t, 'healthy_false_alarms')}/{cell(t, 'healthy_runs')} |")
    out.append(f"| healthy nominal unit: verdict unexplained | {cell(p, 'healthy_unexplained')}/"
               f"{cell(p, 'healthy_runs')} | {cell(t, 'healthy_unexplained')}/{cell(t, 'healthy_runs')} |")
    out.append(f"| faulty runs with verdict unexplained | {cell(p, 'unexplained')}/"
               f"{p.get('short_runs', 0) + p.get('modes_runs', 0)} | {cell(t, 'unexplained')}/"
               f"{t.get('short_runs', 0) + t.get('modes_runs', 0)} |")
    out.append(f"| healthy: 95th percentile of fitness / noise floor | "
               f"{cell(p, 'healthy_fit_ratio_p95', '{:.2f}')} | {cell(t, 'healthy_fit_ratio_p95', '{:.2f}')} |")
    out.append(f"| median CPU time per identification [s] | {cell(p, 'median_cpu_s', '{:.2f}')} | "
               f"{cell(t, 'median_cpu_s', '{:.2f}')} |")
    out.append(f"| mismatch check (verdicts naming a fault): runs checked, explained away | "
               f"{cell(p, 'checked')}, {cell(p, 'explained_by_mismatch')} | "
               f"{cell(t, 'checked')}, {cell(t, 'explained_by_mismatch')} |")
    out.append(f"| ... median CPU time of the check [s] | {cell(p, 'check_median_cpu_s', '{:.2f}')} | "
               f"{cell(t, 'check_median_cpu_s', '{:.2f}')} |")
    out += ["", "Mean identified shorted fraction (k of the faulty phase) by true mu "
            f"{', '.join(f'{m:.2f}' for m in MUS)}, plant traces:", ""]
    for rf, sev in (p.get("short_severity_by_Rf") or {}).items():
        out.append(f"- R_f = {rf} ohm: " + ", ".join(f"{x:.3f}" for x in sev))
    out += ["", "Mean Eq. 9 error [%] per case, plant traces: "
            + ", ".join(f"{n} {e:.2f}" for n, e in (p.get("modes_error_by_case") or {}).items())]
    if p.get("failures"):
        out += ["", "Plant runs not named right: "
                + "; ".join(f"{c} {n} -> {f}" for c, n, f in p["failures"])]
    return "\n".join(out) + "\n"


#: The identification algorithm (``--algorithm``; set before the worker processes fork).
ALGORITHM = "lsq"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--algorithm", default="lsq",
                    help="identification algorithm (default lsq, identify's default)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--healthy", type=int, default=100)
    ap.add_argument("--cases", default="short,modes,healthy")
    ap.add_argument("--models", default="reference,monitoring")
    ap.add_argument("--tune", action="store_true", help="healthy plant on the tuning seeds only")
    args = ap.parse_args()
    global ALGORITHM
    ALGORITHM = args.algorithm
    if args.tune:
        todo = [t for c in args.cases.split(",") for t in tasks(c, "reference", TUNE_SEED0,
                                                                 args.healthy)]
    else:
        todo = [t for m in args.models.split(",") for c in args.cases.split(",")
                for t in tasks(c, m, TEST_SEED0, args.healthy)]
    _warm()
    t0 = time.perf_counter()
    with ProcessPoolExecutor(args.workers, initializer=_warm) as ex:
        rows = list(ex.map(run_one, todo))
    wall = time.perf_counter() - t0
    RESULTS.mkdir(exist_ok=True)
    if args.tune:
        (RESULTS / "plant_tuning.json").write_text(json.dumps(rows, indent=1))
        print(json.dumps(suggest(rows), indent=1))
        return
    (RESULTS / "plant.json").write_text(json.dumps(rows, indent=1))
    text = report(summarise(rows), wall, args.workers)
    (RESULTS / "plant.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
