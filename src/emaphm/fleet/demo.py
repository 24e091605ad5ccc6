"""A simulated fleet, so that the fleet page can be seen without a bench.

:func:`demo_fleet` draws ``n`` actuators from one seed: each has a fault growing along
its own law (:class:`~emaphm.prognosis.DegradationScenario`: dry friction wearing
linearly or faster, an inter-turn short circuit growing exponentially on one phase, a
drifting position-loop gain, backlash, eccentricity) or none (three in ten are healthy),
its own life (the time its fault reaches the failure threshold, 800-2500 h), its own age
(15 % to 108 % of that life: a few are past it) and its own inspection interval, so a
unit has from one inspection (new) to ten.

:func:`record_demo_fleet` writes them into a health history, in one of two ways:

* real (the default): every inspection is a reference-plant trace (switching PWM,
  20 mA sensor noise; :func:`~emaphm.prognosis.simulate_degradation`) diagnosed by
  :func:`~emaphm.prognosis.inspect` exactly as ``emaphm history add`` would, in a pool
  of worker processes (one actuator per task);
* synthetic: no trace and no identification; each inspection records the true ``k``
  plus Gaussian noise of an identification's size
  (:func:`~emaphm.prognosis.synthetic_k_history`) and the verdict
  :func:`~emaphm.diagnosis.diagnose` reads from it. Instant, and a demo of the page,
  not of the diagnosis: such inspections say ``synthetic`` in their source.

Everything flows from one seed: actuator ``i`` draws from the ``i``-th child of
``SeedSequence(seed)``, so a unit does not change when the fleet grows.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator, Sequence

import numpy as np

from ..modes import (backlash as _backlash, eccentricity as _eccentricity, friction as _friction,
                     gain_drift as _gain_drift, short_circuit as _short)
from ..prognosis.simulator import DegradationLaw, DegradationScenario
from ..prognosis.thresholds import DEFAULT_FAILURE_THRESHOLDS
from ..seeds import check_seed

__all__ = ["DemoUnit", "demo_fleet", "record_demo_fleet", "FAULT_KINDS", "MAX_ACTUATORS",
           "MAX_SYNTHETIC"]

#: The most actuators a demo fleet diagnosed from simulated traces may have (about 8 s of
#: CPU each).
MAX_ACTUATORS = 500

#: The most actuators a synthetic demo fleet may have (a fleet to try the site's scale on:
#: recording 10,000 takes minutes, mostly the history's commits).
MAX_SYNTHETIC = 20_000

#: The faults of the demo fleet, dealt in this order (``None``: a healthy unit):
#: (health indicator, degradation law, direction, words).
FAULT_KINDS: tuple = (
    (_friction.INDICATORS[0].name, "linear", 1, "dry friction, wear (linear)"),
    (_short.INDICATORS[0].name, "exponential", 1, "inter-turn short circuit, phase A (exponential)"),
    None,
    (_gain_drift.INDICATORS[0].name, "linear", -1, "position-loop gain drifting down (linear)"),
    (_friction.INDICATORS[0].name, "power", 1, "dry friction, accelerating wear (t^2)"),
    None,
    (_backlash.INDICATORS[0].name, "linear", 1, "backlash, wear (linear)"),
    (_short.INDICATORS[1].name, "exponential", 1, "inter-turn short circuit, phase B (exponential)"),
    None,
    (_eccentricity.INDICATORS[0].name, "linear", 1, "rotor eccentricity (linear)"),
)

_POSITIONS = ("left aileron", "right aileron", "left elevator", "right elevator", "rudder",
              "left spoiler 2", "right spoiler 2", "left flap", "right flap", "trim tab")

_MAX_INSPECTIONS = 10


@dataclass(frozen=True)
class DemoUnit:
    """One simulated actuator: ``scenario`` (None: healthy), its inspection ``times`` (h),
    the ``seed`` of its sensor noise and identifications, and the words for its fault."""

    id: str
    description: str
    scenario: DegradationScenario | None
    times: tuple
    seed: int
    fault: str

    @property
    def eol(self) -> float:
        """True end of life: when its fault reaches the failure threshold (inf if healthy)."""
        return math.inf if self.scenario is None else float(self.scenario.eol)

    def k_true(self) -> np.ndarray:
        """The true fault vectors at its inspections, (n, 8)."""
        from ..faults import K_NOMINAL

        t = np.asarray(self.times, dtype=float)
        if self.scenario is None:
            return np.tile(K_NOMINAL, (t.size, 1))
        return np.atleast_2d(self.scenario.k_at(t))

    def to_dict(self) -> dict[str, Any]:
        return {"id": self.id, "description": self.description, "fault": self.fault,
                "scenario": None if self.scenario is None else self.scenario.to_dict(),
                "times": list(self.times), "seed": self.seed,
                "eol": None if math.isinf(self.eol) else self.eol}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "DemoUnit":
        """The unit :meth:`to_dict` wrote (``eol`` follows from the scenario)."""
        sc = data["scenario"]
        return cls(id=data["id"], description=data["description"],
                   scenario=None if sc is None else DegradationScenario.from_dict(sc),
                   times=tuple(data["times"]), seed=data["seed"], fault=data["fault"])


def _check_count(n: Any, synthetic: bool = False) -> int:
    most = MAX_SYNTHETIC if synthetic else MAX_ACTUATORS
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 1 <= n <= most:
        raise ValueError(f"a demo fleet has 1 to {MAX_ACTUATORS} actuators (1 to "
                         f"{MAX_SYNTHETIC} synthetic), got {n!r}")
    return int(n)


def demo_fleet(n: int = 30, *, seed: int = 0, synthetic: bool = False) -> tuple[DemoUnit, ...]:
    """``n`` demo actuators (module docstring), all drawn from ``seed``; at most
    :data:`MAX_ACTUATORS`, or :data:`MAX_SYNTHETIC` for a ``synthetic`` fleet."""
    n = _check_count(n, synthetic)
    seed = check_seed(seed)
    thr = DEFAULT_FAILURE_THRESHOLDS
    units = []
    for i, child in enumerate(np.random.SeedSequence(seed).spawn(n)):
        rng = np.random.default_rng(child)
        kind = FAULT_KINDS[i % len(FAULT_KINDS)]
        life = float(rng.uniform(800.0, 2500.0))
        if kind is None:
            scenario, words = None, "healthy"
            age = float(rng.uniform(150.0, 2500.0))
            interval = float(rng.uniform(150.0, 400.0))
        else:
            indicator, law, direction, words = kind
            onset = 0.0 if law == "exponential" else float(rng.uniform(0.0, 0.3)) * life
            scenario = DegradationScenario(
                indicator, DegradationLaw.reaching(law, thr.for_indicator(indicator), life,
                                                   onset=onset),
                direction=direction, name=f"demo-{indicator}-{law}")
            age = float(rng.uniform(0.15, 1.08)) * life
            interval = float(rng.uniform(life / 9.0, life / 5.0))
        times = np.arange(0.0, age + 1e-9, interval)
        if times.size > _MAX_INSPECTIONS:          # a long service: the last ten inspections
            times = times[-_MAX_INSPECTIONS:]
        times = np.round(times, 1)
        position = _POSITIONS[i % len(_POSITIONS)]
        units.append(DemoUnit(
            id=f"EMA-{i + 1:03d}", description=f"{position}, aircraft {101 + i // len(_POSITIONS)}",
            scenario=scenario, times=tuple(float(t) for t in times),
            seed=int(child.generate_state(1)[0] % (2 ** 31)), fault=words))
    return tuple(units)


# ----------------------------------------------------------------------------- recording
@dataclass(frozen=True)
class _Task:
    unit: DemoUnit
    db: str
    synthetic: bool
    budget: Any


def _traces(unit: DemoUnit) -> list:
    """The unit's reference-plant traces, one per inspection (noise seeds as
    :func:`~emaphm.prognosis.simulate_degradation` draws them)."""
    from ..prognosis.simulator import simulate_degradation

    if unit.scenario is not None:
        return list(simulate_degradation(unit.scenario, unit.times, seed=unit.seed).traces)
    from ..simulate import DEFAULT_SENSORS, simulate

    seeds = [int(c.generate_state(1)[0])
             for c in np.random.SeedSequence(unit.seed).spawn(len(unit.times))]
    return [simulate(k, sensors=DEFAULT_SENSORS, seed=s, fault_model="paper").with_meta(
        inspection_time=float(t)) for t, k, s in zip(unit.times, unit.k_true(), seeds)]


def _synthetic(unit: DemoUnit) -> np.ndarray:
    from ..prognosis.simulator import synthetic_k_history

    if unit.scenario is not None:
        return synthetic_k_history(unit.scenario, unit.times, seed=unit.seed)
    children = np.random.SeedSequence(unit.seed).spawn(len(unit.times))
    noise = np.stack([np.random.default_rng(c).standard_normal(8) for c in children]) * 0.007
    return np.clip(unit.k_true() + noise, 0.0, 1.0)


def _record(task: _Task, history: Any = None) -> dict:
    """Register one demo actuator and record its inspections (in a worker process for the
    real ones) into ``history`` (open) or the history ``task.db``; returns its summary."""
    import contextlib

    from ..identify import IdentificationConfig
    from ..prognosis.history import HealthHistory
    from ..prognosis.workflow import record_inspection as inspect

    unit = task.unit
    t0 = time.process_time()
    verdicts = []
    with HealthHistory(task.db) if history is None else contextlib.nullcontext(history) as h:
        h.register(unit.id, description=unit.description, time_unit="h")
        if task.synthetic:
            from ..diagnosis import diagnose
            from ..prognosis.uncertainty import IDENTIFICATION_ERROR_P90

            for t, k, k_true in zip(unit.times, _synthetic(unit), unit.k_true()):
                diag = diagnose(k, fault_model="paper")
                h.add(unit.id, t, k, k_lo=np.clip(k - IDENTIFICATION_ERROR_P90, 0.0, 1.0),
                      k_hi=np.clip(k + IDENTIFICATION_ERROR_P90, 0.0, 1.0),
                      spread_method="synthetic", diagnosis=diag.to_dict(),
                      source="synthetic: true k plus identification-sized noise (fleet demo)",
                      extra={"synthetic": True, "fault_model": "paper",
                             "k_true": k_true.tolist()})
                verdicts.append(diag.verdict)
        else:
            for t, trace in zip(unit.times, _traces(unit)):
                ins, _ = inspect(h, unit.id, trace, float(t), seed=unit.seed,
                                 config=IdentificationConfig(budget=task.budget),
                                 source=f"fleet demo: reference plant, {unit.fault}")
                verdicts.append((ins.diagnosis or {}).get("verdict"))
    return {**unit.to_dict(), "verdicts": verdicts, "cpu_s": time.process_time() - t0}


def record_demo_fleet(db: str | Path, units: Sequence[DemoUnit], *, synthetic: bool = False,
                      budget: Any = None, workers: int | None = None,
                      progress: Callable[[dict], None] | None = None) -> list[dict]:
    """Record ``units`` (:func:`demo_fleet`) into the health history ``db``, which must not
    exist yet (the demo never writes into a history that holds anything else).

    Real inspections run in ``workers`` processes (default every core; 0: in this
    process), each committed as it is made; ``budget`` is the identification budget
    (default: the paper's stopping rules). ``progress`` is called with each actuator's
    summary as it finishes. Returns the summaries in the order of ``units``; raises the
    first error once every other actuator is recorded.
    """
    from ..prognosis.history import HealthHistory

    db = Path(db)
    if db.exists():
        raise ValueError(f"{db} exists; the fleet demo writes a new health history: give a new "
                         "--db path or delete that file")
    if not synthetic and len(units) > MAX_ACTUATORS:
        raise ValueError(f"a demo fleet diagnosed from simulated traces has at most "
                         f"{MAX_ACTUATORS} actuators, got {len(units)}; record more with "
                         "synthetic=True (--synthetic)")
    tasks = [_Task(unit=u, db=str(db), synthetic=synthetic, budget=budget) for u in units]
    done: dict[str, dict] = {}
    errors: list = []
    with HealthHistory(db) as h:                # the schema, before the workers open it
        if synthetic:                           # in this process, through this connection:
            _collect(_serial(tasks, h), done, errors, progress)   # an open checks the file
    if not synthetic:
        from ..campaign.executors import make_executor

        _collect(make_executor(workers).map_unordered(_record, tasks), done, errors, progress)
    if errors:
        unit_id, exc = errors[0]
        raise RuntimeError(f"the demo actuator {unit_id} could not be recorded ({exc!r}); "
                           f"{len(done)} others were") from exc
    return [done[u.id] for u in units]


def _serial(tasks: Sequence[_Task], history: Any) -> Iterator[tuple[_Task, Any]]:
    """``(task, summary or exception)`` of each task recorded through ``history``."""
    for task in tasks:
        try:
            yield task, _record(task, history)
        except Exception as exc:                # noqa: BLE001 - reported with the others
            yield task, exc


def _collect(results: Iterable[tuple[_Task, Any]], done: dict, errors: list,
             progress: Callable[[dict], None] | None) -> None:
    for task, result in results:
        if isinstance(result, BaseException):
            errors.append((task.unit.id, result))
            continue
        done[task.unit.id] = result
        if progress is not None:
            progress(result)
