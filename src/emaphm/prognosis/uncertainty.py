"""Uncertainty of one diagnosis: an interval on each component of the identified k.

Three methods, from cheap to thorough (``method=`` of :func:`identify_with_spread`):

``"population"`` (default, free)
    Reuses every monitoring-model run the identification already paid for
    (swarm and polish). Reading the Eq. 4 fitness ``f`` as a weighted sum of
    squared residuals, the likelihood-ratio statistic of a candidate is

        D(k) = n_eff (f(k) - f_min) / f_min

    with ``f_min`` the best fitness (its residual stands in for the noise
    variance) and ``n_eff`` the number of independent residuals: the samples
    of the three phases divided by their integrated autocorrelation time
    (the residual is coloured by the current loop and by the monitoring
    model's approximations, so the raw sample count would claim far too much).
    The interval of component ``i`` is the range of ``k_i`` over the evaluated
    points with ``D <= chi2_1(level)`` (a profile-likelihood interval sampled
    by the swarm); it always contains the identified ``k``. Since it sees only
    the points the swarm visited, it can be narrower than the true region
    where the swarm converged fast.
``"seeds"``
    ``n_runs`` identifications with optimizer seeds spawned from ``seed``
    (sharing one objective, so the trace is set up once): ``k`` is the
    component-wise median, the interval the envelope of the runs joined with
    the population interval of all their evaluations. Measures how well the
    optimizer repeats as well as the fit's flatness. (The default least-squares
    pipeline repeats itself whenever its first start is good enough, the seed only
    drawing its further starts: use a metaheuristic or ``"bootstrap"`` with it.)
``"bootstrap"``
    ``n_runs`` identifications on noise resampled traces: the monitoring
    model's currents at the identified ``k`` plus the residuals, resampled in
    blocks as long as their autocorrelation time (a moving-block bootstrap,
    phases kept together so the currents still sum to zero). The interval is
    the central ``level`` range of the resampled ``k`` joined with the
    identified ``k``. Measures the effect of the measurement noise.

Each interval is then joined with ``k +- error_floor``, the identification's
own error that no single-trace statistic can see: the monitoring model is not
the reference model, and that model discrepancy, not the sensor noise,
dominates the error (the likelihood region of a noisy reference-model trace is
often narrower than 0.001 while the identified k is off by 0.003-0.01). The
default :data:`IDENTIFICATION_ERROR_P90` is the 90th percentile of
``|k_i - k_true,i|`` of PSO (default budget, polished) over 24 simulated
reference-model traces with sensor noise (12 single-fault cases, friction,
backlash, short circuit, eccentricity, gain drift, and nominal, 2 noise seeds
each; ``benchmarks/bench_prognosis.py --calibrate``). Pass ``error_floor=0``
for the bare statistic.

Every random draw comes from ``seed`` (through ``numpy.random.SeedSequence``).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np
from scipy import stats

from ..faults import K_NAMES
from ..seeds import check_seed
from ..fitness import eq4_weights, effective_samples

if TYPE_CHECKING:  # annotations only
    from ..fitness import Eq4Objective

__all__ = ["SPREAD_METHODS", "KInterval", "IdentificationSpread", "identify_with_spread",
           "population_interval", "effective_samples",
           "IDENTIFICATION_ERROR_P90"]

from .choices import SPREAD_METHODS  # noqa: E402  (the CLI reads it without SciPy)

#: 90th percentile of the per-component identification error |k_i - k_true,i| (see the
#: module docstring; benchmarks/results/prognosis.md), rounded up, the three phases given
#: the largest of theirs; k7 (eccentricity phase) gets none: it is undetermined at k6 = 0,
#: which the likelihood region already shows.
IDENTIFICATION_ERROR_P90 = np.array([0.010, 0.0065, 0.003, 0.003, 0.003, 0.0025, 0.0, 0.002])
IDENTIFICATION_ERROR_P90.setflags(write=False)


@dataclass(frozen=True)
class KInterval:
    """An interval on each component of k.

    ``k`` (8,) the point estimate, ``lo`` and ``hi`` (8,) the bounds, ``method``
    one of :data:`SPREAD_METHODS`, ``level`` the nominal probability, ``n`` the
    points behind it (evaluations inside the region, runs or resamples),
    ``details`` numbers of the method (``n_eff``, ``f_min``...).
    """

    k: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    method: str
    level: float
    n: int
    details: dict = field(default_factory=dict)

    @property
    def half_width(self) -> np.ndarray:
        return 0.5 * (self.hi - self.lo)

    def to_dict(self) -> dict[str, Any]:
        return {"k": self.k.tolist(), "lo": self.lo.tolist(), "hi": self.hi.tolist(),
                "method": self.method, "level": self.level, "n": self.n,
                "details": self.details}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "KInterval":
        return cls(k=np.asarray(data["k"], dtype=float), lo=np.asarray(data["lo"], dtype=float),
                   hi=np.asarray(data["hi"], dtype=float), method=data["method"],
                   level=data["level"], n=data["n"], details=dict(data.get("details") or {}))

    def to_frame(self) -> Any:
        """One row per component of k: its name, value and interval (pandas)."""
        from ..frames import require_pandas

        pd = require_pandas("KInterval.to_frame")
        return pd.DataFrame({"component": [f"k{i + 1}" for i in range(len(self.k))],
                             "name": list(K_NAMES), "k": self.k, "lo": self.lo, "hi": self.hi})

    def table(self) -> str:
        lines = [f"{'k':4s} {'component':14s} {'value':>8s} {'interval (' + format(self.level, '.0%') + ', ' + self.method + ')':>34s}"]
        for i, name in enumerate(K_NAMES):
            lines.append(f"k{i + 1:<3d} {name:14s} {self.k[i]:8.4f}   [{self.lo[i]:.4f}, {self.hi[i]:.4f}]")
        return "\n".join(lines)


@dataclass(frozen=True)
class IdentificationSpread:
    """An identification with the interval of its k (results as data); named
    ``Assessment`` before 0.5 (that name, kept for one release with a DeprecationWarning,
    is taken by :mod:`emaphm.assessment`, the assessment of the diagnosis itself).

    ``identification`` is the run whose k is reported (the first run; for
    ``"seeds"`` the run of best fitness); ``runs`` all identifications made;
    ``evaluations`` and ``elapsed_s`` their total cost.
    """

    identification: Any
    interval: KInterval
    runs: tuple
    evaluations: int
    elapsed_s: float

    @property
    def k(self) -> np.ndarray:
        return self.interval.k

    def to_dict(self) -> dict[str, Any]:
        """As data: the identification reported, the interval, every run, the cost."""
        return {"identification": self.identification.to_dict(),
                "interval": self.interval.to_dict(),
                "runs": [r.to_dict() for r in self.runs],
                "evaluations": int(self.evaluations), "elapsed_s": float(self.elapsed_s)}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "IdentificationSpread":
        from ..identify import Identification

        return cls(identification=Identification.from_dict(data["identification"]),
                   interval=KInterval.from_dict(data["interval"]),
                   runs=tuple(Identification.from_dict(r) for r in data["runs"]),
                   evaluations=int(data["evaluations"]), elapsed_s=float(data["elapsed_s"]))

    def to_frame(self) -> Any:
        """The interval of each component (:meth:`KInterval.to_frame`)."""
        return self.interval.to_frame()


class _Recorder:
    """An objective that remembers every point it evaluated (and its fitness)."""

    def __init__(self, base: Eq4Objective) -> None:
        self.base = base
        self.K: list[np.ndarray] = []
        self.f: list[np.ndarray] = []

    def __getattr__(self, name: str) -> Any:      # model, stats, target, weights, ...
        return getattr(self.base, name)

    def __call__(self, K: np.ndarray) -> np.ndarray:
        f = self.base(K)
        self.K.append(np.array(np.atleast_2d(K), dtype=float))
        self.f.append(np.array(f, dtype=float))
        return f

    def residuals(self, K: np.ndarray) -> np.ndarray:
        """The least-squares pipeline's evaluations, recorded with their fitness."""
        R = self.base.residuals(K)
        f = np.einsum("ij,ij->i", R, R)
        f[~np.isfinite(f)] = np.inf
        self.K.append(np.array(np.atleast_2d(K), dtype=float))
        self.f.append(f)
        return R

    def points(self) -> tuple[np.ndarray, np.ndarray]:
        if not self.K:
            return np.empty((0, 8)), np.empty(0)
        return np.concatenate(self.K), np.concatenate(self.f)


