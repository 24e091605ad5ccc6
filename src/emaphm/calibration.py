"""Commissioning: estimate how a healthy unit differs from its data sheet.

No real actuator matches its data-sheet preset to a few percent, and a
model-based diagnosis reads every mismatch as a fault. :func:`calibrate`
fits, to one or more traces of a unit known to be healthy, the parameters in
which units differ (the *nuisance* parameters, :data:`PARAMETERS`):

=============  =====================================================  ===========
name           what it scales                                         unit
=============  =====================================================  ===========
``J``          motor and load inertia (one factor)                    relative
``flux``       magnet flux: back-EMF coefficient = torque constant    relative
``R``          winding resistance (temperature)                       relative
``L``          synchronous inductance                                 relative
``friction``   dry friction FSJ and FDJ (one factor)                  relative
``viscous``    viscous friction C_m                                   relative
``gain_a..c``  each current sensor's gain                             relative
``offset_a..c`` each current sensor's offset                          A
``load``       a constant load torque the bench does not report       N m
=============  =====================================================  ===========

Method: :func:`emaphm.optim.lsq.least_squares_batched` (SciPy's trust-region
reflective, bounded) on the monitoring model's residuals, weighted as in
Eq. 4 and scaled by each trace's white-noise level, with a finite-difference
Jacobian (exact columns for the sensor gains and offsets, which act after the
model). Standard errors come from ``s^2 (J^T J)^-1``, inflated by the
residual's integrated autocorrelation time (a misfit that is not white noise
carries fewer independent samples than it has), plus the model discrepancy of
each parameter measured on plant units (:data:`DISCREPANCY`).

Two kinds of parameters are kept at their data-sheet values, named, and the
fit repeated without them: those the profile does not *identify* (a typical
deviation, :data:`TYPICAL`, changes the fit ratio by less than the misfit that
model error leaves, at least :data:`MIN_EFFECT`: on the diagnostic profile the
current loop hides the winding resistance and inductance, which would absorb
model error instead), and the less certain one of a pair the profile cannot
*separate* (``|correlation| > CORRELATION_LIMIT``: inertia and flux both scale
the current), or that the others predict together (a multiple correlation above
:data:`MULTIPLE_CORRELATION_LIMIT`: flux, inertia, friction, load and the sensor
gains can all be off together). The others then absorb them, which is what the
monitoring model needs to reproduce the unit's currents.

The result is an :class:`~emaphm.params.ActuatorParams` (the unit's, with a
``[calibration]`` section holding the date, the sources, each estimate and
its standard error) that ``diagnose --params`` and the health history read. The
section carries its provenance: the emaphm version, a SHA-256 of each source trace's
signals (:func:`trace_digest`) and a digest of the section and of the parameter values
the calibration set (:func:`emaphm.params.calibration_digest`), so that a parameter file
whose calibration was written or edited by hand is told apart when it is read
(:func:`emaphm.params.load_params` warns).
"""

from __future__ import annotations

import datetime as _dt
import math
import time
from dataclasses import dataclass, field, replace
from typing import Any, Callable, Sequence

import numpy as np

from .faults import K_NOMINAL
from .fitness import (MIN_NOISE, TRANSIENT_MISFIT, aligned_currents, check_diagnosable,
                      effective_samples, eq4_weights, noise_samples, on_model_grid,
                      transient_excess, white_noise_sigma)
from .params import (CALIBRATED_DRIVE_FIELDS, ActuatorParams, Calibration, CurrentSensors,
                     calibration_digest, resolve_params, siemens_1fk7060)
from .search import nuisance_start
from .profiles import Profile
from .traces import Trace, TraceError, fingerprint, validate

__all__ = ["PARAMETERS", "CORRELATION_LIMIT", "MULTIPLE_CORRELATION_LIMIT", "HEALTHY_FIT_LIMIT",
           "CalibrationError", "CalibrationResult", "calibrate", "select_identifiable",
           "TOLERANCE_CHECKED", "DRIVE_PARAMETERS", "DRIVE_SETTINGS", "drive_bounds",
           "estimates", "apply_deviations", "trace_digest"]

#: Calibrated parameters: name -> (lower bound, upper bound, unit) of the deviation.
PARAMETERS: dict[str, tuple[float, float, str]] = {
    "J": (-0.5, 1.0, "relative"), "flux": (-0.3, 0.3, "relative"),
    "R": (-0.5, 1.0, "relative"), "L": (-0.5, 0.5, "relative"),
    "friction": (-0.9, 3.0, "relative"), "viscous": (-0.99, 5.0, "relative"),
    "gain_a": (-0.2, 0.2, "relative"), "gain_b": (-0.2, 0.2, "relative"),
    "gain_c": (-0.2, 0.2, "relative"),
    "offset_a": (-1.0, 1.0, "A"), "offset_b": (-1.0, 1.0, "A"), "offset_c": (-1.0, 1.0, "A"),
    "load": (-2.0, 2.0, "N m"),
}
_NAMES = tuple(PARAMETERS)

#: Estimated beside them on traces with the drive's voltage commands (the recorded-voltage
#: path, :mod:`emaphm.recorded`): the voltage the inverter's legs lose to dead time and
#: device drops [V], the encoder's offset [rad, electrical] and the dry friction's Stribeck
#: speed [rad/s]. A diagnosis searches them
#: again every time (:data:`emaphm.recorded.DRIVE_NUISANCE`); the calibration estimates
#: them so that the unit's own parameters do not absorb them.
DRIVE_PARAMETERS: dict[str, tuple[float, float, str]] = {
    "V_dt": (0.0, 30.0, "V"), "angle": (-0.2, 0.2, "rad (electrical)"),
    "stribeck": (0.0, 5.0, "rad/s")}
PARAMETERS.update(DRIVE_PARAMETERS)

#: The drive's settings a calibration estimates where the user does not know them
#: (``calibrate(drive_unknown=...)``, ``emaphm calibrate --drive-unknown``): name ->
#: (section of the parameters, lowest value, highest value, unit, where a search starts, as
#: a value; None: at the stated one). Values, not deviations: the deviation's bounds are
#: these less the stated value. The gains are relative to the stated ones (their bounds
#: too). The filters start off zero, where a filter of a microsecond does nothing and the
#: fit cannot tell which way to go. The computation delay (0 or 1 period) is no continuous
#: setting: describe it.
DRIVE_SETTINGS: dict[str, tuple[str, float, float, str, float | None]] = {
    n: (CALIBRATED_DRIVE_FIELDS[n], *spec) for n, spec in {
        "velocity_feedforward": (0.0, 1.5, "", None),
        "torque_feedforward": (0.0, 1.5, "", None),
        "speed_filter_s": (0.0, 5e-3, "s", 2.5e-4),
        "current_reference_filter_s": (0.0, 2e-3, "s", 2.5e-4),
        "speed_reference_weight": (0.0, 1.0, "", None),
        "Kp": (-0.5, 1.0, "relative", None), "Kp_w": (-0.5, 1.0, "relative", None),
        "Ki_w": (-0.5, 1.0, "relative", None), "Kp_i": (-0.5, 1.0, "relative", None),
        "Ki_i": (-0.5, 1.0, "relative", None)}.items()}
