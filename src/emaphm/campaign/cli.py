"""``emaphm campaign`` and ``emaphm report``: a thin layer over :mod:`emaphm.campaign`.

    emaphm campaign [--spec FILE.toml] [--scenarios ...] [--algorithms de,pso,gwo]
                    [--runs 10] [--seed S] [--store results.sqlite] [--workers N]
                    [--scheduler tcp://HOST:PORT]
    emaphm campaign --store results.sqlite             resume the stored campaign
    emaphm campaign --store results.sqlite --replay friction-low/pso/3
    emaphm report results.sqlite --out report/

Exit status: 0 all runs stored; 1 some runs failed (run again to retry); 2 bad input
(nothing written); 130 interrupted by Ctrl-C (finished runs kept; run again to resume).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path
from typing import Any

from .._cli_common import UsageError, arg_type, budget_option, writable_folder

__all__ = ["register", "cmd_campaign", "cmd_report"]

_SPEC_OPTIONS = ("spec", "scenarios", "algorithms", "runs", "seed", "noise", "budget", "polish",
                 "fault_model")


_non_negative_int = arg_type(int, lambda n: n >= 0, "expected an integer >= 0")


def _runs(text: str) -> int:
    from .spec import MAX_RUNS                   # imported when parsed: --help stays fast

    return arg_type(int, lambda n: 1 <= n <= MAX_RUNS, f"expected an integer from 1 to "
                    f"{MAX_RUNS} (runs per scenario and algorithm)")(text)


def _noise(text: str) -> float:
    from .spec import MAX_NOISE

    return arg_type(float, lambda x: 0.0 <= x <= MAX_NOISE,
                    f"expected a current noise from 0 to {MAX_NOISE:g} A rms (a servo drive's "
                    "current sensor has tens of milliamperes; default 0.02)")(text)


_workers = arg_type(int, lambda n: 0 <= n <= 4096, "expected an integer from 0 to 4096 "
                    "(local worker processes; 0 runs in this process)")
_timeout = arg_type(float, lambda x: 0.0 < x <= 3600.0, "expected seconds, more than 0 and at "
                    "most 3600")


def _store_option(text: str) -> str:
    """``--store`` (or ``report STORE``) as given, unless it names no file: an empty name
    or ``:memory:`` would keep the runs only until the command ends."""
    from .._sqlite import store_name_problem

    problem = store_name_problem(text)
    if problem is not None:
        raise UsageError(f"--store {text!r} {problem}; give the path of a store file, e.g. "
                         "--store results.sqlite")
    return text


def _existing_store(text: str, what: str) -> Path:
    """An existing store named on the command line: a regular file (a UsageError naming
    what it is instead: missing, a folder, a FIFO, a device, a link loop)."""
    from .._files import regular_file

    return regular_file(_store_option(text), what, give="the path of a campaign store file",
                        error=UsageError, missing=UsageError)


def build_spec(args: argparse.Namespace) -> Any:
    """The spec of the command line: a TOML file and/or options; None to resume the
    store's own spec (store exists, no spec option given)."""
    from .spec import CampaignSpec, parse_algorithms, parse_scenarios

    given = [name for name in _SPEC_OPTIONS if getattr(args, name, None) is not None]
    if not given and Path(args.store).exists():
        return None
    spec = CampaignSpec.from_toml(args.spec) if args.spec else CampaignSpec()
    changes: dict[str, Any] = {}
    if args.scenarios is not None:
        changes["scenarios"] = parse_scenarios(args.scenarios)
    if args.algorithms is not None:
        changes["algorithms"] = parse_algorithms(args.algorithms)
    if args.runs is not None:
        changes["runs"] = args.runs
    if args.seed is not None:
        changes["master_seed"] = args.seed
    if args.noise is not None:
        changes["noise"] = args.noise
    if args.budget is not None:
        changes["budget"] = budget_option(args.budget)
    if args.polish is not None:
        changes["polish"] = args.polish
    if args.fault_model is not None:
        changes["fault_model"] = args.fault_model
    return dataclasses.replace(spec, **changes) if changes else spec


