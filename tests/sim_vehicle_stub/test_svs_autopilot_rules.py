"""Rules the real autopilots keep and the emulator must keep too: no motion
while disarmed, recovery after a disarm in the air, speed and altitude limits, one AMSL
convention, mission acks, DO_REPOSITION, acceleration and yaw-rate targets."""

from __future__ import annotations

import itertools
import math
from typing import Any

import numpy as np
import pytest

from tests.emulator_harness import Client, free_udp_base, make_config, running_emulator

ORIGIN_ALT = 488.0
"""paper-fixed's origin altitude, m AMSL (every home's)."""
PX4_OFFBOARD = 0x60000
ARM, DISARM, FORCE = 1.0, 0.0, 21196.0
TAKEOFF, CHANGE_SPEED, DO_SET_MODE, REPOSITION, COMPONENT_ARM = 22, 178, 176, 192, 400
ACCEPTED, DENIED, FAILED = 0, 2, 4


def _alt(c: Client) -> float:
    msg = c.pump(2.0, lambda m: m.get_type() == "GLOBAL_POSITION_INT")
    assert msg is not None
    return float(msg.relative_alt) / 1000.0


def _high(alt: float) -> Any:
    return lambda m: m.get_type() == "GLOBAL_POSITION_INT" and m.relative_alt >= alt * 1000


def _low(alt: float) -> Any:
    return lambda m: m.get_type() == "GLOBAL_POSITION_INT" and m.relative_alt <= alt * 1000


@pytest.mark.timeout(60)
def test_px4_offboard_before_arming_stays_on_the_ground_and_flies_once_armed() -> None:
    base = free_udp_base(1)
    with running_emulator(make_config(1, base)) as emu, Client(base, 1) as c:
        climb = lambda: c.velocity(0.0, 0.0, -2.0)  # noqa: E731
        c.stream(climb, 0.5)
        assert c.command(DO_SET_MODE, 1, 6, 0) == ACCEPTED  # OFFBOARD while disarmed
        c.stream(climb, 1.5)
        assert not emu.vehicles[0].armed
        assert emu.fleet.alt[0] == 0.0
        assert _alt(c) == 0.0
        assert c.command(COMPONENT_ARM, ARM) == ACCEPTED
        assert c.stream_until(climb, _high(3.0), 10.0) is not None


@pytest.mark.timeout(60)
def test_px4_disarmed_in_the_air_comes_down_and_can_be_armed_again() -> None:
    base = free_udp_base(1)
    with running_emulator(make_config(1, base)) as emu, Client(base, 1) as c:
        assert c.command(COMPONENT_ARM, ARM) == ACCEPTED
        assert c.command(TAKEOFF, *[math.nan] * 6, ORIGIN_ALT + 10.0) == ACCEPTED
        assert c.pump(15.0, _high(5.0)) is not None
        assert c.command(COMPONENT_ARM, DISARM, FORCE) == ACCEPTED
        assert c.pump(20.0, _low(0.05)) is not None
        assert not emu.vehicles[0].armed
        assert emu.vehicles[0].landed
        assert c.command(COMPONENT_ARM, ARM) == ACCEPTED


@pytest.mark.timeout(60)
def test_change_speed_is_capped_at_what_the_persona_flies_and_nonsense_is_denied() -> None:
    base = free_udp_base(2)
    cfg = make_config(2, base, personas=("ardupilot", "px4"))
    with running_emulator(cfg) as emu, Client(base, 1) as ap, Client(base + 1, 2) as px4:
        for c in (ap, px4):
            assert c.command(CHANGE_SPEED, 1, 1e38, -1) == ACCEPTED
            assert c.command(CHANGE_SPEED, 1, math.nan, -1) == DENIED
            assert c.command(CHANGE_SPEED, 1, -3.0, -1) == DENIED
            assert c.command(CHANGE_SPEED, 7, 5.0, -1) == DENIED
        assert emu.fleet.speed[0] == 20.0  # the top of ArduCopter's WPNAV_SPEED range
        assert emu.fleet.speed[1] == emu.vehicles[1].params.get("MPC_XY_VEL_MAX")
        # ArduCopter refuses a takeoff beyond what its Location holds, with FAILED.
        assert ap.command(DO_SET_MODE, 1, 4, 0) == ACCEPTED
        assert ap.command(COMPONENT_ARM, ARM) == ACCEPTED
        assert ap.command(TAKEOFF, 0, 0, 0, 0, 0, 0, 1e9) == FAILED
        assert emu.vehicles[0].takeoff_alt is None


