"""The drive's own signals in a trace: which it has, and the phase voltages it applied.

A trace may carry what a drive logs (:data:`~emaphm.traces.container.DRIVE_COLUMNS`): the
voltage commands in one of three forms, the current references, the speed reference.
This module reads them for the identification that needs no model of the drive's
controller (:mod:`emaphm.models.driven`):

* :func:`voltage_form`: which form of voltage command a trace has (phase voltages first,
  then dq voltages, then duty cycles with the DC link);
* :func:`applied_voltages`: the star-referenced phase voltages applied over each control
  period, on the control grid:

  - ``v_a, v_b, v_c`` as logged, less their mean (a zero-sequence part, which a drive's
    modulation may add, drops out of a star-connected winding);
  - ``v_d, v_q`` turned into phase voltages at the electrical angle ``p theta_m`` of the
    sample they were logged with (the drive's own angle at its control instant; a drive
    that advances that angle to compensate its delay logs the voltages it computed at the
    advanced angle, and this reads them back at the sampled one: log the phase voltages
    or the duty cycles from such a drive);
  - ``d_a, d_b, d_c`` times ``v_dc``, less their mean;

  and, where the trace's metadata says ``voltage_delay_periods = 1`` (a command logged
  when it was computed and applied in the next period), shifted by one period, so that
  period ``k`` gets the command logged at ``k - 1`` (the first period repeats the first
  command). With ``0`` (the default) a command applies in the period it was logged in.
  ``[controller] delay_periods`` says how a drive works, for the model of its controller;
  ``voltage_delay_periods`` says when a logged command was applied, for this path: a drive
  with a computation delay that logs its commands as it applies them has
  ``delay_periods = 1`` and ``voltage_delay_periods = 0``;
* :func:`current_references`, :func:`speed_reference`: the recorded references on the
  control grid, each the one the drive's loop used in the period it was logged in (a
  drive's log of a reference it computed), with ``i_d_ref`` 0 where left out;
* :func:`control_samples`: the samples at the control instants. Commands are held over a
  period, not interpolated, so they must come one sample per control period, or an
  integer number of samples per period (each period's command read at its first); a log
  decimated below the control rate is refused, as is one whose step is no whole fraction
  of the period.
"""

from __future__ import annotations

import math
import numpy as np

from .container import Trace, TraceError

__all__ = ["VOLTAGE_FORMS", "voltage_form", "control_samples", "applied_voltages",
           "delay_periods", "check_commands", "current_references", "speed_reference"]

#: The forms of voltage command a trace may carry, in the order they are read.
VOLTAGE_FORMS = ("phase voltages", "dq voltages", "duty cycles")

#: Relative tolerance of the step of a trace against a whole fraction of the control
#: period (a logger's clock and the drive's drift apart by ppm).
STEP_TOLERANCE = 1e-4

#: How far a phase voltage may exceed the DC link [share] before the command is refused:
#: a star-referenced phase voltage of a two-level inverter stays within 2/3 of it (six-step),
#: within 1/sqrt(3) in the linear range; beyond the link itself a log is in other units.
BEYOND_DC_LINK = 1.0


def voltage_form(trace: Trace) -> str | None:
    """The form of voltage command ``trace`` carries (:data:`VOLTAGE_FORMS`), or None."""
    d = trace.drive
    if all(x in d for x in ("v_a", "v_b", "v_c")):
        return "phase voltages"
    if all(x in d for x in ("v_d", "v_q")):
        return "dq voltages"
    if all(x in d for x in ("d_a", "d_b", "d_c", "v_dc")):
        return "duty cycles"
    return None


def delay_periods(trace: Trace) -> int:
    """The trace's ``voltage_delay_periods`` (0 or 1; 0 when it says nothing)."""
    value = trace.meta.get("voltage_delay_periods", 0) if isinstance(trace.meta, dict) else 0
    if isinstance(value, bool) or value not in (0, 1):
        raise TraceError(f"trace metadata voltage_delay_periods = {value!r}: it says whether a "
                         "logged voltage command was applied in the period it was logged in (0) "
                         "or in the next (1); give 0 or 1")
    return int(value)


