"""From an identified fault vector to a health verdict (fault detection and identification).

A component of ``k`` raises a fault when it leaves its healthy value by more
than its detection threshold. The default thresholds (:data:`DEFAULT_THRESHOLDS`)
were chosen from the spread of ``k`` identified on nominal reference-model
traces with realistic sensor noise (``emaphm.simulate.DEFAULT_SENSORS``) over
20 noise seeds and the three algorithms (``benchmarks/bench_false_alarms.py``,
table in ``BENCHMARKS.md``): each threshold sits 2 to 10 times above the
largest nominal deviation seen there (least for backlash, the noisiest
component), and well below the paper's low fault magnitude (0.25), so nominal
traces raise no alarm and every single fault of the paper's scenarios is named.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from .faults import (K_NOMINAL, as_k, backlash_scale, check_fault_model, eccentricity_phase,
                     friction_scale, gain_scale, shorted_fraction)
from .params import ActuatorParams, siemens_1fk7060

__all__ = ["Thresholds", "DEFAULT_THRESHOLDS", "THRESHOLDS_BY_FAULT_MODEL", "Fault", "Diagnosis",
           "diagnose", "FAULT_MODES"]

FAULT_MODES = ("friction", "backlash", "short_circuit", "eccentricity", "gain_drift")


@dataclass(frozen=True)
class Thresholds:
    """Detection thresholds on the fault vector (deviation from the healthy value).

    ``friction`` on k1, ``backlash`` on k2, ``short_circuit`` on each of k3-k5,
    ``eccentricity`` on k6, ``gain_drift`` on ``|k8 - 0.5|``.
    """

    friction: float = 0.05
    backlash: float = 0.04
    short_circuit: float = 0.03
    eccentricity: float = 0.03
    gain_drift: float = 0.02

    def __post_init__(self) -> None:
        for name, v in asdict(self).items():
            if not (isinstance(v, (int, float)) and math.isfinite(v) and 0 < v < 1):
                raise ValueError(f"Thresholds.{name} must be in (0, 1), got {v!r}")


DEFAULT_THRESHOLDS = Thresholds()

#: Thresholds per fault model (k3..k5 mean different things under each): under
#: ``physical`` a short-circuit component is the shorted fraction of the turns itself.
THRESHOLDS_BY_FAULT_MODEL = {"paper": DEFAULT_THRESHOLDS,
                             "physical": Thresholds(short_circuit=0.02)}


@dataclass(frozen=True)
class Fault:
    """One detected fault: mode, the k component(s), severity and a physical reading."""

    mode: str
    component: str
    k: float
    severity: float          # 0..1, the fault's share of its full range
    reading: str
    phase: str | None = None


@dataclass(frozen=True)
class Diagnosis:
    """Health verdict of one identified fault vector."""

    k: np.ndarray
    faults: tuple[Fault, ...]
    thresholds: Thresholds = DEFAULT_THRESHOLDS
    fault_model: str = "paper"

    @property
    def healthy(self) -> bool:
        return not self.faults

    @property
    def modes(self) -> tuple[str, ...]:
        return tuple(f.mode for f in self.faults)

    def to_dict(self) -> dict[str, Any]:
        return {"healthy": self.healthy, "faults": [asdict(f) for f in self.faults],
                "thresholds": asdict(self.thresholds), "fault_model": self.fault_model}

    def summary(self) -> str:
        if self.healthy:
            return "healthy: no fault above the detection thresholds"
        return "faulty: " + "; ".join(f.reading for f in self.faults)


def diagnose(k, *, thresholds: Thresholds | None = None,
             params: ActuatorParams | None = None, fault_model: str = "paper") -> Diagnosis:
    """Read the faults out of an identified ``k``.

    ``params`` (the healthy actuator, default preset) turns the components into
    physical values for the readings; ``fault_model`` says what k3..k5 mean
    (and picks the default thresholds, :data:`THRESHOLDS_BY_FAULT_MODEL`).
    """
    k = as_k(k)
    check_fault_model(fault_model)
    if thresholds is None:
        thresholds = THRESHOLDS_BY_FAULT_MODEL[fault_model]
    p = params if params is not None else siemens_1fk7060()
    tr, ctl = p.transmission, p.controller
    faults: list[Fault] = []
    if k[0] > thresholds.friction:
        fs = float(friction_scale(k[0]))
        faults.append(Fault("friction", "k1", float(k[0]), float(k[0]),
                            f"dry friction {fs:.2f}x nominal (dynamic {tr.FDJ * fs:.3f} N m, "
                            f"static {tr.FSJ * fs:.3f} N m)"))
    if k[1] > thresholds.backlash:
        bs = float(backlash_scale(k[1]))
        faults.append(Fault("backlash", "k2", float(k[1]), float(k[1]),
                            f"backlash {bs:.1f}x nominal ({tr.backlash * bs * 1e3:.2f} mrad)"))
    for j, ph in enumerate("ABC"):
        kj = float(k[2 + j])
        if kj > thresholds.short_circuit:
            s = float(shorted_fraction(kj))
            if fault_model == "physical":
                reading = (f"inter-turn short circuit in phase {ph}: {100 * s:.1f}% of its turns "
                           f"as seen through a fault resistance of {p.motor.R_f[j]:g} ohm (a "
                           "higher fault resistance needs more shorted turns for the same "
                           "fault current)")
            else:
                reading = (f"{100 * s:.0f}% of phase {ph} turns shorted "
                           f"(R x{1 - s:.2f}, L x{(1 - s) ** 2:.2f})")
            faults.append(Fault("short_circuit", f"k{3 + j}", kj, kj, reading, phase=ph))
    if k[5] > thresholds.eccentricity:
        phase_deg = math.degrees(float(eccentricity_phase(k[6])))
        faults.append(Fault("eccentricity", "k6,k7", float(k[5]), float(k[5]),
                            f"static eccentricity {100 * k[5]:.0f}% of the air gap at "
                            f"{phase_deg:+.0f} deg"))
    drift = float(k[7] - K_NOMINAL[7])
    if abs(drift) > thresholds.gain_drift:
        g = float(gain_scale(k[7]))
        faults.append(Fault("gain_drift", "k8", float(k[7]), abs(drift) / 0.5,
                            f"proportional gain {100 * (g - 1):+.0f}% (Kp {ctl.Kp * g:.1f} 1/s "
                            f"instead of {ctl.Kp:.1f})"))
    return Diagnosis(k=k, faults=tuple(faults), thresholds=thresholds, fault_model=fault_model)
