"""The identification problem: a trace, the actuator it came from, and what is searched.

:class:`IdentificationProblem` (frozen) holds the trace, the healthy actuator's
parameters, the fault model (what k3..k5 mean), the nuisance parameters searched beside
``k``, the monitoring model's sub-steps and the fitness mode. It owns the objective
(Eq. 4 and its residual vector, :class:`emaphm.fitness.Eq4Objective`), the healthy point,
the trace's noise floor, and reads a ``k`` as a diagnosis with its own fault model
(:meth:`IdentificationProblem.diagnose`).

A solver of :mod:`emaphm.optim.solvers` sees the problem through a
:class:`SearchView` (:meth:`IdentificationProblem.view`): the unit box of one search
space (:mod:`emaphm.search`), a batch fitness, the residuals, the starts (a warm start,
then the healthy actuator) and a screened sample of further starts. A view counts what
it evaluates and is made for one search; the problem holds no counters and can be
identified again and again (it is the explicit cache of the objective's set-up).

Build a variant with :func:`dataclasses.replace` (``replace(problem, mode="equivalent")``).
"""

from __future__ import annotations

import inspect
import math
import time
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from .diagnosis import diagnose
from .faults import K_NOMINAL, N_K, as_k, error_pct, loop_report, shorted_fraction
from .fitness import Eq4Objective
from .logs import announce_compiles
from .modes import MODES
from .params import PARAMS_SOURCES, ActuatorParams, resolve_params
from .recorded import (DRIVE_NUISANCE, DRIVEN, NOT_OBSERVABLE, RecordedVoltageObjective,
                       drive_model_of)
from .search import (NUISANCE_RANGE, SEARCH_SPACES, default_search, from_k, nuisance_from_box, nuisance_start,
                     nuisance_to_box, to_k)
from .traces import Trace, validate

__all__ = ["IdentificationProblem", "SearchView", "apply_extra", "DRIFT_NUISANCE", "default_nuisance",
           "LSQ_SAMPLE", "LSQ_SINGLE_FAULT_LEVELS", "single_fault_points", "true_k",
           "true_nuisance", "error_all_pct"]

#: Nuisance parameters searched with k by default for a calibrated unit: what drifts most
#: after a calibration (winding resistance and magnet flux, with temperature).
DRIFT_NUISANCE = ("R", "flux")

#: Space-filling sample (scrambled Sobol points, seeded) from which the least-squares
#: solver takes its further starts, when the first starts are not good enough.
LSQ_SAMPLE = 64

#: Single-fault points added to that sample: each fault component alone at these values,
#: the others healthy (:func:`single_fault_points`). Most actuators have one fault, and
#: a fault whose effect is flat at the healthy value cannot be reached from it by a
#: gradient: a backlash below the gear train's deflection under load (k2 up to about
#: 0.05 with the preset's contact) hardly changes the currents, so least squares from
#: the healthy k stays at k2 = 0 when the truth is 0.25.
LSQ_SINGLE_FAULT_LEVELS = (0.1, 0.25, 0.5, 0.75)


def default_nuisance(params: ActuatorParams | None) -> tuple[str, ...]:
    """The nuisance parameters searched by default: :data:`DRIFT_NUISANCE` for calibrated
    parameters, none for a data sheet."""
    return DRIFT_NUISANCE if params is not None and params.calibration.date else ()


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


def true_k(trace: Trace) -> np.ndarray | None:
    """The fault vector a simulated trace carries in its metadata (None for a bench trace
    or an unreadable one)."""
    k = trace.meta.get("k") if isinstance(trace.meta, dict) else None
    if k is None:
        return None
    try:
        return as_k(k)
    except ValueError:
        return None


def true_nuisance(trace: Trace) -> dict[str, float]:
    """The true values of the parameters searched beside k that a simulated trace's injected
    faults carry (its metadata's ``truth``, :func:`emaphm.simulate.simulate`); empty for a
    bench trace or one without such faults."""
    truth = trace.meta.get("truth") if isinstance(trace.meta, dict) else None
    if not isinstance(truth, dict):
        return {}
    return {str(n): float(v) for n, v in truth.items() if n in NUISANCE_RANGE}


