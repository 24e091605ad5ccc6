"""Campaign specification: what to run, and the list of runs with their seeds.

A :class:`CampaignSpec` names scenarios (named ones from :data:`emaphm.faults.SCENARIOS`
or custom fault vectors), algorithms with their settings, the number of runs, the sensor
noise, the budget and a master seed. :meth:`CampaignSpec.runs_list` expands it into
:class:`Run` objects, in the stable order (scenario, algorithm, run index), each carrying
everything a worker needs, seeds included.

Seeds
-----
All randomness flows from ``master_seed`` through :class:`numpy.random.SeedSequence`::

    root = SeedSequence(master_seed)
    noise_root, optim_root = root.spawn(2)
    noise  of scenario s, run r:               noise_root.spawn(S)[s].spawn(R)[r]
    optimizer of scenario s, algorithm a, run r: optim_root.spawn(S)[s].spawn(A)[a].spawn(R)[r]

(``S, A, R``: numbers of scenarios, algorithms and runs; a child's ``spawn_key`` is its
path, so ``SeedSequence(master_seed, spawn_key=(1, s, a, r))`` rebuilds it directly.)
Each sequence gives one 63-bit integer (``generate_state(1, uint64) >> 1``): the
``noise_seed`` of the measured trace and the ``seed`` of the optimizer. Both integers and
the spawn key are stored with every run, so one run can be replayed alone
(:func:`emaphm.campaign.replay`).

The noise seed does not depend on the algorithm: run ``r`` of a scenario gives every
algorithm the same measured trace (common random numbers), so the algorithms are compared
on the same data and the spread between them is not noise-trace luck. Adding runs keeps
the seeds of the existing ones (a child's key does not depend on how many siblings follow).

TOML
----
See ``docs/campaigns.md`` and ``docs/examples/paper.toml``::

    name = "paper"
    runs = 10
    master_seed = 2023
    scenarios = ["paper"]                 # a group, names, or {name = "x", k = [...]}
    algorithms = ["de", "pso", "gwo"]     # names, or {name = "pso", label = "pso-30", options = {...}}

    [options.pso]                         # settings of the algorithm labelled "pso"
    pop_size = 50
"""

from __future__ import annotations

import hashlib
import json
import math
import re
import tomllib
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from .._text import shown

__all__ = [
    "AlgorithmSpec",
    "CampaignSpec",
    "Run",
    "ScenarioSpec",
    "SpecError",
    "SCENARIO_GROUPS",
    "available_algorithms",
    "paper_spec",
]

#: Scenario groups usable wherever scenario names are: the paper's 11 (five fault modes at
#: two magnitudes plus the multiple-fault case) and the 10 single faults.
SCENARIO_GROUPS: dict[str, tuple[str, ...]] = {
    "paper": ("friction-low", "friction-high", "backlash-low", "backlash-high",
              "short-circuit-low", "short-circuit-high", "eccentricity-low",
              "eccentricity-high", "gain-low", "gain-high", "multiple"),
    "single-faults": ("friction-low", "friction-high", "backlash-low", "backlash-high",
                      "short-circuit-low", "short-circuit-high", "eccentricity-low",
                      "eccentricity-high", "gain-low", "gain-high"),
}

#: The paper's three algorithms, in its order.
PAPER_ALGORITHMS = ("de", "pso", "gwo")

_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.+-]*$")
_DEFAULT_NOISE = 0.02               # A rms, emaphm.simulate.DEFAULT_SENSORS
_DEFAULT_LSB = 40.0 / 4096          # A, a 12-bit ADC over +-20 A

#: Upper bounds of what a spec may ask for: sensor noise [A rms] (a servo drive's current
#: sensor has tens of mA; above 1 A a trace carries nothing a model can fit), runs per
#: scenario and algorithm, runs in all, a population (hours of CPU per run beyond these),
#: monitoring-model sub-steps.
MAX_NOISE = 1.0
MAX_RUNS = 10_000
MAX_TOTAL_RUNS = 1_000_000
MAX_POP_SIZE = 10_000
MAX_N_SUB = 64


