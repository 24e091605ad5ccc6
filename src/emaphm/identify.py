"""Fault identification: the ``k`` whose monitoring-model currents best match a trace.

:func:`minimize` runs a solver (:mod:`emaphm.optim.solvers`) on an
:class:`~emaphm.problem.IdentificationProblem` and returns an :class:`Identification`
(results as data; plots and reports only read it), as pymoo's
``minimize(problem, algorithm, termination, seed)``. :func:`identify` is the thin front
that builds the problem from a trace and the solver from a name, an optimizer, a
function or an :class:`IdentificationConfig`.

A solver is any object of the protocol of :mod:`emaphm.optim.solvers`; by name
(:func:`make_solver`): ``"lsq"`` (the default, :data:`DEFAULT_ALGORITHM`: multistart
least squares on the weighted residuals of Eq. 4), the paper's ``"pso"``, ``"de"``,
``"gwo"`` and the baselines ``"scipy-de"``, ``"cmaes"`` (each an ask/tell optimizer
polished and restarted, :class:`emaphm.optim.solvers.Metaheuristic`). A user's own
optimizer plugs in without touching emaphm: an object with the ask/tell protocol of
:class:`emaphm.optim.Optimizer`, or a plain function ``f(objective, bounds, rng) -> x``
(``docs/python-api.md``).
"""

from __future__ import annotations

import json
import math
import re
import time
import warnings
from dataclasses import dataclass, field, fields, replace
from typing import Any, Callable, Mapping

import numpy as np

from .faults import K_NAMES, error_pct
from .fitness import FITNESS_MODES, misfit_limit
from .optim import (ALL_ALGORITHMS, MaxEvaluations, Optimizer, Termination, WallClock,
                    get_optimizer)
from .optim.lsq import MultistartLeastSquares
from .optim.registry import Renamed, lookup, registered, registered_kind
from .optim.solvers import CallableSolver, Metaheuristic, Solver, optimizer_options, solve
from .params import ActuatorParams
from .recorded import DRIVE_MODELS
from .problem import (DRIFT_NUISANCE, LSQ_SAMPLE, sobol_sample, LSQ_SINGLE_FAULT_LEVELS,
                      IdentificationProblem, default_nuisance, error_all_pct,
                      single_fault_points)
from .seeds import check_seed
from .search import NUISANCE_RANGE, SEARCH_SPACES, default_search, least_squares_search
from .traces import Trace, TraceError

__all__ = ["Identification", "IdentificationConfig", "identify", "minimize", "make_solver",
           "algorithm_names", "algorithm_name",
           "parse_budget", "DEFAULT_ALGORITHM", "ALGORITHM_NAMES", "DRIFT_NUISANCE",
           "default_nuisance", "single_fault_points", "LSQ_SAMPLE", "LSQ_SINGLE_FAULT_LEVELS",
           "LSQ_RESTARTS", "LSQ_ACCEPT_P", "DEFAULT_RESTARTS", "POLISH_MAX_EVALUATIONS",
           "POLISH_LSQ_EVALUATIONS"]


#: The default identification solver: multistart least squares (:func:`make_solver`).
#: The paper's metaheuristics stay selectable by name.
DEFAULT_ALGORITHM = "lsq"

#: Every name :func:`make_solver` accepts: the default pipeline and the optimizers of
#: :data:`emaphm.optim.ALL_ALGORITHMS`.
ALGORITHM_NAMES: tuple[str, ...] = (DEFAULT_ALGORITHM, *sorted(ALL_ALGORITHMS))

def algorithm_names() -> tuple[str, ...]:
    """Every name :func:`make_solver` accepts now: :data:`ALGORITHM_NAMES` and the names
    registered in this process (:func:`emaphm.optim.register`)."""
    return ALGORITHM_NAMES + tuple(sorted(registered()))


def algorithm_name(algorithm: Any) -> str:
    """The name of an algorithm given as a name or as a registered object (its registered
    name); a TypeError that says how to register anything else."""
    if isinstance(algorithm, str):
        return algorithm
    for name, obj in registered().items():
        if obj is algorithm:
            return name
    raise TypeError(f"an algorithm here is a name ({', '.join(algorithm_names())}); register "
                    f"your {type(algorithm).__name__} first, emaphm.optim.register('mine', obj), "
                    "and give 'mine'")


#: Further starts the least-squares solver may take after the first.
LSQ_RESTARTS = 3

