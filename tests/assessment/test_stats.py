"""Proportions and hit/miss POD fits: known answers, and recovery of a known curve."""

import math

import numpy as np
import pytest
from scipy import special

from emaphm.assessment.stats import pod_fit, proportion, wilson


@pytest.mark.parametrize("k,n,lo,hi", [
    (0, 200, 0.0, 0.01884),        # the example: 0 in 200 -> [0, 1.9 %]
    (10, 20, 0.29929, 0.70071),
    (20, 20, 0.83887, 1.0),        # why 20 units cannot show a lower bound of 0.9
    (35, 35, 0.90110, 1.0),        # and 35 can
    (1, 10, 0.01787, 0.40415),
])
def test_wilson_interval_known_answers(k, n, lo, hi):
    got = wilson(k, n)
    assert got == pytest.approx((lo, hi), abs=2e-5)


def test_wilson_refuses_impossible_counts_and_spans_everything_without_trials():
    assert wilson(0, 0) == (0.0, 1.0)
    with pytest.raises(ValueError, match="0 <= k <= n"):
        wilson(3, 2)
    p = proportion(3, 12)
    assert p.rate == 0.25 and p.lo < 0.25 < p.hi


def test_pod_fit_recovers_a_known_logistic_curve_and_bounds_its_a90():
    rng = np.random.default_rng(7)
    b0, b1 = 6.0, 2.5                      # POD(a) = logistic(6 + 2.5 ln a): a50 = 0.0907
    a = np.repeat([0.03, 0.05, 0.08, 0.12, 0.2, 0.3], 60)
    hits = rng.random(a.size) < special.expit(b0 + b1 * np.log(a))
    fit = pod_fit(a, hits)
    a90_true = math.exp((math.log(9) - b0) / b1)
    assert fit.b1 == pytest.approx(b1, rel=0.3)
    assert fit.a90 == pytest.approx(a90_true, rel=0.2)
    assert fit.a90_95 > fit.a90                    # the 95 % bound lies above the estimate
    assert fit.status == "fitted" and fit.note == ""
    assert fit.pod(np.array([fit.a90]))[0] == pytest.approx(0.9)


def test_pod_fit_says_why_there_is_no_curve():
    allhit = pod_fit([0.1, 0.2, 0.3], [1, 1, 1])
    assert "every run a hit" in allhit.note and allhit.status == "every run a hit"
    nohit = pod_fit([0.1, 0.2, 0.3], [0, 0, 0])
    assert "no hit" in nohit.note and nohit.status == "no hit"
    sep = pod_fit([0.1, 0.1, 0.2, 0.3], [0, 0, 1, 1])
    assert sep.a90 is None and "perfect separation" in sep.note and "0.1 and 0.2" in sep.note
    assert sep.status == "separated"
    few = pod_fit([0.1, 0.1, 0.1], [0, 1, 1])
    assert "two sizes" in few.note and few.status == "too few sizes"
    # the record round-trips; one written before the status reads "not recorded"
    from emaphm.assessment.stats import PODFit

    for f in (allhit, nohit, sep, few):
        assert PODFit.from_dict(f.to_dict()) == f
    old = {k: v for k, v in sep.to_dict().items() if k != "status"}
    assert PODFit.from_dict(old).status == "not recorded"
    with pytest.raises(ValueError, match="status must be one of"):
        PODFit(None, None, None, None, 3, "", "maybe")
    with pytest.raises(ValueError, match="no POD curve"):
        sep.pod(np.array([0.1]))
