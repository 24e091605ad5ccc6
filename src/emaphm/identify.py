"""Fault identification: the ``k`` whose monitoring-model currents best match a trace.

:func:`identify` wires the problem layer (:class:`emaphm.fitness.Eq4Objective`,
the box ``[0, 1]^8``) to an optimizer of :mod:`emaphm.optim` and returns an
:class:`Identification` (results as data; plots and reports only read it).
"""

from __future__ import annotations

import dataclasses
import hashlib
import itertools
import json
import re
import threading
import time
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from .faults import K_NAMES, K_NOMINAL, N_K, as_k, error_pct
from .fitness import Eq4Objective, _Stats, misfit_limit
from .optim import (ALL_ALGORITHMS, MaxEvaluations, OptimizeResult, Termination, WallClock,
                    get_optimizer, minimize)
from .optim.local import compass_search
from .params import ActuatorParams
from .search import (default_search, from_k, least_squares_search, nuisance_from_unit,
                     nuisance_to_unit, to_k)
from .traces import Trace, TraceError, validate

__all__ = ["Identification", "identify", "parse_budget", "DEFAULT_ALGORITHM", "ALGORITHM_NAMES"]


#: The default identification pipeline (:func:`identify` without an algorithm): a
#: space-filling sample and batched least squares from the best starts, see
#: :func:`identify`. The paper's metaheuristics stay selectable by name.
DEFAULT_ALGORITHM = "lsq"

#: Every name :func:`identify` accepts: the default pipeline and the optimizers of
#: :data:`emaphm.optim.ALL_ALGORITHMS`.
ALGORITHM_NAMES: tuple[str, ...] = (DEFAULT_ALGORITHM, *sorted(ALL_ALGORITHMS))

#: Space-filling sample (scrambled Sobol points, seeded) from which the least-squares
#: pipeline takes its further starts, when the nominal start is not good enough.
LSQ_SAMPLE = 64

#: Single-fault points added to that sample: each fault component alone at these values,
#: the others healthy (:func:`single_fault_points`). Most actuators have one fault, and
#: a fault whose effect is flat at the healthy value cannot be reached from it by a
#: gradient: a backlash below the gear train's deflection under load (k2 up to about
#: 0.05 with the preset's contact) hardly changes the currents, so least squares from
#: the healthy k stays at k2 = 0 when the truth is 0.25.
LSQ_SINGLE_FAULT_LEVELS = (0.1, 0.25, 0.5, 0.75)

#: Further starts the least-squares pipeline may take after the first (without a budget).
LSQ_RESTARTS = 3

#: A start of the least-squares pipeline is good enough when its fit ratio is below the
#: misfit test's limit at this false-alarm probability (about 2.1): most fits of an
#: actuator the model describes are (a stricter limit than the verdict's, so that a fit
#: the verdict would accept is still checked against another start). Below the
#: suspect limit, further starts stop once one improves the fit by less than 1 % (the
#: model, not the basin, then limits it); above it every start is tried.
LSQ_ACCEPT_P = 0.01

#: Largest budget accepted: 1e8 evaluations (hours of CPU) or a day of wall clock; a larger
#: one is a typo, not a plan.
MAX_BUDGET_EVALUATIONS = 100_000_000
MAX_BUDGET_SECONDS = 86_400.0


