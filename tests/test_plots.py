"""Figures (:mod:`emaphm.plots`): what each panel shows (its data, limits, labels and
legend, read back from the returned Figure); they only read traces and results, never
simulate, and save atomically. Files go to ``tmp_path`` only."""

from __future__ import annotations

import importlib

import numpy as np
import pytest
from support import assert_png_of, legend_texts

matplotlib = pytest.importorskip("matplotlib")

from matplotlib.figure import Figure  # noqa: E402

from emaphm.identify import IdentificationConfig, identify  # noqa: E402
from emaphm.optim import PSO  # noqa: E402
from emaphm.plots import plot_identification, plot_trace, save_figure  # noqa: E402
from emaphm.simulate import simulate  # noqa: E402

# the modules themselves (a package attribute of the same name could shadow them)
monitoring = importlib.import_module("emaphm.models.monitoring")
simulate_mod = importlib.import_module("emaphm.simulate")
reference_mod = importlib.import_module("emaphm.models.reference")


@pytest.fixture(scope="module")
def faulty():
    return simulate(scenario="backlash-high", model="monitoring").with_meta(scenario="backlash-high")


@pytest.fixture(scope="module")
def nominal():
    return simulate(model="monitoring").with_meta(scenario="nominal")


@pytest.fixture(scope="module")
def ident(faulty):
    return identify(faulty, IdentificationConfig("pso", options={"pop_size": 20}, budget=100,
                                                 polish=False), seed=0)


def _covers(ax, lo, hi):
    """The x axis shows all of [lo, hi] and not much more (at most 6 % margins)."""
    x0, x1 = ax.get_xlim()
    assert x0 <= lo and x1 >= hi, ((x0, x1), (lo, hi))
    assert x1 - x0 <= 1.12 * (hi - lo), ((x0, x1), (lo, hi))


def _no_simulation(monkeypatch):
    def boom(*args, **kwargs):
        raise AssertionError("a plot ran a simulation")

    monkeypatch.setattr(monitoring.MonitoringModel, "simulate_population", boom)
    monkeypatch.setattr(monitoring.MonitoringModel, "simulate", boom)
    monkeypatch.setattr(monitoring.MonitoringModel, "weighted_sse", boom)
    monkeypatch.setattr(simulate_mod, "simulate", boom)
    # simulate imports the reference plant on first use: patched where it lives
    monkeypatch.setattr(reference_mod, "run_reference", boom)


# ----------------------------------------------------------------------------- plot_trace
def test_plot_trace_alone(faulty, tmp_path):
    path = tmp_path / "trace.png"
    fig = plot_trace(faulty, path=path)
    assert isinstance(fig, Figure)
    assert len(fig.axes) == 4
    assert [a.get_ylabel() for a in fig.axes] == ["position [rad]", "i_a [A]", "i_b [A]",
                                                  "i_c [A]"]
    # command and position on the first axes, one current per phase on the others
    assert len(fig.axes[0].lines) == 2
    np.testing.assert_array_equal(fig.axes[1].lines[0].get_ydata(), faulty.i_abc[:, 0])
    assert "backlash-high" in fig._suptitle.get_text()
    for ax in fig.axes:
        _covers(ax, faulty.t[0], faulty.t[-1])
    assert fig.axes[-1].get_xlabel() == "time [s]"
    i_a = faulty.i_abc[:, 0]
    y0, y1 = fig.axes[1].get_ylim()
    assert y0 <= i_a.min() and y1 >= i_a.max()             # no current cut off
    assert legend_texts(fig.axes[0]) == ["command", "backlash-high, monitoring"]
    assert_png_of(path, fig)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["trace.png"]


def test_plot_trace_with_overlay(faulty, nominal, tmp_path, monkeypatch):
    _no_simulation(monkeypatch)
    path = tmp_path / "overlay.png"
    fig = plot_trace(faulty, nominal, path=path)
    assert len(fig.axes) == 4
    assert len(fig.axes[0].lines) == 3
    for j, ax in enumerate(fig.axes[1:]):
        assert len(ax.lines) == 2
        ydata = [np.asarray(line.get_ydata()) for line in ax.lines]
        assert any(np.array_equal(y, nominal.i_abc[:, j]) for y in ydata)
        assert any(np.array_equal(y, faulty.i_abc[:, j]) for y in ydata)
        assert legend_texts(ax) == ["nominal, monitoring", "backlash-high, monitoring"]
    assert_png_of(path, fig)


