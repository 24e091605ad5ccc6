"""Prognosis: health history per actuator, fault trends and remaining useful life.

The diagnosis of one trace (:func:`emaphm.identify.identify`) is half of
prognostics; this layer follows a fault over repeated inspections (at the gate,
during maintenance, at intervals in flight) and predicts when it will reach its
failure threshold:

* :mod:`.history`: the SQLite store of inspections (:class:`HealthHistory`);
* :mod:`.workflow`: :func:`record_inspection`, diagnose a trace and record it (``inspect``
  before 0.5, a name that shadowed the standard library's: kept for one release with a
  DeprecationWarning, as ``Assessment`` for :class:`IdentificationSpread`);
* :mod:`.uncertainty`: the interval of each identified component
  (:func:`identify_with_spread`);
* :mod:`.thresholds`: health indicators and failure thresholds per fault mode;
* :mod:`.trends`: degradation trends and the RUL distribution
  (:func:`predict_rul`, :func:`prognose`);
* :mod:`.inspection`: when to look next, the next inspection at a stated risk
  (:func:`next_inspection`, :func:`plan_inspection`, :class:`InspectionPolicy`);
* :mod:`.simulator`: growing faults seen at inspections, for tests and demos;
* :mod:`.metrics`: offline prognostic metrics (Saxena et al. 2010);
* :mod:`.plots`: history, prediction cone and alpha-lambda figures.

Data flows down that list; plots only read results.
"""

from .._lazy import lazy_exports

#: Public name -> the submodule that defines it; imported on first use (PEP 562), so
#: that importing one submodule (e.g. the CLI's) does not load every other one.
_EXPORTS = {
    "Actuator": "history",
    "CalibrationRecord": "history",
    "DuplicateInspectionError": "history",
    "HealthHistory": "history",
    "HistoryData": "history",
    "HistoryError": "history",
    "Inspection": "history",
    "TimeOrderError": "history",
    "UnknownActuatorError": "history",
    "inspect": "workflow",
    "record_inspection": "workflow",
    "trace_fingerprint": "history",
    "alpha_lambda": "metrics",
    "coverage": "metrics",
    "cumulative_relative_accuracy": "metrics",
    "prognostic_horizon": "metrics",
    "relative_accuracy": "metrics",
    "rul_error": "metrics",
    "DEGRADATION_SCENARIOS": "simulator",
    "DegradationLaw": "simulator",
    "DegradationScenario": "simulator",
    "degradation_scenario": "simulator",
    "inspection_times": "simulator",
    "simulate_degradation": "simulator",
    "synthetic_k_history": "simulator",
    "DEFAULT_FAILURE_THRESHOLDS": "thresholds",
    "INDICATORS": "thresholds",
    "FailureThresholds": "thresholds",
    "Prognosis": "trends",
    "RULPrediction": "trends",
    "RULTrack": "trends",
    "TrendFit": "trends",
    "fit_trend": "trends",
    "predict_rul": "trends",
    "prognose": "trends",
    "rul_track": "trends",
    "InspectionPolicy": "inspection",
    "NextInspection": "inspection",
    "next_inspection": "inspection",
    "plan_inspection": "inspection",
    "Assessment": "uncertainty",
    "IdentificationSpread": "uncertainty",
    "KInterval": "uncertainty",
    "identify_with_spread": "uncertainty",
}


__getattr__, __dir__ = lazy_exports(__name__, globals(), _EXPORTS)

__all__ = [
    "HealthHistory", "HistoryData", "Inspection", "Actuator", "CalibrationRecord",
    "record_inspection",
    "trace_fingerprint",
    "HistoryError", "UnknownActuatorError", "TimeOrderError", "DuplicateInspectionError",
    "identify_with_spread", "IdentificationSpread", "KInterval",
    "FailureThresholds", "DEFAULT_FAILURE_THRESHOLDS", "INDICATORS",
    "TrendFit", "fit_trend", "predict_rul", "RULPrediction", "prognose", "Prognosis",
    "rul_track", "RULTrack",
    "InspectionPolicy", "NextInspection", "next_inspection", "plan_inspection",
    "DegradationLaw", "DegradationScenario", "DEGRADATION_SCENARIOS", "degradation_scenario",
    "inspection_times", "synthetic_k_history", "simulate_degradation",
    "rul_error", "relative_accuracy", "cumulative_relative_accuracy", "alpha_lambda",
    "prognostic_horizon", "coverage",
]
