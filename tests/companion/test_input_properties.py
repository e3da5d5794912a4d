"""Properties of the companion's input handling (hypothesis): whatever bytes of positions come
in, only finite, in-range positions of the autopilot's component on one consistent clock come
out of the link; whatever setpoint is asked for, only a finite one inside the envelope leaves;
and the setpoints guidance makes from valid positions always pass that last check."""

from __future__ import annotations

import math
import os

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from companion.geofence import Geofence
from companion.guidance import GuidanceConfig, NedSetpoint, pursuit_xy
from companion.link.local_frame import LocalFrame
from companion.link.messages import (
    GlobalPosition,
    LinkEvent,
    LocalPosition,
    SensorContact,
    SensorSignal,
)
from companion.link.pymavlink_link import PymavlinkLink
from companion.link.telemetry_guard import TelemetryLimits
from companion.mission.setpoint_guard import SetpointGuard

os.environ.setdefault("MAVLINK20", "1")
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

ANY_FLOAT = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True, width=32),
    st.sampled_from([1e38, -1e38, 0.0, 1e5]),
    st.floats(-3000.0, 3000.0, width=32),
)
SAMPLE = st.tuples(
    st.integers(0, 2**32 - 1),  # time_boot_ms
    st.sampled_from([1, 1, 1, 2, 190]),  # component
    ANY_FLOAT,
    ANY_FLOAT,
    ANY_FLOAT,
    ANY_FLOAT,
    ANY_FLOAT,
    ANY_FLOAT,
)
LIMITS = TelemetryLimits(max_speed=40.0, max_rate=15.0)
GUIDE = GuidanceConfig(speed=20.0, altitude=30.0, acceptance_radius=5.0)
FENCE = Geofence.rectangle(3000.0, 3000.0)


def _frame(sample: tuple[int, int, float, float, float, float, float, float]) -> bytes:
    t, component, *values = sample
    mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=component)
    return bytes(mav.local_position_ned_encode(t, *values).pack(mav))


@settings(max_examples=200, deadline=None)
@given(st.lists(SAMPLE, min_size=1, max_size=60))
def test_only_sane_positions_on_one_clock_leave_the_link(
    samples: list[tuple[int, int, float, float, float, float, float, float]],
) -> None:
    link = PymavlinkLink(url="udpin:127.0.0.1:1", target_system=1)
    link.guard.limits = LIMITS
    got: list[tuple[LocalPosition, int]] = []

    def listen(batch: list[LinkEvent]) -> None:
        got.extend((e, link.guard.new_tracks) for e in batch if isinstance(e, LocalPosition))

    link.listener = listen
    for sample in samples:  # the link's own receive path, on real MAVLink bytes
        link._receive(_frame(sample), ("127.0.0.1", 5))
        link._publish_pending()
    assert len(got) + sum(link.guard.dropped.values()) == len(samples)
    previous: LocalPosition | None = None
    tracks = 0
    for pos, new_tracks in got:
        values = (pos.time, pos.north, pos.east, pos.down, pos.vn, pos.ve, pos.vd)
        assert all(math.isfinite(v) for v in values), pos
        assert max(abs(pos.north), abs(pos.east)) <= LIMITS.max_distance
        assert -LIMITS.max_below <= -pos.down <= LIMITS.max_altitude
        assert max(abs(pos.vn), abs(pos.ve), abs(pos.vd)) <= LIMITS.max_speed
        if previous is not None and new_tracks == tracks:  # the same track: one clock, flyable
            assert pos.time >= previous.time
            reach = LIMITS.max_speed * (pos.time - previous.time) + LIMITS.jitter
            assert math.hypot(pos.north - previous.north, pos.east - previous.east) <= reach
        previous, tracks = pos, new_tracks


