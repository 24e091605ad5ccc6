"""Fault coverage beyond the paper (issue 21), on two actuators: the preset and
``examples/actuators/ema-270v-750w.toml`` (10 poles, 270 V, 750 W class), never tuned on.

Every trace comes from the reference plant (physics the monitoring model lacks: Stribeck
friction, PWM, leakage, the contact at its own step) and is diagnosed as ``emaphm
diagnose`` does (:func:`emaphm.verdict.examine`: current sensors from the sum of the
currents, identification, the verdict with the modes' hypotheses and checks).

A. **Inter-turn shorts on the data sheet** (the nominal unit, whose parameters are the
   data sheet's): each phase at shorted fractions 0.05-0.3 through fault resistances
   0.05-0.5 ohm; the right phase named alone, wrong phases, and the fault loop's
   ampere-turns, current and power against the plant's own (the plant reports them;
   within 25 %, and inside the reported ranges of the fits as good).
B. **Commissioned production units** (drawn within :data:`emaphm.units.DEFAULT_TOLERANCES`,
   calibrated on two healthy traces, then diagnosed with their calibration): a healthy
   trace (false alarms, Wilson 95 % interval), a demagnetization of 15 %, a current
   sensor reading 10 % low, one with an offset of +0.2 A, and an inter-turn short of 10 %
   (each on the unit's own phase in turn): the right mode (and phase) named alone, and the
   short never called a sensor fault.

Reported seeds: units 50000+, noise seeds as listed; ``--tune`` runs units 60000+ and
prints what the healthy ones show against each new threshold (the largest single-sensor
gain and offset deviation, the largest flux loss read), seeds no reported figure uses.

Run: ``python benchmarks/bench_fault_coverage.py [--units 20] [--workers 2] [--tune]``
-> ``benchmarks/results/fault_coverage.md`` and ``fault_coverage.json``; ``--offsets``: C.
**Current-sensor offsets** of +-0.1 to +-0.3 A on each phase of the commissioned units ->
``sensor_offsets.md``; ``--tune-shorts``: the coverage of the short's profile intervals on
tuning noise seeds 200+ (what set :data:`emaphm.fault_loops.PROFILE_LR`).
"""

from __future__ import annotations

import os

for _v in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import datetime as _dt  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402
from concurrent.futures import ProcessPoolExecutor  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from _actuators import ACTUATORS, datasheet  # noqa: E402
from bench_identification import _warm, machine  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(__file__).parent / "results"
UNIT_SEED0 = 50_000
TUNE_SEED0 = 60_000
SHORT_MU = (0.05, 0.1, 0.2, 0.3)
SHORT_RF = (0.05, 0.15, 0.5)


def _named(diag) -> list[tuple[str, str | None]]:
    return [(f.mode, f.phase) for f in diag.faults]


