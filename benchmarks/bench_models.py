"""Speed, compile time and memory of the models, on one core.

Run: ``python benchmarks/bench_models.py [--quick]`` -> ``benchmarks/results/models.md``
(the table is printed too).

Measured side by side in one run, single-threaded: every thread pool (Numba,
OpenMP, BLAS) is set to one thread before NumPy and Numba are imported;
``--pin CPU`` also pins the process to one CPU (on a quiet machine; on a
shared one it only ties the run to a busy core). Each timed row also reports
the process CPU time, which time-sharing with other work does not inflate:

* the monitoring model (MM, Numba kernel) on one population of N = 50 random
  candidates ``k`` in [0, 1]^8 over the default diagnostic profile (0.5 s,
  T_s = 125 us, 4000 control periods): fitness only (``weighted_sse``, what an
  optimizer calls) and with traces (``simulate_population``), at n_sub = 1 and 2;
  median over repeats of ms per population and of ns per candidate-step
  ``time / (N * n_steps * n_sub)``;
* the same at N = 1, 10, 50, 200 (scaling);
* side by side with the kernel of an earlier revision (``--baseline-rev``, default
  8a69e1c: three RL branches with the star point held, before the winding circuit),
  extracted with ``git archive`` into a temporary package imported as
  ``emaphm_baseline``: ns per candidate-step of the SIMD kernel alone (P, CP packed
  beforehand) for the baseline (paper fault model) and today's paper and physical
  fault models, repeats interleaved round-robin so that all three see the same load;
  the cost of packing a population (``pack_population``: the exact winding step of
  every candidate) and its share of a population evaluation;
* the NumPy-vectorised MM (``tests/monitoring_numpy.py``, the test oracle) on the same
  population, and its ratio to the kernel;
* the reference model (RM), one trace at n_sub = 128 with and without PWM;
* compile time: a fresh interpreter's first ``weighted_sse`` call with a warm
  on-disk cache (filled by a warm-up interpreter) and with an empty one;
* peak traced memory (``tracemalloc``) of one population evaluation, fitness
  only against traces.

Targets (design notes): 40 ns per candidate-step or better on one core (about
10 ms for 50 candidates over 0.5 s), warm first call under 1 s.
"""

from __future__ import annotations

import os

for _var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
             "NUMEXPR_NUM_THREADS", "VECLIB_MAXIMUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import importlib  # noqa: E402
import datetime as _dt  # noqa: E402
import platform  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
import tracemalloc  # noqa: E402
from dataclasses import replace  # noqa: E402
from pathlib import Path  # noqa: E402

import numba  # noqa: E402
import numpy as np  # noqa: E402

from emaphm.faults import K_NOMINAL  # noqa: E402
from emaphm.models.layout import pack_population  # noqa: E402
from emaphm.models.monitoring import MonitoringModel  # noqa: E402
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))   # the NumPy oracle
from monitoring_numpy import simulate_population_numpy, weighted_sse_numpy  # noqa: E402
from emaphm.models.reference import run_reference  # noqa: E402
from emaphm.profiles import diagnostic  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results" / "models.md"
REPO = Path(__file__).resolve().parent.parent
BASELINE_REV = "8a69e1c"     # before the winding circuit: RL branches, star point held
MAX_RATIO = 1.5              # physical / baseline kernel cost (design notes)
MAX_PACK_SHARE = 0.20        # pack_population / population evaluation
TARGET_NS = 40.0        # ns per candidate-step, one core
TARGET_WARM_S = 1.0     # s, first call in a fresh process with a warm cache
N_MAIN = 50
SEED = 12345


# --- timing helpers -----------------------------------------------------------------------

def _median_time(fn, repeats: int, warmup: int = 1) -> tuple[float, float, float]:
    """``(median, min, median CPU)`` time of ``fn()`` in seconds over ``repeats`` calls.

    The CPU time of each call is kept too (``_CPU``): far below the wall time, it
    says the core was shared with another process during the run.
    """
    for _ in range(warmup):
        fn()
    times, cpu = [], []
    for _ in range(repeats):
        c0 = time.process_time()
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    _CPU.append((sum(cpu), sum(times)))
    return statistics.median(times), min(times), statistics.median(cpu)


