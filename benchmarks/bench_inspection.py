"""When to look next (issue 24): is the planned risk a calibrated probability, and what does
planning by risk save against fixed inspection intervals?

Simulated actuators, each new at t = 0 with one fault growing along its own law
(:class:`emaphm.prognosis.DegradationScenario`, as ``emaphm fleet demo`` deals them: dry
friction wearing linearly or as t^2, backlash, eccentricity, a drifting gain, an inter-turn
short growing exponentially on phase A or B), a life of 800-2500 h (the fault reaches its
failure threshold then) and, for the laws other than the exponential, an onset at 0-30 % of
the life. Every inspection is **synthetic**: the true k plus Gaussian noise of an
identification's size (0.007 per component, as ``fleet demo --synthetic`` records; the
trend's model discrepancy is left out, ``discrepancy={}``, since the synthetic k carries
none), so that hundreds of actuators run in minutes; the plant-trace diagnoses are not run
here (each would be an identification: docs/inspection-planning.md says what that leaves
open).

* **Calibration** (``--calibration-paths`` per law, default 200: linear, accelerating t^2,
  exponential): inspected every L/9 to L/5 until the end of life; at every inspection from
  the 3rd on where an indicator takes part (:func:`emaphm.prognosis.inspection.taking_part`),
  the time ``t*_q`` at which the chance of a crossing reaches ``q`` (no cap, no rule), for
  q from 0.001 to 0.5; realised: the share of decisions whose true crossing came at or
  before ``t*_q``. The acceptance sample takes one decision per actuator (drawn from its
  seed), so the decisions are independent and the binomial margin holds.
* **Policy** (``--paths``, default 200, seeds 0-199): each actuator inspected until it is
  flagged (``act now``) or its fault crosses the threshold before the next planned
  inspection (a *miss*), by the risk policy (the defaults of
  :data:`emaphm.prognosis.inspection.INTERVAL_DEFAULTS`) at risks 0.001 to 0.05,
  and by fixed intervals: every D hours, flagged by the same criterion (a crossing before
  the next fixed inspection more likely than the risk), and, without a prognosis, flagged
  when an identified indicator reaches a share of its threshold (the alarm baseline).
  The *best fixed interval* is the longest D with no miss on these paths, chosen with
  hindsight (which favours it). Also ``--healthy`` actuators (default 50) over 2500 h:
  how many are flagged without a fault.
* ``--tune``: the interval defaults on tuning seeds 1000-1039 (disjoint from the reported
  0-199 and the calibration's 10000+): the fewest inspections per 1000 operating hours
  with no miss and a median life used of at least 0.8, at risk 0.01.

Run: ``python benchmarks/bench_inspection.py [--workers 2]`` -> ``benchmarks/results/
inspection.md``, ``inspection.json``, ``docs/figures/inspection/*.png`` (drawn from the
JSON); ``--tune`` -> ``benchmarks/results/inspection_tuning.json``.
"""

from __future__ import annotations

import os

for _v in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import datetime as _dt  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from concurrent.futures import ProcessPoolExecutor  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from emaphm.prognosis.inspection import MIN_FLAG_INSPECTIONS  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
FIGURES = ROOT / "docs" / "figures" / "inspection"
sys.path.insert(0, str(Path(__file__).resolve().parent))

NOISE = 0.007
QS = (0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.3, 0.5)
RISKS = (0.001, 0.002, 0.005, 0.01, 0.05)
FIXED = (100.0, 150.0, 175.0, 200.0, 225.0, 250.0, 300.0)
FIXED_RISK = 0.01
ALARM_SHARES = (0.5, 0.7)
ALARM_FIXED = (50.0, 75.0, 100.0, 150.0, 200.0)
TUNE_SEEDS = range(1000, 1040)
TUNE_GRID = ((200.0, 150.0, 400.0), (200.0, 200.0, 400.0), (250.0, 150.0, 500.0),
             (250.0, 200.0, 500.0), (300.0, 150.0, 600.0), (300.0, 200.0, 600.0),
             (250.0, 150.0, 800.0), (200.0, 150.0, 600.0), (300.0, 100.0, 600.0),
             (200.0, 50.0, 400.0))
LAWS = {"linear": (("friction", 1), ("backlash", 1), ("eccentricity", 1), ("gain_drift", -1)),
        "power": (("friction", 1),), "exponential": (("short_circuit_a", 1), ("short_circuit_b", 1))}


# ----------------------------------------------------------------------------- the actuators
def fleet_path(seed: int):
    """One simulated actuator of the policy benchmark (module docstring), from ``seed``:
    a fault kind of the demo fleet, a life of 800-2500 h, an onset at 0-30 % of it."""
    from emaphm.fleet.demo import FAULT_KINDS
    from emaphm.prognosis.simulator import DegradationLaw, DegradationScenario
    from emaphm.prognosis.thresholds import DEFAULT_FAILURE_THRESHOLDS as thr

    kinds = [k for k in FAULT_KINDS if k is not None]
    rng = np.random.default_rng(seed)
    indicator, law, direction, _ = kinds[rng.integers(len(kinds))]
    life = rng.uniform(800.0, 2500.0)
    onset = 0.0 if law == "exponential" else rng.uniform(0.0, 0.3) * life
    return DegradationScenario(indicator, DegradationLaw.reaching(
        law, thr.for_indicator(indicator), life, onset=onset), direction=direction,
        name=f"{indicator}-{law}")