def run_short(task: tuple[str, str, float, float, int]) -> dict:
    """One data-sheet short: ``(actuator, phase, mu, R_f, noise seed)``."""
    from emaphm.simulate import DEFAULT_SENSORS, simulate
    from emaphm.verdict import examine

    name, ph, mu, rf, seed = task
    params = datasheet(name)
    tr = simulate(faults=[f"short_circuit:{ph}:{mu}:{rf}"], params=params,
                  sensors=DEFAULT_SENSORS, seed=seed)
    j = "abc".index(ph)
    t0 = time.process_time()
    ex = examine(tr, params=params, seed=0)
    cpu = time.process_time() - t0
    d = ex.diagnosis
    truth = tr.meta["plant"]["fault_current_a_rms"][j]
    truth_mmf = tr.meta["plant"]["fault_mmf_a_rms"][j]
    truth_p = tr.meta["plant"]["fault_power_w"][j]
    shorts = [f for f in d.faults if f.mode == "short_circuit"]
    mine = [f for f in shorts if f.phase == ph.upper()]
    read = mine[0].details if mine else {}
    cur = read.get("fault_current_a_rms")
    iv = read.get("fault_current_interval")
    mmf = read.get("fault_mmf_a_rms")
    return {"actuator": name, "phase": ph, "mu": mu, "R_f": rf, "seed": seed, "cpu_s": cpu,
            "verdict": d.verdict, "named": _named(d),
            "right_alone": _named(d) == [("short_circuit", ph.upper())],
            "wrong_phase": any(f.phase != ph.upper() for f in shorts),
            "sensor": any(f.mode == "current_sensor" for f in d.faults),
            "plant_current": truth, "current": cur, "interval": iv,
            "mu_read": read.get("mu"), "R_f_read": read.get("R_f_ohm"),
            "within_25": cur is not None and abs(cur - truth) <= 0.25 * truth,
            "in_interval": iv is not None and iv[0] * 0.999 <= truth <= iv[1] * 1.001,
            "plant_mmf": truth_mmf, "mmf": read.get("fault_mmf_a_rms"),
            "mmf_interval": read.get("fault_mmf_interval"),
            "mmf_within_25": mmf is not None and abs(mmf - truth_mmf) <= 0.25 * truth_mmf,
            "plant_power": truth_p, "power": read.get("fault_power_w"),
            "power_interval": read.get("fault_power_interval"),
            "plant_mu": mu, "mu_interval": read.get("mu_interval"),
            "plant_R_f": rf, "R_f_interval": read.get("R_f_interval"),
            "determined": read.get("determined"), "open": read.get("open"),
            "profile": read.get("profile"),
            "others": [f for f in _named(d) if f != ("short_circuit", ph.upper())],
            "refit": None if d.refit is None else d.refit.mode}


def _unit_faults(u: int) -> list[tuple[str, str, tuple | None]]:
    """The faults unit ``u`` is diagnosed with: (label, spec, expected named faults)."""
    ph = "abc"
    a, b, c = ph[u % 3], ph[(u + 1) % 3], ph[(u + 2) % 3]
    return [("healthy", None, ()),
            ("demagnetization 15 %", "demagnetization:0.15", (("demagnetization", None),)),
            ("sensor gain 0.9", f"current_sensor:{a}:gain:0.9", (("current_sensor", a.upper()),)),
            ("sensor offset +0.2 A", f"current_sensor:{b}:offset:0.2", (("current_sensor", b.upper()),)),
            ("short 10 %", f"short_circuit:{c}:0.1", (("short_circuit", c.upper()),))]


def run_unit(task: tuple[str, int]) -> dict:
    """One commissioned unit: calibrate on two healthy traces, diagnose its faults."""
    from emaphm.calibration import CalibrationError, calibrate
    from emaphm.modes import THRESHOLDS_BY_FAULT_MODEL
    from emaphm.modes.current_sensor import screen
    from emaphm.simulate import DEFAULT_SENSORS, simulate
    from emaphm.units import draw_unit
    from emaphm.verdict import examine

    name, seed = task
    sheet = datasheet(name)
    unit = draw_unit(sheet, seed)
    healthy = [simulate(unit=unit, params=sheet, sensors=DEFAULT_SENSORS, seed=s) for s in (1, 2)]
    t0 = time.process_time()
    try:
        cal = calibrate(healthy, sheet)
    except CalibrationError as exc:
        return {"actuator": name, "unit": seed, "error": str(exc)}
    out = {"actuator": name, "unit": seed, "calibrate_cpu_s": time.process_time() - t0,
           "runs": []}
    thr = THRESHOLDS_BY_FAULT_MODEL["physical"]
    for i, (label, spec, expected) in enumerate(_unit_faults(seed)):
        tr = simulate(unit=unit, params=sheet, faults=[spec] if spec else [],
                      sensors=DEFAULT_SENSORS, seed=3 + i)
        t0 = time.process_time()
        ex = examine(tr, params=cal.params, seed=0)
        cpu = time.process_time() - t0
        d = ex.diagnosis
        fin = screen(tr, cal.params, thr)
        out["runs"].append({
            "fault": label, "spec": spec, "verdict": d.verdict, "named": _named(d),
            "right_alone": d.verdict == ("faulty" if expected else "healthy")
            and tuple(_named(d)) == tuple(expected),
            "sensor_named": any(f.mode == "current_sensor" for f in d.faults),
            "cpu_s": cpu, "flux": ex.identification.nuisance.get("flux"),
            "gain_dev": abs(fin.fit.gain - 1.0) if fin.fit else None,
            "offset_dev": abs(fin.fit.offset) if fin.fit else None,
            "refit": None if d.refit is None else d.refit.mode})
    return out


