"""Subcommands of the prognosis layer (registered by :func:`emaphm.cli.build_parser`).

    emaphm history register ID [--unit h|cycles] [--description TEXT]
    emaphm history add ID TRACE --at TIME          diagnose a trace and record it
    emaphm history remove ID --at TIME | --id N    take a recorded inspection back
    emaphm history show ID [--plot FILE.png]       the inspections as a table (and figure)
    emaphm history list                            the registered actuators
    emaphm prognose ID [--threshold MODE=VALUE ...] [--plot FILE.png]
                   [--risk 0.05 [--max-interval H] [--min-interval H]]   and when to look next
    emaphm demo-degradation [--scenario NAME] [--synthetic]

The store is ``--db PATH``, else ``$EMAPHM_HISTORY``, else ``emaphm-history.sqlite``
in the working folder (:func:`db_path`). The commands that only read (``history show``,
``history list``, ``prognose``, and ``fleet report``) open it read-only and change nothing.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import tempfile
from pathlib import Path
from typing import Any

from .._cli_common import (UsageError, actuator_id, arg_type, budget_option,
                           identification_seconds, plot_path, shown, warn_if_long)
from .._cli_common import seed as _seed
from .._text import utf8_text

__all__ = ["register", "db_path", "threshold_option", "warn", "inspection_policy",
           "planning_options", "option_words"]

#: Identifications per inspection for the seeds and bootstrap spreads, and inspections of
#: a degradation demo, at most (each is a whole identification).
MAX_SPREAD_RUNS = 100
MAX_INSPECTIONS = 200


def _algorithm_choices() -> tuple[str, ...]:
    """The names --algorithm takes: the built-in ones and those registered in this process
    (:func:`emaphm.optim.register`; read without importing NumPy when none can be)."""
    reg = sys.modules.get("emaphm.optim.registry")
    own = tuple(sorted(reg.registered())) if reg is not None else ()
    return ("lsq", "pso", "de", "gwo", "scipy-de", "cmaes") + own


def _usage(msg: str) -> Exception:
    return UsageError(msg)


def db_path(args: argparse.Namespace) -> Path:
    """The health history a command works on: ``--db``, else ``$EMAPHM_HISTORY`` (when
    set and not empty), else :data:`~emaphm.prognosis.history.DEFAULT_DB`. An empty
    ``--db`` or ``:memory:`` is refused (a :class:`UsageError`): what was recorded there
    would be gone when the command ends. Shared with ``emaphm fleet``."""
    from .._sqlite import store_name_problem
    from .history import DEFAULT_DB

    if args.db is not None:
        problem = store_name_problem(args.db)
        if problem is not None:
            raise UsageError(f"--db {shown(args.db)} {problem}; give the path of a health "
                             "history file, e.g. --db fleet.sqlite")
        return Path(args.db)
    return Path(os.environ.get("EMAPHM_HISTORY") or DEFAULT_DB)


def warn(command: str, text: str | None) -> None:
    """``text`` as one warning line on stderr (``emaphm COMMAND: warning: ...``), if any."""
    if text:
        from .._text import one_line

        print(f"emaphm {command}: warning: {one_line(text, 600)}", file=sys.stderr)


def _trace_path(name: str) -> Path:
    """A trace file argument: a regular file (a :class:`UsageError` naming what it is
    instead: missing, a folder, a FIFO, a device, a link loop)."""
    from .._files import regular_file

    return regular_file(name, "trace file", give="a trace file (.csv or .parquet)",
                        error=UsageError, missing=UsageError)


def _plot_path(value: str | None) -> Path | None:
    return plot_path(value)


def _fmt_time(x: float, unit: str) -> str:
    if not math.isfinite(x):
        return "not reached"
    return f"{x:.0f} {unit}" if abs(x) >= 10 else f"{x:.2g} {unit}"


# ----------------------------------------------------------------------------- history
def cmd_register(args: argparse.Namespace) -> int:
    from .history import HealthHistory, check_registration

    db = db_path(args)
    check_registration(args.actuator, args.unit)     # no new file for an id it would refuse
    with HealthHistory(db) as h:
        a = h.register(args.actuator, description=args.description, time_unit=args.unit)
    print(f"registered {a.id} (time in {a.time_unit}) in {db}", file=sys.stderr)
    return 0


def cmd_calibrate(args: argparse.Namespace) -> int:
    from .._cli_common import calibration_seconds
    from ..calibration import CalibrationError, calibrate
    from ..params import load_params, resolve_params
    from ..progress import CountProgress, compile_notice
    from ..traces import read_trace
    from .history import HealthHistory

    given = load_params(args.params, partial=True) if args.params else None
    with HealthHistory(db_path(args), create=False) as h:
        h.check_time(args.actuator, args.at, "calibration time")   # cheap checks before the fit
        traces = [read_trace(_trace_path(name)) for name in args.traces]
        base = resolve_params(given, traces, warn=False)[0]       # else the traces' own
        progress = CountProgress("calibrating:", enabled=not args.quiet, noun=" model runs")
        if not args.quiet:
            warn_if_long("emaphm history calibrate",
                         calibration_seconds([t.duration for t in traces], base),
                         "this calibration", "calibrate on shorter traces (one 0.5 s "
                         "diagnostic profile each is enough)")
        try:
            with compile_notice(progress, enabled=not args.quiet):
                res = calibrate(traces, given, sources=[Path(n).name for n in args.traces],
                                progress=progress.update)
        except CalibrationError as exc:
            raise _usage(str(exc)) from None
        finally:
            progress.close()
        h.calibrate(args.actuator, args.at, res.params, sources=args.traces)
    if args.json:
        print(json.dumps({**res.to_dict(), "actuator": args.actuator, "at": args.at}))
    else:
        print(res.summary())
    print(f"recorded the calibration of {args.actuator} at {args.at:g}: its inspections from "
          "then on are diagnosed with it", file=sys.stderr)
    return 0


def cmd_list(args: argparse.Namespace) -> int:
    from .history import HealthHistory

    with HealthHistory(db_path(args), readonly=True) as h:
        acts = h.actuators()
    if args.json:
        print(json.dumps([a.to_dict() for a in acts]))
        return 0
    print(f"{'actuator':20s} {'unit':6s} {'inspections':>11s} {'last':>10s}  description")
    for a in acts:
        last = "-" if a.last_time is None else f"{a.last_time:.15g}"
        # one row per actuator: a description's line breaks and tabs read as spaces
        print(f"{a.id:20s} {a.time_unit:6s} {a.n_inspections:11d} {last:>10s}  "
              f"{' '.join(a.description.split())}")
    return 0


def cmd_add(args: argparse.Namespace) -> int:
    from ..progress import SearchProgress, compile_notice
    from ..traces import TraceError, read_trace
    from ..identify import IdentificationConfig
    from .history import HealthHistory
    from .workflow import record_inspection as inspect

    budget = budget_option(args.budget)
    params = None
    if args.params:
        from ..params import load_params

        params = load_params(args.params, partial=True)
    trace_path = Path(args.trace)
    progress = SearchProgress(enabled=not args.quiet,
                              header=f"diagnosing {trace_path} for {args.actuator} at {args.at:g} "
                                     f"({args.algorithm.upper()}, seed {args.seed}, spread: "
                                     f"{args.spread})")
    with HealthHistory(db_path(args), create=False) as h:
        h.check_next(args.actuator, args.at)          # cheap checks before reading the trace
        trace = read_trace(_trace_path(args.trace))
        if not args.quiet:
            if params is None:
                from ..params import resolve_params

                cal = h.calibration(args.actuator, args.at)
                est_params = cal[1] if cal is not None else resolve_params(None, trace)[0]
            else:
                est_params = params
            warn_if_long("emaphm history add",
                         identification_seconds(trace.duration, est_params, args.algorithm, budget,
                                                runs=1 if args.spread == "population" else args.runs),
                         "this inspection",
                         "record a shorter window (one 0.5 s diagnostic profile is enough), or "
                         "cap each identification with --budget (e.g. --budget 60s)")
        try:
            with compile_notice(progress, enabled=not args.quiet):
                config = IdentificationConfig(algorithm=args.algorithm, budget=budget,
                                              fault_model=args.fault_model)
                ins, a = inspect(h, args.actuator, trace, args.at, seed=args.seed, config=config,
                                 method=args.spread, source=str(trace_path), params=params,
                                 n_runs=args.runs, callback=progress)
        except TraceError as exc:        # found in the trace's content: name the file
            raise _usage(f"{trace_path}: {exc}") from None
        finally:
            progress.close()
        unit = h.actuator(args.actuator).time_unit
    if args.json:
        print(json.dumps(ins.to_dict()))
        return 0
    verdict = "HEALTHY" if ins.healthy else "FAULTY"
    faults = (ins.diagnosis or {}).get("faults", [])
    if args.quiet:                                # the record in one line, as fleet demo's
        modes = sorted({str(f.get("mode")) for f in faults})
        print(f"recorded inspection of {args.actuator} at {ins.time:.15g} {unit}: {verdict}"
              + (f" ({', '.join(modes)})" if modes else ""))
        return 0
    print(a.interval.table())
    print(f"\nrecorded inspection of {args.actuator} at {ins.time:.15g} {unit}: {verdict}"
          f" ({a.evaluations} evaluations, {a.elapsed_s:.1f} s)")
    for f in faults:
        print(f"  - {f['mode']}: {f['reading']}")
    return 0


def cmd_remove(args: argparse.Namespace) -> int:
    from .history import HealthHistory

    with HealthHistory(db_path(args), create=False) as h:
        gone = h.remove(args.actuator, at=args.at, inspection_id=args.id)
        unit = h.actuator(args.actuator).time_unit
    if args.json:
        print(json.dumps(gone.to_dict()))
        return 0
    print(f"removed inspection {gone.id} of {gone.actuator} at {gone.time:.15g} {unit}"
          + (f" ({gone.verdict})" if gone.verdict else "")
          + (f", recorded {gone.recorded_utc[:19].replace('T', ' ')} UTC" if gone.recorded_utc else "")
          + (f" from {gone.source}" if gone.source else ""))
    return 0


def _history_table(data: Any) -> str:
    from ..faults import K_NAMES

    unit = data.actuator.time_unit
    w = max(len(n) for n in K_NAMES)                 # full names: ecc_modulus, not ecc_modul
    head = f"{'time [' + unit + ']':>12s}  " + " ".join(f"{n:>{w}s}" for n in K_NAMES) + "  verdict"
    lines = [head]
    for ins in data.inspections:
        row = f"{ins.time:12g}  " + " ".join(f"{x:{w}.4f}" for x in ins.k)
        verdict = "-" if ins.healthy is None else ("healthy" if ins.healthy else "FAULTY: " + ", ".join(
            sorted({f["mode"] for f in (ins.diagnosis or {}).get("faults", [])})))
        lines.append(row + "  " + verdict)
        lines.append(f"{'':12s}  " + " ".join(f"{'+-' + format(0.5 * (h - l), '.4f'):>{w}s}"
                                               for l, h in zip(ins.k_lo, ins.k_hi)))
    return "\n".join(lines)


def cmd_show(args: argparse.Namespace) -> int:
    from .history import HealthHistory
    from .plots import plot_history

    plot = _plot_path(args.plot)
    with HealthHistory(db_path(args), readonly=True) as h:
        data = h.data(args.actuator)
    warn("history show", data.skipped_note())
    if args.json:
        print(json.dumps({"actuator": data.actuator.to_dict(),
                          "inspections": [i.to_dict() for i in data.inspections],
                          "skipped": [x.to_dict() for x in data.skipped]}))
    else:
        a = data.actuator
        print(f"{a.id}{' (' + a.description + ')' if a.description else ''}: "
              f"{data.n} inspections, time in {a.time_unit}")
        if data.n:
            print(_history_table(data))
    if plot:
        plot_history(data, path=plot)
        print(f"wrote {plot}", file=sys.stderr)
    return 0


# ----------------------------------------------------------------------------- prognose
def threshold_option(items: list[str] | None):
    """The failure thresholds of the repeatable ``--threshold MODE=VALUE`` option (the
    defaults when none), or a :class:`UsageError`. Shared with ``emaphm fleet report``."""
    from .thresholds import DEFAULT_FAILURE_THRESHOLDS, parse_threshold

    if not items:
        return DEFAULT_FAILURE_THRESHOLDS
    try:
        return DEFAULT_FAILURE_THRESHOLDS.with_updates(dict(parse_threshold(x) for x in items))
    except ValueError as exc:
        raise _usage(f"--threshold: {exc}") from None


def _unobserved_lines(prog: Any, asked: Any = ()) -> list[str]:
    """What the trends left out: inspections whose drive path could not see a mode, or
    that did not measure an indicator beyond k; and an indicator asked for that no
    inspection measured."""
    from ..modes import INDICATORS
    from .trends import MIN_INSPECTIONS

    n = prog.times.size
    out = [f"{name}: not measured at any of the {n} inspections ({INDICATORS[name].unmeasured})"
           for name in asked if INDICATORS[name].reading is not None
           and name not in prog.beyond_k]
    for name, ix in prog.unobserved.items():
        seen = n - len(ix)
        tail = (f"trended on the other {seen}" if name in prog.predictions else
                f"no trend (it needs {MIN_INSPECTIONS} inspections that measure it)")
        ind = INDICATORS.get(name)
        if ind is not None and ind.reading is not None:
            out.append(f"{name}: not measured on {len(ix)} of {n} inspections "
                       f"({ind.unmeasured}); {tail}")
        else:
            out.append(f"{name}: not observable on {len(ix)} of {n} inspections (their drive "
                       f"path cannot see it: its k there is a placeholder); {tail}")
    return out


def _prognosis_table(prog: Any, asked: Any = ()) -> str:
    from .choices import HEALTHY_SHARE
    from .trends import indicator_state, level_at_last

    unit = prog.time_unit
    seed = next((p.seed for p in prog.predictions.values()), None)
    w = max([13, *(len(n) for n in prog.predictions)])
    lines = [f"prognosis of {prog.actuator} at {prog.t_now:g} {unit} from {prog.times.size} "
             f"inspections" + ("" if seed is None else f" (seed {seed})"),
             f"{'indicator':{w}s} {'now':>7s} {'threshold':>9s}  {'trend (Akaike weight)':24s} "
             f"{'RUL median':>12s}  {'interval':>22s}"]
    for name, p in prog.predictions.items():
        top = max(p.weights, key=p.weights.get)
        model = f"{top} ({p.weights[top]:.2f})"
        span = float(prog.times[-1] - prog.times[0])
        far = 10.0 * max(span, 1e-9)
        if p.no_growth(span):
            rul, iv = "no growth", f"P(within {far:.0f} {unit}) {p.p_fail_within(far):.2f}"
        elif indicator_state(p, span)[0] == "no growth" and level_at_last(p) < HEALTHY_SHARE * \
                p.threshold:                     # a finite fit of a healthy level's scatter
            rul, iv = "no growth", f"fitted {_fmt_time(p.median, unit)}, in the noise"
        else:
            rul = _fmt_time(p.median, unit)
            iv = f"[{_fmt_time(p.lo, unit)}, {_fmt_time(p.hi, unit) if math.isfinite(p.hi) else 'inf'}]"
        lines.append(f"{name:{w}s} {_now_text(p):>7s} {p.threshold:9.3f}  {model:24s} {rul:>12s}  "
                     f"{iv:>22s}")
    if any(_carried_out(p) for p in prog.predictions.values()):
        lines.append(f"(now: > or < marks a trend carried to {prog.t_now:g} {unit} past the range "
                     "its indicator can take, shown at the bound)")
    lines += [f"{n}: {p.extrapolated}" for n, p in prog.predictions.items() if p.extrapolated]
    lines += _unobserved_lines(prog, asked)
    first = prog.first
    if first is not None and math.isfinite(first.median):
        lines.append(f"\nfirst to fail: {first.indicator}, median RUL {_fmt_time(first.median, unit)} "
                     f"({first.level:.0%} interval {_fmt_time(first.lo, unit)} to "
                     f"{_fmt_time(first.hi, unit)}; {first.p_failed:.0%} of the draws already past "
                     "the threshold)")
    else:
        lines.append("\nno fault is predicted to reach its failure threshold")
    carried = [f"{n} {100 * p.discrepancy:.1f} %" for n, p in prog.predictions.items()
               if p.discrepancy > 0]
    if carried:
        lines.append("intervals include the identification's model discrepancy measured on the "
                     "reference plant (" + ", ".join(carried) + " of the indicator)")
    return "\n".join(lines)


def _carried_out(p: Any) -> bool:
    """Whether the trend, carried past the last inspection to t_now, left the range its
    indicator can take (at the last inspection a healthy component's fit dips below 0 by its
    scatter: no extrapolation, shown as it is)."""
    return p.t_now > p.top_fit.t_ref and not p.bounds[0] <= p.current <= p.bounds[1]


def _now_text(p: Any) -> str:
    """The trend's value at t_now, or the bound a trend carried past the last inspection
    passed, with > or <."""
    if _carried_out(p):
        return f">{p.bounds[1]:.3f}" if p.current > p.bounds[1] else f"<{p.bounds[0]:.3f}"
    return f"{p.current:.3f}"


def inspection_policy(args: argparse.Namespace):
    """The :class:`~emaphm.prognosis.inspection.InspectionPolicy` of ``--risk``,
    ``--max-interval``, ``--min-interval`` and ``--default-interval`` (None without
    ``--risk``; an interval without it is a :class:`UsageError`). Shared with ``emaphm
    fleet``."""
    from .inspection import InspectionPolicy

    given = [f"--{n.replace('_', '-')}" for n in ("max_interval", "min_interval",
                                                  "default_interval")
             if getattr(args, n, None) is not None]
    if args.risk is None:
        if given:
            raise _usage(f"{given[0]} plans the next inspection: give --risk too, e.g. --risk 0.05")
        return None
    try:
        return InspectionPolicy(risk=args.risk, max_interval=args.max_interval,
                                min_interval=args.min_interval,
                                default_interval=args.default_interval)
    except ValueError as exc:
        raise _usage(f"{option_words(str(exc))}") from None


def option_words(text: str) -> str:
    """A policy's message in the words of the command line (--max-interval, not max_interval)."""
    for name in ("max_interval", "min_interval", "default_interval"):
        text = text.replace(name, "--" + name.replace("_", "-"))
    return text


