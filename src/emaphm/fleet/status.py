"""The state of one actuator at a glance, and the order of a fleet: who needs attention first.

:func:`assess` reads an actuator's history (:class:`~emaphm.prognosis.HistoryData`)
and, from three inspections on, its prognosis (:func:`~emaphm.prognosis.prognose`),
and keeps what a fleet table shows:

==============  =======================================================================
field           meaning
==============  =======================================================================
verdict         of the last inspection: ``healthy``, ``faulty``, ``unexplained``,
                ``not diagnosed`` (recorded without a diagnosis) or ``not inspected``
worst           the health indicator nearest its failure threshold (below)
level           its value at the last inspection (the identified k), ``ratio`` =
                level / threshold
rul_*           the RUL median and ``level`` interval of ``worst`` (NaN: no prediction,
                fewer than three inspections; inf: the trend does not reach it)
trend           +1, 0 or -1: the sign of the fitted growth rate of ``worst`` at the last
                inspection, 0 unless it differs from zero by two standard errors
past_threshold  an indicator is at or past its threshold: its last identified value,
                or its fitted trend at the last inspection (RUL median 0)
plan            the next inspection at the fleet's risk
                (:class:`~emaphm.prognosis.inspection.NextInspection`: ``at``, the
                driving indicator, the reason; :data:`FLEET_POLICY` unless given), or
                None when no policy was asked for
==============  =======================================================================

The *worst* indicator is, in this order: the one furthest past its threshold; the one
with the shortest RUL median among those growing towards theirs; else the one whose last
value is nearest its threshold (largest ratio). An indicator *grows towards its
threshold* when its trend rises beyond the noise (``trend`` +1) and its RUL median is
finite and within ten times the history's span
(:meth:`~emaphm.prognosis.RULPrediction.no_growth` false). The first condition keeps a
healthy component out: an exponential fitted to the scatter of a k that sits at zero
can cross a distant threshold at a finite time without any real growth, and a fleet
table would then list a healthy unit among the failing ones. Such an actuator's
``no_growth`` is true and its RUL is shown as "no growth"; the per-indicator RUL of
:func:`~emaphm.prognosis.prognose` is kept in ``prognosis``.

:func:`attention_key` orders a fleet: units past a threshold first (furthest past
first), then the shortest RUL median (then the shortest lower bound), then the units
with no predicted failure by how near their threshold they are, then the units never
inspected; ties by id.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Iterable


from ..prognosis.inspection import DEFAULT_RISK, InspectionPolicy, n_samples_for, plan_inspection
from ..prognosis.thresholds import (DEFAULT_FAILURE_THRESHOLDS, INDICATORS, FailureThresholds,
                                    latest_values)
from ..prognosis.trends import growth_rate, indicator_state

if TYPE_CHECKING:  # pragma: no cover
    from ..prognosis.history import Actuator, HistoryData
    from ..prognosis.inspection import NextInspection
    from ..prognosis.trends import Prognosis

__all__ = ["ActuatorStatus", "assess", "attention_key", "order_fleet", "growth_rate",
           "indicator_state", "VERDICTS", "FLEET_POLICY", "inspect_key"]

#: The policy of the fleet's "inspect by" column and of ``emaphm fleet schedule`` unless
#: given: :data:`~emaphm.prognosis.inspection.DEFAULT_RISK` that an indicator crosses its
#: threshold before the inspection, the intervals of the history's time unit.
FLEET_POLICY = InspectionPolicy(risk=DEFAULT_RISK)

#: Verdicts of the last inspection, as the fleet table names them.
VERDICTS = ("unexplained", "faulty", "healthy", "not diagnosed", "not inspected")


@dataclass(frozen=True)
class ActuatorStatus:
    """One actuator's state (module docstring); results as data."""

    actuator: "Actuator"
    n_inspections: int
    last_time: float | None
    last_recorded_utc: str | None
    verdict: str
    faults: tuple[str, ...]
    worst: str | None
    level: float
    threshold: float
    rul_median: float
    rul_lo: float
    rul_hi: float
    rul_level: float
    no_growth: bool
    past_threshold: bool
    trend: int | None
    growth: float
    data: "HistoryData" = field(repr=False)
    prognosis: "Prognosis | None" = field(repr=False, default=None)
    plan: "NextInspection | None" = field(repr=False, default=None)

    @property
    def id(self) -> str:
        return self.actuator.id

    @property
    def ratio(self) -> float:
        """``level / threshold`` of the worst indicator (NaN when never inspected)."""
        return self.level / self.threshold if self.worst is not None else math.nan

    @property
    def predicted(self) -> bool:
        """A failure is predicted: a finite RUL median of an indicator that grows."""
        return math.isfinite(self.rul_median) and not self.no_growth

    @property
    def rul_state(self) -> str:
        """``past threshold``, ``predicted``, ``no growth`` or ``no prediction``."""
        if self.past_threshold:
            return "past threshold"
        if self.prognosis is None:
            return "no prediction"
        return "predicted" if self.predicted else "no growth"


def _verdict(data: "HistoryData") -> tuple[str, tuple[str, ...]]:
    if not data.n:
        return "not inspected", ()
    diag = data.inspections[-1].diagnosis
    if not isinstance(diag, dict):
        return "not diagnosed", ()
    verdict = diag.get("verdict")
    if verdict not in ("healthy", "faulty", "unexplained"):
        verdict = "healthy" if diag.get("healthy") else "faulty"
    modes = []
    for f in diag.get("faults") or ():
        mode = (str(f.get("mode", "fault")) if isinstance(f, dict) else str(f)).replace("_", " ")
        phase = f.get("phase") if isinstance(f, dict) else None
        name = f"{mode} {phase}" if phase else mode
        if name not in modes:
            modes.append(name)
    return str(verdict), tuple(modes)


