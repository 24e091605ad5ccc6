"""One entry point to simulate an actuator: :func:`simulate` -> :class:`Trace`."""

from __future__ import annotations

from dataclasses import replace
from typing import Any, Literal, Sequence

import numpy as np

from . import __version__
from .acquisition import Sensors
from .logs import announce_compiles
from .faults import (as_k, check_fault_model, loop_report, scenario as scenario_k,
                     scenario_fault_model, shorted_fraction)
from .params import ActuatorParams, siemens_1fk7060
from .profiles import Profile, diagnostic
from .modes import Injection, parse_fault
from .seeds import check_seed
from .traces import Trace
from .units import Tolerances, Unit, draw_unit, nominal_unit

__all__ = ["simulate", "MODELS", "DEFAULT_SENSORS"]

MODELS = ("reference", "monitoring")

#: A realistic acquisition chain for "measured" traces: 20 mA rms current noise
#: (about 0.1 % of a 20 A sensor range) and a 12-bit ADC over +-20 A (9.8 mA).
DEFAULT_SENSORS = Sensors(current_noise=0.02, current_lsb=40.0 / 4096)


def simulate(k: Sequence[float] | np.ndarray | str | None = None, *,
             scenario: str | None = None,
             model: Literal["reference", "monitoring"] = "reference",
             params: ActuatorParams | None = None,
             profile: Profile | None = None,
             sensors: Sensors | None = None,
             seed: int | None = None,
             n_sub: int | None = None,
             pwm: bool = True,
             fault_model: str | None = None,
             unit: Unit | None = None,
             unit_seed: int | None = None,
             tolerances: Tolerances | None = None,
             unreported_load: float | None = None,
             faults: Sequence[Injection | str] = (),
             drive_signals: bool = False,
             drive: str | None = None) -> Trace:
    """Simulate the actuator with fault vector ``k`` (or a named ``scenario``).

    Parameters
    ----------
    k, scenario
        The fault vector (8 values in [0, 1]) or a scenario name; nominal if neither.
    model
        ``"reference"``: the plant (switching PWM at a fine step, Stribeck
        friction, compliant backlash, leakage and mutual inductance, physical
        fault loops, a production unit); ``"monitoring"``: the fast model
        (averaged inverter, coarse step, data-sheet parameters).
    fault_model
        Mapping of k3..k5 (:data:`emaphm.faults.FAULT_MODELS`): a scenario's own
        by default, ``"physical"`` for a bare ``k``.
    unit, unit_seed, tolerances, unreported_load
        The production unit the plant plays (reference model only): a drawn
        :class:`~emaphm.units.Unit`, or one drawn here from ``unit_seed`` within
        ``tolerances`` (default :data:`emaphm.units.DEFAULT_TOLERANCES`); the
        nominal unit if none. ``unreported_load`` [N m] overrides the unit's
        constant load that the trace's metadata does not report.
    params
        Healthy data-sheet parameters (default :func:`emaphm.params.siemens_1fk7060`).
    profile
        Command and load profile (default :func:`emaphm.profiles.diagnostic`).
    sensors
        Acquisition chain applied to the recorded signals (default ideal; see
        :data:`DEFAULT_SENSORS` for a realistic one). Noise needs ``seed``.
    seed
        Seed of the sensor noise (an int; same seed, same trace).
    n_sub
        Sub-steps per control period (default 128 for the RM, 1 for the MM).
    pwm
        Reference model only: switching inverter (True) or averaged (False).
    faults
        Faults to simulate beside (or instead of) ``k``, as specs of the fault modes
        (:func:`emaphm.modes.parse_fault`: ``"friction:2.5"``,
        ``"short_circuit:a:0.3:0.05"``) or their :class:`~emaphm.modes.Injection`: the
        components of k they set, what they change in the plant, a faulty current sensor
        of the recording chain. The trace's metadata keeps them as data (``injected``:
        each one's spec, components of k and sensor) and ``truth``: the true values of the
        parameters an identification may search beside k (``{"demag": -0.3}``).
    drive_signals
        Reference model only: the trace also carries what the plant's drive logs
        (:attr:`emaphm.traces.Trace.drive`): the phase voltages it applied in each control
        period (``v_a, v_b, v_c``, star-referenced, as applied: ``voltage_delay_periods``
        0), its current references ``i_d_ref, i_q_ref`` and its speed reference
        ``omega_ref``, digital and exact, held over each period at the recording's
        samples.
    drive
        Reference model only: the firmware the plant's drive runs: emaphm's own cascade as
        ``params.controller`` describes it (None or ``"emaphm"``), or a drive that is not
        emaphm's (:data:`emaphm.models.drives.FOREIGN_DRIVES`).
    """
    if model not in MODELS:
        raise ValueError(f"unknown model {model!r}; choose 'reference' or 'monitoring'")
    if (drive_signals or drive not in (None, "emaphm")) and model != "reference":
        raise ValueError("the drive's signals (drive_signals) and its firmware (drive) are the "
                         "plant's: use model='reference'")
    announce_compiles()
    injections = [parse_fault(f) if isinstance(f, str) else f for f in faults]
    kk, fault_model = _fault_vector(k, scenario, fault_model, injections)
    if seed is not None:
        check_seed(seed)
    params = params if params is not None else siemens_1fk7060()
    profile = profile if profile is not None else diagnostic()
    sensors = sensors if sensors is not None else Sensors()
    unit = _production_unit(params, model, unit, unit_seed, tolerances, unreported_load)
    out, status, sensors, plant_params = _run_model(model, params, unit, injections, sensors, kk,
                                                    profile, fault_model, n_sub, pwm, drive)
    rng = np.random.default_rng(seed) if seed is not None else None
    t_rec, rec = sensors.record(out["t"], {k: out[k] for k in ("theta_ref", "theta_m", "omega_m",
                                                                "i_abc", "torque")}, rng)
    meta = _metadata(model, kk, fault_model, scenario, params, profile, seed, sensors, n_sub, pwm,
                     status, faults, drive, injections)
    if model == "reference":
        meta["unit"] = unit.to_dict()
        meta["plant"] = _plant_report(out, plant_params, kk, fault_model)
    log = {}
    if drive_signals:
        log = _drive_log(out["t"], out["drive"], t_rec)
        meta["voltage_delay_periods"] = 0
    return Trace(t=t_rec, theta_ref=rec["theta_ref"], theta_m=rec["theta_m"], omega_m=rec["omega_m"],
                 i_abc=rec["i_abc"], torque=rec["torque"], meta=meta, drive=log)


