"""Command-line interface: a thin layer over the library.

    emaphm simulate   simulate an actuator and write its trace (CSV or Parquet)
    emaphm scenarios  list the named fault scenarios
    emaphm diagnose   identify the faults of a trace (or of a simulated scenario)
    emaphm calibrate  estimate a healthy unit's parameters from its traces
    emaphm params     write the default parameters (or a motor's, from its data sheet) as TOML
    emaphm import     read a bench export into a trace    (emaphm.traces.importers.cli)
    emaphm campaign, report                   (emaphm.campaign.cli)
    emaphm history, prognose, demo-degradation (emaphm.prognosis.cli)
    emaphm fleet report, fleet demo           (emaphm.fleet.cli)

Bad input exits with status 2 and a message that says what to fix.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import json
import math
import os
import sys
import time
import warnings
from pathlib import Path
from typing import Any, Sequence

from . import __version__
from ._cli_common import (EXIT_USAGE, Parser, UsageError, arg_type, budget_option,
                          calibration_seconds, identification_seconds, negative_values, out_path,
                          plot_path, warn_if_long)
from ._cli_common import seed as _seed
from ._text import one_line, printable_streams, shown
from .firmware import DRIVE_MODELS, FOREIGN_DRIVES

__all__ = ["main", "build_parser", "EXIT_USAGE", "UsageError"]


#: What --params defaults to where a trace is identified (emaphm.params.resolve_params).
_PARAMS_DEFAULT = ("(missing fields from the preset; default: the trace's own actuator, from "
                   "its metadata, else the preset)")


def _load_params(path: str | None):
    from .params import load_params, siemens_1fk7060

    return load_params(path, partial=True) if path else siemens_1fk7060()


def _trace_file(name: str, min_rotation: float | None = None) -> Any:
    """Read the trace file ``name`` (a UsageError when it is missing or not a regular
    file: a folder, a FIFO, a device, a link loop), validated with ``min_rotation`` [rad]
    (None: the default, one revolution)."""
    from ._files import regular_file
    from .traces import read_trace

    path = regular_file(name, "trace file", give="a trace file (.csv or .parquet)",
                        error=UsageError, missing=UsageError)
    return read_trace(path) if min_rotation is None else read_trace(path, min_rotation=min_rotation)


# ----------------------------------------------------------------------------- scenarios
def cmd_scenarios(args: argparse.Namespace) -> int:
    from .faults import K_NAMES, SCENARIO_FAULT_MODELS, SCENARIOS

    if args.json:
        print(json.dumps({n: k.tolist() for n, k in SCENARIOS.items()}))
        return 0
    width = max(len(n) for n in SCENARIOS)
    print(f"{'scenario':{width}s}  {'fault model':11s}  k = [{', '.join(K_NAMES)}]")
    for name, k in SCENARIOS.items():
        print(f"{name:{width}s}  {SCENARIO_FAULT_MODELS[name]:11s}  {','.join(f'{x:g}' for x in k)}")
    return 0


# ----------------------------------------------------------------------------- simulate
def _refuse_diverged(trace, out: Path, params_file: str | None) -> None:
    """A simulated trace with NaN or infinite samples is no recording: refuse to write it,
    saying where the model diverged."""
    from .traces.files import first_nonfinite

    bad = first_nonfinite(trace)
    if bad is None:
        return
    name, row, count = bad
    given = f"the parameters of {params_file}" if params_file else "the parameters"
    raise UsageError(f"the simulation diverged: {name} is NaN or infinite in {count:,} of "
                     f"{trace.n:,} samples from t = {trace.t[row]:.6g} s; {given} make the model "
                     f"unstable (check the units of motor.J_m, motor.L and the gains); {out} was "
                     "not written")


def cmd_simulate(args: argparse.Namespace) -> int:
    from .faults import as_k, scenario
    from .acquisition import Sensors
    from .plots import plot_trace
    from .progress import compile_notice
    from .simulate import DEFAULT_SENSORS, simulate
    from .traces import write_trace

    if args.k is not None and args.scenario is not None or \
            (args.k is None and args.scenario is None and not args.fault):
        raise UsageError("give exactly one of --k K1,...,K8 or --scenario NAME (see `emaphm "
                         "scenarios`), or faults with --fault MODE:... on the nominal actuator")
    out = out_path(args.out, (".csv", ".parquet"), "--out", inputs=[args.params])
    plot = plot_path(args.plot)
    k = as_k(args.k) if args.k is not None else scenario(args.scenario or "nominal")
    faults = _fault_options(args.fault)
    fault_model = _fault_model_option(args)
    params = _load_params(args.params)
    unit = _unit_options(args, params)
    if args.noise is None:
        sensors = DEFAULT_SENSORS if args.seed is not None else Sensors()
    else:
        if not 0.0 <= args.noise <= 1.0:
            raise UsageError(f"--noise {args.noise:g} A rms is outside 0 to 1 A: a current sensor "
                             "of a servo drive has tens of milliamperes (default 0.02)")
        sensors = Sensors(current_noise=args.noise, current_lsb=DEFAULT_SENSORS.current_lsb)
    if args.f_sample is not None or args.aa_cutoff is not None:
        from dataclasses import replace

        sensors = replace(sensors, f_sample=args.f_sample or 0.0,
                          aa_order=args.aa_order if args.aa_cutoff else 0,
                          aa_cutoff=args.aa_cutoff or 0.0)
    if sensors.current_noise > 0 and args.seed is None:
        raise UsageError("sensor noise needs --seed S (randomness always flows from an explicit seed)")
    profile = _profile_option(args.profile)
    if (args.drive_signals or args.firmware) and args.model != "reference":
        raise UsageError("--drive-signals and --firmware describe the plant's drive: use them "
                         "with --model reference")
    t0 = time.perf_counter()
    with compile_notice():
        trace = simulate(k, model=args.model, params=params, sensors=sensors, seed=args.seed,
                         fault_model=fault_model, faults=faults, profile=profile,
                         drive_signals=args.drive_signals, drive=args.firmware, **unit)
    if args.scenario:
        trace = trace.with_meta(scenario=args.scenario)
    elapsed = time.perf_counter() - t0
    _refuse_diverged(trace, out, args.params)
    write_trace(trace, out, finite=True)
    print(f"wrote {out} ({trace.n} samples, {trace.duration:.3f} s, {args.model} model, "
          f"simulated in {elapsed:.2f} s)", file=sys.stderr)
    if plot:
        import numpy as np

        overlay = None
        if (faults or not np.allclose(k, scenario("nominal"))) and not args.no_overlay:
            overlay = simulate(scenario("nominal"), model=args.model, params=params,
                               fault_model=fault_model, profile=profile,
                               **unit).with_meta(scenario="nominal")
        title = None
        if args.fault:                          # the faults, which k alone does not show
            title = (f"{args.model}: {', '.join(args.fault)}"
                     + ("" if np.allclose(k, scenario("nominal"))
                        else f", k = {np.round(k, 3).tolist()}"))
        plot_trace(trace, overlay, path=plot, title=title)
        print(f"wrote {plot}", file=sys.stderr)
    return 0


def _fault_options(specs: list[str] | None) -> list[str]:
    """--fault specs, each checked (a UsageError naming the grammar)."""
    from .modes import fault_specs, parse_fault

    for spec in specs or []:
        try:
            parse_fault(spec)
        except ValueError as exc:
            raise UsageError(f"--fault {shown(spec)}: {exc}; the specs are {fault_specs()}") from None
    return list(specs or [])


def _fault_model_option(args: argparse.Namespace) -> str:
    """--fault-model, else the scenario's own, else physical."""
    from .faults import check_fault_model, scenario_fault_model

    if args.fault_model is not None:
        return check_fault_model(args.fault_model)
    return scenario_fault_model(args.scenario) if args.scenario else "physical"


