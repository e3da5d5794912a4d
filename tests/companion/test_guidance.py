"""Pursuit guidance and the geofence: speed, no overshoot, every commanded point fenced."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from companion.geofence import Geofence
from companion.guidance import GuidanceConfig, pursuit, reached

CFG = GuidanceConfig(speed=20.0, altitude=40.0, acceptance_radius=5.0)
AREA = Geofence.rectangle(1000.0, 1000.0)


def test_pursuit_flies_at_profile_speed_towards_a_far_waypoint() -> None:
    sp = pursuit(np.array([100.0, 100.0]), -40.0, np.array([900.0, 100.0]), CFG, AREA, 0.1)
    assert np.hypot(sp.vn, sp.ve) == 20.0
    assert sp.vn > 0
    assert sp.ve == 0.0


def test_pursuit_slows_so_one_period_does_not_overshoot() -> None:
    sp = pursuit(np.array([100.0, 100.0]), -40.0, np.array([103.0, 100.0]), CFG, AREA, 0.5)
    assert np.isclose(sp.vn * 0.5, 3.0)


def test_pursuit_climbs_to_its_own_altitude() -> None:
    sp = pursuit(np.array([10.0, 10.0]), 0.0, np.array([10.0, 10.0]), CFG, AREA, 0.1)
    assert sp.vd < 0
    assert sp.down == -40.0
    assert sp.vn == 0
    assert sp.ve == 0


def test_waypoint_outside_fence_is_clamped_onto_it() -> None:
    sp = pursuit(np.array([500.0, 500.0]), -40.0, np.array([1500.0, 500.0]), CFG, AREA, 0.1)
    assert (sp.north, sp.east) == (1000.0, 500.0)


@settings(max_examples=200, deadline=None)
@given(
    st.floats(0, 1000),
    st.floats(0, 1000),
    st.floats(-3000, 3000),
    st.floats(-3000, 3000),
    st.floats(0.01, 2.0),
)
def test_look_ahead_point_stays_inside_fence(
    n: float, e: float, wn: float, we: float, period: float
) -> None:
    fence = Geofence(np.array([[0.0, 0.0], [1000.0, 0.0], [1000.0, 1000.0], [0.0, 600.0]]))
    pos = fence.clamp(np.array([n, e]))
    sp = pursuit(pos, -40.0, np.array([wn, we]), CFG, fence, period)
    ahead = pos + period * np.array([sp.vn, sp.ve])
    assert np.hypot(*(fence.clamp(ahead) - ahead)) < 1e-6  # inside, or on the boundary
    assert fence.contains(np.array([sp.north, sp.east]))
    assert np.hypot(sp.vn, sp.ve) <= CFG.speed + 1e-9


def test_reached_within_acceptance_radius_only() -> None:
    assert reached(np.array([0.0, 0.0]), np.array([3.0, 4.0]), 5.0)
    assert not reached(np.array([0.0, 0.0]), np.array([3.0, 4.1]), 5.0)


def test_geofence_rejects_degenerate_polygon() -> None:
    with pytest.raises(ValueError, match=">= 3"):
        Geofence(np.array([[0.0, 0.0], [1.0, 1.0]]))
