"""Benchmark of emaphm.optim against reference implementations at equal budgets.

Run from the repository root::

    python benchmarks/bench_optim.py            # writes benchmarks/results/optim.md
    python benchmarks/bench_optim.py --seeds 3 --out /tmp/optim.md
    python benchmarks/bench_optim.py --overheads  # writes benchmarks/results/overheads.md

What it measures, on the 8-D sphere, Rastrigin and Rosenbrock functions (f* = 0):

* quality: median over seeds of the best f after 10,000 evaluations (50 members x 200
  iterations, initial population included) for our DE, PSO and GWO, scipy's
  differential_evolution (rand/1/bin with our F and CR, and scipy's own defaults:
  best/1/bin, dithered F in [0.5, 1), CR 0.7; both with 50 members, vectorised,
  deferred updating, no polishing, no early stop) and, when niapy is installed, niapy's
  PSO and GWO run on the unit-box form of the problem;
* wall time: median seconds per run;
* overhead: microseconds per iteration of the optimizer's own work, i.e. the run's wall
  time minus the time spent inside the objective, divided by the iterations (median
  over all runs), for a population of 50 and 8 variables. The fault-identification
  objective evaluates 50 simulations in ~10 ms per iteration, the yardstick for "tiny".
"""

from __future__ import annotations

import argparse
import datetime as _dt
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import scipy
from scipy.optimize import differential_evolution

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

from emaphm.optim import DE, GWO, PSO, MaxIterations, minimize  # noqa: E402
from emaphm.optim.problems import rastrigin, rosenbrock, sphere  # noqa: E402

try:  # optional reference (test-only dependency)
    import niapy
    from niapy.algorithms.basic import GreyWolfOptimizer, ParticleSwarmAlgorithm
    from niapy.problems import Problem
    from niapy.task import Task
    from niapy.util.repair import limit
except ImportError:  # pragma: no cover
    niapy = None

N_VAR, N_POP, N_ITER = 8, 50, 200
BUDGET = N_POP * N_ITER


PROBLEMS = {
    "sphere": (sphere, ([-5.12] * N_VAR, [5.12] * N_VAR)),
    "rastrigin": (rastrigin, ([-5.12] * N_VAR, [5.12] * N_VAR)),
    "rosenbrock": (rosenbrock, ([-5.0] * N_VAR, [10.0] * N_VAR)),
}


# ----------------------------------------------------------------------------- runners
# Each runner: (f, bounds, seed, n_iter) -> best f. n_iter counts the initial population.


def ours(opt_factory):
    def run(f, bounds, seed, n_iter):
        res = minimize(f, bounds, opt_factory(n_iter), seed=seed, termination=MaxIterations(n_iter))
        return res.fun

    return run


def scipy_de(**options):
    def run(f, bounds, seed, n_iter):
        lo, hi = np.asarray(bounds[0], float), np.asarray(bounds[1], float)
        rng = np.random.default_rng(seed)
        res = differential_evolution(
            lambda x: f(x.T),
            list(zip(lo, hi, strict=True)),
            maxiter=n_iter - 1,
            init=lo + rng.random((N_POP, N_VAR)) * (hi - lo),
            polish=False,
            tol=0.0,
            atol=0.0,
            vectorized=True,
            updating="deferred",
            rng=rng,
            **options,
        )
        return res.fun

    return run


def niapy_run(make_algo):
    def run(f, bounds, seed, n_iter):
        lo = np.asarray(bounds[0], float)
        width = np.asarray(bounds[1], float) - lo

        class UnitBox(Problem):
            def __init__(self):
                super().__init__(dimension=N_VAR, lower=0.0, upper=1.0)

            def _evaluate(self, u):
                return float(f((lo + u * width)[None, :])[0])

        task = Task(problem=UnitBox(), max_evals=N_POP * n_iter)
        return make_algo(seed).run(task)[1]

    return run