def _holds_something(path: Path) -> bool:
    """Whether a run would check ``path`` against its spec rather than create the store
    there: a file that is not empty and not an SQLite database without tables (mktemp's
    empty file and an empty database are filled by a run)."""
    import sqlite3

    if not path.is_file() or path.stat().st_size == 0:
        return False
    try:
        con = sqlite3.connect(f"{path.resolve().as_uri()}?mode=ro", uri=True)
        try:
            return bool(con.execute("SELECT name FROM sqlite_master WHERE type = 'table'")
                        .fetchall())
        finally:
            con.close()
    except sqlite3.DatabaseError:         # not SQLite: refused by open, as a run refuses it
        return True


def cmd_campaign(args: argparse.Namespace) -> int:
    from ..progress import compile_notice
    from .executors import DaskExecutor, make_executor, warm_up
    from .runner import CampaignInterrupted, ProgressLine, replay, run_campaign
    from .store import CampaignStore

    _store_option(args.store)
    if args.replay is not None:
        return _replay(args, replay)
    if args.workers is not None and args.scheduler is not None:
        raise UsageError("give either --workers (local pool) or --scheduler (Dask cluster), not both")
    spec = build_spec(args)
    if args.dry_run:
        if spec is None or _holds_something(Path(args.store)):  # the store's, or refused
            with CampaignStore.open(args.store, spec, readonly=True) as st:  # as a run is
                spec = st.spec
        for r in spec.runs_list():
            print(f"{r.key}\tseed={r.seed}\tnoise_seed={r.noise_seed}\tspawn_key={list(r.spawn_key)}")
        print(f"{spec.n_runs} runs; spec hash {spec.hash[:12]}", file=sys.stderr)
        return 0
    store_path = Path(args.store)
    executor = make_executor(args.workers, args.scheduler, timeout=args.connect_timeout)
    if hasattr(executor, "check"):            # a wrong scheduler address fails before the store
        executor.check()
    # open (and so validate, or create) the store before starting any worker
    with CampaignStore.open(store_path, spec) as st:
        spec = st.spec
        counts = st.counts()
    quiet = args.quiet
    if not quiet:
        print(f"campaign {spec.name!r}: {spec.n_runs} runs ({len(spec.scenarios)} scenarios x "
              f"{len(spec.algorithms)} algorithms x {spec.runs}), {counts['ok']} already in {store_path}; "
              f"{executor.describe()}", file=sys.stderr)
    progress = None if quiet else ProgressLine(sys.stderr)
    if counts["ok"] < spec.n_runs and not isinstance(executor, DaskExecutor):
        # load (or compile, once, with a notice) the kernels here first: the local workers
        # then find them in Numba's disk cache instead of all compiling them at once
        with compile_notice(progress, enabled=not quiet):
            warm_up()
    try:
        summary = run_campaign(spec, store_path, executor, progress,
                               allow_version_mix=args.allow_version_mix)
    except CampaignInterrupted as exc:
        s = exc.summary
        print(f"emaphm campaign: interrupted; {s.total - s.missing} of {s.total} runs are stored in "
              f"{s.store}. Run the same command again to resume.", file=sys.stderr)
        return 130
    if not quiet or summary.missing:
        print(f"{summary.completed} runs done, {summary.failed} failed, {summary.skipped} already stored, "
              f"in {summary.elapsed_s:.1f} s; {summary.total - summary.missing}/{summary.total} runs in "
              f"{summary.store}", file=sys.stderr)
    if summary.missing:
        print(f"emaphm campaign: {summary.missing} runs are missing or failed; run the same command "
              "again to retry them (failure texts: emaphm report, runs.csv)", file=sys.stderr)
        return 1
    if not quiet:
        print(f"next: emaphm report {summary.store} --out report/", file=sys.stderr)
    return 0


def _replay(args: argparse.Namespace, replay: Any) -> int:
    if not Path(args.store).exists() and not Path(args.store).is_symlink():
        raise UsageError(f"--replay needs an existing --store; {args.store} does not exist")
    _existing_store(args.store, "--store")
    if any(getattr(args, name, None) is not None for name in _SPEC_OPTIONS):
        raise UsageError("--replay takes the spec from the store; leave out the spec options")
    stored, fresh = replay(args.store, args.replay)
    out: dict[str, Any] = {"run_key": args.replay, "replayed": _brief(fresh)}
    if stored is not None:
        out["stored"] = _brief(stored)
        out["identical"] = stored.outcome() == fresh.outcome()
    print(json.dumps(out, indent=1))
    if stored is not None and not out["identical"]:
        print("emaphm campaign: the replayed run differs from the stored one (another emaphm or "
              "numpy version, or another platform?)", file=sys.stderr)
        return 1
    return 0


