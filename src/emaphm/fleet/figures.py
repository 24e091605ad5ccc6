"""The two figures of an actuator's page, drawn as a fleet needs them: thousands, fast.

:func:`emaphm.prognosis.plots.plot_history` and :func:`~emaphm.prognosis.plots.plot_prognosis`
are the reference (``emaphm prognose --plot`` draws them with matplotlib); the pages show
the same content as SVG written by :mod:`emaphm.fleet.svgplot` (matplotlib's text layout
and rasterisation took 0.2 s of CPU per figure, most of a fleet's cold build):

* history: each component of k that moved, with its interval, its failure threshold and
  the points coloured by what each inspection named (:func:`component_status`), the
  eccentricity phase hollow where there is no eccentricity; one legend for the figure,
  at the top, where the reference has one per panel;
* prognosis: per indicator the trend's 90 % cone (at :data:`CONE_POINTS` times), its
  median, the identified values, the threshold, the RUL interval and median; the notes of
  a trend without growth or extrapolated beyond the range of k.

What a figure shows is data first (:meth:`PageFigures.history_panels`,
:meth:`PageFigures.prognosis_panels`: :class:`~emaphm.fleet.svgplot.Panel` objects in
data coordinates, which the tests compare with the reference plots' artists), then text.
A figure is a pure function of its inputs: the same data gives the same bytes.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Sequence

import numpy as np

from ..faults import K_LABELS
from ..modes import axis_label
from ..prognosis.plots import STATE_COLORS, component_status
from ..prognosis.thresholds import (DEFAULT_FAILURE_THRESHOLDS, INDICATOR_COMPONENT,
                                    FailureThresholds)
from .svgplot import Layer, Panel, render

if TYPE_CHECKING:  # pragma: no cover
    from ..prognosis.history import HistoryData
    from ..prognosis.trends import Prognosis

__all__ = ["PageFigures", "CONE_POINTS"]

#: Times at which the prognosis cone is drawn (the reference takes 300; the cone is smooth
#: at a hundred across a page's width).
CONE_POINTS = 120



def _unit(unit: str) -> str:
    return "flight hours" if unit == "h" else unit


def _grid(nrows: int, ncols: int, width: float, height: float, *, left: float, right: float,
          top: float, bottom: float, wgap: float = 0.0, hgap: float = 0.0) -> list[tuple]:
    """The pixel boxes (left, top, width, height) of an ``nrows`` x ``ncols`` grid at these
    margins and gaps, row by row."""
    ax_w = max((width - left - right - (ncols - 1) * wgap) / ncols, 10.0)
    ax_h = max((height - top - bottom - (nrows - 1) * hgap) / nrows, 10.0)
    return [(left + c * (ax_w + wgap), top + r * (ax_h + hgap), ax_w, ax_h)
            for r in range(nrows) for c in range(ncols)]


def _span(values: Sequence[float], margin: float = 0.05, pad: float = 0.05) -> tuple[float, float]:
    """The limits matplotlib's autoscale would give ``values``: their range widened by
    ``margin`` of it on each side (``pad`` either side of a single value)."""
    v = np.asarray([x for x in values if math.isfinite(x)], dtype=float)
    if not v.size:
        return 0.0, 1.0
    lo, hi = float(v.min()), float(v.max())
    if hi - lo <= 1e-12 * max(abs(lo), abs(hi), 1.0):
        d = max(abs(lo) * pad, pad)
        return lo - d, hi + d
    d = margin * (hi - lo)
    return lo - d, hi + d


def _history_panel(data: "HistoryData", j: int, status: np.ndarray, thr: dict, xlim: tuple,
                   bottom: bool, xlabel: str) -> Panel:
    """Component ``j`` of k over the inspections."""
    t, K, lo, hi = data.times, data.K[:, j], data.K_lo[:, j], data.K_hi[:, j]
    show = status[:, 5] == "faulty" if j == 6 else np.ones(t.size, dtype=bool)
    levels = [] if j not in thr else ([0.5 - thr[j], 0.5 + thr[j]] if j == 7 else [thr[j]])
    levels = [y for y in levels if math.isfinite(y)]
    layers = {
        "errorbars": Layer("errorbars", t[show], np.minimum(lo, K)[show],
                           np.maximum(hi, K)[show], color="0.6"),
        "trend": Layer("line", t[show], K[show], color="C0", width=1.0),
        "hollow": Layer("hollow", t[~show], K[~show], color="0.6"),
        **{state: Layer("points", t[show & (status[:, j] == state)],
                        K[show & (status[:, j] == state)], color=c) for state, c in STATE_COLORS},
        "threshold": Layer("hline", [], levels, color="C3"),
    }
    return Panel(title=f"k{j + 1}: {K_LABELS[j]}", xlim=xlim,
                 ylim=_span([*lo, *hi, *K, *levels]), layers=layers,
                 xlabel=xlabel if bottom else "", ylabel=f"k{j + 1} [-]", xticklabels=bottom)


def _cone_panel(prog: "Prognosis", name: str, last: bool) -> Panel:
    """One indicator's trend, cone, threshold and RUL, with the readings it used."""
    p = prog.predictions[name]
    t = prog.times
    t_y, y = prog.readings(name)
    span = max(float(t[-1] - t[0]), 1e-9)
    flat = p.no_growth(span)
    ends = [x for x in (p.hi, p.median) if math.isfinite(x)]
    h = 0.5 * span if flat or not ends else min(max(ends) * 1.15, 1.5 * span)
    grid = np.linspace(float(t[0]), p.t_now + max(h, 0.05 * span), CONE_POINTS)
    lo, mid, hi = p.band(grid, (0.05, 0.5, 0.95))
    layers = {"cone": Layer("band", grid, lo, hi, color="C0", label="trend, 90 % cone"),
              "trend": Layer("line", grid, mid, color="C0", label=f"trend ({p.model})"),
              "identified": Layer("points", t_y, y, color="k", label="identified"),
              "threshold": Layer("hline", [], [p.threshold], color="C3",
                                 label="failure threshold"),
              "now": Layer("vline", [p.t_now], [], color="0.5")}
    xs = [grid[0], grid[-1]]
    if not flat and math.isfinite(p.lo):
        x1 = p.t_now + p.hi if math.isfinite(p.hi) else grid[-1]
        layers["rul"] = Layer("bar", [p.t_now + p.lo, x1], [p.threshold, p.threshold],
                              color="C1", label=f"RUL {p.level:.0%} interval")
        xs += [p.t_now + p.lo, x1]
    if math.isfinite(p.median) and not flat:
        layers["median"] = Layer("diamond", [p.t_now + p.median], [p.threshold], color="C1",
                                 label="median")
        xs.append(p.t_now + p.median)
    # p.beyond(grid) takes the same quantiles again: asked only where they leave bounds
    leaves = bool(np.any(lo > p.bounds[1]) or np.any(hi < p.bounds[0]))
    unit = _unit(prog.time_unit)
    notes = ((p.extrapolated.partition(":")[0] or (p.beyond(grid) if leaves else ""), "bottom"),
             (f"no growth: P(reaching the threshold within {10 * span:.0f} {unit}) "
              f"= {p.p_fail_within(10 * span):.2f}" if flat else "", "top"))
    med = f"{p.median:.0f}" if math.isfinite(p.median) else "not reached"
    hi_txt = f"{p.hi:.0f}" if math.isfinite(p.hi) else "inf"
    return Panel(title=(f"{name}: no growth" if flat else
                        f"{name}: RUL median {med} [{p.lo:.0f}, {hi_txt}] {unit}"),
                 xlim=_span(xs),
                 ylim=(min(0.0, float(np.nanmin(y, initial=0.0)) - 0.01),
                       max(p.threshold * 1.25, float(np.nanmax(y, initial=0.0)) * 1.1)),
                 layers=layers, legend=True, notes=notes,
                 xlabel=f"time [{unit}]" if last else "",
                 ylabel=axis_label(name))


