"""The site fence and the search area against the vehicle's GPS position (GLOBAL_POSITION_INT,
converted to the profile's frame by the link from lat/lon alone): a check that does not trust
the local frame the setpoints are computed in, so a wrong frame shows as a breach."""

from __future__ import annotations

import math
from dataclasses import dataclass

from companion.geofence import Geofence

_POINTS = ("north", "north-east", "east", "south-east", "south", "south-west", "west",
           "north-west")  # fmt: skip


def compass(dn: float, de: float) -> str:
    """The eight-point compass direction of the vector (north, east)."""
    bearing = math.degrees(math.atan2(de, dn)) % 360.0
    return _POINTS[round(bearing / 45.0) % 8]


@dataclass(frozen=True)
class FenceWatch:
    """The profile's fence (WGS84 vertices in the profile's frame) and search area."""

    fence: Geofence
    area: Geofence
    start_margin: float
    """A vehicle farther than this outside the search area is not started, metres."""

    def start_refusal(self, north: float, east: float) -> str | None:
        """Why a vehicle at (north, east) must not start, or None."""
        if self.area.contains((north, east)):
            return None
        d = self.area.distance(north, east)
        if d <= self.start_margin:
            return None
        n, e = self.area.nearest(north, east)
        return (
            f"{d:.0f} m {compass(north - n, east - e)} of the search area (allowed: "
            f"{self.start_margin:g} m outside it)"
        )

    def breach(self, north: float, east: float) -> str | None:
        """How far outside the fence (north, east) is, or None inside."""
        if self.fence.contains((north, east)):
            return None
        n, e = self.fence.nearest(north, east)
        d = math.hypot(north - n, east - e)
        return f"{d:.1f} m {compass(north - n, east - e)} of the fence"
