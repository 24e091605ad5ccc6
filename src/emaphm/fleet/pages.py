"""The fleet site's pages as HTML: the index's rows and cells, and each actuator's page
(state, RUL per indicator, figures, calibration, inspections). Every value from the store is
escaped (:mod:`emaphm.fleet.markup`); nothing here reads the history or writes a file:
:mod:`emaphm.fleet.site` builds the site from these strings."""

from __future__ import annotations

import datetime as _dt
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any, Iterable, Sequence

from .. import modes as _modes
from ..prognosis.thresholds import FailureThresholds
from .markup import esc, fmt_deadline, schedule_key, script_json, unit_rank

if TYPE_CHECKING:  # pragma: no cover - .status imports the prognosis (SciPy): see _render
    from ..prognosis.inspection import InspectionPolicy
    from .status import ActuatorStatus


#: Rows of the index in one page of its table: those the page holds itself (the most
#: urgent, for a browser without JavaScript) and those its script shows at a time.
PAGE_ROWS = 100


#: The pages load only their own files: no inline script (a value that escaped its escaping
#: could not run), nothing from the network. ``file:`` beside ``'self'``: browsers differ in
#: whether ``'self'`` covers the other files of a page opened from disk.
_CSP = ("default-src 'none'; img-src 'self' file:; style-src 'self' file:; "
        "script-src 'self' file:; base-uri 'none'; form-action 'none'")


#: Each health indicator's label (:attr:`emaphm.modes.Indicator.label`).
_INDICATOR_LABEL = {n: i.label for n, i in _modes.INDICATORS.items()}


_DASH = "\u2013"


_TREND = {1: ("\u2191", "rising"), 0: ("\u2192", "steady"), -1: ("\u2193", "falling")}


# ----------------------------------------------------------------------------- formatting
def _fmt_time(x: float | None, unit: str) -> str:
    if x is None or math.isnan(x):
        return "\u2013"
    if math.isinf(x):
        return "\u221e"
    return f"{x:.0f} {unit}" if abs(x) >= 10 else f"{x:.2g} {unit}"


def _fmt_k(x: float) -> str:
    return f"{x:.3f}"


def _date(utc: str | None) -> str:
    if not utc:
        return ""
    return utc[:16].replace("T", " ")


def _num(x: Any) -> float | None:
    """A finite float or None (JSON has no NaN or infinity)."""
    try:
        x = float(x)
    except (TypeError, ValueError):
        return None
    return x if math.isfinite(x) else None


# ----------------------------------------------------------------------------- the rows
def _row(s: ActuatorStatus, rank: int, page: str) -> dict:
    """One actuator as the index's JSON row (also ``fleet.json``). The workers make it
    with rank 0; :func:`_ranked` puts it at its place in the build's order."""
    from .status import VERDICTS

    a = s.actuator
    ratio = _num(s.ratio)
    tags = [s.rul_state, s.verdict]
    if s.past_threshold or s.predicted or s.verdict in ("faulty", "unexplained"):
        tags.append("attention")
    return {
        "rank": rank, "id": a.id, "description": a.description, "time_unit": a.time_unit,
        "page": page, "n_inspections": s.n_inspections, "last_time": _num(s.last_time),
        "last_recorded_utc": s.last_recorded_utc, "verdict": s.verdict, "faults": list(s.faults),
        "worst": s.worst, "level": _num(s.level), "threshold": _num(s.threshold),
        "ratio": ratio, "rul_state": s.rul_state, "rul_median": _num(s.rul_median),
        "rul_lo": _num(s.rul_lo), "rul_hi": _num(s.rul_hi),
        "rul_hi_infinite": bool(math.isinf(s.rul_hi)), "rul_level": s.rul_level,
        "trend": s.trend, "growth": _num(s.growth), "tags": tags, **_inspect_fields(s),
        # what the script sorts on: one key per column, nulls last
        "sort": {"rank": rank, "id": a.id.lower(), "description": a.description.lower(),
                 "last": _num(s.last_time), "verdict": VERDICTS.index(s.verdict),
                 "worst": None if ratio is None else -ratio, "rul": rank,
                 "inspect": None,          # its place in the fleet: _inspect_order
                 "trend": None if s.trend is None else -s.trend, "n": -s.n_inspections},
        "text": " ".join([a.id, a.description, s.verdict, " ".join(s.faults),
                          s.worst or "", s.rul_state]).lower(),
    }