def _profile_option(text: str | None):
    """--profile NAME | FILE.csv -> a Profile (None: the diagnostic profile)."""
    from .profiles import PROFILES, ProfileError, get_profile, read_profile

    if text is None:
        return None
    if text in PROFILES:
        return get_profile(text)
    if not text.lower().endswith(".csv"):
        raise UsageError(f"--profile {shown(text)}: give a built-in profile ({', '.join(PROFILES)}) "
                         "or a CSV file of columns t [s], theta_ref [rad]")
    try:
        return read_profile(text)
    except ProfileError as exc:
        raise UsageError(f"--profile: {exc}") from None


_min_rotation = arg_type(float, lambda x: math.isfinite(x) and x >= 0,
                         "expected a rotation in rad >= 0 (6.283 is one "
                         "revolution, 0 skips the check)")


def _nuisance_option(text: str | None) -> tuple[str, ...] | None:
    """--nuisance R,flux | none -> names (None: identify's default)."""
    from .search import NUISANCE_RANGE

    if text is None:
        return None
    if text.strip().lower() == "none":
        return ()
    names = tuple(x.strip() for x in text.split(",") if x.strip())
    bad = [n for n in names if n not in NUISANCE_RANGE]
    if bad or len(set(names)) != len(names):
        raise UsageError(f"--nuisance {shown(text)}: give none or a comma-separated subset of "
                         f"{', '.join(NUISANCE_RANGE)} (each once)")
    return names