_CPU: list[tuple[float, float]] = []      # (CPU s, wall s) of every timed series


def _peak_bytes(fn) -> int:
    """Peak memory traced by ``tracemalloc`` while ``fn()`` runs (NumPy reports its buffers)."""
    tracemalloc.start()
    tracemalloc.reset_peak()
    base, _ = tracemalloc.get_traced_memory()
    fn()
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return peak - base


_FIRST_CALL = r"""
import os, time, json
t0 = time.perf_counter()
import numpy as np
from emaphm.models.monitoring import MonitoringModel
t1 = time.perf_counter()
mm = MonitoringModel()
K = np.random.default_rng(0).random((50, 8))
n = mm.t.size
t2, c2 = time.perf_counter(), time.process_time()
mm.weighted_sse(K, np.zeros((n, 3)), np.ones((n, 3)))
t3, c3 = time.perf_counter(), time.process_time()
mm.weighted_sse(K, np.zeros((n, 3)), np.ones((n, 3)))
t4 = time.perf_counter()
print(json.dumps({"import": t1 - t0, "first": t3 - t2, "first_cpu": c3 - c2, "second": t4 - t3}))
"""


def _first_call(cache_dir: str) -> dict[str, float]:
    """Run a fresh interpreter with ``NUMBA_CACHE_DIR=cache_dir``; its timings in s."""
    import json
    env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir)
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", _FIRST_CALL], env=env, check=True,
                         capture_output=True, text=True)
    res = json.loads(out.stdout.strip().splitlines()[-1])
    res["process"] = time.perf_counter() - t0
    return res


# --- side by side with an earlier revision ---------------------------------------------

