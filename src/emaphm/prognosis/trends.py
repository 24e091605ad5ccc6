"""Degradation trends of a health indicator and the remaining useful life (RUL).

For one health indicator ``y`` (see :mod:`emaphm.prognosis.thresholds`) observed
at inspection times ``t``, trend models are fitted by least squares, all
written relative to the last inspection ``t_ref`` (so the first parameter is
the current level, well conditioned whatever the time unit). Each shape is a class of
:mod:`emaphm.prognosis.shapes` (its value, Jacobian, fit, crossing and growth), registered
in :data:`~emaphm.prognosis.shapes.SHAPES` (linear, exponential, quadratic, onset: the
table there); this module fits, compares and samples them without knowing which is which.

Linear growth (wear) and exponential growth (self-accelerating damage) are the
two classic degradation shapes; the quadratic is a local second-order trend
that follows growth which is neither, such as a power law ``t^2``: without it a
power-law history is fitted by a curve of the wrong shape and the intervals
miss the truth (``docs/prognosis.md`` has the numbers). ``onset`` is linear
growth that began at an unknown time ``t_onset`` between two inspections, the
indicator flat before it (segmented regression with one breakpoint): a fault
that appears after a healthy stretch of service. Without it the flat
inspections before the onset bend every other model into a convex curve whose
extrapolation reaches the threshold far too early (the inspection planner then
chases a trend that is not there: ``docs/inspection-planning.md``). All four
are fitted by default; a model needs ``p + 2`` inspections (a finite AICc) to
take part.

Each fit carries its parameter covariance ``s^2 (J^T J)^-1`` (Gauss-Newton at
the optimum, ``J`` the Jacobian) with the residual variance
``s^2 = max(RSS / (n - p), sigma_floor^2)``. The floor keeps a lucky run of
collinear points from claiming more certainty than the identification noise
allows. The models are compared by the corrected Akaike criterion

    AICc = n ln(RSS / n) + 2 p + 2 p (p + 1) / (n - p - 1)

and, by default (``selection="average"``), mixed with Akaike weights
``w_m ~ exp(-dAICc_m / 2)``: each model contributes that share of the Monte
Carlo draws. ``selection="aicc"`` keeps only the lowest AICc. Averaging
carries the doubt between the shapes into the interval; on synthetic
histories it brings the coverage of the 90 % interval at mid-life from about
0.7 to 0.8-0.9 where the shape is still ambiguous (exponential growth seen
early looks linear).

The RUL distribution comes by Monte Carlo over the fit uncertainty: draw
``theta`` from a multivariate Student t (``n - p`` degrees of freedom, the
fit's covariance), solve ``y(t*) = threshold`` for each draw (closed form for
both models), and take ``RUL = max(t* - t_now, 0)``; a draw whose trend never
reaches the threshold has an infinite RUL. The median and the central
``level`` interval of the draws are reported. Every draw comes from an
explicit ``numpy.random.Generator`` seed.

A trend knows nothing of the range its indicator can take: a component of k lies in
[0, 1] by definition (:data:`INDICATOR_BOUNDS`), a straight line does not. A prediction
whose trend has to leave that range (its value at ``t_now`` past k = 1, or draws whose
failure threshold, moved by the model discrepancy, lies beyond it) says so in
:attr:`RULPrediction.extrapolated` ("extrapolated beyond k = 1"), and so do the table of
``emaphm prognose`` and the cone of its figure (:meth:`RULPrediction.beyond`).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import Any, Mapping, Sequence

import numpy as np
from ..seeds import check_seed
# the fits, the predictor and the states, read here as before they had modules of their own
from .fits import (DEFAULT_MODELS, MIN_INSPECTIONS, TREND_MODELS, TrendFit, _check_series,
                   fit_trend, fit_trends, select)
from .predictor import RULPrediction, _json_float, predict_rul
from .states import growth_rate, indicator_state, level_at_last
from .. import modes as _modes
from .thresholds import DEFAULT_FAILURE_THRESHOLDS, INDICATORS, FailureThresholds, _indicators

__all__ = ["TREND_MODELS", "SELECTION_RULES", "TrendFit", "fit_trend", "fit_trends", "select",
           "RULPrediction", "predict_rul", "Prognosis", "prognose", "indicator_series",
           "MIN_INSPECTIONS", "DEFAULT_MODELS", "RULTrack", "rul_track", "growth_rate",
           "indicator_state", "level_at_last", "MODEL_DISCREPANCY", "INDICATOR_BOUNDS"]

from .choices import SELECTION_RULES  # noqa: E402  (the CLI reads it without SciPy)

#: The range each health indicator can take (:attr:`emaphm.modes.Indicator.bounds`): a
#: component of k lies in [0, 1] by definition, the gain drift's signed series s (k8 - 0.5)
#: (:func:`indicator_series`) in [-0.5, 0.5]. A trend extrapolated past it predicts a value
#: that cannot exist.
INDICATOR_BOUNDS: Mapping[str, tuple[float, float]] = MappingProxyType(
    {n: i.bounds for n, i in _modes.INDICATORS.items()})

#: Relative systematic error of each health indicator as identified on a calibrated unit
#: (one standard deviation, :attr:`emaphm.modes.Indicator.discrepancy`), which every RUL
#: interval carries (:func:`predict_rul`): the RMS of ``(identified - true) / true`` over
#: the inspections where the true indicator is at least a quarter of its failure
#: threshold, in degradation histories on the reference plant, each unit calibrated first
#: (``benchmarks/bench_prognosis.py --tune-discrepancy``, seeds 100+, apart from the
#: reported 0-2). The plant has physics the monitoring model lacks (the Stribeck drop
#: reads as more Coulomb friction, more so as the friction grows); the three phases share
#: the short circuit's value. Each mode's module gives its figure.
MODEL_DISCREPANCY: Mapping[str, float] = MappingProxyType(
    {n: i.discrepancy for n, i in _modes.INDICATORS.items()})


# ----------------------------------------------------------------------------- all indicators
def indicator_series(K: Any, readings: Mapping[str, Any] | None = None) -> dict[str, np.ndarray]:
    """Health indicator series of a k history ``K`` (n, 8): name -> (n,); an indicator
    beyond k from ``readings`` (name -> (n,), NaN where an inspection did not measure it;
    all NaN without them).

    Like :func:`emaphm.prognosis.thresholds.indicator_values`, except that a centred
    indicator (the gain drift) keeps its sign along the series, ``s (k8 - 0.5)`` with ``s``
    the sign of the latest drift: near zero the absolute value would fold the
    identification noise upward and bend the early trend.
    """
    K = np.atleast_2d(np.asarray(K, dtype=float))
    if K.ndim != 2 or K.shape[1] != 8:
        raise ValueError(f"a k history must have shape (n, 8), got {K.shape}")
    return _indicators(K, readings, signed=True)


@dataclass(frozen=True)
class Prognosis:
    """RUL of every health indicator of one actuator at ``t_now`` (results as data)."""

    actuator: str | None
    t_now: float
    time_unit: str
    predictions: dict
    thresholds: FailureThresholds
    times: np.ndarray = field(repr=False)
    K: np.ndarray = field(repr=False)
    #: the options it was predicted with beyond the history and the seed (``sigma_floor``
    #: and what went to :func:`predict_rul`: ``models``, ``selection``, ``n_samples``...),
    #: so that it can be predicted again alike
    options: Mapping[str, Any] = field(default_factory=dict, repr=False)
    #: indicator -> the inspections (indices into ``times``) its trend left out: the drive
    #: path those were identified on could not see its fault mode (their k there is a
    #: placeholder, :attr:`emaphm.identify.Identification.not_observable`). An indicator
    #: seen on fewer than :data:`MIN_INSPECTIONS` has no prediction.
    unobserved: Mapping[str, tuple] = field(default_factory=dict, repr=False)
    #: indicator beyond k -> its readings along ``times`` (NaN where an inspection did not
    #: measure it), as :func:`prognose` was given them
    beyond_k: Mapping[str, np.ndarray] = field(default_factory=dict, repr=False)

    def observed(self, indicator: str) -> np.ndarray:
        """Which inspections ``indicator``'s trend used (a boolean mask over ``times``)."""
        mask = np.ones(self.times.size, dtype=bool)
        mask[list(self.unobserved.get(indicator, ()))] = False
        return mask

    def readings(self, indicator: str) -> tuple[np.ndarray, np.ndarray]:
        """``(times, values)`` of the readings ``indicator``'s trend used
        (:func:`indicator_series` of the inspections that could see it)."""
        m = self.observed(indicator)
        return self.times[m], _seen_series(self.K, m, indicator, self.beyond_k)

    @property
    def first(self) -> RULPrediction | None:
        """The fault that ends life first: the smallest median RUL among the indicators
        past their threshold or growing towards it (:func:`indicator_state`); None when
        none is (a flat history's trend can cross a distant threshold from its scatter
        alone, which is no prediction of a failure)."""
        span = float(self.times[-1] - self.times[0]) if self.times.size else 0.0
        live = [p for p in self.predictions.values()
                if indicator_state(p, span)[0] != "no growth"]
        return min(live, key=lambda p: (p.median, p.lo)) if live else None

    def to_dict(self, samples: bool = False) -> dict[str, Any]:
        """As data; each prediction with its ``state`` (:func:`indicator_state`: past
        threshold, predicted or no growth), as the table reads it; the history it was
        made from (``times``, ``K``) and its ``options``. ``samples``: with each
        prediction's draws (:meth:`RULPrediction.to_dict`)."""
        span = float(self.times[-1] - self.times[0]) if self.times.size else 0.0
        return {"actuator": self.actuator, "t_now": self.t_now, "time_unit": self.time_unit,
                "thresholds": self.thresholds.to_dict(), "n_inspections": int(self.times.size),
                "predictions": {n: {**p.to_dict(samples), "state": indicator_state(p, span)[0]}
                                for n, p in self.predictions.items()},
                "times": self.times.tolist(), "K": self.K.tolist(),
                "options": json.loads(json.dumps(dict(self.options), default=str)),
                "unobserved": {n: [int(i) for i in ix] for n, ix in self.unobserved.items()},
                "beyond_k": {n: [_json_float(x) for x in v] for n, v in self.beyond_k.items()}}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "Prognosis":
        """The prognosis :meth:`to_dict` wrote (each prediction's draws where it kept
        them)."""
        return cls(actuator=data["actuator"], t_now=data["t_now"], time_unit=data["time_unit"],
                   predictions={_modes.indicator_name(n): _renamed(RULPrediction.from_dict(p))
                                for n, p in data["predictions"].items()},
                   thresholds=FailureThresholds.from_dict(data["thresholds"]),
                   times=np.asarray(data.get("times", []), dtype=float),
                   K=np.asarray(data.get("K", []), dtype=float).reshape(-1, 8),
                   options=dict(data.get("options") or {}),
                   unobserved={_modes.indicator_name(n): tuple(int(i) for i in ix)
                               for n, ix in (data.get("unobserved") or {}).items()},
                   beyond_k={n: np.array([np.nan if x is None else x for x in v], dtype=float)
                             for n, v in (data.get("beyond_k") or {}).items()})

    def to_frame(self) -> Any:
        """One row per health indicator: its threshold, state, median RUL and interval,
        the trend model (pandas)."""
        from ..frames import require_pandas

        pd = require_pandas("Prognosis.to_frame")
        span = float(self.times[-1] - self.times[0]) if self.times.size else 0.0
        return pd.DataFrame([{"indicator": n, "threshold": p.threshold,
                              "state": indicator_state(p, span)[0], "rul_median": p.median,
                              "rul_lo": p.lo, "rul_hi": p.hi, "level": p.level,
                              "p_failed": p.p_failed, "current": p.current, "model": p.model}
                             for n, p in self.predictions.items()])


