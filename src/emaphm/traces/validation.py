"""Validation of a trace (:func:`validate`): SI units (declared, and judged from the
signals: time in s, currents in A, speed against the derivative of the position), enough
clean samples on a uniform grid, one revolution of motion, a star connection."""

from __future__ import annotations

import math
import shlex
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..quantities import QuantityError, measure
from .container import UNITS, Trace, TraceError, _expected_columns
from .zero_sum import best_fit

__all__ = ["MIN_SAMPLES", "validate"]

#: What :func:`validate` advises for a trace that turns less than ``min_rotation``: the
#: Python API's words (the command line says its own, ``emaphm.cli.command_advice``).
ROTATION_ADVICE = ("Record a longer profile, e.g. the default diagnostic profile "
                   "emaphm.profiles.diagnostic(), or pass min_rotation=0 to skip this check")

#: Fewest samples :func:`validate` accepts.
MIN_SAMPLES = 100

# Unit heuristics of validate().
_MAX_TIME_STEP = 0.01  # s; a larger step suggests milliseconds
_MAX_DURATION = 1e3  # s; a longer trace suggests milliseconds
_MAX_CURRENT = 1e3  # A; a larger current suggests milliamperes
_MIN_TIME_STEP_IF_MS = 1e-3  # s; read as ms, a smaller step would be under 1 us
_MAX_SPEED = 2000.0  # rad/s (19,100 rpm); no servo motor turns faster
#: Beyond these no unit explains a value (the importer's reach: 1.6 million revolutions;
#: a current beyond 1000 A read as mA): it is no measurement, and no unit is guessed.
_REACH = {**{x: (1e7, "the {:g} rad of any actuator's recording")
             for x in ("theta_ref", "theta_m")},
          **{x: (1e6, "any actuator's current, in A or in mA ({:g})")
             for x in ("i_a", "i_b", "i_c")}}
_MIN_SPEED_CORRELATION = 0.9  # omega_m vs d(theta_m)/dt must be this collinear to judge units
_RATIO_TOLERANCE = 0.10  # relative distance of a speed ratio to a known factor
_RATIO_BAND = (0.5, 2.0)  # ratios outside this band (and not a known factor) are an error
# Star connection checks of validate().
_STAR_MEAN_LIMIT = 0.10  # |mean(i_a+i_b+i_c)| / RMS phase current
_STAR_AC_LIMIT = 0.25  # RMS of the noise-free part of the sum / that of the phase currents
#: A sum beyond those limits is accepted when one current sensor's gain or offset (in a
#: plausible range, emaphm.traces.zero_sum) explains it, leaving at most this share
#: (the other two sensors' production tolerances leave a few percent)
_STAR_EXPLAINED = 0.08


# --------------------------------------------------------------------------------------
# Units
# --------------------------------------------------------------------------------------

#: The quantity (:mod:`emaphm.quantities`) each column measures.
_KINDS: dict[str, str] = {"t": "time", "theta_ref": "angle", "theta_m": "angle",
                          "omega_m": "angular speed", "i_a": "current", "i_b": "current",
                          "i_c": "current", "torque": "torque",
                          **{f"v_{x}": "voltage" for x in "abcdq"}, "v_dc": "voltage",
                          **{f"d_{x}": "dimensionless" for x in "abc"}, "i_d_ref": "current",
                          "i_q_ref": "current", "omega_ref": "angular speed"}


def _unbracket(unit: str) -> str:
    unit = unit.strip()
    if len(unit) >= 2 and unit[0] + unit[-1] in ("[]", "()"):
        unit = unit[1:-1].strip()
    return unit


def _normalise_symbol(unit: str) -> str:
    return " ".join(_unbracket(unit).split()).lower()


