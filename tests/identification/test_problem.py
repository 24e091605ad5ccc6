"""The identification problem, the typed settings, and a user's own optimizer plugged in.

:class:`emaphm.problem.IdentificationProblem` resolves its settings and reads a k with
its own fault model; :class:`emaphm.identify.IdentificationConfig` round-trips to JSON and
builds the solver it names; an optimizer written outside emaphm (a twenty-line random
search, as an ask/tell object and as a plain function) plugs into ``identify`` through
the public protocol and gives a valid identification and diagnosis.
"""

from __future__ import annotations

import dataclasses
import inspect
import json
from dataclasses import dataclass

import numpy as np
import pytest

from emaphm.faults import K_NOMINAL, SCENARIOS
from emaphm.identify import Identification, IdentificationConfig, identify, make_solver, minimize
from emaphm.optim import MaxEvaluations
from emaphm.optim.lsq import MultistartLeastSquares
from emaphm.optim.solvers import Metaheuristic
from emaphm.params import siemens_1fk7060
from emaphm.problem import IdentificationProblem
from emaphm.simulate import DEFAULT_SENSORS, simulate
from emaphm.diagnosis import diagnose
from emaphm.verdict import diagnose_identification


@pytest.fixture(scope="module")
def short_trace():
    """A 15 % inter-turn short on phase A of the monitoring model, with sensor noise."""
    return simulate(scenario="turn-short-15pct", model="monitoring", sensors=DEFAULT_SENSORS,
                    seed=1, fault_model="physical")


@pytest.fixture(scope="module")
def problem(short_trace):
    return IdentificationProblem(short_trace)


# ----------------------------------------------------------------------------- the problem
def test_the_problem_resolves_its_settings(short_trace, problem):
    assert problem.fault_model == "physical"          # the trace's own
    assert problem.nuisance == () and problem.n_var == 8
    assert problem.params == siemens_1fk7060()
    assert problem.noise_floor > 0
    np.testing.assert_array_equal(problem.healthy, K_NOMINAL)
    np.testing.assert_array_equal(problem.k_true, SCENARIOS["turn-short-15pct"])
    calibrated = dataclasses.replace(siemens_1fk7060(), calibration=dataclasses.replace(
        siemens_1fk7060().calibration, date="2026-01-01T00:00:00+00:00"))
    assert IdentificationProblem(short_trace, params=calibrated).nuisance == ("R", "flux")
    with pytest.raises(ValueError, match="unknown search space"):
        IdentificationProblem(short_trace, search="spiral")


def test_the_problem_reads_a_k_with_its_own_fault_model(short_trace, problem):
    """The same k reads the same way wherever it comes from: under the problem's fault
    model (a trace's own: physical for a bench trace or a physical simulation)."""
    k = SCENARIOS["turn-short-15pct"]
    mine = problem.diagnose(k)
    assert mine.fault_model == "physical" and mine.verdict == "faulty"
    assert [(f.mode, f.phase) for f in mine.faults] == [("short_circuit", "A")]
    assert diagnose(k, fault_model="physical").to_dict() == mine.to_dict()
    with pytest.warns(DeprecationWarning, match="without fault_model"):
        assert diagnose(k).fault_model == "paper"          # the 0.3 default, one more release
    paper = IdentificationProblem(simulate(scenario="short-circuit-low", model="monitoring"))
    assert paper.fault_model == "paper" and paper.diagnose(k).fault_model == "paper"


def test_a_view_maps_the_box_and_counts_one_search(problem):
    view = problem.view("ecc-xy-sq")
    lo, hi = view.bounds
    assert lo.shape == (8,) and np.all(lo == 0) and np.all(hi == 1)
    starts = view.starts()
    assert len(starts) == 1                              # no warm start: the healthy k only
    np.testing.assert_allclose(problem.decode(starts[0], "ecc-xy-sq")[0], K_NOMINAL, atol=1e-12)
    X, f = view.sample(seed=3)
    assert len(X) == view.sample_size == f.size and view.evaluations == f.size
    X2, f2 = problem.view("ecc-xy-sq").sample(seed=3)
    np.testing.assert_array_equal(f, f2)                 # seeded
    warm = dataclasses.replace(problem, start=SCENARIOS["turn-short-5pct"]).view("ecc-xy-sq")
    assert len(warm.starts()) == 2
    np.testing.assert_allclose(problem.decode(warm.starts()[0], "ecc-xy-sq")[0],
                               SCENARIOS["turn-short-5pct"], atol=1e-12)


