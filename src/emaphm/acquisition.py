"""The acquisition chain of a recorded trace: what stands between the actuator's
true signals and the numbers in the file.

The drive's own control loop sees the true currents and angle; the PHM
recorder has its own current sensors and ADC. Per phase ``j`` the recorded
current is::

    i_rec,j = round((g_j i_j + o_j + n_j) / lsb) * lsb,   n_j ~ N(0, current_noise^2)

with a sensor gain ``g_j`` (1 = ideal), an offset ``o_j`` [A] and white noise
from an explicit seed; the angle is quantised by the encoder.
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
    =================  ==========  ==================================================
    """

    current_noise: float = 0.0
    current_lsb: float = 0.0
    encoder_counts: int = 0
    gain: tuple[float, float, float] = (1.0, 1.0, 1.0)
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
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
                "offset": list(self.offset)}

    def with_unit(self, gain, offset) -> "Sensors":
        """These sensors with a unit's own gains and offsets."""
        return Sensors(self.current_noise, self.current_lsb, self.encoder_counts,
                       tuple(gain), tuple(offset))

    def apply(self, theta_m: np.ndarray, i_abc: np.ndarray,
              rng: np.random.Generator | None) -> tuple[np.ndarray, np.ndarray]:
        """Measured ``(theta_m, i_abc)`` from the true signals (new arrays)."""
        i = np.array(i_abc, dtype=float, copy=True)
        i = i * np.asarray(self.gain) + np.asarray(self.offset)
        if self.current_noise > 0:
            if rng is None:
                raise ValueError("sensor noise needs an explicit seed (seed=...)")
            i += rng.normal(0.0, self.current_noise, size=i.shape)
        if self.current_lsb > 0:
            i = np.round(i / self.current_lsb) * self.current_lsb
        th = np.array(theta_m, dtype=float, copy=True)
        if self.encoder_counts > 0:
            q = 2 * np.pi / self.encoder_counts
            th = np.floor(th / q) * q
        return th, i
