"""A faulty phase-current sensor: one phase read with a gain or an offset off.

Told from the machine by the redundancy of three measured currents, before any model runs
(:mod:`emaphm.traces.zero_sum`): in a star connection the currents sum to zero, and a
sensor that reads ``m_j = g i_j + o`` leaves the sum ``(g - 1) i_j + o``. A machine fault
(an inter-turn short, a demagnetized rotor) leaves it at zero, so a short is never read as
a sensor fault, nor the reverse: the trace is corrected for the sensor
(:func:`correct`) before the machine is identified.

:func:`screen` fits one faulty sensor per phase to the sum and keeps the best: a gain is
named on the phase whose waveform the sum follows; an offset alone moves the sum by a
constant, which any phase could carry, and the identification on each corrected trace
tells which (the lowest fit, :func:`emaphm.verdict.examine`). After ``emaphm calibrate``
the currents are first corrected by the unit's calibrated sensors. A deviation is a fault
beyond its threshold (``current_sensor_gain``, relative; ``current_sensor_offset``, A),
set above the spread the production tolerances leave (see :data:`MODE`). With two
measured currents (the third computed) the sum is zero by construction: sensor faults
are not observable, and the verdict says so.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace
from typing import Any, Callable, Mapping

import numpy as np

from ..traces import Trace
from ..traces.zero_sum import SensorFit, best_fit, two_currents
from .base import PHASES, Fault, FaultMode, Grid, Indicator, Injection, Reading, _number

__all__ = ["SensorFinding", "screen", "correct", "resolve", "tolerance", "MODE", "UNOBSERVABLE_NOTE"]

#: The verdict's note on a trace with two measured currents.
UNOBSERVABLE_NOTE = ("current sensor faults are not observable on this trace: two currents "
                     "were measured and the third computed from them, so they sum to zero "
                     "whatever the sensors read; a sensor's gain or offset error reads as a "
                     "machine fault or a misfit")


@dataclass(frozen=True)
class SensorFinding:
    """What the sum of the measured currents says of the sensors.

    ``observable``: three measured currents; ``fit``: the best single-sensor fit
    (:class:`~emaphm.traces.zero_sum.SensorFit`, after the calibrated sensors' correction);
    ``gain_fault``, ``offset_fault``: its gain and offset are past their thresholds;
    ``phase``: the faulty sensor's phase (0, 1, 2), None while an offset alone has not
    been placed (:meth:`placed`).
    """

    observable: bool
    fit: SensorFit | None = None
    gain_fault: bool = False
    offset_fault: bool = False
    phase: int | None = None

    @property
    def faulty(self) -> bool:
        return self.gain_fault or self.offset_fault

    @property
    def needs_phase(self) -> bool:
        """An offset alone, whose phase the sum cannot tell."""
        return self.faulty and self.phase is None

    def placed(self, phase: int) -> "SensorFinding":
        return replace(self, phase=int(phase))

    def to_dict(self) -> dict:
        """Plain form: ``gain`` and ``offset_a`` of the fit beside the verdict, and the
        whole ``fit`` (its phase as a letter) for :meth:`from_dict`."""
        f = self.fit
        return {"observable": self.observable,
                "phase": None if self.phase is None else PHASES[self.phase],
                "gain": None if f is None else f.gain, "offset_a": None if f is None else f.offset,
                "gain_fault": self.gain_fault, "offset_fault": self.offset_fault,
                "fit": None if f is None else {**asdict(f), "phase": PHASES[f.phase]}}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "SensorFinding":
        """The finding :meth:`to_dict` wrote (one written without ``fit``, by an older
        emaphm, reads back without it)."""
        f = data.get("fit")
        fit = None if f is None else SensorFit(**{**f, "phase": PHASES.index(f["phase"])})
        phase = data.get("phase")
        return cls(observable=bool(data["observable"]), fit=fit,
                   gain_fault=bool(data["gain_fault"]), offset_fault=bool(data["offset_fault"]),
                   phase=None if phase is None else PHASES.index(phase))


def _measured(trace: Trace, params) -> np.ndarray:
    """The trace's currents, corrected by the calibrated unit's sensors where it has them."""
    i = np.asarray(trace.i_abc, dtype=float)
    s = params.sensors if params is not None else None
    if s is not None and params.calibration.date and not s.ideal:
        i = s.correct(i)
    return i


def tolerance(params: Any) -> tuple[float, float]:
    """What a healthy unit's sensors may leave in the single-sensor fit beyond the
    thresholds, ``(gain, offset [A])``: nothing after a calibration (the unit's sensors are
    known and undone); on a data sheet the production tolerance of a sensor's gain and
    offset (:data:`emaphm.units.DEFAULT_TOLERANCES`, +-3 % and +-20 mA): three sensors
    within it leave a single-sensor fit up to about twice that (measured: 5.1 % and 52 mA
    on healthy units of both actuators), under threshold plus tolerance."""
    if params is not None and params.calibration.date:
        return 0.0, 0.0
    from ..units import DEFAULT_TOLERANCES as T

    return (float(max(abs(x) for x in T.sensor_gain)),
            float(max(abs(x) for x in T.sensor_offset)))


def screen(trace: Trace, params, thresholds) -> SensorFinding:
    """The sensors of ``trace`` judged from the sum of its currents (``params``: the
    actuator, calibrated or not; ``thresholds``: :class:`emaphm.modes.Thresholds`, on a
    data sheet plus the sensors' production :func:`tolerance`)."""
    if two_currents(trace.i_abc, trace.meta):
        return SensorFinding(observable=False)
    fit = best_fit(_measured(trace, params))
    tol_gain, tol_offset = tolerance(params)
    gain_fault = fit.plausible and abs(fit.gain - 1.0) > thresholds.current_sensor_gain + tol_gain
    offset_fault = fit.plausible and abs(fit.offset) > thresholds.current_sensor_offset + tol_offset
    return SensorFinding(True, fit, bool(gain_fault), bool(offset_fault),
                         fit.phase if gain_fault else None)


def correct(trace: Trace, finding: SensorFinding, phase: int | None = None) -> Trace:
    """``trace`` with the faulty sensor's reading undone on ``phase`` (default the
    finding's): ``i_j = (m_j - o) / g``."""
    j = finding.phase if phase is None else phase
    if j is None or finding.fit is None:
        return trace
    i = np.array(trace.i_abc, dtype=float)
    g = finding.fit.gain if finding.gain_fault else 1.0
    i[:, j] = (i[:, j] - finding.fit.offset) / g
    meta = dict(trace.meta)
    meta["corrected_sensor"] = {"phase": PHASES[j], "gain": g, "offset_a": finding.fit.offset}
    return replace(trace, i_abc=i, meta=meta)


#: With ``score``, :func:`resolve` identifies every phase whose correction scores within
#: this factor of the best.
SCORE_MARGIN = 1.5


def resolve(trace: Trace, finding: SensorFinding, identify: Callable[[Trace], Any],
            score: Callable[[Trace], float] | None = None
            ) -> tuple[SensorFinding, Trace, Any]:
    """``(finding, corrected trace, identification)``: a faulty sensor undone on its phase;
    an offset alone, whose phase the sum cannot tell, on the phase whose corrected trace
    the machine model fits best (``identify(trace)`` -> an object with ``fitness``; its
    result on the chosen trace is returned, None where no choice was needed).

    Without ``score`` each of the three corrections is identified. With ``score(trace)``
    (Eq. 4 of the healthy actuator on a trace) the three are scored first: a wrong phase
    leaves the offset in two phases' currents, a constant no machine fault makes, which
    adds the same to the fit of any k; only the phases scoring within
    :data:`SCORE_MARGIN` of the best are identified (one identification, usually, instead
    of three, and not the slow one of a wrong correction), and the best fit is kept."""
    if not finding.faulty:
        return finding, trace, None
    if not finding.needs_phase:
        return finding, correct(trace, finding), None
    fixed = [correct(trace, finding, j) for j in range(3)]
    phases = range(3)
    if score is not None:
        scores = [score(t) for t in fixed]
        phases = [j for j in phases if scores[j] <= SCORE_MARGIN * min(scores)]
    tries = [(identify(fixed[j]), j) for j in phases]
    ident, j = min(tries, key=lambda x: x[0].fitness)
    placed = finding.placed(j)
    return placed, correct(trace, placed), ident


def as_findings(finding: SensorFinding) -> dict[str, SensorFinding]:
    """``finding`` as the verdict's ``findings`` keep it (under this mode's name)."""
    return {MODE.name: finding}


def read(r: Reading) -> list[Fault]:
    f: SensorFinding | None = r.findings.get(MODE.name)
    if f is None or not f.faulty or f.phase is None:
        return []
    ph = PHASES[f.phase]
    out = []
    if f.gain_fault:
        g = f.fit.gain
        out.append(Fault("current_sensor", f"sensor_{ph.lower()}", g, abs(g - 1.0),
                         f"current sensor of phase {ph} reads {100 * abs(g - 1):.1f}% "
                         f"{'low' if g < 1 else 'high'} (gain {g:.3f}); the machine was "
                         "diagnosed on the corrected currents", phase=ph,
                         details={"kind": "gain", "value": g}))
    if f.offset_fault:
        o = f.fit.offset
        out.append(Fault("current_sensor", f"sensor_{ph.lower()}", o, abs(o),
                         f"current sensor of phase {ph} reads with an offset of {o:+.3f} A; "
                         "the machine was diagnosed on the corrected currents", phase=ph,
                         details={"kind": "offset", "value": o}))
    return out


def inject(severity: float, phase: str | None = "A", kind: str = "gain") -> Injection:
    """A sensor of ``phase`` reading with gain ``severity`` (``kind="gain"``, 0.5 to 1.5)
    or offset ``severity`` A (``kind="offset"``, within +-5 A)."""
    j = PHASES.index((phase or "A").upper())
    if kind == "gain":
        if not 0.5 <= severity <= 1.5:
            raise ValueError(f"a sensor gain is 0.5 to 1.5, got {severity:g}")
        return Injection(sensor=(j, float(severity), 0.0))
    if kind == "offset":
        if not abs(severity) <= 5.0:
            raise ValueError(f"a sensor offset is within +-5 A, got {severity:g}")
        return Injection(sensor=(j, 1.0, float(severity)))
    raise ValueError(f"a current sensor fault is of kind gain or offset, got {kind!r}")


def parse(fields: list[str]) -> Injection:
    """``PHASE:gain:GAIN`` or ``PHASE:offset:AMPERES``."""
    if len(fields) != 3 or fields[0].upper() not in PHASES or fields[1] not in ("gain", "offset"):
        raise ValueError("--fault current_sensor:PHASE:gain:GAIN or current_sensor:PHASE:offset:A, "
                         "e.g. current_sensor:a:gain:0.9")
    return inject(_number(fields[2], "current_sensor"), fields[0].upper(), fields[1])


#: Thresholds: a gain 5 % off or an offset of 0.08 A, beyond the spread the production
#: tolerances of the other sensors leave in a healthy unit's single-sensor fit (gains
#: +-3 %, offsets +-20 mA each; see docs/fault-modes.md for how they were set).
def measure(r: Reading) -> dict[str, float]:
    """The single-sensor fit's gain and offset deviations beyond the unit's tolerance,
    what the screen compares with its thresholds (0 where no single sensor explains the
    sum, or with two measured currents)."""
    f: SensorFinding | None = r.findings.get(MODE.name)
    if f is None or f.fit is None or not f.fit.plausible:
        return {"current_sensor_gain": 0.0, "current_sensor_offset": 0.0}
    tol_gain, tol_offset = tolerance(r.params)
    return {"current_sensor_gain": abs(f.fit.gain - 1.0) - tol_gain,
            "current_sensor_offset": abs(f.fit.offset) - tol_offset}


#: The assessment's sensors: a gain too low (and one too high), and an offset, each on the
#: unit's own phase in turn.
GRIDS = (Grid("current_sensor:gain", "sensor gain", (0.97, 0.95, 0.9, 0.8),
              inject={"kind": "gain"}, magnitude=lambda s: abs(s - 1.0)),
         Grid("current_sensor:offset", "sensor offset [A]", (0.05, 0.1, 0.2, 0.5),
              inject={"kind": "offset"}))

def _stored_fit(extra: Mapping[str, Any]) -> Mapping[str, Any] | None:
    """The sum's single-sensor fit an inspection stored (``extra["sensors"]``, the finding's
    :meth:`SensorFinding.to_dict`), where the sum was observable and one sensor explains it;
    None otherwise (two measured currents, or a sum no single sensor explains)."""
    found = extra.get("sensors")
    if not isinstance(found, Mapping) or not found.get("observable"):
        return None
    fit = found.get("fit")
    if not isinstance(fit, Mapping) or not fit.get("plausible"):
        return None
    return fit


def _gain_reading(phase: int):
    def read_one(diagnosis: Mapping[str, Any], extra: Mapping[str, Any]) -> float | None:
        fit = _stored_fit(extra)
        if fit is None:
            return None
        return abs(float(fit["gain"]) - 1.0) if PHASES.index(fit["phase"]) == phase else 0.0
    return read_one


def _offset_reading(diagnosis: Mapping[str, Any], extra: Mapping[str, Any]) -> float | None:
    fit = _stored_fit(extra)
    return None if fit is None else abs(float(fit["offset"]))


_UNMEASURED = ("the sum of the measured currents was not one sensor's: two measured "
               "currents (the third computed), or a sum no single sensor explains")

#: Trended by what the sum of the three currents says of the sensors at each inspection
#: (after a calibration, against the calibrated sensors): ``current_sensor_gain_a`` to
#: ``_c``, ``|g - 1|`` of the sensor the sum's single-sensor fit places (0 for the other
#: two: the sum shows no gain of theirs beside it), and ``current_sensor_offset``, the
#: sum's constant ``|o|`` [A], which no phase can be told to carry on a healthy unit (one
#: offset of the three's sum). Failure at a gain 10 % off: the drive regulates a torque
#: 10 % off on that phase and distorts the other two through the star point's balance;
#: and at an offset of 0.5 A: a torque ripple at the electrical frequency of
#: ``2/3 o k_T``, 2.4 % of the peak torque on the preset (I_max 14.1 A), 1.6 % on the 270 V
#: design, that the position loop hunts. Model discrepancies: the relative RMS error of the
#: reading against the plant's sensor on calibrated production units, gains 0.85-0.97 and
#: offsets 0.1-0.5 A (``benchmarks/bench_sensor_drift.py --tune --units 6``, unit seeds
#: 80000-80005, apart from the reported 70000+): gain 0.059 on the preset and 0.087 on the
#: 270 V design (mean -0.020; a 3 % gain read within 0.003), offset 0.028 and 0.025; the
#: larger of each is kept.
INDICATORS = (*(Indicator(f"current_sensor_gain_{p.lower()}", f"current sensor {p} gain (|g - 1|)",
                          failure=0.1, discrepancy=0.087, bounds=(0.0, 0.5), phase=p,
                          threshold="current_sensor_gain", reading=_gain_reading(j),
                          unmeasured=_UNMEASURED)
                for j, p in enumerate(PHASES)),
              Indicator("current_sensor_offset", "current sensors' offset [A]", failure=0.5,
                        discrepancy=0.028, bounds=(0.0, 5.0), threshold="current_sensor_offset",
                        reading=_offset_reading, unmeasured=_UNMEASURED))

MODE = FaultMode("current_sensor", "faulty current sensor", threshold=0.05, read=read,
                 inject=inject, threshold_fields={"current_sensor_gain": 0.05,
                                                  "current_sensor_offset": 0.08},
                 severity_unit="sensor gain", grid=(0.97, 0.95, 0.9, 0.8), per_phase=True,
                 spec="PHASE:gain:GAIN or PHASE:offset:AMPERES", parse_fields=parse,
                 measure=measure, extra_grids=GRIDS, indicators=INDICATORS)
