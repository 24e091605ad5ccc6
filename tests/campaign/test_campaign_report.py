"""Campaign reports (:mod:`emaphm.campaign.report`): Eq. 10 reproduces the paper's Table 3,
the tables have the paper's layout, the figures are written, and reports only read.

The store is filled with synthetic results (no model runs): each single-fault scenario
gets the time and error the paper reports for its fault mode, so our tables must give
the paper's numbers back.
"""

from __future__ import annotations

import csv
import re
import sqlite3

import numpy as np
import pytest
from support import assert_png_of, legend_texts

from emaphm.campaign import CampaignStore, RunResult, paper_spec
from emaphm.campaign.report import (PAPER_TABLE3, PAPER_TOTALS, bar_figure, convergence_figure,
                                    performance_coefficient, single_fault_table, summarize,
                                    write_report)
from emaphm.campaign.spec import parse_algorithms
from emaphm.cli import main

ALGOS = ("de", "pso", "gwo")


def synthetic(run, time_s, err, spread=0.1):
    """A result with the given time and error, +-spread around them over run 0 / 1."""
    sign = 1.0 if run.run % 2 == 0 else -1.0
    n_it = 20 + run.run
    hist = tuple(float(x) for x in np.geomspace(1e-2, 1e-4 * (1 + run.run), n_it + 4))
    return RunResult(key=run.key, index=run.index, scenario=run.scenario, algorithm=run.algorithm,
                     optimizer=run.optimizer, run=run.run, seed=run.seed, noise_seed=run.noise_seed,
                     spawn_key=run.spawn_key, status="ok", k_true=run.k_true, k=run.k_true,
                     fitness=hist[-1], error_pct=err * (1 + sign * spread), k_raw=run.k_true,
                     fitness_raw=hist[n_it - 1], error_pct_raw=err * 1.5, evaluations=50 * n_it + 40,
                     iterations=n_it, polish_evaluations=40, elapsed_s=time_s * (1 + sign * spread),
                     kernel_s=time_s / 2, simulate_s=0.05, reason="stall", diverged=0, history=hist)


@pytest.fixture(scope="module")
def paper_store(tmp_path_factory):
    """The paper's campaign (2 runs), every scenario at its fault mode's Table 3 values;
    the multiple-fault case at half the friction values; one extra run failed."""
    spec = paper_spec(runs=2)
    path = tmp_path_factory.mktemp("report") / "paper.sqlite"
    with CampaignStore.open(path, spec) as st:
        for run in spec.runs_list():
            mode = run.scenario.rsplit("-", 1)[0] if run.scenario != "multiple" else "friction"
            t, e, _ = PAPER_TABLE3[mode][run.algorithm]
            if run.scenario == "multiple":
                t, e = t / 2, e / 2
            st.commit(synthetic(run, t, e))
    return path


def test_eq10_reproduces_the_papers_total_pcs():
    """The total row's PC from the mean time and mean error over the five modes: the
    paper's 56.75 / 79.24 / 64.00, which needs GWO's total time 2630.7 (not the printed 2530.7)."""
    t = [np.mean([PAPER_TABLE3[m][a][0] for m in PAPER_TABLE3]) for a in ALGOS]
    e = [np.mean([PAPER_TABLE3[m][a][1] for m in PAPER_TABLE3]) for a in ALGOS]
    assert t == pytest.approx([PAPER_TOTALS[a][0] for a in ALGOS], abs=0.05)
    assert performance_coefficient(t, e) == pytest.approx([PAPER_TOTALS[a][2] for a in ALGOS], abs=0.01)
    typo = performance_coefficient([2936.8, 1498.8, 2530.7], e)
    assert abs(typo[2] - 64.00) > 0.5


def test_eq10_properties():
    pc = performance_coefficient([1.0, 2.0, 3.0, 4.0], [4.0, 3.0, 2.0, 1.0])
    assert pc.sum() == pytest.approx(100.0 * (4 - 1))          # sum_i PC_i = 100 (n - 1)
    assert pc[0] == pc[3] and pc[1] == pc[2] and pc[0] > pc[1]  # smaller t*err, higher PC
    assert np.all(np.isnan(performance_coefficient([1.0, np.nan], [1.0, 1.0])))


