"""Fault vectors for tests: the nominal k with some components set."""

from emaphm.faults import K_NOMINAL


def k_with(**components: float):
    """Nominal k with some components set, by 1-based index: ``k_with(k3=0.25)``."""
    k = K_NOMINAL.copy()
    for name, value in components.items():
        k[int(name[1:]) - 1] = value
    return k
