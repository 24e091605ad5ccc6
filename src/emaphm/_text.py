"""How a value the user gave is echoed in a message: quoted, and cut when long, so that a
100 kB argument or metadata field is never printed whole."""

from __future__ import annotations

from typing import Any

__all__ = ["shown", "one_line"]

#: Characters of a user value echoed in a message before it is cut.
SHOWN_CHARS = 60


def shown(value: Any, limit: int = SHOWN_CHARS) -> str:
    """``repr(value)``, cut to about ``limit`` characters with the full length said:
    ``'EMA-0042'``, or ``'xxxxxxxx...' (100000 characters)``."""
    text = repr(value)
    if len(text) <= limit:
        return text
    size = (f"{len(value)} characters" if isinstance(value, str)
            else f"{len(value)} bytes" if isinstance(value, bytes)
            else f"{len(text)} characters as text")
    quote = text[-1] if text[-1] in "'\"" else ""
    return f"{text[:max(limit - 4, 8)]}...{quote} ({size})"


def one_line(text: str, limit: int = 2000) -> str:
    """``text`` on one line (line breaks as spaces), its middle cut past ``limit``
    characters: the last resort of the CLI's error boundary."""
    flat = " ".join(str(text).splitlines())
    if len(flat) <= limit:
        return flat
    half = limit // 2
    return f"{flat[:half]} [... {len(flat) - 2 * half} characters cut ...] {flat[-half:]}"