def parse_budget(budget: Any) -> Termination | None:
    """A termination from a budget: ``None`` (the algorithm's paper default), an
    int (objective evaluations), a string ``"5000"`` / ``"5000evals"`` /
    ``"30s"`` (wall-clock seconds), or a :class:`emaphm.optim.Termination`. At most
    :data:`MAX_BUDGET_EVALUATIONS` evaluations or :data:`MAX_BUDGET_SECONDS` seconds."""
    if budget is None:
        return None
    if isinstance(budget, bool):
        raise ValueError(f"budget must be a number of evaluations or seconds, got {budget!r}")
    if isinstance(budget, (int, np.integer)):
        if budget <= 0:
            raise ValueError(f"budget must be a positive number of evaluations, got {budget}")
        if budget > MAX_BUDGET_EVALUATIONS:
            raise ValueError(f"budget {budget} is above {MAX_BUDGET_EVALUATIONS:.0e} evaluations "
                             "(hours of CPU); give fewer, or seconds (e.g. 600s)")
        return MaxEvaluations(int(budget))
    if isinstance(budget, str):
        m = re.fullmatch(r"\s*(\d+(?:\.\d*)?)\s*(s|evals?)?\s*", budget)
        if not m:
            raise ValueError(f"budget {budget!r} not understood; use a number of evaluations "
                             "(e.g. 5000) or seconds (e.g. 30s)")
        value, unit = float(m.group(1)), m.group(2)
        if value <= 0:
            raise ValueError(f"budget must be positive, got {budget!r}")
        if unit == "s":
            if value > MAX_BUDGET_SECONDS:
                raise ValueError(f"budget {budget!r} is above a day ({MAX_BUDGET_SECONDS:g} s); "
                                 "give at most 86400s")
            return WallClock(value)
        if value != int(value):
            raise ValueError(f"a budget in evaluations must be a whole number, got {budget!r}")
        return parse_budget(int(value))
    if hasattr(budget, "check"):
        return budget
    raise ValueError(f"budget must be evaluations (int), seconds ('30s') or a Termination, got {budget!r}")


@dataclass(frozen=True)
class Identification:
    """Result of one identification.

    ``k`` identified fault vector; ``fitness`` its Eq. 4 value; ``evaluations``
    monitoring-model runs (polish included); ``elapsed_s`` wall time;
    ``kernel_s`` of it in the model kernel; ``history`` best fitness per
    iteration, the polish's polls appended after the first ``iterations``;
    ``model_trace`` the monitoring model's signals at ``k``; ``k_true`` and
    ``error_pct`` (Eq. 9) where the trace carries its true fault vector (a
    simulation). ``k_raw``, ``fitness_raw``, ``error_pct_raw``: the
    metaheuristic's own result before the polish (equal to the final ones
    without polish). ``restarts``: runs repeated because the fit was far above
    ``noise_floor`` (the Eq. 4 value of a perfect model on this trace);
    ``suspect``: still so after them (a wrong basin, or a model that does not
    describe this actuator). ``evaluations`` and ``polish_s`` count every run;
    ``iterations``, ``history``, ``polish_evaluations`` and ``run_evaluations``
    (its metaheuristic and polish evaluations) are those of the best run.
    ``fault_model``: the mapping of k3..k5 the monitoring model used; ``compile_s``: the
    time to compile (or load from the disk cache) the model kernels and run the model
    once, before ``elapsed_s`` starts.
    """

    algorithm: str
    seed: int | None
    k: np.ndarray
    fitness: float
    evaluations: int
    iterations: int
    elapsed_s: float
    kernel_s: float
    history: np.ndarray
    reason: str
    model_trace: Trace
    k_true: np.ndarray | None = None
    error_pct: float | None = None
    diverged: int = 0
    options: dict = field(default_factory=dict)
    k_raw: np.ndarray | None = None
    fitness_raw: float | None = None
    error_pct_raw: float | None = None
    polish_evaluations: int = 0
    polish_s: float = 0.0
    restarts: int = 0
    noise_floor: float = 0.0
    suspect: bool = False
    run_evaluations: int = 0
    fault_model: str = "paper"
    compile_s: float = 0.0
    nuisance: dict = field(default_factory=dict)

    @property
    def evals_per_s(self) -> float:
        return self.evaluations / self.elapsed_s if self.elapsed_s > 0 else float("nan")

    def to_dict(self) -> dict[str, Any]:
        """JSON-serialisable summary (no traces)."""
        d = {
            "algorithm": self.algorithm,
            "fault_model": self.fault_model,
            "seed": self.seed,
            "k": [float(x) for x in self.k],
            "k_named": {n: float(x) for n, x in zip(K_NAMES, self.k)},
            "fitness": float(self.fitness),
            "evaluations": int(self.evaluations),
            "iterations": int(self.iterations),
            "elapsed_s": float(self.elapsed_s),
            "compile_s": float(self.compile_s),
            "nuisance": dict(self.nuisance),
            "kernel_s": float(self.kernel_s),
            "evals_per_s": float(self.evals_per_s),
            "reason": self.reason,
            "diverged": int(self.diverged),
            "options": _jsonable(self.options),
            "history": [float(x) for x in self.history],
            "polish_evaluations": int(self.polish_evaluations),
            "polish_s": float(self.polish_s),
            "restarts": int(self.restarts),
            "run_evaluations": int(self.run_evaluations),
            "noise_floor": float(self.noise_floor),
            "suspect": bool(self.suspect),
            "k_raw": None if self.k_raw is None else [float(x) for x in self.k_raw],
            "fitness_raw": self.fitness_raw,
        }
        if self.k_true is not None:
            d["k_true"] = [float(x) for x in self.k_true]
            d["error_pct"] = float(self.error_pct)
            d["error_pct_raw"] = self.error_pct_raw
        return d


