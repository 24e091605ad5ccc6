"""Degradation simulator: a fault that grows along a chosen law, seen at inspections.

A :class:`DegradationLaw` gives the fault magnitude ``d(t)`` (the health
indicator of :mod:`emaphm.prognosis.thresholds`) as a function of operating
time ``t`` (flight hours or cycles); ``s = max(t - onset, 0)``:

===========  ================================  ==========================================
kind         d(t)                              parameters
===========  ================================  ==========================================
linear       d0 + rate s                       rate per time unit (wear: Archard's law)
exponential  d0 exp(rate s)                    d0 > 0 incipient fault, rate 1/time unit
power        d0 + rate s^exponent              exponent > 0 (e.g. 2: accelerating)
===========  ================================  ==========================================

A :class:`DegradationScenario` puts that magnitude onto one component of the
fault vector (the gain drift moves ``k8`` away from 0.5 up or down), and knows
its true end of life: the time ``d`` reaches the failure threshold.

Two ways to observe a scenario at inspection times:

* :func:`simulate_degradation`: a reference-model trace (switching PWM,
  realistic sensors) per inspection, for the full loop simulate, identify,
  record, predict (:func:`emaphm.prognosis.history.inspect`);
* :func:`synthetic_k_history`: the true k plus Gaussian noise at the level
  of an identification (per-component standard deviation ``noise``, default
  0.007: the Eq. 9 errors of 0.2-0.4 % measured on noisy reference-model traces
  correspond to per-component errors of 0.005-0.01), for fast statistics of
  the trend and RUL maths.

Both are deterministic given ``seed``: the inspection ``i`` draws from the
``i``-th child of ``numpy.random.SeedSequence(seed)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from .. import modes as _modes
from ..faults import K_NOMINAL, as_k
from ..modes import friction as _friction, gain_drift as _gain_drift, short_circuit as _short
from ..seeds import check_seed
from .thresholds import DEFAULT_FAILURE_THRESHOLDS, INDICATOR_COMPONENT, FailureThresholds

__all__ = ["LAWS", "DegradationLaw", "DegradationScenario", "DEGRADATION_SCENARIOS",
           "degradation_scenario", "inspection_times", "synthetic_k_history",
           "DegradationRun", "simulate_degradation"]

LAWS = ("linear", "exponential", "power")


def _finite(name: str, v: Any, lo: float = -math.inf, lo_open: bool = False) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)) \
            or not math.isfinite(v) or v < lo or (lo_open and v == lo):
        raise ValueError(f"{name} must be a finite number {'>' if lo_open else '>='} {lo:g}, got {v!r}")
    return float(v)


@dataclass(frozen=True)
class DegradationLaw:
    """Fault magnitude over time (module docstring); ``value(t)`` is vectorised."""

    kind: str
    rate: float
    d0: float = 0.0
    exponent: float = 2.0
    onset: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in LAWS:
            raise ValueError(f"unknown degradation law {self.kind!r}; choose one of {', '.join(LAWS)}")
        object.__setattr__(self, "rate", _finite("rate", self.rate, 0.0, lo_open=True))
        object.__setattr__(self, "d0", _finite("d0", self.d0, 0.0, lo_open=self.kind == "exponential"))
        object.__setattr__(self, "exponent", _finite("exponent", self.exponent, 0.0, lo_open=True))
        object.__setattr__(self, "onset", _finite("onset", self.onset, 0.0))

    @classmethod
    def reaching(cls, kind: str, level: float, at: float, *, d0: float | None = None,
                 exponent: float = 2.0, onset: float = 0.0) -> "DegradationLaw":
        """The law of ``kind`` that reaches ``level`` at time ``at``.

        ``d0`` defaults to 0 (linear, power) or ``level / 25`` (exponential: about
        3.2 e-foldings over the life).
        """
        level = _finite("level", level, 0.0, lo_open=True)
        at = _finite("at", at, 0.0, lo_open=True)
        if d0 is None:
            d0 = level / 25.0 if kind == "exponential" else 0.0
        if not 0 <= d0 < level:
            raise ValueError(f"d0 = {d0!r} must be in [0, level = {level:g})")
        s = at - onset
        if s <= 0:
            raise ValueError(f"the fault must reach its level after its onset ({onset:g}), got at = {at:g}")
        if kind == "linear":
            rate = (level - d0) / s
        elif kind == "exponential":
            rate = math.log(level / d0) / s
        elif kind == "power":
            rate = (level - d0) / s ** exponent
        else:
            raise ValueError(f"unknown degradation law {kind!r}; choose one of {', '.join(LAWS)}")
        return cls(kind, rate, d0, exponent, onset)

    def value(self, t: Any) -> np.ndarray:
        s = np.maximum(np.asarray(t, dtype=float) - self.onset, 0.0)
        if self.kind == "linear":
            return self.d0 + self.rate * s
        if self.kind == "exponential":
            return self.d0 * np.exp(self.rate * s)
        return self.d0 + self.rate * s ** self.exponent

    def crossing_time(self, level: float) -> float:
        """First time ``value(t) >= level`` (the onset if it starts above it)."""
        if self.d0 >= level:
            return 0.0
        if self.kind == "linear":
            return self.onset + (level - self.d0) / self.rate
        if self.kind == "exponential":
            return self.onset + math.log(level / self.d0) / self.rate
        return self.onset + ((level - self.d0) / self.rate) ** (1.0 / self.exponent)

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "rate": self.rate, "d0": self.d0, "exponent": self.exponent,
                "onset": self.onset}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "DegradationLaw":
        """The law :meth:`to_dict` wrote."""
        return cls(**dict(data))


@dataclass(frozen=True)
class DegradationScenario:
    """One fault growing along ``law`` on the health indicator ``indicator``.

    ``direction`` (+1 or -1) applies to the gain drift only: k8 = 0.5 + direction d.
    ``k_base`` is the fault vector the growth adds to (nominal by default).
    """

    indicator: str
    law: DegradationLaw
    direction: int = 1
    k_base: tuple = tuple(K_NOMINAL)
    name: str = ""
    thresholds: FailureThresholds = field(default=DEFAULT_FAILURE_THRESHOLDS)

    def __post_init__(self) -> None:
        name = _modes.indicator_name(self.indicator, stacklevel=4)
        if name not in INDICATOR_COMPONENT:
            raise ValueError(f"a degradation scenario grows a component of k; {name} is read "
                             f"beyond k: choose one of {', '.join(INDICATOR_COMPONENT)}")
        object.__setattr__(self, "indicator", name)
        if self.direction not in (1, -1):
            raise ValueError(f"direction must be +1 or -1, got {self.direction!r}")
        object.__setattr__(self, "k_base", tuple(float(x) for x in as_k(self.k_base)))

    @property
    def threshold(self) -> float:
        return self.thresholds.for_indicator(self.indicator)

    @property
    def eol(self) -> float:
        """True end of life: the time the fault reaches its failure threshold."""
        return self.law.crossing_time(self.threshold)

    def k_at(self, t: Any) -> np.ndarray:
        """True fault vectors at times ``t``: (8,) for a scalar, (n, 8) for (n,)."""
        t_arr = np.asarray(t, dtype=float)
        d = np.atleast_1d(self.law.value(t_arr))
        K = np.tile(np.asarray(self.k_base), (d.size, 1))
        ind = _modes.INDICATORS[self.indicator]
        j = ind.component
        if ind.center is not None:
            K[:, j] = ind.center + self.direction * d
        else:
            K[:, j] = K[:, j] + d
        if np.any(K < 0) or np.any(K > 1):
            raise ValueError(f"scenario {self.name or self.indicator}: the fault leaves [0, 1] "
                             f"before t = {float(np.max(t_arr)):g}; stop the inspections earlier")
        return K[0] if t_arr.ndim == 0 else K

    def to_dict(self) -> dict[str, Any]:
        """Plain form: the law, the threshold on the indicator and the end of life it
        gives; ``thresholds`` (every mode's) only where they are not the defaults."""
        d = {"name": self.name, "indicator": self.indicator, "law": self.law.to_dict(),
             "direction": self.direction, "k_base": list(self.k_base),
             "threshold": self.threshold, "eol": self.eol}
        if self.thresholds != DEFAULT_FAILURE_THRESHOLDS:
            d["thresholds"] = self.thresholds.to_dict()
        return d

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "DegradationScenario":
        """The scenario :meth:`to_dict` wrote (``threshold`` and ``eol`` follow from the
        rest; without ``thresholds``, the defaults with the indicator's ``threshold``)."""
        thr = data.get("thresholds")
        thresholds = FailureThresholds.from_dict(thr) if thr is not None else \
            DEFAULT_FAILURE_THRESHOLDS.with_updates({data["indicator"]: data["threshold"]})
        return cls(indicator=data["indicator"], law=DegradationLaw.from_dict(data["law"]),
                   direction=int(data["direction"]), k_base=tuple(data["k_base"]),
                   name=data.get("name", ""), thresholds=thresholds)


def _presets() -> dict[str, DegradationScenario]:
    life = 1000.0
    friction, = _friction.INDICATORS
    gain, = _gain_drift.INDICATORS
    short_a = _short.INDICATORS[0]

    def scenario(name: str, ind: _modes.Indicator, law: str, direction: int = 1):
        return DegradationScenario(ind.name, DegradationLaw.reaching(law, ind.failure, life),
                                   direction=direction, name=name)

    return {
        # wear of the sliding surfaces: friction grows linearly with use (Archard)
        "friction-growth": scenario("friction-growth", friction, "linear"),
        # inter-turn insulation breakdown accelerates: exponential from a 1.2 % short
        "short-circuit-growth": scenario("short-circuit-growth", short_a, "exponential"),
        # slow drift of the position-loop gain downward (component ageing)
        "gain-drift": scenario("gain-drift", gain, "linear", direction=-1),
        # friction with accelerating wear (d ~ t^2): neither trend model is exact
        "friction-power": scenario("friction-power", friction, "power"),
    }


#: Named degradation scenarios, each failing at 1000 time units with the default thresholds.
DEGRADATION_SCENARIOS: Mapping[str, DegradationScenario] = MappingProxyType(_presets())


def degradation_scenario(name: str) -> DegradationScenario:
    """A named degradation scenario (:data:`DEGRADATION_SCENARIOS`)."""
    try:
        return DEGRADATION_SCENARIOS[name]
    except KeyError:
        raise ValueError(f"unknown degradation scenario {name!r}; choose one of "
                         f"{', '.join(DEGRADATION_SCENARIOS)}") from None


def inspection_times(eol: float, n: int, *, start: float = 0.0, last: float = 0.95) -> np.ndarray:
    """``n`` evenly spaced inspection times from ``start`` to ``last * eol``."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ValueError(f"the number of inspections must be a positive integer, got {n!r}")
    if not 0 < last <= 1:
        raise ValueError(f"last must be a fraction of the life in (0, 1], got {last!r}")
    if not start < last * eol:
        raise ValueError(f"the first inspection ({start:g}) must come before the last ({last * eol:g})")
    return np.linspace(start, last * eol, int(n))


def synthetic_k_history(scenario: DegradationScenario, times: Sequence[float], *, seed: int,
                        noise: float | Sequence[float] = 0.007) -> np.ndarray:
    """Identified-like k history (n, 8): the true k plus Gaussian noise, clipped to [0, 1].

    ``noise`` is the per-component standard deviation of an identification
    (a scalar or 8 values).
    """
    seed = check_seed(seed)
    sd = np.broadcast_to(np.asarray(noise, dtype=float), (8,))
    if np.any(~np.isfinite(sd)) or np.any(sd < 0):
        raise ValueError(f"noise must be finite and >= 0, got {noise!r}")
    times = np.asarray(times, dtype=float)
    K = np.atleast_2d(scenario.k_at(times))
    children = np.random.SeedSequence(seed).spawn(times.size)
    E = np.stack([np.random.default_rng(c).standard_normal(8) for c in children]) * sd
    return np.clip(K + E, 0.0, 1.0)


@dataclass(frozen=True)
class DegradationRun:
    """Simulated inspections of a degradation scenario.

    ``times`` (n,), ``k_true`` (n, 8), ``traces`` the n reference-model traces
    (their ``meta`` carries ``k``, the inspection time and the noise seed),
    ``seeds`` the noise seed of each.
    """

    scenario: DegradationScenario
    times: np.ndarray
    k_true: np.ndarray
    traces: tuple
    seeds: tuple

    @property
    def eol(self) -> float:
        return self.scenario.eol

    @property
    def rul_true(self) -> np.ndarray:
        return self.eol - self.times


def simulate_degradation(scenario: DegradationScenario, times: Sequence[float], *, seed: int,
                         model: str = "reference", params: Any = None, profile: Any = None,
                         sensors: Any = None, fault_model: str = "paper",
                         progress: Callable[[int, int], Any] | None = None) -> DegradationRun:
    """One trace per inspection time, with sensor noise (:data:`emaphm.simulate.DEFAULT_SENSORS`
    by default). The inspection ``i`` uses the noise seed drawn from the ``i``-th child of
    ``SeedSequence(seed)``. The degradation presets and their failure thresholds are
    stated in the paper's fault model (``fault_model="paper"``). ``progress(i, n)`` is
    called after each of the ``n`` traces (a progress line)."""
    from ..simulate import DEFAULT_SENSORS, simulate

    seed = check_seed(seed)
    times = np.asarray(times, dtype=float)
    if times.ndim != 1 or times.size == 0 or np.any(np.diff(times) <= 0):
        raise ValueError("inspection times must be a non-empty, strictly increasing 1-D sequence")
    K = np.atleast_2d(scenario.k_at(times))
    seeds = tuple(int(c.generate_state(1)[0]) for c in np.random.SeedSequence(seed).spawn(times.size))
    traces = []
    for t, k, s in zip(times, K, seeds):
        tr = simulate(k, model=model, params=params, profile=profile,
                      sensors=DEFAULT_SENSORS if sensors is None else sensors, seed=s,
                      fault_model=fault_model)
        traces.append(tr.with_meta(inspection_time=float(t), degradation=scenario.to_dict()))
        if progress is not None:
            progress(len(traces), times.size)
    return DegradationRun(scenario=scenario, times=times, k_true=K, traces=tuple(traces), seeds=seeds)
