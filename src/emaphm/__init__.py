"""emaphm: model-based prognostics and health management of PMSM electromechanical actuators.

Simulate healthy and faulty actuators with a high-fidelity reference model and
a fast, batched monitoring model; identify the fault vector ``k`` of a
recorded trace with metaheuristics (Baldo et al., Aerospace 2023, 10, 293).
"""

__version__ = "0.3.0"
