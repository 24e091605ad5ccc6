"""Figures of the prognosis layer. They only read results (histories, predictions,
tracks); they never identify, fit or draw random numbers."""

from __future__ import annotations

import math
import os
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from ..faults import K_LABELS
from ..plots import save_figure
from .thresholds import DEFAULT_FAILURE_THRESHOLDS, INDICATOR_COMPONENT, FailureThresholds

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

    from .history import HistoryData
    from .trends import Prognosis, RULTrack

__all__ = ["plot_history", "plot_prognosis", "plot_alpha_lambda"]


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
                 path: str | os.PathLike[str] | None = None) -> "Figure":
    """Each component of k over the inspections, with its interval and failure threshold.

    A point is red where that inspection named a fault on *that* component, green where
    it did not, grey where the verdict was ``unexplained`` (no fault named). The
    eccentricity phase k7 means nothing without eccentricity: its points are drawn
    hollow, without a line, where k6 is below its detection threshold.
    """
    fig = _figure(11, 9)
    axes = fig.subplots(4, 2, sharex=True,
                        gridspec_kw=_grid(fig, 4, 2, wgap=0.85, hgap=0.4)).ravel()
    t = data.times
    thr = {INDICATOR_COMPONENT[n]: thresholds.for_indicator(n) for n in INDICATOR_COMPONENT}
    status = component_status(data)
    for j, ax in enumerate(axes):
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
            for state, color in (("healthy", "C2"), ("faulty", "C3"), ("unexplained", "0.5")):
                sel = show & (status[:, j] == state)
                if sel.any():
                    ax.plot(t[sel], data.K[sel, j], "o", color=color, ms=4, label=state)
        if j in thr:
            if j == 7:
                for y in (0.5 - thr[j], 0.5 + thr[j]):
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
    fig.suptitle(f"health history of {data.actuator.id}"
                 + (f" ({data.actuator.description})" if data.actuator.description else "")
                 + f": {data.n} inspections", fontsize=10)
    if path is not None:
        save_figure(fig, path)
    return fig


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


def _interesting(prog: "Prognosis", n: int = 3) -> list[str]:
    """The indicators whose threshold is nearest, growing ones only (at least one):
    finite median first, then most likely."""
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
    from .trends import indicator_series

    names = list(indicators) if indicators is not None else _interesting(prog)
    for n in names:
        if n not in prog.predictions:
            raise ValueError(f"no prediction for indicator {n!r}; have {', '.join(prog.predictions)}")
    series = indicator_series(prog.K)
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
        ax.plot(t, series[name], "o", color="k", ms=4, label="identified")
        ax.axhline(p.threshold, color="C3", ls="--", lw=1.0, label="failure threshold")
        ax.axvline(p.t_now, color="0.5", lw=0.8)
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
        top = max(p.threshold * 1.25, float(np.nanmax(series[name])) * 1.1)
        ax.set_ylim(min(0.0, float(np.nanmin(series[name])) - 0.01), top)
        ax.set_ylabel(name + (" (k8 - 0.5, signed)" if name == "gain_drift" else ""))
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="upper left")
    axes[-1].set_xlabel(f"time [{_unit(prog.time_unit)}]")
    fig.suptitle(title or (f"prognosis of {prog.actuator or 'actuator'} at {prog.t_now:g} "
                           f"{_unit(prog.time_unit)} ({prog.times.size} inspections)"), fontsize=10)
    if path is not None:
        save_figure(fig, path)
    return fig


def plot_alpha_lambda(tracks: Sequence["RULTrack"], eol: float | Sequence[float], *,
                      alpha: float = 0.2, labels: Sequence[str] | None = None,
                      time_unit: str = "h", ax: Any = None, title: str | None = None,
                      path: str | os.PathLike[str] | None = None) -> "Figure":
    """Alpha-lambda plot: predicted RUL (median and interval) against the true RUL and
    its ``(1 +- alpha)`` cone, for one or several tracks (the same scenario's histories).

    The time axis is the share of life ``lambda = t / EoL`` so that tracks of
    different lives overlay.
    """
    eols = np.broadcast_to(np.asarray(eol, dtype=float), (len(tracks),))
    if ax is None:
        fig = _figure(7, 4.5)
        ax = fig.subplots(gridspec_kw=_grid(fig, 1, 1, top=0.45 if title else 0.25))
    else:
        fig = ax.figure
    lam = np.linspace(0, 1, 50)
    ax.plot(lam, 1 - lam, color="k", lw=1.2, label="true RUL")
    ax.fill_between(lam, (1 - alpha) * (1 - lam), (1 + alpha) * (1 - lam), color="0.5", alpha=0.2,
                    lw=0, label=f"alpha = {alpha:g} cone")
    for i, (tr, e) in enumerate(zip(tracks, eols)):
        x = tr.times / e
        lo = np.where(np.isfinite(tr.lo), tr.lo, np.nan) / e
        hi = np.where(np.isfinite(tr.hi), tr.hi, 2 * e) / e
        med = np.where(np.isfinite(tr.median), tr.median, np.nan) / e
        lab = labels[i] if labels is not None else None
        c = f"C{i % 10}" if len(tracks) <= 10 else "C0"
        ax.errorbar(x + 0.002 * (i - len(tracks) / 2), med,
                    yerr=np.vstack([np.clip(med - lo, 0, None), np.clip(hi - med, 0, None)]),
                    fmt="o", ms=3, color=c, ecolor=c, elinewidth=0.8, alpha=0.8 if len(tracks) < 5 else 0.35,
                    label=lab)
    ax.axvline(0.5, color="C3", ls=":", lw=0.8)
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1.3)
    ax.set_xlabel("share of life t / EoL")
    ax.set_ylabel("RUL / EoL")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="upper right")
    if title:
        ax.set_title(title, fontsize=9)
    if path is not None:
        save_figure(fig, path)
    return fig
