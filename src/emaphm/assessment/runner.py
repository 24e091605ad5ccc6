"""Run an assessment (:func:`assess`): check the actuator, tune its thresholds on tuning
units, diagnose the reported units, and write the results into a new folder at once.

The units' results are committed one by one to a store in a work folder beside the
output (``.NAME.assessing``), so that running the same command again after an
interruption (Ctrl-C, a kill, a lost worker) resumes: the units already stored are not
run again, and since every unit is a function of its task alone the resumed assessment
holds what an uninterrupted one would. The outputs are written into a temporary folder
and renamed to ``out`` when complete: ``out`` never holds half an assessment.
"""

from __future__ import annotations

import os
import secrets
import shutil
import time
from dataclasses import dataclass, replace
from pathlib import Path
from types import SimpleNamespace
from typing import Any, Callable

import numpy as np

from .spec import AssessmentError, AssessmentSpec
from .store import AssessmentStore
from .tasks import run_task

__all__ = ["assess", "check_tracking", "Outcome", "AssessmentIncomplete", "TRACKING_LIMIT",
           "work_folder"]

#: The largest RMS position error of the healthy nominal actuator on the diagnostic
#: profile, as a share of the profile's travel, of an actuator an assessment accepts.
#: Measured (noise-free plant): the preset 0.072, ema-270v-750w 0.059; an actuator whose
#: torque limit is 20x too low 0.17-0.61, whose proportional gain is 20x too low 0.36-0.39.
TRACKING_LIMIT = 0.15


def check_tracking(params: Any) -> dict[str, float]:
    """Simulate the healthy nominal actuator on the diagnostic profile (reference plant,
    no noise); refuse one that does not follow it (:data:`TRACKING_LIMIT`): a diagnosis
    compares currents along a motion the actuator must make."""
    from ..simulate import simulate

    tr = simulate(params=params)
    err = np.asarray(tr.theta_ref) - np.asarray(tr.theta_m)
    travel = float(np.ptp(tr.theta_ref))
    rms = float(np.sqrt(np.mean(err * err)))
    ratio = rms / travel if travel > 0 else float("inf")
    if not np.isfinite(rms):
        raise AssessmentError(
            "the actuator of --params does not track the diagnostic profile: the simulation of "
            "the healthy actuator diverged (its position is not a finite number); check its "
            "inertia, torque limit, bus voltage and controller gains ([motor] J_m and T_max, "
            "[inverter] V_dc, [controller]), e.g. from emaphm params --datasheet")
    if ratio > TRACKING_LIMIT:
        raise AssessmentError(
            f"the actuator of --params does not track the diagnostic profile: its RMS position "
            f"error is {rms:.3g} rad, {100 * ratio:.0f} % of the profile's {travel:.3g} rad "
            f"travel (an actuator that tracks stays under {100 * TRACKING_LIMIT:.0f} %); check "
            "its torque limit, bus voltage and controller gains ([motor] T_max, [inverter] "
            "V_dc, [controller]), e.g. from emaphm params --datasheet")
    return {"rms_error_rad": rms, "travel_rad": travel, "ratio": ratio}


def _lock(work: Path, out: Path):
    """An exclusive lock on the work folder ``work`` for this process (released when it
    ends, however), held until ``out`` is written: a second assessment into the same
    ``out`` is refused at once, not after all its work when the first has written ``out``
    (nor when it starts as the first writes ``out``)."""
    import fcntl

    try:
        fh = open(work / "lock", "a+b")
    except OSError as exc:                      # the folder went with a run that finished
        raise AssessmentError(f"--out {out}: cannot open the lock of its work folder {work} "
                              f"({exc.strerror or exc}); run the command again") from None
    try:
        fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        fh.close()
        raise AssessmentError(f"--out {out}: another emaphm assess is running into it (its units "
                              f"are in {work}); wait for it to finish, or give another "
                              "folder") from None
    return fh


def work_folder(out: Path) -> Path:
    """Where the units' results of an assessment into ``out`` are kept until it is done."""
    return out.parent / f".{out.name}.assessing"


class AssessmentIncomplete(RuntimeError):
    """Units failed (their errors are stored beside the output); the outputs were not
    written. Running the same assessment again retries them."""

    def __init__(self, failed: list[dict[str, Any]], work: Path) -> None:
        self.failed = failed
        self.work = work
        first = failed[0]["error"].strip().splitlines()[-1]
        super().__init__(f"{len(failed)} unit(s) failed (the first, {failed[0]['key']}: "
                         f"{first}); their results are kept in {work}: run the same command "
                         "again to retry them")


@dataclass(frozen=True)
class Outcome:
    """What :func:`assess` did: the ``summary`` (the dict of ``assessment.json``), the
    files written, the units run in this call and those already stored."""

    summary: dict[str, Any]
    paths: list[Path]
    ran: int
    resumed: int


def _run_phase(tasks: list, store: AssessmentStore, executor: Any, progress: Any) -> tuple[int, int]:
    done = {k for k, r in store.results(tasks[0].phase).items() if "error" not in r} if tasks else set()
    todo = [t for t in tasks if t.key not in done]
    if progress is not None:
        progress.start(len(tasks), len(tasks) - len(todo), len(todo))
    for task, result in executor.map_unordered(run_task, todo):
        if isinstance(result, BaseException):      # a lost worker, a broken pool: retried
            result = {"key": task.key, "phase": task.phase, "index": task.index,
                      "unit_seed": task.unit_seed, "cpu_s": 0.0,
                      "error": f"{type(result).__name__}: {result}"}
        store.put(result)
        if progress is not None:
            progress.update(SimpleNamespace(ok="error" not in result))
    return len(todo), len(tasks) - len(todo)


