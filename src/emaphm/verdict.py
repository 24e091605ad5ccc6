"""The verdict: healthy, faulty or unexplained, and the tests that decide it.

:func:`diagnose` reads the faults of an identified ``k``
(:func:`emaphm.diagnosis.read_faults`) and applies the rules that keep a reading from
being a diagnosis:

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

import math
from dataclasses import replace
from typing import Any

import numpy as np

from .diagnosis import (THRESHOLDS_BY_FAULT_MODEL, Diagnosis, Fault, MismatchFit, Thresholds,
                        Unexplained, fit_ratio_of, read_faults)
from .faults import as_k, check_fault_model
from .fitness import MISFIT_LOG_MEAN, MISFIT_LOG_STD, MISFIT_P, misfit_limit, misfit_p_value
from .params import ActuatorParams, siemens_1fk7060
from .problem import IdentificationProblem
from .search import nuisance_text
from .traces import Trace

__all__ = ["diagnose", "diagnose_identification", "mismatch_fit", "needs_mismatch_check",
           "MISMATCH_NUISANCE", "MISFIT_LOG_MEAN", "MISFIT_LOG_STD", "MISFIT_P",
           "misfit_p_value", "misfit_limit", "fit_ratio_of"]

#: What the mismatch check searches beside k: the winding resistance and magnet flux
#: (relative) and an unreported constant load (N m), within
#: :data:`emaphm.search.NUISANCE_RANGE`.
MISMATCH_NUISANCE = ("R", "flux", "load")


def diagnose(k, *, thresholds: Thresholds | None = None,
             params: ActuatorParams | None = None, fault_model: str = "physical",
             fit_ratio: float | None = None, misfit_p: float = MISFIT_P,
             mismatch: MismatchFit | None = None) -> Diagnosis:
    """The verdict on an identified ``k``: its faults (:func:`emaphm.diagnosis.read_faults`)
    and the rules that make it ``healthy``, ``faulty`` or ``unexplained``.

    ``params`` (the healthy actuator, default preset) turns the components into
    physical values for the readings; ``fault_model`` says what k3..k5 mean
    (default ``"physical"``, as every bare k in emaphm; an identification's own:
    :meth:`emaphm.problem.IdentificationProblem.diagnose`) and picks the default
    thresholds (:data:`emaphm.diagnosis.THRESHOLDS_BY_FAULT_MODEL`).
    ``fit_ratio`` (the identification's Eq. 4 over the trace's noise floor), when
    given, is tested: a fit whose probability under the fit ratios of explained
    actuators (:func:`misfit_p_value`) is below ``misfit_p`` makes the verdict
    ``unexplained``, as does a balanced short circuit on all three phases.
    ``mismatch`` (the mismatch check's fit, :func:`mismatch_fit`),
    when given, keeps only the faults it names too; when it names none of them, the
    verdict is ``unexplained`` (reason ``"mismatch"``): the unit's deviation from its
    data sheet explains the reading as well as a fault does.
    """
    k = as_k(k)
    check_fault_model(fault_model)
    if thresholds is None:
        thresholds = THRESHOLDS_BY_FAULT_MODEL[fault_model]
    p = params if params is not None else siemens_1fk7060()
    faults = read_faults(k, thresholds, p, fault_model)
    unexplained = None
    if fit_ratio is not None:
        pv = misfit_p_value(float(fit_ratio))
        if pv < misfit_p:
            unexplained = Unexplained(
                "misfit", float(fit_ratio), pv,
                f"the best fit is {fit_ratio:.1f}x the trace's noise floor, where the model "
                f"reaches {math.exp(MISFIT_LOG_MEAN):.1f}x on an actuator it describes: this unit "
                "differs from its parameters, or has a fault the model lacks; calibrate it on "
                "healthy traces (emaphm calibrate) and diagnose with --params, and check the "
                "load the bench applies and the current sensor chain")
    sc = k[2:5]
    if unexplained is None and np.all(sc > thresholds.short_circuit) and sc.min() >= 0.5 * sc.max():
        unexplained = Unexplained(
            "balanced-phases", float(sc.min() / sc.max()), None,
            "the same change on all three phases is a mismatch of magnet flux, inertia or "
            "current sensor gain between the unit and its parameters, not three simultaneous "
            "short circuits: calibrate the unit (emaphm calibrate) and diagnose with --params")
    if unexplained is None and mismatch is not None and faults:
        named = {(f.mode, f.phase) for f in read_faults(as_k(mismatch.k), thresholds, p,
                                                          fault_model)}
        kept = [f for f in faults if (f.mode, f.phase) in named]
        if kept:
            faults = kept
        else:                       # the readings stay in ``suspected``
            unexplained = Unexplained(
                "mismatch", 0.0 if mismatch.fit_ratio is None else float(mismatch.fit_ratio),
                None, _mismatch_hint(faults, mismatch))
    if unexplained is not None:
        return Diagnosis(k=k, faults=(), thresholds=thresholds, fault_model=fault_model,
                         unexplained=unexplained, suspected=tuple(faults), mismatch=mismatch)
    return Diagnosis(k=k, faults=tuple(faults), thresholds=thresholds, fault_model=fault_model,
                     mismatch=mismatch)


def _mismatch_hint(faults: list[Fault], mismatch: MismatchFit) -> str:
    read = ", ".join(f"{f.mode.replace('_', ' ')}" + (f" (phase {f.phase})" if f.phase else "")
                     + f" ({f.component} {f.k:.3f})" for f in faults)
    devs = [nuisance_text(n, v) for n, v in mismatch.nuisance.items()]
    return (f"the reading of {read} on data-sheet parameters is explained as well by how this "
            f"unit may differ from its data sheet ({', '.join(devs)}: that fit names no such "
            "fault); calibrate the unit on healthy traces (emaphm calibrate) and diagnose with "
            "--params to tell a small fault from the unit's own tolerances")


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
    kw = dict(thresholds=thresholds, params=params, fault_model=ident.fault_model,
              fit_ratio=fit_ratio_of(ident))
    diag = diagnose(k, **kw)
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
    return diagnose(k, mismatch=m, **kw)