class SpecError(ValueError):
    """A campaign specification is invalid; the message says what to fix."""


def available_algorithms() -> dict[str, type | None]:
    """Algorithms a spec may name: the default least-squares pipeline (``"lsq"``, which
    takes no options: ``None``), the paper's three and the baselines (their classes), and
    those registered in this process (:func:`emaphm.optim.register`: an optimizer class,
    or None for what takes no options)."""
    from emaphm.identify import DEFAULT_ALGORITHM
    from emaphm.optim import ALL_ALGORITHMS, registered, registered_kind

    own = {n: (obj if registered_kind(n) == "optimizer class" else None)
           for n, obj in registered().items()}
    return {DEFAULT_ALGORITHM: None, **ALL_ALGORITHMS, **own}


def _algorithm_name(algorithm: Any) -> str:
    """A name, or a registered object's name (a TypeError that says how to register it)."""
    from emaphm.identify import algorithm_name

    return algorithm_name(algorithm)


def _check_name(what: str, name: Any) -> str:
    if not isinstance(name, str) or not _NAME.match(name):
        raise SpecError(f"{what} name {shown(name)} must be letters, digits and _ . + - "
                        "(no spaces or slashes), starting with a letter or digit")
    return name


def _canonical(value: Any) -> Any:
    """JSON-ready and order-independent form of an option value."""
    if isinstance(value, Mapping):
        return {str(k): _canonical(value[k]) for k in sorted(value)}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_canonical(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


# ----------------------------------------------------------------------------- parts


@dataclass(frozen=True)
class ScenarioSpec:
    """One scenario: a name, its true fault vector and how the report groups it.

    ``mode`` and ``magnitude`` place the scenario in the paper's tables: the named
    scenarios ``<mode>-low`` / ``<mode>-high`` are a fault mode at k = 0.25 / 0.75
    (magnitude ``"low"`` / ``"high"``); ``multiple`` is the multiple-fault case.
    A custom scenario is its own mode with no magnitude unless given.
    """

    name: str
    k: tuple[float, ...]
    mode: str = ""
    magnitude: str = ""
    fault_model: str = "paper"

    @classmethod
    def named(cls, name: str) -> "ScenarioSpec":
        from emaphm.faults import SCENARIO_FAULT_MODELS, SCENARIOS

        if name not in SCENARIOS:
            groups = ", ".join(SCENARIO_GROUPS)
            raise SpecError(f"unknown scenario {shown(name)}; choose one of {', '.join(SCENARIOS)}, "
                            f"a group ({groups}) or a custom {{name = ..., k = [8 values]}}")
        mode, magnitude = name, ""
        m = re.fullmatch(r"(.+)-(low|high)", name)
        if m:
            mode, magnitude = m.group(1), m.group(2)
        return cls(name=name, k=tuple(float(x) for x in SCENARIOS[name]), mode=mode,
                   magnitude=magnitude, fault_model=SCENARIO_FAULT_MODELS[name])

    @classmethod
    def custom(cls, name: str, k: Any, mode: str | None = None, magnitude: str = "",
               fault_model: str = "physical") -> "ScenarioSpec":
        from emaphm.faults import FaultVectorError, as_k, check_fault_model

        _check_name("scenario", name)
        try:
            kk = as_k(k)
            check_fault_model(fault_model)
        except FaultVectorError as exc:
            raise SpecError(f"scenario {name!r}: {exc}") from None
        return cls(name=name, k=tuple(float(x) for x in kk), mode=str(mode or name),
                   magnitude=str(magnitude or ""), fault_model=fault_model)

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "k": list(self.k), "mode": self.mode, "magnitude": self.magnitude,
                "fault_model": self.fault_model}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "ScenarioSpec":
        """The scenario :meth:`to_dict` wrote (validated as a custom one; a table without
        ``fault_model`` is "physical", as in a spec file)."""
        return parse_scenarios([dict(data)])[0]