def _unit_options(args: argparse.Namespace, params) -> dict[str, Any]:
    """--unit-seed, --tolerances and --unreported-load as keyword arguments of simulate()."""
    from .units import load_tolerances

    if args.tolerances is not None and args.unit_seed is None:
        raise UsageError("--tolerances needs --unit-seed N (the seed of the unit to draw)")
    if (args.unit_seed is not None or args.unreported_load is not None) \
            and getattr(args, "model", "reference") != "reference":
        raise UsageError("--unit-seed, --tolerances and --unreported-load describe the plant: "
                         "use them with --model reference")
    out: dict[str, Any] = {}
    if args.unit_seed is not None:
        out["unit_seed"] = args.unit_seed
        if args.tolerances is not None:
            out["tolerances"] = load_tolerances(args.tolerances)
    if args.unreported_load is not None:
        out["unreported_load"] = args.unreported_load
    return out


# ----------------------------------------------------------------------------- diagnose
def _table(ident, diag) -> str:
    from .faults import K_LABELS, K_NAMES
    from .search import nuisance_text
    from .verdict import NOISELESS_NOTE

    lines = [f"{'k':4s} {'component':26s} {'identified':>10s}"
             + (f" {'true':>8s}" if ident.k_true is not None else "")]
    for i, (name, label) in enumerate(zip(K_NAMES, K_LABELS)):
        row = f"k{i + 1:<3d} {label:26s} {ident.k[i]:10.4f}"
        if ident.k_true is not None:
            row += f" {ident.k_true[i]:8.4f}"
        lines.append(row)
    lines.append("")
    not_seen = getattr(ident, "not_observable", ())
    lines.append(f"drive model {getattr(ident, 'drive_model', 'modelled controller')}"
                 + (f" ({', '.join(m.replace('_', ' ') for m in not_seen)} not observable on it: "
                    "reported healthy, not measured)" if not_seen else ""))
    lines.append(f"fault model {ident.fault_model}"
                 + ("; searched with " + ", ".join(nuisance_text(n, v)
                                                   for n, v in ident.nuisance.items())
                    if ident.nuisance else ""))
    lines.append(f"algorithm {ident.algorithm}, seed {ident.seed}: {ident.evaluations} evaluations, "
                 f"{ident.iterations} iterations in {ident.elapsed_s:.2f} s "
                 f"({ident.evals_per_s:.0f} evals/s, {100 * ident.kernel_s / max(ident.elapsed_s, 1e-12):.0f}% "
                 f"in the model kernel), stop: {ident.reason}"
                 + (f"; plus {ident.compile_s:.1f} s compiling or loading the model kernels "
                    "(first run of a process)" if ident.compile_s > 0.5 else ""))
    ratio = ident.fitness / ident.noise_floor if ident.noise_floor > 0 else float("nan")
    noiseless = NOISELESS_NOTE in diag.notes
    if noiseless:
        ratio = float("nan")              # a floor of round-off: no ratio worth printing
    recorded = getattr(ident, "drive_model", "modelled controller") != "modelled controller"
    lines.append(f"fitness ({'Eq. 4 of the currents and the mechanical residual' if recorded else 'Eq. 4'}) "
                 f"{ident.fitness:.4e}"
                 + (f", {ratio:.1f}x the noise floor of the trace" if ratio == ratio else "")
                 + (f" ({ident.restarts} restart{'s' if ident.restarts > 1 else ''})"
                    if ident.restarts else ""))
    if ident.suspect and diag.refit is not None:
        lines.append(f"the fit stays above the noise floor with k alone; the "
                     f"{diag.refit.mode.replace('_', ' ')} hypothesis explains it (below)")
    elif ident.suspect and diag.unexplained is None and not noiseless:
        lines.append("WARNING: the best fit stays far above the trace's noise floor: the search may "
                     "have missed the actuator's k, or the model parameters (--params) do not "
                     "describe this actuator; treat the verdict with care")
    if ident.error_pct is not None:
        lines.append(f"identification error (Eq. 9) {ident.error_pct:.2f}%")
    lines.append("")
    lines.append("verdict: " + diag.verdict.upper())
    for f in diag.faults:
        lines.append(f"  - {f.mode}{' (phase ' + f.phase + ')' if f.phase else ''}: {f.reading}")
    if diag.unexplained is not None:
        u = diag.unexplained
        lines.append(f"  the model does not explain this actuator ({u.reason}"
                     + (f", p = {u.p_value:.1e}" if u.p_value is not None else "") + f"): {u.hint}")
        if diag.mismatch is not None and u.reason == "mismatch":
            lines.append("  mismatch check (k searched with "
                         + ", ".join(nuisance_text(n, v) for n, v in diag.mismatch.nuisance.items())
                         + "): " + ", ".join(f"k{i + 1} {x:.3f}" for i, x in enumerate(diag.mismatch.k)))
        if diag.suspected:
            lines.append("  components above their thresholds, not a diagnosis: "
                         + ", ".join(f"{f.mode}{' ' + f.phase if f.phase else ''}"
                                     for f in diag.suspected))
    if diag.refit is not None:
        r = diag.refit
        lines.append(f"  read on the refit of the {r.mode.replace('_', ' ')} hypothesis (k searched "
                     "with " + ", ".join(nuisance_text(n, v) for n, v in r.nuisance.items())
                     + (f", fit {r.fit_ratio:.2f}x the noise floor" if r.fit_ratio else "")
                     + "): " + ", ".join(f"k{i + 1} {x:.3f}" for i, x in enumerate(r.k)
                                         if abs(x - (0.5 if i in (6, 7) else 0.0)) > 1e-3))
    for note in diag.notes:
        lines.append(f"  note: {note}")
    return "\n".join(lines)


