"""Running campaigns (:mod:`emaphm.campaign.runner`): resume after SIGKILL, Ctrl-C, failures
as values, replay, progress, and the ``emaphm campaign`` command.

The real-model tests use a small campaign (2 scenarios x 2 algorithms x 4 runs, 600
evaluations per run, a quarter to half a second each) so the file stays under half a
minute on two cores.
"""

from __future__ import annotations

import io
import json
import os
import signal
import sqlite3
import subprocess
import sys
import time

import pytest
from support import assert_same_outcome, outcomes, small_spec

from emaphm.campaign import (CampaignInterrupted, CampaignStore, LocalExecutor, ProgressLine, RunResult,
                             SerialExecutor, execute_run, replay, run_campaign)
from emaphm.campaign.spec import parse_algorithms, parse_scenarios
from emaphm.cli import main

SPEC_TOML = """
name = "small"
runs = 4
master_seed = 7
budget = 600
scenarios = ["friction-high", "multiple"]
algorithms = ["pso", "de"]
"""


N = 16      # runs of the small campaign


def row_counts(path) -> tuple[int, int]:
    conn = sqlite3.connect(f"file:{path}?mode=ro", uri=True)
    try:
        return conn.execute("SELECT COUNT(*), COUNT(DISTINCT run_key) FROM runs").fetchone()
    finally:
        conn.close()


def ok_rows(path) -> int:
    try:
        conn = sqlite3.connect(f"file:{path}?mode=ro", uri=True, timeout=5)
        try:
            return conn.execute("SELECT COUNT(*) FROM runs WHERE status = 'ok'").fetchone()[0]
        finally:
            conn.close()
    except sqlite3.Error:
        return 0                                        # not created yet


def start_cli(args, tmp_path) -> subprocess.Popen:
    """``python -m emaphm.cli ARGS`` in its own session (so its workers can be reaped)."""
    return subprocess.Popen([sys.executable, "-m", "emaphm.cli", *args], cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)


def wait_rows(proc, path, n, timeout=90.0) -> int:
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        got = ok_rows(path)
        if got >= n:
            return got
        if proc.poll() is not None:
            pytest.fail(f"campaign exited early ({proc.returncode}): {proc.stderr.read()}")
        time.sleep(0.02)
    pytest.fail(f"no {n} runs stored after {timeout} s")


#: ``emaphm campaign`` whose store signals right after its ``AFTER``-th committed run:
#: Ctrl-C (SIGINT to the whole process group, as a terminal does) or SIGKILL to the campaign
#: process alone. The signal lands mid-campaign however fast the runs are, instead of
#: racing a poll of the store.
SIGNAL_AFTER_COMMITS = """
import os, signal, sys
from emaphm.campaign.store import CampaignStore
from emaphm.cli import main

AFTER, HOW = int(sys.argv[1]), sys.argv[2]
commit, done = CampaignStore.commit, []
# Ctrl-C as in a terminal: a test run from a background job inherits SIGINT ignored
signal.signal(signal.SIGINT, signal.default_int_handler)

def commit_then_signal(self, result):
    written = commit(self, result)
    done.append(result.key)
    if len(done) == AFTER:
        if HOW == "ctrl-c":
            os.killpg(os.getpgrp(), signal.SIGINT)
        else:
            os.kill(os.getpid(), signal.SIGKILL)
    return written

CampaignStore.commit = commit_then_signal
sys.exit(main(sys.argv[3:]))
"""


def start_cli_signalling(args, tmp_path, after: int, how: str) -> subprocess.Popen:
    """:func:`start_cli` that sends ``how`` ("ctrl-c" or "kill") after ``after`` commits."""
    return subprocess.Popen([sys.executable, "-c", SIGNAL_AFTER_COMMITS, str(after), how, *args],
                            cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)


