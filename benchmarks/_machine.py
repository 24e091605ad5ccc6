"""The machine line the benchmark sections print: CPU model, cores, OS, Python and the
versions of the libraries that matter to the section."""

from __future__ import annotations

import importlib
import os
import platform
from pathlib import Path


def machine(*libraries: str) -> str:
    """``"<CPU>, <n> cores, <OS>, Python x.y.z, NumPy a.b, <Library> c.d"``; ``libraries``
    are importable names (``"numba"``, ``"matplotlib"``) after NumPy."""
    cpu = "unknown CPU"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    names = {"numpy": "NumPy", "numba": "Numba", "matplotlib": "matplotlib", "scipy": "SciPy"}
    libs = ", ".join(f"{names.get(m, m)} {importlib.import_module(m).__version__}"
                     for m in ("numpy", *libraries))
    return (f"{cpu}, {os.cpu_count()} cores, {platform.system()} {platform.release()}, "
            f"Python {platform.python_version()}, {libs}")
