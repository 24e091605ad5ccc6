"""Drives that are not emaphm's (issue 32): fault rates on firmwares the parameters do not
describe, on two actuators (the preset and ``examples/actuators/ema-270v-750w.toml``).

Every trace comes from the reference plant with an inverter that loses 1 us of dead time
and 1 V of device drop per leg, a 17-bit encoder and the recording chain's current noise,
on production units drawn within :data:`emaphm.units.DEFAULT_TOLERANCES`. The plant's drive
runs one of these firmwares:

==================  ===========================================================================
firmware            what it is
==================  ===========================================================================
``emaphm``          emaphm's plain cascade (what the data sheet's ``[controller]`` describes)
``feed-forwards``   emaphm's cascade with velocity and torque feed-forward (gain 1 each)
``speed-filter``    emaphm's cascade with a 1 ms low-pass on the speed feedback
``position-pi``     emaphm's cascade with a position PI (Ki = 5 Kp), lower torque (2/3) and
                    current (2/3) limits and a slower speed limit (0.6 omega_max)
``observer-ip``     a foreign drive: I-P speed loop on an observed speed, delay with angle
                    advance (:mod:`emaphm.models.drives`)
``deadbeat``        a foreign drive: predictive current control
``stationary-pi``   a foreign drive: 2-DOF speed PI on a differenced speed, per-phase current
                    PI in the stationary frame
==================  ===========================================================================

A. **Recorded voltages, [controller] NOT describing the drive**: each unit calibrated on
   two healthy traces with the drive's voltage commands (the data sheet's ``[controller]``:
   emaphm's plain cascade), then a third healthy trace and, one at a time, a 10 % short of
   phase A through 0.15 ohm, friction x2, a magnet 15 % weaker and phase B's current sensor
   10 % low, each diagnosed as ``emaphm diagnose`` does: healthy read healthy, each fault
   named right and alone.
B. **The drive described in [controller], no voltages recorded** (the modelled-controller
   path), for the firmwares [controller] can describe: the same, with the firmware in the
   parameters' ``[controller]`` and the inverter's dead time and drop in their ``[inverter]``.
D. **Recorded current references, [controller] NOT describing the drive's outer loops**: as
   A, with the drive's current references ``i_d_ref, i_q_ref`` and no voltages in the
   traces, for the firmwares whose current loop is the data sheet's (emaphm's cascade with
   its options outside the current loop): the current loop modelled, the speed and position
   loops not.
C. **On the data sheet, a drive neither described nor recorded**: healthy units on
   firmwares with a speed filter of 0.1, 0.25 and 1 ms, a period of delay, both
   feed-forwards, a position integrator: the verdicts (``faulty`` must never be one).

Unit seeds 70000+ (no figure is tuned on them), noise seeds 1-5 per trace as listed.

Run: ``python benchmarks/bench_drives.py [--units 20] [--workers 2] [--parts ABCD]
[--firmwares F,...] [--tag TAG]`` -> ``benchmarks/results/drives[-TAG].md`` and ``.json``.
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
from dataclasses import replace  # noqa: E402
from pathlib import Path  # noqa: E402

from _actuators import ACTUATORS, datasheet as _datasheet  # noqa: E402
from _machine import machine  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(__file__).parent / "results"
UNIT_SEED0 = 70_000
TUNE_SEED0 = 80_000
FIRMWARES = ("emaphm", "feed-forwards", "speed-filter", "position-pi", "observer-ip", "deadbeat",
             "stationary-pi")
DESCRIBABLE = ("emaphm", "feed-forwards", "speed-filter", "position-pi")
FAULTS = {"healthy": (), "short 10 % A": ("short_circuit:a:0.1:0.15",),
          "friction x2": ("friction:2",), "demagnetization 15 %": ("demagnetization:0.15",),
          "sensor B gain 0.9": ("current_sensor:b:gain:0.9",),
          "connection C x1.3": ("resistance:c:1.3",)}
EXPECTED = {"healthy": set(), "short 10 % A": {("short_circuit", "A")},
            "friction x2": {("friction", None)},
            "demagnetization 15 %": {("demagnetization", None)},
            "sensor B gain 0.9": {("current_sensor", "B")},
            "connection C x1.3": {("resistance", "C")}}
#: Part C's undescribed firmwares: [controller] options the data sheet does not state.
UNDESCRIBED = {"speed filter 0.1 ms": dict(speed_filter_s=1e-4),
               "speed filter 0.25 ms": dict(speed_filter_s=2.5e-4),
               "speed filter 1 ms": dict(speed_filter_s=1e-3),
               "a period of delay": dict(delay_periods=1),
               "feed-forwards": dict(velocity_feedforward=1.0, torque_feedforward=1.0),
               "position integrator": "position-pi-integrator"}


def _firmware(datasheet, firmware: str):
    """``(plant parameters, drive name)``: the data sheet with the firmware's
    ``[controller]`` options (emaphm's cascade) or a foreign drive, and the inverter's dead
    time and device drop."""
    ctl = datasheet.controller
    options = {"emaphm": {}, "feed-forwards": dict(velocity_feedforward=1.0, torque_feedforward=1.0),
               "speed-filter": dict(speed_filter_s=1e-3),
               "position-pi": dict(Ki=5.0 * ctl.Kp, T_max=datasheet.motor.T_max * 2 / 3,
                                   I_max=datasheet.motor.I_max * 2 / 3,
                                   omega_max=0.6 * ctl.omega_max),
               "position-pi-integrator": dict(Ki=5.0 * ctl.Kp)}
    plant = replace(datasheet, inverter=replace(datasheet.inverter, dead_time=1e-6, device_drop=1.0))
    if firmware in options:
        return replace(plant, controller=replace(ctl, **options[firmware])), None
    return plant, firmware


def _sensors():
    from emaphm.simulate import DEFAULT_SENSORS

    return replace(DEFAULT_SENSORS, encoder_counts=2 ** 17)


def _named(diag) -> list[list]:
    return [[f.mode, f.phase] for f in diag.faults]


def run_unit(task: tuple[str, str, str, int]) -> dict:
    """One unit of part A or B: ``(actuator, firmware, part, unit seed)``."""
    from emaphm.calibration import CalibrationError, calibrate
    from emaphm.simulate import simulate
    from emaphm.verdict import examine

    name, firmware, part, unit_seed = task
    datasheet = _datasheet(name)
    plant, drive = _firmware(datasheet, firmware)
    recorded = part in "AD"
    # A: the parameters state emaphm's plain cascade and no dead time; B: the drive as it
    # is, its firmware ([controller]) and its inverter's dead time and drops ([inverter])
    params = datasheet if recorded else replace(datasheet, controller=plant.controller,
                                                inverter=plant.inverter)
    kw = dict(params=plant, sensors=_sensors(), unit_seed=unit_seed, drive=drive,
              drive_signals=recorded)

    def record(seed, faults=()):
        tr = simulate(seed=seed, faults=list(faults), **kw)
        if part == "D":                # the current references, no voltages
            tr = replace(tr, drive={n: tr.drive[n] for n in ("i_d_ref", "i_q_ref")})
        return tr

    out = {"actuator": name, "firmware": firmware, "part": part, "unit_seed": unit_seed}
    t0 = time.process_time()
    try:
        cal = calibrate([record(1), record(2)], params)
    except CalibrationError as exc:
        out.update(calibrated=False, error=str(exc), cpu_s=time.process_time() - t0)
        return out
    out.update(calibrated=True, calibration_cpu_s=time.process_time() - t0,
               estimates={n: e["value"] for n, e in cal.estimates.items()})
    cases = {}
    for j, (case, faults) in enumerate(FAULTS.items()):
        tr = record(3 + j, faults)
        t1 = time.process_time()
        ex = examine(tr, params=cal.params, seed=0)
        d = ex.diagnosis
        ratio = float(ex.identification.fitness / ex.identification.noise_floor)
        cases[case] = {"verdict": d.verdict, "named": _named(d),
                       "read": [[f.mode, f.phase] for f in (*d.faults, *d.suspected)],
                       "k": [float(x) for x in d.k],
                       "drive_model": ex.identification.drive_model, "fit_ratio": ratio,
                       "verdict_ratio": d.refit.fit_ratio if d.refit is not None else ratio,
                       "cpu_s": time.process_time() - t1}
    out["cases"] = cases
    out["cpu_s"] = time.process_time() - t0
    return out


def run_undescribed(task: tuple[str, str, int]) -> dict:
    """One healthy unit of part C: ``(actuator, undescribed firmware, unit seed)``."""
    from emaphm.simulate import simulate
    from emaphm.verdict import examine

    name, label, unit_seed = task
    datasheet = _datasheet(name)
    spec = UNDESCRIBED[label]
    if isinstance(spec, str):
        plant, drive = _firmware(datasheet, spec)
    else:
        plant, drive = _firmware(datasheet, "emaphm")
        plant = replace(plant, controller=replace(plant.controller, **spec))
    tr = simulate(params=plant, sensors=_sensors(), unit_seed=unit_seed, drive=drive, seed=1)
    t0 = time.process_time()
    ex = examine(tr, params=datasheet, seed=0)
    return {"actuator": name, "firmware": label, "unit_seed": unit_seed,
            "verdict": ex.diagnosis.verdict, "named": _named(ex.diagnosis),
            "cpu_s": time.process_time() - t0}


def _right(case: str, c: dict) -> bool:
    return ({tuple(x) for x in c["named"]} == EXPECTED[case]
            and c["verdict"] == ("healthy" if case == "healthy" else "faulty"))


def _wilson(k: int, n: int) -> tuple[float, float]:
    if n == 0:
        return (float("nan"), float("nan"))
    z = 1.959963984540054
    p = k / n
    d = 1 + z * z / n
    c = (p + z * z / (2 * n)) / d
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return max(0.0, c - h), min(1.0, c + h)


def report(units: list[dict], undescribed: list[dict], args, wall: float) -> str:
    lines = ["## Drives that are not emaphm's (`benchmarks/bench_drives.py`)\n",
             f"Machine: {machine('numba', 'scipy')}; {args.workers} worker processes, load "
             f"average {os.getloadavg()[0]:.2f} at the end; "
             f"{_dt.datetime.now(_dt.timezone.utc):%Y-%m-%d %H:%M} UTC; {wall:.0f} s wall. "
             f"Units {UNIT_SEED0}+ ({args.units} per actuator and firmware), every plant with 1 us "
             "of dead time, 1 V device drop and a 17-bit encoder.\n"]
    for part, title in (("A", "A. Recorded voltages, `[controller]` not describing the drive "
                              "(calibrated units)"),
                        ("B", "B. The drive described in `[controller]`, no voltages recorded "
                              "(calibrated units)"),
                        ("D", "D. Recorded current references, `[controller]` not describing "
                              "the outer loops (calibrated units)")):
        rows = [u for u in units if u["part"] == part]
        if not rows:
            continue
        lines += [f"### {title}\n", "| actuator | firmware | calibrated | "
                  + " | ".join(FAULTS) + " |", "|---|---|---|" + "---|" * len(FAULTS)]
        for name in ACTUATORS:
            for fw in FIRMWARES:
                us = [u for u in rows if u["actuator"] == name and u["firmware"] == fw]
                if not us:
                    continue
                cal = [u for u in us if u["calibrated"]]
                cells = []
                for case in FAULTS:
                    k = sum(_right(case, u["cases"][case]) for u in cal)
                    cells.append(f"{k}/{len(cal)}")
                lines.append(f"| {name} | {fw} | {len(cal)}/{len(us)} | " + " | ".join(cells) + " |")
        lines.append("")
        misses = [(u["actuator"], u["firmware"], u["unit_seed"], case, c["verdict"], c["named"],
                   round(c["fit_ratio"], 2))
                  for u in rows if u["calibrated"] for case, c in u["cases"].items()
                  if not _right(case, c)]
        if misses:
            lines.append("Not right: " + "; ".join(
                f"{a} {f} unit {s} {case}: {v} {n} (fit {r}x)" for a, f, s, case, v, n, r in misses[:40])
                + (f"; and {len(misses) - 40} more" if len(misses) > 40 else "") + ".\n")
        refused = [(u["actuator"], u["firmware"], u["unit_seed"], u["error"][:160])
                   for u in rows if not u["calibrated"]]
        if refused:
            lines.append("Calibration refused: " + "; ".join(f"{a} {f} unit {s}: {e}"
                                                             for a, f, s, e in refused[:10]) + ".\n")
        cpu = [c["cpu_s"] for u in rows if u["calibrated"] for c in u["cases"].values()]
        if cpu:
            cpu.sort()
            lines.append(f"CPU per diagnosis: median {cpu[len(cpu) // 2]:.2f} s, max {cpu[-1]:.2f} s.\n")
    if undescribed:
        lines += ["### C. On the data sheet, a drive neither described nor recorded (healthy "
                  "units)\n", "| actuator | firmware | healthy | unexplained | faulty |",
                  "|---|---|---|---|---|"]
        for name in ACTUATORS:
            for label in UNDESCRIBED:
                us = [u for u in undescribed if u["actuator"] == name and u["firmware"] == label]
                if us:
                    v = [u["verdict"] for u in us]
                    lines.append(f"| {name} | {label} | {v.count('healthy')} | "
                                 f"{v.count('unexplained')} | {v.count('faulty')} |")
        faulty = [u for u in undescribed if u["verdict"] == "faulty"]
        lo, hi = _wilson(len(faulty), len(undescribed))
        lines.append(f"\nFaulty on {len(faulty)} of {len(undescribed)} healthy units (95 % "
                     f"interval {100 * lo:.1f} % to {100 * hi:.1f} %)"
                     + (": " + "; ".join(f"{u['actuator']} {u['firmware']} unit {u['unit_seed']} "
                                        f"{u['named']}" for u in faulty[:10]) if faulty else "")
                     + ".\n")
    return "\n".join(lines)


def tune(args) -> None:
    """Part A (or D) on tuning units: the lognormal of the fit ratios the verdicts read where
    they named the unit's faults right (emaphm.fitness.MISFIT_RECORDED, and the current
    references' with ``--parts D``)."""
    import numpy as np

    part = "D" if args.parts == "D" else "A"
    tasks = [(a, f, part, TUNE_SEED0 + u) for a in args.actuators.split(",")
             for f in args.firmwares.split(",") if part == "A" or f in DESCRIBABLE
             for u in range(args.units)]
    with ProcessPoolExecutor(args.workers) as pool:
        units = list(pool.map(run_unit, tasks, chunksize=1))
    RESULTS.mkdir(exist_ok=True)
    stem = "drives_tuning" + ("_current_references" if part == "D" else "")
    (RESULTS / f"{stem}.json").write_text(json.dumps({"units": units}, indent=1) + "\n")
    # the fits that found the unit's faults (named, or suspected under a misfit): what the
    # model reaches on an actuator it explains, whatever the constants now in use say
    ratios = [c["verdict_ratio"] for u in units if u["calibrated"]
              for case, c in u["cases"].items() if {tuple(x) for x in c["read"]} == EXPECTED[case]]
    logs = np.log(np.asarray([r for r in ratios if r and r > 0]))
    print(f"{len(logs)} fit ratios: log mean {logs.mean():.3f}, log std {logs.std(ddof=1):.3f}; "
          f"median {np.exp(np.median(logs)):.2f}, 99th percentile {np.exp(np.percentile(logs, 99)):.2f}, "
          f"max {np.exp(logs.max()):.2f}")
    wrong = [(u["actuator"], u["firmware"], u["unit_seed"], case, c["verdict"], c["named"],
              round(c["verdict_ratio"] or 0, 2)) for u in units if u["calibrated"]
             for case, c in u["cases"].items() if not _right(case, c)]
    print(f"{len(wrong)} not right:", wrong[:30])
    print("calibration refused:", [(u["actuator"], u["firmware"], u["unit_seed"])
                                   for u in units if not u["calibrated"]])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--units", type=int, default=20)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--parts", default="ABC")
    ap.add_argument("--actuators", default=",".join(ACTUATORS))
    ap.add_argument("--firmwares", default=",".join(FIRMWARES))
    ap.add_argument("--tag", default="", help="name the outputs drives-TAG.json/.md (a run of some "
                                               "firmwares beside another's)")
    ap.add_argument("--tune", action="store_true",
                    help="units 80000+, part A (--parts D: part D): the recorded-voltage (the "
                         "current references') path's misfit constants (the lognormal of the "
                         "verdicts' fit ratios where they were right)")
    args = ap.parse_args()
    if args.tune:
        return tune(args)
    names = args.actuators.split(",")
    fws = args.firmwares.split(",")
    tasks = [(a, f, part, UNIT_SEED0 + u) for part in "ABD" if part in args.parts
             for a in names for f in fws if part == "A" or f in DESCRIBABLE
             for u in range(args.units)]
    c_tasks = [(a, label, UNIT_SEED0 + u) for a in names for label in UNDESCRIBED
               for u in range(args.units)] if "C" in args.parts else []
    t0 = time.time()
    with ProcessPoolExecutor(args.workers) as pool:
        units = list(pool.map(run_unit, tasks, chunksize=1))
        undescribed = list(pool.map(run_undescribed, c_tasks, chunksize=1))
    wall = time.time() - t0
    RESULTS.mkdir(exist_ok=True)
    stem = "drives" + (f"-{args.tag}" if args.tag else "")
    (RESULTS / f"{stem}.json").write_text(json.dumps({"units": units, "undescribed": undescribed},
                                                     indent=1) + "\n")
    text = report(units, undescribed, args, wall)
    (RESULTS / f"{stem}.md").write_text(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
