"""docs/python-api.md runs: its Python blocks, in order, in one namespace, in an empty folder."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_the_python_api_page_runs(tmp_path, monkeypatch, capsys):
    text = (ROOT / "docs" / "python-api.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert len(blocks) >= 6
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    from emaphm.batch import close_pools
    from emaphm.optim import registered, unregister

    before = set(registered())
    try:
        for i, block in enumerate(blocks):
            exec(compile(block, f"python-api.md block {i + 1}", "exec"), namespace)  # noqa: S102
    finally:                          # what the page registers is the page's, not the suite's
        for name in set(registered()) - before:
            unregister(name)
        close_pools()
    out = capsys.readouterr().out
    assert "coordinate_search" in out and "faulty" in out
    assert list(tmp_path.iterdir()) == []          # the page writes nothing where it runs
