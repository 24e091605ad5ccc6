"""What an assessment runs: its settings (:class:`AssessmentSpec`, frozen, JSON in and out,
hashed so that a resumed assessment is the same one), the fault cases the registry of
fault modes gives (:func:`cases`) and the tasks (:class:`Task`, one production unit each)
that the workers execute.

Seeds
-----
Every random choice flows from ``seed``: ``SeedSequence([ASSESS, seed])`` spawns two
branches, one for the **tuning units** (their healthy traces set the thresholds) and one
for the **reported units** (every figure of the report), so that no reported figure comes
from a unit the thresholds were tuned on. Each unit's branch gives its unit seed
(:func:`emaphm.units.draw_unit`) and the noise seed of each of its traces.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass, field, replace
from typing import Any, Mapping

import numpy as np

from ..modes import MODES, PHASES, Grid
from ..seeds import check_seed

__all__ = ["AssessmentSpec", "Case", "Task", "cases", "grid_names", "AssessmentError",
           "HEALTHY", "ASSESS"]

#: The spawn key of an assessment's seeds ("asss"), apart from every other seed of emaphm.
ASSESS = 0x61737373

#: The name of the healthy case.
HEALTHY = "healthy"


class AssessmentError(ValueError):
    """Settings an assessment cannot run with; the message names the fix."""


def grid_names() -> tuple[str, ...]:
    """Every grid the registered fault modes can be assessed on, in the registry's order."""
    return tuple(g.name for m in MODES.values() for g in m.grids())


def _grid(name: str) -> tuple[Any, Grid]:
    for m in MODES.values():
        for g in m.grids():
            if g.name == name:
                return m, g
    raise AssessmentError(f"unknown assessment grid {name!r}; choose from {', '.join(grid_names())}")


@dataclass(frozen=True)
class Case:
    """One fault a unit is diagnosed with: the ``grid`` (row label), its ``mode``, the
    ``severity`` in the grid's unit and its ``magnitude``, the ``phase`` (per-phase modes),
    the injection's keywords (``kwargs``: a fault resistance, a sensor's kind) and the
    faults a right diagnosis names (``expected``: ``(mode, phase)`` pairs)."""

    grid: str
    mode: str
    severity: float
    magnitude: float
    phase: str | None
    kwargs: Mapping[str, Any]
    expected: tuple[tuple[str, str | None], ...]

    def injection(self) -> Any:
        return MODES[self.mode].inject(self.severity, self.phase, **dict(self.kwargs))

    def to_dict(self) -> dict[str, Any]:
        return {"grid": self.grid, "mode": self.mode, "severity": self.severity,
                "magnitude": self.magnitude, "phase": self.phase, "kwargs": dict(self.kwargs),
                "expected": [list(e) for e in self.expected]}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "Case":
        """The case :meth:`to_dict` wrote."""
        return cls(grid=data["grid"], mode=data["mode"], severity=data["severity"],
                   magnitude=data["magnitude"], phase=data["phase"], kwargs=dict(data["kwargs"]),
                   expected=tuple(tuple(e) for e in data["expected"]))