def _check_symbol(column: str, unit: Any, source: str) -> None:
    """Raise TraceError unless ``unit`` is empty or an SI spelling of ``UNITS[column]``."""
    expected = UNITS[column]
    if not isinstance(unit, str):
        raise TraceError(
            f"{source}: the unit of column '{column}' is {unit!r}, expected the string "
            f"'{expected}'"
        )
    if _normalise_symbol(unit) in ("", "-"):
        return
    try:
        found = measure(unit)
    except QuantityError:
        raise TraceError(
            f"{source}: column '{column}' has the unrecognised unit '{_unbracket(unit)}'; "
            f"convert the column to {expected} and write its unit as '{expected}'"
        ) from None
    if found.kind == _KINDS[column]:
        if found.is_si:
            return
        raise TraceError(
            f"{source}: column '{column}' is in '{_unbracket(unit)}', emaphm needs SI "
            f"units ({expected}); multiply the column by {found.how} to convert it to "
            f"{expected} and change its unit to '{expected}', or import the export as it is "
            "with `emaphm import FILE --inspect`"
        )
    raise TraceError(
        f"{source}: column '{column}' has the unit '{_unbracket(unit)}' (a unit of "
        f"{found.si}), but '{column}' must be in {expected}; check the column "
        f"assignment ({_expected_columns()})"
    )


def _check_declared_symbols(units: Any, source: str) -> None:
    if units is None:
        return
    if not isinstance(units, Mapping):
        raise TraceError(
            f"{source}: meta['units'] is a {type(units).__name__}, expected a mapping "
            "of column name to unit string, e.g. {'t': 's', 'omega_m': 'rad/s'}"
        )
    for name, unit in units.items():
        if name == "i_abc":
            _check_symbol("i_a", unit, source)
        elif name in UNITS:
            _check_symbol(name, unit, source)


# --------------------------------------------------------------------------------------
# Validation
# --------------------------------------------------------------------------------------


def _where(trace: Trace, index: int) -> str:
    t = trace.t[index] if 0 <= index < trace.n else math.nan
    return f"row {index} (t = {t:.9g} s)" if math.isfinite(t) else f"row {index}"


_SPEED_FACTORS: tuple[tuple[float, str], ...] = (
    (60 / (2 * math.pi), "omega_m looks like rpm: multiply omega_m by 2*pi/60 to get rad/s"),
    (180 / math.pi, "omega_m looks like deg/s: multiply omega_m by pi/180 to get rad/s"),
    (math.pi / 180, "theta_m looks like degrees: multiply theta_m and theta_ref by pi/180 "
     "to get rad"),
    (1 / 6, "theta_m looks like degrees and omega_m like rpm: multiply theta_m and "
     "theta_ref by pi/180 and omega_m by 2*pi/60"),
    (2 * math.pi, "theta_m looks like revolutions: multiply theta_m and theta_ref by 2*pi "
     "to get rad"),
    (60.0, "theta_m looks like revolutions and omega_m like rpm: multiply theta_m and "
     "theta_ref by 2*pi and omega_m by 2*pi/60"),
    (360.0, "theta_m looks like revolutions and omega_m like deg/s: multiply theta_m and "
     "theta_ref by 2*pi and omega_m by pi/180"),
)


@np.errstate(over="ignore", invalid="ignore")     # a huge speed is refused next, not warned
def _check_speed_scale(trace: Trace) -> None:
    theta, omega = trace.theta_m, trace.omega_m
    if np.ptp(theta) == 0.0:
        return
    d_theta = np.gradient(theta, trace.t)
    sdd = float(np.dot(d_theta, d_theta))
    sww = float(np.dot(omega, omega))
    if sdd == 0.0 or sww == 0.0 or not (math.isfinite(sdd) and math.isfinite(sww)):
        return
    swd = float(np.dot(omega, d_theta))
    cosine = swd / math.sqrt(sdd * sww)
    if abs(cosine) < _MIN_SPEED_CORRELATION:
        # the derivative is too noisy (or the motion too small) to judge the units: the
        # integral of the speed averages the noise out
        _check_position_scale(trace)
        return
    ratio = swd / sdd  # least squares: omega_m ~ ratio * d(theta_m)/dt
    lead = (
        f"omega_m does not match the time derivative of theta_m: the least-squares "
        f"ratio omega_m / (d theta_m/dt) is {ratio:.4g}, expected 1"
    )
    if ratio < 0:
        if abs(math.log(-ratio)) < math.log1p(_RATIO_TOLERANCE):
            raise TraceError(
                f"{lead}; omega_m has the opposite sign to d theta_m/dt: negate omega_m "
                "(or theta_m and theta_ref) so that both use the same positive direction"
            )
        raise TraceError(
            f"{lead}; the sign is opposite too. Check that both are motor-side signals "
            "in rad and rad/s with the same positive direction"
        )
    if abs(math.log(ratio)) < math.log1p(_RATIO_TOLERANCE):
        return
    near = sorted(
        (abs(math.log(ratio / factor)), factor, text) for factor, text in _SPEED_FACTORS
    )
    hits = [
        f"{text} (expected ratio {factor:.4g})"
        for distance, factor, text in near
        if distance < math.log1p(_RATIO_TOLERANCE)
    ]
    if hits:
        raise TraceError(f"{lead}, a units error; " + "; or ".join(hits))
    if not _RATIO_BAND[0] <= ratio <= _RATIO_BAND[1]:
        raise TraceError(
            f"{lead}. Check that theta_m and omega_m are both motor-side (not load-side "
            "through the gear ratio), in rad and rad/s, and come from the same run"
        )


