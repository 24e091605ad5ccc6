"""The search spaces: maps from the optimizers' unit box onto k."""

import numpy as np
import pytest

from emaphm.search import SEARCH_SPACES, from_k, to_k


def test_k_space_is_the_identity():
    Z = np.random.default_rng(0).random((20, 8))
    np.testing.assert_array_equal(to_k(Z, "k"), Z)
    np.testing.assert_array_equal(from_k(Z, "k"), Z)


def test_ecc_xy_maps_the_eccentricity_vector():
    z = np.full(8, 0.5)
    z[5], z[6] = 0.5 + 0.5 * 0.3, 0.5              # x = 0.3, y = 0: modulus 0.3, phase 0 rad
    k = to_k(z)[0]
    assert k[5] == pytest.approx(0.3) and k[6] == pytest.approx(0.5)    # k7 = 0.5 is 0 rad
    z[5], z[6] = 0.5, 0.5                          # the centre: no eccentricity, nominal phase
    assert to_k(z)[0][5] == 0.0 and to_k(z)[0][6] == 0.5
    z[5], z[6] = 1.0, 1.0                          # a corner outside the disk: modulus clipped
    assert to_k(z)[0][5] == 1.0


def test_ecc_xy_round_trip_inside_the_disk():
    rng = np.random.default_rng(1)
    K = rng.random((200, 8))
    K[:, 5] = rng.uniform(0.01, 1.0, 200)          # a defined phase needs some eccentricity
    K[:, 6] = rng.uniform(0.0, 0.999, 200)
    np.testing.assert_allclose(to_k(from_k(K)), K, atol=1e-12)
    other = np.delete(np.arange(8), [5, 6])
    np.testing.assert_array_equal(to_k(from_k(K))[:, other], K[:, other])


def test_unknown_space_is_refused():
    assert set(SEARCH_SPACES) == {"ecc-xy", "k", "ecc-xy-sc", "ecc-xy-sq"}
    with pytest.raises(ValueError, match="unknown search space 'polar'; choose one of ecc-xy, k, "
                                         "ecc-xy-sc, ecc-xy-sq"):
        to_k(np.zeros((1, 8)), "polar")


def test_sparse_short_circuit_space_has_healthy_phases_and_small_shorts():
    from emaphm.search import SC_SEARCH_MAX, default_search

    rng = np.random.default_rng(0)
    Z = rng.uniform(size=(20000, 8))
    K = to_k(Z, "ecc-xy-sc")
    sc = K[:, 2:5]
    assert sc.min() == 0.0 and sc.max() <= SC_SEARCH_MAX
    # half of each coordinate is a healthy phase; an eighth of the box has all three healthy
    assert np.mean(sc == 0.0) == pytest.approx(0.5, abs=0.01)
    assert np.mean(np.all(sc == 0.0, axis=1)) == pytest.approx(0.125, abs=0.01)
    # and the rest concentrates on small shorts: P(0 < k < 0.15) = sqrt(0.25)/2
    assert np.mean((sc > 0) & (sc < 0.15)) == pytest.approx(0.25, abs=0.01)
    # the other components are those of ecc-xy
    assert np.array_equal(np.delete(K, [2, 3, 4], axis=1),
                          np.delete(to_k(Z, "ecc-xy"), [2, 3, 4], axis=1))
    # round trip for shorts inside the range
    k = np.array([[0.2, 0.1, 0.05, 0.0, 0.3, 0.4, 0.3, 0.6]])
    assert to_k(from_k(k, "ecc-xy-sc"), "ecc-xy-sc") == pytest.approx(k)
    assert default_search("physical") == "ecc-xy-sc" and default_search("paper") == "ecc-xy"


def test_squared_short_circuit_space_is_linear_in_the_loops_effect():
    """``ecc-xy-sq``: k = SC_SEARCH_MAX sqrt(z) on k3..k5 (a loop's effect grows as k^2,
    so linearly in z), ecc-xy elsewhere; a round trip inside the range; and the
    least-squares pipeline uses it only under the physical fault model."""
    from emaphm.search import SC_SEARCH_MAX, least_squares_search, nuisance_from_box, nuisance_to_box

    z = np.full((1, 8), 0.5)
    z[0, 2:5] = [0.0, 0.25, 1.0]
    k = to_k(z, "ecc-xy-sq")[0]
    assert k[2:5] == pytest.approx([0.0, 0.5 * SC_SEARCH_MAX, SC_SEARCH_MAX])
    np.testing.assert_array_equal(np.delete(k, [2, 3, 4]), np.delete(to_k(z)[0], [2, 3, 4]))
    kk = np.array([[0.2, 0.1, 0.05, 0.0, 0.3, 0.4, 0.3, 0.6]])
    assert to_k(from_k(kk, "ecc-xy-sq"), "ecc-xy-sq") == pytest.approx(kk)
    assert least_squares_search("physical") == "ecc-xy-sq"
    assert least_squares_search("paper") == "ecc-xy"
    nu = np.array([[0.0, 0.0], [0.3, -0.06]])
    u = nuisance_to_box(nu, ("R", "flux"))
    assert u == pytest.approx(np.array([[0.25, 0.5], [1.0, 0.0]]))
    assert nuisance_from_box(u, ("R", "flux")) == pytest.approx(nu)
