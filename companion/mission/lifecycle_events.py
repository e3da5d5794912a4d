"""What the mission's lifecycle machine (lifecycle.py) hears and what it asks for.

Outcomes are what ``VehicleMission`` reports when it has performed a step the machine asked for
(:class:`Do`); requests come at any time from the link, the operator and the process's signals.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

from companion.autopilots import FlightMode


class Do(enum.Enum):
    """A step of I/O that ``VehicleMission`` performs for the lifecycle machine."""

    CONNECT = "connect"
    """Wait for the vehicle, ask for its streams, learn its frame, check the start position."""
    INSTALL_FENCE = "install_fence"
    """Install the profile's fence on the vehicle (when it has one), beside the mission."""
    LOCATE = "locate"
    """Wait for a HEARTBEAT and a position; say whether the vehicle is airborne and guided."""
    AWAIT_CONTROL = "await_control"
    """Wait until the vehicle is neither paused by someone else nor out of reach."""
    PREPARE = "prepare"
    """Stream neutral setpoints, ask for the guided mode, arm."""
    TAKEOFF = "takeoff"
    """MAV_CMD_NAV_TAKEOFF to the vehicle's altitude."""
    AWAIT_CLIMB_STOP = "await_climb_stop"
    """Wait until the autopilot's own takeoff reaches the altitude or stops climbing."""
    BEGIN_SETPOINTS = "begin_setpoints"
    CLIMB = "climb"
    """Wait until the vehicle is at 95 % of its altitude (setpoints climb)."""
    RETRY = "retry"
    """Wait one vehicle second, then locate again."""
    FLY = "fly"
    """Begin the setpoint stream and set the profile's speed (once per process)."""
    TRANSIT = "transit"
    """Fly to the profile's start point."""
    SAY_TRANSIT_DONE = "say_transit_done"
    START_SEARCH = "start_search"
    """Start the search core (taking back confirmed targets) and the search clock."""
    ANNOUNCE_LEVEL = "announce_level"
    """Record the search level and select its sensor."""
    AWAIT_SEARCH_END = "await_search_end"
    FINISH = "finish"
    """Report whether the vehicle is armed, for the end."""
    RECORD_END = "record_end"
    """Record the end, the speed flown; switch the sensor off."""
    FLY_END_ACTION = "fly_end_action"
    """Ask for the end action (RTL or LAND) and wait until the vehicle has landed and disarmed."""
    SAY_ENDING = "say_ending"
    """Say what the first signal does and that a second one stops at once."""
    EXIT = "exit"
    """Stop commanding at once (a second signal)."""
    SAY_BREACH = "say_breach"
    """Log and record the fence breach."""


# -- outcomes of the steps ------------------------------------------------------------------


@dataclass(frozen=True)
class Began:
    """The mission starts; ``ended``: its durable log already has an ``end`` record."""

    ended: bool


@dataclass(frozen=True)
class Connected:
    pass


@dataclass(frozen=True)
class Located:
    airborne_guided: bool
    """Armed, in the guided mode and above 80 % of the altitude: nothing to prepare."""


@dataclass(frozen=True)
class ControlBack:
    pass


@dataclass(frozen=True)
class Prepared:
    ok: bool
    """In the guided mode and armed (or arm accepted); False: retry."""
    takeoff: bool
    """The autopilot takes off by command and the vehicle is below half its altitude."""


@dataclass(frozen=True)
class TakeoffSent:
    accepted: bool


@dataclass(frozen=True)
class ClimbStopped:
    pass


@dataclass(frozen=True)
class Climbed:
    reached: bool
    """At 95 % of the altitude; False: the climb timed out."""


@dataclass(frozen=True)
class Retried:
    pass


@dataclass(frozen=True)
class SetpointsBegun:
    search_begun: bool
    """The search clock has started (this run, or before a restart: the log's search_start)."""
    start_point: bool
    """The profile has a start point to fly to first."""


@dataclass(frozen=True)
class TransitEnded:
    arrived: bool
    limit: float
    """The time the transit was given, vehicle s."""


@dataclass(frozen=True)
class SearchBegun:
    pass


@dataclass(frozen=True)
class SearchLeft:
    pass


@dataclass(frozen=True)
class Ending:
    armed: bool


@dataclass(frozen=True)
class EndRecorded:
    pass


@dataclass(frozen=True)
class Landed:
    pass


# -- requests at any time -------------------------------------------------------------------


@dataclass(frozen=True)
class EndRequested:
    """End the search (mission time, all targets, climb or transit time-out, a refusal)."""

    reason: str


@dataclass(frozen=True)
class OperatorEnd:
    """The operator ends the mission with ``action`` instead of the configured end action."""

    action: FlightMode
    reason: str


@dataclass(frozen=True)
class Signal:
    """SIGINT or SIGTERM."""


@dataclass(frozen=True)
class Battery:
    remaining: int
    """Per cent; -1 when the autopilot does not know."""
    minimum: float
    home: float | None = None
    """Per cent the flight home needs at the drain measured so far (battery_reserve.py); None:
    no reserve rule (a profile without a site), or not airborne yet."""
    reserve: float = 0.0
    """Per cent that must be left at landing, above ``home``."""


@dataclass(frozen=True)
class Gps:
    """A GPS position against the fence (geo-referenced profiles)."""

    breach: str | None
    """Where outside the fence it is; None inside."""


@dataclass(frozen=True)
class LinkLost:
    pass


Outcome = (
    Began | Connected | Located | ControlBack | Prepared | TakeoffSent | ClimbStopped | Climbed
    | Retried | SetpointsBegun | TransitEnded | SearchBegun | SearchLeft | Ending | EndRecorded
    | Landed
)  # fmt: skip
Request = EndRequested | OperatorEnd | Signal | Battery | Gps | LinkLost
