"""Shared test configuration and fixtures.

Hypothesis runs under the ``emaphm`` profile unless ``HYPOTHESIS_PROFILE``
names another: no deadline (the first call of a Numba function compiles it),
derandomised (the same examples on every run, so a failure reproduces), no
example database, and its home folder in a temporary directory (tests write
nothing into the repository). No kernel is compiled ahead of need in a child process
(``EMAPHM_PREFETCH=0``; ``tests/models/test_warm.py`` tests that on its own).
"""

from __future__ import annotations

import os
import tempfile

import pytest
from hypothesis import HealthCheck, settings
from hypothesis.configuration import set_hypothesis_home_dir

# Hypothesis keeps caches (constants, unicode data) in its home folder, ./.hypothesis by
# default: put it in a temporary folder so that the suite writes nothing into the tree
set_hypothesis_home_dir(tempfile.mkdtemp(prefix="emaphm-hypothesis-"))

settings.register_profile(
    "emaphm",
    deadline=None,
    derandomize=True,
    database=None,
    print_blob=True,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.register_profile("emaphm-explore", parent=settings.get_profile("emaphm"),
                          derandomize=False, max_examples=1000)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "emaphm"))

# the CLI's diagnosis compiles its drive check's kernels in a child process where they are
# not cached (emaphm.models.warm): not beside the suite's own workers
os.environ.setdefault("EMAPHM_PREFETCH", "0")


@pytest.fixture(scope="session")
def nominal_params():
    """The default actuator (Siemens 1FK7060 bench, reconstructed)."""
    from emaphm.params import siemens_1fk7060

    return siemens_1fk7060()


@pytest.fixture(scope="session")
def diag_profile():
    """The default 0.5 s diagnostic profile."""
    from emaphm.profiles import diagnostic

    return diagnostic()

