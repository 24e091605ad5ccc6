"""The mismatch check: is a fault read on data-sheet parameters a fault, or the unit?

No unit matches its data sheet: its inertia, magnet flux, winding resistance,
sensor gains and the load of its bench differ within their tolerances
(:data:`emaphm.units.DEFAULT_TOLERANCES`), and the monitoring model reads part of
that difference as a small fault (an unreported 0.02 N m load as dry friction
1.2x). :func:`emaphm.calibration.calibrate` removes the difference; on parameters
that were not calibrated, :func:`diagnose_identification` checks every verdict that
names a fault: it fits the trace again from the identified k with the deviations
a unit has most (:data:`MISMATCH_NUISANCE`) searched beside k, and keeps only the
faults that fit names too (:func:`emaphm.diagnosis.diagnose`, ``mismatch=``). When
it names none, the verdict is ``unexplained`` (reason ``"mismatch"``) with the hint
to calibrate. The refit starts at the identified k, so it fits at least as well;
it costs one least-squares run (about the identification's) and is made only for
verdicts that name a fault.
"""

from __future__ import annotations

from typing import Any

from .diagnosis import Diagnosis, MismatchFit, Thresholds, diagnose, fit_ratio_of
from .params import ActuatorParams
from .traces import Trace

__all__ = ["MISMATCH_NUISANCE", "needs_mismatch_check", "mismatch_fit",
           "diagnose_identification"]

#: What the mismatch check searches beside k: the winding resistance and magnet flux
#: (relative) and an unreported constant load (N m), within
#: :data:`emaphm.search.NUISANCE_RANGE`.
MISMATCH_NUISANCE = ("R", "flux", "load")


def needs_mismatch_check(params: ActuatorParams | None) -> bool:
    """Whether a fault read with ``params`` is checked against the unit's mismatch: for a
    data sheet (no ``[calibration]`` date; ``None`` is the preset), not for a calibrated
    unit, whose identification already searches its drift (:data:`emaphm.identify.DRIFT_NUISANCE`)."""
    return params is None or not params.calibration.date


def mismatch_fit(trace: Trace, k: Any, *, seed: int, params: ActuatorParams | None = None,
                 fault_model: str | None = None, n_sub: int = 1,
                 mode: str = "phases") -> MismatchFit:
    """Fit ``trace`` again from ``k`` with :data:`MISMATCH_NUISANCE` searched beside it
    (:func:`emaphm.identify.identify`, least squares, warm-started at ``k`` with the
    nuisance at zero, seeded by ``seed``)."""
    from .identify import identify     # local: the search stack is heavy to import

    ident = identify(trace, "lsq", seed=seed, params=params, fault_model=fault_model,
                     n_sub=n_sub, mode=mode, nuisance=MISMATCH_NUISANCE, start=k)
    return MismatchFit(k=ident.k, nuisance=dict(ident.nuisance), fit_ratio=fit_ratio_of(ident))


def diagnose_identification(trace: Trace, ident: Any, *, params: ActuatorParams | None = None,
                            thresholds: Thresholds | None = None, k: Any = None,
                            check: bool = True) -> Diagnosis:
    """The verdict of an identification of ``trace`` (:func:`emaphm.identify.identify`).

    :func:`emaphm.diagnosis.diagnose` of ``k`` (default ``ident.k``) with the fit's
    ratio to the noise floor; then, where it names a fault and ``params`` are a data
    sheet (:func:`needs_mismatch_check`) and ``check`` is true, the mismatch check
    (:func:`mismatch_fit`, seeded by ``ident.seed``, with the identification's fault
    model, sub-steps and fitness mode).
    """
    k = ident.k if k is None else k
    kw = dict(thresholds=thresholds, params=params, fault_model=ident.fault_model,
              fit_ratio=fit_ratio_of(ident))
    diag = diagnose(k, **kw)
    if not (check and diag.verdict == "faulty" and needs_mismatch_check(params)):
        return diag
    opts = getattr(ident, "options", None) or {}
    m = mismatch_fit(trace, k, seed=int(ident.seed or 0), params=params,
                     fault_model=ident.fault_model, n_sub=int(opts.get("n_sub", 1)),
                     mode=str(opts.get("mode", "phases")))
    return diagnose(k, mismatch=m, **kw)