def calibration_path(law: str, i: int):
    """Actuator ``i`` of the calibration set of ``law``; its inspection interval."""
    from emaphm.prognosis.simulator import DegradationLaw, DegradationScenario
    from emaphm.prognosis.thresholds import DEFAULT_FAILURE_THRESHOLDS as thr

    rng = np.random.default_rng([10_000 + list(LAWS).index(law), i])
    indicator, direction = LAWS[law][i % len(LAWS[law])]
    life = rng.uniform(800.0, 2500.0)
    onset = 0.0 if law == "exponential" else rng.uniform(0.0, 0.3) * life
    sc = DegradationScenario(indicator, DegradationLaw.reaching(
        law, thr.for_indicator(indicator), life, onset=onset), direction=direction,
        name=f"{indicator}-{law}")
    return sc, rng.uniform(life / 9.0, life / 5.0), int(rng.integers(2 ** 31))


# ----------------------------------------------------------------------------- calibration
def _quantile_times(preds, qs) -> list[float]:
    from emaphm.prognosis.inspection import risk_time

    return [risk_time(preds, q) for q in qs]


def calibration_task(task: tuple[str, int]) -> dict:
    """Every decision of one calibration actuator: (share of life, t*_q for each q)."""
    from emaphm.prognosis.inspection import n_samples_for, taking_part
    from emaphm.prognosis.simulator import synthetic_k_history
    from emaphm.prognosis.trends import prognose

    law, i = task
    sc, dt, noise_seed = calibration_path(law, i)
    t0 = time.process_time()
    times = np.arange(0.0, sc.eol, dt)
    K = synthetic_k_history(sc, times, seed=noise_seed, noise=NOISE)
    decisions = []
    for n in range(3, times.size + 1):
        prog = prognose(times[:n], K[:n], seed=1000 * i + n, discrepancy={},
                        n_samples=n_samples_for(min(QS)))
        part = taking_part(prog)
        if not part:
            continue
        t_q = _quantile_times([prog.predictions[k] for k in part], QS)
        decisions.append({"n": n, "t": float(times[n - 1]), "life": float(times[n - 1] / sc.eol),
                          "crossed": [bool(sc.eol <= t) for t in t_q]})
    pick = int(np.random.default_rng([20_000, i]).integers(len(decisions))) if decisions else None
    return {"law": law, "i": i, "name": sc.name, "eol": sc.eol, "interval": dt,
            "decisions": decisions, "pick": pick, "cpu_s": time.process_time() - t0}


def calibration_stats(runs: list[dict]) -> dict:
    def rate(rows: list[list[bool]]) -> list[float | None]:
        a = np.array(rows, dtype=float)
        return a.mean(axis=0).tolist() if a.size else [None] * len(QS)

    out = {"qs": list(QS), "laws": {}}
    groups = {law: [r for r in runs if r["law"] == law] for law in LAWS}
    groups["all"] = runs
    for name, rs in groups.items():
        every = [d["crossed"] for r in rs for d in r["decisions"]]
        one = [r["decisions"][r["pick"]]["crossed"] for r in rs if r["pick"] is not None]
        by_stage = {}
        for lo, hi in ((0.0, 0.5), (0.5, 0.75), (0.75, 1.0)):
            rows = [d["crossed"] for r in rs for d in r["decisions"] if lo <= d["life"] < hi]
            by_stage[f"{lo:g}-{hi:g}"] = {"n": len(rows), "realised": rate(rows)}
        out["laws"][name] = {"paths": len(rs), "decisions": len(every), "realised_all": rate(every),
                             "independent": len(one), "realised_one_per_path": rate(one),
                             "by_stage": by_stage}
    n = out["laws"]["all"]["independent"]
    out["acceptance"] = {}
    for q in (0.05, 0.01):
        j = QS.index(q)
        margin = 1.96 * math.sqrt(q * (1 - q) / n)
        realised = out["laws"]["all"]["realised_one_per_path"][j]
        out["acceptance"][str(q)] = {"realised": realised, "margin": margin, "n": n,
                                     "passed": bool(realised <= q + margin)}
    return out


# ----------------------------------------------------------------------------- policies
def policy_task(task: tuple) -> dict:
    """One actuator under one policy: ``("risk", seed, risk, (default, min, max))``,
    ``("fixed", seed, risk, D)``, ``("alarm", seed, share, D)`` or the same with a
    negative seed for a healthy actuator over 2500 h."""
    from emaphm.prognosis.inspection import InspectionPolicy, simulate_policy

    kind, seed, x, spec = task
    sc = fleet_path(seed) if seed >= 0 else None
    horizon = 2500.0 if sc is None else None
    t0 = time.process_time()
    if kind == "alarm":
        run = _alarm(sc, abs(seed), x, spec, horizon)
    else:
        if kind == "risk":
            policy = InspectionPolicy(risk=x, default_interval=spec[0], min_interval=spec[1],
                                      max_interval=spec[2]) if spec else InspectionPolicy(risk=x)
            run = simulate_policy(sc, policy, seed=abs(seed), horizon=horizon, discrepancy={})
        else:
            run = simulate_policy(sc, InspectionPolicy(risk=x), seed=abs(seed),
                                  fixed_interval=spec, horizon=horizon, discrepancy={})
        run = {"n": run.n_inspections, "missed": run.missed, "flagged_at": run.flagged_at,
               "last": float(run.times[-1]), "rules": list(run.rules),
               "risks": list(run.risks), "expected_misses": run.expected_misses}
    return {"kind": kind, "seed": seed, "x": x, "spec": spec,
            "eol": None if sc is None else sc.eol, "name": "healthy" if sc is None else sc.name,
            **run, "cpu_s": time.process_time() - t0}


