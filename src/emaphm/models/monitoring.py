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

The step of one candidate over one control period exists once, in
:mod:`emaphm.models.step` (:func:`~emaphm.models.step.control`,
:func:`~emaphm.models.step.substep`); three drivers run it:

* :func:`simulate_reference` -- a plain single-candidate Python loop over the step as
  plain Python, written to be read (the test oracle);
* :func:`_kernel` -- the Numba kernel, time loop outside and population
  inside, the step inlined, which returns traces or only the fitness (Eq. 4)
  against a target;
* :mod:`emaphm.models.monitoring_simd` -- the same step laid out so that the
  population runs in SIMD lanes, the default of :class:`MonitoringModel`; on the
  same sines it gives the scalar kernel's bits.

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
from ._jit import jit, variants
from .compiling import wait_for
from . import step
from ._monitoring_common import (I_DIVERGED, OMEGA_DIVERGED, STATUS_DIVERGED, STATUS_OK,
                                 STATUS_TRIPPED, _check_step, variant_key)
from .controller import N_CTL, feedforward
from .layout import (C_ECC, C_ECC_PHASE, N_CP, P_C_L, P_C_M, P_CTL, P_D_C, P_INV_I0,
                     P_J_L, P_J_M,
                     P_K_C, P_POLES, P_I_TRIP, P_T_S, P_THETA0, pack, PopulationPacker)
from .step import (N_Q, N_X, control_inline, control_plain_inline, healthy_inline,
                   substep_ideal_inline, initial_q, initial_x,
                   initial_x_inline, row_reader, row_writer, sincos_inline, substep_inline,
                   vector_reader)

__all__ = ["MonitoringModel", "PopulationResult", "simulate_reference", "I_DIVERGED",
           "OMEGA_DIVERGED", "STATUS_OK", "STATUS_DIVERGED", "STATUS_TRIPPED"]

#: Candidates left over after the SIMD kernel's full blocks that :class:`MonitoringModel`
#: runs in the scalar kernel instead: one alone costs about half a block of vector lanes
#: (``benchmarks/bench_models.py --small-batches-only`` measures it), so a lone remainder
#: (a least-squares step, a finite-difference Jacobian of 8 plus its centre) is cheaper
#: outside the lanes.
SCALAR_TAIL = 1


@jit
def _trig(thm, ecc, ecc_phase, p, fdlibm):
    """Sines and cosines of ``p theta_m`` and (with eccentricity) of ``theta_m +
    ecc_phase``: libm's, or :func:`~emaphm.models.step.sincos` (the SIMD kernel's) when
    ``fdlibm``."""
    x = p * thm
    s_g = c_g = 0.0
    if fdlibm:
        s_e, c_e = sincos_inline(x)
        if ecc != 0.0:
            s_g, c_g = sincos_inline(thm + ecc_phase)
    else:
        s_e = math.sin(x)
        c_e = math.cos(x)
        if ecc != 0.0:
            g = thm + ecc_phase
            c_g = math.cos(g)
            s_g = math.sin(g)
    return s_e, c_e, s_g, c_g


#: A candidate's constants (its CP row) and the drive's settings (the head of P), as the
#: step's tuples; the plant's and the drive's state to and from their arrays.
_read_c = row_reader(N_CP, "read_c")
_read_x = row_reader(N_X, "read_x")
_read_q = row_reader(N_Q, "read_q")
_write_x = row_writer(N_X, "write_x")
_write_q = row_writer(N_Q, "write_q")
#: a drive without options keeps the trip, the sum and the integrals (the rest of its state
#: is what the options read)
_write_q_plain = row_writer(6, "write_q_plain")
_read_ctl = vector_reader(N_CTL, "read_ctl")


def _kernel(P, CP, theta_ref, T_load, n_sub, i_target, weights,
            out_i, out_theta, out_omega, out_torque, fitness, status, out_f, fdlibm=False):
    """Simulate ``CP.shape[0]`` candidates over ``theta_ref.shape[0]`` control periods,
    one candidate after another, each period :func:`~emaphm.models.step.control` and
    ``n_sub`` times :func:`~emaphm.models.step.substep` (inlined) on libm's sines
    (``fdlibm``: on the SIMD kernel's, for the test that they agree bit for bit).

    Shapes: ``P (N_P,)``, ``CP (n_pop, N_CP)``, ``theta_ref, T_load (n,)``;
    ``i_target, weights (n, 3)`` or ``(0, 3)`` for no fitness; ``out_i
    (n_pop, n, 3)``, ``out_theta, out_omega, out_torque (n_pop, n)`` or
    zero-sized for no traces; ``fitness, status (n_pop,)`` written in place; ``out_f
    (n_pop, n, 3)`` the fault loops' currents, or zero-sized (the SIMD kernel has no such
    output). ``fitness`` accumulates ``sum_k sum_j weights[k, j] (i_j - i_target[k, j])^2``.
    ``P, CP`` must be packed for ``n_sub`` (ValueError otherwise).

    Runs the compiled variant of :func:`_kernel_body` for the drive (its options at their
    defaults or not) and the inverter (no candidate losing a volt to dead time, or some):
    each variant is compiled the first time it is needed.
    """
    key = variant_key(P, CP)
    wait_for(key)                      # a child compiling it (emaphm.models.warm)
    _VARIANTS[key](P, CP, theta_ref, T_load, n_sub, i_target, weights, out_i, out_theta,
                   out_omega, out_torque, fitness, status, out_f, fdlibm)