def _prefetch_drive_check(params: Any, trace: Any) -> None:
    """The kernels a diagnosis will run, compiled in child processes meanwhile where they
    are not cached (:func:`emaphm.models.warm.prefetch`): on the modelled controller its
    drive's own variant, and on a data sheet the one with options its drive check runs."""
    from .firmware import MODELLED
    from .models.warm import diagnosis_variants, prefetch
    from .params import siemens_1fk7060
    from .recorded import drive_model_of
    from .verdict import needs_mismatch_check

    try:                               # a speed-up only: what it cannot tell, the run will say
        if trace is not None and drive_model_of(trace, None) != MODELLED:
            return
        prefetch(diagnosis_variants(siemens_1fk7060() if params is None else params,
                                    drive_check=needs_mismatch_check(params)))
    except Exception:                  # noqa: BLE001
        return


def cmd_diagnose(args: argparse.Namespace) -> int:
    from .faults import scenario
    from .identify import IdentificationConfig, algorithm_names
    from .params import resolve_params
    from .verdict import examine
    from .plots import plot_identification
    from .progress import SearchProgress, compile_notice
    from .simulate import DEFAULT_SENSORS, simulate
    from .traces import TraceError

    if (args.trace is None) == (args.scenario is None):
        raise UsageError("give exactly one of a TRACE file or --scenario NAME (see `emaphm scenarios`)")
    if args.algorithm not in algorithm_names():
        raise UsageError(f"unknown algorithm {shown(args.algorithm)}; choose one of "
                         f"{', '.join(algorithm_names())}")
    budget = budget_option(args.budget)
    plot = plot_path(args.plot)
    given = _load_params(args.params) if args.params else None   # else the trace's own
    params = given if given is not None else _load_params(None)
    progress = SearchProgress(enabled=not args.quiet,
                              header=f"identifying with {args.algorithm.upper()} (seed {args.seed})")
    if args.trace is not None:
        if args.unit_seed is not None or args.unreported_load is not None \
                or args.tolerances is not None:
            raise UsageError("--unit-seed, --tolerances and --unreported-load describe a simulated "
                             "plant: use them with --scenario, not with a trace file")
        trace = _trace_file(args.trace, args.min_rotation)
    else:
        _prefetch_drive_check(params, None)
        k_true = scenario(args.scenario)
        sim_fault_model = _fault_model_option(args)
        unit = _unit_options(args, params)
        if not args.quiet:
            print(f"simulating scenario {args.scenario} on the reference plant "
                  f"({sim_fault_model} fault model, switching PWM, sensor noise "
                  f"{DEFAULT_SENSORS.current_noise * 1e3:.0f} mA rms, seed {args.seed}"
                  + (f", unit {args.unit_seed}" if args.unit_seed is not None else "") + ")",
                  file=sys.stderr)
        with compile_notice(progress, enabled=not args.quiet):
            trace = simulate(k_true, model="reference", params=params, sensors=DEFAULT_SENSORS,
                             seed=args.seed, fault_model=sim_fault_model,
                             **unit).with_meta(scenario=args.scenario)
    if args.trace is not None:
        params = resolve_params(given, trace, warn=False)[0]
        _prefetch_drive_check(params, trace)
    if not args.quiet:
        warn_if_long("emaphm diagnose", identification_seconds(trace.duration, params,
                                                               args.algorithm, budget),
                     "this identification",
                     "diagnose a shorter window (one 0.5 s diagnostic profile is enough), or "
                     "cap it with --budget (e.g. --budget 60s)")
    try:
        with compile_notice(progress, enabled=not args.quiet):
            config = IdentificationConfig(algorithm=args.algorithm, budget=budget,
                                          fault_model=args.fault_model,
                                          drive_model=args.drive_model,
                                          nuisance=_nuisance_option(args.nuisance),
                                          **({} if args.min_rotation is None
                                             else {"min_rotation": args.min_rotation}))
            exam = examine(trace, params=given, config=config, seed=args.seed,
                           callback=progress)
    except TraceError as exc:            # found in the trace's content: name the file
        raise UsageError(f"{args.trace}: {exc}" if args.trace else str(exc)) from None
    finally:
        progress.close()
    ident, diag = exam.identification, exam.diagnosis
    recorded = (trace.meta.get("parameters") or {}).get("name") \
        if isinstance(trace.meta.get("parameters"), dict) else None
    used = params.name
    if diag.verdict == "unexplained" and isinstance(recorded, str) and recorded != used:
        print(f"emaphm diagnose: note: the trace's metadata says it was simulated for "
              f"{shown(recorded)}, and it was diagnosed with {shown(used)}: give that "
              f"actuator's parameters (--params)", file=sys.stderr)
    if args.json:
        out = {**ident.to_dict(), **diag.to_dict(),
               "scenario": args.scenario or trace.meta.get("scenario"),
               "trace": args.trace, "version": __version__}
        if not args.history:
            out.pop("history", None)
        print(json.dumps(out))
    else:
        print(_table(ident, diag))
    if plot:                # the trace the identification fitted: a faulty sensor undone
        plot_identification(exam.trace, ident, diagnosis=diag, path=plot)
        print(f"wrote {plot}", file=sys.stderr)
    return 0


