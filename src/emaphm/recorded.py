"""Identification from what the drive recorded: the drive paths and their objective.

Every drive runs firmware of its own (feed-forwards, filters, a 2-DOF speed loop, an
observed speed): a monitoring model that simulates emaphm's cascade controller
(:mod:`emaphm.models.controller`) explains only drives that run it, or that
``[controller]`` describes. A drive that logs its voltage commands needs no model of its
controller at all: the **drive paths** (:data:`DRIVE_MODELS`) say what stands in for it.

=============================  ==========================================================
drive model                    what the monitoring model runs
=============================  ==========================================================
``"modelled controller"``      the drive's controller as ``[controller]`` describes it
                               (:class:`emaphm.fitness.Eq4Objective`), residual Eq. 4
``"recorded voltages"``        the winding driven by the logged voltage commands and the
                               measured angle, the mechanics by its torque as an observer
                               of the measured angle (:mod:`emaphm.models.driven`):
                               :class:`RecordedVoltageObjective`, two residuals
``"recorded current            the same, each candidate's voltages from the drive's current
references"``                  loop as ``[controller]`` and ``[inverter]`` describe it
                               (gains ``Kp_i, Ki_i``, ``decoupling``, ``emf_feedforward``,
                               ``delay_periods``, the DC link) on the candidate's own
                               currents towards the logged ``i_d_ref, i_q_ref``
``"recorded speed reference"`` the same, the q-current references from the drive's speed
                               loop as ``[controller]`` describes it (``Kp_w, Ki_w``, the
                               2-DOF weight, the speed filter, the torque feed-forward, the
                               limits) on the measured speed towards the logged
                               ``omega_ref``
=============================  ==========================================================

By default a trace takes the path of the most the drive recorded: its voltage commands
(:func:`emaphm.traces.drive_signals.voltage_form`), else its current references, else its
speed reference, else the modelled controller (:func:`drive_model_of`; ``--drive-model``
forces one). Every path but the modelled controller (:data:`DRIVEN`) models no position
loop; the current loop's integrals start at rest with the trace (a trace that begins with
the drive at rest, as a test profile does).

On those paths the drive's own proportional gain (k8, ``gain_drift``) is not
observable: no position loop is modelled (:data:`NOT_OBSERVABLE`). The inverter's dead
time and device drops (``"V_dt"``), the encoder's offset (``"angle"``) and the dry
friction's Stribeck speed (``"stribeck"``) are searched beside k there
(:data:`DRIVE_NUISANCE`), as a real inverter, encoder and gear train add them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .faults import as_k, check_fault_model
from .firmware import (DRIVE_MODELS, DRIVEN, MODELLED, RECORDED_CURRENT_REFERENCES,
                       RECORDED_SPEED_REFERENCE, RECORDED_VOLTAGES)
from .modes import CONTROLLER_MODES
from .fitness import (check_diagnosable, check_load, eq4_weights, on_model_grid,
                      trace_fault_model, white_noise_sigma)
from .models import driven
from .models.driven_simd import run as run_driven
from .models.controller import CTL_I_MAX, CTL_OMEGA_MAX, speed_loop_references
from .models.inverter import dead_time_width
from .models.layout import PopulationPacker, drive_settings
from .models.monitoring import STATUS_DIVERGED, PopulationResult
from .params import ActuatorParams, siemens_1fk7060
from .traces import Trace, TraceError, validate
from .traces.drive_signals import (applied_voltages, check_commands, control_samples,
                                   current_references, speed_reference, voltage_form)

__all__ = ["DRIVE_MODELS", "MODELLED", "RECORDED_VOLTAGES", "RECORDED_CURRENT_REFERENCES",
           "RECORDED_SPEED_REFERENCE", "DRIVEN", "DRIVE_NUISANCE", "NOT_OBSERVABLE",
           "drive_model_of", "DrivenModel", "RecordedVoltageObjective"]


#: Searched beside k on the recorded-voltage path, always: the voltage the inverter's legs
#: lose to dead time and device drops, the encoder's offset from the magnet's axis, and the
#: dry friction's Stribeck speed (which the mechanical residual sees and data sheets do not
#: state).
DRIVE_NUISANCE = ("V_dt", "angle", "stribeck")

#: The fault modes a path cannot see, by drive model: those in the drive's own position
#: controller (its gain, k8) where no position loop is modelled.
NOT_OBSERVABLE = {MODELLED: (), **{d: CONTROLLER_MODES for d in DRIVEN}}

#: What each path needs of the trace: the drive's signals it reads, as the sentence that
#: names them.
_NEEDS = {RECORDED_VOLTAGES: "the drive's voltage commands (v_a, v_b, v_c; or v_d, v_q; or "
                             "d_a, d_b, d_c with v_dc)",
          RECORDED_CURRENT_REFERENCES: "the drive's current reference i_q_ref (and i_d_ref)",
          RECORDED_SPEED_REFERENCE: "the drive's speed reference omega_ref"}


def _has(trace: Trace, drive: str) -> bool:
    if drive == RECORDED_VOLTAGES:
        return voltage_form(trace) is not None
    if drive == RECORDED_CURRENT_REFERENCES:
        return "i_q_ref" in trace.drive
    if drive == RECORDED_SPEED_REFERENCE:
        return "omega_ref" in trace.drive
    return True


def drive_model_of(trace: Trace, forced: str | None = None) -> str:
    """The drive path for ``trace``: ``forced`` where given (checked against what the trace
    carries), else the first of the recorded voltages, current references and speed
    reference that the trace has, else the modelled controller."""
    if forced is None:
        return next((d for d in DRIVEN if _has(trace, d)), MODELLED)
    if forced not in DRIVE_MODELS:
        raise ValueError(f"unknown drive model {forced!r}; choose one of "
                         + ", ".join(repr(d) for d in DRIVE_MODELS))
    if not _has(trace, forced):
        has = [d for d in DRIVEN if _has(trace, d)] + [MODELLED]
        raise TraceError(f"the drive model {forced!r} needs {_NEEDS[forced]} in the trace; this "
                         f"trace has none: identify it with {has[0]!r}")
    return forced


@dataclass(frozen=True, eq=False)
class DrivenModel:
    """The monitoring model on the paths that model no position loop (:data:`DRIVEN`), for
    one trace: what :class:`~emaphm.models.monitoring.MonitoringModel` is to the modelled
    controller (its ``params``, ``fault_model``, ``nuisance``, ``pack``, ``simulate``,
    ``simulate_population``), over the trace's own samples.

    ``u (n, 3)`` the applied phase voltages, or ``i_ref (n, 2)`` the current references
    that the drive's current loop (``params``' ``[controller]`` and ``[inverter]``) turns
    into each candidate's voltages; ``theta (n,)`` the measured angle, ``omega (n,)`` the
    measured speed, ``i_meas (n, 3)`` the measured currents (corrected for the
    sensors), ``T_load (n,)`` the profile's load on the control grid ``t`` (from 0), with
    the command ``theta_ref`` for the traces it returns.
    """

    params: ActuatorParams
    fault_model: str
    nuisance: tuple
    t: np.ndarray
    u: np.ndarray
    theta: np.ndarray
    omega: np.ndarray
    theta_ref: np.ndarray
    i_meas: np.ndarray
    T_load: np.ndarray
    n_sub: int = 1
    kernel: str = "simd"
    i_ref: np.ndarray | None = None
    _packer: Any = field(default=None, repr=False)

    def __post_init__(self) -> None:
        check_fault_model(self.fault_model)
        object.__setattr__(self, "nuisance", tuple(self.nuisance))
        object.__setattr__(self, "_packer", PopulationPacker(
            self.params, float(self.theta[0]), self.fault_model, n_sub=1,
            nuisance=self.nuisance))
        m, inv = self.params.motor, self.params.inverter
        l_1, l_2 = driven.observer_gains(inv.T_s)
        scale = driven.mechanical_scale(m.J_m + self.params.load.J_l, self.params.controller.k_T)
        object.__setattr__(self, "_observer", np.array([l_1, l_2, scale]))
        object.__setattr__(self, "_trig", driven.sample_sines(self.theta, m.p))
        I_max = self.params.controller.I_max or m.I_max
        object.__setattr__(self, "_i_0", dead_time_width(I_max))

    @property
    def theta0(self) -> float:
        return float(self.theta[0])

    @property
    def scale(self) -> float:
        """[A/rad] of the mechanical residual (:func:`emaphm.models.driven.mechanical_scale`)."""
        return float(self._observer[2])

    def pack(self, K) -> tuple[np.ndarray, np.ndarray]:
        return self._packer(K)

    def run(self, K, w_e: np.ndarray, w_m: np.ndarray, **outputs: bool):
        """:func:`emaphm.models.driven.run` of the population ``K``."""
        P, CP = self.pack(K)
        return run_driven(P, CP, self._observer, self.u, self.theta, self._trig,
                          float(self.omega[0]),
                          self.i_meas, self.T_load, w_e, w_m, self._i_0, kernel=self.kernel,
                          i_ref=self.i_ref, omega=self.omega, **outputs)

    def simulate_population(self, K) -> PopulationResult:
        K = np.atleast_2d(np.asarray(K, dtype=float))
        n = self.t.size
        zero = np.zeros((n, 3))
        _, status, out = self.run(K, zero, np.zeros(n), traces=True)
        status = np.where(status != 0, STATUS_DIVERGED, 0)
        omega = np.repeat(self.omega[None], K.shape[0], axis=0)
        result = PopulationResult(self.t, self.theta_ref, out["theta_m"], omega, out["i_abc"],
                                  out["torque"], status)
        object.__setattr__(result, "f_abc", out["f_abc"])
        return result

    def simulate(self, k, nu=None) -> PopulationResult:
        nu = np.zeros(len(self.nuisance)) if nu is None else np.asarray(nu, dtype=float)
        return self.simulate_population(np.concatenate([as_k(k), nu])[None, :])


@dataclass(frozen=True)
class RecordedVoltageObjective:
    """The objective of the paths that model no position loop (:data:`DRIVEN`; named for
    the first of them): two residuals of one pass of :mod:`emaphm.models.driven`, each
    weighted and summed as Eq. 4 is.

    ``weights (n, 3)``: Eq. 4's weights on the electrical residual (the model's currents
    less the measured ones); ``mech_weights (n,)``: ``T_s`` on the mechanical residual (the
    observer's innovation as a q current, :func:`emaphm.models.driven.mechanical_scale`).
    The fitness is their sum; its noise floor the currents' white noise times the sum of
    all weights (the mechanical residual, a torque read in amperes of q current, carries
    the currents' noise). ``residuals`` stacks both, weighted, for least squares.
    """

    model: DrivenModel
    target: np.ndarray
    weights: np.ndarray
    mech_weights: np.ndarray
    noise_sigma: np.ndarray
    mode: str = "phases"

    @classmethod
    def from_trace(cls, trace: Trace, params: ActuatorParams | None = None, *,
                   fault_model: str | None = None,
                   nuisance: tuple[str, ...] = (),
                   drive_model: str = RECORDED_VOLTAGES) -> "RecordedVoltageObjective":
        """The objective of what ``trace``'s drive recorded, on the path ``drive_model``
        (:data:`DRIVEN`: its voltage commands, current references or speed reference);
        ``nuisance`` always includes :data:`DRIVE_NUISANCE`."""
        if drive_model not in DRIVEN:
            raise ValueError(f"drive model {drive_model!r} models no drive's recording; choose "
                             "one of " + ", ".join(repr(d) for d in DRIVEN))
        fault_model = check_fault_model(fault_model if fault_model is not None
                                        else trace_fault_model(trace))
        params = params if params is not None else siemens_1fk7060()
        validate(trace, min_rotation=0.0)
        check_diagnosable(trace)
        T_s = params.inverter.T_s
        idx = control_samples(trace, T_s)
        if idx.size < 16:
            raise TraceError(f"trace lasts {trace.duration:.3g} s, fewer than 16 control periods "
                             f"of {T_s:g} s; record at least one full diagnostic profile (0.5 s)")
        drive_model_of(trace, drive_model)          # the trace has what the path reads
        omega = np.ascontiguousarray(np.asarray(trace.omega_m)[idx])
        i_ref = None
        if drive_model == RECORDED_VOLTAGES:
            u = applied_voltages(trace, idx, params.motor.p)
            check_commands(trace, u, params.inverter.V_dc)
        else:
            ctl = drive_settings(params)
            u = np.zeros((idx.size, 3))
            if drive_model == RECORDED_CURRENT_REFERENCES:
                i_ref = current_references(trace, idx, float(ctl[CTL_I_MAX]))
            else:
                w_ref = speed_reference(trace, idx, float(ctl[CTL_OMEGA_MAX]))
                i_q = np.empty(idx.size)
                speed_loop_references(w_ref, omega, np.ascontiguousarray(
                    np.asarray(trace.theta_ref, dtype=float)[idx]), ctl, i_q)
                i_ref = np.ascontiguousarray(np.column_stack([np.zeros(idx.size), i_q]))
        t_model = np.asarray(trace.t)[idx] - float(trace.t[0])
        _, _, load = on_model_grid(trace, T_s)
        load = np.resize(load, idx.size) if load.size != idx.size else load
        check_load(load, params)
        i = np.asarray(trace.i_abc)[idx]
        if not params.sensors.ideal:
            i = params.sensors.correct(i)
        nuisance = tuple(nuisance) + tuple(n for n in DRIVE_NUISANCE if n not in nuisance)
        model = DrivenModel(params, fault_model, nuisance, t_model, u,
                            np.ascontiguousarray(np.asarray(trace.theta_m)[idx]), omega,
                            np.ascontiguousarray(np.asarray(trace.theta_ref)[idx]),
                            np.ascontiguousarray(i), np.ascontiguousarray(load), i_ref=i_ref)
        w_e = np.ascontiguousarray(eq4_weights(i, T_s))
        w_m = np.full(idx.size, T_s)
        return cls(model, np.ascontiguousarray(i), w_e, w_m, white_noise_sigma(i))

    @property
    def n_samples(self) -> int:
        return self.target.shape[0]

    def noise_floor(self) -> float:
        """What a perfect model's fit would be: each phase's white noise times its weights,
        and the largest of them times the mechanical residual's weights."""
        sigma = np.asarray(self.noise_sigma)
        return float(np.sum(self.weights * sigma ** 2)
                     + np.sum(self.mech_weights) * float(np.max(sigma)) ** 2)

    def parts(self, K: np.ndarray) -> np.ndarray:
        """``(n_pop, 2)``: each candidate's electrical and mechanical weighted sums."""
        K = np.atleast_2d(np.asarray(K, dtype=float))
        sse, _, _ = self.model.run(K, self.weights, self.mech_weights)
        return sse

    def __call__(self, K: np.ndarray) -> np.ndarray:
        return np.sum(self.parts(K), axis=1)

    def residuals(self, K: np.ndarray) -> np.ndarray:
        """The weighted residuals of each candidate, (n_pop, n * 4): the currents' (as
        Eq. 4 weighs them) and the mechanical one's, so that a row's sum of squares is its
        fitness; inf for a diverged candidate."""
        K = np.atleast_2d(np.asarray(K, dtype=float))
        _, status, out = self.model.run(K, self.weights, self.mech_weights, residuals=True)
        R = out["residuals"].reshape(K.shape[0], -1)        # weighted by the kernel
        R[status != 0] = np.inf
        return R