@dataclass(frozen=True)
class AssessmentSpec:
    """The settings of one assessment of one actuator.

    ==================  ==================================================================
    field               meaning
    ==================  ==================================================================
    params              the actuator's data sheet: an :class:`ActuatorParams`, its
                        :meth:`~ActuatorParams.to_dict` or a TOML path (held as the dict)
    tolerances          the production tolerances units are drawn within (a dict of
                        :class:`emaphm.units.Tolerances`)
    units               reported production units (default 20)
    tune_units          units the thresholds are tuned on (default: as many); 0 keeps the
                        parameters' thresholds (``tune=False``)
    healthy             healthy traces per reported unit diagnosed after calibration
    healthy_datasheet   of those, how many are also diagnosed on the data sheet
    tune_healthy        healthy traces per tuning unit
    target_far          the false-alarm rate the tuned thresholds aim under (calibrated)
    seed                the master seed
    grids               the grids assessed (default every one of the registry)
    severities          grids whose severities replace the registry's, ``{name: (s, ...)}``
    datasheet_faults    also diagnose every faulty trace on the data sheet (slow; off)
    algorithm           the identification's solver (default the least squares)
    drive_signals       the traces carry the drive's voltage commands and references, so
                        that the units are diagnosed on the recorded-voltage path (the
                        drive's controller not modelled); default off: the modelled one
    ==================  ==================================================================
    """

    params: Mapping[str, Any]
    tolerances: Mapping[str, Any] = field(default_factory=dict)
    units: int = 20
    tune_units: int | None = None
    healthy: int = 10
    healthy_datasheet: int = 2
    tune_healthy: int = 4
    target_far: float = 0.01
    seed: int = 0
    grids: tuple[str, ...] | None = None
    severities: Mapping[str, tuple[float, ...]] = field(default_factory=dict)
    datasheet_faults: bool = False
    algorithm: str = "lsq"
    drive_signals: bool = False

    def __post_init__(self) -> None:
        from ..params import ActuatorParams, as_params
        from ..units import Tolerances

        try:
            params = (ActuatorParams.from_dict(dict(self.params), source="--params")
                      if isinstance(self.params, Mapping) else as_params(self.params))
        except ValueError as exc:
            raise AssessmentError(str(exc)) from None
        if params is None:
            raise TypeError("AssessmentSpec needs the actuator's params: an ActuatorParams, a "
                            "dict of its sections or the path of a TOML parameter file")
        object.__setattr__(self, "params", params.to_dict())
        try:
            tol = Tolerances.from_dict(dict(self.tolerances), source="--tolerances")
        except ValueError as exc:
            raise AssessmentError(str(exc)) from None
        object.__setattr__(self, "tolerances", tol.to_dict())
        for name, lo in (("units", 1), ("healthy", 1), ("healthy_datasheet", 0),
                         ("tune_healthy", 1)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < lo:
                raise AssessmentError(f"{name.replace('_', '-')} must be an integer >= {lo}, "
                                      f"got {v!r}")
        if self.units > 10_000:
            raise AssessmentError(f"units = {self.units} is beyond 10000; assess a sample")
        tune = self.units if self.tune_units is None else self.tune_units
        if isinstance(tune, bool) or not isinstance(tune, int) or tune < 0:
            raise AssessmentError(f"tune-units must be an integer >= 0, got {self.tune_units!r}")
        object.__setattr__(self, "tune_units", tune)
        if self.healthy_datasheet > self.healthy:
            raise AssessmentError(f"healthy-datasheet ({self.healthy_datasheet}) cannot exceed "
                                  f"healthy ({self.healthy}): it counts the healthy traces also "
                                  "diagnosed on the data sheet; give --healthy-datasheet "
                                  f"{self.healthy} or fewer")
        if not (isinstance(self.target_far, (int, float)) and 0.0 < self.target_far < 0.5):
            raise AssessmentError(f"target-far must be in (0, 0.5), got {self.target_far!r}")
        object.__setattr__(self, "target_far", float(self.target_far))
        try:
            object.__setattr__(self, "seed", check_seed(self.seed, "seed"))
        except ValueError as exc:
            raise AssessmentError(str(exc)) from None
        grids = grid_names() if self.grids is None else tuple(self.grids)
        for g in grids:
            _grid(g)
        if len(set(grids)) != len(grids):
            raise AssessmentError(f"a grid is named twice in {', '.join(grids)}")
        object.__setattr__(self, "grids", grids)
        sev = {}
        for name, values in dict(self.severities).items():
            m, g = _grid(name)
            vals = tuple(float(v) for v in values)
            if not vals:
                raise AssessmentError(f"the severities of {name} are empty")
            for v in vals:
                try:
                    m.inject(v, PHASES[0] if m.per_phase else None, **dict(g.inject))
                except ValueError as exc:
                    raise AssessmentError(f"severity {v:g} of {name}: {exc}") from None
            sev[name] = vals
        object.__setattr__(self, "severities", sev)
        from ..identify import make_solver

        try:
            make_solver(self.algorithm)
        except ValueError as exc:
            raise AssessmentError(str(exc)) from None

    # ------------------------------------------------------------------ views
    @property
    def tune(self) -> bool:
        """Whether the thresholds are tuned (else the parameters' own are kept)."""
        return bool(self.tune_units)

    def actuator(self) -> Any:
        from ..params import ActuatorParams

        return ActuatorParams.from_dict(dict(self.params), source="assessment")

    def tolerance_set(self) -> Any:
        from ..units import Tolerances

        return Tolerances.from_dict(dict(self.tolerances))

    def severities_of(self, grid: str) -> tuple[float, ...]:
        return self.severities.get(grid) or _grid(grid)[1].severities

    def cases(self, unit_index: int) -> list[Case]:
        return cases(self, unit_index)

    # ------------------------------------------------------------------ identity
    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        if not self.drive_signals:          # a spec from before it existed hashes as it did
            del d["drive_signals"]
        d["grids"] = list(self.grids or ())
        d["severities"] = {k: list(v) for k, v in self.severities.items()}
        return d

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "AssessmentSpec":
        d = dict(data)
        d["grids"] = tuple(d.get("grids") or ()) or None
        d["severities"] = {k: tuple(v) for k, v in (d.get("severities") or {}).items()}
        return cls(**d)

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), sort_keys=True, separators=(",", ":"))

    def hash(self) -> str:
        return hashlib.sha256(self.to_json().encode()).hexdigest()[:16]

    def differences(self, other: "AssessmentSpec") -> list[str]:
        a, b = self.to_dict(), other.to_dict()
        return [f"{k}: {_short(a.get(k))} here, {_short(b.get(k))} there"
                for k in sorted(set(a) | set(b)) if a.get(k) != b.get(k)]

    # ------------------------------------------------------------------ tasks
    def tasks(self, phase: str, thresholds: Mapping[str, float] | None = None) -> list["Task"]:
        """The tasks of ``phase`` (``"tune"`` or ``"assess"``): one production unit each."""
        root = np.random.SeedSequence([ASSESS, self.seed])
        tune_root, unit_root = root.spawn(2)
        if phase == "tune":
            branch, n = tune_root, self.tune_units
        elif phase == "assess":
            branch, n = unit_root, self.units
        else:
            raise ValueError(f"unknown phase {phase!r}")
        out = []
        for i, ss in enumerate(branch.spawn(n)):
            unit_seed, noise0 = (int(x) for x in ss.generate_state(2, dtype=np.uint32))
            out.append(Task(phase, i, unit_seed, noise0, self.to_json(),
                            tuple(sorted((thresholds or {}).items()))))
        if phase == "assess" and self.tune:
            tuned = {t.unit_seed for t in self.tasks("tune")}
            clash = tuned & {t.unit_seed for t in out}
            if clash:      # a 32-bit collision of two spawned branches: never seen, but checked
                raise AssessmentError(f"unit seeds {sorted(clash)} drawn for both tuning and "
                                      "reporting; choose another --seed")
        return out