PARAMETERS.update({n: (lo, hi, unit) for n, (_, lo, hi, unit, _) in DRIVE_SETTINGS.items()})

#: A typical deviation of each parameter (the width of the production tolerance,
#: :data:`emaphm.units.DEFAULT_TOLERANCES`), in the parameter's unit.
TYPICAL: dict[str, float] = {"J": 0.2, "flux": 0.1, "R": 0.25, "L": 0.1, "friction": 0.4,
                             "viscous": 0.4, "gain_a": 0.06, "gain_b": 0.06, "gain_c": 0.06,
                             "offset_a": 0.04, "offset_b": 0.04, "offset_c": 0.04, "load": 0.2,
                             "V_dt": 5.0, "angle": 0.05, "stribeck": 1.0,
                             # the drive's settings: a change a tuning would make
                             "velocity_feedforward": 0.3, "torque_feedforward": 0.3,
                             "speed_filter_s": 2.5e-4, "current_reference_filter_s": 2.5e-4,
                             "speed_reference_weight": 0.2, "Kp": 0.2, "Kp_w": 0.2,
                             "Ki_w": 0.2, "Kp_i": 0.2, "Ki_i": 0.2}

#: The forward difference's step of a parameter whose unit is far below one (seconds of a
#: filter): ``STEP[n] * max(1, |x|)`` instead of ``1e-3 * max(1, |x|)``.
STEP: dict[str, float] = {"speed_filter_s": 1e-6, "current_reference_filter_s": 1e-6}

#: A parameter whose typical deviation moves the fit ratio (Eq. 4 over the noise floor)
#: by less than this -- or less than the fit's own excess over the floor, which is what
#: model error leaves -- is not identifiable on the profile: left free, it would absorb
#: model error instead of measuring the unit.
MIN_EFFECT = 0.1

#: Parameters that switch a piece of physics on, by the value that switches it off: their
#: effect on the fit ratio is not the local one of a typical deviation (the drop's effect
#: saturates: at the plant's own Stribeck speed the slope of the fit is flat) but what
#: switching it off at the fit does (measured on ema-270v-750w units 1-3: the Stribeck
#: drop's local effect 0.12, under the two-level fit's excess of 0.6, where switching it
#: on takes the fit ratios from 1.5-1.7 to 1.06-1.34 and its estimates to 0.97-1.23 rad/s
#: of the plant's 1 rad/s; without it unit 1 was refused at friction +37 %). Such a switch
#: is kept where it improves the fit by :data:`MIN_EFFECT`, not by the fit's excess: it is
#: physics the unit has, and the excess is other model error (ema-270v-750w unit
#: 1045281918: switched on, the fit improves by 0.31 of 1.6).
SWITCHED = {"stribeck": 0.0}

#: Model discrepancy of each estimate: the RMS of (estimate - truth) over production
#: units on the reference plant, which has physics the monitoring model lacks
#: (``benchmarks/bench_commissioning.py --tune``: 60 units on tuning seeds; the sensor
#: gains and offsets pooled over the phases; the inertia against the ratio the currents
#: see, ``(1 + dJ) / (1 + dflux) - 1``, since the flux is kept on every one of them
#: (:data:`MULTIPLE_CORRELATION_LIMIT`); the flux's value is from the earlier run in
#: which 8 of them estimated it, and R, L and viscous, identifiable on none, from a run
#: on 1-2 units). Added in quadrature to the statistical standard error, which alone
#: covers noise, not model error. The flux and the gains' common mode trade with the
#: inertia.
DISCREPANCY: dict[str, float] = {
    "J": 0.013, "flux": 0.036, "R": 0.061, "L": 0.037, "friction": 0.064, "viscous": 0.54,
    "gain_a": 0.013, "gain_b": 0.013, "gain_c": 0.013,
    "offset_a": 0.0018, "offset_b": 0.0018, "offset_c": 0.0018, "load": 0.0017}

#: A pair of estimates more correlated than this is not separable on the profile.
CORRELATION_LIMIT = 0.95

#: Nor is an estimate that the *others together* predict this well (its multiple
#: correlation, from the variance inflation factor: 0.975 is a VIF of 20). Magnet flux,
#: inertia, friction, load and the sensor gains scale the currents jointly (the current
#: loop hides the back-EMF that alone tells the flux apart), so a unit can fit its
#: traces with all of them off together while no pair passes :data:`CORRELATION_LIMIT`:
#: production unit 20003 calibrated to flux and inertia both +17 % and friction +45 %
#: (truth -4.5 %, -1.2 %, +14 %), every pair below 0.95, the flux's multiple correlation
#: 0.993. Measured on the tuning units (``bench_commissioning.py --tune`` seeds, 60
#: units): where the flux survives the pairwise rule (8 units) its multiple correlation is
#: 0.981-0.994; once the flux is kept, no other estimate passes 0.965.
MULTIPLE_CORRELATION_LIMIT = 0.975

#: On the recorded-voltage path, an estimate the others predict (a correlation past the
#: limits) is still kept where the fit without it is this many times worse.
SEPARABLE_WORSE = 1.5

#: A trace whose calibrated fit stays above this many times its noise floor (Eq. 4 of
#: white noise) does not look like a healthy unit the model describes.
HEALTHY_FIT_LIMIT = 4.0

#: The estimates checked against the production tolerances (:class:`emaphm.units.Tolerances`
#: field of each): one whose whole 95 % interval lies outside its tolerance is no unit of this
#: design, but a model that does not describe it (a drive whose control differs from
#: ``[controller]`` calibrates to sensor gains of +10 % and an inertia of -8 %). Not checked:
#: the winding resistance (its temperature), the unreported load (the bench's), the sensor
#: offsets (a sensor's own, which a calibration is there to measure), and the inductance and
#: viscous friction, which the diagnostic profile hardly identifies.
TOLERANCE_CHECKED = {"J": "J", "flux": "flux", "friction": "friction", "gain_a": "sensor_gain",
                     "gain_b": "sensor_gain", "gain_c": "sensor_gain"}


class CalibrationError(ValueError):
    """The traces cannot calibrate the unit (not healthy, too short, no motion)."""


