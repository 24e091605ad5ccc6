"""Fitness of candidate fault vectors against a measured trace (paper Eq. 4).

    e = sum_i sum_j (I_MM,ij - I_meas,ij)^2 / ((dI_meas,ij/dT)^2 + 1) * dT

summed over the samples ``i`` and the three phases ``j``; the derivative is
taken by central differences (``numpy.gradient``) on the measured currents and
divided by the step ``dT``. The weighting depends only on the measured trace,
so it is computed once. The measured trace is resampled onto the monitoring
model's grid (its control instants). Option ``mode="equivalent"`` compares the
single equivalent current instead of the three phases: the magnitude of the
current space vector ``sqrt(i_alpha^2 + i_beta^2)`` (equal to the phase
amplitude for balanced currents).

:class:`Eq4Objective` is the batch objective the optimizers see: ``(n_pop, 8)
-> (n_pop,)``, infinite for a diverged candidate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from ._text import shown
from .faults import check_fault_model
from .firmware import (MODELLED, RECORDED_CURRENT_REFERENCES, RECORDED_SPEED_REFERENCE,
                       RECORDED_VOLTAGES)
from .models.monitoring import STATUS_DIVERGED, MonitoringModel
from .params import ActuatorParams, siemens_1fk7060
from .profiles import Profile, ProfileError
from .traces import Trace, TraceError, resample, validate

__all__ = ["eq4_weights", "equivalent_current", "white_noise_sigma", "Eq4Objective",
           "FITNESS_MODES", "trace_fault_model", "on_model_grid", "aligned_currents", "effective_samples", "check_diagnosable",
           "MISFIT_LOG_MEAN", "MISFIT_LOG_STD", "MISFIT", "MISFIT_RECORDED", "MISFIT_REFERENCES", "MISFIT_P",
           "TRANSIENT_MISFIT", "TRANSIENT_WINDOW", "transient_excess",
           "misfit_p_value", "misfit_limit"]

FITNESS_MODES = ("phases", "equivalent")


def on_model_grid(trace: Trace, T_s: float) -> tuple[np.ndarray, Trace, np.ndarray]:
    """``(t_model, trace on it, load torque)``: the model's grid ``k T_s`` over the trace
    (from its first sample), the trace resampled onto it, and the load torque of the
    profile in its metadata (zero for a bench trace). TraceError if shorter than 16 steps."""
    t0 = float(trace.t[0])
    n = int(np.floor((float(trace.t[-1]) - t0) / T_s + 1e-9)) + 1
    if n < 16:
        raise TraceError(f"trace lasts {trace.duration:.3g} s, fewer than 16 control periods of "
                         f"{T_s:g} s; record at least one full diagnostic profile (0.5 s)")
    t_model = np.arange(n) * T_s
    load = np.zeros(n)
    prof = trace.meta.get("profile") if isinstance(trace.meta, dict) else None
    if prof is not None:
        try:
            load = Profile.from_dict(prof).load_torque(t_model)
        except ProfileError as exc:
            raise TraceError(f"trace metadata {exc}; correct the profile, or delete it from the "
                             "metadata (a trace without one is diagnosed with zero load)") from None
    return t_model, resample(trace, t0 + t_model), load


#: A load torque in a trace's profile above this many times the motor's peak torque is
#: not a test an actuator could follow: a unit slip or a corrupt file.
MAX_LOAD_OVER_T_MAX = 10.0


def check_load(load: np.ndarray, params: ActuatorParams) -> None:
    """Refuse a load torque [N m] (from a trace's profile) that the actuator could not
    hold: more than :data:`MAX_LOAD_OVER_T_MAX` times the motor's peak torque."""
    peak = float(np.max(np.abs(load))) if load.size else 0.0
    limit = MAX_LOAD_OVER_T_MAX * params.motor.T_max
    if peak > limit:
        raise TraceError(f"trace metadata profile: the load torque reaches {peak:.4g} N m, more "
                         f"than {MAX_LOAD_OVER_T_MAX:g} times the motor's peak torque (T_max = "
                         f"{params.motor.T_max:g} N m): no actuator follows its command under "
                         "it; check the load in the metadata (N m) or the parameters (--params)")


def aligned_currents(trace: Trace, t_model: np.ndarray, lag: float = 0.0) -> np.ndarray:
    """The trace's phase currents on the model grid, read ``lag`` [s] later: a declared
    anti-alias filter and sample delay (:meth:`emaphm.params.CurrentSensors.lag`) make
    the recorded currents trail the drive's by that much."""
    t = float(trace.t[0]) + t_model + lag
    return np.stack([np.interp(t, trace.t, trace.i_abc[:, j]) for j in range(3)], axis=1)


def noise_samples(trace: Trace, i_model: np.ndarray, T_s: float) -> np.ndarray:
    """The currents to measure the noise on: those of the coarser of the recorded and the
    model grid. A slow bench trace's own samples (resampling interpolates between them and
    would hide the noise); for a trace recorded faster than the model through an
    anti-alias filter, ``i_model`` on the model grid, where the comparison happens and the
    band-limited noise is nearly white (at the recording rate second differences cancel
    it)."""
    if float(np.median(np.diff(trace.t))) >= 0.999 * T_s:
        return np.asarray(trace.i_abc, dtype=float)
    return np.asarray(i_model, dtype=float)


def trace_fault_model(trace: Trace) -> str:
    """The fault model to diagnose ``trace`` with: the one its metadata names; ``"paper"``
    for a trace simulated by emaphm before fault models existed (metadata with a
    ``model`` but no ``fault_model``); ``"physical"`` for a bench trace."""
    meta = trace.meta if isinstance(trace.meta, dict) else {}
    fm = meta.get("fault_model")
    if fm is not None and not isinstance(fm, str):
        raise TraceError(f"trace metadata fault_model: expected 'physical' or 'paper', got "
                         f"{shown(fm)}; correct it or delete it from the metadata")
    if isinstance(fm, str) and fm:
        return check_fault_model(fm)
    return "paper" if meta.get("model") in ("reference", "monitoring") else "physical"


#: A phase current whose peak-to-peak is below this [A] is dead or disconnected.
DEAD_CHANNEL_A = 1e-3
#: Share of samples at a channel's extreme value that marks a clipped (saturated) sensor.
CLIPPED_SHARE = 0.005
#: Current noise [A rms] below which a recorded trace is taken as noise-free: a current
#: through an ADC carries at least its quantisation noise (0.2 mA for 16 bits over +-20 A).
MIN_NOISE = 1e-4


#: The fit ratio (Eq. 4 at the identified k over the trace's white-noise floor) of traces
#: the monitoring model explains -- healthy and faulty reference-plant traces of the unit
#: it is given (174 tuning runs of ``benchmarks/bench_plant.py --tune``, wrong basins
#: above 10x left out: median 1.31, 99th percentile 2.75) -- is close to lognormal with
#: this mean and standard deviation of its logarithm. Above the white-noise value 1
#: because the plant has physics the model lacks (the Stribeck drop, PWM ripple, leakage,
#: the contact resolved at a finer step). (0.298 before the monitoring model had the
#: compliant backlash contact.) The test assumes nothing about the noise being white: it compares a fit
#: with the fits of actuators the model explains, recorded through the same chain.
MISFIT_LOG_MEAN = 0.242
MISFIT_LOG_STD = 0.187
#: The same for each drive path (:data:`emaphm.firmware.DRIVE_MODELS`): the modelled
#: controller's as above; the recorded voltages' (its two residuals over the currents'
#: noise floor, :class:`emaphm.recorded.RecordedVoltageObjective`) from
#: ``benchmarks/bench_drives.py --tune`` (see :data:`MISFIT_RECORDED`).
MISFIT: dict[str, tuple[float, float]] = {MODELLED: (MISFIT_LOG_MEAN, MISFIT_LOG_STD)}
#: The recorded-voltage path's constants: the fit ratios the verdicts read on healthy and
#: faulty plant traces of calibrated production units (tuning units 80000-80003 of
#: ``benchmarks/bench_drives.py --tune``: six firmwares, both actuators, 228 fits that read
#: the unit's faults right; median 0.69, 99th percentile 3.67, largest 4.99). Wider than the
#: modelled controller's: a unit's own misfit (ratios near 2 on every trace of a few units)
#: weighs more where the currents are not closed in a loop.
MISFIT_RECORDED = (-0.287, 0.569)
MISFIT[RECORDED_VOLTAGES] = MISFIT_RECORDED
#: The current references' (and the speed reference's, which rebuilds them): tuning units
#: 80000-80003 of ``benchmarks/bench_drives.py --tune --parts D`` (emaphm's cascade plain,
#: with both feed-forwards, a 1 ms speed filter, a position PI with other limits; both
#: actuators): 154 fits that read the faults right, median 0.52, 99th percentile 1.08,
#: largest 1.26. Tighter than the recorded voltages': the model's current loop closes on its
#: own currents, as the drive's does, and takes up what the winding model misses.
MISFIT_REFERENCES = (-0.694, 0.291)
MISFIT[RECORDED_CURRENT_REFERENCES] = MISFIT_REFERENCES
MISFIT[RECORDED_SPEED_REFERENCE] = MISFIT_REFERENCES
#: False-alarm probability of the misfit test: a fit ratio whose upper tail probability
#: under that lognormal is below this is ``unexplained``.
MISFIT_P = 1e-4


def misfit_p_value(fit_ratio: float, drive_model: str = MODELLED) -> float:
    """Upper tail probability of ``fit_ratio`` for an actuator the model explains
    (lognormal, :data:`MISFIT`: :data:`MISFIT_LOG_MEAN`, :data:`MISFIT_LOG_STD` on the
    modelled controller)."""
    if not math.isfinite(fit_ratio):
        return 0.0
    if fit_ratio <= 0:
        return 1.0
    mean, std = MISFIT[drive_model]
    z = (math.log(fit_ratio) - mean) / std
    return 0.5 * math.erfc(z / math.sqrt(2.0))


def misfit_limit(p: float = MISFIT_P, drive_model: str = MODELLED) -> float:
    """The fit ratio above which the misfit test says ``unexplained`` at probability ``p``."""
    from scipy.special import ndtri

    mean, std = MISFIT[drive_model]
    return math.exp(mean - std * float(ndtri(p)))


#: A misfit this many times denser in the command's transients than elsewhere
#: (:func:`transient_excess`) points at the drive's control, not at the plant.
TRANSIENT_MISFIT = 3.0
#: How long after a change of the command's slope [s] counts as its transient.
TRANSIENT_WINDOW = 0.02


def transient_excess(theta_ref: np.ndarray, T_s: float, sq_residual: np.ndarray,
                     weights: np.ndarray, sigma: Any) -> float | None:
    """How much denser a fit's misfit is in the command's transients than elsewhere: the
    excess of the weighted squared residual ``sq_residual`` (n, c; already weighted) over
    the white noise ``sigma`` (c,) per unit of weight, in the :data:`TRANSIENT_WINDOW` after
    each change of the command's slope (steps, the ends of ramps, reversals), over the
    same in the rest. A drive whose control differs from its description misfits there
    (its loops act on the transients); a model error of the plant misfits on the ramps too.
    None where it cannot be told (no transient, no excess in them)."""
    ref = np.asarray(theta_ref, dtype=float)
    slope = np.gradient(ref) / T_s
    marks = np.flatnonzero(np.abs(np.diff(slope, prepend=slope[0])) > 1.0)
    window = int(round(TRANSIENT_WINDOW / T_s))
    transient = np.zeros(ref.size, dtype=bool)
    for m in marks:
        transient[m:m + window] = True
    if not transient.any() or transient.all():
        return None
    s2 = 0.0 if sigma is None else np.asarray(sigma, dtype=float) ** 2
    w = np.asarray(weights, dtype=float)
    excess = np.sum(np.asarray(sq_residual, dtype=float) - w * s2, axis=1)
    w = np.sum(w, axis=1)
    inside = max(float(np.sum(excess[transient])) / max(float(np.sum(w[transient])), 1e-300), 0.0)
    outside = max(float(np.sum(excess[~transient])) / max(float(np.sum(w[~transient])), 1e-300),
                  0.0)
    if inside <= 0.0:
        return None
    return inside / outside if outside > 0.0 else float("inf")


def check_diagnosable(trace: Trace) -> None:
    """Refuse currents no diagnosis can read (:class:`TraceError` naming the reason).

    A phase current that is constant (a dead or disconnected sensor), clipped (a share
    :data:`CLIPPED_SHARE` or more of its samples at its largest or smallest value, above
    0.5 A: a saturated sensor or ADC range), or a recorded trace (no ``model`` in its
    metadata) whose noise floor is zero (:func:`white_noise_sigma` below 1e-9 A, round-off,
    on every phase: a synthetic or post-processed file).
    """
    i = np.asarray(trace.i_abc, dtype=float)
    n = i.shape[0]
    for j, ph in enumerate("abc"):
        x = i[:, j]
        span = float(np.ptp(x)) if n else 0.0
        if span < DEAD_CHANNEL_A:
            raise TraceError(f"phase current i_{ph} is constant ({float(x[0]) if n else 0.0:.4g} A "
                             "throughout): a dead or disconnected current sensor cannot be "
                             "diagnosed; check the channel and record again")
        for edge in (x.max(), x.min()):
            share = float(np.mean(x == edge))
            if abs(edge) > 0.5 and share >= CLIPPED_SHARE and np.sum(x == edge) >= 5:
                raise TraceError(f"phase current i_{ph} is clipped at {edge:.4g} A ({100 * share:.1f}% "
                                 "of the samples sit on that value): the sensor or the ADC range "
                                 "saturates; widen the range and record again")
    meta = trace.meta if isinstance(trace.meta, dict) else {}
    if meta.get("model") is None and n > 3 and np.all(white_noise_sigma(i) < 1e-9):
        raise TraceError("the phase currents carry no measurement noise at all, which no recorded "
                         "trace does: the file looks synthetic or post-processed; export the raw "
                         "samples")


def eq4_weights(i_meas: np.ndarray, dT: float) -> np.ndarray:
    """Per-sample weights ``dT / ((dI/dT)^2 + 1)`` of Eq. 4, same shape as ``i_meas``."""
    i_meas = np.asarray(i_meas, dtype=float)
    dIdT = np.gradient(i_meas, axis=0) / dT
    return dT / (dIdT * dIdT + 1.0)


def white_noise_sigma(x: np.ndarray) -> np.ndarray:
    """Standard deviation of the white noise on each column of ``x`` (n, c).

    Robust, from second differences, which cancel a smooth signal:
    ``1.4826 MAD(d2) / sqrt(6)`` (``d2`` of white noise has variance ``6 sigma^2``).
    """
    x = np.asarray(x, dtype=float)
    d2 = x[2:] - 2.0 * x[1:-1] + x[:-2]
    return 1.4826 * np.median(np.abs(d2 - np.median(d2, axis=0)), axis=0) / np.sqrt(6.0)


def effective_samples(residual: np.ndarray, max_lag: int | None = None) -> tuple[float, float]:
    """Independent samples in ``residual`` (n, c): ``(n_eff, tau)``.

    ``tau = 1 + 2 sum_l rho(l)`` is the integrated autocorrelation time of each
    column (mean autocorrelation over the columns), summed over lags until the
    autocorrelation first drops below zero (the initial positive sequence of
    Geyer 1992); ``n_eff = n c / tau``.
    """
    r = np.asarray(residual, dtype=float)
    if r.ndim == 1:
        r = r[:, None]
    n, c = r.shape
    if n < 4:
        return float(n * c), 1.0
    x = r - r.mean(axis=0)
    m = 1 << int(math.ceil(math.log2(2 * n)))
    spec = np.fft.rfft(x, m, axis=0)
    acf = np.fft.irfft(spec * np.conj(spec), m, axis=0)[:n].sum(axis=1)
    if acf[0] <= 0:
        return float(n * c), 1.0
    rho = acf / acf[0]
    max_lag = n // 4 if max_lag is None else max_lag
    tau = 1.0
    for lag in range(1, max_lag):
        if rho[lag] <= 0:
            break
        tau += 2.0 * rho[lag]
    return float(n * c / tau), float(tau)


def equivalent_current(i_abc: np.ndarray) -> np.ndarray:
    """Magnitude of the current space vector, ``(..., 3) -> (...)`` [A]."""
    i_abc = np.asarray(i_abc, dtype=float)
    i_al = (2.0 * i_abc[..., 0] - i_abc[..., 1] - i_abc[..., 2]) / 3.0
    i_be = (i_abc[..., 1] - i_abc[..., 2]) / np.sqrt(3.0)
    return np.hypot(i_al, i_be)


@dataclass(frozen=True)
class Eq4Objective:
    """Eq. 4 between the monitoring model and measured currents, for a population.

    Build it with :meth:`from_trace`. Calling it with ``K`` (n_pop, 8 + nuisance)
    returns the fitness (n_pop,); it holds no state that a call changes (what a search
    evaluated is counted by the search, :class:`emaphm.problem.SearchView`).
    """

    model: MonitoringModel
    target: np.ndarray            # (n, 3) measured currents on the model grid, or (n, 1)
    weights: np.ndarray           # same shape
    mode: Literal["phases", "equivalent"] = "phases"
    noise_sigma: np.ndarray | None = None   # (3,) or (1,) A, white noise of the measured currents

    @classmethod
    def from_trace(cls, trace: Trace, params: ActuatorParams | None = None, *, n_sub: int = 1,
                   mode: str = "phases", load_torque: np.ndarray | None = None,
                   fault_model: str | None = None,
                   nuisance: tuple[str, ...] = ()) -> "Eq4Objective":
        """Fitness against ``trace``: the model replays its command from its first angle.

        The load torque is the one of the profile stored in the trace's metadata
        (a simulated trace) unless given; a bench trace without it gets zero.
        ``fault_model`` maps k3..k5 in the monitoring model (default: the trace's
        own, :func:`trace_fault_model`).
        """
        fault_model = check_fault_model(fault_model if fault_model is not None
                                        else trace_fault_model(trace))
        if mode not in FITNESS_MODES:
            raise ValueError(f"unknown fitness mode {mode!r}; choose one of {', '.join(FITNESS_MODES)}")
        params = params if params is not None else siemens_1fk7060()
        validate(trace, min_rotation=0.0)
        T_s = params.inverter.T_s
        t_model, on_grid, meta_load = on_model_grid(trace, T_s)
        n = t_model.size
        check_diagnosable(trace)
        if load_torque is None:
            load_torque = meta_load
            check_load(load_torque, params)
        else:
            load_torque = np.asarray(load_torque, dtype=float)
            if load_torque.shape != (n,):
                raise ValueError(f"load_torque must have shape ({n},) on the model grid")
        # a calibrated unit's constant load is in the model's parameters (Load.T_0, packed
        # per candidate); its current sensors' gains and offsets are removed below
        profile = Profile.from_samples(t_model, on_grid.theta_ref, load_torque)
        model = MonitoringModel(params, profile, n_sub=n_sub, theta0=float(on_grid.theta_m[0]),
                                fault_model=fault_model, nuisance=tuple(nuisance))
        i = aligned_currents(trace, t_model, params.sensors.lag())
        raw = noise_samples(trace, i, T_s)
        if not params.sensors.ideal:
            i = params.sensors.correct(i)
            raw = params.sensors.correct(raw)
        target = equivalent_current(i)[:, None] if mode == "equivalent" else i
        raw = equivalent_current(raw)[:, None] if mode == "equivalent" else raw
        return cls(model, np.ascontiguousarray(target), np.ascontiguousarray(eq4_weights(target, T_s)),
                   mode, noise_sigma=white_noise_sigma(raw))

    @property
    def n_samples(self) -> int:
        return self.target.shape[0]

    def noise_floor(self) -> float:
        """The Eq. 4 value a perfect model would reach on this trace.

        The white-noise variance of each measured current (:func:`white_noise_sigma`
        of the samples as recorded) times the sum of its weights. A fit many times
        above it has not found the actuator's k. Zero for a noise-free trace.
        """
        sigma = white_noise_sigma(self.target) if self.noise_sigma is None else self.noise_sigma
        return float(np.sum(self.weights * np.asarray(sigma) ** 2))

    def residuals(self, K: np.ndarray) -> np.ndarray:
        """The weighted residuals ``sqrt(weights) (i_model - target)`` of each candidate,
        flattened: (n_pop, n * 3) (or (n_pop, n) in ``"equivalent"`` mode), so that a row's
        sum of squares is its Eq. 4 fitness. A diverged candidate's row is ``inf``."""
        K = np.atleast_2d(np.asarray(K, dtype=float))
        pop = self.model.simulate_population(K)
        i = equivalent_current(pop.i_abc)[..., None] if self.mode == "equivalent" else pop.i_abc
        R = (np.sqrt(self.weights)[None] * (i - self.target[None])).reshape(K.shape[0], -1)
        R[pop.status == STATUS_DIVERGED] = np.inf
        return R

    def __call__(self, K: np.ndarray) -> np.ndarray:
        K = np.atleast_2d(np.asarray(K, dtype=float))
        if self.mode == "phases":
            f, _ = self.model.weighted_sse(K, self.target, self.weights)
            return f
        pop = self.model.simulate_population(K)
        d = equivalent_current(pop.i_abc) - self.target[None, :, 0]
        f = np.sum(self.weights[None, :, 0] * d * d, axis=1)
        f[pop.status == STATUS_DIVERGED] = np.inf
        return f