def _kernel_body(P, CP, theta_ref, T_load, n_sub, i_target, weights,
                 out_i, out_theta, out_omega, out_torque, fitness, status, out_f, fdlibm=False):
    """:func:`_kernel`'s loop, its steps named by the variant (:data:`_VARIANTS`)."""
    _check_step(P, n_sub)
    n_pop = CP.shape[0]
    n = theta_ref.shape[0]
    store = out_i.shape[0] == n_pop and n_pop > 0
    loops = out_f.shape[0] == n_pop and n_pop > 0
    with_fit = i_target.shape[0] == n
    p = P[P_POLES]
    T_s = P[P_T_S]
    dt = T_s / n_sub
    J_m, C_m, J_l, C_l = P[P_J_M], P[P_C_M], P[P_J_L], P[P_C_L]
    K_c, D_c = P[P_K_C], P[P_D_C]
    ctl = _read_ctl(P, P_CTL)
    I_trip = P[P_I_TRIP]
    # state: the plant's x (:data:`~emaphm.models.step.X_FIELDS`) and the drive's q
    X = np.zeros((n_pop, N_X))
    Q = np.zeros((n_pop, N_Q))
    for j in range(n_pop):
        _write_x(X, 0, j, initial_x_inline(P[P_THETA0]))
        fitness[j] = 0.0
        status[j] = STATUS_OK
    ta = tb = tc = wa = wb = wc = 0.0
    for k in range(n):
        if with_fit:
            ta, tb, tc = i_target[k, 0], i_target[k, 1], i_target[k, 2]
            wa, wb, wc = weights[k, 0], weights[k, 1], weights[k, 2]
        ref, w_ff, T_ff = feedforward(theta_ref[k], theta_ref[max(k - 1, 0)],
                                      theta_ref[max(k - 2, 0)], ctl)
        period = (ta, tb, tc, wa, wb, wc, ref, w_ff, T_ff)
        mech = (T_load[k], J_m, C_m, J_l, C_l, K_c, D_c, dt, P[P_INV_I0])
        for j in range(n_pop):
            if status[j] == STATUS_DIVERGED:
                continue
            c = _read_c(CP, 0, j)
            x = _read_x(X, 0, j)
            ecc, ecc_phase = c[C_ECC], c[C_ECC_PHASE]
            s_e, c_e, s_g, c_g = _trig(x[0], ecc, ecc_phase, p, fdlibm)
            q, u_a, u_b, u_c = control_inline(x, _read_q(Q, 0, j), c, ctl, I_trip, period,
                                              s_e, c_e)
            for s in range(n_sub):
                if s > 0:
                    s_e, c_e, s_g, c_g = _trig(x[0], ecc, ecc_phase, p, fdlibm)
                if s == 0 and store:
                    out_i[j, k, 0] = x[9]
                    out_i[j, k, 1] = x[10]
                    out_i[j, k, 2] = x[11]
                    out_theta[j, k] = x[0]
                    out_omega[j, k] = x[1]
                if s == 0 and loops:
                    out_f[j, k, 0] = x[6]
                    out_f[j, k, 1] = x[7]
                    out_f[j, k, 2] = x[8]
                x, tq = substep_inline(x, c, mech, s_e, c_e, s_g, c_g, u_a, u_b, u_c)
                if s == 0 and store:
                    out_torque[j, k] = tq
            if not healthy_inline(x[9], x[10], x[11], x[1], x[0]):
                status[j] = STATUS_DIVERGED
                fitness[j] = np.inf
                continue
            fitness[j] = q[1]
            if q[0] != 0.0:
                status[j] = STATUS_TRIPPED
            _write_q(Q, 0, j, q)
            _write_x(X, 0, j, x)


#: The compiled variants of :func:`_kernel_body` by ``(plain drive, ideal inverter)``
#: (:func:`~emaphm.models._monitoring_common.variant_key`), each cached under its own name.
_VARIANTS = variants(
    _kernel_body, jit,
    drive={True: dict(control_inline=control_plain_inline, _write_q=_write_q_plain),
           False: dict(control_inline=control_inline, _write_q=_write_q)},
    inverter={True: dict(substep_inline=substep_ideal_inline),
              False: dict(substep_inline=substep_inline)})