def _inspect_fields(s: ActuatorStatus) -> dict:
    """The next inspection of ``s`` (:attr:`ActuatorStatus.plan`) as fields of its row."""
    p = s.plan
    if p is None:
        return {"inspect_by": None}
    return {"inspect_by": _num(p.at), "inspect_left": _num(p.at - p.t_now),
            "inspect_now": p.act_now, "inspect_rule": p.rule,
            "inspect_indicator": p.indicator, "inspect_risk": _num(p.risk),
            "inspect_target": p.target, "inspect_reason": p.reason}


def _inspect_order(rows: Sequence[dict]) -> dict[str, int]:
    """The place (1, 2, ...) of each row's id when the "Inspect by" column is sorted: the
    order of ``emaphm fleet schedule`` (:func:`~emaphm.fleet.status.inspect_key`, on the
    rows' fields): due now first (never inspected first of all), then, per time unit
    (flight hours, then cycles), the operating time left until the inspection, soonest
    first (float noise ties); ties by id; rows without a plan last. (The inspect-by times
    themselves do not order the fleet: its actuators are at different operating times.)
    The script sorts on it: one number per row."""
    def key(r: dict) -> tuple:
        planned = r.get("inspect_by") is not None
        return schedule_key(r["id"], r.get("time_unit"),
                            (r.get("inspect_left") or 0.0) if planned else None,
                            due_now=bool(r.get("inspect_now")),
                            never=r.get("inspect_rule") == "never inspected")

    return {r["id"]: i for i, r in enumerate(sorted(rows, key=key), start=1)}


def _policy_words(policy: InspectionPolicy, units: Iterable[str]) -> str:
    """The intervals of ``policy`` for each time unit of ``units``, in words."""
    out = []
    for unit in sorted(set(units), key=unit_rank):
        try:
            iv = policy.intervals(unit)
        except ValueError:
            continue
        out.append(f"default {iv.default:g}, minimum {iv.min:g}, maximum {iv.max:g} {unit}")
    return "; ".join(out)


def _ranked(row: dict, rank: int, inspect: int | None = None) -> dict:
    """``row`` (:func:`_row`) at place ``rank`` of the order of attention and ``inspect``
    of the order of the "Inspect by" column (:func:`_inspect_order`)."""
    return {**row, "rank": rank, "sort": {**row["sort"], "rank": rank, "rul": rank,
                                          "inspect": inspect}}


# ----------------------------------------------------------------------------- HTML pieces
def _head(title: str, prefix: str) -> str:
    return (
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
        "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
        f"<meta http-equiv=\"Content-Security-Policy\" content=\"{_CSP}\">\n"
        "<meta name=\"referrer\" content=\"no-referrer\">\n"
        f"<title>{esc(title)}</title>\n"
        f"<link rel=\"stylesheet\" href=\"{prefix}assets/fleet.css\">\n"
        f"<script src=\"{prefix}assets/fleet.js\" defer></script>\n"
        "</head>\n")


def _verdict_badge(verdict: str, faults: Sequence[str]) -> str:
    cls = verdict.replace(" ", "-")
    out = f"<span class=\"badge v-{esc(cls)}\">{esc(verdict)}</span>"
    if faults:
        out += f"<small>{esc(', '.join(faults))}</small>"
    return out


