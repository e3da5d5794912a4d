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
class NedSetpoint:
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
) -> NedSetpoint:
    """Velocity pointing at the (fenced) waypoint, slowed so one ``period`` never overshoots it.

    ``period`` is the vehicle time until the next setpoint; the look-ahead point
    position + v * period is kept inside the fence. (Two-vectors on floats: numpy's per-call
    overhead was most of the cost; np.hypot keeps the norms to the bit.)
    """
    return pursuit_xy(
        float(position[0]),
        float(position[1]),
        down,
        float(waypoint[0]),
        float(waypoint[1]),
        config,
        fence,
        period,
    )


def pursuit_xy(
    pn: float,
    pe: float,
    down: float,
    wn: float,
    we: float,
    config: GuidanceConfig,
    fence: Geofence,
    period: float,
) -> NedSetpoint:
    """:func:`pursuit` from the position (pn, pe) to the waypoint (wn, we), on floats."""
    tn, te = fence.clamp_xy(wn, we)
    on, oe = tn - pn, te - pe
    distance = float(np.hypot(on, oe))
    period = max(period, 1e-3)
    speed = min(config.speed, distance / period)
    vn, ve = (on / distance * speed, oe / distance * speed) if distance > 0 else (0.0, 0.0)
    ahead = (pn + vn * period, pe + ve * period)
    if not fence.contains(ahead):
        cn, ce = fence.clamp_xy(*ahead)
        vn, ve = (cn - pn) / period, (ce - pe) / period
        norm = float(np.hypot(vn, ve))
        if norm > config.speed:
            scale = config.speed / norm
            vn, ve = vn * scale, ve * scale
    target_down = -config.altitude
    vd = min(max(config.climb_gain * (target_down - down), -config.max_climb), config.max_climb)
    return NedSetpoint(tn, te, target_down, vn, ve, float(vd))
