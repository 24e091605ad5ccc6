"""The fault modes: one module each, collected in one registry.

=================  ========================================================================
mode               module
=================  ========================================================================
friction           :mod:`.friction` (k1)
backlash           :mod:`.backlash` (k2)
short_circuit      :mod:`.short_circuit` (k3..k5, one phase)
eccentricity       :mod:`.eccentricity` (k6, k7)
gain_drift         :mod:`.gain_drift` (k8)
demagnetization    :mod:`.demagnetization` (the magnet flux down on every phase, searched
                   beside k when the residual asks)
current_sensor     :mod:`.current_sensor` (a phase-current sensor's gain or offset, from
                   the sum of the three measured currents)
resistance         :mod:`.resistance` (a high-resistance connection of one phase, searched
                   beside k when the residual asks)
=================  ========================================================================

Each module defines ``MODE``, a :class:`~emaphm.modes.base.FaultMode`: its reading of an
identification, its detection threshold, the unit of its severity and how to simulate
it. :data:`MODES` is the registry in the order verdicts list faults; :class:`Thresholds`
has one field per mode, its default the mode's own. Adding a mode is adding a module
here and its name to :data:`_MODULES`.
"""

from __future__ import annotations

import dataclasses
import importlib
import math
from types import MappingProxyType
from typing import Any, Mapping

from .base import PHASES, Fault, FaultMode, Grid, Indicator, Injection, Reading

__all__ = ["MODES", "FAULT_MODES", "PAPER_MODES", "Thresholds", "DEFAULT_THRESHOLDS", "THRESHOLDS_BY_FAULT_MODEL",
           "thresholds_for", "mode", "read_faults", "parse_fault", "fault_specs", "Fault", "FaultMode", "Grid", "Injection", "Reading",
           "PHASES", "Indicator", "INDICATORS", "INDICATOR_MODE", "INDICATOR_ALIASES", "indicator",
           "indicator_name", "FAILURE_FIELDS", "axis_label", "indicator_readings",
           "CONTROLLER_MODES"]

#: The modules of the modes, in the order a verdict lists their faults.
_MODULES = ("friction", "backlash", "short_circuit", "eccentricity", "gain_drift",
            "demagnetization", "current_sensor", "resistance")

#: name -> mode, in the order a verdict lists their faults.
MODES: Mapping[str, FaultMode] = MappingProxyType(
    {m.name: m for m in (importlib.import_module(f"{__name__}.{n}").MODE for n in _MODULES)})

#: The names of the modes.
FAULT_MODES: tuple[str, ...] = tuple(MODES)

#: The paper's five modes: those of its fault vector k.
PAPER_MODES: tuple[str, ...] = tuple(n for n, m in MODES.items() if m.k_components)


#: name -> health indicator (:class:`~emaphm.modes.base.Indicator`), every mode's, in the
#: registry's order (a prognosis spawns each indicator's seed in this order: a new mode's
#: indicators come after the others').
INDICATORS: Mapping[str, Indicator] = MappingProxyType(
    {i.name: i for m in MODES.values() for i in m.indicators})

#: indicator -> the name of its mode.
INDICATOR_MODE: Mapping[str, str] = MappingProxyType(
    {i.name: m.name for m in MODES.values() for i in m.indicators})

#: An indicator's older name -> its name (accepted with a DeprecationWarning).
INDICATOR_ALIASES: Mapping[str, str] = MappingProxyType(
    {a: i.name for i in INDICATORS.values() for a in i.aliases})


def _failure_fields() -> dict[str, tuple[float, float]]:
    out: dict[str, tuple[float, float]] = {}
    for i in INDICATORS.values():
        field_ = (i.failure, i.bounds[1])
        if out.setdefault(i.threshold, field_) != field_:
            raise ValueError(f"indicators of failure threshold {i.threshold} disagree on its "
                             f"default or range: {out[i.threshold]} and {field_}")
    return out


#: The fields of :class:`emaphm.prognosis.FailureThresholds`: name -> (default, the
#: largest value it may take), one per mode trended (the indicators of a mode's phases
#: share their mode's).
FAILURE_FIELDS: Mapping[str, tuple[float, float]] = MappingProxyType(_failure_fields())


def indicator_name(name: str, *, stacklevel: int = 2) -> str:
    """The indicator called ``name``: its name, from an older one with a
    DeprecationWarning (``short_a`` is ``short_circuit_a``); ValueError naming the known
    ones."""
    if name in INDICATORS:
        return name
    if name in INDICATOR_ALIASES:
        import warnings

        new = INDICATOR_ALIASES[name]
        warnings.warn(f"the health indicator {name} is now called {new}; the old name goes in "
                      "a later release", DeprecationWarning, stacklevel=stacklevel + 1)
        return new
    raise ValueError(f"unknown health indicator {name!r}; choose one of {', '.join(INDICATORS)}")


def indicator_readings(diagnosis: Mapping[str, Any] | None,
                       extra: Mapping[str, Any] | None) -> dict[str, float | None]:
    """Each indicator beyond k as an inspection measured it, from its stored ``diagnosis``
    (:meth:`emaphm.diagnosis.Diagnosis.to_dict`) and record (``extra``): name -> value, None
    where it did not (a malformed record reads as not measured)."""
    out: dict[str, float | None] = {}
    for name, ind in INDICATORS.items():
        if ind.reading is None:
            continue
        try:
            v = ind.reading(diagnosis if isinstance(diagnosis, Mapping) else {},
                            extra if isinstance(extra, Mapping) else {})
            v = None if v is None else float(v)
        except (TypeError, ValueError, KeyError, AttributeError, OverflowError):
            v = None
        out[name] = v if v is not None and math.isfinite(v) else None
    return out


