"""Per-vehicle mission lifecycle: connect, ready, arm, take off, search, end."""

from companion.mission.config import MissionConfig
from companion.mission.phase import Phase
from companion.mission.vehicle_mission import VehicleMission

__all__ = ["MissionConfig", "Phase", "VehicleMission"]
