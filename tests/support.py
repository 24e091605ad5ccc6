"""Helpers the tests share (imported by name: ``from support import k_with``).

* fault vectors: :func:`k_with`;
* figures: :func:`assert_png_of`, :func:`legend_texts`, :func:`markers`;
* agreement of two monitoring-model implementations (``tests/models/``): two
  implementations of the same operations differ only by an ulp of a sine now and then.
  Most trajectories carry that through unchanged and must agree to ``TOL``. Some
  candidates with a heavily shorted phase drive the discrete current loop unstable until
  the drive trips: they amplify any ulp, so the reference does not even agree with its
  own "twin", the same run with ``k`` nudged by ``NUDGE`` (relative). For those the
  tests check what is well defined: the same status, and agreement up to the step where
  the twin departs (the horizon of predictability), less ``MARGIN`` steps since the
  nudge is larger than an ulp. The reference decides which candidates are
  ill-conditioned, so a wrong branch cannot hide behind that label on a
  well-conditioned candidate;
* campaign runs computed by two processes: :func:`assert_same_outcome`; the small
  campaign of the campaign tests, :func:`small_spec`, and a store's outcomes,
  :func:`outcomes`;
* errors and convergence: :func:`rms`, :func:`nrms`, :func:`fitted_order`;
* traces shared by several test modules, as fixtures (``from support import mm_trace``
  makes it one of the module's): :func:`mm_trace`, :func:`mm_gain_low`.
"""

from __future__ import annotations

import numpy as np
import pytest

from emaphm.faults import K_NOMINAL, SCENARIOS

# ----------------------------------------------------------------------------- fault vectors

def k_with(**components: float):
    """Nominal k with some components set, by 1-based index: ``k_with(k3=0.25)``."""
    k = K_NOMINAL.copy()
    for name, value in components.items():
        k[int(name[1:]) - 1] = value
    return k


# ----------------------------------------------------------------------------- errors

def rms(x) -> float:
    """Root mean square of ``x``."""
    return float(np.sqrt(np.mean(np.asarray(x, float) ** 2)))


def nrms(x, ref) -> float:
    """Normalised RMS difference ``rms(x - ref) / rms(ref)``."""
    x, ref = np.asarray(x, float), np.asarray(ref, float)
    return rms(x - ref) / rms(ref)


def fitted_order(steps, errors) -> float:
    """Slope of log(error) against log(step): the observed order of convergence."""
    x, y = np.log(np.asarray(steps, float)), np.log(np.asarray(errors, float))
    return float(np.polyfit(x, y, 1)[0])


# ----------------------------------------------------------------------------- shared traces

@pytest.fixture(scope="session")
def mm_trace():
    """A noise-free monitoring-model trace of a 15 % turn short (the physical fault model),
    fast to make; tests that never reach an identification use it as any valid trace."""
    from emaphm.simulate import simulate

    return simulate(scenario="turn-short-15pct", model="monitoring")


@pytest.fixture(scope="session")
def mm_gain_low():
    """Noise-free monitoring-model trace of the gain-low scenario (k8 = 0.25): the
    monitoring model can match it exactly."""
    from emaphm.simulate import simulate

    return simulate(scenario="gain-low", model="monitoring")


# ----------------------------------------------------------------------------- figures

DPI = 120          # emaphm.plots.save_figure's default


def assert_png_of(path, size_in, dpi: int = DPI) -> None:
    """``path`` is a PNG of a figure of ``size_in`` (width, height) inches at ``dpi`` (or of
    that ``Figure``) as :func:`emaphm.plots.save_figure` writes it: it decodes, has the
    figure's size in pixels, and is drawn (hundreds of colours, not a blank canvas)."""
    from matplotlib.image import imread

    if hasattr(size_in, "get_size_inches"):
        size_in = size_in.get_size_inches()
    img = imread(path)                                  # raises on anything but an image
    w, h = (round(float(x) * dpi) for x in size_in)
    assert img.shape[:2] == (h, w), (img.shape, (h, w))
    colours = np.unique(img.reshape(-1, img.shape[2]), axis=0)
    assert len(colours) > 100, f"{path}: {len(colours)} colours, a blank figure?"


def legend_texts(ax) -> list[str]:
    legend = ax.get_legend()
    return [] if legend is None else [t.get_text() for t in legend.get_texts()]


def markers(ax, marker: str) -> list:
    """The lines of ``ax`` drawn with ``marker`` and no connecting line."""
    return [ln for ln in ax.lines if ln.get_marker() == marker and ln.get_linestyle() == "None"]


# ----------------------------------------------------------------------------- model agreement

TOL = 1e-9            # rtol and atol on currents [A], angles [rad], speeds [rad/s], torque [N m]
NUDGE = 1e-12         # relative nudge of k that makes the reference's twin
MARGIN = 100          # steps: growth of a ~1e4 ulp nudge over an ulp one: ~10 steps at the
                      # current loop's gain of ~3/step, up to ~90 (1.1/step) where the backlash
                      # contact and the stick/slip decisions amplify it (measured 81)
N_RANDOM = 24
#: At least this many of the random candidates must be well conditioned (measured 11 of
#: 24 with the compliant backlash contact, whose impacts amplify an ulp on large backlash).
MIN_WELL = N_RANDOM // 3


def population() -> np.ndarray:
    """24 seeded random candidates, the named scenarios, then the corners 0 and 1."""
    rng = np.random.default_rng(20240611)
    named = np.array([k for k in SCENARIOS.values()])
    corners = np.array([np.zeros(8), np.ones(8)])
    return np.vstack([rng.random((N_RANDOM, 8)), named, corners])