@settings(max_examples=200, deadline=None)
@given(
    st.lists(
        st.tuples(st.booleans(), st.integers(0, 2**32 - 1), ANY_FLOAT, ANY_FLOAT, ANY_FLOAT),
        min_size=1,
        max_size=20,
    )
)
def test_only_finite_sensor_readings_leave_the_link(
    readings: list[tuple[bool, int, float, float, float]],
) -> None:
    link = PymavlinkLink(url="udpin:127.0.0.1:1", target_system=1)
    got: list[LinkEvent] = []
    link.listener = got.extend
    mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    for contact, t, x, y, z in readings:
        msg = (
            mav.debug_vect_encode(b"DET", t, x, y, z)
            if contact
            else mav.named_value_float_encode(t, b"SENS_SIG", x)
        )
        link._receive(bytes(msg.pack(mav)), ("127.0.0.1", 5))
        link._publish_pending()
    assert len(got) + sum(link.guard.dropped.values()) == len(readings)
    for event in got:
        if isinstance(event, SensorContact):
            assert math.isfinite(event.time)
            assert all(math.isfinite(v) for v in (event.north, event.east, event.strength))
        else:
            assert isinstance(event, SensorSignal)
            assert math.isfinite(event.value)


INT32 = st.one_of(st.integers(-(2**31), 2**31 - 1), st.sampled_from([2**31 - 1, -(2**31), 0]))
ORIGIN = LocalFrame(47.397742, 8.545594, 488.0)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 2**32 - 1), INT32, INT32, INT32), min_size=1, max_size=30))
def test_only_gps_positions_on_earth_leave_the_link(
    samples: list[tuple[int, int, int, int]],
) -> None:
    """GLOBAL_POSITION_INT (read by geo-referenced profiles) at any int32 lat/lon/altitude."""
    link = PymavlinkLink(url="udpin:127.0.0.1:1", target_system=1)
    link.use_profile_frame(ORIGIN)
    assert link.alignment is not None
    link.alignment.from_global_origin(ORIGIN.lat, ORIGIN.lon, ORIGIN.alt)
    got: list[LinkEvent] = []
    link.listener = got.extend
    mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    for t, lat, lon, alt in samples:
        msg = mav.global_position_int_encode(t, lat, lon, alt, alt, 0, 0, 0, 0)
        link._receive(bytes(msg.pack(mav)), ("127.0.0.1", 5))
        link._publish_pending()
    outside = sum(
        (lat, lon) != (0, 0) and (abs(lat) > 900_000_000 or abs(lon) > 1_800_000_000)
        for _, lat, lon, _ in samples
    )
    assert link.guard.dropped["lat/lon out of range"] == outside
    for event in got:
        assert isinstance(event, GlobalPosition)
        assert -90.0 <= event.lat <= 90.0, event
        assert -180.0 <= event.lon <= 180.0, event
        assert max(abs(event.north), abs(event.east)) <= link.guard.limits.max_distance


@settings(max_examples=300, deadline=None)
@given(st.tuples(*([ANY_FLOAT] * 6)), st.sampled_from(["velocity", "position"]))
def test_no_setpoint_outside_the_envelope_is_sent(
    values: tuple[float, float, float, float, float, float], kind: str
) -> None:
    guard = SetpointGuard(GUIDE, FENCE, "velocity" if kind == "velocity" else "position", 2.5)
    safe, why = guard.safe(NedSetpoint(*values))
    assert guard.checked == 1
    if safe is None:
        assert kind == "position"  # no safe point known yet: nothing sent
        assert why is not None
        return
    assert all(
        math.isfinite(v) for v in (safe.north, safe.east, safe.down, safe.vn, safe.ve, safe.vd)
    )
    assert guard.cause(safe) is None
    assert (why is None) == (safe == NedSetpoint(*values))


FINITE = st.floats(-5000.0, 8000.0)


@settings(max_examples=300, deadline=None)
@given(FINITE, FINITE, st.floats(-200.0, 5.0), FINITE, FINITE, st.floats(0.001, 2.0))
def test_guidance_from_valid_positions_always_passes_the_check(
    pn: float, pe: float, down: float, wn: float, we: float, period: float
) -> None:
    sp = pursuit_xy(pn, pe, down, wn, we, GUIDE, FENCE, period)
    assert SetpointGuard(GUIDE, FENCE, "velocity", 2.5).cause(sp) is None, sp
    assert np.isfinite([sp.vn, sp.ve, sp.vd]).all()
