"""The names and defaults of the prognosis layer that the command line offers, in a module
light enough to build its parser without importing NumPy, SciPy or the trend models
(``emaphm --help`` imports none of them). Each is defined here and used by its module."""

#: How the trend models are combined: mixed by Akaike weight, or the best alone.
SELECTION_RULES = ("aicc", "average")

#: How the interval of an identified k is obtained (:mod:`emaphm.prognosis.uncertainty`).
SPREAD_METHODS = ("population", "seeds", "bootstrap")

#: The health indicators, one per fault mode (a short circuit one per phase); their
#: components and thresholds are in :mod:`emaphm.prognosis.thresholds`.
INDICATORS = ("friction", "backlash", "short_a", "short_b", "short_c", "eccentricity",
              "gain_drift")

#: An indicator at or above this share of its failure threshold is off its healthy level:
#: it takes part in an inspection plan's risk, growing or not
#: (:mod:`emaphm.prognosis.inspection`), and a trend's crossing before the last inspection
#: counts as past the threshold (:func:`emaphm.prognosis.states.indicator_state`); the same
#: quarter marks where the model discrepancy is measured
#: (:data:`emaphm.prognosis.trends.MODEL_DISCREPANCY`).
HEALTHY_SHARE = 0.25

#: The risk an inspection plan keeps under by default (``emaphm fleet``); how it was set is
#: in :mod:`emaphm.prognosis.inspection`.
DEFAULT_RISK = 0.01

#: The interval defaults in flight hours (:data:`emaphm.prognosis.inspection.INTERVAL_DEFAULTS`):
#: between inspections without a plan, the shortest worth planning, the longest reached.
FLIGHT_HOUR_INTERVALS = {"default": 300.0, "min": 100.0, "max": 600.0}

#: The named degradation scenarios of :data:`emaphm.prognosis.simulator.DEGRADATION_SCENARIOS`.
DEGRADATION_SCENARIO_NAMES = ("friction-growth", "short-circuit-growth", "gain-drift",
                              "friction-power")
