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
    assert set(SEARCH_SPACES) == {"ecc-xy", "k"}
    with pytest.raises(ValueError, match="unknown search space 'polar'; choose one of ecc-xy, k"):
        to_k(np.zeros((1, 8)), "polar")
