"""The acquisition chain of a recorded trace: what stands between the actuator's
true signals and the numbers in the file.

The drive's own control loop sees the true currents and angle; the PHM
recorder has its own current sensors and ADC. Per phase ``j`` the recorded
current is::

    i_rec,j = round(AA[g_j i_j + o_j + n_j] / lsb) * lsb,   n_j ~ N(0, current_noise^2)

with a sensor gain ``g_j`` (1 = ideal), an offset ``o_j`` [A], white noise from an
explicit seed and, optionally, an anti-alias filter ``AA`` (a Butterworth low-pass of
order ``aa_order`` at ``aa_cutoff``, causal like the analogue one) in front of an ADC
sampling at ``f_sample`` (by default the recorder samples at the drive's control
instants, unfiltered). The angle is quantised by the encoder.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Sensors"]


def _phase3(name: str, value, ok) -> tuple[float, float, float]:
    vals = (value,) * 3 if isinstance(value, (int, float)) and not isinstance(value, bool) \
        else tuple(value)
    if len(vals) != 3 or any(isinstance(v, bool) or not isinstance(v, (int, float))
                             or not math.isfinite(v) or not ok(v) for v in vals):
        raise ValueError(f"Sensors.{name} needs a number or 3 per-phase numbers (a, b, c) in "
                         f"range, got {value!r}")
    return tuple(float(v) for v in vals)  # type: ignore[return-value]


@dataclass(frozen=True)
class Sensors:
    """Acquisition chain of the recorded signals.

    =================  ==========  ==================================================
    field              unit        meaning
    =================  ==========  ==================================================
    ``current_noise``  A rms       white Gaussian noise on each phase current
    ``current_lsb``    A           quantisation step of the current ADC (0 = ideal)
    ``encoder_counts`` counts/rev  position quantisation (0 = ideal)
    ``gain``           --          per-phase current sensor gain (a, b, c), 1 = ideal
    ``offset``         A           per-phase current sensor offset (a, b, c)
    ``f_sample``       Hz          recording rate (0: the control instants)
    ``aa_order``       --          anti-alias Butterworth order (0: none)
    ``aa_cutoff``      Hz          anti-alias cut-off frequency
    =================  ==========  ==================================================
    """

    current_noise: float = 0.0
    current_lsb: float = 0.0
    encoder_counts: int = 0
    gain: tuple[float, float, float] = (1.0, 1.0, 1.0)
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    f_sample: float = 0.0
    aa_order: int = 0
    aa_cutoff: float = 0.0

    def __post_init__(self) -> None:
        if isinstance(self.f_sample, bool) or not isinstance(self.f_sample, (int, float)) \
                or not (math.isfinite(self.f_sample) and 0 <= self.f_sample <= 1e6):
            raise ValueError(f"Sensors.f_sample [Hz] must be 0 (the control rate) or up to 1 MHz, "
                             f"got {self.f_sample!r}")
        if isinstance(self.aa_order, bool) or not isinstance(self.aa_order, int) \
                or not 0 <= self.aa_order <= 8:
            raise ValueError(f"Sensors.aa_order must be an integer 0..8, got {self.aa_order!r}")
        if self.aa_order and not (self.f_sample > 0 and 0 < self.aa_cutoff < 0.5 * self.f_sample):
            raise ValueError(f"Sensors.aa_cutoff [Hz] = {self.aa_cutoff!r} must lie between 0 and "
                             f"half the recording rate f_sample = {self.f_sample!r} Hz (give both "
                             "with an anti-alias filter)")
        for name in ("current_noise", "current_lsb"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) \
                    or not (math.isfinite(v) and v >= 0):
                raise ValueError(f"Sensors.{name} [A] must be >= 0, got {v!r}")
        if isinstance(self.encoder_counts, bool) or not isinstance(self.encoder_counts, int) \
                or self.encoder_counts < 0:
            raise ValueError(f"Sensors.encoder_counts [counts/rev] must be an integer >= 0, "
                             f"got {self.encoder_counts!r}")
        object.__setattr__(self, "gain", _phase3("gain", self.gain, lambda v: 0.5 <= v <= 2.0))
        object.__setattr__(self, "offset", _phase3("offset", self.offset, lambda v: abs(v) <= 5.0))

    @property
    def ideal(self) -> bool:
        return (self.current_noise == 0 and self.current_lsb == 0 and self.encoder_counts == 0
                and self.gain == (1.0, 1.0, 1.0) and self.offset == (0.0, 0.0, 0.0))

    def to_dict(self) -> dict:
        return {"current_noise": self.current_noise, "current_lsb": self.current_lsb,
                "encoder_counts": self.encoder_counts, "gain": list(self.gain),
                "offset": list(self.offset), "f_sample": self.f_sample,
                "aa_order": self.aa_order, "aa_cutoff": self.aa_cutoff}

    @classmethod
    def from_dict(cls, data: dict) -> "Sensors":
        """The sensors :meth:`to_dict` wrote (a simulated trace's ``meta["sensors"]``)."""
        d = dict(data)
        for name in ("gain", "offset"):
            if name in d:
                d[name] = tuple(d[name])
        return cls(**d)

    def with_unit(self, gain, offset) -> "Sensors":
        """These sensors with a unit's own gains and offsets."""
        from dataclasses import replace

        return replace(self, gain=tuple(gain), offset=tuple(offset))

    def record(self, t: np.ndarray, signals: dict[str, np.ndarray],
               rng: np.random.Generator | None) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """``(t_rec, recorded)``: the signals ``theta_ref, theta_m, omega_m, i_abc`` (and
        ``torque`` if given) at the control instants ``t``, as this chain records them:
        at ``f_sample`` (interpolated; cubic for the currents) when it is set, the currents
        through the anti-alias filter, with noise, gains, offsets and quantisation."""
        if self.f_sample > 0:
            from scipy.interpolate import CubicSpline

            t_rec = np.arange(0.0, float(t[-1]) + 1e-12, 1.0 / self.f_sample) + float(t[0])
            t_rec = t_rec[t_rec <= float(t[-1]) + 1e-12]
            out = {k: np.interp(t_rec, t, v) for k, v in signals.items() if k != "i_abc"}
            i = CubicSpline(t, signals["i_abc"], axis=0)(t_rec)
        else:
            t_rec, out, i = np.asarray(t), {k: v for k, v in signals.items() if k != "i_abc"}, \
                signals["i_abc"]
        th, i = self.apply(out["theta_m"], i, rng)
        out.update(theta_m=th, i_abc=i)
        return t_rec, out

    def apply(self, theta_m: np.ndarray, i_abc: np.ndarray,
              rng: np.random.Generator | None) -> tuple[np.ndarray, np.ndarray]:
        """Measured ``(theta_m, i_abc)`` from the true signals (new arrays)."""
        i = np.array(i_abc, dtype=float, copy=True)
        i = i * np.asarray(self.gain) + np.asarray(self.offset)
        if self.current_noise > 0:
            if rng is None:
                raise ValueError("sensor noise needs an explicit seed (seed=...)")
            i += rng.normal(0.0, self.current_noise, size=i.shape)
        if self.aa_order:
            from scipy.signal import butter, sosfilt, sosfilt_zi

            sos = butter(self.aa_order, self.aa_cutoff, fs=self.f_sample, output="sos")
            zi = sosfilt_zi(sos)[:, :, None] * i[0][None, None, :]   # settled on the first value
            i, _ = sosfilt(sos, i, axis=0, zi=zi)
        if self.current_lsb > 0:
            i = np.round(i / self.current_lsb) * self.current_lsb
        th = np.array(theta_m, dtype=float, copy=True)
        if self.encoder_counts > 0:
            q = 2 * np.pi / self.encoder_counts
            th = np.floor(th / q) * q
        return th, i