def prognose(times: Any, K: Any, *, seed: int, thresholds: FailureThresholds = DEFAULT_FAILURE_THRESHOLDS,
             indicators: Sequence[str] = INDICATORS, t_now: float | None = None,
             actuator: str | None = None, time_unit: str = "h", sigma_floor: float = 0.003,
             discrepancy: Mapping[str, float] | None = None,
             observed: Mapping[str, Any] | None = None,
             readings: Mapping[str, Any] | None = None, **kwargs: Any) -> Prognosis:
    """RUL of each health indicator from a k history ``K`` (n, 8) at ``times`` (n,).

    ``readings`` (indicator beyond k -> (n,), NaN where an inspection did not measure it,
    :attr:`HistoryData.readings <emaphm.prognosis.history.HistoryData.readings>`): the
    values of the indicators not read from k (a demagnetization's flux lost); each is
    trended over the inspections that measured it (those that did not are listed in
    :attr:`Prognosis.unobserved`, as an unobserved one's), and has no prediction without
    them.

    ``observed`` (indicator -> boolean mask (n,), :attr:`HistoryData.observed
    <emaphm.prognosis.history.HistoryData.observed>`): the inspections whose drive path
    could see the indicator's fault mode; each trend uses those only (the others' k is a
    placeholder, not a healthy reading), and an indicator seen fewer than
    :data:`MIN_INSPECTIONS` times gets no prediction (:attr:`Prognosis.unobserved` says
    which were left out). Default: all.

    Each indicator gets its own seed, spawned from ``seed`` by
    :class:`numpy.random.SeedSequence` in the order of :data:`INDICATORS`, so
    a prediction does not depend on which other indicators were asked for.
    ``sigma_floor`` defaults to 0.003, the per-component repeatability of an
    identification on a noisy reference-model trace (Eq. 9 errors of 0.2-0.3 %);
    ``discrepancy`` (indicator -> relative standard deviation, default
    :data:`MODEL_DISCREPANCY`; ``{}`` for none) is the identification's systematic error
    each RUL carries (:func:`predict_rul`); other keyword arguments go to
    :func:`predict_rul`.
    """
    seed = check_seed(seed)
    indicators = [_known(name) for name in indicators]
    discrepancy = MODEL_DISCREPANCY if discrepancy is None else \
        {_known(n, "discrepancy: "): v for n, v in discrepancy.items()}
    times = np.asarray(times, dtype=float)
    beyond = _beyond_k(readings, times.size)
    series = indicator_series(K, beyond)
    masks = _observed_masks(observed, times.size)
    for name, y in beyond.items():           # an indicator not measured at an inspection
        if not np.all(np.isfinite(y)):
            masks[name] = masks.get(name, np.ones(times.size, dtype=bool)) & np.isfinite(y)
    children = np.random.SeedSequence(seed).spawn(len(INDICATORS))
    preds, unobserved = {}, {}
    for name, ss in zip(INDICATORS, children):
        if name not in indicators or (_modes.INDICATORS[name].component is None
                                      and name not in beyond):
            continue                # not asked for, or a reading beyond k not given
        t, y = times, series[name]
        if name in masks:
            unobserved[name] = tuple(int(i) for i in np.flatnonzero(~masks[name]))
            if int(masks[name].sum()) < MIN_INSPECTIONS:
                continue
            t, y = times[masks[name]], _seen_series(K, masks[name], name, beyond)
        preds[name] = predict_rul(t, y, thresholds.for_indicator(name),
                                  seed=np.random.default_rng(ss), t_now=t_now,
                                  sigma_floor=sigma_floor, indicator=name,
                                  discrepancy=float(discrepancy.get(name, 0.0)),
                                  bounds=INDICATOR_BOUNDS[name], **kwargs)
        preds[name] = _with_seed(preds[name], seed)
    return Prognosis(actuator=actuator, t_now=float(times[-1] if t_now is None else t_now),
                     time_unit=time_unit, predictions=preds, thresholds=thresholds,
                     times=times, K=np.atleast_2d(np.asarray(K, dtype=float)),
                     options={"sigma_floor": sigma_floor, **kwargs}, unobserved=unobserved,
                     beyond_k=beyond)


