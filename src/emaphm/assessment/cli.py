"""``emaphm assess``: a thin layer over :mod:`emaphm.assessment`.

    emaphm assess --params ACT.toml --out DIR [--tolerances TOL.toml] [--units 20]
                  [--target-far 0.01] [--seed N] [--workers N | --scheduler ADDRESS]
                  [--grids friction,short_circuit] [--severities friction=1.25,1.5]
                  [--quiet]

Exit status: 0 written; 1 some units failed (DIR not written; the same command retries
them); 2 bad input (nothing written); 130 interrupted (the units done are kept beside DIR;
the same command resumes).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from .._cli_common import UsageError, arg_type, writable_folder

__all__ = ["register", "cmd_assess"]

_units = arg_type(int, lambda n: 1 <= n <= 10_000, "expected an integer from 1 to 10000 "
                  "(production units)")
_count = arg_type(int, lambda n: 0 <= n <= 10_000, "expected an integer from 0 to 10000")
_traces = arg_type(int, lambda n: 1 <= n <= 10_000, "expected an integer from 1 to 10000 "
                   "(healthy traces per unit)")
_far = arg_type(float, lambda x: 0.0 < x < 0.5, "expected a rate in (0, 0.5), e.g. 0.01")
_seed = arg_type(int, lambda n: n >= 0, "expected an integer >= 0")
_workers = arg_type(int, lambda n: 0 <= n <= 4096, "expected an integer from 0 to 4096 "
                    "(local worker processes; 0 runs in this process)")


def _severities(items: list[str] | None) -> dict[str, tuple[float, ...]]:
    out: dict[str, tuple[float, ...]] = {}
    for item in items or ():
        name, sep, values = item.partition("=")
        if not sep or not values.strip():
            raise UsageError(f"--severities {item!r}: expected GRID=S1,S2,... e.g. friction=1.25,1.5")
        try:
            out[name.strip()] = tuple(float(v) for v in values.split(","))
        except ValueError:
            raise UsageError(f"--severities {item!r}: the severities must be numbers") from None
    return out


def build_spec(args: argparse.Namespace) -> Any:
    from ..params import load_params, siemens_1fk7060
    from ..units import load_tolerances
    from .spec import AssessmentSpec

    params = load_params(args.params) if args.params else siemens_1fk7060()
    tolerances = load_tolerances(args.tolerances).to_dict() if args.tolerances else {}
    grids = (tuple(g.strip() for g in args.grids.split(",") if g.strip())
             if args.grids is not None else None)
    if grids == ():
        raise UsageError(f"--grids {args.grids!r} names no fault grid; give grids separated by "
                         "commas (e.g. friction,short_circuit), or leave --grids out for all")
    return AssessmentSpec(
        params.to_dict(), tolerances, units=args.units,
        tune_units=0 if args.no_tune else args.tune_units, healthy=args.healthy,
        healthy_datasheet=(min(2, args.healthy) if args.healthy_datasheet is None
                           else args.healthy_datasheet), target_far=args.target_far, seed=args.seed,
        grids=grids, severities=_severities(args.severities),
        datasheet_faults=args.datasheet_faults, drive_signals=args.drive_signals)


def cmd_assess(args: argparse.Namespace) -> int:
    from ..campaign.executors import make_executor, warm_up
    from ..progress import RunProgress, compile_notice
    from .runner import AssessmentIncomplete, assess, check_tracking, work_folder

    if args.workers is not None and args.scheduler is not None:
        raise UsageError("give either --workers (local pool) or --scheduler (Dask cluster), not both")
    out = Path(args.out)
    if out.exists():
        raise UsageError(f"--out {out} exists; give a new folder (an assessment is written whole, "
                         "into a folder of its own)")
    if not out.parent.is_dir():
        raise UsageError(f"--out {out}: folder {out.parent} does not exist; create it first")
    writable_folder(out.parent, "--out")
    spec = build_spec(args)
    check_tracking(spec.actuator())          # refused in one line, before anything is said
    executor = make_executor(args.workers, args.scheduler)
    if hasattr(executor, "check"):
        executor.check()
    quiet = args.quiet
    work = work_folder(out)
    if not quiet:
        print(f"emaphm assess: {spec.params.get('name')}: {spec.units} units"
              + (f" (thresholds tuned on {spec.tune_units} others)" if spec.tune else "")
              + f", {len(spec.grids or ())} fault grids; {executor.describe()}"
              + ("; resuming" if work.exists() else ""), file=sys.stderr)
        with compile_notice(None, enabled=True):
            warm_up()

    def progress(phase: str) -> Any:
        if quiet:
            return None
        print(f"{'tuning the thresholds' if phase == 'tune' else 'diagnosing the units'}:",
              file=sys.stderr)
        return RunProgress(sys.stderr)

    try:
        outcome = assess(spec, out, executor=executor, progress=progress)
    except AssessmentIncomplete as exc:
        print(f"emaphm assess: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"emaphm assess: interrupted; the units done are kept in {work}. Run the same "
              "command again to resume.", file=sys.stderr)
        return 130
    a = outcome.summary
    if not quiet:
        from .report import conclusions

        for line in conclusions(a):
            print(line)
        print(f"wrote {out}/ (assessment.json, report.md, params.toml with [thresholds]); "
              f"{a['cpu_s']['total']:.0f} s of CPU, {a['wall_s']:.0f} s wall", file=sys.stderr)
    return 0


def register(sub: Any) -> None:
    """Add ``assess`` to the subcommands of ``emaphm``."""
    a = sub.add_parser(
        "assess", help="what the method detects on an actuator, and how often it false-alarms",
        description="Draw production units of an actuator within its tolerances, simulate them "
                    "on the reference plant healthy and with one fault at a time over a grid of "
                    "severities, diagnose each after calibration (and healthy ones on the data "
                    "sheet), tune the detection thresholds to a false-alarm target on units of "
                    "their own, and write DIR/assessment.json, DIR/report.md (POD curves, false "
                    "alarms, confusion) and DIR/params.toml (the parameters with [thresholds]). "
                    "Resumable: run the same command again after an interruption.")
    a.add_argument("--params", help="the actuator's parameter file (default the preset)")
    a.add_argument("--tolerances", help="production tolerances, TOML [tolerances] (default "
                                        "emaphm.units.DEFAULT_TOLERANCES)")
    a.add_argument("--out", required=True, help="output folder, new")
    a.add_argument("--units", type=_units, default=20, help="reported production units (default 20)")
    a.add_argument("--tune-units", type=_count, default=None,
                   help="units the thresholds are tuned on (default as many as --units; 0: "
                        "none, the thresholds of --params kept, as --no-tune)")
    a.add_argument("--no-tune", action="store_true",
                   help="keep the thresholds of --params (e.g. to check an assessed params.toml "
                        "on new units with another --seed)")
    a.add_argument("--target-far", type=_far, default=0.01,
                   help="false-alarm rate the tuned thresholds aim under (default 0.01)")
    a.add_argument("--healthy", type=_traces, default=10,
                   help="healthy traces per unit diagnosed after calibration (default 10)")
    a.add_argument("--healthy-datasheet", type=_count, default=None,
                   help="of those, how many are also diagnosed on the data sheet (default 2, "
                        "or --healthy where that is fewer)")
    a.add_argument("--grids", help="comma-separated fault grids (default all: "
                                   "emaphm.assessment.grid_names())")
    a.add_argument("--severities", action="append", metavar="GRID=S1,S2",
                   help="the severities of a grid, replacing its default (repeatable)")
    a.add_argument("--datasheet-faults", action="store_true",
                   help="also diagnose every faulty trace on the data sheet (slow)")
    a.add_argument("--drive-signals", action="store_true",
                   help="the traces carry the drive's voltage commands: assess the "
                        "recorded-voltage path, the drive's controller not modelled")
    a.add_argument("--seed", type=_seed, default=0, help="master seed (default 0)")
    a.add_argument("--workers", type=_workers,
                   help="local worker processes (default: all cores; 0: in this process)")
    a.add_argument("--scheduler", help="Dask scheduler address (needs emaphm[dask]; a "
                                       "scheduler you trust)")
    a.add_argument("--quiet", action="store_true", help="no progress, no conclusions")
    a.set_defaults(func=cmd_assess)