def _brief(r: Any) -> dict[str, Any]:
    return {"status": r.status, "seed": r.seed, "noise_seed": r.noise_seed,
            "spawn_key": list(r.spawn_key), "k": None if r.k is None else list(r.k),
            "fitness": r.fitness, "error_pct": r.error_pct, "evaluations": r.evaluations,
            "iterations": r.iterations, "elapsed_s": r.elapsed_s, "error_text": r.error_text}


def cmd_report(args: argparse.Namespace) -> int:
    from .report import write_report

    _existing_store(args.store, "store")
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise UsageError(f"--out {out} exists and is not a folder")
    if not out.parent.exists():
        raise UsageError(f"--out {out}: folder {out.parent} does not exist; create it first")
    writable_folder(out if out.is_dir() else out.parent, "--out")
    paths = write_report(args.store, out, figures=not args.no_figures)
    for p in paths:
        print(p)
    return 0


def register(sub: Any) -> None:
    """Add ``campaign`` and ``report`` to the subcommands of ``emaphm``."""
    c = sub.add_parser(
        "campaign", help="run an algorithm comparison (resumable; local cores or a Dask cluster)",
        description="Run every run of a campaign spec not yet in the store, committing each as it "
                    "finishes. Run the same command again to resume after an interruption.")
    c.add_argument("--spec", help="campaign spec, TOML (see docs/campaigns.md); options below override it")
    c.add_argument("--scenarios", help="comma-separated scenario names or groups (paper, single-faults); "
                                       "default: paper (the 11 of the paper)")
    c.add_argument("--algorithms", help="comma-separated algorithms, default de,pso,gwo "
                                        "(also scipy-de, cmaes)")
    c.add_argument("--runs", type=_runs, help="runs per scenario and algorithm (default 10)")
    c.add_argument("--seed", type=_non_negative_int, help="master seed (default 0)")
    c.add_argument("--noise", type=_noise, help="current sensor noise, A rms (default 0.02)")
    c.add_argument("--budget", help="per run: evaluations (e.g. 5000) or seconds (e.g. 30s, not "
                                    "reproducible); default: each algorithm's stopping rule")
    c.add_argument("--polish", action=argparse.BooleanOptionalAction, default=None,
                   help="compass-search polish after the metaheuristic (default on)")
    c.add_argument("--fault-model", choices=("physical", "paper"), default=None,
                   help="mapping of k3..k5 for every scenario; default each scenario's own (the "
                        "paper's scenarios: paper; turn-short-*: physical)")
    c.add_argument("--store", default="results.sqlite", help="result store, SQLite (default results.sqlite)")
    c.add_argument("--workers", type=_workers,
                   help="local worker processes (default: all cores; 0: in this process)")
    c.add_argument("--scheduler", help="Dask scheduler address, tcp://HOST:PORT, HOST:PORT or "
                                       "tls://HOST:PORT (needs emaphm[dask]; connect only to a "
                                       "scheduler you trust: Dask exchanges pickles)")
    c.add_argument("--connect-timeout", type=_timeout, default=None,
                   help="seconds to wait for the Dask scheduler to answer (default 10)")
    c.add_argument("--replay", metavar="RUN_KEY", help="rerun one stored run alone, e.g. friction-low/pso/3, "
                                                       "and compare it with the stored result")
    c.add_argument("--dry-run", action="store_true", help="list the runs and their seeds; run nothing")
    c.add_argument("--allow-version-mix", action="store_true",
                   help="let this emaphm add runs to a store started by another version")
    c.add_argument("--quiet", action="store_true", help="no progress line")
    c.set_defaults(func=cmd_campaign)

    r = sub.add_parser("report", help="tables (Markdown, CSV) and figures of a campaign store",
                       description="Write the paper's Tables 3 and 4, per-magnitude tables, a side-by-side "
                                   "with the paper's totals, and Figures 7 and 8 and convergence curves, "
                                   "from a campaign store. Reads the store only.")
    r.add_argument("store", help="campaign store (SQLite)")
    r.add_argument("--out", required=True, help="output folder (created if missing)")
    r.add_argument("--no-figures", action="store_true", help="tables only")
    r.set_defaults(func=cmd_report)
