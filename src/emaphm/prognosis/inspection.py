"""When to look next: the next inspection of an actuator at a stated risk.

A remaining useful life is a distribution; a maintenance planner needs a date. The next
inspection ``t*`` is the latest time at which the probability that any monitored health
indicator has crossed its failure threshold stays at or below the ``risk`` the planner
sets:

    F(t) = 1 - prod_i (1 - F_i(t)),    t* = sup { t >= t_now : F(t) <= risk }

``F_i(t)`` is the share of the Monte Carlo draws of indicator ``i``
(:func:`emaphm.prognosis.trends.predict_rul`: the trend models mixed by Akaike weight,
each model's parameter covariance as a Student t, the model discrepancy drawn into the
threshold) that have reached the threshold by ``t``. The indicators' draws come from
independent seeds, so the product is the chance that none has (independence is the
assumption: one fault's growth says nothing of another's).

Then, in this order (:func:`plan_inspection`; ``t_last`` the last inspection,
``t_now`` the time the plan is made, the last inspection unless given):

==========================  ==================================================================
rule                        the next inspection
==========================  ==================================================================
``never inspected``         ``t_now``: inspect now
``too few inspections``     fewer than :data:`MIN_INSPECTIONS` (3): ``t_last`` + the default
                            interval (no trend yet)
``healthy``                 no indicator *takes part* (below): ``t_last`` + the default interval
``confirm``                 the risk would act now, but on a trend of fewer than
                            :data:`MIN_FLAG_INSPECTIONS` inspections, or on indicators that
                            were at their healthy level at the inspection before the last
                            (a rise seen once: the scatter of a healthy unit does that now
                            and then) while a crossing before the confirming inspection is
                            less likely than not: ``t_last`` + the minimum interval
``act now``                 ``F(t_now) > risk`` (an indicator is past its threshold), or
                            ``t* - t_now`` under the minimum interval: ``at = t_now``. A
                            degrading actuator is flagged, not chased with ever shorter
                            intervals
``risk``                    ``t*``, when it comes before ``t_last`` + the maximum interval
``max interval``            ``t_last`` + the maximum interval
==========================  ==================================================================

An indicator takes part in the risk when it is past its threshold or grows towards it
(:func:`~emaphm.prognosis.trends.indicator_state`: its trend rises by more than two
standard errors and its RUL median is finite, within ten times the history's span), or
when its level now is at least :data:`HEALTHY_SHARE` (a quarter) of its threshold,
growing or not. The others are at their *healthy level*: their trends follow the scatter
of an identification around zero, and an exponential fitted to that scatter crosses a
distant threshold in a sizeable share of the draws without any growth (a test shows it
on simulated healthy histories). Their draws are no prediction, so they are left out,
and an actuator with none that takes part is inspected at the default interval.

``at <= t_now`` means *inspect / act now*. The default, minimum and maximum intervals
come from :data:`INTERVAL_DEFAULTS` by the history's time unit, unless given
(:class:`InspectionPolicy`).

The Monte Carlo resolution: the risk quantile must rest on at least
:data:`MIN_DRAWS_IN_TAIL` draws, so :func:`n_samples_for` asks for
``max(4000, ceil(40 / risk))`` draws per indicator (4000, the RUL's default, down to a
risk of 0.01), and a risk below :data:`MIN_RISK` is refused.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, Mapping, Sequence

import numpy as np

if TYPE_CHECKING:  # pragma: no cover - the trend models load on first use (the CLI's help
    from .thresholds import FailureThresholds      # reads the interval defaults without them)
    from .trends import Prognosis, RULPrediction

__all__ = ["IntervalDefaults", "INTERVAL_DEFAULTS", "InspectionPolicy", "NextInspection",
           "crossing_cdf", "first_crossing_cdf", "risk_time", "taking_part", "plan_inspection",
           "next_inspection", "n_samples_for", "check_risk", "HEALTHY_SHARE", "MIN_RISK",
           "MIN_DRAWS_IN_TAIL", "RULES", "DEFAULT_RISK", "MIN_FLAG_INSPECTIONS", "PolicyRun", "simulate_policy", "observe"]

#: The risk of the fleet's "inspect by" column and of ``emaphm fleet schedule`` unless given
#: (docs/inspection-planning.md: the risk at which the simulated fleet had no miss).
from .choices import DEFAULT_RISK, FLIGHT_HOUR_INTERVALS  # noqa: E402  (the CLI's parser reads them)
from .choices import HEALTHY_SHARE  # noqa: E402  (the states read it too)

#: Least number of Monte Carlo draws beyond the risk quantile (:func:`n_samples_for`).
MIN_DRAWS_IN_TAIL = 40

#: Smallest risk a plan is made for: 40 / 1e-4 = 400,000 draws per indicator.
MIN_RISK = 1e-4

#: The rules a plan can follow, in the order they are tried (module docstring).
RULES = ("never inspected", "too few inspections", "healthy", "act now", "confirm", "risk",
         "max interval")

#: Inspections a trend needs before its risk flags an actuator (``act now``); with fewer, a
#: risk that comes within the minimum interval plans an inspection at the minimum interval
#: to confirm (rule ``confirm``). Five: the quadratic trend's first, and the linear trend's
#: three degrees of freedom, whose Student t puts its 1 % quantile at 4.5 standard errors
#: (31.8 with one degree of freedom, at three inspections: a trend of three points flags
#: almost any growth, however slow).
MIN_FLAG_INSPECTIONS = 5


@dataclass(frozen=True)
class IntervalDefaults:
    """The intervals a plan uses unless given, in one time unit: ``default`` (too few
    inspections, or no indicator taking part), ``min`` (shorter: act now) and ``max``
    (the longest a plan reaches), with where they come from (``source``)."""

    default: float
    min: float
    max: float
    source: str = ""


#: Interval defaults by the history's time unit. Flight hours: set by
#: ``benchmarks/bench_inspection.py --tune`` on 40 simulated actuators of tuning seeds
#: (1000-1039; lives of 800-2500 h): of ten candidates, the fewest inspections per 1000
#: operating hours with no miss and a median life used of at least 0.8, at risk 0.01
#: (5.0, against 5.4 and 6.3 for the two others that qualified); the reported seeds are 0-199
#: (docs/inspection-planning.md).
#: Cycles: no fleet in cycles has been simulated; the flight-hour numbers are kept as
#: they are (one cycle for one hour) and said so: give yours.
INTERVAL_DEFAULTS: Mapping[str, IntervalDefaults] = MappingProxyType({
    "h": IntervalDefaults(**FLIGHT_HOUR_INTERVALS,
                          source="the flight-hour defaults, bench_inspection.py --tune"),
    "cycles": IntervalDefaults(**FLIGHT_HOUR_INTERVALS,
                               source="the flight-hour numbers: none measured for cycles; "
                                      "give --max-interval, --min-interval and "
                                      "--default-interval in cycles"),
})


def _positive(name: str, value: Any, *, zero: bool = False) -> float | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) \
            or not math.isfinite(value) or value < 0 or (value == 0 and not zero):
        raise ValueError(f"{name} must be a finite number {'>= 0' if zero else '> 0'} (in the "
                         f"history's time unit, e.g. 200), got {value!r}")
    return float(value)


def check_risk(risk: Any) -> float:
    """``risk`` as a float in ``[MIN_RISK, 1)``, or a ValueError that says what to give."""
    if isinstance(risk, bool) or not isinstance(risk, (int, float, np.integer, np.floating)) \
            or not math.isfinite(risk) or not 0.0 < risk < 1.0:
        raise ValueError(f"risk must be a probability in (0, 1), e.g. 0.05, got {risk!r}")
    if risk < MIN_RISK:
        raise ValueError(f"risk {risk:g} is below {MIN_RISK:g}, the smallest the Monte Carlo "
                         f"draws resolve ({MIN_DRAWS_IN_TAIL / MIN_RISK:,.0f} per indicator); "
                         f"give a risk of at least {MIN_RISK:g}")
    return float(risk)


@dataclass(frozen=True)
class InspectionPolicy:
    """How the next inspection is chosen: the ``risk`` (probability that an indicator has
    crossed its failure threshold by the inspection; default :data:`DEFAULT_RISK`) and the
    intervals, in the history's time unit (None: :data:`INTERVAL_DEFAULTS` of that unit).
    Validated on construction."""

    risk: float = DEFAULT_RISK
    max_interval: float | None = None
    min_interval: float | None = None
    default_interval: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "risk", check_risk(self.risk))
        object.__setattr__(self, "max_interval", _positive("max_interval", self.max_interval))
        object.__setattr__(self, "min_interval",
                           _positive("min_interval", self.min_interval, zero=True))
        object.__setattr__(self, "default_interval",
                           _positive("default_interval", self.default_interval))
        if self.max_interval is not None and self.min_interval is not None \
                and self.min_interval >= self.max_interval:
            raise ValueError(f"min_interval {self.min_interval:g} must be below max_interval "
                             f"{self.max_interval:g}")

    def intervals(self, time_unit: str) -> IntervalDefaults:
        """The default, minimum and maximum intervals for a history timed in ``time_unit``:
        those given, the others from :data:`INTERVAL_DEFAULTS`; the default interval
        capped by the maximum. A ValueError when the minimum is not below the maximum."""
        base = INTERVAL_DEFAULTS.get(time_unit)
        if base is None:
            raise ValueError(f"unknown time unit {time_unit!r}; choose one of "
                             f"{', '.join(INTERVAL_DEFAULTS)}")
        hi = base.max if self.max_interval is None else self.max_interval
        lo = base.min if self.min_interval is None else self.min_interval
        dflt = base.default if self.default_interval is None else self.default_interval
        if lo >= hi:
            raise ValueError(f"the minimum interval {lo:g} {time_unit} must be below the maximum "
                             f"{hi:g} {time_unit}; give --min-interval below --max-interval")
        given = [n for n, v in (("max", self.max_interval), ("min", self.min_interval),
                                ("default", self.default_interval)) if v is not None]
        source = base.source if not given else (
            f"given: {', '.join(given)}" + ("" if len(given) == 3 else f"; else {base.source}"))
        return IntervalDefaults(default=min(dflt, hi), min=lo, max=hi, source=source)

    def to_dict(self) -> dict[str, Any]:
        return {"risk": self.risk, "max_interval": self.max_interval,
                "min_interval": self.min_interval, "default_interval": self.default_interval}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "InspectionPolicy":
        return cls(**dict(data))


def n_samples_for(risk: float, base: int = 4000) -> int:
    """Monte Carlo draws per indicator for a plan at ``risk``: at least ``base`` and at
    least :data:`MIN_DRAWS_IN_TAIL` beyond the risk quantile."""
    return max(int(base), int(math.ceil(MIN_DRAWS_IN_TAIL / check_risk(risk) - 1e-9)))


# ----------------------------------------------------------------------------- probabilities
def crossing_cdf(p: "RULPrediction", t: Any) -> np.ndarray:
    """``F_i(t)``: the share of ``p``'s draws that have reached the threshold by the absolute
    time(s) ``t`` (history's unit; a draw at RUL 0 is past it at ``p.t_now``)."""
    t = np.asarray(t, dtype=float)
    cross = np.sort(p.t_now + np.asarray(p.samples, dtype=float))
    return np.searchsorted(cross, t, side="right") / cross.size


def first_crossing_cdf(predictions: Sequence["RULPrediction"], t: Any) -> np.ndarray:
    """``F(t) = 1 - prod (1 - F_i(t))``: the chance that any of ``predictions`` has crossed
    its threshold by ``t`` (independent indicators); zeros when there are none."""
    t = np.asarray(t, dtype=float)
    survive = np.ones(t.shape)
    for p in predictions:
        survive = survive * (1.0 - crossing_cdf(p, t))
    return 1.0 - survive


def risk_time(predictions: Sequence["RULPrediction"], risk: float) -> float:
    """``t* = sup {t >= t_now : F(t) <= risk}`` over ``predictions`` (one ``t_now``):
    ``t_now`` when ``F(t_now) > risk`` already, ``inf`` when ``F`` never exceeds ``risk``
    (most draws never reach their thresholds). ``F`` is a step function of the draws'
    crossing times, so ``t*`` is the first of them at which ``F`` exceeds ``risk``."""
    if not predictions:
        return math.inf
    t_now = predictions[0].t_now
    if any(p.t_now != t_now for p in predictions):
        raise ValueError("the predictions must count from one t_now")
    cand = np.unique(np.concatenate([t_now + p.samples[np.isfinite(p.samples)]
                                     for p in predictions] + [np.array([t_now])]))
    over = np.flatnonzero(first_crossing_cdf(predictions, cand) > risk)
    return float(cand[over[0]]) if over.size else math.inf


def taking_part(prog: "Prognosis") -> dict[str, str]:
    """The indicators of ``prog`` that take part in the risk, name -> why ("past its
    threshold", "growing towards its threshold" or "at x of its threshold"); the others
    are at their healthy level (module docstring)."""
    from .trends import indicator_state, level_at_last

    span = float(prog.times[-1] - prog.times[0]) if prog.times.size else 0.0
    out = {}
    for name, p in prog.predictions.items():
        state = indicator_state(p, span)[0]
        share = level_at_last(p) / p.threshold
        if state == "past threshold":
            out[name] = "past its threshold"
        elif state == "predicted":
            out[name] = "growing towards its threshold"
        elif share >= HEALTHY_SHARE:
            out[name] = f"at {share:.0%} of its threshold"
    return out


# ----------------------------------------------------------------------------- the plan
@dataclass(frozen=True)
class NextInspection:
    """The next inspection of one actuator (results as data).

    ==============  ==================================================================
    field           meaning
    ==============  ==================================================================
    at              time of the next inspection (history's unit); ``<= t_now``: now
    risk            the predicted probability that a taking-part indicator has crossed
                    its threshold by ``at`` (None: no trend takes part, rules ``never
                    inspected``, ``too few inspections`` and ``healthy``)
    indicator       the indicator that drives the plan (largest ``F_i(at)``; the one
                    nearest its threshold for ``act now``), or None
    reason          in words: which indicator and why, or the fall-back taken
    rule            one of :data:`RULES`
    target          the risk the plan was made for
    t_now, t_last   when it was planned; the last inspection (None: none)
    intervals       the :class:`IntervalDefaults` used (given or by time unit)
    time_unit       the history's unit
    p_indicator     indicator -> ``F_i(at)`` of the taking-part indicators
    t_star          the risk time before the rules (inf: never reached; None: no trend)
    ==============  ==================================================================
    """

    at: float
    risk: float | None
    indicator: str | None
    reason: str
    rule: str
    target: float
    t_now: float
    t_last: float | None
    intervals: IntervalDefaults
    time_unit: str = "h"
    p_indicator: dict = field(default_factory=dict)
    t_star: float | None = None

    @property
    def act_now(self) -> bool:
        """The actuator is due now: ``at <= t_now`` (overdue, or flagged)."""
        return self.at <= self.t_now

    @property
    def interval(self) -> float | None:
        """``at - t_last`` (None before a first inspection)."""
        return None if self.t_last is None else self.at - self.t_last

    def summary(self, actuator: str | None = None) -> str:
        """One line: "next inspection of ID by 1240 h (...)" or "act now: ..."."""
        who = actuator or "the actuator"
        unit = self.time_unit
        if self.rule == "act now":
            return f"act now: {who}: {self.reason}"
        if self.rule == "never inspected":
            return f"inspect {who} now: it has never been inspected"
        if self.act_now:
            return (f"inspect {who} now: its next inspection was due at {_t(self.at, unit)} "
                    f"(now {_t(self.t_now, unit)}; {self.reason})")
        return f"next inspection of {who} by {_t(self.at, unit)} ({self.reason})"

    def to_dict(self) -> dict[str, Any]:
        iv = self.intervals
        return {"at": self.at, "risk": self.risk, "indicator": self.indicator,
                "reason": self.reason, "rule": self.rule, "target": self.target,
                "act_now": self.act_now, "t_now": self.t_now, "t_last": self.t_last,
                "interval": self.interval, "time_unit": self.time_unit,
                "intervals": {"default": iv.default, "min": iv.min, "max": iv.max,
                              "source": iv.source},
                "p_indicator": dict(self.p_indicator),
                "t_star": (None if self.t_star is None
                           else self.t_star if math.isfinite(self.t_star) else None),
                "t_star_never": self.t_star is not None and not math.isfinite(self.t_star)}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "NextInspection":
        """The plan :meth:`to_dict` wrote."""
        iv = data["intervals"]
        t_star = math.inf if data.get("t_star_never") else data.get("t_star")
        return cls(at=data["at"], risk=data["risk"], indicator=data["indicator"],
                   reason=data["reason"], rule=data["rule"], target=data["target"],
                   t_now=data["t_now"], t_last=data["t_last"],
                   intervals=IntervalDefaults(default=iv["default"], min=iv["min"], max=iv["max"],
                                              source=iv["source"]),
                   time_unit=data.get("time_unit", "h"),
                   p_indicator=dict(data.get("p_indicator") or {}), t_star=t_star)


def _t(x: float, unit: str) -> str:
    return f"{x:.0f} {unit}" if abs(x) >= 10 else f"{x:.2g} {unit}"


def _apart(x: float, ref: float, digits: int = 2) -> str:
    """``x`` with as many significant digits (from ``digits``, up to 9) as it takes not to
    read as ``ref`` when they differ: a reason that says "0.05, above the risk 0.05" or
    "within 100 h, under 100 h" contradicts itself on paper."""
    for d in range(digits, 10):
        text = f"{x:.{d}g}"
        if x == ref or text != f"{ref:.{d}g}":
            return text
    return f"{x!r}"


def plan_inspection(times: Any, prognosis: "Prognosis | None" = None, *,
                    policy: InspectionPolicy = InspectionPolicy(), t_now: float | None = None,
                    time_unit: str | None = None, K: Any = None,
                    thresholds: "FailureThresholds | None" = None,
                    indicators: Sequence[str] | None = None,
                    observed: Mapping[str, Any] | None = None,
                    readings: Mapping[str, Any] | None = None) -> NextInspection:
    """The next inspection (module docstring) of an actuator inspected at ``times`` (n,),
    from its ``prognosis`` (required from :data:`~emaphm.prognosis.trends.MIN_INSPECTIONS`
    inspections on; its draws must resolve ``policy.risk``: :func:`n_samples_for`).
    ``t_now`` (default: the prognosis's, else the last inspection, else 0) and
    ``time_unit`` (default: the prognosis's, else ``"h"``). Under three inspections, each
    indicator's latest reading in the k history ``K`` (n, 8) and the ``readings`` beyond k
    (of an inspection that could see it, ``observed``:
    :func:`~emaphm.prognosis.thresholds.latest_values`) is compared with the
    ``thresholds`` of the ``indicators`` (default: all): one at or past its threshold is
    acted on now."""
    from .trends import MIN_INSPECTIONS

    times = np.atleast_1d(np.asarray(times, dtype=float))
    unit = time_unit or (prognosis.time_unit if prognosis is not None else "h")
    iv = policy.intervals(unit)
    t_last = float(times[-1]) if times.size else None
    if t_now is None:
        t_now = prognosis.t_now if prognosis is not None else (t_last or 0.0)
    t_now = float(t_now)
    base = dict(target=policy.risk, t_now=t_now, t_last=t_last, intervals=iv, time_unit=unit)
    if t_last is None:
        return NextInspection(at=t_now, risk=None, indicator=None, rule="never inspected",
                              reason="never inspected: inspect now", **base)
    if times.size < MIN_INSPECTIONS or prognosis is None:
        if times.size >= MIN_INSPECTIONS:
            raise ValueError(f"a plan from {times.size} inspections needs their prognosis "
                             "(emaphm.prognosis.prognose)")
        past = _past_at_last(K, thresholds, indicators, observed, readings)
        if past is not None:
            return NextInspection(at=t_now, risk=None, indicator=past[0], rule="act now",
                                  reason=f"{past[0]} past its failure threshold at the last "
                                         f"inspection ({past[1]:.3g} >= {past[2]:g})", **base)
        return NextInspection(at=t_last + iv.default, risk=None, indicator=None,
                              rule="too few inspections",
                              reason=f"too few inspections ({times.size} of {MIN_INSPECTIONS}): "
                                     f"default interval {_t(iv.default, unit)}", **base)
    if not math.isclose(prognosis.t_now, t_now, rel_tol=0.0, abs_tol=1e-9 * max(1.0, abs(t_now))):
        raise ValueError(f"t_now {t_now:g} differs from the prognosis's ({prognosis.t_now:g}); "
                         "predict from the time you plan at")
    _check_resolution(prognosis, policy.risk)
    part = taking_part(prognosis)
    if not part:
        return NextInspection(at=t_last + iv.default, risk=None, indicator=None, rule="healthy",
                              reason="every indicator at its healthy level (none growing "
                                     f"towards its threshold): default interval "
                                     f"{_t(iv.default, unit)}", **base)
    preds = [prognosis.predictions[n] for n in part]
    t_star = risk_time(preds, policy.risk)
    return _risk_plan(preds, part, t_star, policy, base, int(times.size), prognosis)


def _past_at_last(K: Any, thresholds: Any, indicators: Sequence[str] | None,
                  observed: Mapping[str, Any] | None = None,
                  readings: Mapping[str, Any] | None = None):
    """``(indicator, value, threshold)`` of the indicator furthest past its threshold at the
    last inspection that read it (:func:`~emaphm.prognosis.thresholds.latest_values`), or
    None (also without ``K``)."""
    if K is None:
        return None
    from .thresholds import DEFAULT_FAILURE_THRESHOLDS, INDICATORS, latest_values

    K = np.atleast_2d(np.asarray(K, dtype=float))
    if K.shape[0] == 0:
        return None
    thr = thresholds or DEFAULT_FAILURE_THRESHOLDS
    now = latest_values(K, observed, readings)
    past = [(float(now[n]) / thr.for_indicator(n), n) for n in (indicators or INDICATORS)
            if float(now[n]) >= thr.for_indicator(n)]
    if not past:
        return None
    name = max(past)[1]
    return name, float(now[name]), thr.for_indicator(name)


def _check_resolution(prognosis: "Prognosis", risk: float) -> None:
    need = n_samples_for(risk, base=0)
    few = [n for n, p in prognosis.predictions.items() if p.samples.size < need]
    if few:
        raise ValueError(f"a plan at risk {risk:g} needs at least {need} draws per indicator "
                         f"({MIN_DRAWS_IN_TAIL} beyond the quantile); {few[0]} has "
                         f"{prognosis.predictions[few[0]].samples.size}: predict with "
                         f"n_samples=n_samples_for({risk:g})")


def _soon(f_now: float, t_star: float, t_now: float, risk: float, iv: IntervalDefaults
          ) -> bool:
    """The risk comes within the minimum interval: crossed already (``f_now``, the chance
    at ``t_now``) more likely than the risk, or ``t*`` under the minimum interval."""
    return f_now > risk or t_star - t_now < iv.min


def _new_since_last(prognosis: "Prognosis", part: Mapping[str, str]) -> set[str]:
    """The indicators of ``part`` that did not take part at the inspection before the
    last (:func:`taking_part` of the history without its last inspection, predicted with
    the same seed, draws, thresholds, model discrepancy and options,
    :attr:`~emaphm.prognosis.trends.Prognosis.options`)."""
    from .trends import MIN_INSPECTIONS, prognose

    if prognosis.times.size - 1 < MIN_INSPECTIONS:
        return set(part)
    p0 = prognosis.predictions[next(iter(part))]
    options = {"n_samples": int(p0.samples.size), **prognosis.options}
    observed = {n: prognosis.observed(n)[:-1] for n in prognosis.unobserved}
    before = prognose(prognosis.times[:-1], prognosis.K[:-1], observed=observed,
                      readings={n: r[:-1] for n, r in prognosis.beyond_k.items()},
                      seed=0 if p0.seed is None else int(p0.seed),
                      thresholds=prognosis.thresholds, indicators=list(part),
                      discrepancy={m: prognosis.predictions[m].discrepancy for m in part},
                      **options)
    return set(part) - set(taking_part(before))


def _confirm(preds: list, part: Mapping[str, str], t_star: float, base: dict, risk: float,
             why: str) -> NextInspection:
    """The rule ``confirm``: inspect again at the minimum interval after the last
    inspection (due now where a plan made later has passed it); ``why`` is said after the
    lead indicator and its chance of a crossing by then."""
    iv, unit = base["intervals"], base["time_unit"]
    at = base["t_last"] + iv.min
    p_each = _p_each(preds, at)
    lead = max(p_each, key=lambda k: (p_each[k], -list(p_each).index(k)))
    f_at = float(first_crossing_cdf(preds, at))
    reason = (f"{lead} {part[lead]}: probability {_apart(f_at, risk)} of a crossing within the minimum "
              f"interval {_t(iv.min, unit)}, above the risk {risk:g}, but {why}: inspect again "
              "at the minimum interval to confirm")
    return NextInspection(at=at, risk=f_at, indicator=lead, rule="confirm", reason=reason,
                          p_indicator=p_each, t_star=t_star, **base)


def _risk_plan(preds: list, part: Mapping[str, str], t_star: float, policy: InspectionPolicy,
               base: dict, n: int, prognosis: "Prognosis") -> NextInspection:
    """The rules ``act now``, ``confirm``, ``risk`` and ``max interval`` (module docstring)."""
    from .trends import level_at_last

    iv, unit, t_now, t_last = base["intervals"], base["time_unit"], base["t_now"], base["t_last"]
    risk = policy.risk
    f_now = float(first_crossing_cdf(preds, t_now))
    past = [p for p in preds if p.median <= 0.0]
    soon = _soon(f_now, t_star, t_now, risk, iv)
    if soon and n < MIN_FLAG_INSPECTIONS and not past:
        return _confirm(preds, part, t_star, base, risk,
                        f"a trend of {n} inspections is too uncertain to act on (from "
                        f"{MIN_FLAG_INSPECTIONS})")
    if soon and not past and float(first_crossing_cdf(preds, t_last + iv.min)) < 0.5:
        new = _new_since_last(prognosis, part)
        settled = [p for p in preds if p.indicator not in new]
        if new and not (settled and _soon(float(first_crossing_cdf(settled, t_now)),
                                          risk_time(settled, risk), t_now, risk, iv)):
            return _confirm(preds, part, t_star, base, risk,
                            f"{' and '.join(sorted(new))} rose from its healthy level at this "
                            "inspection alone (one reading is no trend to act on)")
    if soon:
        lead = max(preds, key=lambda p: (float(crossing_cdf(p, min(t_star, t_now + iv.min))),
                                         level_at_last(p) / p.threshold))
        if f_now > risk:
            why = (f"{lead.indicator} {part[lead.indicator]}: probability {_apart(f_now, risk)} "
                   f"that it has crossed its failure threshold already, above the risk {risk:g}")
        else:
            dt = t_star - t_now
            within = _t(dt, unit) if _t(dt, unit) != _t(iv.min, unit) else \
                f"{_apart(dt, iv.min, 3)} {unit}"
            why = (f"{lead.indicator} {part[lead.indicator]} would reach its failure threshold "
                   f"with probability {risk:g} within {within}, under the "
                   f"minimum interval {_t(iv.min, unit)}")
        return NextInspection(at=t_now, risk=f_now, indicator=lead.indicator, rule="act now",
                              reason=why, p_indicator=_p_each(preds, t_now), t_star=t_star, **base)
    cap = t_last + iv.max
    at, rule = (t_star, "risk") if t_star <= cap else (cap, "max interval")
    p_each = _p_each(preds, at)
    lead_name = max(p_each, key=lambda n: (p_each[n], -list(p_each).index(n)))
    f_at = float(first_crossing_cdf(preds, at))
    if rule == "risk":
        why = (f"{lead_name} {part[lead_name]}: probability {risk:g} that it crosses its "
               "failure threshold by then")
    else:
        why = (f"maximum interval {_t(iv.max, unit)}; {lead_name} {part[lead_name]}, "
               f"probability {f_at:.2g} of a crossing by then")
    return NextInspection(at=float(at), risk=f_at, indicator=lead_name, rule=rule, reason=why,
                          p_indicator=p_each, t_star=t_star, **base)


def _p_each(preds: Sequence["RULPrediction"], t: float) -> dict[str, float]:
    return {p.indicator: float(crossing_cdf(p, t)) for p in preds}


def next_inspection(times: Any, K: Any, *, seed: int, policy: InspectionPolicy = InspectionPolicy(),
                    t_now: float | None = None, time_unit: str = "h",
                    **kwargs: Any) -> tuple["Prognosis | None", NextInspection]:
    """The prognosis (from :data:`MIN_INSPECTIONS` inspections on, else None) and the next
    inspection of an actuator whose k history is ``K`` (n, 8) at ``times`` (n,).
    ``kwargs`` go to :func:`~emaphm.prognosis.trends.prognose` (``n_samples`` defaults to
    :func:`n_samples_for` the policy's risk)."""
    from .trends import MIN_INSPECTIONS, prognose

    times = np.atleast_1d(np.asarray(times, dtype=float))
    prog = None
    if times.size >= MIN_INSPECTIONS:
        kwargs.setdefault("n_samples", n_samples_for(policy.risk))
        prog = prognose(times, K, seed=seed, t_now=t_now, time_unit=time_unit, **kwargs)
    return prog, plan_inspection(times, prog, policy=policy, t_now=t_now, time_unit=time_unit,
                                 K=K, thresholds=kwargs.get("thresholds"),
                                 indicators=kwargs.get("indicators"),
                                 observed=kwargs.get("observed"), readings=kwargs.get("readings"))


# ----------------------------------------------------------------------------- a policy, simulated
@dataclass(frozen=True)
class PolicyRun:
    """One simulated actuator inspected by a policy until it is flagged or missed
    (:func:`simulate_policy`; results as data).

    ==============  ==================================================================
    field           meaning
    ==============  ==================================================================
    eol             the true end of life: the fault reaches its failure threshold
    times           (n,) the inspections made, all before ``eol``
    rules           (n,) the rule each inspection's plan followed (:data:`RULES`)
    flagged_at      the inspection that flagged the actuator (act now), or None
    missed          the threshold was crossed before the next planned inspection
    planned         the inspection planned after the last one (None when flagged)
    risks           (n,) the predicted chance of a crossing by each plan's inspection
                    (:attr:`NextInspection.risk`; with a fixed interval, by the next
                    fixed inspection; None where a plan has none: too few inspections,
                    healthy). Their sum over the intervals planned is the number of
                    misses a calibrated risk expects of this actuator
    ==============  ==================================================================
    """

    eol: float
    times: np.ndarray
    rules: tuple
    flagged_at: float | None
    missed: bool
    planned: float | None = None
    risks: tuple = ()

    @property
    def expected_misses(self) -> float:
        """The chance of a miss the plans predicted, summed over the intervals planned
        (not the flagging plan's): what a calibrated risk expects this actuator to miss."""
        return float(sum(r for r, rule in zip(self.risks, self.rules)
                         if r is not None and rule != "act now"))

    @property
    def n_inspections(self) -> int:
        return int(self.times.size)

    @property
    def life_used(self) -> float:
        """``flagged_at / eol``: the share of its life an actuator in service since t = 0
        had used when it was flagged (NaN when it was not)."""
        return math.nan if self.flagged_at is None else self.flagged_at / self.eol

    def to_dict(self) -> dict[str, Any]:
        return {"eol": self.eol, "times": self.times.tolist(), "rules": list(self.rules),
                "flagged_at": self.flagged_at, "missed": self.missed, "planned": self.planned,
                "risks": list(self.risks), "expected_misses": self.expected_misses}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "PolicyRun":
        """The run :meth:`to_dict` wrote (``expected_misses`` is computed again)."""
        return cls(eol=float(data["eol"]), times=np.asarray(data["times"], dtype=float),
                   rules=tuple(data["rules"]), flagged_at=data["flagged_at"],
                   missed=bool(data["missed"]), planned=data.get("planned"),
                   risks=tuple(data.get("risks", ())))


def simulate_policy(scenario: Any, policy: InspectionPolicy = InspectionPolicy(), *, seed: int,
                    fixed_interval: float | None = None, noise: float = 0.007,
                    horizon: float | None = None, max_inspections: int = 500,
                    observer: Any = None, **kwargs: Any) -> PolicyRun:
    """Inspect a simulated actuator from t = 0 by ``policy`` until it is flagged (``act
    now``), its fault crosses the failure threshold before the next planned inspection (a
    miss), or ``horizon`` (default: its end of life) is passed.

    Each inspection sees the true k of ``scenario`` (a
    :class:`~emaphm.prognosis.DegradationScenario`, or None for a healthy actuator, which
    needs ``horizon``) plus Gaussian noise of an identification's size
    (:func:`observe`, ``noise`` per component; inspection ``i`` draws from the ``i``-th
    child of the noise seed, the first child of ``SeedSequence(seed)``, so two policies see
    the same noise at their ``i``-th inspections). ``fixed_interval``: the baseline of a fixed
    interval instead, flagged where the same risk criterion finds a crossing before the
    next fixed inspection likely (``t* - t_now`` under the interval). ``observer(times)``,
    if given, returns the k history (n, 8) at the inspection times so far instead (e.g.
    each a plant trace, identified). ``seed`` spawns the noise seed and one seed per plan;
    ``kwargs`` go to
    :func:`~emaphm.prognosis.trends.prognose` (e.g. ``discrepancy={}`` for synthetic k,
    which carries no model discrepancy)."""
    from ..seeds import check_seed

    seed = check_seed(seed)
    if fixed_interval is not None:
        fixed_interval = float(_positive("fixed_interval", fixed_interval))
        policy = InspectionPolicy(risk=policy.risk, min_interval=fixed_interval,
                                  max_interval=2.0 * fixed_interval,
                                  default_interval=fixed_interval)
    eol = math.inf if scenario is None else float(scenario.eol)
    end = eol if horizon is None else float(horizon)
    if not math.isfinite(end):
        raise ValueError("a healthy actuator (no scenario) needs a horizon")
    noise_ss, plan_ss = np.random.SeedSequence(seed).spawn(2)
    noise_seed = int(noise_ss.generate_state(1)[0])
    times: list[float] = [0.0]
    rules: list[str] = []
    risks: list[float | None] = []
    while True:
        t = np.asarray(times)
        K = (observe(scenario, t, seed=noise_seed, noise=noise) if observer is None
             else np.asarray(observer(t), dtype=float))
        plan_seed = int(plan_ss.spawn(1)[0].generate_state(1)[0])
        prog, plan = next_inspection(t, K, seed=plan_seed, policy=policy, **kwargs)
        rules.append(plan.rule)
        nxt = t[-1] + fixed_interval if fixed_interval is not None else plan.at
        risks.append(plan.risk if fixed_interval is None or plan.rule == "act now" else
                     _risk_by(prog, nxt))
        if plan.rule == "act now":
            return PolicyRun(eol, t, tuple(rules), float(t[-1]), False, risks=tuple(risks))
        if nxt >= eol or nxt > end or len(times) >= max_inspections:
            return PolicyRun(eol, t, tuple(rules), None, bool(nxt >= eol), float(nxt),
                             tuple(risks))
        times.append(float(nxt))


def _risk_by(prog: "Prognosis | None", t: float) -> float | None:
    """The chance that an indicator of ``prog`` taking part has crossed by ``t`` (None
    without a prognosis or with none taking part)."""
    part = taking_part(prog) if prog is not None else {}
    if not part:
        return None
    return float(first_crossing_cdf([prog.predictions[n] for n in part], t))


def observe(scenario: Any, times: Any, *, seed: int, noise: float = 0.007) -> np.ndarray:
    """The k an identification would return at ``times`` (n,): the truth of ``scenario``
    (None: a healthy actuator) plus Gaussian noise, ``noise`` per component, inspection
    ``i`` from the ``i``-th child of ``seed`` (:func:`~emaphm.prognosis.synthetic_k_history`);
    (n, 8)."""
    from .simulator import synthetic_k_history

    times = np.atleast_1d(np.asarray(times, dtype=float))
    if scenario is not None:
        return synthetic_k_history(scenario, times, seed=seed, noise=noise)
    from ..faults import K_NOMINAL

    children = np.random.SeedSequence(seed).spawn(times.size)
    e = np.stack([np.random.default_rng(c).standard_normal(8) for c in children]) * noise
    return np.clip(np.tile(K_NOMINAL, (times.size, 1)) + e, 0.0, 1.0)
