"""Charts as SVG text: what the fleet pages need of a plotting library, without one.

A fleet site draws two figures per actuator, thousands of them; matplotlib took 0.2 s of
CPU per figure (its text layout and rasterisation), most of a cold build. The pages'
figures are simple (lines, points, error bars, a band, reference lines, a legend), so
they are written here as SVG that the browser draws: a few milliseconds each, sharp at
any zoom, and a pure function of the data (the same input gives the same bytes).

The content is data: a :class:`Panel` holds named :class:`Layer` objects in data
coordinates, its limits and texts; :func:`render` lays panels out in pixel boxes and
writes the document. Nothing here knows about actuators (:mod:`emaphm.fleet.figures` does).
Colours follow matplotlib's default cycle (``C0``..``C3``) and grey levels (``"0.6"``),
so the pages look like ``emaphm prognose --plot``.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np

from .markup import esc

__all__ = ["Layer", "Panel", "render", "nice_ticks", "COLORS"]

#: matplotlib's default colour cycle and the greys the figures use.
COLORS = {"C0": "#1f77b4", "C1": "#ff7f0e", "C2": "#2ca02c", "C3": "#d62728", "k": "#000000",
          "0.5": "#808080", "0.6": "#999999"}

#: Kinds of :class:`Layer`.
KINDS = ("line", "points", "hollow", "errorbars", "band", "hline", "vline", "bar", "diamond")

_FONT = "DejaVu Sans, Verdana, Arial, sans-serif"
_PT = 100.0 / 72.0          # pixels per typographic point at the pages' 100 px per inch


@dataclass(frozen=True)
class Layer:
    """One thing drawn in a panel, in data coordinates.

    ``kind`` is one of :data:`KINDS`: a ``line`` through (x, y) (broken at non-finite
    values), ``points`` / ``hollow`` circles or ``diamond`` markers at (x, y), ``errorbars``
    from y to ``y2`` at each x, a ``band`` between y and ``y2`` over x, an ``hline`` at each
    y or a ``vline`` at each x across the panel, a thick ``bar`` along (x, y).
    ``label`` names it in the panel's legend ("" for none).
    """

    kind: str
    x: np.ndarray
    y: np.ndarray
    y2: np.ndarray | None = None
    color: str = "C0"
    label: str = ""
    width: float | None = None                 # a line's width in points (default 1.3)

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"unknown layer kind {self.kind!r}; choose one of {', '.join(KINDS)}")
        for name in ("x", "y", "y2"):
            v = getattr(self, name)
            if v is not None:
                object.__setattr__(self, name, np.atleast_1d(np.asarray(v, dtype=float)))

    @property
    def empty(self) -> bool:
        return (self.x.size if self.kind == "vline" else self.y.size) == 0


@dataclass(frozen=True)
class Panel:
    """One set of axes: limits, texts and layers (drawn in their order)."""

    title: str
    xlim: tuple[float, float]
    ylim: tuple[float, float]
    layers: Mapping[str, Layer]
    xlabel: str = ""
    ylabel: str = ""
    xticklabels: bool = True
    legend: bool = False                       # the labelled layers, at the upper left
    notes: tuple[tuple[str, str], ...] = ()    # (text, "bottom" | "top") at the right, red


def nice_ticks(lo: float, hi: float, n: int = 6) -> tuple[np.ndarray, float]:
    """At most about ``n`` + 1 round tick values in [lo, hi] (steps 1, 2, 2.5 or 5 times a
    power of ten) and their step."""
    span = hi - lo
    if not (math.isfinite(lo) and math.isfinite(hi)) or span <= 0:
        return np.array([lo if math.isfinite(lo) else 0.0]), 1.0
    raw = span / max(n, 1)
    mag = 10.0 ** math.floor(math.log10(raw))
    step = next(m * mag for m in (1.0, 2.0, 2.5, 5.0, 10.0) if m * mag >= raw * (1 - 1e-12))
    first = math.ceil(lo / step - 1e-9)
    last = math.floor(hi / step + 1e-9)
    ticks = np.arange(first, last + 1) * step
    ticks[np.abs(ticks) < step * 1e-9] = 0.0
    return ticks, step


def _tick_label(v: float, step: float) -> str:
    if abs(v) < step * 1e-9:
        return "0"
    power = math.floor(math.log10(step) + 1e-12)
    if abs(v) >= 1e6 or step < 1e-4:          # the significant digits the step needs
        digits = math.floor(math.log10(abs(v))) - power + 1
        return f"{v:.{max(digits, 1) + 1}g}".replace("-", "\u2212")
    decimals = max(0, -power + (round(step / 10.0 ** power, 6) == 2.5))   # 0.25, 2.5: one more
    text = f"{v:.{decimals}f}"
    return "0" if float(text) == 0 else text.replace("-", "\u2212")


def _num(v: float) -> str:
    """A pixel coordinate: two decimals, no trailing zeros, clamped far outside the box."""
    v = min(max(v, -1e5), 1e5)
    s = f"{v:.2f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def _color(c: str) -> str:
    return COLORS.get(c, c)


#: Characters XML 1.0 does not allow in a document, even escaped.
_NOT_XML = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ud800-\udfff\ufffe\uffff]")


def _text(x: float, y: float, s: str, size: float, *, anchor: str = "start",
          color: str = "#000000", rotate: bool = False) -> str:
    rot = f' transform="rotate(-90 {_num(x)} {_num(y)})"' if rotate else ""
    return (f'<text x="{_num(x)}" y="{_num(y)}" font-size="{size * _PT:.1f}" '
            f'text-anchor="{anchor}" fill="{color}"{rot}>'
            f'{esc(_NOT_XML.sub(chr(0xFFFD), s))}</text>')


def _text_width(s: str, size: float) -> float:
    """An estimate of the width in pixels of ``s`` at ``size`` points (DejaVu Sans)."""
    return 0.62 * size * _PT * len(s)


class _Box:
    """A panel's pixel box and its data-to-pixel maps."""

    def __init__(self, panel: Panel, box: tuple[float, float, float, float]) -> None:
        self.x0, self.y0, self.w, self.h = box
        self.xlo, self.xhi = _limits(panel.xlim)
        self.ylo, self.yhi = _limits(panel.ylim)

    def X(self, x: np.ndarray) -> np.ndarray:
        return self.x0 + (np.asarray(x, dtype=float) - self.xlo) / (self.xhi - self.xlo) * self.w

    def Y(self, y: np.ndarray) -> np.ndarray:
        return self.y0 + self.h - (np.asarray(y, dtype=float) - self.ylo) / (
            self.yhi - self.ylo) * self.h