def _indicator_arg(name: str) -> str:
    """``--indicator NAME``: an older name said so on stderr and taken."""
    from .. import modes

    new = modes.INDICATOR_ALIASES.get(name)
    if new is None:
        return name
    warn("prognose", f"--indicator {name} is now called {new}; the old name goes in a later "
                     "release")
    return new


def cmd_prognose(args: argparse.Namespace) -> int:
    from .history import HealthHistory
    from .thresholds import INDICATORS
    from .trends import MIN_INSPECTIONS

    plot = _plot_path(args.plot)
    thresholds = threshold_option(args.threshold)
    if not 0 < args.level < 1:
        raise _usage(f"--level must be in (0, 1), e.g. 0.9, got {args.level}")
    policy = inspection_policy(args)
    with HealthHistory(db_path(args), readonly=True) as h:
        data = h.data(args.actuator)
        if args.at is not None:
            h.check_time(args.actuator, args.at, "--at")
    warn("prognose", data.skipped_note())
    if policy is not None:
        try:
            policy.intervals(data.actuator.time_unit)
        except ValueError as exc:
            raise _usage(option_words(str(exc))) from None
    if data.n < MIN_INSPECTIONS and (policy is None or plot):
        raise _usage(f"{args.actuator} has {data.n} inspection(s); a trend needs at least "
                     f"{MIN_INSPECTIONS}: record more with emaphm history add")
    indicators = [_indicator_arg(n) for n in args.indicator] if args.indicator else INDICATORS
    prog, plan = _prognose_and_plan(data, args, thresholds, indicators, policy)
    if args.json:
        out = prog.to_dict() if prog is not None else _no_trend_dict(data, args, thresholds)
        if plan is not None:
            out["next_inspection"] = plan.to_dict()
        print(json.dumps(out))
    else:
        if prog is not None:
            print(_prognosis_table(prog, indicators if args.indicator else ()))
        if plan is not None:
            print(plan.summary(data.actuator.id))
            print(f"(risk {plan.target:g}; intervals: default {plan.intervals.default:g}, min "
                  f"{plan.intervals.min:g}, max {plan.intervals.max:g} "
                  f"{data.actuator.time_unit}: {plan.intervals.source})")
    if plot:
        from .plots import plot_prognosis

        plot_prognosis(prog, path=plot, indicators=indicators if args.indicator else None)
        print(f"wrote {plot}", file=sys.stderr)
    return 0


