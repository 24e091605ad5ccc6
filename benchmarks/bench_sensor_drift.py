"""The current sensors' health indicators against the plant's own sensors: what the sum of
the three measured currents reads of a drifting gain and an offset at an inspection, after
the unit's calibration.

Each unit (drawn within the production tolerances, both actuators) is calibrated on two
healthy traces, then diagnosed (``examine``, as ``emaphm diagnose``) with one sensor's
gain at 0.97, 0.95, 0.9 and 0.85 and its offset at 0.1, 0.2, 0.3 and 0.5 A (the phase
turning from case to case). The indicators are read from the inspection's finding as a
health history stores it (:data:`emaphm.modes.current_sensor.INDICATORS`): the relative
RMS error of each against the plant's fault is its model discrepancy.

Run: ``python benchmarks/bench_sensor_drift.py --tune [--units 6] [--workers 2]`` (unit
seeds 80000+, the tuning seeds) -> printed; without ``--tune`` on seeds 70000+ ->
``benchmarks/results/sensor_drift.md``.
"""

from __future__ import annotations

import os

for _v in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import datetime as _dt  # noqa: E402
import json  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from concurrent.futures import ProcessPoolExecutor  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _actuators import ACTUATORS, datasheet  # noqa: E402
from _machine import machine  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
GAINS = (0.97, 0.95, 0.9, 0.85)
OFFSETS = (0.1, 0.2, 0.3, 0.5)


def one(task: tuple[str, int]) -> dict:
    from emaphm.calibration import CalibrationError, calibrate
    from emaphm.modes import indicator_readings
    from emaphm.simulate import DEFAULT_SENSORS, simulate
    from emaphm.units import draw_unit
    from emaphm.verdict import examine

    name, seed = task
    sheet = datasheet(name)
    unit = draw_unit(sheet, seed)
    kw = dict(unit=unit, params=sheet, sensors=DEFAULT_SENSORS)
    t0 = time.process_time()
    try:
        cal = calibrate([simulate(seed=1, **kw), simulate(seed=2, **kw)], sheet)
    except CalibrationError as exc:
        return {"actuator": name, "unit_seed": seed, "refused": str(exc)[:100]}
    rows = []
    cases = [("gain", g) for g in GAINS] + [("offset", o) for o in OFFSETS]
    for i, (kind, v) in enumerate(cases):
        ph = "abc"[(seed + i) % 3]
        ex = examine(simulate(seed=3 + i, faults=[f"current_sensor:{ph}:{kind}:{v}"], **kw),
                     params=cal.params, seed=0)
        read = indicator_readings(ex.diagnosis.to_dict(), {"sensors": ex.sensor.to_dict()})
        got = read[f"current_sensor_gain_{ph}"] if kind == "gain" else read["current_sensor_offset"]
        true = abs(v - 1.0) if kind == "gain" else v
        rows.append({"kind": kind, "value": v, "phase": ph, "true": true, "read": got,
                     "named": [[f.mode, f.phase] for f in ex.diagnosis.faults]})
    return {"actuator": name, "unit_seed": seed, "rows": rows, "cpu_s": time.process_time() - t0}


def stats(units: list[dict]) -> dict:
    out = {}
    for kind in ("gain", "offset"):
        rel = [(r["read"] - r["true"]) / r["true"] for u in units for r in u.get("rows", ())
               if r["kind"] == kind and r["read"] is not None]
        missing = sum(r["read"] is None for u in units for r in u.get("rows", ())
                      if r["kind"] == kind)
        rel = np.asarray(rel)
        out[kind] = {"n": int(rel.size), "missing": missing,
                     "rms": float(np.sqrt(np.mean(rel ** 2))) if rel.size else None,
                     "mean": float(rel.mean()) if rel.size else None}
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--units", type=int, default=6)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--tune", action="store_true")
    args = ap.parse_args()
    seed0 = 80_000 if args.tune else 70_000
    tasks = [(a, seed0 + i) for a in ACTUATORS for i in range(args.units)]
    load0 = os.getloadavg()
    w0 = time.perf_counter()
    with ProcessPoolExecutor(args.workers) as ex:
        units = list(ex.map(one, tasks))
    wall = time.perf_counter() - w0
    s = {a: stats([u for u in units if u["actuator"] == a]) for a in ACTUATORS}
    refused = [(u["actuator"], u["unit_seed"]) for u in units if "refused" in u]
    print(json.dumps({"stats": s, "refused": refused, "wall_s": wall}, indent=1))
    if args.tune:
        return
    lines = ["## Current sensors read from the sum of the currents, after calibration", "",
             f"`benchmarks/bench_sensor_drift.py --units {args.units}`, "
             f"{_dt.date.today().isoformat()}, {machine('numba', 'scipy')}; load "
             f"{load0[0]:.2f} before; {args.workers} workers, {wall:.0f} s wall. Production "
             "units (seeds 70000+), each calibrated on two healthy traces, then one sensor's "
             f"gain at {', '.join(map(str, GAINS))} and its offset at "
             f"{', '.join(map(str, OFFSETS))} A, diagnosed as `emaphm diagnose` does; the "
             "indicators as a health history stores them.", "",
             "| actuator | indicator | readings | relative RMS error | mean | not measured |",
             "|---|---|---|---|---|---|"]
    for a, st in s.items():
        for kind, v in st.items():
            lines.append(f"| {a} | current sensor {kind} | {v['n']} | "
                         f"{v['rms']:.3f} | {v['mean']:+.3f} | {v['missing']} |")
    if refused:
        lines += ["", f"Calibrations refused: {refused}."]
    (RESULTS / "sensor_drift.md").write_text("\n".join(lines) + "\n")
    (RESULTS / "sensor_drift.json").write_text(json.dumps({"stats": s, "units": units}, indent=1))


if __name__ == "__main__":
    main()
