"""The two actuators the benchmarks run on: the preset and the 270 V design of
``examples/actuators/``, by the names their tables use."""

from __future__ import annotations

from pathlib import Path

#: name -> the parameter file (None: the preset, :func:`emaphm.params.siemens_1fk7060`).
ACTUATORS = {"preset": None,
             "ema-270v-750w": Path(__file__).resolve().parents[1] / "examples" / "actuators"
             / "ema-270v-750w.toml"}


def datasheet(name: str):
    """The data sheet of actuator ``name`` (one of :data:`ACTUATORS`)."""
    from emaphm.params import load_params, siemens_1fk7060

    path = ACTUATORS[name]
    return siemens_1fk7060() if path is None else load_params(path)
