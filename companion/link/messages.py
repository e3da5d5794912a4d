"""What a link reports about its vehicle, the same for every backend (frames: local NED, metres).

``time`` is always vehicle time in seconds (MAVLink time_boot_ms / time_usec), never wall time.
``received`` is the host's perf_counter when the message arrived, for latency measurement only.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class Heartbeat:
    """A HEARTBEAT from the vehicle's autopilot component."""

    autopilot: int
    custom_mode: int
    armed: bool
    system_status: int


@dataclass(frozen=True, slots=True)
class LocalPosition:
    """Position and velocity in the local NED frame (origin = the profile origin)."""

    time: float
    north: float
    east: float
    down: float
    vn: float
    ve: float
    vd: float
    received: float


@dataclass(frozen=True, slots=True)
class GlobalPosition:
    """GLOBAL_POSITION_INT (the GPS position, independent of any local frame), with the same
    point in the profile's frame (north, east: converted by the link from lat/lon, never from
    the vehicle's local position)."""

    time: float
    lat: float
    lon: float
    relative_alt: float
    """Metres above home."""
    north: float
    east: float


@dataclass(frozen=True, slots=True)
class SystemStatus:
    """Health and battery (SYS_STATUS)."""

    battery_remaining: int
    """Percent, -1 when the vehicle does not know."""
    healthy: bool
    """Every present and enabled sensor reports healthy (incl. GPS and the pre-arm check)."""


@dataclass(frozen=True, slots=True)
class SensorContact:
    """One contact of a sensor: DEBUG_VECT 'DET' (detection) or 'CNF' (confirmation)."""

    kind: str
    time: float
    north: float
    east: float
    strength: float


@dataclass(frozen=True, slots=True)
class SensorSignal:
    """The strongest signal of the active sensor (NAMED_VALUE_FLOAT 'SENS_SIG')."""

    time: float
    value: float


@dataclass(frozen=True, slots=True)
class StatusText:
    """A STATUSTEXT of the vehicle (arming refusals, failsafes, mode changes in its own words)."""

    severity: int
    """MAV_SEVERITY: 0 emergency .. 7 debug."""
    text: str


@dataclass(frozen=True, slots=True)
class StraySource:
    """Messages with the vehicle's system id from another address than the one the link locked
    to (reported once per address; they are dropped)."""

    address: str
    locked: str


LinkEvent = (
    Heartbeat | LocalPosition | GlobalPosition | SystemStatus | SensorContact | SensorSignal | StatusText
    | StraySource
)  # fmt: skip
