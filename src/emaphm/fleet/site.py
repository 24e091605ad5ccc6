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

import hashlib
import json
import os
import time
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Iterator, Sequence

from .._files import StagedWrites, atomic_write_text
from .._text import utf8_text
from ..campaign.executors import LocalExecutor
from ..prognosis.thresholds import DEFAULT_FAILURE_THRESHOLDS, INDICATORS, FailureThresholds
from ..seeds import check_seed
from .cache import (FIGURE_DPI, _INDEX_KEY, _MANIFEST, _actuator_key, _code_fingerprint,
                    _digest, _figure_names, _index_record, _read_key, _read_manifest,
                    _regular, _remove_others, _reusable, _skipped_of)
from . import pages as _pages
from .markup import page_stem
from .pages import (PAGE_ROWS, _actuator_html, _cells, _index_html, _inspect_order, _ranked,
                    _row, _tr)

if TYPE_CHECKING:  # pragma: no cover - .status imports the prognosis (SciPy): see _render
    from ..prognosis.inspection import InspectionPolicy
    from .status import ActuatorStatus

__all__ = ["FleetSite", "build_site", "check_site_folder", "ASSETS", "FIGURE_DPI", "PAGE_ROWS"]


#: The files shipped in ``emaphm/fleet/assets`` and copied to ``OUT/assets``.
ASSETS = ("fleet.css", "fleet.js")


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


#: Most actuators in one task of a worker process or a Dask worker.
_BATCH_MAX = 16


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
    staging = StagedWrites()
    try:
        made, statuses, written = _make(jobs, LocalExecutor(n_workers, warm=False) if pool
                                        else executor,
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
                 staging: StagedWrites, *, redraw: bool, title: str, source: str,
                 thresholds: FailureThresholds, seed: int, level: float,
                 policy: InspectionPolicy) -> int:
    """Stage ``index.html`` and ``fleet.json`` of ``rows`` (ranked, in order) unless what
    they were last written from (``keys``: page stem and key of each row, the settings) is
    the same and both are there as they were written (their SHA-256 in the key file:
    emptied, edited or replaced by a link, they are written again), or ``redraw``;
    returns the files written."""
    meta = {"title": title, "history": source, "seed": seed, "level": level,
            "thresholds": thresholds.to_dict(), "indicators": list(INDICATORS),
            "inspection_policy": policy.to_dict()}
    index_key = _digest({"settings": settings, "meta": meta, "page_rows": _pages.PAGE_ROWS,
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
          progress: Callable[[str], None] | None, staging: StagedWrites) -> tuple[dict, dict, int]:
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


def _write_assets(folder: Path, staging: StagedWrites) -> int:
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
