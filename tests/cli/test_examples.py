"""Every script in ``examples/`` runs, with its short settings, on the current API.

Each example has its command line here (:data:`RUNS`); a new example without one fails
:func:`test_every_example_runs_in_the_tests`. They run as a user runs them (a subprocess
in an empty folder) with DeprecationWarnings as errors, so that an example still on a
deprecated spelling fails here rather than in a user's hands.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = sorted((ROOT / "examples").glob("*.py"))

#: Each example's short run: its arguments ({out} a folder for its files).
RUNS = {
    "own_optimizer.py": ["--quick"],
    "degradation_demo.py": ["--inspections", "3", "--budget", "150", "--out-dir", "{out}"],
    "study.py": ["--quick"],
}


def _run(name: str, tmp_path: Path) -> tuple[subprocess.CompletedProcess, Path]:
    work = tmp_path / "cwd"
    work.mkdir()
    out = tmp_path / "out"
    out.mkdir()
    args = [a.format(out=out) for a in RUNS[name]]
    r = subprocess.run([sys.executable, "-W", "error::DeprecationWarning",
                        str(ROOT / "examples" / name), *args],
                       capture_output=True, text=True, cwd=work, timeout=600)
    assert r.returncode == 0, r.stderr
    assert list(work.iterdir()) == []              # it writes nothing where it is run
    return r, out


def test_every_example_runs_in_the_tests():
    assert EXAMPLES, "no examples found"
    assert sorted(p.name for p in EXAMPLES) == sorted(RUNS)


def test_the_own_optimizer_example_runs(tmp_path):
    r, _ = _run("own_optimizer.py", tmp_path)
    lines = r.stdout.strip().splitlines()
    assert [ln.split(":")[0] for ln in lines] == ["random-search", "coordinate_search"]
    assert "faulty: dry friction" in lines[1]          # the coordinate search finds it


def test_the_degradation_demo_simulates_identifies_and_predicts(tmp_path):
    """The demo's full path (reference-plant traces identified, not the synthetic k), with
    three inspections and a small budget: a growing short read at each, a prediction,
    three figures."""
    r, out = _run("degradation_demo.py", tmp_path)
    rows = re.findall(r"^t = +(\d+) h  identified short_circuit_a = ([\d.]+)  verdict (\w+)$",
                      r.stdout, flags=re.M)
    assert [int(t) for t, _, _ in rows] == [0, 475, 950]
    shorts = [float(x) for _, x, _ in rows]
    assert shorts[0] < 0.05 and shorts[2] > 0.2 and shorts == sorted(shorts)
    assert rows[0][2] == "healthy" and rows[2][2] == "FAULTY"
    assert re.search(r"^after  3 inspections \(t =    950 h\): RUL median", r.stdout, flags=re.M)
    assert "coverage of the true RUL from mid-life" in r.stdout
    assert sorted(p.name for p in out.iterdir()) == [
        f"short-circuit-growth-{x}.png" for x in ("alpha-lambda", "history", "prognosis")]


@pytest.mark.parametrize("name", sorted(RUNS))
def test_the_examples_say_how_to_run_them_short(name):
    """What the tests run is what the example's docstring offers (its flags exist)."""
    text = (ROOT / "examples" / name).read_text()
    for flag in (a for a in RUNS[name] if a.startswith("--")):
        assert f'"{flag}"' in text, f"{name} has no {flag}"


def test_the_study_matches_the_long_way_round(tmp_path):
    """Issue 34's acceptance: a study from a script (a second actuator identified without
    params=, an optimizer registered by name in a 6-run campaign on 2 workers, a batch of 8
    traces on 2 workers, every kind of result through JSON, a frame with two currents and
    no speed), each step checked in the script against the long way round."""
    r, _ = _run("study.py", tmp_path)
    steps = [ln.split(":")[0] for ln in r.stdout.strip().splitlines()]
    assert steps == ["1. own actuator", "2. campaign", "3. batch", "4. round trips", "5. frame"]