def _rul_cell(s: ActuatorStatus) -> str:
    unit = s.actuator.time_unit
    if s.past_threshold:
        return "<span class=\"badge r-past\">past threshold</span>"
    if s.prognosis is None:
        return "\u2013<small>needs 3 inspections</small>" if s.n_inspections else "\u2013"
    if not s.predicted:
        return "<span class=\"muted\">no growth</span>"
    hi = "\u221e" if math.isinf(s.rul_hi) else _fmt_time(s.rul_hi, unit)
    return (f"<strong>{esc(_fmt_time(s.rul_median, unit))}</strong>"
            f"<small>{s.rul_level:.0%}: {esc(_fmt_time(s.rul_lo, unit))} \u2013 {esc(hi)}</small>")


def _trend_cell(s: ActuatorStatus) -> str:
    if s.trend is None:
        return "<span class=\"muted\" title=\"no trend: fewer than 3 inspections\">\u2013</span>"
    arrow, word = _TREND[s.trend]
    rate = f"{s.growth:+.2g} per {s.actuator.time_unit}"
    return (f"<span class=\"trend t{s.trend:+d}\" title=\"{esc(word)}: {esc(rate)}\" "
            f"aria-label=\"{esc(word)}\">{arrow}</span>")


def _inspect_cell(s: ActuatorStatus) -> str:
    """The next inspection: the time (red when due now), the indicator that drives it."""
    p = s.plan
    if p is None:
        return "\u2013"
    unit = s.actuator.time_unit
    title = esc(p.reason)
    if p.act_now:
        what = "act now" if p.rule == "act now" else "inspect now"
        return (f"<strong class=\"due\" title=\"{title}\">{what}</strong>"
                + (f"<small>{esc(p.indicator)}</small>" if p.indicator else ""))
    why = p.indicator or ("default interval" if p.rule in ("healthy", "too few inspections")
                          else p.rule)
    return (f"<span title=\"{title}\">{esc(fmt_deadline(p.at, unit))}</span>"
            f"<small>in {esc(fmt_deadline(p.at - p.t_now, unit))} \u00b7 {esc(why)}</small>")


def _worst_cell(s: ActuatorStatus) -> str:
    if s.worst is None:
        return "\u2013"
    return (f"{esc(_INDICATOR_LABEL.get(s.worst, s.worst))}"
            f"<small>{s.level:.3f} of {s.threshold:.3g} ({s.ratio:.0%})</small>")


_COLUMNS = (  # key, heading, class (the less important ones are dropped on a phone)
    ("rank", "#", "c-rank"), ("id", "Actuator", "c-id"), ("description", "Description", "c-desc"),
    ("last", "Last inspection", "c-last"), ("verdict", "Verdict", "c-verdict"),
    ("worst", "Nearest its threshold", "c-worst"), ("rul", "RUL median (interval)", "c-rul"),
    ("inspect", "Inspect by", "c-inspect"), ("trend", "Trend", "c-trend"),
    ("n", "Inspections", "c-n"))


def _cells(s: ActuatorStatus, page: str) -> dict:
    """The HTML of one actuator's cells of the index (its page at ``page``), per column key
    (:data:`_COLUMNS`), but the rank (:func:`_tr` adds it: it depends on the fleet)."""
    unit = s.actuator.time_unit
    last = "\u2013" if s.last_time is None else (
        f"{esc(_fmt_time(s.last_time, unit))}<small>{esc(_date(s.last_recorded_utc))}</small>")
    return {
        "id": f"<a href=\"{esc(page)}\">{esc(s.id)}</a>",
        "description": esc(s.actuator.description) or "<span class=\"muted\">\u2013</span>",
        "last": last, "verdict": _verdict_badge(s.verdict, s.faults),
        "worst": _worst_cell(s), "rul": _rul_cell(s), "inspect": _inspect_cell(s),
        "trend": _trend_cell(s), "n": str(s.n_inspections)}


