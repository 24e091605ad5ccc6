"""The state of an indicator's prediction (:func:`indicator_state`: past its threshold,
predicted, or no growth), from the growth of its most weighted trend at the last
inspection."""

from __future__ import annotations

import math

from .choices import HEALTHY_SHARE
from .fits import TrendFit
from .predictor import RULPrediction
from .shapes import SHAPES

__all__ = ["growth_rate", "level_at_last", "indicator_state"]


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
    :data:`~emaphm.prognosis.choices.HEALTHY_SHARE` of the threshold, so at or past the
    threshold there too); an exponential
    through one reading above the scatter of zeros, which can reach any level a few days
    on, is not."""
    sign, rate = _trend_sign(p)
    if p.median <= 0.0:
        if p.t_now <= p.top_fit.t_ref or sign > 0 \
                or level_at_last(p) >= HEALTHY_SHARE * p.threshold:
            return "past threshold", sign, rate
        return "no growth", sign, rate
    if sign > 0 and math.isfinite(p.median) and not p.no_growth(span):
        return "predicted", sign, rate
    return "no growth", sign, rate
