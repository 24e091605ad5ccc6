"""Offline prognostic metrics (Saxena, Celaya, Saha, Saha and Goebel, "Metrics for
offline evaluation of prognostic performance", IJPHM 1(1), 2010).

Notation: a prediction made at time ``t`` gives the RUL ``r(t)`` (a point, or
samples of its distribution); the true RUL is ``r*(t) = EoL - t`` with ``EoL``
the true end of life; ``t_P`` is the time of the first prediction.

==============================  ===================================================================
metric                          definition
==============================  ===================================================================
RUL error                       ``Delta(t) = r*(t) - r(t)`` (Saxena's sign: positive = predicted
                                RUL too short, an early, conservative prediction)
relative accuracy               ``RA(t) = 1 - |r*(t) - r(t)| / r*(t)``
alpha-lambda accuracy           at ``t_lambda = t_P + lambda (EoL - t_P)``: the prediction lies
                                in ``[(1 - alpha) r*, (1 + alpha) r*]``; for a distribution,
                                at least the share ``beta`` of its mass does
prognostic horizon              ``PH = EoL - t_i`` with ``t_i`` the first prediction time from
                                which on every prediction lies in ``r* +- alpha EoL`` (the
                                accuracy band of fixed width, alpha a fraction of the life;
                                with ``beta`` for distributions); ``nan`` if none does
cumulative relative accuracy    mean of RA over the predictions
coverage                        share of predictions whose interval ``[lo, hi]`` holds ``r*``
==============================  ===================================================================

All functions take arrays and return floats or arrays (results as data); the
prediction at ``t_lambda`` is the last one made at or before it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

__all__ = ["rul_error", "relative_accuracy", "cumulative_relative_accuracy", "alpha_lambda",
           "AlphaLambda", "prognostic_horizon", "coverage", "alpha_mass"]


def _arr(x: Any, name: str) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.ndim > 1:
        raise ValueError(f"{name} must be a scalar or a 1-D array, got shape {a.shape}")
    return a


def rul_error(rul_true: Any, rul_pred: Any) -> np.ndarray:
    """``r* - r`` (positive: the prediction is early)."""
    return _arr(rul_true, "rul_true") - _arr(rul_pred, "rul_pred")


def relative_accuracy(rul_true: Any, rul_pred: Any) -> np.ndarray:
    """``1 - |r* - r| / r*`` (1 is perfect; ``nan`` where ``r* <= 0``)."""
    rt = _arr(rul_true, "rul_true")
    rp = _arr(rul_pred, "rul_pred")
    with np.errstate(divide="ignore", invalid="ignore"):
        ra = 1.0 - np.abs(rt - rp) / rt
    return np.where(rt > 0, ra, np.nan)


def cumulative_relative_accuracy(rul_true: Any, rul_pred: Any) -> float:
    """Mean relative accuracy over the predictions (ignoring ``r* <= 0``)."""
    ra = np.atleast_1d(relative_accuracy(rul_true, rul_pred))
    ok = np.isfinite(ra)
    return float(np.mean(ra[ok])) if ok.any() else math.nan


def coverage(rul_true: Any, lo: Any, hi: Any) -> float:
    """Share of predictions whose interval ``[lo, hi]`` contains the true RUL."""
    rt, lo, hi = _arr(rul_true, "rul_true"), _arr(lo, "lo"), _arr(hi, "hi")
    inside = (lo <= rt) & (rt <= hi)
    return float(np.mean(inside))


def alpha_mass(samples: Any, low: float, high: float) -> float:
    """Probability mass of RUL ``samples`` inside ``[low, high]`` (inf samples count outside)."""
    s = np.asarray(samples, dtype=float).ravel()
    if s.size == 0:
        raise ValueError("no RUL samples")
    return float(np.mean((s >= low) & (s <= high)))


def _check_track(times: Any, predictions: Any) -> tuple[np.ndarray, np.ndarray]:
    t = np.asarray(times, dtype=float)
    p = np.asarray(predictions, dtype=float)
    if t.ndim != 1 or t.size == 0 or np.any(np.diff(t) <= 0):
        raise ValueError("prediction times must be a non-empty, strictly increasing 1-D array")
    if p.shape[0] != t.size or p.ndim not in (1, 2):
        raise ValueError(f"predictions must be (m,) points or (m, n_samples) samples for "
                         f"{t.size} prediction times, got shape {p.shape}")
    return t, p


def _inside(pred: np.ndarray, low: float, high: float, beta: float) -> tuple[bool, float]:
    """Point: inside the bounds; samples: mass inside >= beta."""
    if pred.ndim == 0:
        return bool(low <= float(pred) <= high), float(low <= float(pred) <= high)
    m = alpha_mass(pred, low, high)
    return bool(m >= beta), m


@dataclass(frozen=True)
class AlphaLambda:
    """Alpha-lambda accuracy at several lambdas (arrays of one length).

    ``lambdas``, ``t_lambda`` (time), ``rul_true``, ``rul_pred`` (the median
    for distributions), ``mass`` (share within the bounds; 0/1 for points),
    ``passed`` (bool); ``alpha``, ``beta`` the criteria.
    """

    alpha: float
    beta: float
    lambdas: np.ndarray
    t_lambda: np.ndarray
    rul_true: np.ndarray
    rul_pred: np.ndarray
    mass: np.ndarray
    passed: np.ndarray

    @property
    def score(self) -> float:
        """Share of the lambdas that pass."""
        return float(np.mean(self.passed))

    def to_dict(self) -> dict[str, Any]:
        return {"alpha": self.alpha, "beta": self.beta, "lambdas": self.lambdas.tolist(),
                "t_lambda": self.t_lambda.tolist(), "rul_true": self.rul_true.tolist(),
                "rul_pred": [float(x) if math.isfinite(x) else None for x in self.rul_pred],
                "mass": self.mass.tolist(), "passed": [bool(x) for x in self.passed],
                "score": self.score}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "AlphaLambda":
        arr = (lambda v: np.asarray(v, dtype=float))
        return cls(alpha=data["alpha"], beta=data["beta"], lambdas=arr(data["lambdas"]),
                   t_lambda=arr(data["t_lambda"]), rul_true=arr(data["rul_true"]),
                   rul_pred=np.array([math.inf if x is None else x for x in data["rul_pred"]],
                                     dtype=float),
                   mass=arr(data["mass"]), passed=np.asarray(data["passed"], dtype=bool))


def alpha_lambda(times: Any, predictions: Any, eol: float, *, alpha: float = 0.2,
                 lambdas: Sequence[float] = (0.5, 0.6, 0.7, 0.8, 0.9), beta: float = 0.5,
                 t_p: float | None = None) -> AlphaLambda:
    """Alpha-lambda accuracy of a track of predictions made at ``times`` (m,).

    ``predictions`` is (m,) point RULs or (m, n_samples) RUL samples; ``eol``
    the true end of life; ``t_p`` the first prediction time (default ``times[0]``).
    """
    t, p = _check_track(times, predictions)
    if not 0 < alpha < 1 or not 0 < beta <= 1:
        raise ValueError(f"alpha must be in (0, 1) and beta in (0, 1], got {alpha!r}, {beta!r}")
    t_p = float(t[0]) if t_p is None else float(t_p)
    if not eol > t_p:
        raise ValueError(f"end of life {eol:g} must come after the first prediction {t_p:g}")
    lam = np.asarray(lambdas, dtype=float)
    if np.any((lam < 0) | (lam > 1)):
        raise ValueError(f"lambdas must be in [0, 1], got {list(lambdas)}")
    rows = []
    for lv in lam:
        tl = t_p + lv * (eol - t_p)
        j = int(np.searchsorted(t, tl, side="right")) - 1
        r_true = eol - tl
        if j < 0:
            rows.append((tl, r_true, math.nan, 0.0, False))
            continue
        # the prediction made at t[j] counts down until t_lambda
        pred = p[j] - (tl - t[j])
        passed, mass = _inside(np.asarray(pred), (1 - alpha) * r_true, (1 + alpha) * r_true, beta)
        point = float(np.median(pred)) if np.ndim(pred) else float(pred)
        rows.append((tl, r_true, point, mass, passed))
    arr = list(zip(*rows))
    return AlphaLambda(alpha=float(alpha), beta=float(beta), lambdas=lam,
                       t_lambda=np.array(arr[0]), rul_true=np.array(arr[1]),
                       rul_pred=np.array(arr[2]), mass=np.array(arr[3]),
                       passed=np.array(arr[4], dtype=bool))


def prognostic_horizon(times: Any, predictions: Any, eol: float, *, alpha: float = 0.1,
                       beta: float = 0.5) -> float:
    """``EoL - t_i``: ``t_i`` the first prediction time from which on all predictions lie
    within ``r* +- alpha EoL`` (mass >= ``beta`` for samples); ``nan`` if none."""
    t, p = _check_track(times, predictions)
    if not 0 < alpha < 1 or not 0 < beta <= 1:
        raise ValueError(f"alpha must be in (0, 1) and beta in (0, 1], got {alpha!r}, {beta!r}")
    ok = []
    for j in range(t.size):
        r_true = eol - t[j]
        ok.append(_inside(np.asarray(p[j]), r_true - alpha * eol, r_true + alpha * eol, beta)[0])
    ok_arr = np.array(ok, dtype=bool)
    for j in range(t.size):
        if ok_arr[j:].all():
            return float(eol - t[j])
    return math.nan