#: Nuisance parameters searched with k by default for a calibrated unit: what drifts most
#: after a calibration (winding resistance and magnet flux, with temperature).
DRIFT_NUISANCE = ("R", "flux")

def default_nuisance(params: ActuatorParams | None) -> tuple[str, ...]:
    """The nuisance parameters searched by default: :data:`DRIFT_NUISANCE` for calibrated
    parameters, none for a data sheet."""
    return DRIFT_NUISANCE if params is not None and params.calibration.date else ()


#: Restarts after a fit far above the noise floor, when no budget is given.
DEFAULT_RESTARTS = 2

#: Largest number of evaluations the polish may spend (it usually needs 150-500).
POLISH_MAX_EVALUATIONS = 2000

#: The least-squares pipeline's polish: a finer, shorter compass search (it starts at a
#: least-squares minimum, step 0.02 of the box down to 1e-3).
POLISH_LSQ_EVALUATIONS = 200


def _terms(termination: Any) -> list[Any]:
    if termination is None:
        return []
    return list(getattr(termination, "terms", None) or [termination])


def _remaining_evaluations(termination: Any, used: int, cap: int) -> int:
    left = cap
    for term in _terms(termination):
        if isinstance(term, MaxEvaluations):
            left = min(left, term.n - used)
    return left


def _remaining_seconds(termination: Any, used: float) -> float:
    left = float("inf")
    for term in _terms(termination):
        if isinstance(term, WallClock):
            left = min(left, term.seconds - used)
    return left


def _jsonable(value: Any) -> Any:
    """Options as plain JSON values (NumPy scalars and arrays included)."""
    return json.loads(json.dumps(value, default=lambda o: o.tolist() if hasattr(o, "tolist") else str(o)))


@dataclass(frozen=True)
class _Run:
    """One metaheuristic run and its polish, in search-space coordinates."""

    res: OptimizeResult
    z: np.ndarray
    fun: float
    history: np.ndarray
    polish_evaluations: int
    polish_s: float


