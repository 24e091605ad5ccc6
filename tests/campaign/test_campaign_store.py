"""The campaign store (:mod:`emaphm.campaign.store`): exact round trips, exactly-once rows,
several writers, and bad input that leaves the file as it was.

Results here are synthetic (no model runs): the store is data in, data out.
"""

from __future__ import annotations

import dataclasses
import multiprocessing
import sqlite3

import numpy as np
import pytest

from emaphm import __version__
from emaphm.campaign import (CampaignStore, IncompatibleStoreError, RunResult, SpecMismatchError,
                             StoreError,
                             paper_spec, run_campaign)
from emaphm.campaign.spec import parse_scenarios
from emaphm.campaign.store import SCHEMA_VERSION


def small_spec(**kw):
    return paper_spec(runs=2, master_seed=3, scenarios=parse_scenarios("friction-low,multiple"), **kw)


def fake_result(run, status="ok", salt=0.0) -> RunResult:
    """A plausible result for ``run`` with awkward floats (they must round-trip exactly)."""
    if status != "ok":
        return RunResult.failure(run, f"RuntimeError: boom in {run.key}")
    rng = np.random.default_rng(run.seed % 2**32)
    k = tuple(float(x) for x in rng.random(8))
    hist = tuple(float(x) for x in np.sort(rng.random(7))[::-1])
    return RunResult(key=run.key, index=run.index, scenario=run.scenario, algorithm=run.algorithm,
                     optimizer=run.optimizer, run=run.run, seed=run.seed, noise_seed=run.noise_seed,
                     spawn_key=run.spawn_key, status="ok", k_true=run.k_true, k=k,
                     fitness=float(rng.random()) / 3 + salt, error_pct=float(rng.random()) * 7,
                     k_raw=k, fitness_raw=0.1 / 3, error_pct_raw=1 / 7, evaluations=5000 + run.run,
                     iterations=99, polish_evaluations=0, elapsed_s=1.234, kernel_s=1.0,
                     simulate_s=0.05, reason="stall", diverged=0, history=hist, worker="test:1",
                     finished_at="2026-01-01T00:00:00+00:00")


def dump(path) -> list[str]:
    """The whole content of a SQLite file, as SQL text (read without writing)."""
    conn = sqlite3.connect(f"file:{path}?mode=ro", uri=True)
    try:
        return list(conn.iterdump())
    finally:
        conn.close()


@pytest.fixture()
def store_path(tmp_path):
    spec = small_spec()
    path = tmp_path / "s.sqlite"
    with CampaignStore.open(path, spec) as st:
        for run in spec.runs_list()[:5]:
            st.commit(fake_result(run))
    return path


# ----------------------------------------------------------------------------- round trips
def test_results_round_trip_exactly(tmp_path):
    spec = small_spec()
    path = tmp_path / "s.sqlite"
    runs = spec.runs_list()
    written = [fake_result(r) for r in runs]
    written[3] = dataclasses.replace(written[3], fitness=float("inf"), history=(0.5, float("inf")))
    with CampaignStore.open(path, spec) as st:
        for r in reversed(written):                     # any commit order
            assert st.commit(r) is True
    with CampaignStore.open(path, readonly=True) as st:
        assert st.spec == spec and st.spec.hash == spec.hash
        assert st.results() == written                 # in run order, bit for bit
        assert st.counts() == {"ok": len(runs), "failed": 0, "total": len(runs)}
        assert st.schema_version == SCHEMA_VERSION and "schema_version" not in st.meta
        assert st.meta["emaphm_version"] == __version__
        assert st.integrity_check() == "ok"
    conn = sqlite3.connect(path)
    assert conn.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
    # one versioning style for both stores: SQLite's user_version, as the health history's
    assert conn.execute("PRAGMA user_version").fetchone()[0] == SCHEMA_VERSION
    conn.close()


def test_exactly_once_success_never_overwritten_failure_replaced(tmp_path):
    spec = small_spec()
    run_a, run_b = spec.runs_list()[:2]
    with CampaignStore.open(tmp_path / "s.sqlite", spec) as st:
        assert st.commit(fake_result(run_a)) is True
        assert st.commit(fake_result(run_a, salt=1.0)) is False          # duplicate: kept first
        assert st.commit(fake_result(run_a, status="failed")) is False   # a failure never erases
        assert st.result(run_a.key) == fake_result(run_a)
        assert st.commit(fake_result(run_b, status="failed")) is True
        assert st.keys("failed") == {run_b.key}
        assert "boom" in st.result(run_b.key).error_text
        assert st.commit(fake_result(run_b)) is True                     # a retry replaces it
        assert st.keys("failed") == set() and st.keys("ok") == {run_a.key, run_b.key}
        n, distinct = st._conn.execute("SELECT COUNT(*), COUNT(DISTINCT run_key) FROM runs").fetchone()
        assert n == distinct == 2


