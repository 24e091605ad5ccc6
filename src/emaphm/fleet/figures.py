"""The two figures of an actuator's page, drawn as a fleet needs them: many, one after the
other, in the same process.

:func:`emaphm.prognosis.plots.plot_history` and :func:`~emaphm.prognosis.plots.plot_prognosis`
are the reference (``emaphm prognose --plot`` draws them); the pages show the same
content. Building a matplotlib figure (its axes, ticks and legends) cost as much as
drawing it, and the prognosis cone's quantiles, taken over the trend's draws at 300
times, half as much again. :class:`PageFigures` keeps one figure per layout (a number of
panels) and, for each actuator, sets its artists' data, limits and texts and saves it:

* history: each component of k that moved, with its interval, its failure threshold and
  the points coloured by what each inspection named (:func:`component_status`), the
  eccentricity phase hollow where there is no eccentricity; one legend for the figure,
  at the top, where the reference has one per panel, placed where it hides least;
* prognosis: per indicator the trend's 90 % cone (at :data:`CONE_POINTS` times), its
  median, the identified values, the threshold, the RUL interval and median; the notes of
  a trend without growth or extrapolated beyond the range of k.

A figure is a pure function of its inputs: one reused for other actuators draws the same
bytes as a fresh one (``tests/fleet/test_fleet_scale.py``). Matplotlib figures are not
for threads to share, so each thread has its own (:func:`page_figures`): a Dask worker
runs tasks in threads.
"""

from __future__ import annotations

import io
import math
import threading
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from ..faults import K_LABELS
from ..prognosis.thresholds import (DEFAULT_FAILURE_THRESHOLDS, INDICATOR_COMPONENT,
                                    FailureThresholds)

if TYPE_CHECKING:  # pragma: no cover
    from ..prognosis.history import HistoryData
    from ..prognosis.trends import Prognosis

__all__ = ["PageFigures", "page_figures", "CONE_POINTS"]

#: Times at which the prognosis cone is drawn (the reference takes 300; the cone is smooth
#: at a hundred across a page's width).
CONE_POINTS = 120

_STATES = (("healthy", "C2"), ("faulty", "C3"), ("unexplained", "0.5"))

_local = threading.local()


def page_figures(dpi: int, compress_level: int) -> "PageFigures":
    """This thread's :class:`PageFigures` for ``dpi`` and PNG ``compress_level``."""
    key = (dpi, compress_level)
    figs = getattr(_local, "figures", None)
    if figs is None or figs.key != key:
        figs = _local.figures = PageFigures(dpi=dpi, compress_level=compress_level)
    return figs


def _unit(unit: str) -> str:
    return "flight hours" if unit == "h" else unit


def _adjust(fig: Any, nrows: int, ncols: int, *, left: float, right: float, top: float,
            bottom: float, wgap: float = 0.0, hgap: float = 0.0) -> None:
    """Place an ``nrows`` x ``ncols`` grid at these margins and gaps, in inches."""
    width, height = fig.get_size_inches()
    ax_w = max((width - left - right - (ncols - 1) * wgap) / ncols, 0.1)
    ax_h = max((height - top - bottom - (nrows - 1) * hgap) / nrows, 0.1)
    fig.subplots_adjust(left=left / width, right=1.0 - right / width, top=1.0 - top / height,
                        bottom=bottom / height, wspace=wgap / ax_w, hspace=hgap / ax_h)


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


