"""Physical parameters of the actuator: frozen, typed, validated, in SI units.

Every quantity is referred to the motor shaft (a gearbox is folded in by the
user: reflect inertias and torques through the ratio). Symbols follow the
textbook and the paper (Baldo et al. 2023, section 3.2):

=========================  ==================  =====================================
field                      unit                meaning
=========================  ==================  =====================================
``Motor.p``                --                  pole pairs
``Motor.R``                ohm                 phase resistance, per phase (a, b, c)
``Motor.L``                H                   synchronous inductance, per phase
``Motor.c0``               V s/rad             back-EMF coefficient, peak per phase
                                               per mechanical rad/s (also N m/A)
``Motor.ecc``              --                  static eccentricity modulus (Eq. 2)
``Motor.ecc_phase``        rad                 static eccentricity phase (Eq. 2)
``Motor.L_sigma``          --                  leakage share of the synchronous inductance
``Motor.mu``               --                  shorted fraction of each phase's turns
``Motor.R_f``              ohm                 fault resistance across the shorted turns
``Motor.J_m``              kg m^2              rotor inertia
``Motor.C_m``              N m s/rad           viscous friction coefficient
``Motor.T_max``            N m                 maximum torque
``Motor.I_max``            A                   maximum phase current, peak
``Inverter.V_dc``          V                   DC link voltage
``Inverter.f_pwm``         Hz                  PWM carrier frequency (= control rate)
``Inverter.Kp_i``          V/A                 dq current controller, proportional
``Inverter.Ki_i``          V/(A s)             dq current controller, integral
``Inverter.I_trip``        A                   overcurrent trip level (peak phase current)
``Inverter.dead_time``     s                   dead time between a leg's switches
``Inverter.device_drop``   V                   its devices' on-state voltage drop
``Controller.Kp``          1/s                 position loop proportional gain
``Controller.Ki``          1/s^2               position loop integral gain
``Controller.Kd``          --                  position loop derivative gain
``Controller.omega_max``   rad/s               speed reference saturation
``Controller.Kp_w``        N m s/rad           speed loop proportional gain
``Controller.Ki_w``        N m/rad             speed loop integral gain
``Controller.k_T``         N m/A               drive's torque constant setting (peak)
``Controller.*``           see :class:`Controller` the drive's options: feed-forwards,
                                               filters, 2-DOF weight, delay, decoupling,
                                               its own torque and current limits
``Transmission.FSJ``       N m                 static (breakaway) dry friction torque
``Transmission.FDJ``       N m                 dynamic (Coulomb) dry friction torque
``Transmission.backlash``  rad                 total backlash width
``Transmission.K_c``       N m/rad             torsional stiffness of the backlash contact
``Transmission.D_c``       N m s/rad           damping of the backlash contact
``Transmission.omega_s``   rad/s               Stribeck speed as stated or calibrated
                                               (0: no drop, Borello's two levels)
``Load.J_l``               kg m^2              load inertia behind the backlash
``Load.C_l``               N m s/rad           load viscous damping
``Plant.omega_s``          rad/s               Stribeck velocity of the dry friction
``CurrentSensors.gain``    --                  per-phase current sensor gain (calibrated)
``CurrentSensors.offset``  A                   per-phase current sensor offset (calibrated)
``CurrentSensors.aa_*``    --, Hz              declared anti-alias filter order, cut-off
``CurrentSensors.delay``   s                   declared sample delay of the currents
``Load.T_0``               N m                 constant load the trace does not report
=========================  ==================  =====================================

``[plant]`` holds physics that only the reference plant has (the monitoring
model uses Borello's two-level friction, with the Stribeck drop only where
``Transmission.omega_s`` states or a calibration estimated it); both models
close the backlash on the compliant contact ``K_c``, ``D_c`` (the monitoring
model on a rigid one where its step does not resolve the contact, see
:mod:`emaphm.models.mechanics`); ``Motor.mu``/``Motor.R_f`` describe an inter-turn short
circuit (healthy: ``mu = 0``), see :mod:`emaphm.models.windings`.

The default preset :func:`siemens_1fk7060` describes the paper's test bench
motor, a Siemens 1FK7060-2AC71. The paper's data table is missing from our
copy, so the motor values are a **reconstruction** consistent with the 1FK7
family (not checked against the data sheet); the mechanics and controller are
our design defaults. Describe another actuator with a TOML file
(:func:`load_params` / :func:`save_params`).
"""

from __future__ import annotations

import math
import os
import re
import tomllib
from dataclasses import asdict, dataclass, field, fields, replace
from pathlib import Path
from typing import Any

import tomli_w

from ._text import shown

__all__ = [
    "C0_1FK7060",
    "ParameterError",
    "Motor",
    "Inverter",
    "Controller",
    "Transmission",
    "Load",
    "Plant",
    "CurrentSensors",
    "Calibration",
    "CalibrationWarning",
    "CALIBRATED_FIELDS",
    "CALIBRATED_DRIVE_FIELDS",
    "calibration_digest",
    "check_calibration",
    "ActuatorParams",
    "siemens_1fk7060",
    "back_emf_coefficient",
    "Tuning",
    "derive_tuning",
    "load_params",
    "save_params",
    "check_plausible",
    "PlausibilityWarning",
    "PLAUSIBLE",
    "PARAMS_SOURCES",
    "ActuatorMismatchWarning",
    "as_params",
    "trace_params",
    "resolve_params",
]


class ParameterError(ValueError):
    """An actuator parameter is missing, of the wrong type or out of range."""


Phase3 = tuple[float, float, float]

def back_emf_coefficient(k_E: float) -> float:
    """The back-EMF coefficient ``c0`` [V s/rad, peak per phase per mechanical rad/s] of a
    voltage constant ``k_E`` [V per 1000 rpm, line-to-line RMS, as catalogues give it]:
    ``sqrt(2) k_E / sqrt(3) / (1000 * 2 pi / 60)`` (RMS to peak, line to phase of a star,
    krpm to rad/s)."""
    return math.sqrt(2.0) * k_E / math.sqrt(3.0) / (1000.0 * 2.0 * math.pi / 60.0)


#: Back-EMF coefficient of the reconstructed 1FK7060-2AC71: k_E = 135 V per 1000 rpm
#: (line-to-line RMS) -> peak per phase per mechanical rad/s [V s/rad].
C0_1FK7060 = back_emf_coefficient(135.0)

# unit of every field, used in error messages and in the TOML comments
_UNITS: dict[str, str] = {
    "p": "pole pairs, integer",
    "R": "ohm",
    "L": "H",
    "c0": "V s/rad",
    "ecc": "-, 0..1",
    "ecc_phase": "rad",
    "J_m": "kg m^2",
    "C_m": "N m s/rad",
    "T_max": "N m",
    "I_max": "A peak",
    "V_dc": "V",
    "f_pwm": "Hz",
    "Kp_i": "V/A",
    "Ki_i": "V/(A s)",
    "I_trip": "A peak",
    "Kp": "1/s",
    "Ki": "1/s^2",
    "Kd": "-",
    "omega_max": "rad/s",
    "Kp_w": "N m s/rad",
    "Ki_w": "N m/rad",
    "k_T": "N m/A peak",
    "velocity_feedforward": "-, gain 0..2",
    "torque_feedforward": "-, gain 0..2",
    "torque_feedforward_inertia": "kg m^2",
    "speed_filter_s": "s",
    "speed_reference_weight": "-, 0..1",
    "current_reference_filter_s": "s",
    "delay_periods": "control periods, 0 or 1",
    "decoupling": "true or false",
    "decoupling_L": "H",
    "emf_feedforward": "true or false",
    "FSJ": "N m",
    "FDJ": "N m",
    "backlash": "rad",
    "J_l": "kg m^2",
    "C_l": "N m s/rad",
    "L_sigma": "-, 0..1",
    "mu": "-, shorted fraction 0..1",
    "R_f": "ohm",
    "omega_s": "rad/s",
    "dead_time": "s",
    "device_drop": "V",
    "K_c": "N m/rad",
    "D_c": "N m s/rad",
    "T_0": "N m",
    "gain": "-, per phase",
    "offset": "A, per phase",
    "aa_order": "-, integer 0..8",
    "aa_cutoff": "Hz",
    "delay": "s",
    "date": "ISO date",
    "sources": "file names",
    "estimates": "[name, value, standard error]",
    "fixed": "names",
    "emaphm_version": "version of emaphm calibrate",
    "trace_sha256": "SHA-256 of each source's signals",
    "digest": "SHA-256 of this block and the calibrated values",
}


