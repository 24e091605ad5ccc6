"""Campaign specs (:mod:`emaphm.campaign.spec`): the paper's campaign, TOML, seeds, bad input.

No model runs here: specs are data, and the run list with its seeds is a pure function
of the spec.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from emaphm.campaign import AlgorithmSpec, CampaignSpec, ScenarioSpec, SpecError, paper_spec
from emaphm.campaign.spec import SCENARIO_GROUPS, parse_algorithms, parse_scenarios
from emaphm.faults import SCENARIOS

EXAMPLE = Path(__file__).resolve().parents[2] / "docs" / "examples" / "paper.toml"


def _toml(tmp_path, text: str) -> Path:
    p = tmp_path / "spec.toml"
    p.write_text(text, encoding="utf-8")
    return p


# ----------------------------------------------------------------------------- the paper's campaign
def test_paper_spec_is_330_runs_in_stable_order():
    spec = paper_spec()
    runs = spec.runs_list()
    assert spec.n_runs == len(runs) == 330 == 11 * 3 * 10
    assert [s.name for s in spec.scenarios] == list(SCENARIO_GROUPS["paper"])
    assert [a.label for a in spec.algorithms] == ["de", "pso", "gwo"]
    assert len({r.key for r in runs}) == 330
    assert [r.index for r in runs] == list(range(330))
    assert runs[0].key == "friction-low/de/0" and runs[-1].key == "multiple/gwo/9"
    # order: scenario, then algorithm, then run index
    assert [r.key for r in runs[:12]] == ([f"friction-low/de/{i}" for i in range(10)]
                                          + ["friction-low/pso/0", "friction-low/pso/1"])
    for r in runs:
        assert np.array_equal(r.k_true, SCENARIOS[r.scenario])


def test_example_file_is_the_paper_spec():
    """docs/examples/paper.toml is what the docs say it is."""
    spec = CampaignSpec.from_toml(EXAMPLE)
    assert spec == paper_spec() and spec.hash == paper_spec().hash


def test_named_scenarios_carry_mode_and_magnitude():
    spec = paper_spec()
    by = {s.name: s for s in spec.scenarios}
    assert (by["short-circuit-low"].mode, by["short-circuit-low"].magnitude) == ("short-circuit", "low")
    assert (by["gain-high"].mode, by["gain-high"].magnitude) == ("gain", "high")
    assert (by["multiple"].mode, by["multiple"].magnitude) == ("multiple", "")


# ----------------------------------------------------------------------------- seeds
def test_seeds_come_from_seedsequence_spawn_and_are_rebuildable():
    spec = paper_spec(runs=3, master_seed=11)
    root = np.random.SeedSequence(11)
    noise_root, optim_root = root.spawn(2)
    runs = spec.runs_list()
    r = runs[0]
    expected = optim_root.spawn(11)[0].spawn(3)[0].spawn(3)[0]
    assert r.spawn_key == (1, 0, 0, 0) == expected.spawn_key
    assert r.seed == int(expected.generate_state(1, np.uint64)[0] >> np.uint64(1))
    # a stored spawn key rebuilds the seed alone, without the rest of the campaign
    for r in runs[::17]:
        ss = np.random.SeedSequence(11, spawn_key=r.spawn_key)
        assert r.seed == int(ss.generate_state(1, np.uint64)[0] >> np.uint64(1))
        assert 0 <= r.seed < 2**63 and 0 <= r.noise_seed < 2**63


def test_noise_is_shared_across_algorithms_not_across_runs_or_scenarios():
    runs = paper_spec(runs=4).runs_list()
    noise = {(r.scenario, r.algorithm, r.run): r.noise_seed for r in runs}
    seeds = [r.seed for r in runs]
    assert len(set(seeds)) == len(seeds)                     # every optimizer seed distinct
    for s in SCENARIO_GROUPS["paper"]:
        for i in range(4):                                   # common random numbers
            assert noise[(s, "de", i)] == noise[(s, "pso", i)] == noise[(s, "gwo", i)]
    assert len({v for (s, a, i), v in noise.items() if a == "de"}) == 11 * 4


def test_more_runs_keep_the_seeds_of_the_existing_ones():
    a = {r.key: (r.seed, r.noise_seed) for r in paper_spec(runs=3).runs_list()}
    b = {r.key: (r.seed, r.noise_seed) for r in paper_spec(runs=5).runs_list()}
    assert all(b[k] == v for k, v in a.items())


def test_master_seed_changes_every_seed():
    a = paper_spec(master_seed=1).runs_list()
    b = paper_spec(master_seed=2).runs_list()
    assert all(x.seed != y.seed and x.noise_seed != y.noise_seed for x, y in zip(a, b))


# ----------------------------------------------------------------------------- TOML and round trips
def test_toml_with_custom_scenarios_variants_and_options(tmp_path):
    spec = CampaignSpec.from_toml(_toml(tmp_path, """
