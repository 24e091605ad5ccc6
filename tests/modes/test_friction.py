"""Dry friction read with the Stribeck drop the two-level model lacks (the friction mode's
hypothesis on a data sheet)."""

from __future__ import annotations

import pytest


@pytest.mark.slow
def test_a_large_friction_on_a_data_sheet_is_read_with_its_stribeck_drop():
    """Friction x2.5 on ema-270v-750w's data sheet: the two-level friction reads 2.68x and
    the fit fails (`unexplained`); the friction mode's hypothesis (its Stribeck speed
    searched beside k) fits, names the friction, and reads it within 0.02 of k1 = 0.75."""
    from pathlib import Path

    from emaphm.params import load_params
    from emaphm.simulate import DEFAULT_SENSORS, simulate
    from emaphm.verdict import examine

    sheet = load_params(Path(__file__).resolve().parents[2] / "examples" / "actuators"
                        / "ema-270v-750w.toml")
    tr = simulate(faults=["friction:2.5"], params=sheet, sensors=DEFAULT_SENSORS, seed=1)
    ex = examine(tr, params=sheet, seed=0)
    d = ex.diagnosis
    assert ex.identification.k[0] > 0.8                     # the two-level reading
    assert [f.mode for f in d.faults] == ["friction"] and d.refit.mode == "friction"
    assert d.faults[0].k == pytest.approx(0.75, abs=0.02)
    assert "stribeck" in d.refit.nuisance