def _known(name: str, what: str = "") -> str:
    """``name`` as a health indicator (an older name with a DeprecationWarning)."""
    try:
        return _modes.indicator_name(name, stacklevel=4)
    except ValueError:
        raise ValueError(f"{what}unknown health indicator {name!r}; choose from "
                         f"{', '.join(INDICATORS)}") from None


def _renamed(p: RULPrediction) -> RULPrediction:
    """A prediction stored under an indicator's older name, under its name."""
    name = _modes.INDICATOR_ALIASES.get(p.indicator)
    return p if name is None else replace(p, indicator=name)


def _beyond_k(readings: Mapping[str, Any] | None, n: int) -> dict[str, np.ndarray]:
    """:func:`prognose`'s ``readings`` checked: indicators beyond k, one value (or NaN) per
    inspection."""
    out = {}
    for name, r in (readings or {}).items():
        name = _known(name, "readings: ")
        if _modes.INDICATORS[name].component is not None:
            raise ValueError(f"readings: {name} is read from k, not given beside it")
        r = np.asarray(r, dtype=float)
        if r.shape != (n,):
            raise ValueError(f"readings[{name!r}] must have one entry per inspection ({n}), "
                             f"got shape {r.shape}")
        out[name] = r
    return out


def _seen_series(K: Any, mask: np.ndarray, indicator: str,
                 readings: Mapping[str, np.ndarray] | None = None) -> np.ndarray:
    """``indicator``'s series (:func:`indicator_series`) over the inspections of ``mask``
    alone: the gain drift's sign is that of the last inspection that saw it."""
    K = np.atleast_2d(np.asarray(K, dtype=float))[mask]
    r = {n: np.asarray(v)[mask] for n, v in (readings or {}).items()}
    return indicator_series(K, r)[indicator] if K.shape[0] else np.empty(0)


