"""The pure update functions against readable loop-by-loop textbook references.

Each vectorised kernel in ``emaphm.optim.{de,pso,gwo}`` receives its random numbers as
arguments, so it can be compared exactly with a plain-Python transcription of the
published equations, fed the same numbers.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy import stats

from emaphm.optim import DE, GWO, PSO
from emaphm.optim.de import binomial_crossover, distinct_indices, greedy_selection, rand1_mutation
from emaphm.optim.gwo import gwo_a, gwo_position_update, rank_leaders, update_leaders
from emaphm.optim.pso import pso_position_update, pso_velocity_update, update_personal_best

RNG = np.random.default_rng(20230301)


# ----------------------------------------------------------------------------- DE


@pytest.mark.parametrize("n_pop", [4, 5, 17, 50])
def test_distinct_indices_are_distinct_and_exclude_target(n_pop):
    rng = np.random.default_rng(n_pop)
    for _ in range(50):
        idx = distinct_indices(rng, n_pop, 3)
        assert idx.shape == (n_pop, 3) and idx.dtype == np.int64
        assert np.all((idx >= 0) & (idx < n_pop))
        rows = np.column_stack([np.arange(n_pop), idx])
        assert all(len(set(r)) == 4 for r in rows.tolist())


def test_distinct_indices_uniform_over_ordered_triples():
    """For n_pop = 5 the 4 * 3 * 2 = 24 ordered triples avoiding the target are equally
    likely (chi-square test, 12,000 draws; p > 1e-3 for a correct sampler)."""
    rng = np.random.default_rng(1)
    n_pop, draws = 5, 2400
    for target in (0, 2, 4):
        counts = dict.fromkeys(itertools.permutations([i for i in range(n_pop) if i != target], 3), 0)
        for _ in range(draws // 5 * 5):
            counts[tuple(distinct_indices(rng, n_pop, 3)[target])] += 1
        assert len(counts) == 24  # no triple outside the allowed set appeared
        assert stats.chisquare(list(counts.values())).pvalue > 1e-3


def test_distinct_indices_needs_enough_members():
    with pytest.raises(ValueError, match=r"need n_pop >= 4, got 3"):
        distinct_indices(RNG, 3, 3)


def test_rand1_mutation_matches_formula():
    pop = RNG.random((6, 3))
    idx = np.array([[1, 2, 3], [0, 2, 5], [4, 1, 0], [5, 4, 2], [3, 0, 1], [2, 3, 4]])
    v = rand1_mutation(pop, idx, 0.7)
    for i, (r1, r2, r3) in enumerate(idx):
        assert np.allclose(v[i], pop[r1] + 0.7 * (pop[r2] - pop[r3]), rtol=0, atol=1e-15)


def test_binomial_crossover_matches_fig3():
    n_pop, n_var = 7, 5
    x, v = RNG.random((n_pop, n_var)), RNG.random((n_pop, n_var)) + 10.0
    r, j_rand = RNG.random((n_pop, n_var)), RNG.integers(0, n_var, n_pop)
    u = binomial_crossover(x, v, 0.4, r, j_rand)
    for i in range(n_pop):  # Fig. 3, transcribed
        for z in range(n_var):
            expected = v[i, z] if (r[i, z] < 0.4 or z == j_rand[i]) else x[i, z]
            assert u[i, z] == expected
    # CR = 0: exactly the forced component comes from the mutant; CR = 1: all of them.
    u0 = binomial_crossover(x, v, 0.0, r, j_rand)
    assert np.array_equal((u0 != x).sum(axis=1), np.ones(n_pop))
    assert np.array_equal(binomial_crossover(x, v, 1.0, r, j_rand), v)


def test_greedy_selection_is_strict_and_pure():
    pop, trial = np.zeros((3, 2)), np.ones((3, 2))
    fit, f_trial = np.array([1.0, 1.0, np.inf]), np.array([0.5, 1.0, np.inf])
    new_pop, new_fit = greedy_selection(pop, fit, trial, f_trial)
    assert np.array_equal(new_pop, [[1, 1], [0, 0], [0, 0]])  # tie and inf-vs-inf keep target
    assert np.array_equal(new_fit, [0.5, 1.0, np.inf])
    assert np.array_equal(pop, np.zeros((3, 2)))


def test_de_first_tell_adopts_initial_population():
    opt = DE(pop_size=6)
    state = opt.init(([-1.0] * 3, [2.0] * 3), np.random.default_rng(0))
    X = opt.ask(state)
    y = np.arange(6.0)
    y[4] = np.nan  # a failed member stays, with fitness inf
    new = opt.tell(state, X, y)
    assert np.allclose(new.population, state.trial, rtol=0, atol=1e-15)
    assert np.array_equal(new.fitness, [0, 1, 2, 3, np.inf, 5])


# ----------------------------------------------------------------------------- PSO


def test_pso_velocity_update_matches_textbook_loop():
    n_pop, n_var = 5, 4
    v, x, pb = (RNG.uniform(-0.5, 0.5, (n_pop, n_var)) for _ in range(3))
    g = RNG.random(n_var)
    r1, r2 = RNG.random((n_pop, n_var)), RNG.random((n_pop, n_var))
    w, c1, c2, vmax = 0.7298, 1.49618, 1.2, 0.1
    out = pso_velocity_update(v, x, pb, g, w, c1, c2, r1, r2, vmax)
    clamped = 0
    for i in range(n_pop):
        for d in range(n_var):
            vi = w * v[i, d] + c1 * r1[i, d] * (pb[i, d] - x[i, d]) + c2 * r2[i, d] * (g[d] - x[i, d])
            clamped += abs(vi) > vmax
            vi = min(max(vi, -vmax), vmax)
            assert out[i, d] == pytest.approx(vi, abs=1e-15)
    assert clamped > 0  # the clamp was exercised


def test_pso_position_update_absorbing_walls():
    x = np.array([[0.5, 0.95, 0.05]])
    v = np.array([[0.1, 0.1, -0.1]])
    x_new, v_new = pso_position_update(x, v)
    assert np.allclose(x_new, [[0.6, 1.0, 0.0]])
    assert np.allclose(v_new, [[0.1, 0.0, 0.0]])  # velocity zeroed where the wall was hit


def test_pso_personal_best_only_on_strict_improvement():
    pb, pbf = np.zeros((3, 1)), np.array([1.0, 1.0, 1.0])
    x, f = np.ones((3, 1)), np.array([0.5, 1.0, np.inf])
    new_pb, new_pbf = update_personal_best(pb, pbf, x, f)
    assert np.array_equal(new_pb[:, 0], [1.0, 0.0, 0.0])
    assert np.array_equal(new_pbf, [0.5, 1.0, 1.0])


def test_pso_state_tracks_swarm_best():
    opt = PSO(pop_size=8)
    state = opt.init(([-1.0] * 2, [1.0] * 2), np.random.default_rng(3))
    for _ in range(5):
        X = opt.ask(state)
        state = opt.tell(state, X, np.sum(X**2, axis=1))
        assert state.best_f == state.pbest_f.min()
        assert np.abs(state.velocity).max() <= opt.v_max


# ----------------------------------------------------------------------------- GWO


def test_gwo_position_update_matches_mirjalili_equations():
    n_pop, n_var = 4, 3
    x, leaders = RNG.random((n_pop, n_var)), RNG.random((3, n_var))
    r1, r2 = RNG.random((3, n_pop, n_var)), RNG.random((3, n_pop, n_var))
    a = 1.3
    out = gwo_position_update(x, leaders, a, r1, r2)
    for i in range(n_pop):  # Mirjalili et al. (2014), eqs. (3.3)-(3.7), transcribed
        for d in range(n_var):
            parts = []
            for k in range(3):
                A = 2 * a * r1[k, i, d] - a
                C = 2 * r2[k, i, d]
                D = abs(C * leaders[k, d] - x[i, d])
                parts.append(leaders[k, d] - A * D)
            expected = min(max(sum(parts) / 3, 0.0), 1.0)
            assert out[i, d] == pytest.approx(expected, abs=1e-15)


def test_gwo_leaders_follow_reference_code():
    """Transcription check against Mirjalili's GWO.m leader update, wolf by wolf."""

    def reference(L, F, x, f):
        L, F = [row.copy() for row in L], list(F)
        for xi, fi in zip(x, f, strict=True):
            if fi < F[0]:
                F[0], L[0] = fi, xi.copy()
            if F[0] < fi < F[1]:
                F[1], L[1] = fi, xi.copy()
            if F[0] < fi and F[1] < fi < F[2]:
                F[2], L[2] = fi, xi.copy()
        return np.array(L), np.array(F)

    rng = np.random.default_rng(5)
    L, F = rng.random((3, 2)), np.full(3, np.inf)
    for _ in range(30):
        x = rng.random((7, 2))
        f = rng.choice([np.inf, 1.0, 2.0, 3.0], size=7) * rng.random(7)
        f[rng.random(7) < 0.2] = 0.5  # some exact ties
        (L, F), (L_ref, F_ref) = update_leaders(L, F, x, f), reference(L, F, x, f)
        assert np.array_equal(L, L_ref) and np.array_equal(F, F_ref)
        assert F[0] <= F[1] <= F[2]