def test_table3_gives_the_papers_numbers_back(paper_store):
    with CampaignStore.open(paper_store, readonly=True) as st:
        spec, cells = st.spec, summarize(st.results())
    rows = single_fault_table(spec, cells)
    assert [r["mode"] for r in rows] == ["friction", "backlash", "short-circuit", "eccentricity",
                                         "gain", "total"]
    for r in rows[:-1]:
        assert len(r["scenarios"]) == 2                       # mean of both magnitudes
        for a in ALGOS:
            t, e, pc = r[a]
            pt, pe, ppc = PAPER_TABLE3[r["mode"]][a]
            assert t == pytest.approx(pt) and e == pytest.approx(pe)
            # the paper's row PCs come from its unrounded data: within 0.3
            assert pc == pytest.approx(ppc, abs=0.3)
    for a in ALGOS:
        t, e, pc = rows[-1][a]
        assert t == pytest.approx(PAPER_TOTALS[a][0], abs=0.05)
        assert pc == pytest.approx(PAPER_TOTALS[a][2], abs=0.01)


def _read_csv(path):
    with open(path, newline="") as fh:
        return list(csv.reader(fh))


def test_write_report_files_tables_and_figures(paper_store, tmp_path):
    conn = sqlite3.connect(f"file:{paper_store}?mode=ro", uri=True)
    before = list(conn.iterdump())
    conn.close()
    out = tmp_path / "report"
    paths = write_report(paper_store, out)
    names = {p.name for p in paths}
    assert names == {"report.md", "table3_single_faults.csv", "table4_multiple_faults.csv",
                     "per_scenario.csv", "paper_comparison.csv", "runs.csv", "fig7_error.png",
                     "fig8_time.png", "convergence.png"}
    for p in paths:
        assert p.parent == out and p.stat().st_size > 0
    assert_png_of(out / "fig7_error.png", (max(8.0, 0.9 * 11), 4.8))
    assert_png_of(out / "fig8_time.png", (max(8.0, 0.9 * 11), 4.8))
    assert_png_of(out / "convergence.png", (11, 3.2 * 2))
    conn = sqlite3.connect(f"file:{paper_store}?mode=ro", uri=True)
    assert list(conn.iterdump()) == before, "a report must not write to the store"
    conn.close()

    t3 = _read_csv(out / "table3_single_faults.csv")
    assert t3[0] == ["mode"] + [f"{a}_{q}" for a in ALGOS for q in ("time_s", "error_pct", "pc_pct")]
    assert [r[0] for r in t3[1:]] == ["friction", "backlash", "short-circuit", "eccentricity", "gain", "total"]
    assert float(t3[-1][1]) == pytest.approx(2936.8, abs=0.05)
    t4 = _read_csv(out / "table4_multiple_faults.csv")
    assert len(t4) == 2 and t4[1][0] == "multiple"
    assert float(t4[1][4]) == pytest.approx(PAPER_TABLE3["friction"]["pso"][0] / 2)
    per = _read_csv(out / "per_scenario.csv")
    assert len(per) == 1 + 11 * 3
    runs = _read_csv(out / "runs.csv")
    assert len(runs) == 1 + 66
    comp = {r[0]: r for r in _read_csv(out / "paper_comparison.csv")[1:]}
    assert set(comp) == set(ALGOS)
    assert float(comp["gwo"][4]) == 2630.7                    # paper_time_s, typo corrected

    # every cell of every numeric column parses as a plain number (no "np.float64(...)")
    for name in CSV_FILES:
        numeric_columns(out / name)
    runs_cols = numeric_columns(out / "runs.csv")
    assert {"seed", "fitness", "evaluations", "k", "k_true", "spawn_key"} <= set(runs_cols)
    assert all(len(k) == 8 for k in runs_cols["k"] if k)

    md = (out / "report.md").read_text()
    assert "| **Total** |" in md and "2530.7 s, is a typo" in md
    assert "## Multiple faults (layout of the paper's Table 4)" in md
    assert "![error per scenario](fig7_error.png)" in md
    assert "| DE time (s) | DE err. (%) | DE PC (%) | PSO time (s) |" in md
    # what decides the numbers: the actuator and the fault model (they were not said)
    assert "Actuator: the preset (siemens-1fk7060-2ac71); fault model" in md