def _thresholds(spec: AssessmentSpec, tune_results: list[dict]) -> tuple[dict, dict]:
    """The thresholds the reported units are diagnosed with (as a calibrated unit reads
    them), and the tuning's account. Tuned from the defaults, whatever thresholds the
    parameters already carry (so that assessing an assessed file does not ratchet them);
    untuned, the parameters' own."""
    from dataclasses import asdict, replace

    from ..modes import THRESHOLDS_BY_FAULT_MODEL
    from .tuning import tune_thresholds

    base = THRESHOLDS_BY_FAULT_MODEL["physical"]
    if not spec.tune:
        return asdict(replace(base, **dict(spec.actuator().thresholds))), {}
    readings = [r["measures"] for u in tune_results for r in u.get("healthy", ())
                if r["measures"]]
    if not readings:
        raise AssessmentError("no tuning unit could be calibrated: the thresholds cannot be "
                              "tuned (see the store's errors); check the tolerances")
    crosstalk = [(r["mode"], r["measures"]) for u in tune_results
                 for r in u.get("crosstalk", ()) if r["measures"]]
    tuned = tune_thresholds(readings, spec.target_far, base, crosstalk)
    return {n: t.value for n, t in tuned.items()}, tuned


def assess(spec: AssessmentSpec, out: str | os.PathLike[str], *, executor: Any = None,
           progress: Callable[[str], Any] | None = None) -> Outcome:
    """Assess the actuator of ``spec`` into the new folder ``out`` (see the module doc).

    ``executor``: an :mod:`emaphm.campaign.executors` executor (default in-process);
    ``progress``: ``progress(phase)`` -> a :class:`emaphm.progress.RunProgress`-like
    object for that phase (``start``, ``update``, ``close``), or None.
    """
    from .. import __version__
    from ..campaign.executors import SerialExecutor
    from .report import summarize

    out = Path(out)
    if out.exists():
        raise AssessmentError(f"--out {out} exists; give a new folder (an assessment is written "
                              "whole, into a folder of its own)")
    executor = executor or SerialExecutor()
    t0 = time.perf_counter()
    tracking = check_tracking(spec.actuator())
    work = work_folder(out)
    try:
        work.mkdir(exist_ok=True)
    except OSError as exc:
        raise AssessmentError(f"--out {out}: cannot make its work folder {work} "
                              f"({exc.strerror or exc}); free some space or fix the folder's "
                              "permissions") from None
    with _lock(work, out):                     # held until --out is written and work gone
        if out.exists():                       # written by the run this one came after
            shutil.rmtree(work, ignore_errors=True)
            raise AssessmentError(f"--out {out} exists (another emaphm assess wrote it while "
                                  "this one started); give a new folder")
        with AssessmentStore.open(work / "units.sqlite", spec) as store:
            ran, resumed, values, tuned = _run_units(spec, store, executor, progress)
            tune_results = list(store.results("tune").values())
            assessed = list(store.results("assess").values())
        failed = [u for u in (*tune_results, *assessed) if "error" in u]
        if failed:
            raise AssessmentIncomplete(failed, work)
        summary = summarize(spec, tuned, values, tune_results, assessed,
                            wall_s=time.perf_counter() - t0, version=__version__, tracking=tracking)
        params = replace(spec.actuator(), thresholds=tuple(sorted(values.items())))
        paths = _write(out, work, summary, params)
        shutil.rmtree(work, ignore_errors=True)
    return Outcome(summary, [out / p.name for p in paths] + [out / "units.sqlite"], ran, resumed)


def _run_units(spec: AssessmentSpec, store: AssessmentStore, executor: Any,
               progress: Callable[[str], Any] | None) -> tuple[int, int, dict, dict]:
    """Run the units ``store`` lacks, the tuning's first: ``(ran, resumed, thresholds,
    the tuning's account)``."""
    ran = resumed = 0
    values: dict = {}
    tuned: dict = {}
    for phase in ("tune", "assess"):
        if phase == "tune" and not spec.tune:
            continue
        if phase == "assess":
            values, tuned = _thresholds(spec, list(store.results("tune").values()))
            tasks = [t.with_thresholds(values) for t in spec.tasks("assess")]
        else:
            tasks = spec.tasks("tune")
        bar = progress(phase) if progress is not None else None
        try:
            n_ran, n_old = _run_phase(tasks, store, executor, bar)
        finally:
            if bar is not None:
                bar.close()
        ran, resumed = ran + n_ran, resumed + n_old
    return ran, resumed, values, tuned


def _write(out: Path, work: Path, summary: dict, params: Any) -> list[Path]:
    """The assessment's files, written into a new folder beside ``out`` and renamed to it
    whole; a failure removes that folder and says every unit is kept in ``work``."""
    from ..params import save_params
    from .report import write_outputs

    tmp = out.parent / f".{out.name}.{secrets.token_hex(4)}.tmp"
    try:
        tmp.mkdir()
        paths = [save_params(params, tmp / "params.toml"), *write_outputs(summary, tmp)]
        shutil.copy2(work / "units.sqlite", tmp / "units.sqlite")
        os.replace(tmp, out)
    except OSError as exc:
        shutil.rmtree(tmp, ignore_errors=True)
        raise AssessmentError(f"--out {out}: cannot write the assessment ({exc.strerror or exc}); "
                              f"every unit is done and kept in {work}: free some space (or fix "
                              "the folder) and run the same command again to write it") from None
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return paths
