"""README.md's walkthrough, run as a new user would: every shell command of its code
blocks, in the order written, in an empty folder, with the ``emaphm`` of this environment.

Each command must exit 0; every file a command reads must have been written by an earlier
one, and every file it says it writes (``--out``, ``--plot``, ``--store``, ``--plot-dir``)
must be there afterwards. The quick start's set-up (venv, pip install, the test suite) is
skipped; budgets are cut (:data:`SHORTER`). The walk still takes about 100 s of CPU
(measured: two calibrations of 15-18 s each, 25 process start-ups of about 1.5 s).
"""

from __future__ import annotations

import json
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from emaphm.faults import K_NAMES

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"

#: What the test appends to a README command (argparse keeps an option's last value), so
#: that the walk takes about a minute instead of many: (command prefix, extra arguments).
SHORTER = (
    ("emaphm diagnose", ["--budget", "2000"]),
    ("emaphm history add", ["--budget", "2000"]),
    # the README's campaign is 4 algorithms x 11 scenarios x 10 runs; in this process
    ("emaphm campaign", ["--scenarios", "gain-high", "--runs", "1", "--budget", "300",
                         "--workers", "0"]),
    ("emaphm demo-degradation", ["--inspections", "4", "--budget", "1000"]),
    # 30 actuators of real diagnoses are minutes of CPU: three of them
    ("emaphm fleet demo --db demo.sqlite", ["--actuators", "3"]),
    # 40 production units on every grid are minutes on every core: two and two, one grid
    ("emaphm assess", ["--units", "2", "--tune-units", "2", "--healthy", "1",
                       "--healthy-datasheet", "1", "--grids", "short_circuit",
                       "--severities", "short_circuit=0.15", "--workers", "0"]),
)
#: README commands not run, and why.
SKIPPED = {
    "emaphm campaign --spec docs/examples/paper.toml --store paper.sqlite "
    "--scheduler tcp://host:8786": "needs a Dask scheduler at that address",
}
#: Set-up parts of the quick start's lines: the environment the test already runs in.
SETUP = re.compile(r"^(python3 -m venv|\.venv/bin/pip install|\.venv/bin/python -m pytest)")
#: Options whose value is a file or folder the command writes.
OUTPUTS = ("--out", "--plot", "--store", "--plot-dir")
#: What a file argument ends with.
FILE_SUFFIXES = (".csv", ".parquet", ".toml", ".sqlite", ".png", ".svg", ".pdf")


def code_blocks(text: str) -> list[tuple[str, str]]:
    """``(language, body)`` of every fenced code block, in order."""
    return re.findall(r"^```(\w*)\n(.*?)^```", text, flags=re.S | re.M)


def walkthrough(text: str) -> list[tuple[str, list[str] | str]]:
    """The README's steps in order: ``("shell", argv)`` for each ``emaphm`` command of the
    bash blocks (set-up parts dropped) and ``("python", source)`` for each Python block."""
    steps: list[tuple[str, list[str] | str]] = []
    for lang, body in code_blocks(text):
        if lang == "python":
            steps.append(("python", body))
            continue
        if lang != "bash":
            continue
        for line in body.splitlines():
            tokens = shlex.split(line, comments=True)
            while tokens:
                n = tokens.index("&&") if "&&" in tokens else len(tokens)
                argv, tokens = tokens[:n], tokens[n + 1:]
                if SETUP.match(" ".join(argv)):
                    continue
                if argv[0] == ".venv/bin/emaphm":
                    argv[0] = "emaphm"
                assert argv[0] == "emaphm", f"README command the test does not know: {argv}"
                steps.append(("shell", argv))
    return steps


def shortened(argv: list[str]) -> list[str]:
    cmd = " ".join(argv)
    extra = [e for prefix, e in SHORTER if cmd.startswith(prefix)]
    return argv + (extra[0] if extra else [])


def inputs_and_outputs(argv: list[str]) -> tuple[list[str], list[str]]:
    """The files a command reads (file-like arguments that are not an output option's
    value) and those it writes."""
    written_by = OUTPUTS + (("--db",) if argv[1:3] == ["fleet", "demo"] else ())
    outputs = [argv[i + 1] for i, a in enumerate(argv[:-1]) if a in written_by]
    reads = [a for i, a in enumerate(argv) if a.endswith(FILE_SUFFIXES) and a not in outputs
             and not (i and argv[i - 1] in written_by)]
    return reads, outputs


