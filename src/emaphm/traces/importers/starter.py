"""What ``emaphm import SOURCE --inspect`` prints: the channels found (name, group, unit,
samples, rate) and a starter channel map, its guesses made from the channel names and
units, to check and edit."""

from __future__ import annotations

import json
import re
import shlex

from ...quantities import QuantityError, measure
from .base import ChannelInfo, SourceInfo
from ..container import DRIVE_COLUMNS, UNITS as _SI
from .channel_map import TARGETS

__all__ = ["describe", "starter_map"]

#: Name patterns (lower case, after removing spaces, dashes and underscores) of each column.
_GUESSES: dict[str, tuple[str, ...]] = {
    "t": (r"^(t|time|zeit|timestamp|times|sec|seconds)$", r"^time", r"zeit"),
    "theta_ref": (r"(ref|soll|cmd|command|setpoint|demand|target)",),
    "theta_m": (r"^(thetam|theta|pos|position|angle|winkel|ist|posm|motorpos)",
                r"(position|angle|winkel|pos)"),
    "omega_m": (r"(omega|speed|velocity|drehzahl|rpm|vel)",),
    "i_a": (r"^(ia|iu|ic?h?1|phasea|currenta|strom(u|a)|ilu|ilu1|ia\d?)$", r"(^|[^a-z])(ia|iu)$",
            r"(phase|strom|current|cur|i)(a|u|1)$"),
    "i_b": (r"^(ib|iv|phaseb|currentb|strom(v|b))$", r"(phase|strom|current|cur|i)(b|v|2)$"),
    "i_c": (r"^(ic|iw|phasec|currentc|strom(w|c))$", r"(phase|strom|current|cur|i)(c|w|3)$"),
    "torque": (r"(torque|moment|drehmoment)",),
}


def _key(name: str) -> str:
    return re.sub(r"[\s_\-.\[\]()]", "", name.lower())


def _kind(unit: str | None) -> str | None:
    try:
        return measure(unit).kind if unit else None
    except QuantityError:
        return None


def _guess(info: SourceInfo) -> dict[str, ChannelInfo]:
    found: dict[str, ChannelInfo] = {}
    used: set[str] = set()
    for target in ("t", "theta_ref", "omega_m", "i_a", "i_b", "i_c", "torque", "theta_m"):
        kind = TARGETS[target]
        for pattern in _GUESSES[target]:
            for c in info.channels:
                if c.label in used or c.text is not None:
                    continue
                unit_kind = _kind(c.unit)
                if unit_kind not in (None, kind) and not (kind == "current"
                                                          and unit_kind == "voltage"):
                    continue
                if re.search(pattern, _key(c.name)):
                    found[target] = c
                    used.add(c.label)
                    break
            if target in found:
                break
    return found


def _printable(text: str) -> str:
    """``text``, its control characters escaped (a TOML comment may hold none)."""
    return text if text.isprintable() else repr(text)[1:-1]


def describe(info: SourceInfo) -> str:
    """The channels of ``info`` as a table, under a line on the file's layout."""
    lines = [_printable(f"{info.path.name}: {info.format}"
                        + (f" ({'; '.join(info.notes)})" if info.notes else ""))]
    rows = [("channel", "group", "unit", "samples", "rate")]
    for c in info.channels:
        rows.append((_printable(c.name), _printable(c.group or ""),
                     "(text)" if c.text is not None else _printable(c.unit or "-"),
                     f"{c.samples:,}" if c.samples is not None else "?",
                     f"{c.rate:g} Hz" if c.rate else ""))
    widths = [min(max(len(r[k]) for r in rows), 40) for k in range(5)]
    for r in rows:
        lines.append("  ".join(x[:40].ljust(w) for x, w in zip(r, widths)).rstrip())
    if not info.channels:
        lines.append("(no numeric channels found)")
    lines += [_printable(x) for x in info.skipped]
    if info.damage:
        lines.append(f"damaged: {info.damage}; listed: what of it can be read")
    return "\n".join(lines)


