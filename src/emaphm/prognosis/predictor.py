"""The remaining useful life of one health indicator (:func:`predict_rul`): the trends of
:mod:`emaphm.prognosis.fits` weighted by their Akaike weights, their parameters drawn from
the fits' uncertainty, each draw's crossing of the failure threshold (the method:
:mod:`emaphm.prognosis.trends`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any, Mapping, Sequence

import numpy as np

from ..seeds import as_generator
from .choices import SELECTION_RULES
from .fits import DEFAULT_MODELS, TrendFit, _inliers, fit_trends, select
from .shapes import SHAPES
from .. import modes as _modes

__all__ = ["RULPrediction", "predict_rul"]


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
    ind = _modes.INDICATORS.get(indicator)
    if ind is not None and ind.component is not None:
        if ind.center is not None:          # a signed series, |k - c| folded
            return f"extrapolated beyond k{ind.component + 1} = 0 or 1"
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
