"""The verdict end to end against SciPy's differential evolution (issue 36).

What a user waits for is the verdict: ``emaphm diagnose``'s whole examination
(:func:`emaphm.verdict.examine`: the current sensors' screen, the identification, the
hypotheses' refits, the fault loops' report, the mismatch check). It is measured here side
by side, in ONE process, against SciPy's vectorized ``differential_evolution`` identifying
the same trace on the same objective (population 48, 5,250 evaluations, no polish, the
metaheuristics' search space; what ``benchmarks/bench_identification.py --pipeline``
runs), both single-threaded (BLAS, OpenMP and Numba threads at 1), CPU time, kernels
compiled before anything is timed.

Traces (reference plant, switching PWM, ``DEFAULT_SENSORS``, noise seeds 1..``--seeds``,
the preset's nominal unit): healthy; the paper's friction-high, short-circuit-high and
multiple; a 10 % short of phase A through 0.15 ohm (physical); a magnet 15 % weaker; phase
A's current sensor 10 % low; and, with the drive's voltage commands recorded (the
recorded-voltage path of issue 32), healthy and the 10 % short.

Also reported: the identification's share of the verdict (``identify`` alone, timed on its
own), and what the verdict read.

Run: ``python benchmarks/bench_end_to_end.py [--seeds 2] [--tag TAG]`` ->
``benchmarks/results/end_to_end[-TAG].md`` and ``.json`` (the emaphm imported: another
version with ``PYTHONPATH=<its src>``, its commit in the report).
"""

from __future__ import annotations

import os

for _v in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import datetime as _dt  # noqa: E402
import json  # noqa: E402
import subprocess  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from _machine import machine  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(__file__).parent / "results"
SCIPY_POP, SCIPY_EVALS = 48, 5250
#: label -> (scenario, faults, drive signals recorded)
TRACES = {
    "healthy": (None, (), False),
    "friction-high (paper)": ("friction-high", (), False),
    "short-circuit-high (paper)": ("short-circuit-high", (), False),
    "multiple (paper)": ("multiple", (), False),
    "short 10 % A through 0.15 ohm": (None, ("short_circuit:a:0.1:0.15",), False),
    "magnet 15 % weaker": (None, ("demagnetization:0.15",), False),
    "sensor A gain 0.9": (None, ("current_sensor:a:gain:0.9",), False),
    "recorded voltages: healthy": (None, (), True),
    "recorded voltages: short 10 % A": (None, ("short_circuit:a:0.1:0.15",), True),
}


def make_trace(label: str, seed: int):
    from emaphm.simulate import DEFAULT_SENSORS, simulate

    scenario, faults, drive = TRACES[label]
    kw = dict(seed=seed, sensors=DEFAULT_SENSORS, drive_signals=drive)
    if scenario is not None:
        return simulate(scenario=scenario, **kw)
    return simulate(faults=list(faults), **kw)


