"""Pick the autopilot class from the MAV_AUTOPILOT value of a HEARTBEAT."""

from __future__ import annotations

from companion.autopilots.ardupilot import ArduCopter
from companion.autopilots.base import Autopilot
from companion.autopilots.px4 import PX4
from companion.errors import CompanionError

_REGISTRY: dict[int, type[Autopilot]] = {cls.mav_autopilot: cls for cls in (PX4, ArduCopter)}


class UnknownAutopilotError(CompanionError, ValueError):
    """A HEARTBEAT from an autopilot the companion cannot command."""


def register(cls: type[Autopilot]) -> type[Autopilot]:
    """Add an autopilot family (usable as a class decorator)."""
    _REGISTRY[cls.mav_autopilot] = cls
    return cls


def autopilot_for(mav_autopilot: int) -> Autopilot:
    """The autopilot that reports ``mav_autopilot`` in its HEARTBEAT."""
    try:
        return _REGISTRY[mav_autopilot]()
    except KeyError:
        known = ", ".join(f"{k} ({c.name})" for k, c in sorted(_REGISTRY.items()))
        raise UnknownAutopilotError(
            f"HEARTBEAT autopilot {mav_autopilot} is not supported; known: {known}"
        ) from None
