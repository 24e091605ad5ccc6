"""The stator windings as a linear circuit: phase self and mutual inductance with
leakage, and inter-turn short circuits as fault loops.

Both fault models of :mod:`emaphm.faults` end up here, as the inductance and
resistance matrices of one linear electrical system, so that the reference
plant and the monitoring model integrate the same equations with their own
schemes.

Winding of phase ``j`` (a, b, c = 0, 1, 2)
------------------------------------------
A surface PMSM has no saliency, so the inductances do not depend on the rotor
angle. The synchronous inductance ``L_j`` of phase ``j`` splits into a leakage
share ``sigma`` (slot, end-winding: links the phase's own turns only) and a
magnetising part (links every phase through the air gap)::

    L_ls,j = sigma L_j                 L_ms,j = (1 - sigma) L_j / 1.5
    self   L_jj = L_ls,j + L_ms,j      mutual L_jk = -0.5 sqrt(L_ms,j L_ms,k)

so that balanced currents see ``L_jj - L_jk = L_j`` (the data-sheet value).
``sigma = 1`` leaves three uncoupled phases of inductance ``L_j``: the paper's
Eq. 5, which the ``paper`` fault model uses.

Inter-turn short circuit of phase ``j``
---------------------------------------
A fraction ``mu_j`` of the phase's turns is bridged by a fault resistance
``R_f,j``. The phase current ``i_j`` flows through the healthy turns, ``i_j -
f_j`` through the shorted ones and the **fault-loop current** ``f_j`` through
``R_f,j``. The magnetomotive force of phase ``j`` is then ``N (i_j - mu_j
f_j)``; every linkage follows from it, with leakage in proportion to turns. In
the state ``x = [i_a, i_b, i_c, f_a, f_b, f_c]`` the circuit is::

    v - v_n [1,1,1,0,0,0] = R_x x + L_x dx/dt + T^T c omega_m
    T = [I_3, -diag(mu)]                      (3 x 6: state -> MMF currents)
    L_x = T^T L_m T + leakage                 leakage_j = L_ls,j [[1, -mu], [-mu, mu]]
    R_x = per phase [[R_j, -mu_j R_j], [-mu_j R_j, mu_j R_j + R_f,j]]
    T_m = c . (T x) = sum_j c_j (i_j - mu_j f_j)

with ``v = [v_a, v_b, v_c, 0, 0, 0]`` (the fault loops have no source),
``c_j`` the back-EMF coefficients of Eq. 2 (the shorted turns carry ``mu_j``
of phase ``j``'s back-EMF) and ``L_m`` the magnetising matrix above. ``L_x``
and ``R_x`` are symmetric positive definite for ``0 < mu < 1``, ``sigma > 0``
and ``R_f >= 0``; input power ``v . x`` = copper and fault-loop loss ``x R_x
x`` + magnetic energy rate + air-gap power ``T_m omega_m``. The fault loop
dissipates ``R_f f^2`` and its MMF opposes the phase's: it brakes. Without
leakage (``sigma = 0``) the shorted turns would be perfectly coupled and
``L_x`` singular: the PWM would drive an unbounded ripple through them.

A phase with ``mu_j = 0`` has no fault loop: its ``f_j`` is an algebraic zero.
The reduced system below keeps a fixed size by giving such a loop a dummy,
decoupled unit inductance and resistance (``f_j`` starts at zero, has no
input and stays zero), which is the ``mu -> 0`` limit.

Star connection
---------------
``i_a + i_b + i_c = 0`` is kept by writing the phase currents in the
orthonormal zero-sum basis ``Q`` (3 x 2): ``i = Q y`` and ``x = S z`` with
``z = [y, f]`` (5 states), ``S = diag(Q, I_3)``. Then the star point voltage
drops out (``Q^T [1, 1, 1] = 0``)::

    L_r dz/dt = -R_r z + S^T (v - T^T c omega_m),   L_r = S^T L_x S,  R_r = S^T R_x S

:func:`zoh` gives the exact step of this system for inputs held over ``dt``
(the monitoring model's update); the plant integrates the same matrices with
its own scheme.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["Q", "N_Z", "winding_matrices", "reduced", "zoh", "healthy"]

#: Orthonormal basis of zero-sum phase currents: i_abc = Q @ y (power invariant).
Q = np.array([[math.sqrt(2.0 / 3.0), 0.0],
              [-1.0 / math.sqrt(6.0), 1.0 / math.sqrt(2.0)],
              [-1.0 / math.sqrt(6.0), -1.0 / math.sqrt(2.0)]])
Q.setflags(write=False)

#: States of the reduced electrical system: 2 zero-sum phase currents + 3 fault loops.
N_Z = 5


def _b3(x, name: str) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.ndim == 0:
        a = np.full(3, float(a))
    if a.shape[-1:] != (3,):
        raise ValueError(f"{name} needs a last axis of 3 per-phase values, got shape {a.shape}")
    return a


def winding_matrices(R, L, sigma, mu, R_f) -> tuple[np.ndarray, np.ndarray]:
    """``(L_x, R_x)``, each ``(..., 6, 6)``, of the state ``[i_a, i_b, i_c, f_a, f_b, f_c]``.

    ``R`` [ohm], ``L`` [H] synchronous inductance, ``mu`` [-] shorted fraction and
    ``R_f`` [ohm] fault resistance, each ``(..., 3)`` per phase; ``sigma`` [-] leakage
    share, ``(...)``. Batch axes broadcast.
    """
    R, L, mu, R_f = (_b3(v, n) for v, n in ((R, "R"), (L, "L"), (mu, "mu"), (R_f, "R_f")))
    sigma = np.asarray(sigma, dtype=float)[..., None]
    R, L, mu, R_f, sigma = np.broadcast_arrays(R, L, mu, R_f, sigma)
    sigma = sigma[..., 0]
    batch = R.shape[:-1]
    L_ls = sigma[..., None] * L
    L_ms = (1.0 - sigma[..., None]) * L / 1.5
    Lm = -0.5 * np.sqrt(L_ms[..., :, None] * L_ms[..., None, :])
    idx = np.arange(3)
    Lm[..., idx, idx] = L_ms
    T = np.zeros(batch + (3, 6))
    T[..., idx, idx] = 1.0
    T[..., idx, 3 + idx] = -mu
    L_x = np.swapaxes(T, -1, -2) @ Lm @ T
    R_x = np.zeros(batch + (6, 6))
    f = 3 + idx
    L_x[..., idx, idx] += L_ls
    L_x[..., idx, f] -= mu * L_ls
    L_x[..., f, idx] -= mu * L_ls
    L_x[..., f, f] += mu * L_ls
    R_x[..., idx, idx] = R
    R_x[..., idx, f] = -mu * R
    R_x[..., f, idx] = -mu * R
    R_x[..., f, f] = mu * R + R_f
    return L_x, R_x


_S = np.zeros((6, N_Z))
_S[:3, :2] = Q
_S[3:, 2:] = np.eye(3)
_S.setflags(write=False)


def reduced(L_x: np.ndarray, R_x: np.ndarray, mu) -> tuple[np.ndarray, np.ndarray]:
    """``(L_r, R_r)`` ``(..., 5, 5)`` of the star-connected system in ``z = [y, f]``.

    A loop with ``mu_j == 0`` is replaced by a decoupled unit inductance and
    resistance (it has no input, so its current stays zero).
    """
    L_r = _S.T @ L_x @ _S
    R_r = _S.T @ R_x @ _S
    mu = np.broadcast_to(np.asarray(mu, dtype=float), L_r.shape[:-2] + (3,))
    for j in range(3):
        off = mu[..., j] == 0.0
        if np.any(off):
            r = 2 + j
            for M in (L_r, R_r):
                M[off, r, :] = 0.0
                M[off, :, r] = 0.0
                M[off, r, r] = 1.0
    return L_r, R_r


def zoh(L_r: np.ndarray, R_r: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact step ``z' = Phi z + Gamma w`` of ``L_r dz/dt = -R_r z + w`` for ``w``
    held over ``dt`` [s]; ``Phi, Gamma`` ``(..., 5, 5)`` [-, A/V].

    Through the symmetric pencil: with ``L_r = C C^T`` and ``C^-1 R_r C^-T = U
    diag(lam) U^T``, ``Phi = C^-T U e^(-lam dt) U^T C^T`` and ``Gamma = C^-T U
    diag((1 - e^(-lam dt))/lam) U^T C^-1``, which stays accurate however stiff a
    fault loop is (``lam dt`` large).
    """
    C = np.linalg.cholesky(L_r)
    Ci = np.linalg.inv(C)
    M = Ci @ R_r @ np.swapaxes(Ci, -1, -2)
    M = 0.5 * (M + np.swapaxes(M, -1, -2))
    lam, U = np.linalg.eigh(M)
    x = lam * dt
    e = np.exp(-x)
    g = -np.expm1(-x) / lam
    CiTU = np.swapaxes(Ci, -1, -2) @ U
    UT = np.swapaxes(U, -1, -2)
    Phi = (CiTU * e[..., None, :]) @ UT @ np.swapaxes(C, -1, -2)
    Gamma = (CiTU * g[..., None, :]) @ np.swapaxes(CiTU, -1, -2)
    return Phi, Gamma


def healthy(R, L) -> bool:
    """True when the three phases are equal (the leakage split is then invisible)."""
    R = np.asarray(R, dtype=float)
    L = np.asarray(L, dtype=float)
    return bool(np.all(R == R[..., :1]) and np.all(L == L[..., :1]))
