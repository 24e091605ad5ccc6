"""Packaging: the dependency floors of pyproject.toml are the versions ``.ci/lower-bounds``
installs and tests (so the two cannot drift apart), and every dependency has a floor; CI
runs the README's test command, which installs the cross-checks' niapy apart from the test
extra."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

from packaging.requirements import Requirement

ROOT = Path(__file__).resolve().parents[1]


def floors() -> dict[str, str]:
    """``name -> pin`` for every dependency of the package and of the tests (the test and
    crosscheck extras): ``numpy>=2.0`` -> ``numpy==2.0.*`` (the floor's series, as
    .ci/lower-bounds installs it)."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    extras = project["optional-dependencies"]
    deps = project["dependencies"] + extras["test"] + extras["crosscheck"]
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


def readme_test_command() -> str:
    """The quick start's command that sets up and runs the test suite."""
    lines = [ln for ln in (ROOT / "README.md").read_text(encoding="utf-8").splitlines()
             if ln.startswith("python3 -m venv") and "pytest" in ln]
    assert len(lines) == 1, lines
    return lines[0]


def test_ci_runs_the_readmes_test_command():
    run = (ROOT / ".ci" / "run").read_text(encoding="utf-8").splitlines()
    assert readme_test_command() in run


def test_niapy_is_apart_from_the_test_extra_and_ci_installs_it():
    """niapy's releases pin numpy narrowly: in the test extra it could break its install.
    It is the crosscheck extra, which the README's (and so CI's) test command installs."""
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"][
        "optional-dependencies"]
    names = {name: {Requirement(d).name for d in deps} for name, deps in extras.items()}
    assert "niapy" not in names["test"] and names["crosscheck"] == {"niapy"}
    assert "'.[test,crosscheck]'" in readme_test_command()