def _prognose_and_plan(data: Any, args: argparse.Namespace, thresholds: Any, indicators: Any,
                       policy: Any) -> tuple[Any, Any]:
    """The prognosis (None under three inspections) and, with a policy, the next inspection."""
    from .trends import MIN_INSPECTIONS, prognose

    observed, readings = data.observed, data.readings     # each read from the records once
    common = dict(seed=args.seed, thresholds=thresholds, indicators=indicators, t_now=args.at,
                  actuator=data.actuator.id, time_unit=data.actuator.time_unit,
                  level=args.level, selection=args.selection, observed=observed,
                  readings=readings)
    if policy is None:
        return prognose(data.times, data.K, **common), None
    from .inspection import n_samples_for, plan_inspection

    prog = None
    if data.n >= MIN_INSPECTIONS:
        prog = prognose(data.times, data.K, n_samples=n_samples_for(policy.risk), **common)
    t_now = args.at if args.at is not None else None
    return prog, plan_inspection(data.times, prog, policy=policy, t_now=t_now,
                                 time_unit=data.actuator.time_unit, K=data.K,
                                 thresholds=thresholds, indicators=indicators,
                                 observed=observed, readings=readings)


def _no_trend_dict(data: Any, args: argparse.Namespace, thresholds: Any) -> dict:
    """``prognose --json`` of an actuator with fewer than three inspections: no predictions."""
    t_now = args.at if args.at is not None else (float(data.times[-1]) if data.n else 0.0)
    return {"actuator": data.actuator.id, "t_now": t_now, "time_unit": data.actuator.time_unit,
            "thresholds": thresholds.to_dict(), "n_inspections": data.n, "predictions": {}}


