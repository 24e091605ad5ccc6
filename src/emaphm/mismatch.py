"""The mismatch check of version 0.3: it lives in :mod:`emaphm.verdict` now, with the
rest of the verdict's rules. This module keeps the old names for one release, with a
warning."""

from __future__ import annotations

import warnings
from typing import Any

from .params import ActuatorParams
from .problem import IdentificationProblem
from .traces import Trace
from .verdict import MISMATCH_NUISANCE, diagnose_identification, needs_mismatch_check
from . import verdict as _verdict

__all__ = ["MISMATCH_NUISANCE", "needs_mismatch_check", "mismatch_fit",
           "diagnose_identification"]

warnings.warn("emaphm.mismatch moved to emaphm.verdict; the old module goes in the next release",
              DeprecationWarning, stacklevel=2)


def mismatch_fit(trace: Trace, k: Any, *, seed: int, params: ActuatorParams | None = None,
                 fault_model: str | None = None, n_sub: int = 1, mode: str = "phases"):
    """:func:`emaphm.verdict.mismatch_fit` of the problem these arguments describe."""
    problem = IdentificationProblem(trace, params=params, fault_model=fault_model, n_sub=n_sub,
                                    mode=mode)
    return _verdict.mismatch_fit(problem, k, seed=seed)
