"""Degradation trends of a health indicator and the remaining useful life (RUL).

For one health indicator ``y`` (see :mod:`emaphm.prognosis.thresholds`) observed
at inspection times ``t``, trend models are fitted by least squares, all
written relative to the last inspection ``t_ref`` (so the first parameter is
the current level, well conditioned whatever the time unit). Each shape is a class of
:mod:`emaphm.prognosis.shapes` (its value, Jacobian, fit, crossing and growth), registered
in :data:`~emaphm.prognosis.shapes.SHAPES`; this module fits, compares and samples them
without knowing which is which:

===========  ====================================  ==========================
model        y(t), tau = t - t_ref                 parameters theta
===========  ====================================  ==========================
linear       a + b tau                             (a, b)
exponential  exp(alpha + b tau)                    (alpha = ln a, b)
quadratic    a + b tau + c tau^2                   (a, b, c)
onset        a + b max(tau, c)                     (a, b, c = t_onset - t_ref)
===========  ====================================  ==========================

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
from scipy import stats

from ..seeds import as_generator, check_seed
from .shapes import SHAPES, crossing_tau
from .thresholds import (DEFAULT_FAILURE_THRESHOLDS, INDICATORS, INDICATOR_COMPONENT,
                         INDICATOR_MODE, FailureThresholds)

__all__ = ["TREND_MODELS", "SELECTION_RULES", "TrendFit", "fit_trend", "fit_trends", "select",
           "RULPrediction", "predict_rul", "Prognosis", "prognose", "indicator_series",
           "MIN_INSPECTIONS", "DEFAULT_MODELS", "RULTrack", "rul_track", "growth_rate",
           "indicator_state", "MODEL_DISCREPANCY", "INDICATOR_BOUNDS"]

TREND_MODELS = tuple(SHAPES)
#: The models fitted by default.
DEFAULT_MODELS = TREND_MODELS
from .choices import SELECTION_RULES  # noqa: E402  (the CLI reads it without SciPy)

#: The range each health indicator can take: a component of k lies in [0, 1] by
#: definition, the gain drift's signed series s (k8 - 0.5) (:func:`indicator_series`) in
#: [-0.5, 0.5]. A trend extrapolated past it predicts a k that cannot exist.
INDICATOR_BOUNDS: Mapping[str, tuple[float, float]] = MappingProxyType(
    {name: (-0.5, 0.5) if name == "gain_drift" else (0.0, 1.0) for name in INDICATORS})

#: Least number of inspections for a trend with an uncertainty (two parameters + one dof).
MIN_INSPECTIONS = 3

#: Relative systematic error of each health indicator as identified on a calibrated unit
#: (one standard deviation), which every RUL interval carries (:func:`predict_rul`): the
#: RMS of ``(identified - true) / true`` over the inspections where the true indicator is
#: at least a quarter of its failure threshold, in degradation histories on the reference
#: plant, each unit calibrated first (``benchmarks/bench_prognosis.py
#: --tune-discrepancy``, seeds 100+, apart from the reported 0-2). The plant has physics
#: the monitoring model lacks (the Stribeck drop reads as more Coulomb friction, more so
#: as the friction grows); the three phases share the short circuit's value.
#: Measured (5 histories of each, 20-35 inspections): friction 0.053 (mean +0.039),
#: backlash 0.058 (+0.025), short circuit 0.020 (+0.012), eccentricity 0.0070, gain drift
#: 0.0051.
MODEL_DISCREPANCY: Mapping[str, float] = MappingProxyType({
    "friction": 0.053, "backlash": 0.058, "short_a": 0.020, "short_b": 0.020, "short_c": 0.020,
    "eccentricity": 0.0070, "gain_drift": 0.0051})

@dataclass(frozen=True)
class TrendFit:
    """One least-squares trend of a health indicator.

    ===========  =======  =========================================================
    field        shape    meaning
    ===========  =======  =========================================================
    model        str      one of :data:`TREND_MODELS` (module docstring)
    theta        (p,)     parameters, time relative to ``t_ref``
    cov          (p, p)   their covariance, ``s^2 (J^T J)^-1``
    t_ref        float    time origin: the last inspection, in the history's unit
    sigma        float    residual standard deviation used (after the floor)
    rss          float    residual sum of squares
    n            int      number of inspections fitted
    aicc         float    corrected Akaike criterion (lower is better)
    ===========  =======  =========================================================
    """

    model: str
    theta: np.ndarray
    cov: np.ndarray
    t_ref: float
    sigma: float
    rss: float
    n: int
    aicc: float

    @property
    def n_params(self) -> int:
        return int(self.theta.shape[0])

    @property
    def dof(self) -> int:
        return self.n - self.n_params

    def value(self, t: Any) -> np.ndarray:
        """Trend at times ``t`` (history's unit)."""
        tau = np.atleast_1d(np.asarray(t, dtype=float)) - self.t_ref
        return SHAPES[self.model].value(self.theta, tau)

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` parameter draws (n, p) from the multivariate Student t of the fit. An
        onset is drawn no later than the last inspection, as it is fitted (where the slope
        is lost in the noise its variance is huge, and an onset drawn far ahead would hold
        the level of the flat part there: ``a + b c`` past any threshold)."""
        chol = _chol(self.cov)
        z = rng.standard_normal((n, self.n_params))
        w = np.sqrt(self.dof / rng.chisquare(self.dof, size=n))
        theta = self.theta[None, :] + (z @ chol.T) * w[:, None]
        return SHAPES[self.model].constrain(theta)

    def crossing_time(self, threshold: Any, theta: np.ndarray | None = None) -> np.ndarray:
        """Absolute time(s) where the trend reaches ``threshold`` (a number, or one per row
        of ``theta``; inf: never)."""
        th = np.atleast_2d(self.theta if theta is None else theta)
        return self.t_ref + crossing_tau(SHAPES[self.model], th, threshold)

    def to_dict(self) -> dict[str, Any]:
        return {"model": self.model, "theta": self.theta.tolist(), "cov": self.cov.tolist(),
                "t_ref": self.t_ref, "sigma": self.sigma, "rss": self.rss, "n": self.n,
                "aicc": self.aicc}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "TrendFit":
        p = len(data["theta"])
        return cls(model=data["model"], theta=np.asarray(data["theta"], dtype=float),
                   cov=np.asarray(data["cov"], dtype=float).reshape(p, p), t_ref=data["t_ref"],
                   sigma=data["sigma"], rss=data["rss"], n=data["n"], aicc=data["aicc"])


def _chol(cov: np.ndarray) -> np.ndarray:
    c = 0.5 * (cov + cov.T)
    try:
        return np.linalg.cholesky(c)
    except np.linalg.LinAlgError:
        w, v = np.linalg.eigh(c)
        return v * np.sqrt(np.clip(w, 0.0, None))


def _aicc(rss: float, n: int, p: int) -> float:
    rss = max(rss, 1e-300)
    if n - p - 1 <= 0:
        return math.inf
    return n * math.log(rss / n) + 2 * p + 2 * p * (p + 1) / (n - p - 1)


def _check_series(t: Any, y: Any) -> tuple[np.ndarray, np.ndarray]:
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    if t.ndim != 1 or y.shape != t.shape:
        raise ValueError(f"times and values must be 1-D arrays of one length, got shapes "
                         f"{t.shape} and {y.shape}")
    if t.size < MIN_INSPECTIONS:
        raise ValueError(f"a degradation trend needs at least {MIN_INSPECTIONS} inspections, "
                         f"got {t.size}; record more inspections first")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(y))):
        raise ValueError("times and indicator values must be finite")
    if np.any(np.diff(t) <= 0):
        raise ValueError("inspection times must be strictly increasing")
    return t, y


def fit_trend(t: Any, y: Any, model: str = "linear", *, sigma_floor: float = 0.0) -> TrendFit:
    """Least-squares fit of one trend model to ``y`` (n,) observed at times ``t`` (n,).

    ``sigma_floor`` is the least residual standard deviation the covariance
    assumes (the identification noise of one inspection, indicator units).
    """
    if model not in TREND_MODELS:
        raise ValueError(f"unknown trend model {model!r}; choose one of {', '.join(TREND_MODELS)}")
    if not (math.isfinite(sigma_floor) and sigma_floor >= 0):
        raise ValueError(f"sigma_floor must be finite and >= 0, got {sigma_floor!r}")
    t, y = _check_series(t, y)
    t_ref = float(t[-1])
    tau = t - t_ref
    shape = SHAPES[model]
    p = shape.n_params
    n = t.size
    if n < p + 1:
        raise ValueError(f"the {model} trend needs at least {p + 1} inspections, got {n}")
    theta = shape.fit(tau, y)
    r = y - shape.value(theta, tau)
    rss = float(r @ r)
    sigma = max(math.sqrt(rss / (n - p)), sigma_floor)
    J = shape.jacobian(theta, tau)
    JtJ = J.T @ J
    try:
        cov = sigma ** 2 * np.linalg.inv(JtJ)
    except np.linalg.LinAlgError:
        cov = sigma ** 2 * np.linalg.pinv(JtJ)
    if not np.all(np.isfinite(cov)):
        cov = np.eye(p) * 1e6
    return TrendFit(model=model, theta=np.asarray(theta, dtype=float), cov=cov, t_ref=t_ref,
                    sigma=sigma, rss=rss, n=n, aicc=_aicc(rss, n, p))


def fit_trends(t: Any, y: Any, models: Sequence[str] = DEFAULT_MODELS, *,
               sigma_floor: float = 0.0) -> dict[str, TrendFit]:
    """Fits of several models, model name -> :class:`TrendFit`."""
    if not models:
        raise ValueError(f"give at least one trend model of {', '.join(TREND_MODELS)}")
    for m in models:
        if m not in TREND_MODELS:
            raise ValueError(f"unknown trend model {m!r}; choose one of {', '.join(TREND_MODELS)}")
    n = np.asarray(t).size
    # a model is compared only once its AICc is finite (n >= p + 2)
    usable = ([m for m in models if n >= SHAPES[m].n_params + 2]
              or [m for m in models if n >= SHAPES[m].n_params + 1] or list(models))
    fits = {m: fit_trend(t, y, m, sigma_floor=sigma_floor) for m in usable}
    # a fit whose covariance means nothing (an exponential whose level is lost in the
    # noise: its Jacobian scales with the level) is left out when another model is there
    lost = [m for m, f in fits.items() if SHAPES[m].lost(f.theta, max(sigma_floor, 1e-6))]
    for m in lost[:len(fits) - 1]:
        del fits[m]
    return fits


def select(fits: Mapping[str, TrendFit]) -> dict[str, float]:
    """Akaike weights ``exp(-dAICc / 2)`` normalised, model -> weight; the best has the largest."""
    names = list(fits)
    a = np.array([fits[m].aicc for m in names])
    if not np.any(np.isfinite(a)):
        return {m: 1.0 / len(names) for m in names}
    d = a - np.min(a[np.isfinite(a)])
    w = np.where(np.isfinite(d), np.exp(-0.5 * d), 0.0)
    w /= w.sum()
    return {m: float(x) for m, x in zip(names, w)}


# ----------------------------------------------------------------------------- RUL
@dataclass(frozen=True)
class RULPrediction:
    """Remaining useful life of one health indicator (results as data).

    ============  =========  ===========================================================
    field         type       meaning
    ============  =========  ===========================================================
    indicator     str        health indicator (:data:`INDICATORS`) or a free name
    threshold     float      failure threshold on it
    t_now         float      time the RUL counts from (history's unit)
    model         str        chosen trend model, or ``"average"`` (Akaike mixture)
    weights       dict       Akaike weight of each fitted model
    fits          dict       model -> :class:`TrendFit`
    median        float      median RUL (inf: the trend does not reach the threshold)
    lo, hi        float      central ``level`` interval of the RUL
    level         float      interval probability, e.g. 0.9
    p_failed      float      share of draws already at or past the threshold at t_now
    samples       (n,)       RUL draws (inf where the threshold is never reached)
    theta         dict       model -> parameter draws (n_m, p), for plots
    current       float      trend value at t_now (chosen model)
    seed          int|None   seed of the draws
    excluded      tuple      inspections left out as outliers
    discrepancy   float      relative model discrepancy drawn into the threshold (1 sd)
    bounds        (lo, hi)   range the indicator can take (:data:`INDICATOR_BOUNDS`)
    extrapolated  str        why the prediction reads its trend outside ``bounds``
                             ("extrapolated beyond k = 1: ..."); "" when it does not
    ============  =========  ===========================================================
    """

    indicator: str
    threshold: float
    t_now: float
    model: str
    weights: dict
    fits: dict
    median: float
    lo: float
    hi: float
    level: float
    p_failed: float
    samples: np.ndarray = field(repr=False)
    theta: dict = field(repr=False)
    current: float = math.nan
    seed: int | None = None
    excluded: tuple = ()
    discrepancy: float = 0.0
    bounds: tuple = (-math.inf, math.inf)
    extrapolated: str = ""
    #: the share of draws that reach the threshold, kept where the draws are not (a
    #: prediction read back from :meth:`to_dict` without ``samples``)
    reach: float | None = field(default=None, repr=False)

    @property
    def top_fit(self) -> TrendFit:
        """The most weighted trend (the largest Akaike weight)."""
        return self.fits[max(self.weights, key=self.weights.get)]

    @property
    def p_reach(self) -> float:
        """Share of draws whose trend ever reaches the threshold."""
        if self.samples.size == 0 and self.reach is not None:
            return float(self.reach)
        return float(np.mean(np.isfinite(self.samples)))

    def no_growth(self, span: float) -> bool:
        """True when this indicator is not growing towards its threshold on the time scale
        of a history spanning ``span``: no finite median and under half the draws ever
        reach it, or a median beyond ten times the span. Tables and figures then say
        "no growth" instead of quoting a remaining life."""
        return bool((not math.isfinite(self.median) and self.p_reach < 0.5)
                    or self.median > 10.0 * max(float(span), 1e-9))

    def p_fail_within(self, horizon: float) -> float:
        """Probability that the threshold is reached within ``horizon`` from ``t_now``."""
        return float(np.mean(self.samples <= horizon))

    def band(self, t: Any, quantiles: Sequence[float] = (0.05, 0.5, 0.95)) -> np.ndarray:
        """Quantiles of the trend over the stored parameter draws at times ``t`` (m,):
        (len(quantiles), m), the prediction cone of the plots."""
        tau = np.atleast_1d(np.asarray(t, dtype=float))
        parts = [SHAPES[m].value(th, tau - self.fits[m].t_ref) for m, th in self.theta.items()]
        return np.quantile(np.concatenate(parts), quantiles, axis=0)

    def beyond(self, t: Any) -> str:
        """The note for a trend that leaves :attr:`bounds`, the range this indicator can
        take, at some of the times ``t``: "extrapolated beyond k = 1" (or "below k = 0")
        where its whole 90 % cone (:meth:`band`) lies outside the range there, "" where it
        does not. (The cone, not its median: the trend of a healthy component that sits at
        0 dips below it by its scatter, which is no extrapolation.)"""
        times = np.atleast_1d(np.asarray(t, dtype=float))
        if not self.theta or times.size == 0:
            return ""
        lo, hi = self.band(times, (0.05, 0.95))
        if np.any(lo > self.bounds[1]):
            return _bound_note(self.indicator, "hi", self.bounds)
        if np.any(hi < self.bounds[0]):
            return _bound_note(self.indicator, "lo", self.bounds)
        return ""

    def to_dict(self, samples: bool = False) -> dict[str, Any]:
        d = {"indicator": self.indicator, "threshold": self.threshold, "t_now": self.t_now,
             "model": self.model, "weights": self.weights,
             "fits": {m: f.to_dict() for m, f in self.fits.items()},
             "rul_median": _json_float(self.median), "rul_lo": _json_float(self.lo),
             "rul_hi": _json_float(self.hi), "level": self.level, "p_failed": self.p_failed,
             "p_reach": self.p_reach, "current": self.current, "seed": self.seed,
             "excluded": list(self.excluded), "discrepancy": self.discrepancy,
             "bounds": [_json_float(b) for b in self.bounds],
             "extrapolated": self.extrapolated or None}
        if samples:
            d["samples"] = [_json_float(x) for x in self.samples]
            d["theta"] = {m: np.asarray(th, dtype=float).tolist() for m, th in self.theta.items()}
        return d

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "RULPrediction":
        """The prediction :meth:`to_dict` wrote; with ``samples=True`` it holds the draws
        (for plots and :meth:`p_fail_within`), else ``p_reach`` stands in for them."""
        inf = (lambda x, sign=1.0: sign * math.inf if x is None else float(x))
        samples = data.get("samples")
        lo, hi = data.get("bounds") or (None, None)
        return cls(indicator=data["indicator"], threshold=data["threshold"], t_now=data["t_now"],
                   model=data["model"], weights=dict(data["weights"]),
                   fits={m: TrendFit.from_dict(f) for m, f in data["fits"].items()},
                   median=inf(data["rul_median"]), lo=inf(data["rul_lo"]),
                   hi=inf(data["rul_hi"]), level=data["level"], p_failed=data["p_failed"],
                   samples=np.array([inf(x) for x in samples] if samples is not None else [],
                                    dtype=float),
                   theta={m: np.asarray(th, dtype=float)
                          for m, th in (data.get("theta") or {}).items()},
                   current=data.get("current", math.nan), seed=data.get("seed"),
                   excluded=tuple(data.get("excluded") or ()),
                   discrepancy=data.get("discrepancy", 0.0), bounds=(inf(lo, -1.0), inf(hi)),
                   extrapolated=data.get("extrapolated") or "",
                   reach=None if samples is not None else data.get("p_reach"))


def _json_float(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def _bound_note(indicator: str, side: str, bounds: tuple) -> str:
    """"extrapolated beyond k = 1" and its kin, in the words of ``indicator``."""
    if indicator == "gain_drift":
        return "extrapolated beyond k8 = 0 or 1"
    if indicator in INDICATOR_COMPONENT:
        return "extrapolated beyond k = 1" if side == "hi" else "extrapolated below k = 0"
    lo, hi = bounds
    return f"extrapolated beyond {hi:g}" if side == "hi" else f"extrapolated below {lo:g}"


def _extrapolation(p: RULPrediction, thresholds: np.ndarray) -> str:
    """:attr:`RULPrediction.extrapolated` of ``p``, whose draws crossed at ``thresholds``
    (one per draw, moved by the model discrepancy)."""
    lo, hi = p.bounds
    if (note := p.beyond(p.t_now)):
        return f"{note}: the trend is at {p.current:.3g} at {p.t_now:g}"
    outside = float(np.mean((thresholds > hi) | (thresholds < lo)))
    if outside > 0:
        side = "hi" if np.any(thresholds > hi) else "lo"
        share = f"{outside:.0%}" if outside >= 0.01 else "under 1%"
        return (f"{_bound_note(p.indicator, side, p.bounds)}: {share} of the draws reach "
                f"their failure threshold (moved by the model discrepancy) only there")
    return ""


def _seed_rng(seed: Any) -> tuple[np.random.Generator, int | None]:
    """The Generator of ``seed`` (:func:`emaphm.seeds.as_generator`) and the seed as an int
    (None for a Generator)."""
    rng = as_generator(seed)
    return rng, (None if rng is seed else int(seed))


def predict_rul(t: Any, y: Any, threshold: float, *, seed: Any, t_now: float | None = None,
                models: Sequence[str] = DEFAULT_MODELS, selection: str = "average",
                level: float = 0.9, n_samples: int = 4000, sigma_floor: float = 0.003,
                reject_outliers: bool = True, indicator: str = "indicator",
                discrepancy: float = 0.0, bounds: tuple[float, float] | None = None) -> RULPrediction:
    """RUL distribution of one health indicator ``y`` (n,) observed at times ``t`` (n,).

    Parameters
    ----------
    threshold
        Failure threshold on ``y`` (> 0).
    seed
        Seed (int) or ``numpy.random.Generator`` of the Monte Carlo draws.
    t_now
        Time the RUL counts from (default: the last inspection); not before it.
    models, selection
        Trend models to fit; ``"aicc"`` keeps the lowest AICc, ``"average"`` mixes
        the models' draws in proportion to their Akaike weights.
    level
        Probability of the reported interval (default 0.9: 5th-95th percentile).
    n_samples
        Monte Carlo draws.
    sigma_floor
        Least residual standard deviation (see :func:`fit_trend`); the default
        0.003 is the per-component repeatability of an identification on a
        noisy reference-model trace (indicator units: k).
    reject_outliers
        Leave out inspections far off every trend (:func:`_inliers`): an
        identification that landed in a wrong basin (it happens: see
        ``docs/prognosis.md``) would otherwise bend the trend. Their indices are
        in :attr:`RULPrediction.excluded`.
    discrepancy
        Relative systematic error of the indicator as identified (one standard
        deviation): the monitoring model reads ``(1 + delta)`` times the true value
        (:data:`MODEL_DISCREPANCY`, measured on plant traces), ``delta ~ N(0,
        discrepancy)`` drawn once per Monte Carlo draw, so the actuator fails where the
        trend reaches ``threshold (1 + delta)``. The trend's scatter cannot see such an
        offset: it moves every inspection alike. 0 (default here): none.
    bounds
        ``(lo, hi)``, the range ``y`` can take (:data:`INDICATOR_BOUNDS` for an indicator of
        k; default: unbounded). A prediction that reads its trend outside it says so in
        :attr:`RULPrediction.extrapolated`.
    """
    if not (isinstance(threshold, (int, float, np.floating)) and math.isfinite(threshold)
            and threshold > 0):
        raise ValueError(f"failure threshold must be a positive number, got {threshold!r}")
    if isinstance(discrepancy, bool) or not isinstance(discrepancy, (int, float, np.floating)) \
            or not (math.isfinite(discrepancy) and 0.0 <= discrepancy < 1.0):
        raise ValueError(f"discrepancy must be a number in [0, 1) (a relative standard "
                         f"deviation, e.g. 0.05), got {discrepancy!r}")
    if selection not in SELECTION_RULES:
        raise ValueError(f"unknown model selection {selection!r}; choose one of "
                         f"{', '.join(SELECTION_RULES)}")
    if not 0.0 < level < 1.0:
        raise ValueError(f"level must be in (0, 1), e.g. 0.9, got {level!r}")
    if isinstance(n_samples, bool) or not isinstance(n_samples, (int, np.integer)) or n_samples < 100:
        raise ValueError(f"n_samples must be an integer >= 100, got {n_samples!r}")
    bounds = _check_bounds(bounds, threshold)
    rng, seed_int = _seed_rng(seed)
    fits = fit_trends(t, y, models, sigma_floor=sigma_floor)
    excluded: tuple = ()
    if reject_outliers:
        keep = _inliers(np.asarray(t, dtype=float), np.asarray(y, dtype=float), fits, sigma_floor)
        if not keep.all():
            excluded = tuple(int(i) for i in np.flatnonzero(~keep))
            fits = fit_trends(np.asarray(t, dtype=float)[keep], np.asarray(y, dtype=float)[keep],
                              models, sigma_floor=sigma_floor)
    t_ref = float(np.asarray(t, dtype=float)[-1])
    t_now = t_ref if t_now is None else float(t_now)
    if t_now < t_ref:
        raise ValueError(f"the time predicted at (t_now, --at) {t_now:.15g} is before the last "
                         f"inspection ({t_ref:.15g}); give a time at or after it")
    weights = select(fits)
    if selection == "aicc":
        best = min(fits, key=lambda m: (fits[m].aicc, list(fits).index(m)))
        counts = {m: (n_samples if m == best else 0) for m in fits}
        model_name = best
    else:
        counts = dict(zip(fits, rng.multinomial(n_samples, [weights[m] for m in fits])))
        model_name = "average"
    thetas, t_star, thr = _draw_crossings(fits, counts, rng, threshold, discrepancy)
    rul = np.maximum(t_star - t_now, 0.0)
    q = np.quantile(rul, [(1 - level) / 2, 0.5, (1 + level) / 2], method="inverted_cdf")
    chosen = fits[model_name] if model_name in fits else fits[max(weights, key=weights.get)]
    p = RULPrediction(indicator=indicator, threshold=float(threshold), t_now=t_now,
                      model=model_name, weights=weights, fits=fits, median=float(q[1]),
                      lo=float(q[0]), hi=float(q[2]), level=float(level),
                      p_failed=float(np.mean(t_star <= t_now)), samples=rul, theta=thetas,
                      current=float(chosen.value(t_now)[0]), seed=seed_int,
                      excluded=excluded, discrepancy=float(discrepancy), bounds=bounds)
    return replace(p, extrapolated=_extrapolation(p, thr))


def _check_bounds(bounds: Any, threshold: float) -> tuple[float, float]:
    if bounds is None:
        return (-math.inf, math.inf)
    try:
        if isinstance(bounds, str):
            raise TypeError
        lo, hi = (float(b) for b in bounds)
    except (TypeError, ValueError):
        raise ValueError(f"bounds must be a pair (lo, hi), e.g. (0, 1), got {bounds!r}") from None
    if not (lo < hi and lo <= threshold <= hi):
        raise ValueError(f"bounds ({lo:g}, {hi:g}) must be an interval that holds the failure "
                         f"threshold {threshold:g}")
    return (lo, hi)


def _draw_crossings(fits: Mapping[str, TrendFit], counts: Mapping[str, int],
                    rng: np.random.Generator, threshold: float, discrepancy: float):
    """``(theta, t_star, thresholds)``: ``counts[m]`` parameter draws of each fit (model ->
    (n_m, p)), the times they reach the failure threshold and that threshold, one per draw
    (moved by ``(1 + delta)``, ``delta ~ N(0, discrepancy)``, where ``discrepancy > 0``)."""
    thetas, crossings, thresholds = {}, [], []
    for m, fit in fits.items():
        if counts[m] == 0:
            continue
        th = fit.sample(rng, int(counts[m]))
        thetas[m] = th
        thr = np.full(th.shape[0], float(threshold))
        if discrepancy > 0:        # (drawn only then: without it the draws are as before)
            thr = threshold * np.maximum(1.0 + discrepancy * rng.standard_normal(th.shape[0]),
                                         0.05)
        crossings.append(fit.crossing_time(thr, th))
        thresholds.append(thr)
    return thetas, np.concatenate(crossings), np.concatenate(thresholds)


def _inliers(t: np.ndarray, y: np.ndarray, fits: Mapping[str, TrendFit], sigma_floor: float,
             p_false: float = 1e-4) -> np.ndarray:
    """Inspections to keep. Leave-one-out: each inspection is compared with the best
    (lowest AICc) linear or quadratic trend fitted without it (the quadratic follows an
    exponential locally; both are linear least squares, so the screen is cheap), in
    units of that fit's residual standard deviation (at least ``sigma_floor``). The
    worst one is left out when it lies beyond the two-sided Student t quantile of
    probability ``p_false`` (with the fit's degrees of freedom: about 7 standard
    deviations from 8 dof on, more with fewer), and the screen repeats. At most one in
    five inspections is left out, never the last two (a genuine acceleration shows
    there first), and only from six inspections on.

    Each screen is one fit per model: the fit without inspection ``i`` misses it by
    ``e_i / (1 - h_i)`` and leaves ``RSS - e_i^2 / (1 - h_i)`` (``e`` the residuals and
    ``h`` the leverages of the fit of all): O(n) per screen instead of a fit per
    inspection (O(n^2), 8 s of the 11 s of a prognosis of 3,000 inspections).
    :func:`_inliers_refit` is the readable reference, fit by fit."""
    keep = np.ones(t.size, dtype=bool)
    if t.size < 6:
        return keep
    models = _screen_models(fits)
    for _ in range(max(1, t.size // 5)):
        idx = np.flatnonzero(keep)
        z = np.zeros(t.size)
        crit = np.full(t.size, np.inf)
        head = idx[:-2]
        z[head], crit[head] = _loo_scores(t[idx], y[idx], models, sigma_floor, p_false)
        worst = int(np.argmax(z / crit))
        if z[worst] <= crit[worst]:
            break
        keep[worst] = False
    return keep


def _screen_models(fits: Mapping[str, TrendFit]) -> tuple[str, ...]:
    """The shapes the outlier screen compares: those of ``fits`` linear in their
    parameters (closed-form leave-one-out), or all such shapes."""
    linear = tuple(m for m, shape in SHAPES.items() if shape.linear)
    return tuple(m for m in fits if SHAPES[m].linear) or linear


def _loo_scores(t: np.ndarray, y: np.ndarray, models: Sequence[str], sigma_floor: float,
                p_false: float) -> tuple[np.ndarray, np.ndarray]:
    """For each inspection but the last two: its distance from the best trend of
    ``models`` fitted without it, in that fit's residual standard deviations, and the
    Student t quantile it is held to (the models and counts of :func:`fit_trends`)."""
    n = t.size
    m = n - 1                                  # points in each leave-one-out fit
    usable = ([k for k in models if m >= SHAPES[k].n_params + 2]
              or [k for k in models if m >= SHAPES[k].n_params + 1] or list(models))
    tau = t - t[-1]                            # the last two stay: t_ref does not move
    best_aicc = np.full(n - 2, np.inf)
    z = np.zeros(n - 2)
    crit = np.full(n - 2, np.inf)
    for model in usable:
        p = SHAPES[model].n_params
        X = SHAPES[model].jacobian(np.zeros(p), tau)
        q = np.linalg.qr(X)[0]
        resid = y - X @ np.linalg.lstsq(X, y, rcond=None)[0]
        e = resid[:-2]
        h = np.einsum("ij,ij->i", q, q)[:-2]                # leverages
        with np.errstate(divide="ignore", invalid="ignore"):
            miss = np.where(h < 1.0 - 1e-12, e / (1.0 - h), np.inf)
            rss = np.maximum(float(resid @ resid) - e * miss, 0.0)
        dof = m - p
        sigma = np.maximum(np.sqrt(rss / dof) if dof > 0 else np.inf, sigma_floor)
        aicc = _aicc_vec(rss, m, p)
        better = aicc < best_aicc
        best_aicc = np.where(better, aicc, best_aicc)
        score = np.abs(miss) / np.maximum(sigma, 1e-12)
        z = np.where(better, score, z)
        crit = np.where(better, float(stats.t.ppf(1.0 - p_false / 2.0, dof)), crit)
    return z, crit


def _aicc_vec(rss: np.ndarray, n: int, p: int) -> np.ndarray:
    """:func:`_aicc` of each residual sum of squares of ``rss``."""
    if n - p - 1 <= 0:
        return np.full(rss.shape, np.inf)
    return n * np.log(np.maximum(rss, 1e-300) / n) + 2 * p + 2 * p * (p + 1) / (n - p - 1)


def _inliers_refit(t: np.ndarray, y: np.ndarray, fits: Mapping[str, TrendFit],
                   sigma_floor: float, p_false: float = 1e-4) -> np.ndarray:
    """:func:`_inliers` as it reads, a fit without each inspection (O(n^2)): the reference
    the tests hold the fast one to."""
    keep = np.ones(t.size, dtype=bool)
    if t.size < 6:
        return keep
    models = _screen_models(fits)
    for _ in range(max(1, t.size // 5)):
        idx = np.flatnonzero(keep)
        z = np.zeros(t.size)
        crit = np.full(t.size, np.inf)
        for i in idx[:-2]:
            rest = idx[idx != i]
            loo = fit_trends(t[rest], y[rest], models, sigma_floor=sigma_floor)
            best = min(loo.values(), key=lambda f: f.aicc)
            z[i] = abs(y[i] - best.value(t[i])[0]) / max(best.sigma, sigma_floor, 1e-12)
            crit[i] = float(stats.t.ppf(1.0 - p_false / 2.0, best.dof))
        worst = int(np.argmax(z / crit))
        if z[worst] <= crit[worst]:
            break
        keep[worst] = False
    return keep


# ----------------------------------------------------------------------------- all indicators
def indicator_series(K: Any) -> dict[str, np.ndarray]:
    """Health indicator series of a k history ``K`` (n, 8): name -> (n,).

    Like :func:`emaphm.prognosis.thresholds.indicator_values`, except that the
    gain drift keeps its sign along the series, ``s (k8 - 0.5)`` with ``s`` the
    sign of the latest drift: near zero the absolute value would fold the
    identification noise upward and bend the early trend.
    """
    K = np.atleast_2d(np.asarray(K, dtype=float))
    if K.ndim != 2 or K.shape[1] != 8:
        raise ValueError(f"a k history must have shape (n, 8), got {K.shape}")
    out = {}
    for name in INDICATORS:
        j = INDICATOR_COMPONENT[name]
        if name == "gain_drift":
            d = K[:, j] - 0.5
            s = 1.0 if d[-1] >= 0 else -1.0
            out[name] = s * d
        else:
            out[name] = K[:, j].copy()
    return out


def growth_rate(fit: TrendFit) -> tuple[float, float]:
    """``(rate, standard error)`` of a trend at its reference time (the last inspection):
    its derivative there and the delta-method error from the fit's covariance."""
    rate, grad = SHAPES[fit.model].growth(fit.theta)
    var = float(grad @ fit.cov @ grad)
    return rate, math.sqrt(max(var, 0.0))


def _trend_sign(p: RULPrediction) -> tuple[int, float]:
    """Sign of the growth of the prediction's most weighted trend, 0 within 2 standard errors."""
    rate, se = growth_rate(p.top_fit)
    if not math.isfinite(rate):
        return 0, rate
    if abs(rate) <= 2.0 * se:
        return 0, rate
    return (1 if rate > 0 else -1), rate


def level_at_last(p: RULPrediction) -> float:
    """The indicator's level at the last inspection: the value there of its most weighted
    trend (not carried to a later ``t_now``: a trend of scatter, carried forward, could
    reach any level); 0 where it is not finite."""
    top = p.top_fit
    level = float(top.value(top.t_ref)[0])
    return level if math.isfinite(level) else 0.0


def indicator_state(p: RULPrediction, span: float) -> tuple[str, int, float]:
    """``(state, trend, growth rate)`` of one indicator's prediction over a history
    spanning ``span``: state ``past threshold`` (the trend is at or past it: RUL median 0),
    ``predicted`` (it grows towards it: its most weighted trend rises by more than two
    standard errors at the last inspection, and its RUL median is finite and not
    :meth:`RULPrediction.no_growth`) or ``no growth``. The rise keeps a healthy component
    out: an exponential fitted to the scatter of a k that sits at zero can cross a
    distant threshold at a finite time without any real growth. Predicted at a ``t_now``
    after the last inspection, a median of 0 is a crossing in between, which is a
    prediction like any other: past the threshold where the trend rises beyond its scatter
    or was off its healthy level at the last inspection (at least
    :data:`~emaphm.prognosis.inspection.HEALTHY_SHARE` of the threshold, so at or past the
    threshold there too); an exponential
    through one reading above the scatter of zeros, which can reach any level a few days
    on, is not."""
    from .inspection import HEALTHY_SHARE

    sign, rate = _trend_sign(p)
    if p.median <= 0.0:
        if p.t_now <= p.top_fit.t_ref or sign > 0 \
                or level_at_last(p) >= HEALTHY_SHARE * p.threshold:
            return "past threshold", sign, rate
        return "no growth", sign, rate
    if sign > 0 and math.isfinite(p.median) and not p.no_growth(span):
        return "predicted", sign, rate
    return "no growth", sign, rate


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

    def observed(self, indicator: str) -> np.ndarray:
        """Which inspections ``indicator``'s trend used (a boolean mask over ``times``)."""
        mask = np.ones(self.times.size, dtype=bool)
        mask[list(self.unobserved.get(indicator, ()))] = False
        return mask

    def readings(self, indicator: str) -> tuple[np.ndarray, np.ndarray]:
        """``(times, values)`` of the readings ``indicator``'s trend used
        (:func:`indicator_series` of the inspections that could see it)."""
        m = self.observed(indicator)
        if not m.any():
            return self.times[m], np.empty(0)
        return self.times[m], indicator_series(self.K[m])[indicator]

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
                "unobserved": {n: [int(i) for i in ix] for n, ix in self.unobserved.items()}}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "Prognosis":
        """The prognosis :meth:`to_dict` wrote (each prediction's draws where it kept
        them)."""
        return cls(actuator=data["actuator"], t_now=data["t_now"], time_unit=data["time_unit"],
                   predictions={n: RULPrediction.from_dict(p)
                                for n, p in data["predictions"].items()},
                   thresholds=FailureThresholds.from_dict(data["thresholds"]),
                   times=np.asarray(data.get("times", []), dtype=float),
                   K=np.asarray(data.get("K", []), dtype=float).reshape(-1, 8),
                   options=dict(data.get("options") or {}),
                   unobserved={n: tuple(int(i) for i in ix)
                               for n, ix in (data.get("unobserved") or {}).items()})

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
             observed: Mapping[str, Any] | None = None, **kwargs: Any) -> Prognosis:
    """RUL of each health indicator from a k history ``K`` (n, 8) at ``times`` (n,).

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
    for name in indicators:
        if name not in INDICATOR_MODE:
            raise ValueError(f"unknown health indicator {name!r}; choose from {', '.join(INDICATORS)}")
    discrepancy = MODEL_DISCREPANCY if discrepancy is None else discrepancy
    unknown = [n for n in discrepancy if n not in INDICATOR_MODE]
    if unknown:
        raise ValueError(f"discrepancy: unknown health indicator(s) {unknown}; choose from "
                         f"{', '.join(INDICATORS)}")
    series = indicator_series(K)
    times = np.asarray(times, dtype=float)
    masks = _observed_masks(observed, times.size)
    children = np.random.SeedSequence(seed).spawn(len(INDICATORS))
    preds, unobserved = {}, {}
    for name, ss in zip(INDICATORS, children):
        if name not in indicators:
            continue
        t, y = times, series[name]
        if name in masks:
            unobserved[name] = tuple(int(i) for i in np.flatnonzero(~masks[name]))
            if int(masks[name].sum()) < MIN_INSPECTIONS:
                continue
            t, y = times[masks[name]], indicator_series(np.asarray(K)[masks[name]])[name]
        preds[name] = predict_rul(t, y, thresholds.for_indicator(name),
                                  seed=np.random.default_rng(ss), t_now=t_now,
                                  sigma_floor=sigma_floor, indicator=name,
                                  discrepancy=float(discrepancy.get(name, 0.0)),
                                  bounds=INDICATOR_BOUNDS[name], **kwargs)
        preds[name] = _with_seed(preds[name], seed)
    return Prognosis(actuator=actuator, t_now=float(times[-1] if t_now is None else t_now),
                     time_unit=time_unit, predictions=preds, thresholds=thresholds,
                     times=times, K=np.atleast_2d(np.asarray(K, dtype=float)),
                     options={"sigma_floor": sigma_floor, **kwargs}, unobserved=unobserved)


def _observed_masks(observed: Mapping[str, Any] | None, n: int) -> dict[str, np.ndarray]:
    """The masks of :func:`prognose`'s ``observed`` that leave an inspection out."""
    masks = {}
    for name, m in (observed or {}).items():
        if name not in INDICATOR_MODE:
            raise ValueError(f"observed: unknown health indicator {name!r}; choose from "
                             f"{', '.join(INDICATORS)}")
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