# ----------------------------------------------------------------------------- demo
def cmd_demo(args: argparse.Namespace) -> int:
    from .simulator import DEGRADATION_SCENARIOS

    names = list(DEGRADATION_SCENARIOS) if args.scenario == "all" else [args.scenario]
    for n in names:
        if n not in DEGRADATION_SCENARIOS:
            raise _usage(f"unknown degradation scenario {shown(n)}; choose one of "
                         f"{', '.join(DEGRADATION_SCENARIOS)} or all")
    if args.inspections < 3:
        raise _usage("--inspections must be at least 3 (a trend needs three points)")
    if args.db is not None:
        db_path(args)                        # an empty name or :memory: is refused
        _demo_ids_free(Path(args.db), [f"demo-{n}-{args.seed + i}" for i, n in enumerate(names)])
    plot_dir = Path(args.plot_dir) if args.plot_dir else None
    if plot_dir is not None:                 # created where missing, as report --out is
        if plot_dir.exists() and not plot_dir.is_dir():
            raise _usage(f"--plot-dir {plot_dir} is a file, not a folder; give a folder")
        try:
            plot_dir.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise _usage(f"--plot-dir {plot_dir} cannot be created ({exc.strerror}); give a "
                         "folder you can write to") from None
    from ..progress import SearchProgress, compile_notice
    from .workflow import run_demo

    results = []
    progress = SearchProgress(enabled=not (args.quiet or args.json))
    with tempfile.TemporaryDirectory() as tmp, compile_notice(progress, enabled=not args.quiet):
        db = Path(args.db) if args.db else Path(tmp) / "demo.sqlite"
        for i, name in enumerate(names):
            results.append(run_demo(name, db=db, n_inspections=args.inspections,
                                    seed=args.seed + i, synthetic=args.synthetic,
                                    budget=args.budget, plot_dir=plot_dir,
                                    quiet=args.quiet or args.json, progress=progress))
    if args.json:
        print(json.dumps(results))
    return 0


