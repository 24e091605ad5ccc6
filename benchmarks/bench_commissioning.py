"""Commissioning: production units on the reference plant, diagnosed before and after
``emaphm calibrate``.

Each unit is drawn from its own seed within :data:`emaphm.units.DEFAULT_TOLERANCES`
(inertia +-10 %, flux +-5 %, resistance 0..+25 %, inductance +-5 %, friction and
viscous +-20 %, current sensor gains +-3 % and offsets +-20 mA per phase, an
unreported load within +-0.1 N m). Per unit:

1. a healthy trace (noise seed 3) diagnosed with the data sheet: the verdict must
   never be ``faulty`` (``healthy`` or ``unexplained``);
2. ``calibrate`` on two other healthy traces (noise seeds 1, 2): CPU time, and
   whether the truth of each estimated deviation lies in its printed 95 % interval
   (for the inertia, kept while the flux is not separable, the truth is the
   ratio the model can see, ``(1 + dJ) / (1 + dflux) - 1``);
3. the healthy trace diagnosed with the calibrated parameters: verdict;
4. one fault added to the unit (in turn: friction x2.5, backlash at k2 = 0.75, gain
   drift k8 = 0.25, an inter-turn short of 10, 20 or 30 % of phase A, B or C through
   0.15 ohm), diagnosed with the calibrated parameters (and so, by default, with the
   winding resistance and magnet flux searched beside k): the right mode alone (the
   right phase for a short), and the Eq. 9 error; and the same faulty trace diagnosed
   with the data sheet (what a unit never calibrated gets, the mismatch check included).

Units use seeds 20000+, apart from every seed used to set a threshold; ``--tune``
draws units from 30000+ and prints each calibrated parameter's model discrepancy
(the RMS of estimate minus truth), which :data:`emaphm.calibration.DISCREPANCY`
adds to the standard errors.

Run: ``python benchmarks/bench_commissioning.py [--units 100] [--workers 2]`` ->
``benchmarks/results/commissioning.md`` and ``commissioning.json``.
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
from bench_plant import largest_deviations  # noqa: E402  (shared: what a threshold must exceed)

RESULTS = Path(__file__).parent / "results"
UNIT_SEED0 = 20_000
TUNE_SEED0 = 30_000
FAULTS = [("friction x2.5", 0, 0.75, "friction", None), ("backlash", 1, 0.75, "backlash", None),
          ("gain drift", 7, 0.25, "gain_drift", None)]
FAULTS += [(f"short {int(100 * mu)} % {ph}", 2 + j, mu, "short_circuit", ph)
           for mu in (0.1, 0.2, 0.3) for j, ph in enumerate("ABC")]


def run_unit(task: tuple[int, int]) -> dict:
    from emaphm.calibration import CalibrationError, calibrate
    from emaphm.diagnosis import fit_ratio_of
    from emaphm.faults import K_NOMINAL
    from emaphm.identify import IdentificationConfig
    from emaphm.verdict import examine
    from emaphm.params import siemens_1fk7060
    from emaphm.simulate import DEFAULT_SENSORS, simulate
    from emaphm.units import draw_unit

    i, seed0 = task
    sheet = siemens_1fk7060()
    unit = draw_unit(sheet, seed0 + i)
    healthy = [simulate(unit=unit, sensors=DEFAULT_SENSORS, seed=s, fault_model="physical")
               for s in (1, 2, 3)]

    def verdict(trace, params):
        # the verdict as `emaphm diagnose` gives it: the sensors from the currents' sum,
        # on the data sheet the mismatch check, the modes' hypotheses
        ex = examine(trace, params=params, config=IdentificationConfig(ALGORITHM), seed=0)
        return ex.identification, ex.diagnosis

    i0, d0 = verdict(healthy[2], sheet)
    out = {"unit": i, "deviations": unit.deviations,
           "uncal_verdict": d0.verdict, "uncal_fit_ratio": fit_ratio_of(i0),
           "uncal_faults": [f.mode for f in d0.faults],
           "uncal_reason": None if d0.unexplained is None else d0.unexplained.reason,
           "uncal_suspected": [f.mode for f in d0.suspected]}
    t = time.process_time()
    try:
        cal = calibrate(healthy[:2], sheet)
    except CalibrationError as exc:
        out.update(cal_error=str(exc), cal_cpu_s=time.process_time() - t)
        return out
    out["cal_cpu_s"] = time.process_time() - t
    dev = unit.deviations
    truth = {"J": (1 + dev["J"]) / (1 + dev["flux"]) - 1 if "flux" in cal.fixed else dev["J"],
             "flux": dev["flux"], "R": dev["R"], "L": dev["L"], "friction": dev["friction"],
             "viscous": dev["viscous"], "load": dev["load"]}
    for j, ph in enumerate("abc"):
        truth[f"gain_{ph}"] = dev["sensor_gain"][j]
        truth[f"offset_{ph}"] = dev["sensor_offset"][j]
    out["cal_fixed"] = list(cal.fixed)
    out["cal_covered"] = {n: bool(e["lo95"] <= truth[n] <= e["hi95"]) for n, e in cal.estimates.items()}
    out["cal_estimates"] = {n: [e["value"], e["se"], truth[n], e["se_stat"]]
                            for n, e in cal.estimates.items()}
    i1, d1 = verdict(healthy[2], cal.params)
    out.update(cal_verdict=d1.verdict, cal_fit_ratio=fit_ratio_of(i1),
               cal_faults=[f.mode for f in d1.faults], cal_k=i1.k.tolist())
    name, idx, val, mode, phase = FAULTS[i % len(FAULTS)]
    k = K_NOMINAL.copy()
    k[idx] = val
    faulty = simulate(k, unit=unit, sensors=DEFAULT_SENSORS, seed=4, fault_model="physical")
    i2, d2 = verdict(faulty, cal.params)
    out.update(fault=name, fault_mode=mode, fault_phase=phase, fault_verdict=d2.verdict,
               fault_named=[(f.mode, f.phase) for f in d2.faults], fault_error_pct=i2.error_pct,
               fault_fit_ratio=fit_ratio_of(i2), fault_k=i2.k.tolist(), fault_index=idx,
               fault_right=[(f.mode, f.phase) for f in d2.faults] == [(mode, phase)])
    # the same faulty trace on the data sheet: what a unit that was never calibrated gets
    i3, d3 = verdict(faulty, sheet)
    out.update(uncal_fault_verdict=d3.verdict,
               uncal_fault_reason=None if d3.unexplained is None else d3.unexplained.reason,
               uncal_fault_right=[(f.mode, f.phase) for f in d3.faults] == [(mode, phase)])
    return out


def report(rows: list[dict], wall: float, workers: int) -> str:
    n = len(rows)
    ok = [r for r in rows if "cal_error" not in r]
    cov: dict[str, list[bool]] = {}
    for r in ok:
        for name, c in r["cal_covered"].items():
            cov.setdefault(name, []).append(c)
    paper_modes = [r for r in ok if r["fault_mode"] != "short_circuit"]
    shorts = [r for r in ok if r["fault_mode"] == "short_circuit"]
    now = _dt.datetime.now(_dt.timezone.utc)
    out = [f"## Commissioning production units ({now:%Y-%m-%d %H:%M} UTC)", "",
           f"Machine: {machine()}; load "
           f"average {os.getloadavg()[0]:.2f} at the end; {n} units (seeds {UNIT_SEED0}+) in "
           f"{wall / 60:.1f} min wall on {workers} workers. Plant traces, physical fault model, "
           f"{ALGORITHM} with identify's defaults.", "",
           "| | result |", "|---|---|",
           f"| healthy unit, data-sheet parameters: verdict faulty | "
           f"{sum(r['uncal_verdict'] == 'faulty' for r in rows)}/{n} "
           f"(unexplained {sum(r['uncal_verdict'] == 'unexplained' for r in rows)}, healthy "
           f"{sum(r['uncal_verdict'] == 'healthy' for r in rows)}) |",
           f"| ... unexplained by the mismatch check (a fault read, explained as well by R, flux "
           f"and an unreported load) | {sum(r.get('uncal_reason') == 'mismatch' for r in rows)}/{n} "
           f"({', '.join(sorted({m for r in rows if r.get('uncal_reason') == 'mismatch' for m in r['uncal_suspected']})) or 'none'}) |",
           f"| calibration refused (unit does not look healthy) | "
           f"{n - len(ok)}/{n} |",
           f"| calibrated, third healthy trace: verdict healthy | "
           f"{sum(r['cal_verdict'] == 'healthy' for r in ok)}/{len(ok)} (faulty "
           f"{sum(r['cal_verdict'] == 'faulty' for r in ok)}) |",
           f"| fault added, right mode (and phase) alone | "
           f"{sum(r['fault_right'] for r in ok)}/{len(ok)} (shorts "
           f"{sum(r['fault_right'] for r in shorts)}/{len(shorts)}, other modes "
           f"{sum(r['fault_right'] for r in paper_modes)}/{len(paper_modes)}) |",
           f"| the same faulty trace with the data sheet (never calibrated): right mode alone | "
           f"{sum(r['uncal_fault_right'] for r in ok)}/{len(ok)} (unexplained "
           f"{sum(r['uncal_fault_verdict'] == 'unexplained' for r in ok)}, of which by the "
           f"mismatch check {sum(r['uncal_fault_reason'] == 'mismatch' for r in ok)}; a wrong "
           f"fault {sum(r['uncal_fault_verdict'] == 'faulty' and not r['uncal_fault_right'] for r in ok)}) |",
           f"| ... mean Eq. 9 error, friction/backlash/gain faults [%] | "
           f"{np.mean([r['fault_error_pct'] for r in paper_modes]):.2f} |" if paper_modes else "",
           f"| calibrate, CPU time per unit [s]: median (max) | "
           f"{np.median([r['cal_cpu_s'] for r in rows]):.2f} ({np.max([r['cal_cpu_s'] for r in rows]):.2f}) |",
           "", "Truth inside the printed 95 % interval, per estimated parameter (units where it "
           "was estimated): " + ", ".join(f"{k} {100 * np.mean(v):.0f} % ({len(v)})"
                                          for k, v in cov.items()), "",
           "Kept at the data sheet (not separable): " + ", ".join(
               f"{k} {sum(k in r['cal_fixed'] for r in ok)}x"
               for k in sorted({x for r in ok for x in r["cal_fixed"]}))]
    miss = [f"unit {r['unit']} {r['fault']}: {r['fault_verdict']} {r['fault_named']}"
            for r in ok if not r["fault_right"]]
    if miss:
        out += ["", "Faults not named right: " + "; ".join(miss)]
    return "\n".join(x for x in out) + "\n"


def not_at_fault(rows: list[dict]) -> dict[str, float]:
    """Each component's largest deviation from healthy on calibrated units where it is
    not at fault (the third healthy trace, and every other added fault), the quantity
    ``bench_plant.py --tune`` sets the detection thresholds from on the nominal unit."""
    return largest_deviations([(r["cal_k"], None) for r in rows if "cal_k" in r]
                              + [(r["fault_k"], r["fault_index"]) for r in rows if "fault_k" in r])


#: The identification algorithm (``--algorithm``; set before the worker processes fork).
ALGORITHM = "lsq"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--algorithm", default="lsq",
                    help="identification algorithm (default lsq, identify's default)")
    ap.add_argument("--units", type=int, default=100)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--tune", action="store_true",
                    help="units from the tuning seeds (30000+): print each parameter's model "
                         "discrepancy (RMS of estimate - truth) for emaphm.calibration")
    args = ap.parse_args()
    global ALGORITHM
    ALGORITHM = args.algorithm
    seed0 = TUNE_SEED0 if args.tune else UNIT_SEED0
    _warm()
    t0 = time.perf_counter()
    with ProcessPoolExecutor(args.workers, initializer=_warm) as ex:
        rows = list(ex.map(run_unit, [(i, seed0) for i in range(args.units)]))
    wall = time.perf_counter() - t0
    RESULTS.mkdir(exist_ok=True)
    if args.tune:
        (RESULTS / "commissioning_tuning.json").write_text(json.dumps(rows, indent=1, default=float))
        err: dict[str, list[float]] = {}
        for r in rows:
            for n, (v, _se, truth, _s) in r.get("cal_estimates", {}).items():
                err.setdefault(n, []).append(v - truth)
        print(json.dumps({n: {"rms": float(np.sqrt(np.mean(np.square(e)))), "n": len(e)}
                          for n, e in err.items()}, indent=1))
        print(json.dumps({"max_not_at_fault": not_at_fault(rows)}, indent=1))
        return
    (RESULTS / "commissioning.json").write_text(json.dumps(rows, indent=1, default=float))
    text = report(rows, wall, args.workers)
    (RESULTS / "commissioning.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
