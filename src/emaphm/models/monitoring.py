"""Monitoring model (MM): the fast, low-fidelity actuator, batched over a population.

Same controller, transmission and fault semantics as the reference model, but
an **averaged inverter** (each leg applies its duty cycle times ``V_dc`` over
the whole control period, no switching), no sensor effects, and a coarse step:
one control period ``T_s = 1/f_pwm`` (125 us at 8 kHz) divided into ``n_sub``
sub-steps (default 1).

The electrics of a candidate are the winding circuit of
:mod:`emaphm.models.windings` (5 states: two zero-sum phase currents and three
fault-loop currents), advanced by its exact step for the leg voltages and
back-EMFs held over the sub-step, ``z' = Phi z + Gamma w``
(:func:`emaphm.models.pmsm.winding_step`; ``Phi, Gamma`` per candidate from
:func:`emaphm.models.layout.pack_population`), stable over the whole
``[0, 1]^8`` box. ``fault_model`` (:data:`emaphm.faults.FAULT_MODELS`) says what
k3..k5 mean: ``"paper"`` scales R, L, c0 of uncoupled phases (no loops);
``"physical"`` shorts a fraction of the turns across the nominal fault
resistance, and a fault-loop current flows. Both run the same update.

Two implementations that tests hold equal to round-off:

* :func:`simulate_reference` -- a plain single-candidate Python loop, written
  to be read;
* :func:`_kernel` -- the Numba kernel, time loop outside and population
  inside, which returns traces or only the fitness (Eq. 4) against a target;
  :mod:`emaphm.models.monitoring_simd` is the same kernel laid out so that the
  population runs in SIMD lanes, the default of :class:`MonitoringModel`.

A candidate whose state leaves the physical range (``|i| > I_DIVERGED`` A,
``|omega| > OMEGA_DIVERGED`` rad/s, or a non-finite value) is frozen, flagged
in ``status`` and given infinite fitness: a diverging candidate is a value,
not an exception. A candidate whose drive trips on overcurrent
(``Inverter.I_trip``) goes on with the inverter in active short circuit and
is flagged ``STATUS_TRIPPED``; its fitness stays finite (and large).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..faults import as_k, check_fault_model
from ..params import ActuatorParams, siemens_1fk7060
from ..profiles import Profile, diagnostic
from ._jit import jit
from ._monitoring_common import (I_DIVERGED, OMEGA_DIVERGED, STATUS_DIVERGED, STATUS_OK,
                                 STATUS_TRIPPED, _check_step)
from .controller import control_step
from .inverter import modulate, overcurrent
from .layout import (C_BACKLASH, C_C0_A, C_C0_B, C_C0_C, C_ECC, C_ECC_PHASE, C_FDJ, C_FSJ,
                     C_GAMMA, C_KP, C_MU_A, C_MU_B, C_MU_C, C_PHI, C_T0, P_C_L, P_C_M, P_I_MAX,
                     P_D_C, P_J_L, P_J_M, P_K_C, P_K_T, P_KD, P_KI, P_KI_I, P_KI_W, P_KP_I, P_KP_W,
                     P_OMEGA_MAX, P_POLES, P_I_TRIP, P_T_MAX, P_T_S, P_THETA0, P_V_DC, pack,
                     PopulationPacker)
from .mechanics import transmission_step
from .pmsm import (back_emf_coeffs, phase_currents, torque_loops, winding_input,
                   winding_step)

__all__ = ["MonitoringModel", "PopulationResult", "simulate_reference", "I_DIVERGED",
           "OMEGA_DIVERGED", "STATUS_OK", "STATUS_DIVERGED", "STATUS_TRIPPED"]

#: Candidates left over after the SIMD kernel's full blocks that :class:`MonitoringModel`
#: runs in the scalar kernel instead: one alone costs about half a block of vector lanes
#: (``benchmarks/bench_models.py --small-batches-only`` measures it), so a lone remainder
#: (a least-squares step, a finite-difference Jacobian of 8 plus its centre) is cheaper
#: outside the lanes.
SCALAR_TAIL = 1


@jit
def _kernel(P, CP, theta_ref, T_load, n_sub, i_target, weights,
            out_i, out_theta, out_omega, out_torque, fitness, status):
    """Simulate ``CP.shape[0]`` candidates over ``theta_ref.shape[0]`` control periods.

    Shapes: ``P (N_P,)``, ``CP (n_pop, N_CP)``, ``theta_ref, T_load (n,)``;
    ``i_target, weights (n, 3)`` or ``(0, 3)`` for no fitness; ``out_i
    (n_pop, n, 3)``, ``out_theta, out_omega, out_torque (n_pop, n)`` or
    zero-sized for no traces; ``fitness, status (n_pop,)`` written in place.
    ``fitness`` accumulates ``sum_k sum_j weights[k, j] (i_j - i_target[k, j])^2``.
    ``P, CP`` must be packed for ``n_sub`` (ValueError otherwise).
    """
    _check_step(P, n_sub)
    n_pop = CP.shape[0]
    n = theta_ref.shape[0]
    store = out_i.shape[0] == n_pop and n_pop > 0
    with_fit = i_target.shape[0] == n
    p = P[P_POLES]
    T_s = P[P_T_S]
    dt = T_s / n_sub
    J_m, C_m, J_l, C_l = P[P_J_M], P[P_C_M], P[P_J_L], P[P_C_L]
    K_c, D_c = P[P_K_C], P[P_D_C]
    V_dc = P[P_V_DC]
    Ki, Kd, omega_max, Kp_w, Ki_w = P[P_KI], P[P_KD], P[P_OMEGA_MAX], P[P_KP_W], P[P_KI_W]
    T_max, k_T, I_max, Kp_i, Ki_i = P[P_T_MAX], P[P_K_T], P[P_I_MAX], P[P_KP_I], P[P_KI_I]
    I_trip = P[P_I_TRIP]
    # state: the winding circuit's z = [y_alpha, y_beta, f_a, f_b, f_c] and i_abc = Q y
    th_m = np.full(n_pop, P[P_THETA0])
    w_m = np.zeros(n_pop)
    th_l = np.full(n_pop, P[P_THETA0])
    w_l = np.zeros(n_pop)
    Z = np.zeros((n_pop, 5))
    I = np.zeros((n_pop, 3))
    integ = np.zeros((n_pop, 4))
    for j in range(n_pop):
        fitness[j] = 0.0
        status[j] = 0
    for k in range(n):
        ref = theta_ref[k]
        T_l = T_load[k]
        for j in range(n_pop):
            if status[j] == STATUS_DIVERGED:
                continue
            thm, wm, thl, wl = th_m[j], w_m[j], th_l[j], w_l[j]
            ia, ib, ic = I[j, 0], I[j, 1], I[j, 2]
            z0, z1, z2, z3, z4 = Z[j, 0], Z[j, 1], Z[j, 2], Z[j, 3], Z[j, 4]
            mu_a, mu_b, mu_c = CP[j, C_MU_A], CP[j, C_MU_B], CP[j, C_MU_C]
            Phi = CP[j, C_PHI:C_GAMMA]
            Gam = CP[j, C_GAMMA:C_GAMMA + 25]
            if with_fit:
                da = ia - i_target[k, 0]
                db = ib - i_target[k, 1]
                dc = ic - i_target[k, 2]
                fitness[j] += weights[k, 0] * da * da + weights[k, 1] * db * db + weights[k, 2] * dc * dc
            s_e = math.sin(p * thm)
            c_e = math.cos(p * thm)
            if status[j] == STATUS_OK and overcurrent(ia, ib, ic, I_trip):
                status[j] = STATUS_TRIPPED
            if status[j] == STATUS_TRIPPED:          # active short circuit, controller stopped
                d_a = d_b = d_c = 0.0
            else:
                v_a, v_b, v_c, T_ref, e0, e1, e2, e3 = control_step(
                    ref, thm, wm, ia, ib, ic, s_e, c_e,
                    integ[j, 0], integ[j, 1], integ[j, 2], integ[j, 3],
                    CP[j, C_KP], Ki, Kd, omega_max, Kp_w, Ki_w, T_max, k_T, I_max, Kp_i, Ki_i,
                    V_dc, T_s)
                integ[j, 0], integ[j, 1], integ[j, 2], integ[j, 3] = e0, e1, e2, e3
                d_a, d_b, d_c = modulate(v_a, v_b, v_c, V_dc)
            for s in range(n_sub):
                if s > 0:
                    s_e = math.sin(p * thm)
                    c_e = math.cos(p * thm)
                ca, cb, cc = back_emf_coeffs(thm, s_e, c_e, CP[j, C_C0_A], CP[j, C_C0_B],
                                             CP[j, C_C0_C], CP[j, C_ECC], CP[j, C_ECC_PHASE])
                tq0 = torque_loops(ia, ib, ic, z2, z3, z4, ca, cb, cc, mu_a, mu_b, mu_c)
                if s == 0 and store:
                    out_i[j, k, 0] = ia
                    out_i[j, k, 1] = ib
                    out_i[j, k, 2] = ic
                    out_theta[j, k] = thm
                    out_omega[j, k] = wm
                    out_torque[j, k] = tq0
                w0, w1, w2, w3, w4 = winding_input(d_a * V_dc, d_b * V_dc, d_c * V_dc,
                                                   ca * wm, cb * wm, cc * wm, mu_a, mu_b, mu_c)
                z0, z1, z2, z3, z4 = winding_step(z0, z1, z2, z3, z4, w0, w1, w2, w3, w4, Phi, Gam)
                ia, ib, ic = phase_currents(z0, z1)
                # the mechanics see the step's mean torque (trapezoid): second order in
                # the fast current transients of the coarse step
                T_m = 0.5 * (tq0 + torque_loops(ia, ib, ic, z2, z3, z4, ca, cb, cc,
                                                mu_a, mu_b, mu_c))
                thm, wm, thl, wl = transmission_step(thm, wm, thl, wl, T_m, T_l + CP[j, C_T0],
                                                     J_m, C_m, CP[j, C_FSJ], CP[j, C_FDJ], J_l, C_l,
                                                     CP[j, C_BACKLASH], K_c, D_c, dt)
            if not (abs(ia) < I_DIVERGED and abs(ib) < I_DIVERGED and abs(ic) < I_DIVERGED
                    and abs(wm) < OMEGA_DIVERGED and abs(thm) < 1e9):
                status[j] = STATUS_DIVERGED
                fitness[j] = np.inf
                continue
            th_m[j], w_m[j], th_l[j], w_l[j] = thm, wm, thl, wl
            I[j, 0], I[j, 1], I[j, 2] = ia, ib, ic
            Z[j, 0], Z[j, 1], Z[j, 2], Z[j, 3], Z[j, 4] = z0, z1, z2, z3, z4


def simulate_reference(params: ActuatorParams, k, profile: Profile, n_sub: int = 1,
                       theta0: float = 0.0, fault_model: str = "paper") -> dict[str, np.ndarray]:
    """Readable single-candidate monitoring model in plain Python (slow).

    Uses the same physics functions as the kernel (their pure-Python
    versions) and the winding step of :func:`emaphm.models.layout.pack` for
    ``apply_faults(params, k, fault_model)``. Returns a dict of arrays ``t,
    theta_ref, theta_m, omega_m, i_abc (n, 3), f_abc (n, 3)`` (fault-loop
    currents) ``, torque`` sampled at the control instants.
    """
    from ..faults import apply_faults  # local: keep module import light

    faulty = apply_faults(params, k, fault_model)
    m, inv, ctl, tr, ld = faulty.motor, faulty.inverter, faulty.controller, faulty.transmission, faulty.load
    T_s = inv.T_s
    dt = T_s / n_sub
    t = profile.grid(T_s)
    ref = profile.theta_ref(t)
    T_load = profile.load_torque(t)
    P, cp = pack(faulty, theta0, fault_model, n_sub=n_sub)
    Phi = tuple(cp[0, C_PHI:C_GAMMA])                 # row by row
    Gam = tuple(cp[0, C_GAMMA:C_GAMMA + 25])
    thm = thl = theta0
    wm = wl = 0.0
    z = (0.0,) * 5                                    # [y_alpha, y_beta, f_a, f_b, f_c]
    ia = ib = ic = 0.0
    integ = (0.0, 0.0, 0.0, 0.0)
    tripped = False
    out = {name: np.zeros(t.size) for name in ("theta_m", "omega_m", "torque")}
    out["i_abc"] = np.zeros((t.size, 3))
    out["f_abc"] = np.zeros((t.size, 3))
    for n in range(t.size):
        s_e, c_e = math.sin(m.p * thm), math.cos(m.p * thm)
        out["theta_m"][n], out["omega_m"][n] = thm, wm
        out["i_abc"][n] = ia, ib, ic
        out["f_abc"][n] = z[2:]
        ca, cb, cc = back_emf_coeffs.py_func(thm, s_e, c_e, *m.c0, m.ecc, m.ecc_phase)
        out["torque"][n] = torque_loops.py_func(ia, ib, ic, *z[2:], ca, cb, cc, *m.mu)
        tripped = tripped or overcurrent.py_func(ia, ib, ic, inv.I_trip)
        if tripped:                     # active short circuit, controller stopped
            duty = (0.0, 0.0, 0.0)
        else:
            v_a, v_b, v_c, _, *integ = control_step.py_func(
                ref[n], thm, wm, ia, ib, ic, s_e, c_e, *integ,
                ctl.Kp, ctl.Ki, ctl.Kd, ctl.omega_max, ctl.Kp_w, ctl.Ki_w, m.T_max, ctl.k_T,
                m.I_max, inv.Kp_i, inv.Ki_i, inv.V_dc, T_s)
            duty = modulate.py_func(v_a, v_b, v_c, inv.V_dc)
        for _ in range(n_sub):
            s_e, c_e = math.sin(m.p * thm), math.cos(m.p * thm)
            ca, cb, cc = back_emf_coeffs.py_func(thm, s_e, c_e, *m.c0, m.ecc, m.ecc_phase)
            T_0 = torque_loops.py_func(ia, ib, ic, *z[2:], ca, cb, cc, *m.mu)
            w = winding_input.py_func(*(d * inv.V_dc for d in duty), ca * wm, cb * wm, cc * wm,
                                      *m.mu)
            z = winding_step.py_func(*z, *w, Phi, Gam)
            ia, ib, ic = phase_currents.py_func(z[0], z[1])
            T_m = 0.5 * (T_0 + torque_loops.py_func(ia, ib, ic, *z[2:], ca, cb, cc, *m.mu))
            thm, wm, thl, wl = transmission_step.py_func(
                thm, wm, thl, wl, T_m, T_load[n] + cp[0, C_T0], m.J_m, m.C_m, tr.FSJ, tr.FDJ,
                ld.J_l, ld.C_l,
                tr.backlash, P[P_K_C], P[P_D_C], dt)
    out.update(t=t, theta_ref=ref)
    return out


@dataclass(frozen=True)
class PopulationResult:
    """Traces of a population, sampled at the control instants ``t``.

    ``i_abc (n_pop, n, 3)`` [A], ``theta_m, omega_m, torque (n_pop, n)``,
    ``status (n_pop,)`` (0 ok, 1 diverged, 2 tripped; a diverged candidate's traces stop
    where it left the physical range and are zero after).
    """

    t: np.ndarray
    theta_ref: np.ndarray
    theta_m: np.ndarray
    omega_m: np.ndarray
    i_abc: np.ndarray
    torque: np.ndarray
    status: np.ndarray


@dataclass(frozen=True)
class MonitoringModel:
    """The monitoring model on one test profile, ready to evaluate populations.

    Parameters
    ----------
    params : ActuatorParams
        The healthy actuator (faults come from the candidates' ``k``).
    profile : Profile
        Test profile (default: :func:`emaphm.profiles.diagnostic`).
    n_sub : int
        Sub-steps per control period; the step is ``T_s / n_sub``.
    theta0 : float
        Initial motor angle [rad] (the actuator starts at rest).
    fault_model : {"paper", "physical"}
        What the short-circuit components k3..k5 of a candidate mean
        (:func:`emaphm.faults.apply_faults`): ``"paper"`` (default) scales R, L, c0 of
        the phase; ``"physical"`` shorts that fraction of its turns across the nominal
        ``Motor.R_f`` (a fault-loop current flows). :meth:`simulate_params` reads
        ``params`` under the same model.
    kernel : {"simd", "scalar"}
        ``"simd"`` (default): :mod:`emaphm.models.monitoring_simd`, the population in
        vector lanes (about 5x faster); ``"scalar"``: :func:`_kernel` of this module,
        one candidate after another, the readable batched reference the SIMD kernel is
        tested against. Both compute the same model to round-off.
    nuisance : tuple of str
        Nuisance parameters each candidate carries after its 8 k
        (:data:`emaphm.models.layout.NUISANCE`: relative deviations of the winding
        resistance ``"R"`` and the magnet flux ``"flux"``, and a constant load torque
        ``"load"`` in N m beside the profile's); populations then have
        ``8 + len(nuisance)`` columns.
    """

    params: ActuatorParams = field(default_factory=siemens_1fk7060)
    profile: Profile = field(default_factory=diagnostic)
    n_sub: int = 1
    theta0: float = 0.0
    kernel: str = "simd"
    fault_model: str = "paper"
    nuisance: tuple = ()

    def __post_init__(self) -> None:
        if isinstance(self.n_sub, bool) or not isinstance(self.n_sub, int) or self.n_sub < 1:
            raise ValueError(f"MonitoringModel.n_sub must be an integer >= 1, got {self.n_sub!r}")
        if self.kernel not in ("simd", "scalar"):
            raise ValueError(f"MonitoringModel.kernel must be 'simd' or 'scalar', got {self.kernel!r}")
        check_fault_model(self.fault_model)
        object.__setattr__(self, "nuisance", tuple(self.nuisance))
        from .layout import NUISANCE

        bad = [n for n in self.nuisance if n not in NUISANCE]
        if bad:
            raise ValueError(f"MonitoringModel.nuisance: unknown {bad}; choose from "
                             f"{', '.join(NUISANCE)}")
        t = self.profile.grid(self.params.inverter.T_s)
        object.__setattr__(self, "_t", t)
        object.__setattr__(self, "_ref", np.ascontiguousarray(self.profile.theta_ref(t)))
        object.__setattr__(self, "_load", np.ascontiguousarray(self.profile.load_torque(t)))
        object.__setattr__(self, "_packer", PopulationPacker(
            self.params, self.theta0, self.fault_model, n_sub=self.n_sub, nuisance=self.nuisance))

    @property
    def t(self) -> np.ndarray:
        """Control (sampling) instants [s]."""
        return self._t

    @property
    def dt(self) -> float:
        """Integration step [s]."""
        return self.params.inverter.T_s / self.n_sub

    def pack(self, K) -> tuple[np.ndarray, np.ndarray]:
        """``(P, CP)`` of the population ``K`` (n_pop, 8) for this model's kernels
        (:func:`emaphm.models.layout.pack_population` with its fault model and step)."""
        return self._packer(K)

    def _run(self, CP, P, i_target, weights, store):
        n_pop, n = CP.shape[0], self._t.size
        shape = (n_pop, n) if store else (0, 0)
        out_i = np.zeros(shape + (3,))
        outs = [np.zeros(shape) for _ in range(3)]
        fitness = np.zeros(n_pop)
        status = np.zeros(n_pop, dtype=np.int64)
        if self.kernel == "scalar":
            parts = [(slice(0, n_pop), _kernel)]
        else:
            from .monitoring_simd import LANES, _kernel as simd
            # full blocks of LANES in vector lanes; a remainder of SCALAR_TAIL or fewer
            # candidates one by one (a block costs about as much as two of them alone)
            tail = n_pop % LANES
            split = n_pop - tail if tail <= SCALAR_TAIL else n_pop
            parts = [(slice(0, split), simd), (slice(split, n_pop), _kernel)]
        for rows, kernel in parts:
            if rows.stop > rows.start:
                kernel(P, CP[rows], self._ref, self._load, self.n_sub, i_target, weights,
                       out_i[rows] if store else out_i, *(o[rows] if store else o for o in outs),
                       fitness[rows], status[rows])
        return out_i, outs, fitness, status

    def simulate_population(self, K) -> PopulationResult:
        """Traces of every candidate in ``K`` (n_pop, 8)."""
        P, CP = self.pack(K)
        empty = np.zeros((0, 3))
        out_i, (th, om, tq), _, status = self._run(CP, P, empty, empty, True)
        return PopulationResult(self._t, self._ref, th, om, out_i, tq, status)

    def simulate(self, k, nu=None) -> PopulationResult:
        """Traces of one fault vector (a population of one), with its nuisance values
        ``nu`` (default zero: the nominal parameters)."""
        nu = np.zeros(len(self.nuisance)) if nu is None else np.asarray(nu, dtype=float)
        return self.simulate_population(np.concatenate([as_k(k), nu])[None, :])

    def weighted_sse(self, K, i_target: np.ndarray, weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``sum_k sum_j weights (i_j - i_target)^2`` per candidate, without storing traces.

        ``i_target, weights`` have shape (n, 3) on the model grid :attr:`t`.
        Returns ``(fitness (n_pop,), status (n_pop,))``; diverged candidates get ``inf``,
        tripped ones (status 2) their finite fitness.
        """
        n = self._t.size
        i_target = np.ascontiguousarray(i_target, dtype=float)
        weights = np.ascontiguousarray(weights, dtype=float)
        if i_target.shape != (n, 3) or weights.shape != (n, 3):
            raise ValueError(f"target currents and weights must have shape ({n}, 3) on the model "
                             f"grid, got {i_target.shape} and {weights.shape}")
        P, CP = self.pack(K)
        _, _, fitness, status = self._run(CP, P, i_target, weights, False)
        return fitness, status

    def simulate_params(self, params: ActuatorParams) -> PopulationResult:
        """Traces of an actuator given by its (possibly faulty) parameters."""
        P, CP = pack(params, self.theta0, self.fault_model, n_sub=self.n_sub)
        empty = np.zeros((0, 3))
        out_i, (th, om, tq), _, status = self._run(CP, P, empty, empty, True)
        return PopulationResult(self._t, self._ref, th, om, out_i, tq, status)