name = "mine"
runs = 2
master_seed = 5
noise = 0.01
budget = 3000
polish = false
scenarios = ["friction-high", {name = "my-case", k = [0.1, 0, 0, 0, 0, 0, 0.5, 0.6]}]
algorithms = ["pso", {name = "pso", label = "pso-20", options = {pop_size = 20}, budget = "default"}, "cmaes"]

[options.pso]
pop_size = 40
"""))
    assert spec.name == "mine" and spec.runs == 2 and spec.budget == 3000 and spec.polish is False
    assert [s.name for s in spec.scenarios] == ["friction-high", "my-case"]
    assert spec.scenarios[1].k == (0.1, 0, 0, 0, 0, 0, 0.5, 0.6) and spec.scenarios[1].mode == "my-case"
    algos = {a.label: a for a in spec.algorithms}
    assert algos["pso"].options == {"pop_size": 40} and algos["pso-20"].options == {"pop_size": 20}
    assert algos["pso-20"].name == "pso" and algos["cmaes"].name == "cmaes"
    runs = {r.key: r for r in spec.runs_list()}
    assert runs["my-case/pso/0"].config.budget == 3000
    assert runs["my-case/pso-20/1"].config.budget is None   # "default": the algorithm's own rule
    assert runs["my-case/pso-20/1"].config.options == {"pop_size": 20}
    # JSON round trip (what the store keeps)
    again = CampaignSpec.from_json(spec.to_json())
    assert again == spec and again.hash == spec.hash


def test_hash_ignores_the_name_but_not_the_rest():
    base = paper_spec(runs=2)
    assert dataclasses.replace(base, name="other").hash == base.hash
    for change in ({"runs": 3}, {"master_seed": 1}, {"noise": 0.0}, {"budget": 600},
                   {"polish": False}, {"search": "k"}):
        assert dataclasses.replace(base, **change).hash != base.hash, change


def test_differences_name_what_changed():
    a = paper_spec(runs=2)
    b = dataclasses.replace(a, runs=3, scenarios=parse_scenarios("friction-low,friction-high"),
                            algorithms=parse_algorithms("de,pso,gwo,cmaes"))
    diffs = a.differences(b)
    assert "runs: 2 -> 3" in diffs
    assert any(d.startswith("scenarios: removed backlash-low") for d in diffs)
    assert "algorithms: added cmaes" in diffs
    assert a.differences(dataclasses.replace(a, name="x")) == []


def test_cli_style_lists_and_groups():
    assert [s.name for s in parse_scenarios("single-faults")] == list(SCENARIO_GROUPS["single-faults"])
    assert [s.name for s in parse_scenarios("multiple, gain-low")] == ["multiple", "gain-low"]
    assert [a.label for a in parse_algorithms("de,pso,scipy-de")] == ["de", "pso", "scipy-de"]


def test_run_lookup_by_key():
    spec = paper_spec(runs=2)
    assert spec.run("gain-high/gwo/1").key == "gain-high/gwo/1"
    with pytest.raises(SpecError, match=r"no run 'gain-high/xx/1' in this campaign; keys look like "
                                        r"friction-low/de/0"):
        spec.run("gain-high/xx/1")


# ----------------------------------------------------------------------------- bad input
@pytest.mark.parametrize("text, match", [
    ('scenarios = ["friction-lo"]', r"unknown scenario 'friction-lo'; choose one of nominal, friction-low"),
    ('algorithms = ["de", "sa"]', r"unknown algorithm 'sa'; choose one of cmaes, de, gwo, lsq, pso, scipy-de"),
    ('algorithms = ["pso"]\n[options.pso]\npop_size = -1',
     r"algorithm 'pso': PSO: pop_size must be an integer >= "),
    ('algorithms = ["pso"]\n[options.pso]\nswarm = 3', r"algorithm 'pso': bad option .*swarm"),
    ('algorithms = ["pso"]\n[options.gwo]\npop_size = 3', r"\[options\] for gwo, which is not among the algorithms"),
    ('runs = 0', r"runs must be an integer from 1 to 10000, got 0"),
    ('runs = 100001', r"runs must be an integer from 1 to 10000, got 100001"),
    ('algorithms = ["pso"]\n[options.pso]\npop_size = 1000000',
     r"algorithm 'pso': pop_size 1e\+06 is above 10000"),
    ('noise = 1e6', r"noise must be a finite number from 0 to 1 A rms, got 1000000.0"),
    ('run = 3', r"unknown key\(s\) run; known keys: "),
    ('budget = "ten"', r"budget 'ten' not understood"),
    ('noise = -0.1', r"noise must be a finite number from 0 to 1 A rms"),
    ('scenarios = ["gain-low", "gain-low"]', r"scenario 'gain-low' appears twice"),
    ('algorithms = ["pso", "pso"]', r"algorithm label 'pso' appears twice; .*use a label"),
    ('scenarios = [{name = "x", k = [0.1, 0.2]}]', r"scenario 'x': fault vector needs 8 components"),
    ('scenarios = [{name = "x", k = [2, 0, 0, 0, 0, 0, 0.5, 0.5]}]', r"k1 \(friction\) = 2 is outside \[0, 1\]"),
    ('scenarios = [{name = "a/b", k = [0, 0, 0, 0, 0, 0, 0.5, 0.5]}]', r"scenario name 'a/b' must be letters"),
    ('search = "polar"', r"unknown search space 'polar'"),
    ('scenarios = [', r"not valid TOML"),
])
def test_bad_spec_files_raise_clear_errors(tmp_path, text, match):
    path = _toml(tmp_path, text)
    with pytest.raises(SpecError, match=match) as info:
        CampaignSpec.from_toml(path)
    assert str(path) in str(info.value)                      # says which file


def test_missing_spec_file():
    with pytest.raises(FileNotFoundError, match=r"spec file nowhere\.toml does not exist"):
        CampaignSpec.from_toml("nowhere.toml")


def test_direct_construction_validates_too():
    with pytest.raises(SpecError, match=r"unknown algorithm 'sa'"):
        CampaignSpec(algorithms=(AlgorithmSpec("sa"),))
    with pytest.raises(SpecError, match=r"outside \[0, 1\]"):
        CampaignSpec(scenarios=(ScenarioSpec("x", (0, 0, 0, 0, 0, 0, 0.5, 1.5)),))
    with pytest.raises(SpecError, match=r"master_seed must be an integer >= 0"):
        CampaignSpec(master_seed=-1)


@pytest.mark.parametrize("toml", ['algorithms = [{name = "pso", options = 5}]',
                                  'algorithms = ["pso"]\n[options]\npso = 3'])
def test_options_that_are_not_a_table_are_refused(tmp_path, toml):
    p = tmp_path / "spec.toml"
    p.write_text('scenarios = ["friction-low"]\n' + toml + "\n")
    with pytest.raises(SpecError, match="must be a table of settings"):
        CampaignSpec.from_toml(p)


def test_the_default_pipeline_is_an_algorithm_of_specs_without_options():
    spec = CampaignSpec(scenarios=("friction-low",), algorithms=("lsq", "pso"), runs=1)
    assert [a.name for a in spec.algorithms] == ["lsq", "pso"]
    assert {r.optimizer for r in spec.runs_list()} == {"lsq", "pso"}
    with pytest.raises(SpecError, match="algorithm 'lsq': lsq takes no options"):
        CampaignSpec(algorithms=(AlgorithmSpec("lsq", options={"pop_size": 4}),))
