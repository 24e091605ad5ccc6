"""When to look next (issue 24): the next inspection at a stated risk.

Known answers first: on a linear trend (the linear model alone, no floor, no model
discrepancy) the chance that the threshold is crossed by ``t`` is a Student t of the
fitted line at ``t``, so the planned time has a closed form, and over many histories of
linear growth with known noise the share of crossings before it is the risk itself.
Then the rules (fall-backs, act now, confirm, the caps), the same seed giving the same
plan, the policy simulated to a flag, the misuse messages, and the command line.
"""

from __future__ import annotations

import csv
import dataclasses
import json
import math

import numpy as np
import pytest
from scipy import optimize, stats

from emaphm.cli import main
from emaphm.prognosis.history import HealthHistory
from emaphm.prognosis.inspection import (INTERVAL_DEFAULTS, MIN_FLAG_INSPECTIONS,
                                         InspectionPolicy, crossing_cdf, first_crossing_cdf,
                                         n_samples_for, next_inspection, plan_inspection,
                                         risk_time, simulate_policy, taking_part)
from emaphm.prognosis.simulator import DegradationLaw, DegradationScenario
from emaphm.prognosis.trends import predict_rul, prognose

LINEAR = dict(models=("linear",), sigma_floor=0.0, discrepancy=0.0)


def _friction_k(levels):
    """k histories (n, 8) with friction at ``levels`` and every other component healthy."""
    K = np.zeros((len(levels), 8))
    K[:, 0] = levels
    K[:, 6] = 0.5
    K[:, 7] = 0.5
    return K


def _analytic_risk_time(t, y, threshold, risk):
    """The planned time of a linear trend in closed form: the ``t`` where the Student t
    (n - 2 dof) of the fitted line reaches the threshold with probability ``risk``."""
    X = np.column_stack([np.ones_like(t), t - t[-1]])
    beta, rss = np.linalg.lstsq(X, y, rcond=None)[:2]
    cov = float(rss[0]) / (t.size - 2) * np.linalg.inv(X.T @ X)

    def excess(tau):
        x = np.array([1.0, tau])
        z = (threshold - x @ beta) / math.sqrt(x @ cov @ x)
        return stats.t.sf(z, t.size - 2) - risk
    return t[-1] + optimize.brentq(excess, 0.0, 1e5)


# ----------------------------------------------------------------------------- known answers
@pytest.mark.parametrize("risk", [0.01, 0.05, 0.2])
def test_the_planned_time_of_a_linear_trend_is_its_student_t_quantile(risk):
    rng = np.random.default_rng(3)
    t = np.linspace(0.0, 600.0, 9)
    y = 0.02 + 4e-4 * t + 0.01 * rng.standard_normal(t.size)
    p = predict_rul(t, y, 0.5, seed=1, n_samples=n_samples_for(risk) * 25, **LINEAR)
    want = _analytic_risk_time(t, y, 0.5, risk)
    got = risk_time([p], risk)
    # Monte Carlo: the quantile of 100,000+ draws, within a few hours of a ~400 h horizon
    assert got == pytest.approx(want, abs=6.0)
    assert crossing_cdf(p, want) == pytest.approx(risk, abs=0.15 * risk + 0.002)


def test_over_linear_histories_with_known_noise_the_share_of_crossings_before_the_plan_is_the_risk():
    # truth: y = 0.5 t / 1000 (+ N(0, 0.01)) crosses 0.5 at 1000 h; six inspections up to
    # 600 h; the linear trend's t quantile is exact, so the realised share is the risk
    risk, n_paths = 0.1, 400
    t = np.linspace(0.0, 600.0, 6)
    rng = np.random.default_rng(11)
    late = 0
    for i in range(n_paths):
        y = 5e-4 * t + 0.01 * rng.standard_normal(t.size)
        p = predict_rul(t, y, 0.5, seed=i, n_samples=4000, **LINEAR)
        late += 1000.0 <= risk_time([p], risk)
    margin = 1.96 * math.sqrt(risk * (1 - risk) / n_paths)
    assert abs(late / n_paths - risk) <= margin + 0.01, late / n_paths


