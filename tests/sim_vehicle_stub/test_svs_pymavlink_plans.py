"""pymavlink recipes (as the ArduPilot and PX4 docs give them) on both personas: a mission
uploaded item by item and flown in AUTO / AUTO.MISSION with MISSION_ITEM_REACHED in order and
DO_JUMP repeats; ArduPilot's REQUEST_DATA_STREAM groups; a pilot's RC_CHANNELS_OVERRIDE in
LOITER; the fence enforced with its SYS_STATUS bit."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import pytest

from tests.emulator_harness import Client, free_udp_base, make_config, running_emulator

STEP = 4_500
"""1e-7 degrees of latitude: about 50 m."""
TAKEOFF, WAYPOINT, JUMP, RTL = 22, 16, 177, 20


Item = tuple[int, int, float, float, int, int, float]


def _upload(c: Client, items: Sequence[Item]) -> Any:
    """(frame, command, p1, p2, lat, lon, z) items; the final MISSION_ACK."""
    c.conn.mav.mission_count_send(c.sysid, 1, len(items), 0)
    for _ in range(len(items) + 2):
        m = c.pump(
            3.0, lambda m: m.get_type() in ("MISSION_REQUEST", "MISSION_REQUEST_INT", "MISSION_ACK")
        )
        assert m is not None, "no answer during the upload"
        if m.get_type() == "MISSION_ACK":
            return m
        frame, cmd, p1, p2, lat, lon, z = items[m.seq]
        c.conn.mav.mission_item_int_send(
            c.sysid, 1, m.seq, frame, cmd, 0, 1, p1, p2, 0, 0, lat, lon, z, 0
        )
    raise AssertionError("the upload never ended")


def _kinds(c: Client, seconds: float) -> set[str]:
    seen: set[str] = set()

    def note(m: Any) -> bool:
        seen.add(m.get_type())
        return False

    c.pump(seconds, note)
    return seen


def _home(c: Client) -> tuple[int, int]:
    c.command(512, 242)
    home = c.pump(3.0, lambda m: m.get_type() == "HOME_POSITION")
    assert home is not None
    return int(home.latitude), int(home.longitude)


@pytest.mark.timeout(90)
@pytest.mark.parametrize("persona", ["ardupilot", "px4"])
def test_a_mission_with_a_jump_is_flown_in_order(persona: str) -> None:
    base = free_udp_base(1)
    with (
        running_emulator(make_config(1, base, personas=(persona,), speedup=20.0)) as emu,
        Client(base, 1) as c,
    ):
        assert c.pump(5.0, lambda m: m.get_type() == "HEARTBEAT") is not None
        lat, lon = _home(c)
        items = [
            (0, WAYPOINT, 0, 0, lat, lon, 0.0),
            (3, TAKEOFF, 0, 0, lat, lon, 10.0),
            (3, WAYPOINT, 0, 0, lat + STEP, lon, 10.0),
            (3, WAYPOINT, 0, 0, lat + STEP, lon + STEP, 10.0),
            (2, JUMP, 2, 1, 0, 0, 0.0),  # back to item 2, once
            (2, RTL, 0, 0, 0, 0, 0.0),
        ]
        assert _upload(c, items).type == 0
        if persona == "ardupilot":
            assert c.command(176, 1, 4) == 0  # GUIDED
            assert c.command(400, 1) == 0
            assert c.command(22, 0, 0, 0, 0, 0, 0, 5.0) == 0
            assert c.command(300, 0, 0) == 0  # MISSION_START: AUTO
        else:
            assert c.command(176, 1, 4, 4) == 0  # AUTO.MISSION
            assert c.command(400, 1) == 0
        reached: list[int] = []

        def landed(m: Any) -> bool:
            if m.get_type() == "MISSION_ITEM_REACHED" and (not reached or reached[-1] != m.seq):
                reached.append(int(m.seq))
            return m.get_type() == "HEARTBEAT" and not m.base_mode & 128 and len(reached) > 2

        assert c.pump(60.0, landed) is not None
        v = emu.vehicles[0]
        assert math.hypot(*(v.fleet.pos[0] - v.home)) < 1.0
    # ArduPilot's item 0 is home; PX4 flies it (a climb to its default takeoff altitude).
    first = [1, 2, 3, 2, 3] if persona == "ardupilot" else [0, 1, 2, 3, 2, 3]
    assert reached[: len(first)] == first


@pytest.mark.timeout(60)
def test_ardupilot_request_data_stream_groups_and_stop() -> None:
    base = free_udp_base(1)
    with (
        running_emulator(make_config(1, base, personas=("ardupilot",), speedup=5.0)),
        Client(base, 1) as c,
    ):
        assert c.pump(5.0, lambda m: m.get_type() == "HEARTBEAT") is not None
        c.conn.mav.request_data_stream_send(1, 1, 0, 4, 1)  # ALL at 4 Hz
        assert {"VFR_HUD", "RC_CHANNELS", "SERVO_OUTPUT_RAW", "MISSION_CURRENT"} <= _kinds(c, 2.0)
        c.conn.mav.request_data_stream_send(1, 1, 0, 0, 0)  # stop all
        c.pump(1.0)
        kinds = _kinds(c, 2.0)
        assert "HEARTBEAT" in kinds
        assert not kinds & {"GLOBAL_POSITION_INT", "VFR_HUD", "SYS_STATUS", "ATTITUDE"}


@pytest.mark.timeout(60)
def test_rc_override_flies_loiter_and_an_unknown_parameter_gets_no_answer() -> None:
    base = free_udp_base(1)
    with (
        running_emulator(make_config(1, base, personas=("ardupilot",), speedup=10.0)) as emu,
        Client(base, 1) as c,
    ):
        assert c.pump(5.0, lambda m: m.get_type() == "HEARTBEAT") is not None
        c.conn.mav.param_request_read_send(1, 1, b"NO_SUCH_PARAM", -1)
        assert c.pump(1.0, lambda m: m.get_type() == "PARAM_VALUE") is None
        assert c.command(176, 1, 4) == 0
        assert c.command(400, 1) == 0
        assert c.command(22, 0, 0, 0, 0, 0, 0, 10.0) == 0
        assert c.pump(
            20.0, lambda m: m.get_type() == "GLOBAL_POSITION_INT" and m.relative_alt > 9500
        )
        assert c.command(176, 1, 5) == 0  # LOITER
        v = emu.vehicles[0]
        start = v.fleet.pos[0].copy()
        # full pitch forward (channel 2 low), the rest centred
        c.stream(
            lambda: c.conn.mav.rc_channels_override_send(1, 1, 1500, 1000, 1500, 1500, 0, 0, 0, 0),
            1.0,
        )
        moved = v.fleet.pos[0] - start
        assert moved[0] > 30.0
        assert abs(moved[1]) < 1.0
        c.stream(
            lambda: c.conn.mav.rc_channels_override_send(1, 1, 1500, 1500, 1500, 1500, 0, 0, 0, 0),
            1.5,
        )
        here = v.fleet.pos[0].copy()
        c.pump(1.0)
        assert math.hypot(*(v.fleet.pos[0] - here)) < 0.5  # centred sticks: LOITER holds


@pytest.mark.timeout(60)
def test_an_uploaded_fence_is_enforced_and_reported_in_sys_status() -> None:
    base = free_udp_base(1)
    with (
        running_emulator(make_config(1, base, personas=("ardupilot",), speedup=10.0)) as emu,
        Client(base, 1) as c,
    ):
        assert c.pump(5.0, lambda m: m.get_type() == "HEARTBEAT") is not None
        lat, lon = _home(c)
        d = 900  # about 10 m: a 20 m square around home
        square = [
            (lat - d, lon - d * 1.5),
            (lat - d, lon + d * 1.5),
            (lat + d, lon + d * 1.5),
            (lat + d, lon - d * 1.5),
        ]
        c.conn.mav.mission_count_send(1, 1, 4, 1)
        for _ in range(6):
            m = c.pump(3.0, lambda m: m.get_type() in ("MISSION_REQUEST", "MISSION_ACK"))
            assert m is not None
            if m.get_type() == "MISSION_ACK":
                break
            a, b = square[m.seq]
            c.conn.mav.mission_item_int_send(
                1, 1, m.seq, 0, 5001, 0, 1, 4, 0, 0, 0, int(a), int(b), 0, 1
            )
        assert m.type == 0
        assert c.command(176, 1, 4) == 0
        assert c.command(400, 1) == 0
        assert c.command(22, 0, 0, 0, 0, 0, 0, 5.0) == 0
        assert c.pump(
            20.0, lambda m: m.get_type() == "GLOBAL_POSITION_INT" and m.relative_alt > 4700
        )
        c.stream_until(
            lambda: c.velocity(5.0, 0.0),
            lambda m: m.get_type() == "HEARTBEAT" and m.custom_mode == 6,  # RTL (FENCE_ACTION 1)
            20.0,
        )
        status = c.pump(2.0, lambda m: m.get_type() == "SYS_STATUS")
        assert status is not None
        assert status.onboard_control_sensors_present & 0x100000
        assert emu.vehicles[0].mode.name == "RTL"
        assert c.pump(30.0, lambda m: m.get_type() == "HEARTBEAT" and not m.base_mode & 128)


@pytest.mark.timeout(60)
@pytest.mark.parametrize("persona", ["ardupilot", "px4"])
def test_circle_and_do_orbit_fly_round_a_point(persona: str) -> None:
    base = free_udp_base(1)
    with (
        running_emulator(make_config(1, base, personas=(persona,), speedup=10.0)) as emu,
        Client(base, 1) as c,
    ):
        assert c.pump(5.0, lambda m: m.get_type() == "HEARTBEAT") is not None
        v = emu.vehicles[0]
        if persona == "ardupilot":
            assert c.command(176, 1, 4) == 0
            assert c.command(400, 1) == 0
            assert c.command(22, 0, 0, 0, 0, 0, 0, 10.0) == 0
        else:
            assert c.command(400, 1) == 0
            assert c.command(22, 0, 0, 0, 0, 0, 0, 488.0 + 10.0) == 0
        assert c.pump(
            20.0, lambda m: m.get_type() == "GLOBAL_POSITION_INT" and m.relative_alt > 9500
        )
        start = v.fleet.pos[0].copy()
        if persona == "ardupilot":
            assert c.command(176, 1, 7) == 0  # CIRCLE: CIRCLE_RADIUS 10 m ahead, 20 deg/s
        else:  # DO_ORBIT: 15 m radius, 3 m/s, about here
            nan = math.nan
            assert c.command(34, 15.0, 3.0, nan, nan, nan, nan, nan) == 0
        assert v.orbit is not None
        centre = (v.orbit.north, v.orbit.east)
        radius = v.orbit.radius
        distances = []
        for _ in range(30):
            c.pump(0.2)
            distances.append(math.dist(v.fleet.pos[0], centre))
        assert v.mode.name == ("CIRCLE" if persona == "ardupilot" else "ORBIT")
        moved = math.dist(v.fleet.pos[0], start)
        assert moved > 5.0  # it went round
        assert all(abs(r - radius) < 0.25 * radius for r in distances[10:]), distances