def simulate_reference(params: ActuatorParams, k, profile: Profile, n_sub: int = 1,
                       theta0: float = 0.0, fault_model: str = "paper") -> dict[str, np.ndarray]:
    """Readable single-candidate monitoring model in plain Python (slow): the test oracle.

    The step of :mod:`emaphm.models.step` as plain Python (:func:`~emaphm.models.step.control`,
    :func:`~emaphm.models.step.substep`) on libm's sines, with the winding step of
    :func:`emaphm.models.layout.pack` for ``apply_faults(params, k, fault_model)``.
    Returns a dict of arrays ``t, theta_ref, theta_m, omega_m, i_abc (n, 3), f_abc (n,
    3)`` (fault-loop currents) ``, torque`` sampled at the control instants.
    """
    from ..faults import apply_faults  # local: keep module import light

    faulty = apply_faults(params, k, fault_model)
    m = faulty.motor
    T_s = faulty.inverter.T_s
    t = profile.grid(T_s)
    ref = profile.theta_ref(t)
    T_load = profile.load_torque(t)
    P, cp = pack(faulty, theta0, fault_model, n_sub=n_sub)
    c = tuple(float(v) for v in cp[0])
    ctl = tuple(float(v) for v in P[P_CTL:P_CTL + N_CTL])
    x, q = initial_x(theta0), initial_q()
    out = {name: np.zeros(t.size) for name in ("theta_m", "omega_m", "torque")}
    out["i_abc"] = np.zeros((t.size, 3))
    out["f_abc"] = np.zeros((t.size, 3))
    for n in range(t.size):
        out["theta_m"][n], out["omega_m"][n] = x[0], x[1]
        out["i_abc"][n] = x[9:12]
        out["f_abc"][n] = x[6:9]
        mech = (T_load[n], m.J_m, m.C_m, faulty.load.J_l, faulty.load.C_l, P[P_K_C], P[P_D_C],
                T_s / n_sub, P[P_INV_I0])
        period = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0) + step.feedforward(
            ref[n], ref[max(n - 1, 0)], ref[max(n - 2, 0)], ctl)
        q, u_a, u_b, u_c = step.control(x, q, c, ctl, P[P_I_TRIP], period,
                                        *_libm_trig(m.p * x[0], 0.0)[:2])
        for s in range(n_sub):
            s_e, c_e = _libm_trig(m.p * x[0], 0.0)[:2]
            s_g, c_g = _libm_trig(x[0] + m.ecc_phase, m.ecc)[2:]
            x, tq = step.substep(x, c, mech, s_e, c_e, s_g, c_g, u_a, u_b, u_c)
            if s == 0:
                out["torque"][n] = tq
    out.update(t=t, theta_ref=ref)
    return out


def _libm_trig(x: float, ecc: float) -> tuple[float, float, float, float]:
    """``(sin x, cos x)`` twice over, the second pair zero without eccentricity (it is
    not read then), as the scalar kernel's :func:`_trig`."""
    s, c = math.sin(x), math.cos(x)
    return s, c, (s if ecc != 0.0 else 0.0), (c if ecc != 0.0 else 0.0)


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

    def _run(self, CP, P, i_target, weights, store, loops=False):
        n_pop, n = CP.shape[0], self._t.size
        shape = (n_pop, n) if store else (0, 0)
        out_i = np.zeros(shape + (3,))
        outs = [np.zeros(shape) for _ in range(3)]
        out_f = np.zeros(((n_pop, n) if loops else (0, 0)) + (3,))
        fitness = np.zeros(n_pop)
        status = np.zeros(n_pop, dtype=np.int64)
        # the compiled variant of both kernels for this drive and inverter (_kernel does the
        # same per call; here once for the population's parts)
        key = variant_key(P, CP)
        wait_for(key)
        scalar = (_VARIANTS[key], (False,))    # libm's sines, as _kernel passes them
        if self.kernel == "scalar" or loops:     # the loops' currents: the scalar kernel's
            parts = [(slice(0, n_pop), scalar)]
        else:
            from .monitoring_simd import LANES, _VARIANTS as SIMD
            # full blocks of LANES in vector lanes; a remainder of SCALAR_TAIL or fewer
            # candidates one by one (a block costs about as much as two of them alone)
            tail = n_pop % LANES
            split = n_pop - tail if tail <= SCALAR_TAIL else n_pop
            parts = [(slice(0, split), (SIMD[key], ())), (slice(split, n_pop), scalar)]
        for rows, (kernel, extra) in parts:
            if rows.stop > rows.start:
                kernel(P, CP[rows], self._ref, self._load, self.n_sub, i_target, weights,
                       out_i[rows] if store else out_i, *(o[rows] if store else o for o in outs),
                       fitness[rows], status[rows], out_f[rows] if loops else out_f, *extra)
        return (out_i, outs, fitness, status) + ((out_f,) if loops else ())

    def simulate_population(self, K) -> PopulationResult:
        """Traces of every candidate in ``K`` (n_pop, 8)."""
        P, CP = self.pack(K)
        empty = np.zeros((0, 3))
        out_i, (th, om, tq), _, status = self._run(CP, P, empty, empty, True)
        return PopulationResult(self._t, self._ref, th, om, out_i, tq, status)

    def loop_currents(self, K) -> np.ndarray:
        """The fault loops' currents ``f_abc (n_pop, n, 3)`` [A] of every candidate in ``K``
        at the control instants (zero where a phase has no loop: the ``"paper"`` fault
        model has none), from the scalar kernel."""
        P, CP = self.pack(K)
        empty = np.zeros((0, 3))
        return self._run(CP, P, empty, empty, False, loops=True)[4]

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
