"""Health indicators and failure thresholds: when a growing fault counts as a failure.

A *health indicator* is the quantity a prognosis follows for a fault mode; it is 0 on a
healthy actuator and grows with the fault, in the mode's severity unit. The fault modes
declare them (:class:`emaphm.modes.Indicator`, each in its mode's module, with the reason
for its failure threshold and how its model discrepancy was measured); this module reads
them from the registry (:data:`emaphm.modes.INDICATORS`):

================  ===============  ======================  =========================================
indicator         fault mode       read from               default failure threshold
================  ===============  ======================  =========================================
friction          friction         k1                      0.5: dry friction 2x nominal
backlash          backlash         k2                      0.5: backlash 50.5x nominal (about 10 mrad)
short_circuit_a   short_circuit    k3                      0.3: 30 % of phase A turns shorted
short_circuit_b   short_circuit    k4                      0.3: same, phase B
short_circuit_c   short_circuit    k5                      0.3: same, phase C
eccentricity      eccentricity     k6                      0.5: static eccentricity of half the gap
gain_drift        gain_drift       abs(k8 - 0.5)           0.25: proportional gain 25 % off nominal
demagnetization   demagnetization  the flux lost, as the   0.2: a fifth of the magnet flux lost
                                   inspection searched it
current_sensor_   current_sensor   the currents' sum: the  0.1: a sensor 10 % off
gain_a, _b, _c                     placed sensor's |g - 1|
current_sensor_   current_sensor   the sum's constant |o|  0.5 A
offset
resistance_a,     resistance       a phase's resistance    0.5: a connection at 1.5x its phase's
_b, _c                             above the median's      resistance
================  ===============  ======================  =========================================

(``short_a`` to ``short_c`` are the short circuit's indicators' names before 0.7; they are
accepted with a DeprecationWarning.) An indicator beyond k is read from each inspection's
stored diagnosis; where an inspection did not measure it, its reading is missing (NaN),
not healthy, and its trend leaves that inspection out.

The paper (Baldo et al. 2023) gives detection scenarios (k = 0.25 and 0.75) but no
failure criterion; the thresholds are ours, chosen as the point where the fault starts
to cost the actuator its function, and kept parameters (:class:`FailureThresholds`,
``emaphm prognose --threshold MODE=VALUE``). All lie well above the detection thresholds
of :data:`emaphm.modes.DEFAULT_THRESHOLDS`, so a fault is detected long before it is
predicted to fail.
"""

from __future__ import annotations

import math
from dataclasses import asdict, field as dc_field, make_dataclass, replace
from types import MappingProxyType
from typing import Any, Mapping

import numpy as np

from .. import modes as _modes
from .._text import shown

__all__ = ["INDICATORS", "INDICATOR_MODE", "INDICATOR_COMPONENT", "FailureThresholds",
           "DEFAULT_FAILURE_THRESHOLDS", "indicator_values", "latest_values", "parse_threshold"]

#: Health indicators, in the registry's order (the paper's k first).
INDICATORS: tuple[str, ...] = tuple(_modes.INDICATORS)

#: The fault mode (:data:`emaphm.modes.FAULT_MODES`) of each indicator.
INDICATOR_MODE: Mapping[str, str] = _modes.INDICATOR_MODE

#: The index in k of each indicator read from k (those beyond k are read from the
#: inspections' stored diagnoses).
INDICATOR_COMPONENT: Mapping[str, int] = MappingProxyType(
    {n: i.component for n, i in _modes.INDICATORS.items() if i.component is not None})


class _FailureThresholds:
    """Failure thresholds per fault mode, on its health indicators (see the module
    docstring): one field per mode trended (:data:`emaphm.modes.FAILURE_FIELDS`), which
    the indicators of a mode's phases share; each in (0, its indicator's upper bound]."""

    def __post_init__(self) -> None:
        for name, v in asdict(self).items():
            hi = _modes.FAILURE_FIELDS[name][1]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) \
                    or not 0.0 < v <= hi:
                raise ValueError(f"failure threshold {name} must be in (0, {hi:g}], got {v!r}")
            object.__setattr__(self, name, float(v))

    def for_indicator(self, indicator: str) -> float:
        """The threshold on ``indicator`` (one of :data:`INDICATORS`; an older name with a
        DeprecationWarning)."""
        try:
            name = _modes.indicator_name(indicator, stacklevel=3)
        except ValueError:
            raise ValueError(f"unknown health indicator {shown(indicator)}; choose one of "
                             f"{', '.join(INDICATORS)}") from None
        return getattr(self, _modes.INDICATORS[name].threshold)

    def with_updates(self, updates: Mapping[str, float]) -> "FailureThresholds":
        """A copy with some modes changed; names may be modes or indicators."""
        fields = {}
        for name, value in updates.items():
            if name in _modes.INDICATORS or name in _modes.INDICATOR_ALIASES:
                name = _modes.INDICATORS[_modes.indicator_name(name, stacklevel=3)].threshold
            if name not in _modes.FAILURE_FIELDS:
                raise ValueError(f"unknown fault mode {shown(name)} for a failure threshold; choose "
                                 f"one of {', '.join(_modes.FAILURE_FIELDS)}")
            fields[name] = value
        return replace(self, **fields)

    def to_dict(self) -> dict[str, float]:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: Mapping[str, float]) -> "FailureThresholds":
        """The thresholds :meth:`to_dict` wrote (a mode it did not know, added since, at
        its default)."""
        return cls(**dict(data))