def error_all_pct(k: Any, k_true: Any, nuisance: Any, truth: Any) -> float:
    """Eq. 9 extended to the parameters searched beside k: the true ones (``truth``, by
    name) against the values found (``nuisance``; 0, nominal, where one was not searched),
    each difference in units of its range (:data:`emaphm.search.NUISANCE_RANGE`, as k's
    components are in units of [0, 1]). Eq. 9 itself where ``truth`` is empty:
    ``100 / sqrt(6.5 + m) sqrt(S_9 + sum_j ((nu_j - nu_j,true) / w_j)^2)`` with ``S_9``
    Eq. 9's sum of squares and ``m`` the parameters of ``truth``."""
    truth = dict(truth or {})
    found = dict(nuisance or {})
    s9 = (error_pct(k, k_true) * math.sqrt(6.5) / 100.0) ** 2
    extra = sum(((found.get(n, 0.0) - v) / (NUISANCE_RANGE[n][1] - NUISANCE_RANGE[n][0])) ** 2
                for n, v in truth.items())
    return 100.0 / math.sqrt(6.5 + len(truth)) * math.sqrt(s9 + extra)


def _sobol(d: int, seed: int):
    """SciPy's scrambled Sobol engine seeded by ``seed`` (``rng=`` where SciPy has it, the
    same stream as the older ``seed=``)."""
    from scipy.stats import qmc

    if "rng" in inspect.signature(qmc.Sobol).parameters:
        return qmc.Sobol(d, scramble=True, rng=seed)
    return qmc.Sobol(d, scramble=True, seed=seed)  # pragma: no cover - SciPy < 1.15


#: Seeds whose Sobol samples :func:`sobol_sample` keeps on disk: a user's own (a campaign's
#: run seeds, a history's); a 64-bit seed spawned for one run is drawn once.
SAMPLE_CACHE_SEEDS = 2 ** 16


def sobol_sample(d: int, seed: int, n: int = LSQ_SAMPLE) -> np.ndarray:
    """The first ``n`` points of SciPy's scrambled Sobol sequence in ``d`` dimensions seeded
    by ``seed`` (:func:`_sobol`): from the kernels' cache folder
    (:func:`emaphm.models.warm.cache_folder`) where an earlier process drew them, else drawn
    and kept there (seeds under :data:`SAMPLE_CACHE_SEEDS`). The same numbers either way;
    what a later process saves is importing ``scipy.stats`` (a third of a second of the
    quick start's diagnosis) to draw them."""
    from importlib import metadata

    from ._files import atomic_write
    from .models.warm import cache_folder

    folder = cache_folder()
    path = None
    if folder is not None and seed in range(SAMPLE_CACHE_SEEDS):
        try:
            version = metadata.version("scipy")
        except metadata.PackageNotFoundError:      # pragma: no cover - SciPy is a dependency
            version = "unknown"
        path = folder / f"sobol-{d}-{seed}-{n}-scipy-{version}.npy"
        try:
            Z = np.load(path, allow_pickle=False)
            if Z.shape == (n, d) and Z.dtype == np.float64 and np.all((Z >= 0) & (Z < 1)):
                return Z
        except (OSError, ValueError):
            pass
    Z = _sobol(d, seed).random(n)
    if path is not None:
        try:
            atomic_write(path, lambda fh: np.save(fh, Z, allow_pickle=False))
        except OSError:
            pass                                   # a read-only cache: drawn each time
    return Z