def _alarm(sc, seed: int, share: float, interval: float, horizon: float | None) -> dict:
    """A fixed interval without a prognosis: flagged when an identified indicator reaches
    ``share`` of its failure threshold. The noise is drawn as simulate_policy draws it."""
    from emaphm.prognosis.inspection import observe
    from emaphm.prognosis.thresholds import (DEFAULT_FAILURE_THRESHOLDS, INDICATORS,
                                             indicator_values)

    eol = math.inf if sc is None else sc.eol
    end = eol if horizon is None else horizon
    noise_ss, _ = np.random.SeedSequence(seed).spawn(2)
    noise_seed = int(noise_ss.generate_state(1)[0])
    n = int(math.floor(min(end, eol) / interval - 1e-9)) + 1
    times = np.arange(n) * interval
    times = times[times < eol]
    K = observe(sc, times, seed=noise_seed, noise=NOISE)
    for j, k in enumerate(K):
        now = indicator_values(k)
        if any(now[i] >= share * DEFAULT_FAILURE_THRESHOLDS.for_indicator(i) for i in INDICATORS):
            return {"n": j + 1, "missed": False, "flagged_at": float(times[j]),
                    "last": float(times[j]), "rules": []}
    nxt = times[-1] + interval
    return {"n": int(times.size), "missed": bool(nxt >= eol), "flagged_at": None,
            "last": float(times[-1]), "rules": []}


class _Identified:
    """The k history of a simulated actuator inspected on the reference plant: at each new
    inspection time a plant trace (switching PWM, sensor noise; the noise seed drawn from the
    inspection's index) diagnosed by :func:`emaphm.prognosis.inspect` as ``emaphm history
    add`` does (data-sheet parameters, no commissioning), recorded in ``store``."""

    def __init__(self, scenario, seed: int, store, params=None) -> None:
        self.scenario, self.seed, self.store, self.n = scenario, seed, store, 0
        self.params = params

    def __call__(self, times: np.ndarray) -> np.ndarray:
        from emaphm.prognosis import inspect, simulate_degradation

        for t in times[self.n:]:
            noise = int(np.random.SeedSequence([self.seed, 7, self.n]).generate_state(1)[0])
            trace = simulate_degradation(self.scenario, [float(t)], seed=noise,
                                         params=self.params).traces[0]
            inspect(self.store, "EMA", trace, float(t), seed=self.seed, params=self.params)
            self.n += 1
        return self.store.data("EMA").K


def real_task(task: tuple) -> dict:
    """One actuator inspected on the reference plant by a policy (``("risk", seed, risk,
    None, params_file)`` or ``("fixed", seed, risk, D, params_file)``; ``params_file`` None:
    the preset), the trends carrying the model discrepancy."""
    import tempfile

    from emaphm.prognosis import HealthHistory
    from emaphm.prognosis.inspection import InspectionPolicy, simulate_policy

    from emaphm.params import load_params

    kind, seed, risk, spec, params_file = task
    params = None if params_file is None else load_params(params_file)
    sc = fleet_path(seed)
    t0 = time.process_time()
    with tempfile.TemporaryDirectory() as tmp, HealthHistory(Path(tmp) / "h.sqlite") as h:
        h.register("EMA")
        run = simulate_policy(sc, InspectionPolicy(risk=risk), seed=seed,
                              fixed_interval=spec if kind == "fixed" else None,
                              observer=_Identified(sc, seed, h, params))
    return {"kind": kind, "seed": seed, "x": risk, "spec": spec, "eol": sc.eol, "name": sc.name,
            "n": run.n_inspections, "missed": run.missed, "flagged_at": run.flagged_at,
            "last": float(run.times[-1]), "rules": list(run.rules),
            "cpu_s": time.process_time() - t0}


def policy_stats(runs: list[dict]) -> dict:
    """Per policy: inspections per actuator and per 1000 operating hours, misses, life used
    at the flag (median, 10th percentile, least, share under 0.6), flags of healthy units."""
    out = {}
    keys = sorted({(r["kind"], r["x"], json.dumps(r["spec"])) for r in runs}, key=str)
    for kind, x, spec in keys:
        rs = [r for r in runs if (r["kind"], r["x"], json.dumps(r["spec"])) == (kind, x, spec)]
        faulty = [r for r in rs if r["eol"] is not None]
        healthy = [r for r in rs if r["eol"] is None]
        used = np.array([r["flagged_at"] / r["eol"] for r in faulty if r["flagged_at"] is not None])
        n = np.array([r["n"] for r in faulty])
        served = np.array([r["flagged_at"] if r["flagged_at"] is not None else
                           min(r["eol"], r["last"]) for r in faulty])
        name = _policy_name(kind, x, json.loads(spec))
        out[name] = {
            "kind": kind, "x": x, "spec": json.loads(spec), "paths": len(faulty),
            "inspections": float(n.mean()), "per_1000h": float(1000 * n.sum() / served.sum()),
            "misses": int(sum(r["missed"] for r in faulty)),
            **_expected(faulty),
            "life_used_median": float(np.median(used)) if used.size else None,
            "life_used_p10": float(np.percentile(used, 10)) if used.size else None,
            "life_used_min": float(used.min()) if used.size else None,
            "flagged_before_0.6": float(np.mean(used < 0.6)) if used.size else None,
            "wasted_h_median": float(np.median([r["eol"] - r["flagged_at"] for r in faulty
                                                if r["flagged_at"] is not None]))
            if used.size else None,
            "least_flag_n": int(min(r["n"] for r in faulty if r["flagged_at"] is not None))
            if used.size else None,
            "flagged_at_floor": float(np.mean([r["flagged_at"] is not None
                                               and r["n"] == MIN_FLAG_INSPECTIONS for r in faulty]))
            if faulty else None,
            "healthy": len(healthy), "healthy_flagged": int(sum(r["flagged_at"] is not None
                                                                for r in healthy)),
            "healthy_per_1000h": (float(1000 * sum(r["n"] for r in healthy)
                                        / sum(r["last"] for r in healthy)) if healthy else None),
            "cpu_s": float(sum(r["cpu_s"] for r in rs)),
        }
    return out


