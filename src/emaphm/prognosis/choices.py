"""The names and defaults of the prognosis layer that the command line offers, in a module
light enough to build its parser without importing NumPy, SciPy or the trend models
(``emaphm --help`` imports none of them). Each is defined here and used by its module, but
the health indicators: the fault modes declare them (:mod:`emaphm.modes`), and the parser
reads them from the registry only when it checks a value or prints the help of the command
that takes them."""

from typing import Any, Iterator, Sequence


class _IndicatorNames(Sequence):
    """The health indicators' names (:data:`emaphm.modes.INDICATORS`), read from the
    registry on first use; ``in`` also holds for an older name (``short_a``), which the
    commands take with a DeprecationWarning."""

    def _names(self) -> tuple[str, ...]:
        from .. import modes

        return tuple(modes.INDICATORS)

    def __getitem__(self, i: Any) -> Any:
        return self._names()[i]

    def __len__(self) -> int:
        return len(self._names())

    def __iter__(self) -> Iterator[str]:
        return iter(self._names())

    def __contains__(self, name: object) -> bool:
        from .. import modes

        return name in modes.INDICATORS or name in modes.INDICATOR_ALIASES

    def __repr__(self) -> str:
        return repr(self._names())


class _FailureDefaults:
    """The default failure thresholds in words, for a help text (read on printing it)."""

    def __str__(self) -> str:
        from .. import modes

        return ", ".join(f"{n} {v:g}" for n, (v, _) in modes.FAILURE_FIELDS.items())

#: How the trend models are combined: mixed by Akaike weight, or the best alone.
SELECTION_RULES = ("aicc", "average")

#: How the interval of an identified k is obtained (:mod:`emaphm.prognosis.uncertainty`).
SPREAD_METHODS = ("population", "seeds", "bootstrap")

#: The health indicators, each fault mode's (a short circuit one per phase), as the
#: command line offers them (:data:`emaphm.modes.INDICATORS`; their thresholds in
#: :mod:`emaphm.prognosis.thresholds`).
INDICATORS: Sequence[str] = _IndicatorNames()

#: The default failure thresholds, as a help text reads them.
FAILURE_DEFAULTS = _FailureDefaults()

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
