"""The profile's frame on a vehicle booted elsewhere: the link learns the vehicle's local origin
(GPS_GLOBAL_ORIGIN, else HOME_POSITION) from a vehicle over real UDP, holds local positions back
until then, shifts them in and position setpoints out by that one offset."""

from __future__ import annotations

import asyncio
import socket
from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from companion.guidance import NedSetpoint
from companion.link.local_frame import LocalFrame
from companion.link.messages import GlobalPosition, LocalPosition
from companion.link.pymavlink_link import PymavlinkLink
from companion.link.vehicle_frame import FrameAlignment

PROFILE = LocalFrame(47.396, 8.638, 440.0)
ORIGIN_NE = (1100.0, 1900.0)
"""Where the vehicle booted (its local origin), metres in the profile's frame."""


class _Vehicle(asyncio.DatagramProtocol):
    """Local position (10, 20) of its own frame; answers REQUEST_MESSAGE for its origin (or only
    for home, at local (x, y) = (3, 4)); records the setpoints it gets."""

    def __init__(self, *, global_origin: bool) -> None:
        self.mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
        self.global_origin = global_origin
        self.transport: asyncio.DatagramTransport | None = None
        self.peer: tuple[str, int] | None = None
        self.setpoints: list[Any] = []
        self.origin = PROFILE.to_geodetic(*ORIGIN_NE, 0.0)

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = transport  # type: ignore[assignment]

    def send(self, msg: Any) -> None:
        assert self.transport is not None
        assert self.peer is not None
        self.transport.sendto(msg.pack(self.mav), self.peer)

    def position(self, time_ms: int) -> None:
        self.send(self.mav.local_position_ned_encode(time_ms, 10.0, 20.0, -30.0, 1.0, 2.0, 0.0))
        lat, lon, _ = PROFILE.to_geodetic(ORIGIN_NE[0] + 10.0, ORIGIN_NE[1] + 20.0, 0.0)
        self.send(
            self.mav.global_position_int_encode(
                time_ms, round(lat * 1e7), round(lon * 1e7), 470_000, 30_000, 100, 200, 0, 0
            )
        )

    def datagram_received(self, data: bytes, addr: tuple[str | Any, int]) -> None:
        lat, lon, alt = self.origin
        for msg in self.mav.parse_buffer(data) or ():
            if msg.get_type() == "SET_POSITION_TARGET_LOCAL_NED":
                self.setpoints.append(msg)
            if msg.get_type() != "COMMAND_LONG":
                continue
            result = mavlink2.MAV_RESULT_UNSUPPORTED
            asked = round(msg.param1)
            if msg.command == mavlink2.MAV_CMD_REQUEST_MESSAGE:
                if asked == mavlink2.MAVLINK_MSG_ID_GPS_GLOBAL_ORIGIN and self.global_origin:
                    self.send(
                        self.mav.gps_global_origin_encode(
                            round(lat * 1e7), round(lon * 1e7), round(alt * 1e3)
                        )
                    )
                    result = mavlink2.MAV_RESULT_ACCEPTED
                elif asked == mavlink2.MAVLINK_MSG_ID_HOME_POSITION:
                    # home 3 m north, 4 m east of the local origin
                    hlat, hlon, _ = PROFILE.to_geodetic(ORIGIN_NE[0] + 3.0, ORIGIN_NE[1] + 4.0, 0)
                    self.send(
                        self.mav.home_position_encode(
                            round(hlat * 1e7),
                            round(hlon * 1e7),
                            round(alt * 1e3),
                            3.0,
                            4.0,
                            0.0,
                            [1.0, 0.0, 0.0, 0.0],
                            0.0,
                            0.0,
                            0.0,
                        )
                    )
                    result = mavlink2.MAV_RESULT_ACCEPTED
            self.send(self.mav.command_ack_encode(msg.command, result))


def _free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


async def _fly(global_origin: bool) -> tuple[list[Any], list[Any], _Vehicle, FrameAlignment]:
    port = _free_udp_port()
    link = PymavlinkLink(url=f"udpin:127.0.0.1:{port}", target_system=1, command_timeout=0.3)
    link.use_profile_frame(PROFILE)
    await link.open()
    vehicle = _Vehicle(global_origin=global_origin)
    await asyncio.get_running_loop().create_datagram_endpoint(
        lambda: vehicle, local_addr=("127.0.0.1", 0)
    )
    vehicle.peer = ("127.0.0.1", port)
    try:
        vehicle.position(1000)
        await asyncio.sleep(0.2)
        before = []
        while not link.events.empty():
            before.append(link.events.get_nowait())
        assert await link.learn_origin(wait=0.5) is None
        vehicle.position(1100)
        await asyncio.sleep(0.2)
        after = []
        while not link.events.empty():
            after.append(link.events.get_nowait())
        link.send_setpoint(
            NedSetpoint(ORIGIN_NE[0] + 100.0, ORIGIN_NE[1] - 50.0, -30.0, 0, 0, 0), "position"
        )
        await asyncio.sleep(0.2)
        assert link.alignment is not None
        return before, after, vehicle, link.alignment
    finally:
        await link.close()


@pytest.mark.parametrize("global_origin", [True, False], ids=["gps-global-origin", "home-only"])
def test_positions_and_setpoints_are_shifted_by_the_vehicles_origin(global_origin: bool) -> None:
    before, after, vehicle, alignment = asyncio.run(_fly(global_origin))
    # Local positions wait for the origin; the GPS position needs none (the fence watch).
    assert not [e for e in before if isinstance(e, LocalPosition)], before
    assert [e for e in before if isinstance(e, GlobalPosition)], before
    assert alignment.origin is not None
    source = "GPS_GLOBAL_ORIGIN" if global_origin else "HOME_POSITION"
    assert alignment.origin.source == source
    (local,) = [e for e in after if isinstance(e, LocalPosition)]
    # 1e-7 degree rounding of the origin: about 1 cm
    assert local.north == pytest.approx(ORIGIN_NE[0] + 10.0, abs=0.05)
    assert local.east == pytest.approx(ORIGIN_NE[1] + 20.0, abs=0.05)
    assert (local.down, local.vn, local.ve) == (-30.0, 1.0, 2.0)
    (gps,) = [e for e in after if isinstance(e, GlobalPosition)]
    assert (gps.north, gps.east) == pytest.approx((local.north, local.east), abs=0.05)
    assert gps.relative_alt == 30.0
    (sp,) = vehicle.setpoints
    assert (sp.x, sp.y, sp.z) == pytest.approx((100.0, -50.0, -30.0), abs=0.05)


def test_home_is_replaced_by_no_later_origin_once_aligned() -> None:
    a = FrameAlignment(PROFILE)
    lat, lon, _ = PROFILE.to_geodetic(500.0, 600.0, 0.0)
    a.from_home(lat, lon, 440.0, 3.0, 4.0)
    assert (a.north, a.east) == pytest.approx((497.0, 596.0), abs=0.01)
    a.from_home(lat, lon, 440.0, 0.0, 0.0)  # a later HOME_POSITION: the offset stays
    assert (a.north, a.east) == pytest.approx((497.0, 596.0), abs=0.01)
    assert a.to_vehicle(*a.to_profile(12.0, -7.0)) == pytest.approx((12.0, -7.0))