@dataclass(frozen=True, eq=False)
class IdentificationProblem:
    """What an identification searches, and against which trace.

    ============  ===================================================================
    field         meaning
    ============  ===================================================================
    trace         the measured (or simulated) trace; validated on construction
    params        the healthy actuator the monitoring model assumes: an
                  :class:`~emaphm.params.ActuatorParams`, a dict or a TOML path; default
                  the trace's own (its metadata's ``"parameters"``), else the preset
                  (:func:`emaphm.params.resolve_params`)
    params_source where ``params`` came from (:data:`emaphm.params.PARAMS_SOURCES`);
                  resolved on construction (``"given"`` for parameters given)
    fault_model   what k3..k5 mean (:data:`emaphm.faults.FAULT_MODELS`); default the
                  trace's own (:func:`emaphm.fitness.trace_fault_model`)
    nuisance      parameters searched beside k (:data:`emaphm.search.NUISANCE_RANGE`);
                  default :func:`default_nuisance` of ``params``
    n_sub, mode   monitoring-model sub-steps and fitness mode (:class:`Eq4Objective`)
    search        search space (:data:`emaphm.search.SEARCH_SPACES`); None: the
                  solver's (least squares :func:`emaphm.search.least_squares_search`,
                  the others :func:`emaphm.search.default_search`)
    start         a fault vector to start a local solver from first (a warm start: the
                  actuator's previous inspection), before the healthy actuator
    min_rotation  least motor rotation range the trace must show [rad]
    objective     a prebuilt objective for this trace (its settings must agree)
    drive_model   what stands in for the drive's controller
                  (:data:`emaphm.recorded.DRIVE_MODELS`); default the trace's best
                  (:func:`emaphm.recorded.drive_model_of`: its recorded voltages where
                  it has them, else the modelled controller)
    held          components of k (0-based) held at their healthy values: the fit
                  without those faults (the verdict asks whether a short explains them)
    ============  ===================================================================

    After construction ``params``, ``params_source``, ``fault_model``, ``nuisance`` and
    ``drive_model`` hold the resolved values. Parameters given for a trace that names
    another actuator warn (:class:`~emaphm.params.ActuatorMismatchWarning`) when the
    problem is first built (a variant made with :func:`dataclasses.replace` keeps the
    source and does not warn again).
    """

    trace: Trace
    params: ActuatorParams | None = None
    fault_model: str | None = None
    nuisance: tuple[str, ...] | None = None
    n_sub: int = 1
    mode: str = "phases"
    search: str | None = None
    start: Any = None
    min_rotation: float = 2 * math.pi
    objective: Any = field(default=None, repr=False)
    drive_model: str | None = None
    params_source: str | None = None
    held: tuple[int, ...] = ()

    def __post_init__(self) -> None:
        held = tuple(sorted({int(j) for j in self.held}))
        if any(not 0 <= j < N_K for j in held):
            raise ValueError(f"held components are indices of k, 0 to {N_K - 1}, got {self.held!r}")
        object.__setattr__(self, "held", held)
        if self.params_source is not None and self.params_source not in PARAMS_SOURCES:
            raise ValueError(f"params_source must be one of {', '.join(PARAMS_SOURCES)}, got "
                             f"{self.params_source!r}")
        params, source = resolve_params(self.params, self.trace, warn=self.params_source is None)
        object.__setattr__(self, "params", params)
        object.__setattr__(self, "params_source", self.params_source or source)
        if self.search is not None and self.search not in SEARCH_SPACES:
            raise ValueError(f"unknown search space {self.search!r}; choose one of "
                             f"{', '.join(SEARCH_SPACES)}")
        if self.start is not None:
            object.__setattr__(self, "start", as_k(self.start))
        obj = self.objective
        drive = drive_model_of(self.trace, self.drive_model)
        object.__setattr__(self, "drive_model", drive)
        if obj is None:
            nuisance = default_nuisance(self.params) if self.nuisance is None else tuple(self.nuisance)
            validate(self.trace, min_rotation=self.min_rotation)
            if drive in DRIVEN:
                if self.mode != "phases" or self.n_sub != 1:
                    raise ValueError(f"the drive model {drive!r} compares the phase currents at "
                                     "the drive's control instants: mode 'phases', n_sub 1")
                obj = RecordedVoltageObjective.from_trace(self.trace, self.params,
                                                          fault_model=self.fault_model,
                                                          nuisance=nuisance, drive_model=drive)
            else:
                obj = Eq4Objective.from_trace(self.trace, self.params, n_sub=self.n_sub,
                                              mode=self.mode, fault_model=self.fault_model,
                                              nuisance=nuisance)
        else:
            if self.nuisance is not None and tuple(self.nuisance) != obj.model.nuisance:
                raise ValueError(f"nuisance {tuple(self.nuisance)} differs from the prebuilt "
                                 f"objective's {obj.model.nuisance}")
            if self.fault_model is not None and self.fault_model != obj.model.fault_model:
                raise ValueError(f"fault_model {self.fault_model!r} differs from the prebuilt "
                                 f"objective's {obj.model.fault_model!r}")
            validate(self.trace, min_rotation=self.min_rotation)
        object.__setattr__(self, "objective", obj)
        object.__setattr__(self, "params", obj.model.params)
        object.__setattr__(self, "fault_model", obj.model.fault_model)
        object.__setattr__(self, "nuisance", obj.model.nuisance)
        object.__setattr__(self, "_floor", obj.noise_floor())
        object.__setattr__(self, "_warm", False)

    # ------------------------------------------------------------------ what it is
    @property
    def n_var(self) -> int:
        """Search variables: the 8 of k and one per nuisance parameter."""
        return N_K + len(self.nuisance)

    @property
    def not_observable(self) -> tuple[str, ...]:
        """The fault modes this problem's drive path cannot see
        (:data:`emaphm.recorded.NOT_OBSERVABLE`): their components of k stay healthy."""
        return NOT_OBSERVABLE[self.drive_model]

    def _fixed(self, K: np.ndarray) -> np.ndarray:
        """``K`` with the components of the modes this path cannot see (k8 at 0.5 where no
        position loop is modelled) and those :attr:`held` at their healthy values."""
        blind = [j for m in self.not_observable for j in MODES[m].k_components] + list(self.held)
        if blind:
            K = np.array(K, dtype=float, copy=True)
            K[..., blind] = K_NOMINAL[blind]
        return K

    @property
    def noise_floor(self) -> float:
        """The Eq. 4 value a perfect model would reach on this trace
        (:meth:`Eq4Objective.noise_floor`); 0 for a noise-free trace."""
        return self._floor

    @property
    def noise_sigma(self) -> float:
        """The trace's white-noise level [A rms], the largest of the phases' (0 for a
        noise-free trace)."""
        sigma = self.objective.noise_sigma
        return float(np.max(sigma)) if sigma is not None and np.size(sigma) else 0.0

    @property
    def healthy(self) -> np.ndarray:
        """The healthy fault vector (nominal k)."""
        return K_NOMINAL.copy()

    @property
    def k_true(self) -> np.ndarray | None:
        """The true k of a simulated trace (:func:`true_k`)."""
        return true_k(self.trace)

    @property
    def nuisance_true(self) -> dict[str, float]:
        """The true values of parameters beside k of a simulated trace's injected faults
        (:func:`true_nuisance`)."""
        return true_nuisance(self.trace)

    def warm_up(self) -> float:
        """Compile (or load from the disk cache) the model kernels by running the model
        once, the first time only; returns the seconds it took (0 once warm)."""
        if self._warm:
            return 0.0
        announce_compiles()
        t0 = time.perf_counter()
        model = self.objective.model
        model.simulate(K_NOMINAL)                                       # the scalar kernel
        model.simulate_population(                                      # the SIMD one
            np.tile(np.concatenate([K_NOMINAL, np.zeros(len(self.nuisance))]), (2, 1)))
        object.__setattr__(self, "_warm", True)
        return time.perf_counter() - t0

    def view(self, search: str) -> "SearchView":
        """The problem in the search space ``search``, for one search."""
        return SearchView(self, search)

    def decode(self, z: np.ndarray, search: str) -> tuple[np.ndarray, np.ndarray]:
        """``(k, nuisance values)`` of a point ``z`` of the search space (k clipped to
        [0, 1])."""
        Z = np.atleast_2d(z)
        k = np.clip(self._fixed(to_k(Z[:, :N_K], search))[0], 0.0, 1.0)
        nu = nuisance_from_box(Z[:, N_K:], self.nuisance)[0] if self.nuisance else np.zeros(0)
        return k, nu

    # ------------------------------------------------------------------ readings
    def diagnose(self, k: Any, **kw: Any) -> Any:
        """:func:`emaphm.diagnosis.diagnose` of ``k`` with this problem's parameters, fault
        model and drive path (``fit_ratio``, ``thresholds``, ``mismatch`` passed on)."""
        kw.setdefault("drive_model", self.drive_model)
        return diagnose(k, params=self.params, fault_model=self.fault_model, **kw)

    def fitness_at(self, k: Any, nuisance: Any = None) -> float:
        """Eq. 4 of the fault vector ``k`` with the parameters searched beside it at
        ``nuisance`` (a mapping by name, as an identification reports them; those left out
        at 0, their nominal value)."""
        extra = dict(nuisance or {})
        row = np.concatenate([as_k(k), [float(extra.get(n, 0.0)) for n in self.nuisance]])
        return float(self.objective(row[None, :])[0])

    def params_at(self, nu: np.ndarray | None = None) -> ActuatorParams:
        """The healthy actuator with the values ``nu`` of the parameters searched beside k
        applied (:func:`apply_extra`)."""
        if nu is None or not self.nuisance:
            return self.params
        return apply_extra(self.params, self.nuisance, nu)

    def fault_loops(self, k: np.ndarray, nu: np.ndarray | None = None, *,
                    params: ActuatorParams | None = None) -> dict[str, list[float]]:
        """What the monitoring model at ``k`` (and ``nu``, or on ``params``) says of each
        phase's fault loop (:func:`loop_report`: its RMS current, the power in its bridge
        and its ampere-turns ``mu i_f``), from the loop currents of the scalar kernel
        (:meth:`emaphm.models.monitoring.MonitoringModel.loop_currents`)."""
        from .models.monitoring import MonitoringModel

        params = self.params_at(nu) if params is None else params
        if self.fault_model != "physical":
            return {"fault_current_a_rms": [0.0] * 3, "fault_power_w": [0.0] * 3,
                    "fault_mmf_a_rms": [0.0] * 3, "R_f_ohm": list(params.motor.R_f)}
        model = self.objective.model
        if self.drive_model in DRIVEN:
            # the inverter's and the encoder's values as searched, the actuator's as given
            drive = {n: float(v) for n, v in zip(self.nuisance, np.zeros(len(self.nuisance))
                                                 if nu is None else nu) if n in DRIVE_NUISANCE}
            trial = replace(self, params=params, nuisance=tuple(drive), objective=None)
            f_abc = trial.objective.model.simulate(k, list(drive.values())).f_abc[0]
        else:
            f_abc = MonitoringModel(params, model.profile, n_sub=model.n_sub, theta0=model.theta0,
                                    fault_model="physical").loop_currents(
                np.asarray(k, dtype=float)[None, :])[0]
        return loop_report(np.mean(f_abc ** 2, axis=0), params.motor.R_f,
                           shorted_fraction(np.asarray(k, dtype=float)[2:5]))

    def model_trace(self, k: np.ndarray, nu: np.ndarray | None = None) -> Trace:
        """The monitoring model's signals at ``k`` (and nuisance values ``nu``), on the
        trace's clock."""
        pop = self.objective.model.simulate(k, nu)
        meta = self.trace.meta
        return Trace(t=pop.t + float(self.trace.t[0]), theta_ref=pop.theta_ref,
                     theta_m=pop.theta_m[0], omega_m=pop.omega_m[0], i_abc=pop.i_abc[0],
                     torque=pop.torque[0],
                     meta={"model": "monitoring", "k": np.asarray(k).tolist(),
                           "identified_from": meta.get("scenario") or meta.get("source")})


