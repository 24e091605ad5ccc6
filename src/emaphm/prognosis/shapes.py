"""The shapes a health indicator's trend can take: one class per shape, in a registry.

Each shape (:class:`TrendShape`) knows its parameters, written relative to the last
inspection ``t_ref`` (``tau = t - t_ref``; the first parameter is the current level), and
everything the trends ask of it: its value, its Jacobian, its least-squares fit, the time
it reaches a threshold and its growth at ``t_ref``. :mod:`emaphm.prognosis.trends` fits,
compares and samples them without knowing which is which: a new shape is one class here,
registered in :data:`SHAPES`, and a shape that misses a method fails loudly instead of
being computed as another.

===========  ====================================  ==========================
shape        y(t), tau = t - t_ref                 parameters theta
===========  ====================================  ==========================
linear       a + b tau                             (a, b)
exponential  exp(alpha + b tau)                    (alpha = ln a, b)
quadratic    a + b tau + c tau^2                   (a, b, c)
onset        a + b max(tau, c)                     (a, b, c = t_onset - t_ref)
===========  ====================================  ==========================
"""

from __future__ import annotations

import math
from types import MappingProxyType
from typing import Any, Mapping

import numpy as np
from scipy import optimize

__all__ = ["TrendShape", "Linear", "Quadratic", "Onset", "Exponential", "SHAPES",
           "crossing_tau"]

_ALPHA_MIN = math.log(1e-9)


