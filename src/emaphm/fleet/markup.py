"""Writing untrusted values into HTML: every text and attribute through :func:`esc`, every
inline JSON through :func:`script_json`, every file name through :func:`page_stem`.

Actuator ids and descriptions come from users (and a history file may have been written
by another tool), so nothing read from a store reaches a page unescaped.
"""

from __future__ import annotations

import hashlib
import html
import json
import re
from typing import Any

__all__ = ["esc", "script_json", "slug", "page_stem"]

_SLUG_DROP = re.compile(r"[^a-z0-9]+")


def esc(value: Any) -> str:
    """``value`` as HTML text, safe in element content and in a double- or single-quoted
    attribute (``& < > " '`` escaped)."""
    return html.escape(str(value), quote=True)


_SCRIPT_ESCAPES = {"<": "\\u003c", ">": "\\u003e", "&": "\\u0026",
                   "\u2028": "\\u2028", "\u2029": "\\u2029"}
_SCRIPT_RE = re.compile("[<>&\u2028\u2029]")


def script_json(obj: Any) -> str:
    """``obj`` as JSON safe inside ``<script type="application/json">``.

    ``<``, ``>`` and ``&`` can only occur inside JSON strings, where the escapes
    ``\\u003c`` etc. mean the same characters to ``JSON.parse``; so no ``</script>``,
    ``<!--`` or ``<script`` can end or confuse the element, whatever the strings hold.
    NaN and infinities are refused (write them as null).
    """
    text = json.dumps(obj, ensure_ascii=False, allow_nan=False, sort_keys=True,
                      separators=(",", ":"))
    return _SCRIPT_RE.sub(lambda m: _SCRIPT_ESCAPES[m.group(0)], text)


def slug(text: str, max_len: int = 40) -> str:
    """A file-name-safe, lower-case rendering of ``text``: runs of anything but ASCII
    letters and digits become one ``-``; at most ``max_len`` characters; ``actuator``
    when nothing is left."""
    s = _SLUG_DROP.sub("-", str(text).lower()).strip("-")[:max_len].strip("-")
    return s or "actuator"


def page_stem(actuator_id: str, digits: int = 10) -> str:
    """The file-name stem of an actuator's page and figures: a slug of its id and the first
    ``digits`` hex digits of the SHA-256 of the id. Ids that differ only in case or in
    characters the slug drops (``EMA/1``, ``ema-1``) get different stems; the name is the
    same on every build and every platform."""
    digest = hashlib.sha256(str(actuator_id).encode("utf-8")).hexdigest()[:digits]
    return f"{slug(actuator_id)}-{digest}"
