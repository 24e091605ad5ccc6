"""What tells the fleet site that a page is up to date: the digest of everything an
actuator's page is made from (its stored records, the build's settings, the code of the
modules that shape a page: :data:`_PAGE_CODE`), the manifest an earlier build left
(``actuators/.figures.json``) and the index's key. :mod:`emaphm.fleet.site` decides with
them what to make again."""

from __future__ import annotations

import hashlib
import json
import os
import stat
from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence

from .. import modes as _modes

if TYPE_CHECKING:  # pragma: no cover - annotations only
    from .._files import StagedWrites


#: Pixels per inch of the figures on the pages: their size is the reference plots' size in
#: inches (:mod:`emaphm.prognosis.plots`) at this scale.
FIGURE_DPI = 100


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
              "emaphm.fleet.pages", "emaphm.fleet.cache",
              # the vocabulary: each indicator's label, threshold and reading
              "emaphm.modes", "emaphm.modes.base",
              *sorted({m.read.__module__ for m in _modes.MODES.values()}))


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


def _remove_others(folder: Path, known: dict, keep: set[str], staging: "StagedWrites") -> int:
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


def _read_key(path: Path) -> str | None:
    try:
        return path.read_text(encoding="ascii").strip() if path.is_file() else None
    except (OSError, ValueError):
        return None