#: SHA-256 of a trace's signals (:func:`emaphm.traces.fingerprint`): what a calibration
#: records of each of its sources.
trace_digest = fingerprint


def apply_deviations(params: ActuatorParams, dev: dict[str, float]) -> ActuatorParams:
    """``params`` with the deviations ``dev`` (names of :data:`PARAMETERS`) applied."""
    d = {n: float(dev.get(n, 0.0)) for n in _NAMES}
    m, tr, ld = params.motor, params.transmission, params.load
    motor = replace(m, J_m=m.J_m * (1 + d["J"]), c0=tuple(c * (1 + d["flux"]) for c in m.c0),
                    R=tuple(r * (1 + d["R"]) for r in m.R), L=tuple(x * (1 + d["L"]) for x in m.L),
                    C_m=m.C_m * (1 + d["viscous"]))
    trans = replace(tr, FSJ=tr.FSJ * (1 + d["friction"]), FDJ=tr.FDJ * (1 + d["friction"]))
    if "stribeck" in dev:
        # a value, not a deviation: the speed of the unit's Stribeck drop (0: none)
        trans = replace(trans, omega_s=max(float(dev["stribeck"]), 0.0))
    load = replace(ld, J_l=ld.J_l * (1 + d["J"]), T_0=ld.T_0 + d["load"])
    s = params.sensors
    sensors = replace(s, gain=tuple(g * (1 + d[f"gain_{p}"]) for g, p in zip(s.gain, "abc")),
                      offset=tuple(o + d[f"offset_{p}"] for o, p in zip(s.offset, "abc")))
    # the drive's own settings stay the data sheet's (emaphm.params.Controller.resolved)
    drive = params.controller.kept_for(m, ld, motor, load)
    out = replace(params, motor=motor, transmission=trans, load=load, sensors=sensors,
                  controller=drive)
    return _drive_settings(out, params, dev)


def _drive_settings(out: ActuatorParams, stated: ActuatorParams,
                    dev: dict[str, float]) -> ActuatorParams:
    """``out`` with the drive settings in ``dev`` (:data:`DRIVE_SETTINGS`) set: each the
    ``stated`` one plus its deviation (times one plus it, for a relative one)."""
    sections: dict[str, dict[str, float]] = {}
    for n, d in dev.items():
        if n in DRIVE_SETTINGS:
            sec, lo, hi, unit, _ = DRIVE_SETTINGS[n]
            v = getattr(getattr(stated, sec), n)
            sections.setdefault(sec, {})[n] = (v * (1.0 + float(d)) if unit == "relative"
                                               else min(max(v + float(d), lo), hi))
    for sec, values in sections.items():
        out = replace(out, **{sec: replace(getattr(out, sec), **values)})
    return out


def drive_bounds(params: ActuatorParams, names: Sequence[str]) -> dict[str, tuple[float, float]]:
    """The deviations' bounds of the drive settings ``names`` (:data:`DRIVE_SETTINGS`) from
    the values ``params`` states, and where their search starts (as deviations)."""
    out = {}
    for n in names:
        sec, lo, hi, unit, start = DRIVE_SETTINGS[n]
        if unit == "relative":
            out[n] = (lo, hi, 0.0)
            continue
        v = float(getattr(getattr(params, sec), n))
        x0 = 0.0 if start is None or v != 0.0 else start - v
        out[n] = (lo - v, hi - v, min(max(x0, lo - v), hi - v))
    return out


@dataclass(frozen=True)
class _Target:
    """One healthy trace on the monitoring model's grid."""

    source: str
    theta_ref: np.ndarray
    load: np.ndarray
    theta0: float
    i_meas: np.ndarray          # (n, 3) as recorded (sensor gains and offsets in it)
    w: np.ndarray               # (n, 3) Eq. 4 weights
    sqrt_w: np.ndarray          # (n, 3) sqrt of the Eq. 4 weights, over the noise sigma
    floor: float                # Eq. 4 value of white noise alone
    floor_sigma: np.ndarray     # (3,) the white noise of each phase [A]
    #: the test profile per control period T_s [s] (the load parameter is packed per
    #: candidate, ``Load.T_0``, not in the profile)
    profiles: dict = field(default_factory=dict, compare=False, repr=False)


def _target(trace: Trace, params: ActuatorParams, source: str) -> _Target:
    validate(trace)
    T_s = params.inverter.T_s
    try:
        t_model, on, load = on_model_grid(trace, T_s)
        check_diagnosable(trace)
    except TraceError as exc:
        raise CalibrationError(f"{source}: {exc}") from None
    i = aligned_currents(trace, t_model, params.sensors.lag())
    sigma = white_noise_sigma(noise_samples(trace, i, T_s))
    if not np.all(sigma > MIN_NOISE):
        raise CalibrationError(f"{source}: the phase currents carry no measurement noise (a "
                               "simulated trace without sensors, or a dead channel); calibrate "
                               "on recorded traces")
    w = eq4_weights(i, T_s)
    return _Target(source, np.ascontiguousarray(on.theta_ref), load, float(on.theta_m[0]), i,
                   w, np.sqrt(w) / sigma, float(np.sum(w * sigma ** 2)), sigma)


