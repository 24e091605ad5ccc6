"""Batches (issue 34, item 6): ``identify`` and ``examine`` of a list of traces give, in
order, what the calls one after the other give, bit for bit, here or on worker processes
whose warm pool the next batch reuses. (Their speed is benchmarks/bench_batch.py's, not a
test's.)"""

from __future__ import annotations

import numpy as np
import pytest

from emaphm import batch
from emaphm.identify import IdentificationConfig, identify
from emaphm.simulate import DEFAULT_SENSORS, simulate
from emaphm.verdict import examine

CONFIG = IdentificationConfig("pso", options={"pop_size": 10}, budget=200)


@pytest.fixture(scope="module")
def traces():
    return [simulate(scenario=s, sensors=DEFAULT_SENSORS, seed=i)
            for i, s in enumerate(("friction-high", "nominal", "backlash-high"))]


def same(a, b):
    np.testing.assert_array_equal(a.k, b.k)
    np.testing.assert_array_equal(a.history, b.history)
    assert (a.fitness, a.evaluations, a.seed) == (b.fitness, b.evaluations, b.seed)


def test_a_batch_is_the_calls_in_a_row(traces):
    one_by_one = [identify(t, CONFIG, seed=5) for t in traces]
    for got, want in zip(identify(traces, CONFIG, seed=5), one_by_one):
        same(got, want)
    for got, want in zip(identify(tuple(traces), CONFIG, seed=5, workers=1), one_by_one):
        same(got, want)
    exams = examine(traces[:2], config=CONFIG, seed=1, loops=False)
    for got, t in zip(exams, traces[:2]):
        want = examine(t, config=CONFIG, seed=1, loops=False)
        same(got.identification, want.identification)
        assert got.diagnosis.to_dict() == want.diagnosis.to_dict()


def test_workers_give_the_same_results_in_order_and_stay_warm(traces):
    try:
        # two processes: this one and a worker of the kept pool, which takes the first
        # trace while this one takes the next
        got = identify(traces, CONFIG, seed=5, workers=2)
        pool = batch._POOLS[1]._pool
        again = identify(traces[::-1], CONFIG, seed=5, workers=2)
        assert batch._POOLS[1]._pool is pool            # the warm workers, reused
    finally:
        batch.close_pools()
    for a, t in zip(got, traces):
        same(a, identify(t, CONFIG, seed=5))
    for a, b in zip(again, got[::-1]):
        same(a, b)


def test_misuse_of_a_batch_says_what_to_give(traces):
    with pytest.raises(TypeError, match="item 1 is a int"):
        identify([traces[0], 3], seed=0)
    with pytest.raises(ValueError, match="workers must be a number of processes"):
        identify(traces, seed=0, workers=-1)
    with pytest.raises(ValueError, match="give a list of traces, or drop workers"):
        identify(traces[0], seed=0, workers=2)
    with pytest.raises(ValueError, match="takes none"):
        identify(traces, seed=0, workers=2, callback=lambda s: None)


def midpoint_here_only(objective, bounds, rng):
    """The middle of the box; a worker process that runs it dies at once (as one the
    kernel's OOM killer took would)."""
    import os

    if str(os.getpid()) != os.environ.get("EMAPHM_TEST_BATCH_PARENT"):
        os._exit(3)
    lo, hi = bounds
    return (lo + hi) / 2.0


def test_a_trace_a_dying_worker_took_is_identified_here(traces, monkeypatch):
    """The worker dies on the trace it took: this process identifies it instead, and the
    batch is still the calls in a row, in order; the next batch starts a new pool."""
    import os

    from emaphm.optim import register, unregister

    monkeypatch.setenv("EMAPHM_TEST_BATCH_PARENT", str(os.getpid()))
    register("midpoint-here-only", midpoint_here_only)
    config = IdentificationConfig("midpoint-here-only", polish=False)
    try:
        batch.close_pools()
        got = identify(traces, config, seed=2, workers=2)
        assert batch._POOLS[1]._pool is None             # the broken pool was let go
        for a, t in zip(got, traces):
            same(a, identify(t, config, seed=2))
    finally:
        batch.close_pools()
        unregister("midpoint-here-only")