def test_the_sobol_sample_seeds_scipy_with_rng_where_it_has_it(problem, monkeypatch, tmp_path):
    """SciPy 1.15 moved its engines' ``seed=`` to ``rng=`` (SPEC 7; ``seed=`` is to be
    deprecated): the sample passes ``rng=`` where SciPy takes it, and warns of nothing
    (drawn afresh: an empty cache folder, where a kept sample is read without SciPy)."""
    import warnings

    from scipy.stats import qmc
    from support import scipy_rng_keyword, spy_on_init

    from emaphm.models import warm

    monkeypatch.setattr(warm, "cache_folder", lambda: tmp_path)
    calls = spy_on_init(monkeypatch, qmc.Sobol)
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)
        problem.view("ecc-xy-sq").sample(seed=3)
    assert calls == [{"scramble": True, scipy_rng_keyword(qmc.Sobol): 3}]


# ----------------------------------------------------------------------------- the settings
def test_the_config_round_trips_to_json_and_builds_its_solver():
    cfg = IdentificationConfig("pso", options={"pop_size": np.int64(30)}, budget="20s",
                               polish=False, restarts=1, suspect_ratio=3.0, search="ecc-xy",
                               n_sub=2, mode="equivalent", fault_model="paper",
                               nuisance=("R", "load"))
    text = json.dumps(cfg.to_dict())
    back = IdentificationConfig.from_dict(json.loads(text))
    assert back == cfg and back.options == {"pop_size": 30}
    solver = back.solver()
    assert isinstance(solver, Metaheuristic) and solver.optimizer.pop_size == 30
    assert (solver.polish, solver.restarts, solver.restart_ratio) == (False, 1, 3.0)
    assert isinstance(IdentificationConfig().solver(), MultistartLeastSquares)
    assert back.termination() is not None
    with pytest.raises(ValueError, match="unknown key"):
        IdentificationConfig.from_dict({"algo": "pso"})
    with pytest.raises(ValueError, match="unknown algorithm"):
        IdentificationConfig("nelder-mead")
    with pytest.raises(ValueError, match="nuisance"):
        IdentificationConfig(nuisance=("J",))


@pytest.fixture(scope="module")
def half_turn_trace():
    """A friction fault on a ramp of half a revolution (less than the default
    min_rotation), monitoring model with sensor noise."""
    from emaphm.profiles import ramp

    return simulate(scenario="friction-high", model="monitoring", sensors=DEFAULT_SENSORS,
                    seed=2, profile=ramp(height=np.pi))


def test_min_rotation_is_a_problem_setting_of_the_config(half_turn_trace):
    """A trace of less than a revolution is refused by default, and identified where the
    config lowers min_rotation; the setting reaches the problem, the result's config and
    the verdict's rebuilt problem, and round-trips to JSON."""
    from emaphm.traces import TraceError

    with pytest.raises(TraceError, match=r"below min_rotation = 6\.283 rad"):
        identify(half_turn_trace, seed=0)
    with pytest.raises(TraceError, match=r"below min_rotation = 6\.283 rad"):
        identify(half_turn_trace, IdentificationConfig(), seed=0)
    cfg = IdentificationConfig(budget=300, min_rotation=3.0)
    assert cfg.problem(half_turn_trace).min_rotation == 3.0
    ident = identify(half_turn_trace, cfg, seed=0)
    assert ident.config.min_rotation == 3.0
    assert ident.k[0] > 0.5                      # the friction (k1 0.75) found
    diag = diagnose_identification(half_turn_trace, ident)    # rebuilds the problem
    assert [f.mode for f in diag.faults] == ["friction"]
    back = IdentificationConfig.from_dict(json.loads(json.dumps(cfg.to_dict())))
    assert back == cfg and back.min_rotation == 3.0
    assert IdentificationConfig.from_dict({"algorithm": "lsq"}).min_rotation == 2 * np.pi
    for bad in (-1.0, float("nan"), float("inf"), "1", True):
        with pytest.raises(ValueError, match=r"min_rotation \[rad\] must be a finite number >= 0"):
            IdentificationConfig(min_rotation=bad)