def _tr(row: dict, cells: dict) -> str:
    """The index's table row of ``row`` (ranked) from its :func:`_cells`."""
    cells = {**cells, "rank": str(row["rank"])}
    state = str(row["rul_state"]).replace(" ", "-")
    return (f"<tr data-i=\"{row['rank'] - 1}\" class=\"s-{esc(state)}\">" + "".join(
        f"<td class=\"{cls}\" data-label=\"{esc(label)}\"><div>{cells[key]}</div></td>"
        for key, label, cls in _COLUMNS) + "</tr>")


#: The fields of a row (:func:`_row`) the index's script reads, beside its table row.
_SCRIPT_FIELDS = ("rank", "id", "description", "sort", "text", "tags")


def _index_html(rows: list[dict], trs: list[str], *, title: str, source: str,
                thresholds: FailureThresholds, seed: int, level: float,
                policy: InspectionPolicy) -> str:
    """The index of ``rows`` (ranked, in order), whose table rows are ``trs``."""
    from .. import __version__

    counts: dict[str, int] = {}
    for r in rows:
        counts[r["rul_state"]] = counts.get(r["rul_state"], 0) + 1
    n_ins = sum(r["n_inspections"] for r in rows)
    units = [str(r["time_unit"]) for r in rows]
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    head = "".join(
        f"<th scope=\"col\" class=\"{cls}\" data-key=\"{key}\">"
        f"<button type=\"button\" data-key=\"{key}\">{esc(label)}</button></th>"
        for key, label, cls in _COLUMNS)
    body = trs[:PAGE_ROWS]
    summary = " \u00b7 ".join(f"<span class=\"count s-{esc(k.replace(' ', '-'))}\">"
                              f"{counts[k]} {esc(k)}</span>"
                              for k in ("past threshold", "predicted", "no growth", "no prediction")
                              if k in counts)
    options = "".join(f"<option value=\"{esc(v)}\">{esc(t)}</option>" for v, t in (
        ("", "all actuators"), ("attention", "needing attention"),
        ("past threshold", "past threshold"), ("predicted", "failure predicted"),
        ("no growth", "no growth"), ("no prediction", "no prediction yet"),
        ("unexplained", "verdict unexplained"), ("faulty", "verdict faulty"),
        ("healthy", "verdict healthy")))
    sort_options = "".join(f"<option value=\"{key}\">{esc(label)}</option>"
                           for key, label, _ in _COLUMNS if key != "rank")
    thr = ", ".join(f"{k.replace('_', ' ')} {v:g}" for k, v in thresholds.to_dict().items())
    # what the script reads of each row, with its table row (fleet.json has every field):
    # the whole rows made the index of 10,000 actuators 20 MB, these 12
    data = {"actuators": [{**{k: r[k] for k in _SCRIPT_FIELDS}, "html": tr}
                          for r, tr in zip(rows, trs)], "page_rows": PAGE_ROWS}
    more = (f"<p class=\"more\" id=\"more\">The first {len(body)} of {len(rows)} actuators, in "
            "order of attention: the page's script (JavaScript) sorts, filters and pages through "
            "all of them; <a href=\"fleet.json\">fleet.json</a> lists every one.</p>\n"
            if len(rows) > len(body) else "")
    return (
        _head(title, "") +
        "<body class=\"index\">\n<header class=\"top\">\n"
        f"<h1>{esc(title)}</h1>\n"
        f"<p class=\"meta\">{len(rows)} actuators \u00b7 {n_ins} inspections \u00b7 "
        f"history <code>{esc(source)}</code> \u00b7 inspections planned at risk "
        f"<b id=\"risk\">{policy.risk:g}</b> \u00b7 built {esc(now)} by emaphm "
        f"{esc(__version__)}</p>\n"
        f"<p class=\"summary\">{summary}</p>\n</header>\n<main>\n"
        "<form class=\"controls\" id=\"controls\" role=\"search\" autocomplete=\"off\">\n"
        "<label>Filter <input type=\"search\" id=\"filter\" "
        "placeholder=\"id, description, fault\u2026\"></label>\n"
        f"<label>Show <select id=\"show\">{options}</select></label>\n"
        f"<label>Sort <select id=\"sort\"><option value=\"rank\">attention (RUL)</option>"
        f"{sort_options}</select></label>\n"
        f"<output id=\"shown\" aria-live=\"polite\">{len(body)} of {len(rows)} shown</output>\n"
        "<span class=\"pager\" id=\"pager\" hidden><button type=\"button\" id=\"prev\">"
        "\u2039 previous</button> <output id=\"page\"></output> <button type=\"button\" "
        "id=\"next\">next \u203a</button></span>\n"
        "</form>\n"
        "<table id=\"fleet\" class=\"fleet\">\n"
        f"<caption>Actuators needing attention first: past a failure threshold, then the "
        f"shortest median remaining useful life (RUL, {level:.0%} interval below it).</caption>\n"
        f"<thead><tr>{head}</tr></thead>\n<tbody>\n" + "\n".join(body) + "\n</tbody>\n</table>\n"
        "<p class=\"empty\" id=\"empty\" hidden>No actuator matches the filter.</p>\n"
        + more +
        "<section class=\"notes\"><h2>How to read it</h2><ul>\n"
        "<li><b>Nearest its threshold</b>: the health indicator furthest past its failure "
        "threshold, else the one with the shortest RUL median among those growing, else the "
        "one nearest its threshold; below it, its last identified value against the "
        "threshold.</li>\n"
        "<li><b>Past threshold</b>: the last identified value, or the degradation trend "
        "fitted to the inspections, is at or past the failure threshold.</li>\n"
        "<li><b>RUL</b>: remaining useful life from the last inspection, median and "
        f"{level:.0%} interval of the Monte Carlo draws over the fitted degradation trends "
        f"(seed {seed}); a trend needs three inspections. <i>No growth</i>: no indicator "
        "rises beyond the noise towards its threshold within ten times the span of the "
        "history.</li>\n"
        "<li><b>Inspect by</b>: the next inspection, the latest operating time at which the "
        "chance that an indicator has crossed its failure threshold stays under a risk of "
        f"{policy.risk:g} (as <code>emaphm prognose --risk</code>), and the indicator that "
        "sets it; <i>act now</i> (red): that chance is reached within the minimum interval, "
        "or already; a default interval under three inspections or with every indicator at "
        f"its healthy level (intervals: {esc(_policy_words(policy, units))}). Times are "
        "rounded down. Sort by it to see what is due first (then, per time unit, the "
        "soonest); <code>emaphm fleet schedule</code> with the same <code>--risk</code> and "
        "intervals writes it as a table or a calendar.</li>\n"
        "<li><b>Trend</b>: the sign of the fitted growth rate of that indicator at the last "
        "inspection (\u2192 when within two standard errors of zero).</li>\n"
        f"<li>Failure thresholds: {esc(thr)}.</li>\n</ul></section>\n</main>\n"
        f"<script type=\"application/json\" id=\"fleet-data\">{script_json(data)}</script>\n"
        "</body>\n</html>\n")


