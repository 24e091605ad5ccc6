"""The kernel cache's folders (:mod:`emaphm.models._jit`): one per digest of the model
sources, and the stale ones pruned: the current one and the most recently used other one
kept, and any used within the hour; nothing but ``kernels-<16 hex>`` folders directly in
the cache's root is ever touched; two processes pruning at once do not trip over each
other."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time
from pathlib import Path

from emaphm.models import _jit
from emaphm.models._jit import MIN_AGE_S, prune_stale

NOW = 1.9e9
CURRENT = "c" * 16
HOUR = 3600.0


def kernels(root: Path, digest: str, age_s: float, now: float = NOW) -> Path:
    """A cache folder of ``digest`` with an index file, last used ``age_s`` before ``now``."""
    folder = root / f"kernels-{digest}"
    folder.mkdir()
    (folder / "monitoring._kernel-232.py311.nbi").write_bytes(b"index")
    for path in (folder / "monitoring._kernel-232.py311.nbi", folder):
        os.utime(path, (now - age_s, now - age_s))
    return folder


def names(root: Path) -> set[str]:
    return {p.name for p in root.iterdir()}


def test_prune_keeps_the_current_the_newest_other_and_the_recently_used(tmp_path):
    kernels(tmp_path, CURRENT, 30 * 24 * HOUR)                  # current: kept however old
    kernels(tmp_path, "1" * 16, 2 * HOUR)                      # the newest other: kept
    kernels(tmp_path, "3" * 16, 5 * HOUR)                      # stale
    kernels(tmp_path, "4" * 16, 9 * 24 * HOUR)                 # stale
    removed = prune_stale(tmp_path, CURRENT, now=NOW)
    assert sorted(removed) == [f"kernels-{'3' * 16}", f"kernels-{'4' * 16}"]
    assert names(tmp_path) == {f"kernels-{d * 16}" for d in "c1"}
    assert prune_stale(tmp_path, CURRENT, now=NOW) == []
    # used within the hour: kept even when no other is to be kept (another version runs)
    kernels(tmp_path, "2" * 16, 0.5 * HOUR)
    assert prune_stale(tmp_path, CURRENT, keep_others=0, now=NOW) == [f"kernels-{'1' * 16}"]
    assert names(tmp_path) == {f"kernels-{d * 16}" for d in "c2"}


def test_prune_counts_a_folder_as_used_when_numba_wrote_into_it(tmp_path):
    """Numba rewrites its files in place (the folder's own time does not move): the newest
    time of the folder and its files is when it was last used."""
    old = kernels(tmp_path, "5" * 16, 10 * HOUR)
    kernels(tmp_path, "6" * 16, 8 * HOUR)
    os.utime(old / "monitoring._kernel-232.py311.nbi", (NOW - 60, NOW - 60))
    assert prune_stale(tmp_path, CURRENT, keep_others=0, now=NOW) == [f"kernels-{'6' * 16}"]


def test_prune_touches_nothing_but_kernel_folders_of_the_root(tmp_path):
    root = tmp_path / "cache"
    root.mkdir()
    outside = tmp_path / "elsewhere"
    outside.mkdir()
    (outside / "precious.txt").write_text("keep")
    (root / f"kernels-{'7' * 16}").symlink_to(outside, target_is_directory=True)
    (root / f"kernels-{'8' * 16}").write_text("a file, not a cache")
    (root / "kernels-not-a-digest").mkdir()
    (root / f"kernels-{'9' * 16}-copy").mkdir()
    (root / "notes").mkdir()
    inner = root / "notes" / f"kernels-{'a' * 16}"          # not directly in the root
    inner.mkdir()
    kernels(root, "b" * 16, 30 * 24 * HOUR)
    for p in [*root.iterdir(), inner]:
        os.utime(p, (NOW - 99 * HOUR, NOW - 99 * HOUR), follow_symlinks=False)
    before = names(root)
    assert prune_stale(root, CURRENT, keep_others=0, now=NOW) == [f"kernels-{'b' * 16}"]
    assert names(root) == before - {f"kernels-{'b' * 16}"}
    assert (outside / "precious.txt").read_text() == "keep" and inner.is_dir()
    assert prune_stale(tmp_path / "no-such-root", CURRENT) == []


def test_concurrent_prunes_remove_each_folder_once_and_raise_nothing(tmp_path):
    for d in "0123456789":
        kernels(tmp_path, d * 16, 50 * HOUR)
    results, errors = [], []

    def prune():
        try:
            results.append(prune_stale(tmp_path, CURRENT, keep_others=0, now=NOW))
        except Exception as exc:              # noqa: BLE001  (the test's point)
            errors.append(exc)

    threads = [threading.Thread(target=prune) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == []
    removed = sorted(sum(results, []))
    assert removed == sorted(f"kernels-{d * 16}" for d in "0123456789")   # each once
    assert names(tmp_path) == set()


def test_a_removal_left_half_done_is_finished_later(tmp_path):
    doomed = tmp_path / f".stale-kernels-{'d' * 16}-12345"
    doomed.mkdir()
    (doomed / "x.nbc").write_bytes(b"")
    (tmp_path / ".stale-something-else").mkdir()
    prune_stale(tmp_path, CURRENT, now=NOW)
    assert names(tmp_path) == {".stale-something-else"}


def test_importing_the_kernels_prunes_their_cache_root(tmp_path):
    """A process that declares the kernels prunes the root of its cache: a stale folder
    goes, the newest other stays."""
    now = time.time()
    kernels(tmp_path, "e" * 16, 3 * MIN_AGE_S, now)
    kernels(tmp_path, "f" * 16, 2 * MIN_AGE_S, now)
    env = {**os.environ, "EMAPHM_CACHE_DIR": str(tmp_path)}
    out = subprocess.run([sys.executable, "-c", "from emaphm.models import _jit; "
                          "print(_jit.CACHE_DIR.name)"], env=env, check=True,
                         capture_output=True, text=True).stdout.strip()
    assert out == f"kernels-{_jit.SOURCES_DIGEST}"
    assert names(tmp_path) == {out, f"kernels-{'f' * 16}"}