# ----------------------------------------------------------------------------- calibrate
def cmd_calibrate(args: argparse.Namespace) -> int:
    from pathlib import Path

    from .calibration import DRIVE_SETTINGS, CalibrationError, calibrate
    from .params import resolve_params, save_params
    from .progress import CountProgress, compile_notice

    unknown = [n.strip() for n in args.drive_unknown.split(",") if n.strip()]
    strange = [n for n in unknown if n not in DRIVE_SETTINGS]
    if strange:
        raise UsageError(f"--drive-unknown {','.join(strange)}: no drive setting a calibration "
                         f"estimates; choose from {', '.join(DRIVE_SETTINGS)} (describe the "
                         "others, delay_periods and decoupling among them, in [controller])")

    out = out_path(args.out, (".toml",), "--out", inputs=[*args.traces, args.params])
    plot = plot_path(args.plot)
    given = _load_params(args.params) if args.params else None     # else the traces' own
    traces = [_trace_file(name) for name in args.traces]
    params, source = resolve_params(given, traces, warn=False)
    around = {"given": args.params, "trace": f"the traces' own actuator ({shown(params.name)})",
              "preset": "the default preset"}[source]
    progress = CountProgress("calibrating:", enabled=not args.quiet, noun=" model runs",
                             header=f"calibrating on {len(traces)} healthy trace(s) around {around}")
    if not args.quiet:
        warn_if_long("emaphm calibrate", calibration_seconds([t.duration for t in traces], params),
                     "this calibration", "calibrate on shorter traces (one 0.5 s diagnostic "
                     "profile each is enough)")
    try:
        with compile_notice(progress, enabled=not args.quiet):
            res = calibrate(traces, given, sources=[str(Path(n).name) for n in args.traces],
                            progress=progress.update, drive_unknown=unknown)
    except CalibrationError as exc:
        raise UsageError(str(exc)) from None
    finally:
        progress.close()
    save_params(res.params, out)
    if args.json:
        d = res.to_dict()
        d.update(out=str(out), version=__version__)
        print(json.dumps(d))
    else:
        print(res.summary())
    print(f"wrote {out}: pass it with --params to diagnose this unit", file=sys.stderr)
    if plot:
        from .plots import plot_calibration

        plot_calibration(res, path=plot)
        print(f"wrote {plot}", file=sys.stderr)
    return 0


