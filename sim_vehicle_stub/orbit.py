"""Circling a point: ArduCopter's CIRCLE mode and PX4's DO_ORBIT (its ORBIT mode).

The vehicle pursues a point that runs round the circle at the commanded speed; the tau-lag
loop does the rest. ArduCopter's CIRCLE centres the circle CIRCLE_RADIUS ahead of the vehicle
and turns at CIRCLE_RATE (deg/s, positive clockwise); PX4's DO_ORBIT takes the radius (param1,
negative counter-clockwise), the tangential speed (param2) and the centre (param5/6, NaN: here).
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass
class Orbit:
    """A circle in the profile's frame and where on it the pursued point is."""

    north: float
    east: float
    radius: float
    rate: float
    """rad/s, positive clockwise seen from above (north towards east)."""
    angle: float
    """Of the pursued point about the centre, from north towards east, rad."""

    def advance(self, dt: float) -> tuple[float, float]:
        """The pursued point ``dt`` s later."""
        self.angle = (self.angle + self.rate * dt) % (2 * math.pi)
        return (
            self.north + self.radius * math.cos(self.angle),
            self.east + self.radius * math.sin(self.angle),
        )


def circle_ahead(north: float, east: float, yaw: float, radius: float, rate_deg: float) -> Orbit:
    """ArduCopter CIRCLE: centre ``radius`` m ahead, starting where the vehicle is."""
    cn, ce = north + radius * math.cos(yaw), east + radius * math.sin(yaw)
    return Orbit(cn, ce, radius, math.radians(rate_deg), yaw + math.pi)


def orbit_about(
    north: float, east: float, here: tuple[float, float], radius: float, speed: float
) -> Orbit:
    """PX4 DO_ORBIT about (north, east), entered at the nearest point of the circle."""
    r = abs(radius)
    direction = 1.0 if radius >= 0 else -1.0
    angle = math.atan2(here[1] - east, here[0] - north)
    return Orbit(north, east, r, direction * abs(speed) / max(r, 1.0), angle)
