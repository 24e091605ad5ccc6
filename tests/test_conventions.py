"""One convention across the API (issue 34, item 10): parameters as an object, a dict or a
path everywhere; the names that clashed kept for one release with a DeprecationWarning;
the result's counts under the optimizers' names too; a nameplate read with or without its
``[datasheet]`` wrapper; ``py.typed`` shipped."""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest

from emaphm.params import load_params

ROOT = Path(__file__).resolve().parents[1]
EMA270 = ROOT / "examples" / "actuators" / "ema-270v-750w.toml"


def test_params_as_an_object_a_dict_or_a_path_in_the_specs():
    from emaphm.assessment.spec import AssessmentSpec
    from emaphm.campaign import CampaignSpec

    p = load_params(EMA270)
    specs = [CampaignSpec(params=x, runs=1) for x in (p, p.to_dict(), str(EMA270))]
    assert specs[0] == specs[1] == specs[2] and specs[0].params == p.to_dict()
    a = [AssessmentSpec(x) for x in (p, p.to_dict(), EMA270)]
    assert a[0].params == a[1].params == a[2].params == p.to_dict()
    with pytest.raises(TypeError, match="params must be an ActuatorParams"):
        CampaignSpec(params=3.0)


def test_the_renamed_names_warn_for_one_release():
    import emaphm.prognosis.uncertainty as unc
    from emaphm.prognosis import IdentificationSpread, record_inspection
    from emaphm.prognosis import workflow

    with pytest.warns(DeprecationWarning, match="now IdentificationSpread"):
        assert unc.Assessment is IdentificationSpread
    with pytest.warns(DeprecationWarning, match="now record_inspection"):
        with pytest.raises(TypeError):
            workflow.inspect()                     # warns, then record_inspection's own error
    assert record_inspection.__name__ == "record_inspection"


def test_a_nameplate_with_or_without_its_wrapper():
    from emaphm.datasheet import Nameplate

    data = tomllib.loads((ROOT / "examples/actuators/ema-270v-750w.nameplate.toml").read_text())
    assert Nameplate.from_dict(data["datasheet"]) == Nameplate.from_dict(data)


def test_the_result_counts_under_the_optimizers_names():
    from emaphm.identify import Identification

    d = {"algorithm": "pso", "seed": 0, "k": [0.0] * 8, "fitness": 1.5, "evaluations": 40,
         "iterations": 2, "elapsed_s": 0.1, "kernel_s": 0.1, "history": [2.0, 1.5],
         "reason": "max_evaluations"}
    ident = Identification.from_dict(d)
    assert (ident.nfev, ident.nit, ident.best_f) == (40, 2, 1.5)


def test_py_typed_is_shipped():
    import importlib.resources

    assert importlib.resources.files("emaphm").joinpath("py.typed").is_file()
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert "py.typed" in pyproject["tool"]["setuptools"]["package-data"]["emaphm"]
