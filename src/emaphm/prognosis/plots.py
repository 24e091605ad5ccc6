"""Figures of the prognosis layer. They only read results (histories, predictions,
tracks); they never identify, fit or draw random numbers."""

from __future__ import annotations

import math
import os
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from ..faults import K_LABELS
from ..modes import INDICATORS, axis_label
from ..plots import save_figure
from .thresholds import DEFAULT_FAILURE_THRESHOLDS, INDICATOR_COMPONENT, FailureThresholds

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

    from .history import HistoryData
    from .trends import Prognosis, RULTrack

__all__ = ["plot_history", "plot_prognosis", "plot_alpha_lambda", "ALPHA_LAMBDA_Y_MAX",
           "interesting_indicators", "moved_components", "component_status", "MOVED_SHARE",
           "STATE_COLORS"]

#: The colour of an inspection's point by what it named (:func:`component_status`), in
#: Matplotlib's colour notation; the fleet's SVG figures use the same.
STATE_COLORS = (("healthy", "C2"), ("faulty", "C3"), ("unexplained", "0.5"))


def _figure(width: float, height: float) -> "Figure":
    """A figure without a layout engine: the axes are placed at fixed margins in inches
    (:func:`_grid`). Matplotlib's constrained layout measures every tick label before the
    drawing, which doubled the time to save these many-axes figures (a fleet site draws
    two per actuator); the margins below leave room for the labels these figures have."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height))


def _grid(fig: "Figure", nrows: int, ncols: int, *, left: float = 0.8, right: float = 0.2,
          top: float = 0.65, bottom: float = 0.6, wgap: float = 0.0,
          hgap: float = 0.0) -> dict[str, float]:
    """``gridspec_kw`` placing an ``nrows`` x ``ncols`` grid at these margins and gaps
    between the axes, all in inches."""
    width, height = fig.get_size_inches()
    ax_w = max((width - left - right - (ncols - 1) * wgap) / ncols, 0.1)
    ax_h = max((height - top - bottom - (nrows - 1) * hgap) / nrows, 0.1)
    return {"left": left / width, "right": 1.0 - right / width, "top": 1.0 - top / height,
            "bottom": bottom / height, "wspace": wgap / ax_w, "hspace": hgap / ax_h}


def _unit(unit: str) -> str:
    return "flight hours" if unit == "h" else unit


def plot_history(data: "HistoryData", *, thresholds: FailureThresholds = DEFAULT_FAILURE_THRESHOLDS,
                 path: str | os.PathLike[str] | None = None,
                 components: Sequence[int] | None = None) -> "Figure":
    """Each component of k over the inspections, with its interval and failure threshold.

    ``components``: the indices of k to draw (default all eight), e.g.
    :func:`moved_components` for a page that shows only what changed.

    A point is red where that inspection named a fault on *that* component, green where
    it did not, grey where the verdict was ``unexplained`` (no fault named). The
    eccentricity phase k7 means nothing without eccentricity: its points are drawn
    hollow, without a line, where k6 is below its detection threshold.
    """
    shown = list(range(8)) if components is None else sorted({int(c) for c in components})
    if not shown or not all(0 <= c < 8 for c in shown):
        raise ValueError(f"components must be indices of k in 0..7, got {components!r}")
    nrows = (len(shown) + 1) // 2
    fig = _figure(11, 1.2 + 1.95 * nrows)          # 9 in for all eight
    grid = fig.subplots(nrows, 2, sharex=True, squeeze=False,
                        gridspec_kw=_grid(fig, nrows, 2, wgap=0.85, hgap=0.4)).ravel()
    for ax in grid[len(shown):]:                 # an odd count leaves one cell empty
        ax.set_visible(False)
    axes = grid[:len(shown)]
    t = data.times
    thr = {INDICATOR_COMPONENT[n]: thresholds.for_indicator(n) for n in INDICATOR_COMPONENT}
    center = {i.component: i.center for i in INDICATORS.values() if i.center is not None}
    status = component_status(data)
    for j, ax in zip(shown, axes):
        if data.n:
            err = np.vstack([data.K[:, j] - data.K_lo[:, j], data.K_hi[:, j] - data.K[:, j]])
            show = np.ones(data.n, dtype=bool)
            if j == 6:                       # the phase of an eccentricity that is not there
                show = status[:, 5] == "faulty"
                ax.plot(t[~show], data.K[~show, j], "o", mfc="none", color="0.6", ms=4,
                        label="no eccentricity: phase meaningless")
            if show.any():
                ax.errorbar(t[show], data.K[show, j], yerr=np.clip(err[:, show], 0, None), fmt="-",
                            color="C0", lw=1.0, ecolor="0.6", capsize=2)
            for state, color in STATE_COLORS:
                sel = show & (status[:, j] == state)
                if sel.any():
                    ax.plot(t[sel], data.K[sel, j], "o", color=color, ms=4, label=state)
        if j in thr:
            if j in center:                  # |k - c| at its threshold on either side
                for y in (center[j] - thr[j], center[j] + thr[j]):
                    ax.axhline(y, color="C3", ls="--", lw=1.0)
            else:
                ax.axhline(thr[j], color="C3", ls="--", lw=1.0, label="failure threshold")
        ax.set_title(f"k{j + 1}: {K_LABELS[j]}", fontsize=9)
        ax.set_ylabel(f"k{j + 1} [-]")
        ax.grid(True, alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=6, loc="best")
    for ax in axes[-2:]:
        ax.set_xlabel(f"time [{_unit(data.actuator.time_unit)}]")
        ax.xaxis.set_tick_params(labelbottom=True)
    hidden = 8 - len(shown)
    fig.suptitle(f"health history of {data.actuator.id}"
                 + (f" ({data.actuator.description})" if data.actuator.description else "")
                 + f": {data.n} inspections"
                 + (f"; {hidden} other components not shown (each stayed below "
                    f"{MOVED_SHARE:.0%} of its threshold)" if hidden and components is not None
                    and set(shown) >= set(moved_components(data, thresholds)) else
                    f"; {hidden} components not shown" if hidden else ""), fontsize=10)
    if path is not None:
        save_figure(fig, path)
    return fig


#: A component "moved" when it reached this share of its failure threshold (for the
#: gain drift: of its distance from 0.5) at some inspection, or was named faulty.
MOVED_SHARE = 0.25


def moved_components(data: "HistoryData", thresholds: FailureThresholds = DEFAULT_FAILURE_THRESHOLDS,
                     always: Sequence[int] = ()) -> list[int]:
    """The indices of k worth a panel: those that reached :data:`MOVED_SHARE` of their
    failure threshold or were named faulty at some inspection, with the eccentricity phase
    beside a moved eccentricity and ``always``; the friction alone when nothing moved."""
    out = {int(c) for c in always}
    if data.n:
        status = component_status(data)
        for name, c in INDICATOR_COMPONENT.items():
            x = INDICATORS[name].of_k(data.K)
            if np.any(x >= MOVED_SHARE * thresholds.for_indicator(name)) \
                    or np.any(status[:, c] == "faulty"):
                out.add(c)
    if 5 in out:
        out.add(6)
    return sorted(out) or [0]


def component_status(data: "HistoryData") -> np.ndarray:
    """``(n_inspections, 8)`` of ``"healthy"``, ``"faulty"`` or ``"unexplained"``: whether
    each inspection named a fault on each component of k (its diagnosis' ``component``
    fields, e.g. ``"k3"`` or ``"k6,k7"``)."""
    out = np.full((data.n, 8), "healthy", dtype=object)
    for i, ins in enumerate(data.inspections):
        diag = ins.diagnosis or {}
        if diag.get("verdict") == "unexplained":
            out[i, :] = "unexplained"
            continue
        for f in diag.get("faults", []):
            for comp in str(f.get("component", "")).split(","):
                comp = comp.strip()
                if comp.startswith("k") and comp[1:].isdigit() and 1 <= int(comp[1:]) <= 8:
                    out[i, int(comp[1:]) - 1] = "faulty"
    return out


def interesting_indicators(prog: "Prognosis", n: int = 3) -> list[str]:
    """The ``n`` indicators worth a panel of :func:`plot_prognosis`, whose threshold is
    nearest: growing ones only (at least one), finite median first, then most likely.
    The fleet site draws these beside the worst."""
    span = float(prog.times[-1] - prog.times[0])
    preds = list(prog.predictions.values())
    preds.sort(key=lambda p: (p.no_growth(span), not math.isfinite(p.median), p.median,
                              -p.p_reach))
    growing = [p for p in preds if not p.no_growth(span)]
    return [p.indicator for p in (growing or preds[:1])[:n]]


def plot_prognosis(prog: "Prognosis", *, indicators: Sequence[str] | None = None,
                   eol_true: dict | None = None, path: str | os.PathLike[str] | None = None,
                   horizon: float | None = None, title: str | None = None) -> "Figure":
    """Trend, failure threshold and prediction cone of each indicator, with the RUL interval.

    ``indicators`` defaults to the three whose threshold is nearest;
    ``eol_true`` (indicator -> time) marks a known end of life (simulations);
    ``horizon`` how far past the last inspection to draw (default: past the
    largest finite upper RUL bound, at most 1.5 times the history's span).
    """
    names = list(indicators) if indicators is not None else interesting_indicators(prog)
    for n in names:
        if n not in prog.predictions:
            raise ValueError(f"no prediction for indicator {n!r}; have {', '.join(prog.predictions)}")
    fig = _figure(10, 3.2 * len(names) + 0.6)
    axes = np.atleast_1d(fig.subplots(len(names), 1,
                                      gridspec_kw=_grid(fig, len(names), 1, hgap=0.75)))
    t = prog.times
    span = max(float(t[-1] - t[0]), 1e-9)
    for ax, name in zip(axes, names):
        p = prog.predictions[name]
        flat = p.no_growth(span)
        if horizon is None and flat:          # nothing to reach: do not stretch the axis
            h = 0.5 * span
        elif horizon is None:
            ends = [x for x in (p.hi, p.median) if math.isfinite(x)]
            h = min(max(ends) * 1.15 if ends else 0.5 * span, 1.5 * span)
            if eol_true and name in eol_true:
                h = max(h, 1.05 * (eol_true[name] - p.t_now))
        else:
            h = horizon
        grid = np.linspace(float(t[0]), p.t_now + max(h, 0.05 * span), 300)
        lo, mid, hi = p.band(grid, (0.05, 0.5, 0.95))
        ax.fill_between(grid, lo, hi, color="C0", alpha=0.18, lw=0, label="trend, 90 % cone")
        ax.plot(grid, mid, color="C0", lw=1.3, label=f"trend ({p.model})")
        t_y, y = prog.readings(name)
        ax.plot(t_y, y, "o", color="k", ms=4, label="identified")
        ax.axhline(p.threshold, color="C3", ls="--", lw=1.0, label="failure threshold")
        ax.axvline(p.t_now, color="0.5", lw=0.8)
        if (note := p.extrapolated.partition(":")[0] or p.beyond(grid)):    # k lies in [0, 1]
            ax.text(0.99, 0.04, note, transform=ax.transAxes, ha="right", fontsize=8, color="C3")
        if flat:
            ax.text(0.99, 0.95, f"no growth: P(reaching the threshold within "
                    f"{10 * span:.0f} {_unit(prog.time_unit)}) = {p.p_fail_within(10 * span):.2f}",
                    transform=ax.transAxes, ha="right", va="top", fontsize=8, color="C3")
        elif math.isfinite(p.lo):
            x0 = p.t_now + p.lo
            x1 = p.t_now + p.hi if math.isfinite(p.hi) else grid[-1]
            ax.plot([x0, x1], [p.threshold, p.threshold], color="C1", lw=6, alpha=0.6,
                    solid_capstyle="butt", label=f"RUL {p.level:.0%} interval")
        if math.isfinite(p.median) and not flat:
            ax.plot([p.t_now + p.median], [p.threshold], "D", color="C1", ms=7, label="median")
        if eol_true and name in eol_true:
            ax.axvline(eol_true[name], color="C3", lw=1.0, ls=":", label="true end of life")
        med = f"{p.median:.0f}" if math.isfinite(p.median) else "not reached"
        hi_txt = f"{p.hi:.0f}" if math.isfinite(p.hi) else "inf"
        ax.set_title(f"{name}: no growth" if flat else
                     f"{name}: RUL median {med} [{p.lo:.0f}, {hi_txt}] {_unit(prog.time_unit)}",
                     fontsize=9)
        top = max(p.threshold * 1.25, float(np.nanmax(y, initial=0.0)) * 1.1)
        ax.set_ylim(min(0.0, float(np.nanmin(y, initial=0.0)) - 0.01), top)
        ax.set_ylabel(axis_label(name))
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="upper left")
    axes[-1].set_xlabel(f"time [{_unit(prog.time_unit)}]")
    fig.suptitle(title or (f"prognosis of {prog.actuator or 'actuator'} at {prog.t_now:g} "
                           f"{_unit(prog.time_unit)} ({prog.times.size} inspections)"), fontsize=10)
    if path is not None:
        save_figure(fig, path)
    return fig


#: Highest RUL / EoL the alpha-lambda plot draws: larger values (and intervals without an
#: upper bound) are clipped to the top edge, drawn as up-triangles and counted in a note.
ALPHA_LAMBDA_Y_MAX = 2.5


def plot_alpha_lambda(tracks: Sequence["RULTrack"], eol: float | Sequence[float], *,
                      alpha: float = 0.2, labels: Sequence[str] | None = None,
                      time_unit: str = "h", ax: Any = None, title: str | None = None,
                      path: str | os.PathLike[str] | None = None,
                      y_max: float = ALPHA_LAMBDA_Y_MAX) -> "Figure":
    """Alpha-lambda plot: predicted RUL (median and interval) against the true RUL and
    its ``(1 +- alpha)`` cone, for one or several tracks (the same scenario's histories).

    The time axis is the share of life ``t / EoL`` so that tracks of different lives
    overlay; the RUL axis is ``RUL / EoL``. A dotted line marks mid-life (``t = EoL / 2``),
    from which the coverage of the true RUL is counted. Nothing leaves the axes silently:
    the axes reach every finite value up to ``y_max`` (and every prediction time); a
    median or an upper bound above ``y_max``, an upper bound that is infinite (no upper
    bound) and a median that is infinite (the threshold not reached) are drawn at the top
    edge as up-triangles, and a note on the panel says how many.
    """

    eols = np.broadcast_to(np.asarray(eol, dtype=float), (len(tracks),))
    if ax is None:
        fig = _figure(7, 4.5)
        ax = fig.subplots(gridspec_kw=_grid(fig, 1, 1, top=0.45 if title else 0.25))
    else:
        fig = ax.figure
    xs, meds, los, his = [], [], [], []
    for tr, e in zip(tracks, eols):
        xs.append(np.asarray(tr.times, dtype=float) / e)
        meds.append(np.asarray(tr.median, dtype=float) / e)   # +inf: threshold not reached
        los.append(np.asarray(tr.lo, dtype=float) / e)
        his.append(np.asarray(tr.hi, dtype=float) / e)         # +inf: no upper bound
    finite = [v[np.isfinite(v)] for v in (*meds, *los, *his)]
    finite = np.concatenate(finite) if finite else np.zeros(0)
    top = 1.3 if finite.size == 0 else float(min(max(1.3, 1.05 * finite.max()), y_max))
    bottom = 0.0 if finite.size == 0 else float(min(0.0, 1.05 * finite.min()))
    x_right = max([1.0] + [float(x.max()) * 1.02 for x in xs if x.size])
    edge = top - 0.01 * (top - bottom)                # where clipped values are drawn

    lam = np.linspace(0, 1, 50)
    ax.plot(lam, 1 - lam, color="k", lw=1.2, label="true RUL")
    ax.fill_between(lam, (1 - alpha) * (1 - lam), (1 + alpha) * (1 - lam), color="0.5", alpha=0.2,
                    lw=0, label=f"alpha = {alpha:g} cone: true RUL +-{alpha:.0%}")
    n_med_out = n_med_inf = n_hi_out = n_hi_inf = 0
    many = len(tracks) >= 5
    for i, (tr, x, med, lo, hi) in enumerate(zip(tracks, xs, meds, los, his)):
        c = f"C{i % 10}" if len(tracks) <= 10 else "C0"
        if labels is not None:
            lab = labels[i]
        elif i == 0:
            lab = (f"predicted RUL: median, {tr.level:.0%} interval"
                   + (f" ({len(tracks)} histories)" if len(tracks) > 1 else ""))
        else:
            lab = None
        x = x + 0.002 * (i - len(tracks) / 2)
        med_in = np.isfinite(med) & (med <= top)
        med_up = ~med_in & ~np.isnan(med)              # above the axis or not reached
        n_med_out += int(np.sum(med_up & np.isfinite(med)))
        n_med_inf += int(np.sum(np.isinf(med)))
        hi_up = ~(np.isfinite(hi) & (hi <= top))
        n_hi_out += int(np.sum(hi_up & np.isfinite(hi)))
        n_hi_inf += int(np.sum(np.isinf(hi)))
        y = np.where(med_in, med, np.where(med_up, edge, np.nan))
        hi_c = np.where(hi_up, edge, hi)
        lo_c = np.where(np.isfinite(lo), np.minimum(lo, edge), y)
        ax.errorbar(x[med_in], y[med_in],
                    yerr=np.vstack([np.clip(y - lo_c, 0, None), np.clip(hi_c - y, 0, None)])[:, med_in],
                    fmt="o", ms=3, color=c, ecolor=c, elinewidth=0.8, alpha=0.35 if many else 0.8,
                    label=lab)
        if med_up.any():
            ax.vlines(x[med_up], lo_c[med_up], edge, color=c, lw=0.8, alpha=0.35 if many else 0.8)
        clipped = med_up | (med_in & hi_up)
        if clipped.any():
            ax.plot(x[clipped], np.full(int(clipped.sum()), edge), "^", ms=5, color=c,
                    alpha=0.5 if many else 0.9)
    ax.axvline(0.5, color="C3", ls=":", lw=0.8, label="mid-life (t = EoL / 2)")
    ax.set_xlim(0, x_right)
    ax.set_ylim(bottom, top)
    if n_med_out + n_med_inf + n_hi_out + n_hi_inf:
        ax.plot([], [], "^", ms=5, color="0.3", label=f"off the axis (above {top:.2g})")
        parts = []
        if n_med_out or n_med_inf:
            parts.append(f"{n_med_out + n_med_inf} median{'s' if n_med_out + n_med_inf != 1 else ''}"
                         + (f" ({n_med_inf} threshold not reached)" if n_med_inf else ""))
        if n_hi_out or n_hi_inf:
            parts.append(f"{n_hi_out + n_hi_inf} upper bound{'s' if n_hi_out + n_hi_inf != 1 else ''}"
                         + (f" ({n_hi_inf} unbounded)" if n_hi_inf else ""))
        ax.text(0.01, 0.02, "above the axis, drawn at its edge: " + ", ".join(parts),
                transform=ax.transAxes, ha="left", va="bottom", fontsize=7, color="0.2")
    same = len(tracks) > 0 and bool(np.all(eols == eols[0]))
    life = f"; EoL = {eols[0]:g} {_unit(time_unit)}" if same else ""
    ax.set_xlabel(f"share of life t / EoL [-]{life}")
    ax.set_ylabel("RUL / EoL [-]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="upper right")
    if title:
        ax.set_title(title, fontsize=9)
    if path is not None:
        save_figure(fig, path)
    return fig
