"""The verdict: healthy, faulty or unexplained, and the tests that decide it.

:func:`diagnose_identification` is the verdict of an identification, as ``emaphm
diagnose`` and the health history give it. :func:`diagnose` (implemented beside the
readings in :mod:`emaphm.diagnosis`, below the identification problem, which reads a k
with it) reads the faults of an identified ``k`` and applies the rules that keep a
reading from being a diagnosis:

* the **misfit test**: a fit whose ratio to the trace's noise floor is improbable for an
  actuator the model describes (:func:`emaphm.fitness.misfit_p_value`, below
  :data:`MISFIT_P`) is ``unexplained`` (reason ``"misfit"``);
* **balanced phases**: the same change on all three phases is a mismatch of flux,
  inertia or sensor gain between the unit and its parameters, not three shorts;
* the **mismatch check** (:func:`diagnose_identification`, on data-sheet parameters): no
  unit matches its data sheet (its inertia, magnet flux, winding resistance, sensor
  gains and the load of its bench differ within their tolerances,
  :data:`emaphm.units.DEFAULT_TOLERANCES`), and the monitoring model reads part of that
  difference as a small fault (an unreported 0.02 N m load as dry friction 1.2x).
  :func:`emaphm.calibration.calibrate` removes the difference; on parameters that were
  not calibrated, every verdict that names a fault is checked: the trace is fitted again
  from the identified k with the deviations a unit has most
  (:data:`MISMATCH_NUISANCE`) searched beside k, and only the faults that fit names too
  are kept. When it names none, the verdict is ``unexplained`` (reason ``"mismatch"``)
  with the hint to calibrate. The refit starts at the identified k, so it fits at least
  as well; it costs one least-squares run (about the identification's) and is made only
  for verdicts that name a fault.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from .diagnosis import Diagnosis, MismatchFit, Thresholds, diagnose, fit_ratio_of
from .fitness import (MIN_NOISE, MISFIT_LOG_MEAN, MISFIT_LOG_STD, MISFIT_P, misfit_limit,
                      misfit_p_value)
from .params import ActuatorParams
from .problem import IdentificationProblem
from .traces import Trace

__all__ = ["diagnose", "diagnose_identification", "mismatch_fit", "needs_mismatch_check",
           "MISMATCH_NUISANCE", "NOISELESS_NOTE", "MISFIT_LOG_MEAN", "MISFIT_LOG_STD", "MISFIT_P",
           "misfit_p_value", "misfit_limit", "fit_ratio_of"]

#: The note of a verdict on a trace without measurement noise (every phase's white-noise
#: level below :data:`emaphm.fitness.MIN_NOISE`, less than an ADC's quantisation): the
#: misfit test compares the fit with the noise, and there is none to compare with.
NOISELESS_NOTE = ("the trace carries no measurement noise (a simulation without sensors, or "
                  "post-processed currents): the misfit test, which compares the fit with the "
                  "noise, was not made, so a model that does not describe this actuator is not "
                  "caught; record the currents as measured (or simulate with --seed)")

#: What the mismatch check searches beside k: the winding resistance and magnet flux
#: (relative) and an unreported constant load (N m), within
#: :data:`emaphm.search.NUISANCE_RANGE`.
MISMATCH_NUISANCE = ("R", "flux", "load")


def needs_mismatch_check(params: ActuatorParams | None) -> bool:
    """Whether a fault read with ``params`` is checked against the unit's mismatch: for a
    data sheet (no ``[calibration]`` date; ``None`` is the preset), not for a calibrated
    unit, whose identification already searches its drift
    (:data:`emaphm.problem.DRIFT_NUISANCE`)."""
    return params is None or not params.calibration.date


def mismatch_fit(problem: IdentificationProblem, k: Any, *, seed: int) -> MismatchFit:
    """Fit the trace of ``problem`` again from ``k`` with :data:`MISMATCH_NUISANCE` searched
    beside it (least squares, warm-started at ``k`` with the nuisance at zero, seeded by
    ``seed``; the problem's parameters, fault model, sub-steps and fitness mode)."""
    from .identify import minimize     # local: the search stack is heavy to import

    refit = replace(problem, nuisance=MISMATCH_NUISANCE, start=k, search=None, objective=None)
    ident = minimize(refit, "lsq", seed=seed)
    return MismatchFit(k=ident.k, nuisance=dict(ident.nuisance), fit_ratio=fit_ratio_of(ident))


def diagnose_identification(trace: Trace | IdentificationProblem, ident: Any, *,
                            params: ActuatorParams | None = None,
                            thresholds: Thresholds | None = None, k: Any = None,
                            check: bool = True) -> Diagnosis:
    """The verdict of an identification (:func:`emaphm.identify.identify`) of a trace.

    :func:`diagnose` of ``k`` (default ``ident.k``) with the identification's fault model
    and the fit's ratio to the noise floor; then, where it names a fault and the
    parameters are a data sheet (:func:`needs_mismatch_check`) and ``check`` is true, the
    mismatch check (:func:`mismatch_fit`, seeded by ``ident.seed``). ``trace`` may be the
    identification's problem (its parameters, sub-steps and fitness mode are then the
    check's; ``params`` must not be given beside it), or the trace with the ``params``
    it was identified with.
    """
    if isinstance(trace, IdentificationProblem):
        if params is not None:
            raise ValueError("give params to the IdentificationProblem, not beside it")
        problem, params = trace, trace.params
    else:
        problem = None
    k = ident.k if k is None else k
    noiseless = 0.0 <= getattr(ident, "noise_sigma", np.inf) < MIN_NOISE
    kw = dict(thresholds=thresholds, params=params, fault_model=ident.fault_model,
              fit_ratio=None if noiseless else fit_ratio_of(ident))
    notes = (NOISELESS_NOTE,) if noiseless else ()
    diag = replace(diagnose(k, **kw), notes=notes)
    if not (check and diag.verdict == "faulty" and needs_mismatch_check(params)):
        return diag
    if problem is None:
        config = getattr(ident, "config", None)
        opts = getattr(ident, "options", None) or {}
        problem = IdentificationProblem(
            trace, params=params, fault_model=ident.fault_model,
            n_sub=int(config.n_sub if config is not None else opts.get("n_sub", 1)),
            mode=str(config.mode if config is not None else opts.get("mode", "phases")))
    m = mismatch_fit(problem, k, seed=int(ident.seed or 0))
    return replace(diagnose(k, mismatch=m, **kw), notes=notes)