def test_any_indicator_crossing_multiplies_the_chances_of_none():
    rng = np.random.default_rng(0)
    t = np.linspace(0.0, 500.0, 7)
    a = predict_rul(t, 0.01 + 5e-4 * t + 0.005 * rng.standard_normal(7), 0.5, seed=1, **LINEAR)
    b = predict_rul(t, 0.01 + 3e-4 * t + 0.005 * rng.standard_normal(7), 0.3, seed=2, **LINEAR)
    grid = np.array([500.0, 700.0, 900.0, 1200.0])
    both = first_crossing_cdf([a, b], grid)
    np.testing.assert_allclose(both, 1 - (1 - crossing_cdf(a, grid)) * (1 - crossing_cdf(b, grid)))
    assert np.all(both >= np.maximum(crossing_cdf(a, grid), crossing_cdf(b, grid)))
    t_star = risk_time([a, b], 0.05)
    assert first_crossing_cdf([a, b], t_star) > 0.05
    assert first_crossing_cdf([a, b], np.nextafter(t_star, 0)) <= 0.05
    assert risk_time([a, b], 0.05) <= min(risk_time([a], 0.05), risk_time([b], 0.05))


# ----------------------------------------------------------------------------- the rules
def _plan(t, levels, policy=InspectionPolicy(risk=0.05), **kw):
    return next_inspection(np.asarray(t, float), _friction_k(levels), seed=0, policy=policy,
                           discrepancy={}, **kw)


def test_fall_backs_never_give_no_answer():
    dflt = INTERVAL_DEFAULTS["h"]
    never = plan_inspection([], None, policy=InspectionPolicy(risk=0.05))
    assert (never.at, never.rule, never.act_now) == (0.0, "never inspected", True)
    _, two = _plan([0.0, 100.0], [0.0, 0.01])
    assert (two.at, two.rule, two.risk) == (100.0 + dflt.default, "too few inspections", None)
    assert "too few inspections" in two.reason and "default interval" in two.reason
    # already past its threshold at the second inspection: act now, however few
    _, past = _plan([0.0, 100.0], [0.0, 0.7])
    assert (past.at, past.rule, past.indicator) == (100.0, "act now", "friction")
    # a flat, healthy history: no trend to extrapolate, the default interval
    rng = np.random.default_rng(5)
    _, flat = _plan(np.arange(8) * 150.0, np.abs(0.007 * rng.standard_normal(8)))
    assert (flat.rule, flat.at, flat.risk) == ("healthy", 7 * 150.0 + dflt.default, None)


def test_healthy_indicators_scatter_into_crossings_so_they_take_no_part():
    # seven flat indicators at zero, scattered by identification-sized noise: their trend
    # draws (an exponential fitted to the scatter) cross within an interval often enough
    # to drive any plan; the healthy rule leaves them out
    from emaphm.faults import K_NOMINAL

    rng = np.random.default_rng(8)
    t = np.arange(6) * 200.0
    f_all, rules = [], []
    for i in range(10):
        K = np.clip(K_NOMINAL + 0.007 * rng.standard_normal((t.size, 8)), 0.0, 1.0)
        prog, plan = next_inspection(t, K, seed=i, discrepancy={})
        rules.append(plan.rule)
        f_all.append(float(first_crossing_cdf(list(prog.predictions.values()),
                                              1000.0 + INTERVAL_DEFAULTS["h"].default)))
    assert np.mean(f_all) > 0.1, f_all
    # the one left: the gain's scatter rose by more than two standard errors at the last
    # inspection (the fleet's "growing"); at the one before it took no part, so the rise
    # is confirmed at the minimum interval, not flagged
    assert rules.count("healthy") == 9 and rules.count("confirm") == 1, rules
    k = rules.index("confirm")
    rng = np.random.default_rng(8)
    for i in range(k + 1):
        K = np.clip(K_NOMINAL + 0.007 * rng.standard_normal((t.size, 8)), 0.0, 1.0)
    _, plan = next_inspection(t, K, seed=k, discrepancy={})
    assert plan.at == t[-1] + INTERVAL_DEFAULTS["h"].min and plan.risk > 0.01
    assert "at this inspection alone" in plan.reason and plan.indicator == "gain_drift"
    # the same history without that last reading: healthy (nothing took part)
    assert next_inspection(t[:-1], K[:-1], seed=k, discrepancy={})[1].rule == "healthy"