@pytest.mark.timeout(60)
def test_one_amsl_convention_reported_and_commanded_and_px4_takes_mavproxy_takeoff() -> None:
    base = free_udp_base(2)
    # 11 km apart: the tangent plane drops 9.5 m below the ellipsoid there.
    cfg = make_config(2, base, start_positions=((1000.0, 1000.0), (12000.0, 1000.0)))
    with running_emulator(cfg), Client(base, 1) as near, Client(base + 1, 2) as far:
        homes = []
        for c in (near, far):
            c.heartbeat()
            assert c.command(512, 242) == ACCEPTED
            home = c.last.get("HOME_POSITION") or c.pump(
                3.0, lambda m: m.get_type() == "HOME_POSITION"
            )
            assert home is not None
            homes.append(home.altitude / 1000.0)
        assert homes == [pytest.approx(ORIGIN_ALT, abs=0.001)] * 2
        # A takeoff to HOME_POSITION.altitude + 20 ends 20 m up, and GLOBAL_POSITION_INT.alt
        # is home's altitude plus relative_alt.
        assert far.command(COMPONENT_ARM, ARM) == ACCEPTED
        assert far.command(TAKEOFF, *[math.nan] * 6, homes[1] + 20.0) == ACCEPTED
        top = far.pump(20.0, _high(19.7))
        assert top is not None
        settled = far.pump(3.0, lambda m: False) or far.last["GLOBAL_POSITION_INT"]
        assert settled.relative_alt / 1000.0 == pytest.approx(20.0, abs=0.3)
        assert settled.alt / 1000.0 == pytest.approx(
            ORIGIN_ALT + settled.relative_alt / 1000, abs=0.01
        )
        # MAVProxy's `takeoff 20` sends 20 m, below home AMSL: PX4 climbs to MIS_TAKEOFF_ALT.
        assert near.command(COMPONENT_ARM, ARM) == ACCEPTED
        assert near.command(TAKEOFF, 0, 0, 0, 0, 0, 0, 20.0) == ACCEPTED
        assert near.pump(15.0, _high(2.2)) is not None


@pytest.mark.timeout(60)
def test_mission_count_asks_for_items_and_clear_all_is_acknowledged() -> None:
    base = free_udp_base(1)
    with running_emulator(make_config(1, base)), Client(base, 1) as c:
        assert c.pump(5.0, lambda m: m.get_type() == "HEARTBEAT") is not None  # learn its port
        c.conn.mav.mission_count_send(1, 1, 0, 0)
        ack = c.pump(2.0, lambda m: m.get_type() == "MISSION_ACK")
        assert ack is not None
        assert (ack.type, ack.target_system) == (0, 245)  # an empty upload: ACCEPTED at once
        c.conn.mav.mission_count_send(1, 1, 3, 0)
        # PX4 after boot asks with the legacy MISSION_REQUEST (measured on PX4 SITL).
        ask = c.pump(2.0, lambda m: m.get_type() in ("MISSION_REQUEST", "MISSION_REQUEST_INT"))
        assert ask is not None
        assert (ask.get_type(), ask.seq, ask.target_system) == ("MISSION_REQUEST", 0, 245)
        c.conn.mav.mission_clear_all_send(1, 1, 0)
        ack = c.pump(2.0, lambda m: m.get_type() == "MISSION_ACK")
        assert ack is not None
        assert (ack.type, ack.target_system) == (0, 245)


@pytest.mark.timeout(60)
@pytest.mark.parametrize(("persona", "mode"), [("ardupilot", "GUIDED"), ("px4", "HOLD")])
def test_do_reposition_flies_to_the_point_as_mavproxy_guided_asks(persona: str, mode: str) -> None:
    base = free_udp_base(1)
    with running_emulator(make_config(1, base, personas=(persona,))) as emu, Client(base, 1) as c:
        v = emu.vehicles[0]
        if persona == "ardupilot":
            assert c.command(DO_SET_MODE, 1, 4, 0) == ACCEPTED
        assert c.command(COMPONENT_ARM, ARM) == ACCEPTED
        alt = 12.0 if persona == "ardupilot" else ORIGIN_ALT + 12.0
        assert c.command(TAKEOFF, 0, 0, 0, 0, 0, 0, alt) == ACCEPTED
        assert c.pump(20.0, _high(11.7)) is not None
        lat, lon, _ = emu.geo.to_geodetic(
            *(np.array([x]) for x in (1100.0, 1000.0, 0.0))
        )  # 100 m north
        c.conn.mav.command_int_send(
            1,
            1,
            6,
            REPOSITION,
            0,
            0,
            -1,
            1,
            0,
            math.nan,
            int(float(lat[0]) * 1e7),
            int(float(lon[0]) * 1e7),
            15.0,
        )
        ack = c.pump(3.0, lambda m: m.get_type() == "COMMAND_ACK" and m.command == REPOSITION)
        assert ack is not None
        assert ack.result == ACCEPTED
        assert v.mode.name == mode
        there = c.pump(
            20.0,
            lambda m: (
                m.get_type() == "LOCAL_POSITION_NED" and abs(m.x - 100.0) < 1.0
            ),  # from its boot point
        )
        assert there is not None
        assert c.pump(10.0, _high(14.7)) is not None


