"""Health indicators and failure thresholds: when a growing fault counts as a failure.

A *health indicator* is the quantity of the fault vector ``k`` whose growth a
prognosis follows; it is 0 on a healthy actuator and grows with the fault.
There is one per fault component:

==============  ==============  =============  ==================================================
indicator       fault mode      from k         default failure threshold (design default)
==============  ==============  =============  ==================================================
friction        friction        k1             0.5: dry friction 2x nominal (FSJ, FDJ x (1 + 2 k1))
backlash        backlash        k2             0.5: backlash 50.5x nominal (about 10 mrad)
short_a         short_circuit   k3             0.3: 30 % of phase A turns shorted
short_b         short_circuit   k4             0.3: same, phase B
short_c         short_circuit   k5             0.3: same, phase C
eccentricity    eccentricity    k6             0.5: static eccentricity of half the air gap
gain_drift      gain_drift      abs(k8 - 0.5)  0.25: proportional gain 25 % off nominal
==============  ==============  =============  ==================================================

The paper (Baldo et al. 2023) gives detection scenarios (k = 0.25 and 0.75) but
no failure criterion; the thresholds are ours, chosen as the point where the
fault starts to cost the actuator its function, and kept parameters
(:class:`FailureThresholds`, ``emaphm prognose --threshold MODE=VALUE``):

* friction 0.5: twice the nominal dry friction. The position loop still
  tracks, but the stick-slip dead zone and the current spent on friction
  double; beyond it the torque margin of a flight-control actuator shrinks fast.
* backlash 0.5: about 10 mrad of lost motion at the motor, far past what a
  surface actuator accepts before limit-cycle oscillation (flutter) concerns.
* short circuit 0.3: 30 % of a phase's turns shorted (R x 0.7, L x 0.49, that
  phase's back-EMF x 0.7). Inter-turn shorts heat and spread quickly, so the
  threshold sits lower than the mechanical ones.
* eccentricity 0.5: half the air gap; the unbalanced magnetic pull grows and
  rotor-stator rub becomes a risk.
* gain drift 0.25: the proportional gain 25 % off (the paper's fault
  magnitudes 0.25 and 0.75 around the nominal 0.5); the position loop's
  damping and bandwidth change enough to miss its specification.

All thresholds lie well above the detection thresholds of
:data:`emaphm.diagnosis.DEFAULT_THRESHOLDS` (0.02-0.05), so a fault is
detected long before it is predicted to fail.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace
from types import MappingProxyType
from typing import Mapping

import numpy as np

from .._text import shown

__all__ = ["INDICATORS", "INDICATOR_MODE", "INDICATOR_COMPONENT", "FailureThresholds",
           "DEFAULT_FAILURE_THRESHOLDS", "indicator_values", "latest_values", "parse_threshold"]

#: Health indicators in the order of k.
from .choices import INDICATORS  # noqa: E402  (the CLI's parser reads it there)

#: The fault mode (:data:`emaphm.diagnosis.FAULT_MODES`) of each indicator.
INDICATOR_MODE: Mapping[str, str] = MappingProxyType({
    "friction": "friction", "backlash": "backlash", "short_a": "short_circuit",
    "short_b": "short_circuit", "short_c": "short_circuit", "eccentricity": "eccentricity",
    "gain_drift": "gain_drift"})

#: The index in k each indicator is read from.
INDICATOR_COMPONENT: Mapping[str, int] = MappingProxyType({
    "friction": 0, "backlash": 1, "short_a": 2, "short_b": 3, "short_c": 4,
    "eccentricity": 5, "gain_drift": 7})


@dataclass(frozen=True)
class FailureThresholds:
    """Failure thresholds per fault mode, on the health indicator (see the module docstring).

    =============  =======  =====================================================
    field          default  indicator it applies to
    =============  =======  =====================================================
    friction       0.5      k1
    backlash       0.5      k2
    short_circuit  0.3      each of k3, k4, k5
    eccentricity   0.5      k6
    gain_drift     0.25     abs(k8 - 0.5) (at most 0.5)
    =============  =======  =====================================================
    """

    friction: float = 0.5
    backlash: float = 0.5
    short_circuit: float = 0.3
    eccentricity: float = 0.5
    gain_drift: float = 0.25

    def __post_init__(self) -> None:
        for name, v in asdict(self).items():
            hi = 0.5 if name == "gain_drift" else 1.0
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) \
                    or not 0.0 < v <= hi:
                raise ValueError(f"failure threshold {name} must be in (0, {hi:g}], got {v!r}")
            object.__setattr__(self, name, float(v))

    def for_indicator(self, indicator: str) -> float:
        """The threshold on ``indicator`` (one of :data:`INDICATORS`)."""
        if indicator not in INDICATOR_MODE:
            raise ValueError(f"unknown health indicator {shown(indicator)}; choose one of "
                             f"{', '.join(INDICATORS)}")
        return getattr(self, INDICATOR_MODE[indicator])

    def with_updates(self, updates: Mapping[str, float]) -> "FailureThresholds":
        """A copy with some modes changed; names may be modes or indicators."""
        fields = {}
        for name, value in updates.items():
            mode = INDICATOR_MODE.get(name, name)
            if mode not in asdict(self):
                raise ValueError(f"unknown fault mode {shown(name)} for a failure threshold; choose "
                                 f"one of {', '.join(asdict(self))}")
            fields[mode] = value
        return replace(self, **fields)

    def to_dict(self) -> dict[str, float]:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: Mapping[str, float]) -> "FailureThresholds":
        return cls(**dict(data))


DEFAULT_FAILURE_THRESHOLDS = FailureThresholds()


def indicator_values(K: np.ndarray) -> dict[str, np.ndarray]:
    """Health indicators of fault vectors ``K`` (n, 8) or (8,): name -> (n,) or scalar."""
    K = np.asarray(K, dtype=float)
    if K.shape[-1] != 8:
        raise ValueError(f"fault vectors need 8 components, got shape {K.shape}")
    out = {}
    for name in INDICATORS:
        j = INDICATOR_COMPONENT[name]
        out[name] = np.abs(K[..., j] - 0.5) if name == "gain_drift" else K[..., j].copy()
    return out


def latest_values(K: np.ndarray, observed: Mapping[str, np.ndarray] | None = None) -> dict[str, float]:
    """Each health indicator at the last inspection of ``K`` (n, 8) that could see its
    fault mode (``observed``: :attr:`~emaphm.prognosis.history.HistoryData.observed`;
    default every inspection); 0 (healthy) where none could."""
    values = indicator_values(np.atleast_2d(K))
    out = {}
    for name, v in values.items():
        m = None if observed is None else observed.get(name)
        seen = np.flatnonzero(m) if m is not None else np.arange(v.size)
        out[name] = float(v[seen[-1]]) if seen.size else 0.0
    return out


def parse_threshold(text: str) -> tuple[str, float]:
    """Parse ``MODE=VALUE`` (e.g. ``friction=0.4``) as given to ``--threshold``."""
    name, sep, value = text.partition("=")
    name = name.strip().replace("-", "_")
    if not sep:
        raise ValueError(f"threshold {shown(text)} must read MODE=VALUE, e.g. friction=0.4")
    try:
        v = float(value)
    except ValueError:
        raise ValueError(f"threshold {shown(text)}: {shown(value)} is not a number; write e.g. "
                         "friction=0.4") from None
    valid = set(asdict(DEFAULT_FAILURE_THRESHOLDS)) | set(INDICATORS)
    if name not in valid:
        raise ValueError(f"threshold {shown(text)}: unknown fault mode {shown(name)}; choose one of "
                         f"{', '.join(asdict(DEFAULT_FAILURE_THRESHOLDS))}")
    return name, v
