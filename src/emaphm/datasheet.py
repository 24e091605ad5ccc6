"""A motor from its catalogue page: a ``[datasheet]`` table in the units catalogues print
(``emaphm params --datasheet NAMEPLATE.toml``) converted to emaphm's per-phase SI
parameters, with the drive's gains derived as the preset's were
(:func:`emaphm.params.derive_tuning`). Every conversion is in ``docs/bench-import.md``.

========================  =========================  ===================================
nameplate field           catalogue convention       emaphm field
========================  =========================  ===================================
``poles``                 number of poles (even)     ``Motor.p = poles / 2``
``ke``                    V per 1000 rpm, line to    ``Motor.c0 = sqrt(2) ke / sqrt(3) /
                          line, RMS                  (1000 2 pi / 60)`` [V s/rad]
``kt`` (check only)       N m per A RMS              compared with ``1.5 sqrt(2) c0``
``r_ll`` or ``r_ph``      line to line / per phase   ``Motor.R = r_ll / 2`` (star)
``l_ll`` or ``l_ph``      line to line / per phase   ``Motor.L = l_ll / 2`` (star)
``j_rotor``               kg cm^2 (any inertia)      ``Motor.J_m`` [kg m^2]
``t_max``                 N m                        ``Motor.T_max``
``i_max``                 A RMS                      ``Motor.I_max = sqrt(2) i_max`` (peak)
``v_dc`` (optional)       V                          ``Inverter.V_dc``
``f_pwm`` (optional)      Hz, kHz                    ``Inverter.f_pwm``
``gear_ratio`` (opt.)     motor turns per load turn  folds ``j_load`` onto the shaft
``j_load`` (optional)     at the load side           ``Load.J_l = j_load / gear_ratio^2``
``n_max`` (optional)      rpm                        ``Controller.omega_max`` [rad/s]
========================  =========================  ===================================

A value is a number with its unit (``"1.3 kg cm^2"``, ``"7.6 mH"``); a bare number is read
in V/krpm for ``ke`` (the catalogue's unit) and in SI for every other field (``j_rotor``
in kg m^2, ``l_ll`` in H, ``f_pwm`` in Hz): give the unit where the catalogue prints
another (:data:`ACCELERATION_RANGE` catches a rotor inertia read 1e4 times too large).

The rest comes from the template (the preset, :func:`emaphm.params.siemens_1fk7060`),
scaled to the motor where it is a design default of ours: dry and viscous friction in
proportion to the peak torque, the backlash contact's stiffness and damping in proportion
to the reduced inertia of motor and load (the same 513 Hz resonance), the load inertia
equal to the rotor's where none is given. :class:`Datasheet` says which values came from
where, and warns when ``ke`` and ``kt`` disagree by more than 5 % or a value is unlike
any servo motor.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, replace

from .params import (ActuatorParams, Controller, Inverter, Load, Motor, ParameterError,
                     Transmission, back_emf_coefficient, check_plausible, derive_tuning,
                     read_toml, siemens_1fk7060)
from .quantities import QuantityError, measure, quantity, split

__all__ = ["Nameplate", "Datasheet", "load_nameplate", "convert", "KE_KT_TOLERANCE"]

#: Largest relative disagreement of ``kt`` with the ``1.5 sqrt(2) c0`` that ``ke`` gives
#: before a warning (catalogues give kt warm, ke cold: 5-8 % apart is common).
KE_KT_TOLERANCE = 0.05
_RPM = 2.0 * math.pi / 60.0
_FIELDS = {
    "name": None, "poles": None, "ke": ("back-EMF constant", "V/krpm"),
    "kt": ("torque constant", "N m/A"), "r_ll": ("resistance", "ohm"),
    "r_ph": ("resistance", "ohm"), "l_ll": ("inductance", "H"), "l_ph": ("inductance", "H"),
    "j_rotor": ("inertia", "kg m^2"), "t_max": ("torque", "N m"), "i_max": ("current", "A"),
    "v_dc": ("voltage", "V"), "f_pwm": ("frequency", "Hz"), "gear_ratio": None,
    "j_load": ("inertia", "kg m^2"), "n_max": ("angular speed", "rpm"),
}
_REQUIRED = ("poles", "ke", "j_rotor", "t_max", "i_max")
#: The rotor's acceleration at peak torque, ``t_max / j_rotor`` [rad/s^2], of servo motors
#: from about 0.3 to 300 N m (catalogues: about 3e3 for the largest, 1e5 for the smallest);
#: outside it a warning asks for the inertia's unit (a bare 1.3 is 1.3 kg m^2, not kg cm^2).
ACCELERATION_RANGE = (300.0, 1e6)


@dataclass(frozen=True)
class Nameplate:
    """A motor's catalogue data in SI (``ke`` kept in V/krpm line-to-line RMS, as the
    conversion formula takes it; ``i_max`` RMS; ``r_ll``/``l_ll`` line to line); None
    where the nameplate leaves an optional value out."""

    name: str
    poles: int
    ke: float
    r_ll: float
    l_ll: float
    j_rotor: float
    t_max: float
    i_max: float
    kt: float | None = None
    v_dc: float | None = None
    f_pwm: float | None = None
    gear_ratio: float = 1.0
    j_load: float | None = None
    n_max: float | None = None

    @classmethod
    def from_dict(cls, data: dict, source: str = "nameplate") -> "Nameplate":
        """A nameplate from a file's tables (``{"datasheet": {...}}``) or from the
        ``[datasheet]`` table itself (``{"poles": 10, "ke": "30 V/krpm", ...}``)."""
        if isinstance(data, dict) and "datasheet" not in data and set(data) & set(_REQUIRED):
            data = {"datasheet": data}
        table = data.get("datasheet") if isinstance(data, dict) else None
        if not isinstance(table, dict):
            raise ParameterError(f"{source}: no [datasheet] table; write the motor's catalogue "
                                 "values under [datasheet] (see docs/bench-import.md)")
        extra = sorted(set(table) - set(_FIELDS))
        if extra:
            raise ParameterError(f"{source}: unknown field(s) {extra} in [datasheet]; known: "
                                 f"{', '.join(_FIELDS)}")
        missing = [f for f in _REQUIRED if f not in table]
        for pair in (("r_ll", "r_ph"), ("l_ll", "l_ph")):
            if pair[0] in table and pair[1] in table:
                raise ParameterError(f"{source}: [datasheet] gives both {pair[0]} (line to line) "
                                     f"and {pair[1]} (per phase); give one of them")
            if pair[0] not in table and pair[1] not in table:
                missing.append(f"{pair[0]} (or {pair[1]})")
        if missing:
            raise ParameterError(f"{source}: [datasheet] is missing {', '.join(missing)}")
        kw = {}
        for key, value in table.items():
            where = f"{source}: [datasheet] {key}"
            if key == "name":
                kw[key] = str(value)
            elif key == "poles":
                kw[key] = _poles(value, where)
            elif key == "gear_ratio":
                kw[key] = _positive(value, where)
                if not GEAR_RATIOS[0] <= kw[key] <= GEAR_RATIOS[1]:
                    raise ParameterError(f"{where}: {kw[key]:g} is beyond the gear ratios of "
                                         f"actuators ({GEAR_RATIOS[0]:g} to {GEAR_RATIOS[1]:g} "
                                         "motor turns per load turn)")
            else:
                kind, default = _FIELDS[key]
                try:
                    v = (_ke(value, where) if key == "ke" else
                         quantity(value, kind, where=where, default=default))
                except QuantityError as exc:
                    raise ParameterError(str(exc)) from None
                kw[key] = _positive(v, where)
        for key, half in (("r_ph", "r_ll"), ("l_ph", "l_ll")):
            if key in kw:
                kw[half] = 2.0 * kw.pop(key)
        kw.setdefault("name", "custom")
        return cls(**kw)


#: The most poles of a servo motor (torque motors reach about 100; emaphm's
#: :data:`~emaphm.params.PLAUSIBLE` takes up to 100 pole pairs) and the span of gear
#: ratios (motor turns per load turn) an actuator has.
MAX_POLES = 200
GEAR_RATIOS = (1e-3, 1e5)
#: The nameplate field each converted parameter comes from, named in a refusal.
_FROM = {"motor.p": "poles", "motor.c0": "ke", "motor.R": "r_ll (or r_ph)",
         "motor.L": "l_ll (or l_ph)", "motor.J_m": "j_rotor", "motor.T_max": "t_max",
         "motor.I_max": "i_max", "inverter.V_dc": "v_dc", "inverter.f_pwm": "f_pwm",
         "load.J_l": "j_load and gear_ratio", "controller.omega_max": "n_max",
         "controller.k_T": "ke"}


def _poles(value, where: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 2 <= value <= MAX_POLES:
        raise ParameterError(f"{where}: expected the number of poles, an even integer from 2 to "
                             f"{MAX_POLES} (the most a servo motor has), got {value!r:.40}")
    if value % 2:
        raise ParameterError(f"{where}: {value} poles is odd; poles counts the magnet poles "
                             f"(twice the pole pairs): {value} pole pairs is poles = {2 * value}")
    return value


def _positive(value, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) \
            or not math.isfinite(value) or value <= 0:
        raise ParameterError(f"{where}: expected a positive number, got {value!r:.40}")
    return float(value)


def _ke(value, where: str) -> float:
    """``ke`` in V/krpm (line-to-line RMS): a bare number is taken in V/krpm, a number in
    V/krpm (or mV/rpm) is kept as written, any other back-EMF unit is converted."""
    number, unit = split(value, "back-EMF constant", where=where)
    per_krpm = measure("V/krpm")
    if unit is None or unit.factor == per_krpm.factor:
        return number
    return unit.to_si(number) / per_krpm.factor


@dataclass(frozen=True)
class Datasheet:
    """The converted parameters, where each value came from, and the warnings."""

    params: ActuatorParams
    derived: tuple[tuple[str, float, str], ...]
    from_template: tuple[str, ...]
    warnings: tuple[str, ...]

    def summary(self) -> str:
        lines = [f"{name:22s} {value:12.6g}  {how}" for name, value, how in self.derived]
        lines.append("from the template (the preset's design defaults, scaled where said): "
                     + ", ".join(self.from_template))
        return "\n".join(lines)


def load_nameplate(path: str | os.PathLike[str]) -> Nameplate:
    """Read a ``[datasheet]`` TOML file (:class:`~emaphm.params.ParameterError` naming the
    file and the field)."""
    return Nameplate.from_dict(read_toml(path, "nameplate", ParameterError), source=str(path))


def convert(plate: Nameplate, template: ActuatorParams | None = None) -> Datasheet:
    """The emaphm parameters of the motor on ``plate`` (see the module docstring)."""
    t = template if template is not None else siemens_1fk7060()
    c0 = back_emf_coefficient(plate.ke)
    R, L = plate.r_ll / 2.0, plate.l_ll / 2.0
    J_l = (plate.j_load / plate.gear_ratio ** 2 if plate.j_load is not None
           else t.load.J_l * (plate.j_rotor / t.motor.J_m))
    torque_ratio = plate.t_max / t.motor.T_max
    motor = replace(t.motor, p=plate.poles // 2, R=(R, R, R), L=(L, L, L), c0=(c0, c0, c0),
                    J_m=plate.j_rotor, T_max=plate.t_max, I_max=math.sqrt(2.0) * plate.i_max,
                    C_m=t.motor.C_m * torque_ratio)
    f_pwm = plate.f_pwm if plate.f_pwm is not None else t.inverter.f_pwm
    tune = derive_tuning(motor, f_pwm, J_l, t)
    inverter = Inverter(V_dc=plate.v_dc if plate.v_dc is not None else t.inverter.V_dc,
                        f_pwm=f_pwm, Kp_i=tune.Kp_i, Ki_i=tune.Ki_i, I_trip=tune.I_trip)
    # the drive's data-sheet settings (limits, feed-forward inertia, decoupling inductance)
    # are this motor's, resolved again when the actuator is assembled
    controller = replace(t.controller, Kp=tune.Kp, Kp_w=tune.Kp_w, Ki_w=tune.Ki_w, k_T=tune.k_T,
                         omega_max=plate.n_max if plate.n_max is not None
                         else t.controller.omega_max, torque_feedforward_inertia=None,
                         decoupling_L=None, T_max=None, I_max=None)
    reduced = 1.0 / (1.0 / motor.J_m + 1.0 / J_l)
    reduced_t = 1.0 / (1.0 / t.motor.J_m + 1.0 / t.load.J_l)
    tr = t.transmission
    transmission = replace(tr, FSJ=tr.FSJ * torque_ratio, FDJ=tr.FDJ * torque_ratio,
                           K_c=tr.K_c * (reduced / reduced_t), D_c=tr.D_c * (reduced / reduced_t))
    load = Load(J_l=J_l, C_l=t.load.C_l * torque_ratio, T_0=t.load.T_0)
    params = replace(t, name=plate.name, motor=motor, inverter=inverter, controller=controller,
                     transmission=transmission, load=load)
    try:
        check_plausible(params, source=plate.name)
    except ParameterError as exc:
        given = [f"[datasheet] {v}" for k, v in _FROM.items() if f" {k} [" in str(exc)]
        raise ParameterError(str(exc) + (f" (from {given[0]})" if given else "")) from None
    return Datasheet(params=params, derived=_derived(plate, params),
                     from_template=_from_template(plate), warnings=_warnings(plate, params))


def _derived(plate: Nameplate, p: ActuatorParams) -> tuple[tuple[str, float, str], ...]:
    m, inv, c = p.motor, p.inverter, p.controller
    return (
        ("motor.p", m.p, f"poles {plate.poles} / 2"),
        ("motor.c0 [V s/rad]", m.c0[0], f"sqrt(2) x {plate.ke:g} V/krpm / sqrt(3) / 104.72"),
        ("motor.R [ohm]", m.R[0], f"line to line {plate.r_ll:g} ohm / 2"),
        ("motor.L [H]", m.L[0], f"line to line {plate.l_ll:g} H / 2"),
        ("motor.J_m [kg m^2]", m.J_m, "j_rotor"),
        ("motor.I_max [A peak]", m.I_max, f"sqrt(2) x {plate.i_max:g} A rms"),
        ("load.J_l [kg m^2]", p.load.J_l, f"j_load / gear_ratio^2 ({plate.gear_ratio:g})"
         if plate.j_load is not None else "the rotor's, as the preset (no j_load given)"),
        ("inverter.Kp_i [V/A]", inv.Kp_i, "the preset's crossover, 0.2375 rad per period"),
        ("inverter.Ki_i [V/(A s)]", inv.Ki_i, "zero on the winding's pole R/L"),
        ("controller.Kp_w", c.Kp_w, "speed loop on the shaft's inertia J_m + J_l"),
        ("controller.Ki_w", c.Ki_w, "integral corner as the preset's"),
        ("controller.Kp [1/s]", c.Kp, "position loop as the preset's"),
        ("controller.k_T [N m/A]", c.k_T, "1.5 c0"),
        ("inverter.I_trip [A]", inv.I_trip, "the preset's margin over T_max / k_T"),
    )


def _from_template(plate: Nameplate) -> tuple[str, ...]:
    out = ["motor.L_sigma", "motor.R_f", "transmission.backlash", "plant.omega_s", "sensors",
           "transmission.FSJ/FDJ, motor.C_m, load.C_l (x t_max / 18 N m)",
           "transmission.K_c/D_c (x reduced inertia)"]
    if plate.v_dc is None:
        out.append("inverter.V_dc")
    if plate.f_pwm is None:
        out.append("inverter.f_pwm")
    if plate.n_max is None:
        out.append("controller.omega_max")
    return tuple(out)


def _warnings(plate: Nameplate, p: ActuatorParams) -> tuple[str, ...]:
    m, out = p.motor, []
    kt_ke = 1.5 * math.sqrt(2.0) * m.c0[0]
    if plate.kt is not None and abs(plate.kt / kt_ke - 1.0) > KE_KT_TOLERANCE:
        out.append(f"kt = {plate.kt:.4g} N m/A rms and ke = {plate.ke:.4g} V/krpm disagree by "
                   f"{100 * (plate.kt / kt_ke - 1):+.1f} % (ke gives {kt_ke:.4g} N m/A rms, limit "
                   f"{100 * KE_KT_TOLERANCE:.0f} %): check that ke is line to line RMS per 1000 "
                   "rpm and kt per A RMS; emaphm uses ke (c0)")
    if plate.t_max > 1.3 * kt_ke * plate.i_max:
        out.append(f"t_max = {plate.t_max:g} N m is more than the {kt_ke * plate.i_max:.3g} N m that "
                   f"i_max = {plate.i_max:g} A rms gives: check i_max (A rms) and t_max")
    v_phase = m.c0[0] * p.controller.omega_max
    if v_phase > p.inverter.V_dc / math.sqrt(3.0):
        out.append(f"the back-EMF at omega_max = {p.controller.omega_max:.4g} rad/s is "
                   f"{v_phase:.4g} V peak per phase, above the {p.inverter.V_dc / math.sqrt(3):.4g} V "
                   f"a {p.inverter.V_dc:g} V DC link can oppose: check ke and v_dc")
    tau = m.L[0] / m.R[0]
    if not 1e-4 <= tau <= 0.1:
        out.append(f"the electrical time constant L/R = {tau * 1e3:.3g} ms is unlike a servo "
                   "motor's (0.1-100 ms): check r_ll (ohm) and l_ll (H, mH)")
    if not 1e-7 <= m.J_m <= 1.0:
        out.append(f"j_rotor = {m.J_m:.3g} kg m^2 is unlike a servo motor's (1e-7 to 1 kg m^2): "
                   "give its unit, e.g. \"1.1 kg cm^2\"")
    elif not ACCELERATION_RANGE[0] <= m.T_max / m.J_m <= ACCELERATION_RANGE[1]:
        out.append(f"t_max / j_rotor = {m.T_max / m.J_m:.3g} rad/s^2 is unlike a servo motor's "
                   f"({ACCELERATION_RANGE[0]:g} to {ACCELERATION_RANGE[1]:g} rad/s^2): check "
                   f"j_rotor = {m.J_m:.3g} kg m^2 (a bare number is kg m^2; catalogues print kg "
                   "cm^2: give the unit, e.g. \"1.3 kg cm^2\")")
    return tuple(out)