class _HistoryPanel:
    """The artists of one component's panel, made once."""

    def __init__(self, ax: Any) -> None:
        from matplotlib.collections import LineCollection

        self.ax = ax
        self.err = LineCollection([], colors="0.6", linewidths=1.0)
        ax.add_collection(self.err)
        self.caps, = ax.plot([], [], "_", color="0.6", ms=4, mew=1.0, ls="none")
        self.line, = ax.plot([], [], "-", color="C0", lw=1.0)
        self.hollow, = ax.plot([], [], "o", mfc="none", color="0.6", ms=4, ls="none")
        self.points = {s: ax.plot([], [], "o", color=c, ms=4, ls="none")[0] for s, c in _STATES}
        self.thr = [ax.axhline(0.0, color="C3", ls="--", lw=1.0) for _ in range(2)]
        ax.grid(True, alpha=0.3)

    def draw(self, data: "HistoryData", j: int, status: np.ndarray, thr: dict, xlim: tuple,
             bottom: bool, xlabel: str) -> None:
        t, K, lo, hi = data.times, data.K[:, j], data.K_lo[:, j], data.K_hi[:, j]
        show = status[:, 5] == "faulty" if j == 6 else np.ones(t.size, dtype=bool)
        self.hollow.set_data(t[~show], K[~show])
        self.line.set_data(t[show], K[show])
        self.err.set_segments([np.array([[x, a], [x, b]]) for x, a, b in
                               zip(t[show], np.minimum(lo, K)[show], np.maximum(hi, K)[show])])
        self.caps.set_data(np.r_[t[show], t[show]], np.r_[np.minimum(lo, K)[show],
                                                           np.maximum(hi, K)[show]])
        for state, line in self.points.items():
            sel = show & (status[:, j] == state)
            line.set_data(t[sel], K[sel])
        levels = [] if j not in thr else ([0.5 - thr[j], 0.5 + thr[j]] if j == 7 else [thr[j]])
        for line, y in zip(self.thr, levels + [math.nan] * 2):
            line.set_visible(math.isfinite(y))
            line.set_ydata([y, y] if math.isfinite(y) else [0.0, 0.0])
        self.ax.set_xlim(*xlim)
        self.ax.set_ylim(*_span([*lo, *hi, *K, *levels]))
        self.ax.set_title(f"k{j + 1}: {K_LABELS[j]}", fontsize=9, y=1.0)   # y: not searched
        self.ax.set_ylabel(f"k{j + 1} [-]")
        self.ax.set_xlabel(xlabel if bottom else "")
        self.ax.xaxis.set_tick_params(labelbottom=bottom)


