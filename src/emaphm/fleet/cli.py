"""``emaphm fleet``: the fleet health site (registered by :func:`emaphm.cli.build_parser`).

    emaphm fleet report --db fleet.sqlite --out site/ [--actuator ID ...] [--threshold MODE=V]
                        [--risk 0.01 --max-interval H --min-interval H --default-interval H]
                        [--workers N | --scheduler tcp://HOST:PORT]
    emaphm fleet demo --db demo.sqlite [--actuators 30] [--seed S] [--synthetic]
    emaphm fleet schedule --db fleet.sqlite --out plan.csv|plan.ics [--risk 0.01]
                          [--start 2026-12-01 --per-day 8] [--site URL]

The store is ``--db PATH``, else ``$EMAPHM_HISTORY``, else ``emaphm-history.sqlite``, as
for ``emaphm history``. This module imports nothing heavy until a command runs.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path
from typing import Any

from .._cli_common import UsageError, arg_type, budget_option, writable_folder
from .._cli_common import seed as _seed

__all__ = ["register"]


def _usage(msg: str) -> Exception:
    return UsageError(msg)


def _site_folder(text: str) -> Path:
    """The ``--out`` folder of the site: a folder this process can write in, or one it can
    create (its nearest existing parent writable), that is new, an earlier site or holds none
    of the site's names (:func:`~emaphm.fleet.site.check_site_folder`); else a
    :class:`UsageError` before any work is done or announced."""
    out = Path(text)
    if not text.strip():
        raise _usage("--out is empty; give a folder for the site, e.g. --out fleet-site/")
    if out.exists() and not out.is_dir():
        raise _usage(f"--out {out} is a file, not a folder; give a folder for the site")
    existing = out
    while not existing.exists():
        if existing.parent == existing:
            break
        existing = existing.parent
    if existing.exists() and not existing.is_dir():
        raise _usage(f"--out {out}: {existing} is a file, not a folder; give a folder for the site")
    writable_folder(existing, "--out")
    if out.is_dir():
        from .site import check_site_folder

        try:
            check_site_folder(out)
        except ValueError as exc:
            raise _usage(str(exc)) from None
    return out


def _planning_policy(args: argparse.Namespace, units: Any):
    """The :class:`~emaphm.prognosis.inspection.InspectionPolicy` of the planning options
    (``--risk``, default :data:`~emaphm.prognosis.inspection.DEFAULT_RISK`, and the
    intervals), checked against each time unit of ``units``: one helper for ``fleet
    report`` and ``fleet schedule``, so both plan alike."""
    from ..prognosis.cli import inspection_policy, option_words
    from ..prognosis.inspection import DEFAULT_RISK

    if args.risk is None:
        args.risk = DEFAULT_RISK
    policy = inspection_policy(args)
    for unit in sorted(set(units)):
        try:
            policy.intervals(unit)
        except ValueError as exc:
            raise _usage(option_words(str(exc))) from None
    return policy


def cmd_report(args: argparse.Namespace) -> int:
    from ..prognosis.cli import db_path, threshold_option, warn
    from ..prognosis.history import HealthHistory, skipped_note
    from .site import build_site

    thresholds = threshold_option(args.threshold)
    if not 0 < args.level < 1:
        raise _usage(f"--level must be in (0, 1), e.g. 0.9, got {args.level}")
    out = _site_folder(args.out)
    if args.workers is not None and args.scheduler is not None:
        raise _usage("give either --workers (local processes) or --scheduler (Dask cluster), "
                     "not both")
    executor = None
    if args.scheduler is not None:       # a wrong address fails before any work is announced
        from ..campaign.executors import DaskExecutor

        executor = DaskExecutor(args.scheduler, warm=False)
        executor.check()
    db = db_path(args)
    with HealthHistory(db, readonly=True) as h:          # bad input fails before any drawing
        for actuator in args.actuator or ():
            h.actuator(actuator)
        n = len(set(args.actuator or ())) or len(h.actuators())
        if not n:
            raise _usage(f"the health history {db} has no actuators; register them first "
                         f"(emaphm history register ID --db {db})")
        policy = _planning_policy(args, (a.time_unit for a in h.actuators()))
        if not args.quiet:
            print(f"building the fleet site of {n} actuator{'s' if n != 1 else ''} from {db} "
                  f"into {out}/", file=sys.stderr)
        from ..progress import StatusLine

        line = StatusLine(enabled=not args.quiet)
        try:
            site = build_site(h, out, actuators=args.actuator, thresholds=thresholds,
                              seed=args.seed, level=args.level, workers=args.workers,
                              title=args.title, redraw=args.redraw, executor=executor,
                              policy=policy, progress=lambda text: line.show(text))
        finally:
            line.close()
    skipped = site.skipped
    if skipped:                                  # one line for the whole fleet
        first = skipped_note(*skipped[0])
        others = sum(len(s) for _, s in skipped[1:])
        warn("fleet report", first + (f"; and {others} more of {len(skipped) - 1} other "
                                      "actuator(s) (emaphm history show ID names them)"
                                      if others else ""))
    if args.json:
        print(json.dumps({"index": str(site.index), "actuators": len(site.rows),
                          "risk": policy.risk, "elapsed_s": site.elapsed_s,
                          "workers": site.workers,
                          "drawn": site.drawn, "written": site.written,
                          "pages": {k: str(v) for k, v in site.pages.items()}}))
    else:
        past = sum(r["rul_state"] == "past threshold" for r in site.rows)
        predicted = sum(r["rul_state"] == "predicted" for r in site.rows)
        kept = len(site.rows) - site.drawn
        print(f"{'wrote' if site.written else 'up to date, nothing written:'} {site.index} "
              f"({len(site.rows)} actuators: {past} past a threshold, "
              f"{predicted} with a predicted failure; inspections planned at risk "
              f"{policy.risk:g}) in {site.elapsed_s:.1f} s"
              + (f"; the pages of {kept} were up to date" if kept else ""))
        for r in site.rows[:3]:
            if r["rul_state"] in ("past threshold", "predicted"):
                rul = "past threshold" if r["rul_state"] == "past threshold" else \
                    f"RUL median {r['rul_median']:.0f} {r['time_unit']}"
                print(f"  {r['id']}: {r['worst']}, {rul}")
    return 0


def cmd_demo(args: argparse.Namespace) -> int:
    from .demo import MAX_ACTUATORS, MAX_SYNTHETIC, demo_fleet, record_demo_fleet

    most = MAX_SYNTHETIC if args.synthetic else MAX_ACTUATORS
    if not 1 <= args.actuators <= most:
        raise _usage(f"--actuators must be 1 to {most}, got {args.actuators}"
                     + ("" if args.synthetic else f" ({MAX_SYNTHETIC} with --synthetic)"))
    budget = budget_option(args.budget)
    from ..prognosis.cli import db_path

    db = db_path(args)
    if os.path.lexists(db):
        raise _usage(f"--db {db} exists; the fleet demo writes a new health history: give a new "
                     "path or delete that file")
    if not db.parent.exists():
        raise _usage(f"--db {db}: folder {db.parent} does not exist; create it first")
    writable_folder(db.parent, "--db")
    units = demo_fleet(args.actuators, seed=args.seed, synthetic=args.synthetic)
    n_ins = sum(len(u.times) for u in units)
    quiet = args.quiet or args.json
    if not quiet:
        how = ("synthetic inspections: true k plus identification-sized noise, no trace "
               "diagnosed (a demo of the page, not of the diagnosis)" if args.synthetic else
               "each a reference-plant trace diagnosed as emaphm history add does")
        print(f"recording {len(units)} demo actuators, {n_ins} inspections, into {db}: {how}",
              file=sys.stderr)
    t0 = time.perf_counter()

    def progress(summary: dict) -> None:
        if not quiet:
            print(f"  {summary['id']}  {summary['fault']:48s} {len(summary['times']):2d} "
                  f"inspections  {summary['cpu_s']:6.1f} s CPU", file=sys.stderr)

    results = record_demo_fleet(db, units, synthetic=args.synthetic, budget=budget,
                                workers=args.workers, progress=progress)
    elapsed = time.perf_counter() - t0
    if args.json:
        print(json.dumps({"db": str(db), "elapsed_s": elapsed, "actuators": results}))
    else:
        print(f"recorded {len(results)} actuators ({n_ins} inspections) in {db} in "
              f"{elapsed:.1f} s; see them with: emaphm fleet report --db {db} --out fleet-site/")
    return 0


def _date(text: str):
    import datetime as dt

    try:
        return dt.date.fromisoformat(text.strip())
    except ValueError:
        raise _usage(f"--start {text!r} is not a date; write it as YYYY-MM-DD, e.g. "
                     "--start 2026-12-01") from None


def _calendar(args: argparse.Namespace):
    """The :class:`~emaphm.fleet.schedule.Calendar` of ``--start`` and ``--per-day`` (both or
    neither), or None."""
    if (args.start is None) != (args.per_day is None):
        given, other = ("--start", "--per-day") if args.start is not None else ("--per-day", "--start")
        raise _usage(f"{given} maps operating time onto dates together with {other}: give both, "
                     "e.g. --start 2026-12-01 --per-day 8")
    if args.start is None:
        return None
    from .schedule import Calendar

    return Calendar(start=_date(args.start), per_day=args.per_day)


def cmd_schedule(args: argparse.Namespace) -> int:
    from .._cli_common import out_path
    from ..prognosis.cli import db_path, threshold_option, warn
    from ..prognosis.history import HealthHistory, skipped_note

    thresholds = threshold_option(args.threshold)
    out = out_path(args.out, (".csv", ".ics"), "--out")
    calendar = _calendar(args)
    if out.suffix.lower() == ".ics" and calendar is None:
        raise _usage(f"--out {out}: calendar events need dates, and a history's time is "
                     "operating time (flight hours or cycles): give --start DATE (the date of "
                     "the plan) and --per-day H (operating hours or cycles a day), or write "
                     "a .csv")
    from .schedule import assess_fleet, check_one_unit, rows_from, write_csv, write_ics

    db = db_path(args)
    with HealthHistory(db, readonly=True) as h:
        for actuator in args.actuator or ():
            h.actuator(actuator)
        every = h.actuators()
        policy = _planning_policy(args, (a.time_unit for a in every))
        chosen = set(args.actuator or ())
        if calendar is not None:                     # before the fleet is assessed
            try:
                check_one_unit(a.time_unit for a in every if not chosen or a.id in chosen)
            except ValueError as exc:
                raise _usage(str(exc)) from None
        statuses = assess_fleet(h, policy=policy, thresholds=thresholds, seed=args.seed,
                                actuators=args.actuator)
    try:
        rows = rows_from(statuses, base=args.site, calendar=calendar)
    except ValueError as exc:                        # a date past 9999-12-31
        raise _usage(str(exc)) from None
    skipped = [s for s in statuses if s.data.skipped]
    if skipped:
        warn("fleet schedule", skipped_note(skipped[0].actuator, skipped[0].data.skipped)
             + (f"; and {len(skipped) - 1} other actuator(s)" if len(skipped) > 1 else ""))
    try:
        if out.suffix.lower() == ".ics":
            write_ics(rows, out, source=str(db.resolve()))
        else:
            write_csv(rows, out)
    except ValueError as exc:                        # an event on 9999-12-31 ends past it
        raise _usage(str(exc)) from None
    if args.json:
        print(json.dumps({"out": str(out), "risk": policy.risk,
                          "rows": [r.to_dict() for r in rows]}))
        return 0
    now = sum(r.due_now for r in rows)
    print(f"wrote {out}: {len(rows)} actuator{'s' if len(rows) != 1 else ''}, {now} due now "
          f"(risk {policy.risk:g})")
    from .markup import fmt_deadline

    shown = 3
    for r in rows[:shown]:
        when = fmt_deadline(r.inspect_by, r.time_unit) + (f" ({r.date})" if r.date else "")
        print(f"  {r.actuator}: {'now, ' if r.due_now else ''}by {when}: {r.reason}")
    rest = rows[shown:]
    if rest:
        due = sum(r.due_now for r in rest)
        print(f"  and {len(rest)} more" + (f" ({due} of them due now)" if due else "")
              + f": see {out}")
    return 0


# ----------------------------------------------------------------------------- wiring
_workers = arg_type(int, lambda w: w >= 0, "workers must be a non-negative integer (0: in this "
                    "process)")


def register(subparsers: Any) -> None:
    """Add ``fleet report``, ``fleet demo`` and ``fleet schedule`` to the ``emaphm`` parser."""
    from ..prognosis.cli import planning_options

    fp = subparsers.add_parser("fleet", help="the fleet health site: every actuator at a glance")
    fs = fp.add_subparsers(dest="fleet_command", required=True)

    r = fs.add_parser(
        "report", help="write the fleet health site (static HTML) of a health history",
        description="Write a static site: an index of every actuator (verdict, the indicator "
                    "nearest its threshold, RUL median and interval, trend), units needing "
                    "attention first, sortable and filterable; and a page per actuator with "
                    "its figures, calibration and inspections. It opens from disk (no server, "
                    "no network). Its \"Inspect by\" column plans the next inspection of each "
                    "actuator with the options of emaphm fleet schedule (--risk and the "
                    "intervals, the same defaults): give both commands the same, and the "
                    "pages a schedule links to show the times it plans. --out is updated "
                    "where an earlier fleet report wrote it (only what changed is made "
                    "again; a change of these options makes every page again); a folder "
                    "holding an index.html, fleet.json, assets/ or actuators/ that no fleet "
                    "report wrote is refused.")
    r.add_argument("--db", help="health history database (default $EMAPHM_HISTORY or "
                                "emaphm-history.sqlite)")
    r.add_argument("--out", required=True,
                   help="folder of the site: new (created), the folder of an earlier fleet "
                        "report (updated), or one without index.html, fleet.json, assets/ and "
                        "actuators/ (its other files left alone); else refused")
    r.add_argument("--actuator", action="append", metavar="ID",
                   help="only this actuator (repeatable; default: all)")
    r.add_argument("--threshold", action="append", metavar="MODE=VALUE",
                   help="failure threshold of a fault mode (repeatable), as for emaphm prognose")
    r.add_argument("--seed", type=_seed, default=0,
                   help="seed of the RUL Monte Carlo draws (default 0)")
    r.add_argument("--level", type=float, default=0.9,
                   help="probability of the RUL interval (default 0.9)")
    planning_options(r, default_risk=True)        # the "Inspect by" column, as fleet schedule
    r.add_argument("--workers", type=_workers, default=None,
                   help="processes making the pages (default: every core; 0: this process)")
    r.add_argument("--scheduler", help="make the pages on a Dask cluster: its scheduler's "
                                       "address, tcp://HOST:PORT, HOST:PORT or tls://HOST:PORT "
                                       "(needs emaphm[dask] there and here; connect only to a "
                                       "scheduler you trust: Dask exchanges pickles)")
    r.add_argument("--title", default="Fleet health", help="title of the site")
    r.add_argument("--redraw", action="store_true",
                   help="make every page and figure again (default: keep those whose inputs "
                        "did not change since the last build into --out)")
    r.add_argument("--json", action="store_true")
    r.add_argument("--quiet", action="store_true")
    r.set_defaults(func=cmd_report)

    d = fs.add_parser(
        "demo", help="fill a new health history with a simulated fleet",
        description="Record N simulated actuators with different faults, growth rates and "
                    "ages into a new health history. By default every inspection is a "
                    "reference-plant trace diagnosed as emaphm history add does (about 4 "
                    "minutes of CPU for 30 actuators: 2 minutes on two free cores); --synthetic records the true k "
                    "plus identification-sized noise instead, in seconds: a demo of the page, "
                    "not of the diagnosis.")
    d.add_argument("--db", required=True, help="the new health history (must not exist)")
    d.add_argument("--actuators", type=int, default=30,
                   help="how many (default 30; at most 500, 20000 with --synthetic)")
    d.add_argument("--seed", type=_seed, default=0, help="seed of the whole fleet (default 0)")
    d.add_argument("--synthetic", action="store_true",
                   help="no traces, no identifications: true k plus noise (seconds)")
    d.add_argument("--budget", help="evaluations per identification (default: the paper's rules)")
    d.add_argument("--workers", type=_workers, default=None,
                   help="processes diagnosing (default: every core; 0: this process)")
    d.add_argument("--json", action="store_true")
    d.add_argument("--quiet", action="store_true")
    d.set_defaults(func=cmd_demo)
    _register_schedule(fs)


_per_day = arg_type(float, lambda x: math.isfinite(x) and 0 < x <= 1e6,
                    "operating time per day must be a number in (0, 1e6], e.g. 8 (hours a day)")


def _register_schedule(fs: Any) -> None:
    from ..prognosis.cli import planning_options

    s = fs.add_parser(
        "schedule", help="write the fleet's next inspections (CSV, or iCalendar with dates)",
        description="Plan the next inspection of every actuator at a stated risk (as emaphm "
                    "prognose --risk does) and write the schedule: one row (.csv) or all-day "
                    "calendar event (.ics) per actuator, with the driving indicator, the "
                    "predicted risk, the reason and a link to its page on the fleet site "
                    "(made by emaphm fleet report with the same --risk and intervals). "
                    "Order: those due now first; then, per time unit (flight hours, then "
                    "cycles: the two are not compared), the operating time left, soonest "
                    "first. Times are operating time; --start and --per-day map them onto "
                    "dates (a .ics needs them), for actuators timed in one unit: a history "
                    "with both hours and cycles is planned with dates one unit at a time "
                    "(--actuator). A calendar event keeps its UID from plan to plan "
                    "(actuator and history), so importing an updated plan moves it.")
    s.add_argument("--db", help="health history database (default $EMAPHM_HISTORY or "
                                "emaphm-history.sqlite)")
    s.add_argument("--out", required=True, help="the schedule: plan.csv or plan.ics")
    planning_options(s, default_risk=True)
    s.add_argument("--start", metavar="DATE",
                   help="date of the plan (YYYY-MM-DD): each actuator is taken to be at its last "
                        "inspection's operating time then")
    s.add_argument("--per-day", type=_per_day, metavar="H",
                   help="operating time an actuator accrues per day, in its history's unit "
                        "(e.g. 8 flight hours); one number for one unit: the actuators planned "
                        "with dates must all be timed in h, or all in cycles (else refused)")
    s.add_argument("--site", default="fleet-site/",
                   help="where the fleet site lives (folder or URL; default fleet-site/, as "
                        "emaphm fleet report --out fleet-site/ writes it): the rows link to "
                        "SITE/actuators/<page>.html (a URL's path is percent-encoded, its "
                        "?query kept at the end)")
    s.add_argument("--actuator", action="append", metavar="ID",
                   help="only this actuator (repeatable; default: all)")
    s.add_argument("--threshold", action="append", metavar="MODE=VALUE",
                   help="failure threshold of a fault mode (repeatable), as for emaphm prognose")
    s.add_argument("--seed", type=_seed, default=0,
                   help="seed of the Monte Carlo draws (default 0)")
    s.add_argument("--json", action="store_true")
    s.set_defaults(func=cmd_schedule)
