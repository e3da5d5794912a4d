"""Sensor sources behind one interface."""

from companion.sensors.base import SensorSource
from companion.sensors.mavlink_source import MavlinkSensorSource

__all__ = ["MavlinkSensorSource", "SensorSource"]
