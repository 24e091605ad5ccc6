"""The fleet health site: a static HTML report of every actuator of a health history.

:func:`build_site` writes, into a folder::

    index.html                  one row per actuator, units needing attention first,
                                sortable and filterable (assets/fleet.js); the first
                                :data:`PAGE_ROWS` rows are in the page itself, and every row
                                is inline as JSON (with its table row as HTML), which the
                                script sorts, filters and shows a page at a time
    fleet.json                  the same rows for programs
    assets/fleet.css, fleet.js  shipped with emaphm: no CDN, works offline and from file://
    actuators/STEM.html         a page per actuator: state, RUL per indicator, figures,
                                calibration, inspections
    actuators/STEM-history.svg  the components of k that moved, as
                                :func:`emaphm.prognosis.plots.plot_history` draws them
    actuators/STEM-prognosis.svg  trend, cone and RUL as :func:`~emaphm.prognosis.plots.
                                plot_prognosis` draws them (from three inspections on);
                                both written as SVG by :mod:`emaphm.fleet.figures` (the
                                browser draws them)

``STEM`` is :func:`emaphm.fleet.markup.page_stem` of the id (a slug and a hash), safe for
any id. Every value from the store is escaped (:mod:`emaphm.fleet.markup`). The figures
are only read from the history and its prognosis: nothing is identified or simulated again.

An actuator's page and figures depend on that actuator alone (its inspections,
calibrations and registration) and on the build's settings (thresholds, seed, level,
title, the inspection policy of the "Inspect by" column, and the version of emaphm and
the code of the modules that shape a page): ``actuators/.figures.json`` keeps, per page stem, the SHA-256 of all of it, the
sizes of the files it made, and its row of the index. A rebuild into the same folder
reads every actuator's stored records in one pass without decoding them, hashes them and
stats each actuator's files: one whose digest and files are unchanged costs nothing more;
the others are read from the history, assessed (the prognosis), drawn and written again.
The index and ``fleet.json`` are written again only when a row, the order or the settings
changed (``actuators/.index-key``); ``redraw=True`` makes every page again.
A build of the whole history removes the pages and figures of actuators an earlier build
into the folder wrote that the history no longer has; a build of some ``actuators`` keeps
the others'.

The folder is new, one a build wrote before (its ``actuators/.figures.json``, written
first of all, marks it), or one that holds none of the names a build writes
(:func:`check_site_folder`; its other files are left alone), so a site never overwrites an
``index.html`` it did not write.

The "Inspect by" column is the next inspection of each actuator at the build's
``policy`` (:class:`~emaphm.prognosis.inspection.InspectionPolicy`; default
:data:`~emaphm.fleet.status.FLEET_POLICY`), as ``emaphm fleet schedule`` plans it with the
same options; the index and the pages say the risk. Its times are shown rounded down
(:func:`~emaphm.fleet.markup.fmt_deadline`) with the operating time left until them,
and the column sorts as the schedule does: due now first, then per time unit the time
left, soonest first, ties by id.

The pages are made in ``workers`` processes (default: every core), or on a Dask cluster
(``executor``: :class:`emaphm.campaign.DaskExecutor`), a few actuators per task; a task
returns the bytes of its files, which this process writes (a cluster need not share the
folder). The result does not depend on where they were made. Every file a build writes
(pages, figures, the manifest, the assets, the index and ``fleet.json``) is first written
whole beside its place under a temporary name; once all are written they are flushed to
disk together and renamed into place, pages first and the index last. A build that fails
before (a full disk, a crash) removes its temporary files and leaves the site as it was,
never half new and half old; an interrupted rename leaves every file whole, and never an
index that links to a missing page, nor a manifest that vouches for a file not on disk.
A rebuild repairs what it finds damaged: an index or ``fleet.json`` emptied, edited or
replaced by a link (their SHA-256 are kept with the index key), a page or figure of
another size, or a link in its place, an asset that differs; a link in the place of
``assets/`` is replaced by a folder, one in the place of ``actuators/`` refused: a build
writes nothing outside its folder.

Only the worker's part imports the prognosis (SciPy); no part imports matplotlib: a
rebuild in which nothing changed imports neither.
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import json
import math
import os
import secrets
import stat
import time
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Iterable, Iterator, Sequence

from .. import modes as _modes
from .._files import atomic_write_text
from .._text import utf8_text
from ..prognosis.thresholds import DEFAULT_FAILURE_THRESHOLDS, INDICATORS, FailureThresholds
from ..seeds import check_seed
from .markup import esc, fmt_deadline, page_stem, schedule_key, script_json, unit_rank

if TYPE_CHECKING:  # pragma: no cover - .status imports the prognosis (SciPy): see _render
    from ..prognosis.inspection import InspectionPolicy
    from .status import ActuatorStatus

__all__ = ["FleetSite", "build_site", "check_site_folder", "ASSETS", "FIGURE_DPI", "PAGE_ROWS"]

#: The files shipped in ``emaphm/fleet/assets`` and copied to ``OUT/assets``.
ASSETS = ("fleet.css", "fleet.js")

#: Pixels per inch of the figures on the pages: their size is the reference plots' size in
#: inches (:mod:`emaphm.prognosis.plots`) at this scale.
FIGURE_DPI = 100

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


@dataclass(frozen=True)
class FleetSite:
    """What :func:`build_site` wrote: ``index`` and a page per actuator id (``pages``),
    the wall-clock seconds it took, the worker processes it started (0: none, the pages
    were made in this process or on a Dask cluster), for how many actuators it made the
    page and drew the figures (``drawn``; the others' were up to date) and how many files
    it wrote (``written``: pages, figures, the index, ``fleet.json``, assets; 0 when
    nothing changed).

    ``rows`` are the index's rows in its order (as in ``fleet.json``); ``skipped`` the
    ``(Actuator, SkippedInspection tuple)`` of each actuator with stored inspections the
    analyses leave out. ``statuses`` holds the :class:`~emaphm.fleet.status.ActuatorStatus`
    of the actuators assessed in this process (``workers=0``) in the index's order; pages
    made by worker processes or a cluster return only their rows (a status with its
    prognosis' draws is about half a megabyte)."""

    out: Path
    index: Path
    pages: dict
    statuses: tuple = field(repr=False)
    elapsed_s: float = 0.0
    workers: int = 0
    drawn: int = 0
    rows: tuple = field(repr=False, default=())
    skipped: tuple = field(repr=False, default=())
    written: int = 0


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
    """Everything one actuator's page is made from, picklable: a worker process, or a Dask
    worker on another machine, makes it without the history or the site folder."""

    data: Any
    records: tuple
    thresholds: FailureThresholds
    seed: int
    level: float
    title: str
    stem: str
    key: str
    policy: Any = None             # InspectionPolicy; None: FLEET_POLICY


#: What an earlier build made, per page stem (module docstring).
_MANIFEST = ".figures.json"

#: The digest of everything the index was last written from.
_INDEX_KEY = ".index-key"

#: The modules whose code shapes a page or a figure: a change in any of them makes every
#: page again.
_PAGE_CODE = ("emaphm.plots", "emaphm.faults", "emaphm.prognosis.history",
              "emaphm.prognosis.plots", "emaphm.prognosis.trends", "emaphm.prognosis.shapes",
              "emaphm.prognosis.fits", "emaphm.prognosis.predictor", "emaphm.prognosis.states",
              "emaphm.prognosis.choices",
              "emaphm.prognosis.thresholds", "emaphm.prognosis.inspection",
              "emaphm.fleet.status", "emaphm.fleet.site",
              "emaphm.fleet.markup", "emaphm.fleet.figures", "emaphm.fleet.svgplot",
              # the vocabulary: each indicator's label, threshold and reading
              "emaphm.modes", "emaphm.modes.base",
              *sorted({m.read.__module__ for m in _modes.MODES.values()}))

#: Most actuators in one task of a worker process or a Dask worker.
_BATCH_MAX = 16


def _code_fingerprint() -> str:
    import importlib.util

    from .. import __version__

    h = hashlib.sha256(f"emaphm {__version__} px per inch {FIGURE_DPI} svg".encode())
    for name in _PAGE_CODE:
        spec = importlib.util.find_spec(name)
        if spec is not None and spec.origin and os.path.exists(spec.origin):
            h.update(Path(spec.origin).read_bytes())
    return h.hexdigest()


def _plain(o: Any) -> Any:
    return getattr(o, "tolist", str)(o)


def _digest(obj: Any) -> str:
    text = json.dumps(obj, sort_keys=True, default=_plain)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def _actuator_key(data: Any, records: Sequence[Any], settings: str) -> str:
    """SHA-256 of everything an actuator's page, figures and row are made from: its
    registration, inspections (those left out too), calibrations, and the ``settings``
    digest of the build."""
    return _digest({
        "settings": settings, "actuator": data.actuator.to_dict(),
        "inspections": [i.to_dict() for i in data.inspections],
        "skipped": [s.to_dict() for s in data.skipped],
        "calibrations": [[r.time, list(r.sources), r.recorded_utc, r.params.to_dict()]
                         for r in records]})


def _read_manifest(folder: Path) -> dict:
    if not (folder / _MANIFEST).is_file():     # a FIFO or a device there would never end
        return {}
    try:
        data = json.loads((folder / _MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def _reusable(entry: Any, key: str, folder: Path) -> bool:
    """Whether an earlier build made this actuator's page from the same inputs and its
    files are all still there, as large as they were written (a stat each)."""
    if not isinstance(entry, dict) or entry.get("key") != key:
        return False
    files = entry.get("files")
    if not (isinstance(files, dict) and files and isinstance(entry.get("row"), dict)
            and isinstance(entry.get("cells"), dict) and isinstance(entry.get("order"), list)
            and isinstance(entry.get("figures"), dict)):
        return False
    for name, size in files.items():
        if not isinstance(name, str) or Path(name).name != name:
            return False
        try:
            st = os.lstat(folder / name)            # a link in its place is not the page
        except (OSError, ValueError):
            return False
        if not stat.S_ISREG(st.st_mode) or st.st_size != size:
            return False
    return True


def _remove_others(folder: Path, known: dict, keep: set[str], staging: "_Staging") -> int:
    """Remove from ``folder`` (and from the manifest ``known``) the page and figures of
    every actuator an earlier build wrote that is not in ``keep``: a site rebuilt from a
    history without them must not keep serving their pages. Only the files a build
    names after a manifest stem are removed (when ``staging`` commits). Returns how many
    actuators were removed."""
    gone = [s for s in known if s not in keep]
    for stem in gone:
        del known[stem]
        if Path(stem).name != stem:             # a stem is a plain name (page_stem)
            continue
        for name in (f"{stem}.html", *_figure_names(stem)):
            staging.remove(folder / name)
    return len(gone)


def _figure_names(stem: str) -> tuple[str, str]:
    return f"{stem}-history.svg", f"{stem}-prognosis.svg"


def _render(job: _Job, keep: bool = False) -> dict:
    """One actuator's status, page, figures and index row: the whole task of a worker.
    The files come back as bytes (name -> bytes) for the caller to write; ``keep`` keeps
    the :class:`ActuatorStatus` too (in this process only: it is half a megabyte)."""
    from .status import FLEET_POLICY, assess, attention_key

    status = assess(job.data, thresholds=job.thresholds, seed=job.seed, level=job.level,
                    policy=FLEET_POLICY if job.policy is None else job.policy)
    files, figures = _draw(status, job.data, job.thresholds, job.stem)
    page = f"{job.stem}.html"
    files[page] = _actuator_html(status, figures, job.records,
                                 fleet_title=job.title).encode("utf-8")
    return {"id": status.id, "stem": job.stem, "key": job.key,
            "row": _row(status, 0, f"actuators/{page}"),
            "cells": _cells(status, f"actuators/{page}"),
            "order": list(attention_key(status)), "figures": figures, "files": files,
            "skipped": [x.to_dict() for x in job.data.skipped],
            "status": status if keep else None}


def _render_batch(jobs: Sequence[_Job]) -> list[dict]:
    """:func:`_render` of a few actuators: one task of a worker process or a Dask worker."""
    return [_render(job) for job in jobs]


def _draw(status: "ActuatorStatus", data: Any, thresholds: FailureThresholds,
          stem: str) -> tuple[dict, dict]:
    """The figures of one actuator as SVG bytes (name -> bytes) and as the page shows them
    (``history``/``prognosis`` -> (name, width, height) in pixels), written by
    :class:`~emaphm.fleet.figures.PageFigures`."""
    from ..prognosis.plots import MOVED_SHARE, interesting_indicators, moved_components
    from ..prognosis.thresholds import INDICATOR_COMPONENT
    from .figures import PageFigures

    draw = PageFigures(px_per_inch=FIGURE_DPI)
    files: dict[str, bytes] = {}
    figures: dict[str, tuple] = {}
    hist_name, prog_name = _figure_names(stem)
    if status.n_inspections:
        # the components that moved (and the worst): a panel per flat line of a healthy
        # component cost most of a fresh site's drawing time
        always = [INDICATOR_COMPONENT[status.worst]] if status.worst in INDICATOR_COMPONENT else []
        shown = moved_components(data, thresholds, always)
        hidden = 8 - len(shown)
        svg, w, h = draw.history(data, components=shown, thresholds=thresholds, note=(
            f"; {hidden} other components not shown (each stayed below {MOVED_SHARE:.0%} of "
            "its threshold)" if hidden else ""))
        files[hist_name], figures["history"] = svg, (hist_name, w, h)
    prog = status.prognosis
    if prog is not None:                      # the worst, and up to two more that grow
        span = float(prog.times[-1] - prog.times[0])
        names = [status.worst] + [n for n in interesting_indicators(prog) if n != status.worst
                                  and not prog.predictions[n].no_growth(span)]
        svg, w, h = draw.prognosis(prog, indicators=names[:3])
        files[prog_name], figures["prognosis"] = svg, (prog_name, w, h)
    return files, figures


class _LocalPool:
    """Worker processes on this machine, spawned (they start clean, whatever this process
    holds, as the campaign's do), with the ``map_unordered`` of
    :mod:`emaphm.campaign.executors`. Unlike the campaign's pool they load no model
    kernels: drawing needs none."""

    def __init__(self, workers: int) -> None:
        self.workers = workers

    def map_unordered(self, fn: Callable[[Any], Any],
                      items: Iterable[Any]) -> Iterator[tuple[Any, Any]]:
        import multiprocessing
        from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

        items = list(items)
        if not items:
            return
        pool = ProcessPoolExecutor(max_workers=min(self.workers, len(items)),
                                   mp_context=multiprocessing.get_context("spawn"))
        try:
            running = {pool.submit(fn, item): item for item in items}
            while running:
                done, _ = wait(running, return_when=FIRST_COMPLETED)
                for fut in done:
                    item = running.pop(fut)
                    try:
                        value = fut.result()
                    except Exception as exc:        # noqa: BLE001 - yielded as a value
                        value = exc
                    yield item, value
        finally:
            pool.shutdown(wait=True, cancel_futures=True)


def _batches(jobs: list[_Job], workers: int) -> list[list[_Job]]:
    """The jobs in tasks of a few actuators: about four tasks per worker, at most
    :data:`_BATCH_MAX` actuators each (a task per actuator would spend more on passing
    work around than a fleet's worth of pages)."""
    size = max(1, min(_BATCH_MAX, len(jobs) // (4 * max(workers, 1))))
    return [jobs[i:i + size] for i in range(0, len(jobs), size)]


def _run(jobs: list[_Job], executor: Any,
         progress: Callable[[str], None] | None) -> Iterator[dict]:
    """The :func:`_render` results of ``jobs`` as they are made: in this process without
    an ``executor``, else in its tasks (``map_unordered``)."""
    if executor is None:
        for i, job in enumerate(jobs):
            res = _render(job, keep=True)
            if progress:
                progress(f"{i + 1}/{len(jobs)} {res['id']}")
            yield res
        return
    done = 0
    batches = _batches(jobs, getattr(executor, "workers", None) or 8)
    for batch, value in executor.map_unordered(_render_batch, batches):
        if isinstance(value, BaseException):
            ids = ", ".join(j.data.actuator.id for j in batch[:3])
            raise RuntimeError(f"the pages of {ids}{', ...' if len(batch) > 3 else ''} could "
                               f"not be made ({type(value).__name__}: {value})") from value
        for res in value:
            done += 1
            yield res
        if progress and value:
            progress(f"{done}/{len(jobs)} {value[-1]['id']}")


class _Staging:
    """The files of a build, each written whole beside its place under a temporary name,
    then renamed into place all together (:meth:`commit`) once every one is written and
    flushed: a build that fails on the way (a full disk, a crash of the drawing) removes
    them (:meth:`discard`) and leaves the site as it was, never half new and half old.
    A rename needs no room on the disk, and replaces a link in the file's place (never
    writing through it)."""

    def __init__(self) -> None:
        self.moves: list[tuple[Path, Path]] = []
        self.removals: list[Path] = []

    def write(self, path: Path, payload: bytes) -> None:
        tmp = path.parent / f".{path.name}.{secrets.token_hex(6)}.tmp"
        try:
            with open(tmp, "xb") as fh:
                fh.write(payload)
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise
        self.moves.append((tmp, path))

    def remove(self, path: Path) -> None:
        self.removals.append(path)

    def commit(self) -> None:
        if self.moves:
            _sync([tmp for tmp, _ in self.moves])
        for tmp, path in self.moves:
            os.replace(tmp, path)
        self.moves = []
        for path in self.removals:
            path.unlink(missing_ok=True)

    def discard(self) -> None:
        for tmp, _ in self.moves:
            tmp.unlink(missing_ok=True)
        self.moves = []


def _sync(paths: Sequence[Path]) -> None:
    """Flush ``paths`` to disk: the whole system's buffers at once where the platform can
    (``os.sync``), else each file."""
    if hasattr(os, "sync"):
        os.sync()
        return
    for path in paths:                          # pragma: no cover - Windows
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_BINARY", 0))
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


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


# ----------------------------------------------------------------------------- the build
#: What a build writes at the top of its folder: anything else there is left alone.
_SITE_NAMES = ("index.html", "fleet.json", "assets", "actuators")


def check_site_folder(folder: str | os.PathLike[str]) -> None:
    """A ValueError unless ``folder`` may take the site: missing, a site an earlier build
    wrote (its manifest ``actuators/.figures.json``, or the index key of an older build,
    is there), or one that holds none of the names a build writes (:data:`_SITE_NAMES`:
    a fresh clone's ``.git`` or ``CNAME`` stays as it is). Someone else's ``index.html``,
    ``fleet.json``, ``assets/`` or ``actuators/`` would be overwritten."""
    p = Path(folder)
    if not p.exists():
        return
    if not p.is_dir():
        raise ValueError(f"--out {p} is a file, not a folder; give a folder for the site")
    if (p / "actuators").is_symlink():
        raise ValueError(f"--out {p}: its actuators/ is a link to {os.readlink(p / 'actuators')}; "
                         "a site writes only inside its folder: make actuators/ a folder (move "
                         "the pages there) or give another folder")
    if any((p / "actuators" / name).is_file() for name in (_MANIFEST, _INDEX_KEY)):
        return
    try:
        found = [name for name in _SITE_NAMES if os.path.lexists(p / name)]
    except OSError as exc:
        raise ValueError(f"--out {p}: cannot read the folder ({exc.strerror or exc}); give a "
                         "folder you can read and write") from None
    if found:
        raise ValueError(f"--out {p} holds {', '.join(found)}, not of an emaphm fleet site, "
                         "which the site would overwrite: give a new folder, one without "
                         "them, or the folder of an earlier emaphm fleet report")


def _out_folder(out: str | os.PathLike[str]) -> Path:
    """The site folder ``out``, its ``actuators/`` and ``assets/`` folders made; a link in
    the place of either is not followed out of the site: the assets' (emaphm's own
    files) is replaced by a folder, the pages' refused (:func:`check_site_folder`)."""
    p = Path(out)
    check_site_folder(p)
    pages = p / "actuators"
    try:
        if (p / "assets").is_symlink():
            (p / "assets").unlink()
        pages.mkdir(parents=True, exist_ok=True)
        (p / "assets").mkdir(exist_ok=True)
        if not (p / "actuators" / _MANIFEST).is_file():     # the folder is the site's now
            atomic_write_text(p / "actuators" / _MANIFEST, "{}\n")
    except OSError as exc:
        raise ValueError(f"cannot create the site folder {p} ({exc.strerror}); give a folder "
                         "you can write to") from None
    return p


def _actuators(h: Any, actuators: Sequence[str] | None) -> list:
    """The :class:`~emaphm.prognosis.history.Actuator` records to build (``actuators``:
    those ids, each checked; default all), refused before anything is written."""
    every = h.actuators()
    if actuators:
        by_id = {a.id: a for a in every}
        for i in actuators:
            if i not in by_id:
                h.actuator(i)                  # UnknownActuatorError, naming the registered
        every = [by_id[i] for i in dict.fromkeys(actuators)]
    if not every:
        raise ValueError(f"the health history {h.path} has no actuators; register them "
                         f"first (emaphm history register ID --db {h.path})")
    return every


def _skipped_of(entry: dict) -> tuple:
    """The :class:`~emaphm.prognosis.history.SkippedInspection` records a manifest entry
    noted (an unchanged actuator's, for the command's warning)."""
    from ..prognosis.history import SkippedInspection

    out = []
    for d in entry.get("skipped") or ():
        try:
            out.append(SkippedInspection.from_dict(d))
        except (TypeError, ValueError, KeyError):
            continue
    return tuple(out)


def build_site(history: Any, out: str | os.PathLike[str], *,
               actuators: Sequence[str] | None = None,
               thresholds: FailureThresholds = DEFAULT_FAILURE_THRESHOLDS, seed: int = 0,
               level: float = 0.9, workers: int | None = None, title: str = "Fleet health",
               redraw: bool = False, progress: Callable[[str], None] | None = None,
               executor: Any = None, policy: InspectionPolicy | None = None) -> FleetSite:
    """Write the fleet health site of ``history`` (a path or an open
    :class:`~emaphm.prognosis.HealthHistory`) into the folder ``out`` (created if missing).

    ``actuators`` limits it to those ids (default: all); ``thresholds``, ``seed`` and
    ``level`` go to :func:`emaphm.prognosis.prognose`; ``workers`` processes make the
    pages (default every core, 0 or 1: in this process), or ``executor``, any object with
    the ``map_unordered(fn, items)`` of :mod:`emaphm.campaign.executors` (a
    :class:`~emaphm.campaign.DaskExecutor` spreads them over a Dask cluster); the pages
    still up to date in ``out`` are kept unless ``redraw`` (module docstring);
    ``progress`` is called with a short line as pages are made. ``policy`` plans the
    "Inspect by" column (default :data:`~emaphm.fleet.status.FLEET_POLICY`, at
    :data:`~emaphm.prognosis.inspection.DEFAULT_RISK`); a change of it makes every page
    and row again. ``out`` must be new, a folder a build wrote before, or one without the
    names a build writes (:func:`check_site_folder`).
    """
    from ..prognosis.history import HealthHistory
    from ..prognosis.inspection import InspectionPolicy

    seed = check_seed(seed)
    if not 0.0 < level < 1.0:
        raise ValueError(f"level must be in (0, 1), e.g. 0.9, got {level!r}")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers < 0):
        raise ValueError(f"workers must be a non-negative integer, got {workers!r}")
    if executor is not None and not callable(getattr(executor, "map_unordered", None)):
        raise ValueError("executor must have a map_unordered(fn, items) method, e.g. "
                         "emaphm.campaign.DaskExecutor('tcp://HOST:8786')")
    if policy is None:
        policy = InspectionPolicy()            # FLEET_POLICY, without importing .status
    elif not isinstance(policy, InspectionPolicy):
        raise ValueError("policy must be an emaphm.prognosis.inspection.InspectionPolicy, "
                         f"e.g. InspectionPolicy(risk=0.05), got {policy!r}")
    t0 = time.perf_counter()
    # every option that changes a page or a row of the index: in both
    common = {"thresholds": thresholds, "seed": seed, "level": level, "title": title,
              "policy": policy}
    settings = {**common, "thresholds": thresholds.to_dict(), "policy": policy.to_dict(),
                "code": _code_fingerprint()}
    own = not isinstance(history, HealthHistory)
    h = HealthHistory(history, readonly=True) if own else history
    try:
        acts = _actuators(h, actuators)
        folder = _out_folder(out)
        figdir = folder / "actuators"
        known = _read_manifest(figdir)         # kept for the actuators not built this time
        stems, jobs, entries, skipped = _plan(h, acts, common, _digest(settings), known,
                                              figdir, redraw)
    finally:
        if own:
            h.close()
    n_workers = (os.cpu_count() or 1) if workers is None else workers
    pool = executor is None and n_workers > 1 and len(jobs) > 1
    staging = _Staging()
    try:
        made, statuses, written = _make(jobs, _LocalPool(n_workers) if pool else executor,
                                        figdir, progress, staging)
        entries.update(made)
        removed = 0 if actuators else _remove_others(figdir, known, set(stems.values()),
                                                     staging)
        if made or removed or not _regular(figdir / _MANIFEST):
            known.update({stems[i]: e for i, e in made.items()})
            staging.write(figdir / _MANIFEST, (json.dumps(
                known, sort_keys=True, separators=(",", ":")) + "\n").encode())
        order = sorted(entries, key=lambda i: tuple(entries[i]["order"]))  # attention_key
        places = _inspect_order([entries[i]["row"] for i in order])
        rows = [_ranked(entries[i]["row"], rank, places.get(i))
                for rank, i in enumerate(order, start=1)]
        written += _write_assets(folder, staging)
        written += _write_index(folder, rows, [entries[i]["cells"] for i in order],
                                [[stems[i], entries[i]["key"]] for i in order], settings,
                                staging, redraw=redraw, title=title,
                                source=utf8_text(h.path.name),
                                thresholds=thresholds, seed=seed, level=level, policy=policy)
        staging.commit()
    except OSError as exc:
        staging.discard()
        raise OSError(exc.errno, f"{exc.strerror or exc}; the site in {folder} was left as it "
                      "was", exc.filename) from None
    except BaseException:
        staging.discard()
        raise
    return FleetSite(out=folder, index=folder / "index.html",
                     pages={i: figdir / f"{stems[i]}.html" for i in order},
                     statuses=tuple(statuses[i] for i in order if i in statuses),
                     elapsed_s=time.perf_counter() - t0, drawn=len(jobs),
                     workers=min(n_workers, len(jobs)) if pool else 0, rows=tuple(rows),
                     skipped=tuple(skipped), written=written)


def _write_index(folder: Path, rows: list[dict], cells: list[dict], keys: list, settings: dict,
                 staging: _Staging, *, redraw: bool, title: str, source: str,
                 thresholds: FailureThresholds, seed: int, level: float,
                 policy: InspectionPolicy) -> int:
    """Stage ``index.html`` and ``fleet.json`` of ``rows`` (ranked, in order) unless what
    they were last written from (``keys``: page stem and key of each row, the settings) is
    the same and both are there as they were written (their SHA-256 in the key file:
    emptied, edited or replaced by a link, they are written again), or ``redraw``;
    returns the files written."""
    index = folder / "index.html"
    meta = {"title": title, "history": source, "seed": seed, "level": level,
            "thresholds": thresholds.to_dict(), "indicators": list(INDICATORS),
            "inspection_policy": policy.to_dict()}
    index_key = _digest({"settings": settings, "meta": meta, "page_rows": PAGE_ROWS,
                         "rows": keys})
    key_file = folder / "actuators" / _INDEX_KEY
    stored = _read_key(key_file)
    if not redraw and stored is not None and stored == _index_record(index_key, folder):
        return 0
    trs = [_tr(row, c) for row, c in zip(rows, cells)]
    # keys sorted: a row kept from the manifest (sorted there) and a row drawn now read alike
    payloads = {"fleet.json": (json.dumps({**meta, "actuators": rows}, indent=1, sort_keys=True,
                                          allow_nan=False) + "\n").encode(),
                "index.html": _index_html(rows, trs, title=title, source=source,
                                          thresholds=thresholds, seed=seed, level=level,
                                          policy=policy).encode()}
    for name, payload in payloads.items():
        staging.write(folder / name, payload)
    record = {"key": index_key, **{n: hashlib.sha256(b).hexdigest() for n, b in payloads.items()}}
    staging.write(key_file, (json.dumps(record, sort_keys=True) + "\n").encode())
    return 2


def _index_record(index_key: str, folder: Path) -> str | None:
    """What the key file holds when the index and ``fleet.json`` of ``index_key`` are there
    as written (regular files, their digests), else None."""
    digests = {}
    for name in ("fleet.json", "index.html"):
        path = folder / name
        if not _regular(path):
            return None
        try:
            digests[name] = hashlib.sha256(path.read_bytes()).hexdigest()
        except OSError:
            return None
    return json.dumps({"key": index_key, **digests}, sort_keys=True)


def _regular(path: Path) -> bool:
    """Whether ``path`` is a regular file itself (not a link to one)."""
    try:
        return stat.S_ISREG(os.lstat(path).st_mode)
    except OSError:
        return False


def _plan(h: Any, acts: list, common: dict, digest: str, known: dict, figdir: Path,
          redraw: bool) -> tuple[dict, list[_Job], dict, list]:
    """Page stems, the jobs (with the options ``common``) of the actuators whose page must
    be made, the manifest entries of those whose page is up to date, by id, and the
    ``(Actuator, skipped records)`` of those with records the analyses leave out; ``digest``
    is that of the build's settings. Only the actuators whose records changed are read
    from the history ``h`` (:meth:`~emaphm.prognosis.HealthHistory.record_digests`)."""
    stems = {a.id: page_stem(a.id) for a in acts}
    if len(set(stems.values())) != len(stems):          # a 40-bit hash prefix collided
        stems = {i: page_stem(i, digits=64) for i in stems}
    stored = h.record_digests()
    jobs, reused, skipped = [], {}, []
    for a in acts:
        entry, data = known.get(stems[a.id]), None
        if stored is not None:
            key = _digest([digest, stored.get(a.id, "")])
        else:                                  # the history read record by record
            data, recs = h.data(a.id), h.calibrations(a.id)
            key = _actuator_key(data, recs, digest)
        if not redraw and _reusable(entry, key, figdir):
            reused[a.id] = entry
            found = data.skipped if data is not None else _skipped_of(entry)
        else:
            if data is None:
                data, recs = h.data(a.id), h.calibrations(a.id)
            jobs.append(_Job(data=data, records=tuple(recs), stem=stems[a.id], key=key,
                             **common))
            found = data.skipped
        if found:
            skipped.append((a, tuple(found)))
    return stems, jobs, reused, skipped


def _make(jobs: list[_Job], executor: Any, figdir: Path,
          progress: Callable[[str], None] | None, staging: _Staging) -> tuple[dict, dict, int]:
    """Make the pages of ``jobs`` and stage their files as they come (``staging``); returns
    their manifest entries and kept statuses by id, and the files written."""
    made: dict[str, dict] = {}
    statuses: dict[str, Any] = {}
    written = 0
    for res in _run(jobs, executor, progress):
        for name, payload in res["files"].items():
            staging.write(figdir / name, payload)
            written += 1
        for name in _figure_names(res["stem"]):       # one it no longer has (fewer inspections)
            if name not in res["files"]:
                staging.remove(figdir / name)
        made[res["id"]] = {"key": res["key"], "figures": res["figures"], "row": res["row"],
                           "cells": res["cells"], "order": res["order"],
                           "skipped": res["skipped"],
                           "files": {n: len(b) for n, b in res["files"].items()}}
        if res["status"] is not None:
            statuses[res["id"]] = res["status"]
    return made, statuses, written


def _write_assets(folder: Path, staging: _Staging) -> int:
    """Stage the shipped assets where what is there differs (or is a link); returns how
    many."""
    n = 0
    for name in ASSETS:
        payload = resources.files("emaphm.fleet").joinpath("assets", name).read_bytes()
        path = folder / "assets" / name
        try:
            same = _regular(path) and path.read_bytes() == payload
        except OSError:
            same = False
        if not same:
            staging.write(path, payload)
            n += 1
    return n


def _read_key(path: Path) -> str | None:
    try:
        return path.read_text(encoding="ascii").strip() if path.is_file() else None
    except (OSError, ValueError):
        return None