def test_a_slow_growth_is_capped_by_the_maximum_interval_and_a_fast_one_by_its_risk():
    t = np.arange(6) * 100.0
    _, slow = _plan(t, 0.05 + 1e-4 * t + [0, 0.002, -0.001, 0.001, 0.0, -0.002])
    assert slow.rule == "max interval" and slow.at == 500.0 + INTERVAL_DEFAULTS["h"].max
    assert slow.risk < 0.05 and slow.indicator == "friction"
    _, fast = _plan(t, 0.05 + 6e-4 * t + [0, 0.002, -0.001, 0.001, 0.0, -0.002])
    assert fast.rule == "risk" and 500.0 + 50.0 <= fast.at < 500.0 + 400.0
    assert fast.risk == pytest.approx(fast.target, abs=0.01) and fast.risk > fast.target
    assert "friction growing towards its threshold" in fast.reason
    # the max interval given: the cap moves
    _, capped = _plan(t, 0.05 + 1e-4 * t, InspectionPolicy(risk=0.05, max_interval=150.0))
    assert capped.at == 650.0 and capped.rule == "max interval"


def test_near_its_threshold_an_actuator_is_flagged_and_not_chased():
    t = np.arange(8) * 100.0
    levels = 0.02 + 6.5e-4 * t + 0.004 * np.sin(t)             # 0.475 at 700 h of 0.5
    _, plan = _plan(t, levels)
    assert plan.rule == "act now" and plan.at == 700.0 and plan.act_now
    assert "minimum interval" in plan.reason or "crossed" in plan.reason
    # with fewer inspections than a trend needs to be trusted, confirm instead of acting
    _, early = _plan(t[:3], [0.02, 0.2, 0.4])
    assert early.rule == "confirm" and early.at == 200.0 + INTERVAL_DEFAULTS["h"].min
    assert f"from {MIN_FLAG_INSPECTIONS}" in early.reason


def test_a_plan_made_later_than_due_says_inspect_now():
    t = np.arange(6) * 100.0
    due = 500.0 + INTERVAL_DEFAULTS["h"].max
    _, plan = _plan(t, 0.05 + 1e-4 * t, t_now=due + 300.0)
    assert plan.at == due and plan.act_now and plan.t_now == due + 300.0
    assert plan.summary("EMA-7").startswith(
        f"inspect EMA-7 now: its next inspection was due at {due:.0f} h")


def test_the_same_seed_gives_the_same_plan_and_another_seed_nearly_the_same():
    t = np.arange(7) * 100.0
    levels = 0.02 + 4e-4 * t + [0, 0.004, -0.003, 0.002, 0, -0.004, 0.003]
    a = _plan(t, levels)[1]
    b = _plan(t, levels)[1]
    assert a == b
    c = next_inspection(t, _friction_k(levels), seed=9, policy=InspectionPolicy(risk=0.05),
                        discrepancy={})[1]
    assert c.rule == a.rule and abs(c.at - a.at) < 0.05 * (a.at - 600.0)


def test_the_draws_resolve_the_risk():
    assert n_samples_for(0.05) == 4000 and n_samples_for(0.001) == 40_000
    t = np.arange(6) * 100.0
    prog = prognose(t, _friction_k(0.05 + 6e-4 * t), seed=0)          # 4000 draws
    with pytest.raises(ValueError, match="needs at least 40000 draws per indicator"):
        plan_inspection(t, prog, policy=InspectionPolicy(risk=0.001))


