"""How a value the user gave is echoed in a message: quoted, and cut when long, so that a
100 kB argument or metadata field is never printed whole."""

from __future__ import annotations

import codecs
import sys
from typing import Any

__all__ = ["shown", "one_line", "utf8_text", "printable_streams"]

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


def utf8_text(text: str) -> str:
    """``text`` that encodes as UTF-8 (for a database or a file): a file name's bytes that
    are no UTF-8 (held by Python as surrogates, e.g. a Latin-1 'caf\\xe9.csv') written as
    ``\\xNN``; other text unchanged."""
    try:
        return text.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")
    except UnicodeEncodeError:                      # a surrogate no file name's byte gives
        return text.encode("utf-8", "backslashreplace").decode("utf-8")


def _escape(exc: UnicodeError) -> tuple[str, int]:
    """Encoding errors of a stream: what it cannot encode written as :func:`utf8_text` does
    (a file name's bytes that are no UTF-8 as ``\\xNN``), then as ``\\xNN`` what the
    stream's encoding lacks (an 'é' on an ASCII stream): the output stays valid text."""
    if not isinstance(exc, UnicodeEncodeError):
        raise exc
    text = utf8_text(exc.object[exc.start:exc.end])
    return text.encode(exc.encoding, "backslashreplace").decode(exc.encoding), exc.end


codecs.register_error("emaphm-escape", _escape)


def printable_streams() -> None:
    """Make stdout and stderr print any text: under ``LC_ALL=C`` (an ASCII stream) a
    description or a file name with 'é' is no UnicodeEncodeError."""
    for stream in (sys.stdout, sys.stderr):
        if hasattr(stream, "reconfigure"):
            stream.reconfigure(errors="emaphm-escape")