class _DrivenTarget:
    """One healthy trace with the drive's voltage commands (or current or speed references),
    on its path that models no position loop
    (:class:`emaphm.recorded.RecordedVoltageObjective`): its residuals (currents and
    mechanics, each over the currents' white noise) at a unit's parameters."""

    columns = 4

    def __init__(self, trace: Trace, params: ActuatorParams, source: str,
                 drive_model: str = "recorded voltages") -> None:
        from .recorded import DRIVE_NUISANCE, RecordedVoltageObjective

        validate(trace)
        try:
            obj = RecordedVoltageObjective.from_trace(
                trace, replace(params, sensors=CurrentSensors()), fault_model="physical",
                nuisance=DRIVE_NUISANCE, drive_model=drive_model)
        except TraceError as exc:
            raise CalibrationError(f"{source}: {exc}") from None
        sigma = np.asarray(obj.noise_sigma)
        if not np.all(sigma > MIN_NOISE):
            raise CalibrationError(f"{source}: the phase currents carry no measurement noise (a "
                                   "simulated trace without sensors, or a dead channel); "
                                   "calibrate on recorded traces")
        self.source, self.model, self.i_raw = source, obj.model, obj.model.i_meas
        s_max = float(np.max(sigma))
        self.w = np.concatenate([obj.weights, obj.mech_weights[:, None]], axis=1)
        self.over_sigma = 1.0 / np.append(sigma, s_max)[None, :]
        self.sqrt_w = np.sqrt(self.w) * self.over_sigma
        self.floor = float(np.sum(self.w * np.append(sigma, s_max)[None, :] ** 2))
        self.size = self.w.size

    def run(self, params: ActuatorParams, dev: dict[str, float], **outputs: bool):
        """The trace's driven model (its recorded voltages, or references through the
        drive's loops) at a unit's ``params`` (its sensors' gains and offsets undone on the
        measured currents) and the inverter's and encoder's values in ``dev``."""
        from .recorded import DrivenModel

        s = params.sensors
        i = np.ascontiguousarray(s.correct(self.i_raw)) if not s.ideal else self.i_raw
        m = self.model
        names = tuple(DRIVE_PARAMETERS)
        model = DrivenModel(replace(params, sensors=CurrentSensors()), "physical", names, m.t,
                            m.u, m.theta, m.omega, m.theta_ref, i, m.T_load, i_ref=m.i_ref)
        K = np.concatenate([K_NOMINAL, [dev.get(n, 0.0) for n in names]])[None]
        return model.run(K, self.w[:, :3], self.w[:, 3], **outputs)

    def residual(self, params: ActuatorParams, dev: dict[str, float]) -> np.ndarray | None:
        """The normalised residuals (currents, mechanics) at ``params``, or None where the
        model diverged."""
        _, status, out = self.run(params, dev, residuals=True)
        if status[0] != 0:
            return None
        return (out["residuals"][0] * self.over_sigma).ravel()       # weighted by the kernel

    def fit(self, params: ActuatorParams, dev: dict[str, float]):
        """``(t, measured, model)`` currents and the fit ratio at ``params``."""
        sse, _, out = self.run(params, dev, traces=True)
        s = params.sensors
        model_i = out["i_abc"][0] * np.asarray(s.gain) + np.asarray(s.offset)
        return (self.model.t, self.i_raw, model_i), float(np.sum(sse[0])) / self.floor


def _model_currents(params: ActuatorParams, tg: _Target) -> np.ndarray:
    from .models.monitoring import MonitoringModel

    T_s = params.inverter.T_s
    prof = tg.profiles.get(T_s)
    if prof is None:
        prof = tg.profiles[T_s] = Profile.from_samples(
            np.arange(tg.theta_ref.size) * T_s, tg.theta_ref, tg.load)
    mm = MonitoringModel(params, prof, theta0=tg.theta0, fault_model="physical")
    r = mm.simulate(K_NOMINAL)
    i = r.i_abc[0]
    s = params.sensors
    return i * np.asarray(s.gain) + np.asarray(s.offset)


@dataclass(frozen=True)
class CalibrationResult:
    """A calibrated unit: its parameters, each estimate with its uncertainty, the fit.

    ``estimates``: name -> ``{"value", "se", "lo95", "hi95", "unit"}`` (deviations from
    the data sheet; parameters kept at the data sheet are absent and listed in
    ``fixed``); ``correlated``: the estimates found not separable, each with its partner
    (or ``"J+friction+gain_b"``: the others that predict it together) and the (multiple)
    correlation;
    ``weak``: the parameters found not identifiable, with the change of the fit ratio a
    typical deviation of theirs makes (see :data:`MIN_EFFECT`);
    ``fit_ratio``: per source, the fitted Eq. 4 over the trace's white-noise floor;
    ``fits``: per source, ``(t, measured, model)`` currents on the model grid (for plots;
    not in :meth:`to_dict`); ``params_source``: where the data sheet calibrated around came
    from (:data:`emaphm.params.PARAMS_SOURCES`).
    """

    params: ActuatorParams
    estimates: dict[str, dict[str, Any]]
    fixed: tuple[str, ...]
    correlated: tuple[tuple[str, str, float], ...]
    weak: tuple[tuple[str, float], ...]
    fit_ratio: dict[str, float]
    evaluations: int
    elapsed_s: float
    fits: tuple[tuple[np.ndarray, np.ndarray, np.ndarray], ...] = ()   # (t, measured, model)
    params_source: str = "given"

    def to_dict(self) -> dict[str, Any]:
        return {"estimates": self.estimates, "fixed": list(self.fixed),
                "correlated": [list(c) for c in self.correlated],
                "not_identifiable": [list(w) for w in self.weak],
                "fit_ratio": self.fit_ratio, "evaluations": self.evaluations,
                "elapsed_s": self.elapsed_s, "calibration": self.params.calibration.date,
                "parameters": self.params.to_dict(), "params_source": self.params_source}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "CalibrationResult":
        """The result :meth:`to_dict` wrote (without the ``fits``, which it leaves out)."""
        return cls(params=ActuatorParams.from_dict(data["parameters"], source="calibration"),
                   estimates={n: dict(e) for n, e in data["estimates"].items()},
                   fixed=tuple(data["fixed"]),
                   correlated=tuple((str(a), str(b), float(r)) for a, b, r in data["correlated"]),
                   weak=tuple((str(n), float(e)) for n, e in data["not_identifiable"]),
                   fit_ratio=dict(data["fit_ratio"]), evaluations=int(data["evaluations"]),
                   elapsed_s=float(data["elapsed_s"]),
                   params_source=str(data.get("params_source", "given")))

    def summary(self) -> str:
        w = max([10] + [len(n) for n in self.estimates])
        # a setting in seconds (a filter's) in scientific notation: four decimals hide it
        fmt = lambda x, n, e: (f"{x:+{n}.3e}" if e["unit"] == "s" else f"{x:+{n}.4f}")  # noqa: E731
        lines = [f"{'parameter':{w}s} {'deviation':>10s} {'95 % interval':>22s}  unit"]
        for n, e in self.estimates.items():
            lines.append(f"{n:{w}s} {fmt(e['value'], 10, e)} [{fmt(e['lo95'], 9, e)}, "
                         f"{fmt(e['hi95'], 9, e)}]  {e['unit']}")
        if self.weak:
            lines.append("not identifiable on this profile (a typical deviation changes the fit "
                         "less than model error does), kept at the data sheet: "
                         + ", ".join(f"{n} ({e:.2f})" for n, e in self.weak))
        if self.correlated:
            lines.append("not separable, the less certain kept at the data sheet: "
                         + "; ".join(f"{a} ~ {b} (r = {r:+.3f})" for a, b, r in self.correlated))
        lines.append("fit / noise floor: " + ", ".join(f"{s} {r:.2f}x"
                                                      for s, r in self.fit_ratio.items()))
        lines.append(f"{self.evaluations} model runs in {self.elapsed_s:.2f} s")
        return "\n".join(lines)


