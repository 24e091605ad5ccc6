"""Prognosis: health history per actuator, fault trends and remaining useful life.

The diagnosis of one trace (:func:`emaphm.identify.identify`) is half of
prognostics; this layer follows a fault over repeated inspections (at the gate,
during maintenance, at intervals in flight) and predicts when it will reach its
failure threshold:

* :mod:`.history`: the SQLite store of inspections (:class:`HealthHistory`,
  :func:`inspect` = diagnose a trace and record it);
* :mod:`.uncertainty`: the interval of each identified component
  (:func:`identify_with_spread`);
* :mod:`.thresholds`: health indicators and failure thresholds per fault mode;
* :mod:`.trends`: degradation trends and the RUL distribution
  (:func:`predict_rul`, :func:`prognose`);
* :mod:`.simulator`: growing faults seen at inspections, for tests and demos;
* :mod:`.metrics`: offline prognostic metrics (Saxena et al. 2010);
* :mod:`.plots`: history, prediction cone and alpha-lambda figures.

Data flows down that list; plots only read results.
"""

from .history import (Actuator, DuplicateInspectionError, HealthHistory, HistoryData, HistoryError,
                      Inspection, TimeOrderError, UnknownActuatorError, inspect, trace_fingerprint)
from .metrics import (alpha_lambda, coverage, cumulative_relative_accuracy, prognostic_horizon,
                      relative_accuracy, rul_error)
from .simulator import (DEGRADATION_SCENARIOS, DegradationLaw, DegradationScenario,
                        degradation_scenario, inspection_times, simulate_degradation,
                        synthetic_k_history)
from .thresholds import DEFAULT_FAILURE_THRESHOLDS, INDICATORS, FailureThresholds
from .trends import (Prognosis, RULPrediction, RULTrack, TrendFit, fit_trend, predict_rul, prognose,
                     rul_track)
from .uncertainty import Assessment, KInterval, identify_with_spread

__all__ = [
    "HealthHistory", "HistoryData", "Inspection", "Actuator", "inspect", "trace_fingerprint",
    "HistoryError", "UnknownActuatorError", "TimeOrderError", "DuplicateInspectionError",
    "identify_with_spread", "Assessment", "KInterval",
    "FailureThresholds", "DEFAULT_FAILURE_THRESHOLDS", "INDICATORS",
    "TrendFit", "fit_trend", "predict_rul", "RULPrediction", "prognose", "Prognosis",
    "rul_track", "RULTrack",
    "DegradationLaw", "DegradationScenario", "DEGRADATION_SCENARIOS", "degradation_scenario",
    "inspection_times", "synthetic_k_history", "simulate_degradation",
    "rul_error", "relative_accuracy", "cumulative_relative_accuracy", "alpha_lambda",
    "prognostic_horizon", "coverage",
]