def axis_label(name: str) -> str:
    """The trend axis label of indicator ``name`` (a free name as itself)."""
    ind = INDICATORS.get(name)
    return ind.axis if ind is not None else f"{name} [-]"


def indicator(name: str) -> Indicator:
    """The health indicator called ``name`` (an older name with a DeprecationWarning)."""
    return INDICATORS[indicator_name(name, stacklevel=3)]


#: The modes whose fault is in the drive's position controller (:attr:`FaultMode.in_controller`).
CONTROLLER_MODES: tuple[str, ...] = tuple(n for n, m in MODES.items() if m.in_controller)


def mode(name: str) -> FaultMode:
    """The mode registered as ``name`` (ValueError naming the known ones)."""
    try:
        return MODES[name]
    except KeyError:
        raise ValueError(f"unknown fault mode {name!r}; choose one of {', '.join(MODES)}") from None


def _check(self: Any) -> None:
    for f in dataclasses.fields(self):
        v = getattr(self, f.name)
        if not (isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                and 0 < v < 1):
            raise ValueError(f"Thresholds.{f.name} must be in (0, 1), got {v!r}")


#: Detection thresholds, one field per mode (its default the mode's ``threshold``), each on
#: the measure its mode compares: ``friction`` on k1, ``backlash`` on k2,
#: ``short_circuit`` on each of k3-k5, ``eccentricity`` on k6, ``gain_drift`` on
#: ``|k8 - 0.5|``.
Thresholds = dataclasses.make_dataclass(
    "Thresholds", [(name, float, dataclasses.field(default=v))
                   for m in MODES.values() for name, v in m.fields().items()],
    frozen=True, namespace={"__post_init__": _check, "__module__": __name__,
                            "__doc__": "Detection thresholds, one field per fault mode "
                                       "(emaphm.modes.MODES), each on the measure its "
                                       "mode compares."})

DEFAULT_THRESHOLDS = Thresholds()

#: Thresholds per fault model (k3..k5 mean different things under each; under
#: ``physical`` a short-circuit component is the shorted fraction of the turns itself).
#: ``physical``: set on reference-plant traces (Stribeck friction, PWM, leakage, the
#: contact at the plant's step) -- ``benchmarks/bench_plant.py --tune``: 100 healthy runs,
#: 40 inter-turn shorts, 35 runs of the other modes of the nominal unit; and
#: ``bench_commissioning.py --tune``: 60 calibrated production units, healthy and with one
#: fault -- on tuning seeds disjoint from the seeds they are reported on: 1.25x the largest
#: deviation of each component in the runs where it is not at fault (friction 0.080,
#: backlash 0.027, short circuit 0.014, eccentricity 0.011, gain 0.012), at least 0.015.
#: ``paper``: the same for the components both models share; 0.03 of the paper's turn
#: removal for a short circuit (the earlier twin-trace benchmark's value).
THRESHOLDS_BY_FAULT_MODEL = MappingProxyType({
    fm: Thresholds(**{name: v for m in MODES.values() for name, v in m.fields(fm).items()})
    for fm in ("paper", "physical")})


def thresholds_for(fault_model: str, params: Any = None) -> Any:
    """The detection thresholds of a diagnosis under ``fault_model``: the defaults
    (:data:`THRESHOLDS_BY_FAULT_MODEL`), with the actuator's own ``[thresholds]``
    (:attr:`emaphm.params.ActuatorParams.thresholds`, tuned by ``emaphm assess``) in place:
    all of them under the ``physical`` fault model, the one they were tuned on; under
    another, those whose default is the same under both models (every mode's but the short
    circuit's: the ``paper``'s turn removal reads another k3..k5 and keeps its own); for
    parameters without a calibration (a data sheet) only where they are higher than the
    defaults: they were tuned for a calibrated unit."""
    base = THRESHOLDS_BY_FAULT_MODEL[fault_model]
    own = getattr(params, "thresholds", ())
    if not own:
        return base
    if fault_model != "physical":
        tuned_on = THRESHOLDS_BY_FAULT_MODEL["physical"]
        own = tuple((n, v) for n, v in own if getattr(base, n) == getattr(tuned_on, n))
    if not params.calibration.date:
        # tuned for a calibrated unit: on a data sheet, whose unit differs from it by its
        # tolerances, a threshold is only ever raised (emaphm assess measured a lowered
        # one calling 5 of 40 healthy data-sheet diagnoses faulty)
        own = tuple((n, max(v, getattr(base, n))) for n, v in own)
    return dataclasses.replace(base, **dict(own))


def read_faults(reading: Reading) -> list[Fault]:
    """Every mode's faults in ``reading``, in the registry's order."""
    out: list[Fault] = []
    for m in MODES.values():
        out.extend(m.read(reading))
    return out


def parse_fault(text: str) -> Injection:
    """The injection of a fault spec ``MODE[:FIELDS]`` (``friction:2.5``,
    ``short_circuit:a:0.3:0.05``; each mode's grammar is its ``spec``)."""
    if not isinstance(text, str) or not text.strip():
        raise ValueError("a fault spec is MODE:FIELDS, e.g. friction:2.5 or short_circuit:a:0.15")
    name, *fields = [f.strip() for f in text.strip().split(":")]
    return mode(name).parse(fields)


def fault_specs() -> str:
    """The ``--fault`` grammar of every mode, for help texts."""
    return ", ".join(f"{m.name}:{m.spec}" for m in MODES.values() if m.inject is not None)