def _demo_ids_free(db: Path, ids: list[str]) -> None:
    """Refuse a demo whose actuators a history ``db`` holds already (an earlier demo of the
    same scenario and seed), before any simulation; say which ones are added to a history
    that holds others."""
    if not db.exists() or (db.is_file() and db.stat().st_size == 0):    # a new history (an
        return                                                          # empty file: mktemp)
    from .history import HealthHistory

    with HealthHistory(db, readonly=True) as h:
        have = {a.id for a in h.actuators()}
    taken = [i for i in ids if i in have]
    if taken:
        raise _usage(f"{db} holds {', '.join(taken)} already (an earlier demo-degradation with "
                     "this scenario and seed); give another --seed, or another --db (the demo "
                     "records into a history of its own without --db)")
    if have:
        print(f"adding {', '.join(ids)} to {db}, beside its {len(have)} actuator(s)",
              file=sys.stderr)


# ----------------------------------------------------------------------------- wiring
_time = arg_type(float, lambda t: math.isfinite(t) and t >= 0,
                 "time must be a finite number >= 0 (flight hours or cycles)")
#: ``history remove --at``: any finite time, so that a record stored beyond the range a
#: history holds (an older version took --at 1e308) can be named and taken back.
_any_time = arg_type(float, math.isfinite, "time must be a finite number, e.g. 1250")
_inspection_id = arg_type(int, lambda n: n >= 1, "expected an inspection id, an integer >= 1 "
                          "(emaphm history show ID --json lists them)")