class _ConePanel:
    """The artists of one indicator's panel of the prognosis, made once."""

    def __init__(self, ax: Any) -> None:
        self.ax = ax
        self.cone = ax.fill_between([0.0, 1.0], [0.0, 0.0], [0.0, 0.0], color="C0", alpha=0.18,
                                    lw=0)
        self.mid, = ax.plot([], [], color="C0", lw=1.3)
        self.points, = ax.plot([], [], "o", color="k", ms=4, ls="none")
        self.thr = ax.axhline(0.0, color="C3", ls="--", lw=1.0)
        self.now = ax.axvline(0.0, color="0.5", lw=0.8)
        self.bar, = ax.plot([], [], color="C1", lw=6, alpha=0.6, solid_capstyle="butt")
        self.median, = ax.plot([], [], "D", color="C1", ms=7, ls="none")
        self.note = ax.text(0.99, 0.04, "", transform=ax.transAxes, ha="right", fontsize=8,
                            color="C3")
        self.flat = ax.text(0.99, 0.95, "", transform=ax.transAxes, ha="right", va="top",
                            fontsize=8, color="C3")
        ax.grid(True, alpha=0.3)

    def draw(self, prog: "Prognosis", name: str, y: np.ndarray, last: bool) -> None:
        p = prog.predictions[name]
        t = prog.times
        span = max(float(t[-1] - t[0]), 1e-9)
        flat = p.no_growth(span)
        ends = [x for x in (p.hi, p.median) if math.isfinite(x)]
        h = 0.5 * span if flat or not ends else min(max(ends) * 1.15, 1.5 * span)
        grid = np.linspace(float(t[0]), p.t_now + max(h, 0.05 * span), CONE_POINTS)
        lo, mid, hi = p.band(grid, (0.05, 0.5, 0.95))
        self.cone.set_verts([np.column_stack([np.r_[grid, grid[::-1]], np.r_[lo, hi[::-1]]])])
        self.mid.set_data(grid, mid)
        self.points.set_data(t, y)
        self.thr.set_ydata([p.threshold, p.threshold])
        self.now.set_xdata([p.t_now, p.t_now])
        # p.beyond(grid) takes the same quantiles again: asked only where they leave bounds
        leaves = bool(np.any(lo > p.bounds[1]) or np.any(hi < p.bounds[0]))
        self.note.set_text(p.extrapolated.partition(":")[0] or (p.beyond(grid) if leaves else ""))
        unit = _unit(prog.time_unit)
        self.flat.set_text(f"no growth: P(reaching the threshold within {10 * span:.0f} {unit}) "
                           f"= {p.p_fail_within(10 * span):.2f}" if flat else "")
        xs = [grid[0], grid[-1]]
        handles = [(self.cone, "trend, 90 % cone"), (self.mid, f"trend ({p.model})"),
                   (self.points, "identified"), (self.thr, "failure threshold")]
        if not flat and math.isfinite(p.lo):
            x1 = p.t_now + p.hi if math.isfinite(p.hi) else grid[-1]
            self.bar.set_data([p.t_now + p.lo, x1], [p.threshold, p.threshold])
            xs += [p.t_now + p.lo, x1]
            handles.append((self.bar, f"RUL {p.level:.0%} interval"))
        else:
            self.bar.set_data([], [])
        if math.isfinite(p.median) and not flat:
            self.median.set_data([p.t_now + p.median], [p.threshold])
            xs.append(p.t_now + p.median)
            handles.append((self.median, "median"))
        else:
            self.median.set_data([], [])
        self.ax.set_xlim(*_span(xs))
        top = max(p.threshold * 1.25, float(np.nanmax(y)) * 1.1)
        self.ax.set_ylim(min(0.0, float(np.nanmin(y)) - 0.01), top)
        med = f"{p.median:.0f}" if math.isfinite(p.median) else "not reached"
        hi_txt = f"{p.hi:.0f}" if math.isfinite(p.hi) else "inf"
        self.ax.set_title(f"{name}: no growth" if flat else
                          f"{name}: RUL median {med} [{p.lo:.0f}, {hi_txt}] {unit}", fontsize=9,
                          y=1.0)
        self.ax.set_ylabel(name + (" (k8 - 0.5, signed)" if name == "gain_drift" else "") + " [-]")
        self.ax.set_xlabel(f"time [{unit}]" if last else "")
        self.ax.legend([a for a, _ in handles], [b for _, b in handles], fontsize=7,
                       loc="upper left")


