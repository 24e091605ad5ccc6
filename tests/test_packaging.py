"""Packaging: the dependency floors of pyproject.toml are the versions ``.ci/lower-bounds``
installs and tests (so the two cannot drift apart), and every dependency has a floor."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

from packaging.requirements import Requirement

ROOT = Path(__file__).resolve().parents[1]


def floors() -> dict[str, str]:
    """``name -> pin`` for every dependency and test dependency: ``numpy>=2.0`` ->
    ``numpy==2.0.*`` (the floor's series, as .ci/lower-bounds installs it)."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    deps = project["dependencies"] + project["optional-dependencies"]["test"]
    out: dict[str, str] = {}
    for dep in deps:
        r = Requirement(dep)
        lower = [s.version for s in r.specifier if s.operator == ">="]
        assert len(lower) == 1, f"{dep}: every dependency needs one floor (>=)"
        extras = f"[{','.join(sorted(r.extras))}]" if r.extras else ""
        out[r.name] = f"{r.name}{extras}=={lower[0]}.*"
    return out


def script_array(name: str) -> list[str]:
    text = (ROOT / ".ci" / "lower-bounds").read_text(encoding="utf-8")
    m = re.search(rf"^{name}=\((.*?)\)", text, flags=re.S | re.M)
    assert m, f".ci/lower-bounds has no {name}=( ... )"
    body = "\n".join(line.split("#", 1)[0] for line in m.group(1).splitlines())
    return [w.strip('"') for w in body.split()]


def test_the_lower_bounds_script_pins_pyprojects_floors():
    want = floors()
    unpinned = script_array("UNPINNED")
    assert set(unpinned) <= set(want), unpinned
    assert sorted(script_array("PINS")) == sorted(v for k, v in want.items() if k not in unpinned)


def test_extras_share_one_floor():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    seen: dict[str, str] = {}
    for dep in project["dependencies"] + sum(project["optional-dependencies"].values(), []):
        r = Requirement(dep)
        assert seen.setdefault(r.name, str(r.specifier)) == str(r.specifier), dep


def test_the_lower_bounds_smoke_set_names_test_files_that_exist():
    smoke = script_array("SMOKE")
    assert len(smoke) >= 8
    missing = [p for p in smoke if not (ROOT / p).is_file()]
    assert missing == [], f".ci/lower-bounds SMOKE names files that do not exist: {missing}"