_spread_runs = arg_type(int, lambda n: 2 <= n <= MAX_SPREAD_RUNS,
                        f"expected an integer from 2 to {MAX_SPREAD_RUNS} (identifications of "
                        "one inspection)")
_inspections = arg_type(int, lambda n: 3 <= n <= MAX_INSPECTIONS,
                        f"expected an integer from 3 to {MAX_INSPECTIONS} (a trend needs three "
                        "points; each is an identification)")
_evaluations = arg_type(int, lambda n: 1 <= n <= 100_000_000,
                        "expected a number of evaluations from 1 to 1e8")


def _db_arg(p: argparse.ArgumentParser) -> None:
    p.add_argument("--db", help="health history database (default $EMAPHM_HISTORY or "
                                "emaphm-history.sqlite)")


def register(subparsers: Any) -> None:
    """Add ``history``, ``prognose`` and ``demo-degradation`` to the ``emaphm`` parser."""
    _register_history(subparsers)
    _register_prognose(subparsers)
    _register_demo(subparsers)


def _register_history(subparsers: Any) -> None:
    hp = subparsers.add_parser("history", help="health history of actuators: register, add, "
                                               "remove, show")
    hs = hp.add_subparsers(dest="history_command", required=True,
                           metavar="{register,calibrate,add,remove,show,list}")

    r = hs.add_parser("register", help="register an actuator before its first inspection")
    r.add_argument("actuator", type=actuator_id, help="actuator id, e.g. EMA-0042")
    r.add_argument("--description", default="", type=utf8_text,
                   help="free text, e.g. 'left aileron, A320 MSN 1234'")
    r.add_argument("--unit", choices=("h", "cycles"), default="h",
                   help="time unit of its inspections: flight hours (default, 0 to 1e6) or "
                        "cycles (0 to 1e9)")
    _db_arg(r)
    r.set_defaults(func=cmd_register)

    c = hs.add_parser("calibrate", help="calibrate an actuator on healthy traces and record it",
                      description="Run emaphm calibrate on traces of the actuator known to be "
                                  "healthy and record the result: inspections at or after --at "
                                  "are diagnosed with these parameters unless --params is given.")
    c.add_argument("actuator", type=actuator_id)
    c.add_argument("traces", nargs="+", help="healthy traces (.csv or .parquet)")
    c.add_argument("--at", type=_time, required=True, help="time of the calibration")
    c.add_argument("--params", help="data-sheet parameters TOML (default: the traces' own "
                   "actuator, from their metadata, else the preset)")
    c.add_argument("--json", action="store_true")
    c.add_argument("--quiet", action="store_true", help="no progress line")
    _db_arg(c)
    c.set_defaults(func=cmd_calibrate)

    _register_add(hs)

    rm = hs.add_parser("remove", help="take a recorded inspection back (a wrong time, a wrong trace)",
                       description="Remove one inspection of an actuator, named by its time or "
                                   "its id (emaphm history show --json lists both), and print "
                                   "what was removed.")
    rm.add_argument("actuator", type=actuator_id)
    which = rm.add_mutually_exclusive_group(required=True)
    which.add_argument("--at", type=_any_time, help="the time of the inspection to remove")
    which.add_argument("--id", type=_inspection_id, help="the id of the inspection to remove")
    rm.add_argument("--json", action="store_true")
    _db_arg(rm)
    rm.set_defaults(func=cmd_remove)

    s = hs.add_parser("show", help="the inspections of an actuator (table, optional figure)")
    s.add_argument("actuator", type=actuator_id)
    s.add_argument("--plot", help="write each k component over time (.png/.svg/.pdf)")
    s.add_argument("--json", action="store_true")
    _db_arg(s)
    s.set_defaults(func=cmd_show)

    ls = hs.add_parser("list", help="the registered actuators")
    ls.add_argument("--json", action="store_true")
    _db_arg(ls)
    ls.set_defaults(func=cmd_list)