def _toml_string(text: str) -> str:
    """``text`` as a TOML basic string: quotes, backslashes and control characters (a line
    break in a channel's name) escaped, as JSON escapes them, which TOML reads alike."""
    return json.dumps(text, ensure_ascii=False)


def _command_name(name: str) -> str:
    """A file name as the command line a comment suggests takes it: quoted for the shell;
    one with a line break or another control character cannot be written on one line."""
    if name.isprintable():
        return shlex.quote(name)
    return (f"{name!r:.80} (its name holds a line break or another control character: "
            "rename the file first)")


def starter_map(info: SourceInfo) -> str:
    """A channel map to edit: the columns guessed from the channel names (each with the
    unit the file declares, or a placeholder that the map refuses until it is set)."""
    found = _guess(info)
    timed = list(found.values()) or list(info.channels)
    rates = {c.rate for c in timed if c.rate}
    name = _command_name(info.path.name)
    lines = [f"# channel map for {name}: check every line, then run",
             f"#   emaphm import {name} --map THIS.toml --out trace.parquet",
             "# value in SI = (scale * recorded + offset) converted from unit; a current",
             "# recorded in V (a probe) takes scale = \"10 A/V\" or its sensitivity \"100 mV/A\".",
             ""]
    if "t" not in found and not info.own_time and len(rates) > 1:
        at = {r: [c.label for c in timed if c.rate == r] for r in sorted(rates)}
        lines += ["# the channels are at different rates, and emaphm needs one time base:"]
        lines += [f"#   {r:g} Hz: {_printable(', '.join(names))}" for r, names in at.items()]
        lines += ["# record or export them at one rate (or resample them in the recorder)", ""]
    elif "t" not in found and not info.own_time and not rates:
        lines += ["[time]", "rate = 0  # sample rate in Hz (the file has no time channel): SET IT",
                  ""]
    lines.append("[channels]")
    for target in TARGETS:
        c = found.get(target)
        if c is None:
            optional = {"t": "from [time] rate or the file's time base",
                        "omega_m": "derived from theta_m", "i_c": "-(i_a + i_b)",
                        "torque": "optional"}
            if target in DRIVE_COLUMNS:         # what a drive logs, if it does
                if target == DRIVE_COLUMNS[0]:
                    lines.append("# what the drive logs, if it does (docs/drives.md): voltage "
                                 "commands v_a, v_b, v_c (or v_d, v_q; or d_a, d_b, d_c with "
                                 "v_dc), i_d_ref, i_q_ref, omega_ref")
                lines.append(f"# {target} = {{ name = \"...\", unit = \"{_SI[target]}\" }}")
                continue
            if target in optional:
                lines.append(f"# {target} = {{ name = \"...\", unit = \"...\" }}  "
                             f"# left out: {optional[target]}")
            else:
                lines.append(f"{target} = {{ name = \"?\", unit = \"?\" }}  # not found: SET IT")
            continue
        fields = [f"name = {_toml_string(c.name)}"]
        if c.group:
            fields.append(f"group = {_toml_string(c.group)}")
        unit = c.unit or "?"
        fields.append(f"unit = {_toml_string(unit)}")
        if _kind(c.unit) == "voltage" and TARGETS[target] == "current":
            fields.append('scale = "? A/V"')
        note = "" if c.unit else "  # the file declares no unit: SET IT"
        lines.append(f"{target} = {{ {', '.join(fields)} }}{note}")
    lines += ["", "# every channel of the file:"]
    lines += [f"#   {c.label!r} " + ("(text, not read)" if c.text is not None else
                                          f"[{c.unit or '-'}]") for c in info.channels[:200]]
    lines += [f"# {_printable(s)}" for s in info.skipped]
    return "\n".join(lines) + "\n"
