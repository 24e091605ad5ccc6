"""What a named short's fault loop is, read from the one fit: its profile along the
fault-bridge resistance.

A short of the fraction ``mu`` of a phase's turns through a bridge ``R_f`` draws a loop
current ``i_f``; the terminal currents see its ampere-turns ``mu i_f`` and, for a severe
short, the loop's own inductance. For a mild one ``mu`` and ``R_f`` trade off along a
valley where ``mu i_f`` stays and ``i_f``, ``R_f i_f^2`` do not (docs/fault-modes.md).
So the verdict reports the ampere-turns as the short's severity and every quantity of the
loop as an interval over the fits that are as good.

**The profile.** Along the phase's fault resistance (:data:`PROFILE_DECADES` points over
the ``Rf_*`` search range, decades of ``Motor.R_f``), the shorted fraction that fits the
trace best, the rest of the fit held (its other k components and the parameters it
searched beside k): one batched search (successive grids of :data:`PROFILE_GRID`
fractions around the best, every resistance at once, :data:`PROFILE_ROUNDS` rounds), not a
refit per point. **The criterion**: the points whose Eq. 4 is within :data:`PROFILE_LR` of
the profile's best, a likelihood ratio (with Gaussian residuals whose variance the best fit
estimates, ``-2 log L = n log(F / F_best)``) whose threshold is set by the monitoring
model's discrepancy, not by the noise alone: within 2 % of the best, the plant's loop
current fell outside on 27 of 70 tuning shorts (its physics the model lacks, the PWM ripple
in the loop among them, biases the valley's floor), and the noise's own threshold (3.84
over the trace's effective samples) is narrower still. The threshold was measured on
shorts of tuning seeds (:data:`PROFILE_LR`). The interval's ends are where the profile
crosses the threshold, between the profile's points (linear between them): never a point,
and said to be ``open`` (at the ``"low"`` or ``"high"`` end of the fault resistance) where
it reaches the searched range's end.

A quantity is **determined** where its interval spans less than a factor
:data:`DETERMINED` (its upper end over its lower end).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from .faults import MAX_SHORTED_FRACTION, loop_report
from .firmware import MODELLED
from .models.layout import MU_MIN
from .modes.short_circuit import LOOP_QUANTITIES
from .problem import IdentificationProblem
from .search import NUISANCE_RANGE

__all__ = ["profile", "intervals", "PROFILE_DECADES", "PROFILE_LR", "PROFILE_GRID", "PROFILE_ROUNDS",
           "DETERMINED", "QUANTITIES"]

#: Points of the profile along the fault resistance (over the ``Rf_*`` search range).
PROFILE_DECADES = 21
#: Shorted fractions per round of the profile's search, and its rounds: each round
#: narrows the grid around the best to a third (9 points, 6 rounds: ``mu`` to 1e-3 of the
#: first span).
PROFILE_GRID = 9
PROFILE_ROUNDS = 6
#: A point of the profile fits "as well" when its Eq. 4 is within this share of the
#: profile's best (see the module doc). Measured by ``benchmarks/bench_fault_coverage.py
#: --tune-shorts`` (70 shorts of 5-30 % through 0.05-0.5 ohm on both actuators, tuning
#: noise seeds 200+): the plant's loop current inside at 0.02, 0.05, 0.08, 0.1: 43, 55, 63,
#: 70 of 70 (its shorted fraction 49, 59, 67, 70; the median current interval 1.6x, 1.9x,
#: 2.2x, 2.3x wide): the smallest share tried with 90 % inside, and a margin.
PROFILE_LR = 0.1
#: A quantity whose interval spans less than this factor is determined by the fit.
DETERMINED = 2.0

#: The loop's quantities a short reports: name -> the name of its interval.
QUANTITIES = LOOP_QUANTITIES


def profile(problem: IdentificationProblem, k: np.ndarray, extra: dict, j: int) -> dict[str, Any]:
    """The loop of phase ``j``'s short at the fit ``(k, extra)`` (the values searched beside
    k by name) and each quantity's interval over the fits as good along the profile.

    Returns each of :data:`QUANTITIES` at the fit, its interval ``[lo, hi]``, the names of
    those determined (``determined``), and where an interval reaches the end of the
    searched range (``open``: ``"low"``, ``"high"`` or both, of the fault resistance).
    """
    name = f"Rf_{'abc'[j]}"
    names = tuple(n for n in extra if n != name) + (name,)
    trial = replace(problem, nuisance=names, start=None, search=None, objective=None)
    lo_d, hi_d = NUISANCE_RANGE[name]
    r_f = float(extra.get(name, 0.0))
    decades = np.unique(np.append(np.linspace(lo_d, hi_d, PROFILE_DECADES), r_f))
    nu = np.array([float(extra.get(n, 0.0)) for n in names[:-1]])
    k = np.asarray(k, dtype=float)
    mu, F = _best_fractions(trial, k, nu, decades, j)
    # the profile's points and, last, the fit itself, in one run of the model
    Q = _quantities(trial, k, nu, np.append(mu, k[2 + j]), np.append(decades, r_f), j)
    out: dict[str, Any] = {q: float(v[-1]) for q, v in Q.items()}
    Q = {q: v[:-1] for q, v in Q.items()}
    out.update(intervals(Q, F, out))
    # the profile itself: each point's bridge, fraction, fit over the best and loop
    out["profile"] = {q: Q[q].tolist() for q in QUANTITIES}
    out["profile"]["fit_over_best"] = (F / F.min()).tolist()
    return out


def intervals(Q: dict[str, np.ndarray], F: np.ndarray, at: dict[str, float],
              tolerance: float = PROFILE_LR) -> dict[str, Any]:
    """Each quantity's interval over the profile's points that fit within ``tolerance``
    of its best (``Q[q]`` and ``F`` at each point, in the order of the fault resistance;
    ``at``: the quantities at the fit, always inside), its ends where the profile crosses
    the threshold between a point inside and the next outside (linear in the profile's
    steps); which quantities are ``determined`` (:data:`DETERMINED`) and whether the
    interval reaches the profile's ends (``open``)."""
    F = np.asarray(F, dtype=float)
    threshold = F.min() * (1.0 + tolerance)
    idx = np.flatnonzero(F <= threshold)
    first, last = int(idx[0]), int(idx[-1])
    ends = [{q: float(Q[q][i]) for q in QUANTITIES} for i in range(first, last + 1)]
    for inside, outside in ((first, first - 1), (last, last + 1)):
        if 0 <= outside < F.size:
            w = (threshold - F[inside]) / (F[outside] - F[inside])
            ends.append({q: float(Q[q][inside] + w * (Q[q][outside] - Q[q][inside]))
                         for q in QUANTITIES})
    out: dict[str, Any] = {}
    for q, iv in QUANTITIES.items():
        vals = [e[q] for e in ends] + [at[q]]
        out[iv] = [float(min(vals)), float(max(vals))]
    out["determined"] = [q for q, iv in QUANTITIES.items()
                         if out[iv][0] > 0 and out[iv][1] <= DETERMINED * out[iv][0]]
    out["open"] = [side for side, edge in (("low", first == 0), ("high", last == F.size - 1))
                   if edge]
    return out


