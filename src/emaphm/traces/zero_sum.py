"""The redundancy of three measured phase currents: in a star connection they sum to zero.

A current sensor that reads with a gain ``g`` and an offset ``o`` on phase ``j``
(``m_j = g i_j + o``, the others right) leaves a sum

    s = m_a + m_b + m_c = (g - 1) i_j + o = beta m_j + c,
    beta = 1 - 1/g,   c = o / g

since the true currents sum to zero. :func:`single_sensor_fits` fits ``s = beta m_j + c``
for each phase by least squares and :func:`best_fit` picks the phase that explains the
sum best: a gain moves the sum with that phase's own waveform, which tells the phase; an
offset alone moves it by a constant, which does not (any phase; the machine model tells
it, :mod:`emaphm.modes.current_sensor`). A machine fault (an inter-turn short of a
phase, an eccentricity) leaves the sum at zero: it never reads as a sensor fault here.

With two measured currents and the third computed from them the sum is zero by
construction and says nothing (:func:`two_currents`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["SensorFit", "single_sensor_fits", "best_fit", "two_currents", "smooth_rms",
           "GAIN_RANGE", "OFFSET_RANGE"]

#: Gains a current sensor can read with and still be called a sensor fault (a sign error,
#: a gain of -1, is wiring: outside).
GAIN_RANGE = (0.5, 1.5)
#: Offsets [A] a current sensor can read with, as a share of the RMS phase current: twice
#: it. A constant sum is an offset whatever its size (a wiring error moves the sum with a
#: phase's waveform, a gain outside :data:`GAIN_RANGE`); the bound only keeps a sum that is
#: mostly a constant of its own (a bias of the acquisition far above the currents) from
#: reading as one sensor. ``emaphm assess`` found a 0.5 A offset on a unit drawing 1 A rms
#: refused as a wiring error under the former bound, half the RMS current.
OFFSET_RANGE = 2.0


def smooth_rms(x: np.ndarray) -> float:
    """RMS of the smooth (noise-free) part of ``x``: ``sqrt(mean(x[k] x[k+1]))`` after its
    mean is removed (white noise averages out of the lag-1 product), 0 if negative."""
    x = np.asarray(x, dtype=float)
    x = x - x.mean()
    p = float(np.mean(x[:-1] * x[1:])) if x.size > 1 else 0.0
    return math.sqrt(p) if p > 0 else 0.0


@dataclass(frozen=True)
class SensorFit:
    """The sum explained by one faulty sensor on ``phase`` (0, 1, 2): its ``gain`` and
    ``offset`` [A]; ``residual`` the smooth RMS of what it leaves of the sum over that of
    the phase currents (0 is a perfect explanation); ``sum_ratio`` the same of the sum
    itself; ``plausible``: a gain in :data:`GAIN_RANGE` and an offset within
    :data:`OFFSET_RANGE` of the RMS phase current."""

    phase: int
    gain: float
    offset: float
    residual: float
    sum_ratio: float
    plausible: bool


def single_sensor_fits(i_abc: np.ndarray) -> list[SensorFit]:
    """One :class:`SensorFit` per phase for the measured currents ``i_abc`` (n, 3) [A]."""
    m = np.asarray(i_abc, dtype=float)
    s = m.sum(axis=1)
    i_rms = float(np.sqrt(np.mean(m * m))) or 1.0
    p_phase = float(np.mean([smooth_rms(m[:, j]) ** 2 for j in range(3)])) or 1.0
    scale = math.sqrt(p_phase)
    sum_ratio = smooth_rms(s) / scale
    out = []
    for j in range(3):
        A = np.column_stack([m[:, j], np.ones_like(s)])
        (beta, c), *_ = np.linalg.lstsq(A, s, rcond=None)
        gain = 1.0 / (1.0 - beta) if beta != 1.0 else math.inf
        offset = c * gain
        r = s - A @ np.array([beta, c])
        plausible = (GAIN_RANGE[0] <= gain <= GAIN_RANGE[1]
                     and abs(offset) <= OFFSET_RANGE * i_rms)
        out.append(SensorFit(j, float(gain), float(offset), smooth_rms(r) / scale,
                             float(sum_ratio), bool(plausible)))
    return out


def best_fit(i_abc: np.ndarray) -> SensorFit:
    """The plausible single-sensor fit that leaves the least of the sum (the least
    residual of all three where none is plausible)."""
    fits = single_sensor_fits(i_abc)
    pool = [f for f in fits if f.plausible] or fits
    return min(pool, key=lambda f: f.residual)


def two_currents(i_abc: np.ndarray, meta: dict | None = None) -> bool:
    """Whether the third current was computed from the two measured (the trace's metadata
    says so, ``currents_measured: 2``, or the sum is zero to round-off)."""
    if isinstance(meta, dict) and meta.get("currents_measured") == 2:
        return True
    m = np.asarray(i_abc, dtype=float)
    if m.size == 0:
        return False
    scale = float(np.max(np.abs(m))) or 1.0
    return bool(np.max(np.abs(m.sum(axis=1))) <= 1e-9 * scale)
