"""Another version of emaphm for a benchmark to run beside this tree: its ``src/`` taken
from git (``git archive``), to be put on ``PYTHONPATH`` of a fresh process."""

from __future__ import annotations

import subprocess
import tarfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def extract_src(rev: str, dest: Path) -> Path:
    """``src/`` of git revision ``rev`` under ``dest``; returns its path."""
    archive = dest / "src.tar"
    with open(archive, "wb") as f:
        subprocess.run(["git", "archive", rev, "src"], cwd=ROOT, stdout=f, check=True)
    with tarfile.open(archive) as t:
        t.extractall(dest, filter="data")
    return dest / "src"
