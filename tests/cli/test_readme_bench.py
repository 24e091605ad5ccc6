"""README's "Your own actuator and bench": its commands, run in order in a folder that holds
what a user brings (a nameplate, three CSV exports of a rig in a German locale), as a new
user would run them."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from benchfiles import german_csv

ROOT = Path(__file__).resolve().parents[2]


def section_commands() -> list[str]:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text[text.index("## Your own actuator and bench"):]
    block = re.search(r"```sh\n(.*?)```", section, flags=re.S).group(1)
    return [line.split("  #")[0].strip() for line in block.splitlines() if line.strip()]


def test_the_section_is_the_three_commands_then_calibrate_and_diagnose():
    cmds = section_commands()
    assert cmds[0].startswith("emaphm params --datasheet")
    assert cmds[1].startswith("emaphm import") and "--inspect" in cmds[1]
    assert cmds[2].startswith("emaphm import") and "--map" in cmds[2]
    assert any(c.startswith("emaphm calibrate") for c in cmds)
    assert cmds[-1].startswith("emaphm diagnose")


@pytest.mark.slow
def test_the_sections_commands_run_in_order(tmp_path):
    from emaphm.params import load_params
    from emaphm.simulate import DEFAULT_SENSORS, simulate

    shutil.copy(ROOT / "examples" / "actuators" / "ema-270v-750w.nameplate.toml",
                tmp_path / "motor.nameplate.toml")
    params = load_params(ROOT / "examples" / "actuators" / "ema-270v-750w.toml")
    for name, k, seed in (("run1", None, 1), ("run2", None, 2),
                          ("run3", [0, 0, 0.15, 0, 0, 0, 0.5, 0.5], 3)):
        trace = simulate(k, params=params, sensors=DEFAULT_SENSORS, seed=seed, unit_seed=5)
        german_csv(trace, tmp_path / f"{name}.csv")
    bindir = Path(sys.executable).parent
    env = {**os.environ, "PATH": f"{bindir}{os.pathsep}{os.environ.get('PATH', '')}"}
    out = ""
    for cmd in section_commands():
        r = subprocess.run(cmd, shell=True, cwd=tmp_path, env=env, capture_output=True,
                           text=True, timeout=600)
        assert r.returncode == 0, f"`{cmd}`:\n{r.stderr[-2000:]}"
        assert "Traceback" not in r.stderr
        out = r.stdout
    assert "short_circuit (phase A)" in out, out