class PageFigures:
    """The history and prognosis figures of the pages (module docstring), as PNG bytes at
    ``dpi`` with zlib level ``compress_level``. Not for threads to share."""

    def __init__(self, *, dpi: int = 100, compress_level: int = 1) -> None:
        self.key = (dpi, compress_level)
        self.dpi = dpi
        self.compress_level = compress_level
        self._history: dict[int, tuple] = {}
        self._prognosis: dict[int, tuple] = {}

    def _png(self, fig: Any) -> tuple[bytes, int, int]:
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=self.dpi,
                    pil_kwargs={"compress_level": self.compress_level})
        w, h = fig.get_size_inches()
        return buf.getvalue(), int(round(w * self.dpi)), int(round(h * self.dpi))

    def _figure(self, width: float, height: float) -> Any:
        import matplotlib

        matplotlib.use("Agg", force=False)
        from matplotlib.figure import Figure

        return Figure(figsize=(width, height), dpi=self.dpi)

    def _history_layout(self, nrows: int) -> tuple:
        if nrows not in self._history:
            from matplotlib.lines import Line2D

            fig = self._figure(11, 1.5 + 1.95 * nrows)
            axes = fig.subplots(nrows, 2, sharex=True, squeeze=False).ravel()
            _adjust(fig, nrows, 2, left=0.8, right=0.2, top=0.95, bottom=0.6, wgap=0.85,
                    hgap=0.4)
            panels = [_HistoryPanel(ax) for ax in axes]
            keys = [Line2D([], [], marker="o", color=c, ms=4, ls="none") for _, c in _STATES]
            keys += [Line2D([], [], color="C3", ls="--", lw=1.0),
                     Line2D([], [], marker="o", mfc="none", color="0.6", ms=4, ls="none")]
            below_title = 1.0 - 0.42 / fig.get_size_inches()[1]
            fig.legend(keys, [s for s, _ in _STATES] + ["failure threshold",
                                                       "phase without eccentricity"],
                       loc="upper center", bbox_to_anchor=(0.5, below_title), ncols=5,
                       fontsize=7, frameon=False)
            title = fig.suptitle("", fontsize=10)
            self._history[nrows] = (fig, panels, title)
        return self._history[nrows]

    def history(self, data: "HistoryData", *, components: Sequence[int],
                thresholds: FailureThresholds = DEFAULT_FAILURE_THRESHOLDS,
                note: str = "") -> tuple[bytes, int, int]:
        """Each component of k in ``components`` over the inspections (PNG bytes, width and
        height in pixels); ``note`` ends the title (what is not shown)."""
        from ..prognosis.plots import component_status

        shown = sorted({int(c) for c in components})
        if not shown or not all(0 <= c < 8 for c in shown):
            raise ValueError(f"components must be indices of k in 0..7, got {components!r}")
        fig, panels, title = self._history_layout((len(shown) + 1) // 2)
        status = component_status(data)
        thr = {INDICATOR_COMPONENT[n]: thresholds.for_indicator(n) for n in INDICATOR_COMPONENT}
        xlim = _span(data.times)
        xlabel = f"time [{_unit(data.actuator.time_unit)}]"
        for k, panel in enumerate(panels):
            panel.ax.set_visible(k < len(shown))
            if k < len(shown):
                panel.draw(data, shown[k], status, thr, xlim, k >= len(shown) - 2, xlabel)
        a = data.actuator
        title.set_text(f"health history of {a.id}" + (f" ({a.description})" if a.description
                                                       else "") + f": {data.n} inspections"
                       + note)
        return self._png(fig)

    def _prognosis_layout(self, n: int) -> tuple:
        if n not in self._prognosis:
            fig = self._figure(10, 3.2 * n + 0.6)
            axes = np.atleast_1d(fig.subplots(n, 1))
            _adjust(fig, n, 1, left=0.8, right=0.2, top=0.65, bottom=0.6, hgap=0.75)
            self._prognosis[n] = (fig, [_ConePanel(ax) for ax in axes],
                                  fig.suptitle("", fontsize=10))
        return self._prognosis[n]

    def prognosis(self, prog: "Prognosis", *, indicators: Sequence[str]) -> tuple[bytes, int, int]:
        """Trend, cone, threshold and RUL of each of ``indicators`` (PNG bytes, width and
        height in pixels)."""
        from ..prognosis.trends import indicator_series

        names = list(indicators)
        for n in names:
            if n not in prog.predictions:
                raise ValueError(f"no prediction for indicator {n!r}; have "
                                 f"{', '.join(prog.predictions)}")
        if not 1 <= len(names) <= 3:
            raise ValueError(f"a page's prognosis shows 1 to 3 indicators, got {len(names)}")
        fig, panels, title = self._prognosis_layout(len(names))
        series = indicator_series(prog.K)
        for k, (panel, name) in enumerate(zip(panels, names)):
            panel.draw(prog, name, np.asarray(series[name], dtype=float), k == len(names) - 1)
        title.set_text(f"prognosis of {prog.actuator or 'actuator'} at {prog.t_now:g} "
                       f"{_unit(prog.time_unit)} ({prog.times.size} inspections)")
        return self._png(fig)
