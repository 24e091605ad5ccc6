"""The fleet health site: a static HTML report of every actuator of a health history.

:func:`build_site` writes, into a folder::

    index.html                  one row per actuator, units needing attention first,
                                sortable and filterable (assets/fleet.js), the rows also
                                inline as JSON for the script
    fleet.json                  the same rows for programs
    assets/fleet.css, fleet.js  shipped with emaphm: no CDN, works offline and from file://
    actuators/STEM.html         a page per actuator: state, RUL per indicator, figures,
                                calibration, inspections
    actuators/STEM-history.png  :func:`emaphm.prognosis.plots.plot_history`
    actuators/STEM-prognosis.png  :func:`emaphm.prognosis.plots.plot_prognosis` (from three
                                inspections on)

``STEM`` is :func:`emaphm.fleet.markup.page_stem` of the id (a slug and a hash), safe for
any id. Every value from the store is escaped (:mod:`emaphm.fleet.markup`); every file is
written atomically (:mod:`emaphm._files`), the pages before the index, so an interrupted
build never leaves an index that links to a missing page. The figures are only read
from the history and its prognosis: nothing is identified or simulated again.

The prognosis and the figures of each actuator are computed in ``workers`` processes
(default: every core); the result does not depend on their number. Drawing is most of
the cost (about a second of CPU per actuator), so a rebuild into the same folder draws
again only the figures whose inputs changed: ``actuators/.figures.json`` keeps, per
actuator, the SHA-256 of everything its figures are drawn from (its inspections, the
thresholds, the seed and level of the prognosis, the versions of emaphm and matplotlib
and the code of the plotting modules); ``redraw=True`` ignores it. A build of the whole
history removes the pages and figures of actuators an earlier build into the folder
wrote that the history no longer has; a build of some ``actuators`` keeps the others'.
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import json
import math
import os
import time
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any, Callable, Sequence

from .._files import atomic_write, atomic_write_text
from ..prognosis.thresholds import DEFAULT_FAILURE_THRESHOLDS, INDICATORS, FailureThresholds
from ..seeds import check_seed
from .markup import esc, page_stem, script_json
from .status import VERDICTS, ActuatorStatus, assess, indicator_state, order_fleet

__all__ = ["FleetSite", "build_site", "ASSETS", "FIGURE_DPI"]

#: The files shipped in ``emaphm/fleet/assets`` and copied to ``OUT/assets``.
ASSETS = ("fleet.css", "fleet.js")

#: Resolution of the figures on the pages (dots per inch of their matplotlib size).
FIGURE_DPI = 100

#: The pages load only their own files: no inline script (a value that escaped its escaping
#: could not run), nothing from the network. ``file:`` beside ``'self'``: browsers differ in
#: whether ``'self'`` covers the other files of a page opened from disk.
_CSP = ("default-src 'none'; img-src 'self' file:; style-src 'self' file:; "
        "script-src 'self' file:; base-uri 'none'; form-action 'none'")

_INDICATOR_LABEL = {"friction": "friction (k1)", "backlash": "backlash (k2)",
                    "short_a": "short circuit A (k3)", "short_b": "short circuit B (k4)",
                    "short_c": "short circuit C (k5)", "eccentricity": "eccentricity (k6)",
                    "gain_drift": "gain drift (|k8 - 0.5|)"}

_DASH = "\u2013"

_TREND = {1: ("\u2191", "rising"), 0: ("\u2192", "steady"), -1: ("\u2193", "falling")}


@dataclass(frozen=True)
class FleetSite:
    """What :func:`build_site` wrote: ``index`` and a page per actuator id (``pages``),
    the statuses in the index's order, the wall-clock seconds it took, the worker
    processes it used (0: none) and for how many actuators it drew figures (the others'
    were still up to date)."""

    out: Path
    index: Path
    pages: dict
    statuses: tuple = field(repr=False)
    elapsed_s: float = 0.0
    workers: int = 0
    drawn: int = 0


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


# ----------------------------------------------------------------------------- work per actuator
@dataclass(frozen=True)
class _Job:
    data: Any
    thresholds: FailureThresholds
    seed: int
    level: float
    folder: str
    stem: str
    key: str = ""
    reuse: Any = None          # the figures of an earlier build with the same key


#: Remembers which inputs drew the figures in ``actuators/`` (module docstring).
_MANIFEST = ".figures.json"

#: The modules whose code shapes a figure: a change in any of them redraws every figure.
_FIGURE_CODE = ("emaphm.plots", "emaphm.prognosis.plots", "emaphm.prognosis.trends",
                "emaphm.prognosis.thresholds", "emaphm.fleet.status", "emaphm.fleet.site")


def _code_fingerprint() -> str:
    import importlib.util
    from importlib.metadata import PackageNotFoundError, version

    from .. import __version__

    try:
        mpl = version("matplotlib")
    except PackageNotFoundError:                # pragma: no cover - a dependency
        mpl = "?"
    h = hashlib.sha256(f"emaphm {__version__} matplotlib {mpl} dpi {FIGURE_DPI}".encode())
    for name in _FIGURE_CODE:
        spec = importlib.util.find_spec(name)
        if spec is not None and spec.origin and os.path.exists(spec.origin):
            h.update(Path(spec.origin).read_bytes())
    return h.hexdigest()


def _figure_key(data: Any, thresholds: FailureThresholds, seed: int, level: float,
                code: str) -> str:
    """SHA-256 of everything an actuator's figures are drawn from."""
    a = data.actuator
    payload = {"actuator": [a.id, a.description, a.time_unit],
               "inspections": [i.to_dict() for i in data.inspections],
               "thresholds": thresholds.to_dict(), "seed": seed, "level": level, "code": code}
    text = json.dumps(payload, sort_keys=True, default=lambda o: getattr(o, "tolist", str)(o))
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def _read_manifest(folder: Path) -> dict:
    if not (folder / _MANIFEST).is_file():     # a FIFO or a device there would never end
        return {}
    try:
        data = json.loads((folder / _MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def _reusable(entry: Any, key: str, folder: Path) -> dict | None:
    """The figures an earlier build drew from the same inputs, if they are all still there."""
    if not isinstance(entry, dict) or entry.get("key") != key:
        return None
    figures = entry.get("figures")
    if not isinstance(figures, dict):
        return None
    try:
        out = {k: (str(v[0]), int(v[1]), int(v[2])) for k, v in figures.items()}
    except (TypeError, ValueError, IndexError):
        return None
    if not all((folder / name).is_file() for name, _, _ in out.values()):
        return None
    return out


def _remove_others(folder: Path, known: dict, keep: set[str]) -> None:
    """Remove from ``folder`` (and from the manifest ``known``) the page and figures of
    every actuator an earlier build wrote that is not in ``keep``: a site rebuilt from a
    history without them must not keep serving their pages. Only the files a build
    names after a manifest stem are removed."""
    for stem in [s for s in known if s not in keep]:
        del known[stem]
        if Path(stem).name != stem:             # a stem is a plain name (page_stem)
            continue
        for name in (f"{stem}.html", *_figure_names(stem)):
            (folder / name).unlink(missing_ok=True)


def _figure_names(stem: str) -> tuple[str, str]:
    return f"{stem}-history.png", f"{stem}-prognosis.png"


def _assess_and_draw(job: _Job) -> tuple[ActuatorStatus, dict]:
    """One actuator's status, and its figures written into ``job.folder``: name -> (width,
    height) in pixels. Runs in a worker process."""
    from ..plots import save_figure
    from ..prognosis.plots import (interesting_indicators, moved_components, plot_history,
                                   plot_prognosis)
    from ..prognosis.thresholds import INDICATOR_COMPONENT

    status = assess(job.data, thresholds=job.thresholds, seed=job.seed, level=job.level)
    if job.reuse is not None:
        return status, dict(job.reuse)
    figures = {}
    hist_name, prog_name = _figure_names(job.stem)
    if status.n_inspections:
        # the components that moved (and the worst): a panel per flat line of a healthy
        # component cost most of a fresh site's drawing time
        always = [INDICATOR_COMPONENT[status.worst]] if status.worst in INDICATOR_COMPONENT else []
        fig = plot_history(job.data, thresholds=job.thresholds,
                           components=moved_components(job.data, job.thresholds, always))
        save_figure(fig, Path(job.folder) / hist_name, dpi=FIGURE_DPI)
        figures["history"] = (hist_name, *_pixels(fig))
    prog = status.prognosis
    if prog is not None:                      # the worst, and up to two more that grow
        span = float(prog.times[-1] - prog.times[0])
        names = [status.worst] + [n for n in interesting_indicators(prog) if n != status.worst
                                  and not prog.predictions[n].no_growth(span)]
        fig = plot_prognosis(prog, indicators=names[:3])
        save_figure(fig, Path(job.folder) / prog_name, dpi=FIGURE_DPI)
        figures["prognosis"] = (prog_name, *_pixels(fig))
    return status, figures


def _pixels(fig: Any) -> tuple[int, int]:
    w, h = fig.get_size_inches()
    return int(round(w * FIGURE_DPI)), int(round(h * FIGURE_DPI))


def _run(jobs: list[_Job], workers: int,
         progress: Callable[[str], None] | None) -> list[tuple[ActuatorStatus, dict]]:
    if workers <= 1 or sum(j.reuse is None for j in jobs) <= 1:
        out = []
        for i, job in enumerate(jobs):
            out.append(_assess_and_draw(job))
            if progress:
                progress(f"{i + 1}/{len(jobs)} {job.data.actuator.id}")
        return out
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    # spawned workers start clean, whatever the parent holds (as the campaign's do); their
    # imports run side by side, so a fork server's shared imports would save CPU, not time
    with ProcessPoolExecutor(max_workers=min(workers, len(jobs)),
                             mp_context=multiprocessing.get_context("spawn")) as pool:
        out = []
        for i, res in enumerate(pool.map(_assess_and_draw, jobs)):
            out.append(res)
            if progress:
                progress(f"{i + 1}/{len(jobs)} {res[0].id}")
        return out


# ----------------------------------------------------------------------------- the rows
def _row(s: ActuatorStatus, rank: int, page: str) -> dict:
    """One actuator as the index's JSON row (also ``fleet.json``)."""
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
        "trend": s.trend, "growth": _num(s.growth), "tags": tags,
        # what the script sorts on: one key per column, nulls last
        "sort": {"rank": rank, "id": a.id.lower(), "description": a.description.lower(),
                 "last": _num(s.last_time), "verdict": VERDICTS.index(s.verdict),
                 "worst": None if ratio is None else -ratio, "rul": rank,
                 "trend": None if s.trend is None else -s.trend, "n": -s.n_inspections},
        "text": " ".join([a.id, a.description, s.verdict, " ".join(s.faults),
                          s.worst or "", s.rul_state]).lower(),
    }


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


def _worst_cell(s: ActuatorStatus) -> str:
    if s.worst is None:
        return "\u2013"
    return (f"{esc(_INDICATOR_LABEL.get(s.worst, s.worst))}"
            f"<small>{s.level:.3f} of {s.threshold:.3g} ({s.ratio:.0%})</small>")


_COLUMNS = (  # key, heading, class (the less important ones are dropped on a phone)
    ("rank", "#", "c-rank"), ("id", "Actuator", "c-id"), ("description", "Description", "c-desc"),
    ("last", "Last inspection", "c-last"), ("verdict", "Verdict", "c-verdict"),
    ("worst", "Nearest its threshold", "c-worst"), ("rul", "RUL median (interval)", "c-rul"),
    ("trend", "Trend", "c-trend"), ("n", "Inspections", "c-n"))


def _index_html(rows: list[dict], statuses: list[ActuatorStatus], *, title: str, source: str,
                thresholds: FailureThresholds, seed: int, level: float) -> str:
    from .. import __version__

    counts: dict[str, int] = {}
    for s in statuses:
        counts[s.rul_state] = counts.get(s.rul_state, 0) + 1
    n_ins = sum(s.n_inspections for s in statuses)
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    head = "".join(
        f"<th scope=\"col\" class=\"{cls}\" data-key=\"{key}\">"
        f"<button type=\"button\" data-key=\"{key}\">{esc(label)}</button></th>"
        for key, label, cls in _COLUMNS)
    body = []
    for row, s in zip(rows, statuses):
        unit = s.actuator.time_unit
        last = "\u2013" if s.last_time is None else (
            f"{esc(_fmt_time(s.last_time, unit))}<small>{esc(_date(s.last_recorded_utc))}</small>")
        cells = {
            "rank": str(row["rank"]),
            "id": f"<a href=\"{esc(row['page'])}\">{esc(s.id)}</a>",
            "description": esc(s.actuator.description) or "<span class=\"muted\">\u2013</span>",
            "last": last, "verdict": _verdict_badge(s.verdict, s.faults),
            "worst": _worst_cell(s), "rul": _rul_cell(s), "trend": _trend_cell(s),
            "n": str(s.n_inspections)}
        state = s.rul_state.replace(" ", "-")
        body.append(f"<tr data-i=\"{row['rank'] - 1}\" class=\"s-{esc(state)}\">" + "".join(
            f"<td class=\"{cls}\" data-label=\"{esc(label)}\"><div>{cells[key]}</div></td>"
            for key, label, cls in _COLUMNS) + "</tr>")
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
    data = {"actuators": rows}
    return (
        _head(title, "") +
        "<body class=\"index\">\n<header class=\"top\">\n"
        f"<h1>{esc(title)}</h1>\n"
        f"<p class=\"meta\">{len(statuses)} actuators \u00b7 {n_ins} inspections \u00b7 "
        f"history <code>{esc(source)}</code> \u00b7 built {esc(now)} by emaphm "
        f"{esc(__version__)}</p>\n"
        f"<p class=\"summary\">{summary}</p>\n</header>\n<main>\n"
        "<form class=\"controls\" id=\"controls\" role=\"search\" autocomplete=\"off\">\n"
        "<label>Filter <input type=\"search\" id=\"filter\" "
        "placeholder=\"id, description, fault\u2026\"></label>\n"
        f"<label>Show <select id=\"show\">{options}</select></label>\n"
        f"<label>Sort <select id=\"sort\"><option value=\"rank\">attention (RUL)</option>"
        f"{sort_options}</select></label>\n"
        f"<output id=\"shown\" aria-live=\"polite\">{len(rows)} of {len(rows)} shown</output>\n"
        "</form>\n"
        "<table id=\"fleet\" class=\"fleet\">\n"
        f"<caption>Actuators needing attention first: past a failure threshold, then the "
        f"shortest median remaining useful life (RUL, {level:.0%} interval below it).</caption>\n"
        f"<thead><tr>{head}</tr></thead>\n<tbody>\n" + "\n".join(body) + "\n</tbody>\n</table>\n"
        "<p class=\"empty\" id=\"empty\" hidden>No actuator matches the filter.</p>\n"
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
        "<li><b>Trend</b>: the sign of the fitted growth rate of that indicator at the last "
        "inspection (\u2192 when within two standard errors of zero).</li>\n"
        f"<li>Failure thresholds: {esc(thr)}.</li>\n</ul></section>\n</main>\n"
        f"<script type=\"application/json\" id=\"fleet-data\">{script_json(data)}</script>\n"
        "</body>\n</html>\n")


def _dl(items: Sequence[tuple[str, str]]) -> str:
    return "<dl class=\"facts\">" + "".join(f"<div><dt>{esc(k)}</dt><dd>{v}</dd></div>"
                                            for k, v in items) + "</dl>"


def _prognosis_table(s: ActuatorStatus) -> str:
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


def _actuator_html(s: ActuatorStatus, figures: dict, records: Sequence[Any], *, rank: int,
                   total: int, fleet_title: str) -> str:
    a = s.actuator
    unit = a.time_unit
    facts = [
        ("Verdict (last inspection)", _verdict_badge(s.verdict, s.faults)),
        ("Nearest its threshold", _worst_cell(s)),
        ("RUL median (interval)", _rul_cell(s)),
        ("Trend", _trend_cell(s)),
        ("Inspections", f"{s.n_inspections}" + (
            f"<small>last at {esc(_fmt_time(s.last_time, unit))}, "
            f"{esc(_date(s.last_recorded_utc))} UTC</small>" if s.last_time is not None else "")),
        ("Time unit", "flight hours (h)" if unit == "h" else esc(unit)),
        ("Registered", esc(_date(a.created_utc)) + " UTC"),
        ("Attention rank", f"{rank} of {total}"),
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


# ----------------------------------------------------------------------------- the build
def _out_folder(out: str | os.PathLike[str]) -> Path:
    p = Path(out)
    if p.exists() and not p.is_dir():
        raise ValueError(f"--out {p} is a file, not a folder; give a folder for the site")
    try:
        (p / "actuators").mkdir(parents=True, exist_ok=True)
        (p / "assets").mkdir(exist_ok=True)
    except OSError as exc:
        raise ValueError(f"cannot create the site folder {p} ({exc.strerror}); give a folder "
                         "you can write to") from None
    return p


def _read(history: Any, actuators: Sequence[str] | None) -> tuple[list, dict, str]:
    from ..prognosis.history import HealthHistory

    own = not isinstance(history, HealthHistory)
    h = HealthHistory(history, readonly=True) if own else history
    try:
        ids = list(actuators) if actuators else [a.id for a in h.actuators()]
        if not ids:
            raise ValueError(f"the health history {h.path} has no actuators; register them "
                             f"first (emaphm history register ID --db {h.path})")
        datas = [h.data(i) for i in dict.fromkeys(ids)]
        records = {d.actuator.id: h.calibrations(d.actuator.id) for d in datas}
        return datas, records, h.path.name
    finally:
        if own:
            h.close()


def build_site(history: Any, out: str | os.PathLike[str], *,
               actuators: Sequence[str] | None = None,
               thresholds: FailureThresholds = DEFAULT_FAILURE_THRESHOLDS, seed: int = 0,
               level: float = 0.9, workers: int | None = None, title: str = "Fleet health",
               redraw: bool = False,
               progress: Callable[[str], None] | None = None) -> FleetSite:
    """Write the fleet health site of ``history`` (a path or an open
    :class:`~emaphm.prognosis.HealthHistory`) into the folder ``out`` (created if missing).

    ``actuators`` limits it to those ids (default: all); ``thresholds``, ``seed`` and
    ``level`` go to :func:`emaphm.prognosis.prognose`; ``workers`` processes draw the
    figures (default every core, 0 or 1: in this process); figures still up to date in
    ``out`` are kept unless ``redraw`` (module docstring); ``progress`` is called with a
    short line per actuator done.
    """
    seed = check_seed(seed)
    if not 0.0 < level < 1.0:
        raise ValueError(f"level must be in (0, 1), e.g. 0.9, got {level!r}")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers < 0):
        raise ValueError(f"workers must be a non-negative integer, got {workers!r}")
    t0 = time.perf_counter()
    datas, records, source = _read(history, actuators)
    folder = _out_folder(out)
    stems = {d.actuator.id: page_stem(d.actuator.id) for d in datas}
    if len(set(stems.values())) != len(stems):          # a 40-bit hash prefix collided
        stems = {i: page_stem(i, digits=64) for i in stems}
    n_workers = (os.cpu_count() or 1) if workers is None else workers
    figdir = folder / "actuators"
    code = _code_fingerprint()
    known = _read_manifest(figdir)             # kept for the actuators not built this time
    manifest = {} if redraw else known
    jobs = []
    for d in datas:
        stem = stems[d.actuator.id]
        key = _figure_key(d, thresholds, seed, level, code)
        jobs.append(_Job(data=d, thresholds=thresholds, seed=seed, level=level,
                         folder=str(figdir), stem=stem, key=key,
                         reuse=_reusable(manifest.get(stem), key, figdir)))
    results = _run(jobs, n_workers, progress)
    figures = {s.id: f for s, f in results}
    if not actuators:                 # the whole history: pages of others are not its own
        _remove_others(figdir, known, {j.stem for j in jobs})
    known.update({j.stem: {"key": j.key, "figures": figures[j.data.actuator.id]} for j in jobs})
    atomic_write_text(figdir / _MANIFEST, json.dumps(known, indent=1, sort_keys=True) + "\n")
    n_draw = sum(j.reuse is None for j in jobs)
    statuses = order_fleet(s for s, _ in results)
    for name in ASSETS:
        payload = resources.files("emaphm.fleet").joinpath("assets", name).read_bytes()
        atomic_write(folder / "assets" / name, lambda fh, b=payload: fh.write(b))
    pages = {}
    for rank, s in enumerate(statuses, start=1):
        page = folder / "actuators" / f"{stems[s.id]}.html"
        atomic_write_text(page, _actuator_html(s, figures[s.id], records[s.id], rank=rank,
                                               total=len(statuses), fleet_title=title))
        pages[s.id] = page
    rows = [_row(s, rank, f"actuators/{stems[s.id]}.html")
            for rank, s in enumerate(statuses, start=1)]
    meta = {"title": title, "history": source, "seed": seed, "level": level,
            "thresholds": thresholds.to_dict(), "indicators": list(INDICATORS)}
    atomic_write_text(folder / "fleet.json",
                      json.dumps({**meta, "actuators": rows}, indent=1, allow_nan=False) + "\n")
    index = folder / "index.html"
    atomic_write_text(index, _index_html(rows, statuses, title=title, source=source,
                                         thresholds=thresholds, seed=seed, level=level))
    return FleetSite(out=folder, index=index, pages=pages, statuses=tuple(statuses),
                     elapsed_s=time.perf_counter() - t0, drawn=n_draw,
                     workers=min(n_workers, len(jobs)) if n_workers > 1 and n_draw > 1 else 0)