def _residual(objective: Any, k: np.ndarray, nu: Any = None) -> np.ndarray:
    """Weighted residual sqrt(w) (model - measured) at ``k`` (and nuisance values ``nu``)
    on the model grid (n, c)."""
    pop = objective.model.simulate(k, nu)
    i = np.asarray(pop.i_abc[0], dtype=float)
    target, weights = np.asarray(objective.target), np.asarray(objective.weights)
    if target.shape[1] == 1:          # "equivalent" fitness mode
        from ..fitness import equivalent_current

        i = equivalent_current(i)[:, None]
    return np.sqrt(weights) * (i - target)


def population_interval(K: np.ndarray, f: np.ndarray, k: np.ndarray, f_min: float, n_eff: float,
                        level: float = 0.9) -> tuple[np.ndarray, np.ndarray, int]:
    """``(lo, hi, n_in)``: range of each component over the evaluated points ``K`` (m, 8)
    with fitness ``f`` (m,) inside the likelihood region ``n_eff (f - f_min) / f_min <=
    chi2_1(level)``, joined with the estimate ``k``."""
    K = np.asarray(K, dtype=float)
    f = np.asarray(f, dtype=float)
    k = np.asarray(k, dtype=float)
    crit = float(stats.chi2.ppf(level, 1))
    if not (math.isfinite(f_min) and f_min > 0):
        return k.copy(), k.copy(), 0
    ok = np.isfinite(f)
    D = np.full(f.shape, np.inf)
    D[ok] = n_eff * (f[ok] - f_min) / f_min
    inside = K[D <= crit]
    lo = np.minimum(k, inside.min(axis=0)) if inside.size else k.copy()
    hi = np.maximum(k, inside.max(axis=0)) if inside.size else k.copy()
    return np.clip(lo, 0.0, 1.0), np.clip(hi, 0.0, 1.0), int(inside.shape[0])