def test_the_walkthrough_is_what_the_test_runs():
    steps = walkthrough(README.read_text(encoding="utf-8"))
    cmds = [" ".join(argv) for kind, argv in steps if kind == "shell"]
    # the quick start's job without its set-up, then "Using it" in order
    assert cmds[0] == "emaphm diagnose --scenario friction-high --plot diagnosis.png"
    assert cmds[1] == "emaphm scenarios" and cmds[-1].startswith("emaphm fleet report")
    assert set(SKIPPED) <= set(cmds), "a skipped command is no longer in the README"
    assert sum(kind == "python" for kind, _ in steps) == 1
    for prefix, _ in SHORTER:
        assert any(c.startswith(prefix) for c in cmds), prefix


@pytest.mark.slow
def test_readme_commands_run_in_order_in_an_empty_folder(tmp_path):
    bindir = Path(sys.executable).parent
    assert (bindir / "emaphm").exists(), "the emaphm console script of this environment"
    env = {k: v for k, v in os.environ.items() if k != "EMAPHM_HISTORY"}
    env["PATH"] = f"{bindir}{os.pathsep}{env.get('PATH', '')}"
    written: set[str] = set()
    outputs_of: dict[str, str] = {}
    for kind, step in walkthrough(README.read_text(encoding="utf-8")):
        if kind == "python":
            before = set(os.listdir(tmp_path))
            r = subprocess.run([sys.executable, "-c", step], cwd=tmp_path, env=env,
                               capture_output=True, text=True, timeout=600)
            assert r.returncode == 0, f"README's Python block:\n{r.stderr[-3000:]}"
            new = set(os.listdir(tmp_path)) - before
            assert "gain.parquet" in new
            written |= new
            continue
        cmd = " ".join(step)
        if cmd in SKIPPED:
            continue
        argv = shortened(step)
        reads, outputs = inputs_and_outputs(argv)
        for f in reads:      # written itself, or in a folder an earlier command wrote
            assert any(p in written for p in (f, *map(str, Path(f).parents))) \
                and (tmp_path / f).exists(), f"`{cmd}` reads {f}, which no earlier README command wrote"
        r = subprocess.run(argv, cwd=tmp_path, env=env, capture_output=True, text=True,
                           timeout=600)
        assert r.returncode == 0, f"`{' '.join(argv)}` exited {r.returncode}:\n{r.stderr[-3000:]}"
        assert "Traceback" not in r.stderr, cmd
        for f in outputs:
            assert (tmp_path / f).exists(), f"`{cmd}` did not write {f}"
            written.add(f)
        outputs_of[cmd] = r.stdout
    # the store the history commands share, in the folder (no $EMAPHM_HISTORY here)
    assert (tmp_path / "emaphm-history.sqlite").exists()
    assert (tmp_path / "report" / "report.md").exists()
    # --json carries the trace's scenario from its metadata
    (js,) = [out for cmd, out in outputs_of.items()
             if "--json" in cmd.split() and "sc.parquet" in cmd.split()]
    d = json.loads(js)
    assert d["scenario"] == "short-circuit-high" and d["trace"] == "sc.parquet"
    assert d["algorithm"] == "de" and d["seed"] == 3
    # a severe short's JSON carries its fault loop: current, power, ampere-turns
    (js,) = [out for cmd, out in outputs_of.items()
             if "--json" in cmd.split() and "severe.parquet" in cmd.split()]
    (short,) = [f for f in json.loads(js)["faults"] if f["mode"] == "short_circuit"]
    assert short["phase"] == "A"
    for key in ("fault_current_a_rms", "fault_power_w", "fault_mmf_a_rms", "mu", "R_f_ohm"):
        assert short[key] > 0, key
    # the history table names every component in full
    (show,) = [out for cmd, out in outputs_of.items() if cmd.startswith("emaphm history show")]
    header = show.splitlines()[1].split()
    assert header[2:10] == list(K_NAMES), header
    assert "3 inspections" in show
    # the unit calibrated with the assessed parameters names its short with their thresholds
    (assessed,) = [out for cmd, out in outputs_of.items()
                   if cmd == "emaphm diagnose inspection.parquet --params unit7-assessed.toml"]
    assert "verdict: FAULTY" in assessed and "short circuit" in assessed and "phase A" in assessed
    (prog,) = [out for cmd, out in outputs_of.items() if cmd.startswith("emaphm prognose")]
    assert "first to fail: short_circuit_a" in prog