def _limits(lim: tuple[float, float]) -> tuple[float, float]:
    """Axis limits that map: finite and increasing ((0, 1) where they are not finite)."""
    lo, hi = (float(v) for v in lim)
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return 0.0, 1.0
    return (lo, hi) if hi > lo else (lo, lo + 1.0)


def _runs(ok: np.ndarray) -> list[slice]:
    """The stretches where ``ok`` is true."""
    edges = np.flatnonzero(np.diff(np.r_[0, ok.astype(np.int8), 0]))
    return [slice(a, b) for a, b in zip(edges[::2], edges[1::2])]


def _path(px: np.ndarray, py: np.ndarray) -> str:
    """An SVG path through the points, broken where a coordinate is not finite."""
    ok = np.isfinite(px) & np.isfinite(py)
    parts, pen = [], False
    for x, y, good in zip(px, py, ok):
        if good:
            parts.append(f"{'L' if pen else 'M'}{_num(x)} {_num(y)}")
        pen = bool(good)
    return "".join(parts)


def _layer(b: _Box, layer: Layer) -> str:
    c = _color(layer.color)
    x, y = b.X(layer.x), b.Y(layer.y)
    k = layer.kind
    if k == "line":
        d = _path(x, y)
        w = (1.3 if layer.width is None else layer.width) * _PT
        return f'<path d="{d}" fill="none" stroke="{c}" stroke-width="{w:.2f}"/>' if d else ""
    if k in ("points", "hollow"):
        fill = "none" if k == "hollow" else c
        return "".join(f'<circle cx="{_num(a)}" cy="{_num(v)}" r="2.8" fill="{fill}" '
                       f'stroke="{c}"/>' for a, v in zip(x, y)
                       if math.isfinite(a) and math.isfinite(v))
    if k == "diamond":
        return "".join(_diamond(a, v, c) for a, v in zip(x, y)
                       if math.isfinite(a) and math.isfinite(v))
    if k == "errorbars":
        y2 = b.Y(layer.y2)
        d = "".join(f"M{_num(a)} {_num(u)}V{_num(v)}M{_num(a - 2.8)} {_num(u)}h5.6"
                    f"M{_num(a - 2.8)} {_num(v)}h5.6" for a, u, v in zip(x, y, y2)
                    if math.isfinite(a) and math.isfinite(u) and math.isfinite(v))
        return f'<path d="{d}" fill="none" stroke="{c}" stroke-width="{_PT:.2f}"/>' if d else ""
    if k == "band":                     # a closed polygon per stretch where both edges exist
        y2 = b.Y(layer.y2)
        d = "".join(_path(np.r_[x[s], x[s][::-1]], np.r_[y[s], y2[s][::-1]]) + "Z"
                    for s in _runs(np.isfinite(x) & np.isfinite(y) & np.isfinite(y2)))
        return f'<path d="{d}" fill="{c}" fill-opacity="0.18" stroke="none"/>' if d else ""
    if k == "hline":
        return "".join(f'<path d="M{_num(b.x0)} {_num(v)}h{_num(b.w)}" stroke="{c}" '
                       f'stroke-width="{_PT:.2f}" stroke-dasharray="5 3"/>'
                       for v in y if math.isfinite(v))
    if k == "vline":
        return "".join(f'<path d="M{_num(a)} {_num(b.y0)}v{_num(b.h)}" stroke="{c}" '
                       f'stroke-width="{0.8 * _PT:.2f}"/>' for a in x if math.isfinite(a))
    d = _path(x, y)                                                        # bar
    return (f'<path d="{d}" stroke="{c}" stroke-opacity="0.6" stroke-width="{6 * _PT:.1f}" '
            'fill="none"/>' if d else "")


