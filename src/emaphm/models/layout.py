"""Flat float64 layouts of the parameters, as the compiled kernels take them.

``P`` holds what every candidate shares (the drive and the healthy parts);
``CP`` holds one row per candidate with what the fault vector changes. Both
the reference model (one faulty actuator) and the monitoring model (a
population of candidate ``k``) are fed through these, so a candidate's row
built from ``(nominal, k)`` by :func:`pack_population` equals the row of
:func:`pack` applied to ``apply_faults(nominal, k, fault_model)``.

A row carries the candidate's electrics twice: as parameters (``R, L, c0``
per phase, what the paper's fault model scales; ``mu``, the shorted
fractions of the physical one) and as the exact step of its winding circuit
(:mod:`emaphm.models.windings`) for the sub-step ``dt = T_s / n_sub``:
``Phi`` and ``Gamma`` (5 x 5 each, row by row) of ``z' = Phi z + Gamma w``,
which is what the monitoring model integrates. ``P[P_DT]`` records that
``dt``; the kernels refuse a ``CP`` packed for another one.

=================  =========================================================
fault model        winding circuit of a candidate (``s`` = shorted fraction)
=================  =========================================================
``"paper"``        ``R (1 - s)``, ``L (1 - s)^2``, uncoupled phases
                   (``sigma = 1``), no fault loops; ``c0 (1 - s)``
``"physical"``     healthy ``R, L, c0``, leakage ``Motor.L_sigma``, fault
                   loops ``mu = s`` across ``Motor.R_f`` of the nominal motor
=================  =========================================================
"""

from __future__ import annotations

import math
from collections import OrderedDict
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..faults import (as_k, backlash_width, check_fault_model, eccentricity_phase,
                      friction_scale, gain_scale, shorted_fraction, N_K)
from ..params import ActuatorParams
from .inverter import dead_time_width
from .controller import (CTL_A_I, CTL_A_W, CTL_B_W, CTL_DECOUPLING, CTL_DELAY, CTL_EMF_FF,
                         CTL_I_MAX, CTL_J_TFF, CTL_K_T, CTL_K_VFF, CTL_KD, CTL_KI, CTL_KI_I,
                         CTL_KI_W, CTL_KP_I, CTL_KP_W, CTL_L_D, CTL_OMEGA_MAX, CTL_P, CTL_T_MAX,
                         CTL_T_S, CTL_V_DC, N_CTL)
from .mechanics import CONTACT_RESOLVED
from .windings import N_Z, reduced, winding_matrices, zoh

# shared parameters P[...]: first the drive's settings in the controller's order
# (:data:`emaphm.models.controller.CTL_FIELDS`, the tuple ``control_step`` reads), then the rest
P_CTL = 0
(P_KI, P_KD, P_OMEGA_MAX, P_KP_W, P_KI_W, P_T_MAX, P_K_T, P_I_MAX, P_KP_I, P_KI_I, P_V_DC,
 P_T_S) = (P_CTL + CTL_KI, P_CTL + CTL_KD, P_CTL + CTL_OMEGA_MAX, P_CTL + CTL_KP_W,
           P_CTL + CTL_KI_W, P_CTL + CTL_T_MAX, P_CTL + CTL_K_T, P_CTL + CTL_I_MAX,
           P_CTL + CTL_KP_I, P_CTL + CTL_KI_I, P_CTL + CTL_V_DC, P_CTL + CTL_T_S)
P_POLES = P_CTL + CTL_P
(P_J_M, P_C_M, P_J_L, P_C_L, P_THETA0, P_I_TRIP, P_DT, P_K_C, P_D_C,
 P_INV_I0) = range(N_CTL, N_CTL + 10)
N_P = N_CTL + 10

# per-candidate parameters CP[:, ...]
(C_KP, C_FSJ, C_FDJ, C_BACKLASH, C_R_A, C_R_B, C_R_C, C_L_A, C_L_B, C_L_C,
 C_C0_A, C_C0_B, C_C0_C, C_ECC, C_ECC_PHASE, C_MU_A, C_MU_B, C_MU_C) = range(18)