#: Part C's sensor offsets [A], each on each phase of every unit.
OFFSETS = (-0.3, -0.2, -0.1, 0.1, 0.2, 0.3)


def run_offsets(task: tuple[str, int]) -> dict:
    """Part C, one commissioned unit: calibrate it on two healthy traces, then an offset of
    each size of :data:`OFFSETS` on each phase (one trace each, noise seeds 10+)."""
    from emaphm.calibration import CalibrationError, calibrate
    from emaphm.simulate import DEFAULT_SENSORS, simulate
    from emaphm.units import draw_unit
    from emaphm.verdict import examine

    name, seed = task
    sheet = datasheet(name)
    unit = draw_unit(sheet, seed)
    healthy = [simulate(unit=unit, params=sheet, sensors=DEFAULT_SENSORS, seed=s) for s in (1, 2)]
    try:
        cal = calibrate(healthy, sheet)
    except CalibrationError as exc:
        return {"actuator": name, "unit": seed, "error": str(exc)}
    runs = []
    for i, (ph, off) in enumerate((ph, off) for ph in "abc" for off in OFFSETS):
        tr = simulate(unit=unit, params=sheet, faults=[f"current_sensor:{ph}:offset:{off}"],
                      sensors=DEFAULT_SENSORS, seed=10 + i)
        d = examine(tr, params=cal.params, seed=0).diagnosis
        runs.append({"phase": ph, "offset": off, "verdict": d.verdict, "named": _named(d),
                     "right_alone": _named(d) == [("current_sensor", ph.upper())]})
    return {"actuator": name, "unit": seed, "runs": runs}


def _offsets_table(units: list[dict]) -> list[str]:
    out = ["| actuator | offset [A] | runs | named right, alone | interval (Wilson 95 %) | "
           "unexplained | another fault named |", "|---|---|---|---|---|---|---|"]
    for name in ACTUATORS:
        us = [u for u in units if u["actuator"] == name and "runs" in u]
        for off in OFFSETS:
            rs = [r for u in us for r in u["runs"] if r["offset"] == off]
            n, k = len(rs), sum(r["right_alone"] for r in rs)
            lo, hi = wilson(k, n)
            out.append(f"| {name} | {off:+g} | {n} | {k}/{n} | {100 * lo:.0f}-{100 * hi:.0f} % | "
                       f"{sum(r['verdict'] == 'unexplained' for r in rs)} | "
                       f"{sum(r['verdict'] == 'faulty' and not r['right_alone'] for r in rs)} |")
        rs = [r for u in us for r in u["runs"]]
        k = sum(r["right_alone"] for r in rs)
        lo, hi = wilson(k, len(rs))
        out.append(f"| {name} | all | {len(rs)} | {k}/{len(rs)} | {100 * lo:.0f}-{100 * hi:.0f} % | "
                   f"{sum(r['verdict'] == 'unexplained' for r in rs)} | "
                   f"{sum(r['verdict'] == 'faulty' and not r['right_alone'] for r in rs)} |")
        failed = [u for u in units if u["actuator"] == name and "error" in u]
        if failed:
            out.append(f"| {name} | calibration refused | {len(failed)} units | | | | |")
    return out


def wilson(k: int, n: int, z: float = 1.959964) -> tuple[float, float]:
    """Wilson score 95 % interval of a proportion k/n."""
    if n == 0:
        return (math.nan, math.nan)
    p = k / n
    den = 1 + z * z / n
    centre = (p + z * z / (2 * n)) / den
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / den
    return (max(0.0, centre - half), min(1.0, centre + half))