class _Fitter:
    """The calibration's least squares: the residuals of every trace at a vector of
    deviations, and their Jacobian (forward differences for the physical parameters, one
    simulation each; exact columns for the sensor gains and offsets, which act after the
    model), run on :func:`emaphm.optim.lsq.least_squares_batched`."""

    def __init__(self, base: ActuatorParams, targets: list[_Target],
                 progress: Callable[[int], Any] | None) -> None:
        self.base, self.targets, self.progress = base, targets, progress
        self.count = 0                    # model simulations so far
        self.m = sum(t.size if isinstance(t, _DrivenTarget) else t.i_meas.size for t in targets)
        self._cache: dict[bytes, list[np.ndarray] | None] = {}
        #: traces on the recorded-voltage path: every column by differences (the sensors'
        #: gains and offsets act on the measured currents the model reads, not after it)
        self.driven = any(isinstance(t, _DrivenTarget) for t in targets)
        #: each parameter's (lower, upper) bound of the deviation: :data:`PARAMETERS`', the
        #: drive settings' from their stated values (:func:`drive_bounds`)
        self.bounds = {n: (lo, hi) for n, (lo, hi, _) in PARAMETERS.items()}

    def currents(self, x: np.ndarray, names: list[str]) -> list[np.ndarray] | None:
        """Model currents of each trace at ``x``, before the sensors' gains and offsets
        (those act after the model, so their Jacobian columns need no simulation)."""
        key = np.asarray(x, dtype=float).tobytes() + ",".join(names).encode()
        if key not in self._cache:
            p = apply_deviations(self.base, dict(zip(names, x)))
            p = replace(p, sensors=CurrentSensors())      # applied below, after the model
            out: list[np.ndarray] | None = []
            for tg in self.targets:
                self.count += 1
                i = _model_currents(p, tg)
                if self.progress is not None:
                    self.progress(self.count)
                if not np.all(np.isfinite(i)):
                    out = None
                    break
                out.append(i)
            self._cache.clear()
            self._cache[key] = out
        return self._cache[key]

    def sensors(self, x: np.ndarray, names: list[str]) -> tuple[np.ndarray, np.ndarray]:
        s = apply_deviations(self.base, dict(zip(names, x))).sensors
        return np.asarray(s.gain), np.asarray(s.offset)

    def _driven_residual(self, x: np.ndarray, names: list[str]) -> np.ndarray:
        dev = dict(zip(names, (float(v) for v in x)))
        p = apply_deviations(self.base, dev)
        out = []
        for tg in self.targets:
            self.count += 1
            r = tg.residual(p, dev) if isinstance(tg, _DrivenTarget) else None
            if not isinstance(tg, _DrivenTarget):
                i = _model_currents(replace(p, sensors=CurrentSensors()), tg)
                g, o = np.asarray(p.sensors.gain), np.asarray(p.sensors.offset)
                r = ((i * g + o - tg.i_meas) * tg.sqrt_w).ravel() if np.all(np.isfinite(i)) else None
            if self.progress is not None:
                self.progress(self.count)
            if r is None or not np.all(np.isfinite(r)):
                return np.full(self.m, 1e6)
            out.append(r)
        return np.concatenate(out)

    def residual(self, x: np.ndarray, names: list[str]) -> np.ndarray:
        if self.driven:
            return self._driven_residual(x, names)
        cur = self.currents(x, names)
        if cur is None:
            return np.full(self.m, 1e6)
        g, o = self.sensors(x, names)
        return np.concatenate([((i * g + o - tg.i_meas) * tg.sqrt_w).ravel()
                               for i, tg in zip(cur, self.targets)])

    def jacobian(self, x: np.ndarray, names: list[str]) -> np.ndarray:
        r0 = self.residual(x, names)
        cur = None if self.driven else self.currents(x, names)
        J = np.zeros((self.m, len(names)))
        g0 = np.asarray(self.base.sensors.gain)
        for c, n in enumerate(names):
            if (n.startswith("gain_") or n.startswith("offset_")) and not self.driven:
                j = "abc".index(n[-1])
                col = []
                for i, tg in zip(cur or [np.zeros_like(t.i_meas) for t in self.targets],
                                 self.targets):
                    d = np.zeros_like(tg.i_meas)
                    d[:, j] = (g0[j] * i[:, j] if n.startswith("gain_") else 1.0) * tg.sqrt_w[:, j]
                    col.append(d.ravel())
                J[:, c] = np.concatenate(col)
                continue
            h = STEP.get(n, 1e-3) * max(1.0, abs(x[c]))
            if x[c] + h > self.bounds[n][1]:
                h = -h
            xh = np.array(x, dtype=float)
            xh[c] += h
            J[:, c] = (self.residual(xh, names) - r0) / h
        if not self.driven:
            self.currents(x, names)         # leave the cache at x
        return J

    def fit(self, names: list[str], x0: np.ndarray) -> Any:
        """SciPy's result (``x``, residual ``fun``, ``jac``) of the fit of ``names`` from
        ``x0``, on :func:`emaphm.optim.lsq.least_squares_batched` (trust-region reflective,
        one BLAS thread)."""
        from .optim.lsq import least_squares_batched

        lo = np.array([self.bounds[n][0] for n in names])
        hi = np.array([self.bounds[n][1] for n in names])
        _, res = least_squares_batched(
            lambda X: np.stack([self.residual(x, names) for x in X]), np.clip(x0, lo, hi),
            (lo, hi), jac=lambda x, r0: self.jacobian(x, names),
            x_scale=np.maximum(hi - lo, 1e-3) / 10, xtol=1e-8, ftol=1e-8, gtol=1e-8,
            max_nfev=60, max_evals=math.inf, full_output=True)
        return res