def _metadata(model: str, k: np.ndarray, fault_model: str, scenario: str | None,
              params: ActuatorParams, profile: Profile, seed: int | None, sensors: Sensors,
              n_sub: int | None, pwm: bool, status: str, faults: Sequence[Any],
              drive: str | None, injections: Sequence[Injection] = ()) -> dict[str, Any]:
    """A simulated trace's metadata: how it was made."""
    meta = {
        "model": model,
        "k": k.tolist(),
        "fault_model": fault_model,
        "scenario": scenario,
        "parameters": params.to_dict(),
        "profile": profile.to_dict(),
        "seed": None if seed is None else int(seed),
        "sensors": sensors.to_dict(),
        "n_sub": n_sub or (128 if model == "reference" else 1),
        "pwm": bool(pwm) if model == "reference" else False,
        "drive": status,
        "emaphm_version": __version__,
    }
    if drive not in (None, "emaphm"):
        meta["firmware"] = drive
    if faults:
        meta["faults"] = [f if isinstance(f, str) else repr(f) for f in faults]
        meta.update(_injected(faults, injections, params, _plant_of(injections)))
    return meta


def _injected(faults: Sequence[Any], injections: Sequence[Injection], params: ActuatorParams,
              plant: Any) -> dict[str, Any]:
    """The injected faults as data (:meth:`emaphm.modes.Injection.to_dict`, with each one's
    spec) and ``truth``: the values the parameters searched beside k
    (:data:`emaphm.search.NUISANCE_RANGE`) take on the plant the injections make, read from
    its parameters against the data sheet (a lost flux is ``demag``, a changed resistance
    ``R``, a fault-bridge resistance ``Rf_a``..``Rf_c`` in decades, a load ``load``)."""
    items = [{"spec": f if isinstance(f, str) else repr(f),
              "mode": f.split(":")[0].strip() if isinstance(f, str) else None, **inj.to_dict()}
             for f, inj in zip(faults, injections)]
    faulty = plant(params)
    m, f = params.motor, faulty.motor
    truth = {"demag": float(np.mean(np.divide(f.c0, m.c0)) - 1.0),
             "R": float(np.mean(np.divide(f.R, m.R)) - 1.0),
             **{f"Rf_{p}": float(np.log10(b / a)) for p, a, b in zip("abc", m.R_f, f.R_f)},
             "load": float(faulty.load.T_0 - params.load.T_0)}
    return {"injected": items, "truth": {n: v for n, v in truth.items() if v != 0.0}}


