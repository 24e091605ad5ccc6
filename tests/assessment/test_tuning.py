"""Thresholds tuned from healthy readings: the normal quantile at the Bonferroni share,
censored measures, and the two guards."""

import numpy as np
import pytest
from scipy import stats

from emaphm.assessment.tuning import FLOOR, MARGIN, tolerance_factor, tune_thresholds
from emaphm.modes import DEFAULT_THRESHOLDS, Thresholds

FIELDS = list(Thresholds.__dataclass_fields__)


def readings(**columns):
    n = len(next(iter(columns.values())))
    return [{name: float(col[i]) for name, col in columns.items()} for i in range(n)]


def test_a_normal_measure_gets_its_quantile_at_the_share_of_the_target():
    rng = np.random.default_rng(1)
    x = rng.normal(0.05, 0.004, 80)      # as many as 20 tuning units give
    tuned = tune_thresholds(readings(friction=x), 0.01, DEFAULT_THRESHOLDS)
    z = stats.norm.ppf(1 - 0.01 / len(FIELDS))
    t = tuned["friction"]
    k = tolerance_factor(80, z)
    assert z < k < 1.2 * z                # 80 traces: a little above the quantile itself
    assert t.quantile == pytest.approx(x.mean() + k * x.std(ddof=1))
    guard = x.mean() + MARGIN * (x.max() - x.mean())
    assert t.value == pytest.approx(max(t.quantile, guard, FLOOR * DEFAULT_THRESHOLDS.friction))
    assert t.rule == ("tolerance limit" if t.quantile > guard else "1.25 x largest")
    # a stricter target asks for a higher threshold
    strict = tune_thresholds(readings(friction=x), 0.001, DEFAULT_THRESHOLDS)["friction"]
    assert strict.value > t.value


def test_the_tolerance_factor_covers_the_quantile_with_95_percent_confidence():
    """By simulation: the limit mean + k sd of n normal draws lies above the true quantile in
    95 % of samples; and it tends to the quantile itself as n grows."""
    rng = np.random.default_rng(3)
    z = float(stats.norm.ppf(1 - 0.01 / 8))
    for n in (12, 80):
        x = rng.normal(size=(20000, n))
        limit = x.mean(axis=1) + tolerance_factor(n, z) * x.std(axis=1, ddof=1)
        assert np.mean(limit > z) == pytest.approx(0.95, abs=0.006)
    assert tolerance_factor(10**6, float(z)) == pytest.approx(z, rel=0.01)
    assert tolerance_factor(12, z) > tolerance_factor(80, z) > z


def test_a_measure_at_its_bound_is_censored_not_averaged_in():
    # a k component: X ~ N(0, 0.01), read as max(X, 0) (half the traces at the bound)
    rng = np.random.default_rng(2)
    x = np.maximum(rng.normal(0.0, 0.01, 2000), 0.0)
    t = tune_thresholds(readings(backlash=x), 0.01, DEFAULT_THRESHOLDS)["backlash"]
    assert t.censored > 800
    assert t.mean == pytest.approx(0.0, abs=0.001) and t.sd == pytest.approx(0.01, rel=0.08)
    # the plain mean and sd of the clipped values would put the threshold far lower
    naive = x.mean() + stats.norm.ppf(1 - 0.01 / len(FIELDS)) * x.std()
    assert t.quantile > 1.2 * naive


def test_the_guards_largest_seen_and_half_the_default():
    few = readings(eccentricity=[0.0, 0.0, 0.0, 0.0], gain_drift=[0.001, 0.002, 0.0015, 0.03])
    tuned = tune_thresholds(few, 0.01, DEFAULT_THRESHOLDS)
    ecc = tuned["eccentricity"]
    assert ecc.rule == "half the default" and ecc.value == FLOOR * DEFAULT_THRESHOLDS.eccentricity
    gain = tuned["gain_drift"]
    mean = np.mean([0.001, 0.002, 0.0015, 0.03])
    assert gain.value >= mean + MARGIN * (0.03 - mean) > 0.03
    # a field with no reading keeps its default, and says so
    assert tuned["demagnetization"].value == DEFAULT_THRESHOLDS.demagnetization
    assert "default kept" in tuned["demagnetization"].rule
    assert set(tuned) == set(FIELDS)


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="no healthy readings"):
        tune_thresholds([], 0.01, DEFAULT_THRESHOLDS)
    with pytest.raises(ValueError, match="target_far"):
        tune_thresholds(readings(friction=[0.1]), 0.0, DEFAULT_THRESHOLDS)


def test_a_threshold_stays_above_what_another_modes_fault_leaves_in_its_measure():
    """A severe short brakes the motor and reads as a little friction: the friction
    threshold stays above 1.25 times that, the short's own measure is not held against
    its own threshold."""
    rng = np.random.default_rng(4)
    healthy = readings(friction=rng.normal(0.01, 0.003, 80), short_circuit=np.zeros(80))
    crosstalk = [("short_circuit", {"friction": 0.09, "short_circuit": 0.2}),
                 ("backlash", {"friction": 0.02, "short_circuit": 0.004})]
    tuned = tune_thresholds(healthy, 0.01, DEFAULT_THRESHOLDS, crosstalk)
    assert tuned["friction"].rule == "cross-talk"
    assert tuned["friction"].value == pytest.approx(MARGIN * 0.09)
    assert tuned["friction"].crosstalk == 0.09
    # the short's own reading under a short is no cross-talk; under a backlash it is
    assert tuned["short_circuit"].crosstalk == 0.004
    assert tuned["short_circuit"].value == FLOOR * DEFAULT_THRESHOLDS.short_circuit
    without = tune_thresholds(healthy, 0.01, DEFAULT_THRESHOLDS)
    assert without["friction"].value < tuned["friction"].value
