"""What the monitoring model's kernels share: the physical range a candidate must stay
in, the status codes a candidate ends with, and the check that the packed parameters
fit the kernel's step. :mod:`~emaphm.models.step`, :mod:`~emaphm.models.monitoring`
(the scalar kernel and the model), :mod:`~emaphm.models.monitoring_simd` and the NumPy
oracle of the tests import them from here, so no kernel module imports another for
them."""

from __future__ import annotations

import numpy as np

from ._jit import jit
from .controller import N_CTL, plain
from .layout import C_OMEGA_S, C_V_DT, P_CTL, P_DT, P_T_S, drive_settings

__all__ = ["I_DIVERGED", "OMEGA_DIVERGED", "STATUS_OK", "STATUS_DIVERGED", "STATUS_TRIPPED",
           "variant_key", "variant_of"]

#: A candidate whose phase current exceeds this [A] has diverged (frozen, fitness inf).
I_DIVERGED = 1e4
#: A candidate whose motor speed exceeds this [rad/s] has diverged.
OMEGA_DIVERGED = 1e5
#: Status of a candidate: ran to the end within the physical range.
STATUS_OK = 0
#: Status: left the physical range (or went non-finite) and was frozen there.
STATUS_DIVERGED = 1
#: Status: the drive tripped on overcurrent and went on in active short circuit.
STATUS_TRIPPED = 2


@jit
def _check_step(P, n_sub):
    """The electrics in CP were packed for the sub-step ``T_s / n_sub``."""
    if P[P_DT] != P[P_T_S] / n_sub:
        raise ValueError("CP holds the winding step for another n_sub: pack the population "
                         "with the n_sub the kernel runs")


def variant_key(P: np.ndarray, CP: np.ndarray) -> tuple[bool, bool]:
    """Which compiled variant of a kernel runs a population: ``(plain, ideal)``, the drive's
    options all at their defaults (:func:`emaphm.models.controller.plain`) and an ideal plant:
    no candidate's inverter losing a volt to dead time, no candidate's friction with a
    Stribeck drop (its step then skips their work: the same numbers)."""
    CP = np.asarray(CP)
    return (bool(plain.py_func(P[P_CTL:P_CTL + N_CTL])),
            not bool(np.any(CP[:, C_V_DT] != 0.0) or np.any(CP[:, C_OMEGA_S] != 0.0)))


def variant_of(params) -> tuple[bool, bool]:
    """:func:`variant_key` of the actuator ``params`` itself (every candidate at its
    inverter's loss and its friction's Stribeck speed): the variant a population of it
    runs."""
    return (bool(plain.py_func(drive_settings(params))),
            params.inverter.V_lost == 0.0 and params.transmission.omega_s == 0.0)
