"""The fleet's inspection schedule: one row (CSV) or calendar event (iCalendar) per actuator.

:func:`schedule` plans the next inspection of every actuator of a health history at one
risk (:func:`~emaphm.fleet.status.assess` with an
:class:`~emaphm.prognosis.inspection.InspectionPolicy`) and returns the rows, soonest
first (:func:`~emaphm.fleet.status.inspect_key`). Each row names the driving indicator,
the predicted risk, the reason and the link to the actuator's page on the fleet site
(``BASE/actuators/STEM.html``, named as :func:`~emaphm.fleet.site.build_site` names it).

Times are in each history's unit (flight hours or cycles: operating time, not dates). A
row gets a date when a start date and the operating time per day are given
(:class:`Calendar`): the start is the date of the plan, on which each actuator's operating
time is taken to be that of its last inspection; it accrues ``per_day`` units a day from
then on, so an inspection due at ``at`` falls on ``start + (at - t_last) / per_day`` days
(a unit due now, or overdue, on the start date). Neither unit of a history is a calendar
unit, so without a :class:`Calendar` the rows have no date and the iCalendar file, whose
events need one, is refused. A :class:`Calendar` has one ``per_day`` in one unit: the
actuators of a plan with dates must all be timed in that unit (a fleet timed in flight
hours and in cycles is refused; plan each unit apart). A date past the last one a
calendar holds (9999-12-31) is refused, naming the actuator, not written.

The rows come in the order of :func:`~emaphm.fleet.status.inspect_key`: those due now
first; then, by time unit (flight hours, then cycles: the units are not comparable),
the operating time left to the next inspection, soonest first (the order of the dates);
ties by id.

:func:`write_csv` (every number in full, as a plain decimal) and :func:`write_ics`
(RFC 5545: all-day events, CRLF lines folded at 75 octets, text escaped; an event's UID
names its actuator and history, not its date, so that a calendar that imports an
updated plan moves the event, ``SEQUENCE`` and ``DTSTAMP`` telling it which is newer)
write them atomically.
"""

from __future__ import annotations

import csv
import datetime as _dt
import hashlib
import io
import math
from urllib.parse import quote, urlsplit, urlunsplit
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

from .._files import atomic_write_text
from ..prognosis.inspection import InspectionPolicy
from ..prognosis.thresholds import DEFAULT_FAILURE_THRESHOLDS, FailureThresholds
from ..seeds import check_seed
from .markup import fmt_deadline, page_stem, plain_number, unit_rank
from .status import FLEET_POLICY, ActuatorStatus, assess, inspect_key

__all__ = ["Calendar", "DateRangeError", "ScheduleRow", "schedule", "assess_fleet", "rows_from",
           "page_links", "check_one_unit", "units_message", "write_csv", "write_ics",
           "CSV_COLUMNS"]

#: The columns of the CSV schedule, in order.
CSV_COLUMNS = ("actuator", "description", "inspect_by", "time_unit", "date", "due_now",
               "rule", "indicator", "risk", "target_risk", "reason", "last_inspection",
               "inspections", "link")


@dataclass(frozen=True)
class Calendar:
    """How operating time maps onto dates: the ``start`` date of the plan and the
    operating time an actuator accrues per day (``per_day``, in its history's unit)."""

    start: _dt.date
    per_day: float

    def __post_init__(self) -> None:
        if not isinstance(self.start, _dt.date):
            raise ValueError(f"start must be a date, e.g. 2026-12-01, got {self.start!r}")
        if isinstance(self.per_day, bool) or not isinstance(self.per_day, (int, float)) \
                or not math.isfinite(self.per_day) or not 0 < self.per_day <= 1e6:
            raise ValueError(f"per_day must be a number in (0, 1e6] (operating hours or cycles "
                             f"a day, e.g. 8), got {self.per_day!r}")

    def date_of(self, at: float, t_last: float | None) -> _dt.date:
        """The date an inspection due at ``at`` falls on (the start when due now); a
        :class:`DateRangeError` when that is past the last date there is (9999-12-31)."""
        if t_last is None or at <= t_last:
            return self.start
        ratio = (at - t_last) / self.per_day
        if not ratio < _dt.date.max.toordinal():     # more days than a calendar has, or inf:
            raise DateRangeError(None, self.start)   # no count worth printing
        days = math.floor(ratio)
        try:
            return self.start + _dt.timedelta(days=days)
        except OverflowError:
            raise DateRangeError(days, self.start) from None


