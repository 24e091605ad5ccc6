"""What the method detects on *your* actuator, and how often it false-alarms
(``emaphm assess``).

Production units of an actuator are drawn within its tolerances and simulated on the
reference plant: healthy, and with one fault at a time over a grid of severities of every
registered fault mode. Each trace is diagnosed as a user would, after ``emaphm calibrate``
on two healthy traces of its unit (and, for healthy traces, on the data sheet too). The
detection thresholds are tuned to a false-alarm target on units of their own, and the
figures are measured on the others: false-alarm rates with their intervals, probability
of detection and of correct identification per mode and severity (MIL-HDBK-1823A-style
curves), the smallest severity named right, the confusion between modes.

=================  ====================================================================
module             role
=================  ====================================================================
``spec``           the settings (:class:`AssessmentSpec`), the fault cases, the tasks
``tasks``          one unit's work (:func:`run_task`), as a worker executes it
``tuning``         thresholds from the readings of healthy units
``stats``          Wilson intervals, hit/miss POD fits
``store``          the units' results as they finish (resume)
``report``         ``assessment.json``, ``report.md``, the figures
``runner``         :func:`assess`: the whole of it into a new folder
``cli``            ``emaphm assess``
=================  ====================================================================
"""

from .._lazy import lazy_exports

_EXPORTS = {"AssessmentSpec": "spec", "AssessmentError": "spec", "grid_names": "spec",
            "assess": "runner", "Outcome": "runner", "check_tracking": "runner",
            "wilson": "stats", "pod_fit": "stats"}

__getattr__, __dir__ = lazy_exports(__name__, globals(), _EXPORTS)

__all__ = ["AssessmentSpec", "AssessmentError", "assess", "Outcome", "check_tracking",
           "grid_names", "wilson", "pod_fit"]