def apply_extra(params: ActuatorParams, names: tuple[str, ...], values: Any) -> ActuatorParams:
    """``params`` with the values of the parameters searched beside k applied as the model's
    packing applies them (:data:`emaphm.models.layout.NUISANCE`): R and the flux scaled
    (``"R"``, ``"flux"``, ``"demag"``: relative deviations), the load added (``"load"``,
    N m), a phase's fault-bridge resistance scaled by decades (``"Rf_a"``..``"Rf_c"``), one
    phase's resistance scaled (``"R_a"``..``"R_c"``, relative)."""
    m, ld = params.motor, params.load
    R, c0, R_f, T_0 = list(m.R), list(m.c0), list(m.R_f), ld.T_0
    for name, v in zip(names, np.asarray(values, dtype=float).reshape(-1)):
        if name == "R":
            R = [r * (1.0 + v) for r in R]
        elif name in ("flux", "demag"):
            c0 = [c * (1.0 + v) for c in c0]
        elif name == "load":
            T_0 = T_0 + float(v)
        elif name.startswith("Rf_"):
            j = "abc".index(name[-1])
            R_f[j] = R_f[j] * 10.0 ** float(v)
        elif name in ("R_a", "R_b", "R_c"):
            j = "abc".index(name[-1])
            R[j] = R[j] * (1.0 + float(v))
        elif name not in DRIVE_NUISANCE:       # the inverter's and the encoder's, not the actuator's
            raise ValueError(f"unknown parameter {name!r} beside k")
    return replace(params, motor=replace(m, R=tuple(R), c0=tuple(c0), R_f=tuple(R_f)),
                   load=replace(ld, T_0=T_0))