def select_identifiable(fitter: _Fitter, names: list[str], *,
                        correlation_limit: float = CORRELATION_LIMIT,
                        multiple_limit: float = MULTIPLE_CORRELATION_LIMIT,
                        x0: np.ndarray | None = None) -> dict[str, Any]:
    """Fit ``names`` and keep at the data sheet, one at a time, each estimate the profile
    does not identify (:data:`MIN_EFFECT`) or cannot separate from the others
    (``correlation_limit``, ``multiple_limit``), refitting from where the last fit ended.

    Returns ``{"res", "names", "fixed", "pairs", "weak", "cov"}``: the last fit, the
    estimated names, those kept at the data sheet, the non-separable pairs (or the
    estimate and the others that predict it, with the multiple correlation), the weak
    ones (with the change of the fit ratio a typical deviation makes) and the covariance.
    ``x0``: where the first fit starts (default the data sheet, every deviation zero).
    """
    names = list(names)
    fixed: list[str] = []
    pairs: list[tuple[str, str, float]] = []
    weak: list[tuple[str, float]] = []
    x0 = np.zeros(len(names)) if x0 is None else np.asarray(x0, dtype=float)
    floor_r = float(sum(np.sum(tg.w) for tg in fitter.targets))  # sum r^2 of white noise alone
    least = math.inf
    while True:
        res = fitter.fit(names, x0)
        # practical identifiability: what a typical deviation of each parameter does to
        # the fit ratio, against the misfit model error leaves; on the recorded-voltage path
        # the first fit's (every parameter free): a refit there can stop in another valley
        # of the dead time's drop, whose misfit is not the model's error
        ratio = float(res.fun @ res.fun) / floor_r
        least = min(least, ratio) if fitter.driven else ratio
        excess = max(least - 1.0, MIN_EFFECT)
        Jm = np.asarray(res.jac)
        effect = np.array([_switched_effect(fitter, names, res, c) / floor_r if n in SWITCHED
                           else float(np.sum(Jm[:, c] ** 2)) * TYPICAL[n] ** 2 / floor_r
                           for c, n in enumerate(names)])
        # a switch (SWITCHED) is kept where it improves the fit at all (MIN_EFFECT): it
        # adds physics the plant has, where a deviation could absorb the model's error
        limit = np.array([MIN_EFFECT if n in SWITCHED else excess for n in names])
        if len(names) > 1 and np.any(effect < limit):
            drop = int(np.argmin(np.where(effect < limit, effect, np.inf)))
            weak.append((names[drop], float(effect[drop])))
            fixed.append(names.pop(drop))
            x0 = np.delete(res.x, drop)
            continue
        cov, corr = _covariance(res, fitter.targets)
        if len(names) <= 1:
            break
        drop, pair = _inseparable(names, cov, corr, correlation_limit, multiple_limit,
                                  fitter.bounds)
        if drop is None:
            break
        if fitter.driven:
            # on the recorded-voltage path the currents' scale, the inertia and the frictions
            # trade through the mechanics only in part: an estimate the others "predict" is
            # kept where the fit without it is clearly worse (the linear correlation is local)
            trial = fitter.fit(names[:drop] + names[drop + 1:], np.delete(res.x, drop))
            if float(trial.fun @ trial.fun) / floor_r > SEPARABLE_WORSE * ratio + MIN_EFFECT:
                break
        pairs.append(pair)
        fixed.append(names.pop(drop))
        x0 = np.delete(res.x, drop)          # the refit starts where the last fit ended
    return {"res": res, "names": names, "fixed": fixed, "pairs": pairs, "weak": weak, "cov": cov}


def _switched_effect(fitter: _Fitter, names: list[str], res: Any, c: int) -> float:
    """How much worse the fit ``res`` of ``names`` gets (its sum of squared residuals) with
    the piece of physics ``names[c]`` switches on set off (:data:`SWITCHED`): one model run
    per trace."""
    x = np.array(res.x, dtype=float)
    x[c] = SWITCHED[names[c]]
    r = fitter.residual(x, names)
    return float(r @ r) - float(res.fun @ res.fun)


def _inseparable(names: list[str], cov: np.ndarray, corr: np.ndarray, correlation_limit: float,
                 multiple_limit: float, bounds: dict[str, tuple[float, float]]
                 ) -> tuple[int | None, tuple[str, str, float] | None]:
    """The estimate to keep at the data sheet (the less certain, relative to its range, of
    the most correlated pair past ``correlation_limit``; else the least certain of those
    the others predict past ``multiple_limit``) and why; ``(None, None)`` when none."""
    worst = None
    for a in range(len(names)):
        for b in range(a + 1, len(names)):
            r = corr[a, b]
            if abs(r) > correlation_limit and (worst is None or abs(r) > abs(worst[2])):
                worst = (a, b, float(r))
    span = lambda j: bounds[names[j]][1] - bounds[names[j]][0]  # noqa: E731
    doubt = lambda j: math.sqrt(cov[j, j]) / span(j)                      # noqa: E731
    if worst is not None:
        a, b, r = worst
        return (a if doubt(a) >= doubt(b) else b), (names[a], names[b], r)
    multiple = _multiple_correlation(corr)
    over = [j for j in range(len(names)) if multiple[j] > multiple_limit]
    if not over:
        return None, None
    drop = max(over, key=doubt)
    partners = [names[j] for j in np.argsort(-np.abs(corr[drop]))
                if j != drop and abs(corr[drop, j]) > 0.5][:3] or ["the others"]
    return drop, (names[drop], "+".join(partners), float(multiple[drop]))


def estimates(names: list[str], x: np.ndarray, cov: np.ndarray) -> dict[str, dict[str, Any]]:
    """Each estimate with its standard error: the statistical one (``se_stat``, from the
    covariance) and the total with the model discrepancy (:data:`DISCREPANCY`) in
    quadrature (``se``), and its 95 % interval."""
    se = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    out = {}
    for n, v, s in zip(names, x, se):
        tot = math.hypot(float(s), DISCREPANCY.get(n, 0.0))
        out[n] = {"value": float(v), "se": tot, "lo95": float(v - 1.96 * tot),
                  "hi95": float(v + 1.96 * tot), "unit": PARAMETERS[n][2], "se_stat": float(s)}
    return out