#: The CSV files of a report, and their text columns (every other column is numeric).
CSV_FILES = ("table3_single_faults.csv", "table4_multiple_faults.csv", "per_scenario.csv",
             "paper_comparison.csv", "runs.csv")
TEXT_COLUMNS = {"mode", "scenario", "magnitude", "algorithm", "optimizer", "status", "reason",
                "run_key", "version", "error_text"}
#: Numeric columns holding space-separated vectors.
VECTOR_COLUMNS = {"k", "k_true", "spawn_key"}
PLAIN_NUMBER = re.compile(r"^-?(\d+(\.\d*)?|\.\d+)([eE][-+]?\d+)?$|^-?inf$")


def numeric_columns(path) -> dict[str, list]:
    """Every numeric column of a report CSV, parsed: each cell is empty (n/a) or a plain
    decimal number (a vector column: numbers separated by spaces). Fails on anything else,
    e.g. ``np.float64(57.42)``."""
    header, *rows = _read_csv(path)
    assert rows, path
    cols = {}
    for j, name in enumerate(header):
        if name in TEXT_COLUMNS:
            continue
        values = []
        for r in rows:
            cell = r[j]
            parts = cell.split(" ") if name in VECTOR_COLUMNS else [cell]
            bad = [x for x in parts if x and not PLAIN_NUMBER.match(x)]
            assert not bad, f"{path.name}, column {name}: {bad[0]!r} is not a plain number"
            values.append([float(x) for x in parts if x] if name in VECTOR_COLUMNS
                          else (float(cell) if cell else None))
        cols[name] = values
    return cols


def test_the_committed_results_hold_plain_numbers():
    """docs/results (the paper campaign's report) as the reader gets it."""
    from pathlib import Path

    results = Path(__file__).resolve().parents[2] / "docs" / "results"
    for name in CSV_FILES:
        cols = numeric_columns(results / name)
        assert all(v is None or np.isfinite(v) for c, vs in cols.items()
                   if c not in VECTOR_COLUMNS for v in vs), name
    runs = numeric_columns(results / "runs.csv")
    assert len(runs["fitness"]) == 330                    # 3 algorithms x 11 scenarios x 10 runs

def test_report_with_baselines_failures_and_missing_runs(tmp_path):
    spec = paper_spec(runs=2, algorithms=parse_algorithms("pso,cmaes"))
    path = tmp_path / "s.sqlite"
    with CampaignStore.open(path, spec) as st:
        for run in spec.runs_list():
            if run.scenario.startswith("gain"):
                continue                                      # not run yet
            if run.key == "backlash-low/cmaes/1":
                st.commit(RunResult.failure(run, "Traceback...\nRuntimeError: boom"))
                continue
            st.commit(synthetic(run, 2.0 if run.algorithm == "pso" else 1.0, 1.0))
    out = tmp_path / "r"
    write_report(path, out, figures=False)
    md = (out / "report.md").read_text()
    assert "35 of 44 runs stored, 1 failed" in md
    assert "CMA-ES PC (%)" in md and "| Prop. gain | n/a |" in md
    runs = {r[0]: r for r in _read_csv(out / "runs.csv")[1:]}
    assert runs["backlash-low/cmaes/1"][8] == "failed" and runs["backlash-low/cmaes/1"][-1] == "RuntimeError: boom"
    # DE, PSO and GWO not all there: no relative PC beside the paper's
    comp = _read_csv(out / "paper_comparison.csv")
    assert [r[0] for r in comp[1:]] == ["pso"] and comp[1][3] == ""
    assert not (out / "fig7_error.png").exists()


def test_cli_report(paper_store, tmp_path, capsys):
    out = tmp_path / "cli-report"
    assert main(["report", str(paper_store), "--out", str(out), "--no-figures"]) == 0
    assert (out / "report.md").exists() and "report.md" in capsys.readouterr().out
    assert main(["report", str(tmp_path / "none.sqlite"), "--out", str(out)]) == 2
    assert "does not exist" in capsys.readouterr().err