#: ``Phi`` (25 entries, row-major) and ``Gamma`` (25) of the winding circuit's exact step
C_PHI = 18
C_GAMMA = C_PHI + N_Z * N_Z
C_PHI_END = C_GAMMA
C_GAMMA_END = C_GAMMA + N_Z * N_Z
#: a constant load torque [N m] the candidate adds to the profile's: the unit's unreported
#: load ``Load.T_0``, plus the ``"load"`` nuisance (read by the monitoring model's kernels;
#: the reference plant takes its whole load from ``run_reference(extra_load=)``)
C_T0 = C_GAMMA + N_Z * N_Z
#: the voltage [V] a leg loses to the inverter's dead time and device drops (the data
#: sheet's ``Inverter.V_lost`` as packed, plus the ``"V_dt"`` nuisance); what only the
#: recorded-voltage model reads (:mod:`emaphm.models.driven`): the offset [rad, mechanical]
#: of the encoder's zero from the magnet's axis (the ``"angle"`` nuisance; zero as packed);
#: the Stribeck speed [rad/s] of the dry friction (``Transmission.omega_s`` as packed, 0:
#: Borello's two levels; the ``"stribeck"`` nuisance replaces it), which every model steps
C_V_DT = C_T0 + 1
C_DELTA = C_T0 + 2
C_OMEGA_S = C_T0 + 3
N_CP = C_T0 + 4


#: Shorted fraction [-] below which a phase has no fault loop. Such a loop (inductance
#: ``mu sigma L``) is stiffer than the exact step resolves in double precision (as mu -> 0
#: its inductance underflows and ``L_r`` turns singular), and its effect on the phase
#: currents and the torque, of order ``mu^2``, is far below round-off.
MU_MIN = 1e-6