@pytest.mark.timeout(60)
def test_acceleration_targets_and_yaw_rate_are_followed_not_dropped() -> None:
    base = free_udp_base(1)
    with (
        running_emulator(make_config(1, base, personas=("ardupilot",))) as emu,
        Client(base, 1) as c,
    ):
        assert c.command(DO_SET_MODE, 1, 4, 0) == ACCEPTED
        assert c.command(COMPONENT_ARM, ARM) == ACCEPTED
        assert c.command(TAKEOFF, 0, 0, 0, 0, 0, 0, 10.0) == ACCEPTED
        assert c.pump(20.0, _high(9.7)) is not None
        # type_mask 3135: use afx, afy, afz only (+ ignore yaw, yaw rate); 1 m/s^2 east.
        accel = lambda: c.conn.mav.set_position_target_local_ned_send(  # noqa: E731
            0, 1, 1, 1, 3135, 0, 0, 0, 0, 0, 0, 0.0, 1.0, 0.0, 0, 0
        )
        fast = c.stream_until(
            accel, lambda m: m.get_type() == "LOCAL_POSITION_NED" and m.vy > 3.0, 15.0
        )
        assert fast is not None
        assert abs(fast.vx) < 0.1
        # type_mask 1479: velocity zero, yaw ignored, yaw rate 0.5 rad/s used.
        yaws: list[float] = []

        def spin_and_watch() -> None:
            c.conn.mav.set_position_target_local_ned_send(
                0, 1, 1, 1, 1479, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0.5
            )
            yaws.append(float(emu.fleet.yaw[0]))

        c.stream(spin_and_watch, 2.0)
        turned = sum(math.remainder(b - a, 2 * math.pi) for a, b in itertools.pairwise(yaws))
        assert turned > 0.3


@pytest.mark.timeout(60)
def test_attitude_targets_lean_the_vehicle_and_thrust_sets_the_climb() -> None:
    base = free_udp_base(1)
    cfg = make_config(1, base, personas=("ardupilot",))
    with running_emulator(cfg) as emu, Client(base, 1) as c:
        assert c.command(DO_SET_MODE, 1, 4, 0) == ACCEPTED
        assert c.command(COMPONENT_ARM, ARM) == ACCEPTED
        assert c.command(TAKEOFF, 0, 0, 0, 0, 0, 0, 10.0) == ACCEPTED
        assert c.pump(20.0, _high(9.7)) is not None
        half = math.radians(-10.0) / 2  # 10 degrees nose down, heading north
        q = [math.cos(half), 0.0, math.sin(half), 0.0]

        def lean() -> None:
            c.conn.mav.set_attitude_target_send(0, 1, 1, 7, q, 0, 0, 0, 0.7)

        fast = c.stream_until(
            lean, lambda m: m.get_type() == "LOCAL_POSITION_NED" and m.vx > 4.0, 15.0
        )
        assert fast is not None
        assert abs(fast.vy) < 0.1
        assert fast.vz < -0.5  # thrust 0.7: climbing
        # A quaternion that is not unit length stops the vehicle where it is.
        bad = [1.0, 0.5, 0.0, 0.0]

        def bad_lean() -> None:
            c.conn.mav.set_attitude_target_send(0, 1, 1, 7, bad, 0, 0, 0, 0.7)

        stopped = c.stream_until(
            bad_lean, lambda m: m.get_type() == "LOCAL_POSITION_NED" and abs(m.vx) < 0.05, 15.0
        )
        assert stopped is not None
        assert emu.vehicles[0].mode.name == "GUIDED"
