"""Seeds: one check (``emaphm.seeds.check_seed``), and every entry point that takes a seed
refuses a bad one with its message (a copy of the check elsewhere words it otherwise;
``tests/test_architecture.py`` also looks for such copies in the source)."""

from __future__ import annotations

import numpy as np
import pytest

from emaphm.seeds import as_generator, check_seed

#: The end of check_seed's message: what every refusal of a seed says.
WHY = r"\(randomness always flows from an explicit seed, e\.g\. 0\)"
BAD = [None, -1, 1.5, True, "0"]


@pytest.mark.parametrize("seed", BAD)
def test_check_seed_refuses_with_the_fix(seed):
    with pytest.raises(ValueError, match=rf"^unit seed must be a non-negative integer, got .* {WHY}$"):
        check_seed(seed, "unit seed")


def test_check_seed_takes_numpys_integers():
    assert check_seed(np.int64(7)) == 7 and type(check_seed(np.uint8(3))) is int


@pytest.mark.parametrize("seed", BAD)
def test_as_generator_refuses_through_check_seed(seed, monkeypatch):
    import emaphm.seeds

    calls = []
    monkeypatch.setattr(emaphm.seeds, "check_seed",
                        lambda s, what="seed": calls.append(s) or check_seed(s, what))
    with pytest.raises(ValueError, match=rf"^seed must be given explicitly as a non-negative "
                                         rf"integer or a numpy.random.Generator, got .* {WHY}$"):
        emaphm.seeds.as_generator(seed)
    assert calls == [seed]


def test_as_generator_passes_a_generator_and_seeds_one():
    g = np.random.default_rng(1)
    assert as_generator(g) is g
    assert as_generator(np.int64(5)).random() == np.random.default_rng(5).random()


def _entry_points():
    from emaphm.fleet.demo import demo_fleet
    from emaphm.fleet.site import build_site
    from emaphm.prognosis.simulator import (degradation_scenario, simulate_degradation,
                                            synthetic_k_history)
    from emaphm.prognosis.trends import predict_rul, prognose, rul_track

    t = np.linspace(0.0, 500.0, 8)
    y = 0.01 + 8e-4 * t
    sc = degradation_scenario("friction-growth")
    return {
        "synthetic_k_history": lambda s: synthetic_k_history(sc, t, seed=s),
        "simulate_degradation": lambda s: simulate_degradation(sc, t, seed=s),
        "predict_rul": lambda s: predict_rul(t, y, 0.5, seed=s),
        "prognose": lambda s: prognose(t, np.zeros((8, 8)), seed=s),
        "rul_track": lambda s: rul_track(t, y, 0.5, seed=s),
        "demo_fleet": lambda s: demo_fleet(3, seed=s),
        "build_site": lambda s: build_site("no-such-history.sqlite", "no-such-site", seed=s),
    }


ENTRY_POINTS = ["synthetic_k_history", "simulate_degradation", "predict_rul", "prognose",
                "rul_track", "demo_fleet", "build_site"]


@pytest.mark.parametrize("name", ENTRY_POINTS)
def test_every_entry_point_refuses_a_bad_seed_with_the_one_message(name):
    call = _entry_points()[name]
    for seed in (-1, 1.5, True):
        with pytest.raises(ValueError, match=rf"seed must .*, got {seed!r} {WHY}"):
            call(seed)