def _dl(items: Sequence[tuple[str, str]]) -> str:
    return "<dl class=\"facts\">" + "".join(f"<div><dt>{esc(k)}</dt><dd>{v}</dd></div>"
                                            for k, v in items) + "</dl>"


def _prognosis_table(s: ActuatorStatus) -> str:
    from .status import indicator_state

    prog = s.prognosis
    if prog is None:
        n = s.n_inspections
        return (f"<p class=\"muted\">No prediction: {n} inspection{'s' if n != 1 else ''}; a "
                "degradation trend needs at least 3.</p>")
    unit = s.actuator.time_unit
    span = float(prog.times[-1] - prog.times[0])
    rows = []
    for name, p in prog.predictions.items():
        top = max(p.weights, key=p.weights.get)
        state, sign, rate = indicator_state(p, span)
        arrow, word = _TREND[sign]
        if state == "past threshold":
            rul, iv = "<span class=\"badge r-past\">past threshold</span>", ""
        elif state == "no growth":
            rul = "<span class=\"muted\">no growth</span>"
            if math.isfinite(p.median) and not p.no_growth(span):
                rul += (f"<small>fitted median {esc(_fmt_time(p.median, unit))}, but the trend "
                        "does not rise beyond the noise</small>")
            iv = f"P(within {_fmt_time(10 * span, unit)}) {p.p_fail_within(10 * span):.2f}"
        else:
            rul = esc(_fmt_time(p.median, unit))
            iv = f"{_fmt_time(p.lo, unit)} \u2013 {_fmt_time(p.hi, unit)}"
        cls = " class=\"worst\"" if name == s.worst else ""
        rows.append(
            f"<tr{cls}><th scope=\"row\">{esc(_INDICATOR_LABEL.get(name, name))}</th>"
            f"<td>{p.current + 0.0:.3f}</td><td>{p.threshold:.3g}</td>"
            f"<td>{esc(top)} ({p.weights[top]:.2f})</td>"
            f"<td><span class=\"trend t{sign:+d}\" title=\"{esc(word)}: {rate:+.2g} per "
            f"{esc(unit)}\">{arrow}</span></td><td>{rul}</td><td>{esc(iv)}</td></tr>")
    return ("<div class=\"scroll\"><table class=\"data\"><thead><tr><th scope=\"col\">indicator"
            "</th><th scope=\"col\">trend now</th><th scope=\"col\">threshold</th>"
            "<th scope=\"col\">trend model (Akaike weight)</th><th scope=\"col\">trend</th>"
            f"<th scope=\"col\">RUL median</th><th scope=\"col\">{s.rul_level:.0%} interval</th>"
            "</tr></thead><tbody>" + "".join(rows) + "</tbody></table></div>")