#: The integral of omega_m and the change of theta_m must be this collinear for
#: :func:`_check_position_scale` to judge their scales.
_MIN_INTEGRAL_CORRELATION = 0.99


def _check_position_scale(trace: Trace) -> None:
    """The change of ``theta_m`` against the integral of ``omega_m`` dt, where the derivative
    of a noisy or coarsely quantised position cannot judge it (:func:`_check_speed_scale`):
    a least-squares ratio at a known factor is a units error (57.3: positions in degrees
    with the speed in rad/s). Other ratios are left alone: an integral drifts with a
    speed sensor's offset."""
    theta = trace.theta_m - trace.theta_m[0]
    omega = trace.omega_m
    integral = np.concatenate(([0.0], np.cumsum(0.5 * (omega[1:] + omega[:-1]) * np.diff(trace.t))))
    sii, stt = float(np.dot(integral, integral)), float(np.dot(theta, theta))
    if not (sii > 0.0 and stt > 0.0 and math.isfinite(sii) and math.isfinite(stt)):
        return
    sit = float(np.dot(integral, theta))
    if sit / math.sqrt(sii * stt) < _MIN_INTEGRAL_CORRELATION:
        return
    ratio = sit / sii  # theta_m - theta_m[0] ~ ratio * integral of omega_m dt
    if abs(math.log(ratio)) < math.log1p(_RATIO_TOLERANCE):
        return
    lead = (f"theta_m does not match the integral of omega_m: its change is {ratio:.4g} times "
            "the integral of omega_m dt, expected 1")
    if abs(math.log(ratio * math.pi / 180)) < math.log1p(_RATIO_TOLERANCE):
        raise TraceError(f"{lead}; positions look like degrees: multiply theta_m and theta_ref "
                         "by pi/180 to get rad (or import the export with its units: `emaphm "
                         "import FILE --inspect`)")
    hits = [text for factor, text in _SPEED_FACTORS
            if abs(math.log(ratio * factor)) < math.log1p(_RATIO_TOLERANCE)]
    if hits:
        raise TraceError(f"{lead}, a units error; " + "; or ".join(hits))


def _clock(seconds: float) -> str:
    return (f"{seconds / 3600:.3g} h" if seconds >= 3600 else f"{seconds / 60:.3g} min"
            if seconds >= 60 else f"{seconds:.3g} s")


def _import_command(source: Any, options: str) -> str:
    """The command ``emaphm import FILE OPTIONS``, in backquotes, with the file the trace
    was read from as a shell takes it (``FILE`` where it is not known)."""
    return f"`emaphm import {shlex.quote(str(source)) if source else 'FILE'} {options}`"


def _check_reach(trace: Trace) -> None:
    """Refuse positions and currents beyond :data:`_REACH`: absurd values, not a unit."""
    cols = trace.columns()
    for name, (reach, what) in _REACH.items():
        beyond = np.abs(cols[name]) > reach
        if beyond.any():
            first = int(np.argmax(beyond))
            raise TraceError(
                f"column '{name}' reaches {cols[name][first]:.4g} at {_where(trace, first)}, "
                f"beyond {what.format(reach)}: not a unit to convert, the values are not "
                "physical; check the export (or its scale)")


