"""The names of the prognosis layer's strategies, in a module light enough for the CLI to
offer them as choices without importing SciPy or the trend models."""

#: How the trend models are combined: mixed by Akaike weight, or the best alone.
SELECTION_RULES = ("aicc", "average")

#: How the interval of an identified k is obtained (:mod:`emaphm.prognosis.uncertainty`).
SPREAD_METHODS = ("population", "seeds", "bootstrap")