def _expected(faulty: list[dict]) -> dict:
    """Per rule that planned an interval with a trend (``risk`` and ``max interval``: the
    risk rule; ``confirm``: a trend too short to act on, inspected again at the minimum
    interval): intervals per actuator, the misses their predicted risks expect (the sum of
    each plan's chance of a crossing by its inspection) and the misses that happened in
    them. None for the alarm baseline, which plans no risk."""
    if not faulty or not all("risks" in r for r in faulty):
        return {"by_rule": None}
    out = {}
    for name, rules in (("risk rule", ("risk", "max interval")), ("confirm", ("confirm",))):
        n = expected = happened = 0
        for r in faulty:
            for i, (x, rule) in enumerate(zip(r["risks"], r["rules"])):
                if rule in rules and x is not None:
                    n += 1
                    expected += x
                    happened += bool(r["missed"] and i == len(r["rules"]) - 1)
        out[name] = {"per_actuator": n / len(faulty), "expected": expected, "missed": happened}
    return {"by_rule": out}


def _floor(best: dict, stats: dict) -> dict:
    """What 30 % fewer inspections than the best fixed interval asks of any policy that
    flags with the shared rule, which acts on a trend of at least
    :data:`~emaphm.prognosis.inspection.MIN_FLAG_INSPECTIONS` inspections: the target per
    actuator, and the least share of actuators that must be flagged at exactly that many
    (the others one later, none missed) to reach it."""
    target = 0.7 * best["inspections"]
    return {"min_flag_inspections": MIN_FLAG_INSPECTIONS, "target": target,
            "share_at_floor_needed": float(min(max(MIN_FLAG_INSPECTIONS + 1 - target, 0.0), 1.0))
            if target > MIN_FLAG_INSPECTIONS else None,
            "least_flag_n": min((v["least_flag_n"] for v in stats.values()
                                 if v["kind"] != "alarm" and v.get("least_flag_n") is not None),
                                default=None),
            "at_floor": {name: v["flagged_at_floor"] for name, v in stats.items()
                         if v["kind"] != "alarm" and v.get("flagged_at_floor") is not None}}


def _policy_name(kind: str, x: float, spec) -> str:
    if kind == "risk":
        return f"risk {x:g}" + ("" if spec is None else " ({:g}/{:g}/{:g} h)".format(*spec))
    if kind == "fixed":
        return f"fixed {spec:g} h"
    return f"alarm {x:g}, fixed {spec:g} h"


def comparison(stats: dict) -> dict:
    """The best fixed intervals (longest with no miss, with hindsight) beside the risk
    policy at each risk."""
    fixed = {v["spec"]: v for v in stats.values() if v["kind"] == "fixed"}
    clean = [d for d, v in fixed.items() if v["misses"] == 0]
    best = max(clean) if clean else None
    alarm = [v for v in stats.values() if v["kind"] == "alarm" and v["misses"] == 0]
    best_alarm = max(alarm, key=lambda v: (v["spec"], -v["inspections"])) if alarm else None
    clean_risk = [v for v in stats.values() if v["kind"] == "risk" and v["misses"] == 0]
    at_zero = min(clean_risk, key=lambda v: v["inspections"]) if clean_risk else None
    fewest = [v for v in stats.values() if v["kind"] == "risk"]
    out = {"best_fixed": best, "floor": None if best is None else _floor(fixed[best], stats),
           "best_alarm": None if best_alarm is None else
           {"share": best_alarm["x"], "interval": best_alarm["spec"]}, "risk": {},
           "risk_at_zero_misses": None if at_zero is None or best is None else
           {"risk": at_zero["x"], "inspections": at_zero["inspections"],
            "per_1000h": at_zero["per_1000h"], "life_used_median": at_zero["life_used_median"],
            "fewer_per_actuator": 1 - at_zero["inspections"] / fixed[best]["inspections"],
            "fewer_per_1000h": 1 - at_zero["per_1000h"] / fixed[best]["per_1000h"]},
           "least_misses": min(v["misses"] for v in fewest) if fewest else None}
    for v in stats.values():
        if v["kind"] != "risk" or best is None:
            continue
        b = fixed[best]
        out["risk"][str(v["x"])] = {
            "misses": v["misses"], "fewer_per_actuator": 1 - v["inspections"] / b["inspections"],
            "fewer_per_1000h": 1 - v["per_1000h"] / b["per_1000h"],
            "life_used_median": v["life_used_median"],
            "passed_per_actuator": bool(v["misses"] == 0 and v["inspections"] <= 0.7 * b["inspections"]
                                        and (v["life_used_median"] or 0) >= 0.6),
            "passed_per_1000h": bool(v["misses"] == 0 and v["per_1000h"] <= 0.7 * b["per_1000h"]
                                     and (v["life_used_median"] or 0) >= 0.6)}
    return out