class DateRangeError(ValueError):
    """A date past the last one a calendar holds (9999-12-31): ``days`` after ``start``."""

    def __init__(self, days: int | None, start: _dt.date) -> None:
        self.days, self.start = days, start
        count = f"{days:,}" if days is not None else \
            f"more than {(_dt.date.max - start).days:,}"
        super().__init__(f"{count} days after {start.isoformat()}, past "
                         f"{_dt.date.max.isoformat()}, the last date a calendar holds")


@dataclass(frozen=True)
class ScheduleRow:
    """One actuator's next inspection as the schedule writes it (results as data)."""

    actuator: str
    description: str
    inspect_by: float
    time_unit: str
    date: _dt.date | None
    due_now: bool
    rule: str
    indicator: str | None
    risk: float | None
    target_risk: float
    reason: str
    last_inspection: float | None
    inspections: int
    link: str

    def to_dict(self) -> dict[str, Any]:
        d = dict(self.__dict__)
        d["date"] = None if self.date is None else self.date.isoformat()
        return d

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "ScheduleRow":
        """The row :meth:`to_dict` wrote (the date from its ISO form)."""
        d = dict(data)
        d["date"] = None if d.get("date") is None else _dt.date.fromisoformat(d["date"])
        return cls(**d)


def page_links(ids: Sequence[str], base: str) -> dict[str, str]:
    """The link of each actuator's page under the site ``base``, named as
    :func:`~emaphm.fleet.site.build_site` names the pages (a 64-digit hash for every id
    when two of the 10-digit names collide). A ``base`` that is a URL (``scheme://``)
    keeps its query and fragment at the end, after the page, and its path is
    percent-encoded (a space as ``%20``; an escape already there is kept); a folder is
    joined as it is."""
    stems = {i: page_stem(i) for i in ids}
    if len(set(stems.values())) != len(stems):
        stems = {i: page_stem(i, digits=64) for i in ids}
    if "://" in base:
        u = urlsplit(base)
        path = quote(u.path, safe="/%:@!$&'()*+,;=-._~")
        path = path if path.endswith("/") else path + "/"
        return {i: urlunsplit((u.scheme, u.netloc, f"{path}actuators/{s}.html", u.query,
                               u.fragment)) for i, s in stems.items()}
    prefix = base if not base or base.endswith("/") else base + "/"
    return {i: f"{prefix}actuators/{s}.html" for i, s in stems.items()}


def check_one_unit(time_units: Iterable[str]) -> None:
    """A ValueError when the actuators timed in ``time_units`` (one per actuator) are timed
    in more than one unit: a :class:`Calendar`'s operating time per day is in one (module
    docstring)."""
    units: dict[str, int] = {}
    for u in time_units:
        units[u] = units.get(u, 0) + 1
    if len(units) > 1:
        raise ValueError(units_message(units))


def units_message(units: dict[str, int]) -> str:
    """Why a plan with dates is refused for actuators timed in ``units`` (unit -> how many)."""
    order = sorted(units, key=unit_rank)
    said = " and ".join(f"{units[u]} in {u}" for u in order)
    return (f"dates map one unit of operating time onto days, and these actuators are timed "
            f"in {len(units)} units ({said}): plan each unit apart, naming its actuators with "
            "--actuator ID, or leave out --start and --per-day (a .csv without dates)")


def rows_from(statuses: Sequence[ActuatorStatus], *, base: str = "fleet-site/",
              calendar: Calendar | None = None) -> list[ScheduleRow]:
    """The schedule rows of assessed actuators (each with its ``plan``), soonest first
    (:func:`~emaphm.fleet.status.inspect_key`). With a ``calendar`` they must share one
    time unit, and every date must be on a calendar (else a ValueError naming the
    actuator: nothing is written)."""
    links = page_links([s.id for s in statuses], base)
    if calendar is not None:
        check_one_unit(s.actuator.time_unit for s in statuses)
    rows = []
    late: list[tuple[ActuatorStatus, DateRangeError]] = []
    for s in sorted(statuses, key=inspect_key):
        p = s.plan
        if p is None:
            raise ValueError(f"{s.id} was assessed without an inspection policy")
        day = None
        if calendar is not None:
            try:
                day = calendar.date_of(p.at, p.t_last)
            except DateRangeError as exc:
                late.append((s, exc))
                continue
        rows.append(ScheduleRow(
            actuator=s.id, description=s.actuator.description, inspect_by=p.at,
            time_unit=p.time_unit, date=day,
            due_now=p.act_now, rule=p.rule, indicator=p.indicator, risk=p.risk,
            target_risk=p.target, reason=p.reason, last_inspection=p.t_last,
            inspections=s.n_inspections, link=links[s.id]))
    if late:
        s, exc = late[0]
        raise ValueError(
            f"the next inspection of {s.id}, "
            f"{fmt_deadline(s.plan.at - s.plan.t_last, s.plan.time_unit)} after its last, "
            f"would fall {exc}"
            + (f" (as would that of {len(late) - 1} other actuator"
               f"{'s' if len(late) > 2 else ''})" if len(late) > 1 else "")
            + f": give more operating time per day than {calendar.per_day:g} (--per-day) "
              "or an earlier start date (--start)")
    return rows


