"""Compile kernel variants ahead of need, in another process.

The monitoring model's kernels come in variants (:func:`emaphm.models._monitoring_common.
variant_key`: a plain drive or one with options, an ideal inverter or one with dead time),
each compiled the first time it runs. A diagnosis on a data sheet runs the plain drive's
variant for its identification, and the one with options for its drive check
(:func:`emaphm.verdict.drive_check`: refits with a speed filter, a period of delay,
feed-forwards). On a machine with a second core, :func:`prefetch` compiles each in a child
process of its own (``python -m emaphm.models.warm``) while this process compiles the
reference plant and simulates (``emaphm diagnose --scenario``) or reads the trace; a kernel
about to run a variant a child is compiling waits for it
(:func:`wait_for`) and then loads it from the disk cache. A variant already cached, a
machine with one core or ``EMAPHM_PREFETCH=0`` start no child; a child still running when
this process exits is stopped (what it finished stays cached).
"""

from __future__ import annotations

import os
import subprocess
import sys
from typing import Iterable

from ._monitoring_common import variant_of
from .compiling import PENDING, stop_children, wait_for

__all__ = ["prefetch", "diagnosis_variants", "wait_for", "cached", "compile_variants", "cache_folder",
           "stop_children"]


def cache_folder():
    """The folder the kernels are cached in (a :class:`pathlib.Path`; None where nothing
    is cached), which other work drawn once per environment may share: a search's Sobol
    sample (:func:`emaphm.problem.sobol_sample`). Emptied with the kernels when their
    sources change."""
    from ._jit import CACHE_DIR

    return CACHE_DIR


def _kernels(key: tuple[bool, bool]) -> list:
    from . import monitoring, monitoring_simd

    return [monitoring._VARIANTS[key], monitoring_simd._VARIANTS[key]]


def cached(key: tuple[bool, bool]) -> bool:
    """Whether both kernels' variant ``key`` are in the disk cache (True where it cannot be
    told: no cache, or a Numba whose cache is laid out otherwise)."""
    for kernel in _kernels(key):
        cache = getattr(kernel, "_cache", None)
        index = getattr(getattr(cache, "_cache_file", None), "_index_path", None)
        if index is not None and not os.path.exists(index):
            return False
    return True


def prefetch(keys: Iterable[tuple[bool, bool]]) -> list[tuple[bool, bool]]:
    """Start compiling each of the variants ``keys`` not yet cached in a child process of
    its own; returns the keys it started (none on a single core, or with
    ``EMAPHM_PREFETCH=0``)."""
    if os.environ.get("EMAPHM_PREFETCH", "1") == "0" or (os.cpu_count() or 1) < 2:
        return []
    from ._jit import CACHE_DIR

    if CACHE_DIR is None:               # nothing to share through: each process compiles
        return []
    todo = [k for k in dict.fromkeys(keys) if k not in PENDING and not cached(k)]
    env = dict(os.environ, EMAPHM_PREFETCH="0")
    for plain, ideal in todo:           # one child each: they compile side by side
        PENDING[(plain, ideal)] = subprocess.Popen(
            [sys.executable, "-m", "emaphm.models.warm", f"{int(plain)}{int(ideal)}"],
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            env=env)
    return todo


def diagnosis_variants(params, drive_check: bool) -> list[tuple[bool, bool]]:
    """The variants a diagnosis of ``params`` on the modelled controller runs: its drive's
    own, and with ``drive_check`` (a data sheet's verdict) the one with options."""
    plain, ideal = variant_of(params)
    return [(plain, ideal)] + ([(False, ideal)] if drive_check else [])


def compile_variants(keys: Iterable[tuple[bool, bool]]) -> None:
    """Compile (or load) both kernels' variants ``keys`` as a diagnosis runs them: the
    preset with a drive option (``plain`` False: a speed-feedback filter) and dead time
    (``ideal`` False), nine healthy candidates through :class:`~emaphm.models.monitoring.
    MonitoringModel` (a block of vector lanes and a remainder in the scalar kernel)."""
    from dataclasses import replace

    import numpy as np

    from ..faults import K_NOMINAL
    from ..params import siemens_1fk7060
    from .monitoring import MonitoringModel

    sheet = siemens_1fk7060()
    for plain, ideal in keys:
        params = sheet
        if not plain:
            params = replace(params, controller=replace(params.controller, speed_filter_s=2.5e-4))
        if not ideal:
            params = replace(params, inverter=replace(params.inverter, dead_time=1e-6))
        MonitoringModel(params).simulate_population(np.tile(K_NOMINAL, (9, 1)))


def main(argv: list[str]) -> int:
    compile_variants((a[0] == "1", a[1] == "1") for a in argv)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