def _observed_masks(observed: Mapping[str, Any] | None, n: int) -> dict[str, np.ndarray]:
    """The masks of :func:`prognose`'s ``observed`` that leave an inspection out."""
    masks = {}
    for name, m in (observed or {}).items():
        name = _known(name, "observed: ")
        m = np.asarray(m, dtype=bool)
        if m.shape != (n,):
            raise ValueError(f"observed[{name!r}] must have one entry per inspection ({n}), "
                             f"got shape {m.shape}")
        if not m.all():
            masks[name] = m
    return masks


def _with_seed(p: RULPrediction, seed: int) -> RULPrediction:
    return replace(p, seed=seed)


# ----------------------------------------------------------------------------- along a history
@dataclass(frozen=True)
class RULTrack:
    """RUL predictions made at successive inspections of one history (for the metrics).

    Prediction ``j`` uses the first ``n_used[j]`` inspections and counts from
    ``times[j]``. ``median``, ``lo``, ``hi`` (m,); ``samples`` (m, n_samples).
    """

    indicator: str
    threshold: float
    level: float
    times: np.ndarray
    n_used: np.ndarray
    median: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    samples: np.ndarray = field(repr=False)
    models: tuple = ()

    def to_dict(self) -> dict[str, Any]:
        return {"indicator": self.indicator, "threshold": self.threshold, "level": self.level,
                "times": self.times.tolist(), "n_used": self.n_used.tolist(),
                "median": [_json_float(x) for x in self.median],
                "lo": [_json_float(x) for x in self.lo], "hi": [_json_float(x) for x in self.hi],
                "models": list(self.models)}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "RULTrack":
        """The track :meth:`to_dict` wrote (without its draws: ``samples`` is empty)."""
        arr = (lambda v: np.array([math.inf if x is None else x for x in v], dtype=float))
        return cls(indicator=data["indicator"], threshold=data["threshold"],
                   level=data["level"], times=np.asarray(data["times"], dtype=float),
                   n_used=np.asarray(data["n_used"], dtype=int), median=arr(data["median"]),
                   lo=arr(data["lo"]), hi=arr(data["hi"]), samples=np.zeros((0, 0)),
                   models=tuple(data.get("models") or ()))

    def to_frame(self) -> Any:
        """One row per prediction along the history (pandas)."""
        from ..frames import require_pandas

        pd = require_pandas("RULTrack.to_frame")
        return pd.DataFrame({"time": self.times, "n_used": self.n_used, "median": self.median,
                             "lo": self.lo, "hi": self.hi,
                             "model": list(self.models) or [None] * len(self.times)})


