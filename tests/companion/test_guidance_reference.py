"""Pursuit guidance on floats gives the array form's setpoints, to the bit."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from companion.geofence import Geofence
from companion.guidance import GuidanceConfig, NedSetpoint, pursuit

CFG = GuidanceConfig(speed=20.0, altitude=40.0, acceptance_radius=5.0)
FENCES = [
    Geofence.rectangle(1000.0, 1000.0),
    Geofence(np.array([[0.0, 0.0], [1000.0, 0.0], [1000.0, 1000.0], [0.0, 600.0]])),
]


def _reference(
    position: np.ndarray, down: float, waypoint: np.ndarray, fence: Geofence, period: float
) -> NedSetpoint:
    """The numpy form pursuit had before (vectors as arrays)."""
    target = fence.clamp(np.asarray(waypoint, dtype=float))
    offset = target - position
    distance = float(np.hypot(offset[0], offset[1]))
    period = max(period, 1e-3)
    speed = min(CFG.speed, distance / period)
    velocity = offset / distance * speed if distance > 0 else np.zeros(2)
    ahead = position + velocity * period
    if not fence.contains(ahead):
        velocity = (fence.clamp(ahead) - position) / period
        norm = float(np.hypot(velocity[0], velocity[1]))
        if norm > CFG.speed:
            velocity *= CFG.speed / norm
    target_down = -CFG.altitude
    vd = float(np.clip(CFG.climb_gain * (target_down - down), -CFG.max_climb, CFG.max_climb))
    return NedSetpoint(
        float(target[0]), float(target[1]), target_down, float(velocity[0]), float(velocity[1]), vd
    )


@settings(max_examples=500, deadline=None)
@given(
    st.sampled_from(range(len(FENCES))),
    st.floats(-100, 1100), st.floats(-100, 1100),
    st.floats(-1500, 2500), st.floats(-1500, 2500),
    st.floats(-80, 5), st.floats(0.0, 2.0), st.booleans(),
)  # fmt: skip
def test_pursuit_matches_the_array_form(
    fence: int, n: float, e: float, wn: float, we: float, down: float, period: float, near: bool
) -> None:
    position = np.array([n, e])
    waypoint = position + np.array([wn, we]) * 1e-3 if near else np.array([wn, we])
    got = pursuit(position, down, waypoint, CFG, FENCES[fence], period)
    assert got == _reference(position, down, waypoint, FENCES[fence], period)
