"""The workflows of prognosis: diagnose a trace and record it; a whole degradation demo.

:func:`record_inspection` is what ``emaphm history add``, the fleet demo and the degradation demo
do for each inspection: the cheap checks, the identification with the interval of each
component (:func:`emaphm.prognosis.uncertainty.identify_with_spread`), the verdict
(:func:`emaphm.verdict.diagnose_identification`) and the record
(:meth:`emaphm.prognosis.history.HealthHistory.add`). The store itself only stores.
:func:`run_demo` is ``emaphm demo-degradation``: simulate a growing fault, diagnose each
inspection, record it and predict the remaining useful life.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from .history import HealthHistory, Inspection, trace_fingerprint

__all__ = ["record_inspection", "inspect", "run_demo"]

#: inspect()'s keywords of version 0.3 that are identification settings now
#: (:class:`emaphm.identify.IdentificationConfig`).
_OLD_CONFIG = ("algorithm", "budget", "options", "polish", "suspect_ratio", "fault_model",
               "n_sub", "mode", "nuisance")


def record_inspection(history: HealthHistory, actuator_id: str, trace: Any, at: float, *, seed: int,
            config: Any = None, method: str = "population", n_runs: int = 5,
            level: float = 0.9, source: str | None = None, params: Any = None,
            thresholds: Any = None, start: Any = None, callback: Any = None,
            **deprecated: Any) -> tuple[Inspection, Any]:
    """Diagnose ``trace`` and record it as the inspection of ``actuator_id`` at time ``at``.

    The cheap checks (registered actuator, time after the last, trace not recorded yet,
    trace valid) run before the identification, so a refused inspection costs nothing
    and records nothing. ``config`` (:class:`emaphm.identify.IdentificationConfig`,
    default the least-squares pipeline's) holds the identification's settings; ``method``,
    ``n_runs`` and ``level`` the interval's
    (:func:`emaphm.prognosis.uncertainty.identify_with_spread`); ``params`` the healthy
    actuator (an :class:`~emaphm.params.ActuatorParams`, a dict or a TOML path; default:
    the actuator's own calibration at ``at``, else the trace's own actuator, else the
    preset: :func:`emaphm.params.resolve_params`; the identification's ``params_source``
    says which). With
    the least-squares pipeline the search starts first from ``start``, by default the k
    of the actuator's last inspection under the same fault model (a warm start: faults
    grow slowly between inspections). Returns ``(inspection, assessment)``
    (:class:`emaphm.prognosis.uncertainty.IdentificationSpread`). The keywords of version 0.3
    (``algorithm``, ``budget``, ``options``, ``fault_model``, ...) still work for one
    release, with a DeprecationWarning.
    """
    from ..fitness import trace_fault_model
    from ..identify import DEFAULT_ALGORITHM, IdentificationConfig
    from ..modes.current_sensor import UNOBSERVABLE_NOTE, as_findings
    from ..params import as_params
    from ..traces import validate
    from ..verdict import diagnose_identification, screen_sensors
    from .uncertainty import identify_with_spread

    if deprecated:
        config = _old_keywords(config, deprecated)
    config = IdentificationConfig() if config is None else config
    fp = trace_fingerprint(trace)
    history.check_next(actuator_id, at, fp)
    validate(trace, min_rotation=config.min_rotation)
    calibrated_at = None
    params = as_params(params)
    if params is None:                 # the actuator's own calibration, where it has one
        cal = history.calibration(actuator_id, at)
        if cal is not None:
            calibrated_at, params = cal
    fault_model = config.fault_model or trace_fault_model(trace)
    if config.algorithm == DEFAULT_ALGORITHM and start is None:
        previous = history.inspections(actuator_id)
        if previous and (previous[-1].extra or {}).get("fault_model", "paper") == fault_model:
            start = previous[-1].k
    # the current sensors judged from the sum of the currents; the machine identified on
    # the corrected trace (emaphm.verdict.examine does the same for one diagnosis)
    finding, work, _ = screen_sensors(trace, params=params, config=config, seed=seed,
                                      thresholds=thresholds)
    a = identify_with_spread(work, config, seed=seed, method=method, level=level, n_runs=n_runs,
                             params=params, start=start, callback=callback)
    ident = a.identification
    if calibrated_at is not None:       # given here, from the history: say so
        ident = replace(ident, params_source="calibration")
        a = replace(a, identification=ident)
    diag = diagnose_identification(work, ident, params=params, thresholds=thresholds, k=a.k,
                                   findings=as_findings(finding))
    if not finding.observable:
        diag = replace(diag, notes=diag.notes + (UNOBSERVABLE_NOTE,))
    extra = {"elapsed_s": a.elapsed_s, "error_pct": ident.error_pct,
             "fault_model": ident.fault_model,
             # the drive path, and the modes it could not see (their k is a placeholder)
             "drive_model": ident.drive_model,
             "not_observable": list(ident.not_observable),
             "calibrated_at": calibrated_at,
             "nuisance": dict(ident.nuisance),
             "parameters": None if params is None else params.to_dict(),
             "params_source": ident.params_source,
             "k_true": None if ident.k_true is None else ident.k_true.tolist(),
             "interval_details": {k: v for k, v in a.interval.details.items()
                                  if isinstance(v, (int, float, str))},
             "budget": ident.options.get("budget"),
             "sensors": finding.to_dict(),
             "seed_used": ident.seed}          # the run kept; ``seed`` replays the inspection
    ins = history.add(actuator_id, at, a.k, k_lo=a.interval.lo, k_hi=a.interval.hi,
                      spread_method=a.interval.method, level=a.interval.level,
                      diagnosis=diag.to_dict(), fingerprint=fp, algorithm=ident.algorithm,
                      seed=int(seed), fitness=ident.fitness, evaluations=a.evaluations,
                      source=source, extra=extra)
    return ins, a


def inspect(*args: Any, **kw: Any) -> tuple[Inspection, Any]:
    """:func:`record_inspection` under its name before 0.5 (which shadowed the standard
    library's ``inspect``), kept for one release with a DeprecationWarning."""
    warnings.warn("emaphm.prognosis.inspect is now record_inspection (the old name shadows the "
                  "standard library's inspect); it goes in the next release",
                  DeprecationWarning, stacklevel=2)
    return record_inspection(*args, **kw)


def _old_keywords(config: Any, kw: dict[str, Any]) -> Any:
    """The 0.3 keywords as an identification config, with a warning."""
    from ..identify import IdentificationConfig

    unknown = sorted(set(kw) - set(_OLD_CONFIG))
    if unknown:
        raise TypeError(f"inspect() got unexpected keyword argument(s) {', '.join(unknown)}")
    warnings.warn(f"inspect({', '.join(f'{k}=' for k in kw)}) is the 0.3 spelling, kept for one "
                  "release: give the identification's settings as config=IdentificationConfig(...)",
                  DeprecationWarning, stacklevel=3)
    if config is not None:
        raise ValueError("give config= or the old keywords, not both")
    return IdentificationConfig(**kw)


def _record_demo(h: HealthHistory, actuator: str, sc: Any, times: np.ndarray, *, seed: int,
                 synthetic: bool, budget: Any, progress: Any) -> None:
    """The inspections of a degradation demo, into the history ``h``: the true k with
    identification-sized noise (``synthetic``), or reference-plant traces diagnosed."""
    from ..identify import IdentificationConfig
    from .simulator import simulate_degradation, synthetic_k_history

    h.register(actuator, description=f"degradation demo {sc.name}", time_unit="h")
    if synthetic:
        K = synthetic_k_history(sc, times, seed=seed)
        for t, k in zip(times, K):
            h.add(actuator, float(t), k, spread_method="synthetic")
        return

    def simulated(i: int, n: int) -> None:
        if progress is not None:
            progress.show(f"{sc.name}: simulated inspection {i}/{n}", force=i == n)

    run = simulate_degradation(sc, times, seed=seed, progress=simulated)
    config = IdentificationConfig(budget=budget)
    for j, (t, tr) in enumerate(zip(times, run.traces)):
        if progress is not None:
            progress.restart(f"{sc.name}: inspection {j + 1}/{len(times)}: ")
        record_inspection(h, actuator, tr, float(t), seed=seed, config=config, callback=progress)
    if progress is not None:
        progress.close()


def _demo_rows(data: Any, sc: Any, times: np.ndarray, seed: int, actuator: str,
               out: Any) -> tuple[list[dict], list[Any], Any]:
    """Per inspection: the true and identified indicator and, from the third on, the RUL
    predicted from the inspections so far (printed as a table through ``out``)."""
    from .trends import MIN_INSPECTIONS, indicator_series, prognose

    y = indicator_series(data.K)[sc.indicator]
    y_true = indicator_series(sc.k_at(times))[sc.indicator]
    out(f"{'time h':>8s} {'true':>7s} {'ident':>7s} {'RUL median':>10s} {'90% interval':>16s} "
        f"{'true RUL':>9s}")
    rows, preds, last = [], [], None
    for i in range(1, data.n + 1):
        row = {"time": float(times[i - 1]), "true": float(y_true[i - 1]),
               "identified": float(y[i - 1]), "rul_true": float(sc.eol - times[i - 1])}
        if i >= MIN_INSPECTIONS:
            prog = prognose(data.times[:i], data.K[:i], seed=seed, indicators=(sc.indicator,),
                            actuator=actuator)
            p = prog.predictions[sc.indicator]
            preds.append(p)
            last = prog
            row.update(rul_median=p.median if math.isfinite(p.median) else None,
                       rul_lo=p.lo if math.isfinite(p.lo) else None,
                       rul_hi=p.hi if math.isfinite(p.hi) else None)
            iv = f"[{p.lo:.0f}, {p.hi:.0f}]"
            out(f"{row['time']:8.0f} {row['true']:7.4f} {row['identified']:7.4f} {p.median:10.0f} "
                f"{iv:>16s} {row['rul_true']:9.0f}")
        else:
            out(f"{row['time']:8.0f} {row['true']:7.4f} {row['identified']:7.4f}")
        rows.append(row)
    return rows, preds, last


def run_demo(name: str, *, db: Path, n_inspections: int = 8, seed: int = 0,
             synthetic: bool = False, budget: Any = None, plot_dir: Path | None = None,
             quiet: bool = False, progress: Any = None) -> dict:
    """The whole loop on one degradation scenario: simulate, diagnose, record, predict.

    Returns a JSON-able summary (per inspection: time, true and identified
    indicator, RUL median and interval, true RUL; and the metrics). ``progress``: a
    :class:`emaphm.progress.SearchProgress` to show the simulations and identifications on.
    """
    from . import metrics
    from .plots import plot_alpha_lambda, plot_prognosis
    from .simulator import degradation_scenario, inspection_times
    from .trends import MIN_INSPECTIONS, RULTrack

    sc = degradation_scenario(name)
    times = inspection_times(sc.eol, n_inspections)
    out = print if not quiet else (lambda *a, **k: None)
    out(f"\n== {name}: {sc.indicator} grows along a {sc.law.kind} law to {sc.threshold:g} at "
        f"{sc.eol:g} h; {n_inspections} inspections, "
        f"{'synthetic k (true + noise)' if synthetic else 'reference-model traces, identified'}")
    actuator = f"demo-{name}-{seed}"
    with HealthHistory(db) as h:
        _record_demo(h, actuator, sc, times, seed=seed, synthetic=synthetic, budget=budget,
                     progress=progress)
        data = h.data(actuator)
    rows, preds, last = _demo_rows(data, sc, times, seed, actuator, out)
    track = RULTrack(indicator=sc.indicator, threshold=sc.threshold, level=preds[0].level,
                     times=times[MIN_INSPECTIONS - 1:], n_used=np.arange(MIN_INSPECTIONS, data.n + 1),
                     median=np.array([p.median for p in preds]), lo=np.array([p.lo for p in preds]),
                     hi=np.array([p.hi for p in preds]),
                     samples=np.stack([p.samples for p in preds]),
                     models=tuple(p.model for p in preds))
    rul_true = sc.eol - track.times
    late = track.times >= 0.5 * sc.eol
    al = metrics.alpha_lambda(track.times, track.samples, sc.eol, alpha=0.2)
    summary = {
        "scenario": sc.to_dict(), "synthetic": synthetic, "seed": seed, "rows": rows,
        "coverage_from_midlife": metrics.coverage(rul_true[late], track.lo[late], track.hi[late])
        if late.any() else None,
        "relative_accuracy_last": float(metrics.relative_accuracy(rul_true[-1], track.median[-1])),
        "alpha_lambda": al.to_dict(),
        "prognostic_horizon": metrics.prognostic_horizon(track.times, track.samples, sc.eol,
                                                         alpha=0.1),
    }
    out(f"coverage of the true RUL from mid-life: {summary['coverage_from_midlife']}, "
        f"alpha-lambda (alpha 0.2, beta 0.5) passed at lambda "
        f"{[float(x) for x in al.lambdas[al.passed]]}, prognostic horizon (alpha 0.1) "
        f"{summary['prognostic_horizon']:.0f} h")
    if plot_dir is not None and last is not None:
        p1 = plot_dir / f"{name}-prognosis.png"
        plot_prognosis(last, indicators=(sc.indicator,), eol_true={sc.indicator: sc.eol}, path=p1)
        p2 = plot_dir / f"{name}-alpha-lambda.png"
        plot_alpha_lambda([track], sc.eol, title=f"{name}: alpha-lambda", path=p2)
        out(f"wrote {p1} and {p2}")
    return summary
