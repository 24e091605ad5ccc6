"""The fault vector k: validation, the mapping onto parameters, scenarios, Eq. 9, packing."""

from __future__ import annotations

import math

import numpy as np
import pytest
from support import k_with
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from emaphm.faults import (K_NAMES, K_NOMINAL, MAX_SHORTED_FRACTION, N_K, PAPER_SCENARIOS,
                           SCENARIO_FAULT_MODELS, SCENARIOS, FaultVectorError, apply_faults,
                           as_k, error_pct, scenario, scenario_fault_model)
from emaphm.models.layout import (C_BACKLASH, C_C0_A, C_ECC, C_ECC_PHASE, C_FDJ, C_FSJ,
                                  C_GAMMA, C_KP, C_L_A, C_MU_A, C_PHI, C_R_A, N_CP, P_DT, P_T_S,
                                  pack, pack_population, PopulationPacker)
from emaphm.models import layout as packer_module
from emaphm.params import siemens_1fk7060

NOMINAL = siemens_1fk7060()
unit = st.floats(0.0, 1.0, allow_nan=False)
k_vectors = arrays(np.float64, N_K, elements=unit)


_k = k_with      # nominal k with some components set, by 1-based index


# --------------------------------------------------------------------------- as_k

def test_nominal_vector():
    assert K_NOMINAL.tolist() == [0, 0, 0, 0, 0, 0, 0.5, 0.5]
    assert len(K_NAMES) == N_K == 8
    assert not K_NOMINAL.flags.writeable


def test_as_k_accepts_sequences_and_strings():
    assert as_k([0, 0, 0, 0, 0, 0, 0.5, 0.5]).tolist() == K_NOMINAL.tolist()
    assert as_k("0.75,0,0,0,0,0,0.5,0.5").tolist() == _k(k1=0.75).tolist()
    assert as_k(" 0.75, 0,0,0,0,0,0.5,0.5 ").dtype == np.float64


@pytest.mark.parametrize("bad, match", [
    ([0.0] * 7, r"needs 8 components \(friction, backlash, .*\), got shape \(7,\)"),
    ([[0.0] * 8], r"needs 8 components.*got shape \(1, 8\)"),
    ([0, 0, float("nan"), 0, 0, 0, 0.5, 0.5], r"non-finite components"),
    ([0, 0, 0, 0, 0, 0, float("inf"), 0.5], r"non-finite components"),
    ([0, 0, 1.5, 0, 0, 0, 0.5, 0.5], r"component k3 \(short_a\) = 1\.5 is outside \[0, 1\]"),
    ([0, -0.1, 0, 0, 0, 0, 0.5, 0.5], r"component k2 \(backlash\) = -0\.1 is outside \[0, 1\]"),
    ("0.1,zero,0,0,0,0,0.5,0.5", r"not a comma-separated list of 8 numbers"),
])
def test_as_k_rejects(bad, match):
    with pytest.raises(FaultVectorError, match=match):
        as_k(bad)


def test_apply_faults_validates_k():
    with pytest.raises(FaultVectorError, match=r"k8 \(gain\) = 2 is outside"):
        apply_faults(NOMINAL, _k(k8=2.0))
    with pytest.raises(FaultVectorError, match="needs 8 components"):
        apply_faults(NOMINAL, [0.0] * 9)


# --------------------------------------------------------------------------- apply_faults

def test_nominal_k_leaves_parameters_unchanged():
    assert apply_faults(NOMINAL, K_NOMINAL) == NOMINAL


@given(unit)
def test_friction_k1(k1):
    f = apply_faults(NOMINAL, _k(k1=k1))
    assert f.transmission.FSJ == pytest.approx(NOMINAL.transmission.FSJ * (1 + 2 * k1), rel=1e-15)
    assert f.transmission.FDJ == pytest.approx(NOMINAL.transmission.FDJ * (1 + 2 * k1), rel=1e-15)
    assert f.transmission.backlash == NOMINAL.transmission.backlash
    assert f.motor == NOMINAL.motor and f.controller == NOMINAL.controller


def test_friction_known_values():
    f = apply_faults(NOMINAL, _k(k1=1.0))                   # Table 1: x3 at k1 = 1
    assert f.transmission.FSJ == pytest.approx(3 * 0.12)
    assert f.transmission.FDJ == pytest.approx(3 * 0.08)
    f = apply_faults(NOMINAL, _k(k1=0.25))
    assert f.transmission.FDJ == pytest.approx(0.12)


