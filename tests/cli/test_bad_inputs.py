"""The bad-input corpus of issue 10, generated: one case per class of malformed input to
``diagnose``, ``simulate``, ``calibrate``, ``history``, ``campaign`` and ``report``.

Every case runs the command in-process (:func:`emaphm.cli.main`) in a folder of its own
and asserts what a user must see: exit status 2, exactly one line on stderr, no
traceback, the words that name the problem; and that it changed nothing: every file in
the folder has the same bytes afterwards and no file (a temporary one included) was left.
A case that could block (a FIFO, a device) runs under an alarm: hanging fails it.

A case about permissions (a read-only file or folder) is ``unprivileged``: as root, for
whom permissions do not bite, it runs in a child process without the capabilities that
override them (``CAP_DAC_OVERRIDE``, ``CAP_DAC_READ_SEARCH``), so that it runs as root too;
as another user it runs in-process like the others.
"""

from __future__ import annotations

import ctypes
import hashlib
import json
import os
import random
import shutil
import signal
import stat
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import pytest

from emaphm.cli import main
from emaphm.simulate import simulate
from emaphm.traces import Trace, write_trace

IS_ROOT = hasattr(os, "geteuid") and os.geteuid() == 0


# ----------------------------------------------------------------------------- inputs
@dataclass(frozen=True)
class Base:
    """Valid inputs the cases start from (made once)."""

    trace: Trace              # a 0.5 s monitoring-model trace of the nominal actuator
    csv: Path
    history: Path             # a health history with EMA-1 registered
    store: Path               # a campaign store holding a spec and no run


@pytest.fixture(scope="module")
def base(tmp_path_factory) -> Base:
    from emaphm.campaign import CampaignStore
    from emaphm.campaign.spec import paper_spec, parse_algorithms, parse_scenarios
    from emaphm.prognosis.history import HealthHistory

    folder = tmp_path_factory.mktemp("base")
    trace = simulate(scenario="nominal", model="monitoring")
    csv = folder / "good.csv"
    write_trace(trace, csv)
    history = folder / "history.sqlite"
    with HealthHistory(history) as h:
        h.register("EMA-1")
    store = folder / "store.sqlite"
    spec = paper_spec(runs=1, scenarios=parse_scenarios("gain-low"),
                      algorithms=parse_algorithms("pso"))
    CampaignStore.open(store, spec).close()
    return Base(trace, csv, history, store)


def _with(trace: Trace, **changes) -> Trace:
    cols = dict(t=trace.t, theta_ref=trace.theta_ref, theta_m=trace.theta_m,
                omega_m=trace.omega_m, i_abc=trace.i_abc, meta=trace.meta)
    cols.update(changes)
    return Trace(**cols)


def _deep_csv(base: Base, path: Path, depth: int = 200_000) -> None:
    """A CSV trace whose metadata JSON is nested ``depth`` deep."""
    lines = base.csv.read_text().splitlines(keepends=True)
    lines[0] = "# emaphm-trace 1 {\"x\": " + "[" * depth + "]" * depth + "}\n"
    path.write_text("".join(lines))


def _deep_parquet(base: Base, path: Path, depth: int = 200_000) -> None:
    import pyarrow.parquet as pq

    write_trace(base.trace, path)
    table = pq.read_table(path)
    meta = dict(table.schema.metadata)
    meta[b"emaphm"] = b'{"x": ' + b"[" * depth + b"]" * depth + b"}"
    pq.write_table(table.replace_schema_metadata(meta), path)


def _profile(base: Base, path: Path, change: Callable[[dict], None]) -> None:
    meta = json.loads(json.dumps(base.trace.meta))
    change(meta["profile"])
    write_trace(base.trace.with_meta(profile=meta["profile"]), path)


def _toml(path: Path, text: str) -> None:
    path.write_text(text)


def _random_bytes(path: Path, n: int = 64 * 1024, seed: int = 0) -> None:
    path.write_bytes(random.Random(seed).randbytes(n))


