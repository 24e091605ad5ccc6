"""What every fault mode is: its reading of an identification, its threshold, its severity
in the unit a user reads, and how to make a trace of it.

A :class:`FaultMode` is data with two functions: ``read(reading) -> [Fault]`` (the faults
it names, with a physical reading) and ``inject(severity, phase)`` (an :class:`Injection`:
what to change in the plant to simulate the fault at that severity). The registry of
:mod:`emaphm.modes` collects them; adding a mode is adding one module there.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, Callable, Mapping

import numpy as np

if TYPE_CHECKING:                   # annotations only: params reads the modes' thresholds
    from ..params import ActuatorParams

__all__ = ["Fault", "Reading", "Injection", "FaultMode", "Grid", "Indicator", "PHASES",
           "searched_values"]

#: The phases, as faults name them.
PHASES = ("A", "B", "C")


@dataclass(frozen=True)
class Fault:
    """One detected fault: ``mode``, the component(s) it reads (``"k1"``, ``"k6,k7"``,
    a parameter name), its value there (``k``), ``severity`` (the share of the mode's
    range, 0..1, or the mode's own measure), a physical ``reading`` in words, the
    ``phase`` where it applies, and ``details``: the mode's own quantities (a short's
    fault-loop current, a sensor's gain...), flattened into :meth:`to_dict`."""

    mode: str
    component: str
    k: float
    severity: float
    reading: str
    phase: str | None = None
    details: Mapping[str, Any] = field(default_factory=dict, compare=False)

    def to_dict(self) -> dict[str, Any]:
        d = {"mode": self.mode, "component": self.component, "k": self.k,
             "severity": self.severity, "reading": self.reading, "phase": self.phase}
        d.update(self.details)
        return d

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "Fault":
        """The fault :meth:`to_dict` wrote (the keys beyond the six fields are its
        ``details``)."""
        own = ("mode", "component", "k", "severity", "reading", "phase")
        return cls(**{n: data[n] for n in own if n in data},
                   details={n: v for n, v in data.items() if n not in own})


@dataclass(frozen=True)
class Reading:
    """What a mode reads its faults from: the identified ``k``, the healthy actuator
    ``params``, the ``fault_model``, the detection ``thresholds``, the values of the
    parameters searched beside k (``extra``, e.g. ``{"flux": -0.12}``) and the findings
    of the checks made for the modes (``findings``, by mode name)."""

    k: np.ndarray
    params: ActuatorParams
    fault_model: str
    thresholds: Any
    extra: Mapping[str, float] = field(default_factory=dict)
    findings: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Injection:
    """A fault to simulate: components of ``k`` to set (index -> value), and a function
    ``plant(params) -> params`` for what k does not hold; ``sensor``: ``(phase index,
    gain, offset [A])`` of a faulty current sensor in the recording chain."""

    k: Mapping[int, float] = field(default_factory=dict)
    plant: Callable[[ActuatorParams], ActuatorParams] | None = None
    sensor: tuple[int, float, float] | None = None

    def to_dict(self) -> dict[str, Any]:
        """As data (what a trace's metadata keeps): the components of k set (``"k1"``..),
        whether the plant changes, the faulty sensor (phase, gain, offset [A])."""
        return {"k": {f"k{j + 1}": float(v) for j, v in sorted(self.k.items())},
                "plant": self.plant is not None,
                "sensor": None if self.sensor is None else {
                    "phase": PHASES[self.sensor[0]], "gain": float(self.sensor[1]),
                    "offset_a": float(self.sensor[2])}}


@dataclass(frozen=True)
class Grid:
    """Severities an assessment (:mod:`emaphm.assessment`) simulates a mode at.

    ``name`` labels its rows (the mode's name, or ``mode:variant`` where a mode is assessed
    more than one way, a current sensor's gain and offset); ``severities`` in
    ``severity_unit``, the unit a user reads; ``inject``: keywords of the mode's
    ``inject`` beside severity and phase (``{"kind": "offset"}``); ``variants``: keywords
    that alternate from one production unit to the next (a short's fault resistance), so
    that a grid covers them without multiplying its runs. ``magnitude(severity)`` is the
    size of the fault, 0 for a healthy actuator (``|g - 1|`` of a gain), on which the
    probability of detection grows."""

    name: str
    severity_unit: str
    severities: tuple[float, ...]
    inject: Mapping[str, Any] = field(default_factory=dict)
    variants: tuple[Mapping[str, Any], ...] = ()
    magnitude: Callable[[float], float] = abs


def _identity_measure(r: "Reading") -> dict[str, float]:
    return {}


def searched_values(diagnosis: Mapping[str, Any],
                    extra: Mapping[str, Any]) -> tuple[Mapping[str, Any], ...]:
    """The values an inspection searched beside k, as it stored them, in the order a
    reading takes them: the refit its verdict was read on (the diagnosis'
    ``hypothesis_check``), then its identification's (``extra["nuisance"]``), each empty
    where absent (a malformed record raises, which a reading takes as not measured:
    :func:`emaphm.modes.indicator_readings`)."""
    refit = diagnosis.get("hypothesis_check") or {}
    return refit.get("nuisance") or {}, extra.get("nuisance") or {}


@dataclass(frozen=True)
class Indicator:
    """A health indicator a mode is trended by (:mod:`emaphm.prognosis`): 0 on a healthy
    unit, growing with the fault, read in the mode's severity unit.

    ===============  ================================================================
    field            meaning
    ===============  ================================================================
    name             its name (``--indicator``), the mode's own or ``MODE_PHASE``
    label            in words, for plots, tables and the fleet site
    failure          the default failure threshold on it, with the reason in its mode's
                     module (:class:`emaphm.prognosis.FailureThresholds` field
                     ``threshold``, default the mode's name)
    discrepancy      its relative systematic error as identified (one standard
                     deviation), measured on plant traces; every RUL carries it
    component        the index of k it is read from (None: read from a stored
                     inspection by ``reading``)
    center           where a component's healthy level is not 0 (the gain drift's
                     k8 = 0.5): the indicator is ``|k - center|``, its series trended
                     signed along a history
    bounds           the range the indicator (its signed series) can take
    phase            the phase it applies to, for a mode of one phase
    aliases          older names, accepted with a DeprecationWarning
    reading          ``reading(diagnosis, extra) -> float | None`` of an indicator
                     beyond k: its value from an inspection's stored diagnosis
                     (:meth:`emaphm.diagnosis.Diagnosis.to_dict`) and record
                     (``Inspection.extra``); None where the inspection did not measure
                     it (distinct from a reading below detection)
    unmeasured       why an inspection may not have measured it, and what measures it
                     (for the prognosis' account of the readings it left out)
    ===============  ================================================================
    """

    name: str
    label: str
    failure: float
    discrepancy: float = 0.0
    component: int | None = None
    center: float | None = None
    bounds: tuple[float, float] = (0.0, 1.0)
    phase: str | None = None
    aliases: tuple[str, ...] = ()
    threshold: str = ""
    reading: Callable[[Mapping[str, Any], Mapping[str, Any]], float | None] | None = None
    unmeasured: str = ""

    def __post_init__(self) -> None:
        if (self.component is None) == (self.reading is None):
            raise ValueError(f"indicator {self.name}: give a component of k or a reading, one")
        if not self.bounds[0] < self.failure <= self.bounds[1]:
            raise ValueError(f"indicator {self.name}: failure threshold {self.failure} outside "
                             f"its bounds {self.bounds}")

    @property
    def axis(self) -> str:
        """Its trend's axis label (a centred one's signed series says so)."""
        if self.center is not None:
            return f"{self.name} (k{self.component + 1} - {self.center:g}, signed) [-]"
        return f"{self.name} [-]"

    def of_k(self, K: np.ndarray) -> np.ndarray:
        """Its values of fault vectors ``K`` (..., 8) (a component of k only)."""
        x = np.asarray(K, dtype=float)[..., self.component]
        return x.copy() if self.center is None else np.abs(x - self.center)

    def series_of_k(self, K: np.ndarray) -> np.ndarray:
        """Its series along a k history ``K`` (n, 8): as :meth:`of_k`, except that a
        centred one keeps its sign, that of the latest reading (near its healthy level the
        absolute value would fold the identification noise upward and bend the early
        trend)."""
        x = np.asarray(K, dtype=float)[:, self.component]
        if self.center is None:
            return x.copy()
        d = x - self.center
        return d if d.size == 0 or d[-1] >= 0 else -d


@dataclass(frozen=True)
class FaultMode:
    """A fault mode of the registry.

    ==================  =================================================================
    field               meaning
    ==================  =================================================================
    name                its name in verdicts, thresholds and ``--fault``
    label               in words
    threshold           default detection threshold, on the measure ``read`` compares
    threshold_fields    the mode's fields of :class:`emaphm.modes.Thresholds` with their
                        defaults, where it has more than one (default ``{name: threshold}``)
    thresholds_by_fm    thresholds that differ by fault model (``{"physical": 0.018}``)
    read                ``read(Reading) -> list[Fault]``
    inject              ``inject(severity, phase) -> Injection`` (None: not simulated)
    severity_unit       the unit of a severity, as a user reads it (``"x nominal"``)
    grid                severities an assessment runs by default
    per_phase           whether the mode has a phase
    spec                the ``--fault`` grammar after the name, for help texts
    parse_fields        a parser of the spec's fields, where the mode reads more than
                        ``[PHASE:]SEVERITY``
    k_components        the components of the paper's k it reads (none for a mode beside k)
    hypothesis          ``hypothesis(problem, ident, diag) -> names or None``: when the
                        residual of an identification asks for the mode, the parameters
                        to search beside k in a refit (the verdict makes it,
                        :func:`emaphm.verdict.diagnose_identification`)
    refit_from_healthy  whether that refit also starts from the healthy actuator (a fault
                        the first fit made up for what the mode explains can hold a refit
                        from k in its basin); False where the mode is read at k already
                        and its refit only adds its parameters (a short's bridge)
    measure             ``measure(Reading) -> {threshold field: value}``: what ``read``
                        compares with each of its thresholds (the largest over the
                        phases), so that an assessment can set the thresholds from the
                        readings of healthy units
    magnitude           the size of a severity, 0 for healthy (default ``|severity|``;
                        ``|s - 1|`` for a factor of nominal)
    grids               the assessment's grids, where the mode has more than ``grid``
                        (default: one :class:`Grid` of ``grid`` in ``severity_unit``)
    indicators          the :class:`Indicator` s it is trended by (prognosis)
    in_controller       the fault is in the position controller the drive runs (a gain):
                        a drive path that does not model the controller cannot see it
    ==================  =================================================================
    """

    name: str
    label: str
    threshold: float
    read: Callable[[Reading], list[Fault]]
    inject: Callable[..., Injection] | None = None
    thresholds_by_fm: Mapping[str, float] = field(default_factory=dict)
    threshold_fields: Mapping[str, float] = field(default_factory=dict)
    severity_unit: str = ""
    grid: tuple[float, ...] = ()
    per_phase: bool = False
    spec: str = "SEVERITY"
    parse_fields: Callable[[list[str]], Injection] | None = None
    hypothesis: Callable[[Any, Any, Any], tuple[str, ...] | None] | None = None
    refit_from_healthy: bool = True
    k_components: tuple[int, ...] = ()
    measure: Callable[[Reading], dict[str, float]] = _identity_measure
    magnitude: Callable[[float], float] = abs
    extra_grids: tuple[Grid, ...] = ()
    indicators: tuple[Indicator, ...] = ()
    in_controller: bool = False

    def __post_init__(self) -> None:
        # each indicator's failure threshold field defaults to the mode's name
        object.__setattr__(self, "indicators", tuple(
            i if i.threshold else replace(i, threshold=self.name) for i in self.indicators))

    def grids(self) -> tuple[Grid, ...]:
        """The grids an assessment runs this mode on (none where it cannot be simulated)."""
        if self.inject is None:
            return ()
        if self.extra_grids:
            return self.extra_grids
        if not self.grid:
            return ()
        return (Grid(self.name, self.severity_unit, tuple(self.grid), magnitude=self.magnitude),)

    def threshold_for(self, fault_model: str) -> float:
        return float(self.thresholds_by_fm.get(fault_model, self.threshold))

    def fields(self, fault_model: str | None = None) -> dict[str, float]:
        """The mode's fields of :class:`emaphm.modes.Thresholds` and their defaults (under
        ``fault_model``)."""
        if self.threshold_fields:
            return dict(self.threshold_fields)
        return {self.name: self.threshold if fault_model is None else self.threshold_for(fault_model)}

    def parse(self, fields: list[str]) -> Injection:
        """The injection of a ``--fault NAME:FIELDS`` spec (``fields`` split at ``:``):
        ``[PHASE:]SEVERITY`` unless the mode reads more (:attr:`parse_fields`)."""
        if self.inject is None:
            raise ValueError(f"fault mode {self.name} cannot be simulated")
        if self.parse_fields is not None:
            return self.parse_fields(fields)
        phase = None
        if self.per_phase:
            if not fields or fields[0].upper() not in PHASES:
                raise ValueError(f"--fault {self.name}:{self.spec}: the phase first (a, b or c)")
            phase, fields = fields[0].upper(), fields[1:]
        if len(fields) != 1:
            raise ValueError(f"--fault {self.name}:{self.spec} ({self.severity_unit})")
        return self.inject(_number(fields[0], self.name), phase)


def _number(text: str, what: str) -> float:
    try:
        x = float(text)
    except ValueError:
        raise ValueError(f"--fault {what}: {text!r} is not a number") from None
    if not np.isfinite(x):
        raise ValueError(f"--fault {what}: {text!r} is not a finite number")
    return x