def rul_track(t: Any, y: Any, threshold: float, *, seed: int, start: int = MIN_INSPECTIONS,
              indicator: str = "indicator", **kwargs: Any) -> RULTrack:
    """Predict the RUL at every inspection from the ``start``-th on, each with the
    inspections seen so far (what an operator would have predicted then). Step
    ``j`` draws from the ``j``-th child of ``SeedSequence(seed)``; other keyword
    arguments go to :func:`predict_rul`."""
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    _check_series(t, y)
    seed = check_seed(seed)
    if not MIN_INSPECTIONS <= start <= t.size:
        raise ValueError(f"start must be between {MIN_INSPECTIONS} and the number of "
                         f"inspections ({t.size}), got {start!r}")
    steps = range(start, t.size + 1)
    children = np.random.SeedSequence(seed).spawn(len(steps))
    preds = [predict_rul(t[:i], y[:i], threshold, seed=np.random.default_rng(c),
                         indicator=indicator, **kwargs) for i, c in zip(steps, children)]
    return RULTrack(indicator=indicator, threshold=float(threshold), level=preds[0].level,
                    times=t[start - 1:].copy(), n_used=np.arange(start, t.size + 1),
                    median=np.array([p.median for p in preds]), lo=np.array([p.lo for p in preds]),
                    hi=np.array([p.hi for p in preds]),
                    samples=np.stack([p.samples for p in preds]),
                    models=tuple(p.model for p in preds))