def _check(method: str, level: float, n_runs: int, seed: Any) -> None:
    if method not in SPREAD_METHODS:
        raise ValueError(f"unknown spread method {method!r}; choose one of {', '.join(SPREAD_METHODS)}")
    if isinstance(level, bool) or not isinstance(level, (int, float, np.floating)) or not 0 < level < 1:
        raise ValueError(f"level must be in (0, 1), e.g. 0.9, got {level!r}")
    if isinstance(n_runs, bool) or not isinstance(n_runs, (int, np.integer)) or n_runs < 2:
        raise ValueError(f"n_runs must be an integer >= 2, got {n_runs!r}")
    check_seed(seed)


def identify_with_spread(trace: Any, config: Any = None, *, seed: int,
                         method: str = "population", level: float = 0.9, n_runs: int = 5,
                         params: Any = None, start: Any = None, error_floor: Any = None,
                         retries: int = 2, callback: Any = None, **deprecated: Any) -> IdentificationSpread:
    """Identify ``k`` of ``trace`` and the interval of each component.

    ``config`` (an :class:`emaphm.identify.IdentificationConfig`, default the
    least-squares pipeline's) holds the problem and solver settings, ``params`` the
    healthy actuator and ``start`` a warm start of the least-squares solver; ``trace`` may
    also be an :class:`emaphm.problem.IdentificationProblem` (its settings are then the
    problem's). ``method`` is one of :data:`SPREAD_METHODS` (module docstring); ``n_runs``
    the identifications of ``"seeds"`` and ``"bootstrap"``; ``level`` the nominal
    probability of the interval; ``error_floor`` (scalar or 8 values, default
    :data:`IDENTIFICATION_ERROR_P90`) the least half-width of each component's interval.
    An identification whose fitness exceeds the config's ``suspect_ratio`` (default the
    misfit test's limit) times the trace's noise floor
    (:meth:`emaphm.fitness.Eq4Objective.noise_floor`) is *suspect* (the optimizer
    ended in a wrong basin: before the restarts, PSO with its default budget did so
    on 2 of 90 benchmark inspections, at Eq. 9 errors above 70 %, fitness 700 times
    the noise level); the first identification runs again with up to ``retries`` more
    seeds or starts (spawned from ``seed``) and keeps the best run. ``details`` records
    ``fitness_ratio``, ``retries`` and ``suspect`` (still suspect after the retries).
    The keywords of version 0.3 (``algorithm``, ``budget``, ``options``, ``polish``,
    ``suspect_ratio``, ``objective``, ``fault_model``, ``n_sub``, ``mode``, ``nuisance``)
    still work for one release, with a DeprecationWarning.
    """
    from ..fitness import misfit_limit
    from ..identify import IdentificationConfig, minimize
    from ..problem import IdentificationProblem

    if deprecated:
        config, trace = _old_keywords(config, trace, params, deprecated)
    config = IdentificationConfig() if config is None else config
    suspect_ratio = misfit_limit() if config.suspect_ratio is None else config.suspect_ratio
    _check(method, level, n_runs, seed)
    floor = _error_floor(error_floor)
    t0 = time.perf_counter()
    problem = trace if isinstance(trace, IdentificationProblem) else config.problem(trace, params,
                                                                                    start=start)
    trace = problem.trace
    base = problem.objective
    rec = _Recorder(base)
    recording = replace(problem, objective=rec)
    run_seeds = [int(s.generate_state(1)[0] % (2 ** 31))
                 for s in np.random.SeedSequence(int(seed)).spawn(n_runs + 1)]

    def run(s: int, prob: Any, restarts: int = 0) -> Any:
        return minimize(prob, replace(config, restarts=restarts).solver(), config.budget, seed=s,
                        callback=callback)

    first = run(int(seed), recording, retries)    # identify retries a wrong basin itself
    f_noise = first.noise_floor
    limit = suspect_ratio * f_noise if f_noise > 0 else math.inf
    n_retries = first.restarts
    runs = [first]
    if method == "seeds":
        runs += [run(s, recording) for s in run_seeds[1:n_runs]]
    spent = int(sum(r.evaluations for r in runs))     # every run, kept or not
    if method == "seeds":
        runs = [r for r in runs if r.fitness <= limit] or runs
    K, f = rec.points()
    K = K[:, :8]                       # the intervals are of k (nuisance columns follow it)
    best = min(runs, key=lambda r: r.fitness)
    f_min = float(min(np.min(f[np.isfinite(f)]) if np.isfinite(f).any() else np.inf, best.fitness))
    res = _residual(base, best.k, [best.nuisance[n] for n in base.model.nuisance] or None)
    n_eff, tau = effective_samples(res)
    details = {"n_eff": n_eff, "tau": tau, "f_min": f_min, "evaluated": int(f.size),
               "chi2_crit": float(stats.chi2.ppf(level, 1)), "f_noise": f_noise,
               "fitness_ratio": float(best.fitness / f_noise) if f_noise > 0 else math.nan,
               "retries": n_retries, "suspect": bool(best.fitness > limit)}
    if method == "population":
        lo, hi, n_in = population_interval(K, f, first.k, f_min, n_eff, level)
        interval = KInterval(first.k.copy(), lo, hi, method, float(level), n_in, details)
        ident = first
    elif method == "seeds":
        ks = np.stack([r.k for r in runs])
        k_med = np.median(ks, axis=0)
        lo, hi, n_in = population_interval(K, f, k_med, f_min, n_eff, level)
        lo, hi = np.minimum(lo, ks.min(axis=0)), np.maximum(hi, ks.max(axis=0))
        details.update(seeds=[r.seed for r in runs], k_runs=ks.tolist(), in_region=n_in)
        interval = KInterval(k_med, lo, hi, method, float(level), len(runs), details)
        ident = best
    else:
        ks = _bootstrap(problem, first, run, run_seeds[1:n_runs + 1], tau)
        runs += ks[1]
        kb = np.stack([r.k for r in ks[1]])
        q_lo, q_hi = np.quantile(kb, [(1 - level) / 2, (1 + level) / 2], axis=0)
        lo, hi = np.minimum(q_lo, first.k), np.maximum(q_hi, first.k)
        details.update(k_runs=kb.tolist(), block=ks[0])
        interval = KInterval(first.k.copy(), lo, hi, method, float(level), kb.shape[0], details)
        ident = first
    return IdentificationSpread(identification=ident, interval=_with_floor(interval, floor), runs=tuple(runs),
                      evaluations=spent + (0 if method != "bootstrap" else
                                           int(sum(r.evaluations for r in runs[1:]))),
                      elapsed_s=time.perf_counter() - t0)