_PREFIXES = {"": 1.0, "m": 1e-3, "u": 1e-6, "\u00b5": 1e-6, "k": 1e3, "M": 1e6}


def _value_in_text(text: str, unit: str) -> float | None:
    """The SI value a text such as ``"3.15 ohm"``, ``"22 mH"`` or ``"8kHz"`` means when its
    unit is ``unit`` (with an SI prefix m, u, k, M); None if it says something else."""
    m = re.fullmatch(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(\S*(?: \S+)?)\s*", text)
    if not m or not unit:
        return None
    number, given = float(m.group(1)), m.group(2).replace("\u03a9", "ohm")
    for prefix, factor in _PREFIXES.items():
        if given[:len(prefix)] == prefix and given[len(prefix):].lower() == unit.lower():
            return number * factor
    return None


def _not_a_number(where: str, name: str, value: Any, expected: str) -> ParameterError:
    """The error for a field given as text or another non-number; for text with a number
    and the field's unit (``"3.15 ohm"``, ``"22 mH"``), how to write it."""
    if isinstance(value, str):
        unit = _UNITS.get(name, "").replace(", per phase", "")
        si = _value_in_text(value, unit)
        fix = (f"; write {name} = {si:g} (a bare number in {unit})" if si is not None
               else f"; write {name} as a bare number in {unit}" if unit else "")
        return ParameterError(f"{where}: expected {expected}, got the string {shown(value)}{fix}")
    return ParameterError(f"{where}: expected {expected}, got {shown(value)}")


def _check(owner: str, name: str, value: float, *, lo: float | None = None,
           hi: float | None = None, strict_lo: bool = True) -> float:
    unit = _UNITS.get(name, "")
    where = f"{owner}.{name} [{unit}]"
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise _not_a_number(where, name, value, f"a number in {unit}")
    v = float(value)
    if not math.isfinite(v):
        raise ParameterError(f"{where} must be finite, got {value!r}")
    if lo is not None and (v <= lo if strict_lo else v < lo):
        rel = ">" if strict_lo else ">="
        raise ParameterError(f"{where} must be {rel} {lo:g}, got {v:g}")
    if hi is not None and v > hi:
        raise ParameterError(f"{where} must be <= {hi:g}, got {v:g}")
    return v


def _phase3(owner: str, name: str, value: Any, *, lo: float = 0.0,
            strict_lo: bool = True, hi: float | None = None) -> Phase3:
    """Accept a scalar (same on all phases) or three per-phase values."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        value = (value, value, value)
    unit = _UNITS[name].replace(", per phase", "")
    expected = f"a number in {unit} or 3 per-phase numbers (a, b, c)"
    if isinstance(value, (str, bytes, dict)) or isinstance(value, bool):
        raise _not_a_number(f"{owner}.{name} [{_UNITS[name]}]", name, value, expected)
    try:
        vals = tuple(value)
    except TypeError:
        raise _not_a_number(f"{owner}.{name} [{_UNITS[name]}]", name, value, expected) from None
    if len(vals) != 3:
        raise ParameterError(
            f"{owner}.{name} [{_UNITS[name]}] needs 3 per-phase values (a, b, c), "
            f"got {len(vals)}")
    return tuple(_check(owner, name, v, lo=lo, strict_lo=strict_lo, hi=hi)  # type: ignore[return-value]
                 for v in vals)


@dataclass(frozen=True)
class Motor:
    """Three-phase star-connected surface PMSM (Eq. 5, 6 and 2 of the paper).

    Per-phase values are tuples ``(a, b, c)``; a scalar is broadcast. A short
    circuit makes them unequal (see :mod:`emaphm.faults`).
    """

    p: int = 4
    R: Phase3 = (3.15, 3.15, 3.15)
    L: Phase3 = (22e-3, 22e-3, 22e-3)
    c0: Phase3 = (C0_1FK7060, C0_1FK7060, C0_1FK7060)
    ecc: float = 0.0
    ecc_phase: float = 0.0
    J_m: float = 7.7e-4
    C_m: float = 5e-4
    T_max: float = 18.0
    I_max: float = 14.14
    L_sigma: float = 0.15
    mu: Phase3 = (0.0, 0.0, 0.0)
    R_f: Phase3 = (0.15, 0.15, 0.15)

    def __post_init__(self) -> None:
        o = "Motor"
        object.__setattr__(self, "L_sigma", _check(o, "L_sigma", self.L_sigma, lo=0.0, hi=1.0))
        object.__setattr__(self, "mu", _phase3(o, "mu", self.mu, strict_lo=False, hi=0.99))
        object.__setattr__(self, "R_f", _phase3(o, "R_f", self.R_f, strict_lo=False))
        if isinstance(self.p, bool) or not isinstance(self.p, int) or self.p < 1:
            raise ParameterError(f"{o}.p [pole pairs, integer] must be an integer >= 1, got {self.p!r}")
        for name in ("R", "L", "c0"):
            object.__setattr__(self, name, _phase3(o, name, getattr(self, name)))
        object.__setattr__(self, "ecc", _check(o, "ecc", self.ecc, lo=0.0, hi=1.0, strict_lo=False))
        object.__setattr__(self, "ecc_phase", _check(o, "ecc_phase", self.ecc_phase))
        for name in ("J_m", "T_max", "I_max"):
            object.__setattr__(self, name, _check(o, name, getattr(self, name), lo=0.0))
        object.__setattr__(self, "C_m", _check(o, "C_m", self.C_m, lo=0.0, strict_lo=False))

    @property
    def k_T(self) -> float:
        """Torque per peak q-axis ampere of the healthy motor, ``1.5 * c0`` [N m/A]."""
        return 1.5 * sum(self.c0) / 3.0


@dataclass(frozen=True)
class Inverter:
    """Two-level voltage-source inverter on a DC link, with its dq current loop.

    The current loop runs once per PWM period (single update, as Siemens S120
    drives at 8 kHz do), so ``1/f_pwm`` is also the control period ``T_s``.
    A sampled phase current above ``I_trip`` trips the drive: from then on
    the inverter holds the active short circuit (all low-side switches on,
    every leg at 0 V), the usual safe state of a PMSM drive, and the
    controller stops. Healthy operation peaks near 8 A on the diagnostic
    profile; a current loop that a heavy short circuit has made unstable
    trips instead of ringing at hundreds of amperes.

    ``dead_time`` [s] between a leg's two switches and the devices' on-state
    ``device_drop`` [V] take :attr:`V_lost` off each leg's voltage, against its current
    (default none): the plant resolves it with its PWM ripple, the monitoring model
    averages it over a current band (:func:`emaphm.models.inverter.dead_time_drop`).
    """

    V_dc: float = 600.0
    f_pwm: float = 8000.0
    Kp_i: float = 41.8
    Ki_i: float = 6000.0
    I_trip: float = 25.0
    dead_time: float = 0.0
    device_drop: float = 0.0

    def __post_init__(self) -> None:
        o = "Inverter"
        for name in ("V_dc", "f_pwm", "Kp_i", "I_trip"):
            object.__setattr__(self, name, _check(o, name, getattr(self, name), lo=0.0))
        object.__setattr__(self, "Ki_i", _check(o, "Ki_i", self.Ki_i, lo=0.0, strict_lo=False))
        object.__setattr__(self, "dead_time", _check(o, "dead_time", self.dead_time, lo=0.0,
                                                     strict_lo=False, hi=0.1 / self.f_pwm))
        object.__setattr__(self, "device_drop", _check(o, "device_drop", self.device_drop,
                                                       lo=0.0, strict_lo=False, hi=20.0))

    @property
    def V_lost(self) -> float:
        """What a leg loses to the dead time and the devices' drops [V], against its
        current: ``V_dc dead_time / T_s + device_drop``."""
        return self.V_dc * self.dead_time * self.f_pwm + self.device_drop

    @property
    def T_s(self) -> float:
        """Control and PWM period [s]."""
        return 1.0 / self.f_pwm


@dataclass(frozen=True)
class Controller:
    """The drive's firmware: cascade position controller, position PID -> speed PI ->
    torque reference -> dq current loop (:mod:`emaphm.models.controller`).

    ``omega_ref = Kp*e + Ki*int(e) + Kd*de/dt`` (derivative on the measured
    position, i.e. ``-Kd*omega_m``), saturated at ``omega_max``; then
    ``T_ref = Kp_w*(omega_ref - omega_m) + Ki_w*int(...)``, saturated at the
    torque limit with back-calculation anti-windup on both integrators. Fault k8
    scales ``Kp``. The q-axis current reference is ``T_ref / k_T`` (saturated at the
    current limit): ``k_T`` is the drive's setting for the healthy motor (``1.5*c0``),
    which a motor fault does not change.

    The usual options of a servo drive, each defaulting to the plain cascade above:

    ==============================  ============================================================
    field                           meaning
    ==============================  ============================================================
    ``velocity_feedforward``        gain on the command's backward difference over ``T_s``,
                                    added to the speed reference (after the position PID's
                                    saturation, saturated again at ``omega_max``)
    ``torque_feedforward``          gain on ``J`` times the command's second backward
                                    difference over ``T_s^2``, added to the torque reference
                                    (after the speed PI, outside its anti-windup, saturated
                                    at the torque limit)
    ``torque_feedforward_inertia``  that ``J`` [kg m^2], a drive setting (default the data
                                    sheet's ``J_m + J_l``: calibrating the unit's inertia
                                    does not change the firmware)
    ``speed_filter_s``              time constant of a first-order low-pass on the speed
                                    feedback (0: none); the filtered speed feeds the speed
                                    PI and the position loop's derivative, the back-EMF
                                    feed-forward keeps the raw speed
    ``speed_reference_weight``      ``b`` of a 2-DOF speed PI: its proportional part on
                                    ``b omega_ref - omega``
    ``current_reference_filter_s``  time constant of a low-pass on the q-current reference
    ``delay_periods``               0: the voltages computed from period k's samples are
                                    applied in period k; 1: in period k + 1
    ``decoupling``                  dq cross-coupling terms (``-omega_e L i_q`` on v_d,
                                    ``+omega_e L i_d`` on v_q) from the measured currents
                                    and speed, with the drive's ``decoupling_L`` [H]
                                    (default the data sheet's mean phase inductance)
    ``emf_feedforward``             the back-EMF feed-forward ``k_T/1.5 omega`` on v_q
    ``T_max``, ``I_max``            the drive's torque [N m] and current [A peak] limits
                                    (default the motor's): the current limit is on the
                                    q-axis reference (``i_d,ref = 0``, so on its magnitude)
    ==============================  ============================================================

    ``None`` for ``torque_feedforward_inertia``, ``decoupling_L``, ``T_max`` and ``I_max``
    means the data sheet's value (:meth:`resolved`), and is left out of a written file. A
    production unit (:func:`emaphm.units.draw_unit`), a calibration and a fault
    (:func:`emaphm.faults.apply_faults`) change the motor, not the drive: each keeps these
    settings at the data sheet's (:meth:`kept_for`).
    """

    Kp: float = 60.0
    Ki: float = 0.0
    Kd: float = 0.0
    omega_max: float = 200.0
    Kp_w: float = 0.6
    Ki_w: float = 12.0
    k_T: float = 1.5 * C0_1FK7060
    velocity_feedforward: float = 0.0
    torque_feedforward: float = 0.0
    torque_feedforward_inertia: float | None = None
    speed_filter_s: float = 0.0
    speed_reference_weight: float = 1.0
    current_reference_filter_s: float = 0.0
    delay_periods: int = 0
    decoupling: bool = False
    decoupling_L: float | None = None
    emf_feedforward: bool = True
    T_max: float | None = None
    I_max: float | None = None

    def __post_init__(self) -> None:
        o = "Controller"
        object.__setattr__(self, "Kp", _check(o, "Kp", self.Kp, lo=0.0))
        object.__setattr__(self, "k_T", _check(o, "k_T", self.k_T, lo=0.0))
        object.__setattr__(self, "omega_max", _check(o, "omega_max", self.omega_max, lo=0.0))
        object.__setattr__(self, "Kp_w", _check(o, "Kp_w", self.Kp_w, lo=0.0))
        for name in ("Ki", "Kd", "Ki_w"):
            object.__setattr__(self, name, _check(o, name, getattr(self, name), lo=0.0, strict_lo=False))
        for name in ("velocity_feedforward", "torque_feedforward"):
            object.__setattr__(self, name, _check(o, name, getattr(self, name), lo=0.0,
                                                  strict_lo=False, hi=2.0))
        for name in ("speed_filter_s", "current_reference_filter_s"):
            object.__setattr__(self, name, _check(o, name, getattr(self, name), lo=0.0,
                                                  strict_lo=False, hi=0.1))
        object.__setattr__(self, "speed_reference_weight",
                           _check(o, "speed_reference_weight", self.speed_reference_weight,
                                  lo=0.0, strict_lo=False, hi=1.0))
        if isinstance(self.delay_periods, bool) or self.delay_periods not in (0, 1):
            raise ParameterError(f"{o}.delay_periods [control periods, 0 or 1] must be 0 (the "
                                 "voltages apply in the period they are computed in) or 1 (in "
                                 f"the next), got {shown(self.delay_periods)}")
        object.__setattr__(self, "delay_periods", int(self.delay_periods))
        for name in ("decoupling", "emf_feedforward"):
            if not isinstance(getattr(self, name), bool):
                raise ParameterError(f"{o}.{name} [true or false] must be true or false, got "
                                     f"{shown(getattr(self, name))}")
        for name in ("torque_feedforward_inertia", "decoupling_L", "T_max", "I_max"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, _check(o, name, getattr(self, name), lo=0.0))

    def resolved(self, motor: "Motor", load: "Load") -> "Controller":
        """The controller with each ``None`` setting at the value of the data sheet
        ``motor`` and ``load``: the torque feed-forward's inertia ``J_m + J_l``, the
        decoupling's mean phase inductance, the motor's torque and current limits."""
        return replace(
            self,
            torque_feedforward_inertia=(motor.J_m + load.J_l if self.torque_feedforward_inertia
                                        is None else self.torque_feedforward_inertia),
            decoupling_L=sum(motor.L) / 3.0 if self.decoupling_L is None else self.decoupling_L,
            T_max=motor.T_max if self.T_max is None else self.T_max,
            I_max=motor.I_max if self.I_max is None else self.I_max)

    def kept_for(self, motor: "Motor", load: "Load", new_motor: "Motor",
                 new_load: "Load") -> "Controller":
        """The controller of an actuator whose motor and load change from ``motor, load``
        (the data sheet's) to ``new_motor, new_load`` (a production unit, a calibration, a
        fault): the settings that default to the data sheet's inertia or inductance keep
        the data sheet's value where the change moves it (the firmware does not change
        with the unit), the others are left as they are."""
        J_moved = motor.J_m + load.J_l != new_motor.J_m + new_load.J_l
        L_moved = sum(motor.L) != sum(new_motor.L)
        ctl = self
        if J_moved and ctl.torque_feedforward_inertia is None:
            ctl = replace(ctl, torque_feedforward_inertia=motor.J_m + load.J_l)
        if L_moved and ctl.decoupling_L is None:
            ctl = replace(ctl, decoupling_L=sum(motor.L) / 3.0)
        if motor.T_max != new_motor.T_max and ctl.T_max is None:
            ctl = replace(ctl, T_max=motor.T_max)
        if motor.I_max != new_motor.I_max and ctl.I_max is None:
            ctl = replace(ctl, I_max=motor.I_max)
        return ctl


@dataclass(frozen=True)
class Transmission:
    """Dry friction (Borello's discontinuous stick/slip), backlash, and the contact
    that closes it: the gear train's torsional stiffness ``K_c`` and damping ``D_c``
    (defaults ``4000 N m/rad`` and ``0.5 N m s/rad``: a well-damped two-mass
    resonance near 500 Hz with the preset's inertias).

    ``omega_s`` [rad/s]: the Stribeck speed of the dry friction as the unit's file states
    it, the sliding friction ``FDJ + (FSJ - FDJ) exp(-(omega/omega_s)^2)``; 0 (the default,
    what data sheets give) is Borello's two levels, no drop. ``emaphm calibrate`` estimates
    it per unit where the profile identifies it, and the monitoring model then steps it; the
    reference plant takes it as its own where stated (else ``Plant.omega_s``)."""

    FSJ: float = 0.12
    FDJ: float = 0.08
    backlash: float = 2e-4
    K_c: float = 4000.0
    D_c: float = 0.5
    omega_s: float = 0.0

    def __post_init__(self) -> None:
        o = "Transmission"
        for name in ("FSJ", "FDJ", "backlash"):
            object.__setattr__(self, name, _check(o, name, getattr(self, name), lo=0.0, strict_lo=False))
        object.__setattr__(self, "K_c", _check(o, "K_c", self.K_c, lo=0.0))
        object.__setattr__(self, "D_c", _check(o, "D_c", self.D_c, lo=0.0, strict_lo=False))
        object.__setattr__(self, "omega_s", _check(o, "omega_s", self.omega_s, lo=0.0,
                                                   strict_lo=False))
        if self.FDJ > self.FSJ:
            raise ParameterError(
                f"Transmission.FDJ [N m] = {self.FDJ:g} exceeds Transmission.FSJ [N m] = "
                f"{self.FSJ:g}: the dynamic friction torque must not exceed the static one")


@dataclass(frozen=True)
class Load:
    """The driven load behind the backlash (a control surface referred to the shaft)."""

    J_l: float = 7.7e-4
    C_l: float = 5e-4
    T_0: float = 0.0

    def __post_init__(self) -> None:
        o = "Load"
        object.__setattr__(self, "J_l", _check(o, "J_l", self.J_l, lo=0.0))
        object.__setattr__(self, "C_l", _check(o, "C_l", self.C_l, lo=0.0, strict_lo=False))
        object.__setattr__(self, "T_0", _check(o, "T_0", self.T_0, lo=-50.0, hi=50.0))


@dataclass(frozen=True)
class CurrentSensors:
    """Known gains and offsets of the recording's current sensors (a calibration finds them).

    A measured phase current is ``gain_j * i_j + offset_j``; diagnosis divides it back.
    A known anti-alias filter (Butterworth of order ``aa_order`` at ``aa_cutoff``) and a
    sample ``delay`` make the recorded currents lag the drive's; diagnosis aligns them
    by that lag (:meth:`lag`, the filter's group delay at low frequency plus the delay).
    """

    gain: Phase3 = (1.0, 1.0, 1.0)
    offset: Phase3 = (0.0, 0.0, 0.0)
    aa_order: int = 0
    aa_cutoff: float = 0.0
    delay: float = 0.0

    def __post_init__(self) -> None:
        o = "CurrentSensors"
        if isinstance(self.aa_order, bool) or not isinstance(self.aa_order, int) \
                or not 0 <= self.aa_order <= 8:
            raise ParameterError(f"{o}.aa_order [-, integer 0..8] must be 0 (no filter) to 8, "
                                 f"got {self.aa_order!r}")
        object.__setattr__(self, "aa_cutoff", _check(o, "aa_cutoff", self.aa_cutoff, lo=0.0,
                                                     strict_lo=self.aa_order > 0, hi=1e6))
        object.__setattr__(self, "delay", _check(o, "delay", self.delay, lo=0.0,
                                                 strict_lo=False, hi=0.01))
        object.__setattr__(self, "gain", _phase3(o, "gain", self.gain, lo=0.5, hi=2.0))
        object.__setattr__(self, "offset", _phase3(o, "offset", self.offset, lo=-5.0,
                                                    strict_lo=False, hi=5.0))

    @property
    def ideal(self) -> bool:
        return (self.gain == (1.0, 1.0, 1.0) and self.offset == (0.0, 0.0, 0.0)
                and self.lag() == 0.0)

    def lag(self) -> float:
        """Lag [s] of the recorded currents behind the true ones at low frequency: the
        anti-alias filter's group delay at DC (``a_1/a_0`` of its denominator, e.g.
        ``sqrt(2)/(2 pi f_c)`` for a 2nd-order Butterworth) plus the sample delay."""
        if not self.aa_order:
            return float(self.delay)
        from scipy.signal import butter

        _, a = butter(self.aa_order, 2.0 * math.pi * self.aa_cutoff, analog=True)
        return float(a[-2] / a[-1]) + float(self.delay)

    def correct(self, i_abc):
        """The true currents of measured ones ``i_abc (n, 3)`` (a new array)."""
        import numpy as np

        return (np.asarray(i_abc, dtype=float) - np.asarray(self.offset)) / np.asarray(self.gain)


@dataclass(frozen=True)
class Calibration:
    """Where a unit's parameters came from: date, source traces, each estimate with its
    standard error, and the parameters kept at their data-sheet values (not separable on
    the calibration profile). Written by ``emaphm calibrate``; empty for a data sheet.

    Its provenance: ``emaphm_version`` (of the calibration), ``trace_sha256`` (one digest
    per source: of its signals, :func:`emaphm.calibration.trace_digest`) and ``digest``
    (:func:`calibration_digest`: of this block and of the parameter values the
    calibration set, :data:`CALIBRATED_FIELDS`). :func:`load_params` warns
    (:class:`CalibrationWarning`) when a block lacks it or no longer matches it: written
    or edited by hand, not by ``emaphm calibrate``."""

    date: str = ""
    sources: tuple[str, ...] = ()
    estimates: tuple[tuple[str, float, float], ...] = ()
    fixed: tuple[str, ...] = ()
    emaphm_version: str = ""
    trace_sha256: tuple[str, ...] = ()
    digest: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "date", str(self.date))
        object.__setattr__(self, "sources", tuple(str(x) for x in self.sources))
        try:
            est = tuple((str(n), float(v), float(se)) for n, v, se in self.estimates)
        except (TypeError, ValueError):
            raise ParameterError("Calibration.estimates must be a list of [name, value, "
                                 f"standard error] triples, got {self.estimates!r}") from None
        object.__setattr__(self, "estimates", est)
        object.__setattr__(self, "fixed", tuple(str(x) for x in self.fixed))
        object.__setattr__(self, "emaphm_version", str(self.emaphm_version))
        object.__setattr__(self, "trace_sha256", tuple(str(x) for x in self.trace_sha256))
        object.__setattr__(self, "digest", str(self.digest))

    @property
    def claimed(self) -> bool:
        """Whether the block says the unit was calibrated (a date, sources or estimates)."""
        return bool(self.date or self.sources or self.estimates)


class CalibrationWarning(UserWarning):
    """A parameter file's ``[calibration]`` block that ``emaphm calibrate`` did not write as
    it stands: without provenance, or edited since (:func:`check_calibration`)."""


#: The parameter values a calibration sets (:func:`emaphm.calibration.apply_deviations`),
#: covered by the block's digest with the block itself.
CALIBRATED_FIELDS: tuple[tuple[str, str], ...] = (
    ("motor", "J_m"), ("motor", "c0"), ("motor", "R"), ("motor", "L"), ("motor", "C_m"),
    ("transmission", "FSJ"), ("transmission", "FDJ"), ("load", "J_l"), ("load", "T_0"),
    ("sensors", "gain"), ("sensors", "offset"))

#: The drive's settings a calibration may estimate where the user does not know them
#: (:data:`emaphm.calibration.DRIVE_SETTINGS`), by the section that holds each: the digest
#: covers the value of each that the block's estimates name.
CALIBRATED_DRIVE_FIELDS: dict[str, str] = {
    "velocity_feedforward": "controller", "torque_feedforward": "controller",
    "speed_filter_s": "controller", "current_reference_filter_s": "controller",
    "speed_reference_weight": "controller", "Kp": "controller", "Kp_w": "controller",
    "Ki_w": "controller", "Kp_i": "inverter", "Ki_i": "inverter"}


def calibration_digest(params: "ActuatorParams") -> str:
    """``"sha256:..."`` of the ``[calibration]`` block of ``params`` (its digest left out)
    and of the values of :data:`CALIBRATED_FIELDS`, as canonical JSON (every number a
    float, written exactly): a file read back as written gives the same digest."""
    import hashlib
    import json

    c = params.calibration
    values = {}
    for sec, name in CALIBRATED_FIELDS:
        v = getattr(getattr(params, sec), name)
        values[f"{sec}.{name}"] = [float(x) for x in v] if isinstance(v, tuple) else float(v)
    for name, _, _ in c.estimates:
        if name in CALIBRATED_DRIVE_FIELDS:
            sec = CALIBRATED_DRIVE_FIELDS[name]
            values[f"{sec}.{name}"] = float(getattr(getattr(params, sec), name))
        elif name == "stribeck":
            # the Stribeck speed a calibration estimated (a file calibrated before it was
            # estimated keeps its digest: the value is covered only where the block names it)
            values["transmission.omega_s"] = float(params.transmission.omega_s)
    content = {"calibration": {"date": c.date, "sources": list(c.sources),
                               "estimates": [[n, float(v), float(se)] for n, v, se in c.estimates],
                               "fixed": list(c.fixed), "emaphm_version": c.emaphm_version,
                               "trace_sha256": list(c.trace_sha256)},
               "values": values}
    text = json.dumps(content, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return "sha256:" + hashlib.sha256(text.encode()).hexdigest()


def check_calibration(params: "ActuatorParams", source: str = "parameters") -> None:
    """Warn (:class:`CalibrationWarning`, one line) when the ``[calibration]`` block of
    ``params`` claims a calibration without its provenance (no digest: written by hand
    or by an older emaphm), or when its digest does not match the block and the
    calibrated values (:func:`calibration_digest`: edited after ``emaphm calibrate``
    wrote them). A data sheet (an empty block) says nothing."""
    import warnings

    c = params.calibration
    if not c.claimed and not c.digest:
        return
    if not c.digest:
        warnings.warn(f"{source}: its [calibration] block has no provenance (no digest of what "
                      "emaphm calibrate wrote): its estimates are taken on trust; run emaphm "
                      "calibrate on the unit's healthy traces to write them, or remove the block "
                      "to use the values as a data sheet", CalibrationWarning, stacklevel=3)
    elif c.digest != calibration_digest(params):
        warnings.warn(f"{source}: its [calibration] block does not match its digest: the "
                      "estimates or the calibrated parameters (motor, friction, load, sensors) "
                      "were edited after emaphm calibrate wrote them; calibrate the unit again, "
                      "or remove the block to use the values as a data sheet",
                      CalibrationWarning, stacklevel=3)


@dataclass(frozen=True)
class Plant:
    """Physics that only the reference plant has (the monitoring model lacks it).

    Dry friction falls from ``FSJ`` to ``FDJ`` with speed (Stribeck):
    ``T_f = FDJ + (FSJ - FDJ) exp(-(omega/omega_s)^2)`` while moving; default
    ``omega_s = 1 rad/s``. (Files written before 0.3 also held the
    backlash contact's ``K_c`` and ``D_c`` here; they are read into ``[transmission]``.)
    """

    omega_s: float = 1.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "omega_s", _check("Plant", "omega_s", self.omega_s, lo=0.0))


_SECTIONS = {"motor": Motor, "inverter": Inverter, "controller": Controller,
             "transmission": Transmission, "load": Load, "plant": Plant,
             "sensors": CurrentSensors, "calibration": Calibration}

#: Sections and fields added after files were first written: a file without them takes
#: the defaults (a healthy winding, the default plant physics, ideal sensors, no calibration).
_OPTIONAL_SECTIONS = {"plant", "sensors", "calibration"}
_OPTIONAL_FIELDS = {"motor": {"L_sigma", "mu", "R_f"}, "load": {"T_0"},
                    "inverter": {"dead_time", "device_drop"},
                    "controller": {"velocity_feedforward", "torque_feedforward",
                                   "torque_feedforward_inertia", "speed_filter_s",
                                   "speed_reference_weight", "current_reference_filter_s",
                                   "delay_periods", "decoupling", "decoupling_L",
                                   "emf_feedforward", "T_max", "I_max"},
                    "transmission": {"K_c", "D_c", "omega_s"},
                    "sensors": {"aa_order", "aa_cutoff", "delay"},
                    "calibration": {"emaphm_version", "trace_sha256", "digest"}}


@dataclass(frozen=True)
class ActuatorParams:
    """The whole actuator: motor, inverter, controller, transmission, load."""

    motor: Motor = field(default_factory=Motor)
    inverter: Inverter = field(default_factory=Inverter)
    controller: Controller = field(default_factory=Controller)
    transmission: Transmission = field(default_factory=Transmission)
    load: Load = field(default_factory=Load)
    plant: Plant = field(default_factory=Plant)
    sensors: CurrentSensors = field(default_factory=CurrentSensors)
    calibration: Calibration = field(default_factory=Calibration)
    name: str = "custom"
    #: This actuator's detection thresholds, ``(name, value)`` pairs of the fields of
    #: :class:`emaphm.modes.Thresholds` in place of the defaults (the file's
    #: ``[thresholds]`` table, written by ``emaphm assess``); empty: the defaults. They
    #: apply under the ``physical`` fault model, and all but the short circuit's under the
    #: ``paper``'s (:func:`emaphm.modes.thresholds_for`).
    thresholds: tuple[tuple[str, float], ...] = ()

    def __post_init__(self) -> None:
        for sec, cls in _SECTIONS.items():
            if not isinstance(getattr(self, sec), cls):
                raise ParameterError(f"ActuatorParams.{sec} must be a {cls.__name__}, "
                                     f"got {type(getattr(self, sec)).__name__}")
        object.__setattr__(self, "thresholds", _check_thresholds(self.thresholds))

    def to_dict(self) -> dict[str, Any]:
        """Plain nested dict (JSON/TOML serialisable); ``thresholds`` only where set."""
        d: dict[str, Any] = {"name": self.name}
        for sec in _SECTIONS:
            sub = asdict(getattr(self, sec))
            # a setting left to the data sheet (None) is left out: TOML has no null
            d[sec] = {k: ([list(x) if isinstance(x, tuple) else x for x in v]
                          if isinstance(v, tuple) else v) for k, v in sub.items() if v is not None}
        if self.thresholds:
            d["thresholds"] = dict(self.thresholds)
        return d

    @classmethod
    def from_dict(cls, data: dict[str, Any], *, source: str = "parameters",
                  defaults: "ActuatorParams | None" = None) -> "ActuatorParams":
        """Build from a nested dict. Sections or fields left out are errors,
        unless ``defaults`` is given, which then fills them."""
        if not isinstance(data, dict):
            raise ParameterError(f"{source}: expected a table of sections, got {type(data).__name__}")
        unknown = set(data) - set(_SECTIONS) - {"name", "thresholds"}
        if "datasheet" in unknown:
            raise ParameterError(
                f"{source}: a [datasheet] table is a motor's catalogue page, not parameters; "
                "convert it first: emaphm params --datasheet FILE --out PARAMS.toml, and give "
                "PARAMS.toml")
        if unknown:
            raise ParameterError(
                f"{source}: unknown section(s) {sorted(unknown)}; expected "
                f"{sorted(_SECTIONS)}")
        data = _moved_contact(data)
        parts: dict[str, Any] = {}
        for sec, klass in _SECTIONS.items():
            given = data.get(sec)
            base = getattr(defaults, sec) if defaults is not None else None
            if given is None and sec in _OPTIONAL_SECTIONS:
                parts[sec] = base if base is not None else klass()
                continue
            if given is None:
                if base is None:
                    raise ParameterError(f"{source}: missing section [{sec}] with fields "
                                         + ", ".join(f"{f.name} [{_UNITS[f.name]}]" for f in fields(klass)))
                parts[sec] = base
                continue
            if not isinstance(given, dict):
                raise ParameterError(f"{source}: [{sec}] must be a table, got {given!r}")
            names = {f.name for f in fields(klass)}
            extra = set(given) - names
            if extra:
                raise ParameterError(
                    f"{source}: unknown field(s) {sorted(extra)} in [{sec}]; known fields: "
                    + ", ".join(f"{n} [{_UNITS[n]}]" for n in sorted(names)))
            missing = names - set(given) - _OPTIONAL_FIELDS.get(sec, set())
            if missing and base is None:
                raise ParameterError(
                    f"{source}: [{sec}] is missing "
                    + ", ".join(f"{n} [{_UNITS[n]}]" for n in sorted(missing)))
            kw = {n: given[n] for n in given}
            try:
                parts[sec] = replace(base, **kw) if base is not None else klass(**kw)
            except ParameterError as exc:        # name the file and the section
                raise ParameterError(f"{source}: {exc}") from None
        name = data.get("name", defaults.name if defaults is not None else "custom")
        limits = data.get("thresholds", defaults.thresholds if defaults is not None else ())
        if isinstance(limits, dict):
            limits = tuple(limits.items())
        elif limits and not isinstance(limits, tuple):
            raise ParameterError(f"{source}: [thresholds] must be a table of name = value, "
                                 f"got {limits!r}")
        try:
            params = cls(name=str(name), thresholds=limits, **parts)
        except ParameterError as exc:
            raise ParameterError(f"{source}: {exc}") from None
        check_plausible(params, source=source)
        return params


def _check_thresholds(items: Any) -> tuple[tuple[str, float], ...]:
    """``[thresholds]`` as sorted ``(name, value)`` pairs, each a field of
    :class:`emaphm.modes.Thresholds` with a value in (0, 1)."""
    if not items:
        return ()
    from .modes import Thresholds       # local: the modes read these parameters

    known = {f.name for f in fields(Thresholds)}
    out = {}
    try:
        pairs = list(dict(items).items())
    except (TypeError, ValueError):
        raise ParameterError(f"[thresholds] must be a table of name = value, got {items!r}") from None
    for name, value in pairs:
        if name not in known:
            raise ParameterError(f"[thresholds] has an unknown threshold {name!r}; known: "
                                 + ", ".join(sorted(known)))
        if isinstance(value, bool) or not isinstance(value, (int, float)) \
                or not math.isfinite(value) or not 0.0 < value < 1.0:
            raise ParameterError(f"[thresholds] {name} = {value!r} must be a number in (0, 1)")
        out[str(name)] = float(value)
    return tuple(sorted(out.items()))


def _moved_contact(data: dict[str, Any]) -> dict[str, Any]:
    """``data`` with a file's ``[plant] K_c, D_c`` (where files before 0.3 kept the backlash
    contact) moved to ``[transmission]``, unless that section gives them itself."""
    plant = data.get("plant")
    if not isinstance(plant, dict) or not ({"K_c", "D_c"} & set(plant)):
        return data
    data = dict(data)
    data["plant"] = {k: v for k, v in plant.items() if k not in ("K_c", "D_c")}
    tr = data.get("transmission")
    if tr is None or isinstance(tr, dict):
        data["transmission"] = {**{k: plant[k] for k in ("K_c", "D_c") if k in plant}, **(tr or {})}
    return data


class PlausibilityWarning(UserWarning):
    """A parameter near the edge of what servo actuators have (:data:`PLAUSIBLE`): used,
    but worth a look at its unit; the command line prints it as one line."""


#: The healthy values servo actuators have, per field: ``(refused below, warned below,
#: warned above, refused above)`` in the field's SI unit (None: no bound), and the unit
#: to give where a value is beyond. A value beyond is refused (it makes no actuator, or
#: makes the models' numbers meaningless: a rotor of 1e-30 kg m^2 gives a trace of NaN),
#: a value near is used with a :class:`PlausibilityWarning`. The preset and the examples
#: sit well inside; the edges span servo motors from about 50 W to 100 kW.
PLAUSIBLE: dict[tuple[str, str], tuple[float | None, float | None, float | None, float | None,
                                       str]] = {
    ("motor", "p"): (None, None, 30, 100, "pole pairs, half the poles"),
    ("motor", "R"): (1e-4, 1e-3, 100.0, 1e3, "ohm per phase: 3.15 ohm, not 3150 milliohm"),
    ("motor", "L"): (1e-7, 1e-5, 0.3, 1.0, "henries per phase: 22 mH = 0.022"),
    ("motor", "c0"): (1e-4, 1e-3, 10.0, 100.0, "V s/rad peak per phase: ke = 135 V/krpm is "
                      "c0 = 1.05; convert a catalogue's ke with emaphm params --datasheet"),
    ("motor", "J_m"): (1e-9, 1e-7, 10.0, 100.0, "kg m^2: 7.7 kg cm^2 = 7.7e-4"),
    ("motor", "C_m"): (None, None, 1.0, 10.0, "N m s/rad"),
    ("motor", "T_max"): (1e-3, 0.05, 5e3, 1e5, "N m"),
    ("motor", "I_max"): (1e-2, 0.3, 1e3, 1e4, "A peak"),
    ("motor", "ecc_phase"): (-1e3, None, None, 1e3, "rad"),
    ("motor", "R_f"): (None, None, None, 1e6, "ohm"),
    ("inverter", "V_dc"): (1.0, 12.0, 1500.0, 1e4, "volts"),
    ("inverter", "Kp_i"): (None, None, 1e4, 1e5, "V/A"),
    ("inverter", "Ki_i"): (None, None, 1e8, 1e9, "V/(A s)"),
    ("inverter", "I_trip"): (None, None, 5e3, 1e5, "A peak"),
    ("controller", "Kp"): (None, None, 1e4, 1e5, "1/s"),
    ("controller", "Ki"): (None, None, 1e8, 1e9, "1/s^2"),
    ("controller", "Kd"): (None, None, 100.0, 1e3, "-"),
    ("controller", "omega_max"): (None, 1.0, 1e4, 1e5, "rad/s: 3000 rpm = 314.16"),
    ("controller", "Kp_w"): (None, None, 1e4, 1e5, "N m s/rad"),
    ("controller", "Ki_w"): (None, None, 1e7, 1e8, "N m/rad"),
    ("controller", "k_T"): (1e-4, 1e-3, 20.0, 150.0, "N m per A peak"),
    ("transmission", "FSJ"): (None, None, 1e3, 1e5, "N m"),
    ("transmission", "FDJ"): (None, None, 1e3, 1e5, "N m"),
    ("transmission", "backlash"): (None, None, 0.1, 1.0, "radians at the motor: 1 deg = "
                                   "0.01745"),
    ("transmission", "K_c"): (1e-3, 1.0, 1e8, 1e10, "N m/rad"),
    ("transmission", "D_c"): (None, None, 1e4, 1e6, "N m s/rad"),
    ("transmission", "omega_s"): (None, None, 1e3, 1e4, "rad/s"),
    ("load", "J_l"): (1e-9, 1e-7, 100.0, 1e4, "kg m^2 at the motor shaft"),
    ("load", "C_l"): (None, None, 100.0, 1e3, "N m s/rad"),
    ("plant", "omega_s"): (1e-3, 1e-2, 1e3, 1e4, "rad/s"),
}
#: The sampled loops' gain per control period above which they are unstable (a P loop
#: ``x += g (r - x)`` diverges for ``g > 2``): the current loop on the winding
#: (``Kp_i T_s / L``) and the speed loop on the rotor alone, as when the backlash is open
#: (``Kp_w T_s / J_m``; the plant stays finite up to about 100, diverges at 750: refused
#: from 20, warned from 2). The preset's are 0.24 and 0.10.
LOOP_GAIN_LIMIT = 2.0
SPEED_LOOP_REFUSED = 20.0


def _ranges(params: ActuatorParams, where: str) -> list[str]:
    """Refuse a field beyond :data:`PLAUSIBLE`; the warnings of those near its edges."""
    import warnings

    near = []
    for (sec, name), (lo, warn_lo, warn_hi, hi, unit) in PLAUSIBLE.items():
        value = getattr(getattr(params, sec), name)
        values = value if isinstance(value, tuple) else (value,)
        field_ = f"{sec}.{name} [{_UNITS[name]}]"
        for v in (min(values), max(values)):
            if (lo is not None and v < lo) or (hi is not None and v > hi):
                span = (f"{lo:g} to {hi:g}" if lo is not None and hi is not None
                        else f"below {hi:g}" if hi is not None else f"above {lo:g}")
                raise ParameterError(f"{where} {field_} = {v:g} is beyond what any servo actuator "
                                     f"has ({span}): give {unit}")
            if (warn_lo is not None and v < warn_lo) or (warn_hi is not None and v > warn_hi):
                near.append(f"{field_} = {v:g} is unlike a servo actuator's (usually "
                            f"{warn_lo if warn_lo is not None else lo or 0:g} to "
                            f"{warn_hi if warn_hi is not None else hi:g}): check it is in {unit}")
                break
    for text in near:
        warnings.warn(f"{where} {text}", PlausibilityWarning, stacklevel=4)
    return near


def _loops(params: ActuatorParams, where: str) -> None:
    """Refuse gains that make the sampled current or speed loop diverge on this motor; warn
    of a speed loop gain above the limit of the rotor alone."""
    import warnings

    m, inv, c = params.motor, params.inverter, params.controller
    g_i = inv.Kp_i * inv.T_s / min(m.L)
    if g_i > LOOP_GAIN_LIMIT:
        raise ParameterError(
            f"{where} inverter.Kp_i = {inv.Kp_i:g} V/A on motor.L = {min(m.L):g} H at {inv.f_pwm:g} "
            f"Hz is a current loop gain of {g_i:.3g} per period (Kp_i T_s / L), above the "
            f"{LOOP_GAIN_LIMIT:g} where a sampled loop diverges: check motor.L (henries) or derive "
            "the gains for this motor (emaphm params --datasheet)")
    g_w = c.Kp_w * inv.T_s / m.J_m
    if g_w > SPEED_LOOP_REFUSED:
        raise ParameterError(
            f"{where} controller.Kp_w = {c.Kp_w:g} N m s/rad on motor.J_m = {m.J_m:g} kg m^2 is a "
            f"speed loop gain of {g_w:.3g} per period (Kp_w T_s / J_m), far above the "
            f"{LOOP_GAIN_LIMIT:g} where the loop on the rotor alone (the backlash open) diverges: "
            "give J_m in kg m^2 (7.7 kg cm^2 = 7.7e-4) or derive the gains for this motor "
            "(emaphm params --datasheet)")
    if g_w > LOOP_GAIN_LIMIT:
        warnings.warn(f"{where} controller.Kp_w = {c.Kp_w:g} N m s/rad on motor.J_m = {m.J_m:g} "
                      f"kg m^2 is a speed loop gain of {g_w:.3g} per period, above the "
                      f"{LOOP_GAIN_LIMIT:g} of a stable loop on the rotor alone: check J_m, or "
                      "derive the gains for this motor", PlausibilityWarning, stacklevel=4)


def check_plausible(params: ActuatorParams, *, source: str = "parameters") -> None:
    """Refuse healthy parameters no servo actuator has, with the likely unit slip named;
    warn (:class:`PlausibilityWarning`) of those near the edge (:data:`PLAUSIBLE`).

    Each field is checked on its own at construction; this checks them together, on
    parameters a user gives (files, specs), not on faulty ones (a 99 % short is allowed
    to have an implausible phase). ParameterError names the field and the fix.
    """
    m, inv = params.motor, params.inverter
    where = f"{source}:"
    if not 500.0 <= inv.f_pwm <= 100e3:
        why = (f"the models take one step per PWM period, so {inv.f_pwm:g} Hz would ask for "
               f"{0.5 * inv.f_pwm:.3g} steps per 0.5 s test" if inv.f_pwm > 100e3 else
               "a current loop that slow cannot control a servo motor; give hertz, not kilohertz")
        raise ParameterError(f"{where} inverter.f_pwm [Hz] = {inv.f_pwm:g} is outside 500 Hz to "
                             f"100 kHz, the range of servo drives (8000 = 8 kHz): {why}")
    for j, ph in enumerate("abc"):
        R, L = m.R[j], m.L[j]
        if L > 1.0:
            raise ParameterError(f"{where} motor.L [H] of phase {ph} = {L:g} H is above 1 H; give "
                                 "henries (22 mH = 0.022)")
        if R * m.I_max > inv.V_dc:
            raise ParameterError(
                f"{where} motor.R [ohm] of phase {ph} = {R:g} times motor.I_max [A] = {m.I_max:g} "
                f"is {R * m.I_max:g} V, above inverter.V_dc = {inv.V_dc:g} V: the drive could not "
                "push its rated current; give ohms (3.15 ohm, not 3150 milliohm)")
        if L / R < 2.0 * inv.T_s:
            raise ParameterError(
                f"{where} the electrical time constant L/R of phase {ph} = {L / R * 1e6:.3g} us is "
                f"under two PWM periods ({2e6 * inv.T_s:.3g} us): no current loop at "
                f"{inv.f_pwm:g} Hz controls it; check the units of motor.L [H] and motor.R [ohm]")
    _ranges(params, where)
    _loops(params, where)


def siemens_1fk7060() -> ActuatorParams:
    """The paper's bench: Siemens 1FK7060-2AC71 on an S120 drive (reconstructed).

    Motor values are reconstructed from the 1FK7 family and the order code, NOT
    taken from the data sheet (the paper's Table 2 is missing from our copy):
    p = 4, R = 3.15 ohm, L = 22 mH (T_el = 7 ms), k_E = 135 V/krpm line-to-line
    RMS -> c0 = sqrt(2)*135/sqrt(3)/104.72 = 1.0526 V s/rad peak per phase,
    J_m = 7.7e-4 kg m^2, T_max = 18 N m, I_max = 10 A RMS = 14.14 A peak.
    Mechanics and controller are design defaults of emaphm: a load inertia
    equal to the rotor's, dry friction 0.08 / 0.12 N m (dynamic / static),
    backlash 2e-4 rad, DC link 600 V, PWM and control at 8 kHz.
    """
    return ActuatorParams(name="siemens-1fk7060-2ac71")


@dataclass(frozen=True)
class Tuning:
    """The drive's settings :func:`derive_tuning` gives an actuator: the dq current loop
    (``Kp_i`` V/A, ``Ki_i`` V/(A s)), the overcurrent trip ``I_trip`` [A peak], the
    position gain ``Kp`` [1/s], the speed loop (``Kp_w`` N m s/rad, ``Ki_w`` N m/rad) and
    the torque constant setting ``k_T`` [N m/A peak]."""

    Kp_i: float
    Ki_i: float
    I_trip: float
    Kp: float
    Kp_w: float
    Ki_w: float
    k_T: float


def derive_tuning(motor: Motor, f_pwm: float, J_load: float,
                  template: "ActuatorParams | None" = None) -> Tuning:
    """The preset's tuning carried over to another actuator, loop by loop.

    The preset's loops (:func:`siemens_1fk7060`, our design) are read as bandwidths
    relative to the control rate and gains proportional to the plant they control, so
    that another motor's loops respond as the preset's do:

    ==========  ====================================================================
    setting     rule (``0``: the template's value, ``r = f_pwm / f_pwm0``)
    ==========  ====================================================================
    ``Kp_i``    ``Kp_i0 (L / L0) r``: the current loop crosses over at the same fraction
                of the control rate (0.2375 rad per period: 1900 rad/s at 8 kHz)
    ``Ki_i``    ``Ki_i0 (R / R0) r``: its zero stays on the winding's pole R/L
    ``Kp``      ``Kp0 r``: the position loop as fast relative to the current loop
    ``Kp_w``    ``Kp_w0 (J / J0) r``: the speed loop's bandwidth ``Kp_w / J`` scales as
                the current loop's, ``J = J_m + J_load`` at the motor shaft
    ``Ki_w``    ``Ki_w0 (J / J0) r^2``: its integral corner in the same ratio
    ``I_trip``  ``I_trip0 (T_max / k_T) / (T_max0 / k_T0)``: the same margin over the
                current of the peak torque
    ``k_T``     ``1.5 c0``, the healthy motor's torque per peak ampere
    ==========  ====================================================================

    With the template's own motor, rate and load every ratio is 1: the preset's values.
    """
    t = template if template is not None else siemens_1fk7060()
    tm, ti, tc = t.motor, t.inverter, t.controller
    r = f_pwm / ti.f_pwm
    L, R = sum(motor.L) / 3.0, sum(motor.R) / 3.0
    J = motor.J_m + J_load
    k_T = 1.5 * sum(motor.c0) / 3.0
    return Tuning(
        Kp_i=ti.Kp_i * (L / (sum(tm.L) / 3.0)) * r,
        Ki_i=ti.Ki_i * (R / (sum(tm.R) / 3.0)) * r,
        I_trip=ti.I_trip * (motor.T_max / k_T) / (tm.T_max / tc.k_T),
        Kp=tc.Kp * r,
        Kp_w=tc.Kp_w * (J / (tm.J_m + t.load.J_l)) * r,
        Ki_w=tc.Ki_w * (J / (tm.J_m + t.load.J_l)) * r * r,
        k_T=k_T,
    )


def read_toml(path: str | os.PathLike[str], what: str,
              error: type[Exception] = ValueError) -> dict[str, Any]:
    """The table of a TOML file; ``error`` naming ``what`` and the path when it cannot be read."""
    from ._files import regular_file

    p = regular_file(path, what, give="a TOML file", error=error, missing=error)
    try:
        with p.open("rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise error(f"{what} {p} does not exist") from None
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{what} {p} is not valid TOML: {exc}") from None
    except UnicodeDecodeError:
        raise error(f"{what} {p} is not a UTF-8 text file; give a TOML file") from None


def load_params(path: str | os.PathLike[str], *, partial: bool = False) -> ActuatorParams:
    """Read parameters from a TOML file with sections [motor], [inverter],
    [controller], [transmission], [load] (SI units, per-phase values as lists).

    With ``partial=True`` fields left out are taken from :func:`siemens_1fk7060`.
    """
    p = Path(path)
    data = read_toml(p, "parameter file", ParameterError)
    params = ActuatorParams.from_dict(data, source=str(p),
                                      defaults=siemens_1fk7060() if partial else None)
    check_calibration(params, source=str(p))
    return params


def _with_units(lines: list[str]) -> list[str]:
    """TOML lines with each field's unit as a comment above it (``# R [ohm]``)."""
    out = ["# emaphm actuator parameters, SI units; the unit of each field is in the comment",
           "# above it. Per-phase values are lists (a, b, c)."]
    section = ""
    for line in lines:
        if line.startswith("["):
            section = line.strip()
        key = line.split("=", 1)[0].strip() if "=" in line and not line.startswith(" ") else ""
        if section == "[thresholds]":         # values of the measures on k, not of the
            out.append(line)                  # parameters of the same name (backlash [rad])
            if line == section:
                out.append("# detection thresholds of each mode's measure on k (dimensionless; "
                           "emaphm assess tunes them)")
            continue
        if key in _UNITS:
            out.append(f"# {key} [{_UNITS[key]}]")
        out.append(line)
    return out


def save_params(params: ActuatorParams, path: str | os.PathLike[str]) -> Path:
    """Write parameters as TOML (atomically: a temporary file, then a rename)."""
    p = Path(path)
    text = "\n".join(_with_units(tomli_w.dumps(params.to_dict()).splitlines())) + "\n"
    from ._files import atomic_write_text

    return atomic_write_text(p, text)


# ----------------------------------------------------------------------------- which actuator

#: Where the parameters an identification used came from, in the order they are looked
#: for (:func:`resolve_params`): given by the caller, a health history's calibration of
#: the unit, the trace's own metadata (the actuator it was simulated or recorded on), the
#: preset (:func:`siemens_1fk7060`).
PARAMS_SOURCES = ("given", "calibration", "trace", "preset")


class ActuatorMismatchWarning(UserWarning):
    """Parameters given for a trace that names another actuator (another name) in its
    metadata; a calibration of the trace's own actuator does not warn. The command line
    prints it as one line."""


def as_params(value: Any, *, what: str = "params") -> "ActuatorParams | None":
    """Parameters from what the API accepts everywhere: an :class:`ActuatorParams`, a
    mapping (:meth:`ActuatorParams.to_dict`'s form; sections left out are the preset's,
    as a file given to ``--params``) or the path of a TOML file (:func:`load_params`,
    ``partial=True``); None stays None. Anything else is a :class:`TypeError` that names
    ``what``."""
    if value is None or isinstance(value, ActuatorParams):
        return value
    if isinstance(value, dict) or (hasattr(value, "keys") and hasattr(value, "__getitem__")
                                   and not isinstance(value, (str, bytes))):
        return ActuatorParams.from_dict(dict(value), source=what, defaults=siemens_1fk7060())
    if isinstance(value, (str, os.PathLike)):
        return load_params(value, partial=True)
    raise TypeError(f"{what} must be an ActuatorParams, a dict of its sections or the path of a "
                    f"TOML parameter file, got {type(value).__name__}")


def trace_params(trace: Any) -> "ActuatorParams | None":
    """The actuator a trace names in its metadata (``meta["parameters"]``, written by
    :func:`emaphm.simulate.simulate`), or None where it names none. Metadata that do not
    read as parameters are a :class:`ParameterError` that says so."""
    meta = getattr(trace, "meta", trace)
    data = meta.get("parameters") if isinstance(meta, dict) else None
    if data is None:
        return None
    try:
        return ActuatorParams.from_dict(data, source="the trace's metadata \"parameters\"")
    except (ParameterError, TypeError, ValueError) as exc:
        raise ParameterError(f"{exc}; give the actuator's parameters (params=, --params), or "
                             "remove \"parameters\" from the trace's metadata") from None


def resolve_params(params: Any, trace: Any = None, *,
                   warn: bool = True) -> "tuple[ActuatorParams, str]":
    """``(parameters, source)``: the actuator a trace is identified or diagnosed on, and
    where it came from (:data:`PARAMS_SOURCES`).

    ``params`` given (an :class:`ActuatorParams`, a dict or a TOML path, :func:`as_params`)
    wins (``"given"``); a health history's calibration of the unit is given the same way
    by :func:`emaphm.prognosis.record_inspection`, which reports ``"calibration"``; else
    the trace's own (:func:`trace_params`, ``"trace"``); else the preset (``"preset"``).
    ``trace`` may be a list of traces: their own actuators must then agree. With ``warn``,
    parameters given for a trace that names another actuator (another ``name``) warn
    (:class:`ActuatorMismatchWarning`); a calibration of the trace's own actuator, or a
    variant of it, keeps its name and does not.
    """
    traces = list(trace) if isinstance(trace, (list, tuple)) else [trace]
    owns = [trace_params(t) for t in traces if t is not None]
    own = next((p for p in owns if p is not None), None)
    if any(p is not None and p != own for p in owns):
        raise ValueError("the traces name different actuators in their metadata; give the "
                         "parameters of the one they were recorded on (params=, --params)")
    given = as_params(params)
    if given is None:
        return (own, "trace") if own is not None else (siemens_1fk7060(), "preset")
    if warn and own is not None and given.name != own.name:
        import warnings

        warnings.warn(f"the trace names the actuator {shown(own.name)} in its metadata, and "
                      f"other parameters ({shown(given.name)}) were given: the monitoring "
                      "model uses the given ones; leave params (--params) out to use the "
                      "trace's own", ActuatorMismatchWarning, stacklevel=2)
    return given, "given"