def contenders():
    c = {
        "emaphm DE (rand/1/bin, F 0.5, CR 0.9)": ours(lambda n: DE(pop_size=N_POP, max_iter=n)),
        "emaphm PSO (w 0.7298, c 1.49618, v_max 0.2)": ours(lambda n: PSO(pop_size=N_POP, max_iter=n)),
        "emaphm GWO (a: 2 -> 0 over the budget)": ours(lambda n: GWO(pop_size=N_POP, max_iter=n)),
        "scipy DE, same settings (rand1bin, 0.5, 0.9)": scipy_de(
            strategy="rand1bin", mutation=0.5, recombination=0.9
        ),
        "scipy DE, its defaults (best1bin, F~U(0.5,1), CR 0.7)": scipy_de(),
    }
    if niapy is not None:
        c["niapy PSO (same w, c1, c2, clamp; unit box)"] = niapy_run(
            lambda s: ParticleSwarmAlgorithm(
                population_size=N_POP, w=0.7298, c1=1.49618, c2=1.49618,
                min_velocity=-0.2, max_velocity=0.2, repair=limit, seed=s,
            )
        )
        c["niapy GWO (unit box)"] = niapy_run(lambda s: GreyWolfOptimizer(population_size=N_POP, seed=s))
    return c


# ----------------------------------------------------------------------------- overhead


class Timed:
    """Wraps an objective and accumulates the wall time spent inside it."""

    def __init__(self, f):
        self.f, self.inside = f, 0.0

    def __call__(self, X):
        t0 = time.perf_counter()
        y = self.f(X)
        self.inside += time.perf_counter() - t0
        return y


# ----------------------------------------------------------------------------- report