def _register_add(hs: Any) -> None:
    from .choices import SPREAD_METHODS

    a = hs.add_parser("add", help="diagnose a trace and record it as an inspection")
    a.add_argument("actuator", type=actuator_id)
    a.add_argument("trace", help="trace file (.csv or .parquet)")
    a.add_argument("--at", type=_time, required=True,
                   help="time of the inspection (flight hours, 0 to 1e6, or cycles, 0 to 1e9), "
                        "after the last one")
    a.add_argument("--algorithm", default="lsq", choices=_algorithm_choices(),
                   help="lsq (default: least squares, warm-started from the last inspection), "
                        "the paper's pso, de, gwo, or the baselines")
    a.add_argument("--fault-model", choices=("physical", "paper"), default=None,
                   help="mapping of k3..k5: default the trace's own, physical for a bench trace")
    a.add_argument("--seed", type=_seed, default=0, help="seed of the optimizer (default 0)")
    a.add_argument("--budget", help="evaluations (e.g. 5000) or seconds (e.g. 10s); default: "
                                    "the paper's stopping rules")
    a.add_argument("--spread", choices=SPREAD_METHODS, default="population",
                   help="interval of k: population (free, default), seeds or bootstrap")
    a.add_argument("--runs", type=_spread_runs, default=5,
                   help="identifications for seeds/bootstrap (default 5)")
    a.add_argument("--params", help="actuator parameters TOML (default: the actuator's latest "
                                    "calibration at that time, else the trace's own actuator, "
                                    "else the preset)")
    a.add_argument("--json", action="store_true")
    a.add_argument("--quiet", action="store_true",
                   help="no progress and no table: the record in one line")
    _db_arg(a)
    a.set_defaults(func=cmd_add)


