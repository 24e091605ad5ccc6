"""Detection thresholds tuned to an actuator, from the readings of its healthy units.

A healthy diagnosis is a false alarm when any of the ``m`` measures the thresholds guard
(:attr:`emaphm.modes.FaultMode.measure`: k1 for friction, the largest of k3..k5 for a
short, the flux lost for a demagnetization, a sensor's gain and offset...) exceeds its
threshold. To keep the rate of that under ``target`` the target is split evenly among the
measures (Bonferroni: ``target / m`` each, an upper bound whatever their dependence), and
each threshold is the larger of

* the upper 95 % confidence bound of the ``1 - target / m`` quantile of a normal fitted
  to the measure on the tuning units' healthy traces: the one-sided normal **tolerance
  limit** ``mean + k sd``, with ``k`` from the noncentral t distribution (``k`` is 3.02
  for an infinite sample at a 1 % target over eight measures, 3.52 for 80 traces, 4.80
  for 12), so that a small tuning set cannot claim a tail it has not seen. A measure that
  sits at its bound (k1 = 0, say) on many traces is a **censored** observation: its fit is
  the censored-normal (Tobit) maximum likelihood, so the zeros pull the fit down only as
  much as they should;
* the largest value seen, with a margin of a quarter of its distance from the mean
  (``mean + 1.25 (largest - mean)``: 1.25 times the largest for a measure centred on 0,
  the rule the default thresholds were set by; a measure with a bias, the plant's
  Stribeck friction read as more Coulomb friction, keeps its bias);
* 1.25 times the largest value the measure takes on the tuning units' faulty traces of
  the *other* modes (the **cross-talk**: a severe short brakes the motor and reads as a
  little friction; a threshold under that names a second fault beside the first); and
* half the default threshold: a floor for a measure that never moved on the tuning
  units, where a handful of traces says little about its tail.

The tuning units are drawn from their own seeds (:meth:`AssessmentSpec.tasks`), apart from
every reported unit; the false-alarm rate reported beside the thresholds is measured
again on the reported units.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any, Mapping, Sequence

import numpy as np
from scipy import optimize, stats

__all__ = ["tune_thresholds", "tolerance_factor", "TunedThreshold", "MARGIN", "FLOOR",
           "CONFIDENCE"]

#: The largest healthy value seen, its distance from the mean times this, at least (the
#: default thresholds' rule, 1.25 times the largest, for a measure centred on 0).
MARGIN = 1.25
#: The share of the default threshold a tuned one never goes under.
FLOOR = 0.5
#: A share of the traces at the bound (or more) makes a measure censored there.
CENSORED_SHARE = 0.1
#: A measure within this of 0 is at its bound (a k component the solver left at 0).
AT_BOUND = 1e-6


@dataclass(frozen=True)
class TunedThreshold:
    """One threshold as tuned: its ``value`` and why (the fit and the rules)."""

    name: str
    value: float
    default: float
    n: int
    largest: float
    mean: float
    sd: float
    censored: int
    quantile: float
    crosstalk: float
    rule: str

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "TunedThreshold":
        """The threshold :meth:`to_dict` wrote."""
        return cls(**dict(data))


def _censored_normal(x: np.ndarray, bound: float) -> tuple[float, float]:
    """Maximum-likelihood (mu, sigma) of a normal observed as ``max(X, bound)``."""
    at = x <= bound
    free = x[~at]
    n_at = int(at.sum())

    def nll(theta: np.ndarray) -> float:
        mu, log_s = theta
        s = math.exp(log_s)
        ll = stats.norm.logpdf(free, mu, s).sum() if free.size else 0.0
        ll += n_at * stats.norm.logcdf((bound - mu) / s)
        return -float(ll)

    s0 = float(np.std(x)) or 1e-6
    res = optimize.minimize(nll, np.array([float(np.mean(x)), math.log(s0)]), method="Nelder-Mead",
                            options={"xatol": 1e-9, "fatol": 1e-12, "maxiter": 4000})
    return float(res.x[0]), float(math.exp(res.x[1]))


#: The confidence of the tolerance limit.
CONFIDENCE = 0.95


def tolerance_factor(n: int, z: float, confidence: float = CONFIDENCE) -> float:
    """``k`` of the one-sided normal tolerance limit ``mean + k sd`` of ``n`` values that
    lies above the quantile ``z`` (a standard normal quantile) with ``confidence``."""
    if n < 2:
        return math.inf
    return float(stats.nct.ppf(confidence, n - 1, z * math.sqrt(n)) / math.sqrt(n))


def tune_thresholds(readings: Sequence[Mapping[str, float]], target_far: float,
                    defaults: Any,
                    crosstalk: Sequence[tuple[str, Mapping[str, float]]] = ()
                    ) -> dict[str, TunedThreshold]:
    """The thresholds (one per field of ``defaults``, a :class:`emaphm.modes.Thresholds`)
    that keep the false-alarm rate of the healthy ``readings`` (one mapping of measures per
    healthy trace) under ``target_far``, and stay above the ``crosstalk`` (``(mode,
    measures)`` of faulty traces: each measure not of that mode's own thresholds); see the
    module doc."""
    from ..modes import MODES

    others: dict[str, list[float]] = {}
    for mode, measures in crosstalk:
        own = set(MODES[mode].fields()) if mode in MODES else set()
        for name, v in measures.items():
            if name not in own and math.isfinite(v):
                others.setdefault(name, []).append(float(v))
    names = [f for f in asdict(defaults)]
    if not readings:
        raise ValueError("no healthy readings to tune the thresholds on")
    if not 0.0 < target_far < 0.5:
        raise ValueError(f"target_far must be in (0, 0.5), got {target_far!r}")
    z = float(stats.norm.ppf(1.0 - target_far / len(names)))
    out = {}
    for name in names:
        default = float(getattr(defaults, name))
        x = np.array([float(r[name]) for r in readings if name in r], dtype=float)
        x = x[np.isfinite(x)]
        if x.size == 0:
            out[name] = TunedThreshold(name, default, default, 0, math.nan, math.nan, math.nan,
                                       0, math.nan, math.nan, "no reading: the default kept")
            continue
        # a k component at its bound reads 0 to within the solver's tolerance
        low = 0.0 if 0.0 <= float(x.min()) <= AT_BOUND else float(x.min())
        n_at = int(np.sum(x <= low + (AT_BOUND if low == 0.0 else 0.0)))
        censored = low == 0.0 and n_at >= max(2, CENSORED_SHARE * x.size) and n_at < x.size
        if n_at == x.size:               # never moved off one value: no spread to fit
            mu, sd = low, 0.0
        elif censored:
            mu, sd = _censored_normal(np.where(x <= AT_BOUND, 0.0, x), 0.0)
        else:
            mu, sd = float(np.mean(x)), float(np.std(x, ddof=1))
        q = mu + tolerance_factor(x.size, z) * sd if x.size >= 2 else math.nan
        centre = float(np.mean(x))
        candidates = {"tolerance limit": q,
                      "1.25 x largest": centre + MARGIN * (float(x.max()) - centre),
                      "cross-talk": MARGIN * max(others.get(name, [0.0])),
                      "half the default": FLOOR * default}
        candidates = {k: v for k, v in candidates.items() if math.isfinite(v)}
        rule = max(candidates, key=candidates.get)
        value = float(min(max(candidates.values()), 0.99))
        out[name] = TunedThreshold(name, value, default, int(x.size), float(x.max()), mu, sd,
                                   n_at if censored else 0, float(q),
                                   max(others.get(name, [math.nan])), rule)
    return out