def test_diagnose_min_rotation_on_the_command_line(half_turn_trace, tmp_path, capsys):
    from emaphm.cli import main
    from emaphm.traces import write_trace

    path = write_trace(half_turn_trace, tmp_path / "half-turn.csv")
    assert main(["diagnose", str(path), "--quiet", "--budget", "300"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "below min_rotation = 6.283 rad" in err
    assert main(["diagnose", str(path), "--quiet", "--budget", "300", "--min-rotation", "3",
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["verdict"] == "faulty" and [f["mode"] for f in out["faults"]] == ["friction"]
    with pytest.raises(SystemExit) as exit_:
        main(["diagnose", str(path), "--min-rotation", "-1"])
    assert exit_.value.code == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "expected a rotation in rad >= 0" in err


def test_an_identification_carries_the_settings_that_replay_it(problem):
    first = identify(problem, IdentificationConfig("de", options={"pop_size": 20}, budget=300),
                     seed=5)
    cfg = IdentificationConfig.from_dict(json.loads(json.dumps(first.config.to_dict())))
    again = identify(problem.trace, cfg, seed=5)
    np.testing.assert_array_equal(first.k, again.k)
    assert first.fitness == again.fitness and first.evaluations == again.evaluations


def test_identify_is_a_thin_front():
    src = inspect.getsource(identify)
    assert len(src.splitlines()) <= 80
    # 9 since issue 34: workers=, for a list of traces (a batch)
    assert len(inspect.signature(identify).parameters) <= 9
    assert len(inspect.signature(minimize).parameters) <= 8


# ----------------------------------------------------------------------------- plugged in
@dataclass(frozen=True)
class RandomSearchState:
    bounds: object
    rng: object
    best_x: np.ndarray
    best_f: float
    nfev: int
    nit: int
    history: np.ndarray


@dataclass(frozen=True)
class RandomSearch:
    """Twenty lines of random search with the ask/tell protocol of emaphm.optim.Optimizer."""

    n: int = 40
    name: str = "random-search"

    def init(self, bounds, rng):
        return RandomSearchState(bounds, rng, np.zeros(bounds.n_var), np.inf, 0, 0, np.empty(0))

    def ask(self, state):
        rng = np.random.Generator(type(state.rng.bit_generator)())
        rng.bit_generator.state = state.rng.bit_generator.state
        return state.bounds.from_normalized(rng.random((self.n, state.bounds.n_var)))

    def tell(self, state, X, y):
        rng = np.random.Generator(type(state.rng.bit_generator)())
        rng.bit_generator.state = state.rng.bit_generator.state
        rng.random((self.n, state.bounds.n_var))                      # what ask drew
        i = int(np.argmin(y))
        better = y[i] < state.best_f
        return dataclasses.replace(
            state, rng=rng, best_x=X[i] if better else state.best_x,
            best_f=float(y[i]) if better else state.best_f, nfev=state.nfev + len(y),
            nit=state.nit + 1, history=np.append(state.history, min(y[i], state.best_f)))

    def default_termination(self):
        return MaxEvaluations(800)


def random_search(objective, bounds, rng):
    """The same as a plain function ``f(objective, bounds, rng) -> x``."""
    lo, hi = bounds
    best, f_best = None, np.inf
    for _ in range(20):
        X = lo + (hi - lo) * rng.random((40, lo.size))
        f = objective(X)
        if f.min() < f_best:
            best, f_best = X[int(np.argmin(f))], float(f.min())
    return best


@pytest.mark.parametrize("solver", [RandomSearch(), random_search], ids=["ask-tell", "function"])
def test_a_users_own_optimizer_plugs_into_identify(short_trace, problem, solver):
    ident = identify(short_trace, solver, seed=11)
    assert isinstance(ident, Identification) and ident.config is None
    assert ident.algorithm in ("random-search", "random_search")
    assert ident.evaluations >= 800 and np.all((ident.k >= 0) & (ident.k <= 1))
    assert ident.fitness == pytest.approx(problem.objective(ident.k)[0], rel=1e-9)
    assert ident.fitness < problem.objective(K_NOMINAL)[0]       # it found something
    again = identify(short_trace, solver, seed=11)
    np.testing.assert_array_equal(ident.k, again.k)
    diag = diagnose_identification(short_trace, ident)
    assert diag.verdict in ("healthy", "faulty", "unexplained")
    json.dumps({**ident.to_dict(), **diag.to_dict()})


def test_make_solver_has_the_identification_defaults():
    lsq = make_solver("lsq")
    assert lsq.restarts == 3 and 1.9 < lsq.accept_ratio < 2.1 and lsq.polish_evaluations == 200
    pso = make_solver("pso")
    assert pso.restarts == 2 and pso.polish and pso.polish_evaluations == 2000
    assert make_solver("pso", budget=True).restarts == 0
    assert make_solver("pso", polish=False).restarts == 0


def test_the_sobol_sample_is_kept_and_read_back_bit_for_bit(tmp_path, monkeypatch):
    """A later process reads the search's sample instead of importing scipy.stats to draw
    it: the same numbers; a damaged file is drawn again; a seed spawned for one run (64
    bits) is not kept."""
    import numpy as np

    from emaphm import problem as P
    from emaphm.models import warm

    monkeypatch.setattr(warm, "cache_folder", lambda: tmp_path)
    drawn = P._sobol(10, 3).random(P.LSQ_SAMPLE)
    first = P.sobol_sample(10, 3)
    (kept,) = tmp_path.glob("sobol-10-3-64-scipy-*.npy")
    assert np.array_equal(first, drawn) and np.array_equal(np.load(kept), drawn)
    assert np.array_equal(P.sobol_sample(10, 3), drawn)
    kept.write_bytes(b"not an array")
    assert np.array_equal(P.sobol_sample(10, 3), drawn)
    assert np.array_equal(np.load(kept), drawn)                 # written again, whole
    P.sobol_sample(10, 2 ** 40)
    assert len(list(tmp_path.glob("sobol-*"))) == 1
