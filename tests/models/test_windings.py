"""The winding circuit of emaphm.models.windings: known answers and properties."""

import numpy as np
import pytest
import scipy.linalg

from emaphm.models.windings import Q, healthy, reduced, winding_matrices, zoh

R = np.full(3, 3.15)
L = np.full(3, 22e-3)


def test_zero_sum_basis_is_orthonormal_and_has_no_common_mode():
    assert Q.T @ Q == pytest.approx(np.eye(2), abs=1e-15)
    assert Q.T @ np.ones(3) == pytest.approx(np.zeros(2), abs=1e-15)


@pytest.mark.parametrize("sigma", [0.05, 0.15, 0.5, 1.0])
def test_healthy_star_connection_sees_the_synchronous_inductance(sigma):
    Lx, Rx = winding_matrices(R, L, sigma, [0, 0, 0], 0.15)
    Lr, Rr = reduced(Lx, Rx, [0, 0, 0])
    # whatever the leakage split, balanced (zero-sum) currents see L and R
    assert Lr[:2, :2] == pytest.approx(22e-3 * np.eye(2), rel=1e-12)
    assert Rr[:2, :2] == pytest.approx(3.15 * np.eye(2), rel=1e-12)
    # no fault loop: dummy loops decoupled from the phases
    assert np.all(Lr[:2, 2:] == 0) and np.all(Rr[:2, 2:] == 0)
    assert healthy(R, L)


def test_paper_limit_sigma_one_is_three_uncoupled_phases():
    Lx, _ = winding_matrices(R, [20e-3, 22e-3, 24e-3], 1.0, [0, 0, 0], 0.1)
    assert Lx[:3, :3] == pytest.approx(np.diag([20e-3, 22e-3, 24e-3]), abs=1e-18)


@pytest.mark.parametrize("mu", [[0.1, 0, 0], [0.05, 0.3, 0], [0.2, 0.1, 0.3], [0.99, 0, 0]])
def test_fault_loop_matrices_are_symmetric_positive_definite(mu):
    Lx, Rx = winding_matrices(R, L, 0.15, mu, [0.05, 0.5, 0.2])
    for M in (Lx, Rx):
        assert M == pytest.approx(M.T, abs=1e-18)
    on = [0, 1, 2] + [3 + j for j in range(3) if mu[j] > 0]
    assert np.linalg.eigvalsh(Lx[np.ix_(on, on)]).min() > 0
    assert np.linalg.eigvalsh(Rx[np.ix_(on, on)]).min() > 0


def test_without_leakage_the_shorted_turns_are_perfectly_coupled():
    # sigma -> 0: the loop's inductance matrix becomes singular (unbounded PWM ripple)
    Lx, _ = winding_matrices(R, L, 1e-9, [0.2, 0, 0], 0.1)
    on = [0, 1, 2, 3]
    ev = np.linalg.eigvalsh(Lx[np.ix_(on, on)])
    assert ev.min() / ev.max() < 1e-8


def test_fault_loop_flux_linkage_follows_the_turns():
    # the shorted turns of phase a (fraction mu) carry mu of phase a's magnetising linkage
    mu = 0.2
    Lx, _ = winding_matrices(R, L, 0.15, [mu, 0, 0], 0.1)
    x = np.array([1.0, -0.5, -0.5, 0.0, 0.0, 0.0])       # phase currents only
    lam = Lx @ x
    # lambda_f = -(linkage of the shorted turns) = -mu * lambda_a
    assert lam[3] == pytest.approx(-mu * lam[0], rel=1e-12)


@pytest.mark.parametrize("mu", [[0, 0, 0], [0.1, 0, 0], [0.2, 0.05, 0.3], [1e-6, 0, 0]])
@pytest.mark.parametrize("dt", [1e-6, 125e-6, 1e-3])
def test_zoh_matches_scipy_expm(mu, dt):
    Lx, Rx = winding_matrices(R, L, 0.15, mu, 0.1)
    Lr, Rr = reduced(Lx, Rx, mu)
    Phi, Gamma = zoh(Lr, Rr, dt)
    A = -np.linalg.solve(Lr, Rr)
    Phi_ref = scipy.linalg.expm(A * dt)
    Gamma_ref = (np.eye(5) - Phi_ref) @ np.linalg.inv(Rr)
    assert Phi == pytest.approx(Phi_ref, abs=1e-9)
    assert Gamma == pytest.approx(Gamma_ref, rel=1e-6, abs=1e-12)


def test_batched_matrices_equal_the_single_ones():
    rng = np.random.default_rng(0)
    mu = rng.uniform(0, 0.3, (7, 3))
    mu[2] = 0.0
    Lx, Rx = winding_matrices(np.tile(R, (7, 1)), L, 0.15, mu, 0.2)
    Phi, Gamma = zoh(*reduced(Lx, Rx, mu), 125e-6)
    for j in range(7):
        lx, rx = winding_matrices(R, L, 0.15, mu[j], 0.2)
        p, g = zoh(*reduced(lx, rx, mu[j]), 125e-6)
        assert Phi[j] == pytest.approx(p, rel=1e-12, abs=1e-15)
        assert Gamma[j] == pytest.approx(g, rel=1e-12, abs=1e-15)