class _Points:
    """The search points of screened candidates, each made when it is read."""

    def __init__(self, view: "SearchView", K: np.ndarray, Z_nu: np.ndarray) -> None:
        self.view, self.K, self.Z_nu = view, K, Z_nu

    def __len__(self) -> int:
        return self.K.shape[0]

    def __getitem__(self, i: int) -> np.ndarray:
        return self.view.point(self.K[i], self.Z_nu[i])


class SearchView:
    """An :class:`IdentificationProblem` in one search space, as a solver of
    :mod:`emaphm.optim.solvers` sees it: the unit box ``[0, 1]^n_var`` (``bounds``), the
    batch fitness ``evaluate(Z)`` and the weighted residuals ``residuals(Z)`` of Eq. 4,
    ``starts()`` (the problem's warm start, then the healthy actuator), ``sample(seed)``
    (a seeded space-filling sample and the single-fault points, screened by their
    fitness) and ``fitness_floor`` (the trace's noise floor).

    It counts what it evaluates (``evaluations``, ``diverged``: candidates whose
    simulation left the physical range, ``kernel_s``: seconds in the model): one view per
    search.
    """

    def __init__(self, problem: IdentificationProblem, search: str) -> None:
        if search not in SEARCH_SPACES:
            raise ValueError(f"unknown search space {search!r}; choose one of "
                             f"{', '.join(SEARCH_SPACES)}")
        self.problem = problem
        self.search = search
        n = problem.n_var
        self.bounds = (np.zeros(n), np.ones(n))
        self.fitness_floor = problem.noise_floor
        self.sample_size = LSQ_SAMPLE + len(single_fault_points())
        self.evaluations = 0
        self.diverged = 0
        self.kernel_s = 0.0

    def candidates(self, Z: np.ndarray) -> np.ndarray:
        """Search points (n, n_var) -> candidate rows ``[k, nuisance]``."""
        Z = np.atleast_2d(Z)
        names = self.problem.nuisance
        K = self.problem._fixed(to_k(Z[:, :N_K], self.search))
        if not names:
            return K
        return np.hstack([K, nuisance_from_box(Z[:, N_K:], names)])

    def _count(self, t0: float, n: int, bad: int) -> None:
        self.kernel_s += time.perf_counter() - t0
        self.evaluations += n
        self.diverged += bad

    def _fitness(self, K: np.ndarray) -> np.ndarray:
        t0 = time.perf_counter()
        f = self.problem.objective(K)
        self._count(t0, f.size, int(np.count_nonzero(~np.isfinite(f))))
        return f

    def evaluate(self, Z: np.ndarray) -> np.ndarray:
        """Eq. 4 of each search point (inf where the simulation diverged)."""
        return self._fitness(self.candidates(Z))

    def residuals(self, Z: np.ndarray) -> np.ndarray:
        """The weighted residuals of each search point (rows; inf where it diverged)."""
        K = self.candidates(Z)
        t0 = time.perf_counter()
        R = self.problem.objective.residuals(K)
        self._count(t0, R.shape[0], int(np.count_nonzero(~np.all(np.isfinite(R), axis=1))))
        return R

    def point(self, k: np.ndarray, nu_box: np.ndarray) -> np.ndarray:
        """The search point of a fault vector ``k`` and nuisance box coordinates."""
        return np.clip(np.hstack([from_k(k[None, :], self.search),
                                  np.reshape(nu_box, (1, -1))])[0], 0.0, 1.0)

    def _nu0(self) -> np.ndarray:
        names = self.problem.nuisance
        return nuisance_to_box(nuisance_start(names)[None, :], names) if names else np.zeros((1, 0))

    def starts(self) -> list[np.ndarray]:
        """The problem's warm start (if any), then the healthy actuator, nuisance at zero."""
        nu0 = self._nu0()
        first = [] if self.problem.start is None else [self.point(self.problem.start, nu0)]
        return first + [self.point(K_NOMINAL, nu0)]

    def sample(self, seed: int) -> tuple[_Points, np.ndarray]:
        """``(points, fitness)`` of :data:`LSQ_SAMPLE` scrambled Sobol points drawn with
        ``seed`` in the metaheuristics' space (:func:`emaphm.search.default_search`: short
        circuits sparse) and of the :func:`single_fault_points` (nuisance at zero)."""
        names = self.problem.nuisance
        n_var = self.problem.n_var
        axes = single_fault_points()
        Z = sobol_sample(n_var, seed)
        K = np.vstack([to_k(Z[:, :N_K], default_search(self.problem.fault_model)), axes])
        Z = np.vstack([Z, np.tile(np.concatenate([np.zeros(N_K), self._nu0()[0]]),
                                  (len(axes), 1))])
        nu = nuisance_from_box(Z[:, N_K:], names) if names else np.zeros((K.shape[0], 0))
        f = self._fitness(np.hstack([K, nu]))
        return _Points(self, K, Z[:, N_K:]), f