# ----------------------------------------------------------------------------- simulated
def test_a_degrading_actuator_is_flagged_after_a_handful_of_inspections_and_not_missed():
    law = DegradationLaw.reaching("linear", 0.5, 1000.0, onset=100.0)
    sc = DegradationScenario("friction", law)
    run = simulate_policy(sc, InspectionPolicy(risk=0.01), seed=4, discrepancy={})
    assert run.flagged_at is not None and not run.missed
    assert 0.6 <= run.life_used < 1.0
    assert run.n_inspections <= 15 and run.rules[-1] == "act now"
    gaps = np.diff(run.times)
    assert gaps.min() >= INTERVAL_DEFAULTS["h"].min - 1e-9
    # each plan's predicted risk: none before a trend, at most the risk where the risk
    # rule set the time, above it where a trend too short to act on asked to confirm
    # (here 0.126 and 0.054); their sum over the planned intervals is what a calibrated
    # risk expects this actuator to miss
    assert len(run.risks) == run.n_inspections and run.risks[0] is None
    for r, rule in zip(run.risks, run.rules):
        assert (r is None) == (rule in ("too few inspections", "healthy")), (r, rule)
        assert rule not in ("risk", "max interval") or r <= 0.01 + 1e-12
        assert rule != "confirm" or r > 0.01
    assert "confirm" in run.rules
    assert run.expected_misses == pytest.approx(sum(
        r for r, rule in zip(run.risks, run.rules) if r is not None and rule != "act now"))
    assert run.to_dict()["expected_misses"] == run.expected_misses
    # a fixed interval sees the same noise at its i-th inspection and is flagged by the
    # same criterion: the chance of a crossing before its next inspection
    fixed = simulate_policy(sc, InspectionPolicy(risk=0.01), seed=4, fixed_interval=100.0,
                            discrepancy={})
    np.testing.assert_allclose(np.diff(fixed.times), 100.0)
    assert fixed.flagged_at is not None or fixed.missed
    # its risks are those of its own next inspection, 100 h on: within the risk where the
    # trend did not ask to confirm
    assert all(r <= 0.01 + 1e-12 for r, rule in zip(fixed.risks, fixed.rules)
               if rule in ("risk", "max interval"))
    assert any(rule in ("risk", "max interval") for rule in fixed.rules)
    # a healthy actuator is inspected at the default interval to the horizon, never flagged
    healthy = simulate_policy(None, InspectionPolicy(risk=0.01), seed=4, horizon=1500.0)
    assert healthy.flagged_at is None and not healthy.missed
    assert set(healthy.rules) <= {"too few inspections", "healthy"}


def test_the_single_rise_check_predicts_the_shorter_history_alike(monkeypatch):
    """The check that an indicator took part at the inspection before the last predicts
    the history without its last reading with the prognosis's own seed and options."""
    from emaphm.faults import K_NOMINAL
    from emaphm.prognosis import inspection, trends

    t = np.arange(7) * 150.0
    K = np.tile(K_NOMINAL, (t.size, 1))
    K[:, 0] = np.maximum(0.0, 4e-4 * (t - 300.0))
    prog = trends.prognose(t, K, seed=3, models=("linear", "onset"), sigma_floor=0.004,
                           n_samples=900, discrepancy={})
    assert dict(prog.options) == {"sigma_floor": 0.004, "models": ("linear", "onset"),
                                  "n_samples": 900}
    seen = {}
    real = trends.prognose

    def spy(times, K, **kw):
        seen.update(kw, n=len(times))
        return real(times, K, **kw)

    monkeypatch.setattr(trends, "prognose", spy)
    part = inspection.taking_part(prog)
    assert "friction" in part
    assert inspection._new_since_last(prog, part) == set()      # growing at both
    assert seen["n"] == t.size - 1 and seen["seed"] == 3
    assert seen["models"] == ("linear", "onset") and seen["sigma_floor"] == 0.004
    assert seen["n_samples"] == 900 and seen["indicators"] == list(part)


