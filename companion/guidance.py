"""Waypoint -> setpoint: pursuit guidance at the profile's speed, altitude hold, geofence."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from companion.geofence import Geofence

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class GuidanceConfig:
    """How a vehicle flies towards its waypoint."""

    speed: float
    """Horizontal speed ||V_U||, m/s."""
    altitude: float
    """This vehicle's altitude above home, m (Assumption III: each vehicle its own)."""
    acceptance_radius: float
    """A waypoint counts as reached within this horizontal distance, m."""
    climb_gain: float = 1.0
    """Vertical velocity per metre of altitude error, 1/s."""
    max_climb: float = 5.0
    """Largest vertical speed commanded, m/s."""


@dataclass(frozen=True)
class Setpoint:
    """One setpoint in the local NED frame; velocity and the point it steers to."""

    north: float
    east: float
    down: float
    vn: float
    ve: float
    vd: float


def reached(position: FloatArray, waypoint: FloatArray, radius: float) -> bool:
    """True when the horizontal distance to the waypoint is within ``radius``."""
    return math.hypot(position[0] - waypoint[0], position[1] - waypoint[1]) <= radius


def pursuit(
    position: FloatArray,
    down: float,
    waypoint: FloatArray,
    config: GuidanceConfig,
    fence: Geofence,
    period: float,
) -> Setpoint:
    """Velocity pointing at the (fenced) waypoint, slowed so one ``period`` never overshoots it.

    ``period`` is the vehicle time until the next setpoint; the look-ahead point
    position + v * period is kept inside the fence.
    """
    target = fence.clamp(np.asarray(waypoint, dtype=float))
    offset = target - position
    distance = float(np.hypot(offset[0], offset[1]))
    period = max(period, 1e-3)
    speed = min(config.speed, distance / period)
    velocity = offset / distance * speed if distance > 0 else np.zeros(2)
    ahead = position + velocity * period
    if not fence.contains(ahead):
        velocity = (fence.clamp(ahead) - position) / period
        norm = float(np.hypot(velocity[0], velocity[1]))
        if norm > config.speed:
            velocity *= config.speed / norm
    target_down = -config.altitude
    vd = float(
        np.clip(config.climb_gain * (target_down - down), -config.max_climb, config.max_climb)
    )
    return Setpoint(
        float(target[0]), float(target[1]), target_down, float(velocity[0]), float(velocity[1]), vd
    )
