"""Where a vehicle's mission is in its lifecycle."""

from __future__ import annotations

import enum


class Phase(enum.Enum):
    CONNECT = "connect"
    """Waiting for the vehicle's heartbeat and position."""
    PREPARE = "prepare"
    """Streaming setpoints, switching to the guided mode, arming."""
    CLIMB = "climb"
    """Taking off to this vehicle's altitude."""
    TRANSIT = "transit"
    """Flying at its altitude to the profile's start point; the search clock has not started."""
    SEARCH = "search"
    PAUSED = "paused"
    """Someone else changed the mode (a pilot): not commanding, waiting."""
    LINK_LOST = "link_lost"
    RETURN = "return"
    """End action (RTL or land) requested."""
    DONE = "done"