def _params_used(ins: Any, unit: str) -> str:
    """Which parameters an inspection was diagnosed with, in words."""
    extra = ins.extra if isinstance(ins.extra, dict) else {}
    at = extra.get("calibrated_at")
    params = extra.get("parameters")
    name = params.get("name") if isinstance(params, dict) else None
    if isinstance(at, (int, float)) and not isinstance(at, bool):
        return f"calibration of {_fmt_time(float(at), unit)}"
    if isinstance(params, dict):
        return f"given: {name or 'parameters'}"
    if extra.get("synthetic"):
        return "none (synthetic)"
    return "data sheet"


def _calibration_html(s: ActuatorStatus, records: Sequence[Any]) -> str:
    unit = s.actuator.time_unit
    data = s.data
    parts = []
    if data.n:
        last = data.inspections[-1]
        extra = last.extra if isinstance(last.extra, dict) else {}
        params = extra.get("parameters")
        used = _params_used(last, unit)
        parts.append(f"<p>The last inspection ({esc(_fmt_time(last.time, unit))}) was diagnosed "
                     f"with: <strong>{esc(used)}</strong>"
                     + (" (the emaphm preset; this actuator has no recorded calibration "
                        "it was diagnosed with)." if used == "data sheet" else ".") + "</p>")
        cal = params.get("calibration") if isinstance(params, dict) else None
        if isinstance(cal, dict) and cal.get("estimates"):
            parts.append(_estimates_table(cal))
        nuisance = extra.get("nuisance")
        if isinstance(nuisance, dict) and nuisance:
            parts.append("<p>Searched beside k at that inspection (drift since the "
                         "calibration): " + esc(", ".join(
                             f"{k} {100 * float(v):+.1f} %" for k, v in nuisance.items()
                             if isinstance(v, (int, float)))) + "</p>")
    if records:
        rows = "".join(
            f"<tr><td>{esc(_fmt_time(r.time, unit))}</td>"
            f"<td>{esc(', '.join(Path(x).name for x in r.sources) or '-')}</td>"
            f"<td>{esc(_date(r.recorded_utc))}</td></tr>" for r in records)
        parts.append("<h3>Calibrations recorded</h3><div class=\"scroll\"><table class=\"data\">"
                     "<thead><tr><th scope=\"col\">from</th><th scope=\"col\">fitted on</th>"
                     "<th scope=\"col\">recorded (UTC)</th></tr></thead><tbody>" + rows
                     + "</tbody></table></div>")
    else:
        parts.append("<p class=\"muted\">No calibration recorded for this actuator "
                     "(<code>emaphm history calibrate</code>).</p>")
    return "".join(parts)