@given(unit)
def test_backlash_k2(k2):
    f = apply_faults(NOMINAL, _k(k2=k2))
    assert f.transmission.backlash == pytest.approx(NOMINAL.transmission.backlash * (1 + 99 * k2),
                                                    rel=1e-15)
    assert f.transmission.FSJ == NOMINAL.transmission.FSJ


def test_backlash_known_values():
    assert apply_faults(NOMINAL, _k(k2=1.0)).transmission.backlash == pytest.approx(2e-2)  # x100
    assert apply_faults(NOMINAL, _k(k2=0.75)).transmission.backlash == pytest.approx(2e-4 * 75.25)


@pytest.mark.parametrize("phase", [0, 1, 2])
@given(s=unit)
def test_short_circuit_k3_k4_k5(phase, s):
    f = apply_faults(NOMINAL, _k(**{f"k{3 + phase}": s})).motor
    m = NOMINAL.motor
    eff = min(s, 0.99)
    for j in range(3):
        if j == phase:
            assert f.R[j] == pytest.approx(m.R[j] * (1 - eff), rel=1e-14)
            assert f.L[j] == pytest.approx(m.L[j] * (1 - eff) ** 2, rel=1e-14)
            assert f.c0[j] == pytest.approx(m.c0[j] * (1 - eff), rel=1e-14)
        else:
            assert (f.R[j], f.L[j], f.c0[j]) == (m.R[j], m.L[j], m.c0[j])
    assert f.ecc == 0.0 and f.p == m.p and f.J_m == m.J_m


def test_short_circuit_known_values_and_cap():
    m = apply_faults(NOMINAL, _k(k4=0.75)).motor
    assert m.R[1] == pytest.approx(3.15 / 4)
    assert m.L[1] == pytest.approx(22e-3 / 16)
    assert m.c0[1] == pytest.approx(NOMINAL.motor.c0[1] / 4)
    # a fully shorted phase is capped at 99 %: R, L stay > 0
    assert MAX_SHORTED_FRACTION == 0.99
    m = apply_faults(NOMINAL, _k(k3=1.0, k4=1.0, k5=1.0)).motor
    assert m.R == pytest.approx((3.15 * 0.01,) * 3)
    assert m.L == pytest.approx((22e-3 * 1e-4,) * 3)
    assert min(m.L) > 0 and min(m.R) > 0


@given(k6=unit, k7=unit)
def test_eccentricity_k6_k7(k6, k7):
    m = apply_faults(NOMINAL, _k(k6=k6, k7=k7)).motor
    assert m.ecc == k6
    assert m.ecc_phase == pytest.approx(2 * math.pi * (k7 - 0.5), abs=1e-15)
    assert -math.pi <= m.ecc_phase <= math.pi


def test_eccentricity_phase_known_values():
    # Table 1: k7 = 0 -> -180 deg, 1 -> +180 deg; nominal 0.5 -> 0 rad exactly
    assert apply_faults(NOMINAL, _k(k6=0.3, k7=0.5)).motor.ecc_phase == 0.0
    assert apply_faults(NOMINAL, _k(k6=0.3, k7=0.0)).motor.ecc_phase == pytest.approx(-math.pi)
    assert apply_faults(NOMINAL, _k(k6=0.3, k7=1.0)).motor.ecc_phase == pytest.approx(math.pi)
    assert apply_faults(NOMINAL, _k(k6=0.3, k7=0.75)).motor.ecc_phase == pytest.approx(math.pi / 2)


@given(unit)
def test_gain_k8(k8):
    f = apply_faults(NOMINAL, _k(k8=k8))
    assert f.controller.Kp == pytest.approx(NOMINAL.controller.Kp * (0.5 + k8), rel=1e-15)
    # the drive's model of the motor is not changed by any fault
    assert f.controller.k_T == NOMINAL.controller.k_T
    assert f.controller.Kp_w == NOMINAL.controller.Kp_w


def test_gain_known_values():
    assert apply_faults(NOMINAL, _k(k8=0.0)).controller.Kp == pytest.approx(30.0)   # -50 %
    assert apply_faults(NOMINAL, _k(k8=1.0)).controller.Kp == pytest.approx(90.0)   # +50 %
    assert apply_faults(NOMINAL, _k(k8=0.25)).controller.Kp == pytest.approx(45.0)