def calibrate(traces: Sequence[Trace], params: ActuatorParams | None = None, *,
              sources: Sequence[str] | None = None, free: Sequence[str] | None = None,
              fit_limit: float = HEALTHY_FIT_LIMIT,
              correlation_limit: float = CORRELATION_LIMIT,
              multiple_limit: float = MULTIPLE_CORRELATION_LIMIT,
              progress: Callable[[int], Any] | None = None,
              tolerances: Any = None,
              drive_unknown: Sequence[str] = ()) -> CalibrationResult:
    """Calibrate a healthy unit on ``traces`` around its data sheet ``params`` (an
    :class:`ActuatorParams`, a dict or a TOML path; default the traces' own actuator,
    their metadata's ``"parameters"``, else the preset: :func:`emaphm.params.resolve_params`;
    :attr:`CalibrationResult.params_source` says which).

    ``free``: the parameters to estimate (default the unit's own of :data:`PARAMETERS` and
    the dry friction's Stribeck speed; on the recorded-voltage path the drive's too);
    ``sources``: a name per trace for the report; ``progress``: called with the number of
    model simulations so far after each (a progress line); ``correlation_limit`` and
    ``multiple_limit``: when estimates count as not separable (:data:`CORRELATION_LIMIT`,
    :data:`MULTIPLE_CORRELATION_LIMIT`). Raises :class:`CalibrationError`
    when a trace does not look healthy after calibration (its fit stays above
    ``fit_limit`` times its noise floor) or cannot be used, and when an estimate lies outside
    the production ``tolerances`` (default :data:`emaphm.units.DEFAULT_TOLERANCES`) by more
    than its own 95 % interval (:data:`TOLERANCE_CHECKED`): the model does not describe the
    unit (its drive's control, most often), and the parameters would absorb it.

    ``drive_unknown``: drive settings the user does not know (:data:`DRIVE_SETTINGS`:
    feed-forward gains, filters, the 2-DOF weight, the loops' gains), estimated beside the
    unit's parameters with their intervals and written into the calibrated parameters
    (``[controller]``, ``[inverter]``), which the calibration's digest then covers. They
    act where the drive is modelled: the modelled controller's path, and on the current
    references' the current loop's gains.
    """
    traces = list(traces)
    base, params_source = resolve_params(params, traces)
    if not traces:
        raise CalibrationError("calibration needs at least one trace of the healthy unit")
    sources = _sources(traces, sources)
    free, drive_unknown = _free(free, drive_unknown)
    from .recorded import DRIVEN, drive_model_of

    drives = [drive_model_of(tr) for tr in traces]
    targets = [_DrivenTarget(tr, base, src, d) if d in DRIVEN else _target(tr, base, src)
               for tr, src, d in zip(traces, sources, drives)]
    if any(isinstance(tg, _DrivenTarget) for tg in targets):
        free += [n for n in DRIVE_PARAMETERS if n not in free]
        # the currents' common gain scales what the recorded voltages drive (R, L, the
        # inertia, the frictions and the load scale with it, exactly): phase A's sensor
        # sets the scale, the others are read against it
        free = [n for n in free if n != "gain_a"]
    t0 = time.perf_counter()
    fitter = _Fitter(base, targets, progress)
    settings = drive_bounds(base, drive_unknown)
    fitter.bounds.update({n: (lo, hi) for n, (lo, hi, _) in settings.items()})
    x0 = np.array([settings[n][2] if n in settings else _start(base, n) for n in free])
    if fitter.driven:
        # the inverter's, the encoder's and the friction's own first: the dead time moves the
        # currents by amperes where the unit's deviations move them by milliamperes, and a
        # first fit of everything from zero lands in the dead time's valley
        drive = [n for n in free if n in DRIVE_PARAMETERS]
        # from where a diagnosis starts them (the Stribeck speed at 1 rad/s: at 0 the
        # friction does not change with it, and the fit would stay there)
        first = fitter.fit(drive, nuisance_start(tuple(drive)))
        x0 = np.array([first.x[drive.index(n)] if n in drive else x for n, x in zip(free, x0)])
    sel = select_identifiable(fitter, free, correlation_limit=correlation_limit,
                              multiple_limit=multiple_limit, x0=x0)
    res, names = sel["res"], sel["names"]
    dev = dict(zip(names, (float(v) for v in res.x)))
    unit = apply_deviations(base, dev)
    fits, ratios = _trace_fits(targets, unit, dev, base.inverter.T_s)
    elapsed = time.perf_counter() - t0
    bad = {s: r for s, r in ratios.items() if not r <= fit_limit}
    if bad:
        raise CalibrationError(
            "the unit does not look healthy after calibration: "
            + ", ".join(f"{s} fits at {r:.1f}x its noise floor" for s, r in bad.items())
            + f" (a healthy unit fits below {fit_limit:g}x); "
            + (_DRIVE_DIFFERS if _in_transients(targets, fits, base) else
               "diagnose it (emaphm diagnose) before using it as a reference, or check that the "
               "traces are of this unit and its parameters (--params)"))
    est = estimates(names, res.x, sel["cov"])
    _check_tolerances(est, tolerances, relative="gain_a" not in free and "gain_b" in free,
                      fixed=sel["fixed"])
    unit = _provenance(unit, traces, sources, est, sel["fixed"])
    return CalibrationResult(params=unit, estimates=est,
                             fixed=tuple(sel["fixed"]), correlated=tuple(sel["pairs"]),
                             weak=tuple(sel["weak"]), fit_ratio=ratios,
                             evaluations=fitter.count, elapsed_s=elapsed, fits=tuple(fits),
                             params_source=params_source)


def _free(free: Sequence[str] | None, drive_unknown: Sequence[str]) -> tuple[list[str], list[str]]:
    """The parameters a calibration estimates (``free``, default :data:`PARAMETERS`' own and
    the dry friction's Stribeck speed, which data sheets do not state: estimated per unit
    where the profile identifies it, and written into ``[transmission]``) with the drive
    settings the user does not know, each name checked."""
    names = list(free) if free is not None else list(_NAMES) + ["stribeck"]
    unknown = [n for n in names if n not in PARAMETERS]
    if unknown:
        raise ValueError(f"unknown calibration parameter(s) {unknown}; choose from "
                         + ", ".join(_NAMES))
    drive_unknown = list(drive_unknown)
    strange = [n for n in drive_unknown if n not in DRIVE_SETTINGS]
    if strange:
        raise ValueError(f"unknown drive setting(s) {strange}; a calibration estimates "
                         + ", ".join(DRIVE_SETTINGS) + " (describe the others in [controller])")
    return names + [n for n in drive_unknown if n not in names], drive_unknown


def _start(base: ActuatorParams, name: str) -> float:
    """Where the fit starts ``name``: a deviation at zero (the data sheet), the Stribeck
    speed (a value) at the stated one, else at the reference plant's 1 rad/s (at 0 the
    friction does not change with it, and the fit would stay there)."""
    if name != "stribeck":
        return 0.0
    return base.transmission.omega_s or float(nuisance_start(("stribeck",))[0])


def _sources(traces: list[Trace], sources: Sequence[str] | None) -> list[str]:
    """A name per trace (``trace 1``, ... where none are given); a recording given twice
    refused (it would weigh twice and narrow the intervals it has not earned)."""
    from .traces.container import fingerprint

    sources = list(sources) if sources is not None else [f"trace {i + 1}" for i in range(len(traces))]
    if len(sources) != len(traces):
        raise ValueError("give one source name per trace")
    seen: dict[str, str] = {}
    for tr, src in zip(traces, sources):
        fp = fingerprint(tr)
        if fp in seen:
            raise CalibrationError(f"{src} is the same recording as {seen[fp]}; give each "
                                   "trace of the healthy unit once (other recordings of it "
                                   "narrow the intervals, a copy does not)")
        seen[fp] = src
    return sources


