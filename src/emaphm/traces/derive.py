"""The channels a trace may leave out, derived the one way: the motor speed from its
position, the third phase current from the other two.

:func:`derive_missing` is what ``emaphm import`` (:func:`emaphm.traces.importers.import_trace`)
and :meth:`emaphm.traces.Trace.from_pandas` (and :meth:`~emaphm.traces.Trace.from_columns`)
do with a recording that lacks them, and what they note in the metadata
(:func:`derived_meta`): ``currents_measured`` (2 or 3) and, under ``derived``, how each
derived channel was made.
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np

__all__ = ["DERIVABLE", "derive_missing", "derived_meta", "SPEED_NOTE", "THIRD_CURRENT_NOTE"]

#: The channels that may be left out, and what each is derived from.
DERIVABLE = {"omega_m": ("theta_m", "t"), "i_c": ("i_a", "i_b")}

SPEED_NOTE = "derived from theta_m (central differences)"
THIRD_CURRENT_NOTE = "-(i_a + i_b): current sensor faults are not observable"


def derive_missing(cols: Mapping[str, np.ndarray], t: np.ndarray) -> tuple[dict[str, np.ndarray],
                                                                           dict[str, str]]:
    """``(columns, notes)``: ``cols`` with ``omega_m`` (``np.gradient`` of ``theta_m`` over
    ``t``, central differences inside, one-sided at the ends; 0 for one sample) and ``i_c``
    (``-(i_a + i_b)``: a star winding's currents sum to zero) where they are missing, and a
    note for each channel derived."""
    out = dict(cols)
    notes = {}
    if "omega_m" not in out:
        t = np.asarray(t, dtype=float)
        out["omega_m"] = (np.gradient(np.asarray(out["theta_m"], dtype=float), t) if t.size > 1
                          else np.zeros_like(t))
        notes["omega_m"] = SPEED_NOTE
    if "i_c" not in out:
        out["i_c"] = -(np.asarray(out["i_a"], dtype=float) + np.asarray(out["i_b"], dtype=float))
        notes["i_c"] = THIRD_CURRENT_NOTE
    return out, notes


def derived_meta(meta: Mapping[str, Any], notes: Mapping[str, str]) -> dict[str, Any]:
    """``meta`` with what :func:`derive_missing` did: ``currents_measured: 2`` where ``i_c``
    was derived, and the ``derived`` notes."""
    out = dict(meta)
    if "i_c" in notes:
        out["currents_measured"] = 2
    if notes:
        out["derived"] = {**dict(out.get("derived") or {}), **notes}
    return out
