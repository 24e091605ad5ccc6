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

File formats (chosen by suffix, see :func:`write_trace` / :func:`read_trace`):

* ``.csv``: first line ``# emaphm-trace 1 {json metadata}``, then a header row with the
  column names, then one comma-separated row per sample written with ``repr`` of each
  float (shortest exact round trip). The reader also accepts bench exports without the
  metadata line: columns in any order, extra columns ignored, ``;`` or tab delimiters,
  names written as ``name [unit]`` and an optional units row such as ``[s],[rad],...``.
* ``.parquet``: one float64 column per quantity; the metadata JSON is stored in the schema
  metadata under the key ``b"emaphm"``.

Writes are atomic: the file is written to a temporary sibling and moved over the target
with :func:`os.replace`, so a failure never leaves a half-written file.
"""

from .container import COLUMNS, OPTIONAL_COLUMNS, UNITS, Trace, TraceError, resample
from .files import SUFFIXES, read_trace, write_trace
from .metadata import FORMAT_VERSION
from .validation import MIN_SAMPLES, validate

__all__ = [
    "COLUMNS",
    "OPTIONAL_COLUMNS",
    "UNITS",
    "MIN_SAMPLES",
    "SUFFIXES",
    "FORMAT_VERSION",
    "TraceError",
    "Trace",
    "validate",
    "write_trace",
    "read_trace",
    "resample",
]