def scipy_de(trace, seed: int) -> dict:
    """SciPy's vectorized DE on the objective emaphm identifies this trace with (the
    trace's drive path, its nuisance), in the metaheuristics' search space, no polish."""
    from scipy.optimize import differential_evolution

    from emaphm.problem import IdentificationProblem
    from emaphm.search import default_search

    problem = IdentificationProblem(trace)
    view = problem.view(default_search(problem.fault_model))
    n = problem.n_var
    pop = -(-SCIPY_POP // n)
    t = time.process_time()
    res = differential_evolution(lambda Z: view.evaluate(Z.T), [(0.0, 1.0)] * n, popsize=pop,
                                 maxiter=SCIPY_EVALS // (pop * n) - 1, tol=0.0, atol=0.0,
                                 polish=False, vectorized=True, updating="deferred", rng=seed)
    cpu = time.process_time() - t
    return {"cpu_s": cpu, "evaluations": view.evaluations,
            "fit_ratio": float(res.fun / problem.noise_floor)}


def ours(trace) -> dict:
    from emaphm.identify import identify
    from emaphm.verdict import examine

    t = time.process_time()
    ex = examine(trace, seed=0)
    cpu = time.process_time() - t
    t = time.process_time()
    ident = identify(trace, seed=0)
    cpu_ident = time.process_time() - t
    d = ex.diagnosis
    return {"cpu_s": cpu, "identify_cpu_s": cpu_ident, "verdict": d.verdict,
            "named": [[f.mode, f.phase] for f in d.faults],
            "evaluations": int(ex.identification.evaluations),
            "identify_evaluations": int(ident.evaluations),
            "drive_model": ex.identification.drive_model}


def warm() -> None:
    """Compile and load every kernel the workload runs, on traces not measured."""
    for label in ("healthy", "short 10 % A through 0.15 ohm", "recorded voltages: healthy"):
        tr = make_trace(label, 99)
        ours(tr)
        scipy_de(tr, 0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--traces", default=",".join(TRACES),
                    help="comma-separated labels (default: all)")
    ap.add_argument("--tag", default="",
                    help="write end_to_end-TAG.md (another version on PYTHONPATH, say)")
    args = ap.parse_args()
    labels = args.traces.split(",")
    t0 = time.time()
    warm()
    rows = []
    for label in labels:
        for seed in range(1, args.seeds + 1):
            tr = make_trace(label, seed)
            a = ours(tr)
            b = scipy_de(tr, seed)
            rows.append({"trace": label, "seed": seed, "emaphm": a, "scipy": b,
                         "ratio": a["cpu_s"] / b["cpu_s"]})
            print(f"{label:34s} seed {seed}: verdict {a['cpu_s']:.2f} s ({a['verdict']} "
                  f"{a['named']}), identify {a['identify_cpu_s']:.2f} s, SciPy DE "
                  f"{b['cpu_s']:.2f} s: {rows[-1]['ratio']:.2f}x", flush=True)
    RESULTS.mkdir(exist_ok=True)
    stem = "end_to_end" + (f"-{args.tag}" if args.tag else "")
    (RESULTS / f"{stem}.json").write_text(json.dumps(rows, indent=1))
    (RESULTS / f"{stem}.md").write_text(report(rows, args, time.time() - t0))
    print((RESULTS / f"{stem}.md").read_text())


def _span(xs) -> str:
    lo, hi = min(xs), max(xs)
    return f"{lo:.2f}" if f"{lo:.2f}" == f"{hi:.2f}" else f"{lo:.2f}-{hi:.2f}"


def report(rows: list[dict], args, wall: float) -> str:
    import emaphm

    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], text=True,
                            cwd=Path(emaphm.__file__).parent,
                            capture_output=True).stdout.strip() or "unknown"
    load = os.getloadavg()[0]
    ratios = [r["ratio"] for r in rows]
    out = ["## The verdict end to end against SciPy's DE (`benchmarks/bench_end_to_end.py`)", "",
           f"Machine: {machine('numba', 'scipy')}; load average {load:.2f} at the end; "
           f"{_dt.datetime.now(_dt.timezone.utc):%Y-%m-%d %H:%M} UTC; emaphm at {commit}; "
           f"{wall:.0f} s wall. One process, single-threaded, CPU time; noise seeds 1-"
           f"{args.seeds} per trace; the preset's nominal unit. emaphm: `examine` (what "
           "`emaphm diagnose` runs, the whole verdict) and `identify` alone; SciPy: "
           f"`differential_evolution` (population {SCIPY_POP}, {SCIPY_EVALS:,} evaluations, "
           "vectorized, no polish) identifying the same trace on the same objective.", "",
           "| trace | verdict read | emaphm, whole verdict | of it, the identification | "
           "SciPy DE, identification only | ratio |", "|---|---|---|---|---|---|"]
    for label in dict.fromkeys(r["trace"] for r in rows):
        rs = [r for r in rows if r["trace"] == label]
        reads = sorted({r["emaphm"]["verdict"] + (": " + ", ".join(
            m + (f" {p}" if p else "") for m, p in r["emaphm"]["named"]) if r["emaphm"]["named"]
            else "") for r in rs})
        out.append(f"| {label} | {'; '.join(reads)} | "
                   f"{_span([r['emaphm']['cpu_s'] for r in rs])} s | "
                   f"{_span([r['emaphm']['identify_cpu_s'] for r in rs])} s | "
                   f"{_span([r['scipy']['cpu_s'] for r in rs])} s | "
                   f"{_span([r['ratio'] for r in rs])}x |")
    out += ["", f"Median ratio {np.median(ratios):.2f}x, largest {max(ratios):.2f}x "
            f"(issue 36's target: median <= 0.1x, none above 0.3x)."]
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    main()