def _check_time_scale(dt: float, duration: float, source: Any = None) -> None:
    """Time in s: a step above 0.01 s is milliseconds. A trace longer than 1000 s is a
    long recording in seconds where its step read as ms would be under 1 us; with a step
    of 1-10 ms it may be either, and both readings are said. ``dt`` is the mean step and
    ``duration`` the span of the time column, in its own unit; ``source`` the file it was
    read from, named in the command the fix gives."""
    if dt > 1000 * _MAX_TIME_STEP:
        raise TraceError(
            f"column 't' has a mean step of {dt:.6g} (duration {duration:.6g}): neither seconds "
            f"nor milliseconds (a trace in seconds has a step <= {_MAX_TIME_STEP} s, in ms <= "
            f"{1000 * _MAX_TIME_STEP:g} ms); the column holds no time of a test: check the export")
    if dt > _MAX_TIME_STEP:
        raise TraceError(
            f"column 't' looks like milliseconds, not seconds: mean step {dt:.6g}, duration "
            f"{duration:.6g} (a trace in seconds has a step <= {_MAX_TIME_STEP} s and lasts <= "
            f"{_MAX_DURATION:g} s); divide t by 1000, or import the export with its time unit: "
            f"{_import_command(source, '--inspect')}")
    if duration <= _MAX_DURATION:
        return
    cut = ("cut the test out of the recording with "
           + _import_command(source, "--map MAP.toml --window START:END --out TRACE.parquet"))
    if dt < _MIN_TIME_STEP_IF_MS:
        raise TraceError(
            f"the trace lasts {_clock(duration)} ({duration:.6g} s at {1 / dt:.6g} Hz), longer "
            f"than the {_MAX_DURATION:g} s a trace to diagnose may last; a diagnosis needs one "
            f"test profile (0.5 s): {cut}")
    raise TraceError(
        f"column 't' spans {duration:.6g} with a mean step of {dt:.6g}: in seconds the trace "
        f"lasts {_clock(duration)}, longer than the {_MAX_DURATION:g} s a trace to diagnose may "
        f"last ({cut}); in milliseconds it lasts {duration / 1000:.4g} s (divide t by 1000)")


def _check_speed_plausible(trace: Trace) -> None:
    """A motor speed no servo motor reaches, where the same numbers read as deg/s would be
    plausible: positions and speed recorded in degrees and deg/s (consistent with each
    other, so :func:`_check_speed_scale` cannot see it)."""
    peak = float(np.max(np.abs(trace.omega_m))) if trace.n else 0.0
    if peak <= _MAX_SPEED:
        return
    as_degrees = peak * math.pi / 180.0
    if as_degrees <= _MAX_SPEED:
        raise TraceError(
            f"column 'omega_m' reaches {peak:.6g} rad/s ({peak * 60 / (2 * math.pi):.3g} rpm), "
            f"beyond any servo motor (at most {_MAX_SPEED:g} rad/s): positions look like "
            "degrees and the speed like deg/s; multiply theta_m and theta_ref by pi/180 and "
            "omega_m by pi/180, or import the export with its units: `emaphm import FILE "
            "--inspect`")
    raise TraceError(
        f"column 'omega_m' reaches {peak:.6g} rad/s ({peak * 60 / (2 * math.pi):.3g} rpm), "
        f"beyond any servo motor (at most {_MAX_SPEED:g} rad/s); check the unit of omega_m "
        "and theta_m (rad/s and rad, motor side)")


def _lag1_power(x: np.ndarray) -> float:
    """mean(x[k] x[k+1]): the power of the smooth part of ``x``; white noise averages out."""
    return float(np.mean(x[:-1] * x[1:]))