def _error_floor(error_floor: Any) -> np.ndarray:
    """The least half-width of each component's interval (8,), checked."""
    floor = np.broadcast_to(np.asarray(IDENTIFICATION_ERROR_P90 if error_floor is None
                                       else error_floor, dtype=float), (8,))
    if np.any(~np.isfinite(floor)) or np.any(floor < 0):
        raise ValueError(f"error_floor must be finite and >= 0 (a scalar or 8 values), got {error_floor!r}")
    return floor


def _with_floor(interval: KInterval, floor: np.ndarray) -> KInterval:
    """``interval`` joined with ``k +- floor`` (clipped to [0, 1])."""
    if not np.any(floor > 0):
        return interval
    lo = np.clip(np.minimum(interval.lo, interval.k - floor), 0.0, 1.0)
    hi = np.clip(np.maximum(interval.hi, interval.k + floor), 0.0, 1.0)
    return replace(interval, lo=lo, hi=hi, details={**interval.details, "error_floor": floor.tolist()})


def _bootstrap(problem: Any, first: Any, run: Any, seeds: list[int], tau: float) -> tuple[int, list]:
    """Moving-block bootstrap of the residual currents; one identification per resample."""
    base = problem.objective
    pop = base.model.simulate(first.k)
    model_i = np.asarray(pop.i_abc[0], dtype=float)
    target = np.asarray(base.target)
    if target.shape[1] != 3:
        raise ValueError("the bootstrap resamples phase currents; use the default fitness mode "
                         "'phases'")
    e = target - model_i
    n = e.shape[0]
    block = int(min(max(1, math.ceil(tau)), max(1, n // 4)))
    T_s = float(base.model.params.inverter.T_s)
    out = []
    for s in seeds:
        rng = np.random.default_rng(s)
        starts = rng.integers(0, n - block + 1, size=int(math.ceil(n / block)))
        idx = (starts[:, None] + np.arange(block)[None, :]).ravel()[:n]
        new_target = np.ascontiguousarray(model_i + e[idx])
        obj = replace(base, target=new_target, weights=np.ascontiguousarray(eq4_weights(new_target, T_s)))
        out.append(run(s, replace(problem, objective=obj)))
    return block, out


#: identify_with_spread()'s keywords of version 0.3 and where each goes now.
_OLD_CONFIG = ("algorithm", "budget", "options", "polish", "suspect_ratio", "fault_model",
               "n_sub", "mode", "nuisance")


def _old_keywords(config: Any, trace: Any, params: Any, kw: dict[str, Any]) -> tuple[Any, Any]:
    """The 0.3 keywords as a config (and a problem for a prebuilt objective), with a warning."""
    import warnings

    from ..identify import IdentificationConfig
    from ..problem import IdentificationProblem

    unknown = sorted(set(kw) - set(_OLD_CONFIG) - {"objective"})
    if unknown:
        raise TypeError(f"identify_with_spread() got unexpected keyword argument(s) "
                        f"{', '.join(unknown)}")
    warnings.warn(f"identify_with_spread({', '.join(f'{k}=' for k in kw)}) is the 0.3 spelling, "
                  "kept for one release: give the settings as an IdentificationConfig (and a "
                  "prebuilt objective in an IdentificationProblem)", DeprecationWarning,
                  stacklevel=3)
    if config is not None:
        raise ValueError("give an IdentificationConfig or the old keywords, not both")
    config = IdentificationConfig(**{k: kw[k] for k in _OLD_CONFIG if k in kw})
    if kw.get("objective") is not None:
        trace = IdentificationProblem(trace, params=params, objective=kw["objective"],
                                      n_sub=config.n_sub, mode=config.mode)
    return config, trace


def __getattr__(name: str) -> Any:
    """``Assessment``, the name of :class:`IdentificationSpread` before 0.5, kept for one
    release with a DeprecationWarning."""
    if name == "Assessment":
        import warnings

        warnings.warn("emaphm.prognosis.Assessment is now IdentificationSpread (an "
                      "identification with the interval of its k; emaphm.assessment is "
                      "another thing); the old name goes in the next release",
                      DeprecationWarning, stacklevel=2)
        return IdentificationSpread
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
