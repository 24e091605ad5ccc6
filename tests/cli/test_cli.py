"""The command-line interface (:func:`emaphm.cli.main`), run in-process.

What a user sees: each subcommand does its job and writes only where it is told; bad
input exits with status 2, a message on stderr that says what is wrong, and nothing
written at the output path. Files go to ``tmp_path`` only.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from support import assert_png_of

from emaphm import __version__
from emaphm.cli import EXIT_USAGE, main
from emaphm.faults import SCENARIOS
from emaphm.params import load_params, siemens_1fk7060
from emaphm.simulate import simulate
from emaphm.traces import Trace, read_trace, write_trace


#: What `diagnose --json` must carry (on top of the diagnosis' own fields).
JSON_KEYS = {"algorithm", "seed", "k", "fitness", "evaluations", "iterations", "elapsed_s",
             "healthy", "faults", "k_true", "error_pct"}


def _listing(folder):
    return sorted(p.name for p in folder.rglob("*"))


def _fails(argv, capsys, folder, match):
    """Run ``main(argv)``: exit status 2, ``match`` on stderr, nothing new in ``folder``."""
    before = _listing(folder)
    rc = main(argv)
    out, err = capsys.readouterr()
    assert rc == EXIT_USAGE == 2
    assert match in err, err
    assert err.startswith("emaphm ") and "error:" in err
    assert "Traceback" not in err
    assert _listing(folder) == before, "a failed command left files behind"
    return out, err


# ----------------------------------------------------------------------------- fixtures
@pytest.fixture(scope="module")
def rm_trace_file(tmp_path_factory):
    """A reference-model trace written by `emaphm simulate` (module scope: simulated once)."""
    folder = tmp_path_factory.mktemp("cli_traces")
    path = folder / "gain-high.csv"
    assert main(["simulate", "--scenario", "gain-high", "--out", str(path)]) == 0
    return path


@pytest.fixture()
def workdir(tmp_path):
    d = tmp_path / "work"
    d.mkdir()
    return d


# ----------------------------------------------------------------------------- scenarios
def test_scenarios_lists_all_names(capsys):
    assert main(["scenarios"]) == 0
    out, _ = capsys.readouterr()
    lines = out.strip().splitlines()
    assert len(SCENARIOS) == 14
    assert len(lines) == 1 + 14
    names = [line.split()[0] for line in lines[1:]]
    assert names == list(SCENARIOS)
    assert [line.split()[1] for line in lines[1:]] == ["paper"] * 12 + ["physical"] * 2
    assert "0.25,0,0,0,0,0,0.5,0.5" in out             # friction-low


def test_scenarios_json(capsys):
    assert main(["scenarios", "--json"]) == 0
    out, _ = capsys.readouterr()
    data = json.loads(out)
    assert list(data) == list(SCENARIOS)
    for name, k in SCENARIOS.items():
        assert data[name] == k.tolist()


def test_version(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert __version__ in capsys.readouterr().out


def test_no_command_is_a_usage_error(capsys):
    with pytest.raises(SystemExit) as exc:
        main([])
    assert exc.value.code == 2


# ----------------------------------------------------------------------------- simulate
def test_simulate_scenario_writes_a_readable_csv(rm_trace_file, capsys):
    tr = read_trace(rm_trace_file)
    assert tr.meta["k"] == SCENARIOS["gain-high"].tolist()
    assert tr.meta["model"] == "reference"
    assert tr.meta["scenario"] == "gain-high"
    assert tr.n == 4000
    assert np.abs(tr.i_abc).max() > 0.5


def test_simulate_parquet_monitoring_model(workdir, capsys):
    out = workdir / "x.parquet"
    assert main(["simulate", "--scenario", "friction-high", "--model", "monitoring",
                 "--out", str(out)]) == 0
    _, err = capsys.readouterr()
    assert f"wrote {out}" in err
    tr = read_trace(out)
    assert tr.meta["model"] == "monitoring"
    assert tr.meta["k"] == SCENARIOS["friction-high"].tolist()
    ref = simulate(scenario="friction-high", model="monitoring")
    np.testing.assert_array_equal(tr.i_abc, ref.i_abc)
    assert _listing(workdir) == ["x.parquet"]


def test_simulate_with_k(workdir, capsys):
    out = workdir / "k.csv"
    k = "0,0,0,0.25,0,0,0.5,0.5"
    assert main(["simulate", "--k", k, "--model", "monitoring", "--out", str(out)]) == 0
    tr = read_trace(out)
    assert tr.meta["k"] == [0, 0, 0, 0.25, 0, 0, 0.5, 0.5]
    assert tr.meta["scenario"] is None
    nominal = simulate(model="monitoring")
    assert not np.allclose(tr.i_abc, nominal.i_abc)


def test_simulate_with_seed_adds_sensor_noise(workdir, capsys):
    a, b = workdir / "a.csv", workdir / "b.csv"
    assert main(["simulate", "--scenario", "nominal", "--model", "monitoring", "--seed", "3",
                 "--out", str(a)]) == 0
    assert main(["simulate", "--scenario", "nominal", "--model", "monitoring", "--seed", "3",
                 "--out", str(b)]) == 0
    ta, tb = read_trace(a), read_trace(b)
    assert ta.meta["seed"] == 3 and ta.meta["sensors"]["current_noise"] == pytest.approx(0.02)
    assert ta == tb                                         # same seed, same file
    clean = simulate(model="monitoring")
    noise = ta.i_abc - clean.i_abc
    assert 0.01 < noise.std() < 0.03


def test_simulate_plot_writes_a_png(workdir, capsys):
    out, png = workdir / "x.csv", workdir / "x.png"
    assert main(["simulate", "--scenario", "backlash-high", "--model", "monitoring",
                 "--out", str(out), "--plot", str(png)]) == 0
    assert_png_of(png, (10, 9))                             # plot_trace's figure
    assert _listing(workdir) == ["x.csv", "x.png"]


def test_simulate_plot_of_a_fault_shows_it(workdir, capsys, monkeypatch):
    """A --fault trace's figure overlays the nominal run and names the fault in its title
    (k is nominal there: the figure showed neither)."""
    import emaphm.plots as plots

    seen = {}
    monkeypatch.setattr(plots, "plot_trace",
                        lambda trace, overlay, path=None, title=None: seen.update(
                            overlay=overlay, title=title))
    assert main(["simulate", "--fault", "demagnetization:0.15", "--model", "monitoring",
                 "--out", str(workdir / "d.csv"), "--plot", str(workdir / "d.png")]) == 0
    assert seen["overlay"] is not None and seen["title"] == "monitoring: demagnetization:0.15"


def test_diagnose_plot_of_a_sensor_fault_shows_the_currents_that_were_fitted(workdir, capsys,
                                                                               monkeypatch):
    """Phase B's sensor reads 0.8 of its current: the fit is of the currents with that undone,
    and so is the figure (it drew the raw currents against the model of the corrected)."""
    import emaphm.plots as plots

    seen = {}
    monkeypatch.setattr(plots, "plot_identification",
                        lambda trace, ident, diagnosis=None, path=None: seen.update(trace=trace))
    raw = workdir / "s.parquet"
    assert main(["simulate", "--fault", "current_sensor:b:gain:0.8", "--model", "monitoring",
                 "--seed", "1", "--out", str(raw)]) == 0
    assert main(["diagnose", str(raw), "--quiet", "--json", "--plot", str(workdir / "s.png")]) == 0
    assert "current_sensor" in capsys.readouterr().out
    i_b = read_trace(raw).i_abc[:, 1]
    np.testing.assert_allclose(seen["trace"].i_abc[:, 1], i_b / 0.8, rtol=0.02,
                               atol=0.02 * np.abs(i_b).max())


def test_simulate_partial_params_change_the_result(workdir, capsys):
    toml = workdir / "heavy.toml"
    toml.write_text("[transmission]\nFDJ = 0.3\nFSJ = 0.45\n")
    plain, heavy = workdir / "plain.csv", workdir / "heavy.csv"
    base = ["simulate", "--scenario", "nominal", "--model", "monitoring"]
    assert main(base + ["--out", str(plain)]) == 0
    assert main(base + ["--params", str(toml), "--out", str(heavy)]) == 0
    tp, th = read_trace(plain), read_trace(heavy)
    assert th.meta["parameters"]["transmission"]["FDJ"] == 0.3
    assert th.meta["parameters"]["motor"] == tp.meta["parameters"]["motor"]   # rest from preset
    assert np.abs(th.i_abc - tp.i_abc).max() > 0.05


# ----------------------------------------------------------------------------- params
def test_params_writes_the_preset_as_toml(workdir, capsys):
    out = workdir / "m.toml"
    assert main(["params", "--out", str(out)]) == 0
    assert load_params(out) == siemens_1fk7060()
    assert _listing(workdir) == ["m.toml"]


def test_params_rejects_bad_out(workdir, capsys):
    _fails(["params", "--out", str(workdir / "m.json")], capsys, workdir, "must end in .toml")
    _fails(["params", "--out", str(workdir / "nope" / "m.toml")], capsys, workdir,
           "does not exist")


# ----------------------------------------------------------------------------- diagnose
def test_diagnose_scenario_json(capsys):
    rc = main(["diagnose", "--scenario", "gain-high", "--json", "--quiet", "--budget", "3000"])
    out, err = capsys.readouterr()
    assert rc == 0
    lines = out.strip().splitlines()
    assert len(lines) == 1, out                          # ONE JSON object on stdout
    d = json.loads(lines[0])
    assert isinstance(d, dict)
    assert JSON_KEYS <= set(d)
    assert d["algorithm"] == "lsq" and d["seed"] == 0 and d["scenario"] == "gain-high"
    assert d["version"] == __version__
    assert d["k_true"] == SCENARIOS["gain-high"].tolist()
    assert d["options"]["budget"] == "3000"
    assert 0 < d["evaluations"] <= 3000                  # the default pipeline needs hundreds
    assert "history" not in d                            # only with --history
    assert abs(d["k"][7] - 0.75) < 0.03
    assert not d["healthy"] and "gain_drift" in [f["mode"] for f in d["faults"]]
    assert "iteration " not in err                       # --quiet: no progress line


def test_diagnose_trace_file_with_plot(rm_trace_file, workdir, capsys):
    png = workdir / "ident.png"
    rc = main(["diagnose", str(rm_trace_file), "--algorithm", "de", "--seed", "2",
               "--budget", "1000", "--plot", str(png), "--json", "--history"])
    out, err = capsys.readouterr()
    assert rc == 0
    d = json.loads(out)
    assert d["algorithm"] == "de" and d["seed"] == 2
    assert d["trace"] == str(rm_trace_file) and d["scenario"] == rm_trace_file.stem
    assert d["k_true"] == SCENARIOS["gain-high"].tolist()     # from the file's metadata
    assert isinstance(d["error_pct"], float)
    assert isinstance(d["history"], list) and d["history"]
    assert "identifying with DE" in err
    assert_png_of(png, (11, 11))                            # plot_identification's figure
    assert _listing(workdir) == ["ident.png"]


def test_diagnose_table_output(rm_trace_file, capsys):
    assert main(["diagnose", str(rm_trace_file), "--budget", "500", "--quiet"]) == 0
    out, _ = capsys.readouterr()
    assert "verdict: " in out and "fitness (Eq. 4)" in out
    assert "identification error (Eq. 9)" in out
    assert out.count("\nk") >= 8


# ----------------------------------------------------------------------------- bad input
def test_simulate_unknown_scenario(workdir, capsys):
    _fails(["simulate", "--scenario", "nope", "--out", str(workdir / "x.csv")], capsys,
           workdir, "unknown scenario 'nope'")


def test_diagnose_unknown_scenario(workdir, capsys):
    _fails(["diagnose", "--scenario", "nope", "--plot", str(workdir / "p.png")], capsys,
           workdir, "unknown scenario 'nope'")


def test_diagnose_unknown_algorithm(workdir, capsys):
    _fails(["diagnose", "--scenario", "nominal", "--algorithm", "nelder",
            "--plot", str(workdir / "p.png")], capsys, workdir,
           "unknown algorithm 'nelder'; choose one of lsq, cmaes, de, gwo, pso, scipy-de")


@pytest.mark.parametrize("budget, match", [("0", "--budget: budget must be a positive"),
                                           ("abc", "--budget: budget 'abc' not understood"),
                                           ("1.5", "whole number")])
def test_diagnose_bad_budget(workdir, capsys, budget, match):
    _fails(["diagnose", "--scenario", "nominal", "--budget", budget,
            "--plot", str(workdir / "p.png")], capsys, workdir, match)


@pytest.mark.parametrize("command", ["diagnose", "simulate"])
@pytest.mark.parametrize("seed", ["x", "-1", "1.5"])
def test_bad_seed_is_an_argparse_error(workdir, capsys, command, seed):
    argv = [command, "--scenario", "nominal", "--seed", seed]
    if command == "simulate":
        argv += ["--out", str(workdir / "x.csv")]
    else:
        argv += ["--plot", str(workdir / "p.png")]
    before = _listing(workdir)
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "seed must be a non-negative integer" in err
    assert _listing(workdir) == before


def test_diagnose_missing_trace_file(workdir, capsys):
    _fails(["diagnose", str(workdir / "missing.csv"), "--plot", str(workdir / "p.png")],
           capsys, workdir, "missing.csv does not exist")


def test_diagnose_csv_with_a_missing_column(rm_trace_file, workdir, capsys):
    tr = read_trace(rm_trace_file)
    bad = workdir / "bench.csv"
    cols = np.column_stack([tr.t, tr.theta_ref, tr.theta_m, tr.omega_m, tr.i_abc[:, :2]])
    np.savetxt(bad, cols, delimiter=",", header="t,theta_ref,theta_m,omega_m,i_a,i_b",
               comments="")
    _fails(["diagnose", str(bad), "--plot", str(workdir / "p.png")], capsys, workdir,
           "missing column(s) ['i_c']")


def test_diagnose_trace_with_nan(rm_trace_file, workdir, capsys):
    tr = read_trace(rm_trace_file)
    i = np.array(tr.i_abc)
    i[1234, 2] = np.nan
    bad = workdir / "nan.parquet"
    write_trace(Trace(t=tr.t, theta_ref=tr.theta_ref, theta_m=tr.theta_m, omega_m=tr.omega_m,
                      i_abc=i, meta=tr.meta), bad)
    _, err = _fails(["diagnose", str(bad), "--plot", str(workdir / "p.png")], capsys, workdir,
                    "non-finite")
    assert "i_c" in err and "row 1234" in err


def test_diagnose_needs_a_trace_or_a_scenario(rm_trace_file, workdir, capsys):
    _fails(["diagnose"], capsys, workdir, "give exactly one of a TRACE file or --scenario")
    _fails(["diagnose", str(rm_trace_file), "--scenario", "nominal"], capsys, workdir,
           "give exactly one")


def test_diagnose_bad_plot_suffix(workdir, capsys):
    _fails(["diagnose", "--scenario", "nominal", "--plot", str(workdir / "p.txt")], capsys,
           workdir, "must end in .png or .svg or .pdf")


def test_simulate_k_with_seven_values(workdir, capsys):
    _fails(["simulate", "--k", "0,0,0,0,0,0,0.5", "--out", str(workdir / "x.csv")], capsys,
           workdir, "fault vector needs 8 components")


def test_simulate_k_out_of_range(workdir, capsys):
    _fails(["simulate", "--k", "0,0,0,0,0,0,0.5,1.5", "--out", str(workdir / "x.csv")],
           capsys, workdir, "k8 (gain) = 1.5 is outside [0, 1]")


def test_simulate_k_and_scenario_exclusive(workdir, capsys):
    out = str(workdir / "x.csv")
    _fails(["simulate", "--k", "0,0,0,0,0,0,0.5,0.5", "--scenario", "nominal", "--out", out],
           capsys, workdir, "give exactly one of --k")
    _fails(["simulate", "--out", out], capsys, workdir, "give exactly one of --k")


@pytest.mark.parametrize("name, match", [("x.txt", "must end in .csv or .parquet"),
                                         ("x", "must end in .csv or .parquet"),
                                         ("missing/x.csv", "does not exist; create it first")])
def test_simulate_bad_out(workdir, capsys, name, match):
    _fails(["simulate", "--scenario", "nominal", "--out", str(workdir / name)], capsys,
           workdir, match)


def test_simulate_bad_plot_path(workdir, capsys):
    # the plot path is checked before anything is simulated or written
    _fails(["simulate", "--scenario", "nominal", "--out", str(workdir / "x.csv"),
            "--plot", str(workdir / "missing" / "x.png")], capsys, workdir, "does not exist")


def test_simulate_noise_needs_a_seed(workdir, capsys):
    _fails(["simulate", "--scenario", "nominal", "--noise", "0.05",
            "--out", str(workdir / "x.csv")], capsys, workdir, "sensor noise needs --seed")


def test_simulate_bad_params_file(workdir, capsys):
    toml = workdir / "bad.toml"
    toml.write_text("[transmission]\nFDJ = -1.0\n")
    _fails(["simulate", "--scenario", "nominal", "--params", str(toml),
            "--out", str(workdir / "x.csv")], capsys, workdir, "FDJ")
    _fails(["simulate", "--scenario", "nominal", "--params", str(workdir / "none.toml"),
            "--out", str(workdir / "x.csv")], capsys, workdir, "does not exist")


def test_existing_output_is_kept_on_failure(workdir, capsys):
    out = workdir / "x.csv"
    out.write_text("precious")
    _fails(["simulate", "--k", "0,0,0", "--out", str(out)], capsys, workdir,
           "fault vector needs 8 components")
    assert out.read_text() == "precious"


def test_the_cli_starts_without_the_heavy_modules():
    # `emaphm --help` and `emaphm scenarios` build the parser only: no SciPy optimizer,
    # Matplotlib, Numba kernel or trend model is imported for that (checked by module,
    # not by a clock)
    import subprocess
    import sys

    code = ("import sys, emaphm.cli as c; c.build_parser(); "
            "print('\\n'.join(sorted(sys.modules)))")
    mods = set(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                              check=True).stdout.split())
    heavy = {"scipy.optimize", "scipy.stats", "matplotlib", "numba", "emaphm.models.monitoring",
             "emaphm.models.monitoring_simd", "emaphm.prognosis.trends",
             "emaphm.prognosis.uncertainty", "emaphm.campaign.runner", "emaphm.identify",
             "emaphm.fleet.site", "emaphm.fleet.demo", "emaphm.fleet.status"}
    assert not (heavy & mods), sorted(heavy & mods)
    assert {"emaphm.prognosis.cli", "emaphm.campaign.cli", "emaphm.fleet.cli"} <= mods


def test_emaphm_help_imports_no_numpy():
    """`emaphm --help` (issue 37: it imported NumPy again, 0.3 s of CPU) and the parser of
    every subcommand load no NumPy, SciPy or pandas: what each command needs is imported
    when it runs."""
    import subprocess
    import sys

    code = ("import sys, emaphm.cli as c\n"
            "try:\n    c.main(['--help'])\nexcept SystemExit:\n    pass\n"
            "c.build_parser()\n"
            "print('\\n'.join(sorted(sys.modules)))")
    mods = set(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                              check=True).stdout.split())
    assert not {"numpy", "scipy", "pandas", "pyarrow"} & mods, sorted(
        {"numpy", "scipy", "pandas", "pyarrow"} & mods)


def test_python_dash_m_emaphm_is_the_command_line():
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-m", "emaphm", "--version"], capture_output=True,
                          text=True)
    assert done.returncode == 0 and done.stdout.startswith("emaphm "), done
    bad = subprocess.run([sys.executable, "-m", "emaphm", "no-such-command"],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "Traceback" not in bad.stderr


def test_the_error_boundary_names_the_path_of_an_os_error_and_exits_2(monkeypatch, capsys):
    # what no check foresaw (a disk that fills, a permission lost mid-run) still reaches
    # the user as one line naming the path (the corpus of malformed inputs is in
    # test_bad_inputs.py)
    import emaphm.cli as cli

    def full_disk(args):
        raise OSError(28, "No space left on device", "/data/out/x.parquet")

    monkeypatch.setattr(cli, "cmd_scenarios", full_disk)
    rc = cli.main(["scenarios"])
    err = capsys.readouterr().err
    assert rc == 2 and "Traceback" not in err and err.count("\n") == 1
    assert err == ("emaphm scenarios: error: /data/out/x.parquet: No space left on device; check "
                   "the path, that it is a file where a file is meant, its permissions and the "
                   "free space\n")


def test_an_unexpected_exception_is_shown_as_a_bug(monkeypatch, capsys):
    import emaphm.cli as cli

    def boom(args):
        raise KeyError("surprise")

    monkeypatch.setattr(cli, "cmd_scenarios", boom)
    rc = cli.main(["scenarios"])
    err = capsys.readouterr().err
    assert rc == 1 and "Traceback" in err and "this is a bug in emaphm" in err


def _imported(source: str, package: str) -> set[str]:
    """Every module a source file of ``package`` imports, however written (absolute,
    relative, a name imported from a package, ``import_module("...")``)."""
    import ast

    names: set[str] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")
                base = ".".join(parts[:len(parts) - node.level + 1] + ([base] if base else []))
            names.add(base)
            names.update(f"{base}.{a.name}" for a in node.names)
        elif isinstance(node, ast.Constant) and isinstance(node.value, str) \
                and node.value.startswith("emaphm."):
            names.add(node.value)
    return names


@pytest.mark.parametrize("text", ["from emaphm.cli import main", "import emaphm.cli",
                                  "from ..cli import UsageError", "from .. import cli",
                                  "importlib.import_module('emaphm.cli')"])
def test_the_import_scan_sees_every_way_of_importing_the_cli(text):
    assert "emaphm.cli" in _imported(text, "emaphm.campaign")
    assert "emaphm.cli" not in _imported("from .._cli_common import UsageError", "emaphm.campaign")


def test_no_module_imports_the_top_cli_back():
    # the house: subcommand modules and the library import shared helpers from
    # emaphm._cli_common (below them all), never emaphm.cli, the entry point on top
    from pathlib import Path

    import emaphm

    root = Path(emaphm.__file__).parent
    files = sorted(root.rglob("*.py"))
    offenders = []
    for path in files:
        module = ".".join(("emaphm",) + path.relative_to(root).with_suffix("").parts)
        module = module.removesuffix(".__init__")
        if module in ("emaphm.cli", "emaphm.__main__"):    # the entry point and `python -m`
            continue
        package = module if path.name == "__init__.py" else module.rpartition(".")[0]
        if "emaphm.cli" in _imported(path.read_text(), package):
            offenders.append(module)
    assert not offenders, offenders
    assert len(files) > 40                        # the scan saw the package


def test_diagnose_shows_progress_on_a_terminal(rm_trace_file, capsys, monkeypatch):
    import sys

    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    assert main(["diagnose", str(rm_trace_file), "--budget", "400"]) == 0
    err = capsys.readouterr().err
    assert err.startswith("identifying with LSQ (seed 0)\n")
    assert "\riteration " in err and " evaluations" in err and err.endswith("\n")
    assert main(["diagnose", str(rm_trace_file), "--budget", "400", "--quiet"]) == 0
    assert capsys.readouterr().err == ""


def test_a_long_identification_is_announced_with_an_estimate(rm_trace_file, capsys,
                                                             monkeypatch):
    # the estimate is samples x evaluations x a per-candidate-step cost: a cost a million
    # times the real one makes this 0.5 s trace a long identification (no clock involved)
    import emaphm._cli_common as common

    monkeypatch.setattr(common, "SECONDS_PER_CANDIDATE_STEP", 1e-3)
    assert main(["diagnose", str(rm_trace_file), "--budget", "300"]) == 0
    err = capsys.readouterr().err
    notes = [ln for ln in err.splitlines() if "note:" in ln]
    # the default pipeline: 4000 model steps x 300 evaluations x 4 (small batches) x 1 ms
    assert notes == ["emaphm diagnose: note: this identification may take about 1h19m on one "
                     "core; diagnose a shorter window (one 0.5 s diagnostic profile is enough), "
                     "or cap it with --budget (e.g. --budget 60s)"]
    monkeypatch.setattr(common, "SECONDS_PER_CANDIDATE_STEP", 40e-9)
    assert main(["diagnose", str(rm_trace_file), "--budget", "300"]) == 0
    assert "note:" not in capsys.readouterr().err


def test_the_estimate_counts_the_default_stopping_rule_and_the_budget(nominal_params):
    from emaphm._cli_common import expected_evaluations, identification_seconds

    # PSO: 200 iterations of 50, its initial swarm, and at most 2000 polish evaluations
    assert expected_evaluations("pso") == 200 * 50 + 50 + 2000
    assert expected_evaluations("pso", 5000) == 5000
    assert expected_evaluations("de", "30s") is None          # the budget bounds the time
    # lsq: its whole run in population evaluations' worth, or 4x a smaller budget
    assert expected_evaluations("lsq") == 5000 and expected_evaluations("lsq", 300) == 1200
    # a 500 s trace at the 8 kHz PWM: 4e6 model steps
    s = identification_seconds(500.0, nominal_params, "pso", 10_000)
    assert s == pytest.approx(4e6 * 10_000 * 40e-9)
    assert identification_seconds(500.0, nominal_params, "pso", 10_000, runs=5) == pytest.approx(5 * s)


def test_a_long_calibration_is_announced(nominal_params):
    import io

    from emaphm._cli_common import calibration_seconds, warn_if_long
    from emaphm.calibration import PARAMETERS

    short = calibration_seconds([0.5, 0.5], nominal_params)       # two diagnostic profiles
    assert short < 60.0
    buf = io.StringIO()
    assert not warn_if_long("emaphm calibrate", short, "this calibration", "hint", buf)
    long = calibration_seconds([30.0], nominal_params)             # a 30 s recording
    assert long == pytest.approx(30 * 8000 * 20 * (len(PARAMETERS) + 1) * 7e-6)
    assert warn_if_long("emaphm calibrate", long, "this calibration", "calibrate on shorter "
                        "traces", buf)
    assert buf.getvalue().startswith("emaphm calibrate: note: this calibration may take about ")
    assert buf.getvalue().endswith(" on one core; calibrate on shorter traces\n")


def test_simulate_help_names_every_mode_that_can_be_injected(capsys):
    """--fault's help lists every mode a trace can be given (it listed the paper's five;
    demagnetization and the current sensor were only in the error message)."""
    from emaphm.modes import MODES

    with pytest.raises(SystemExit):
        main(["simulate", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    for name, mode in MODES.items():
        if mode.inject is not None:
            assert f"{name}:" in text, name


def test_a_trace_of_another_actuator_says_whose_it_is(tmp_path, capsys):
    """A trace of ema-270v-750w is diagnosed on its own actuator, which its metadata names
    (issue 34); diagnosed with the preset given it reads unexplained (1000x the noise floor),
    and a warning and the note say whose it is."""
    from emaphm.params import load_params, save_params, siemens_1fk7060
    from emaphm.simulate import DEFAULT_SENSORS, simulate
    from emaphm.traces import write_trace

    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    ema = load_params(root / "examples" / "actuators" / "ema-270v-750w.toml")
    path = write_trace(simulate(model="monitoring", params=ema, sensors=DEFAULT_SENSORS, seed=1),
                       tmp_path / "ema.parquet")
    assert main(["diagnose", str(path), "--quiet", "--json"]) == 0
    out, err = capsys.readouterr()
    d = json.loads(out)
    assert d["verdict"] == "healthy" and d["params_source"] == "trace"
    assert d["parameters"]["name"] == "ema-270v-750w" and "warning" not in err
    preset = save_params(siemens_1fk7060(), tmp_path / "preset.toml")
    assert main(["diagnose", str(path), "--quiet", "--json", "--params", str(preset)]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["verdict"] == "unexplained"
    assert ("the trace's metadata says it was simulated for 'ema-270v-750w', and it was "
            "diagnosed with 'siemens-1fk7060-2ac71': give that actuator's parameters") in err
    assert err.count("emaphm diagnose: warning: the trace names the actuator 'ema-270v-750w'") == 1
    assert main(["diagnose", str(path), "--quiet", "--json", "--params",
                 str(root / "examples" / "actuators" / "ema-270v-750w.toml")]) == 0
    assert "metadata says" not in capsys.readouterr().err


def test_the_history_commands_offer_every_built_in_algorithm():
    """`history add --algorithm` lists the built-in names without importing NumPy (a copy of
    them in the parser's module): the copy must be the optimizers' own list."""
    from emaphm.identify import ALGORITHM_NAMES
    from emaphm.optim.registry import RESERVED, registered
    from emaphm.prognosis.cli import _algorithm_choices

    built_in = set(_algorithm_choices()) - set(registered())     # others' own, where any
    assert built_in == set(ALGORITHM_NAMES) == set(RESERVED)