def _check_star(trace: Trace) -> None:
    """The phase currents sum to zero (a star connection), or one current sensor's gain or
    offset explains what they sum to (a sensor fault, diagnosed as such by
    :mod:`emaphm.modes.current_sensor`); otherwise a wiring error, refused."""
    try:
        _check_zero_sum(trace)
    except TraceError as exc:
        fit = best_fit(trace.i_abc)
        if fit.plausible and fit.residual <= _STAR_EXPLAINED:
            return
        raise TraceError(
            f"{exc}; no single current sensor's gain or offset explains it (the best, phase "
            f"{'abc'[fit.phase]} read with gain {fit.gain:.3g} and offset {fit.offset:+.3g} A, "
            f"leaves {fit.residual:.0%} of the phase current in the sum, where a faulty "
            f"sensor would leave at most {_STAR_EXPLAINED:.0%})") from None


def _check_zero_sum(trace: Trace) -> None:
    i_abc = trace.i_abc
    i_rms = float(np.sqrt(np.mean(i_abc * i_abc)))
    if i_rms == 0.0:
        return
    s = i_abc.sum(axis=1)
    worst = int(np.argmax(np.abs(s)))
    hint = (
        "Check for a swapped or missing phase, a wrong sign on one phase or a current "
        "sensor offset; if only two phases were measured, set i_c = -(i_a + i_b)"
    )
    flat = [p for k, p in enumerate(("i_a", "i_b", "i_c")) if np.ptp(i_abc[:, k]) == 0.0]
    if flat:
        hint = f"{', '.join(flat)} is constant throughout (a missing phase?). " + hint
    mean = float(np.mean(s))
    where = (
        f"largest |i_a + i_b + i_c| = {abs(s[worst]):.4g} A at {_where(trace, worst)}"
    )
    if abs(mean) > _STAR_MEAN_LIMIT * i_rms:
        raise TraceError(
            f"the phase currents do not sum to zero as a star connection requires: "
            f"mean(i_a + i_b + i_c) = {mean:.4g} A is {abs(mean) / i_rms:.0%} of the RMS "
            f"phase current {i_rms:.4g} A (limit {_STAR_MEAN_LIMIT:.0%}); {where}. {hint}"
        )
    # Compare the smooth (noise-free) parts only, so that white measurement noise, which
    # does not cancel in the sum, is not mistaken for a wiring error; demand that the
    # excess stands well above the estimator's own scatter (5 sigma for white noise).
    s_ac = s - mean
    p_phase = float(np.mean([_lag1_power(i_abc[:, k]) for k in range(3)]))
    p_sum = _lag1_power(s_ac)
    scatter = float(np.mean(s_ac * s_ac)) / math.sqrt(trace.n - 1)
    if p_phase <= 0.0 or p_sum <= _STAR_AC_LIMIT**2 * p_phase + 5.0 * scatter:
        return
    ratio = math.sqrt(p_sum / p_phase)
    if ratio > _STAR_AC_LIMIT:
        raise TraceError(
            f"the phase currents do not sum to zero as a star connection requires: the "
            f"RMS of i_a + i_b + i_c is {ratio:.0%} of the RMS phase current (limit "
            f"{_STAR_AC_LIMIT:.0%}); {where}. {hint}"
        )


def _check_time_column(trace: Trace, rtol_dt: float, source: Any = None) -> None:
    """``t`` strictly increasing, in seconds and uniform within ``rtol_dt`` (``source``:
    :func:`_check_time_scale`)."""
    t = trace.t
    steps = np.diff(t)
    bad = steps <= 0
    if bad.any():
        first = int(np.argmax(bad)) + 1
        raise TraceError(
            f"column 't' is not strictly increasing: t[{first}] = {t[first]:.9g} s <= "
            f"t[{first - 1}] = {t[first - 1]:.9g} s ({_where(trace, first)}); sort the "
            "samples by time and drop duplicated time stamps"
        )

    _check_time_scale(trace.dt, trace.duration, source)
    dt = trace.dt

    spread = float((steps.max() - steps.min()) / dt)
    if spread > rtol_dt:
        first = int(np.argmax(np.abs(steps - dt) > 0.5 * rtol_dt * dt)) + 1
        raise TraceError(
            f"column 't' is not uniform: the time steps spread by {spread:.3g} of the mean "
            f"step {dt:.6g} s (tolerance rtol_dt = {rtol_dt:g}); the first irregular step "
            f"ends at {_where(trace, first)}. Resample onto a uniform grid: "
            "emaphm.traces.resample(trace, numpy.linspace(trace.t[0], trace.t[-1], "
            "trace.n)) (read files with read_trace(path, validate=False) first)"
        )