def control_samples(trace: Trace, T_s: float) -> np.ndarray:
    """The indices of the samples at the control instants ``t_0 + k T_s``: every sample for
    a trace logged once per control period, every m-th for one logged m times per period.
    TraceError for a log decimated below the control rate, or at a step that is no whole
    fraction of the period."""
    dt = trace.dt
    if not (math.isfinite(dt) and dt > 0):
        raise TraceError("the trace has too few samples to read the drive's commands")
    ratio = T_s / dt
    m = round(ratio)
    if ratio < 1.0 - STEP_TOLERANCE:
        raise TraceError(
            f"the drive's voltage commands are logged every {dt * 1e6:.4g} us, less often than "
            f"the drive's control period of {T_s * 1e6:.4g} us: a command holds for one period, "
            "so a decimated log misses most of them and cannot drive the winding; log one "
            "sample per control period (or check [inverter] f_pwm)")
    if m < 1 or abs(ratio - m) > STEP_TOLERANCE * ratio:
        raise TraceError(
            f"the trace's step of {dt * 1e6:.6g} us is no whole fraction of the control period "
            f"{T_s * 1e6:.6g} us, so its samples do not fall on the control instants where the "
            "voltage commands change; log at the control rate or a whole multiple of it (or "
            "check [inverter] f_pwm)")
    n = (trace.n - 1) // m + 1
    return np.arange(n) * m


def applied_voltages(trace: Trace, samples: np.ndarray, p: int) -> np.ndarray:
    """``(n, 3)`` [V]: the star-referenced phase voltages applied over each control period
    whose first sample is ``samples`` (see the module's docstring), the trace's delay
    applied. ``p``: the motor's pole pairs (for dq voltages)."""
    d = trace.drive
    form = voltage_form(trace)
    if form is None:
        raise TraceError("the trace carries no voltage commands (v_a, v_b, v_c; or v_d, v_q; or "
                         "d_a, d_b, d_c with v_dc); identify it with the drive's model instead "
                         "(--drive-model 'modelled controller')")
    if form == "phase voltages":
        v = np.column_stack([d["v_a"], d["v_b"], d["v_c"]])[samples]
    elif form == "dq voltages":
        theta_e = p * np.asarray(trace.theta_m)[samples]
        s, c = np.sin(theta_e), np.cos(theta_e)
        v_d, v_q = d["v_d"][samples], d["v_q"][samples]
        # the inverse Park and Clarke transforms of emaphm.models.inverter
        v_al = -v_d * c + v_q * s
        v_be = -v_d * s - v_q * c
        v = np.column_stack([v_al, -0.5 * v_al + 0.5 * math.sqrt(3.0) * v_be,
                             -0.5 * v_al - 0.5 * math.sqrt(3.0) * v_be])
    else:
        duty = np.column_stack([d["d_a"], d["d_b"], d["d_c"]])[samples]
        v = duty * d["v_dc"][samples, None]
    v = v - v.mean(axis=1, keepdims=True)
    if delay_periods(trace):
        v = np.vstack([v[:1], v[:-1]])
    return np.ascontiguousarray(v)


