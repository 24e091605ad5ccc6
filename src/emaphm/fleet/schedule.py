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
events need one, is refused.

:func:`write_csv` and :func:`write_ics` (RFC 5545: all-day events, CRLF lines folded at 75
octets, text escaped) write them atomically.
"""

from __future__ import annotations

import csv
import datetime as _dt
import io
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

from .._files import atomic_write_text
from ..prognosis.inspection import InspectionPolicy
from ..prognosis.thresholds import DEFAULT_FAILURE_THRESHOLDS, FailureThresholds
from ..seeds import check_seed
from .markup import page_stem
from .status import FLEET_POLICY, ActuatorStatus, assess, inspect_key

__all__ = ["Calendar", "ScheduleRow", "schedule", "assess_fleet", "rows_from", "page_links", "write_csv",
           "write_ics", "CSV_COLUMNS"]

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
        """The date an inspection due at ``at`` falls on (the start when due now)."""
        if t_last is None or at <= t_last:
            return self.start
        return self.start + _dt.timedelta(days=math.floor((at - t_last) / self.per_day))


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


def page_links(ids: Sequence[str], base: str) -> dict[str, str]:
    """The link of each actuator's page under the site ``base``, named as
    :func:`~emaphm.fleet.site.build_site` names the pages (a 64-digit hash for every id
    when two of the 10-digit names collide)."""
    stems = {i: page_stem(i) for i in ids}
    if len(set(stems.values())) != len(stems):
        stems = {i: page_stem(i, digits=64) for i in ids}
    prefix = base if not base or base.endswith("/") else base + "/"
    return {i: f"{prefix}actuators/{s}.html" for i, s in stems.items()}


def rows_from(statuses: Sequence[ActuatorStatus], *, base: str = "fleet-site/",
              calendar: Calendar | None = None) -> list[ScheduleRow]:
    """The schedule rows of assessed actuators (each with its ``plan``), soonest first."""
    links = page_links([s.id for s in statuses], base)
    rows = []
    for s in sorted(statuses, key=inspect_key):
        p = s.plan
        if p is None:
            raise ValueError(f"{s.id} was assessed without an inspection policy")
        rows.append(ScheduleRow(
            actuator=s.id, description=s.actuator.description, inspect_by=p.at,
            time_unit=p.time_unit, date=None if calendar is None else calendar.date_of(p.at, p.t_last),
            due_now=p.act_now, rule=p.rule, indicator=p.indicator, risk=p.risk,
            target_risk=p.target, reason=p.reason, last_inspection=p.t_last,
            inspections=s.n_inspections, link=links[s.id]))
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
        return f"{value:.6g}"
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


def _event(r: ScheduleRow, stamp: str) -> list[str]:
    what = (f"ACT NOW: {r.actuator}" if r.due_now and r.rule == "act now"
            else f"Inspect {r.actuator}")
    if r.indicator:
        what += f" ({r.indicator}" + (f", risk {r.risk:.2g})" if r.risk is not None else ")")
    unit = r.time_unit
    words = [f"{r.actuator}" + (f" ({r.description})" if r.description else "")
             + f": inspect by {r.inspect_by:.0f} {unit}", r.reason,
             f"planned at risk {r.target_risk:g}"
             + (f", predicted {r.risk:.2g}" if r.risk is not None else ""),
             f"last inspection {r.last_inspection:g} {unit}, {r.inspections} in all"
             if r.last_inspection is not None else "never inspected",
             f"page: {r.link}"]
    day = r.date
    lines = ["BEGIN:VEVENT",
             f"UID:{page_stem(r.actuator, digits=64)}-{r.inspect_by:.6g}@emaphm",
             f"DTSTAMP:{stamp}",
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


def write_ics(rows: Sequence[ScheduleRow], path: str | Path, *, name: str = "Fleet inspections",
              now: _dt.datetime | None = None) -> Path:
    """The schedule as an iCalendar file: an all-day event per actuator on its date
    (every row needs one: a :class:`Calendar`), written atomically."""
    missing = [r.actuator for r in rows if r.date is None]
    if missing:
        raise ValueError(f"calendar events need dates and {missing[0]} has none: give a start "
                         "date and the operating time per day (--start DATE --per-day H)")
    stamp = (now or _dt.datetime.now(_dt.timezone.utc)).strftime("%Y%m%dT%H%M%SZ")
    lines = ["BEGIN:VCALENDAR", "VERSION:2.0", "PRODID:-//emaphm//fleet schedule//EN",
             "CALSCALE:GREGORIAN", "METHOD:PUBLISH", f"X-WR-CALNAME:{_ics_text(name)}"]
    for r in rows:
        lines += _event(r, stamp)
    lines.append("END:VCALENDAR")
    path = Path(path)
    atomic_write_text(path, "".join(_fold(line) for line in lines))
    return path
