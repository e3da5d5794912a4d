"""MAVLink backends behind one interface."""

from companion.link.base import LinkError, SetpointKind, VehicleLink
from companion.link.messages import (
    Heartbeat,
    LinkEvent,
    LocalPosition,
    SensorContact,
    SensorSignal,
    SystemStatus,
)

__all__ = [
    "Heartbeat",
    "LinkError",
    "LinkEvent",
    "LocalPosition",
    "SensorContact",
    "SensorSignal",
    "SetpointKind",
    "SystemStatus",
    "VehicleLink",
]