@dataclass(frozen=True)
class AlgorithmSpec:
    """One algorithm of a campaign: registry ``name``, a unique ``label``, its settings.

    ``options`` go to the optimizer's constructor (e.g. ``{"pop_size": 30}``);
    ``budget`` overrides the campaign's (``None``: inherit; ``"default"``: the
    algorithm's own stopping rule). The same algorithm may appear twice under two
    labels with different settings.
    """

    name: str
    label: str = ""
    options: dict = field(default_factory=dict, hash=False)
    budget: Any = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "label", self.label or self.name)

    def to_dict(self) -> dict[str, Any]:
        d = {"name": self.name, "label": self.label, "options": _canonical(self.options)}
        if self.budget is not None:
            d["budget"] = self.budget
        return d

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "AlgorithmSpec":
        """The algorithm :meth:`to_dict` wrote (its name and options are checked by the
        :class:`CampaignSpec` that holds it)."""
        return parse_algorithms([dict(data)])[0]


@dataclass(frozen=True)
class Run:
    """One run of a campaign: everything a worker needs, and nothing else.

    ``key`` is ``"<scenario>/<algorithm label>/<run index>"``, unique in a campaign.
    ``seed`` seeds the optimizer, ``noise_seed`` the sensor noise of the measured trace;
    ``spawn_key`` is the optimizer seed's path in the master SeedSequence. ``config`` holds
    the identification's problem and solver settings
    (:class:`emaphm.identify.IdentificationConfig`); ``fault_model`` is the scenario's,
    with which the trace is simulated (and identified).
    """

    key: str
    index: int
    scenario: str
    k_true: tuple[float, ...]
    algorithm: str              # label
    config: Any = field(hash=False)     # emaphm.identify.IdentificationConfig
    run: int
    master_seed: int
    spawn_key: tuple[int, ...]
    seed: int
    noise_seed: int
    noise: float
    adc_lsb: float
    params: dict | None = field(default=None, hash=False)
    fault_model: str = "paper"

    @property
    def optimizer(self) -> str:
        """The registry name of the run's algorithm (``config.algorithm``)."""
        return self.config.algorithm


# ----------------------------------------------------------------------------- spec


def _seed_int(ss: np.random.SeedSequence) -> int:
    return int(ss.generate_state(1, np.uint64)[0] >> np.uint64(1))


def _budget_value(owner: str, budget: Any) -> Any:
    """Validate a budget and return its canonical form (None, "default", int or str)."""
    from emaphm.identify import parse_budget

    if budget is None or budget == "default":
        return budget
    if isinstance(budget, float) and budget.is_integer():
        budget = int(budget)
    if isinstance(budget, str) and budget.strip().isdigit():
        budget = int(budget.strip())
    try:
        parse_budget(budget)
    except ValueError as exc:
        raise SpecError(f"{owner}: {exc}") from None
    if not isinstance(budget, (int, str)):
        raise SpecError(f"{owner}: budget must be evaluations (int), seconds ('30s') or 'default', "
                        f"got {budget!r}")
    return budget


