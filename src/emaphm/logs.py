"""What emaphm says through :mod:`logging` (the logger ``"emaphm"``).

The first time in a process that Numba starts compiling one of the model kernels (the
first run on a machine, or after the model's sources changed: up to a minute), emaphm logs
:data:`COMPILE_MESSAGE` at INFO before it does; a kernel loaded from the disk cache says
nothing. Show it with ``logging.basicConfig(level=logging.INFO)`` (or a handler on the
``"emaphm"`` logger). The command line prints its own notice on stderr instead
(:func:`emaphm.progress.compile_notice`).
"""

from __future__ import annotations

import logging
from typing import Any

__all__ = ["LOGGER", "COMPILE_MESSAGE", "announce_compiles"]

#: The logger of emaphm.
LOGGER = logging.getLogger("emaphm")

COMPILE_MESSAGE = ("compiling the model kernels (the first run on this machine only; cached on "
                   "disk for the next runs): this can take up to a minute")

_STATE = {"installed": False, "said": False}


def announce_compiles() -> None:
    """Log :data:`COMPILE_MESSAGE` once, when Numba first starts compiling in this process
    (a listener on Numba's ``numba:compile`` event, installed once; idempotent)."""
    if _STATE["installed"]:
        return
    _STATE["installed"] = True
    try:
        from numba.core import event
    except ImportError:                  # pragma: no cover - numba is a dependency
        return

    class _Announce(event.Listener):
        def on_start(self, ev: Any) -> None:
            if not _STATE["said"]:
                _STATE["said"] = True
                LOGGER.info(COMPILE_MESSAGE)

        def on_end(self, ev: Any) -> None:
            pass

    event.register("numba:compile", _Announce())