# ----------------------------------------------------------------------------- figures
def test_the_bar_figures_show_the_mean_and_the_range_of_every_cell(paper_store):
    from matplotlib.container import BarContainer

    with CampaignStore.open(paper_store, readonly=True) as st:
        spec, cells = st.spec, summarize(st.results())
    scen = [s.name for s in spec.scenarios]
    fig = bar_figure(spec, cells, "error", "identification error, Eq. 9 [%]", "Fig. 7")
    (ax,) = fig.axes
    bars = [c for c in ax.containers if isinstance(c, BarContainer)]
    assert len(bars) == len(ALGOS) and all(len(b) == len(scen) for b in bars)
    for b, a in zip(bars, ALGOS):
        np.testing.assert_allclose([r.get_height() for r in b],
                                   [cells[(s, a)].stat("error") for s in scen])
    top = max(cells[(s, a)].stat("error", "max") for s in scen for a in ALGOS)
    assert ax.get_ylim()[0] == 0.0 and ax.get_ylim()[1] > top       # whiskers inside
    assert [t.get_text() for t in ax.get_xticklabels()] == scen
    assert ax.get_ylabel() == "identification error, Eq. 9 [%]" and ax.get_title() == "Fig. 7"
    assert legend_texts(ax) == ["DE", "PSO", "GWO"]
    # the whiskers run from the minimum to the maximum of each cell
    err = [c for c in ax.containers if not isinstance(c, BarContainer)]
    assert len(err) == len(ALGOS)
    segs = np.asarray(err[0].lines[2][0].get_segments())           # DE, one per scenario
    np.testing.assert_allclose(segs[:, 0, 1], [cells[(s, "de")].stat("error", "min") for s in scen])
    np.testing.assert_allclose(segs[:, 1, 1], [cells[(s, "de")].stat("error", "max") for s in scen])


def test_the_convergence_figure_has_one_median_per_algorithm_and_scenario(paper_store):
    with CampaignStore.open(paper_store, readonly=True) as st:
        spec, results = st.spec, st.results()
    fig = convergence_figure(spec, results)
    shown = [ax for ax in fig.axes if ax.get_visible()]
    assert [ax.get_title() for ax in shown] == ["friction-high", "short-circuit-high", "gain-high",
                                                "multiple"]
    for ax in shown:
        assert len(ax.lines) == len(ALGOS) and len(ax.collections) == len(ALGOS)   # + IQR bands
        assert legend_texts(ax) == ["DE (n=2)", "PSO (n=2)", "GWO (n=2)"]
        assert ax.get_yscale() == "log" and ax.get_xlabel() == "evaluations"
        assert ax.get_ylabel() == "best fitness (Eq. 4)"
        for line in ax.lines:
            y = np.asarray(line.get_ydata())
            assert np.all(np.diff(y[np.isfinite(y)]) <= 0)          # best-so-far medians
            # the synthetic runs end at 1e-4 and 2e-4 after 50 x (20 or 21) + 40 evaluations
            assert np.nanmin(y) == pytest.approx(1.5e-4)
            assert line.get_xdata()[-1] == pytest.approx(50 * 21 + 40)      # the longer run
    assert convergence_figure(spec, []) is None


def test_the_setup_line_names_parameters_that_are_not_the_presets():
    """A partial parameter file keeps the preset's name with other values: said so (the
    report read 'the preset' or the preset's name as if it were the preset)."""
    import dataclasses
    from types import SimpleNamespace as NS

    from emaphm.campaign.report import _setup_line
    from emaphm.params import siemens_1fk7060

    preset, sc = siemens_1fk7060(), [NS(fault_model="paper"), NS(fault_model="physical")]
    heavier = dataclasses.replace(preset, motor=dataclasses.replace(preset.motor, J_m=1e-3))
    line = lambda params: _setup_line(NS(params=params, scenarios=sc, polish=False), [])
    assert line(None).startswith(f"Actuator: the preset ({preset.name}); fault models of the "
                                 "scenarios: paper, physical")
    assert line(preset.to_dict()).startswith("Actuator: the preset")
    assert line(heavier.to_dict()).startswith(f"Actuator: {preset.name} (the spec's parameters, "
                                              "the preset's name with other values)")