#: The columns of the plant's drive log (:func:`emaphm.models.reference.run_reference`).
_DRIVE_LOG = ("v_a", "v_b", "v_c", "i_d_ref", "i_q_ref", "omega_ref")


def _drive_log(t: np.ndarray, log: np.ndarray, t_rec: np.ndarray) -> dict[str, np.ndarray]:
    """The drive's log at the recording's samples ``t_rec``: each period's values held
    (a command is not interpolated between control instants)."""
    idx = np.clip(np.searchsorted(t, t_rec + 1e-9 * (t[1] - t[0]), side="right") - 1, 0,
                  t.size - 1)
    return {name: np.ascontiguousarray(log[idx, j]) for j, name in enumerate(_DRIVE_LOG)}


def _run_model(model: str, params: ActuatorParams, unit: Unit, injections: Sequence[Injection],
               sensors: Sensors, k: np.ndarray, profile: Profile, fault_model: str,
               n_sub: int | None, pwm: bool, drive: str | None):
    """``(signals, drive status, the recording chain, the plant's parameters)`` of one
    simulation: the plant (a production unit, the injections' changes, its drive's
    firmware) or the monitoring model."""
    from .models.reference import run_reference     # the kernels: imported on first use

    plant = _plant_of(injections)
    if model == "reference":
        sensors = _faulty_sensors(sensors.with_unit(unit.sensor_gain, unit.sensor_offset),
                                  injections)
        plant_params = plant(unit.params)
        out = run_reference(plant_params, k, profile, fault_model=fault_model,
                            n_sub=n_sub or 128, pwm=pwm, extra_load=unit.load + unit.params.load.T_0,
                            drive=None if drive == "emaphm" else drive)
        return out, ("tripped" if out["trip_time"] is not None else "ok"), sensors, plant_params
    out, status = _run_monitoring(plant(params), profile, k, n_sub or 1, fault_model)
    return out, status, _faulty_sensors(sensors, injections), None


def _fault_vector(k: Any, scenario: str | None, fault_model: str | None,
                  injections: Sequence[Injection]) -> tuple[np.ndarray, str]:
    """The fault vector to simulate (``k``, a scenario's, or nominal, with the components
    the injections set) and its fault model (a scenario's own, ``"physical"`` for k)."""
    if k is not None and scenario is not None:
        raise ValueError("give either a fault vector k or a scenario name, not both")
    kk = scenario_k(scenario) if scenario is not None else as_k(k if k is not None else
                                                                 scenario_k("nominal"))
    if fault_model is None:
        fault_model = scenario_fault_model(scenario) if scenario is not None else "physical"
    check_fault_model(fault_model)
    if injections:
        kk = kk.copy()
        for inj in injections:
            for j, v in inj.k.items():
                kk[j] = v
        kk = as_k(kk)
    return kk, fault_model