def assess(data: "HistoryData", *, thresholds: FailureThresholds = DEFAULT_FAILURE_THRESHOLDS,
           seed: int = 0, level: float = 0.9, prognosis: "Prognosis | None" = None,
           policy: InspectionPolicy | None = FLEET_POLICY) -> ActuatorStatus:
    """The state of one actuator from its history (module docstring).

    With three inspections or more its prognosis is computed (:func:`emaphm.prognosis.prognose`
    with ``seed``, ``thresholds`` and ``level``, and the draws ``policy``'s risk needs)
    unless ``prognosis`` is given; with a ``policy``, its next inspection
    (:func:`~emaphm.prognosis.inspection.plan_inspection`, from its last inspection).
    """
    from ..prognosis.trends import MIN_INSPECTIONS

    verdict, faults = _verdict(data)
    base = dict(actuator=data.actuator, n_inspections=data.n,
                last_time=float(data.times[-1]) if data.n else None,
                last_recorded_utc=data.inspections[-1].recorded_utc if data.n else None,
                verdict=verdict, faults=faults, rul_level=float(level), data=data)
    if not data.n:
        plan = None if policy is None else plan_inspection(
            data.times, None, policy=policy, time_unit=data.actuator.time_unit)
        return ActuatorStatus(worst=None, level=math.nan, threshold=math.nan,
                              rul_median=math.nan, rul_lo=math.nan, rul_hi=math.nan,
                              no_growth=False, past_threshold=False, trend=None,
                              growth=math.nan, prognosis=None, plan=plan, **base)
    observed, readings = data.observed, data.readings     # each read from the records once
    now = latest_values(data.K, observed, readings)  # a placeholder k is no reading
    thr = {n: thresholds.for_indicator(n) for n in INDICATORS}
    ratio = {n: float(now[n]) / thr[n] for n in INDICATORS}
    if prognosis is None and data.n >= MIN_INSPECTIONS:
        from ..prognosis.trends import prognose

        draws = {} if policy is None else {"n_samples": n_samples_for(policy.risk)}
        prognosis = prognose(data.times, data.K, seed=seed, thresholds=thresholds,
                             actuator=data.actuator.id, time_unit=data.actuator.time_unit,
                             level=level, observed=observed, readings=readings, **draws)
    preds = prognosis.predictions if prognosis is not None else {}
    past = [n for n in INDICATORS if ratio[n] >= 1.0 or (n in preds and preds[n].median <= 0.0)]
    span = float(data.times[-1] - data.times[0])
    states = {n: indicator_state(p, span) for n, p in preds.items()}
    growing = [n for n in INDICATORS if n in states and states[n][0] == "predicted"]
    if past:
        worst = max(past, key=lambda n: (ratio[n], -INDICATORS.index(n)))
    elif growing:
        worst = min(growing, key=lambda n: (preds[n].median, preds[n].lo, INDICATORS.index(n)))
    else:
        worst = max(INDICATORS, key=lambda n: (ratio[n], -INDICATORS.index(n)))
    p = preds.get(worst)
    if p is not None:
        _, trend, rate = states[worst]
        rul = (p.median, p.lo, p.hi)
        flat = worst not in growing and not past
    else:
        trend, rate, rul, flat = None, math.nan, (math.nan,) * 3, False
    plan = None if policy is None else plan_inspection(
        data.times, prognosis, policy=policy, time_unit=data.actuator.time_unit, K=data.K,
        thresholds=thresholds, observed=observed, readings=readings)
    return ActuatorStatus(worst=worst, level=float(now[worst]), threshold=thr[worst],
                          rul_median=float(rul[0]), rul_lo=float(rul[1]), rul_hi=float(rul[2]),
                          no_growth=bool(flat), past_threshold=bool(past), trend=trend,
                          growth=float(rate), prognosis=prognosis, plan=plan, **base)


def attention_key(status: ActuatorStatus) -> tuple:
    """Sort key: units needing attention first (module docstring)."""
    if status.worst is None:
        return (3, 0.0, 0.0, status.id)
    if status.past_threshold:
        return (0, -status.ratio, 0.0, status.id)
    if status.predicted:
        return (1, status.rul_median, status.rul_lo, status.id)
    return (2, -status.ratio, 0.0, status.id)


def inspect_key(status: ActuatorStatus) -> tuple:
    """Sort key of the schedule: the units due now first (never inspected first of all,
    then as far past due as they are), whatever their time unit; then by time unit
    (flight hours, then cycles: an hour and a cycle do not compare) the operating time
    left to the next inspection (``at - t_now``, the order of the dates a
    :class:`~emaphm.fleet.schedule.Calendar` gives), soonest first; ties (within float
    noise: 299.99999999999994 is 300) by id; units without a plan last."""
    from .markup import schedule_key

    p = status.plan
    if p is None:
        return schedule_key(status.id)
    return schedule_key(status.id, p.time_unit, p.at - p.t_now, due_now=p.act_now,
                        never=p.t_last is None)



def order_fleet(statuses: Iterable[ActuatorStatus]) -> list[ActuatorStatus]:
    """The statuses in order of attention (:func:`attention_key`)."""
    return sorted(statuses, key=attention_key)
