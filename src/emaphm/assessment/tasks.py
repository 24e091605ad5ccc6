"""The work of one production unit, as a worker executes it (:func:`run_task`: a pure
function of its :class:`~emaphm.assessment.spec.Task`, so that an interrupted assessment
resumed on any executor holds the results of an uninterrupted one).

Every trace comes from the **reference plant** (physics the monitoring model lacks: the
drive's PWM, Stribeck friction, leakage, the backlash contact at its own step) playing the
unit drawn within the tolerances; each is diagnosed as ``emaphm diagnose`` does
(:func:`emaphm.verdict.examine`: the current sensors from the sum of the currents, the
identification, the verdict with its checks and the modes' hypotheses), without the fault
loops' report, which is a reading and no part of the verdict.
"""

from __future__ import annotations

import time
import traceback
from dataclasses import replace
from typing import Any

from .spec import HEALTHY, Case, Task

__all__ = ["run_task", "measures_of"]

#: Noise seeds of a unit's traces: ``noise0 + j`` with ``j`` from these offsets.
CALIBRATION_TRACES = (0, 1)
FIRST_HEALTHY = 2


def measures_of(ex: Any, params: Any) -> dict[str, float]:
    """What each threshold is compared with in the examination ``ex`` (every mode's
    :attr:`~emaphm.modes.FaultMode.measure` on the verdict's reading)."""
    from ..modes import MODES, Reading, thresholds_for
    from ..modes.current_sensor import as_findings

    d = ex.diagnosis
    ident = ex.identification
    k, extra = ident.k, dict(ident.nuisance or {})
    if d.refit is not None:
        k, extra = d.refit.k, dict(d.refit.nuisance)
    r = Reading(k=k, params=params, fault_model=ident.fault_model,
                thresholds=thresholds_for(ident.fault_model, params), extra=extra,
                findings=as_findings(ex.sensor))
    out: dict[str, float] = {}
    for m in MODES.values():
        out.update({name: float(v) for name, v in m.measure(r).items()})
    return out


def _outcome(ex: Any, cpu_s: float, expected: tuple = ()) -> dict[str, Any]:
    from ..diagnosis import fit_ratio_of

    d = ex.diagnosis
    named = [[f.mode, f.phase] for f in d.faults]
    want = "faulty" if expected else "healthy"
    return {"verdict": d.verdict, "named": named,
            "right": d.verdict == want and sorted(map(tuple, named), key=str)
            == sorted(expected, key=str),
            "reason": None if d.unexplained is None else d.unexplained.reason,
            "fit_ratio": fit_ratio_of(ex.identification), "cpu_s": cpu_s}


def _examine(trace: Any, params: Any, config: Any, expected: tuple = ()) -> tuple[Any, dict]:
    """The examination of ``trace`` and its outcome; a trace the diagnosis refuses (its
    currents no sensor fault explains, say) is an outcome too, ``"refused"`` with the
    reason, not the loss of the unit's other runs."""
    from ..verdict import examine

    t0 = time.process_time()
    try:
        ex = examine(trace, params=params, config=config, seed=0, loops=False)
    except ValueError as exc:            # TraceError and its kin: what diagnose refuses
        return None, {"verdict": "refused", "named": [], "right": False, "reason": str(exc),
                      "fit_ratio": None, "cpu_s": time.process_time() - t0}
    return ex, _outcome(ex, time.process_time() - t0, expected)


def run_task(task: Task) -> dict[str, Any]:
    """Execute one unit's task; never raises for a failing unit (its result carries the
    ``error``)."""
    t0 = time.process_time()
    try:
        from ..campaign.executors import warm_up

        warm_up()
        t0 = time.process_time()
        out = _tune(task) if task.phase == "tune" else _assess(task)
    except Exception as exc:              # noqa: BLE001 - a failure is a value
        text = "".join(traceback.format_exception(type(exc), exc, exc.__traceback__, limit=-6))
        out = {"error": text.strip()}
    out.update(key=task.key, phase=task.phase, index=task.index, unit_seed=task.unit_seed,
               cpu_s=time.process_time() - t0)
    return out


def _unit(task: Task) -> tuple[Any, Any, Any, Any]:
    """The spec, the data sheet (with the task's thresholds), the unit, the config."""
    from ..identify import IdentificationConfig
    from ..units import draw_unit

    spec = task.spec()
    sheet = spec.actuator()
    if task.thresholds:
        sheet = replace(sheet, thresholds=task.thresholds)
    unit = draw_unit(sheet, task.unit_seed, spec.tolerance_set())
    return spec, sheet, unit, IdentificationConfig(spec.algorithm)


