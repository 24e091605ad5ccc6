"""Run a campaign: every run of a spec not yet in the store, on an executor, committed
one by one as they finish.

:func:`run_campaign` is the entry point; :func:`execute_run` is the pure function the
workers call (one run = simulate the reference model's measured trace with the spec's
sensor noise and the run's noise seed, then identify it with the run's algorithm and
seed); :func:`replay` reruns one stored run alone.

Resuming is running again: the runs already stored as successes are skipped, failures
are retried, and since every run is a function of its :class:`~emaphm.campaign.spec.Run`
alone, an interrupted-then-resumed campaign holds exactly the results of an
uninterrupted one, whatever the executor and the number of workers.
"""

from __future__ import annotations

import functools
import os
import time
import traceback
from dataclasses import dataclass
from typing import Any

from ..progress import RunProgress
from .executors import make_executor, warm_up
from .spec import CampaignSpec, Run
from .store import CampaignStore, RunResult

__all__ = ["CampaignInterrupted", "CampaignSummary", "ProgressLine", "execute_run",
           "execute_registered",
           "replay", "run_campaign"]


# ----------------------------------------------------------------------------- one run


def execute_run(run: Run) -> RunResult:
    """Execute one run; never raises for a failing run (it returns a failure result).

    Deterministic: the same ``run`` gives the same :meth:`RunResult.outcome` in any
    process on the same platform and software.
    """
    try:
        warm_up()                               # outside the timing; no-op once warm
        from emaphm.identify import identify
        from emaphm.acquisition import Sensors
        from emaphm.params import ActuatorParams
        from emaphm.simulate import simulate

        params = ActuatorParams.from_dict(run.params, source="campaign params") if run.params else None
        t0 = time.perf_counter()
        trace = simulate(run.k_true, model="reference", params=params,
                         sensors=Sensors(current_noise=run.noise, current_lsb=run.adc_lsb),
                         seed=run.noise_seed,
                         fault_model=run.fault_model).with_meta(scenario=run.scenario)
        simulate_s = time.perf_counter() - t0
        ident = identify(trace, run.config, seed=run.seed, params=params)
        return RunResult.from_identification(run, ident, simulate_s)
    except Exception as exc:                    # noqa: BLE001 - a failure is a value
        text = "".join(traceback.format_exception(type(exc), exc, exc.__traceback__, limit=-6))
        return RunResult.failure(run, text.strip())


def execute_registered(plugins: dict[str, Any], run: Run) -> RunResult:
    """:func:`execute_run` in a process that may not know the spec's registered algorithms:
    ``plugins`` (name -> object, :func:`emaphm.optim.register`) are registered first."""
    from emaphm.optim import register

    for name, obj in plugins.items():
        register(name, obj, replace=True)
    return execute_run(run)


def _task(spec: CampaignSpec) -> Any:
    """What each run executes: :func:`execute_run`, with the registered algorithms the spec
    names sent along (the workers' registries are their own)."""
    from emaphm.optim import registered

    own = registered()
    plugins = {a.name: own[a.name] for a in spec.algorithms if a.name in own}
    return functools.partial(execute_registered, plugins) if plugins else execute_run


# ----------------------------------------------------------------------------- progress

#: The campaign's progress line (runs done / total, failures, elapsed, ETA): the shared
#: :class:`emaphm.progress.RunProgress`, under the name this module has always exported.
ProgressLine = RunProgress


# ----------------------------------------------------------------------------- campaign


@dataclass(frozen=True)
class CampaignSummary:
    """What :func:`run_campaign` did.

    ``total`` runs in the spec; ``skipped`` already stored as successes before this call;
    ``completed`` and ``failed`` in this call; ``missing`` not stored as successes
    afterwards (failures, or cancelled by an interruption); ``elapsed_s`` wall time.
    """

    store: str
    total: int
    skipped: int
    completed: int
    failed: int
    missing: int
    elapsed_s: float
    interrupted: bool = False

    @property
    def finished(self) -> bool:
        """Every run of the spec is stored as a success."""
        return self.missing == 0