def _writer(path, start):
    spec = small_spec()
    runs = spec.runs_list()
    with CampaignStore.open(path, spec) as st:
        for i in range(5 * len(runs)):               # overlapping keys, many transactions
            st.commit(fake_result(runs[(start + i) % len(runs)]))


def test_two_processes_writing_one_store(tmp_path):
    """Both processes create and fill the same store at once: no error, every run once."""
    path = tmp_path / "s.sqlite"
    ctx = multiprocessing.get_context("spawn")
    procs = [ctx.Process(target=_writer, args=(str(path), s)) for s in (0, 3)]
    for p in procs:
        p.start()
    for p in procs:
        p.join(60)
        assert p.exitcode == 0
    spec = small_spec()
    with CampaignStore.open(path, spec) as st:
        assert st.integrity_check() == "ok"
        assert st.results() == [fake_result(r) for r in spec.runs_list()]


# ----------------------------------------------------------------------------- bad input, nothing destroyed
def test_other_spec_is_refused_with_the_differences(store_path):
    before = dump(store_path)
    other = dataclasses.replace(small_spec(), runs=3, master_seed=4)
    with pytest.raises(SpecMismatchError) as info:
        CampaignStore.open(store_path, other)
    msg = str(info.value)
    assert "holds a different campaign" in msg and "the store was not changed" in msg
    assert "runs: 2 -> 3" in msg and "master_seed: 3 -> 4" in msg
    assert f"emaphm campaign --store {store_path}" in msg and "another --store path" in msg
    assert info.value.differences == ["runs: 2 -> 3", "master_seed: 3 -> 4"]
    assert dump(store_path) == before


def test_same_spec_under_another_name_is_accepted(store_path):
    with CampaignStore.open(store_path, dataclasses.replace(small_spec(), name="renamed")) as st:
        assert len(st.keys()) == 5


def test_store_of_another_schema_version_is_refused(store_path):
    conn = sqlite3.connect(store_path)
    with conn:
        conn.execute("PRAGMA user_version = 999")
        conn.execute("UPDATE meta SET value = '9.9.9' WHERE key = 'emaphm_version'")
    conn.close()
    before = dump(store_path)
    for kw in ({"spec": small_spec()}, {"spec": None}, {"readonly": True}):
        with pytest.raises(IncompatibleStoreError,
                           match=r"campaign store of schema version 999 written by emaphm 9\.9\.9; "
                                 rf"this emaphm \(.*\) reads schema version {SCHEMA_VERSION}.*it was not changed"):
            CampaignStore.open(store_path, **kw)
    assert dump(store_path) == before


def _version_2_store(path):
    """``path`` turned into a store as emaphm wrote it at schema version 2: the same tables,
    its version in ``meta.schema_version`` and ``user_version`` 0."""
    conn = sqlite3.connect(path)
    with conn:
        conn.execute("PRAGMA user_version = 0")
        conn.execute("INSERT INTO meta (key, value) VALUES ('schema_version', '2')")
    conn.close()


def test_a_version_2_store_is_read_as_it_is_and_migrated_by_a_writing_open(store_path):
    _version_2_store(store_path)
    before = store_path.read_bytes()
    with CampaignStore.open(store_path, readonly=True) as st:      # reading changes nothing
        assert st.schema_version == 2 and len(st.results()) == 5
    assert store_path.read_bytes() == before
    assert not list(store_path.parent.glob("*-wal")) and not list(store_path.parent.glob("*-shm"))
    with CampaignStore.open(store_path, small_spec()) as st:          # resuming migrates it
        assert st.schema_version == SCHEMA_VERSION and "schema_version" not in st.meta
        assert len(st.keys()) == 5
        st.commit(fake_result(small_spec().runs_list()[6]))
    conn = sqlite3.connect(store_path)
    assert conn.execute("PRAGMA user_version").fetchone()[0] == SCHEMA_VERSION
    assert conn.execute("SELECT count(*) FROM meta WHERE key = 'schema_version'").fetchone()[0] == 0
    conn.close()
    with CampaignStore.open(store_path, readonly=True) as st:
        assert len(st.keys()) == 6


