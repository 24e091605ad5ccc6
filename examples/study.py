"""A study from a researcher's script, each step checked against the long way round.

1. Simulate dry friction x2 on a second actuator (``examples/actuators/ema-270v-750w.toml``)
   and identify it without ``params=``: the trace's own actuator is used, as if given.
2. Register an optimizer of one's own by name and run a 6-run campaign with it on two
   worker processes: each stored run is the run executed alone, here.
3. Identify a batch of 8 traces on 2 workers: the 8 calls in a row, in order.
4. Every kind of result through JSON and back (``emaphm.results``): the same.
5. A frame with two currents and no speed (pandas): the trace emaphm derives from it is
   the one built by hand, and it identifies alike.

Run: ``python examples/study.py [--quick]`` (the tests run it with ``--quick``). It prints
one line per step and fails (an AssertionError) where a step differs from its long way.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from emaphm import results
from emaphm.campaign import CampaignSpec, CampaignStore, LocalExecutor, execute_run, run_campaign
from emaphm.identify import IdentificationConfig, identify
from emaphm.optim import register
from emaphm.params import load_params
from emaphm.prognosis import identify_with_spread, next_inspection
from emaphm.simulate import DEFAULT_SENSORS, simulate
from emaphm.traces import Trace
from emaphm.verdict import examine

ACTUATOR = Path(__file__).resolve().parent / "actuators" / "ema-270v-750w.toml"


def coordinate_search(objective, bounds, rng):
    """An optimizer of one's own: polls +-step along every axis from a random start."""
    lo, hi = bounds
    x = lo + (hi - lo) * rng.random(lo.size)
    fx = objective(x[None])[0]
    step = 0.25 * (hi - lo)
    while np.max(step / (hi - lo)) > 1e-3:
        X = np.clip(np.vstack([x + np.diag(step), x - np.diag(step)]), lo, hi)
        f = objective(X)
        if f.min() < fx:
            x, fx = X[np.argmin(f)], f.min()
        else:
            step = step / 2
    return x


def same(a, b) -> bool:
    return bool(np.array_equal(a.k, b.k) and a.fitness == b.fitness
                and a.evaluations == b.evaluations)


def own_actuator(budget: int) -> object:
    ema = load_params(ACTUATOR)
    trace = simulate(scenario="friction-high", params=ema, sensors=DEFAULT_SENSORS, seed=1)
    config = IdentificationConfig("pso", budget=budget)
    mine = identify(trace, config, seed=0)                       # no params=
    assert mine.params_source == "trace" and same(mine, identify(trace, config, seed=0,
                                                                 params=ema))
    print(f"1. own actuator: {mine.params.name}, k1 = {mine.k[0]:.3f}, the same as given")
    return trace


def campaign(folder: Path, budget: int) -> None:
    register("coord", coordinate_search)
    spec = CampaignSpec(scenarios=["friction-high", "backlash-high"], algorithms=["coord"],
                        runs=3, budget=budget, master_seed=11, name="study")
    summary = run_campaign(spec, folder / "study.sqlite", LocalExecutor(2))
    assert summary.completed == 6 and summary.failed == 0
    with CampaignStore.open(folder / "study.sqlite", readonly=True) as st:
        stored = {r.key: r for r in st.results()}
    for run in spec.runs_list():                                 # the long way: one by one
        alone = execute_run(run)
        assert stored[run.key].k == alone.k and stored[run.key].fitness == alone.fitness
    print(f"2. campaign: {len(stored)} runs of 'coord' on 2 workers, each as run alone")


def batch(budget: int) -> list:
    traces = [simulate(scenario=s, sensors=DEFAULT_SENSORS, seed=i)
              for i, s in enumerate(["friction-high", "backlash-high", "nominal", "gain-low"] * 2)]
    config = IdentificationConfig("pso", budget=budget)
    many = identify(traces, config, seed=3, workers=2)
    assert all(same(a, identify(t, config, seed=3)) for a, t in zip(many, traces))
    print(f"3. batch: {len(many)} traces on 2 workers, the calls in a row, in order")
    return traces


def round_trips(trace, budget: int) -> None:
    config = IdentificationConfig("pso", budget=budget)
    exam = examine(trace, config=config, seed=0, loops=False)
    spread = identify_with_spread(trace, config, seed=0)
    history = np.tile(exam.identification.k, (4, 1)) + np.linspace(0, 0.1, 4)[:, None] * [1, 0, 0, 0, 0, 0, 0, 0]
    prog, plan = next_inspection([0.0, 100.0, 200.0, 300.0], history, seed=0, n_samples=4000)
    kinds = [exam.identification, config, exam.diagnosis, spread, spread.interval, prog,
             prog.predictions["friction"], plan, load_params(ACTUATOR)]
    for r in kinds:
        back = results.loads(results.dumps(r))
        assert type(back) is type(r) and back.to_dict() == r.to_dict(), type(r).__name__
    print(f"4. round trips: {len(kinds)} kinds through JSON, each the same")


def frame(trace, budget: int) -> None:
    import pandas as pd

    cols = trace.columns()
    df = pd.DataFrame({c: cols[c] for c in ("t", "theta_ref", "theta_m", "i_a", "i_b")})
    derived = Trace.from_pandas(df, meta=trace.meta)
    by_hand = Trace(t=trace.t, theta_ref=trace.theta_ref, theta_m=trace.theta_m,
                    omega_m=np.gradient(trace.theta_m, trace.t),
                    i_abc=np.column_stack([trace.i_a, trace.i_b, -(trace.i_a + trace.i_b)]),
                    meta={**trace.meta, "currents_measured": 2})
    assert np.array_equal(derived.omega_m, by_hand.omega_m)
    assert np.array_equal(derived.i_abc, by_hand.i_abc)
    config = IdentificationConfig("pso", budget=budget)
    assert same(identify(derived, config, seed=0), identify(by_hand, config, seed=0))
    print("5. frame: two currents and no speed, derived as by hand, identified alike")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small budgets (the tests')")
    args = ap.parse_args()
    budget = 400 if args.quick else 3000
    trace = own_actuator(budget)
    with tempfile.TemporaryDirectory() as folder:
        campaign(Path(folder), budget)
    batch(budget)
    round_trips(trace, budget)
    frame(trace, budget)


if __name__ == "__main__":
    main()
