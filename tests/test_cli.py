"""The command-line interface (:func:`emaphm.cli.main`), run in-process.

What a user sees: each subcommand does its job and writes only where it is told; bad
input exits with status 2, a message on stderr that says what is wrong, and nothing
written at the output path. Files go to ``tmp_path`` only.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from emaphm import __version__
from emaphm.cli import EXIT_USAGE, main
from emaphm.faults import SCENARIOS
from emaphm.params import load_params, siemens_1fk7060
from emaphm.simulate import simulate
from emaphm.traces import Trace, read_trace, write_trace

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"

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
    data = png.read_bytes()
    assert data.startswith(PNG_SIGNATURE) and len(data) > 10_000
    assert _listing(workdir) == ["x.csv", "x.png"]


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
    assert d["algorithm"] == "pso" and d["seed"] == 0 and d["scenario"] == "gain-high"
    assert d["version"] == __version__
    assert d["k_true"] == SCENARIOS["gain-high"].tolist()
    assert d["options"]["budget"] == "3000"
    assert d["evaluations"] >= 3000
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
    assert png.read_bytes().startswith(PNG_SIGNATURE)
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
           "unknown algorithm 'nelder'; choose one of cmaes, de, gwo, pso, scipy-de")


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


def test_the_error_boundary_names_the_path_of_an_os_error_and_exits_2(tmp_path, capsys):
    not_a_folder = tmp_path / "afile"
    not_a_folder.write_text("x")
    rc = main(["simulate", "--scenario", "nominal", "--model", "monitoring",
               "--out", str(not_a_folder / "x.csv")])
    err = capsys.readouterr().err
    assert rc == 2 and "Traceback" not in err and str(not_a_folder) in err
    assert err.count("\n") == 1


def test_an_unexpected_exception_is_shown_as_a_bug(monkeypatch, capsys):
    import emaphm.cli as cli

    def boom(args):
        raise KeyError("surprise")

    monkeypatch.setattr(cli, "cmd_scenarios", boom)
    rc = cli.main(["scenarios"])
    err = capsys.readouterr().err
    assert rc == 1 and "Traceback" in err and "this is a bug in emaphm" in err


@pytest.mark.parametrize("args, words", [
    (["diagnose", "--scenario", "nominal", "--budget", "99999999999999999999999"],
     "above 1e+08 evaluations"),
    (["diagnose", "--scenario", "nominal", "--budget", "100000s"], "above a day"),
    (["simulate", "--scenario", "nominal", "--noise", "1e6", "--seed", "1", "--out", "x.csv"],
     "outside 0 to 1 A"),
])
def test_options_out_of_any_plausible_range_are_refused(args, words, capsys, tmp_path,
                                                        monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(args) == 2
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err
    assert list(tmp_path.iterdir()) == []
