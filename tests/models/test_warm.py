"""Kernel variants compiled ahead of need in a child process (:mod:`emaphm.models.warm`):
started only for variants not yet cached, on a second core, unless EMAPHM_PREFETCH=0;
a kernel about to run a variant waits for the child that compiles it; a child left over
at exit is stopped. The child itself runs ``python -m emaphm.models.warm``, tested on a
variant already cached (it loads it and exits 0)."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from emaphm.models import compiling, warm
from emaphm.models.monitoring import MonitoringModel


class FakeChild:
    def __init__(self, args, **kw):
        self.args = args
        self.waited = self.terminated = False

    def wait(self):
        self.waited = True

    def poll(self):
        return None

    def terminate(self):
        self.terminated = True


@pytest.fixture()
def children(monkeypatch):
    started = []
    monkeypatch.setattr(warm.subprocess, "Popen",
                        lambda args, **kw: started.append(FakeChild(args, **kw)) or started[-1])
    monkeypatch.setattr(warm.os, "cpu_count", lambda: 2)
    monkeypatch.setenv("EMAPHM_PREFETCH", "1")
    monkeypatch.setattr(warm, "PENDING", {})
    monkeypatch.setattr(compiling, "PENDING", warm.PENDING)
    return started


def test_a_variant_not_cached_is_compiled_in_a_child_and_waited_for(children, monkeypatch):
    monkeypatch.setattr(warm, "cached", lambda key: key != (False, True))
    assert warm.prefetch([(False, True), (True, True), (False, True)]) == [(False, True)]
    (child,) = children
    assert child.args[1:] == ["-m", "emaphm.models.warm", "01"]
    assert warm.prefetch([(False, True)]) == []               # already on its way
    # the kernel that runs it waits for the child, once
    MonitoringModel(kernel="scalar").simulate_population(
        np.tile([0, 0, 0, 0, 0, 0, 0.5, 0.5], (1, 1)))        # the plain variant: no wait
    assert not child.waited
    warm.wait_for((False, True))
    assert child.waited and warm.PENDING == {}
    # at exit a child still running is stopped
    warm.prefetch([(False, True)])
    warm.stop_children()
    assert children[-1].terminated and warm.PENDING == {}


@pytest.mark.parametrize("setting, cores, expected", [("0", 2, []), ("1", 1, [])])
def test_no_child_where_it_cannot_help(children, monkeypatch, setting, cores, expected):
    monkeypatch.setenv("EMAPHM_PREFETCH", setting)
    monkeypatch.setattr(warm.os, "cpu_count", lambda: cores)
    monkeypatch.setattr(warm, "cached", lambda key: False)
    assert warm.prefetch([(False, True)]) == expected and children == []


def test_the_child_compiles_or_loads_a_variant():
    MonitoringModel().simulate_population(np.tile([0, 0, 0, 0, 0, 0, 0.5, 0.5], (9, 1)))
    assert warm.cached((True, True))
    done = subprocess.run([sys.executable, "-m", "emaphm.models.warm", "11"], timeout=600,
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr


def test_a_diagnosis_asks_for_the_variants_its_populations_run():
    from dataclasses import replace

    from emaphm.models._monitoring_common import variant_key
    from emaphm.params import siemens_1fk7060

    sheet = siemens_1fk7060()
    lagged = replace(sheet, controller=replace(sheet.controller, speed_filter_s=1e-3),
                     inverter=replace(sheet.inverter, dead_time=1e-6))
    for params in (sheet, lagged):
        key = variant_key(*MonitoringModel(params).pack(np.tile([0, 0, 0, 0, 0, 0, .5, .5],
                                                                (2, 1))))
        assert warm.diagnosis_variants(params, drive_check=False) == [key]
        assert warm.diagnosis_variants(params, drive_check=True) == [key, (False, key[1])]
    assert warm.diagnosis_variants(lagged, drive_check=False) == [(False, False)]