def machine() -> dict[str, str]:
    cpu = platform.processor()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = f"{cpu} / {line.split(':', 1)[1].strip()}" if cpu else line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    try:
        nproc = subprocess.run(["nproc"], capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        nproc = str(os.cpu_count())
    load = os.getloadavg() if hasattr(os, "getloadavg") else ("?",)
    return {
        "date": _dt.datetime.now().astimezone().strftime("%Y-%m-%d %H:%M %Z"),
        "processor": cpu or "unknown",
        "nproc": nproc,
        "load average at start (1 min)": f"{load[0]:.2f}" if load[0] != "?" else "?",
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "niapy": getattr(niapy, "__version__", "not installed") if niapy else "not installed",
        "platform": platform.platform(),
    }


# ----------------------------------------------------------------------------- overheads


def _cpu(fn):
    """CPU seconds (time.process_time) of one call ``fn()``."""
    t0 = time.process_time()
    fn()
    return time.process_time() - t0


def overheads(reps: int) -> list[tuple[str, str, float, str, float]]:
    """The adapters and identify's fixed cost, each beside its reference, side by side.

    Rows: (what, reference name, reference s, ours name, ours s), CPU medians.
    """
    import copy
    import dataclasses

    import cma

    from emaphm.identify import IdentificationConfig, identify
    from emaphm.problem import IdentificationProblem
    from emaphm.optim.base import advance, as_bounds, child_rng
    from emaphm.optim.baselines import CMAES, ScipyDE, _cma_step, _Owned
    from emaphm.simulate import DEFAULT_SENSORS, simulate

    box, n_iter = ([-5.12] * N_VAR, [5.12] * N_VAR), N_ITER
    term = MaxIterations(n_iter)

    def scipy_own():
        opt = ScipyDE()
        rng = child_rng(np.random.default_rng(1))
        init = opt.initial_population(as_bounds(box), rng)
        differential_evolution(lambda x: sphere(x.T), list(zip(*box)), init=init, rng=rng,
                               maxiter=n_iter - 1, tol=0, atol=0, polish=False, vectorized=True,
                               updating="deferred")

    class CopyEveryTell:
        """The value semantics of before: every tell on a deep copy of its state (for
        scipy-de the two deep copies per generation it made; for cmaes one more than its one)."""

        def __init__(self, opt):
            self.opt, self.name = opt, opt.name

        def __getattr__(self, name):
            return getattr(self.opt, name)

        def tell(self, state, X, y):
            return self.opt.tell(copy.deepcopy(state), X, y)

    class CopyingCMAES(CMAES):
        """cmaes as before: a deep copy of cma's strategy on every tell."""

        def tell(self, state, X, y):
            es = copy.deepcopy(state.es)
            big = np.finfo(np.float64).max / 1e3
            fit = np.where(np.isfinite(y), y, big).tolist()
            es.tell([s.copy() for s in state.pending], fit)
            pending = tuple(np.array(s, dtype=np.float64) for s in es.ask())
            return dataclasses.replace(state, engine=_Owned(es, _cma_step), pending=pending,
                                       **advance(state, X, y))

    def cma_own():
        rng = child_rng(np.random.default_rng(1))
        es = cma.CMAEvolutionStrategy(np.full(N_VAR, 0.5), 0.3, {
            "bounds": [0.0, 1.0], "randn": lambda *s: rng.standard_normal(s), "verbose": -9,
            "verb_log": 0, "verb_disp": 0, "popsize": 10})
        lo, w = -5.12, 10.24
        for _ in range(n_iter):
            U = es.ask()
            es.tell(U, sphere(lo + np.clip(np.array(U), 0, 1) * w).tolist())

    def ours(opt):
        return lambda: minimize(sphere, box, opt, seed=1, termination=term)

    trace = simulate(scenario="gain-high", sensors=DEFAULT_SENSORS, seed=1)
    problem = IdentificationProblem(trace)
    config = IdentificationConfig("pso", options={"pop_size": 4}, budget=1, polish=False)

    def ident(cold):
        def run():
            t0 = time.process_time()
            r = identify(trace if cold else problem, config, seed=0)
            run.fixed = time.process_time() - t0 - r.kernel_s
        return run

    pairs = [
        ("scipy-de, 48 x 200 on sphere: SciPy's own call vs the adapter",
         "differential_evolution", scipy_own, "ScipyDE", ours(ScipyDE())),
        ("scipy-de: before (two deep copies per generation) vs now", "before",
         ours(CopyEveryTell(ScipyDE())), "now", ours(ScipyDE())),
        ("cmaes, 10 x 200 on sphere: cma's own loop vs the adapter", "cma ask/tell",
         cma_own, "CMAES", ours(CMAES())),
        ("cmaes: before (a deep copy per tell) vs now", "before", ours(CopyingCMAES()),
         "now", ours(CMAES())),
    ]
    rows = []
    for what, ref_name, ref, our_name, our in pairs:
        ref(), our()                                   # warm up
        a, b = [], []
        for _ in range(reps):
            a.append(_cpu(ref))
            b.append(_cpu(our))
        rows.append((what, ref_name, float(np.median(a)), our_name, float(np.median(b))))
        print(f"{what}: {rows[-1][2] * 1e3:.1f} vs {rows[-1][4] * 1e3:.1f} ms", flush=True)
    cold, warm = ident(True), ident(False)
    cold(), warm()
    a, b = [], []
    for _ in range(reps * 3):
        cold()
        a.append(cold.fixed)
        warm()
        b.append(warm.fixed)
    rows.append(("identify's fixed cost per call (CPU minus kernel; pso, 4 evaluations, no polish)",
                 "from the trace (a new problem)", float(np.median(a)),
                 "from a problem the caller keeps",
                 float(np.median(b))))
    print(f"identify fixed: {rows[-1][2] * 1e3:.1f} vs {rows[-1][4] * 1e3:.1f} ms", flush=True)
    return rows


def overheads_report(args) -> int:
    info = machine()
    rows = overheads(args.reps)
    info["load average at end (1 min)"] = f"{os.getloadavg()[0]:.2f}"
    lines = [
        ("## Overheads: the baselines' adapters and identify's fixed cost "
         "(`benchmarks/bench_optim.py --overheads`)"),
        "",
        "Generated by `python benchmarks/bench_optim.py --overheads` (do not edit by hand).",
        "",
        "| machine | |",
        "| --- | --- |",
        *[f"| {k} | {v} |" for k, v in info.items()],
        "",
        (f"CPU time (`time.process_time`), median of {args.reps} interleaved repetitions "
         f"({3 * args.reps} for identify), each pair measured side by side in one process. "
         "Objective: the 8-D sphere (negligible), so the times are the optimizers' own."),
        "",
        "| measurement | reference | ms | ours | ms | ours / reference |",
        "| --- | --- | ---: | --- | ---: | ---: |",
    ]
    for what, rn, rt, on, ot in rows:
        lines.append(f"| {what} | {rn} | {rt * 1e3:.1f} | {on} | {ot * 1e3:.1f} | {ot / rt:.2f} |")
    lines += [
        "",
        "Notes:",
        "",
        ("- cmaes and scipy-de hand their engine (cma's strategy, scipy's solver) from the "
         "newest state to the next `tell`, which advances it in place; an old state told again "
         "is rebuilt by replaying from a snapshot kept every 32 tells (the results are the ones "
         "a copy per tell gave, tested)."),
        ("- scipy-de still runs the mutation of each generation twice (once to ask for the trial "
         "points, once to take their fitness), the rest of its gap to SciPy's own call."),
        ("- identify keeps the objectives it built (per thread, 8, by the trace's value and the "
         "settings), so a second identification of a trace skips the model's set-up, the trace's "
         "validation and the kernels' warm-up."),
        "",
    ]
    out = args.out or Path(__file__).resolve().parent / "results" / "overheads.md"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("\n".join(lines))
    print(f"wrote {out}")
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=20, help="runs per cell (default 20)")
    ap.add_argument("--out", type=Path, default=None,
                    help="default benchmarks/results/optim.md (overheads.md with --overheads)")
    ap.add_argument("--overheads", action="store_true",
                    help="measure the adapters' and identify's overheads instead")
    ap.add_argument("--reps", type=int, default=7, help="repetitions with --overheads (default 7)")
    args = ap.parse_args(argv)
    if args.overheads:
        return overheads_report(args)
    args.out = args.out or Path(__file__).resolve().parent / "results" / "optim.md"

    info = machine()
    rows = []
    for name, run in contenders().items():
        cells, overheads = [], []
        for prob, (f, bounds) in PROBLEMS.items():
            funs, walls = [], []
            for s in range(args.seeds):
                timed = Timed(f)
                t0 = time.perf_counter()
                funs.append(run(timed, bounds, s, N_ITER))
                walls.append(time.perf_counter() - t0)
                overheads.append((walls[-1] - timed.inside) / N_ITER * 1e6)
            cells.append((float(np.median(funs)), float(np.median(walls)), float(np.mean(funs))))
            med_f, med_t, _ = cells[-1]
            print(f"{name:55s} {prob:10s} median f {med_f:.3g}  {med_t * 1e3:.1f} ms/run", flush=True)
        rows.append((name, cells, float(np.median(overheads))))

    lines = [
        "## Optimizers: quality and overhead against scipy and niapy (`benchmarks/bench_optim.py`)",
        "",
        "Generated by `python benchmarks/bench_optim.py` (do not edit by hand).",
        "",
        "| machine | |",
        "| --- | --- |",
        *[f"| {k} | {v} |" for k, v in info.items()],
        "",
        f"Budget: {BUDGET:,} evaluations per run ({N_POP} members x {N_ITER} iterations, the "
        f"initial population included), 8 variables, {args.seeds} seeds per cell. "
        "Quality is the median best f (f* = 0; for Rastrigin also the mean); time is the "
        "median wall time per run; "
        "overhead is the optimizer's own time per iteration (run time minus time inside the "
        "objective, population of 50), to compare with ~10 ms per iteration for the EMA "
        "fitness (50 simulations).",
        "",
        "| optimizer | sphere f | Rastrigin f | Rastrigin mean f | Rosenbrock f | sphere ms/run "
        "| Rastrigin ms/run | Rosenbrock ms/run | overhead us/iter |",
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for name, cells, ovh in rows:
        q = f"{cells[0][0]:.3g} | {cells[1][0]:.3g} | {cells[1][2]:.3g} | {cells[2][0]:.3g}"
        t = " | ".join(f"{c[1] * 1e3:.1f}" for c in cells)
        lines.append(f"| {name} | {q} | {t} | {ovh:.0f} |")
    lines += [
        "",
        "Notes:",
        "",
        "- GWO here runs with `max_iter=200` so that `a` reaches 0 at this budget (its paper "
        "budget is 150 iterations). Its update is not translation invariant: it is precise near "
        "the lower corner of the box and much less so at mid-box, where these optima lie "
        "(see `tests/test_optim_conformance.py::test_gwo_is_biased_towards_lower_corner`).",
        "- scipy's own defaults (best/1/bin with dither) converge faster than rand/1/bin on these "
        "functions; rand/1/bin is used because it is the paper's algorithm (Fig. 3). `DE(F=(0.5, 1.0))` "
        "gives dithering with our DE.",
        "- Rastrigin runs end in one of two groups (a good basin, f ~ 3-8, or a poor one, "
        "f ~ 20-30), so its median over a few seeds jumps between them; the mean is the steadier "
        "figure. Over 100 seeds at 7,500 evaluations our GWO and niapy's are indistinguishable "
        "there (medians 20.1 and 17.8, quartiles 8-25 for both, Mann-Whitney p = 0.31; "
        "tests/test_optim_crosscheck.py).",
        "- niapy calls the objective once per point in Python, so its times and overhead include "
        "per-point call costs our batch interface avoids.",
        "- The machine may be shared: timings are indicative, qualities are exact for these seeds.",
        "",
    ]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text("\n".join(lines))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