def _register_prognose(subparsers: Any) -> None:
    from .choices import FAILURE_DEFAULTS, INDICATORS, SELECTION_RULES

    p = subparsers.add_parser("prognose", help="fault trends and remaining useful life of an actuator")
    p.add_argument("actuator", type=actuator_id)
    a = p.add_argument("--threshold", action="append", metavar="MODE=VALUE",
                       help="failure threshold of a fault mode (repeatable), e.g. friction=0.4; "
                            "defaults %(failure_defaults)s")
    a.failure_defaults = FAILURE_DEFAULTS     # read from the modes when the help is printed
    p.add_argument("--indicator", action="append", choices=INDICATORS, metavar="INDICATOR",
                   help="predict only these health indicators (repeatable): %(choices)s")
    p.add_argument("--plot", help="write trend, threshold and prediction cone (.png/.svg/.pdf)")
    p.add_argument("--seed", type=_seed, default=0, help="seed of the Monte Carlo draws (default 0)")
    p.add_argument("--level", type=float, default=0.9, help="probability of the RUL interval (default 0.9)")
    p.add_argument("--selection", choices=SELECTION_RULES, default="average",
                   help="mix the trend models by Akaike weight (average, default) or keep the best (aicc)")
    p.add_argument("--at", type=_time, help="count the RUL from this time (default: the last inspection)")
    p.add_argument("--json", action="store_true")
    _db_arg(p)
    planning_options(p)
    p.set_defaults(func=cmd_prognose)


_risk = arg_type(float, lambda r: math.isfinite(r) and 0.0 < r < 1.0,
                 "risk must be a probability in (0, 1), e.g. 0.05")
_interval = arg_type(float, lambda x: math.isfinite(x) and x > 0,
                     "interval must be a finite number > 0 in the history's time unit, e.g. 200")
_min_interval = arg_type(float, lambda x: math.isfinite(x) and x >= 0,
                         "minimum interval must be a finite number >= 0 in the history's time "
                         "unit, e.g. 50")


def planning_options(p: argparse.ArgumentParser, *, default_risk: bool = False) -> None:
    """``--risk`` and the intervals of an inspection plan (``prognose``; ``fleet``, whose
    risk defaults to :data:`~emaphm.prognosis.inspection.DEFAULT_RISK`)."""
    from .choices import DEFAULT_RISK, FLIGHT_HOUR_INTERVALS

    d = argparse.Namespace(**FLIGHT_HOUR_INTERVALS)
    p.add_argument("--risk", type=_risk,
                   help="plan the next inspection: the latest time at which the probability "
                        "that an indicator has crossed its failure threshold stays <= RISK, "
                        "e.g. 0.05" + (f" (default {DEFAULT_RISK:g})" if default_risk else "")
                        + " (see docs/inspection-planning.md)")
    p.add_argument("--max-interval", type=_interval, metavar="H",
                   help=f"longest interval a plan reaches (default {d.max:g} h; a history in "
                        "cycles takes the same numbers: give yours)")
    p.add_argument("--min-interval", type=_min_interval, metavar="H",
                   help=f"shortest interval worth planning: a risk that comes sooner flags the "
                        f"actuator now (default {d.min:g} h)")
    p.add_argument("--default-interval", type=_interval, metavar="H",
                   help=f"interval under three inspections or with every indicator at its "
                        f"healthy level (default {d.default:g} h)")


def _register_demo(subparsers: Any) -> None:
    from .choices import DEGRADATION_SCENARIO_NAMES as DEGRADATION_SCENARIOS

    d = subparsers.add_parser("demo-degradation",
                              help="simulate a growing fault, diagnose, record and predict, end to end")
    d.add_argument("--scenario", default="friction-growth",
                   help=f"one of {', '.join(DEGRADATION_SCENARIOS)}, or all")
    d.add_argument("--inspections", type=_inspections, default=8,
                   help="inspections over the life (default 8)")
    d.add_argument("--seed", type=_seed, default=0)
    d.add_argument("--synthetic", action="store_true",
                   help="skip the identifications: true k plus identification-level noise")
    d.add_argument("--budget", type=_evaluations,
                   help="evaluations per identification (default: the paper's rules)")
    d.add_argument("--db", help="keep the demo's history in this database (default: a temporary one)")
    d.add_argument("--plot-dir", help="write the prognosis and alpha-lambda figures here")
    d.add_argument("--json", action="store_true")
    d.add_argument("--quiet", action="store_true")
    d.set_defaults(func=cmd_demo)