def winding_step_matrices(R, L, sigma, mu, R_f, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """``(Phi, Gamma)`` ``(n, 25)`` [-, A/V]: the exact step of each candidate's winding
    circuit over ``dt`` [s], row by row.

    ``R`` [ohm], ``L`` [H], ``mu`` [-], ``R_f`` [ohm] ``(n, 3)`` or broadcastable,
    ``sigma`` [-] leakage share (see :func:`emaphm.models.windings.winding_matrices`).
    A loop with ``mu_j < MU_MIN`` is absent: exactly decoupled (no round-off coupling
    from the eigen-decomposition), so its current stays exactly zero.
    """
    mu = np.asarray(mu, dtype=float)
    mu = np.where(mu < MU_MIN, 0.0, mu)
    L_x, R_x = winding_matrices(R, L, sigma, mu, R_f)
    L_r, R_r = reduced(L_x, R_x, mu)
    Phi, Gamma = zoh(L_r, R_r, dt)
    mu = np.broadcast_to(mu, Phi.shape[:-2] + (3,))
    for j in range(3):
        off = mu[..., j] == 0.0
        if np.any(off):
            r = 2 + j
            for M in (Phi, Gamma):
                M[off, r, :] = 0.0
                M[off, :, r] = 0.0
            Phi[off, r, r] = np.exp(-dt)             # the dummy unit loop of reduced()
            Gamma[off, r, r] = -np.expm1(-dt)
    n = Phi.shape[:-2]
    return Phi.reshape(n + (N_Z * N_Z,)), Gamma.reshape(n + (N_Z * N_Z,))


def _sub_step(params: ActuatorParams, n_sub: int) -> float:
    if isinstance(n_sub, bool) or int(n_sub) != n_sub or n_sub < 1:
        raise ValueError(f"n_sub must be an integer >= 1, got {n_sub!r}")
    return params.inverter.T_s / int(n_sub)


def pack_shared(params: ActuatorParams, theta0: float = 0.0, n_sub: int = 1) -> np.ndarray:
    """The shared parameter vector P; ``theta0`` [rad] is the initial motor
    (and load) angle, at rest (a recorded trace need not start at zero);
    ``P[P_DT] = T_s / n_sub`` the sub-step the electrics are packed for;
    ``P[P_K_C], P[P_D_C]`` the backlash contact the kernels step, ``K_c = 0`` (rigid)
    where ``dt`` does not resolve it (:func:`contact_resolved`); ``P[P_INV_I0]`` one over
    the current below which the dead time's voltage error fades
    (:func:`emaphm.models.inverter.dead_time_width`)."""
    m, inv, load = params.motor, params.inverter, params.load
    tr = params.transmission
    P = np.empty(N_P)
    P[P_CTL:P_CTL + N_CTL] = drive_settings(params)
    P[P_J_M] = m.J_m
    P[P_C_M] = m.C_m
    P[P_J_L] = load.J_l
    P[P_C_L] = load.C_l
    P[P_THETA0] = theta0
    P[P_I_TRIP] = inv.I_trip
    P[P_DT] = _sub_step(params, n_sub)
    resolved = contact_resolved(params, P[P_DT])
    P[P_K_C] = tr.K_c if resolved else 0.0
    P[P_D_C] = tr.D_c if resolved else 0.0
    P[P_INV_I0] = 1.0 / dead_time_width(params.controller.I_max or m.I_max)
    return P


def drive_settings(params: ActuatorParams) -> np.ndarray:
    """The drive's settings as :func:`emaphm.models.controller.control_step` reads them
    (:data:`~emaphm.models.controller.CTL_FIELDS`), from the parameters' ``[controller]``
    and ``[inverter]``: the options as the controller's coefficients (a filter's time
    constant as ``1 - exp(-T_s / tau)``, 1 without a filter; the torque feed-forward as its
    gain times its inertia), the limits and the data-sheet settings as the parameters
    resolved them (:meth:`emaphm.params.Controller.resolved`)."""
    m, inv = params.motor, params.inverter
    ctl = params.controller.resolved(m, params.load)
    T_s = inv.T_s
    out = np.empty(N_CTL)
    out[CTL_KI] = ctl.Ki
    out[CTL_KD] = ctl.Kd
    out[CTL_OMEGA_MAX] = ctl.omega_max
    out[CTL_KP_W] = ctl.Kp_w
    out[CTL_KI_W] = ctl.Ki_w
    out[CTL_T_MAX] = ctl.T_max
    out[CTL_K_T] = ctl.k_T
    out[CTL_I_MAX] = ctl.I_max
    out[CTL_KP_I] = inv.Kp_i
    out[CTL_KI_I] = inv.Ki_i
    out[CTL_V_DC] = inv.V_dc
    out[CTL_T_S] = T_s
    out[CTL_K_VFF] = ctl.velocity_feedforward
    out[CTL_J_TFF] = ctl.torque_feedforward * ctl.torque_feedforward_inertia
    out[CTL_A_W] = _filter_coefficient(ctl.speed_filter_s, T_s)
    out[CTL_B_W] = ctl.speed_reference_weight
    out[CTL_A_I] = _filter_coefficient(ctl.current_reference_filter_s, T_s)
    out[CTL_DECOUPLING] = 1.0 if ctl.decoupling else 0.0
    out[CTL_L_D] = ctl.decoupling_L
    out[CTL_EMF_FF] = 1.0 if ctl.emf_feedforward else 0.0
    out[CTL_DELAY] = float(ctl.delay_periods)
    out[CTL_P] = m.p
    return out


def _filter_coefficient(tau: float, T_s: float) -> float:
    """``1 - exp(-T_s / tau)`` of a first-order low-pass of time constant ``tau`` [s]
    sampled every ``T_s`` [s]; 1 (no filter) for ``tau = 0``."""
    return 1.0 if tau <= 0.0 else -math.expm1(-T_s / tau)


def contact_resolved(params: ActuatorParams, dt: float) -> bool:
    """Whether a step ``dt`` [s] resolves the backlash contact's two-mass resonance
    ``omega_c = sqrt(K_c (J_m + J_l) / (J_m J_l))``: ``omega_c dt <=``
    :data:`~emaphm.models.mechanics.CONTACT_RESOLVED` (0.4 for the preset at 8 kHz)."""
    J_m, J_l, K_c = params.motor.J_m, params.load.J_l, params.transmission.K_c
    return math.sqrt(K_c * (J_m + J_l) / (J_m * J_l)) * dt <= CONTACT_RESOLVED


def pack(params: ActuatorParams, theta0: float = 0.0, fault_model: str = "paper", *,
         n_sub: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """``(P, CP)`` for one actuator as it is (faults already applied); CP has one row.

    ``fault_model`` says which winding circuit ``params`` describe: ``"paper"``
    (uncoupled phases with their own ``R, L``; ``Motor.mu`` must be zero) or
    ``"physical"`` (``Motor.L_sigma``, ``mu``, ``R_f``). ``n_sub``: sub-steps per
    control period the electrics are stepped with.
    """
    check_fault_model(fault_model)
    m, tr, ctl = params.motor, params.transmission, params.controller
    if fault_model == "paper" and any(m.mu):
        raise ValueError(f"the paper's fault model has no fault loops, but Motor.mu = {m.mu}; "
                         "pack with fault_model='physical'")
    P = pack_shared(params, theta0, n_sub)
    row = np.empty(N_CP)
    row[C_KP] = ctl.Kp
    row[C_FSJ] = tr.FSJ
    row[C_FDJ] = tr.FDJ
    row[C_BACKLASH] = tr.backlash
    row[C_R_A:C_R_C + 1] = m.R
    row[C_L_A:C_L_C + 1] = m.L
    row[C_C0_A:C_C0_C + 1] = m.c0
    row[C_ECC] = m.ecc
    row[C_ECC_PHASE] = m.ecc_phase
    row[C_MU_A:C_MU_C + 1] = m.mu
    sigma = 1.0 if fault_model == "paper" else m.L_sigma
    row[C_PHI:C_GAMMA], row[C_GAMMA:C_T0] = _one_winding(
        tuple(m.R), tuple(m.L), float(sigma), tuple(m.mu), tuple(m.R_f), float(P[P_DT]))
    row[C_T0] = params.load.T_0
    row[C_V_DT] = params.inverter.V_lost
    row[C_DELTA] = 0.0
    row[C_OMEGA_S] = tr.omega_s
    return P, row[None, :]


@lru_cache(maxsize=64)
def _one_winding(R: tuple, L: tuple, sigma: float, mu: tuple, R_f: tuple,
                 dt: float) -> tuple[np.ndarray, np.ndarray]:
    """:func:`winding_step_matrices` of one winding, kept by value: an actuator packed
    again and again with the same winding (calibration's one-parameter-at-a-time
    differences, a model per trace) does its Cholesky factor and eigen-decomposition
    once. Read-only arrays."""
    Phi, Gamma = winding_step_matrices(np.array(R)[None], np.array(L)[None], sigma,
                                       np.array(mu)[None], np.array(R_f)[None], dt)
    Phi, Gamma = Phi[0], Gamma[0]
    Phi.flags.writeable = False
    Gamma.flags.writeable = False
    return Phi, Gamma


@dataclass(frozen=True)
class Nuisance:
    """A parameter a candidate may carry beside its k: its ``name``, the range ``lo..hi``
    it is searched over, its ``unit`` (``"relative"``: a deviation from the nominal value,
    ``"N m"``, ``"decades"``), what it is, in ``words``, and where a search starts it
    (``start``: the nominal 0, but where 0 is a flat end of its effect)."""

    name: str
    lo: float
    hi: float
    unit: str
    words: str
    start: float = 0.0


#: Every parameter a candidate may carry beside its k, listed once (the search ranges and
#: the words of :mod:`emaphm.search` read them from here): relative deviations of the
#: winding resistance (``"R"``: a winding warmer than at calibration, up to +30 %, about
#: 75 K, or cooler) and of the magnet flux (``"flux"``: the back-EMF coefficient, so the
#: torque per ampere, within +-6 % with temperature; ``"demag"``: the same, searched over
#: the losses of a demagnetized rotor, down to half, :mod:`emaphm.modes.demagnetization`)
#: from the nominal parameters, a constant load torque (``"load"``, in N m, added to the
#: profile's: a load the bench does not report, 1.5x the +-0.1 N m of
#: :data:`emaphm.units.DEFAULT_TOLERANCES`), and each phase's fault-bridge resistance as a
#: decade ratio to ``Motor.R_f`` (``"Rf_a"``, ``"Rf_b"``, ``"Rf_c"``: ``R_f x 10**value``
#: from 0.03x to 10x; it changes the winding step of a shorted phase only,
#: :mod:`emaphm.modes.short_circuit`). Searched on the recorded-voltage path
#: (:mod:`emaphm.models.driven`): the voltage a leg loses to the inverter's dead time and its
#: devices' drops (``"V_dt"``, V, the same on every leg, opposing its current), the
#: offset of the encoder's zero from the magnet's axis (``"angle"``, electrical radians,
#: read there only), and the speed below which the dry friction rises from its dynamic to
#: its static level (``"stribeck"``, rad/s: the Stribeck drop, which data sheets do not
#: state; a value that replaces ``Transmission.omega_s``, which every model steps).
NUISANCE_PARAMETERS: dict[str, Nuisance] = {n.name: n for n in (
    Nuisance("R", -0.1, 0.3, "relative", "winding resistance"),
    Nuisance("flux", -0.06, 0.06, "relative", "magnet flux"),
    Nuisance("load", -0.15, 0.15, "N m", "unreported constant load"),
    Nuisance("demag", -0.5, 0.02, "relative", "magnet flux"),
    Nuisance("Rf_a", -1.5, 1.0, "decades", "fault resistance of phase A"),
    Nuisance("Rf_b", -1.5, 1.0, "decades", "fault resistance of phase B"),
    Nuisance("Rf_c", -1.5, 1.0, "decades", "fault resistance of phase C"),
    # one phase's resistance (its winding and its connection), a loose or corroded
    # connection raising it up to 3x (emaphm.modes.resistance)
    Nuisance("R_a", -0.1, 2.0, "relative", "resistance of phase A"),
    Nuisance("R_b", -0.1, 2.0, "relative", "resistance of phase B"),
    Nuisance("R_c", -0.1, 2.0, "relative", "resistance of phase C"),
    Nuisance("V_dt", 0.0, 30.0, "V", "inverter dead time and device drops"),
    Nuisance("angle", -0.2, 0.2, "rad (electrical)", "encoder offset"),
    # a search starts the Stribeck speed at the reference plant's 1 rad/s: at 0 (no drop)
    # the friction does not change with it, and least squares could not leave it
    Nuisance("stribeck", 0.0, 5.0, "rad/s", "Stribeck speed of the dry friction", start=1.0),
)}
#: Their names.
NUISANCE = tuple(NUISANCE_PARAMETERS)

#: The extra parameters that scale the back-EMF coefficients.
_FLUX = ("flux", "demag")

#: The extra parameters that scale one phase's resistance, in the order of the phases.
_PHASE_R = ("R_a", "R_b", "R_c")


def pack_population(nominal: ActuatorParams, K: np.ndarray, theta0: float = 0.0,
                    fault_model: str = "paper", *, n_sub: int = 1,
                    nuisance: tuple[str, ...] = ()) -> tuple[np.ndarray, np.ndarray]:
    """``(P, CP)`` for a population of fault vectors ``K`` (n_pop, 8) on a healthy actuator.

    ``fault_model`` maps k3..k5 (:func:`emaphm.faults.apply_faults`): ``"paper"``
    scales R, L, c0; ``"physical"`` shorts a fraction ``mu`` of the turns across the
    nominal ``Motor.R_f``. ``n_sub``: sub-steps per control period. ``nuisance``:
    names from :data:`NUISANCE`; ``K`` then has ``8 + len(nuisance)`` columns, the
    extra ones each candidate's relative deviation of that parameter. Rows of K are not
    range-checked here (the optimizers keep them in the box); use
    :func:`emaphm.faults.as_k` for user input. A model that packs many populations
    keeps a :class:`PopulationPacker` instead (the same rows, with the shared work done
    once).
    """
    return PopulationPacker(nominal, theta0, fault_model, n_sub=n_sub, nuisance=nuisance)(K)


class PopulationPacker:
    """:func:`pack_population` for one healthy actuator, populations after populations.

    What no fault vector changes is packed once (``P`` and the healthy row), and the
    winding step matrices of the last :attr:`CACHE_SIZE` distinct windings (a phase's
    ``R, L, mu``) are kept: the candidates of a finite-difference Jacobian, or of a
    search closing in, repeat the same few windings, whose exact step (a Cholesky
    factor and an eigen-decomposition each) is otherwise most of the packing. The rows
    are bit-identical to an uncached packing's.
    """

    #: Distinct windings whose step matrices are kept (least recently used dropped).
    CACHE_SIZE = 256

    def __init__(self, nominal: ActuatorParams, theta0: float = 0.0, fault_model: str = "paper",
                 *, n_sub: int = 1, nuisance: tuple[str, ...] = ()) -> None:
        check_fault_model(fault_model)
        nuisance = tuple(nuisance)
        bad = [n for n in nuisance if n not in NUISANCE]
        if bad:
            raise ValueError(f"unknown nuisance parameter(s) {bad}; choose from {', '.join(NUISANCE)}")
        self.nominal, self.fault_model, self.nuisance = nominal, fault_model, nuisance
        self.P, self.base = pack(nominal, theta0, fault_model, n_sub=n_sub)
        self._sigma = 1.0 if fault_model == "paper" else nominal.motor.L_sigma
        self._R_f = np.array(nominal.motor.R_f)
        self._windings: OrderedDict[bytes, tuple[np.ndarray, np.ndarray]] = OrderedDict()
        # a healthy candidate's winding is the nominal one, already packed in the base row
        healthy = np.hstack([self.base[0, C_R_A:C_R_C + 1], self.base[0, C_L_A:C_L_C + 1],
                             self.base[0, C_MU_A:C_MU_C + 1]])
        self._windings[healthy.tobytes()] = (self.base[0, C_PHI:C_GAMMA].copy(),
                                             self.base[0, C_GAMMA:C_T0].copy())

    def __call__(self, K: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        nuisance = self.nuisance
        K = np.atleast_2d(np.asarray(K, dtype=float))
        if K.ndim != 2 or K.shape[1] != N_K + len(nuisance):
            raise ValueError(f"population of fault vectors must have shape (n_pop, {N_K + len(nuisance)})"
                             f" ({N_K} k and {len(nuisance)} nuisance), got {K.shape}")
        K, NU = K[:, :N_K], K[:, N_K:]
        CP = np.repeat(self.base, K.shape[0], axis=0)
        R_f = None
        for j, name in enumerate(nuisance):
            if name == "load":
                CP[:, C_T0] += NU[:, j]
                continue
            if name == "V_dt":
                CP[:, C_V_DT] += NU[:, j]
                continue
            if name == "angle":
                CP[:, C_DELTA] += NU[:, j] / self.nominal.motor.p
                continue
            if name == "stribeck":
                # searched as a value (from 0, no drop), not as a deviation of the stated one
                CP[:, C_OMEGA_S] = NU[:, j]
                continue
            if name.startswith("Rf_"):
                if R_f is None:
                    R_f = np.tile(self._R_f, (K.shape[0], 1))
                R_f[:, "abc".index(name[-1])] *= 10.0 ** NU[:, j]
                continue
            if name in _PHASE_R:
                CP[:, C_R_A + _PHASE_R.index(name)] *= 1.0 + NU[:, j]
                continue
            cols = slice(C_R_A, C_R_C + 1) if name == "R" else slice(C_C0_A, C_C0_C + 1)
            CP[:, cols] *= 1.0 + NU[:, j:j + 1]
        CP[:, C_KP] *= gain_scale(K[:, 7])
        fs = friction_scale(K[:, 0])
        CP[:, C_FSJ] *= fs
        CP[:, C_FDJ] *= fs
        CP[:, C_BACKLASH] = backlash_width(CP[:, C_BACKLASH], K[:, 1])
        s = shorted_fraction(K[:, 2:5])
        if self.fault_model == "paper":
            CP[:, C_R_A:C_R_C + 1] *= 1.0 - s
            CP[:, C_L_A:C_L_C + 1] *= (1.0 - s) ** 2
            CP[:, C_C0_A:C_C0_C + 1] *= 1.0 - s
            mu = np.zeros_like(s)
        else:
            CP[:, C_MU_A:C_MU_C + 1] = s
            mu = s
        CP[:, C_ECC] = K[:, 5]
        CP[:, C_ECC_PHASE] = eccentricity_phase(K[:, 6])
        CP[:, C_PHI:C_GAMMA], CP[:, C_GAMMA:C_T0] = self._matrices(
            CP[:, C_R_A:C_R_C + 1], CP[:, C_L_A:C_L_C + 1], mu, R_f)
        return self.P.copy(), CP

    def _matrices(self, R: np.ndarray, L: np.ndarray, mu: np.ndarray,
                  R_f: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``(Phi, Gamma)`` (n, 25) of each row's winding (its fault-bridge resistances
        ``R_f`` (n, 3), default the nominal ones), from the cache where it is."""
        parts = [R, L, mu] if R_f is None else [R, L, mu, R_f]
        keys = np.ascontiguousarray(np.hstack(parts))
        rows = [keys[i].tobytes() for i in range(keys.shape[0])]
        cache = self._windings
        missing = list(dict.fromkeys(r for r in rows if r not in cache))
        if missing:
            first: dict[bytes, int] = {}
            for i, r in enumerate(rows):
                first.setdefault(r, i)
            idx = [first[r] for r in missing]
            Phi, Gamma = _population_matrices(R[idx], L[idx], self._sigma, mu[idx],
                                              self._R_f if R_f is None else R_f[idx],
                                              self.P[P_DT])
            for i, r in enumerate(missing):
                cache[r] = (Phi[i], Gamma[i])
        Phi = np.empty((len(rows), N_Z * N_Z))
        Gamma = np.empty((len(rows), N_Z * N_Z))
        for i, r in enumerate(rows):
            Phi[i], Gamma[i] = cache[r]
            cache.move_to_end(r)
        while len(cache) > self.CACHE_SIZE:
            cache.popitem(last=False)
        return Phi, Gamma


def _population_matrices(R, L, sigma, mu, R_f, dt):
    """:func:`winding_step_matrices` of the rows with finite parameters; NaN matrices for
    the others (such a candidate diverges at its first step, as a value)."""
    n = R.shape[0]
    Phi = np.full((n, N_Z * N_Z), np.nan)
    Gamma = np.full((n, N_Z * N_Z), np.nan)
    ok = np.all(np.isfinite(R) & np.isfinite(L) & np.isfinite(mu), axis=1)
    if np.ndim(R_f) == 2:
        ok &= np.all(np.isfinite(R_f) & (R_f > 0), axis=1)
    if np.any(ok):
        Phi[ok], Gamma[ok] = winding_step_matrices(R[ok], L[ok], sigma, mu[ok],
                                                   R_f[ok] if np.ndim(R_f) == 2 else R_f, dt)
    return Phi, Gamma


__all__ = ["pack", "pack_shared", "contact_resolved", "drive_settings", "Nuisance",
           "NUISANCE_PARAMETERS", "pack_population", "PopulationPacker", "winding_step_matrices", "MU_MIN", "N_P",
           "N_CP", "C_T0", "NUISANCE", "as_k"]
