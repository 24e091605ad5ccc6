"""Figures from results. Plots only read traces and results; they never simulate."""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

    from .identify import Identification
    from .traces import Trace

__all__ = ["plot_trace", "plot_identification", "plot_calibration", "save_figure"]

_PHASES = ("i_a", "i_b", "i_c")


def _figure(nrows: int, height: float) -> tuple["Figure", np.ndarray]:
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10, height), layout="constrained")
    axes = np.atleast_1d(fig.subplots(nrows, 1, sharex=True))
    return fig, axes


def save_figure(fig: "Figure", path: str | os.PathLike[str], dpi: int = 120) -> Path:
    """Save atomically: a temporary file in the same folder, then a rename."""
    p = Path(path)
    if not p.parent.exists():
        raise FileNotFoundError(f"cannot write {p}: folder {p.parent} does not exist; create it first")
    tmp = p.with_name(f".{p.stem}.tmp-{os.getpid()}{p.suffix}")
    try:
        fig.savefig(tmp, dpi=dpi)
        os.replace(tmp, p)
    finally:
        tmp.unlink(missing_ok=True)
    return p


def _label(trace: "Trace", default: str) -> str:
    meta = trace.meta if isinstance(trace.meta, dict) else {}
    name = meta.get("scenario")
    model = meta.get("model")
    parts = [str(x) for x in (name, model) if x]
    return ", ".join(parts) if parts else default


def plot_trace(trace: "Trace", overlay: "Trace | None" = None, *,
               path: str | os.PathLike[str] | None = None, title: str | None = None) -> "Figure":
    """Command vs motor position and the three phase currents.

    ``overlay`` (e.g. the nominal run) is drawn dashed in grey under ``trace``.
    """
    fig, ax = _figure(4, 9.0)
    lab = _label(trace, "trace")
    ax[0].plot(trace.t, trace.theta_ref, "k--", lw=1.0, label="command")
    if overlay is not None:
        ax[0].plot(overlay.t, overlay.theta_m, color="0.6", lw=1.2, label=_label(overlay, "overlay"))
    ax[0].plot(trace.t, trace.theta_m, color="C0", lw=1.2, label=lab)
    ax[0].set_ylabel("position [rad]")
    ax[0].legend(loc="upper right", fontsize=8)
    for j, name in enumerate(_PHASES):
        a = ax[j + 1]
        if overlay is not None:
            a.plot(overlay.t, overlay.i_abc[:, j], color="0.6", lw=1.0, ls="--",
                   label=_label(overlay, "overlay"))
        a.plot(trace.t, trace.i_abc[:, j], color=f"C{j + 1}", lw=0.8, label=lab)
        a.set_ylabel(f"{name} [A]")
        a.legend(loc="upper right", fontsize=8)
    ax[-1].set_xlabel("time [s]")
    k = trace.meta.get("k") if isinstance(trace.meta, dict) else None
    fig.suptitle(title or (f"{lab}: k = {np.round(k, 3).tolist()}" if k is not None else lab), fontsize=10)
    if path is not None:
        save_figure(fig, path)
    return fig


def plot_identification(measured: "Trace", ident: "Identification", *,
                        path: str | os.PathLike[str] | None = None) -> "Figure":
    """Measured vs identified phase currents and the convergence curve."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11, 9), layout="constrained")
    gs = fig.add_gridspec(4, 1, height_ratios=[1, 1, 1, 1.1])
    model = ident.model_trace
    first = None
    for j, name in enumerate(_PHASES):
        a = fig.add_subplot(gs[j, 0], sharex=first)
        first = first or a
        a.plot(measured.t, measured.i_abc[:, j], color="0.55", lw=1.6, label="measured")
        a.plot(model.t, model.i_abc[:, j], color=f"C{j + 1}", lw=0.8, label="monitoring model at k")
        a.set_ylabel(f"{name} [A]")
        a.legend(loc="upper right", fontsize=8)
    a.set_xlabel("time [s]")
    c = fig.add_subplot(gs[3, 0])
    it = np.arange(1, ident.history.size + 1)
    c.semilogy(it, ident.history, color="C0")
    c.set_xlabel("iteration")
    c.set_ylabel("best fitness (Eq. 4)")
    c.grid(True, which="both", alpha=0.3)
    title = (f"{ident.algorithm.upper()} seed {ident.seed}: k = {np.round(ident.k, 3).tolist()}, "
             f"{ident.evaluations} evaluations in {ident.elapsed_s:.2f} s")
    if ident.error_pct is not None:
        title += f", error {ident.error_pct:.2f}% (Eq. 9)"
    fig.suptitle(title, fontsize=10)
    if path is not None:
        save_figure(fig, path)
    return fig


def plot_calibration(result, *, path: str | os.PathLike[str] | None = None,
                     source: int = 0) -> "Figure":
    """Measured vs calibrated monitoring-model currents of one source trace, and the residual.

    ``result`` is an :class:`emaphm.calibration.CalibrationResult`; ``source`` the index of
    the trace to draw.
    """
    fig, ax = _figure(4, 9.0)
    t, meas, model = result.fits[source]
    name = list(result.fit_ratio)[source]
    for j, ph in enumerate(_PHASES):
        ax[j].plot(t, meas[:, j], color="0.55", lw=1.6, label="measured")
        ax[j].plot(t, model[:, j], color=f"C{j + 1}", lw=0.8, label="calibrated model")
        ax[j].set_ylabel(f"{ph} [A]")
        ax[j].legend(loc="upper right", fontsize=8)
    for j, ph in enumerate(_PHASES):
        ax[3].plot(t, meas[:, j] - model[:, j], color=f"C{j + 1}", lw=0.6, label=ph)
    ax[3].set_ylabel("measured - model [A]")
    ax[3].legend(loc="upper right", fontsize=8, ncol=3)
    ax[3].set_xlabel("time [s]")
    est = [f"{n} {e['value']:+.3f}" for n, e in result.estimates.items()]
    fig.suptitle(f"calibration on {name}: fit {result.fit_ratio[name]:.2f}x the noise floor\n"
                 "deviations from the data sheet: " + ", ".join(est[:7])
                 + ("\n" + ", ".join(est[7:]) if len(est) > 7 else ""), fontsize=9)
    if path is not None:
        save_figure(fig, path)
    return fig
