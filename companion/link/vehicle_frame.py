"""The profile's frame on a vehicle whose local frame starts wherever it booted.

A real autopilot's LOCAL_POSITION_NED is metres from its own origin (ArduPilot: the EKF
origin, set at the first GPS fix where it booted; PX4: its local position reference), not the
profile's origin. The vehicle says where that origin is: GPS_GLOBAL_ORIGIN names it directly;
HOME_POSITION gives home in WGS84 and in the local frame (x, y), so origin = home - (x, y).
Once either arrived, the link shifts positions in (vehicle -> profile) and position setpoints
out (profile -> vehicle) by one constant offset. Velocities need no conversion: both frames
are north-east-down. Vertical stays the vehicle's own (altitude above its origin, which the
profile's altitudes mean: "above home").

The two tangent planes differ by a rotation of (distance between origins) / (Earth radius):
1e-4 rad for origins 600 m apart, 0.2 m at the far end of a 2 km box, below GPS noise.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

from companion.link.local_frame import LocalFrame

log = logging.getLogger(__name__)
OWN = "own"
"""VehicleOrigin.source of a vehicle flown in its own frame (origin beyond the reach)."""


@dataclass(frozen=True)
class VehicleOrigin:
    """Where the vehicle's local frame starts, and how it was learnt."""

    lat: float
    lon: float
    alt: float
    source: str
    """'GPS_GLOBAL_ORIGIN' or 'HOME_POSITION'; 'own' when flown in its own frame."""


class FrameAlignment:
    """The offset of a vehicle's local origin in the profile's frame (None until known)."""

    def __init__(self, profile: LocalFrame, reach: float | None = None) -> None:
        self.profile = profile
        self.reach = reach
        """None: always shift (a geo-referenced profile). A distance (m): shift only an origin
        within it of the profile's; one farther away is the vehicle's own frame (no shift)."""
        self.origin: VehicleOrigin | None = None
        self.north = 0.0
        self.east = 0.0

    @property
    def ready(self) -> bool:
        return self.origin is not None

    def from_global_origin(self, lat: float, lon: float, alt: float) -> None:
        """GPS_GLOBAL_ORIGIN: the local frame's origin itself (preferred over home)."""
        if self.origin is not None and self.origin.source == "GPS_GLOBAL_ORIGIN":
            return
        self._set(VehicleOrigin(lat, lon, alt, "GPS_GLOBAL_ORIGIN"), 0.0, 0.0)

    def from_home(self, lat: float, lon: float, alt: float, x: float, y: float) -> None:
        """HOME_POSITION: home in WGS84 and at (x, y) in the local frame; used until (or
        unless) GPS_GLOBAL_ORIGIN arrives."""
        if self.origin is not None:
            return
        self._set(VehicleOrigin(lat, lon, alt, "HOME_POSITION"), x, y)

    def _set(self, origin: VehicleOrigin, x: float, y: float) -> None:
        n, e, _ = self.profile.to_local(origin.lat, origin.lon, origin.alt)
        if self.reach is not None and math.hypot(n - x, e - y) > self.reach:
            log.info(
                "vehicle frame: local origin %.1f km from the profile origin (from %s): flown "
                "in its own frame",
                math.hypot(n - x, e - y) / 1000.0,
                origin.source,
            )
            self.origin = VehicleOrigin(origin.lat, origin.lon, origin.alt, OWN)
            self.north = self.east = 0.0
            return
        self.origin = origin
        self.north, self.east = n - x, e - y
        log.info(
            "vehicle frame: local origin %.1f m north, %.1f m east of the profile origin (from %s)",
            self.north,
            self.east,
            origin.source,
        )

    def to_profile(self, north: float, east: float) -> tuple[float, float]:
        return north + self.north, east + self.east

    def to_vehicle(self, north: float, east: float) -> tuple[float, float]:
        return north - self.north, east - self.east