# ----------------------------------------------------------------------------- running
def _map(fn, tasks: list, workers: int, label: str) -> list:
    t0 = time.perf_counter()
    out = []
    if workers <= 1:
        it = map(fn, tasks)
        pool = None
    else:
        import multiprocessing

        pool = ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn"))
        it = pool.map(fn, tasks, chunksize=4)
    try:
        for i, r in enumerate(it, 1):
            out.append(r)
            if i % 50 == 0 or i == len(tasks):
                print(f"  {label}: {i}/{len(tasks)} ({time.perf_counter() - t0:.0f} s)",
                      file=sys.stderr, flush=True)
    finally:
        if pool is not None:
            pool.shutdown()
    return out


def tune(workers: int) -> dict:
    from emaphm.prognosis.inspection import INTERVAL_DEFAULTS

    tasks = [("risk", s, 0.01, spec) for spec in TUNE_GRID for s in TUNE_SEEDS]
    runs = _map(policy_task, tasks, workers, "tuning")
    rows = []
    for spec in TUNE_GRID:
        (st,) = policy_stats([r for r in runs if tuple(r["spec"]) == spec]).values()
        rows.append({"default": spec[0], "min": spec[1], "max": spec[2], **st})
    ok = [r for r in rows if r["misses"] == 0 and (r["life_used_median"] or 0) >= 0.8]
    chosen = min(ok, key=lambda r: r["per_1000h"]) if ok else None
    d = INTERVAL_DEFAULTS["h"]
    return {"seeds": [TUNE_SEEDS.start, TUNE_SEEDS.stop - 1], "risk": 0.01,
            "rule": "fewest inspections per 1000 h with no miss and a median life used >= 0.8",
            "grid": [{k: v for k, v in r.items() if k != "cpu_s"} for r in rows],
            "cpu_s": float(sum(r["cpu_s"] for r in runs)), "runs": runs,
            "chosen": None if chosen is None else
            {k: chosen[k] for k in ("default", "min", "max")},
            "in_code": {"default": d.default, "min": d.min, "max": d.max}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--paths", type=int, default=200)
    ap.add_argument("--calibration-paths", type=int, default=200, help="per law")
    ap.add_argument("--healthy", type=int, default=50)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--tune", action="store_true")
    ap.add_argument("--real", type=int, default=0, metavar="N",
                    help="only: the first N actuators inspected on the reference plant (each "
                         "inspection identified) by the risk policy at 0.01 and the best fixed "
                         "interval of the synthetic run; added to inspection.json and .md")
    ap.add_argument("--params", type=Path, default=None, metavar="FILE",
                    help="with --real: the actuator's parameters (TOML, e.g. "
                         "examples/actuators/ema-270v-750w.toml; default the preset), its "
                         "results kept beside the preset's")
    ap.add_argument("--figures-only", action="store_true",
                    help="redraw the figures and write the report again from "
                         "benchmarks/results/inspection.json")
    args = ap.parse_args()
    RESULTS.mkdir(parents=True, exist_ok=True)
    if args.tune:
        res = tune(args.workers)
        (RESULTS / "inspection_tuning.json").write_text(json.dumps(res, indent=1) + "\n")
        print(json.dumps(res["chosen"]), res["in_code"])
        return
    if args.real:
        real(args.real, args.workers, args.params)
        return
    if args.figures_only:
        res = json.loads((RESULTS / "inspection.json").read_text())
        res["policies"] = policy_stats(res["policy_runs"])      # what the runs say now
        res["comparison"] = comparison(res["policies"])
        (RESULTS / "inspection.json").write_text(json.dumps(res, allow_nan=False) + "\n")
        figures(res)
        (RESULTS / "inspection.md").write_text(report(res))
        return
    wall0, cpu0 = time.perf_counter(), time.process_time()
    load0 = os.getloadavg()
    cal_tasks = [(law, i) for law in LAWS for i in range(args.calibration_paths)]
    cal_runs = _map(calibration_task, cal_tasks, args.workers, "calibration")
    seeds = list(range(args.paths)) + [-(1 + i) for i in range(args.healthy)]
    tasks = [("risk", s, r, None) for r in RISKS for s in seeds]
    tasks += [("fixed", s, FIXED_RISK, d) for d in FIXED for s in seeds if s >= 0]
    tasks += [("alarm", s, a, d) for a in ALARM_SHARES for d in ALARM_FIXED for s in seeds]
    runs = _map(policy_task, tasks, args.workers, "policies")
    best = comparison(policy_stats(runs))["best_fixed"]
    if best is not None:            # the best fixed interval on the healthy units too
        runs += _map(policy_task, [("fixed", s, FIXED_RISK, best) for s in seeds if s < 0],
                     args.workers, "healthy, best fixed")
    stats = policy_stats(runs)
    res = {"meta": _meta(args, wall0, cpu0, load0, cal_runs, runs),
           "calibration": calibration_stats(cal_runs), "policies": stats,
           "comparison": comparison(stats), "calibration_runs": cal_runs, "policy_runs": runs}
    (RESULTS / "inspection.json").write_text(json.dumps(res, allow_nan=False) + "\n")
    figures(res)
    (RESULTS / "inspection.md").write_text(report(res))
    print((RESULTS / "inspection.md").read_text())


def real(n: int, workers: int, params_file: Path | None = None) -> None:
    """The plant-trace check (``--real N [--params FILE]``), added to the synthetic run's
    results: the preset's under ``real``, another actuator's under ``real_actuators[name]``."""
    res = json.loads((RESULTS / "inspection.json").read_text())
    best = res["comparison"]["best_fixed"]
    wall0 = time.perf_counter()
    load0 = os.getloadavg()
    name = None
    if params_file is not None:
        from emaphm.params import load_params

        params_file = params_file.resolve()
        name = load_params(params_file).name or params_file.stem
    tasks = [("risk", s, FIXED_RISK, None, params_file) for s in range(n)]
    tasks += [("fixed", s, FIXED_RISK, best, params_file) for s in range(n)]
    runs = _map(real_task, tasks, workers, "plant traces")
    stats = policy_stats(runs)
    synthetic = {k: policy_stats([r for r in res["policy_runs"] if r["seed"] in range(n)
                                  and r["kind"] == v["kind"] and r["x"] == v["x"]
                                  and r["spec"] == v["spec"]])[k] for k, v in stats.items()}
    out = {"paths": n, "stats": stats, "synthetic_same_paths": synthetic, "runs": runs,
           "wall_s": time.perf_counter() - wall0,
           "cpu_s_workers": float(sum(r["cpu_s"] for r in runs)),
           "load_before": list(load0), "load_after": list(os.getloadavg()),
           "actuator": name or "preset", "date": _dt.date.today().isoformat()}
    if name is None:
        res["real"] = out
    else:
        res.setdefault("real_actuators", {})[name] = out
    (RESULTS / "inspection.json").write_text(json.dumps(res, allow_nan=False) + "\n")
    (RESULTS / "inspection.md").write_text(report(res))
    print((RESULTS / "inspection.md").read_text())


def _meta(args, wall0: float, cpu0: float, load0: tuple, cal_runs: list, runs: list) -> dict:
    from _machine import machine
    from emaphm.prognosis.inspection import INTERVAL_DEFAULTS

    d = INTERVAL_DEFAULTS["h"]
    return {"date": _dt.date.today().isoformat(), "machine": machine("scipy"),
            "workers": args.workers, "wall_s": time.perf_counter() - wall0,
            "cpu_s_workers": float(sum(r["cpu_s"] for r in cal_runs + runs)),
            "load_before": list(load0), "load_after": list(os.getloadavg()),
            "intervals": {"default": d.default, "min": d.min, "max": d.max},
            "paths": args.paths, "calibration_paths_per_law": args.calibration_paths,
            "healthy": args.healthy, "noise": NOISE, "fixed_risk": FIXED_RISK}


# ----------------------------------------------------------------------------- figures, report
def figures(res: dict) -> None:
    """The calibration curve and inspections against misses, drawn from the results."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    FIGURES.mkdir(parents=True, exist_ok=True)
    cal = res["calibration"]
    qs = np.array(cal["qs"])
    fig, ax = plt.subplots(figsize=(5.2, 4.4))
    ax.plot([0, 0.55], [0, 0.55], color="0.6", lw=1, ls="--", label="realised = planned")
    n = cal["laws"]["all"]["independent"]
    band = 1.96 * np.sqrt(qs * (1 - qs) / n)
    ax.fill_between(qs, qs - band, qs + band, color="0.85", label=f"95 % margin, n = {n}")
    for name, style in (("linear", "o-"), ("power", "s-"), ("exponential", "^-"), ("all", "k.-")):
        r = cal["laws"][name]["realised_all"]
        ax.plot(qs, r, style, ms=4, label=f"{name} ({cal['laws'][name]['decisions']} decisions)")
    ax.plot(qs, cal["laws"]["all"]["realised_one_per_path"], "kx", ms=7,
            label="all, one decision per actuator")
    ax.set(xscale="log", yscale="log", xlim=(0.0008, 0.6), ylim=(0.0003, 0.7),
           xlabel="planned risk q", ylabel="realised: crossing at or before t*_q",
           title="Is the risk a probability? (synthetic k)")
    ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    fig.savefig(FIGURES / "calibration.png", dpi=110)
    plt.close(fig)

    st = res["policies"]
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
    for ax, key, xlabel in ((axes[0], "inspections", "inspections per actuator (to its flag)"),
                            (axes[1], "per_1000h", "inspections per 1000 operating hours")):
        groups = (("fixed", None, "o", "C0", f"fixed D, flagged at risk {res['meta']['fixed_risk']:g}"),
                  ("alarm", 0.5, "s", "C2", "fixed D, flagged at 0.5 of the threshold"),
                  ("alarm", 0.7, "D", "C4", "fixed D, flagged at 0.7 of the threshold"),
                  ("risk", None, "*", "C3", "risk policy"))
        for kind, share, marker, color, label in groups:
            pts = sorted((v[key], v["misses"], v["x"] if kind == "risk" else v["spec"])
                         for v in st.values() if v["kind"] == kind
                         and (share is None or v["x"] == share))
            if not pts:
                continue
            xs, ys, tags = zip(*pts)
            ax.plot(xs, ys, marker, color=color, ms=10 if kind == "risk" else 6, ls="-" if
                    kind != "risk" else "none", lw=0.8, label=label)
            if kind in ("fixed", "risk"):
                for x, y, tag in zip(xs, ys, tags):
                    ax.annotate(f"{tag:g}" + (" h" if kind == "fixed" else ""), (x, y),
                                fontsize=7, color=color, xytext=(4, 4 if kind == "risk" else -9),
                                textcoords="offset points")
        ax.set(xlabel=xlabel, ylabel=f"misses of {res['meta']['paths']} actuators")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.suptitle("Inspections against misses (synthetic k, 200 simulated actuators)", fontsize=10)
    fig.tight_layout()
    fig.savefig(FIGURES / "policy.png", dpi=110)
    plt.close(fig)


def _by_rule(v: dict, rule: str) -> str:
    b = (v.get("by_rule") or {}).get(rule)
    return "-" if b is None else (f"{b['per_actuator']:.2f}, {b['expected']:.1f} / "
                                  f"{b['missed']}")


def _f(x, fmt=".2f") -> str:
    return "-" if x is None else format(x, fmt)


def report(res: dict) -> str:
    m, cal, st, cmp_ = res["meta"], res["calibration"], res["policies"], res["comparison"]
    iv = m["intervals"]
    md = [f"## Inspection planning: risk calibration and the policy against fixed intervals "
          f"({m['date']}, {m['workers']} worker processes, {m['wall_s']:.0f} s wall, "
          f"{m['cpu_s_workers']:.0f} s CPU in the workers; load average {m['load_before'][0]:.1f} "
          f"before, {m['load_after'][0]:.1f} after)", "",
          f"{m['machine']}. `benchmarks/bench_inspection.py`; method and definitions in "
          "[docs/inspection-planning.md](docs/inspection-planning.md). Every inspection is "
          f"synthetic: the true k plus N(0, {m['noise']}) per component (an identification's "
          "error size, as `fleet demo --synthetic`), no trace diagnosed, no model discrepancy.",
          "", "### Is the planned risk a probability?", "",
          f"{m['calibration_paths_per_law']} actuators per law, lives 800-2500 h, inspected every "
          "L/9 to L/5; at each inspection from the 3rd on where an indicator takes part, the "
          "time t*_q at which the chance of a crossing reaches q. Realised: the share of "
          "decisions whose true crossing came at or before t*_q (at most q if calibrated).", "",
          "| decisions | n | " + " | ".join(f"q = {q:g}" for q in cal["qs"]) + " |",
          "|---|---|" + "---|" * len(cal["qs"])]
    for name, v in cal["laws"].items():
        md.append(f"| {name}, every decision | {v['decisions']} | "
                  + " | ".join(_f(x, ".3f") for x in v["realised_all"]) + " |")
    v = cal["laws"]["all"]
    md.append(f"| all, one per actuator | {v['independent']} | "
              + " | ".join(_f(x, ".3f") for x in v["realised_one_per_path"]) + " |")
    for stage, s in v["by_stage"].items():
        md.append(f"| all, life {stage} | {s['n']} | "
                  + " | ".join(_f(x, ".3f") for x in s["realised"]) + " |")
    md += ["", "Acceptance (one decision per actuator, independent): "
           + "; ".join(f"risk {q}: realised {a['realised']:.4f} <= {q} + {a['margin']:.4f} "
                       f"(n = {a['n']}): {'yes' if a['passed'] else 'NO'}"
                       for q, a in cal["acceptance"].items()) + ".", "",
           "![calibration](docs/figures/inspection/calibration.png)", "",
           "### The risk policy against fixed intervals", "",
           f"{m['paths']} actuators (seeds 0-{m['paths'] - 1}) inspected from t = 0 until flagged "
           f"or missed; {m['healthy']} healthy ones over 2500 h. Risk policy: intervals default "
           f"{iv['default']:g} h, min {iv['min']:g} h, max {iv['max']:g} h "
           "(`INTERVAL_DEFAULTS`, tuned on seeds 1000-1039). Fixed D: flagged when a crossing "
           f"before the next inspection is more likely than {m['fixed_risk']:g}; alarm: flagged "
           "when an identified indicator reaches a share of its threshold (no prognosis). "
           "Life used: t_flag / EoL (service from t = 0).", "",
           "*Intervals planned with a trend*, by the rule that set them: the **risk rule** "
           "(`risk` and `max interval`: the chance of a crossing by the inspection at most the "
           "risk) and **confirm** (a trend of 3-4 inspections put a crossing within the "
           "minimum interval: inspected again at it, not flagged). For each: intervals per "
           "actuator, the misses their predicted chances expect (the sum over the intervals "
           "and actuators) and the misses that happened in them. A risk of 0.01 per interval, "
           "planned 2-3 times over an actuator's life, expects a few misses in 200 actuators.",
           "",
           "| policy | inspections per actuator | per 1000 h | misses | risk rule: intervals "
           "per actuator, misses expected / happened | confirm: intervals per actuator, misses "
           "expected / happened | life used: median | "
           "10th pct | least | flagged before 0.6 | wasted life median [h] | healthy flagged |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    order = sorted(st.items(), key=lambda kv: ({"risk": 0, "fixed": 1, "alarm": 2}[kv[1]["kind"]],
                                               kv[1]["x"], kv[1]["spec"] or 0))
    for name, v in order:
        hf = "-" if not v["healthy"] else f"{v['healthy_flagged']} of {v['healthy']}"
        md.append(f"| {name} | {v['inspections']:.2f} | {v['per_1000h']:.2f} | {v['misses']} | "
                  f"{_by_rule(v, 'risk rule')} | {_by_rule(v, 'confirm')} | "
                  f"{_f(v['life_used_median'])} | {_f(v['life_used_p10'])} | "
                  f"{_f(v['life_used_min'])} | {_f(v['flagged_before_0.6'])} | "
                  f"{_f(v['wasted_h_median'], '.0f')} | {hf} |")
    b = cmp_["best_fixed"]
    md += ["", "Best fixed interval (longest with no miss, chosen with hindsight): "
           + ("none in the grid" if b is None else f"{b:g} h")
           + (f"; best alarm baseline: share {cmp_['best_alarm']['share']:g} every "
              f"{cmp_['best_alarm']['interval']:g} h" if cmp_["best_alarm"] else "") + "."]
    for r, c in cmp_["risk"].items():
        md.append(f"* risk {r}: {c['misses']} misses; {100 * c['fewer_per_actuator']:+.0f} % "
                  f"fewer inspections per actuator, {100 * c['fewer_per_1000h']:+.0f} % per 1000 h "
                  f"than fixed {b:g} h; median life used {_f(c['life_used_median'])}; the "
                  f"acceptance (no miss, >= 30 % fewer, median life used >= 0.6): per actuator "
                  f"{'met' if c['passed_per_actuator'] else 'NOT met'}, per 1000 h "
                  f"{'met' if c['passed_per_1000h'] else 'NOT met'}")
    z = cmp_.get("risk_at_zero_misses")
    if z is not None:
        md.append(f"* at equal misses (none): risk {z['risk']:g}, the risk policy with no miss "
                  f"and the fewest inspections: {z['inspections']:.2f} per actuator "
                  f"({100 * z['fewer_per_actuator']:+.0f} % fewer than fixed {b:g} h), "
                  f"{z['per_1000h']:.2f} per 1000 h ({100 * z['fewer_per_1000h']:+.0f} %), "
                  f"median life used {_f(z['life_used_median'])}; the acceptance's 30 % "
                  f"fewer per actuator "
                  f"{'met' if z['fewer_per_actuator'] >= 0.3 else 'NOT met'}")
    elif cmp_.get("least_misses") is not None:
        md.append(f"* at equal misses (none): no risk of the grid had no miss (the fewest: "
                  f"{cmp_['least_misses']}); the acceptance is NOT met")
    f = cmp_.get("floor")
    if f is not None and f["share_at_floor_needed"] is not None:
        at = "; ".join(f"{name} {share:.2f}" for name, share in f["at_floor"].items()
                       if name.startswith("risk") or name == f"fixed {b:g} h")
        md.append(f"* what 30 % fewer asks: every policy here flags with one rule, which acts "
                  f"on a trend of at least {f['min_flag_inspections']} inspections (the fewest "
                  f"inspections up to a flag, measured in every policy: {f['least_flag_n']}); "
                  f"30 % fewer "
                  f"than fixed {b:g} h is {f['target']:.2f} inspections per actuator, which "
                  f"needs at least {100 * f['share_at_floor_needed']:.0f} % of the actuators "
                  f"flagged at their {f['min_flag_inspections']}th inspection (the rest at the "
                  f"next) and none missed. Share flagged at the "
                  f"{f['min_flag_inspections']}th: {at}")
    md += ["", "![policy](docs/figures/inspection/policy.png)", ""]
    if "real" in res:
        md += _real_report(res["real"])
    for other in res.get("real_actuators", {}).values():
        md += _real_report(other)
    return "\n".join(md)


def _real_report(real: dict) -> list[str]:
    who = real.get("actuator", "preset")
    md = ["### The same policies on plant traces (a check, not statistics)" if who == "preset"
          else f"### The same policies on another actuator's plant traces: {who}", "",
          f"The first {real['paths']} of the actuators above"
          + ("" if who == "preset" else f", {who}'s reference plant and data sheet "
             f"(`examples/actuators/{who}.toml`; {real.get('date', '')})")
          + ", every inspection a reference-plant "
          "trace (switching PWM, Stribeck friction, sensor noise) identified by the default "
          "pipeline on the data sheet (no commissioning), the trends carrying the model "
          f"discrepancy (`MODEL_DISCREPANCY`). {real['wall_s']:.0f} s wall, "
          f"{real['cpu_s_workers']:.0f} s CPU in the workers (load average "
          f"{real['load_before'][0]:.1f} before, {real['load_after'][0]:.1f} after).", "",
          "| policy | actuators | plant: inspections per actuator | per 1000 h | misses | "
          "life used median | least | synthetic, same actuators: inspections | per 1000 h | "
          "misses | life used median |",
          "|---|---|---|---|---|---|---|---|---|---|---|"]
    for name, v in real["stats"].items():
        w = real["synthetic_same_paths"][name]
        md.append(f"| {name} | {v['paths']} | {v['inspections']:.2f} | {v['per_1000h']:.2f} | "
                  f"{v['misses']} | {_f(v['life_used_median'])} | {_f(v['life_used_min'])} | "
                  f"{w['inspections']:.2f} | {w['per_1000h']:.2f} | {w['misses']} | "
                  f"{_f(w['life_used_median'])} |")
    return md + [""]


if __name__ == "__main__":
    main()