def _truncated(src: Path, path: Path) -> None:
    data = src.read_bytes()
    path.write_bytes(data[: len(data) // 2])


def _read_only_folder(path: Path) -> Path:
    path.mkdir()
    path.chmod(stat.S_IRUSR | stat.S_IXUSR)
    return path


def _copy(src: Path, path: Path) -> Path:
    shutil.copyfile(src, path)
    return path


def _fifo(path: Path) -> Path:
    """A named pipe with no writer: opening it for reading blocks until one comes."""
    os.mkfifo(path)
    return path


def _link(target: str | Path, path: Path) -> Path:
    os.symlink(target, path)
    return path


def _read_only_file(path: Path) -> Path:
    path.chmod(stat.S_IRUSR)
    return path


# ----------------------------------------------------------------------------- running
class Hung(BaseException):
    """A case ran past its alarm (a BaseException: the CLI's error boundary must not turn
    it into an exit status)."""


def _drop_file_override() -> None:                  # pragma: no cover - in the child
    """preexec_fn: take the capabilities that override file permissions out of the
    bounding set, so that the command, even as root, gets them no more after exec."""
    libc = ctypes.CDLL(None, use_errno=True)
    for cap in (1, 2):                              # CAP_DAC_OVERRIDE, CAP_DAC_READ_SEARCH
        if libc.prctl(24, cap, 0, 0, 0) != 0:       # PR_CAPBSET_DROP
            os._exit(97)


def run_unprivileged(argv: list[str], cwd: Path, timeout: float = 120.0) -> tuple[int, str, str]:
    """``emaphm ARGV`` in a child process for which file permissions bite, root included
    (:func:`_drop_file_override`): ``(exit status, stdout, stderr)``; a skip where the
    platform cannot drop the capabilities."""
    code = "import sys\nfrom emaphm.cli import main\nsys.exit(main(sys.argv[1:]))"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    proc = subprocess.run([sys.executable, "-c", code, *argv], cwd=cwd, env=env, text=True,
                          capture_output=True, timeout=timeout,
                          preexec_fn=_drop_file_override if IS_ROOT else None)
    if proc.returncode == 97 and IS_ROOT:
        pytest.skip("cannot drop CAP_DAC_OVERRIDE here; run the suite as a non-root user")
    return proc.returncode, proc.stdout, proc.stderr


def _run_in_process(argv: list[str], capsys, timeout: int) -> tuple[int, str, str]:
    def alarm(signum, frame):
        raise Hung(f"the command ran past {timeout} s (blocked on a FIFO or a device?)")

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.alarm(timeout)
    try:
        rc = main(argv)
    except SystemExit as exc:                # argparse's own refusals
        rc = exc.code
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    out, err = capsys.readouterr()
    return rc, out, err


# ----------------------------------------------------------------------------- the corpus
@dataclass(frozen=True)
class Case:
    """make(folder, base) -> argv; the words the message must hold; whether file
    permissions must bite (``unprivileged``: a read-only file or folder); the seconds it
    may take before it counts as hung."""

    make: Callable[[Path, Base], list[str]]
    words: list[str]
    unprivileged: bool = False
    timeout: int = 600


CASES: dict[str, Case] = {}


def case(name: str, *words: str, unprivileged: bool = False, timeout: int = 600):
    def register(make):
        CASES[name] = Case(make, list(words), unprivileged, timeout)
        return make
    return register


# tracebacks before (exit 1) --------------------------------------------------------
@case("deep-metadata-csv", "metadata is nested too deeply")
def _(d, b):
    _deep_csv(b, d / "deep.csv")
    return ["diagnose", str(d / "deep.csv")]


@case("huge-metadata-csv", "above the 1,048,576 a trace's metadata can be")
def _(d, b):
    lines = b.csv.read_text().splitlines(keepends=True)
    lines[0] = "# emaphm-trace 1 {\"x\": \"" + "a" * 2_000_000 + "\"}\n"
    (d / "huge.csv").write_text("".join(lines))
    return ["diagnose", str(d / "huge.csv")]


@case("deep-metadata-parquet", "metadata is nested too deeply")
def _(d, b):
    _deep_parquet(b, d / "deep.parquet")
    return ["diagnose", str(d / "deep.parquet")]


@case("deep-metadata-history-add", "metadata is nested too deeply")
def _(d, b):
    _deep_csv(b, d / "deep.csv")
    return ["history", "add", "EMA-1", str(d / "deep.csv"), "--at", "10",
            "--db", str(_copy(b.history, d / "h.sqlite"))]


@case("trace-path-is-a-folder", "is a folder; give a trace file")
def _(d, b):
    (d / "trace.csv").mkdir()
    return ["diagnose", str(d / "trace.csv")]


@case("out-in-a-read-only-folder", "cannot write in the folder", "Permission denied",
      unprivileged=True)
def _(d, b):
    ro = _read_only_folder(d / "ro")
    return ["simulate", "--scenario", "nominal", "--model", "monitoring", "--out", str(ro / "x.csv")]


@case("plot-in-a-read-only-folder", "--plot: cannot write in the folder", unprivileged=True)
def _(d, b):
    ro = _read_only_folder(d / "ro")
    return ["diagnose", str(_copy(b.csv, d / "t.csv")), "--plot", str(ro / "p.png")]


@case("out-under-a-file", "is a file, not a folder")
def _(d, b):
    (d / "afile").write_text("x")
    return ["simulate", "--scenario", "nominal", "--model", "monitoring",
            "--out", str(d / "afile" / "x.csv")]


@case("plot-under-a-file", "--plot: ", "is a file, not a folder")
def _(d, b):
    (d / "afile").write_text("x")
    return ["diagnose", str(_copy(b.csv, d / "t.csv")), "--plot", str(d / "afile" / "p.png")]


@case("simulate-out-is-a-folder", "--out", "is a folder; give a file name")
def _(d, b):
    (d / "x.csv").mkdir()
    return ["simulate", "--scenario", "nominal", "--out", str(d / "x.csv")]


@case("simulate-params-is-a-folder", "p.toml is a folder; give a TOML file")
def _(d, b):
    (d / "p.toml").mkdir()
    return ["simulate", "--scenario", "nominal", "--params", str(d / "p.toml"),
            "--out", str(d / "x.csv")]


@case("f-pwm-1e9", "inverter.f_pwm [Hz] = 1e+09 is outside 500 Hz to 100 kHz")
def _(d, b):
    _toml(d / "p.toml", "[inverter]\nf_pwm = 1e9\n")
    return ["simulate", "--scenario", "nominal", "--params", str(d / "p.toml"),
            "--out", str(d / "x.csv")]


@case("history-db-of-random-bytes", "is not an emaphm health history")
def _(d, b):
    _random_bytes(d / "h.sqlite")
    return ["history", "show", "EMA-1", "--db", str(d / "h.sqlite")]


@case("history-db-truncated", "h.sqlite is damaged", "Restore it from a backup")
def _(d, b):
    _truncated(b.history, d / "h.sqlite")
    return ["history", "show", "EMA-1", "--db", str(d / "h.sqlite")]


@case("history-add-to-random-bytes", "is not an emaphm health history")
def _(d, b):
    _random_bytes(d / "h.sqlite")
    return ["history", "add", "EMA-1", str(_copy(b.csv, d / "t.csv")), "--at", "1",
            "--db", str(d / "h.sqlite")]


@case("campaign-store-truncated", "store.sqlite")
def _(d, b):
    _truncated(b.store, d / "store.sqlite")
    return ["campaign", "--store", str(d / "store.sqlite"), "--workers", "0"]


@case("campaign-store-of-random-bytes", "store.sqlite", "not an emaphm campaign store")
def _(d, b):
    _random_bytes(d / "store.sqlite")
    return ["campaign", "--store", str(d / "store.sqlite"), "--workers", "0"]


@case("campaign-dry-run-on-a-truncated-store", "store.sqlite")
def _(d, b):
    _truncated(b.store, d / "store.sqlite")
    return ["campaign", "--store", str(d / "store.sqlite"), "--dry-run"]


@case("campaign-dry-run-on-random-bytes", "not an emaphm campaign store")
def _(d, b):
    _random_bytes(d / "store.sqlite")
    return ["campaign", "--store", str(d / "store.sqlite"), "--dry-run"]


@case("report-of-a-truncated-store", "store.sqlite")
def _(d, b):
    _truncated(b.store, d / "store.sqlite")
    return ["report", str(d / "store.sqlite"), "--out", str(d / "report")]


@case("report-of-random-bytes", "not an emaphm campaign store")
def _(d, b):
    _random_bytes(d / "store.sqlite")
    return ["report", str(d / "store.sqlite"), "--out", str(d / "report")]


@case("report-out-in-a-read-only-folder", "--out: cannot write in the folder",
      unprivileged=True)
def _(d, b):
    ro = _read_only_folder(d / "ro")
    return ["report", str(_copy(b.store, d / "store.sqlite")), "--out", str(ro / "report")]


@case("report-out-under-a-file", "--out", "exists and is not a folder")
def _(d, b):
    (d / "report").write_text("x")
    return ["report", str(_copy(b.store, d / "store.sqlite")), "--out", str(d / "report")]


# a verdict on nonsense before (exit 0) ------------------------------------------------
@case("all-zero-currents", "phase current i_a is constant", "dead or disconnected")
def _(d, b):
    write_trace(_with(b.trace, i_abc=np.zeros_like(b.trace.i_abc)), d / "zeros.csv")
    return ["diagnose", str(d / "zeros.csv")]


@case("metadata-load-1e300", "profile.load[0].value = 1e+300 N m is beyond any actuator test")
def _(d, b):
    _profile(b, d / "t.csv", lambda p: p["load"].append({"shape": "Constant", "value": 1e300}))
    return ["diagnose", str(d / "t.csv")]


@case("metadata-load-beyond-the-motor", "load torque reaches 500 N m", "T_max = 18 N m")
def _(d, b):
    _profile(b, d / "t.csv", lambda p: p["load"].append({"shape": "Constant", "value": 500.0}))
    return ["diagnose", str(d / "t.csv")]


@case("toml-in-milliohm-and-millihenry", "motor.L [H] of phase a = 22 H is above 1 H",
      "22 mH = 0.022")
def _(d, b):
    _toml(d / "p.toml", "[motor]\nR = 3150\nL = 22\n")
    return ["simulate", "--scenario", "nominal", "--params", str(d / "p.toml"),
            "--out", str(d / "x.csv")]


@case("toml-in-milliohm", "is 44541 V, above inverter.V_dc = 600 V", "3.15 ohm, not 3150 milliohm")
def _(d, b):
    _toml(d / "p.toml", "[motor]\nR = 3150\n")
    return ["diagnose", str(_copy(b.csv, d / "t.csv")), "--params", str(d / "p.toml")]


# partial before: the right exit, the wrong words ---------------------------------------
@case("latin-1-csv", "not a UTF-8 text file", "export the CSV as UTF-8")
def _(d, b):
    text = b.csv.read_text().replace("emaphm-trace 1 {", "emaphm-trace 1 {\"note\": \"Pr\u00fcfstand\", ", 1)
    (d / "t.csv").write_bytes(text.encode("latin-1"))
    return ["diagnose", str(d / "t.csv")]


@case("binary-csv", "t.csv")
def _(d, b):
    _random_bytes(d / "t.csv", 4096, seed=1)
    return ["diagnose", str(d / "t.csv")]


@case("metadata-profile-abc", "profile.command[0].height: expected a number in rad, got the "
                              "string 'abc'")
def _(d, b):
    _profile(b, d / "t.csv", lambda p: p["command"][0].update(height="abc"))
    return ["diagnose", str(d / "t.csv")]


@case("metadata-profile-duration-abc", "profile.duration: expected a number in s, got the "
                                       "string 'abc'")
def _(d, b):
    _profile(b, d / "t.csv", lambda p: p.update(duration="abc"))
    return ["history", "add", "EMA-1", str(d / "t.csv"), "--at", "1",
            "--db", str(_copy(b.history, d / "h.sqlite"))]


@case("r-as-text-with-a-unit", "R [ohm]: expected a number in ohm or 3 per-phase numbers",
      "got the string '3.15 ohm'; write R = 3.15")
def _(d, b):
    _toml(d / "p.toml", '[motor]\nR = "3.15 ohm"\n')
    return ["simulate", "--scenario", "nominal", "--params", str(d / "p.toml"),
            "--out", str(d / "x.csv")]


@case("budget-negative-seconds", "--budget: budget must be positive, got '-1s'")
def _(d, b):
    return ["diagnose", str(_copy(b.csv, d / "t.csv")), "--budget", "-1s"]


@case("budget-negative-exponent", "--budget: budget must be positive, got '-1e6'")
def _(d, b):
    return ["history", "add", "EMA-1", str(_copy(b.csv, d / "t.csv")), "--at", "1",
            "--budget", "-1e6", "--db", str(_copy(b.history, d / "h.sqlite"))]


@case("budget-huge", "above 1e+08 evaluations")
def _(d, b):
    return ["diagnose", str(_copy(b.csv, d / "t.csv")), "--budget", "99999999999999999999999"]


@case("budget-beyond-a-day", "--budget: budget '100000s' is above a day (86400 s)")
def _(d, b):
    return ["diagnose", "--scenario", "nominal", "--budget", "100000s",
            "--plot", str(d / "p.png")]


@case("campaign-budget-huge", "above 1e+08 evaluations")
def _(d, b):
    return ["campaign", "--store", str(d / "s.sqlite"), "--budget", "99999999999999999999999",
            "--dry-run"]


@case("simulate-noise-1e6", "--noise 1e+06 A rms is outside 0 to 1 A")
def _(d, b):
    return ["simulate", "--scenario", "nominal", "--noise", "1e6", "--seed", "1",
            "--out", str(d / "x.csv")]


@case("campaign-noise-1e6", "--noise: expected a current noise from 0 to 1 A rms")
def _(d, b):
    return ["campaign", "--store", str(d / "s.sqlite"), "--noise", "1e6", "--dry-run"]


@case("campaign-runs-beyond-reason", "--runs: expected an integer from 1 to 10000")
def _(d, b):
    return ["campaign", "--store", str(d / "s.sqlite"), "--runs", "100000000", "--dry-run"]


@case("campaign-pop-size-beyond-reason", "pop_size 1e+08 is above 10000")
def _(d, b):
    _toml(d / "spec.toml", 'algorithms = ["pso"]\n[options.pso]\npop_size = 100000000\n')
    return ["campaign", "--spec", str(d / "spec.toml"), "--store", str(d / "s.sqlite"),
            "--dry-run"]


@case("history-spread-runs-beyond-reason", "--runs: expected an integer from 2 to 100")
def _(d, b):
    return ["history", "add", "EMA-1", str(_copy(b.csv, d / "t.csv")), "--at", "1",
            "--spread", "seeds", "--runs", "100000", "--db", str(_copy(b.history, d / "h.sqlite"))]


@case("f-pwm-10", "inverter.f_pwm [Hz] = 10 is outside 500 Hz to 100 kHz", "give hertz")
def _(d, b):
    _toml(d / "p.toml", "[inverter]\nf_pwm = 10\n")
    return ["simulate", "--scenario", "nominal", "--params", str(d / "p.toml"),
            "--out", str(d / "x.csv")]


@case("actuator-id-100-kB-register", "actuator id 'xxxxx", "(100000 characters) is longer "
                                                          "than 200 characters")
def _(d, b):
    return ["history", "register", "x" * 100_000, "--db", str(d / "h.sqlite")]


@case("actuator-id-100-kB-add", "(100000 characters) is longer than 200 characters")
def _(d, b):
    return ["history", "add", "x" * 100_000, str(_copy(b.csv, d / "t.csv")), "--at", "1",
            "--db", str(_copy(b.history, d / "h.sqlite"))]


@case("actuator-id-100-kB-prognose", "(100000 characters) is longer than 200 characters")
def _(d, b):
    return ["prognose", "x" * 100_000, "--db", str(_copy(b.history, d / "h.sqlite"))]


@case("actuator-id-too-long-for-the-store", "actuator id 'yyyy", "(150 characters) must be "
                                                                "1-64 characters")
def _(d, b):
    return ["history", "register", "y" * 150, "--db", str(_copy(b.history, d / "h.sqlite"))]


@case("dask-inproc-address", "scheme inproc:// is not supported")
def _(d, b):
    return ["campaign", "--store", str(d / "s.sqlite"), "--scheduler", "inproc://x"]


@case("unknown-scenario-100-kB", "unknown scenario 'zzzz", "(100000 characters)")
def _(d, b):
    return ["diagnose", "--scenario", "z" * 100_000]


@case("demo-unknown-scenario-100-kB", "unknown degradation scenario 'wwww", "(100000 characters)")
def _(d, b):
    return ["demo-degradation", "--scenario", "w" * 100_000, "--synthetic"]


@case("history-without-a-subcommand", "required: {register,calibrate,add,remove,show,list}",
      "see emaphm history --help")
def _(d, b):
    return ["history"]


# issue 22 and 25 (items 1, 5, 6, 9): bench imports and trace limits -----------------------
def _bench_csv(b: Base, path: Path, *, t_offset: float = 0.0, degrees: bool = False,
               rows: slice = slice(None)) -> Path:
    """A bench export of the base trace: t, ref, pos, a, b (two currents)."""
    tr = b.trace
    f = 180 / np.pi if degrees else 1.0
    data = np.column_stack([tr.t + t_offset, tr.theta_ref * f, tr.theta_m * f, tr.i_a, tr.i_b])
    lines = ["t,ref,pos,a,b"] + [",".join(repr(float(x)) for x in row) for row in data[rows]]
    path.write_text("\n".join(lines) + "\n")
    return path


_MAP = ('[channels]\nt = {name = "t", unit = "s"}\ntheta_ref = {name = "ref", unit = "rad"}\n'
        'theta_m = {name = "pos", unit = "rad"}\ni_a = {name = "a", unit = "A"}\n'
        'i_b = {name = "b", unit = "A"}\n')


def _import(d: Path, source: Path, map_text: str = _MAP) -> list[str]:
    _toml(d / "map.toml", map_text)
    return ["import", str(source), "--map", str(d / "map.toml"), "--out", str(d / "out.parquet")]


@case("import-unknown-channel", "no channel 'Pos' in bench.csv (did you mean 'pos'?)",
      "the file has 't', 'ref', 'pos', 'a', 'b'")
def _(d, b):
    return _import(d, _bench_csv(b, d / "bench.csv"), _MAP.replace('"pos"', '"Pos"'))


@case("import-unit-that-does-not-convert", "[channels] theta_m: unit 'ms' is a unit of time, "
                                           "which does not convert to the angle")
def _(d, b):
    return _import(d, _bench_csv(b, d / "bench.csv"),
                   _MAP.replace('name = "pos", unit = "rad"', 'name = "pos", unit = "ms"'))


@case("import-channels-of-different-length", "the channels have different lengths",
      "and no common time base")
def _(d, b):
    from scipy.io import savemat

    tr = b.trace
    savemat(d / "bench.mat", {"ref": tr.theta_ref, "pos": tr.theta_m, "a": tr.i_a,
                              "b": tr.i_b[:-10]})
    return _import(d, d / "bench.mat", "[time]\nrate = 8000\n" + _MAP.split("\n", 2)[0] + "\n"
                   + _MAP.split("\n", 2)[2])


@case("import-time-going-back", "the time base is not increasing: row 2,000 is at t = 0 s")
def _(d, b):
    src = _bench_csv(b, d / "bench.csv")
    lines = src.read_text().splitlines()
    lines[2001] = "0.0" + lines[2001][lines[2001].index(","):]
    src.write_text("\n".join(lines) + "\n")
    return _import(d, src)


@case("import-nan-run", "channel 'a' (i_a) has a run of 50 NaN sample(s) from t = 0.125 s")
def _(d, b):
    src = _bench_csv(b, d / "bench.csv")
    lines = src.read_text().splitlines()
    for k in range(1001, 1051):
        cells = lines[k].split(",")
        cells[3] = "nan"
        lines[k] = ",".join(cells)
    src.write_text("\n".join(lines) + "\n")
    return _import(d, src)


@case("import-window-outside-the-recording", "no samples in the window 10.0:11.0 s; the "
                                             "recording spans 0 to 0.499875 s")
def _(d, b):
    return _import(d, _bench_csv(b, d / "bench.csv")) + ["--window", "10:11"]


@case("import-window-malformed", "--window '10-11': expected START:END in seconds")
def _(d, b):
    return _import(d, _bench_csv(b, d / "bench.csv")) + ["--window", "10-11"]


@case("import-out-is-its-source", "--out", "bench.csv", "is the command's input",
      "would overwrite what is read; give another file name")
def _(d, b):
    argv = _import(d, _bench_csv(b, d / "bench.csv"))
    return argv[:-1] + [str(d / "bench.csv")]


@case("params-out-is-its-datasheet", "--out", "np.toml", "is the command's input")
def _(d, b):
    _toml(d / "np.toml", "[datasheet]\npoles = 8\n")
    return ["params", "--datasheet", str(d / "np.toml"), "--out", str(d / "np.toml")]


@case("calibrate-out-is-its-params", "--out", "p.toml", "is the command's input")
def _(d, b):
    _toml(d / "p.toml", 'name = "unit"\n')
    return ["calibrate", str(_bench_csv(b, d / "bench.csv")), "--params", str(d / "p.toml"),
            "--out", str(d / "p.toml")]


@case("import-without-a-map", "give --map MAP.toml and --out", "or --inspect")
def _(d, b):
    return ["import", str(_bench_csv(b, d / "bench.csv")), "--out", str(d / "o.csv")]


@case("csv-of-5-million-rows", "at least 2,", "rows, above the 2,000,000 samples a trace may have",
      "--window START:END")
def _(d, b):
    (d / "big.csv").write_bytes(b"t,theta_ref,theta_m,omega_m,i_a,i_b,i_c\n"
                                + b"0,0,0,0,0,0,0\n" * 5_000_000)
    return ["diagnose", str(d / "big.csv")]


@case("trace-file-above-the-size-limit", "the file is 600 MB, above the 537 MB a trace file may be")
def _(d, b):
    with open(d / "sparse.csv", "wb") as fh:                 # a sparse file: no disk used
        fh.write(b"t,theta_ref,theta_m,omega_m,i_a,i_b,i_c\n")
        fh.truncate(600_000_000)
    return ["diagnose", str(d / "sparse.csv")]


@case("decimal-comma-csv", "the numbers are written with a decimal comma (e.g. '0,0')",
      "emaphm import t.csv --inspect")
def _(d, b):
    tr = b.trace
    data = np.column_stack([tr.t, tr.theta_ref, tr.theta_m, tr.omega_m, tr.i_abc])
    lines = ["t;theta_ref;theta_m;omega_m;i_a;i_b;i_c"] + [
        ";".join(repr(float(x)).replace(".", ",") for x in row) for row in data]
    (d / "t.csv").write_text("\n".join(lines) + "\n")
    return ["diagnose", str(d / "t.csv")]


@case("an-hour-of-trace", "in seconds the trace lasts 1 h", "--window START:END",
      "in milliseconds it lasts 3.6 s")
def _(d, b):
    import pyarrow as pa
    import pyarrow.parquet as pq

    n = 1_800_001                                              # an hour at 500 Hz
    z = np.zeros(n)
    t = np.arange(n) * 2e-3
    pq.write_table(pa.table({"t": t, "theta_ref": z, "theta_m": z, "omega_m": z, "i_a": z,
                             "i_b": z, "i_c": z}), d / "hour.parquet")
    return ["diagnose", str(d / "hour.parquet")]


@case("positions-in-degrees-with-speed-in-deg-per-s", "positions look like degrees and the "
                                                       "speed like deg/s")
def _(d, b):
    tr = b.trace
    write_trace(_with(tr, theta_ref=np.degrees(tr.theta_ref), theta_m=np.degrees(tr.theta_m),
                      omega_m=np.degrees(tr.omega_m), meta={}), d / "deg.csv")
    return ["diagnose", str(d / "deg.csv")]


# issue 37 items 1-4: damaged binary exports, read in the sandbox ---------------------------
def _bench(b: Base, d: Path, fmt: str) -> tuple[Path, Path]:
    """A bench export of the base trace in ``fmt`` (tests/benchfiles.py) and its map."""
    from benchfiles import WRITERS

    write, name = WRITERS[fmt]
    path, text = write(b.trace, d / name)
    _toml(d / "map.toml", text)
    return path, d / "map.toml"


def _import_bench(d: Path, path: Path, inspect: bool) -> list[str]:
    if inspect:
        return ["import", str(path), "--inspect"]
    return ["import", str(path), "--map", str(d / "map.toml"), "--out", str(d / "out.parquet")]


def _small_mat(path: Path, compressed: bool = False) -> Path:
    from scipy.io import savemat

    savemat(path, {"a": np.arange(10.0), "b": np.ones(5)}, do_compression=compressed)
    return path


def _changed(path: Path, at: int, new: bytes) -> Path:
    data = bytearray(path.read_bytes())
    data[at:at + len(new)] = new
    path.write_bytes(bytes(data))
    return path


def _cut(path: Path, n: int) -> Path:
    path.write_bytes(path.read_bytes()[:n])
    return path


for _inspect in (False, True):
    _how = "inspect" if _inspect else "import"

    @case(f"{_how}-mat-shorter-than-its-header", "m.mat: the file is 100 bytes, shorter than the "
          "128-byte header of a MATLAB file: it is truncated or not a MATLAB file")
    def _(d, b, inspect=_inspect):
        _toml(d / "map.toml", _MAP)
        return _import_bench(d, _cut(_small_mat(d / "m.mat"), 100), inspect)

    @case(f"{_how}-mat73-header-cut-short", "bench_v73.mat: the file is truncated",
          "its HDF5 header says it ends at byte")
    def _(d, b, inspect=_inspect):
        path, _ = _bench(b, d, "mat73")
        return _import_bench(d, _cut(path, 600), inspect)

    @case(f"{_how}-mat-one-byte-changed-in-a-variable-header",    # SIGSEGV in scipy before
          "m.mat: not a readable MATLAB file: variable 1 (at byte 128): its data is of data "
          "type 246, which MATLAB does not write there; the file is damaged")
    def _(d, b, inspect=_inspect):
        _toml(d / "map.toml", _MAP)
        return _import_bench(d, _changed(_small_mat(d / "m.mat"), 176, b"\xf6"), inspect)

    @case(f"{_how}-mat-compressed-4-bytes-zeroed", "m.mat: not a readable MATLAB file: variable "
          "1 (at byte 128): its compressed data are damaged (zlib: Error -3")
    def _(d, b, inspect=_inspect):
        _toml(d / "map.toml", _MAP)
        return _import_bench(d, _changed(_small_mat(d / "m.mat", True), 150, bytes(4)), inspect)

    @case(f"{_how}-mat73-damaged-hdf5-heap", "bench_v73.mat: cannot be read as a MATLAB file, it "
          "is damaged or is not one (RuntimeError: Object visitation failed (bad local heap "
          "signature)")
    def _(d, b, inspect=_inspect):
        path, _ = _bench(b, d, "mat73")
        return _import_bench(d, _changed(path, path.read_bytes().find(b"HEAP"), b"JEAP"), inspect)

    @case(f"{_how}-mdf-data-groups-linked-in-a-loop",           # asammdf went round forever
          "bench.mf4: not a readable MDF file: the chain of its data groups links back to the "
          "one at byte")
    def _(d, b, inspect=_inspect):
        path, _ = _bench(b, d, "mdf4")
        data = path.read_bytes()
        first = data.find(b"##DG")
        second = data.find(b"##DG", first + 1)
        return _import_bench(d, _changed(path, second + 24, first.to_bytes(8, "little")), inspect)


@case("import-tdms-damaged-properties", "bench.tdms: cannot be read as a TDMS file, it is "
      "damaged or is not one (NotImplementedError: Unsupported data type to read")
def _(d, b):
    path, _ = _bench(b, d, "tdms")
    name = b"/'Motor'/'IW'"
    return _import_bench(d, _changed(path, path.read_bytes().find(name) + len(name) + 19,
                                     b"\xff" * 4), False)


@case("import-tdms-property-of-an-unknown-type", "bench.tdms: not a readable TDMS file (a value "
      "of data type code 248, which TDMS does not define); the file is damaged")
def _(d, b):                         # it said "(KeyError: 248)", no cause
    path, _ = _bench(b, d, "tdms")
    name = b"unit_string"
    return _import_bench(d, _changed(path, path.read_bytes().find(name) + len(name),
                                     (248).to_bytes(4, "little")), False)


@case("import-mat-truncated", "bench_v5.mat: the file is truncated", "variable 5 (at byte",
      "the 4 variable(s) before it are whole", "--inspect` lists what of it can be read")
def _(d, b):
    path, _ = _bench(b, d, "mat5")
    return _import_bench(d, _cut(path, int(path.stat().st_size * 0.6)), False)


@case("import-tdms-truncated", "bench.tdms: the file is truncated", "segment 1 (at byte 0) needs")
def _(d, b):
    path, _ = _bench(b, d, "tdms")
    return _import_bench(d, _cut(path, path.stat().st_size - 100), False)


# issue 37 items 5-6: absurd motors, and no trace written with a non-finite sample --------
_PLATE = ('[datasheet]\nname = "m"\npoles = 8\nke = "135 V/krpm"\nr_ll = "6.3 ohm"\n'
          'l_ll = "44 mH"\nj_rotor = "7.7 kg cm^2"\nt_max = "18 N m"\ni_max = "10 A"\n')


def _plate(d: Path, **fields: str) -> list[str]:
    text = _PLATE
    for key, value in fields.items():
        text = "\n".join(x for x in text.splitlines() if not x.startswith(f"{key} ")) + \
            f"\n{key} = {value}\n"
    _toml(d / "np.toml", text)
    return ["params", "--datasheet", str(d / "np.toml"), "--out", str(d / "p.toml")]


@case("datasheet-gear-ratio-1e200", "np.toml: [datasheet] gear_ratio: 1e+200 is beyond the gear "
                                    "ratios of actuators (0.001 to 100000")
def _(d, b):
    return _plate(d, gear_ratio="1e200", j_load='"1 kg m^2"')


@case("datasheet-poles-1e12", "[datasheet] poles: expected the number of poles, an even integer "
                              "from 2 to 200")
def _(d, b):
    return _plate(d, poles="1000000000000")


@case("datasheet-ke-1e308", "motor.c0 [V s/rad] = 7.79697e+305 is beyond what any servo actuator "
                            "has", "(from [datasheet] ke)")
def _(d, b):
    return _plate(d, ke='"1e308 V/krpm"')


@case("simulate-rotor-of-1e-30-kg-m2", "p.toml: motor.J_m [kg m^2] = 1e-30 is beyond what any "
                                       "servo actuator has (1e-09 to 100): give kg m^2")
def _(d, b):
    _toml(d / "p.toml", "[motor]\nJ_m = 1e-30\n")
    return ["simulate", "--scenario", "nominal", "--params", str(d / "p.toml"),
            "--out", str(d / "x.csv")]


@case("simulate-rotor-the-gains-do-not-fit", "speed loop gain of 750 per period (Kp_w T_s / J_m)")
def _(d, b):
    _toml(d / "p.toml", "[motor]\nJ_m = 1e-7\n")
    return ["simulate", "--scenario", "nominal", "--params", str(d / "p.toml"),
            "--out", str(d / "x.csv")]


@case("assess-grids-empty", "--grids '' names no fault grid", "leave --grids out for all")
def _(d, b):
    return ["assess", "--out", str(d / "a"), "--grids", "", "--workers", "0"]


# issue 37 partial items: values and maps that no recording has ------------------------------
_MAP_RATE = _MAP.split("\n", 2)[0] + "\n" + _MAP.split("\n", 2)[2]   # [channels] without t


@case("import-rate-of-1e-300-hz", "[time] rate = 1e-300 Hz is outside 1 Hz to 10 MHz")
def _(d, b):
    return _import(d, _bench_csv(b, d / "bench.csv"), '[time]\nrate = "1e-300 Hz"\n' + _MAP_RATE)


@case("import-start-1e308", "[time] start = 1e+308 s is beyond 1e+10 s")
def _(d, b):
    return _import(d, _bench_csv(b, d / "bench.csv"),
                   "[time]\nrate = 8000\nstart = 1e308\n" + _MAP_RATE)


@case("import-offset-1e308", "[channels] i_a.offset = 1e+308 is beyond +-1e+06")
def _(d, b):
    return _import(d, _bench_csv(b, d / "bench.csv"),
                   _MAP.replace('i_a = {name = "a", unit = "A"}',
                                'i_a = {name = "a", unit = "A", offset = 1e308}'))


@case("import-currents-of-1e298", "channel 'a' (i_a) reaches 1e+298 A at row 0, beyond the "
                                  "100000 A of any actuator's recording")
def _(d, b):
    src = _bench_csv(b, d / "bench.csv")
    lines = src.read_text().splitlines()
    lines[1:] = [",".join(c[:3] + [repr(float(c[3]) * 0 + 1e298)] + c[4:])
                 for c in (x.split(",") for x in lines[1:])]
    src.write_text("\n".join(lines) + "\n")
    return _import(d, src)


@case("import-theta-ref-of-1e300", "channel 'ref' (theta_ref) reaches 1e+300 rad")
def _(d, b):
    src = _bench_csv(b, d / "bench.csv")
    lines = src.read_text().splitlines()
    cells = lines[5].split(",")
    cells[1] = "1e300"
    lines[5] = ",".join(cells)
    src.write_text("\n".join(lines) + "\n")
    return _import(d, src)


@case("import-scale-that-overflows", "channel 'a' (i_a) reaches inf A at row")
def _(d, b):
    src = _bench_csv(b, d / "bench.csv")
    lines = src.read_text().splitlines()
    cells = lines[3].split(",")
    cells[3] = "1e305"
    lines[3] = ",".join(cells)
    src.write_text("\n".join(lines) + "\n")
    return _import(d, src, _MAP.replace('i_a = {name = "a", unit = "A"}',
                                        'i_a = {name = "a", unit = "A", scale = 1e9}'))


@case("import-theta-ref-and-theta-m-on-one-channel", "[channels] theta_ref and theta_m both "
                                                     "name channel 'pos'")
def _(d, b):
    return _import(d, _bench_csv(b, d / "bench.csv"), _MAP.replace('"ref"', '"pos"'))


@case("import-theta-m-on-the-time-channel", "[channels] t and theta_m both name channel 't'")
def _(d, b):
    return _import(d, _bench_csv(b, d / "bench.csv"),
                   _MAP.replace('theta_m = {name = "pos"', 'theta_m = {name = "t"'))


@case("import-theta-m-on-the-time-column-of-a-rate", "bench.csv: channel 't' (theta_m) rises by "
      "0.000125 rad at every sample, 1 times the time step: it is a time column")
def _(d, b):                         # t from [time] rate, theta_m on the t column: HEALTHY
    return _import(d, _bench_csv(b, d / "bench.csv"), "[time]\nrate = 8000\n"
                   + _MAP_RATE.replace('theta_m = {name = "pos"', 'theta_m = {name = "t"'))


@case("import-truncated-mdf", "bench.mf4: the file is truncated")
def _(d, b):                         # asammdf printed "Exception ignored in MDF4.__del__"
    path, _ = _bench(b, d, "mdf4")
    return _import_bench(d, _cut(path, path.stat().st_size // 2), False)


@case("history-list-of-a-campaign-store", "store.sqlite is an emaphm campaign store (emaphm "
                                          "campaign, emaphm report read it), not a health "
                                          "history; it was not changed")
def _(d, b):                         # it said "schema version 3, newer than this emaphm ..."
    return ["history", "list", "--db", str(_copy(b.store, d / "store.sqlite"))]


# issue 25 item 2 and 7: regular files only, whatever the argument -------------------------
#: the message of a FIFO, of a link to a device and of a link loop
FIFO = "is a FIFO (named pipe), not a regular file"
ZERO = "is a link to /dev/zero, a character device, not a regular file"
LOOP = "is a symbolic link loop"


@case("trace-is-a-fifo", "trace file", "t.csv " + FIFO, "give a trace file", timeout=30)
def _(d, b):
    return ["diagnose", str(_fifo(d / "t.csv"))]


@case("params-is-a-fifo", "parameter file", "p.toml " + FIFO, "give a TOML file", timeout=30)
def _(d, b):
    return ["diagnose", str(_copy(b.csv, d / "t.csv")), "--params", str(_fifo(d / "p.toml"))]


@case("history-add-trace-is-a-fifo", "t.csv " + FIFO, timeout=30)
def _(d, b):
    return ["history", "add", "EMA-1", str(_fifo(d / "t.csv")), "--at", "1",
            "--db", str(_copy(b.history, d / "h.sqlite"))]


@case("history-add-params-is-a-fifo", "p.toml " + FIFO, timeout=30)
def _(d, b):
    return ["history", "add", "EMA-1", str(_copy(b.csv, d / "t.csv")), "--at", "1",
            "--params", str(_fifo(d / "p.toml")), "--db", str(_copy(b.history, d / "h.sqlite"))]


@case("history-calibrate-trace-is-a-fifo", "t.csv " + FIFO, timeout=30)
def _(d, b):
    return ["history", "calibrate", "EMA-1", str(_fifo(d / "t.csv")), "--at", "1",
            "--db", str(_copy(b.history, d / "h.sqlite"))]


@case("calibrate-trace-links-to-dev-zero", "t.csv " + ZERO, timeout=30)
def _(d, b):
    return ["calibrate", str(_link("/dev/zero", d / "t.csv")), "--out", str(d / "cal.toml")]


@case("trace-links-to-dev-zero", "trace file", "z.parquet " + ZERO, timeout=30)
def _(d, b):
    return ["diagnose", str(_link("/dev/zero", d / "z.parquet"))]


@case("params-links-to-dev-urandom", "p.toml is a link to /dev/urandom, a character device",
      timeout=30)
def _(d, b):
    return ["simulate", "--scenario", "nominal", "--params", str(_link("/dev/urandom", d / "p.toml")),
            "--out", str(d / "x.csv")]


@case("tolerances-is-a-fifo", "tolerance file", "tol.toml " + FIFO, timeout=30)
def _(d, b):
    return ["simulate", "--scenario", "nominal", "--unit-seed", "1", "--tolerances",
            str(_fifo(d / "tol.toml")), "--out", str(d / "x.csv")]


@case("nameplate-links-to-dev-zero", "nameplate", "plate.toml " + ZERO, timeout=30)
def _(d, b):
    return ["params", "--datasheet", str(_link("/dev/zero", d / "plate.toml")),
            "--out", str(d / "p.toml")]


@case("import-source-is-a-fifo", "source", "bench.csv " + FIFO, "give the exported file",
      timeout=30)
def _(d, b):
    return _import(d, _fifo(d / "bench.csv"))


@case("import-map-is-a-fifo", "channel map", "m.toml " + FIFO, timeout=30)
def _(d, b):
    return ["import", str(_bench_csv(b, d / "bench.csv")), "--map", str(_fifo(d / "m.toml")),
            "--out", str(d / "out.parquet")]


@case("campaign-spec-is-a-fifo", "spec file", "spec.toml " + FIFO, timeout=30)
def _(d, b):
    return ["campaign", "--spec", str(_fifo(d / "spec.toml")), "--store", str(d / "s.sqlite"),
            "--dry-run"]


@case("campaign-store-links-to-dev-zero", "s.sqlite " + ZERO, timeout=30)
def _(d, b):
    return ["campaign", "--store", str(_link("/dev/zero", d / "s.sqlite")), "--dry-run"]


@case("report-of-a-fifo", "store", "s.sqlite " + FIFO, timeout=30)
def _(d, b):
    return ["report", str(_fifo(d / "s.sqlite")), "--out", str(d / "report")]


@case("history-db-is-a-fifo", "health history", "h.sqlite " + FIFO, timeout=30)
def _(d, b):
    return ["history", "show", "EMA-1", "--db", str(_fifo(d / "h.sqlite"))]


@case("history-db-links-to-dev-zero", "h.sqlite " + ZERO, timeout=30)
def _(d, b):
    return ["history", "add", "EMA-1", str(_copy(b.csv, d / "t.csv")), "--at", "1",
            "--db", str(_link("/dev/zero", d / "h.sqlite"))]


@case("trace-is-a-link-loop", "trace file", "t.csv " + LOOP, "point the link at a file")
def _(d, b):
    return ["diagnose", str(_link(d / "t.csv", d / "t.csv"))]


@case("params-is-a-link-loop", "parameter file", "p.toml " + LOOP)
def _(d, b):
    _link(d / "q.toml", d / "p.toml")
    _link(d / "p.toml", d / "q.toml")
    return ["simulate", "--scenario", "nominal", "--params", str(d / "p.toml"),
            "--out", str(d / "x.csv")]


@case("history-add-trace-is-a-link-loop", "t.csv " + LOOP)
def _(d, b):
    return ["history", "add", "EMA-1", str(_link(d / "t.csv", d / "t.csv")), "--at", "1",
            "--db", str(_copy(b.history, d / "h.sqlite"))]


@case("history-db-is-a-link-loop", "h.sqlite " + LOOP)
def _(d, b):
    return ["history", "list", "--db", str(_link(d / "h.sqlite", d / "h.sqlite"))]


@case("trace-is-a-dangling-link", "t.csv is a link to", "gone.csv, which does not exist")
def _(d, b):
    return ["diagnose", str(_link(d / "gone.csv", d / "t.csv"))]


# issue 25 item 3 and 12: stores that cannot be written, and names that are no store ----------
@case("history-add-to-a-read-only-history", "cannot write the health history",
      "h.sqlite: the file is read-only (Permission denied)", "it was not changed",
      unprivileged=True)
def _(d, b):
    db = _read_only_file(_copy(b.history, d / "h.sqlite"))
    return ["history", "add", "EMA-1", str(_copy(b.csv, d / "t.csv")), "--at", "1",
            "--db", str(db)]


@case("history-register-in-a-read-only-history", "cannot write the health history",
      "the file is read-only (Permission denied)", unprivileged=True)
def _(d, b):
    return ["history", "register", "EMA-2",
            "--db", str(_read_only_file(_copy(b.history, d / "h.sqlite")))]


@case("history-add-in-a-read-only-folder", "cannot write the health history",
      "its folder", "is not writable (Permission denied)", unprivileged=True)
def _(d, b):
    ro = d / "ro"
    ro.mkdir()
    _copy(b.history, ro / "h.sqlite")
    ro.chmod(stat.S_IRUSR | stat.S_IXUSR)
    return ["history", "add", "EMA-1", str(_copy(b.csv, d / "t.csv")), "--at", "1",
            "--db", str(ro / "h.sqlite")]


@case("history-register-new-in-a-read-only-folder", "cannot create the health history",
      "cannot write in the folder", "Permission denied", unprivileged=True)
def _(d, b):
    return ["history", "register", "EMA-2", "--db", str(_read_only_folder(d / "ro") / "h.sqlite")]


@case("fleet-demo-db-in-a-read-only-folder", "--db: cannot write in the folder",
      "Permission denied", unprivileged=True)
def _(d, b):
    return ["fleet", "demo", "--synthetic", "--actuators", "2",
            "--db", str(_read_only_folder(d / "ro") / "f.sqlite")]


@case("fleet-report-out-in-a-read-only-folder", "--out: cannot write in the folder",
      "Permission denied", unprivileged=True)
def _(d, b):
    return ["fleet", "report", "--db", str(_copy(b.history, d / "h.sqlite")),
            "--out", str(_read_only_folder(d / "ro") / "site")]


@case("campaign-in-a-read-only-store", "cannot write the campaign store",
      "the file is read-only (Permission denied)", unprivileged=True)
def _(d, b):
    return ["campaign", "--store", str(_read_only_file(_copy(b.store, d / "store.sqlite"))),
            "--workers", "0"]


@case("campaign-new-store-in-a-read-only-folder", "cannot create the campaign store",
      "in the folder", "Permission denied", unprivileged=True)
def _(d, b):                         # it said "ro/store.sqlite is damaged ... Restore it"
    return ["campaign", "--store", str(_read_only_folder(d / "ro") / "store.sqlite"),
            "--workers", "0", "--runs", "1", "--scenarios", "gain-low", "--algorithms", "pso"]


@case("simulate-profile-of-2-rows-in-1-ms", "p.csv: the command lasts 0.001 s (2 rows), shorter "
      "than the 0.0125 s a diagnosis needs (100 samples at 8 kHz)")
def _(d, b):                         # it wrote a trace of 16 samples, exit 0
    (d / "p.csv").write_text("t,theta_ref\n0,0\n0.001,0.001\n")
    return ["simulate", "--scenario", "nominal", "--model", "monitoring", "--profile",
            str(d / "p.csv"), "--out", str(d / "x.csv")]


@case("simulate-profile-that-does-not-move", "p.csv: theta_ref is 1 rad in every row: a command "
      "that does not move the actuator identifies nothing")
def _(d, b):
    (d / "p.csv").write_text("t,theta_ref\n0,1\n0.5,1\n")
    return ["simulate", "--scenario", "nominal", "--model", "monitoring", "--profile",
            str(d / "p.csv"), "--out", str(d / "x.csv")]


@case("simulate-profile-of-1.5-million-rows", "p.csv: at least 1,", "rows, above the 1,000,000 "
      "rows a profile file may hold")
def _(d, b):                         # it said "more than 1,251,286 rows, above the 2,000,000"
    rows = "".join(f"{k * 1e-5:.5f},0\n" for k in range(1_500_000))
    (d / "p.csv").write_text("t,theta_ref\n" + rows)
    return ["simulate", "--scenario", "nominal", "--model", "monitoring", "--profile",
            str(d / "p.csv"), "--out", str(d / "x.csv")]


def _absurd(d: Path, b: Base, **changes) -> list[str]:
    write_trace(_with(b.trace, **changes), d / "t.csv")
    return ["diagnose", str(d / "t.csv"), "--quiet"]


# values no unit explains are said to be absurd, not guessed a unit; no numpy warning printed
@case("trace-currents-of-1e298", "column 'i_a' reaches 1e+298 at row 10", "beyond any actuator's "
      "current, in A or in mA (1e+06): not a unit to convert, the values are not physical")
def _(d, b):                         # it said "looks like mA, not A ... divide by 1000"
    i = b.trace.i_abc.copy()
    i[10, 0] = 1e298
    return _absurd(d, b, i_abc=i)


@case("trace-time-step-of-1e296", "column 't' has a mean step of 1.25e+296", "neither seconds nor "
      "milliseconds")
def _(d, b):                         # it said "looks like milliseconds ... divide t by 1000"
    return _absurd(d, b, t=b.trace.t * 1e300)


@case("trace-starting-at-1e308", "column 't' starts at 5e+307 s, beyond the 1e+10 s (the year "
      "2286) of any clock")
def _(d, b):                         # it shifted a "clock time" to 0, then refused t[1] <= t[0]
    return _absurd(d, b, t=b.trace.t + 5e307)


@case("trace-theta-m-of-1e300", "column 'theta_m' reaches", "beyond the 1e+07 rad of any "
      "actuator's recording")
def _(d, b):                         # it was diagnosed HEALTHY
    return _absurd(d, b, theta_m=b.trace.theta_m * 1e300)


@case("trace-speed-of-1e300", "column 'omega_m' reaches 7.7", "beyond any servo motor")
def _(d, b):                         # numpy printed "RuntimeWarning: overflow encountered in dot"
    return _absurd(d, b, omega_m=b.trace.omega_m * 1e300)


def _short(d: Path, b: Base) -> Path:
    """The first 400 samples of the base trace (less than a revolution), without its profile."""
    tr, k = b.trace, slice(0, 400)
    meta = {key: v for key, v in tr.meta.items() if key != "profile"}
    return write_trace(Trace(t=tr.t[k], theta_ref=tr.theta_ref[k], theta_m=tr.theta_m[k],
                             omega_m=tr.omega_m[k], i_abc=tr.i_abc[k], meta=meta), d / "short.csv")


# advice that applies to the command that was run (it advised min_rotation=0 everywhere) -----
@case("import-shorter-than-a-revolution", "rad is below min_rotation = 6.283 rad",
      "Import a longer --window (or the whole recording), or record a longer profile")
def _(d, b):
    return _import(d, _bench_csv(b, d / "bench.csv", rows=slice(0, 400)))


@case("diagnose-shorter-than-a-revolution", "rad is below min_rotation",
      "or pass --min-rotation 0 to skip this check")
def _(d, b):
    return ["diagnose", str(_short(d, b)), "--quiet"]


@case("history-add-shorter-than-a-revolution", "rad is below min_rotation",
      "revolution. Record a longer profile (e.g. the built-in diagnostic profile, 0.5 s)")
def _(d, b):
    return ["history", "add", "EMA-1", str(_short(d, b)), "--at", "1", "--quiet", "--db",
            str(_copy(b.history, d / "h.sqlite"))]


@case("history-db-in-memory", "--db ':memory:' names SQLite's in-memory database",
      "give the path of a health history file")
def _(d, b):
    return ["history", "register", "EMA-1", "--db", ":memory:"]


@case("history-db-empty-name", "--db '' is empty", "give the path of a health history file")
def _(d, b):
    return ["history", "list", "--db", ""]


@case("history-add-db-empty-name", "--db '' is empty")
def _(d, b):
    return ["history", "add", "EMA-1", str(_copy(b.csv, d / "t.csv")), "--at", "1", "--db", ""]


@case("fleet-demo-db-in-memory", "--db ':memory:' names SQLite's in-memory database")
def _(d, b):
    return ["fleet", "demo", "--synthetic", "--db", ":memory:"]


@case("fleet-report-db-empty-name", "--db '' is empty")
def _(d, b):
    return ["fleet", "report", "--db", "", "--out", str(d / "site")]


@case("demo-degradation-db-in-memory", "--db ':memory:' names SQLite's in-memory database")
def _(d, b):
    return ["demo-degradation", "--synthetic", "--db", ":memory:"]


@case("campaign-store-in-memory", "--store ':memory:' names SQLite's in-memory database")
def _(d, b):
    return ["campaign", "--store", ":memory:", "--dry-run"]


@case("campaign-store-empty-name", "--store '' is empty")
def _(d, b):
    return ["campaign", "--store", "", "--runs", "1", "--workers", "0"]


@case("report-of-an-empty-store-name", "--store '' is empty")
def _(d, b):
    return ["report", "", "--out", str(d / "report")]


def _empty(path: Path) -> Path:
    path.write_bytes(b"")
    return path


@case("history-show-of-an-empty-file", "h.sqlite is an empty file, not a health history",
      "it was not changed")
def _(d, b):
    return ["history", "show", "EMA-1", "--db", str(_empty(d / "h.sqlite"))]


@case("history-list-of-an-empty-file", "is an empty file, not a health history")
def _(d, b):
    return ["history", "list", "--db", str(_empty(d / "h.sqlite"))]


@case("prognose-of-an-empty-file", "is an empty file, not a health history")
def _(d, b):
    return ["prognose", "EMA-1", "--db", str(_empty(d / "h.sqlite"))]


@case("fleet-report-of-an-empty-file", "is an empty file, not a health history")
def _(d, b):
    return ["fleet", "report", "--db", str(_empty(d / "h.sqlite")), "--out", str(d / "site")]


@case("history-add-to-an-empty-file", "is an empty file, not a health history")
def _(d, b):
    return ["history", "add", "EMA-1", str(_copy(b.csv, d / "t.csv")), "--at", "1",
            "--db", str(_empty(d / "h.sqlite"))]


@case("history-show-of-a-missing-file", "no health history at", "register an actuator first")
def _(d, b):
    return ["history", "show", "EMA-1", "--db", str(d / "h.sqlite")]


@case("fleet-report-of-a-missing-file", "no health history at")
def _(d, b):
    return ["fleet", "report", "--db", str(d / "h.sqlite"), "--out", str(d / "site")]


@case("prognose-of-an-empty-sqlite-database", "is an empty SQLite database, not a health "
                                              "history")
def _(d, b):
    import sqlite3

    sqlite3.connect(d / "h.sqlite").execute("PRAGMA user_version = 0").close()
    con = sqlite3.connect(d / "h.sqlite")
    con.execute("VACUUM")                          # a valid, table-less SQLite file
    con.close()
    return ["prognose", "EMA-1", "--db", str(d / "h.sqlite")]


# issue 25 item 4: times a history holds, and taking an inspection back --------------------
@case("history-add-at-1e308", "inspection time 1e+308 h is beyond the 1e+06 flight hours a "
                              "history holds")
def _(d, b):
    return ["history", "add", "EMA-1", str(_copy(b.csv, d / "t.csv")), "--at", "1e308",
            "--db", str(_copy(b.history, d / "h.sqlite"))]


@case("history-calibrate-at-1e308", "calibration time 1e+308 h is beyond")
def _(d, b):
    return ["history", "calibrate", "EMA-1", str(_copy(b.csv, d / "t.csv")), "--at", "1e308",
            "--db", str(_copy(b.history, d / "h.sqlite"))]


@case("prognose-at-1e308", "--at 1e+308 h is beyond the 1e+06 flight hours")
def _(d, b):
    return ["prognose", "EMA-1", "--at", "1e308", "--db", str(_copy(b.history, d / "h.sqlite"))]


@case("history-remove-what-is-not-there", "EMA-1 has no inspection at 7 h; nothing was removed")
def _(d, b):
    return ["history", "remove", "EMA-1", "--at", "7", "--db", str(_copy(b.history, d / "h.sqlite"))]


@case("history-remove-without-saying-which", "one of the arguments --at --id is required")
def _(d, b):
    return ["history", "remove", "EMA-1", "--db", str(_copy(b.history, d / "h.sqlite"))]


@case("history-remove-at-infinity", "--at: time must be a finite number")
def _(d, b):
    return ["history", "remove", "EMA-1", "--at", "inf", "--db", str(_copy(b.history, d / "h.sqlite"))]


# ----------------------------------------------------------------------------- the test
def _snapshot(folder: Path) -> dict[str, str]:
    """Every path under ``folder`` with the hash of its bytes (folders: "dir"; a link: its
    target, never followed; a FIFO or a device: its kind, never read)."""
    out = {}
    for root, dirs, files in os.walk(folder):
        for name in dirs + files:
            p = Path(root) / name
            rel = str(p.relative_to(folder))
            mode = os.lstat(p).st_mode
            if stat.S_ISLNK(mode):
                out[rel] = f"link to {os.readlink(p)}"
            elif stat.S_ISDIR(mode):
                out[rel] = "dir"
            elif stat.S_ISREG(mode):
                out[rel] = hashlib.sha256(p.read_bytes()).hexdigest()
            else:
                out[rel] = f"special {stat.S_IFMT(mode):o}"
    return dict(sorted(out.items()))


@pytest.mark.parametrize("name", list(CASES))
def test_bad_input_is_one_line_exit_2_and_changes_nothing(name, base, tmp_path, capsys):
    c = CASES[name]
    folder = tmp_path / "case"
    folder.mkdir()
    argv = c.make(folder, base)
    words = c.words
    before = _snapshot(folder)
    if c.unprivileged:
        rc, out, err = run_unprivileged(argv, folder, timeout=c.timeout)
    else:
        rc, out, err = _run_in_process(argv, capsys, c.timeout)
    assert rc == 2, err
    assert err.endswith("\n") and err.count("\n") == 1, f"not one line on stderr:\n{err}"
    assert err.startswith("emaphm ") and ": error: " in err
    assert "Traceback" not in err
    for w in words:
        assert w in err, f"{w!r} not in {err!r}"
    assert len(err) < 1200, "a user value was echoed whole"
    assert _snapshot(folder) == before, "an input changed or a file was left behind"
    for p in folder.rglob("*"):              # give read-only folders back to the cleanup
        if p.is_dir():
            p.chmod(stat.S_IRWXU)


def test_the_reading_commands_read_a_read_only_history_in_a_read_only_folder(tmp_path):
    """history show, history list, prognose and fleet report on a history whose file and
    folder this process cannot write (as root: without CAP_DAC_OVERRIDE): they work, and
    leave the folder as it was, no -wal or -shm file included (SQLite's mode=ro needs the
    -shm file, which a read-only folder cannot take: the file is opened immutable)."""
    from emaphm.prognosis.history import HealthHistory

    ro = tmp_path / "ro"
    ro.mkdir()
    with HealthHistory(ro / "h.sqlite") as h:
        h.register("EMA-R")
        for i, t in enumerate((10.0, 20.0, 30.0, 40.0)):
            h.add("EMA-R", t, [0.1 + 0.05 * i, 0, 0, 0, 0, 0, 0.5, 0.5])
    _read_only_file(ro / "h.sqlite")
    ro.chmod(stat.S_IRUSR | stat.S_IXUSR)
    before = _snapshot(ro)
    assert list(before) == ["h.sqlite"]
    db = ["--db", str(ro / "h.sqlite")]
    try:
        for argv in (["history", "show", "EMA-R"], ["history", "list"], ["prognose", "EMA-R"],
                     ["fleet", "report", "--out", str(tmp_path / "site"), "--workers", "0"]):
            rc, out, err = run_unprivileged(argv + db, tmp_path)
            assert rc == 0, (argv, err)
            assert "EMA-R" in out and "Traceback" not in err
            assert _snapshot(ro) == before, argv
        # a command that writes is refused in one line, before any work
        rc, _, err = run_unprivileged(["history", "register", "EMA-S"] + db, tmp_path)
        assert rc == 2 and err.count("\n") == 1 and "cannot write the health history" in err
        assert _snapshot(ro) == before
    finally:
        ro.chmod(stat.S_IRWXU)


def _warned(argv, capsys) -> str:
    """Run ``argv`` that succeeds with warnings; its stderr, which must be warning lines only."""
    assert main(argv) == 0
    err = capsys.readouterr().err
    lines = err.splitlines()
    assert lines and all(": warning: " in line for line in lines if "warning" in line)
    assert "Traceback" not in err
    return err


def test_clock_times_are_shifted_to_zero_with_one_warning_line(base, tmp_path, capsys):
    src = _bench_csv(base, tmp_path / "epoch.csv", t_offset=1.7e9)
    argv = _import(tmp_path, src) + ["--quiet"]
    # the import starts the trace at 0 itself, and keeps the clock time in its metadata
    assert main(argv) == 0
    from emaphm.traces import read_trace
    assert read_trace(tmp_path / "out.parquet").meta["source"]["t_start"] == 1.7e9
    trace = read_trace(tmp_path / "out.parquet")
    write_trace(_with(base.trace, t=base.trace.t + 1.7e9), tmp_path / "epoch_trace.csv")
    capsys.readouterr()
    err = _warned(["diagnose", str(tmp_path / "epoch_trace.csv"), "--budget", "40", "--quiet",
                   "--json"], capsys)
    assert err.count("\n") == 1 and err.startswith("emaphm diagnose: warning: ")
    assert "holds clock times (starts at 1700000000 s, a Unix time: 2023-11-14 22:13:20 UTC); " \
           "shifted to start at 0" in err
    assert "put on their uniform grid" in err
    assert trace.t[0] == 0.0


def test_an_export_shorter_than_its_profile_warns_with_both_durations(base, tmp_path, capsys):
    short = Trace(t=base.trace.t[:2400], theta_ref=base.trace.theta_ref[:2400],
                  theta_m=base.trace.theta_m[:2400], omega_m=base.trace.omega_m[:2400],
                  i_abc=base.trace.i_abc[:2400], meta=base.trace.meta)
    write_trace(short, tmp_path / "short.csv")
    err = _warned(["diagnose", str(tmp_path / "short.csv"), "--budget", "40", "--quiet",
                   "--json"], capsys)
    assert err.count("\n") == 1
    assert "the trace lasts 0.2999 s, shorter than its test profile (diagnostic, 0.5 s)" in err


def test_the_corpus_covers_every_class_of_issue_10():
    # the 14 bad and 15 partial classes, each with at least one case
    classes = ["deep-metadata-csv", "deep-metadata-parquet", "deep-metadata-history-add",
               "trace-path-is-a-folder", "out-under-a-file", "plot-under-a-file",
               "simulate-out-is-a-folder", "simulate-params-is-a-folder", "f-pwm-1e9",
               "history-db-of-random-bytes", "campaign-store-truncated",
               "campaign-store-of-random-bytes", "campaign-dry-run-on-a-truncated-store",
               "report-of-random-bytes", "report-out-under-a-file", "all-zero-currents",
               "metadata-load-1e300", "toml-in-milliohm-and-millihenry", "latin-1-csv",
               "binary-csv", "metadata-profile-abc", "r-as-text-with-a-unit",
               "budget-negative-seconds", "budget-huge", "simulate-noise-1e6", "f-pwm-10",
               "actuator-id-100-kB-add", "dask-inproc-address"]
    assert not set(classes) - set(CASES)


def test_a_simulation_that_diverges_is_not_written(base, tmp_path, capsys, monkeypatch):
    """A trace with NaN samples (a model that diverged on parameters the bounds let through)
    is refused in one line, and no file is written (issue 37: J_m = 1e-30 wrote a trace of
    NaN with exit 0)."""
    import emaphm.simulate

    t = base.trace
    diverged = _with(t, omega_m=np.where(t.t > 0.25, np.nan, t.omega_m))
    monkeypatch.setattr(emaphm.simulate, "simulate", lambda *a, **kw: diverged)
    rc = main(["simulate", "--scenario", "nominal", "--model", "monitoring",
               "--out", str(tmp_path / "x.csv")])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1, err
    assert "the simulation diverged: omega_m is NaN or infinite in 1,999 of 4,000 samples from " \
           "t = 0.250125 s" in err and "x.csv was not written" in err
    assert list(tmp_path.iterdir()) == []


def test_write_trace_refuses_a_non_finite_trace_where_asked(base, tmp_path):
    from emaphm.traces import TraceError

    bad = _with(base.trace, theta_m=np.where(base.trace.t > 0.1, np.inf, base.trace.theta_m))
    with pytest.raises(TraceError, match=r"x.parquet: not written: column theta_m holds 3,199 "
                                         r"samples that are NaN or infinite, the first at row 801"):
        write_trace(bad, tmp_path / "x.parquet", finite=True)
    assert list(tmp_path.iterdir()) == []
    write_trace(bad, tmp_path / "x.parquet")               # the library writes what it is given


def test_a_parameter_near_its_edge_is_one_warning_line(base, tmp_path, capsys):
    (tmp_path / "p.toml").write_text("[controller]\nomega_max = 20000.0\n")
    err = _warned(["simulate", "--scenario", "nominal", "--model", "monitoring", "--params",
                   str(tmp_path / "p.toml"), "--out", str(tmp_path / "x.csv")], capsys)
    warning = [x for x in err.splitlines() if ": warning: " in x]
    assert warning == [f"emaphm simulate: warning: {tmp_path / 'p.toml'}: controller.omega_max "
                       "[rad/s] = 20000 is unlike a servo actuator's (usually 1 to 10000): check "
                       "it is in rad/s: 3000 rpm = 314.16"]


# issue 37 partial items: file names that are no UTF-8, and a C locale ----------------------
def test_a_latin1_file_name_is_imported_diagnosed_and_recorded(base, tmp_path, capsys):
    """A name holding bytes that are no UTF-8 (Latin-1 'é' = 0xe9; Python holds it as a
    surrogate) was "surrogates not allowed" in import, diagnose and history add."""
    src = _bench_csv(base, tmp_path / os.fsdecode(b"b\xe9nch.csv"))
    out = tmp_path / os.fsdecode(b"tr\xe9.parquet")
    csv = write_trace(base.trace, tmp_path / os.fsdecode(b"caf\xe9.csv"))
    _toml(tmp_path / "map.toml", _MAP)
    db = ["--db", str(tmp_path / os.fsdecode(b"h\xe9.sqlite"))]
    fit = ["--budget", "30", "--quiet"]
    for argv in (["import", str(src), "--map", str(tmp_path / "map.toml"), "--out", str(out)],
                 ["import", str(out), "--inspect"],
                 ["diagnose", str(out)] + fit, ["diagnose", str(csv)] + fit,
                 ["history", "register", "EMA-1"] + db,
                 ["history", "add", "EMA-1", str(out), "--at", "1"] + db + fit,
                 ["history", "show", "EMA-1"] + db):
        rc, _, err = _run_in_process(argv, capsys, 600)
        assert rc == 0, (argv, err)
        assert "Traceback" not in err and "surrogates" not in err
    from emaphm.prognosis.history import HealthHistory

    with HealthHistory(tmp_path / os.fsdecode(b"h\xe9.sqlite"), create=False) as h:
        assert h.inspections("EMA-1")[0].source.endswith("tr\\xe9.parquet")   # its bytes, shown


def _in_c_locale(argv: list[str], cwd: Path) -> tuple[int, str, str]:
    """``emaphm ARGV`` in a child process under ``LC_ALL=C PYTHONUTF8=0``: an ASCII locale,
    in which Python holds every non-ASCII byte of a name or an argument as a surrogate."""
    code = "import sys\nfrom emaphm.cli import main\nsys.exit(main(sys.argv[1:]))"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path), "LC_ALL": "C",
           "PYTHONUTF8": "0", "PYTHONIOENCODING": ""}
    arg_bytes = [a.encode() for a in argv]
    proc = subprocess.run([sys.executable.encode(), b"-c", code.encode(), *arg_bytes], cwd=cwd,
                          env=env, capture_output=True, timeout=300)
    return (proc.returncode, proc.stdout.decode("utf-8", "replace"),
            proc.stderr.decode("utf-8", "replace"))


def test_lc_all_c_keeps_unicode_paths_and_leaves_no_empty_history(base, tmp_path):
    """Under LC_ALL=C PYTHONUTF8=0 a history named 'hé.sqlite' was written but not read
    back, a description 'vérin' failed and left an empty database, an id the history
    refuses left one too, and printing 'é' to the ASCII stdout failed."""
    db = ["--db", "hé.sqlite"]
    rc, _, err = _in_c_locale(["history", "register", "EMA-é"] + db, tmp_path)
    assert rc == 2 and err.count("\n") == 1 and "must be 1-64 characters" in err
    assert not (tmp_path / "hé.sqlite").exists(), "a refused id left a database behind"
    for argv in (["history", "register", "EMA-1", "--description", "vérin gauche"] + db,
                 ["history", "show", "EMA-1"] + db, ["history", "list"] + db,
                 ["fleet", "report", "--out", "sité", "--workers", "0", "--quiet"] + db):
        rc, out, err = _in_c_locale(argv, tmp_path)
        assert rc == 0, (argv, err)
        assert "Traceback" not in err and "surrogates" not in err
    rc, out, _ = _in_c_locale(["history", "list"] + db, tmp_path)
    assert "v\\xe9rin gauche" in out                      # the ASCII stdout escapes the 'é'
    from emaphm.prognosis.history import HealthHistory

    with HealthHistory(tmp_path / "hé.sqlite", create=False) as h:
        assert h.actuator("EMA-1").description == "vérin gauche"
    assert "hé.sqlite" in (tmp_path / "sité" / "index.html").read_text()


def test_cr_only_line_endings_read_as_any_other(base, tmp_path, capsys):
    """An old Mac export (lines ended by a lone CR) read as "no rows of numbers found": a
    bench export imports, and a trace file reads, the same as with LF endings."""
    from emaphm.traces import read_trace

    lf = _bench_csv(base, tmp_path / "lf.csv")
    cr = tmp_path / "cr.csv"
    cr.write_bytes(lf.read_bytes().replace(b"\n", b"\r"))
    _toml(tmp_path / "map.toml", _MAP)
    for src in (lf, cr):
        argv = ["import", str(src), "--map", str(tmp_path / "map.toml"), "--out",
                str(tmp_path / f"{src.stem}.parquet"), "--quiet"]
        assert _run_in_process(argv, capsys, 120)[0] == 0
    a, b = read_trace(tmp_path / "lf.parquet"), read_trace(tmp_path / "cr.parquet")
    assert np.array_equal(a.i_abc, b.i_abc) and np.array_equal(a.theta_m, b.theta_m)
    trace_lf = write_trace(base.trace, tmp_path / "t.csv")
    (tmp_path / "t_cr.csv").write_bytes(trace_lf.read_bytes().replace(b"\n", b"\r"))
    assert np.array_equal(read_trace(tmp_path / "t_cr.csv").i_abc, base.trace.i_abc)


@pytest.mark.parametrize("chunk", [1, 2, 3, 7, 1 << 16])
def test_csv_lines_end_at_lf_crlf_or_a_lone_cr_across_chunks(chunk):
    import io

    from emaphm.traces.csv_format import _raw_lines

    data = b"a\r\nbb\rccc\n\r\nd\r"
    assert list(_raw_lines(io.BytesIO(data), 100, chunk)) == [b"a\r\n", b"bb\r", b"ccc\n",
                                                              b"\r\n", b"d\r"]
    assert list(_raw_lines(io.BytesIO(b"x" * 50 + b"\n"), 10, chunk)) == [b"x" * 11]


@pytest.mark.parametrize("change", [
    lambda tr: {"omega_m": tr.omega_m * 1e300}, lambda tr: {"theta_m": tr.theta_m * 1e300},
    lambda tr: {"i_abc": tr.i_abc * 1e298}, lambda tr: {"t": tr.t * 1e300},
    lambda tr: {"t": tr.t + 5e307}])
def test_absurd_values_are_refused_without_a_numpy_warning(base, tmp_path, change):
    """numpy's RuntimeWarnings ("overflow encountered in dot") were printed before the
    refusal: under pytest they are caught, so they are made errors here."""
    import warnings

    from emaphm.traces import TraceError, read_trace

    write_trace(_with(base.trace, **change(base.trace)), tmp_path / "t.csv")
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        with pytest.raises(TraceError):
            read_trace(tmp_path / "t.csv")