def reap(proc) -> None:
    """Kill what is left of the process group we started (orphaned pool workers)."""
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The small campaign, uninterrupted, in this process (serial executor)."""
    path = tmp_path_factory.mktemp("reference") / "ref.sqlite"
    summary = run_campaign(small_spec(), path, SerialExecutor())
    assert summary.finished and summary.completed == N and summary.failed == 0
    return path


# ----------------------------------------------------------------------------- resume after SIGKILL
def test_sigkill_then_resume_gives_the_uninterrupted_results(tmp_path, reference):
    spec_file = tmp_path / "small.toml"
    spec_file.write_text(SPEC_TOML)
    store = tmp_path / "killed.sqlite"
    proc = start_cli_signalling(["campaign", "--spec", str(spec_file), "--store", str(store),
                                 "--workers", "2", "--quiet"], tmp_path, 2, "kill")
    try:
        _, err = proc.communicate(timeout=120)           # killed after its 2nd stored run
    finally:
        reap(proc)
    assert proc.returncode == -signal.SIGKILL, err
    n_killed, distinct = row_counts(store)
    assert n_killed == distinct == 2
    with CampaignStore.open(store, readonly=True) as st:
        assert st.integrity_check() == "ok"

    # resume with the same spec, on a local pool this time
    summary = run_campaign(small_spec(), store, LocalExecutor(2))
    assert summary.skipped == n_killed and summary.completed == N - n_killed
    assert summary.finished and summary.failed == 0
    assert row_counts(store) == (N, N)                  # every run exactly once
    got, want = outcomes(store), outcomes(reference)
    assert got.keys() == want.keys()
    for key in want:                                    # k, fitness, evaluations, seeds, history...
        assert_same_outcome(got[key], want[key], key)
    # a third call has nothing left to do
    again = run_campaign(None, store, SerialExecutor())
    assert again.skipped == N and again.completed == 0 and again.finished


# ----------------------------------------------------------------------------- Ctrl-C
def test_ctrl_c_stops_cleanly_keeps_runs_and_says_how_to_resume(tmp_path):
    store = tmp_path / "int.sqlite"
    args = ["campaign", "--scenarios", "gain-high", "--algorithms", "pso", "--runs", "8",
            "--budget", "600", "--store", str(store), "--workers", "2"]
    proc = start_cli_signalling(args, tmp_path, 1, "ctrl-c")
    try:
        _, err = proc.communicate(timeout=120)
    finally:
        reap(proc)
    assert proc.returncode == 130, err
    assert "interrupted;" in err and "Run the same command again to resume" in err
    assert "Traceback" not in err
    assert row_counts(store) == (1, 1)                  # the run committed before the Ctrl-C
    with CampaignStore.open(store, readonly=True) as st:
        assert st.integrity_check() == "ok" and st.keys("failed") == set()


class _FakeExecutor:
    """Yields canned values, then raises KeyboardInterrupt; records that it was closed."""

    def __init__(self, values, interrupt_after=None):
        self.values, self.interrupt_after, self.closed = values, interrupt_after, False

    def map_unordered(self, fn, items):
        try:
            for i, item in enumerate(items):
                if i == self.interrupt_after:
                    raise KeyboardInterrupt
                yield item, self.values(item)
        finally:
            self.closed = True


def _ok(run):
    return RunResult(key=run.key, index=run.index, scenario=run.scenario, algorithm=run.algorithm,
                     optimizer=run.optimizer, run=run.run, seed=run.seed, noise_seed=run.noise_seed,
                     spawn_key=run.spawn_key, status="ok", k_true=run.k_true, k=run.k_true, fitness=0.0,
                     error_pct=0.0, evaluations=1, iterations=1, elapsed_s=0.1, history=(0.0,))


def test_keyboard_interrupt_keeps_committed_runs(tmp_path):
    ex = _FakeExecutor(_ok, interrupt_after=5)
    with pytest.raises(CampaignInterrupted) as info:
        run_campaign(small_spec(), tmp_path / "s.sqlite", ex)
    s = info.value.summary
    assert isinstance(info.value, KeyboardInterrupt) and ex.closed
    assert s.interrupted and s.completed == 5 and s.missing == N - 5 and not s.finished
    assert row_counts(tmp_path / "s.sqlite") == (5, 5)


# ----------------------------------------------------------------------------- failures are values
def test_failing_runs_are_recorded_counted_and_retried(tmp_path, monkeypatch):
    import emaphm.identify

    spec = small_spec(scenarios=parse_scenarios("friction-high"), algorithms=parse_algorithms("pso"),
                      runs=2, budget=300)
    bad_seed = spec.runs_list()[0].seed
    real = emaphm.identify.identify

    def flaky(trace, algorithm, *, seed, **kw):
        if seed == bad_seed:
            raise RuntimeError("numerical trouble")
        return real(trace, algorithm, seed=seed, **kw)

    monkeypatch.setattr(emaphm.identify, "identify", flaky)
    path = tmp_path / "s.sqlite"
    first = run_campaign(spec, path, SerialExecutor())
    assert (first.completed, first.failed, first.missing) == (1, 1, 1) and not first.finished
    with CampaignStore.open(path, readonly=True) as st:
        failed = st.result(spec.runs_list()[0].key)
        assert failed.status == "failed" and failed.k is None
        assert "RuntimeError: numerical trouble" in failed.error_text
    monkeypatch.setattr(emaphm.identify, "identify", real)
    second = run_campaign(spec, path, SerialExecutor())           # a rerun retries the failure
    assert (second.skipped, second.completed, second.failed) == (1, 1, 0) and second.finished
    assert row_counts(path) == (2, 2)


def test_an_executor_error_becomes_a_failure_row(tmp_path):
    spec = small_spec(runs=1)                                     # 4 runs
    summary = run_campaign(spec, tmp_path / "s.sqlite",
                           _FakeExecutor(lambda run: OSError("worker lost")))
    assert summary.failed == 4 and summary.completed == 0 and summary.missing == 4
    with CampaignStore.open(tmp_path / "s.sqlite", readonly=True) as st:
        assert all(r.error_text == "OSError: worker lost" for r in st.results(status="failed"))


def test_execute_run_never_raises():
    spec = small_spec(runs=1)
    run = spec.runs_list()[0]
    import dataclasses

    broken = dataclasses.replace(run, k_true=(2.0,) * 8)
    r = execute_run(broken)
    assert r.status == "failed" and "k1 (friction) = 2 is outside [0, 1]" in r.error_text


# ----------------------------------------------------------------------------- replay
def test_replay_one_run_alone_gives_the_stored_result(reference, capsys):
    key = "multiple/de/3"
    stored, fresh = replay(reference, key)
    assert stored.outcome() == fresh.outcome()
    assert fresh.seed == stored.seed and fresh.spawn_key == (1, 1, 1, 3)
    assert main(["campaign", "--store", str(reference), "--replay", "friction-high/pso/0"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["identical"] is True and out["stored"]["k"] == out["replayed"]["k"]


# ----------------------------------------------------------------------------- progress
def test_progress_line_non_tty_prints_about_every_tenth():
    buf = io.StringIO()
    p = ProgressLine(buf, tty=False)
    runs = small_spec(runs=10).runs_list()
    p.start(len(runs), 0, len(runs))
    for r in runs:
        p.update(_ok(r) if r.run != 3 else RunResult.failure(r, "x"))
    p.close()
    lines = buf.getvalue().splitlines()
    assert 10 <= len(lines) <= 12
    assert lines[-1].startswith("runs 36/40 (90%)  failures 4  elapsed ") and lines[-1].endswith("ETA 0s")


def test_progress_line_tty_rewrites_one_line():
    buf = io.StringIO()
    p = ProgressLine(buf, tty=True)
    runs = small_spec().runs_list()
    p.start(16, 8, 8)
    for r in runs[:8]:
        p.update(_ok(r))
    p.close()
    text = buf.getvalue()
    assert text.count("\n") == 1 and text.startswith("\rruns 8/16") and "runs 16/16 (100%)" in text


# ----------------------------------------------------------------------------- the command
def _listing(folder):
    return sorted(p.name for p in folder.rglob("*"))


def test_cli_refuses_a_changed_spec_and_leaves_the_store(reference, capsys):
    before = outcomes(reference)
    rc = main(["campaign", "--store", str(reference), "--scenarios", "friction-high,multiple",
               "--algorithms", "pso,de", "--runs", "5", "--seed", "7", "--budget", "600"])
    err = capsys.readouterr().err
    assert rc == 2 and "holds a different campaign" in err and "runs: 4 -> 5" in err
    assert outcomes(reference) == before


@pytest.mark.parametrize("argv, match", [
    (["--algorithms", "pso,sa"], "unknown algorithm 'sa'; choose one of cmaes, de, gwo, lsq, pso, scipy-de"),
    (["--scenarios", "gain"], "unknown scenario 'gain'"),
    (["--workers", "2", "--scheduler", "tcp://localhost:1"], "give either --workers"),
    (["--budget", "lots"], "budget 'lots' not understood"),
    (["--spec", "nowhere.toml"], "spec file nowhere.toml does not exist"),
])
def test_cli_bad_input_exits_2_and_writes_nothing(tmp_path, capsys, argv, match):
    before = _listing(tmp_path)
    rc = main(["campaign", "--store", str(tmp_path / "s.sqlite"), *argv])
    err = capsys.readouterr().err
    assert rc == 2 and match in err and "Traceback" not in err
    assert _listing(tmp_path) == before


def test_cli_dry_run_lists_runs_and_seeds(tmp_path, capsys):
    assert main(["campaign", "--store", str(tmp_path / "s.sqlite"), "--scenarios", "gain-low",
                 "--algorithms", "pso,cmaes", "--runs", "2", "--dry-run"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert [line.split("\t")[0] for line in out] == ["gain-low/pso/0", "gain-low/pso/1",
                                                     "gain-low/cmaes/0", "gain-low/cmaes/1"]
    assert not (tmp_path / "s.sqlite").exists()


def test_cli_dry_run_on_a_store_refuses_a_campaign_it_does_not_hold(tmp_path, capsys):
    """--dry-run with options on an existing store lists what a run would do, and so
    refuses what a run refuses (it listed the paper's 198 runs for a store of 2)."""
    import dataclasses

    from emaphm.campaign import CampaignStore
    from emaphm.campaign.spec import CampaignSpec, parse_algorithms, parse_scenarios

    store = tmp_path / "s.sqlite"
    spec = dataclasses.replace(CampaignSpec(), scenarios=parse_scenarios("gain-low"),
                               algorithms=parse_algorithms("pso"), runs=2)
    with CampaignStore.open(store, spec):
        pass
    before = store.read_bytes()
    assert main(["campaign", "--store", str(store), "--runs", "6", "--dry-run"]) == 2
    assert "holds a different campaign" in capsys.readouterr().err
    assert main(["campaign", "--store", str(store), "--dry-run"]) == 0
    assert len(capsys.readouterr().out.splitlines()) == 2
    assert store.read_bytes() == before
    # an empty file (mktemp's) or an empty database: a run fills it, a dry run lists its runs
    (tmp_path / "empty.sqlite").touch()
    import sqlite3

    con = sqlite3.connect(tmp_path / "blank.sqlite")
    con.execute("PRAGMA user_version = 1")           # a database of one page, no table
    con.commit()
    con.close()
    assert (tmp_path / "blank.sqlite").stat().st_size > 0
    for name in ("empty.sqlite", "blank.sqlite"):
        assert main(["campaign", "--store", str(tmp_path / name), "--scenarios", "gain-low",
                     "--algorithms", "pso", "--runs", "2", "--dry-run"]) == 0, name
        assert len(capsys.readouterr().out.splitlines()) == 2


def _die_on_one(x):
    """A run whose worker process dies (as an OOM kill or a segfault would)."""
    if x == 1:
        os._exit(3)
    return x * 10


def test_a_dead_worker_fails_its_runs_and_the_campaign_goes_on():
    from concurrent.futures.process import BrokenProcessPool

    from emaphm.campaign.executors import LocalExecutor

    out = dict(LocalExecutor(1).map_unordered(_die_on_one, range(6)))
    assert sorted(out) == list(range(6))                      # every item comes back once
    assert isinstance(out[1], BrokenProcessPool)
    done = [x for x, v in out.items() if not isinstance(v, Exception)]
    assert {3, 4, 5} <= set(done)                             # a new pool ran the rest
    assert all(out[x] == 10 * x for x in done)


def test_an_unreachable_scheduler_fails_before_the_store_is_written(tmp_path, monkeypatch):
    from emaphm.campaign.executors import DaskExecutor
    from emaphm.cli import main

    def refuse(self):
        raise ValueError(f"cannot reach the Dask scheduler at {self.scheduler}")

    monkeypatch.setattr(DaskExecutor, "check", refuse)
    store = tmp_path / "x.sqlite"
    rc = main(["campaign", "--scenarios", "friction-low", "--algorithms", "pso", "--runs", "1",
               "--store", str(store), "--scheduler", "tcp://127.0.0.1:1", "--quiet"])
    assert rc == 2 and not store.exists()


# ----------------------------------------------------------------------------- no orphans
def _processes_with(marker: str) -> list[int]:
    """Pids of the live processes whose environment carries ``marker`` (Linux /proc)."""
    out = []
    for d in os.listdir("/proc"):
        if not d.isdigit():
            continue
        try:
            with open(f"/proc/{d}/environ", "rb") as fh:
                env = fh.read()
            with open(f"/proc/{d}/stat") as fh:
                state = fh.read().rsplit(")", 1)[1].split()[0]
        except OSError:
            continue
        if marker.encode() in env and state != "Z":
            out.append(int(d))
    return out


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_a_killed_campaign_takes_its_workers_with_it(tmp_path):
    import uuid

    spec_file = tmp_path / "small.toml"
    spec_file.write_text(SPEC_TOML)
    store = tmp_path / "orphans.sqlite"
    marker = f"EMAPHM_ORPHAN_CHECK=1-{uuid.uuid4().hex}"
    key, value = marker.split("=", 1)
    proc = subprocess.Popen([sys.executable, "-m", "emaphm.cli", "campaign", "--spec",
                             str(spec_file), "--store", str(store), "--workers", "2", "--quiet"],
                            cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            text=True, start_new_session=True, env={**os.environ, key: value})
    try:
        wait_rows(proc, store, 1)
        assert len(_processes_with(marker)) >= 3            # the campaign and its 2 workers
        os.kill(proc.pid, signal.SIGKILL)                   # no handler of the parent runs
        proc.wait(30)
        t0 = time.monotonic()
        while _processes_with(marker) and time.monotonic() - t0 < 5.0:
            time.sleep(0.1)
        left = _processes_with(marker)
    finally:
        reap(proc)
    assert left == [], f"processes of the killed campaign still alive 5 s later: {left}"


def test_a_run_of_the_default_pipeline_is_executed_and_stored():
    spec = small_spec(runs=1)
    run = spec.runs_list()[0]
    import dataclasses

    from emaphm.identify import IdentificationConfig

    r = execute_run(dataclasses.replace(run, config=IdentificationConfig("lsq")))
    assert r.status == "ok", r.error_text
    assert r.optimizer == "lsq" and 0 < r.evaluations < 2000 and r.error_pct < 5.0