def test_a_version_1_store_in_the_meta_table_is_refused_unchanged(store_path):
    _version_2_store(store_path)
    conn = sqlite3.connect(store_path)
    with conn:
        conn.execute("UPDATE meta SET value = '1' WHERE key = 'schema_version'")
    conn.close()
    before = dump(store_path)
    with pytest.raises(IncompatibleStoreError, match="schema version 1 written by emaphm"):
        CampaignStore.open(store_path, small_spec())
    assert dump(store_path) == before


def test_runs_of_another_emaphm_version_are_not_mixed(store_path):
    conn = sqlite3.connect(store_path)
    with conn:
        conn.execute("UPDATE runs SET version = '0.0.1'")
    conn.close()
    before = dump(store_path)

    class Never:
        def map_unordered(self, fn, items):
            raise AssertionError("nothing may run")

    with pytest.raises(IncompatibleStoreError, match=r"holds results of emaphm 0\.0\.1; this is emaphm "
                                                     r".*--allow-version-mix.*The store was not changed"):
        run_campaign(None, store_path, Never())
    assert dump(store_path) == before


def test_foreign_files_are_refused_untouched(tmp_path):
    text = tmp_path / "notes.sqlite"
    text.write_bytes(b"my precious notes\n" * 10)
    with pytest.raises(IncompatibleStoreError, match=r"is not an emaphm campaign store \(not a SQLite "
                                                     r"database\); it was not changed"):
        CampaignStore.open(text, small_spec())
    assert text.read_bytes() == b"my precious notes\n" * 10

    other = tmp_path / "other.sqlite"
    conn = sqlite3.connect(other)
    with conn:
        conn.execute("CREATE TABLE accounts (id INTEGER, name TEXT)")
        conn.execute("INSERT INTO accounts VALUES (1, 'a')")
    conn.close()
    before = dump(other)
    with pytest.raises(IncompatibleStoreError, match=r"a SQLite database but not an emaphm campaign "
                                                     r"store \(tables: accounts\)"):
        CampaignStore.open(other, small_spec())
    assert dump(other) == before


def test_missing_store_and_folder(tmp_path):
    with pytest.raises(FileNotFoundError, match=r"no campaign store at .*nope\.sqlite"):
        CampaignStore.open(tmp_path / "nope.sqlite")
    with pytest.raises(FileNotFoundError, match=r"folder .*missing does not exist; create it first"):
        CampaignStore.open(tmp_path / "missing" / "s.sqlite", small_spec())
    assert not (tmp_path / "nope.sqlite").exists()


def test_readonly_store_refuses_writes(store_path):
    spec = small_spec()
    with CampaignStore.open(store_path, readonly=True) as st:
        with pytest.raises(StoreError, match=r"was opened read-only"):
            st.commit(fake_result(spec.runs_list()[6]))
    with CampaignStore.open(store_path) as st:
        assert len(st.keys()) == 5


def test_a_damaged_store_is_refused_unchanged_with_the_way_out(tmp_path):
    import random

    from emaphm.campaign import CampaignSpec, CampaignStore, IncompatibleStoreError

    p = tmp_path / "s.sqlite"
    spec = CampaignSpec(scenarios=("friction-low",), algorithms=("pso",), runs=2)
    with CampaignStore.open(p, spec):
        pass
    data = bytearray(p.read_bytes())
    rnd = random.Random(0)
    for i in range(200, len(data)):                      # keep the header, scramble the rest
        data[i] = rnd.randrange(256)
    p.write_bytes(bytes(data))
    before = p.read_bytes()
    for kw in ({}, {"readonly": True}):
        with pytest.raises(IncompatibleStoreError, match="damaged|cannot be read") as err:
            CampaignStore.open(p, **kw)
        assert "it was not changed" in str(err.value)
    assert p.read_bytes() == before


def test_a_file_that_is_no_store_is_refused_with_a_fix_that_fits_report_too(tmp_path):
    """`emaphm report` takes the store as its argument: the fix no longer says --store
    alone ('Give another --store path')."""
    (tmp_path / "spec.toml").write_text("runs = 2\n")
    with pytest.raises(IncompatibleStoreError, match=r"not a SQLite database\); it was not "
                                                     r"changed. Give the path of a store that "
                                                     r"emaphm campaign wrote"):
        CampaignStore.open(tmp_path / "spec.toml", readonly=True)
    assert (tmp_path / "spec.toml").read_text() == "runs = 2\n"