def _diamond(x: float, y: float, c: str) -> str:
    """matplotlib's ``"D"`` marker at 7 points: a square of 13.7 px diagonal, on its tip."""
    r = 3.5 * 1.41421356 * _PT
    return (f'<path d="M{_num(x)} {_num(y - r)}L{_num(x + r)} {_num(y)}L{_num(x)} {_num(y + r)}'
            f'L{_num(x - r)} {_num(y)}Z" fill="{c}"/>')


def legend_key(kind: str, color: str, x: float, y: float) -> str:
    """The small sample of a layer's look that a legend shows, centred at (x, y)."""
    c = _color(color)
    if kind in ("points", "hollow"):
        return (f'<circle cx="{_num(x)}" cy="{_num(y)}" r="2.8" '
                f'fill="{"none" if kind == "hollow" else c}" stroke="{c}"/>')
    if kind == "diamond":
        return _diamond(x, y, c)
    if kind == "band":
        return (f'<rect x="{_num(x - 10)}" y="{_num(y - 5)}" width="20" height="10" fill="{c}" '
                'fill-opacity="0.18"/>')
    width = {"bar": 6 * _PT, "line": 1.3 * _PT}.get(kind, _PT)
    dash = ' stroke-dasharray="5 3"' if kind == "hline" else ""
    opacity = ' stroke-opacity="0.6"' if kind == "bar" else ""
    return (f'<path d="M{_num(x - 10)} {_num(y)}h20" stroke="{c}" stroke-width="{width:.2f}"'
            f'{dash}{opacity}/>')