# ----------------------------------------------------------------------------- params
def cmd_params(args: argparse.Namespace) -> int:
    from .params import save_params, siemens_1fk7060

    out = out_path(args.out, (".toml",), "--out", inputs=[args.datasheet])
    if args.datasheet is None:
        save_params(siemens_1fk7060(), out)
        print(f"wrote {out}: the reconstructed Siemens 1FK7060-2AC71 preset in SI units; edit it "
              "and pass it with --params", file=sys.stderr)
        return 0
    from .datasheet import convert, load_nameplate

    sheet = convert(load_nameplate(args.datasheet))
    save_params(sheet.params, out)
    if not args.quiet:
        print(sheet.summary())
    for text in sheet.warnings:
        print(f"emaphm params: warning: {text}", file=sys.stderr)
    print(f"wrote {out}: {sheet.params.name} in emaphm's per-phase SI parameters; pass it with "
          "--params", file=sys.stderr)
    return 0


def _plant_arguments(p: argparse.ArgumentParser, *, diagnose: bool = False) -> None:
    p.add_argument("--fault-model", choices=("physical", "paper"), default=None,
                   help=("mapping of k3..k5 in the monitoring model: physical (inter-turn fault "
                         "loop) or paper (turns removed); default the trace's own, physical for a "
                         "bench trace" if diagnose else
                         "physical (inter-turn fault loop) or paper (turns removed: R x(1-k), "
                         "L x(1-k)^2); default the scenario's own, physical for --k"))
    where = "the simulated plant (with --scenario)" if diagnose else "the plant (--model reference)"
    p.add_argument("--unit-seed", type=_seed, default=None,
                   help=f"draw {where} as a production unit within tolerances, from this seed")
    p.add_argument("--tolerances", default=None,
                   help="TOML file with [tolerances] name = [lo, hi] (with --unit-seed; see "
                        "emaphm.units)")
    p.add_argument("--unreported-load", type=float, default=None,
                   help=f"constant load torque [N m] on {where} that the trace does not report")


def _drive_arguments(p: argparse.ArgumentParser, diagnose: bool = False) -> None:
    """The drive's options: what the plant's drive runs and logs (simulate), or what
    stands in for it (diagnose)."""
    if diagnose:
        p.add_argument("--drive-model", choices=DRIVE_MODELS, default=None,
                       help="what stands in for the drive's controller: 'recorded voltages' (no "
                            "controller modelled), 'recorded current references' (the current "
                            "loop of [controller] modelled), 'recorded speed reference' (the "
                            "speed and current loops modelled) or 'modelled controller' (the "
                            "whole [controller]); default the first the trace has the signals for")
        return
    p.add_argument("--drive-signals", action="store_true",
                   help="also record what the plant's drive logs: the phase voltages it applied "
                        "(v_a, v_b, v_c), its current and speed references")
    p.add_argument("--firmware", choices=sorted(FOREIGN_DRIVES), default=None,
                   help="the plant's drive runs this firmware, not emaphm's cascade: "
                        + "; ".join(f"{k}: {v}" for k, v in FOREIGN_DRIVES.items()))


def _calibrate_parser(sub) -> None:
    cal = sub.add_parser("calibrate", help="estimate a healthy unit's parameters from its traces",
                         description="Fit inertia, flux, resistance, inductance, friction, "
                                     "current sensor gains and offsets and an unreported load "
                                     "of a unit known to be healthy; write its parameters.")
    cal.add_argument("traces", nargs="+", help="traces of the healthy unit (.csv or .parquet)")
    cal.add_argument("--out", required=True, help="calibrated parameters, .toml")
    cal.add_argument("--params", help=f"data-sheet parameters TOML {_PARAMS_DEFAULT}")
    cal.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    cal.add_argument("--plot", help="measured vs calibrated currents of the first trace (.png)")
    cal.add_argument("--drive-unknown", metavar="KEY,...", default="",
                     help="drive settings you do not know, estimated beside the unit and "
                          "written into [controller]/[inverter]: velocity_feedforward, "
                          "torque_feedforward, speed_filter_s, current_reference_filter_s, "
                          "speed_reference_weight, Kp, Kp_w, Ki_w, Kp_i, Ki_i")
    cal.add_argument("--quiet", action="store_true")
    cal.set_defaults(func=cmd_calibrate)