def check_commands(trace: Trace, v: np.ndarray, V_dc: float, where: str = "") -> None:
    """Refuse commands no drive on a DC link of ``V_dc`` [V] (the trace's ``v_dc`` where it
    has one) could apply: duty cycles outside [0, 1], a DC link at or below 0 V, a phase
    voltage beyond the link (commands in other units, or not the drive's)."""
    d = trace.drive
    if "v_dc" in d:
        bad = np.flatnonzero(~(d["v_dc"] > 0.0))
        if bad.size:
            raise TraceError(f"{where}v_dc is {d['v_dc'][bad[0]]:.4g} V at t = "
                             f"{trace.t[bad[0]]:.6g} s: a DC link is above 0 V; check the "
                             "channel and its unit (V)")
        V_dc = float(np.max(d["v_dc"]))
    for name in ("d_a", "d_b", "d_c"):
        if name in d:
            x = d[name]
            bad = np.flatnonzero((x < -1e-9) | (x > 1.0 + 1e-9))
            if bad.size:
                raise TraceError(f"{where}duty cycle {name} is {x[bad[0]]:.4g} at t = "
                                 f"{trace.t[bad[0]]:.6g} s, outside [0, 1]; log the legs' duty "
                                 "cycles as fractions of the period (not percent)")
    peak, row = _peak(v)
    if peak > BEYOND_DC_LINK * V_dc:
        raise TraceError(f"{where}the voltage commands reach {peak:.4g} V (period {row}), beyond "
                         f"the DC link of {V_dc:.4g} V, which no inverter on it applies: check "
                         "their unit (V), that they are phase and not line voltages, or the "
                         "DC link ([inverter] V_dc or the trace's v_dc)")


def _peak(x: np.ndarray) -> tuple[float, int]:
    """The largest magnitude in ``x (n, m)`` and its row (0 for none)."""
    if not x.size:
        return 0.0, 0
    a = np.max(np.abs(x), axis=1)
    row = int(np.argmax(a))
    return float(a[row]), row


#: How far a recorded current reference may exceed the drive's current limit [share]
#: before it is refused as in other units (a drive clamps its reference at the limit).
BEYOND_CURRENT_LIMIT = 1.5


def current_references(trace: Trace, samples: np.ndarray, I_max: float) -> np.ndarray:
    """``(n, 2)`` [A]: the recorded ``(i_d_ref, i_q_ref)`` at ``samples`` (``i_d_ref`` 0
    where the trace has none). TraceError where the trace has no ``i_q_ref``, or where a
    reference exceeds the drive's current limit ``I_max`` [A] by half (amperes in another
    unit, or not this drive's)."""
    d = trace.drive
    if "i_q_ref" not in d:
        raise TraceError("the trace carries no current reference i_q_ref; identify it from its "
                         "voltage commands or with the drive's model (--drive-model)")
    i_q = np.asarray(d["i_q_ref"], dtype=float)[samples]
    i_d = (np.asarray(d["i_d_ref"], dtype=float)[samples] if "i_d_ref" in d
           else np.zeros_like(i_q))
    ref = np.column_stack([i_d, i_q])
    peak, row = _peak(ref)
    if peak > BEYOND_CURRENT_LIMIT * I_max:
        raise TraceError(f"the current references reach {peak:.4g} A (period {row}), "
                         f"{peak / I_max:.1f}x the drive's current limit of {I_max:.4g} A, which "
                         "a drive clamps its reference at: check their unit (A, not mA or "
                         "percent) and the limit ([controller] I_max)")
    return np.ascontiguousarray(ref)


def speed_reference(trace: Trace, samples: np.ndarray, omega_max: float) -> np.ndarray:
    """``(n,)`` [rad/s]: the recorded ``omega_ref`` at ``samples``. TraceError where the
    trace has none, or where it exceeds the drive's speed limit ``omega_max`` by half
    (rpm logged as rad/s, or not this drive's)."""
    d = trace.drive
    if "omega_ref" not in d:
        raise TraceError("the trace carries no speed reference omega_ref; identify it from its "
                         "voltage commands or current references, or with the drive's model "
                         "(--drive-model)")
    w = np.ascontiguousarray(np.asarray(d["omega_ref"], dtype=float)[samples])
    peak, _ = _peak(w[:, None])
    if peak > BEYOND_CURRENT_LIMIT * omega_max:
        raise TraceError(f"the speed reference reaches {peak:.4g} rad/s, {peak / omega_max:.1f}x "
                         f"the drive's speed limit of {omega_max:.4g} rad/s: check its unit "
                         "(rad/s of the motor, not rpm) and the limit ([controller] omega_max)")
    return w