#: A start of the least-squares solver is good enough when its fit ratio is below the
#: misfit test's limit at this false-alarm probability (about 2.0): most fits of an
#: actuator the model describes are (a stricter limit than the verdict's, so that a fit
#: the verdict would accept is still checked against another start). Below the
#: suspect limit, further starts stop once one improves the fit by less than 1 % (the
#: model, not the basin, then limits it); above it every start is tried.
LSQ_ACCEPT_P = 0.01

#: Restarts of a metaheuristic after a fit far above the noise floor, when no budget is
#: given and it is polished.
DEFAULT_RESTARTS = 2

#: Largest number of evaluations a metaheuristic's polish may spend (it usually needs
#: 150-500).
POLISH_MAX_EVALUATIONS = 2000

#: The least-squares solver's polish: a finer, shorter compass search (it starts at a
#: least-squares minimum, step 0.02 of the box down to 1e-3).
POLISH_LSQ_EVALUATIONS = 200

#: Largest budget accepted: 1e8 evaluations (hours of CPU) or a day of wall clock; a larger
#: one is a typo, not a plan.
MAX_BUDGET_EVALUATIONS = 100_000_000
MAX_BUDGET_SECONDS = 86_400.0


def parse_budget(budget: Any) -> Termination | None:
    """A termination from a budget, the one convention of emaphm: ``None`` (the algorithm's
    own stopping rule), an int (objective evaluations), a float (wall-clock seconds), a
    string ``"5000"`` / ``"5000evals"`` (evaluations) or ``"30s"`` (seconds), or a
    :class:`emaphm.optim.Termination`. At most :data:`MAX_BUDGET_EVALUATIONS` evaluations
    or :data:`MAX_BUDGET_SECONDS` seconds."""
    if budget is None:
        return None
    if isinstance(budget, bool):
        raise ValueError(f"budget must be a number of evaluations or seconds, got {budget!r}")
    if isinstance(budget, (float, np.floating)):
        if not (math.isfinite(budget) and budget > 0):
            raise ValueError(f"a budget in seconds (a float) must be positive, got {budget!r}")
        if budget > MAX_BUDGET_SECONDS:
            raise ValueError(f"budget {budget!r} s is above a day ({MAX_BUDGET_SECONDS:g} s); "
                             "give at most 86400.0 (a float is seconds, an int evaluations)")
        return WallClock(float(budget))
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
    once, before ``elapsed_s`` starts; ``config``: the settings it was made with (None for
    a solver that has no name in :data:`ALGORITHM_NAMES`: a user's own); ``noise_sigma``:
    the trace's white-noise level [A rms], the largest of the phases'; ``drive_model``:
    what stood in for the drive's controller (:data:`emaphm.recorded.DRIVE_MODELS`), and
    ``not_observable`` the fault modes that path cannot see (their components of k are
    reported healthy, not measured); ``at_bounds``: the parameters searched beside k whose
    fit ended at an end of their range (the unit is further off than the range allows);
    ``params_source``: where the healthy actuator's parameters came from
    (:data:`emaphm.params.PARAMS_SOURCES`: given, a history's calibration, the trace's own,
    the preset) and ``params`` those parameters; ``skipped``: what the solver promises and
    did not make, with the reason (``{"polish": ..., "restarts": ...}``: a budget too small
    for the polish, a fit far above the noise floor with no restart left);
    ``nuisance_true``: the true values of parameters beside k of a simulated trace's
    injected faults (``{"demag": -0.3}``: :func:`emaphm.problem.true_nuisance`), and
    ``error_all_pct`` Eq. 9 extended to them (:func:`emaphm.problem.error_all_pct`: a
    parameter not searched counts as nominal), where the trace has its truth.
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
    config: "IdentificationConfig | None" = field(default=None, compare=False, repr=False)
    noise_sigma: float = float("nan")
    drive_model: str = "modelled controller"
    not_observable: tuple[str, ...] = ()
    at_bounds: tuple[str, ...] = ()
    params_source: str = "preset"
    params: ActuatorParams | None = field(default=None, compare=False, repr=False)
    skipped: dict = field(default_factory=dict)
    nuisance_true: dict = field(default_factory=dict)
    error_all_pct: float | None = None

    @property
    def nfev(self) -> int:
        """:attr:`evaluations`, by the name of the optimizers' states and SciPy's results."""
        return self.evaluations

    @property
    def nit(self) -> int:
        """:attr:`iterations`, by the name of the optimizers' states and SciPy's results."""
        return self.iterations

    @property
    def best_f(self) -> float:
        """:attr:`fitness`, by the name of a callback's state."""
        return self.fitness

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
            "noise_sigma": float(self.noise_sigma),
            "suspect": bool(self.suspect),
            "k_raw": None if self.k_raw is None else [float(x) for x in self.k_raw],
            "fitness_raw": self.fitness_raw,
            "drive_model": self.drive_model,
            "not_observable": list(self.not_observable),
            "at_bounds": list(self.at_bounds),
            "params_source": self.params_source,
            "skipped": dict(self.skipped),
            "nuisance_true": dict(self.nuisance_true),
            "error_all_pct": self.error_all_pct,
            "parameters": None if self.params is None else self.params.to_dict(),
        }
        d["config"] = None if self.config is None else self.config.to_dict()
        if self.k_true is not None:
            d["k_true"] = [float(x) for x in self.k_true]
            d["error_pct"] = float(self.error_pct)
            d["error_pct_raw"] = self.error_pct_raw
        return d

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "Identification":
        """The identification :meth:`to_dict` wrote (``model_trace``, a trace, is not in it:
        None here); ``from_dict(x.to_dict()).to_dict() == x.to_dict()``."""
        d = dict(data)
        arr = (lambda v: None if v is None else np.asarray(v, dtype=float))
        params = d.get("parameters")
        config = d.get("config")
        return cls(
            algorithm=d["algorithm"], seed=d["seed"], k=arr(d["k"]), fitness=float(d["fitness"]),
            evaluations=int(d["evaluations"]), iterations=int(d["iterations"]),
            elapsed_s=float(d["elapsed_s"]), kernel_s=float(d["kernel_s"]),
            history=arr(d["history"]), reason=d["reason"], model_trace=None,
            k_true=arr(d.get("k_true")), error_pct=d.get("error_pct"),
            diverged=int(d.get("diverged", 0)), options=dict(d.get("options") or {}),
            k_raw=arr(d.get("k_raw")), fitness_raw=d.get("fitness_raw"),
            error_pct_raw=d.get("error_pct_raw"),
            polish_evaluations=int(d.get("polish_evaluations", 0)),
            polish_s=float(d.get("polish_s", 0.0)), restarts=int(d.get("restarts", 0)),
            noise_floor=float(d.get("noise_floor", 0.0)), suspect=bool(d.get("suspect", False)),
            run_evaluations=int(d.get("run_evaluations", 0)),
            fault_model=d.get("fault_model", "paper"), compile_s=float(d.get("compile_s", 0.0)),
            nuisance=dict(d.get("nuisance") or {}),
            config=None if config is None else IdentificationConfig.from_dict(config),
            noise_sigma=float(d.get("noise_sigma", float("nan"))),
            drive_model=d.get("drive_model", "modelled controller"),
            not_observable=tuple(d.get("not_observable") or ()),
            at_bounds=tuple(d.get("at_bounds") or ()),
            params_source=d.get("params_source", "preset"),
            params=None if params is None else ActuatorParams.from_dict(params,
                                                                        source="identification"),
            skipped=dict(d.get("skipped") or {}),
            nuisance_true=dict(d.get("nuisance_true") or {}), error_all_pct=d.get("error_all_pct"))