def traces(r) -> dict:
    """The trace arrays of a ``PopulationResult`` by name."""
    return {"i_abc": r.i_abc, "theta_m": r.theta_m, "omega_m": r.omega_m, "torque": r.torque}


def conditioning(mm, K: np.ndarray):
    """``(reference, well, horizon)``: the population run by ``mm``, which candidates
    agree with their nudged twin over the whole trace, and the first step where each
    one departs from it (``mm.t.size`` when it never does)."""
    reference = mm.simulate_population(K)
    twin = mm.simulate_population(K + NUDGE * (0.5 - K))     # stays inside [0, 1]
    departs = np.max(np.abs(reference.i_abc - twin.i_abc), axis=2) > TOL
    horizon = np.where(departs.any(axis=1), departs.argmax(axis=1), mm.t.size)
    return reference, horizon == mm.t.size, horizon


def assert_traces_agree(candidate: dict, reference, well, horizon) -> None:
    """To ``TOL`` on well-conditioned candidates, up to their horizon on the others."""
    for name, ref in traces(reference).items():
        np.testing.assert_allclose(candidate[name][well], ref[well], rtol=TOL, atol=TOL,
                                   err_msg=name)
    for j in np.flatnonzero(~well):
        h = max(horizon[j] - MARGIN, 0)
        for name, ref in traces(reference).items():
            np.testing.assert_allclose(candidate[name][j, :h], ref[j, :h], rtol=TOL, atol=TOL,
                                       err_msg=f"{name}, candidate {j}, first {h} steps")


# ----------------------------------------------------------------------------- campaign runs
#: Relative tolerance on the float fields of one run computed by two processes.
RUN_RTOL = 1e-12


def assert_same_outcome(got: dict, want: dict, key: str = "") -> None:
    """Two outcomes (``RunResult.outcome()``) of the same run computed by two processes:
    keys, seeds, counts, reasons and statuses exactly; fitness, errors, k and the history to
    ``RUN_RTOL``.

    Every process runs the kernels Numba compiled into its on-disk cache, and that cache
    does not track the physics modules a kernel inlines (see
    :mod:`emaphm.models.monitoring_simd`). A process that loads a kernel cached before an
    edit of those modules and one that compiles it anew (when another process rewrites the
    cache meanwhile) run the same model with different rounding: a history once differed in
    its 16th digit that way. Same runs, seeds and evaluation counts are what an executor
    must guarantee; bit-identical arithmetic across processes is not ours to promise.
    """
    assert got.keys() == want.keys(), key
    for name, w in want.items():
        g = got[name]
        floats = isinstance(w, float) or (isinstance(w, (tuple, list)) and len(w) > 0
                                          and all(isinstance(x, float) for x in w))
        if floats and g is not None:
            np.testing.assert_allclose(np.asarray(g, dtype=float), np.asarray(w, dtype=float),
                                       rtol=RUN_RTOL, atol=0.0, err_msg=f"{key}: {name}")
        else:
            assert g == w, (key, name, g, w)


#: The small campaign of the campaign tests: 2 scenarios x 2 algorithms x 4 runs, 600
#: evaluations per run (a quarter to half a second each).
SMALL_CAMPAIGN = {"scenarios": "friction-high,multiple", "algorithms": "pso,de", "runs": 4,
                  "master_seed": 7, "budget": 600, "name": "small"}


def small_spec(**kw):
    """:data:`SMALL_CAMPAIGN` as a :class:`~emaphm.campaign.CampaignSpec`; ``kw`` replaces
    its fields or adds others (scenarios and algorithms as names; None: the default of
    :func:`~emaphm.campaign.paper_spec`)."""
    from emaphm.campaign import paper_spec
    from emaphm.campaign.spec import parse_algorithms, parse_scenarios

    fields = {k: v for k, v in {**SMALL_CAMPAIGN, **kw}.items() if v is not None}
    if isinstance(fields.get("scenarios"), str):
        fields["scenarios"] = parse_scenarios(fields["scenarios"])
    if isinstance(fields.get("algorithms"), str):
        fields["algorithms"] = parse_algorithms(fields["algorithms"])
    return paper_spec(**fields)


def outcomes(path) -> dict[str, dict]:
    """Run key -> ``RunResult.outcome()`` of every result in the campaign store at ``path``."""
    from emaphm.campaign import CampaignStore

    with CampaignStore.open(path, readonly=True) as st:
        return {r.key: r.outcome() for r in st.results()}


# ----------------------------------------------------------------------------- SciPy's seeding

def spy_on_init(monkeypatch, cls) -> list[dict]:
    """The keyword arguments of every construction of ``cls`` from now on (its signature,
    which emaphm reads to choose ``rng=`` or ``seed=``, stays the class's own)."""
    import functools

    calls: list[dict] = []
    init = cls.__init__

    @functools.wraps(init)
    def spied(self, *args, **kw):
        calls.append(kw)
        init(self, *args, **kw)

    monkeypatch.setattr(cls, "__init__", spied)
    return calls


def scipy_rng_keyword(cls) -> str:
    """``"rng"`` where SciPy's ``cls`` takes it (SciPy >= 1.15, SPEC 7), else ``"seed"``."""
    import inspect

    return "rng" if "rng" in inspect.signature(cls).parameters else "seed"