def test_plot_trace_without_path_writes_nothing(faulty, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    fig = plot_trace(faulty, title="custom")
    assert fig._suptitle.get_text() == "custom"
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("suffix, magic", [(".svg", b"<?xml"), (".pdf", b"%PDF")])
def test_plot_trace_other_formats(faulty, tmp_path, suffix, magic):
    path = tmp_path / f"trace{suffix}"
    plot_trace(faulty, path=path)
    assert path.read_bytes().startswith(magic)


# ----------------------------------------------------------------------------- plot_identification
def test_plot_identification_reads_only(faulty, ident, tmp_path, monkeypatch):
    _no_simulation(monkeypatch)
    path = tmp_path / "ident.png"
    fig = plot_identification(faulty, ident, path=path)
    assert isinstance(fig, Figure)
    assert len(fig.axes) == 5
    # measured and model currents come from the trace and the Identification as they are
    for j, ax in enumerate(fig.axes[:3]):
        np.testing.assert_array_equal(ax.lines[0].get_ydata(), faulty.i_abc[:, j])
        np.testing.assert_array_equal(ax.lines[1].get_ydata(), ident.model_trace.i_abc[:, j])
        assert ax.lines[1].get_linestyle() == "--"          # the model does not hide the data
    # the residual panel: measured - model of each phase, on the same grid here
    res = fig.axes[3]
    assert len(res.lines) == 3 and res.get_ylabel() == "measured - model [A]"
    for j in range(3):
        np.testing.assert_allclose(res.lines[j].get_ydata(),
                                   faulty.i_abc[:, j] - ident.model_trace.i_abc[:, j], atol=1e-12)
    conv = fig.axes[4]
    np.testing.assert_array_equal(conv.lines[0].get_ydata(), ident.history)
    assert conv.get_yscale() == "log"
    assert conv.get_legend() is not None
    title = fig._suptitle.get_text()
    assert "PSO seed 0" in title and f"{ident.evaluations} evaluations" in title
    assert "(Eq. 9)" in title
    assert [a.get_ylabel() for a in fig.axes] == ["i_a [A]", "i_b [A]", "i_c [A]",
                                                  "measured - model [A]", "best fitness (Eq. 4)"]
    for ax in fig.axes[:4]:
        _covers(ax, faulty.t[0], faulty.t[-1])
        assert legend_texts(ax)                             # every panel says what it shows
    assert legend_texts(fig.axes[0]) == ["measured", "monitoring model at k"]
    assert legend_texts(res) == ["i_a", "i_b", "i_c", "+-2 sigma of the noise"]
    # the convergence axis runs over the iterations (no polish here), no further
    _covers(conv, 1, ident.history.size)
    assert ident.polish_evaluations == 0 and ident.iterations == ident.history.size
    assert conv.get_xlabel() == "iteration (then polish poll)"
    y0, y1 = conv.get_ylim()
    assert y0 <= ident.history.min() and y1 >= ident.history.max()
    assert_png_of(path, fig)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ident.png"]


def test_plot_identification_says_a_sensor_was_corrected(faulty, ident, monkeypatch):
    """The currents of a trace whose sensor the diagnosis undid are not the measured ones:
    the phase's legend and the residual's axis say so."""
    _no_simulation(monkeypatch)
    fixed = faulty.with_meta(corrected_sensor={"phase": "B", "gain": 0.8, "offset_a": 0.0})
    fig = plot_identification(fixed, ident)
    labels = [ax.get_legend().get_texts()[0].get_text() for ax in fig.axes[:3]]
    assert labels == ["measured", "measured, phase B's sensor corrected", "measured"]
    assert fig.axes[3].get_ylabel() == "corrected - model [A]"


def test_plot_identification_marks_the_polish_and_the_noise_floor(tmp_path):
    from emaphm.simulate import DEFAULT_SENSORS

    tr = simulate(scenario="friction-high", model="monitoring", sensors=DEFAULT_SENSORS, seed=1)
    ident = identify(tr, PSO(pop_size=20), seed=0)
    assert ident.polish_evaluations > 0 and ident.noise_floor > 0
    fig = plot_identification(tr, ident)
    conv = fig.axes[4]
    # the curve, the end of the metaheuristic (vertical), the noise floor (horizontal)
    assert len(conv.lines) == 3
    assert conv.lines[1].get_xdata()[0] == pytest.approx(ident.iterations + 0.5)
    assert conv.lines[2].get_ydata()[0] == pytest.approx(ident.noise_floor)
    labels = [t.get_text() for t in conv.get_legend().get_texts()]
    assert "noise floor of the trace" in labels and any("polish" in x for x in labels)
    # the noise band of the residual panel: +-2 sigma of the trace's noise (20 mA)
    (band,) = fig.axes[3].patches
    y = np.asarray(band.get_path().transformed(band.get_patch_transform()).vertices)[:, 1] \
        if not hasattr(band, "get_xy") or isinstance(band.get_xy(), tuple) \
        else np.asarray(band.get_xy())[:, 1]
    assert 0.03 < y.max() < 0.06 and y.min() == pytest.approx(-y.max())


def test_the_diagnosis_figure_heads_its_title_with_the_verdict(faulty, ident, monkeypatch):
    """HEALTHY, FAULTY with the faults named, or UNEXPLAINED with its reason: read from the
    Diagnosis given, never made by the plot (no simulation)."""
    from dataclasses import replace

    from emaphm.diagnosis import Diagnosis, Unexplained
    from emaphm.modes import Fault
    from emaphm.plots import verdict_line

    friction = Fault("friction", "k1", 0.75, 0.75, "dry friction 2.5x nominal")
    short = Fault("short_circuit", "k3", 0.3, 0.3, "inter-turn short", phase="a")
    faulty_dx = Diagnosis(k=ident.k, faults=(friction, short))
    healthy_dx = replace(faulty_dx, faults=())
    odd_dx = replace(healthy_dx, unexplained=Unexplained("misfit", 9.0, 1e-6, "calibrate it"))
    assert [d.verdict for d in (healthy_dx, faulty_dx, odd_dx)] == ["healthy", "faulty",
                                                                     "unexplained"]
    _no_simulation(monkeypatch)
    titles = [plot_identification(faulty, ident, diagnosis=d)._suptitle.get_text()
              for d in (healthy_dx, faulty_dx, odd_dx)]
    assert [t.splitlines()[0] for t in titles] == [
        "verdict: HEALTHY", "verdict: FAULTY: friction, short circuit (phase a)",
        "verdict: UNEXPLAINED (misfit)"]
    assert all("PSO seed 0" in t.splitlines()[1] for t in titles)
    assert verdict_line(faulty_dx) == "FAULTY: friction, short circuit (phase a)"
    assert "verdict" not in plot_identification(faulty, ident)._suptitle.get_text()


# ----------------------------------------------------------------------------- save_figure
def test_save_into_a_missing_folder_raises_and_leaves_nothing(faulty, tmp_path):
    target = tmp_path / "missing" / "x.png"
    with pytest.raises(FileNotFoundError, match="does not exist"):
        plot_trace(faulty, path=target)
    assert list(tmp_path.iterdir()) == []


def test_failed_save_leaves_no_temp_file_and_keeps_the_old_file(faulty, tmp_path):
    fig = plot_trace(faulty)
    target = tmp_path / "x.unknownformat"
    with pytest.raises(ValueError):                        # matplotlib: unsupported format
        save_figure(fig, target)
    assert list(tmp_path.iterdir()) == []
    # an existing figure is replaced only by a complete new one
    good = tmp_path / "x.png"
    save_figure(fig, good)
    first = good.read_bytes()
    (tmp_path / "y.png").write_bytes(b"old")

    class Broken(Figure):
        def savefig(self, fname, **kw):            # save_figure hands over an open file
            fname.write(b"half a figure")
            raise RuntimeError("disk full")

    with pytest.raises(RuntimeError, match="disk full"):
        save_figure(Broken(), tmp_path / "y.png")
    assert (tmp_path / "y.png").read_bytes() == b"old"
    assert good.read_bytes() == first
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.png", "y.png"]


def test_save_figure_returns_the_path(faulty, tmp_path):
    fig = plot_trace(faulty)
    out = save_figure(fig, str(tmp_path / "z.png"))
    assert out == tmp_path / "z.png"
    assert_png_of(out, fig)