def _trace(unit: Any, sheet: Any, seed: int, injection: Any = None, *,
           drive_signals: bool = False) -> Any:
    from ..simulate import DEFAULT_SENSORS, simulate

    return simulate(unit=unit, params=sheet, faults=[injection] if injection is not None else [],
                    sensors=DEFAULT_SENSORS, seed=seed, drive_signals=drive_signals)


def _calibrated(task: Task, unit: Any, sheet: Any) -> tuple[Any, dict]:
    """The unit calibrated on its two calibration traces, or ``(None, {"error": ...})``."""
    from ..calibration import CalibrationError, calibrate

    ds = task.spec().drive_signals
    traces = [_trace(unit, sheet, task.noise0 + j, drive_signals=ds) for j in CALIBRATION_TRACES]
    t0 = time.process_time()
    try:
        cal = calibrate(traces, sheet)
    except CalibrationError as exc:
        return None, {"calibration_error": str(exc), "calibrate_cpu_s": time.process_time() - t0}
    return cal, {"calibrate_cpu_s": time.process_time() - t0,
                 "calibration_fixed": list(cal.fixed)}


def _tune(task: Task) -> dict[str, Any]:
    """A tuning unit: calibrate it, read its healthy traces' measures, and those of one
    faulty trace at the largest severity of every other grid (alternating from unit to
    unit: each grid on half the tuning units): what a fault of one mode leaves in the
    measures of the others, the cross-talk a threshold must stay above."""
    spec, sheet, unit, config = _unit(task)
    cal, out = _calibrated(task, unit, sheet)
    if cal is None:
        return out
    readings = []
    seed = task.noise0 + FIRST_HEALTHY
    for _ in range(spec.tune_healthy):
        ex, res = _examine(_trace(unit, sheet, seed, drive_signals=spec.drive_signals),
                           cal.params, config)
        readings.append({**res, "noise_seed": seed,
                         "measures": {} if ex is None else measures_of(ex, cal.params)})
        seed += 1
    out["healthy"] = readings
    crosstalk = []
    largest: dict[str, Case] = {}
    for case in spec.cases(task.index):
        if case.grid not in largest or case.magnitude > largest[case.grid].magnitude:
            largest[case.grid] = case
    for gi, case in enumerate(largest.values()):
        if (gi + task.index) % 2:
            continue
        tr = _trace(unit, sheet, seed, case.injection(), drive_signals=spec.drive_signals)
        ex, res = _examine(tr, cal.params, config, case.expected)
        crosstalk.append({**res, "case": case.grid, "mode": case.mode, "severity": case.severity,
                          "noise_seed": seed,
                          "measures": {} if ex is None else measures_of(ex, cal.params)})
        seed += 1
    out["crosstalk"] = crosstalk
    return out


def _assess(task: Task) -> dict[str, Any]:
    """A reported unit: calibrate it; diagnose its healthy traces after calibration (and
    the first ``healthy_datasheet`` on the data sheet too), then each fault of its cases
    after calibration (and on the data sheet with ``datasheet_faults``)."""
    spec, sheet, unit, config = _unit(task)
    cal, out = _calibrated(task, unit, sheet)
    runs: list[dict[str, Any]] = []
    out["runs"] = runs
    seed = task.noise0 + FIRST_HEALTHY
    for j in range(spec.healthy):
        tr = _trace(unit, sheet, seed, drive_signals=spec.drive_signals)
        base = {"case": HEALTHY, "mode": None, "severity": 0.0, "magnitude": 0.0,
                "phase": None, "kwargs": {}, "noise_seed": seed}
        if cal is not None:
            runs.append({**base, "path": "calibrated", **_examine(tr, cal.params, config)[1]})
        if j < spec.healthy_datasheet:
            runs.append({**base, "path": "datasheet", **_examine(tr, sheet, config)[1]})
        seed += 1
    for case in spec.cases(task.index):
        runs.extend(_fault_runs(case, unit, sheet, cal, config, seed, spec.datasheet_faults,
                                spec.drive_signals))
        seed += 1
    return out


def _fault_runs(case: Case, unit: Any, sheet: Any, cal: Any, config: Any, seed: int,
                datasheet: bool, drive_signals: bool = False) -> list[dict[str, Any]]:
    tr = _trace(unit, sheet, seed, case.injection(), drive_signals=drive_signals)
    base = {"case": case.grid, "mode": case.mode, "severity": case.severity,
            "magnitude": case.magnitude, "phase": case.phase, "kwargs": dict(case.kwargs),
            "noise_seed": seed}
    out = []
    if cal is not None:
        out.append({**base, "path": "calibrated",
                    **_examine(tr, cal.params, config, case.expected)[1]})
    if datasheet:
        out.append({**base, "path": "datasheet", **_examine(tr, sheet, config, case.expected)[1]})
    return out
