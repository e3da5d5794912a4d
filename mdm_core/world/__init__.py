"""The search world: area, targets (fixed, pop-up, dynamic, false) and the two sensors, batched."""

from mdm_core.world.area import Area, BoundaryRule
from mdm_core.world.scenario import Scenario
from mdm_core.world.sensors import Sensor, contacts, first_entry_time
from mdm_core.world.targets import RandomWalk, TargetSpec, TargetTracks

__all__ = [
    "Area",
    "BoundaryRule",
    "RandomWalk",
    "Scenario",
    "Sensor",
    "TargetSpec",
    "TargetTracks",
    "contacts",
    "first_entry_time",
]