def _trace_fits(targets: list, unit: ActuatorParams, dev: dict[str, float], T_s: float
                ) -> tuple[list, dict[str, float]]:
    """Each trace's ``(t, measured, model)`` currents at the calibrated ``unit`` and its fit
    against its own noise floor, by source."""
    fits = []
    ratios: dict[str, float] = {}
    for tg in targets:
        if isinstance(tg, _DrivenTarget):
            fit, ratios[tg.source] = tg.fit(unit, dev)
            fits.append(fit)
            continue
        i = _model_currents(unit, tg)
        fits.append((np.arange(i.shape[0]) * T_s, tg.i_meas, i))
        ratios[tg.source] = float(np.sum(tg.w * (i - tg.i_meas) ** 2) / tg.floor)
    return fits, ratios


def _provenance(unit: ActuatorParams, traces: Sequence[Trace], sources: Sequence[str],
                est: dict[str, dict[str, Any]], fixed: Sequence[str]) -> ActuatorParams:
    """The calibrated unit with its ``[calibration]`` block: date, sources, estimates, the
    parameters kept, the emaphm version, the sources' digests and the block's own."""
    from . import __version__

    calib = Calibration(date=_dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
                        sources=tuple(sources),
                        estimates=tuple((n, e["value"], e["se"]) for n, e in est.items()),
                        fixed=tuple(fixed), emaphm_version=__version__,
                        trace_sha256=tuple(trace_digest(tr) for tr in traces))
    unit = replace(unit, calibration=calib)
    return replace(unit, calibration=replace(calib, digest=calibration_digest(unit)))


#: What calibrate's refusal says where the misfit sits in the command's transients.
_DRIVE_DIFFERS = ("the misfit sits in the command's transients (steps, reversals), not on its "
                  "ramps: the drive's control likely differs from [controller] (a filter on the "
                  "speed feedback, a computation delay, feed-forwards, other limits); record "
                  "the drive's voltage commands with the currents (calibrated without modelling "
                  "the controller, docs/drives.md), or describe the drive in [controller]")


def _in_transients(targets: list, fits: list, base: ActuatorParams) -> bool:
    """Whether the calibrated fits misfit mostly in the command's transients
    (:func:`emaphm.fitness.transient_excess`), on the traces of the modelled controller."""
    for tg, (_, measured, model) in zip(targets, fits):
        if isinstance(tg, _DrivenTarget):
            continue
        share = transient_excess(tg.theta_ref, base.inverter.T_s, tg.w * (model - measured) ** 2,
                                 tg.w, tg.floor_sigma)
        if share is not None and share >= TRANSIENT_MISFIT:
            return True
    return False


#: The estimates that carry the magnet flux's deviation where the flux was kept at the data
#: sheet (not separable from them on the profile): the currents see the inertia and the dry
#: friction only through the torque ``k_T i``, so each reads as its ratio to the flux.
PER_FLUX = ("J", "friction")


def _check_tolerances(est: dict[str, dict[str, Any]], tolerances: Any,
                      relative: bool = False, fixed: Sequence[str] = ()) -> None:
    """Refuse estimates whose whole 95 % interval lies outside their production tolerance
    (:data:`TOLERANCE_CHECKED`), naming them. ``relative``: the sensor gains were read
    against phase A's (the recorded-voltage path), so each may be off by both tolerances.
    ``fixed``: the parameters kept at the data sheet; with the flux among them, an estimate
    of :data:`PER_FLUX` is its ratio to the unit's flux, which spreads over both tolerances
    (a unit of inertia +9 % and flux -5 % reads J +15 %)."""
    from .units import DEFAULT_TOLERANCES

    tol = DEFAULT_TOLERANCES if tolerances is None else tolerances
    out = []
    for name, e in est.items():
        field_ = TOLERANCE_CHECKED.get(name)
        if field_ is None:
            continue
        lo, hi = getattr(tol, field_)
        if relative and field_ == "sensor_gain":
            lo, hi = 2.0 * lo, 2.0 * hi
        if name in PER_FLUX and "flux" in fixed and "flux" not in est:
            f_lo, f_hi = tol.flux
            lo, hi = (1.0 + lo) / (1.0 + f_hi) - 1.0, (1.0 + hi) / (1.0 + f_lo) - 1.0
        if e["lo95"] > hi or e["hi95"] < lo:
            unit = " A" if e["unit"] == "A" else ""
            scale = 1.0 if unit else 100.0
            pct = "" if unit else " %"
            out.append(f"{name} {scale * e['value']:+.3g}{unit}{pct} (95 % interval "
                       f"{scale * e['lo95']:+.3g} to {scale * e['hi95']:+.3g}{unit}{pct}; tolerance "
                       f"{scale * lo:+.3g} to {scale * hi:+.3g}{unit}{pct})")
    if out:
        raise CalibrationError(
            "the calibration puts " + "; ".join(out) + " outside what a unit of this design "
            "spreads over: the model does not describe this actuator, and its parameters would "
            "absorb the difference. Most often the drive's control differs from [controller] (a "
            "speed filter, a delay, feed-forwards, other limits): record the drive's voltage "
            "commands with the currents (calibrated without modelling the controller, "
            "docs/drives.md) or describe the drive in [controller]; else check the data sheet "
            "(--params) and the current sensors")


def _multiple_correlation(corr: np.ndarray) -> np.ndarray:
    """Each estimate's multiple correlation with all the others, ``sqrt(1 - 1 / VIF)`` from
    the variance inflation factors ``diag(corr^-1)`` (1 where the others predict it
    exactly: a singular ``corr``)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        vif = np.diag(np.linalg.pinv(corr))
        r2 = np.where(np.isfinite(vif) & (vif >= 1.0), 1.0 - 1.0 / vif, 1.0)
    return np.sqrt(np.clip(r2, 0.0, 1.0))


def _covariance(res: Any, targets: list[_Target]) -> tuple[np.ndarray, np.ndarray]:
    """Covariance and correlation of the estimates at a least-squares solution."""
    Jm = np.asarray(res.jac, dtype=float)
    m, p = Jm.shape
    r = np.asarray(res.fun, dtype=float)
    s2 = float(r @ r) / max(m - p, 1)
    # a residual that is not white carries fewer independent samples
    n_eff = 0.0
    off = 0
    for tg in targets:
        cols = getattr(tg, "columns", 3)
        k = tg.size if cols == 4 else tg.i_meas.size
        n_eff += effective_samples(r[off:off + k].reshape(-1, cols))[0]
        off += k
    inflate = max(m / max(n_eff, 1.0), 1.0)
    JtJ = Jm.T @ Jm
    cov = np.linalg.pinv(JtJ) * s2 * inflate
    d = np.sqrt(np.clip(np.diag(cov), 1e-300, None))
    corr = cov / np.outer(d, d)
    return cov, corr