# ----------------------------------------------------------------------------- solvers


def make_solver(name: str, *, options: Mapping[str, Any] | None = None, polish: bool = True,
                restarts: int | None = None, suspect_ratio: float | None = None,
                budget: bool = False) -> Solver:
    """The solver registered as ``name`` with emaphm's identification defaults.

    ``"lsq"``: :class:`~emaphm.optim.lsq.MultistartLeastSquares` from a warm start (if
    the problem has one) and the healthy actuator, then, while the fit is above the
    misfit test's limit at :data:`LSQ_ACCEPT_P`, from the best points of the problem's
    seeded sample (at most ``restarts`` further starts, default :data:`LSQ_RESTARTS`),
    polished (:data:`POLISH_LSQ_EVALUATIONS`). It takes no ``options``.

    The others: :class:`~emaphm.optim.solvers.Metaheuristic` over the optimizer
    :func:`emaphm.optim.get_optimizer` builds from ``name`` and ``options``, polished
    (``polish``, at most :data:`POLISH_MAX_EVALUATIONS`), run again with spawned seeds
    while the fit exceeds ``suspect_ratio`` times the trace's noise floor: ``restarts``
    times (default :data:`DEFAULT_RESTARTS` with the polish and no ``budget``, else 0).

    ``suspect_ratio`` (default: the misfit test's limit,
    :func:`emaphm.fitness.misfit_limit`, the fit ratio an actuator the model describes
    exceeds with probability :data:`emaphm.fitness.MISFIT_P`) also says when a further
    least-squares start is worth it. ``budget``: whether a budget caps the search (then
    the metaheuristics restart by default no more).
    """
    if name not in algorithm_names():
        raise ValueError(f"unknown algorithm {name!r}; choose one of {', '.join(algorithm_names())}"
                         " (or register your own: emaphm.optim.register)")
    if restarts is not None and (isinstance(restarts, bool) or not isinstance(restarts, (int, np.integer))
                                 or restarts < 0):
        raise ValueError(f"restarts must be an integer >= 0, got {restarts!r}")
    if suspect_ratio is None:
        suspect_ratio = misfit_limit()
    if isinstance(suspect_ratio, bool) or not isinstance(suspect_ratio, (int, float)) \
            or not suspect_ratio > 1:
        raise ValueError(f"suspect_ratio must be a number > 1, got {suspect_ratio!r}")
    if name == DEFAULT_ALGORITHM:
        if options:
            raise ValueError(f"{DEFAULT_ALGORITHM!r} takes no optimizer options, got {dict(options)}")
        return MultistartLeastSquares(
            restarts=LSQ_RESTARTS if restarts is None else int(restarts),
            accept_ratio=misfit_limit(LSQ_ACCEPT_P), settle_ratio=float(suspect_ratio),
            polish_evaluations=POLISH_LSQ_EVALUATIONS if polish else 0)
    kind = registered_kind(name)
    if kind in ("function", "solver") and options:
        raise ValueError(f"{name!r} (a registered {kind}) takes no options, got {dict(options)}")
    if kind == "function":
        return _callable(lookup(name), name, polish, restarts, float(suspect_ratio), budget)
    if kind == "solver":
        return Renamed(lookup(name), name)
    optimizer = get_optimizer(name, **dict(options or {}))
    return _metaheuristic(optimizer, polish, restarts, suspect_ratio, budget,
                          label=name if kind is not None else "")


