"""The settings of an assessment: validation, identity, seeds and the cases of a unit."""

import json

import pytest

from emaphm.assessment.spec import AssessmentError, AssessmentSpec, cases, grid_names
from emaphm.modes import MODES
from emaphm.params import siemens_1fk7060

SHEET = siemens_1fk7060().to_dict()


def test_every_simulable_mode_is_assessed_on_a_grid_of_its_own():
    names = grid_names()
    for m in MODES.values():
        if m.inject is not None:
            assert any(n == m.name or n.startswith(m.name + ":") for n in names), m.name
    assert "current_sensor:gain" in names and "current_sensor:offset" in names


@pytest.mark.parametrize("kw,message", [
    ({"units": 0}, "units must be an integer >= 1"),
    ({"units": 2.5}, "units must be an integer"),
    ({"tune_units": -1}, "tune-units"),
    ({"target_far": 0.0}, "target-far"),
    ({"target_far": 0.7}, "target-far"),
    ({"healthy": 2, "healthy_datasheet": 3}, "cannot exceed"),
    ({"seed": -1}, "seed"),
    ({"grids": ("friction", "wear")}, "unknown assessment grid 'wear'"),
    ({"grids": ("friction", "friction")}, "named twice"),
    ({"severities": {"friction": (4.0,)}}, "severity 4 of friction"),
    ({"severities": {"backlash": ()}}, "empty"),
    ({"tolerances": {"JJ": [0, 1]}}, "unknown tolerance"),
    ({"algorithm": "simplex"}, "simplex"),
])
def test_bad_settings_are_refused_with_the_fix(kw, message):
    with pytest.raises(AssessmentError, match=message):
        AssessmentSpec(SHEET, **kw)


def test_bad_parameters_are_refused():
    bad = json.loads(json.dumps(SHEET))
    bad["motor"]["p"] = 0
    with pytest.raises(AssessmentError, match="p"):
        AssessmentSpec(bad)


def test_the_spec_round_trips_and_its_hash_names_its_settings():
    spec = AssessmentSpec(SHEET, units=3, grids=("friction", "short_circuit"),
                          severities={"friction": (1.5, 2.0)}, seed=4)
    again = AssessmentSpec.from_dict(json.loads(spec.to_json()))
    assert again == spec and again.hash() == spec.hash()
    other = AssessmentSpec(SHEET, units=3, grids=("friction", "short_circuit"),
                           severities={"friction": (1.5, 2.0)}, seed=5)
    assert other.hash() != spec.hash()
    assert any(d.startswith("seed: 5 here, 4 there") for d in other.differences(spec))


def test_tuning_and_reported_units_come_from_disjoint_seeds_and_the_same_every_time():
    spec = AssessmentSpec(SHEET, units=30, seed=11)
    tune, rep = spec.tasks("tune"), spec.tasks("assess")
    assert len(tune) == len(rep) == 30
    assert not {t.unit_seed for t in tune} & {t.unit_seed for t in rep}
    assert [t.unit_seed for t in rep] == [t.unit_seed for t in spec.tasks("assess")]
    assert [t.unit_seed for t in rep] != [t.unit_seed for t in
                                          AssessmentSpec(SHEET, units=30, seed=12).tasks("assess")]
    # the first units stay the same when more are assessed
    assert [t.unit_seed for t in AssessmentSpec(SHEET, units=5, seed=11).tasks("assess")] == \
        [t.unit_seed for t in rep[:5]]
    assert AssessmentSpec(SHEET, units=3, tune_units=0).tasks("tune") == []


def test_a_units_cases_turn_the_phase_and_the_fault_resistance_from_unit_to_unit():
    spec = AssessmentSpec(SHEET, grids=("friction", "short_circuit", "current_sensor:offset"))
    c0, c1 = cases(spec, 0), cases(spec, 1)
    assert [c.grid for c in c0].count("short_circuit") == 4
    shorts0 = [c for c in c0 if c.grid == "short_circuit"]
    shorts1 = [c for c in c1 if c.grid == "short_circuit"]
    assert shorts0[0].phase != shorts1[0].phase
    assert shorts0[0].kwargs == {"R_f": 0.05} and shorts1[0].kwargs == {}
    assert shorts0[0].expected == (("short_circuit", shorts0[0].phase),)
    friction = [c for c in c0 if c.grid == "friction"]
    assert [c.magnitude for c in friction] == pytest.approx([0.25, 0.5, 1.0, 1.5])
    assert friction[0].expected == (("friction", None),)
    offset = [c for c in c0 if c.grid == "current_sensor:offset"][0]
    inj = offset.injection()
    assert inj.sensor[1:] == (1.0, offset.severity)        # an offset, gain 1


def test_the_cli_fits_its_defaults_to_what_is_given(capsys):
    """--healthy 1 alone: the data-sheet share follows it (the default 2 refused it, naming
    a flag never typed); given, a share beyond --healthy is refused naming the flag; a bad
    --healthy is described as what it counts."""
    import argparse

    from emaphm.assessment import cli as acli
    from emaphm.cli import main

    parser = argparse.ArgumentParser()
    acli.register(parser.add_subparsers(dest="command"))

    def spec(*argv):
        return acli.build_spec(parser.parse_args(["assess", "--out", "x", *argv]))

    assert (spec("--healthy", "1").healthy_datasheet, spec().healthy_datasheet) == (1, 2)
    with pytest.raises(AssessmentError, match=r"healthy-datasheet \(3\) cannot exceed healthy "
                                              r"\(2\).*give --healthy-datasheet 2 or fewer"):
        spec("--healthy", "2", "--healthy-datasheet", "3")
    with pytest.raises(SystemExit) as exit_:
        main(["assess", "--out", "x", "--healthy", "-1"])
    assert exit_.value.code == 2 and "(healthy traces per unit)" in capsys.readouterr().err


def test_the_recorded_voltage_path_is_a_setting_that_keeps_older_specs_hash():
    """``drive_signals`` (``emaphm assess --drive-signals``) is in a spec's JSON only when
    on: a spec written before it existed hashes as it did and resumes its store."""
    from emaphm.assessment import AssessmentSpec
    from emaphm.params import siemens_1fk7060

    plain = AssessmentSpec(siemens_1fk7060(), units=2)
    rec = AssessmentSpec(siemens_1fk7060(), units=2, drive_signals=True)
    assert "drive_signals" not in plain.to_dict() and rec.to_dict()["drive_signals"] is True
    assert plain.hash() != rec.hash()
    assert AssessmentSpec.from_dict(rec.to_dict()) == rec
    assert AssessmentSpec.from_dict(plain.to_dict()) == plain
