"""The pymavlink link turns off every stream the mission does not read (SET_MESSAGE_INTERVAL -1)."""

from __future__ import annotations

import asyncio
import socket
from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from companion.link.pymavlink_link import PymavlinkLink

_UNREAD = {30, 2, 24, 147, 242, 245}  # ATTITUDE, SYSTEM_TIME, GPS_RAW_INT, BATTERY, HOME, EXT_STATE
_GPI = 33


class _Vehicle(asyncio.DatagramProtocol):
    """Answers every COMMAND_LONG 511 with ACCEPTED and notes what was switched off."""

    def __init__(self) -> None:
        self.mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
        self.mav.robust_parsing = True
        self.off: set[int] = set()
        self.transport: asyncio.DatagramTransport | None = None

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = transport  # type: ignore[assignment]

    def datagram_received(self, data: bytes, addr: tuple[str | Any, int]) -> None:
        for msg in self.mav.parse_buffer(data) or ():
            if msg.get_type() == "COMMAND_LONG" and msg.command == 511:
                if msg.param2 == -1.0:
                    self.off.add(round(msg.param1))
                ack = self.mav.command_ack_encode(511, 0)
                assert self.transport is not None
                self.transport.sendto(ack.pack(self.mav), addr)


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.mark.asyncio
async def test_unread_streams_are_switched_off() -> None:
    port = _free_port()
    loop = asyncio.get_running_loop()
    link = PymavlinkLink(url=f"udpin:127.0.0.1:{port}", target_system=1, command_timeout=0.5)
    await link.open()
    vehicle = _Vehicle()
    transport, _ = await loop.create_datagram_endpoint(lambda: vehicle, local_addr=("127.0.0.1", 0))
    try:
        hb = vehicle.mav.heartbeat_encode(2, 12, 0, 0, 3)
        transport.sendto(hb.pack(vehicle.mav), ("127.0.0.1", port))  # the vehicle speaks first
        await asyncio.sleep(0.05)
        await asyncio.wait_for(link.configure_streams(), 10.0)
    finally:
        transport.close()
        await link.close()
    assert vehicle.off == _UNREAD | {_GPI}