def _estimates_table(cal: dict) -> str:
    units = {"offset_a": "A", "offset_b": "A", "offset_c": "A", "load": "N m"}
    rows = []
    for item in cal.get("estimates") or ():
        try:
            name, value, se = str(item[0]), float(item[1]), float(item[2])
        except (TypeError, ValueError, IndexError):
            continue
        u = units.get(name)
        if u is None:
            val, ci = f"{100 * value:+.2f} %", f"\u00b1 {100 * 1.96 * se:.2f} %"
        else:
            val, ci = f"{value:+.4g} {u}", f"\u00b1 {1.96 * se:.2g} {u}"
        rows.append(f"<tr><th scope=\"row\">{esc(name)}</th><td>{esc(val)}</td><td>{esc(ci)}</td></tr>")
    fixed = cal.get("fixed") or ()
    sources = cal.get("sources") or ()
    return ("<div class=\"scroll\"><table class=\"data\"><caption>Calibrated deviations from the "
            f"data sheet{(' (' + esc(str(cal.get('date'))) + ')') if cal.get('date') else ''}"
            "</caption><thead><tr><th scope=\"col\">parameter</th><th scope=\"col\">deviation"
            "</th><th scope=\"col\">95 % interval</th></tr></thead><tbody>" + "".join(rows)
            + "</tbody></table></div>"
            + (f"<p>Kept at the data sheet: {esc(', '.join(map(str, fixed)))}.</p>" if fixed else "")
            + (f"<p>Fitted on: {esc(', '.join(Path(str(x)).name for x in sources))}.</p>"
               if sources else ""))


def _inspections_table(s: ActuatorStatus) -> str:
    data = s.data
    unit = s.actuator.time_unit
    if not data.n:
        return "<p class=\"muted\">No inspection recorded yet.</p>"
    from ..faults import K_LABELS

    khead = "".join(f"<th scope=\"col\" title=\"{esc(label)}\">k{j + 1}</th>"
                    for j, label in enumerate(K_LABELS))
    rows = []
    for ins in reversed(data.inspections):
        diag = ins.diagnosis if isinstance(ins.diagnosis, dict) else None
        verdict = "not diagnosed" if diag is None else str(diag.get("verdict") or (
            "healthy" if diag.get("healthy") else "faulty"))
        faults = [str(f.get("mode")).replace("_", " ")
                  + (f" {f.get('phase')}" if f.get("phase") else "")
                  for f in (diag or {}).get("faults") or () if isinstance(f, dict)]
        kcells = "".join(
            f"<td>{_fmt_k(k)}<small>[{_fmt_k(lo)}, {_fmt_k(hi)}]</small></td>"
            for k, lo, hi in zip(ins.k, ins.k_lo, ins.k_hi))
        fp = ins.fingerprint or ""
        algo = esc(ins.algorithm or "\u2013") + (f" <small>seed {int(ins.seed)}</small>"
                                                  if ins.seed is not None else "")
        src = Path(str(ins.source)).name if ins.source else ""
        rows.append(
            f"<tr><th scope=\"row\">{esc(_fmt_time(ins.time, unit))}"
            f"<small>{esc(_date(ins.recorded_utc))}</small></th>"
            f"<td>{_verdict_badge(verdict, faults)}</td>{kcells}<td>{algo}</td>"
            f"<td>{esc(ins.fault_model)}</td><td>{esc(_params_used(ins, unit))}</td>"
            f"<td><code title=\"{esc(fp)}\">{esc(fp[:12]) or _DASH}</code>"
            + (f"<small title=\"{esc(ins.source)}\">{esc(src)}</small>" if src else "")
            + "</td></tr>")
    level = data.inspections[-1].level
    return ("<div class=\"scroll\"><table class=\"data inspections\"><caption>Newest first; "
            "k with its interval"
            + (f" ({esc(data.inspections[-1].spread_method)}, {float(level):.0%})"
               if level is not None and data.inspections[-1].spread_method else "")
            + "</caption><thead><tr><th scope=\"col\">time</th><th scope=\"col\">verdict</th>"
            + khead + "<th scope=\"col\">algorithm</th><th scope=\"col\">fault model</th>"
            "<th scope=\"col\">parameters</th><th scope=\"col\">trace fingerprint</th></tr>"
            "</thead><tbody>" + "".join(rows) + "</tbody></table></div>")