def _baseline_package(rev: str, root: str):
    """``emaphm`` of git revision ``rev``, extracted under ``root`` and imported as
    ``emaphm_baseline`` (its modules import each other relatively)."""
    archive = subprocess.run(["git", "-C", str(REPO), "archive", rev, "src/emaphm"],
                             check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", root], input=archive, check=True)
    os.rename(os.path.join(root, "src", "emaphm"), os.path.join(root, "emaphm_baseline"))
    sys.path.insert(0, root)
    return importlib.import_module("emaphm_baseline")


def _kernel_call(kernel, P, CP, ref, load, n_sub, target, weights):
    """The SIMD kernel alone on packed ``P, CP``: fitness only, as ``weighted_sse`` runs it."""
    import inspect

    n_pop = CP.shape[0]
    fitness = np.zeros(n_pop)
    status = np.zeros(n_pop, dtype=np.int64)
    none3, none2 = np.zeros((0, 0, 3)), np.zeros((0, 0))
    # kernels since 6999cb1 take the fault loops' output too (none asked here)
    loops = (none3,) if "out_f" in inspect.signature(getattr(kernel, "py_func", kernel)).parameters else ()
    return lambda: kernel(P, CP, ref, load, n_sub, target, weights, none3, none2, none2, none2,
                          fitness, status, *loops)


def _interleaved(fns: dict, repeats: int) -> dict:
    """Median CPU and wall time [s] of each ``fns[name]()``, the calls taken round-robin."""
    for fn in fns.values():
        fn()
    wall = {name: [] for name in fns}
    cpu = {name: [] for name in fns}
    for _ in range(repeats):
        for name, fn in fns.items():
            c0, t0 = time.process_time(), time.perf_counter()
            fn()
            wall[name].append(time.perf_counter() - t0)
            cpu[name].append(time.process_time() - c0)
    for name in fns:
        _CPU.append((sum(cpu[name]), sum(wall[name])))
    return {name: (statistics.median(wall[name]), statistics.median(cpu[name])) for name in fns}


def side_by_side(rev: str, quick: bool) -> list[tuple[str, str, str]]:
    """Rows: the SIMD kernel of revision ``rev`` (paper) against today's paper and
    physical kernels, N = 50, n_sub = 1, and the cost of packing a population."""
    from emaphm.models.monitoring_simd import _kernel as new_kernel
    repeats = 9 if quick else 41
    profile = diagnostic()
    K = np.random.default_rng(SEED).random((N_MAIN, 8))
    rows: list[tuple[str, str, str]] = []
    with tempfile.TemporaryDirectory(prefix="emaphm-baseline-") as root:
        base = _baseline_package(rev, root)
        from emaphm_baseline.models.layout import pack_population as base_pack
        from emaphm_baseline.models.monitoring import MonitoringModel as BaseModel
        from emaphm_baseline.models.monitoring_simd import _kernel as base_kernel
        old = BaseModel(profile=profile)
        new = {fm: MonitoringModel(profile=profile, fault_model=fm) for fm in ("paper", "physical")}
        # the Stribeck drop stated (the plant's 1 rad/s): the full plant step, its
        # branch-free exponential in the lanes (the kernel's variant with dead time)
        stated = replace(new["physical"].params, transmission=replace(
            new["physical"].params.transmission, omega_s=1.0))
        new["physical, Stribeck drop stated"] = MonitoringModel(stated, profile=profile,
                                                                fault_model="physical")
        n_steps = old.t.size
        ref, load = old._ref, old._load
        target = old.simulate_population(K_NOMINAL[None]).i_abc[0]
        weights = np.ones_like(target)
        P0, CP0 = base_pack(old.params, K)
        fns = {f"baseline {rev} (paper)": _kernel_call(base_kernel, P0, CP0, ref, load, 1,
                                                       target, weights)}
        for fm, model in new.items():
            P, CP = model.pack(K)
            fns[f"today, {fm}"] = _kernel_call(new_kernel, P, CP, ref, load, 1, target, weights)
        kern = _interleaved(fns, repeats)
        packs = _interleaved({fm: (lambda m=m: m.pack(K)) for fm, m in new.items()}, repeats)
        whole = _interleaved({fm: (lambda m=m: m.weighted_sse(K, target, weights))
                              for fm, m in new.items()}, max(3, repeats // 2))
        del base
    ns = {name: cpu / (N_MAIN * n_steps) * 1e9 for name, (_, cpu) in kern.items()}
    ns_wall = {name: w / (N_MAIN * n_steps) * 1e9 for name, (w, _) in kern.items()}
    base_ns = ns[f"baseline {rev} (paper)"]
    for name in fns:
        ratio = ns[name] / base_ns
        tgt = ""
        if name.endswith("physical"):
            tgt = f"<= {MAX_RATIO} x baseline ({'met' if ratio <= MAX_RATIO else 'missed'})"
        rows.append((f"Side by side, SIMD kernel alone, N = {N_MAIN}, n_sub = 1, fitness only, "
                     f"{name}: ns per candidate-step",
                     f"{ns[name]:.1f} CPU ({ns_wall[name]:.1f} wall); {ratio:.2f} x baseline", tgt))
    stated = "today, physical, Stribeck drop stated"
    if stated in ns:
        rows.append((f"Side by side, the Stribeck drop's cost: SIMD kernel, N = {N_MAIN}, "
                     "physical, the drop stated against none (the ideal plant's step; the full step runs the dead time's terms too, at 0 V)",
                     f"{ns[stated] / ns['today, physical']:.3f} x", ""))
    for fm in new:
        share = packs[fm][1] / whole[fm][1]
        rows.append((f"Side by side, `pack_population` (exact winding step), N = {N_MAIN}, {fm}: "
                     "ms per population",
                     f"{packs[fm][1] * 1e3:.3f} CPU ({packs[fm][0] * 1e3:.3f} wall); "
                     f"{100 * share:.0f} % of `weighted_sse` ({whole[fm][1] * 1e3:.2f} ms CPU)",
                     f"<= {100 * MAX_PACK_SHARE:.0f} % "
                     f"({'met' if share <= MAX_PACK_SHARE else 'missed'})"))
    return rows


# --- machine ------------------------------------------------------------------------------

def _machine() -> dict[str, str]:
    cpu = platform.processor() or platform.machine()
    info: dict[str, str] = {}
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if not line.strip():
                    break                                   # first processor only
                key, _, val = line.partition(":")
                info[key.strip()] = val.strip()
    except OSError:
        pass
    if "model name" in info:
        cpu = (f"{info['model name']} (family {info.get('cpu family', '?')}, model "
               f"{info.get('model', '?')}, stepping {info.get('stepping', '?')}, "
               f"{float(info.get('cpu MHz', 'nan')):.0f} MHz)")
    ram = "?"
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemTotal"):
                    ram = f"{int(line.split()[1]) / 2**20:.1f} GiB"
                    break
    except OSError:
        pass
    os_name = platform.platform()
    try:
        with open("/etc/os-release") as f:
            for line in f:
                if line.startswith("PRETTY_NAME="):
                    os_name = f"{line.split('=', 1)[1].strip().strip(chr(34))} ({platform.release()})"
    except OSError:
        pass
    allowed = sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else []
    load = os.getloadavg() if hasattr(os, "getloadavg") else (float("nan"),) * 3
    return {
        "CPU": cpu,
        "cores": (f"{os.cpu_count()} logical; the benchmark ran single-threaded (every thread "
                  f"pool at 1) on CPU(s) {allowed}"),
        "RAM": ram,
        "OS": os_name,
        "Python": platform.python_version(),
        "NumPy": np.__version__,
        "Numba": numba.__version__,
        "load average at start (1/5/15 min)": " / ".join(f"{x:.2f}" for x in load),
    }


# --- the benchmark ------------------------------------------------------------------------

def run(quick: bool, baseline_rev: str = BASELINE_REV,
        only_side_by_side: bool = False) -> tuple[list[tuple[str, str, str]], dict[str, str], str]:
    """All measurements: table rows ``(measurement, value, target)``, machine, a note."""
    def reps(full, q):
        return q if quick else full

    if only_side_by_side:
        rows = side_by_side(baseline_rev, quick)
        cpu, wall = (sum(x) for x in zip(*_CPU))
        return rows, _machine(), (f"Only the side-by-side rows (--side-by-side-only). The process "
                                  f"got {100 * cpu / wall:.0f} % of its core.")

    profile = diagnostic()
    rng = np.random.default_rng(SEED)
    K200 = rng.random((200, 8))
    K = K200[:N_MAIN]
    rows: list[tuple[str, str, str]] = []
    models = {n_sub: MonitoringModel(profile=profile, n_sub=n_sub) for n_sub in (1, 2)}
    mm = models[1]
    n_steps = mm.t.size
    target = mm.simulate_population(K_NOMINAL[None]).i_abc[0]     # nominal MM currents
    weights = np.ones_like(target)
    status = mm.simulate_population(K).status
    n_diverged = int(np.count_nonzero(status == 1))
    n_tripped = int(np.count_nonzero(status == 2))

    def ns_per(t, n_pop, n_sub):
        return t / (n_pop * n_steps * n_sub) * 1e9

    def met(ok):
        return "met" if ok else "missed"

    # 1. one population, N = 50, n_sub = 1 and 2
    main = {}
    for n_sub, model in models.items():
        for kind in ("fitness", "traces"):
            if kind == "fitness":
                fn, label = (lambda m=model: m.weighted_sse(K, target, weights)), \
                    "fitness only (`weighted_sse`)"
            else:
                fn, label = (lambda m=model: m.simulate_population(K)), \
                    "with traces (`simulate_population`)"
            med, best, cpu = _median_time(fn, reps(31, 7))
            main[(n_sub, kind)] = cpu
            ns, ns_cpu = ns_per(med, N_MAIN, n_sub), ns_per(cpu, N_MAIN, n_sub)
            head = f"MM, N = {N_MAIN}, n_sub = {n_sub}, {label}"
            rows.append((f"{head}: ms per population",
                         f"{med * 1e3:.2f} (min {best * 1e3:.2f}, CPU {cpu * 1e3:.2f})",
                         "about 10 ms" if n_sub == 1 else ""))
            rows.append((f"{head}: ns per candidate-step", f"{ns:.1f} (CPU {ns_cpu:.1f})",
                         f"<= {TARGET_NS:.0f} ns ({met(ns_cpu <= TARGET_NS)} on CPU time)"
                         if n_sub == 1 else ""))

    # 1b. the scalar kernel (one candidate after another) on the same population
    scalar = MonitoringModel(profile=profile, n_sub=1, kernel="scalar")
    med, _, cpu = _median_time(lambda: scalar.weighted_sse(K, target, weights), reps(31, 7))
    rows.append((f"Scalar kernel (`kernel='scalar'`), N = {N_MAIN}, n_sub = 1, fitness only: "
                 "ns per candidate-step",
                 f"{ns_per(med, N_MAIN, 1):.1f} (CPU {ns_per(cpu, N_MAIN, 1):.1f}; "
                 f"{med * 1e3:.2f} ms; scalar / SIMD {cpu / main[(1, 'fitness')]:.1f} x on CPU time)",
                 ""))

    # 2. scaling with N (n_sub = 1)
    for n_pop in (1, 10, 50, 200):
        Kn = K200[:n_pop]  # (small batches against N = 50: --small-batches-only)
        r = min(101, max(3, reps(2000 // n_pop, 300 // n_pop)))
        for kind in ("fitness", "traces"):
            fn = ((lambda: mm.weighted_sse(Kn, target, weights)) if kind == "fitness"
                  else (lambda: mm.simulate_population(Kn)))
            med, _, cpu = _median_time(fn, r)
            rows.append((f"MM scaling, N = {n_pop}, n_sub = 1, {kind}: ns per candidate-step",
                         f"{ns_per(med, n_pop, 1):.1f} (CPU {ns_per(cpu, n_pop, 1):.1f}; "
                         f"{med * 1e3:.2f} ms)",
                         f"<= {TARGET_NS:.0f} ns" if kind == "fitness" else ""))

    # 3. NumPy-vectorised MM on the same population
    packed = {n_sub: pack_population(mm.params, K, n_sub=n_sub) for n_sub in (1, 2)}
    P, CP = packed[1]
    ref, load = mm.profile.theta_ref(mm.t), mm.profile.load_torque(mm.t)
    for n_sub in (1, 2):
        med, _, cpu = _median_time(
            lambda: weighted_sse_numpy(*packed[n_sub], ref, load, n_sub, target, weights),
            reps(5, 1), warmup=0 if quick else 1)
        head = f"NumPy-vectorised MM, N = {N_MAIN}, n_sub = {n_sub}, fitness only"
        rows.append((f"{head}: ms per population",
                     f"{med * 1e3:.0f} (CPU {cpu * 1e3:.0f}; "
                     f"{ns_per(cpu, N_MAIN, n_sub):.0f} ns per candidate-step on CPU time)", ""))
        rows.append((f"{head}: NumPy / Numba (CPU time)",
                     f"{cpu / main[(n_sub, 'fitness')]:.0f} x", ""))
    med, _, cpu = _median_time(lambda: simulate_population_numpy(P, CP, ref, load, 1),
                               reps(3, 1), warmup=0)
    rows.append((f"NumPy-vectorised MM, N = {N_MAIN}, n_sub = 1, with traces: ms per population",
                 f"{med * 1e3:.0f} (CPU {cpu * 1e3:.0f}; {cpu / main[(1, 'traces')]:.0f} x Numba "
                 "on CPU time)", ""))

    # 4. reference model, one trace (a mixed fault, eccentricity on: every branch runs)
    k_rm = np.array([0.25, 0.1, 0.05, 0.0, 0.0, 0.2, 0.3, 0.55])
    for pwm in (True, False):
        med, _, cpu = _median_time(
            lambda: run_reference(mm.params, k_rm, profile, n_sub=128, pwm=pwm), reps(7, 2))
        rows.append((f"RM, one trace, n_sub = 128, pwm = {pwm}: s per trace",
                     f"{med:.3f} (CPU {cpu:.3f}; {ns_per(cpu, 1, 128):.1f} ns per sub-step "
                     "on CPU time)", ""))

    # 5. compile time in fresh interpreters (NUMBA_CACHE_DIR in temporary folders)
    with tempfile.TemporaryDirectory(prefix="emaphm-numba-warm-") as warm, \
            tempfile.TemporaryDirectory(prefix="emaphm-numba-cold-") as cold_root:
        colds = [_first_call(warm)]                     # compiles and fills the warm cache
        warm_runs = [_first_call(warm) for _ in range(reps(3, 1))]
        colds += [_first_call(os.path.join(cold_root, str(i))) for i in range(reps(1, 0))]
    for label, runs, tgt in (
            ("warm on-disk cache", warm_runs,
             lambda x: f"< {TARGET_WARM_S:.0f} s ({met(x < TARGET_WARM_S)})"),
            ("empty cache (cold compile)", colds, lambda x: "")):
        r = {key: statistics.median(run_[key] for run_ in runs) for key in runs[0]}
        rows.append((f"First `weighted_sse` call (N = 50) in a fresh process, {label}: s",
                     f"{r['first']:.3f} (CPU {r['first_cpu']:.3f}; import {r['import']:.2f} s, "
                     f"whole process {r['process']:.2f} s)", tgt(r["first"])))

    # 5b. side by side with the kernel of an earlier revision
    rows += side_by_side(baseline_rev, quick)

    # 6. peak memory of one population evaluation
    for n_pop in (N_MAIN, 200):
        Kn = K200[:n_pop]
        fit = _peak_bytes(lambda: mm.weighted_sse(Kn, target, weights))
        tr = _peak_bytes(lambda: mm.simulate_population(Kn))
        rows.append((f"Peak traced memory, MM, N = {n_pop}, n_sub = 1: fitness only vs traces",
                     f"{fit / 2**10:.0f} KiB vs {tr / 2**20:.1f} MiB", ""))
    fit = _peak_bytes(lambda: weighted_sse_numpy(P, CP, ref, load, 1, target, weights))
    rows.append((f"Peak traced memory, NumPy-vectorised MM, N = {N_MAIN}, fitness only",
                 f"{fit / 2**10:.0f} KiB", ""))

    cpu, wall = (sum(x) for x in zip(*_CPU))
    note = (f"Population: N random k in [0, 1]^8 (seed {SEED}); {n_diverged} of the {N_MAIN} "
            f"leave the physical range and stop early, {n_tripped} trip on overcurrent. "
            "MM rows use the default SIMD kernel unless they say otherwise. Target currents: the nominal MM trace, "
            "unit weights. Over all timed in-process calls the process got "
            f"{100 * cpu / wall:.0f} % of its core (CPU time / wall time): where the wall time "
            "of a row is well above its CPU time, the core was shared with other work during "
            "that row, and the CPU time is the better measure of the code's speed (targets "
            "are judged on it).")
    return rows, _machine(), note


#: Population sizes of the small-batch measurement: a least-squares Jacobian of 8 or 10
#: parameters (8 to 11 candidates), a polish poll (16, 20), against N = 50.
BATCHES = (1, 8, 9, 10, 11, 16, 17, 20, 25, 50)


def small_batches(quick: bool) -> list[tuple[str, str, str]]:
    """ns per candidate-step of the fitness at small N against N = 50, interleaved (every
    size timed in turn, repeatedly), CPU time, in this process."""
    profile = diagnostic()
    mm = MonitoringModel(profile=profile)
    n_steps = mm.t.size
    K = np.random.default_rng(SEED).random((max(BATCHES), 8))
    target = mm.simulate_population(K_NOMINAL[None]).i_abc[0]
    weights = np.ones_like(target)
    for n in BATCHES:
        mm.weighted_sse(K[:n], target, weights)               # compile / warm
    cpu = {n: [] for n in BATCHES}
    for _ in range(3 if quick else 15):
        for n in BATCHES:
            reps = max(1, 100 // n)
            t = time.process_time()
            for _ in range(reps):
                mm.weighted_sse(K[:n], target, weights)
            cpu[n].append((time.process_time() - t) / reps)
    ns = {n: float(np.median(cpu[n])) / (n * n_steps) * 1e9 for n in BATCHES}
    rows = []
    for n in BATCHES:
        ratio = ns[n] / ns[N_MAIN]
        rows.append((f"Small batches, N = {n}, fitness only: ns per candidate-step (CPU), and "
                     f"against N = {N_MAIN}", f"{ns[n]:.1f} ({ratio:.2f} x)",
                     ("<= 1.5 x: " + ("met" if ratio <= 1.5 else "missed")) if 9 <= n <= 25 else ""))
    return rows


def _markdown(rows, machine, note, quick: bool, started: str) -> str:
    lines = ["## Models: speed, compile time, memory (`benchmarks/bench_models.py`)", "",
             f"Run {started} UTC{' with --quick (fewer repeats)' if quick else ''}, on one core. "
             "Default diagnostic profile (0.5 s, T_s = 125 us, 4000 control periods). "
             "ns per candidate-step = time / (N x 4000 x n_sub). Times are medians over "
             "repeats of the wall time (CPU: of the process CPU time). " + note, "",
             "| Measurement | Value | Target |", "|---|---|---|"]
    lines += [f"| {m} | {v} | {t} |" for m, v, t in rows]
    lines += ["", "Machine:", ""]
    lines += [f"- {key}: {val}" for key, val in machine.items()]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer repeats (a smoke run)")
    ap.add_argument("--out", type=Path, default=None,
                    help=f"Markdown file to write (default {RESULTS.relative_to(REPO)}; "
                         "none with --side-by-side-only)")
    ap.add_argument("--pin", type=int, default=None, metavar="CPU",
                    help="pin the process (and its subprocesses) to this CPU")
    ap.add_argument("--baseline-rev", default=BASELINE_REV, metavar="REV",
                    help=f"git revision whose kernel is timed side by side (default {BASELINE_REV})")
    ap.add_argument("--title", default=None,
                    help="heading of the Markdown file (default: the models benchmark's)")
    ap.add_argument("--side-by-side-only", action="store_true",
                    help="only the side-by-side rows (baseline vs today's kernels, pack cost)")
    ap.add_argument("--small-batches-only", action="store_true",
                    help="only the small-batch rows (N = 1..25 against 50) -> results/batches.md")
    args = ap.parse_args(argv)
    if args.small_batches_only:
        started = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M")
        load = os.getloadavg()[0]
        rows = small_batches(args.quick)
        text = _markdown(rows, _machine(), f"Only the small-batch rows (--small-batches-only), "
                         f"interleaved, CPU time; load average {load:.2f} at the start. The "
                         "kernel runs full blocks of 8 candidates in SIMD lanes and a lone "
                         "remainder alone in the scalar kernel; packing caches the winding "
                         "matrices.", args.quick, started)
        text = text.replace("## Models: speed, compile time, memory",
                            "## Models: small batches")
        out = RESULTS.parent / "batches.md"
        out.write_text(text)
        print(text)
        return 0
    if args.pin is not None:
        os.sched_setaffinity(0, {args.pin})
    started = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M")
    rows, machine, note = run(args.quick, args.baseline_rev, args.side_by_side_only)
    text = _markdown(rows, machine, note, args.quick, started)
    if args.title:
        text = text.replace("## Models: speed, compile time, memory (`benchmarks/bench_models.py`)",
                            f"## {args.title}", 1)
    out = args.out if args.out is not None or args.side_by_side_only else RESULTS
    if out is not None:
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