def assess_fleet(history: Any, *, policy: InspectionPolicy = FLEET_POLICY,
                 thresholds: FailureThresholds = DEFAULT_FAILURE_THRESHOLDS, seed: int = 0,
                 actuators: Sequence[str] | None = None) -> list[ActuatorStatus]:
    """Every actuator (or ``actuators``) of ``history`` (a path or an open
    :class:`~emaphm.prognosis.HealthHistory`, read only) assessed with its next inspection."""
    from ..prognosis.history import HealthHistory

    seed = check_seed(seed)
    own = not isinstance(history, HealthHistory)
    h = HealthHistory(history, readonly=True) if own else history
    try:
        ids = list(dict.fromkeys(actuators)) if actuators else [a.id for a in h.actuators()]
        if not ids:
            raise ValueError(f"the health history {h.path} has no actuators; register them "
                             f"first (emaphm history register ID --db {h.path})")
        datas = [h.data(i) for i in ids]
    finally:
        if own:
            h.close()
    return [assess(d, thresholds=thresholds, seed=seed, policy=policy) for d in datas]


def schedule(history: Any, *, policy: InspectionPolicy = FLEET_POLICY,
             thresholds: FailureThresholds = DEFAULT_FAILURE_THRESHOLDS, seed: int = 0,
             actuators: Sequence[str] | None = None, base: str = "fleet-site/",
             calendar: Calendar | None = None) -> list[ScheduleRow]:
    """The next inspection of every actuator (or of ``actuators``) of ``history``
    (:func:`assess_fleet`), soonest first."""
    statuses = assess_fleet(history, policy=policy, thresholds=thresholds, seed=seed,
                            actuators=actuators)
    return rows_from(statuses, base=base, calendar=calendar)