def _axes(panel: Panel, box: tuple[float, float, float, float], clip: str) -> str:
    b = _Box(panel, box)
    out = [f'<clipPath id="{clip}"><rect x="{_num(b.x0)}" y="{_num(b.y0)}" width="{_num(b.w)}" '
           f'height="{_num(b.h)}"/></clipPath>']
    grid, labels = [], []
    xt, xs = nice_ticks(b.xlo, b.xhi, max(2, int(b.w // 110)))
    for v in xt:
        px = float(b.X(v))
        grid.append(f"M{_num(px)} {_num(b.y0)}v{_num(b.h)}")
        if panel.xticklabels:
            labels.append(_text(px, b.y0 + b.h + 14, _tick_label(v, xs), 8, anchor="middle"))
    yt, ys = nice_ticks(b.ylo, b.yhi, max(2, int(b.h // 35)))
    for v in yt:
        py = float(b.Y(v))
        grid.append(f"M{_num(b.x0)} {_num(py)}h{_num(b.w)}")
        labels.append(_text(b.x0 - 5, py + 4, _tick_label(v, ys), 8, anchor="end"))
    out.append(f'<path d="{"".join(grid)}" stroke="#b0b0b0" stroke-opacity="0.5" '
               'stroke-width="0.8"/>')
    out.append(f'<g clip-path="url(#{clip})">')
    out += [_layer(b, layer) for layer in panel.layers.values() if not layer.empty]
    out.append("</g>")
    out.append(f'<rect x="{_num(b.x0)}" y="{_num(b.y0)}" width="{_num(b.w)}" height="{_num(b.h)}" '
               'fill="none" stroke="#000000" stroke-width="0.8"/>')
    out += labels
    out.append(_text(b.x0 + b.w / 2, b.y0 - 6, panel.title, 9, anchor="middle"))
    if panel.xlabel:
        out.append(_text(b.x0 + b.w / 2, b.y0 + b.h + 32, panel.xlabel, 9, anchor="middle"))
    if panel.ylabel:
        out.append(_text(b.x0 - 52, b.y0 + b.h / 2, panel.ylabel, 9, anchor="middle",
                         rotate=True))
    for text, where in panel.notes:
        if text:
            y = b.y0 + 16 if where == "top" else b.y0 + b.h - 8
            out.append(_text(b.x0 + b.w - 6, y, text, 8, anchor="end", color=COLORS["C3"]))
    if panel.legend:
        keys = [(layer.kind, layer.color, layer.label) for layer in panel.layers.values()
                if layer.label]
        if keys:
            w = 34 + max(_text_width(t, 7) for _, _, t in keys)
            h = 8 + 14 * len(keys)
            out.append(f'<rect x="{_num(b.x0 + 6)}" y="{_num(b.y0 + 6)}" width="{_num(w)}" '
                       f'height="{h}" fill="#ffffff" fill-opacity="0.8" stroke="#cccccc"/>')
            for i, (kind, color, text) in enumerate(keys):
                y = b.y0 + 17 + 14 * i
                out.append(legend_key(kind, color, b.x0 + 22, y))
                out.append(_text(b.x0 + 38, y + 3.5, text, 7))
    return "".join(out)


def render(width: int, height: int, panels: Sequence[tuple[Panel, tuple[float, float, float,
                                                                           float]]], *,
           title: str = "", legend: Sequence[tuple[str, str, str]] = (),
           legend_y: float = 0.0) -> bytes:
    """An SVG document ``width`` x ``height`` pixels of ``panels``, each with its pixel box
    (left, top, width, height); ``title`` centred at the top; ``legend`` (kind, colour,
    text) as one centred row at ``legend_y`` pixels from the top."""
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
           f'viewBox="0 0 {width} {height}" font-family="{_FONT}">',
           f'<rect width="{width}" height="{height}" fill="#ffffff"/>']
    if title:
        out.append(_text(width / 2, 22, title, 10, anchor="middle"))
    if legend:
        widths = [30 + _text_width(t, 7) + 14 for _, _, t in legend]
        x = (width - sum(widths)) / 2
        for (kind, color, text), w in zip(legend, widths):
            out.append(legend_key(kind, color, x + 12, legend_y))
            out.append(_text(x + 28, legend_y + 3.5, text, 7))
            x += w
    out += [_axes(p, box, f"c{i}") for i, (p, box) in enumerate(panels)]
    out.append("</svg>\n")
    return "\n".join(out).encode("utf-8")
