"""The vocabulary of drives: the firmwares the reference plant can run and the drive paths
of the identification. Names only (no imports): the command line's choices read them
without loading the models.

* :data:`FOREIGN_DRIVES`: firmwares that are not emaphm's cascade
  (:mod:`emaphm.models.drives`), by name, with what they are;
* :data:`DRIVE_MODELS`: what stands in for a drive's controller when a trace is identified
  (:mod:`emaphm.recorded`): the controller as ``[controller]`` describes it, the voltage
  commands the drive recorded, its recorded current references (the current loop
  modelled), or its recorded speed reference (the speed and current loops modelled).
"""

from __future__ import annotations

__all__ = ["FOREIGN_DRIVES", "MODELLED", "RECORDED_VOLTAGES", "RECORDED_CURRENT_REFERENCES",
           "RECORDED_SPEED_REFERENCE", "DRIVE_MODELS", "DRIVEN"]

#: Firmwares that are not emaphm's, by name, with what they are.
FOREIGN_DRIVES = {
    "observer-ip": "position P + velocity feed-forward, I-P speed loop on an observed speed, "
                   "decoupled dq current PI, one period of delay with the angle advanced",
    "deadbeat": "position PI, speed PI on a filtered speed, predictive (deadbeat) current "
                "control",
    "stationary-pi": "position P, 2-DOF speed PI on a speed differenced from the angle over "
                     "four periods, per-phase current PI in the stationary frame (no dq "
                     "frame, no decoupling)",
}

#: The drive's controller as the parameters' ``[controller]`` describes it.
MODELLED = "modelled controller"
#: No controller: the winding driven by the voltage commands the drive recorded.
RECORDED_VOLTAGES = "recorded voltages"
#: The current loop as ``[controller]`` describes it, on the current references the drive
#: recorded: no position or speed loop.
RECORDED_CURRENT_REFERENCES = "recorded current references"
#: The speed and current loops as ``[controller]`` describes them, on the speed reference
#: the drive recorded: no position loop.
RECORDED_SPEED_REFERENCE = "recorded speed reference"
#: What stands in for a drive's controller when a trace is identified.
DRIVE_MODELS = (MODELLED, RECORDED_VOLTAGES, RECORDED_CURRENT_REFERENCES,
                RECORDED_SPEED_REFERENCE)
#: The paths that model no position loop: the winding driven by what the drive recorded,
#: the mechanics an observer of the measured angle (:mod:`emaphm.models.driven`).
DRIVEN = (RECORDED_VOLTAGES, RECORDED_CURRENT_REFERENCES, RECORDED_SPEED_REFERENCE)