FailureThresholds = make_dataclass(
    "FailureThresholds", [(n, float, dc_field(default=v))
                          for n, (v, _) in _modes.FAILURE_FIELDS.items()],
    bases=(_FailureThresholds,), frozen=True,
    namespace={"__module__": __name__, "__doc__": _FailureThresholds.__doc__})

DEFAULT_FAILURE_THRESHOLDS = FailureThresholds()


def indicator_values(K: np.ndarray, readings: Mapping[str, Any] | None = None
                     ) -> dict[str, np.ndarray]:
    """Health indicators of fault vectors ``K`` (n, 8) or (8,): name -> (n,) or scalar; an
    indicator beyond k from ``readings`` (name -> its values, as ``K``'s rows; NaN where
    not measured), NaN without them."""
    K = np.asarray(K, dtype=float)
    if K.shape[-1] != 8:
        raise ValueError(f"fault vectors need 8 components, got shape {K.shape}")
    return _indicators(K, readings, signed=False)


def _indicators(K: np.ndarray, readings: Mapping[str, Any] | None,
                signed: bool) -> dict[str, np.ndarray]:
    """Every indicator of fault vectors ``K`` (..., 8), those beyond k from ``readings``
    (NaN without them); ``signed``: a centred one as its series along a history
    (:meth:`emaphm.modes.Indicator.series_of_k`), else its value."""
    out = {}
    for name, ind in _modes.INDICATORS.items():
        if ind.component is not None:
            out[name] = ind.series_of_k(K) if signed else ind.of_k(K)
        else:
            r = None if readings is None else readings.get(name)
            out[name] = np.full(K.shape[:-1], np.nan) if r is None else \
                np.array(r, dtype=float).reshape(K.shape[:-1])
    return out


def latest_values(K: np.ndarray, observed: Mapping[str, np.ndarray] | None = None,
                  readings: Mapping[str, Any] | None = None) -> dict[str, float]:
    """Each health indicator at the last inspection of ``K`` (n, 8) that could see its
    fault mode (``observed``: :attr:`~emaphm.prognosis.history.HistoryData.observed`;
    default every inspection) and measured it (``readings``, for an indicator beyond k:
    :attr:`~emaphm.prognosis.history.HistoryData.readings`); 0 (healthy) where none
    did."""
    values = indicator_values(np.atleast_2d(K), readings)
    out = {}
    for name, v in values.items():
        m = None if observed is None else observed.get(name)
        seen = np.ones(v.size, dtype=bool) if m is None else np.asarray(m, dtype=bool).copy()
        seen &= np.isfinite(v)
        ix = np.flatnonzero(seen)
        out[name] = float(v[ix[-1]]) if ix.size else 0.0
    return out


def parse_threshold(text: str) -> tuple[str, float]:
    """Parse ``MODE=VALUE`` (e.g. ``friction=0.4``) as given to ``--threshold``; an
    indicator's name stands for its mode's threshold."""
    name, sep, value = text.partition("=")
    name = name.strip().replace("-", "_")
    if not sep:
        raise ValueError(f"threshold {shown(text)} must read MODE=VALUE, e.g. friction=0.4")
    try:
        v = float(value)
    except ValueError:
        raise ValueError(f"threshold {shown(text)}: {shown(value)} is not a number; write e.g. "
                         "friction=0.4") from None
    valid = set(_modes.FAILURE_FIELDS) | set(INDICATORS) | set(_modes.INDICATOR_ALIASES)
    if name not in valid:
        raise ValueError(f"threshold {shown(text)}: unknown fault mode {shown(name)}; choose one of "
                         f"{', '.join(_modes.FAILURE_FIELDS)}")
    return name, v
