"""Measured or simulated actuator traces, in three rooms: the container
(:mod:`~emaphm.traces.container`: :class:`Trace`, :func:`resample`), its validation
(:mod:`~emaphm.traces.validation`: :func:`validate`) and its files
(:mod:`~emaphm.traces.files`: :func:`read_trace`, :func:`write_trace`, over
:mod:`~emaphm.traces.csv_format` and :mod:`~emaphm.traces.parquet_format`). Every public
name is importable from here: ``from emaphm.traces import Trace, read_trace``.

A :class:`Trace` holds what the diagnosis needs from one run of the actuator, sampled on
one uniform time grid. Every quantity is SI:

==========  =======  ===========================================
column      unit     meaning
==========  =======  ===========================================
t           s        time, uniform and strictly increasing
theta_ref   rad      position command (motor side)
theta_m     rad      motor position
omega_m     rad/s    motor speed, d(theta_m)/dt
i_a         A        phase current a
i_b         A        phase current b
i_c         A        phase current c
torque      N m      motor torque T_m (optional, simulations only)
==========  =======  ===========================================

and, optionally, what the drive logs (:data:`DRIVE_COLUMNS`, :attr:`Trace.drive`): the
phase voltages commanded for each control period ``v_a, v_b, v_c`` [V, star-referenced]
or ``v_d, v_q`` [V, the dq frame], or the legs' duty cycles ``d_a, d_b, d_c`` [1] with
the DC link ``v_dc`` [V]; the current references ``i_d_ref, i_q_ref`` [A]; the speed
reference ``omega_ref`` [rad/s]. The metadata key ``voltage_delay_periods`` (0 or 1,
default 0) says whether a logged command was applied in the period it was logged in or in
the next (:mod:`emaphm.drive`).

File formats (chosen by suffix, see :func:`write_trace` / :func:`read_trace`):

* ``.csv``: first line ``# emaphm-trace 1 {json metadata}``, then a header row with the
  column names, then one comma-separated row per sample, each float written as the
  shortest text that reads back to the same double. The reader also accepts bench exports without the
  metadata line: columns in any order, extra columns ignored, ``;`` or tab delimiters,
  names written as ``name [unit]`` and an optional units row such as ``[s],[rad],...``.
* ``.parquet``: one float64 column per quantity; the metadata JSON is stored in the schema
  metadata under the key ``b"emaphm"``.

A trace holds at most :data:`MAX_SAMPLES` samples and a trace file at most
:data:`MAX_FILE_BYTES` bytes; both are checked before a file is read whole. Exports in
other layouts (decimal commas, ms, degrees, MATLAB, TDMS, MDF 4) are read by
:mod:`emaphm.traces.importers` (``emaphm import``).

Writes are atomic: the file is written to a temporary sibling and moved over the target
with :func:`os.replace`, so a failure never leaves a half-written file.
"""

from .._lazy import lazy_exports

#: Public name -> the submodule that defines it; imported on first use (PEP 562), so that
#: importing one submodule (the CLI's, ``emaphm --help``) does not load NumPy and the rest.
_EXPORTS = {
    "COLUMNS": "container", "OPTIONAL_COLUMNS": "container", "UNITS": "container",
    "DRIVE_COLUMNS": "container", "DRIVE_GROUPS": "container",
    "Trace": "container", "TraceError": "container", "TraceWarning": "container",
    "fingerprint": "container", "resample": "container",
    "SUFFIXES": "files", "read_trace": "files", "write_trace": "files",
    "MAX_FILE_BYTES": "limits", "MAX_SAMPLES": "limits",
    "FORMAT_VERSION": "metadata",
    "MIN_SAMPLES": "validation", "validate": "validation",
}

__getattr__, __dir__ = lazy_exports(__name__, globals(), _EXPORTS)

__all__ = [
    "COLUMNS",
    "OPTIONAL_COLUMNS",
    "DRIVE_COLUMNS",
    "DRIVE_GROUPS",
    "UNITS",
    "MIN_SAMPLES",
    "MAX_SAMPLES",
    "MAX_FILE_BYTES",
    "SUFFIXES",
    "FORMAT_VERSION",
    "TraceError",
    "TraceWarning",
    "Trace",
    "validate",
    "write_trace",
    "read_trace",
    "resample",
    "fingerprint",
]