def _best_fractions(trial: IdentificationProblem, k: np.ndarray, nu: np.ndarray,
                    decades: np.ndarray, j: int) -> tuple[np.ndarray, np.ndarray]:
    """At each fault resistance (``decades``), the shorted fraction of phase ``j`` that fits
    best, the rest held at ``k`` and ``nu``, and its Eq. 4: successive grids around the
    best, every resistance in one population."""
    n = decades.size
    center = np.full(n, float(k[2 + j]))
    half = np.full(n, max(0.9 * float(k[2 + j]), 0.02))
    offsets = np.linspace(-1.0, 1.0, PROFILE_GRID)
    F = np.full(n, np.inf)
    for _ in range(PROFILE_ROUNDS):
        M = np.clip(center[:, None] + half[:, None] * offsets, MU_MIN, MAX_SHORTED_FRACTION)
        K = np.repeat(k[None, :], n * PROFILE_GRID, axis=0)
        K[:, 2 + j] = M.ravel()
        rows = np.hstack([K, np.repeat(nu[None, :], K.shape[0], axis=0),
                          np.repeat(decades, PROFILE_GRID)[:, None]])
        fit = np.asarray(trial.objective(rows), dtype=float).reshape(n, PROFILE_GRID)
        best = np.argmin(np.where(np.isfinite(fit), fit, np.inf), axis=1)
        center = M[np.arange(n), best]
        F = fit[np.arange(n), best]
        half = half / 3.0
    return center, F


def _quantities(trial: IdentificationProblem, k: np.ndarray, nu: np.ndarray, mu: np.ndarray,
                decades: np.ndarray, j: int) -> dict[str, np.ndarray]:
    """Phase ``j``'s loop at each shorted fraction ``mu`` through the bridge ``decades``
    (decades of ``Motor.R_f``), the rest at ``k`` and ``nu``: every point in one run of the
    model (the scalar kernel's loop currents on the modelled controller)."""
    K = np.repeat(k[None, :], mu.size, axis=0)
    K[:, 2 + j] = mu
    rows = np.hstack([K, np.repeat(nu[None, :], mu.size, axis=0), decades[:, None]])
    model = trial.objective.model
    if trial.drive_model == MODELLED:
        f = model.loop_currents(rows)[:, :, j]
    else:
        f = model.simulate_population(rows).f_abc[:, :, j]
    loops = loop_report(np.mean(f ** 2, axis=1), trial.params.motor.R_f[j] * 10.0 ** decades, mu)
    return {"mu": mu, **{q: np.asarray(v) for q, v in loops.items()}}