def _run_monitoring(params: ActuatorParams, profile: Profile, k: np.ndarray, n_sub: int,
                    fault_model: str) -> tuple[dict, str]:
    """The monitoring model's signals for one k, as the plant's, and its drive status;
    a diverged state is an error here (one simulation a user asked for)."""
    from .models.monitoring import STATUS_OK, STATUS_TRIPPED, MonitoringModel

    r = MonitoringModel(params, profile, n_sub=n_sub, fault_model=fault_model).simulate(k)
    out = {"t": r.t, "theta_ref": r.theta_ref, "theta_m": r.theta_m[0],
           "omega_m": r.omega_m[0], "i_abc": r.i_abc[0], "torque": r.torque[0]}
    status = {STATUS_OK: "ok", STATUS_TRIPPED: "tripped"}.get(int(r.status[0]), "diverged")
    if status == "diverged":
        raise ValueError(f"the monitoring model diverged for k = {k.tolist()}: its state left "
                         "the physical range; check the parameters (e.g. the current loop gains "
                         "against the inductance)")
    return out, status


def _production_unit(params: ActuatorParams, model: str, unit: Unit | None, unit_seed: int | None,
                     tolerances: Tolerances | None, unreported_load: float | None) -> Unit:
    """The production unit the plant plays: given, drawn from ``unit_seed`` within
    ``tolerances``, or the nominal one; with ``unreported_load`` [N m] as its load."""
    if unit is not None and unit_seed is not None:
        raise ValueError("give either a unit or a unit_seed, not both")
    if unit_seed is not None:
        unit = draw_unit(params, unit_seed, tolerances) if tolerances is not None \
            else draw_unit(params, unit_seed)
    elif tolerances is not None:
        raise ValueError("tolerances need a unit_seed to draw a unit with")
    if unreported_load is not None:
        if not (isinstance(unreported_load, (int, float)) and np.isfinite(unreported_load)
                and abs(unreported_load) <= 5.0):
            raise ValueError(f"unreported_load [N m] must be a number within +-5, "
                             f"got {unreported_load!r}")
        unit = replace(unit or nominal_unit(params), load=float(unreported_load))
    if unit is not None and model != "reference":
        raise ValueError("a production unit (unit, unit_seed, unreported_load) is what the "
                         "plant plays: use model='reference'")
    return unit if unit is not None else nominal_unit(params)


def _plant_of(injections: Sequence[Injection]):
    """The injections' changes of the plant, composed (the identity without any)."""
    def plant(params: ActuatorParams) -> ActuatorParams:
        for inj in injections:
            if inj.plant is not None:
                params = inj.plant(params)
        return params
    return plant


def _faulty_sensors(sensors: Sensors, injections: Sequence[Injection]) -> Sensors:
    """``sensors`` with the injections' faulty current sensors: the phase's gain times the
    fault's, its offset plus the fault's."""
    gain, offset = list(sensors.gain), list(sensors.offset)
    for inj in injections:
        if inj.sensor is not None:
            j, g, o = inj.sensor
            gain[j] *= g
            offset[j] += o
    if gain == list(sensors.gain) and offset == list(sensors.offset):
        return sensors
    return replace(sensors, gain=tuple(gain), offset=tuple(offset))


def _plant_report(out: dict, params: ActuatorParams, k: np.ndarray, fault_model: str) -> dict:
    """What the plant knows and a trace does not: each phase's fault-loop current (RMS
    over the trace, the PWM ripple the samples miss included) and the mean power in its
    fault bridge ``R_f i_f^2`` and its ampere-turns ``mu i_f`` (:func:`emaphm.faults.loop_report`;
    zero on a phase without a loop)."""
    i_f = np.asarray(out["i_fault"], dtype=float)
    ripple = np.asarray(out.get("i_fault_ripple", np.zeros_like(i_f)), dtype=float)
    ms = np.mean(i_f * i_f, axis=0) + np.mean(ripple * ripple, axis=0)
    physical = fault_model == "physical"
    mu = shorted_fraction(k[2:5]) if physical else np.zeros(3)
    return {**loop_report(ms, params.motor.R_f, mu),
            "mu": [float(x) for x in mu] if physical else None}