@given(k_vectors)
def test_apply_faults_is_pure_and_keeps_unrelated_parts(k):
    before = NOMINAL.to_dict()
    f = apply_faults(NOMINAL, k)
    assert NOMINAL.to_dict() == before
    assert f.inverter == NOMINAL.inverter and f.load == NOMINAL.load
    assert f.motor.J_m == NOMINAL.motor.J_m and f.motor.T_max == NOMINAL.motor.T_max
    # the faulty parameters are valid parameters (FDJ <= FSJ kept, all positive)
    assert f.transmission.FDJ <= f.transmission.FSJ


# --------------------------------------------------------------------------- scenarios

def test_scenario_names_and_values():
    assert set(SCENARIOS) == {
        "nominal", "friction-low", "friction-high", "backlash-low", "backlash-high",
        "short-circuit-low", "short-circuit-high", "eccentricity-low", "eccentricity-high",
        "gain-low", "gain-high", "multiple", "turn-short-5pct", "turn-short-15pct"}
    assert len(SCENARIOS) == 14
    assert len(PAPER_SCENARIOS) == 11 and "nominal" not in PAPER_SCENARIOS
    assert {SCENARIO_FAULT_MODELS[n] for n in PAPER_SCENARIOS} == {"paper"}
    assert scenario_fault_model("turn-short-15pct") == "physical"
    assert scenario("turn-short-15pct")[2] == 0.15
    assert SCENARIOS["nominal"].tolist() == K_NOMINAL.tolist()
    for mode, idx in [("friction", 0), ("backlash", 1), ("short-circuit", 2),
                      ("eccentricity", 5), ("gain", 7)]:
        for level, value in [("low", 0.25), ("high", 0.75)]:
            k = scenario(f"{mode}-{level}")
            expected = K_NOMINAL.copy()
            expected[idx] = value
            assert k.tolist() == expected.tolist(), (mode, level)
    # paper Eq. 8
    assert scenario("multiple").tolist() == [0.0133, 0.05, 0.003, 0, 0, 0.012, 0.5, 0.35]
    for name in SCENARIOS:
        as_k(SCENARIOS[name])        # all inside the box


def test_scenario_returns_a_copy_and_rejects_unknown_names():
    k = scenario("friction-high")
    k[0] = 0.0
    assert scenario("friction-high")[0] == 0.75
    with pytest.raises(FaultVectorError, match=r"unknown scenario 'friction-medium'; choose one of"):
        scenario("friction-medium")


# --------------------------------------------------------------------------- error (Eq. 9)

def test_error_pct_known_values():
    kt = scenario("friction-high")
    assert error_pct(kt, kt) == 0.0
    # one component off by d: 100 d / sqrt(6.5)
    k = kt.copy()
    k[0] = 0.65
    assert error_pct(k, kt) == pytest.approx(100 * 0.1 / math.sqrt(6.5), rel=1e-12)
    k = kt.copy()
    k[7] = 0.3
    assert error_pct(k, kt) == pytest.approx(100 * 0.2 / math.sqrt(6.5), rel=1e-12)
    # the eccentricity phase counts with weight k6_true: nothing without eccentricity ...
    k = kt.copy()
    k[6] = 0.9
    assert error_pct(k, kt) == 0.0
    # ... and k6_true * (k7 - k7_true)^2 with it
    kt = scenario("eccentricity-high")
    k = kt.copy()
    k[6] = 0.9
    assert error_pct(k, kt) == pytest.approx(100 / math.sqrt(6.5) * math.sqrt(0.75 * 0.4 ** 2), rel=1e-12)
    # the weight is the true k6, not the estimated one
    k[5] = 0.0
    assert error_pct(k, kt) == pytest.approx(
        100 / math.sqrt(6.5) * math.sqrt(0.75 ** 2 + 0.75 * 0.4 ** 2), rel=1e-12)


def test_error_pct_combined_and_batched():
    kt = scenario("multiple")
    k = kt + np.array([0.01, -0.02, 0.0, 0.03, 0.0, 0.1, 0.2, -0.05])
    s = 0.01 ** 2 + 0.02 ** 2 + 0.03 ** 2 + 0.1 ** 2 + 0.012 * 0.2 ** 2 + 0.05 ** 2
    assert error_pct(k, kt) == pytest.approx(100 / math.sqrt(6.5) * math.sqrt(s), rel=1e-12)
    batch = error_pct(np.stack([kt, k, kt]), kt)
    assert batch.shape == (3,)
    assert batch.tolist() == pytest.approx([0.0, error_pct(k, kt), 0.0])