# ----------------------------------------------------------------------------- CSV
def _cell(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return plain_number(value)            # every digit: 3456788.8, not 3.45679e+06
    if isinstance(value, _dt.date):
        return value.isoformat()
    text = str(value)
    # a spreadsheet runs a cell that starts with = + - @ as a formula: not from a stored id
    return "'" + text if text[:1] in ("=", "+", "-", "@", "\t", "\r") else text


def write_csv(rows: Sequence[ScheduleRow], path: str | Path) -> Path:
    """The schedule as CSV (:data:`CSV_COLUMNS`, one row per actuator), written atomically."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(CSV_COLUMNS)
    for r in rows:
        d = r.to_dict()
        d["date"] = r.date
        w.writerow([_cell(d[c]) for c in CSV_COLUMNS])
    path = Path(path)
    atomic_write_text(path, buf.getvalue())
    return path


# ----------------------------------------------------------------------------- iCalendar
def _ics_text(text: str) -> str:
    """RFC 5545 TEXT: backslash, semicolon, comma escaped; line breaks as \\n."""
    text = text.replace("\\", "\\\\").replace(";", "\\;").replace(",", "\\,")
    return text.replace("\r\n", "\\n").replace("\n", "\\n").replace("\r", "\\n")


def _fold(line: str) -> str:
    """One content line folded at 75 octets (CRLF + a space), never inside a character."""
    out, cur, size = [], [], 0
    for ch in line:
        n = len(ch.encode("utf-8"))
        if size + n > (75 if not out else 74):
            out.append("".join(cur))
            cur, size = [], 0
        cur.append(ch)
        size += n
    out.append("".join(cur))
    return "\r\n ".join(out) + "\r\n"


def _event(r: ScheduleRow, stamp: str, sequence: int, source: str) -> list[str]:
    what = (f"ACT NOW: {r.actuator}" if r.due_now and r.rule == "act now"
            else f"Inspect {r.actuator}")
    if r.indicator:
        what += f" ({r.indicator}" + (f", risk {r.risk:.2g})" if r.risk is not None else ")")
    unit = r.time_unit
    words = [f"{r.actuator}" + (f" ({r.description})" if r.description else "")
             + f": inspect by {fmt_deadline(r.inspect_by, unit)}", r.reason,
             f"planned at risk {r.target_risk:g}"
             + (f", predicted {r.risk:.2g}" if r.risk is not None else ""),
             f"last inspection {plain_number(r.last_inspection)} {unit}, {r.inspections} in all"
             if r.last_inspection is not None else "never inspected",
             f"page: {r.link}"]
    day = r.date
    lines = ["BEGIN:VEVENT",
             f"UID:{page_stem(r.actuator, digits=64)}{source}@emaphm",
             f"DTSTAMP:{stamp}",
             f"LAST-MODIFIED:{stamp}",
             f"SEQUENCE:{sequence}",
             f"DTSTART;VALUE=DATE:{day:%Y%m%d}",
             f"DTEND;VALUE=DATE:{day + _dt.timedelta(days=1):%Y%m%d}",
             f"SUMMARY:{_ics_text(what)}",
             f"DESCRIPTION:{_ics_text(chr(10).join(words))}",
             "TRANSP:TRANSPARENT"]
    if "://" in r.link:
        lines.append(f"URL:{r.link}")
    if r.due_now:
        lines.append("PRIORITY:1")
    return lines + ["END:VEVENT"]


#: ``SEQUENCE`` of an event counts the seconds from this moment to the plan's ``now``: a
#: plan made later carries a higher one (32 bits last until 2088), without a counter kept
#: between runs.
_SEQUENCE_EPOCH = _dt.datetime(2020, 1, 1, tzinfo=_dt.timezone.utc)


def write_ics(rows: Sequence[ScheduleRow], path: str | Path, *, name: str = "Fleet inspections",
              now: _dt.datetime | None = None, source: str | None = None) -> Path:
    """The schedule as an iCalendar file: an all-day event per actuator on its date
    (every row needs one: a :class:`Calendar`), written atomically.

    Each event's UID is the actuator's (its page stem with the 64-digit hash) and, given
    a ``source`` (the history the plan is made from, e.g. its resolved path), 16 hex
    digits of its SHA-256: the same actuator of the same history keeps its UID from plan
    to plan, so a calendar that imports the plan again moves the event to its new date
    instead of adding one; ``SEQUENCE`` (seconds since 2020 at ``now``) and ``DTSTAMP``
    tell it the newer."""
    missing = [r.actuator for r in rows if r.date is None]
    if missing:
        raise ValueError(f"calendar events need dates and {missing[0]} has none: give a start "
                         "date and the operating time per day (--start DATE --per-day H)")
    last = [r.actuator for r in rows if r.date >= _dt.date.max]
    if last:
        raise ValueError(f"the next inspection of {last[0]} falls on {_dt.date.max.isoformat()}, "
                         "the last date there is, and its all-day event would end the day after: "
                         "give more operating time per day (--per-day) or an earlier start date "
                         "(--start)")
    now = now or _dt.datetime.now(_dt.timezone.utc)
    if now.tzinfo is None:
        now = now.replace(tzinfo=_dt.timezone.utc)
    now = now.astimezone(_dt.timezone.utc)
    stamp = now.strftime("%Y%m%dT%H%M%SZ")
    sequence = min(max(0, int((now - _SEQUENCE_EPOCH).total_seconds())), 2**31 - 1)
    tag = "" if source is None else "-" + hashlib.sha256(
        str(source).encode("utf-8", "surrogatepass")).hexdigest()[:16]
    lines = ["BEGIN:VCALENDAR", "VERSION:2.0", "PRODID:-//emaphm//fleet schedule//EN",
             "CALSCALE:GREGORIAN", "METHOD:PUBLISH", f"X-WR-CALNAME:{_ics_text(name)}"]
    for r in rows:
        lines += _event(r, stamp, sequence, tag)
    lines.append("END:VCALENDAR")
    path = Path(path)
    atomic_write_text(path, "".join(_fold(line) for line in lines))
    return path