class PageFigures:
    """The history and prognosis figures of the pages (module docstring), as SVG bytes
    with their size in pixels (``px_per_inch`` times the reference plots' size in inches).
    Holds no state: threads and processes may share one."""

    def __init__(self, *, px_per_inch: int = 100) -> None:
        self.px_per_inch = px_per_inch

    def history_panels(self, data: "HistoryData", *, components: Sequence[int],
                       thresholds: FailureThresholds = DEFAULT_FAILURE_THRESHOLDS
                       ) -> list[Panel]:
        """A :class:`~emaphm.fleet.svgplot.Panel` per component in ``components``."""
        shown = sorted({int(c) for c in components})
        if not shown or not all(0 <= c < 8 for c in shown):
            raise ValueError(f"components must be indices of k in 0..7, got {components!r}")
        status = component_status(data)
        thr = {INDICATOR_COMPONENT[n]: thresholds.for_indicator(n) for n in INDICATOR_COMPONENT}
        xlim = _span(data.times)
        xlabel = f"time [{_unit(data.actuator.time_unit)}]"
        return [_history_panel(data, j, status, thr, xlim, k >= len(shown) - 2, xlabel)
                for k, j in enumerate(shown)]

    @staticmethod
    def history_title(data: "HistoryData", note: str = "") -> str:
        a = data.actuator
        return (f"health history of {a.id}" + (f" ({a.description})" if a.description else "")
                + f": {data.n} inspections" + note)

    def history(self, data: "HistoryData", *, components: Sequence[int],
                thresholds: FailureThresholds = DEFAULT_FAILURE_THRESHOLDS,
                note: str = "") -> tuple[bytes, int, int]:
        """Each component of k in ``components`` over the inspections (SVG bytes, width and
        height in pixels); ``note`` ends the title (what is not shown)."""
        panels = self.history_panels(data, components=components, thresholds=thresholds)
        nrows = (len(panels) + 1) // 2
        s = self.px_per_inch / 100.0
        w, h = round(1100 * s), round((150 + 195 * nrows) * s)
        boxes = _grid(nrows, 2, w, h, left=80 * s, right=20 * s, top=95 * s, bottom=60 * s,
                      wgap=85 * s, hgap=40 * s)
        keys = [("points", c, state) for state, c in STATE_COLORS] + [
            ("hline", "C3", "failure threshold"), ("hollow", "0.6", "phase without eccentricity")]
        return render(w, h, list(zip(panels, boxes)), title=self.history_title(data, note),
                      legend=keys, legend_y=52 * s), w, h

    def prognosis_panels(self, prog: "Prognosis", *, indicators: Sequence[str]) -> list[Panel]:
        """A :class:`~emaphm.fleet.svgplot.Panel` per indicator in ``indicators`` (1 to 3)."""
        names = list(indicators)
        for n in names:
            if n not in prog.predictions:
                raise ValueError(f"no prediction for indicator {n!r}; have "
                                 f"{', '.join(prog.predictions)}")
        if not 1 <= len(names) <= 3:
            raise ValueError(f"a page's prognosis shows 1 to 3 indicators, got {len(names)}")
        return [_cone_panel(prog, name, k == len(names) - 1) for k, name in enumerate(names)]

    @staticmethod
    def prognosis_title(prog: "Prognosis") -> str:
        return (f"prognosis of {prog.actuator or 'actuator'} at {prog.t_now:g} "
                f"{_unit(prog.time_unit)} ({prog.times.size} inspections)")

    def prognosis(self, prog: "Prognosis", *, indicators: Sequence[str]) -> tuple[bytes, int, int]:
        """Trend, cone, threshold and RUL of each of ``indicators`` (SVG bytes, width and
        height in pixels)."""
        panels = self.prognosis_panels(prog, indicators=indicators)
        s = self.px_per_inch / 100.0
        w, h = round(1000 * s), round((320 * len(panels) + 60) * s)
        boxes = _grid(len(panels), 1, w, h, left=80 * s, right=20 * s, top=65 * s,
                      bottom=60 * s, hgap=75 * s)
        return render(w, h, list(zip(panels, boxes)), title=self.prognosis_title(prog)), w, h