def _search(fitness: Callable[[np.ndarray], np.ndarray], optimizer: Any, seed: int,
            termination: Any, callback: Any, polish: bool, t0: float, n_var: int = 8) -> _Run:
    box = (np.zeros(n_var), np.ones(n_var))
    res: OptimizeResult = minimize(fitness, box, optimizer, seed=seed, termination=termination,
                                   callback=callback)
    z, fun, history = res.x, float(res.fun), np.asarray(res.history, dtype=float)
    # the polish is charged to the budget and skipped when a callback stopped the run
    evals = _remaining_evaluations(termination, res.nfev, POLISH_MAX_EVALUATIONS)
    seconds = _remaining_seconds(termination, time.perf_counter() - t0)
    if polish and np.isfinite(fun) and res.reason != "callback" and evals >= 2 * z.size \
            and seconds > 0:
        pol = compass_search(fitness, z, box, f0=fun, max_evals=evals, max_seconds=seconds)
        return _Run(res, pol.x, float(pol.fun), np.concatenate([history, pol.history[1:]]),
                    pol.nfev, pol.elapsed_s)
    return _Run(res, z, fun, history, 0, 0.0)


#: Objectives :func:`identify` built, kept per thread (least recently used dropped): a
#: campaign identifies the same trace with several algorithms and seeds.
OBJECTIVE_CACHE_SIZE = 8

_OBJECTIVES = threading.local()


def _trace_digest(trace: Trace) -> bytes:
    """A digest of the trace's value: every array's bytes and its metadata."""
    h = hashlib.blake2b(digest_size=20)
    for a in (trace.t, trace.theta_ref, trace.theta_m, trace.omega_m, trace.i_abc, trace.torque):
        h.update(b"-" if a is None else np.ascontiguousarray(a).tobytes())
        h.update(b"|")
    h.update(json.dumps(trace.meta, sort_keys=True, default=str).encode())
    return h.digest()


def _cached_objective(trace: Trace, params: ActuatorParams | None, n_sub: int, mode: str,
                      fault_model: str | None, nuisance: tuple[str, ...]) -> tuple[Eq4Objective, bool]:
    """``(objective, warm)``: the objective :func:`identify` builds for ``trace``, from
    the cache (``warm``, its ``stats`` fresh) when it was built before for an equal trace
    with equal settings.

    Keyed by value (the trace's digest and the frozen parameters), so a hit is the
    objective a fresh build would give; the trace was validated when it was built, and
    its model has run (its kernels are compiled).
    """
    cache = getattr(_OBJECTIVES, "cache", None)
    if cache is None:
        cache = _OBJECTIVES.cache = OrderedDict()
    key = (_trace_digest(trace), params, n_sub, mode, fault_model, nuisance)
    hit = cache.get(key)
    if hit is not None:
        cache.move_to_end(key)
        return dataclasses.replace(hit, stats=_Stats()), True
    validate(trace)
    objective = Eq4Objective.from_trace(trace, params, n_sub=n_sub, mode=mode,
                                        fault_model=fault_model, nuisance=nuisance)
    cache[key] = objective
    while len(cache) > OBJECTIVE_CACHE_SIZE:
        cache.popitem(last=False)
    return objective, False


def _restart_seeds(seed: int, n: int) -> list[int]:
    """Seeds of the restarts, spawned from the identification's seed."""
    return [int(s.generate_state(1)[0] % 2**31) for s in np.random.SeedSequence([seed, 1]).spawn(n)]


def _k_true(trace: Trace) -> np.ndarray | None:
    k = trace.meta.get("k") if isinstance(trace.meta, dict) else None
    if k is None:
        return None
    try:
        return as_k(k)
    except ValueError:
        return None


def single_fault_points() -> np.ndarray:
    """``(n, 8)``: each fault component (k1..k6, k8) alone at each of
    :data:`LSQ_SINGLE_FAULT_LEVELS` (k8 that far below and above its healthy 0.5), the
    others healthy."""
    rows = []
    for j in (0, 1, 2, 3, 4, 5, 7):
        for v in LSQ_SINGLE_FAULT_LEVELS:
            for x in ((0.5 - v / 2, 0.5 + v / 2) if j == 7 else (v,)):
                k = K_NOMINAL.copy()
                k[j] = x
                rows.append(k)
    return np.array(rows)


