"""Results to a file and back, one way for every kind: :func:`save` and :func:`load`.

A result is written as JSON: ``{"emaphm_result": KIND, "emaphm_version": ..., "data":
result.to_dict()}``, and read back with the class's ``from_dict``, so that
``load(save(x, path)).to_dict() == x.to_dict()`` (numbers exact: JSON keeps every digit
of a float). :func:`dumps` and :func:`loads` do the same with a string. A list of results
of one kind is saved as a list.

=========================  =====================================================
kind                       class
=========================  =====================================================
``identification``         :class:`emaphm.identify.Identification`
``identification_config``  :class:`emaphm.identify.IdentificationConfig`
``diagnosis``              :class:`emaphm.diagnosis.Diagnosis`
``calibration``            :class:`emaphm.calibration.CalibrationResult`
``spread``                 :class:`emaphm.prognosis.IdentificationSpread`
``interval``               :class:`emaphm.prognosis.KInterval`
``prognosis``              :class:`emaphm.prognosis.Prognosis`
``rul_prediction``         :class:`emaphm.prognosis.RULPrediction`
``rul_track``              :class:`emaphm.prognosis.RULTrack`
``next_inspection``        :class:`emaphm.prognosis.NextInspection`
``inspection_policy``      :class:`emaphm.prognosis.InspectionPolicy`
``inspection``             :class:`emaphm.prognosis.Inspection` (a history's record)
``alpha_lambda``           :class:`emaphm.prognosis.metrics.AlphaLambda`
``parameters``             :class:`emaphm.params.ActuatorParams`
``examination``            :class:`emaphm.verdict.Examination` (its trace's fingerprint)
``sensor_finding``         :class:`emaphm.modes.current_sensor.SensorFinding`
``unit``                   :class:`emaphm.units.Unit` (with its true parameters)
``actuator``               :class:`emaphm.prognosis.history.Actuator`
``skipped_inspection``     :class:`emaphm.prognosis.history.SkippedInspection`
``removed_inspection``     :class:`emaphm.prognosis.history.RemovedInspection`
``policy_run``             :class:`emaphm.prognosis.inspection.PolicyRun`
``degradation_law``        :class:`emaphm.prognosis.DegradationLaw`
``degradation_scenario``   :class:`emaphm.prognosis.DegradationScenario`
``demo_unit``              :class:`emaphm.fleet.demo.DemoUnit`
``schedule_row``           :class:`emaphm.fleet.schedule.ScheduleRow`
``campaign_spec``          :class:`emaphm.campaign.CampaignSpec`
``scenario_spec``          :class:`emaphm.campaign.ScenarioSpec`
``algorithm_spec``         :class:`emaphm.campaign.AlgorithmSpec`
``run_result``             :class:`emaphm.campaign.RunResult` (a campaign's stored run)
``sensors``                :class:`emaphm.acquisition.Sensors` (a recording chain)
``assessment_case``        :class:`emaphm.assessment.spec.Case`
``proportion``             :class:`emaphm.assessment.stats.Proportion`
``tuned_threshold``        :class:`emaphm.assessment.tuning.TunedThreshold`
=========================  =====================================================

What ``to_dict`` leaves out is not saved: the traces (an identification's
``model_trace``, an examination's trace: its fingerprint is kept), a calibration's fitted
currents and, unless asked for (``Prognosis.to_dict(samples=True)``), a prediction's
draws. A unit is saved with its true parameters (``Unit.to_dict(params=True)``).
"""

from __future__ import annotations

import importlib
import json
import os
from pathlib import Path
from typing import Any

__all__ = ["KINDS", "save", "load", "dumps", "loads", "kind_of"]