def build_parser() -> argparse.ArgumentParser:
    ap = Parser(prog="emaphm", description=__doc__.split("\n")[0],
                formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--version", action="version", version=f"emaphm {__version__}")
    sub = ap.add_subparsers(dest="command", required=True, metavar="COMMAND")

    s = sub.add_parser("simulate", help="simulate an actuator and write its trace")
    s.add_argument("--model", choices=("reference", "monitoring"), default="reference")
    s.add_argument("--k", help="fault vector, 8 comma-separated values in [0,1], e.g. 0.75,0,0,0,0,0,0.5,0.5")
    s.add_argument("--scenario", help="a named scenario (see `emaphm scenarios`)")
    s.add_argument("--out", required=True, help="output trace, .csv or .parquet")
    s.add_argument("--plot", help="also write a figure (.png/.svg/.pdf)")
    s.add_argument("--no-overlay", action="store_true", help="do not overlay the nominal run on the plot")
    s.add_argument("--fault", action="append", metavar="MODE:...",
                   help="a fault of a mode to simulate, repeatable: friction:2.5 (x nominal), "
                        "backlash:10, short_circuit:a:0.3[:R_F_OHM] (shorted fraction, fault "
                        "resistance), eccentricity:0.1, gain_drift:0.9 (x nominal), "
                        "demagnetization:0.15 (flux lost), current_sensor:b:gain:0.9 or "
                        "current_sensor:b:offset:0.2 (A), resistance:b:1.3 (x the phase's "
                        "resistance: a high-resistance connection)")
    s.add_argument("--seed", type=_seed, help="seed of the sensor noise (enables realistic sensors)")
    s.add_argument("--noise", type=float, help="current noise in A rms (default 0.02 with --seed, else 0)")
    s.add_argument("--params", help="actuator parameters TOML (missing fields from the default preset)")
    s.add_argument("--f-sample", type=float, default=None,
                   help="record at this rate [Hz] (default: the control instants, 8 kHz)")
    s.add_argument("--aa-cutoff", type=float, default=None,
                   help="anti-alias low-pass cut-off [Hz] before the ADC (needs --f-sample)")
    s.add_argument("--aa-order", type=int, default=2, help="anti-alias Butterworth order (default 2)")
    _drive_arguments(s)
    s.add_argument("--profile", metavar="NAME|FILE.csv",
                   help="the command: a built-in profile (diagnostic, the default; sine, chirp, "
                        "step, ramp, trapezoid) or a CSV file of columns t [s], theta_ref [rad] "
                        "(a trace file too), replayed from its first sample")
    _plant_arguments(s)
    s.set_defaults(func=cmd_simulate)

    c = sub.add_parser("scenarios", help="list the named fault scenarios")
    c.add_argument("--json", action="store_true")
    c.set_defaults(func=cmd_scenarios)

    d = sub.add_parser("diagnose", help="identify the faults of a trace")
    d.add_argument("trace", nargs="?", help="trace file (.csv or .parquet)")
    d.add_argument("--scenario", help="simulate this scenario on the reference model and diagnose it")
    d.add_argument("--algorithm", default="lsq",
                   help="lsq (default: batched least squares from the healthy start and a "
                        "seeded sample), the paper's pso, de, gwo, or the baselines scipy-de "
                        "and cmaes")
    d.add_argument("--seed", type=_seed, default=0, help="seed of the optimizer (and of the sensor noise)")
    d.add_argument("--budget", help="evaluations (e.g. 5000) or wall-clock seconds (e.g. 10s); "
                                    "default: the paper's stopping rules")
    d.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    d.add_argument("--history", action="store_true", help="include the convergence history in the JSON")
    d.add_argument("--plot", help="write measured vs identified currents and convergence (.png)")
    d.add_argument("--params", help=f"actuator parameters TOML {_PARAMS_DEFAULT}")
    d.add_argument("--quiet", action="store_true", help="no progress line")
    d.add_argument("--min-rotation", type=_min_rotation, default=None, metavar="RAD",
                   help="least motor rotation range the trace must show [rad] (default 6.283, "
                        "one revolution, which the eccentricity needs; 0 skips the check, and "
                        "the eccentricity read from a shorter trace is then a guess)")
    _drive_arguments(d, diagnose=True)
    d.add_argument("--nuisance", default=None,
                   help="parameters searched with k so that a drift is not read as a fault: "
                        "none, or a comma-separated subset of R (winding resistance), flux "
                        "(magnet flux), load (an unreported constant load, N m); default R,flux "
                        "for calibrated --params, none for a data sheet, whose faults the "
                        "mismatch check then confirms with R,flux,load searched beside k")
    _plant_arguments(d, diagnose=True)
    d.set_defaults(func=cmd_diagnose)

    _calibrate_parser(sub)

    p = sub.add_parser("params", help="write the default actuator parameters (or a motor's, from "
                                      "its data sheet) to a TOML file")
    p.add_argument("--out", required=True)
    p.add_argument("--datasheet", help="a [datasheet] TOML in catalogue units (poles, ke in V/krpm "
                                       "line to line, r_ll, l_ll, j_rotor, t_max, i_max...; see "
                                       "docs/bench-import.md): convert it instead")
    p.add_argument("--quiet", action="store_true", help="do not print the converted values")
    p.set_defaults(func=cmd_params)

    # subcommands of the campaign, prognosis and fleet layers live beside their code
    for module in ("emaphm.traces.importers.cli", "emaphm.campaign.cli", "emaphm.assessment.cli",
                   "emaphm.prognosis.cli", "emaphm.fleet.cli"):
        try:
            register = importlib.import_module(module).register
        except ModuleNotFoundError as exc:
            if exc.name is None or not module.startswith(exc.name):
                raise
            continue
        register(sub)
    return ap


@contextlib.contextmanager
def trace_warnings_as_lines(cmd: str):
    """Inside: a :class:`~emaphm.traces.TraceWarning` (a trace read, but not quite as
    written), a :class:`~emaphm.params.CalibrationWarning` (a parameter file's
    calibration not as ``emaphm calibrate`` wrote it) or a
    :class:`~emaphm.params.PlausibilityWarning` (a parameter near the edge of what servo
    actuators have) or an :class:`~emaphm.params.ActuatorMismatchWarning` (parameters given
    for a trace of another actuator, once) is printed as one line on stderr, ``CMD: warning: ...``; other
    warnings as Python prints them."""
    from .params import ActuatorMismatchWarning, CalibrationWarning, PlausibilityWarning
    from .traces import TraceWarning

    with warnings.catch_warnings():
        warnings.simplefilter("always", TraceWarning)
        warnings.simplefilter("always", PlausibilityWarning)
        warnings.simplefilter("once", ActuatorMismatchWarning)
        original = warnings.showwarning

        def show(message, category, filename, lineno, file=None, line=None):
            if issubclass(category, (TraceWarning, CalibrationWarning, PlausibilityWarning,
                                     ActuatorMismatchWarning)):
                print(f"{cmd}: warning: {one_line(str(message))}", file=sys.stderr)
            else:
                original(message, category, filename, lineno, file, line)

        warnings.showwarning = show
        yield


#: What a command says in place of validate()'s advice for a trace that turns less than a
#: revolution (``min_rotation=0`` is a keyword of the Python API, not an option of these).
_ROTATION_ADVICE = {
    "diagnose": "Record a longer profile (e.g. the built-in diagnostic profile), or pass "
                "--min-rotation 0 to skip this check (the eccentricity is then not identified)",
    "import": "Import a longer --window (or the whole recording), or record a longer profile "
              "(e.g. the built-in diagnostic profile)",
}


def command_advice(command: str, text: str) -> str:
    """``text`` with the Python API's advice replaced by what ``command`` can do."""
    if "min_rotation=0" not in text:
        return text
    from .traces.validation import ROTATION_ADVICE

    return text.replace(ROTATION_ADVICE, _ROTATION_ADVICE.get(
        command, "Record a longer profile (e.g. the built-in diagnostic profile, 0.5 s)"))


def main(argv: Sequence[str] | None = None) -> int:
    printable_streams()
    parser = build_parser()
    args = parser.parse_args(negative_values(parser, sys.argv[1:] if argv is None else argv))
    cmd = " ".join(["emaphm", args.command] + ([args.history_command]
                                               if getattr(args, "history_command", None) else []))

    def error(text: str) -> int:
        print(f"{cmd}: error: {one_line(command_advice(args.command, text))}", file=sys.stderr)
        return EXIT_USAGE

    # the one error boundary: an expected failure is one line and exit 2, anything else is a
    # bug, shown with its traceback
    try:
        with trace_warnings_as_lines(cmd):
            return args.func(args)
    except UsageError as exc:
        return error(str(exc))
    except (ValueError, FileNotFoundError) as exc:   # TraceError, ParameterError, FaultVectorError...
        return error(str(exc))
    except KeyboardInterrupt:
        print(f"{cmd}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:      # e.g. `emaphm scenarios | head -3`
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 0
    except OSError as exc:                           # a folder, no permission, a full disk...
        path = f"{exc.filename}: " if getattr(exc, "filename", None) else ""
        return error(f"{path}{exc.strerror or exc}; check the path, that it is a file where a "
                     "file is meant, its permissions and the free space")
    except RecursionError:
        return error("the input is nested too deeply to read (e.g. trace metadata); the file is "
                     "malformed: export it again")
    except MemoryError:
        return error("the input needs more memory than this machine has; use a shorter or less "
                     "finely sampled trace")
    except Exception:                                # noqa: BLE001 - a bug: say so, keep the trace
        import traceback

        traceback.print_exc()
        print(f"{cmd}: this is a bug in emaphm {__version__}, not a problem with your input: "
              "please report it to the emaphm maintainers with the command line and the "
              "traceback above", file=sys.stderr)
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
