"""Every script in ``examples/`` runs, with its short settings (``--quick``)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = sorted((ROOT / "examples").glob("*.py"))


def test_there_are_examples():
    assert any(p.name == "own_optimizer.py" for p in EXAMPLES)


@pytest.mark.parametrize("path", [p for p in EXAMPLES if p.name == "own_optimizer.py"],
                         ids=lambda p: p.name)
def test_the_own_optimizer_example_runs(path, tmp_path):
    r = subprocess.run([sys.executable, str(path), "--quick"], capture_output=True, text=True,
                       cwd=tmp_path, timeout=600)
    assert r.returncode == 0, r.stderr
    lines = r.stdout.strip().splitlines()
    assert [ln.split(":")[0] for ln in lines] == ["random-search", "coordinate_search"]
    assert "faulty: dry friction" in lines[1]          # the coordinate search finds it
    assert list(tmp_path.iterdir()) == []              # it writes nothing
