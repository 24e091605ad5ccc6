"""Writing untrusted values into HTML: every text and attribute through :func:`esc`, every
inline JSON through :func:`script_json`, every file name through :func:`page_stem`.

Actuator ids and descriptions come from users (and a history file may have been written
by another tool), so nothing read from a store reaches a page unescaped.

Numbers as the fleet shows them: a deadline (an "inspect by" time) through
:func:`fmt_deadline`, rounded *down* (:func:`floor_deadline`: shown, it is never later
than computed); a number in a table meant for programs (the schedule's CSV) through
:func:`plain_number`, every digit of the float, never in exponent notation.
"""

from __future__ import annotations

import hashlib
import html
import json
import math
import re
from decimal import Decimal
from typing import Any

__all__ = ["esc", "script_json", "slug", "page_stem", "floor_deadline", "fmt_deadline",
           "plain_number", "UNIT_ORDER", "unit_rank", "schedule_key"]

#: The order of the time units when a fleet's rows are grouped by unit (flight hours first).
UNIT_ORDER = ("h", "cycles")


def unit_rank(unit: str) -> tuple[int, str]:
    """Sort key of a time unit: :data:`UNIT_ORDER`'s place, other units after, by name."""
    return (UNIT_ORDER.index(unit) if unit in UNIT_ORDER else len(UNIT_ORDER), unit)


def schedule_key(ident: str, unit: str | None = None, left: float | None = None, *,
                 due_now: bool = False, never: bool = False) -> tuple:
    """The order of :func:`~emaphm.fleet.status.inspect_key` from plain values, for
    whatever holds them (an :class:`~emaphm.fleet.status.ActuatorStatus`, a row of the
    site; here, so that a rebuild with nothing changed imports no prognosis): the
    actuator's id, its time ``unit`` and the operating time ``left`` to its next inspection
    (None: no plan), whether it is ``due_now`` and ``never`` inspected."""
    if left is None:
        return (2, 0, "", 0.0, ident)
    left = -math.inf if never else float(f"{left:.12g}")
    if due_now:
        return (0, 0, "", left, ident)
    return (1, *unit_rank(str(unit)), left, ident)


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


# ----------------------------------------------------------------------------- numbers
#: Relative distance within which a deadline counts as the nearest whole number: the float
#: noise of a sum (``100/3 * 9`` is 299.99999999999994) is not a deadline an hour earlier.
_NOISE = 1e-13


def floor_deadline(x: float) -> tuple[float, int]:
    """``x`` rounded down as :func:`fmt_deadline` shows it, and the decimals shown: whole
    units from 10 on, else two significant digits (float noise below a relative
    :data:`_NOISE` rounds up, not down). Not finite: ``(x, 0)``."""
    x = float(x)
    if not math.isfinite(x) or x == 0.0:
        return (x + 0.0, 0)
    decimals = 0 if abs(x) >= 10 else 1 - math.floor(math.log10(abs(x)))
    scale = 10.0 ** decimals
    y = x * scale
    near = round(y)
    v = (near if abs(y - near) <= _NOISE * max(1.0, abs(y)) else math.floor(y)) / scale
    return (v + 0.0, 0 if abs(v) >= 10 else decimals)


def fmt_deadline(x: float | None, unit: str) -> str:
    """An inspect-by time as shown: rounded down (:func:`floor_deadline`), with its unit;
    a dash when there is none."""
    if x is None or math.isnan(x):
        return "\u2013"
    if math.isinf(x):
        return "\u221e"
    v, decimals = floor_deadline(x)
    return f"{v:.{decimals}f} {unit}"


def plain_number(x: float) -> str:
    """``x`` with every digit of the float (the shortest text that reads back as ``x``),
    as a plain decimal, never in exponent notation: ``3456788.8``, ``0.00001``, ``300``."""
    x = float(x)
    if not math.isfinite(x):
        return repr(x)
    text = format(Decimal(repr(x)), "f")
    if "." in text:
        text = text.rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text
