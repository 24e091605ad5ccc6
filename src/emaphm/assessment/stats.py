"""The statistics of an assessment: proportions with their intervals, and hit/miss POD
curves in the manner of MIL-HDBK-1823A.

Intervals
---------
A proportion ``k / n`` (a false-alarm rate, a probability of detection) gets the **Wilson
score** 95 % interval (:func:`wilson`): unlike the Wald interval it stays inside [0, 1]
and keeps close to its nominal coverage for small ``n`` and for rates near 0 or 1, where
an assessment's rates are. ``0 / 200`` gives [0, 1.9 %].

POD curve
---------
MIL-HDBK-1823A models hit/miss data by a generalised linear model in the log of the
size: ``POD(a) = F(b0 + b1 ln a)`` with ``F`` the logistic function (:func:`pod_fit`,
maximum likelihood). ``a90`` is the size detected with probability 0.9, and ``a90/95``
the upper end of its one-sided 95 % confidence bound, from the profile likelihood of
``a90`` (the likelihood-ratio bound the handbook recommends): the largest ``a`` whose
constrained fit ``POD(a) = 0.9`` is not rejected at 95 % by the likelihood-ratio test
(``2 (l_max - l(a)) <= chi2_1(0.90) = 2.706``, one-sided 95 %). The fit needs misses
and hits that overlap in size; where every run is a hit (or none), there is no curve and
:func:`pod_fit` says why.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from scipy import optimize, special, stats

__all__ = ["wilson", "Proportion", "proportion", "PODFit", "pod_fit", "Z95"]

#: The two-sided 95 % normal quantile.
Z95 = float(stats.norm.ppf(0.975))


def wilson(k: int, n: int, z: float = Z95) -> tuple[float, float]:
    """The Wilson score interval of ``k`` successes in ``n`` trials (95 % by default);
    ``(0, 1)`` for ``n = 0``."""
    if n <= 0:
        return 0.0, 1.0
    if not 0 <= k <= n:
        raise ValueError(f"a proportion needs 0 <= k <= n, got k={k}, n={n}")
    p = k / n
    den = 1.0 + z * z / n
    mid = (p + z * z / (2 * n)) / den
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / den
    # exact at the ends: 0/n has lower bound 0, n/n upper bound 1
    return (0.0 if k == 0 else max(0.0, mid - half)), (1.0 if k == n else min(1.0, mid + half))


@dataclass(frozen=True)
class Proportion:
    """``k`` of ``n``, its ``rate`` and Wilson 95 % interval ``[lo, hi]``."""

    k: int
    n: int
    rate: float
    lo: float
    hi: float

    def to_dict(self) -> dict[str, float | int]:
        return {"k": self.k, "n": self.n, "rate": self.rate, "lo": self.lo, "hi": self.hi}

    @classmethod
    def from_dict(cls, d: dict) -> "Proportion":
        """The proportion :meth:`to_dict` wrote."""
        return cls(int(d["k"]), int(d["n"]), float(d["rate"]), float(d["lo"]), float(d["hi"]))


def proportion(k: int, n: int) -> Proportion:
    lo, hi = wilson(k, n)
    return Proportion(int(k), int(n), (k / n) if n else float("nan"), lo, hi)


#: What :func:`pod_fit` found, :attr:`PODFit.status`: a curve with its bound; a curve whose
#: bound lies beyond the sizes tried; or why there is no curve. ``"not recorded"``: a fit
#: read from a record written before the status was (:meth:`PODFit.from_dict`).
POD_STATUS = ("fitted", "bound beyond", "too few sizes", "no hit", "every run a hit",
              "separated", "not growing", "not recorded")


@dataclass(frozen=True)
class PODFit:
    """A hit/miss POD curve ``POD(a) = logistic(b0 + b1 ln a)``, or why there is none.

    ``a90``: the size detected with probability 0.9; ``a90_95``: its one-sided 95 % upper
    confidence bound (profile likelihood); None where the fit does not exist (``note``
    says why) or the bound lies beyond the sizes tried (``a90_95`` None, ``note`` says so).
    ``status``: which of these it is, one of :data:`POD_STATUS` (for programs; ``note``
    is for people).
    """

    b0: float | None
    b1: float | None
    a90: float | None
    a90_95: float | None
    n: int
    note: str = ""
    status: str = "fitted"

    def __post_init__(self) -> None:
        if self.status not in POD_STATUS:
            raise ValueError(f"status must be one of {', '.join(POD_STATUS)}, got "
                             f"{self.status!r}")

    @classmethod
    def from_dict(cls, d: dict) -> "PODFit":
        """The fit :meth:`to_dict` wrote (a record without ``status``: "not recorded")."""
        return cls(d["b0"], d["b1"], d["a90"], d["a90_95"], int(d["n"]), d.get("note", ""),
                   d.get("status", "not recorded"))

    def pod(self, a: np.ndarray) -> np.ndarray:
        """The fitted POD at sizes ``a``."""
        if self.b0 is None or self.b1 is None:
            raise ValueError(f"no POD curve: {self.note}")
        return special.expit(self.b0 + self.b1 * np.log(np.asarray(a, dtype=float)))

    def to_dict(self) -> dict[str, float | int | str | None]:
        return {"b0": self.b0, "b1": self.b1, "a90": self.a90, "a90_95": self.a90_95,
                "n": self.n, "note": self.note, "status": self.status}


#: logit(0.9)
_LOGIT90 = math.log(9.0)
#: The likelihood-ratio statistic of a one-sided 95 % bound (chi2 with 1 dof at 0.90).
_LR95 = float(stats.chi2.ppf(0.90, 1))


def _nll(beta: np.ndarray, x: np.ndarray, y: np.ndarray) -> float:
    eta = beta[0] + beta[1] * x
    # -log L of a logistic regression, stable for any eta
    return float(np.sum(np.logaddexp(0.0, eta) - y * eta))


def pod_fit(sizes: Sequence[float], hits: Sequence[bool]) -> PODFit:
    """Fit a hit/miss POD curve to ``sizes`` (> 0) and ``hits`` (see the module doc)."""
    a = np.asarray(sizes, dtype=float)
    y = np.asarray(hits, dtype=float)
    if a.shape != y.shape or a.ndim != 1:
        raise ValueError("sizes and hits must be two sequences of the same length")
    keep = a > 0
    a, y = a[keep], y[keep]
    n = int(a.size)
    if n < 3 or np.unique(a).size < 2:
        return PODFit(None, None, None, None, n, "fewer than two sizes tried", "too few sizes")
    if y.sum() == 0:
        return PODFit(None, None, None, None, n, "no hit at any size: no curve", "no hit")
    if y.sum() == n:
        return PODFit(None, None, None, None, n,
                      f"every run a hit (the smallest size tried, {a.min():g}, is detected "
                      "every time): no curve, a90 is below the sizes tried", "every run a hit")
    x = np.log(a)
    if x[y == 1].min() > x[y == 0].max():
        return PODFit(None, None, None, None, n,
                      "hits and misses do not overlap in size (perfect separation): "
                      f"a90 lies between {np.exp(x[y == 0].max()):g} and "
                      f"{np.exp(x[y == 1].min()):g}", "separated")
    res = optimize.minimize(_nll, np.array([0.0, 1.0]), args=(x, y), method="BFGS")
    b0, b1 = (float(v) for v in res.x)
    if not (math.isfinite(b0) and math.isfinite(b1)) or b1 <= 0:
        return PODFit(b0, b1, None, None, n, "the fitted POD does not grow with size",
                      "not growing")
    l_max = -_nll(res.x, x, y)
    a90 = math.exp((_LOGIT90 - b0) / b1)

    def deficit(log_a: float) -> float:
        # the best fit constrained to POD(a) = 0.9: b0 = logit90 - b1 log a, b1 free
        f = lambda b: _nll(np.array([_LOGIT90 - b * log_a, b]), x, y)  # noqa: E731
        r = optimize.minimize_scalar(f, bounds=(1e-6, 1e3), method="bounded")
        return 2.0 * (l_max + r.fun) - _LR95

    lo = math.log(a90)
    hi = float(x.max()) + math.log(4.0)      # search the bound up to 4x the largest size
    if deficit(hi) < 0:
        return PODFit(b0, b1, a90, None, n,
                      f"the 95 % bound of a90 lies beyond 4x the largest size tried ({a.max():g})",
                      "bound beyond")
    log_bound = optimize.brentq(deficit, lo, hi, xtol=1e-6)
    return PODFit(b0, b1, a90, math.exp(log_bound), n)