def _short(v: Any) -> str:
    text = json.dumps(v, sort_keys=True)
    return text if len(text) <= 60 else text[:57] + "..."


def cases(spec: AssessmentSpec, unit_index: int) -> list[Case]:
    """The faults reported unit ``unit_index`` is diagnosed with: every severity of every
    grid of ``spec``; a per-phase mode on a phase that turns from unit to unit (and from
    grid to grid), a grid's variants (a short's fault resistance) turning from unit to
    unit, in the order of the registry."""
    out = []
    for gi, name in enumerate(spec.grids or ()):
        m, g = _grid(name)
        variant = dict(g.variants[unit_index % len(g.variants)]) if g.variants else {}
        kwargs = {**dict(g.inject), **variant}
        phase = PHASES[(unit_index + gi) % 3] if m.per_phase else None
        for s in spec.severities_of(name):
            out.append(Case(name, m.name, float(s), float(g.magnitude(s)), phase, kwargs,
                            ((m.name, phase),)))
    return out


@dataclass(frozen=True)
class Task:
    """One production unit's work: ``phase`` (``"tune"``: calibrate it and read its healthy
    traces; ``"assess"``: calibrate it and diagnose its healthy and faulty traces),
    its ``index`` in the phase, its ``unit_seed``, the first of its noise seeds
    (``noise0``; trace ``j`` uses ``noise0 + j``), the spec (JSON, so that a task is
    self-contained on a remote worker) and, for ``"assess"``, the thresholds to diagnose
    with."""

    phase: str
    index: int
    unit_seed: int
    noise0: int
    spec_json: str
    thresholds: tuple[tuple[str, float], ...] = ()

    @property
    def key(self) -> str:
        return f"{self.phase}/{self.index}"

    def spec(self) -> AssessmentSpec:
        return AssessmentSpec.from_dict(json.loads(self.spec_json))

    def with_thresholds(self, thresholds: Mapping[str, float]) -> "Task":
        return replace(self, thresholds=tuple(sorted(thresholds.items())))