@given(k_vectors, k_vectors)
def test_error_pct_properties(k, kt):
    e = error_pct(k, kt)
    assert e >= 0.0
    # the k7 term is bounded by its weight: Eq. 9 never exceeds 100*sqrt(8/6.5)
    assert e <= 100 * math.sqrt(8 / 6.5) + 1e-9
    # symmetric in everything but the k7 weight, zero on equal vectors
    assert error_pct(kt, kt) == 0.0
    if k[5] == kt[5]:
        assert error_pct(kt, k) == pytest.approx(e, rel=1e-12, abs=1e-12)


# --------------------------------------------------------------------------- packing

@given(arrays(np.float64, st.tuples(st.integers(1, 6), st.just(N_K)), elements=unit),
       st.sampled_from(["paper", "physical"]), st.sampled_from([1, 2, 5]))
def test_pack_population_rows_equal_pack_of_apply_faults(K, fault_model, n_sub):
    P, CP = pack_population(NOMINAL, K, 0.0, fault_model, n_sub=n_sub)
    assert CP.shape == (K.shape[0], N_CP)
    assert P[P_DT] == P[P_T_S] / n_sub
    for j, k in enumerate(K):
        P1, row = pack(apply_faults(NOMINAL, k, fault_model), 0.0, fault_model, n_sub=n_sub)
        np.testing.assert_array_equal(P, P1)
        np.testing.assert_allclose(CP[j], row[0], rtol=1e-15, atol=0.0)


def test_pack_population_winding_step_of_each_fault_model():
    """Paper: R, L, c0 scaled, no loops (their rows and columns of Phi, Gamma exactly
    decoupled); physical: R, L, c0 healthy, mu = k3..k5 and loops coupled to the phases."""
    K = np.stack([K_NOMINAL, _k(k3=0.4), _k(k4=0.2, k5=0.995)])
    _, paper = pack_population(NOMINAL, K, fault_model="paper")
    _, phys = pack_population(NOMINAL, K, fault_model="physical")
    m = NOMINAL.motor
    assert paper[1, C_R_A] == pytest.approx(0.6 * m.R[0]) and not paper[:, C_MU_A:C_MU_A + 3].any()
    np.testing.assert_array_equal(phys[:, C_R_A:C_R_A + 3], np.tile(m.R, (3, 1)))
    np.testing.assert_array_equal(phys[:, C_C0_A:C_C0_A + 3], np.tile(m.c0, (3, 1)))
    np.testing.assert_array_equal(phys[:, C_MU_A:C_MU_A + 3],
                                  [[0, 0, 0], [0.4, 0, 0], [0, 0.2, MAX_SHORTED_FRACTION]])
    # the healthy candidate is the same circuit under both models (leakage invisible)
    np.testing.assert_allclose(phys[0, C_PHI:], paper[0, C_PHI:], rtol=1e-12, atol=1e-15)
    for row in paper:
        Phi = row[C_PHI:C_GAMMA].reshape(5, 5)
        assert not Phi[2:, :2].any() and not Phi[:2, 2:].any()
    Phi = phys[1, C_PHI:C_GAMMA].reshape(5, 5)
    Gam = phys[1, C_GAMMA:C_GAMMA + 25].reshape(5, 5)
    assert abs(Phi[0, 2]) > 1e-3 and abs(Gam[2, 0]) > 1e-3         # loop a couples to i_alpha
    assert not Phi[3:, :3].any() and not Phi[:3, 3:].any()                        # b, c: none
    np.testing.assert_allclose(Gam, Gam.T, rtol=1e-12, atol=1e-18)               # symmetric


def test_pack_refuses_loops_under_the_paper_model():
    faulty = apply_faults(NOMINAL, _k(k3=0.3), "physical")
    with pytest.raises(ValueError, match="fault_model='physical'"):
        pack(faulty)
    with pytest.raises(FaultVectorError, match="unknown fault model"):
        pack_population(NOMINAL, K_NOMINAL[None], fault_model="ideal")
    with pytest.raises(ValueError, match="n_sub must be an integer >= 1"):
        pack_population(NOMINAL, K_NOMINAL[None], n_sub=0)


def test_pack_layout_known_values():
    P, CP = pack_population(NOMINAL, np.stack([K_NOMINAL, _k(k1=1, k2=1, k4=0.5, k6=0.2, k7=1, k8=1)]))
    nom, f = CP
    assert nom[C_KP] == 60.0 and nom[C_FSJ] == 0.12 and nom[C_FDJ] == 0.08
    assert nom[C_BACKLASH] == 2e-4 and nom[C_ECC] == 0.0 and nom[C_ECC_PHASE] == 0.0
    assert f[C_KP] == pytest.approx(90.0) and f[C_FSJ] == pytest.approx(0.36)
    assert f[C_BACKLASH] == pytest.approx(2e-2)
    assert f[C_R_A:C_R_A + 3] == pytest.approx([3.15, 3.15 / 2, 3.15])
    assert f[C_L_A:C_L_A + 3] == pytest.approx([22e-3, 22e-3 / 4, 22e-3])
    assert f[C_C0_A + 1] == pytest.approx(NOMINAL.motor.c0[1] / 2)
    assert f[C_ECC] == 0.2 and f[C_ECC_PHASE] == pytest.approx(math.pi)


