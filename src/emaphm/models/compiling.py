"""The kernel variants being compiled in child processes (:mod:`emaphm.models.warm` starts
them), for the kernels to wait for: the one module of that work the kernels import, so that
it imports none of them."""

from __future__ import annotations

import atexit
import subprocess

__all__ = ["PENDING", "wait_for"]

#: variant key (:func:`emaphm.models._monitoring_common.variant_key`) -> the child compiling it
PENDING: dict[tuple[bool, bool], subprocess.Popen] = {}


def wait_for(key: tuple[bool, bool]) -> None:
    """Wait for a child compiling variant ``key`` (if one is), so that this process loads
    it from the cache instead of compiling it a second time."""
    child = PENDING.pop(key, None)
    if child is not None:
        child.wait()


@atexit.register
def stop_children() -> None:
    """Stop the children still compiling (what they finished stays cached)."""
    for child in set(PENDING.values()):
        if child.poll() is None:
            child.terminate()
    PENDING.clear()