class CampaignInterrupted(KeyboardInterrupt):
    """Ctrl-C stopped a campaign; the runs committed so far are kept. ``summary`` says
    how far it got."""

    def __init__(self, summary: CampaignSummary) -> None:
        super().__init__(f"campaign interrupted: {summary.total - summary.missing} of "
                         f"{summary.total} runs stored in {summary.store}")
        self.summary = summary


def run_campaign(spec: CampaignSpec | None, store: str | os.PathLike[str] | CampaignStore,
                 executor: Any = None, progress: Any = None, *,
                 allow_version_mix: bool = False) -> CampaignSummary:
    """Run every run of ``spec`` that ``store`` does not hold yet; commit each as it finishes.

    Parameters
    ----------
    spec
        The campaign; None resumes the store's own spec.
    store
        A store path (created if missing) or an open :class:`CampaignStore`. An existing
        store must have been created with the same spec (else :class:`SpecMismatchError`,
        nothing changed).
    executor
        Where runs execute (:mod:`emaphm.campaign.executors`); default a local process pool
        over all cores.
    progress
        An object with ``start(total, already, todo)``, ``update(result)`` and ``close()``,
        e.g. :class:`ProgressLine`; None for silence.
    allow_version_mix
        Let this emaphm add runs to a store holding runs of another version.

    Returns
    -------
    CampaignSummary

    Raises
    ------
    CampaignInterrupted
        On Ctrl-C (a ``KeyboardInterrupt``): nothing more is submitted, pending runs are
        cancelled, committed runs are kept; run again to resume.
    """
    own = not isinstance(store, CampaignStore)
    st = CampaignStore.open(store, spec) if own else store
    try:
        if spec is not None and not own and spec.hash != st.spec.hash:
            CampaignStore.open(st.path, spec).close()       # raises the mismatch error
        spec = st.spec
        runs = spec.runs_list()
        done = st.keys("ok")
        todo = [r for r in runs if r.key not in done]
        if todo:
            st.check_version(allow_version_mix)
        t0 = time.perf_counter()
        completed = failed = 0
        if progress is not None:
            progress.start(len(runs), len(runs) - len(todo), len(todo))
        executor = executor if executor is not None else make_executor()
        stream = executor.map_unordered(_task(spec), todo) if todo else iter(())
        interrupted = False
        try:
            for run, value in stream:
                result = value if isinstance(value, RunResult) else RunResult.failure(
                    run, f"{type(value).__name__}: {value}")
                st.commit(result)
                completed += result.ok
                failed += not result.ok
                if progress is not None:
                    progress.update(result)
        except KeyboardInterrupt:
            interrupted = True
        finally:
            close = getattr(stream, "close", None)
            if close is not None:
                close()
            if progress is not None:
                progress.close()
        missing = len(runs) - len(st.keys("ok") & {r.key for r in runs})
        summary = CampaignSummary(store=str(st.path), total=len(runs), skipped=len(runs) - len(todo),
                                  completed=completed, failed=failed, missing=missing,
                                  elapsed_s=time.perf_counter() - t0, interrupted=interrupted)
        if interrupted:
            raise CampaignInterrupted(summary)
        return summary
    finally:
        if own:
            st.close()


def replay(store: str | os.PathLike[str] | CampaignStore, key: str) -> tuple[RunResult | None, RunResult]:
    """Rerun the run ``key`` of a stored campaign alone, in this process.

    Returns ``(stored, fresh)``: the stored result (None if the run is not stored yet)
    and the new one. ``stored.outcome() == fresh.outcome()`` for a reproducible run.
    """
    own = not isinstance(store, CampaignStore)
    st = CampaignStore.open(store, readonly=True) if own else store
    try:
        run = st.spec.run(key)
        stored = st.result(key)
    finally:
        if own:
            st.close()
    return stored, execute_run(run)