def _metaheuristic(optimizer: Any, polish: bool, restarts: int | None, suspect_ratio: float,
                   budget: bool, label: str = "") -> Metaheuristic:
    if restarts is None:          # none under a budget (a cap) or for the bare algorithm
        restarts = DEFAULT_RESTARTS if not budget and polish else 0
    return Metaheuristic(optimizer, polish=bool(polish), restarts=int(restarts),
                         restart_ratio=float(suspect_ratio),
                         polish_evaluations=POLISH_MAX_EVALUATIONS, label=label)


def _callable(fn: Any, name: str, polish: bool, restarts: int | None, suspect_ratio: float,
              budget: bool) -> CallableSolver:
    """A plain function polished and restarted as the metaheuristics are."""
    if restarts is None:
        restarts = DEFAULT_RESTARTS if not budget and polish else 0
    return CallableSolver(fn, name=name, polish=bool(polish), restarts=int(restarts),
                          restart_ratio=float(suspect_ratio),
                          polish_evaluations=POLISH_MAX_EVALUATIONS)


def as_solver(solver: Any, *, budget: bool = False) -> Solver:
    """A solver from what :func:`identify` accepts: a registered name (:func:`make_solver`),
    a solver object, an ask/tell optimizer (a :class:`Metaheuristic` with the
    identification's defaults) or a function ``f(objective, bounds, rng) -> x``
    (:class:`~emaphm.optim.solvers.CallableSolver`)."""
    if isinstance(solver, str):
        return make_solver(solver, budget=budget)
    own = next((n for n, obj in registered().items() if obj is solver), None)
    if own is not None:                    # a registered object goes by its name
        return make_solver(own, budget=budget)
    if all(hasattr(solver, m) for m in ("init", "step", "result")):
        return solver
    if isinstance(solver, Optimizer):
        return _metaheuristic(solver, True, None, misfit_limit(), budget)
    if callable(solver):
        return _callable(solver, "", True, None, misfit_limit(), budget)
    raise ValueError(f"solver must be a name ({', '.join(algorithm_names())}), a solver, an ask/tell "
                     f"optimizer or a function f(objective, bounds, rng) -> x; got "
                     f"{type(solver).__name__}")


def _solver_settings(solver: Solver) -> tuple[dict, bool]:
    """``(options, polish)`` of a solver as :attr:`Identification.options` reports them."""
    if isinstance(solver, Metaheuristic):
        return optimizer_options(solver.optimizer), solver.polish
    if isinstance(solver, CallableSolver):
        return {}, solver.polish
    if isinstance(solver, MultistartLeastSquares):
        return {}, solver.polish_evaluations > 0
    return {}, False