def test_gwo_leaders_replace_without_demotion():
    leaders = np.array([[0.0], [1.0], [2.0]])
    lf = np.array([1.0, 2.0, 3.0])
    # A wolf better than alpha replaces it; the old alpha is dropped (GWO.m).
    new, nf = update_leaders(leaders, lf, np.array([[9.0], [8.0]]), np.array([0.5, 10.0]))
    assert np.array_equal(new[:, 0], [9.0, 1.0, 2.0]) and np.array_equal(nf, [0.5, 2.0, 3.0])
    # Between alpha and beta -> beta; a tie with alpha changes nothing; inputs untouched.
    new, nf = update_leaders(leaders, lf, np.array([[7.0], [6.0]]), np.array([1.0, 1.5]))
    assert np.array_equal(new[:, 0], [0.0, 6.0, 2.0]) and np.array_equal(nf, [1.0, 1.5, 3.0])
    assert np.array_equal(leaders[:, 0], [0.0, 1.0, 2.0])


def test_gwo_first_pack_is_ranked():
    x = np.arange(10.0)[:, None]
    f = np.array([5.0, np.nan, 3.0, 3.0, 9.0, 1.0, np.inf, 8.0, 7.0, 6.0])
    f = np.where(np.isfinite(f), f, np.inf)
    L, F = rank_leaders(x, f)
    assert np.array_equal(L[:, 0], [5.0, 2.0, 3.0]) and np.array_equal(F, [1.0, 3.0, 3.0])
    # In GWO.tell the first pack is ranked, later packs go through the GWO.m rule: a
    # pack in decreasing order of fitness would otherwise leave beta and delta empty.
    opt = GWO(pop_size=5)
    state = opt.init(([0.0], [1.0]), np.random.default_rng(0))
    X = np.linspace(0.1, 0.5, 5)[:, None]
    state = opt.tell(state, X, np.array([5.0, 4.0, 3.0, 2.0, 1.0]))
    assert np.array_equal(state.leaders_f, [1.0, 2.0, 3.0])
    assert np.allclose(state.leaders[:, 0], [0.5, 0.4, 0.3])
    state = opt.tell(state, X, np.array([0.9, 0.8, 0.7, 0.6, 2.5]))
    # 0.9 -> alpha, then 0.8, 0.7, 0.6 each replace alpha (no demotion); 2.5 -> delta
    assert np.array_equal(state.leaders_f, [0.6, 2.0, 2.5])


def test_gwo_a_schedule():
    assert gwo_a(0, 150) == 2.0
    assert gwo_a(75, 150) == 1.0
    assert gwo_a(150, 150) == 0.0 and gwo_a(400, 150) == 0.0
    assert np.allclose(np.diff([gwo_a(t, 150) for t in range(151)]), -2.0 / 150)


def test_gwo_state_alpha_is_best_so_far():
    opt = GWO(pop_size=6, max_iter=10)
    state = opt.init(([-1.0] * 2, [1.0] * 2), np.random.default_rng(4))
    best = np.inf
    for _ in range(10):
        X = opt.ask(state)
        y = np.sum(X**2, axis=1)
        best = min(best, y.min())
        state = opt.tell(state, X, y)
        assert state.leaders_f[0] == best == state.best_f
        assert state.leaders_f[0] <= state.leaders_f[1] <= state.leaders_f[2]
