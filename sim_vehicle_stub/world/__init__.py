"""The search world: area, targets (fixed, pop-up, dynamic, false) and the two sensors, batched."""

from sim_vehicle_stub.world.area import Area, BoundaryRule
from sim_vehicle_stub.world.scenario import Scenario
from sim_vehicle_stub.world.sensors import Sensor, contacts, first_entry_time
from sim_vehicle_stub.world.targets import RandomWalk, TargetSpec, TargetTracks

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