def _least_squares(objective: Eq4Objective, full: Callable[[np.ndarray], np.ndarray], search: str,
                   nu_names: tuple[str, ...], fault_model: str, start: np.ndarray | None, seed: int,
                   termination: Any, callback: Any, polish: bool, floor: float,
                   restarts: int, limit: float) -> tuple[_Run, int]:
    """The default pipeline (see :func:`identify`): ``(run, starts taken)``."""
    from scipy.stats import qmc

    from .optim.lsq import multistart_least_squares

    n_var = N_K + len(nu_names)
    ev0 = objective.stats.evaluations
    nu0 = nuisance_to_unit(np.zeros((1, len(nu_names))), nu_names) if nu_names else np.zeros((1, 0))

    def point(k: np.ndarray, nu_unit: np.ndarray) -> np.ndarray:
        return np.clip(np.hstack([from_k(k[None, :], search), nu_unit.reshape(1, -1)])[0], 0.0, 1.0)

    max_evals = _remaining_evaluations(termination, 0, np.iinfo(np.int64).max)
    sampled = [0]                       # the sample's evaluations, charged to the budget

    def starts():
        if start is not None:
            yield point(start, nu0)
        yield point(K_NOMINAL, nu0)
        # the best of a seeded space-filling sample, drawn in the metaheuristics' space
        # (short circuits sparse), only when the first starts were not good enough and
        # the budget leaves room for it and one more start
        axes = single_fault_points()
        n_sample = LSQ_SAMPLE + len(axes)
        if max_evals - objective.stats.evaluations + ev0 < n_sample + n_var + 1:
            return
        sampled[0] = n_sample
        sample_space = default_search(fault_model)
        Z = qmc.Sobol(n_var, scramble=True, seed=seed).random(LSQ_SAMPLE)
        K = np.vstack([to_k(Z[:, :N_K], sample_space), axes])
        Z = np.vstack([Z, np.tile(np.concatenate([np.zeros(N_K), nu0[0]]), (len(axes), 1))])
        nu = nuisance_from_unit(Z[:, N_K:], nu_names) if nu_names else np.zeros((n_sample, 0))
        f = objective(np.hstack([K, nu]))
        for i in np.argsort(f, kind="stable")[:restarts]:
            if np.isfinite(f[i]):
                yield point(K[i], Z[i, N_K:])

    max_seconds = _remaining_seconds(termination, 0.0)
    accept = misfit_limit(LSQ_ACCEPT_P) * floor
    box = (np.zeros(n_var), np.ones(n_var))
    res, info = multistart_least_squares(
        lambda Z: objective.residuals(full(Z)), itertools.islice(starts(), 1 + restarts), box,
        accept=accept, settle=limit, polish_evals=POLISH_LSQ_EVALUATIONS if polish else 0,
        max_evals=max_evals, max_seconds=max_seconds, callback=callback,
        fitness=lambda Z: objective(full(Z)), charged=lambda: sampled[0])
    raw = OptimizeResult(x=info["x_raw"], fun=info["f_raw"],
                         nfev=res.nfev - info["polish_evaluations"], nit=res.nit,
                         history=res.history, reason=res.reason, elapsed_s=res.elapsed_s,
                         algorithm=DEFAULT_ALGORITHM)
    return _Run(raw, res.x, float(res.fun), res.history, info["polish_evaluations"],
                info["polish_s"]), info["starts"]


