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

from dataclasses import dataclass, replace
from typing import Any, Callable, Mapping

import numpy as np

from .diagnosis import (Diagnosis, MismatchFit, Refit, Thresholds, Unexplained, diagnose,
                        fit_ratio_of)
from .modes import MODES, short_circuit as _short, thresholds_for
from .fitness import (MIN_NOISE, MISFIT_LOG_MEAN, MISFIT_LOG_STD, MISFIT_P, TRANSIENT_MISFIT,
                      misfit_limit, misfit_p_value, transient_excess)
from .faults import K_NOMINAL
from .firmware import MODELLED
from .params import ActuatorParams, as_params, resolve_params
from .problem import IdentificationProblem
from .recorded import DRIVE_NUISANCE
from .traces import Trace

__all__ = ["diagnose", "diagnose_identification", "examine", "Examination", "screen_sensors",
           "mismatch_fit", "drive_check", "transient_share", "DRIVE_DEVIATIONS", "DRIVE_HINT",
           "TRANSIENT_MISFIT", "needs_mismatch_check",
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


def mismatch_fit(problem: IdentificationProblem, k: Any, *, seed: int,
                 nuisance: tuple[str, ...] = MISMATCH_NUISANCE) -> MismatchFit:
    """Fit the trace of ``problem`` again from ``k`` with ``nuisance`` (default
    :data:`MISMATCH_NUISANCE`) searched beside it (least squares, warm-started at ``k``
    with the nuisance at zero, seeded by ``seed``; the problem's parameters, fault model,
    sub-steps and fitness mode)."""
    from .identify import minimize     # local: the search stack is heavy to import

    refit = replace(problem, nuisance=tuple(nuisance), start=k, search=None, objective=None)
    ident = minimize(refit, "lsq", seed=seed)
    return MismatchFit(k=ident.k, nuisance=dict(ident.nuisance), fit_ratio=fit_ratio_of(ident))


#: The deviations of a drive from its ``[controller]`` most likely in firmware the data sheet
#: does not describe: on a data sheet, a fault the modelled controller reads is kept only if
#: the refit with each of these drives that fits as well names it too
#: (:func:`drive_check`): a small lag on the speed feedback fits as backlash at 1.2x the
#: noise floor, with no misfit to see.
DRIVE_DEVIATIONS: dict[str, dict[str, Any]] = {
    "a 0.25 ms speed-feedback filter": dict(speed_filter_s=2.5e-4),
    "a 1 ms speed-feedback filter": dict(speed_filter_s=1e-3),
    "a period of computation delay": dict(delay_periods=1),
    "velocity and torque feed-forward": dict(velocity_feedforward=1.0, torque_feedforward=1.0),
}


def drive_check(problem: IdentificationProblem, k: Any, ratio: float | None, faults: Any, *,
                seed: int, read: Callable[[np.ndarray, dict, float | None], Diagnosis]
                ) -> tuple[tuple, str | None]:
    """``(faults kept, the deviation that explains the others)``: refit ``problem`` from
    ``k`` with the drive's likeliest deviations from its ``[controller]``
    (:data:`DRIVE_DEVIATIONS`, one at a time, on the modelled controller); a refit that fits
    at least about as well (within :data:`HYPOTHESIS_GAIN` of ``ratio``) and does not name a
    fault takes that fault from the verdict. ``read(k, extra, ratio)`` is the verdict on a
    refit. Faults of one phase (a short, a current sensor) are not checked: the control acts
    on the three phases alike."""
    from .identify import make_solver, minimize     # local: the search stack is heavy

    kept, why = list(faults), None
    if not kept or problem.drive_model != MODELLED:
        return tuple(kept), None
    if all(f.phase is not None for f in kept):
        # the drive's control acts on the three phases alike: no deviation of it reads as
        # one phase's fault (measured: every refit of a short or a sensor named it again)
        return tuple(kept), None
    ctl = problem.params.controller
    for name, options in DRIVE_DEVIATIONS.items():
        if all(getattr(ctl, key) == value for key, value in options.items()):
            continue                   # the description already has it
        trial = replace(problem, params=replace(problem.params, controller=replace(ctl, **options)),
                        start=k, search=None, objective=None)
        if ratio is not None and _far_off(trial, k, ratio):
            continue
        try:
            # local (from k and from the healthy actuator, no further starts): the question
            # is whether the deviation fits about as well as the verdict, and a refit that
            # stays far above it (the further starts' trigger) cannot
            r = minimize(trial, make_solver("lsq", restarts=0), seed=seed)
        except ValueError:             # a drive that does not follow the command at all
            continue
        r_ratio = fit_ratio_of(r)
        if ratio is not None and r_ratio is not None and r_ratio > (1.0 + HYPOTHESIS_GAIN) * ratio:
            continue
        named = {(f.mode, f.phase) for f in read(r.k, dict(r.nuisance), r_ratio).faults}
        gone = [f for f in kept if (f.mode, f.phase) not in named]
        if gone:
            kept = [f for f in kept if (f.mode, f.phase) in named]
            why = why or name
        if not kept:
            break
    return tuple(kept), why


#: A drive deviation whose model fits ``k`` and the healthy actuator both this many times
#: worse than the verdict's fit is not refitted (:func:`drive_check`): its refit could not
#: come within :data:`HYPOTHESIS_GAIN` of the fit. Measured on the preset's plant traces
#: (the paper's and beyond-the-paper faults, healthy units with undescribed filters and a
#: period of delay, noise seeds 1-5): a refit from ``k`` improved its start by 1.1-1.3x; the
#: deviations far off started at 20-2,300x, the ones that matter at 0.7-1.1x.
DRIVE_SCREEN = 4.0


def _far_off(trial: IdentificationProblem, k: Any, ratio: float) -> bool:
    """Whether the drive deviation ``trial`` fits both ``k`` (its nuisance at zero) and the
    healthy actuator more than :data:`DRIVE_SCREEN` times worse than ``ratio``: two
    evaluations that spare a refit of some fifty."""
    floor = trial.noise_floor
    if not floor > 0:
        return False
    nu = np.zeros(len(trial.nuisance))
    K = np.vstack([np.hstack([np.asarray(k, dtype=float), nu]), np.hstack([K_NOMINAL, nu])])
    f = trial.objective(K)
    return bool(np.all(f / floor > DRIVE_SCREEN * ratio))


def transient_share(problem: IdentificationProblem, k: Any, nu: Any = None) -> float | None:
    """How much more of the fit's misfit lies in the command's transients than their share
    of the trace: the excess of the weighted squared residual over the noise, per unit of
    weight, in the 20 ms after each change of the command's slope (steps, the ends of
    ramps, reversals), over the same in the rest. A drive whose control differs from
    ``[controller]`` misfits there (its loops act on the transients); a model error of the
    plant misfits on the ramps too. None where it cannot be told (a recorded-voltage path,
    no transient, no excess)."""
    if problem.drive_model != MODELLED:
        return None
    obj = problem.objective
    row = np.concatenate([np.asarray(k, dtype=float),
                          np.zeros(len(problem.nuisance)) if nu is None else np.asarray(nu)])
    R = obj.residuals(row[None, :])[0].reshape(obj.weights.shape)
    if not np.all(np.isfinite(R)):
        return None
    return transient_excess(obj.model.profile.theta_ref(obj.model.t),
                            problem.params.inverter.T_s, R * R, obj.weights, obj.noise_sigma)


#: What to do when the drive's control likely differs from its description.
DRIVE_HINT = ("the misfit sits in the command's transients (steps, reversals), not on its "
              "ramps: the drive's control likely differs from [controller] (a filter on the "
              "speed feedback, a computation delay, feed-forwards, other limits); record the "
              "drive's voltage commands with the currents (v_a, v_b, v_c or v_d, v_q: "
              "identified without modelling the controller, docs/drives.md), or describe the "
              "drive in [controller]")


#: A mode's hypothesis refit is kept when it lowers the fit ratio by this share at least
#: (or turns a misfit into a fit the misfit test accepts): searching one more parameter
#: always fits a little better.
HYPOTHESIS_GAIN = 0.03


def _problem_of(trace: Trace | IdentificationProblem, ident: Any,
                params: ActuatorParams | None) -> IdentificationProblem:
    """The problem ``ident`` was made on: given, or rebuilt from the trace with the
    identification's parameters, fault model, searched names, sub-steps, mode and least
    rotation."""
    if isinstance(trace, IdentificationProblem):
        return trace
    config = getattr(ident, "config", None)
    opts = getattr(ident, "options", None) or {}
    return IdentificationProblem(
        trace, params=params, fault_model=ident.fault_model,
        nuisance=tuple(getattr(ident, "nuisance", {}) or ()),
        n_sub=int(config.n_sub if config is not None else opts.get("n_sub", 1)),
        mode=str(config.mode if config is not None else opts.get("mode", "phases")),
        min_rotation=config.min_rotation if config is not None else 2 * np.pi,
        drive_model=getattr(ident, "drive_model", None))


def _hypotheses(problem: IdentificationProblem, ident: Any, diag: Diagnosis, seed: int,
                read: Callable[[np.ndarray, dict, float | None], Diagnosis]) -> Refit | None:
    """The refits the fault modes ask for (:attr:`emaphm.modes.FaultMode.hypothesis`),
    from the identified k and from the healthy actuator; the best one that fits clearly
    better, or None. On a data sheet (:func:`needs_mismatch_check`) a refit must also name
    its own mode (``read(k, extra, fit_ratio)``: the verdict on it): there, the parameter
    a hypothesis adds (a weaker magnet, say) also absorbs the unit's own deviations from
    the data sheet, and a better fit that names nothing of its mode is the unit's mismatch,
    not its fault."""
    base = fit_ratio_of(ident)
    best: Refit | None = None
    for m in MODES.values():
        names = m.hypothesis(problem, ident, diag) if m.hypothesis is not None else None
        if not names:
            continue
        r = _refit(problem, tuple(names), ident.k, seed, m.refit_from_healthy)
        ratio = fit_ratio_of(r)
        if base is not None and ratio is not None:
            drive = getattr(ident, "drive_model", MODELLED)
            better = ratio < (1.0 - HYPOTHESIS_GAIN) * base or (
                misfit_p_value(base, drive) < MISFIT_P <= misfit_p_value(ratio, drive))
        else:
            better = r.fitness < (1.0 - HYPOTHESIS_GAIN) * ident.fitness
        if better and needs_mismatch_check(problem.params):
            better = any(f.mode == m.name for f in read(r.k, dict(r.nuisance), ratio).faults)
        if better and (best is None or (ratio or r.fitness) < (best.fit_ratio or np.inf)):
            best = Refit(m.name, r.k, dict(r.nuisance), ratio)
    return best


def _refit(problem: IdentificationProblem, names: tuple[str, ...], k: np.ndarray,
           seed: int, from_healthy: bool = True) -> Any:
    """A hypothesis' least-squares refit from the identified k and (``from_healthy``) from
    the healthy actuator, the better: a fault the first fit made up for what the hypothesis
    explains (a backlash for a weaker magnet) can hold the refit from k in its basin."""
    from .identify import minimize     # local: the search stack is heavy to import

    best = None
    for start in ((k, None) if from_healthy else (k,)):
        trial = replace(problem, nuisance=names, start=start, search=None, objective=None)
        r = minimize(trial, "lsq", seed=seed)
        if best is None or r.fitness < best.fitness:
            best = r
    return best


#: The fit without the faults read beside a short "fits as well" within this share of the
#: verdict's (:func:`_parsimony`). Measured: the shorts of 2 % read on the other phases
#: beside a 10 % short on ema-270v-750w's feed-forward drive (recorded current references,
#: bench_drives' tuning units 80000-80005) cost +1.5 to +14 % when held; a real fault beside
#: a short costs more when held (data sheets of both actuators, a 10 % short through 0.15
#: ohm, noise seeds 1-2): friction x1.25 +25 to +83 %, x1.5 +76 to +190 %, a 5 % short of
#: a second phase +76 to +620 %, backlash x10 beside a 20 % short +430 to +750 %.
PARSIMONY_GAIN = 0.2


def _parsimony(problem: IdentificationProblem, diag: Diagnosis, k: np.ndarray, extra: dict,
               ratio: float | None, seed: int,
               read: Callable[[np.ndarray, dict, float | None], Diagnosis]) -> tuple | None:
    """Where a short is named beside other faults of k (physical fault model): the fit with
    those others held healthy and the short's fault resistance searched, from ``k``. When
    it fits as well (within :data:`PARSIMONY_GAIN` of ``ratio``) and names the short alone,
    the short explains them (a severe short's loop losses read as friction, a short on
    another phase beside it): ``(that fit, (the short's phase, the faults it explains))``,
    else None. One least-squares run, made only for such verdicts."""
    from .identify import minimize     # local: the search stack is heavy to import

    shorts = [f for f in diag.faults if f.mode == _short.MODE.name]
    if problem.fault_model != "physical" or not shorts or len(diag.faults) < 2:
        return None
    main = max(shorts, key=lambda f: f.k)
    others = [f for f in diag.faults if f is not main]
    held = {c for f in others for c in _components(f)}
    (j,) = _components(main)
    if not held or j in held:
        return None
    # the other phases' shorts held too: what the fit read there is what the short explains
    held = sorted(held | (set(_short.MODE.k_components) - {j}))
    rf = f"Rf_{main.phase.lower()}"
    start = np.array(k, dtype=float)
    start[held] = K_NOMINAL[held]
    trial = replace(problem, nuisance=tuple(extra) + (() if rf in extra else (rf,)),
                    held=tuple(held), start=start, search=None, objective=None)
    r = minimize(trial, "lsq", seed=seed)
    r_ratio = fit_ratio_of(r)
    if ratio is not None and r_ratio is not None:
        if r_ratio > (1.0 + PARSIMONY_GAIN) * ratio:
            return None
    elif not r.fitness <= (1.0 + PARSIMONY_GAIN) * trial.fitness_at(k, extra):
        return None
    named = {(f.mode, f.phase) for f in read(r.k, dict(r.nuisance), r_ratio).faults}
    if named != {(main.mode, main.phase)}:
        return None
    words = [f"{f.mode.replace('_', ' ')}{' ' + f.phase if f.phase else ''}" for f in others
             if (f.mode, f.phase) not in named]
    return r, (main.phase, *words)


def _components(fault: Any) -> tuple[int, ...]:
    """The components of k a named fault reads (its mode's, its own phase's of a per-phase
    mode; none for a mode beside k)."""
    mode = MODES[fault.mode]
    if mode.per_phase and mode.k_components:
        return (mode.k_components["ABC".index(fault.phase)],)
    return mode.k_components


def _fault_loops(problem: IdentificationProblem, k: np.ndarray, extra: dict,
                 diag: Diagnosis) -> dict | None:
    """Each named short's fault loop (physical fault model) at the fit: its RMS current,
    the power in its bridge, its ampere-turns, its shorted fraction and bridge, each with
    its interval over the fits as good along the profile of the fit
    (:func:`emaphm.fault_loops.profile`)."""
    from .fault_loops import profile

    shorts = [f for f in (*diag.faults, *diag.suspected) if f.mode == _short.MODE.name]
    if problem.fault_model != "physical" or not shorts:
        return None
    return {f.phase: profile(problem, k, extra, "ABC".index(f.phase)) for f in shorts}


def _bound_note(name: str, value: float) -> str:
    """The note of a parameter searched beside k that ended at an end of its range."""
    from .search import NUISANCE_RANGE, nuisance_text

    lo, hi = NUISANCE_RANGE[name]
    return (f"the fit put the {nuisance_text(name, value)} at the end of its range ({lo:g} to "
            f"{hi:g}): the unit is further off than the range allows, and the other readings may "
            "carry the rest; calibrate the unit again (emaphm calibrate) if it has changed")


def diagnose_identification(trace: Trace | IdentificationProblem, ident: Any, *,
                            params: ActuatorParams | None = None,
                            thresholds: Thresholds | None = None, k: Any = None,
                            check: bool = True, findings: dict | None = None,
                            loops: bool = True) -> Diagnosis:
    """The verdict of an identification (:func:`emaphm.identify.identify`) of a trace.

    :func:`diagnose` of ``k`` (default ``ident.k``) with the identification's fault model,
    the values of the parameters it searched beside k and the fit's ratio to the noise
    floor (``findings``: what the checks before the identification found, e.g. the
    current sensors). Then, where ``check`` is true: the fault modes' hypotheses
    (:attr:`emaphm.modes.FaultMode.hypothesis`: a refit with the parameters a mode adds,
    kept when it fits clearly better, :data:`HYPOTHESIS_GAIN`; the verdict is then read
    on it, ``refit``), each named short's fault loop (its current and power, and the
    range of the current over the fault resistances that fit as well), and, where the
    verdict names a fault and the parameters are a data sheet
    (:func:`needs_mismatch_check`), the mismatch check (:func:`mismatch_fit`, seeded by
    ``ident.seed``). ``loops=False`` leaves out the fault loops' report (their current,
    power and ampere-turns: readings, not part of the verdict; profiling the valley of a
    short costs a few refits). ``trace`` may be the identification's problem (its parameters,
    sub-steps and fitness mode are then the checks'; ``params`` must not be given beside
    it), or the trace with the ``params`` it was identified with (default: the
    identification's own, :attr:`emaphm.identify.Identification.params`).
    """
    if isinstance(trace, IdentificationProblem):
        if params is not None:
            raise ValueError("give params to the IdentificationProblem, not beside it")
        params = trace.params
    elif params is None:                 # the actuator the identification was made on
        params = getattr(ident, "params", None) or resolve_params(None, trace)[0]
    else:
        params = as_params(params)
    k = ident.k if k is None else k
    seed = int(ident.seed or 0)
    findings = dict(findings or {})
    noiseless = 0.0 <= getattr(ident, "noise_sigma", np.inf) < MIN_NOISE
    kw = dict(thresholds=thresholds, params=params, fault_model=ident.fault_model,
              drive_model=getattr(ident, "drive_model", MODELLED))
    ratio = None if noiseless else fit_ratio_of(ident)
    extra = dict(getattr(ident, "nuisance", {}) or {})
    notes = (NOISELESS_NOTE,) if noiseless else ()
    notes += tuple(_bound_note(n, extra[n]) for n in getattr(ident, "at_bounds", ()) if n in extra)
    diag = diagnose(k, fit_ratio=ratio, extra=extra, findings=findings, **kw)
    if not check:
        return replace(diag, notes=notes)
    problem = _problem_of(trace, ident, params)

    def read(k_: np.ndarray, extra_: dict, ratio_: float | None) -> Diagnosis:
        """The verdict on a refit (its k, values beside k and fit ratio)."""
        return diagnose(k_, fit_ratio=None if noiseless else ratio_, extra=extra_,
                        findings=findings, **kw)

    refit = _hypotheses(problem, ident, diag, seed, read)
    if refit is not None:
        k, extra = refit.k, dict(refit.nuisance)
        ratio = None if noiseless else refit.fit_ratio
        diag = diagnose(k, fit_ratio=ratio, extra=extra, findings=findings, **kw)
    lean = _parsimony(problem, diag, k, extra, ratio, seed, read)
    if lean is not None:
        r, dropped = lean
        k, extra = r.k, dict(r.nuisance)
        ratio = None if noiseless else fit_ratio_of(r)
        refit = Refit(_short.MODE.name, r.k, dict(r.nuisance), fit_ratio_of(r))
        diag = diagnose(k, fit_ratio=ratio, extra=extra, findings=findings, **kw)
        notes += (f"the short read in phase {dropped[0]} explains what was read beside it "
                  f"({', '.join(dropped[1:])}): the fit without it, the short's fault "
                  "resistance searched, fits as well, so it is not named",)
    report = _fault_loops(problem, k, extra, diag) if loops else None
    if report is not None:
        findings["fault_loops"] = report
        diag = diagnose(k, fit_ratio=ratio, extra=extra, findings=findings, **kw)
    if diag.verdict == "faulty" and needs_mismatch_check(params):
        names = tuple(("demag" if n == "flux" and "demag" in extra else n)
                      for n in MISMATCH_NUISANCE)
        names += tuple(n for n in extra if n.startswith("Rf_") or n in DRIVE_NUISANCE)
        m = mismatch_fit(problem, k, seed=seed, nuisance=names)
        diag = diagnose(k, fit_ratio=ratio, extra=extra, findings=findings, mismatch=m, **kw)
    if diag.verdict == "faulty" and needs_mismatch_check(params):
        diag = _drive_deviations(problem, diag, k, ratio, seed, read)
    if diag.unexplained is not None and diag.unexplained.reason == "misfit":
        share = transient_share(problem, k, [extra.get(n, 0.0) for n in problem.nuisance])
        if share is not None and share >= TRANSIENT_MISFIT:
            diag = replace(diag, unexplained=replace(diag.unexplained, hint=DRIVE_HINT))
    return replace(diag, notes=notes, refit=refit)


def _drive_deviations(problem, diag, k, ratio, seed, read) -> Diagnosis:
    """The verdict after :func:`drive_check`: the faults a likely drive deviation explains as
    well dropped; where none is left, ``unexplained`` (reason ``"drive"``)."""
    kept, why = drive_check(problem, k, ratio, diag.faults, seed=seed, read=read)
    if why is None:
        return diag
    if kept:
        return replace(diag, faults=kept)
    gone = ", ".join(f.mode.replace("_", " ") + (f" (phase {f.phase})" if f.phase else "")
                     for f in diag.faults)
    return replace(diag, faults=(), suspected=diag.faults, unexplained=Unexplained(
        "drive", 0.0 if ratio is None else float(ratio), None,
        f"{gone}, or {why} the drive's description lacks: a drive with it fits this trace as "
        "well and names no such fault; record the drive's voltage commands with the currents "
        "(identified without modelling the controller, docs/drives.md), or describe the drive "
        "in [controller]"))


@dataclass(frozen=True)
class Examination:
    """The whole examination of one trace (:func:`examine`): the ``identification`` the
    verdict reads (of the ``trace`` examined: corrected for a faulty current sensor), the
    ``diagnosis`` and the ``sensor`` finding; ``k`` and ``nuisance``: what the verdict was
    read on (a hypothesis' refit where one was kept, :attr:`Diagnosis.refit`, else the
    identification's), and ``error_all_pct`` their error against a simulated trace's truth
    (:func:`emaphm.problem.error_all_pct`: Eq. 9 with the parameters beside k; None for a
    bench trace).

    :meth:`to_dict` keeps the identification, the diagnosis, the sensor finding, ``k``,
    ``nuisance`` and ``error_all_pct`` (each as its own ``to_dict``), and of the trace only
    its fingerprint (:func:`emaphm.traces.fingerprint`, of its signals: SHA-256), not the
    trace: JSON has no compact exact form of its signals, and the trace has its own files
    (:func:`emaphm.traces.write_trace`). An examination read back (:meth:`from_dict`) has ``trace``
    None and ``trace_fingerprint`` set; what the identification's ``to_dict`` leaves out
    (its ``model_trace``) is not kept either."""

    identification: Any
    diagnosis: Diagnosis
    trace: Trace | None
    sensor: Any
    k: Any = None
    nuisance: dict | None = None
    error_all_pct: float | None = None
    trace_fingerprint: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """Plain, JSON-ready form (the class docstring says what is kept)."""
        from .traces import fingerprint

        fp = self.trace_fingerprint
        if fp is None and self.trace is not None:
            fp = fingerprint(self.trace)
        return {"identification": self.identification.to_dict(),
                "diagnosis": self.diagnosis.to_dict(), "sensor": self.sensor.to_dict(),
                "k": None if self.k is None else [float(x) for x in self.k],
                "nuisance": None if self.nuisance is None else dict(self.nuisance),
                "error_all_pct": self.error_all_pct, "trace_fingerprint": fp}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "Examination":
        """The examination :meth:`to_dict` wrote, without its trace (``trace`` None)."""
        from .identify import Identification
        from .modes.current_sensor import SensorFinding

        k = data.get("k")
        nu = data.get("nuisance")
        return cls(identification=Identification.from_dict(data["identification"]),
                   diagnosis=Diagnosis.from_dict(data["diagnosis"]), trace=None,
                   sensor=SensorFinding.from_dict(data["sensor"]),
                   k=None if k is None else np.asarray(k, dtype=float),
                   nuisance=None if nu is None else dict(nu),
                   error_all_pct=data.get("error_all_pct"),
                   trace_fingerprint=data.get("trace_fingerprint"))


def screen_sensors(trace: Trace, *, params: ActuatorParams | None, config: Any, seed: int,
                   thresholds: Thresholds | None = None, callback: Any = None
                   ) -> tuple[Any, Trace, Any]:
    """The current sensors of ``trace`` judged from the sum of its currents
    (:func:`emaphm.modes.current_sensor.screen`, with ``thresholds``, default the
    actuator's) and a faulty one undone: ``(finding, corrected trace, identification or
    None)``. An offset alone is placed on the phase whose corrected trace the model fits
    best (:func:`~emaphm.modes.current_sensor.resolve`: the three corrections scored at
    the healthy actuator, the likely ones identified); the identification made for that
    choice is returned, with ``config`` and ``seed``."""
    from .faults import K_NOMINAL
    from .fitness import trace_fault_model
    from .identify import identify
    from .modes.current_sensor import resolve, screen

    fault_model = config.fault_model or trace_fault_model(trace)
    actuator = resolve_params(params, trace, warn=False)[0]
    limits = thresholds if thresholds is not None else thresholds_for(fault_model, actuator)
    scored = replace(config, fault_model=fault_model)
    return resolve(trace, screen(trace, actuator, limits),
                   lambda t: identify(t, config, seed=seed, params=params, callback=callback),
                   lambda t: scored.problem(t, params).fitness_at(K_NOMINAL))


def examine(trace: Trace | list, *, params: Any = None, config: Any = None,
            seed: int = 0, callback: Any = None, thresholds: Thresholds | None = None,
            loops: bool = True, workers: int | None = None) -> Examination | list[Examination]:
    """Fault detection and identification of one trace, as ``emaphm diagnose`` makes it.

    1. The current sensors, judged from the sum of the three measured currents
       (:func:`emaphm.modes.current_sensor.screen`); a faulty one is undone on its phase
       (an offset alone is placed on the phase whose corrected trace the model fits
       best), and the machine is identified on the corrected trace. With two measured
       currents sensor faults are not observable, and the verdict says so.
    2. The identification (:func:`emaphm.identify.identify` with ``config``, default the
       least-squares solver's settings; ``params`` the actuator, default the preset).
    3. The verdict with its checks (:func:`diagnose_identification`; ``loops``: with the
       report of a short's fault loop).

    A list of traces is a batch (:func:`emaphm.batch.examine_many`): each examined as this
    call would examine it alone, on ``workers`` processes; the examinations in order.
    """
    if isinstance(trace, (list, tuple)):
        from .batch import examine_many

        return examine_many(trace, workers=workers, params=params, config=config, seed=seed,
                            callback=callback, thresholds=thresholds, loops=loops)
    if workers is not None and workers > 1:
        raise ValueError("workers= shares a list of traces among processes; give a list of "
                         "traces, or drop workers")
    from .identify import IdentificationConfig, identify
    from .modes.current_sensor import UNOBSERVABLE_NOTE, as_findings

    config = IdentificationConfig() if config is None else config
    finding, work, ident = screen_sensors(trace, params=params, config=config, seed=seed,
                                          thresholds=thresholds, callback=callback)
    if ident is None:
        ident = identify(work, config, seed=seed, params=params, callback=callback)
    diag = diagnose_identification(work, ident, params=params, thresholds=thresholds,
                                   findings=as_findings(finding), loops=loops)
    if not finding.observable:
        diag = replace(diag, notes=diag.notes + (UNOBSERVABLE_NOTE,))
    return _examination(ident, diag, work, finding)


def _examination(ident: Any, diag: Diagnosis, work: Trace, finding: Any) -> Examination:
    """The examination, with what the verdict was read on and its error against the truth."""
    from .problem import error_all_pct

    refit = diag.refit
    k = np.asarray(ident.k if refit is None else refit.k, dtype=float)
    nu = dict(ident.nuisance if refit is None else refit.nuisance)
    k_true = getattr(ident, "k_true", None)
    err = None if k_true is None else error_all_pct(k, k_true, nu,
                                                    getattr(ident, "nuisance_true", {}))
    return Examination(ident, diag, work, finding, k, nu, err)
