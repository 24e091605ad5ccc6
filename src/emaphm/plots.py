"""Figures from results. Plots only read traces and results; they never simulate."""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

    from .diagnosis import Diagnosis
    from .identify import Identification
    from .traces import Trace

__all__ = ["plot_trace", "plot_identification", "plot_calibration", "save_figure", "verdict_line"]

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
    from ._files import atomic_write

    fmt = p.suffix[1:].lower() or "png"
    return atomic_write(p, lambda fh: fig.savefig(fh, dpi=dpi, format=fmt))


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


def verdict_line(diagnosis: "Diagnosis") -> str:
    """The verdict of a diagnosis in a few words, as a figure's title says it:
    ``HEALTHY``, ``FAULTY: friction, short circuit (phase a)`` or ``UNEXPLAINED
    (misfit)``."""
    if diagnosis.unexplained is not None:
        return f"UNEXPLAINED ({diagnosis.unexplained.reason})"
    if not diagnosis.faults:
        return "HEALTHY"
    return "FAULTY: " + ", ".join(f.mode.replace("_", " ") + (f" (phase {f.phase})" if f.phase else "")
                                  for f in diagnosis.faults)


def plot_identification(measured: "Trace", ident: "Identification", *,
                        diagnosis: "Diagnosis | None" = None,
                        path: str | os.PathLike[str] | None = None) -> "Figure":
    """Measured vs identified phase currents, their residual, and the convergence curve.

    Panels: each phase current, measured (grey) under the monitoring model at the
    identified k (dashed); the residual measured - model of the three phases with the
    band of +-2 sigma of the trace's white noise (a fit at the noise floor stays inside);
    the best fitness per iteration, the polish's polls after a dotted line, and the
    trace's noise floor (the fitness a perfect model would reach) as a dashed line.
    ``diagnosis`` (the verdict of ``ident``, :class:`emaphm.diagnosis.Diagnosis`, as
    :func:`emaphm.verdict.diagnose_identification` gives it): its verdict heads the title
    (:func:`verdict_line`); it is read, not made here (a verdict refits the model).
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    from .fitness import white_noise_sigma

    # fixed margins in inches, not a layout engine: the constrained layout measured every
    # tick label before the drawing, 0.44 s of the quick start's 1.2 s figure
    fig = Figure(figsize=(11, 11))
    w, h, gap = 11.0, 11.0, 0.62
    ax_h = (h - 1.0 - 0.62 - 4 * gap) / 5
    gs = fig.add_gridspec(5, 1, height_ratios=[1, 1, 1, 0.9, 1.1], left=1.05 / w,
                          right=1 - 0.2 / w, top=1 - 1.0 / h, bottom=0.62 / h,
                          hspace=gap / ax_h)
    model = ident.model_trace
    fixed = measured.meta.get("corrected_sensor") if isinstance(measured.meta, dict) else None
    label = "measured" if not fixed else f"measured, phase {fixed['phase']}'s sensor corrected"
    first = None
    for j, name in enumerate(_PHASES):
        a = fig.add_subplot(gs[j, 0], sharex=first)
        first = first or a
        a.plot(measured.t, measured.i_abc[:, j], color="0.45", lw=1.0,
               label=label if fixed and _PHASES[j].endswith(str(fixed["phase"]).lower())
               else "measured")
        a.plot(model.t, model.i_abc[:, j], color=f"C{j + 1}", lw=1.0, ls="--",
               label="monitoring model at k")
        a.set_ylabel(f"{name} [A]")
        a.legend(loc="upper right", fontsize=7, framealpha=0.8)
    r = fig.add_subplot(gs[3, 0], sharex=first)
    for j, name in enumerate(_PHASES):
        res = measured.i_abc[:, j] - np.interp(measured.t, model.t, model.i_abc[:, j])
        r.plot(measured.t, res, color=f"C{j + 1}", lw=0.5, label=name)
    sigma = float(np.max(white_noise_sigma(np.asarray(measured.i_abc, dtype=float))))
    if sigma > 0:
        r.axhspan(-2 * sigma, 2 * sigma, color="0.85", zorder=0, label="+-2 sigma of the noise")
    r.set_ylabel("measured - model [A]" if not fixed else "corrected - model [A]")
    r.set_xlabel("time [s]")
    r.legend(loc="upper right", fontsize=7, ncol=4, framealpha=0.8)
    c = fig.add_subplot(gs[4, 0])
    it = np.arange(1, ident.history.size + 1)
    c.semilogy(it, ident.history, color="C0", label="best fitness")
    if ident.polish_evaluations and ident.iterations < ident.history.size:
        c.axvline(ident.iterations + 0.5, color="0.3", ls=":", lw=1.0,
                  label=f"{ident.algorithm.upper()} ends, polish polls after")
    if ident.noise_floor > 0:
        c.axhline(ident.noise_floor, color="C3", ls="--", lw=1.0,
                  label="noise floor of the trace")
    c.set_xlabel("iteration (then polish poll)")
    c.set_ylabel("best fitness (Eq. 4)")
    c.grid(True, which="both", alpha=0.3)
    c.legend(loc="upper right", fontsize=7, framealpha=0.8)
    title = (f"{ident.algorithm.upper()} seed {ident.seed}: k = {np.round(ident.k, 3).tolist()}, "
             f"{ident.evaluations} evaluations in {ident.elapsed_s:.2f} s")
    if ident.error_pct is not None:
        title += f", error {ident.error_pct:.2f}% (Eq. 9)"
    if diagnosis is not None:
        title = f"verdict: {verdict_line(diagnosis)}\n{title}"
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