#: Each kind of result: the module and the class that reads it.
KINDS: dict[str, tuple[str, str]] = {
    "identification": ("emaphm.identify", "Identification"),
    "identification_config": ("emaphm.identify", "IdentificationConfig"),
    "diagnosis": ("emaphm.diagnosis", "Diagnosis"),
    "calibration": ("emaphm.calibration", "CalibrationResult"),
    "spread": ("emaphm.prognosis.uncertainty", "IdentificationSpread"),
    "interval": ("emaphm.prognosis.uncertainty", "KInterval"),
    "prognosis": ("emaphm.prognosis.trends", "Prognosis"),
    "rul_prediction": ("emaphm.prognosis.predictor", "RULPrediction"),
    "rul_track": ("emaphm.prognosis.trends", "RULTrack"),
    "next_inspection": ("emaphm.prognosis.inspection", "NextInspection"),
    "inspection_policy": ("emaphm.prognosis.inspection", "InspectionPolicy"),
    "inspection": ("emaphm.prognosis.history", "Inspection"),
    "alpha_lambda": ("emaphm.prognosis.metrics", "AlphaLambda"),
    "parameters": ("emaphm.params", "ActuatorParams"),
    "examination": ("emaphm.verdict", "Examination"),
    "sensor_finding": ("emaphm.modes.current_sensor", "SensorFinding"),
    "unit": ("emaphm.units", "Unit"),
    "actuator": ("emaphm.prognosis.history", "Actuator"),
    "skipped_inspection": ("emaphm.prognosis.history", "SkippedInspection"),
    "removed_inspection": ("emaphm.prognosis.history", "RemovedInspection"),
    "policy_run": ("emaphm.prognosis.inspection", "PolicyRun"),
    "degradation_law": ("emaphm.prognosis.simulator", "DegradationLaw"),
    "degradation_scenario": ("emaphm.prognosis.simulator", "DegradationScenario"),
    "demo_unit": ("emaphm.fleet.demo", "DemoUnit"),
    "schedule_row": ("emaphm.fleet.schedule", "ScheduleRow"),
    "campaign_spec": ("emaphm.campaign.spec", "CampaignSpec"),
    "scenario_spec": ("emaphm.campaign.spec", "ScenarioSpec"),
    "algorithm_spec": ("emaphm.campaign.spec", "AlgorithmSpec"),
    "run_result": ("emaphm.campaign.store", "RunResult"),
    "sensors": ("emaphm.acquisition", "Sensors"),
    "assessment_case": ("emaphm.assessment.spec", "Case"),
    "proportion": ("emaphm.assessment.stats", "Proportion"),
    "tuned_threshold": ("emaphm.assessment.tuning", "TunedThreshold"),
}

#: What a kind's ``to_dict`` is given to write all that its ``from_dict`` needs.
_WRITE_ALL: dict[str, dict[str, Any]] = {"unit": {"params": True}}


def _class(kind: str) -> type:
    module, name = KINDS[kind]
    return getattr(importlib.import_module(module), name)


def kind_of(result: Any) -> str:
    """The kind of ``result`` (:data:`KINDS`); a TypeError for anything else."""
    for kind, (module, name) in KINDS.items():
        cls = type(result)
        if cls.__name__ == name and cls.__module__ == module:
            return kind
    raise TypeError(f"{type(result).__name__} is not an emaphm result that save() knows; "
                    f"known: {', '.join(n for _, n in KINDS.values())}")


def _payload(result: Any) -> dict[str, Any]:
    from . import __version__

    if isinstance(result, (list, tuple)):
        kinds = {kind_of(r) for r in result}
        if len(kinds) != 1:
            raise TypeError(f"a list of results is saved when they are of one kind, got "
                            f"{', '.join(sorted(kinds)) or 'an empty list'}")
        kind = kinds.pop()
        return {"emaphm_result": kind, "emaphm_version": __version__, "many": True,
                "data": [r.to_dict(**_WRITE_ALL.get(kind, {})) for r in result]}
    kind = kind_of(result)
    return {"emaphm_result": kind, "emaphm_version": __version__,
            "data": result.to_dict(**_WRITE_ALL.get(kind, {}))}


def dumps(result: Any, **json_kw: Any) -> str:
    """``result`` (or a list of results of one kind) as JSON text."""
    return json.dumps(_payload(result), **json_kw)


def loads(text: str) -> Any:
    """The result :func:`dumps` wrote."""
    try:
        payload = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ValueError(f"not an emaphm result: not JSON ({exc})") from None
    kind = payload.get("emaphm_result") if isinstance(payload, dict) else None
    if kind not in KINDS:
        raise ValueError(f"not an emaphm result of a known kind (emaphm_result: {kind!r}); "
                         f"known: {', '.join(KINDS)}")
    cls = _class(kind)
    if payload.get("many"):
        return [cls.from_dict(d) for d in payload["data"]]
    return cls.from_dict(payload["data"])


def save(result: Any, path: str | os.PathLike[str]) -> Path:
    """Write ``result`` (or a list of results of one kind) to ``path`` as JSON
    (atomically); returns the path."""
    from ._files import atomic_write_text

    return atomic_write_text(Path(path), dumps(result, indent=1) + "\n")


def load(path: str | os.PathLike[str]) -> Any:
    """The result (or the list) :func:`save` wrote to ``path``."""
    return loads(Path(path).read_text(encoding="utf-8"))