def identify(trace: Trace, algorithm: str = DEFAULT_ALGORITHM, *, seed: int,
             budget: Any = None, params: ActuatorParams | None = None,
             options: dict[str, Any] | None = None, n_sub: int = 1, mode: str = "phases",
             polish: bool = True, search: str | None = None, restarts: int | None = None,
             suspect_ratio: float | None = None,
             callback: Callable[[Any], bool | None] | None = None,
             objective: Eq4Objective | None = None,
             fault_model: str | None = None,
             nuisance: tuple[str, ...] | None = None,
             start: Any = None) -> Identification:
    """Identify the fault vector of ``trace``.

    Parameters
    ----------
    trace
        Measured (or simulated) trace; validated first.
    algorithm
        ``"lsq"`` (default, :data:`DEFAULT_ALGORITHM`): batched least squares on the
        weighted residuals of Eq. 4 (:func:`emaphm.optim.lsq.multistart_least_squares`,
        SciPy's trust-region reflective method with a Jacobian from one batched kernel
        call), started from ``start`` if given, then the healthy actuator, then, while
        the fit is above the misfit test's limit at :data:`LSQ_ACCEPT_P`, the best
        points of a seeded space-filling sample of :data:`LSQ_SAMPLE` candidates and
        the single-fault points (:func:`single_fault_points`; charged to the budget; at
        most ``restarts`` further starts, default :data:`LSQ_RESTARTS`), searched in
        :func:`emaphm.search.least_squares_search`; the best refined and polished. It
        needs some hundreds of model runs where the metaheuristics need thousands. Or
        ``"pso"``, ``"de"``, ``"gwo"`` (the paper's) or the baselines ``"scipy-de"``,
        ``"cmaes"`` (:data:`emaphm.optim.ALL_ALGORITHMS`).
    seed
        Seed of the optimizer (an int; same seed, same result).
    budget
        See :func:`parse_budget`; ``None`` keeps the algorithm's paper defaults.
    params
        The healthy actuator the monitoring model assumes (default preset).
    options
        Optimizer settings, e.g. ``{"pop_size": 40}``.
    n_sub, mode
        Monitoring model sub-steps and fitness mode (:class:`Eq4Objective`).
    polish
        Refine the metaheuristic's best point by a batched compass search
        (:func:`emaphm.optim.local.compass_search`, step 0.05 down to 1e-4,
        at most 2000 evaluations; about 0.1 s). It is charged to an evaluation
        or wall-clock budget (and skipped when too little is left), and skipped
        when a callback stopped the run. False gives the bare algorithm, as in
        the paper.
    search
        Search space (:mod:`emaphm.search`): ``"ecc-xy"`` (Cartesian
        eccentricity), ``"ecc-xy-sc"`` (and sparse short circuits) or ``"k"`` (the
        paper's, k itself); default :func:`emaphm.search.default_search` of the
        fault model (``"ecc-xy-sc"`` under physical, ``"ecc-xy"`` under paper).
    restarts, suspect_ratio
        A fit whose Eq. 4 value exceeds ``suspect_ratio`` times the trace's noise
        floor (:meth:`Eq4Objective.noise_floor`, the value a perfect model would
        reach) ended in a wrong basin; it is run again, up to ``restarts`` times,
        with seeds spawned from ``seed``, and the best run is kept. ``None``: 2
        restarts without an explicit ``budget`` and with the polish, none with a
        budget (it caps the evaluations) or with ``polish=False`` (the bare
        algorithm); an explicit number applies in any case, each run with the
        budget. A result still above the limit is flagged ``suspect``. Default
        ``suspect_ratio``: the misfit test's limit (:func:`emaphm.fitness.misfit_limit`,
        the fit ratio an actuator the model describes exceeds with probability
        :data:`emaphm.fitness.MISFIT_P`), the same test that makes a verdict
        ``unexplained``.
    callback
        Called with the optimizer state after every iteration; True stops.
    objective
        A prebuilt objective for this trace (reused across runs to skip setup).
    fault_model
        Mapping of k3..k5 in the monitoring model (:data:`emaphm.faults.FAULT_MODELS`);
        default the trace's own (:func:`emaphm.fitness.trace_fault_model`: its
        metadata's, ``"physical"`` for a bench trace).
    start
        ``"lsq"`` only: a fault vector to start from first (the actuator's previous
        inspection; a warm start), before the healthy actuator.
    nuisance
        Nuisance parameters searched jointly with k (names of
        :data:`emaphm.search.NUISANCE_RANGE`: ``"R"`` the winding resistance, ``"flux"``
        the magnet flux, as relative deviations from ``params`` within that range), so
        that a unit that drifted since its calibration is not read as faulty; reported
        in ``Identification.nuisance``, never in k. Default: ``("R", "flux")`` when
        ``params`` carry a calibration (``emaphm calibrate``; the parameters that drift
        most after it, with the winding's and the magnets' temperature), none for data-sheet
        parameters (a prebuilt ``objective`` brings its own).
    """
    if algorithm not in ALGORITHM_NAMES:
        raise ValueError(f"unknown algorithm {algorithm!r}; choose one of "
                         f"{', '.join(ALGORITHM_NAMES)}")
    if start is not None:
        if algorithm != DEFAULT_ALGORITHM:
            raise ValueError(f"start (a warm start) is an option of {DEFAULT_ALGORITHM!r}, not of "
                             f"{algorithm!r}")
        start = as_k(start)
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    if restarts is None:          # none under a budget (a cap) or for the bare algorithm
        if algorithm == DEFAULT_ALGORITHM:
            restarts = LSQ_RESTARTS
        else:
            restarts = DEFAULT_RESTARTS if budget is None and polish else 0
    if isinstance(restarts, bool) or not isinstance(restarts, (int, np.integer)) or restarts < 0:
        raise ValueError(f"restarts must be an integer >= 0, got {restarts!r}")
    if suspect_ratio is None:
        suspect_ratio = misfit_limit()
    if isinstance(suspect_ratio, bool) or not isinstance(suspect_ratio, (int, float)) \
            or not suspect_ratio > 1:
        raise ValueError(f"suspect_ratio must be a number > 1, got {suspect_ratio!r}")
    if search is not None:
        to_k(np.zeros((1, 8)), search)   # validates the search space name
    termination = parse_budget(budget)
    if algorithm == DEFAULT_ALGORITHM:
        if options:
            raise ValueError(f"{DEFAULT_ALGORITHM!r} takes no optimizer options, got {options}")
        optimizer = None
    else:
        optimizer = get_optimizer(algorithm, **(options or {}))
    if objective is None:
        if nuisance is None:
            nuisance = default_nuisance(params)
        objective, warm = _cached_objective(trace, params, n_sub, mode, fault_model,
                                            tuple(nuisance))
    elif nuisance is not None and tuple(nuisance) != objective.model.nuisance:
        raise ValueError(f"nuisance {tuple(nuisance)} differs from the prebuilt objective's "
                         f"{objective.model.nuisance}")
    elif fault_model is not None and fault_model != objective.model.fault_model:
        raise ValueError(f"fault_model {fault_model!r} differs from the prebuilt objective's "
                         f"{objective.model.fault_model!r}")
    else:
        validate(trace)
        warm = False
    fault_model = objective.model.fault_model
    if search is None:
        search = (least_squares_search(fault_model) if algorithm == DEFAULT_ALGORITHM
                  else default_search(fault_model))
    # compile (or load from the disk cache) the kernels before the clock starts; an
    # objective that has run already has them
    tc = time.perf_counter()
    if algorithm == DEFAULT_ALGORITHM:
        import scipy.optimize  # noqa: F401  (imported before the clock, like the kernels)
        import scipy.stats  # noqa: F401
    if not warm:
        objective.model.simulate(K_NOMINAL)                         # the scalar kernel
        objective.model.simulate_population(                         # the SIMD one
            np.tile(np.concatenate([K_NOMINAL, np.zeros(len(objective.model.nuisance))]), (2, 1)))
    compile_s = time.perf_counter() - tc
    k0 = objective.stats.kernel_s
    e0 = objective.stats.diverged
    ev0 = objective.stats.evaluations
    t0 = time.perf_counter()

    nu_names = objective.model.nuisance
    n_var = N_K + len(nu_names)

    def full(Z: np.ndarray) -> np.ndarray:
        """Search points -> candidate rows [k, nuisance]."""
        Z = np.atleast_2d(Z)
        if not nu_names:
            return to_k(Z, search)
        return np.hstack([to_k(Z[:, :N_K], search), nuisance_from_unit(Z[:, N_K:], nu_names)])

    def fitness(Z: np.ndarray) -> np.ndarray:
        return objective(full(Z))

    def run(run_seed: int) -> _Run:
        return _search(fitness, optimizer, run_seed, termination, callback, polish, t0, n_var)

    floor = objective.noise_floor()
    limit = suspect_ratio * floor if floor > 0 else np.inf
    if algorithm == DEFAULT_ALGORITHM:
        best, n_starts = _least_squares(objective, full, search, nu_names, fault_model, start,
                                        int(seed), termination, callback, polish, floor,
                                        int(restarts), limit)
        runs = [best]
    else:
        best = run(int(seed))
        runs = [best]
        # a fit far above the trace's noise floor ended in a wrong basin: run again with
        # seeds spawned from ``seed`` (unless a callback asked to stop)
        for run_seed in _restart_seeds(int(seed), int(restarts)):
            if best.fun <= limit or runs[-1].res.reason == "callback":
                break
            runs.append(run(run_seed))
            if runs[-1].fun < best.fun:
                best = runs[-1]
        n_starts = len(runs)
    z, fit, history, res = best.z, best.fun, best.history, best.res
    if not np.isfinite(fit):
        raise TraceError("no fault vector reproduces this trace: every candidate of the monitoring "
                         "model diverged (infinite fitness); the trace's command or load "
                         "(metadata) or the parameters (--params) do not describe a working "
                         "actuator")
    k_raw = np.clip(to_k(np.atleast_2d(res.x)[:, :N_K], search)[0], 0.0, 1.0)
    k = np.clip(to_k(np.atleast_2d(z)[:, :N_K], search)[0], 0.0, 1.0)
    nu = full(z)[0, N_K:]
    elapsed = time.perf_counter() - t0
    pop = objective.model.simulate(k, nu)
    model_trace = Trace(t=pop.t + float(trace.t[0]), theta_ref=pop.theta_ref, theta_m=pop.theta_m[0],
                        omega_m=pop.omega_m[0], i_abc=pop.i_abc[0], torque=pop.torque[0],
                        meta={"model": "monitoring", "k": k.tolist(), "identified_from":
                              trace.meta.get("scenario") or trace.meta.get("source")})
    k_true = _k_true(trace)
    return Identification(
        algorithm=algorithm, seed=int(seed), k=k, fitness=fit,
        evaluations=(objective.stats.evaluations - ev0 if algorithm == DEFAULT_ALGORITHM
                     else sum(r.res.nfev + r.polish_evaluations for r in runs)),
        iterations=int(res.nit), elapsed_s=elapsed, kernel_s=objective.stats.kernel_s - k0,
        history=history, reason=res.reason, model_trace=model_trace,
        k_true=k_true, error_pct=None if k_true is None else float(error_pct(k, k_true)),
        diverged=objective.stats.diverged - e0,
        fault_model=fault_model, compile_s=compile_s,
        nuisance={n: float(v) for n, v in zip(nu_names, nu)},
        options={**(options or {}), "n_sub": n_sub, "mode": mode, "polish": bool(polish),
                 "search": search,
                 "budget": None if budget is None else str(budget)},
        k_raw=k_raw, fitness_raw=float(res.fun),
        error_pct_raw=None if k_true is None else float(error_pct(k_raw, k_true)),
        polish_evaluations=best.polish_evaluations, polish_s=sum(r.polish_s for r in runs),
        restarts=n_starts - 1, noise_floor=floor, suspect=bool(fit > limit),
        run_evaluations=int(best.res.nfev) + best.polish_evaluations,
    )

