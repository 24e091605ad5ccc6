"""Least-squares trends of one health indicator: each shape of
:mod:`emaphm.prognosis.shapes` fitted with its covariance, compared by the corrected
Akaike criterion, and the screen that leaves outlying inspections out (the method:
:mod:`emaphm.prognosis.trends`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable, Mapping, Sequence

import numpy as np
from scipy import stats

from .shapes import SHAPES, crossing_tau

__all__ = ["TREND_MODELS", "DEFAULT_MODELS", "MIN_INSPECTIONS", "TrendFit", "fit_trend",
           "fit_trends", "select"]

TREND_MODELS = tuple(SHAPES)
#: The models fitted by default.
DEFAULT_MODELS = TREND_MODELS
#: Least number of inspections for a trend with an uncertainty (two parameters + one dof).
MIN_INSPECTIONS = 3


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
    return _screen(t, fits, lambda idx, models: _loo_scores(t[idx], y[idx], models,
                                                            sigma_floor, p_false))


def _screen(t: np.ndarray, fits: Mapping[str, TrendFit],
            scores: Callable[[np.ndarray, tuple[str, ...]], tuple[np.ndarray, np.ndarray]]
            ) -> np.ndarray:
    """The outlier screen's rule (:func:`_inliers`): from six inspections on, at most one in
    five left out, one at a time, never the last two. ``scores(idx, models)``: the
    distance and the quantile it is held to of each kept inspection ``idx`` but the last
    two."""
    keep = np.ones(t.size, dtype=bool)
    if t.size < 6:
        return keep
    models = _screen_models(fits)
    for _ in range(max(1, t.size // 5)):
        idx = np.flatnonzero(keep)
        z = np.zeros(t.size)
        crit = np.full(t.size, np.inf)
        head = idx[:-2]
        z[head], crit[head] = scores(idx, models)
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
    def scores(idx: np.ndarray, models: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray]:
        z, crit = np.zeros(idx.size - 2), np.full(idx.size - 2, np.inf)
        for j, i in enumerate(idx[:-2]):
            rest = idx[idx != i]
            loo = fit_trends(t[rest], y[rest], models, sigma_floor=sigma_floor)
            best = min(loo.values(), key=lambda f: f.aicc)
            z[j] = abs(y[i] - best.value(t[i])[0]) / max(best.sigma, sigma_floor, 1e-12)
            crit[j] = float(stats.t.ppf(1.0 - p_false / 2.0, best.dof))
        return z, crit

    return _screen(t, fits, scores)