@given(arrays(np.float64, st.tuples(st.integers(1, 12), st.just(N_K)), elements=unit),
       st.sampled_from(["paper", "physical"]), st.integers(0, 2**31 - 1))
def test_population_packer_rows_equal_uncached_packing(K, fault_model, seed):
    """A packer reused over populations (its winding cache warm, rows repeated, evicted
    and recomputed) gives exactly the rows of a fresh packing."""
    rng = np.random.default_rng(seed)
    packer = PopulationPacker(NOMINAL, 0.0, fault_model)
    packer.CACHE_SIZE = 4                                   # force evictions
    for _ in range(3):
        K2 = np.vstack([K, K[rng.integers(0, len(K), 3)]])     # repeated windings
        P, CP = packer(K2)
        P0, CP0 = pack_population(NOMINAL, K2, 0.0, fault_model)
        np.testing.assert_array_equal(P, P0)
        np.testing.assert_array_equal(CP, CP0)
        assert len(packer._windings) <= 4
        K = np.clip(K + rng.normal(0.0, 0.05, K.shape), 0.0, 1.0)


def test_population_packer_computes_each_winding_once():
    """A finite-difference batch changes the winding of a few candidates only: the
    others' step matrices come from the cache."""
    packer = PopulationPacker(NOMINAL, 0.0, "physical")
    x = _k(k1=0.3, k3=0.2)
    K = np.tile(x, (9, 1)) + np.vstack([np.zeros(N_K), 1e-3 * np.eye(N_K)])
    calls = []
    real = packer_module._population_matrices

    def spy(R, *a):
        calls.append(R.shape[0])
        return real(R, *a)

    packer_module._population_matrices = spy
    try:
        packer(K)
        packer(K)
    finally:
        packer_module._population_matrices = real
    # distinct windings: the centre and the three shorts moved (k3, k4, k5); then none
    assert calls == [4]


def test_pack_population_shape_error():
    with pytest.raises(ValueError, match=r"shape \(n_pop, 8\)"):
        pack_population(NOMINAL, np.zeros((3, 7)))


def test_error_pct_takes_the_eccentricity_phase_the_short_way_round():
    """k7 = 0 and k7 = 1 are the same angle (+-180 deg): no error between them."""
    k_true = np.array([0, 0, 0, 0, 0, 0.5, 0.0, 0.5])
    assert error_pct(np.array([0, 0, 0, 0, 0, 0.5, 1.0, 0.5]), k_true) == pytest.approx(0.0, abs=1e-12)
    near = np.array([0, 0, 0, 0, 0, 0.5, 0.98, 0.5])          # 0.02 of a turn away
    assert error_pct(near, k_true) == pytest.approx(100 / np.sqrt(6.5) * np.sqrt(0.5 * 0.02**2))


# --------------------------------------------------------------------------- fault models

def test_physical_fault_model_keeps_the_winding_and_records_the_shorted_turns():
    k = [0.0, 0.0, 0.15, 0.0, 0.3, 0.0, 0.5, 0.5]
    f = apply_faults(NOMINAL, k, "physical")
    m = NOMINAL.motor
    assert f.motor.R == m.R and f.motor.L == m.L and f.motor.c0 == m.c0
    assert f.motor.mu == (0.15, 0.0, 0.3)
    assert f.motor.R_f == m.R_f
    p = apply_faults(NOMINAL, k, "paper")
    assert p.motor.mu == (0.0, 0.0, 0.0)
    assert p.motor.R[0] == pytest.approx(m.R[0] * 0.85)
    # the other components map the same way under both models
    assert f.transmission == p.transmission
    # the drive keeps its data-sheet settings (its decoupling inductance the healthy motor's)
    assert f.controller.resolved(m, NOMINAL.load) == p.controller.resolved(m, NOMINAL.load)
    with pytest.raises(FaultVectorError, match="unknown fault model 'ideal'; choose 'physical'"):
        apply_faults(NOMINAL, k, "ideal")
