"""PX4 / ArduPilot differences behind one base class and a registry."""

from companion.autopilots.ardupilot import ArduCopter
from companion.autopilots.base import Autopilot, FlightMode, ModeCommand
from companion.autopilots.px4 import PX4
from companion.autopilots.registry import UnknownAutopilotError, autopilot_for, register

__all__ = [
    "PX4",
    "ArduCopter",
    "Autopilot",
    "FlightMode",
    "ModeCommand",
    "UnknownAutopilotError",
    "autopilot_for",
    "register",
]