class TrendShape:
    """One shape of trend. ``name`` its key in :data:`SHAPES`, ``n_params`` the length of
    its ``theta``; ``linear``: linear in its parameters (fitted in closed form, and the
    shapes the outlier screen of :mod:`emaphm.prognosis.trends` compares)."""

    name: str = ""
    n_params: int = 0
    linear: bool = False

    def value(self, theta: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """The trend at ``tau`` (m,) of parameters ``theta`` (..., p) -> (..., m)."""
        raise NotImplementedError(f"{type(self).__name__}.value")

    def jacobian(self, theta: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """d value / d theta at ``tau`` (m,) for one ``theta`` (p,) -> (m, p)."""
        raise NotImplementedError(f"{type(self).__name__}.jacobian")

    def fit(self, tau: np.ndarray, y: np.ndarray) -> np.ndarray:
        """The least-squares ``theta`` (p,) of ``y`` (n,) at ``tau`` (n,), ascending, the
        last 0."""
        raise NotImplementedError(f"{type(self).__name__}.fit")

    def level_and_time(self, theta: np.ndarray, threshold: Any) -> tuple[np.ndarray, np.ndarray]:
        """For each row of ``theta`` (n, p): the level the crossing is judged from (at
        ``t_ref``, or where the trend starts to move) and the ``tau`` at which the trend
        reaches ``threshold`` (a number or one per row; +inf: never), each (n,)."""
        raise NotImplementedError(f"{type(self).__name__}.level_and_time")

    def growth(self, theta: np.ndarray) -> tuple[float, np.ndarray]:
        """The trend's derivative at ``t_ref`` and its gradient with respect to ``theta``
        (for the delta method)."""
        raise NotImplementedError(f"{type(self).__name__}.growth")

    def constrain(self, theta: np.ndarray) -> np.ndarray:
        """Parameter draws (n, p) held where the fit holds them (in place, returned)."""
        return theta

    def lost(self, theta: np.ndarray, noise: float) -> bool:
        """Whether a fit's covariance means nothing at this noise level [indicator units]
        (its Jacobian vanishes with a parameter lost in the noise)."""
        return False


class Linear(TrendShape):
    """Wear at a steady rate: ``a + b tau``."""

    name, n_params, linear = "linear", 2, True

    def value(self, theta, tau):
        theta = np.asarray(theta, dtype=float)
        return theta[..., 0:1] + theta[..., 1:2] * tau

    def jacobian(self, theta, tau):
        return np.column_stack([np.ones_like(tau), tau])

    def fit(self, tau, y):
        return np.linalg.lstsq(self.jacobian(None, tau), y, rcond=None)[0]

    def level_and_time(self, theta, threshold):
        a, b = theta[:, 0], theta[:, 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            return a, np.where(b > 0, (threshold - a) / b, np.inf)

    def growth(self, theta):
        return float(theta[1]), np.eye(self.n_params)[1]


class Quadratic(Linear):
    """A local second-order trend (growth that is neither linear nor exponential, such as
    a power law): ``a + b tau + c tau^2``."""

    name, n_params, linear = "quadratic", 3, True

    def value(self, theta, tau):
        theta = np.asarray(theta, dtype=float)
        return theta[..., 0:1] + theta[..., 1:2] * tau + theta[..., 2:3] * tau * tau

    def jacobian(self, theta, tau):
        return np.column_stack([np.ones_like(tau), tau, tau * tau])

    def level_and_time(self, theta, threshold):
        a, b, c = theta[:, 0], theta[:, 1], theta[:, 2]
        gap = threshold - a
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            disc = b * b + 4.0 * c * gap
            sq = np.sqrt(np.where(disc >= 0, disc, np.nan))
            # roots of c tau^2 + b tau - gap = 0 in the stable form q / c and -gap / q;
            # c = 0 leaves the linear root gap / b; the smallest positive root counts
            q = -0.5 * (b + np.where(b >= 0, 1.0, -1.0) * sq)
            roots = np.stack([q / c, -gap / q])
            roots = np.where(np.isfinite(roots) & (roots > 0), roots, np.inf)
            return a, np.min(roots, axis=0)


class Onset(TrendShape):
    """Linear growth that began at an unknown time between two inspections, flat before
    it (segmented regression with one breakpoint): ``a + b max(tau, c)``."""

    name, n_params = "onset", 3

    def value(self, theta, tau):
        theta = np.asarray(theta, dtype=float)
        return theta[..., 0:1] + theta[..., 1:2] * np.maximum(tau, theta[..., 2:3])

    def jacobian(self, theta, tau):
        b, c = float(theta[1]), float(theta[2])
        return np.column_stack([np.ones_like(tau), np.maximum(tau, c), b * (tau < c)])

    def fit(self, tau, y):
        return _fit_onset(tau, y)

    def level_and_time(self, theta, threshold):
        # flat until the onset c, linear after it: below the threshold at max(0, c), a
        # rising line reaches it beyond there (fits and draws keep c <= 0; a theta given
        # to crossing_time by hand may not)
        a, b = theta[:, 0], theta[:, 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            return (a + b * np.maximum(theta[:, 2], 0.0),
                    np.where(b > 0, (threshold - a) / b, np.inf))

    def growth(self, theta):                  # the onset is before t_ref
        return float(theta[1]), np.eye(self.n_params)[1]

    def constrain(self, theta):
        """An onset is drawn no later than the last inspection, as it is fitted (where the
        slope is lost in the noise its variance is huge, and an onset drawn far ahead would
        hold the level of the flat part there: ``a + b c`` past any threshold)."""
        theta[:, 2] = np.minimum(theta[:, 2], 0.0)
        return theta


class Exponential(TrendShape):
    """Self-accelerating damage: ``exp(alpha + b tau)``."""

    name, n_params = "exponential", 2

    def value(self, theta, tau):
        theta = np.asarray(theta, dtype=float)
        return np.exp(np.clip(theta[..., 0:1] + theta[..., 1:2] * tau, -700.0, 700.0))

    def jacobian(self, theta, tau):
        y = self.value(theta, tau)
        return np.column_stack([y, tau * y])

    def fit(self, tau, y):
        return _fit_exponential(tau, y)

    def level_and_time(self, theta, threshold):
        a, b = theta[:, 0], theta[:, 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            return (np.exp(np.clip(a, -700.0, 700.0)),
                    np.where(b > 0, (np.log(threshold) - a) / b, np.inf))

    def lost(self, theta, noise):
        """Its level ``exp(alpha)`` below the noise: the Jacobian scales with it."""
        return math.exp(float(theta[0])) < noise

    def growth(self, theta):                  # exp(alpha + b tau): d/dtau = exp(alpha) b
        level = math.exp(min(float(theta[0]), 700.0))
        b = float(theta[1])
        return level * b, np.array([level * b, level])


#: The trend shapes by name, in the order they are fitted and listed.
SHAPES: Mapping[str, TrendShape] = MappingProxyType(
    {s.name: s for s in (Linear(), Exponential(), Quadratic(), Onset())})


def crossing_tau(shape: TrendShape, theta: np.ndarray, threshold: Any) -> np.ndarray:
    """Time relative to ``t_ref`` where the trend reaches ``threshold`` (a number, or one
    per draw) (n, p) -> (n,): +inf if it never does, 0 if the trend is at or above it at
    ``t_ref`` already (failed already, counted at ``t_ref``, whatever the slope)."""
    level, tau = shape.level_and_time(theta, threshold)
    return np.where(level >= threshold, 0.0, tau)


#: Rates ``b * span`` at which :func:`_fit_exponential` evaluates the profiled cost before
#: refining the best: every 1 over the bounds (+-60), every 0.1 where growth is realistic.
_RATE_GRID = np.unique(np.r_[np.linspace(-60.0, 60.0, 121), np.linspace(-5.0, 5.0, 101)])


def _fit_exponential(tau: np.ndarray, y: np.ndarray) -> np.ndarray:
    """(alpha, b) of ``y = exp(alpha + b tau)`` by least squares in y, within the bounds
    ``alpha`` in [ln 1e-9, ln 10], ``b`` in +-60 / span.

    Variable projection: at a fixed rate ``b`` the cost is a parabola in the level
    ``A = exp(alpha)``, whose constrained minimum is its vertex clipped to the bounds; the
    profiled cost of ``b`` alone is evaluated on :data:`_RATE_GRID` and refined between the
    best point's neighbours by bounded Brent. The same minimum as a trust-region search
    from several starts (``tests/prognosis/test_prognosis_trends.py`` checks it against
    ``scipy.optimize.least_squares``), a tenth of the time: a fleet site fits it for every
    indicator of every actuator.
    """
    span = max(float(tau[-1] - tau[0]), 1e-12)
    a_lo, a_hi = math.exp(_ALPHA_MIN), 10.0
    yy = float(y @ y)

    def profile(rates: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        E = np.exp(np.multiply.outer(rates / span, tau))            # (m, n), tau <= 0
        ee = np.einsum("ij,ij->i", E, E)
        ey = E @ y
        A = np.clip(ey / ee, a_lo, a_hi)
        return A, yy - 2.0 * A * ey + A * A * ee

    cost = profile(_RATE_GRID)[1]
    i = int(np.argmin(cost))
    lo, hi = _RATE_GRID[max(i - 1, 0)], _RATE_GRID[min(i + 1, _RATE_GRID.size - 1)]
    res = optimize.minimize_scalar(lambda r: float(profile(np.array([r]))[1][0]),
                                   bounds=(lo, hi), method="bounded",
                                   options={"xatol": 1e-9})
    r = float(res.x) if res.fun <= cost[i] else float(_RATE_GRID[i])
    level = float(profile(np.array([r]))[0][0])
    return np.array([math.log(level), r / span])


def _onset_profile(tau: np.ndarray, y: np.ndarray, c: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For each onset in ``c`` (m,): the least-squares level ``a`` and slope ``b`` of
    ``y = a + b max(tau, c)`` and its residual sum of squares, each (m,); ``tau`` (n,)
    ascending, its last 0 (the reference time).

    In closed form, O(n + m) time and memory (the regressor matrix ``max(tau, c)`` of
    every onset, (m, n), held 1.6 GB at 10,000 inspections): with the ``r`` points after
    ``c`` (their mean time ``m``, their own sum of squares ``S`` and cross product ``P``
    with ``y``, ``d = m - c``), the centred sums are ``s_xx = S + r d^2 (1 - r / n)`` and
    ``s_xy = P + d sum(y - mean(y))`` over them. The sums over the points after ``c`` are
    taken from the end (reversed cumulative sums, the times measured from the last),
    where they are small: no sum over all the points is subtracted from another.
    """
    n = tau.size
    cu = np.asarray(c, dtype=float)
    yc = y - y.mean()

    def from_end(x: np.ndarray) -> np.ndarray:      # [k] = sum of x[k:], [n] = 0
        return np.concatenate([np.cumsum(x[::-1])[::-1], np.zeros(1)])

    k = np.searchsorted(tau, cu, side="right")       # points at or before the onset
    r = (n - k).astype(float)
    s1, s2 = from_end(tau)[k], from_end(tau * tau)[k]
    sy, sty = from_end(yc)[k], from_end(tau * yc)[k]
    with np.errstate(divide="ignore", invalid="ignore"):
        m = np.where(r > 0, s1 / r, cu)
        own = np.where(r > 0, np.maximum(s2 - s1 * m, 0.0), 0.0)
        cross = np.where(r > 0, sty - m * sy, 0.0)
    d = m - cu
    sxx = own + r * d * d * (1.0 - r / n)
    sxy = cross + d * sy
    with np.errstate(divide="ignore", invalid="ignore"):      # every x alike: no slope
        b = np.where(sxx > 0, sxy / sxx, 0.0)
    xm = cu + r * d / n
    a = float(y.mean()) - b * xm
    rss = np.maximum(float(yc @ yc) - b * sxy, 0.0)
    return a, b, rss


def _fit_onset(tau: np.ndarray, y: np.ndarray) -> np.ndarray:
    """(a, b, c) of ``y = a + b max(tau, c)`` by least squares, the onset ``c`` between the
    first inspection and the third from last (at least three inspections on the slope, the
    one at the onset included; ``c`` at the first is the linear trend).

    Exact, in closed form: with the onset between inspections ``j`` and ``j + 1`` the
    ``m = j + 1`` first regressors are ``c``, so the centred sums are ``s_xy = alpha c +
    beta`` and ``s_xx = A c^2 + B c + C``, and the residual ``s_yy - s_xy^2 / s_xx`` is
    least where ``s_xy^2 / s_xx`` is greatest: at the stretch's ends or at its one
    stationary point ``c* = (beta B - 2 alpha C) / (alpha B - 2 beta A)``. Every candidate
    of every stretch is evaluated and the least residual kept.
    """
    n = tau.size
    edges = tau[:max(n - 2, 1)]
    cand = [edges]
    if edges.size >= 2:
        m = np.arange(1, edges.size, dtype=float)               # points at or before c
        ys, ts = float(y.sum()), tau.sum()
        yh = np.cumsum(y)[:m.size]
        st = ts - np.cumsum(tau)[:m.size]                        # sums over the rest
        qt = float(tau @ tau) - np.cumsum(tau * tau)[:m.size]
        pt = float(tau @ y) - np.cumsum(tau * y)[:m.size]
        alpha, beta = yh - m * ys / n, pt - st * ys / n
        A, B, C = m * (1.0 - m / n), -2.0 * m * st / n, qt - st * st / n
        with np.errstate(divide="ignore", invalid="ignore"):
            cs = (beta * B - 2.0 * alpha * C) / (alpha * B - 2.0 * beta * A)
        cs = np.clip(np.where(np.isfinite(cs), cs, edges[:-1]), edges[:-1], edges[1:])
        cand.append(cs)
    c = np.concatenate(cand)
    a, b, rss = _onset_profile(tau, y, c)
    i = int(np.argmin(rss))
    return np.array([float(a[i]), float(b[i]), float(c[i])])