def test_a_flat_indicator_below_the_noise_floor_is_not_flagged_by_onset_draws():
    """Friction flat at 0.2 (taking part: 40 % of its threshold) with a slope far under the
    noise floor: the onset's variance is huge, and onsets drawn after the last inspection
    held the flat level past the threshold (act now, p_failed 0.375). Drawn no later than
    the last inspection, none is past."""
    from emaphm.faults import K_NOMINAL

    t = np.arange(8) * 150.0
    K = np.tile(K_NOMINAL, (t.size, 1))
    K[:, 0] = 0.2 + np.r_[np.zeros(6), 1e-9, 2e-9]
    prog, plan = next_inspection(t, K, seed=0, discrepancy={})
    assert plan.rule != "act now" and prog.predictions["friction"].p_failed == 0.0
    assert np.all(prog.predictions["friction"].theta["onset"][:, 2] <= 0.0)


def test_a_confirming_plan_is_anchored_to_the_last_inspection_and_a_big_jump_acts():
    """A rise seen once is confirmed at the minimum interval after the last inspection:
    planned later than that, it is due now (not pushed on). A jump to 0.45 of a 0.5
    threshold, whose crossing before the confirming inspection is more likely than not,
    is acted on at once."""
    from emaphm.faults import K_NOMINAL

    rng = np.random.default_rng(0)
    t = np.arange(8) * 150.0
    K = np.tile(K_NOMINAL, (t.size, 1))
    K[:, 0] = np.abs(0.01 + rng.normal(0.0, 0.003, t.size))
    K[-1, 0] = 0.06
    iv = INTERVAL_DEFAULTS["h"]
    _, plan = next_inspection(t, K, seed=1, t_now=1250.0)
    assert plan.rule == "confirm" and plan.at == t[-1] + iv.min
    _, later = next_inspection(t, K, seed=1, t_now=t[-1] + 2 * iv.min)
    assert later.at <= later.t_now
    K[-1, 0] = 0.45
    _, jump = next_inspection(t, K, seed=1)
    assert jump.rule == "act now", jump.reason


# ----------------------------------------------------------------------------- misuse
@pytest.mark.parametrize("kw, message", [
    (dict(risk=0.0), r"risk must be a probability in \(0, 1\)"),
    (dict(risk=1.0), r"risk must be a probability in \(0, 1\)"),
    (dict(risk=float("nan")), r"risk must be a probability in \(0, 1\)"),
    (dict(risk=True), r"risk must be a probability in \(0, 1\)"),
    (dict(risk=1e-6), r"below 0.0001, the smallest the Monte Carlo draws resolve"),
    (dict(max_interval=0.0), "max_interval must be a finite number > 0"),
    (dict(max_interval=-5.0), "max_interval must be a finite number > 0"),
    (dict(min_interval=-1.0), "min_interval must be a finite number >= 0"),
    (dict(default_interval=math.inf), "default_interval must be a finite number > 0"),
    (dict(min_interval=300.0, max_interval=200.0), "min_interval 300 must be below max_interval 200"),
])
def test_a_policy_refuses_what_makes_no_plan(kw, message):
    with pytest.raises(ValueError, match=message):
        InspectionPolicy(**kw)


def test_the_defaults_given_in_part_are_checked_together():
    with pytest.raises(ValueError, match="the minimum interval 900 h must be below the maximum"):
        InspectionPolicy(min_interval=900.0).intervals("h")
    iv = InspectionPolicy(max_interval=150.0).intervals("h")
    assert iv.default == 150.0 and "given: max" in iv.source      # capped by the maximum
    with pytest.raises(ValueError, match="unknown time unit 'days'"):
        InspectionPolicy().intervals("days")


# ----------------------------------------------------------------------------- command line
def _rc(argv):
    """The exit status of ``emaphm ARGV``, whether the parser (SystemExit) or the command
    refused it."""
    try:
        return main(argv)
    except SystemExit as exc:
        return exc.code

@pytest.fixture()
def history(tmp_path):
    db = tmp_path / "h.sqlite"
    t = np.arange(8) * 100.0
    rng = np.random.default_rng(2)
    with HealthHistory(db) as h:
        h.register("EMA-7")
        for ti, k in zip(t, _friction_k(0.02 + 4e-4 * t + 0.004 * rng.standard_normal(8))):
            h.add("EMA-7", float(ti), k)
        h.register("EMA-2")
        for ti in (0.0, 100.0):
            h.add("EMA-2", ti, _friction_k([0.0])[0])
        h.register("EMA-0")
    return str(db)