# ----------------------------------------------------------------------------- config


@dataclass(frozen=True)
class IdentificationConfig:
    """The problem and solver settings of an identification, as one typed value.

    Campaigns, the health history, the spread estimate and the mismatch check carry this
    instead of identify's keywords; it round-trips to JSON (:meth:`to_dict`,
    :meth:`from_dict`). What it does not hold is the data: the trace, the parameters and
    the seed.

    ==============  ========================================================================
    field           meaning
    ==============  ========================================================================
    algorithm       a name of :func:`algorithm_names` (:func:`make_solver`): a built-in
                    one or one registered (:func:`emaphm.optim.register`; the registered
                    object itself is taken by its name)
    options         the optimizer's settings (e.g. ``{"pop_size": 30}``); none for ``lsq``
    budget          evaluations (int), wall-clock seconds (``"30s"``) or None (the
                    algorithm's own stopping rule), :func:`parse_budget`
    polish          refine the best point by a compass search
    restarts        further runs or starts (None: :func:`make_solver`'s default)
    suspect_ratio   fit ratio of a wrong basin (None: the misfit test's limit)
    search          search space (None: the solver's own)
    n_sub, mode     monitoring-model sub-steps and fitness mode
    fault_model     what k3..k5 mean (None: the trace's own)
    nuisance        parameters searched beside k (None: by the parameters' calibration)
    min_rotation    least motor rotation range the trace must show [rad] (default one
                    revolution, which the eccentricity needs; 0 skips the check)
    drive_model     what stands in for the drive's controller (None: the trace's best,
                    :func:`emaphm.recorded.drive_model_of`)
    ==============  ========================================================================

    The first group chooses and tunes the solver, the second (``search`` on) describes
    the problem (:meth:`problem`).
    """

    algorithm: str = DEFAULT_ALGORITHM
    options: Mapping[str, Any] = field(default_factory=dict, hash=False)
    budget: Any = None
    polish: bool = True
    restarts: int | None = None
    suspect_ratio: float | None = None
    search: str | None = None
    n_sub: int = 1
    mode: str = "phases"
    fault_model: str | None = None
    nuisance: tuple[str, ...] | None = None
    min_rotation: float = 2 * math.pi
    drive_model: str | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "algorithm", algorithm_name(self.algorithm))
        object.__setattr__(self, "options", dict(_jsonable(dict(self.options or {}))))
        if self.drive_model is not None and self.drive_model not in DRIVE_MODELS:
            raise ValueError(f"unknown drive model {self.drive_model!r}; choose one of "
                             + ", ".join(repr(d) for d in DRIVE_MODELS))
        if isinstance(self.min_rotation, bool) or not isinstance(self.min_rotation, (int, float)) \
                or not (math.isfinite(self.min_rotation) and self.min_rotation >= 0):
            raise ValueError(f"min_rotation [rad] must be a finite number >= 0 (0 skips the "
                             f"check), got {self.min_rotation!r}")
        object.__setattr__(self, "min_rotation", float(self.min_rotation))
        if self.nuisance is not None:
            object.__setattr__(self, "nuisance", tuple(self.nuisance))
            bad = [n for n in self.nuisance if n not in NUISANCE_RANGE]
            if bad:
                raise ValueError(f"nuisance: unknown {bad}; choose from {', '.join(NUISANCE_RANGE)}")
        if self.search is not None and self.search not in SEARCH_SPACES:
            raise ValueError(f"unknown search space {self.search!r}; choose one of "
                             f"{', '.join(SEARCH_SPACES)}")
        if self.mode not in FITNESS_MODES:
            raise ValueError(f"unknown fitness mode {self.mode!r}; choose one of "
                             f"{', '.join(FITNESS_MODES)}")
        if not isinstance(self.polish, bool):
            raise ValueError(f"polish must be True or False, got {self.polish!r}")
        parse_budget(self.budget)
        self.solver()                      # validates the name, the options, the restarts

    def solver(self) -> Solver:
        """The solver these settings describe (:func:`make_solver`)."""
        return make_solver(self.algorithm, options=self.options, polish=self.polish,
                           restarts=self.restarts, suspect_ratio=self.suspect_ratio,
                           budget=self.budget is not None)

    def termination(self) -> Termination | None:
        """The budget as a termination (:func:`parse_budget`)."""
        return parse_budget(self.budget)

    def problem(self, trace: Trace, params: ActuatorParams | None = None, *,
                start: Any = None) -> IdentificationProblem:
        """The identification problem of ``trace`` with these settings."""
        return IdentificationProblem(trace, params=params, fault_model=self.fault_model,
                                     nuisance=self.nuisance, n_sub=self.n_sub, mode=self.mode,
                                     search=self.search, start=start,
                                     min_rotation=self.min_rotation, drive_model=self.drive_model)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON values; :meth:`from_dict` of it gives an equal config."""
        d = {f.name: getattr(self, f.name) for f in fields(self)}
        d["options"] = dict(self.options)
        d["nuisance"] = None if self.nuisance is None else list(self.nuisance)
        d["budget"] = self.budget if self.budget is None or isinstance(self.budget, (int, str)) \
            else float(self.budget) if isinstance(self.budget, (float, np.floating)) \
            else str(self.budget)
        return d

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "IdentificationConfig":
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise ValueError(f"identification config: unknown key(s) {', '.join(unknown)}; "
                             f"known: {', '.join(sorted(known))}")
        return cls(**dict(data))


# ----------------------------------------------------------------------------- minimize


def minimize(problem: IdentificationProblem, solver: Any = DEFAULT_ALGORITHM,
             termination: Any = None, *, seed: int,
             callback: Callable[[Any], bool | None] | None = None) -> Identification:
    """Identify the fault vector of ``problem`` with ``solver`` (a name, a solver, an
    optimizer or a function, :func:`as_solver`), stopped by ``termination`` (a
    :class:`~emaphm.optim.Termination` or a budget, :func:`parse_budget`; None: the
    solver's own rule). ``seed`` (an int) seeds every random choice; ``callback(state)``
    is called as the search progresses (True stops it).

    The model kernels are compiled (or loaded from the disk cache) before the clock
    starts (:attr:`Identification.compile_s`). Raises :class:`~emaphm.traces.TraceError`
    when every candidate diverged (no k reproduces the trace).
    """
    seed = check_seed(seed)
    budget = termination
    term = parse_budget(termination)
    solver = as_solver(solver, budget=term is not None)
    if problem.start is not None and getattr(solver, "kind", "") != "least_squares":
        raise ValueError(f"the problem's warm start is used by the least-squares solver, not by "
                         f"{solver.name!r}; drop start= or identify with 'lsq'")
    search = problem.search or (least_squares_search(problem.fault_model)
                                if getattr(solver, "kind", "") == "least_squares"
                                else default_search(problem.fault_model))
    view = problem.view(search)
    tc = time.perf_counter()
    if getattr(solver, "kind", "") == "least_squares":
        import scipy.optimize  # noqa: F401  (imported before the clock, like the kernels)

        sobol_sample(problem.n_var, seed)     # its sample drawn (or read) before the clock
    problem.warm_up()
    compile_s = time.perf_counter() - tc
    t0 = time.perf_counter()
    res = solve(view, solver, term, seed=seed, callback=callback)
    if not np.isfinite(res.fun):
        raise TraceError("no fault vector reproduces this trace: every candidate of the monitoring "
                         "model diverged (infinite fitness); the trace's command or load "
                         "(metadata) or the parameters (--params) do not describe a working "
                         "actuator")
    k_raw, _ = problem.decode(res.x_raw, search)
    k, nu = problem.decode(res.x, search)
    elapsed = time.perf_counter() - t0
    k_true = problem.k_true
    floor = problem.noise_floor
    ratio = getattr(solver, "settle_ratio", getattr(solver, "restart_ratio", misfit_limit()))
    options, polish = _solver_settings(solver)
    return Identification(
        algorithm=solver.name, seed=seed, k=k, fitness=float(res.fun), evaluations=int(res.nfev),
        iterations=int(res.nit), elapsed_s=elapsed, kernel_s=view.kernel_s,
        history=res.history, reason=res.reason, model_trace=problem.model_trace(k, nu),
        k_true=k_true, error_pct=None if k_true is None else float(error_pct(k, k_true)),
        diverged=view.diverged, fault_model=problem.fault_model, compile_s=compile_s,
        nuisance={n: float(v) for n, v in zip(problem.nuisance, nu)},
        options={**options, "n_sub": problem.n_sub, "mode": problem.mode,
                 "polish": bool(polish), "search": search,
                 "budget": None if budget is None else str(budget)},
        k_raw=k_raw, fitness_raw=float(res.fun_raw),
        error_pct_raw=None if k_true is None else float(error_pct(k_raw, k_true)),
        polish_evaluations=int(res.polish_evaluations), polish_s=float(res.polish_s),
        restarts=int(res.starts) - 1, noise_floor=floor,
        suspect=bool(res.fun > (ratio * floor if floor > 0 else np.inf)),
        run_evaluations=int(res.run_evaluations), noise_sigma=problem.noise_sigma,
        config=_config_of(problem, solver, budget, options, polish),
        drive_model=problem.drive_model, not_observable=problem.not_observable,
        at_bounds=_at_bounds(problem.nuisance, nu), params_source=problem.params_source,
        params=problem.params, skipped=dict(getattr(res, "skipped", None) or {}),
        nuisance_true=problem.nuisance_true,
        error_all_pct=None if k_true is None else error_all_pct(
            k, k_true, dict(zip(problem.nuisance, nu)), problem.nuisance_true))


#: A parameter searched beside k within this share of its range from an end sits at it.
AT_BOUND = 1e-3


def _at_bounds(names: tuple[str, ...], values: Any) -> tuple[str, ...]:
    """The parameters searched beside k whose values sit at an end of their range
    (:data:`emaphm.search.NUISANCE_RANGE`), a range that is not a physical one (the
    encoder's offset, a zero dead time or Stribeck speed is a value, not a bound)."""
    out = []
    for name, v in zip(names, np.asarray(values, dtype=float).reshape(-1)):
        lo, hi = NUISANCE_RANGE[name]
        tol = AT_BOUND * (hi - lo)
        if (v <= lo + tol and lo != 0.0) or v >= hi - tol:
            out.append(name)
    return tuple(out)


def _named(solver: Solver) -> bool:
    """Whether ``solver`` is what its name builds: a built-in name, or a name registered to
    the solver's own function, optimizer (or its class) or solver."""
    name = solver.name
    if name in ALGORITHM_NAMES:
        return not (isinstance(solver, Metaheuristic) and solver.label)
    kind = registered_kind(name)
    if kind is None:
        return False
    obj = lookup(name)
    if isinstance(solver, CallableSolver):
        return solver.fn is obj
    if isinstance(solver, Metaheuristic):
        return solver.optimizer is obj or type(solver.optimizer) is obj
    return isinstance(solver, Renamed) and solver.solver is obj


def _config_of(problem: IdentificationProblem, solver: Solver, budget: Any, options: dict,
               polish: bool) -> IdentificationConfig | None:
    """The settings an identification was made with (None for a solver without a name of
    :data:`ALGORITHM_NAMES`); the restarts and the suspect ratio as resolved."""
    if not _named(solver):
        return None
    return IdentificationConfig(
        algorithm=solver.name, options=options,
        budget=budget if budget is None or isinstance(budget, (int, np.integer, str, float)) else None,
        polish=polish, restarts=getattr(solver, "restarts", None),
        suspect_ratio=getattr(solver, "settle_ratio", getattr(solver, "restart_ratio", None)),
        search=problem.search, n_sub=problem.n_sub, mode=problem.mode,
        fault_model=problem.fault_model, nuisance=problem.nuisance,
        min_rotation=problem.min_rotation, drive_model=problem.drive_model)


# ----------------------------------------------------------------------------- identify

#: identify()'s keywords of version 0.3, kept for one release with a warning, and where
#: each belongs now: the problem's or the solver's settings (IdentificationConfig).
_OLD_KEYWORDS = {"budget": "termination", "options": "config", "polish": "config",
                 "restarts": "config", "suspect_ratio": "config", "n_sub": "problem",
                 "mode": "problem", "search": "problem", "nuisance": "problem",
                 "start": "problem", "objective": "problem"}


def identify(trace: Trace | IdentificationProblem | list, solver: Any = DEFAULT_ALGORITHM, *,
             seed: int, termination: Any = None, params: Any = None,
             fault_model: str | None = None,
             callback: Callable[[Any], bool | None] | None = None, workers: int | None = None,
             **deprecated: Any) -> Identification | list[Identification]:
    """Identify the fault vector of a trace (see :func:`minimize`).

    ``trace`` is a :class:`~emaphm.traces.Trace` (its problem is built with ``params``,
    default the preset, and ``fault_model``, default the trace's own) or an
    :class:`~emaphm.problem.IdentificationProblem` (for the nuisance, a warm start, the
    fitness mode, ...). ``solver`` is a name of :data:`ALGORITHM_NAMES` (default
    ``"lsq"``), an :class:`IdentificationConfig` (its settings, the budget included), a
    solver, an ask/tell optimizer or a function ``f(objective, bounds, rng) -> x``.
    ``termination``: a budget or a termination (:func:`parse_budget`). ``seed``: an int,
    required (same seed, same result). ``callback(state)``: progress; True stops.

    ``params``: an :class:`~emaphm.params.ActuatorParams`, a dict or a TOML path (default:
    the trace's own, else the preset; :func:`emaphm.params.resolve_params`).

    A list of traces is a batch (:func:`emaphm.batch.identify_many`): each identified as
    this call would identify it alone, on ``workers`` processes (None, 0 or 1: here, one
    after the other); the identifications come back in the order of the traces.

    The keywords of version 0.3 (``budget``, ``options``, ``polish``, ``restarts``,
    ``suspect_ratio``, ``n_sub``, ``mode``, ``search``, ``nuisance``, ``start``,
    ``objective``) still work for one release, with a DeprecationWarning.
    """
    seed = check_seed(seed)
    if isinstance(trace, (list, tuple)):
        from .batch import identify_many

        return identify_many(trace, solver, workers=workers, seed=seed, termination=termination,
                             params=params, fault_model=fault_model, callback=callback,
                             **deprecated)
    if workers is not None and workers > 1:
        raise ValueError("workers= shares a list of traces among processes; give a list of "
                         "traces, or drop workers")
    if isinstance(trace, IdentificationProblem) and (params is not None or fault_model is not None):
        raise ValueError("give params and fault_model to the IdentificationProblem, not beside it")
    if deprecated:
        trace, solver, termination = _old_keywords(trace, solver, termination, params,
                                                   fault_model, deprecated)
    if isinstance(solver, IdentificationConfig):
        termination = solver.budget if termination is None else termination
        problem = (trace if isinstance(trace, IdentificationProblem) else
                   replace(solver, fault_model=fault_model or solver.fault_model).problem(trace, params))
        solver = solver.solver()
    else:
        solver = as_solver(solver, budget=parse_budget(termination) is not None)
        problem = (trace if isinstance(trace, IdentificationProblem) else
                   IdentificationProblem(trace, params=params, fault_model=fault_model))
    return minimize(problem, solver, termination, seed=seed, callback=callback)


def _old_keywords(trace: Any, solver: Any, termination: Any, params: Any, fault_model: Any,
                  kw: dict[str, Any]) -> tuple[Any, Any, Any]:
    """identify()'s 0.3 keywords as a problem, a config and a termination (with a warning)."""
    unknown = sorted(set(kw) - set(_OLD_KEYWORDS))
    if unknown:
        raise TypeError(f"identify() got unexpected keyword argument(s) {', '.join(unknown)}")
    warnings.warn(f"identify({', '.join(f'{k}=' for k in kw)}) is the 0.3 spelling, kept for one "
                  "release: give the problem's settings (nuisance, start, mode, n_sub, search, "
                  "objective) in an IdentificationProblem, the solver's (options, polish, "
                  "restarts, suspect_ratio) in an IdentificationConfig or a solver, and the "
                  "budget as termination=", DeprecationWarning, stacklevel=3)
    if "budget" in kw:
        if termination is not None:
            raise ValueError("give termination= or the old budget=, not both")
        termination = kw["budget"]
    if any(_OLD_KEYWORDS[k] == "config" for k in kw):
        if not isinstance(solver, str):
            raise ValueError("options, polish, restarts and suspect_ratio go with a solver name")
        if "start" in kw and solver != DEFAULT_ALGORITHM and kw.get("start") is not None:
            raise ValueError(f"start (a warm start) is an option of {DEFAULT_ALGORITHM!r}, not of "
                             f"{solver!r}")
        solver = make_solver(solver, options=kw.get("options"), polish=kw.get("polish", True),
                             restarts=kw.get("restarts"), suspect_ratio=kw.get("suspect_ratio"),
                             budget=parse_budget(termination) is not None)
    elif kw.get("start") is not None and isinstance(solver, str) and solver != DEFAULT_ALGORITHM:
        raise ValueError(f"start (a warm start) is an option of {DEFAULT_ALGORITHM!r}, not of "
                         f"{solver!r}")
    problem_kw = {k: v for k, v in kw.items() if _OLD_KEYWORDS[k] == "problem"}
    if problem_kw and not isinstance(trace, IdentificationProblem):
        trace = IdentificationProblem(trace, params=params, fault_model=fault_model, **problem_kw)
    return trace, solver, termination


def _jsonable(value: Any) -> Any:
    """Options as plain JSON values (NumPy scalars and arrays included)."""
    return json.loads(json.dumps(value, default=lambda o: o.tolist() if hasattr(o, "tolist") else str(o)))