def _figure_html(figures: dict, key: str, alt: str, caption: str) -> str:
    if key not in figures:
        return ""
    name, w, h = figures[key]
    return (f"<figure><a href=\"{esc(name)}\"><img src=\"{esc(name)}\" width=\"{w}\" "
            f"height=\"{h}\" alt=\"{esc(alt)}\" loading=\"lazy\"></a>"
            f"<figcaption>{esc(caption)}</figcaption></figure>")


def _actuator_html(s: ActuatorStatus, figures: dict, records: Sequence[Any], *,
                   fleet_title: str) -> str:
    """The page of one actuator. It depends on that actuator alone (and the build's
    settings), not on the rest of the fleet: its place in the order of attention is the
    index's, so that a new inspection of one actuator writes one page."""
    a = s.actuator
    unit = a.time_unit
    facts = [
        ("Verdict (last inspection)", _verdict_badge(s.verdict, s.faults)),
        ("Nearest its threshold", _worst_cell(s)),
        ("RUL median (interval)", _rul_cell(s)),
        ("Trend", _trend_cell(s)),
        ("Inspect by", _inspect_cell(s) + (
            f"<small>{esc(s.plan.reason)}</small><small>planned at risk {s.plan.target:g}"
            f"</small>" if s.plan is not None else "")),
        ("Inspections", f"{s.n_inspections}" + (
            f"<small>last at {esc(_fmt_time(s.last_time, unit))}, "
            f"{esc(_date(s.last_recorded_utc))} UTC</small>" if s.last_time is not None else "")),
        ("Time unit", "flight hours (h)" if unit == "h" else esc(unit)),
        ("Registered", esc(_date(a.created_utc)) + " UTC"),
    ]
    desc = (f"<p class=\"desc\">{esc(a.description)}</p>" if a.description else "")
    figs = (_figure_html(figures, "history", f"health history of {a.id}: each component of k "
                         "over the inspections with its interval and failure threshold",
                         "Each component of k over the inspections, with its interval; red: a "
                         "fault named on that component, dashed: the failure threshold.")
            + _figure_html(figures, "prognosis", f"prognosis of {a.id}: trend, threshold and "
                           "prediction cone", "Trend, failure threshold and 90 % prediction "
                           "cone of the indicators nearest their thresholds; the bar on the "
                           "threshold is the RUL interval, the diamond its median."))
    return (
        _head(f"{a.id} \u2013 {fleet_title}", "../") +
        "<body class=\"actuator\">\n<header class=\"top\">\n"
        f"<nav><a href=\"../index.html\">\u2190 {esc(fleet_title)}</a></nav>\n"
        f"<h1>{esc(a.id)}</h1>\n{desc}\n</header>\n<main>\n"
        f"<section>{_dl(facts)}</section>\n"
        f"<section><h2>Remaining useful life</h2>{_prognosis_table(s)}</section>\n"
        + (f"<section class=\"figures\"><h2>Figures</h2>{figs}</section>\n" if figs else "")
        + f"<section><h2>Calibration</h2>{_calibration_html(s, records)}</section>\n"
        f"<section><h2>Inspections</h2>{_inspections_table(s)}</section>\n"
        "</main>\n</body>\n</html>\n")