@dataclass(frozen=True)
class CampaignSpec:
    """What a campaign runs. Build it directly, with :func:`paper_spec`,
    :meth:`from_toml` or :meth:`from_dict`; it validates itself on construction.

    ============  ==================  ===============  ===========================================
    Field         Type                Default          Meaning
    ============  ==================  ===============  ===========================================
    scenarios     ScenarioSpec...     the paper's 11   scenarios (names, groups or custom k)
    algorithms    AlgorithmSpec...    de, pso, gwo     algorithms with their settings
    runs          int 1..10000        10               runs of each algorithm on each scenario
    master_seed   int >= 0            0                root of every seed (see module docs)
    noise         float 0..1          0.02             current sensor noise, A rms
    adc_lsb       float >= 0          40/4096          current quantisation step, A (0: none)
    budget        int, str, None      None             per run: evaluations, "30s" (wall clock,
                                                       not reproducible), None/"default": each
                                                       algorithm's own stopping rule
    polish        bool                True             compass-search polish (identify's default);
                                                       False: the bare algorithms, as the paper
    search        str                 "auto"           search space (emaphm.search); "auto":
                                                       the fault model's default
    n_sub         int >= 1            1                monitoring-model sub-steps
    fitness_mode  str                 "phases"         Eq. 4 on the three phases or "equivalent"
    params        ActuatorParams,     None             healthy actuator (an ActuatorParams, its
                  dict, path or None                   to_dict or a TOML path; held as the
                                                       dict); None: the default preset
    fault_model   str or None         None             mapping of k3..k5 for every scenario
                                                       ("paper" or "physical"); None: each
                                                       scenario's own (a named scenario's, or
                                                       a custom one's ``fault_model``, default
                                                       "physical"); stores written before fault
                                                       models existed read as "paper"
    name          str                 "campaign"       a label (not part of the identity)
    ============  ==================  ===============  ===========================================
    """

    scenarios: tuple[ScenarioSpec, ...] = ()
    algorithms: tuple[AlgorithmSpec, ...] = ()
    runs: int = 10
    master_seed: int = 0
    noise: float = _DEFAULT_NOISE
    adc_lsb: float = _DEFAULT_LSB
    budget: Any = None
    polish: bool = True
    search: str = "auto"
    n_sub: int = 1
    fitness_mode: str = "phases"
    params: dict | None = field(default=None, hash=False)
    fault_model: str | None = None
    name: str = "campaign"

    def __post_init__(self) -> None:
        from emaphm.fitness import FITNESS_MODES
        from emaphm.search import SEARCH_SPACES

        scen = tuple(self.scenarios) or tuple(ScenarioSpec.named(n) for n in SCENARIO_GROUPS["paper"])
        scen = tuple(ScenarioSpec.named(s) if isinstance(s, str) else s for s in scen)
        for s in scen:
            if not isinstance(s, ScenarioSpec):
                raise SpecError(f"scenarios must be names or ScenarioSpec, got {s!r}")
            ScenarioSpec.custom(s.name, s.k, fault_model=s.fault_model)  # validates name, k
        if self.fault_model is not None:
            from emaphm.faults import FAULT_MODELS

            if self.fault_model not in FAULT_MODELS:
                raise SpecError(f"unknown fault_model {self.fault_model!r}; choose one of "
                                f"{', '.join(FAULT_MODELS)}")
            scen = tuple(replace(s, fault_model=self.fault_model) for s in scen)
        _no_duplicates("scenario", [s.name for s in scen])
        object.__setattr__(self, "scenarios", scen)

        algos = tuple(self.algorithms) or tuple(AlgorithmSpec(n) for n in PAPER_ALGORITHMS)
        algos = tuple(a if isinstance(a, AlgorithmSpec) else AlgorithmSpec(_algorithm_name(a))
                      for a in algos)
        registry = available_algorithms()
        checked = []
        for a in algos:
            if not isinstance(a, AlgorithmSpec):
                raise SpecError(f"algorithms must be names or AlgorithmSpec, got {a!r}")
            if a.name not in registry:
                raise SpecError(f"unknown algorithm {a.name!r}; choose one of "
                                f"{', '.join(sorted(registry))} (or register your own in this "
                                "process: emaphm.optim.register(name, obj))")
            _check_name("algorithm label", a.label)
            if not isinstance(a.options, Mapping):
                raise SpecError(f"algorithm {a.label!r}: options must be a table, got {a.options!r}")
            pop = a.options.get("pop_size")
            if isinstance(pop, (int, float, np.integer, np.floating)) and not isinstance(pop, bool) \
                    and pop > MAX_POP_SIZE:
                raise SpecError(f"algorithm {a.label!r}: pop_size {pop:g} is above {MAX_POP_SIZE}; "
                                "each iteration would run that many models (the defaults are "
                                "10-50)")
            try:
                if registry[a.name] is None:
                    if a.options:
                        raise SpecError(f"algorithm {a.label!r}: {a.name} takes no options, got "
                                        f"{dict(a.options)}")
                else:
                    registry[a.name](**dict(a.options))
            except TypeError as exc:
                raise SpecError(f"algorithm {a.label!r}: bad option ({exc}); see the docstring of "
                                f"{registry[a.name].__name__} for its settings") from None
            except ValueError as exc:
                raise SpecError(f"algorithm {a.label!r}: {exc}") from None
            checked.append(AlgorithmSpec(a.name, a.label, dict(_canonical(dict(a.options))),
                                         _budget_value(f"algorithm {a.label!r}", a.budget)))
        _no_duplicates("algorithm label", [a.label for a in checked])
        object.__setattr__(self, "algorithms", tuple(checked))

        object.__setattr__(self, "runs", _int("runs", self.runs, 1, MAX_RUNS))
        object.__setattr__(self, "master_seed", _int("master_seed", self.master_seed, 0))
        object.__setattr__(self, "n_sub", _int("n_sub", self.n_sub, 1, MAX_N_SUB))
        object.__setattr__(self, "noise", _real("noise", self.noise, MAX_NOISE, "A rms"))
        total = len(self.scenarios) * len(self.algorithms) * self.runs
        if total > MAX_TOTAL_RUNS:
            raise SpecError(f"{total} runs in all ({len(self.scenarios)} scenarios x "
                            f"{len(self.algorithms)} algorithms x {self.runs}) is above "
                            f"{MAX_TOTAL_RUNS}; split the campaign")
        object.__setattr__(self, "adc_lsb", _real("adc_lsb", self.adc_lsb))
        object.__setattr__(self, "budget", _budget_value("budget", self.budget))
        if not isinstance(self.polish, bool):
            raise SpecError(f"polish must be true or false, got {self.polish!r}")
        if self.search not in SEARCH_SPACES + ("auto",):
            raise SpecError(f"unknown search space {self.search!r}; choose auto or one of "
                            f"{', '.join(SEARCH_SPACES)}")
        if self.fitness_mode not in FITNESS_MODES:
            raise SpecError(f"unknown fitness_mode {self.fitness_mode!r}; choose one of "
                            f"{', '.join(FITNESS_MODES)}")
        if self.params is not None:
            from emaphm.params import ParameterError, as_params

            try:
                p = as_params(self.params, what="spec params")
            except ParameterError as exc:
                raise SpecError(str(exc)) from None
            object.__setattr__(self, "params", _canonical(p.to_dict()))
        if not isinstance(self.name, str) or not self.name:
            raise SpecError(f"name must be a non-empty string, got {self.name!r}")

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_dict(cls, data: Mapping[str, Any], *, base_dir: str | Path | None = None,
                  source: str = "spec", stored: bool = False) -> "CampaignSpec":
        """Build from the TOML schema (see the module docstring); ``params`` may be a
        TOML file name, relative to ``base_dir``, or an inline table. ``stored``: the
        spec of a store (a custom scenario without ``fault_model`` is then "paper")."""
        try:
            return cls._from_dict(dict(data), base_dir, stored)
        except SpecError as exc:
            raise SpecError(f"{source}: {exc}") from None

    @classmethod
    def _from_dict(cls, data: dict[str, Any], base_dir: str | Path | None,
                   stored: bool = False) -> "CampaignSpec":
        known = {f.name for f in fields(cls)} | {"options"}
        unknown = sorted(set(data) - known)
        if unknown:
            raise SpecError(f"unknown key(s) {', '.join(unknown)}; known keys: {', '.join(sorted(known))}")
        kw: dict[str, Any] = {k: v for k, v in data.items()
                              if k not in ("scenarios", "algorithms", "options", "params")}
        if "scenarios" in data:
            # a stored spec written before fault models existed: its scenarios are the paper's
            kw["scenarios"] = parse_scenarios(data["scenarios"],
                                              default_fault_model="paper" if stored else "physical")
        options = data.get("options", {})
        if not isinstance(options, Mapping):
            raise SpecError("[options] must be a table of tables, one per algorithm label")
        if "algorithms" in data:
            kw["algorithms"] = parse_algorithms(data["algorithms"], options)
        elif options:
            kw["algorithms"] = parse_algorithms(list(PAPER_ALGORITHMS), options)
        params = data.get("params")
        if isinstance(params, str):
            from emaphm.params import ParameterError, load_params

            path = Path(params)
            if base_dir is not None and not path.is_absolute():
                path = Path(base_dir) / path
            if not path.exists() and not path.is_symlink():    # a link loop: said below
                raise SpecError(f"params file {path} does not exist")
            try:
                kw["params"] = load_params(path, partial=True).to_dict()
            except ParameterError as exc:
                raise SpecError(str(exc)) from None
        elif params is not None:
            kw["params"] = params
        return cls(**kw)

    @classmethod
    def from_toml(cls, path: str | Path) -> "CampaignSpec":
        """Read a spec file (TOML)."""
        from emaphm._files import regular_file

        p = regular_file(path, "spec file", give="a TOML file", error=SpecError)
        try:
            data = tomllib.loads(p.read_text(encoding="utf-8"))
        except tomllib.TOMLDecodeError as exc:
            raise SpecError(f"{p}: not valid TOML ({exc})") from None
        return cls.from_dict(data, base_dir=p.parent, source=str(p))

    def to_dict(self) -> dict[str, Any]:
        """Plain, JSON-ready form; :meth:`from_dict` of it gives an equal spec."""
        d = {
            "name": self.name,
            "scenarios": [s.to_dict() for s in self.scenarios],
            "algorithms": [a.to_dict() for a in self.algorithms],
            "runs": self.runs,
            "master_seed": self.master_seed,
            "noise": self.noise,
            "adc_lsb": self.adc_lsb,
            "budget": self.budget,
            "polish": self.polish,
            "search": self.search,
            "n_sub": self.n_sub,
            "fitness_mode": self.fitness_mode,
            "params": self.params,
        }
        if self.fault_model is not None:
            d["fault_model"] = self.fault_model
        return d

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), sort_keys=True)

    @classmethod
    def from_json(cls, text: str) -> "CampaignSpec":
        return cls.from_dict(json.loads(text), source="stored spec", stored=True)

    # ------------------------------------------------------------------ identity
    def identity(self) -> dict[str, Any]:
        """Everything that decides the results (all but ``name``)."""
        d = self.to_dict()
        d.pop("name")
        return d

    @property
    def hash(self) -> str:
        """SHA-256 of the canonical JSON of :meth:`identity`."""
        text = json.dumps(self.identity(), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()

    def differences(self, other: "CampaignSpec") -> list[str]:
        """Human-readable differences in identity, ``self`` first (empty if none)."""
        a, b = self.identity(), other.identity()
        out = []
        for key in a:
            if a[key] == b[key]:
                continue
            if key == "scenarios":
                out.append(_list_diff("scenarios", [s["name"] for s in a[key]],
                                      [s["name"] for s in b[key]], a[key], b[key]))
            elif key == "algorithms":
                out.append(_list_diff("algorithms", [x["label"] for x in a[key]],
                                      [x["label"] for x in b[key]], a[key], b[key]))
            elif key == "params":
                out.append("params: the actuator parameters differ")
            else:
                out.append(f"{key}: {a[key]!r} -> {b[key]!r}")
        return out

    # ------------------------------------------------------------------ runs
    @property
    def n_runs(self) -> int:
        return len(self.scenarios) * len(self.algorithms) * self.runs

    def runs_list(self) -> list[Run]:
        """Every run, in the order (scenario, algorithm, run index), seeds attached."""
        from emaphm.identify import IdentificationConfig

        S, A, R = len(self.scenarios), len(self.algorithms), self.runs
        noise_root, optim_root = np.random.SeedSequence(self.master_seed).spawn(2)
        noise_seqs = [s.spawn(R) for s in noise_root.spawn(S)]
        optim_seqs = [[a.spawn(R) for a in s.spawn(A)] for s in optim_root.spawn(S)]
        out: list[Run] = []
        for i, sc in enumerate(self.scenarios):
            for j, al in enumerate(self.algorithms):
                budget = al.budget if al.budget is not None else self.budget
                config = IdentificationConfig(
                    algorithm=al.name, options=dict(al.options),
                    budget=None if budget == "default" else budget, polish=self.polish,
                    search=None if self.search == "auto" else self.search, n_sub=self.n_sub,
                    mode=self.fitness_mode, fault_model=sc.fault_model)
                for r in range(R):
                    ss = optim_seqs[i][j][r]
                    out.append(Run(
                        key=f"{sc.name}/{al.label}/{r}", index=len(out), scenario=sc.name,
                        k_true=sc.k, algorithm=al.label, config=config, run=r,
                        master_seed=self.master_seed, spawn_key=tuple(int(x) for x in ss.spawn_key),
                        seed=_seed_int(ss), noise_seed=_seed_int(noise_seqs[i][r]),
                        noise=self.noise, adc_lsb=self.adc_lsb, params=self.params,
                        fault_model=sc.fault_model))
        return out

    def run(self, key: str) -> Run:
        """The run with ``key`` (``"<scenario>/<algorithm>/<index>"``)."""
        for r in self.runs_list():
            if r.key == key:
                return r
        raise SpecError(f"no run {shown(key)} in this campaign; keys look like "
                        f"{self.scenarios[0].name}/{self.algorithms[0].label}/0")


# ----------------------------------------------------------------------------- helpers


def paper_spec(runs: int = 10, master_seed: int = 2023, **kw: Any) -> CampaignSpec:
    """The paper's comparison: DE, PSO, GWO x the 11 scenarios x ``runs``, default
    settings, realistic sensor noise (:data:`emaphm.simulate.DEFAULT_SENSORS`).
    Other :class:`CampaignSpec` fields (``scenarios`` too) may be given in ``kw``."""
    kw.setdefault("scenarios", tuple(ScenarioSpec.named(n) for n in SCENARIO_GROUPS["paper"]))
    kw.setdefault("algorithms", tuple(AlgorithmSpec(n) for n in PAPER_ALGORITHMS))
    kw.setdefault("name", "paper")
    return CampaignSpec(runs=runs, master_seed=master_seed, **kw)


def parse_scenarios(items: Any, default_fault_model: str = "physical") -> tuple[ScenarioSpec, ...]:
    """Scenarios from names, groups, comma-separated strings or ``{name, k}`` tables
    (a table without ``fault_model`` gets ``default_fault_model``)."""
    if isinstance(items, str):
        items = [x for x in (p.strip() for p in items.split(",")) if x]
    if not isinstance(items, (list, tuple)) or not items:
        raise SpecError("scenarios must be a non-empty list of names, groups or {name, k} tables")
    out: list[ScenarioSpec] = []
    for item in items:
        if isinstance(item, ScenarioSpec):
            out.append(item)
        elif isinstance(item, str):
            if item in SCENARIO_GROUPS:
                out.extend(ScenarioSpec.named(n) for n in SCENARIO_GROUPS[item])
            else:
                out.append(ScenarioSpec.named(item))
        elif isinstance(item, Mapping):
            extra = set(item) - {"name", "k", "mode", "magnitude", "fault_model"}
            if extra or "name" not in item or "k" not in item:
                raise SpecError(f"a custom scenario is a table {{name = ..., k = [8 values]}} "
                                f"(optionally mode, magnitude, fault_model), got {dict(item)!r}")
            out.append(ScenarioSpec.custom(item["name"], item["k"], item.get("mode"),
                                           item.get("magnitude", ""),
                                           item.get("fault_model", default_fault_model)))
        else:
            raise SpecError(f"a scenario is a name or a {{name, k}} table, got {item!r}")
    return tuple(out)


def parse_algorithms(items: Any, options: Mapping[str, Any] | None = None) -> tuple[AlgorithmSpec, ...]:
    """Algorithms from names, comma-separated strings or ``{name, label, options, budget}``
    tables; ``options`` maps labels to settings for the plain names."""
    options = dict(options or {})
    if isinstance(items, str):
        items = [x for x in (p.strip() for p in items.split(",")) if x]
    if not isinstance(items, (list, tuple)) or not items:
        raise SpecError("algorithms must be a non-empty list of names or {name, ...} tables")
    out: list[AlgorithmSpec] = []
    for item in items:
        if isinstance(item, AlgorithmSpec):
            out.append(item)
        elif isinstance(item, str):
            opts = options.pop(item, {})
            if not isinstance(opts, Mapping):
                raise SpecError(f"[options.{item}] must be a table of settings, got {opts!r}")
            out.append(AlgorithmSpec(item, item, dict(opts)))
        elif isinstance(item, Mapping):
            extra = set(item) - {"name", "label", "options", "budget"}
            if extra or "name" not in item:
                raise SpecError(f"an algorithm table has name and optionally label, options, "
                                f"budget; got {dict(item)!r}")
            label = item.get("label") or item["name"]
            own, extra_opts = item.get("options", {}), options.pop(label, {})
            for where, o in ((f"the options of algorithm {label!r}", own),
                             (f"[options.{label}]", extra_opts)):
                if not isinstance(o, Mapping):
                    raise SpecError(f"{where} must be a table of settings, e.g. "
                                    f"{{pop_size = 30}}, got {o!r}")
            opts = dict(own)
            opts.update(extra_opts)
            out.append(AlgorithmSpec(item["name"], label, opts, item.get("budget")))
        else:
            raise SpecError(f"an algorithm is a name or a {{name, ...}} table, got {item!r}")
    if options:
        raise SpecError(f"[options] for {', '.join(sorted(options))}, which is not among the "
                        f"algorithms ({', '.join(a.label for a in out)})")
    return tuple(out)


def _no_duplicates(what: str, names: Sequence[str]) -> None:
    seen: set[str] = set()
    for n in names:
        if n in seen:
            raise SpecError(f"{what} {n!r} appears twice; give each one once"
                            + (" (use a label to run an algorithm twice with other settings)"
                               if what.startswith("algorithm") else ""))
        seen.add(n)


def _int(name: str, value: Any, minimum: int, maximum: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum \
            or (maximum is not None and value > maximum):
        bounds = f">= {minimum}" if maximum is None else f"from {minimum} to {maximum}"
        raise SpecError(f"{name} must be an integer {bounds}, got {shown(value)}")
    return int(value)


def _real(name: str, value: Any, maximum: float | None = None, unit: str = "") -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)) \
            or not math.isfinite(float(value)) or value < 0 \
            or (maximum is not None and value > maximum):
        bounds = ">= 0" if maximum is None else f"from 0 to {maximum:g}"
        unit = f" {unit}" if unit else ""
        raise SpecError(f"{name} must be a finite number {bounds}{unit}, got {shown(value)}")
    return float(value)


def _list_diff(what: str, a: list[str], b: list[str], da: list, db: list) -> str:
    gone = [x for x in a if x not in b]
    new = [x for x in b if x not in a]
    parts = []
    if gone:
        parts.append(f"removed {', '.join(gone)}")
    if new:
        parts.append(f"added {', '.join(new)}")
    if not parts:
        if a != b:
            parts.append(f"order changed ({', '.join(a)} -> {', '.join(b)})")
        else:
            changed = [n for n, x, y in zip(a, da, db) if x != y]
            parts.append(f"settings of {', '.join(changed)} changed")
    return f"{what}: {'; '.join(parts)}"