def test_prognose_risk_json_gains_the_next_inspection_and_keeps_the_rest(history, capsys):
    assert main(["prognose", "EMA-7", "--db", history, "--json"]) == 0
    plain = json.loads(capsys.readouterr().out)
    assert main(["prognose", "EMA-7", "--db", history, "--json", "--risk", "0.05"]) == 0
    out = json.loads(capsys.readouterr().out)
    nxt = out.pop("next_inspection")
    # the options say n_samples where the plan asked for it (4000 by default too)
    assert out.pop("options") == {**plain.pop("options"), "n_samples": 4000}
    assert out == plain                         # 4000 draws either way: the same RUL
    assert {"at", "risk", "indicator", "reason"} <= set(nxt)
    assert nxt["indicator"] == "friction" and nxt["rule"] in ("risk", "max interval")
    assert nxt["at"] > 700.0 and nxt["target"] == 0.05
    # the same plan as in Python
    with HealthHistory(history, readonly=True) as h:
        data = h.data("EMA-7")
    _, plan = next_inspection(data.times, data.K, seed=0, policy=InspectionPolicy(risk=0.05))
    assert nxt["at"] == plan.at and nxt["reason"] == plan.reason


def test_prognose_risk_text_says_when_in_one_line(history, capsys):
    assert main(["prognose", "EMA-7", "--db", history, "--risk", "0.05"]) == 0
    out = capsys.readouterr().out
    assert "first to fail: friction" in out                  # the table is still there
    assert sum(line.startswith("next inspection of EMA-7 by ") for line in out.splitlines()) == 1
    assert main(["prognose", "EMA-7", "--db", history, "--risk", "0.05", "--at", "2000"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert sum(line.startswith(("act now: EMA-7", "inspect EMA-7 now")) for line in lines) == 1


def test_prognose_risk_under_three_inspections_falls_back(history, capsys):
    assert main(["prognose", "EMA-2", "--db", history, "--risk", "0.05", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["predictions"] == {} and out["n_inspections"] == 2
    assert out["next_inspection"]["at"] == 100.0 + INTERVAL_DEFAULTS["h"].default
    assert out["next_inspection"]["reason"].startswith("too few inspections")
    assert main(["prognose", "EMA-0", "--db", history, "--risk", "0.05"]) == 0
    assert "inspect EMA-0 now: it has never been inspected" in capsys.readouterr().out
    # without --risk the refusal stands: a trend needs three inspections
    assert main(["prognose", "EMA-2", "--db", history]) == 2


def _one_reading_jump():
    """A fleet unit's history (seven inspections, friction growing) whose short_b, at zero
    all along, reads 0.016 at the last inspection: an exponential through that one reading
    has its rate at the fit's bound and reaches any level a few days on."""
    t = np.array([0.0, 293.8, 587.7, 881.5, 1175.3, 1469.1, 1763.0])
    K = _friction_k([0.0001, 0.0152, 0.0937, 0.1422, 0.2106, 0.2909, 0.3498])
    K[:, 2] = [0.0, 0.0075, 0.0026, 0.0, 0.0, 0.0, 0.0084]
    K[:, 3] = [0.0, 0.0009, 0.0, 0.0, 0.0, 0.0, 0.0158]
    K[:, 7] = [0.4971, 0.5062, 0.5038, 0.4969, 0.4907, 0.5035, 0.4847]
    return t, K


def test_a_plan_made_after_the_last_inspection_does_not_act_on_a_jump_carried_forward():
    """Planned at 1900 h (after the last inspection, 1763 h), the exponential through
    short_b's one reading has crossed by then in half its draws (median RUL 0). That is a
    prediction, not a reading: short_b rises by no more than its scatter and was at 5 % of
    its threshold at the last inspection, so it is at its healthy level and the plan is the
    friction's, as at 1763 h. (It read 'act now: short_b past its threshold'.)"""
    from emaphm.prognosis.trends import indicator_state

    t, K = _one_reading_jump()
    policy = InspectionPolicy(risk=0.01)
    prog, plan = next_inspection(t, K, seed=0, policy=policy, t_now=1900.0)
    p = prog.predictions["short_circuit_b"]
    assert p.median == 0.0 and p.current > 1.0                 # the carried-forward trend
    assert indicator_state(p, 1763.0)[0] == "no growth"
    assert "short_circuit_b" not in taking_part(prog) and prog.first.indicator == "friction"
    assert plan.rule != "act now" and plan.indicator == "friction" and plan.at > 1900.0
    _, at_last = next_inspection(t, K, seed=0, policy=policy)
    assert at_last.indicator == "friction" and at_last.at == pytest.approx(plan.at, abs=60.0)
    # a reading past its threshold at the last inspection stays past, whenever planned
    K[-1, 3] = 0.35
    prog, plan = next_inspection(t, K, seed=0, policy=policy, t_now=1900.0)
    assert indicator_state(prog.predictions["short_circuit_b"], 1763.0)[0] == "past threshold"
    assert plan.rule == "act now"


def test_prognose_table_marks_a_trend_carried_past_its_range(tmp_path, capsys):
    """The table at 1900 h: short_b's trend is past k = 1 there (shown at the bound, marked,
    said below the table) and reads no growth, as the planner treats it."""
    t, K = _one_reading_jump()
    db = str(tmp_path / "h.sqlite")
    with HealthHistory(db) as h:
        h.register("EMA-1")
        for ti, k in zip(t, K):
            h.add("EMA-1", float(ti), k)
    assert main(["prognose", "EMA-1", "--db", db, "--at", "1900", "--risk", "0.01"]) == 0
    out = capsys.readouterr().out
    row = next(line for line in out.splitlines() if line.startswith("short_circuit_b"))
    assert ">1.000" in row and "no growth" in row and "in the noise" in row
    assert "past the range its indicator can take, shown at the bound" in out
    assert "first to fail: friction" in out and "act now" not in out
    # the JSON says what the table says: each prediction's state
    assert main(["prognose", "EMA-1", "--db", db, "--at", "1900", "--json"]) == 0
    preds = json.loads(capsys.readouterr().out)["predictions"]
    assert (preds["short_circuit_b"]["state"], preds["friction"]["state"]) == ("no growth", "predicted")
    # at the last inspection a healthy component's fit below 0 is scatter, shown as it is
    assert main(["prognose", "EMA-1", "--db", db]) == 0
    out = capsys.readouterr().out
    assert "<0.000" not in out and ">1.000" not in out and "shown at the bound" not in out
    from emaphm.prognosis.cli import _now_text

    with HealthHistory(db, readonly=True) as h:
        data = h.data("EMA-1")
    p = prognose(data.times, data.K, seed=0).predictions["short_circuit_c"]
    assert _now_text(dataclasses.replace(p, current=-0.0012)) == "-0.001"
    assert _now_text(dataclasses.replace(p, current=-0.0012, t_now=1900.0)) == "<0.000"


def test_prognose_risk_under_three_inspections_acts_on_an_indicator_past_its_threshold(
        tmp_path, capsys):
    """One inspection with friction 0.76 (threshold 0.5): act now, as the fleet's schedule
    says; a --threshold above the reading plans the default interval. (The command planned
    the default interval: it did not pass the k history to the planner.)"""
    db = str(tmp_path / "h.sqlite")
    with HealthHistory(db) as h:
        h.register("X-1")
        h.add("X-1", 10.0, _friction_k([0.76])[0])
    assert main(["prognose", "X-1", "--db", db, "--risk", "0.05", "--json"]) == 0
    nxt = json.loads(capsys.readouterr().out)["next_inspection"]
    assert (nxt["at"], nxt["rule"], nxt["indicator"]) == (10.0, "act now", "friction")
    assert main(["prognose", "X-1", "--db", db, "--risk", "0.05"]) == 0
    assert "act now: X-1: friction past its failure threshold" in capsys.readouterr().out
    out = tmp_path / "plan.csv"
    assert main(["fleet", "schedule", "--db", db, "--risk", "0.05", "--out", str(out)]) == 0
    capsys.readouterr()
    row = next(csv.DictReader(out.open()))
    assert float(row["inspect_by"]) == nxt["at"]
    assert main(["prognose", "X-1", "--db", db, "--risk", "0.05", "--json",
                 "--threshold", "friction=0.9"]) == 0
    nxt = json.loads(capsys.readouterr().out)["next_inspection"]
    assert nxt["rule"] == "too few inspections"


@pytest.mark.parametrize("argv, needle", [
    (["--risk", "0"], "risk must be a probability in (0, 1)"),
    (["--risk", "1"], "risk must be a probability in (0, 1)"),
    (["--risk", "-0.1"], "risk must be a probability in (0, 1)"),
    (["--risk", "nan"], "risk must be a probability in (0, 1)"),
    (["--risk", "0.00001"], "below 0.0001"),
    (["--risk", "0.05", "--max-interval", "0"], "interval must be a finite number > 0"),
    (["--risk", "0.05", "--max-interval", "-100"], "interval must be a finite number > 0"),
    (["--risk", "0.05", "--min-interval", "900"], "the minimum interval 900 h must be below"),
    (["--max-interval", "100"], "--max-interval plans the next inspection: give --risk too"),
])
def test_prognose_risk_refuses_bad_input_in_one_line(history, capsys, argv, needle):
    assert _rc(["prognose", "EMA-7", "--db", history, *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err and needle in err, err


def test_prognose_risk_of_an_unknown_actuator_is_one_line(history, capsys):
    assert main(["prognose", "EMA-9", "--db", history, "--risk", "0.05"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "'EMA-9' is not registered" in err


def test_reasons_never_print_a_number_equal_to_the_one_it_is_compared_with():
    """'probability 0.05 ..., above the risk 0.05' and 'within 100 h, under the minimum
    interval 100 h' (0.0501 and 99.99 rounded) read as contradictions: digits are added
    until the two differ on paper."""
    from emaphm.prognosis.inspection import _apart

    assert _apart(0.0501, 0.05) == "0.0501" and _apart(0.0500001, 0.05) == "0.0500001"
    assert _apart(0.2, 0.05) == "0.2" and _apart(0.05, 0.05) == "0.05"
    assert _apart(99.99, 100.0, 3) == "99.99" and _apart(150.0, 100.0, 3) == "150"


def test_a_crossing_after_the_last_inspection_off_the_healthy_level_stays_a_crossing():
    """Friction at 87 % of its threshold, rising within its scatter (4 inspections): carried
    to 1500 h it has crossed in 86 % of the draws. Off its healthy level, that is a
    crossing (first to fail, past threshold), as the plan says, not 'no growth'; and the
    table at the last inspection quotes its median, not 'in the noise'."""
    from emaphm.prognosis.cli import _prognosis_table
    from emaphm.prognosis.thresholds import DEFAULT_FAILURE_THRESHOLDS
    from emaphm.prognosis.trends import indicator_state

    t = np.array([0.0, 100.0, 200.0, 300.0])
    thr = DEFAULT_FAILURE_THRESHOLDS.for_indicator("friction")
    K = _friction_k(np.array([0.3, 0.55, 0.45, 0.62]) / 0.7 * thr)
    later = prognose(t, K, seed=0, t_now=1500.0, indicators=["friction"])
    p = later.predictions["friction"]
    assert p.median == 0.0 and indicator_state(p, 300.0)[0] == "past threshold"
    assert later.first is p
    plan = plan_inspection(t, later, t_now=1500.0, time_unit="h", K=K)
    assert plan.rule == "act now" and plan.indicator == "friction"
    row = next(line for line in _prognosis_table(prognose(t, K, seed=0)).splitlines()
               if line.startswith("friction"))
    assert "in the noise" not in row and "no growth" not in row
