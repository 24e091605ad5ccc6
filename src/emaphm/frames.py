"""pandas for those who use it: the one place emaphm imports it (lazily), for
:meth:`emaphm.traces.Trace.to_pandas`, :meth:`~emaphm.traces.Trace.from_pandas`,
:meth:`emaphm.prognosis.history.HealthHistory.frame` and
:meth:`emaphm.campaign.CampaignStore.frame`. pandas is not a dependency of emaphm: install
it with ``pip install 'emaphm[pandas]'``."""

from __future__ import annotations

from collections.abc import Sequence
from types import ModuleType
from typing import Any

__all__ = ["require_pandas", "vector_columns"]


def require_pandas(what: str) -> ModuleType:
    """The pandas module, or a ModuleNotFoundError saying how to install it for ``what``."""
    try:
        import pandas
    except ImportError:
        raise ModuleNotFoundError(f"{what} needs pandas, which is not installed: pip install "
                                  "'emaphm[pandas]'", name="pandas") from None
    return pandas


def vector_columns(row: dict[str, Any], name: str, values: Sequence[float] | None,
                   labels: Sequence[str]) -> None:
    """Put ``values`` into ``row`` as one column per component, ``{name}_{label}`` (None
    values as NaN)."""
    for label, k in zip(labels, range(len(labels))):
        row[f"{name}_{label}"] = float("nan") if values is None else float(values[k])