def validate(
    trace: Trace, *, min_rotation: float = 2 * np.pi, rtol_dt: float = 1e-3,
    source: Any = None,
) -> Trace:
    """Check that ``trace`` can be diagnosed; return it unchanged, or raise :class:`TraceError`.

    Checks, in order: declared units (``meta["units"]``) are SI; at least
    :data:`MIN_SAMPLES` samples; all values finite; ``t`` strictly increasing, in
    seconds (step <= 0.01 s and duration <= 1000 s) and uniform (relative spread of the
    steps <= ``rtol_dt``); currents in A (|i| <= 1000 A); ``omega_m`` consistent with
    the derivative of ``theta_m`` (catches rpm, deg/s, degrees, revolutions and sign
    errors when there is clear motion; where the speed is too noisy for the
    derivative, its integral against the change of theta_m catches positions in degrees) and below 2000 rad/s (degrees and deg/s together); rotation range ``max(theta_m) - min(theta_m) >=
    min_rotation`` (rad, 0 disables); phase currents summing to about zero (star
    connection).

    ==============  =====  ==========================================================
    argument        unit   meaning
    ==============  =====  ==========================================================
    min_rotation    rad    least motor rotation range; one revolution by default
    rtol_dt         1      largest (max step - min step) / mean step
    source          -      the file the trace was read from, named in the commands the
                           fixes give (``emaphm import FILE ...`` without it)
    ==============  =====  ==========================================================
    """
    if not isinstance(trace, Trace):
        raise TypeError(f"validate() needs a Trace, got {type(trace).__name__}")
    if not (math.isfinite(min_rotation) and min_rotation >= 0):
        raise ValueError(f"min_rotation must be finite and >= 0 rad, got {min_rotation!r}")
    if not (math.isfinite(rtol_dt) and rtol_dt > 0):
        raise ValueError(f"rtol_dt must be finite and > 0, got {rtol_dt!r}")

    _check_declared_symbols(trace.meta.get("units"), "meta['units']")

    n = trace.n
    if n < MIN_SAMPLES:
        raise TraceError(
            f"trace too short: {n} samples, at least {MIN_SAMPLES} are needed; record a "
            "longer profile, e.g. the default diagnostic profile "
            "emaphm.profiles.diagnostic()"
        )

    for name, values in trace.columns().items():
        bad = ~np.isfinite(values)
        if bad.any():
            first = int(np.argmax(bad))
            kind = "NaN" if np.isnan(values[first]) else "inf"
            raise TraceError(
                f"column '{name}' holds {int(bad.sum())} non-finite value(s), the first "
                f"({kind}) at {_where(trace, first)}; remove or interpolate the bad "
                "samples (or cut the trace before them)"
            )

    _check_reach(trace)
    _check_time_column(trace, rtol_dt, source)

    for k, name in enumerate(("i_a", "i_b", "i_c")):
        column = trace.i_abc[:, k]
        big = np.abs(column) > _MAX_CURRENT
        if big.any():
            first = int(np.argmax(big))
            raise TraceError(
                f"column '{name}' looks like mA, not A: |{name}| = {abs(column[first]):.6g} "
                f"> {_MAX_CURRENT:g} at {_where(trace, first)}; divide the phase currents "
                "by 1000"
            )

    _check_speed_scale(trace)
    _check_speed_plausible(trace)

    if min_rotation > 0:
        rotation = float(np.ptp(trace.theta_m))
        if rotation < min_rotation:
            raise TraceError(
                f"trace too short in rotation: max(theta_m) - min(theta_m) = "
                f"{rotation:.4g} rad is below min_rotation = {min_rotation:.4g} rad; "
                "eccentricity identification needs at least one full mechanical "
                f"revolution. {ROTATION_ADVICE}"
            )

    _check_star(trace)
    return trace
