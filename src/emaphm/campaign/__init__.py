"""Campaigns: the paper's algorithm comparison (and variants) at scale, resumable,
local or on a Dask cluster, with tables and figures.

>>> from emaphm.campaign import paper_spec, run_campaign, write_report   # doctest: +SKIP
>>> spec = paper_spec(runs=10, master_seed=2023)                          # 330 runs
>>> run_campaign(spec, "results.sqlite")               # all cores; run again to resume
>>> write_report("results.sqlite", "report/")          # tables (Markdown, CSV), figures

=================  ===========================================================
module             role
=================  ===========================================================
spec               :class:`CampaignSpec` (TOML or code), runs and their seeds
store              :class:`CampaignStore`: one SQLite file, one row per run
runner             :func:`run_campaign`, :func:`execute_run`, :func:`replay`
executors          serial, local process pool, Dask (imported only there)
report             Tables 3 and 4 of the paper, per-magnitude tables, figures
cli                ``emaphm campaign`` and ``emaphm report``
=================  ===========================================================

See ``docs/campaigns.md``.
"""

from .executors import DaskExecutor, LocalExecutor, SerialExecutor, make_executor
from .report import write_report
from .runner import (CampaignInterrupted, CampaignSummary, ProgressLine, execute_run, replay,
                     run_campaign)
from .spec import (AlgorithmSpec, CampaignSpec, Run, ScenarioSpec, SpecError, available_algorithms,
                   paper_spec)
from .store import (CampaignStore, IncompatibleStoreError, RunResult, SpecMismatchError,
                    StoreError)

__all__ = [
    "AlgorithmSpec",
    "CampaignInterrupted",
    "CampaignSpec",
    "CampaignStore",
    "CampaignSummary",
    "DaskExecutor",
    "IncompatibleStoreError",
    "LocalExecutor",
    "ProgressLine",
    "Run",
    "RunResult",
    "ScenarioSpec",
    "SerialExecutor",
    "SpecError",
    "SpecMismatchError",
    "StoreError",
    "available_algorithms",
    "execute_run",
    "make_executor",
    "paper_spec",
    "replay",
    "run_campaign",
    "write_report",
]
