"""From an identified fault vector to the faults it names (fault detection and identification).

A component of ``k`` raises a fault when it leaves its healthy value by more
than its detection threshold (:func:`read_faults`: each fault mode of the registry
:mod:`emaphm.modes` reads its own). The thresholds (:data:`THRESHOLDS_BY_FAULT_MODEL`)
were set on reference-*plant* traces -- physics the monitoring model lacks
(Stribeck friction, a compliant backlash contact, PWM ripple, leakage), realistic
sensor noise -- of healthy and faulty units on tuning seeds
(``benchmarks/bench_plant.py --tune``) and are reported on other seeds
(``benchmarks/bench_plant.py``, table in ``BENCHMARKS.md``): 1.25x the largest
deviation of each component in runs where it is not at fault, on the nominal
unit and on calibrated production units (``bench_commissioning.py --tune``).
The plant's Stribeck friction reads as up to 0.08 of friction, so that threshold
is the widest; all stay well below the paper's low fault magnitude (0.25).
(Before the monitoring model had the compliant backlash contact, the plant's
contact read as up to 0.11 of backlash and that threshold was 0.143.)

:func:`diagnose` applies to the faults read the rules that make the verdict ``healthy``,
``faulty`` or ``unexplained`` given the statistics of an identification (the misfit
test on its fit ratio, balanced phases, the mismatch check's refit); the tests that
produce those statistics for an identification are in :mod:`emaphm.verdict`.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any, Mapping

import numpy as np

from .faults import as_k, check_fault_model
from .firmware import MODELLED
from .fitness import (MISFIT, MISFIT_LOG_MEAN, MISFIT_LOG_STD, MISFIT_P, misfit_limit,
                      misfit_p_value)
from .modes import (DEFAULT_THRESHOLDS, FAULT_MODES, THRESHOLDS_BY_FAULT_MODEL, Fault, Reading,
                    Thresholds, thresholds_for)
from .modes import read_faults as _read_modes
from .params import ActuatorParams, siemens_1fk7060
from .search import nuisance_text

__all__ = ["Thresholds", "DEFAULT_THRESHOLDS", "THRESHOLDS_BY_FAULT_MODEL", "Fault", "Diagnosis",
           "MismatchFit", "Unexplained", "diagnose", "read_faults", "FAULT_MODES", "VERDICTS",
           "MISFIT_LOG_MEAN", "MISFIT_LOG_STD", "MISFIT_P", "misfit_p_value", "misfit_limit",
           "fit_ratio_of"]

VERDICTS = ("healthy", "faulty", "unexplained")


@dataclass(frozen=True)
class Unexplained:
    """Why the identified k is not a diagnosis: ``reason`` (``"misfit"``: the best fit is
    statistically above what the model reaches on an actuator it describes;
    ``"balanced-phases"``: the same change on all three phases, a calibration mismatch
    rather than three shorts; ``"mismatch"``: on data-sheet parameters, the fit with the
    unit's likeliest deviations from its data sheet searched beside k names none of the
    faults, its fit ratio the statistic, 0 without a noise floor), the ``statistic`` tested, its ``p_value`` (None where the
    rule is not a statistical test) and a ``hint`` of what to do."""

    reason: str
    statistic: float
    p_value: float | None
    hint: str


@dataclass(frozen=True)
class MismatchFit:
    """The fit of a trace with the unit's likeliest deviations from its data sheet searched
    beside ``k`` (:func:`emaphm.mismatch.mismatch_fit`): its ``k``, the ``nuisance`` values
    found (name -> value, :data:`emaphm.search.NUISANCE_RANGE`) and its ``fit_ratio``
    (None without a noise floor). A fault read on data-sheet parameters is kept only if
    this fit names it too."""

    k: np.ndarray
    nuisance: dict
    fit_ratio: float | None = None

    def to_dict(self) -> dict[str, Any]:
        return {"k": [float(x) for x in self.k],
                "nuisance": {n: float(v) for n, v in self.nuisance.items()},
                "fit_ratio": None if self.fit_ratio is None else float(self.fit_ratio)}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "MismatchFit":
        return cls(np.asarray(data["k"], dtype=float), dict(data["nuisance"]), data.get("fit_ratio"))


@dataclass(frozen=True)
class Refit:
    """The refit a fault mode's hypothesis asked for (:func:`emaphm.verdict.diagnose_identification`):
    the ``mode``, its ``k``, the values of the parameters it searched beside k
    (``nuisance``) and its ``fit_ratio``. Kept when it fits clearly better than the
    identification; the verdict is then read on it."""

    mode: str
    k: np.ndarray
    nuisance: dict
    fit_ratio: float | None = None

    def to_dict(self) -> dict[str, Any]:
        return {"mode": self.mode, "k": [float(x) for x in self.k],
                "nuisance": {n: float(v) for n, v in self.nuisance.items()},
                "fit_ratio": None if self.fit_ratio is None else float(self.fit_ratio)}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "Refit":
        return cls(data["mode"], np.asarray(data["k"], dtype=float), dict(data["nuisance"]),
                   data.get("fit_ratio"))


@dataclass(frozen=True)
class Diagnosis:
    """Health verdict of one identified fault vector.

    ``verdict`` is ``"healthy"``, ``"faulty"`` (``faults`` names them) or
    ``"unexplained"`` (``unexplained`` says why; ``faults`` is then empty, and the
    components above their thresholds are kept in ``suspected``). ``mismatch``: the
    mismatch check's fit, where one was made (data-sheet parameters and a fault read);
    ``notes``: what the verdict could not test, in words (e.g. a trace without
    measurement noise, on which the misfit test is not made); ``refit``: the refit of a
    fault mode's hypothesis the verdict was read on, where one fitted clearly better.
    """

    k: np.ndarray
    faults: tuple[Fault, ...]
    thresholds: Thresholds = DEFAULT_THRESHOLDS
    fault_model: str = "paper"
    unexplained: Unexplained | None = None
    suspected: tuple[Fault, ...] = ()
    mismatch: MismatchFit | None = None
    notes: tuple[str, ...] = ()
    refit: Refit | None = None

    @property
    def verdict(self) -> str:
        if self.unexplained is not None:
            return "unexplained"
        return "faulty" if self.faults else "healthy"

    @property
    def healthy(self) -> bool:
        return self.verdict == "healthy"

    @property
    def modes(self) -> tuple[str, ...]:
        return tuple(f.mode for f in self.faults)

    def to_dict(self) -> dict[str, Any]:
        """As data; the k read is ``k_read`` (beside an identification's ``k`` in the
        command line's JSON, it differs from it where a hypothesis' refit was read)."""
        return {"verdict": self.verdict, "healthy": self.healthy,
                "faults": [f.to_dict() for f in self.faults],
                "unexplained": None if self.unexplained is None else asdict(self.unexplained),
                "suspected": [f.to_dict() for f in self.suspected],
                "thresholds": asdict(self.thresholds), "fault_model": self.fault_model,
                "mismatch_check": None if self.mismatch is None else self.mismatch.to_dict(),
                "hypothesis_check": None if self.refit is None else self.refit.to_dict(),
                "notes": list(self.notes), "k_read": [float(x) for x in self.k]}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "Diagnosis":
        """The diagnosis :meth:`to_dict` wrote (extra keys, such as an identification's in
        the command line's JSON, are ignored)."""
        u, m, r = data.get("unexplained"), data.get("mismatch_check"), data.get("hypothesis_check")
        return cls(k=np.asarray(data["k_read"], dtype=float),
                   faults=tuple(Fault.from_dict(f) for f in data["faults"]),
                   thresholds=Thresholds(**data["thresholds"]), fault_model=data["fault_model"],
                   unexplained=None if u is None else Unexplained(**u),
                   suspected=tuple(Fault.from_dict(f) for f in data.get("suspected", ())),
                   mismatch=None if m is None else MismatchFit.from_dict(m),
                   notes=tuple(data.get("notes", ())),
                   refit=None if r is None else Refit.from_dict(r))

    def to_frame(self) -> Any:
        """The faults named (and, for an unexplained verdict, those suspected) as a
        :class:`pandas.DataFrame`, one row each (``suspected`` says which)."""
        from .frames import require_pandas

        pd = require_pandas("Diagnosis.to_frame")
        rows = [{**f.to_dict(), "suspected": False} for f in self.faults]
        rows += [{**f.to_dict(), "suspected": True} for f in self.suspected]
        cols = ["mode", "component", "k", "severity", "reading", "phase", "suspected"]
        return pd.DataFrame(rows, columns=list(dict.fromkeys(cols + [c for r in rows for c in r])))

    def summary(self) -> str:
        if self.unexplained is not None:
            u = self.unexplained
            return f"unexplained ({u.reason}): {u.hint}"
        if self.healthy:
            return "healthy: no fault above the detection thresholds"
        return "faulty: " + "; ".join(f.reading for f in self.faults)


def fit_ratio_of(ident: Any) -> float | None:
    """An identification's fit over its trace's noise floor (None without a floor)."""
    floor = getattr(ident, "noise_floor", 0.0)
    return float(ident.fitness / floor) if floor and floor > 0 else None


def diagnose(k, *, thresholds: Thresholds | None = None,
             params: ActuatorParams | None = None, fault_model: str | None = None,
             fit_ratio: float | None = None, misfit_p: float = MISFIT_P,
             mismatch: MismatchFit | None = None, extra: Mapping[str, float] | None = None,
             findings: Mapping[str, Any] | None = None,
             drive_model: str = MODELLED) -> Diagnosis:
    """The verdict on an identified ``k``: its faults (:func:`emaphm.diagnosis.read_faults`)
    and the rules that make it ``healthy``, ``faulty`` or ``unexplained``.

    ``params`` (the healthy actuator, default preset) turns the components into
    physical values for the readings; ``fault_model`` says what k3..k5 mean (an
    identification's own: :meth:`emaphm.problem.IdentificationProblem.diagnose`) and
    picks the default thresholds (:data:`THRESHOLDS_BY_FAULT_MODEL`). Give it: without
    it a k is read under ``"paper"`` for one more release, with a DeprecationWarning,
    then under ``"physical"`` like every bare k in emaphm (``simulate --k``, a bench
    trace).
    ``fit_ratio`` (the identification's Eq. 4 over the trace's noise floor), when
    given, is tested: a fit whose probability under the fit ratios of explained
    actuators (:func:`misfit_p_value`) is below ``misfit_p`` makes the verdict
    ``unexplained``, as does a balanced short circuit on all three phases.
    ``mismatch`` (the mismatch check's fit, :func:`emaphm.verdict.mismatch_fit`),
    when given, keeps only the faults it names too; when it names none of them, the
    verdict is ``unexplained`` (reason ``"mismatch"``): the unit's deviation from its
    data sheet explains the reading as well as a fault does. ``extra``: the values of the
    parameters searched beside k (a demagnetization reads the flux there); ``findings``:
    what the checks made for the modes found (:func:`emaphm.modes.read_faults`);
    ``drive_model``: the identification's drive path, whose own fit ratios the misfit test
    compares with (:data:`emaphm.fitness.MISFIT`).
    """
    k = as_k(k)
    if fault_model is None:
        import warnings

        warnings.warn("diagnose(k) without fault_model reads k3..k5 as the paper's turn "
                      "removal; give fault_model='physical' or 'paper' (the default becomes "
                      "'physical' in the next release)", DeprecationWarning, stacklevel=2)
        fault_model = "paper"
    check_fault_model(fault_model)
    if thresholds is None:
        thresholds = thresholds_for(fault_model, params)
    p = params if params is not None else siemens_1fk7060()
    faults = read_faults(k, thresholds, p, fault_model, extra, findings)
    unexplained = None
    if fit_ratio is not None:
        pv = misfit_p_value(float(fit_ratio), drive_model)
        if pv < misfit_p:
            unexplained = Unexplained(
                "misfit", float(fit_ratio), pv,
                f"the best fit is {fit_ratio:.1f}x the trace's noise floor, where the model "
                f"reaches {math.exp(MISFIT[drive_model][0]):.1f}x on an actuator it describes"
                + (f" (on its {drive_model})" if drive_model != MODELLED else "") + ": this unit "
                "differs from its parameters, or has a fault the model lacks; calibrate it on "
                "healthy traces (emaphm calibrate) and diagnose with --params, and check the "
                "load the bench applies and the current sensor chain"
                + ("" if p.name == siemens_1fk7060().name else
                   f"; the limit was measured on the preset, not on {p.name}: physics the model "
                   "lacks (the Stribeck drop of a large dry friction) can weigh more on another "
                   "design, and emaphm assess measures how often its healthy and faulty units "
                   "read unexplained"))
    sc = k[2:5]
    if unexplained is None and np.all(sc > thresholds.short_circuit) and sc.min() >= 0.5 * sc.max():
        unexplained = Unexplained(
            "balanced-phases", float(sc.min() / sc.max()), None,
            "the same change on all three phases is a mismatch of magnet flux, inertia or "
            "current sensor gain between the unit and its parameters, not three simultaneous "
            "short circuits: calibrate the unit (emaphm calibrate) and diagnose with --params")
    if unexplained is None and mismatch is not None and faults:
        named = {(f.mode, f.phase) for f in read_faults(as_k(mismatch.k), thresholds, p,
                                                          fault_model, mismatch.nuisance,
                                                          findings)}
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


def read_faults(k: np.ndarray, thresholds: Thresholds, p: ActuatorParams, fault_model: str,
                extra: Mapping[str, float] | None = None,
                findings: Mapping[str, Any] | None = None) -> list[Fault]:
    """The faults every mode of :data:`emaphm.modes.MODES` reads in ``k`` (and in the
    values ``extra`` of the parameters searched beside it, the ``findings`` of the checks
    made), with physical readings."""
    return _read_modes(Reading(np.asarray(k, dtype=float), p, fault_model, thresholds,
                               extra or {}, findings or {}))
