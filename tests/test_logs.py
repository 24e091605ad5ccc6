"""The first compile is announced through logging (issue 34, item 8), and importing
``emaphm.simulate`` loads no kernel (nor Numba) until a simulation runs: a warm import
well under a second (benchmarks measure the time; the test checks what is imported)."""

from __future__ import annotations

import subprocess
import sys

from emaphm.logs import COMPILE_MESSAGE


def run(code: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)


def test_the_first_compile_is_logged_once():
    code = ("import logging; logging.basicConfig(level=logging.INFO, format='%(name)s: %(message)s')\n"
            "from emaphm.logs import announce_compiles\n"
            "announce_compiles(); announce_compiles()\n"
            "import numba\n"
            "numba.njit(lambda x: x + 1)(1); numba.njit(lambda x: x + 2)(1)\n")
    out = run(code)
    assert out.returncode == 0, out.stderr
    assert out.stderr.count(f"emaphm: {COMPILE_MESSAGE}") == 1


def test_nothing_is_logged_without_a_compile():
    out = run("import logging; logging.basicConfig(level=logging.INFO)\n"
              "import emaphm.simulate\n")
    assert out.returncode == 0 and out.stderr == ""


def test_importing_simulate_loads_no_kernel():
    out = run("import sys, emaphm.simulate\n"
              "print(sorted(m for m in ('numba', 'emaphm.models.monitoring', "
              "'emaphm.models.reference', 'scipy') if m in sys.modules))\n")
    assert out.returncode == 0 and out.stdout.strip() == "[]", out.stderr