def _shorts_table(rows: list[dict]) -> list[str]:
    out = ["| actuator | runs | right phase alone | wrong phase | another fault beside | "
           "unexplained | called a sensor fault | ampere-turns within 25 % | current within "
           "25 % | plant current in its interval | plant power in its interval | plant "
           "fraction in its interval | current interval's width (median, max) | current "
           "determined | median CPU |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for name in ACTUATORS:
        rs = [r for r in rows if r["actuator"] == name]
        n = len(rs)
        inside = lambda x, iv: iv is not None and iv[0] * 0.999 <= x <= iv[1] * 1.001  # noqa: E731
        p_in = sum(inside(r["plant_power"], r["power_interval"]) for r in rs)
        mu_in = sum(inside(r["plant_mu"], r.get("mu_interval")) for r in rs)
        widths = [r["interval"][1] / r["interval"][0] for r in rs if r["interval"]]
        out.append(f"| {name} | {n} | {sum(r['right_alone'] for r in rs)}/{n} | "
                   f"{sum(r['wrong_phase'] for r in rs)} | "
                   f"{sum(bool(r.get('others')) for r in rs)} | "
                   f"{sum(r['verdict'] == 'unexplained' for r in rs)} | "
                   f"{sum(r['sensor'] for r in rs)} | {sum(r['mmf_within_25'] for r in rs)}/{n} | "
                   f"{sum(r['within_25'] for r in rs)}/{n} | "
                   f"{sum(r['in_interval'] for r in rs)}/{n} | {p_in}/{n} | {mu_in}/{n} | "
                   f"{np.median(widths):.2f}x, {max(widths):.2f}x | "
                   f"{sum('fault_current_a_rms' in (r.get('determined') or ()) for r in rs)}/{n} | "
                   f"{np.median([r['cpu_s'] for r in rs]):.2f} s |")
    out += ["", "By shorted fraction (both actuators): ampere-turns within 25 % / current within "
            "25 % / current in the range / named right alone", "",
            "| fraction | " + " | ".join(f"R_f {rf} ohm" for rf in SHORT_RF)
            + " |", "|---|" + "---|" * len(SHORT_RF)]
    for mu in SHORT_MU:
        cells = []
        for rf in SHORT_RF:
            rs = [r for r in rows if r["mu"] == mu and r["R_f"] == rf]
            cells.append(f"{sum(r['mmf_within_25'] for r in rs)}/{sum(r['within_25'] for r in rs)}"
                         f"/{sum(r['in_interval'] for r in rs)}"
                         f"/{sum(r['right_alone'] for r in rs)} of {len(rs)}")
        out.append(f"| {mu} | " + " | ".join(cells) + " |")
    return out


#: The tolerances of the short's profile tried by ``--tune-shorts`` (its likelihood-ratio
#: threshold, :data:`emaphm.fault_loops.PROFILE_LR`).
TOLERANCES = (0.02, 0.05, 0.1, 0.15, 0.2, 0.3, 0.5)


def _covered(r: dict, tolerance: float) -> dict[str, bool] | None:
    """Whether the plant's loop current, power, shorted fraction and bridge fall inside the
    intervals the run's profile gives at ``tolerance`` (None: no profile, the short not
    read)."""
    from emaphm.fault_loops import QUANTITIES, intervals

    prof = r.get("profile")
    if not prof:
        return None
    Q = {q: np.asarray(prof[q]) for q in QUANTITIES}
    at = {q: r[k] for q, k in (("fault_current_a_rms", "current"), ("fault_power_w", "power"),
                               ("fault_mmf_a_rms", "mmf"), ("mu", "mu_read"),
                               ("R_f_ohm", "R_f_read"))}
    iv = intervals(Q, np.asarray(prof["fit_over_best"]), at, tolerance)
    inside = lambda x, ab: ab[0] * 0.999 <= x <= ab[1] * 1.001   # noqa: E731
    return {"current": inside(r["plant_current"], iv["fault_current_interval"]),
            "power": inside(r["plant_power"], iv["fault_power_interval"]),
            "mu": inside(r["plant_mu"], iv["mu_interval"]),
            "R_f": inside(r["plant_R_f"], iv["R_f_interval"]),
            "width": iv["fault_current_interval"][1] / iv["fault_current_interval"][0]}


def _tune_shorts(rows: list[dict]) -> list[str]:
    """Coverage of the plant's loop by the profile's intervals at each tolerance."""
    out = ["| tolerance | runs | plant current inside | power | shorted fraction | bridge "
           "| median current width (hi/lo) |", "|---|---|---|---|---|---|---|"]
    for tol in TOLERANCES:
        cov = [c for c in (_covered(r, tol) for r in rows) if c is not None]
        n = len(cov)
        out.append(f"| {tol:g} | {n} | " + " | ".join(
            f"{sum(c[q] for c in cov)}/{n}" for q in ("current", "power", "mu", "R_f"))
            + f" | {np.median([c['width'] for c in cov]):.2f} |")
    return out


def _profile_lr() -> float:
    from emaphm.fault_loops import PROFILE_LR

    return PROFILE_LR


def _units_table(units: list[dict]) -> list[str]:
    out = ["| actuator | fault | units | named right, alone | interval (Wilson 95 %) | faulty | "
           "unexplained | median CPU |", "|---|---|---|---|---|---|---|---|"]
    for name in ACTUATORS:
        us = [u for u in units if u["actuator"] == name and "runs" in u]
        for label in [f[0] for f in _unit_faults(0)]:
            rs = [r for u in us for r in u["runs"] if r["fault"] == label]
            n, k = len(rs), sum(r["right_alone"] for r in rs)
            lo, hi = wilson(k, n)
            out.append(f"| {name} | {label} | {n} | {k}/{n} | {100 * lo:.0f}-{100 * hi:.0f} % | "
                       f"{sum(r['verdict'] == 'faulty' for r in rs)} | "
                       f"{sum(r['verdict'] == 'unexplained' for r in rs)} | "
                       f"{np.median([r['cpu_s'] for r in rs]):.2f} s |")
        shorts = [r for u in us for r in u["runs"] if r["fault"].startswith("short")]
        out.append(f"| {name} | 10 % short called a sensor fault | {len(shorts)} | "
                   f"{sum(r['sensor_named'] for r in shorts)} | | | | |")
        failed = [u for u in units if u["actuator"] == name and "error" in u]
        if failed:
            out.append(f"| {name} | calibration refused | {len(failed)} | | | | | |")
    return out


def _tune(units: list[dict]) -> list[str]:
    healthy = [r for u in units if "runs" in u for r in u["runs"] if r["fault"] == "healthy"]
    g = max(r["gain_dev"] for r in healthy)
    o = max(r["offset_dev"] for r in healthy)
    flux = min(r["flux"] for r in healthy if r["flux"] is not None)
    from emaphm.modes import DEFAULT_THRESHOLDS as T

    return [f"tuning units ({len(healthy)} healthy traces): largest single-sensor gain deviation "
            f"{g:.4f} (threshold {T.current_sensor_gain}), offset {o:.4f} A (threshold "
            f"{T.current_sensor_offset}), lowest flux drift read {flux:+.4f} (demagnetization "
            f"threshold -{T.demagnetization})"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--units", type=int, default=20, help="production units per actuator")
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--tune", action="store_true", help="the tuning units 60000+ only")
    ap.add_argument("--tune-shorts", action="store_true",
                    help="shorts on tuning noise seeds 200+ only: the coverage of the plant's "
                         "loop by the profile's intervals at each tolerance")
    ap.add_argument("--offsets", action="store_true",
                    help="part C only: sensor offsets of +-0.1 to +-0.3 A on each phase of "
                         "commissioned units (seeds 50000+) -> results/sensor_offsets.md")
    args = ap.parse_args()
    if args.offsets:
        t0 = time.time()
        with ProcessPoolExecutor(args.workers, initializer=_warm) as ex:
            units = list(ex.map(run_offsets, [(name, UNIT_SEED0 + u) for name in ACTUATORS
                                              for u in range(args.units)]))
        now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
        lines = [f"## Current-sensor offsets on commissioned units ({now})", "",
                 f"Machine: {machine()}; load average {os.getloadavg()[0]:.2f} at the end; "
                 f"{(time.time() - t0) / 60:.1f} min wall on {args.workers} workers. "
                 f"`benchmarks/bench_fault_coverage.py --offsets`: {args.units} production "
                 f"units per actuator (seeds {UNIT_SEED0}+), each calibrated on two healthy "
                 "traces (noise seeds 1, 2), then an offset of each size on each phase (one "
                 "trace each, noise seeds 10+), diagnosed as `emaphm diagnose` does with the "
                 "calibration: the right sensor named, alone.", ""] + _offsets_table(units)
        (RESULTS / "sensor_offsets.md").write_text("\n".join(lines) + "\n")
        (RESULTS / "sensor_offsets.json").write_text(json.dumps(units, indent=1))
        print("\n".join(lines))
        return
    if args.tune_shorts:
        tasks = [(name, ph, mu, rf, 200 + i) for name in ACTUATORS
                 for i, (ph, mu, rf) in enumerate((ph, mu, rf) for ph in "abc"
                                                  for mu in SHORT_MU for rf in SHORT_RF)]
        with ProcessPoolExecutor(args.workers, initializer=_warm) as ex:
            rows = list(ex.map(run_short, tasks))
        (RESULTS / "fault_coverage_shorts_tuning.json").write_text(json.dumps(rows, indent=1))
        print("\n".join(_tune_shorts(rows)))
        return
    seed0 = TUNE_SEED0 if args.tune else UNIT_SEED0
    t0 = time.time()
    shorts = [] if args.tune else [
        (name, ph, mu, rf, 100 + i) for name in ACTUATORS
        for i, (ph, mu, rf) in enumerate((ph, mu, rf) for ph in "abc" for mu in SHORT_MU
                                         for rf in SHORT_RF)]
    unit_tasks = [(name, seed0 + u) for name in ACTUATORS for u in range(args.units)]
    with ProcessPoolExecutor(args.workers, initializer=_warm) as ex:
        short_rows = list(ex.map(run_short, shorts))
        units = list(ex.map(run_unit, unit_tasks))
    wall = time.time() - t0
    if args.tune:
        print("\n".join(_tune(units)))
        (RESULTS / "fault_coverage_tuning.json").write_text(json.dumps(units, indent=1))
        return
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    lines = [f"## Fault coverage beyond the paper: severe shorts, demagnetization, current sensors ({now})",
             "", f"Machine: {machine()}; load average {os.getloadavg()[0]:.2f} at the end; "
             f"{wall / 60:.1f} min wall on {args.workers} workers. Reference-plant traces "
             "diagnosed as `emaphm diagnose` does (`emaphm.verdict.examine`). Actuators: the "
             "preset and `examples/actuators/ema-270v-750w.toml` (never tuned on). "
             "`benchmarks/bench_fault_coverage.py`.", "",
             "### A. Inter-turn shorts on the data sheet (the nominal unit)", "",
             f"Each phase at shorted fractions {', '.join(map(str, SHORT_MU))} through "
             f"{', '.join(map(str, SHORT_RF))} ohm (noise seeds 100+). The fault-loop current is "
             "the monitoring model's at the fit, against the RMS current the plant reports (its "
             "PWM ripple included); the intervals are those of the profile of the fit along "
             "the fault resistance (`emaphm.fault_loops`: the fits within `PROFILE_LR` = "
             f"{_profile_lr():g} of the best, tuned on noise seeds 200+ with `--tune-shorts`), "
             "a quantity determined where its interval spans less than a factor 2. The "
             "ampere-turns are the loop's `mu i_f` rms, what the terminal currents see: for a "
             "mild short the shorted fraction and the bridge trade off along a valley where "
             "the current and the power change and the ampere-turns do not.", ""]
    lines += _shorts_table(short_rows)
    lines += ["", f"### B. Commissioned production units ({args.units} per actuator, seeds "
              f"{UNIT_SEED0}+)", "",
              "Calibrated on two healthy traces (noise seeds 1, 2), then each fault on its own "
              "trace (seeds 3-7), diagnosed with the calibration; a sensor fault and the short "
              "on the unit's own phase in turn.", ""]
    lines += _units_table(units)
    (RESULTS / "fault_coverage.md").write_text("\n".join(lines) + "\n")
    (RESULTS / "fault_coverage.json").write_text(json.dumps(
        {"shorts": short_rows, "units": units, "wall_s": wall}, indent=1))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
