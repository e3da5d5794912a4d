"""What the pymavlink link does with a vehicle that behaves like a stock ArduCopter, over real UDP:
it asks for the streams it needs and names one that never comes, switches nothing off, locks to
the first sender of the vehicle's id, shows the vehicle's reason for a refusal, never loops on a
parameter the vehicle does not have, and says whom it heard while waiting for its vehicle."""

from __future__ import annotations

import asyncio
import logging
import socket
from collections import Counter
from pathlib import Path
from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from companion.link.messages import Heartbeat, StraySource
from companion.link.outcome import Outcome
from companion.link.pymavlink_link import PymavlinkLink
from companion.link.streams import needs
from companion.mission import MissionConfig, VehicleMission
from mdm_profiles import load_profile

_ARM_REFUSAL = "Arm: Throttle (RC3) is not neutral"


class _StockCopter(asyncio.DatagramProtocol):
    """Streams nothing until asked; SET_MESSAGE_INTERVAL starts LOCAL_POSITION_NED (SYS_STATUS
    it never sends); arming is refused with a STATUSTEXT first; no MDM_SENSOR parameter."""

    def __init__(self, system: int = 1, custom_mode: int = 0) -> None:
        self.mav = mavlink2.MAVLink(None, srcSystem=system, srcComponent=1)
        self.mav.robust_parsing = True
        self.custom_mode = custom_mode
        self.received: Counter[str] = Counter()
        self.intervals: dict[int, float] = {}
        self.transport: asyncio.DatagramTransport | None = None
        self.peer: tuple[str, int] | None = None
        self.time_ms = 0

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = transport  # type: ignore[assignment]

    def send(self, msg: Any) -> None:
        assert self.transport is not None
        assert self.peer is not None
        self.transport.sendto(msg.pack(self.mav), self.peer)

    def heartbeat(self) -> None:
        self.send(
            self.mav.heartbeat_encode(
                mavlink2.MAV_TYPE_QUADROTOR,
                mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA,
                mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
                self.custom_mode,
                mavlink2.MAV_STATE_STANDBY,
            )
        )

    def tick(self) -> None:
        """10 ms of vehicle time: the position if it was asked for."""
        self.time_ms += 10
        interval = self.intervals.get(mavlink2.MAVLINK_MSG_ID_LOCAL_POSITION_NED)
        if interval and self.time_ms % round(interval / 1000) == 0:
            self.send(self.mav.local_position_ned_encode(self.time_ms, 0, 0, 0, 0, 0, 0))

    def datagram_received(self, data: bytes, addr: tuple[str | Any, int]) -> None:
        for msg in self.mav.parse_buffer(data) or ():
            kind = msg.get_type()
            self.received[kind] += 1
            if kind != "COMMAND_LONG":
                continue
            if msg.command == mavlink2.MAV_CMD_SET_MESSAGE_INTERVAL:
                self.intervals[round(msg.param1)] = msg.param2
                result = mavlink2.MAV_RESULT_ACCEPTED
            elif msg.command == mavlink2.MAV_CMD_COMPONENT_ARM_DISARM:
                self.send(
                    self.mav.statustext_encode(
                        mavlink2.MAV_SEVERITY_CRITICAL, _ARM_REFUSAL.encode()
                    )
                )
                result = mavlink2.MAV_RESULT_FAILED
            else:
                result = mavlink2.MAV_RESULT_UNSUPPORTED
            self.send(self.mav.command_ack_encode(msg.command, result))


def _free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


async def _vehicle(port: int, **options: Any) -> _StockCopter:
    vehicle = _StockCopter(**options)
    await asyncio.get_running_loop().create_datagram_endpoint(
        lambda: vehicle, local_addr=("127.0.0.1", 0)
    )
    vehicle.peer = ("127.0.0.1", port)
    return vehicle


async def _run_vehicle(vehicle: _StockCopter) -> None:
    while True:
        if vehicle.time_ms % 1000 == 0:
            vehicle.heartbeat()
        vehicle.tick()
        await asyncio.sleep(0.01)


def test_missing_streams_are_asked_for_and_one_never_sent_is_named() -> None:
    port = _free_udp_port()

    async def main() -> tuple[list[str], _StockCopter, float | None]:
        link = PymavlinkLink(url=f"udpin:127.0.0.1:{port}", target_system=1, command_timeout=0.3)
        await link.open()
        vehicle = await _vehicle(port)
        runner = asyncio.create_task(_run_vehicle(vehicle))
        try:
            problems = await link.request_streams(needs(global_position=False), wait=1.0)
            return problems, vehicle, link.streams.rate("LOCAL_POSITION_NED")
        finally:
            runner.cancel()
            vehicle.transport.close()  # type: ignore[union-attr]
            await link.close()

    problems, vehicle, rate = asyncio.run(main())
    asked = vehicle.intervals
    assert asked[mavlink2.MAVLINK_MSG_ID_LOCAL_POSITION_NED] == pytest.approx(100_000)
    assert rate == pytest.approx(10.0, rel=0.2)
    assert all(interval > 0 for interval in asked.values()), "nothing is switched off"
    assert len(problems) == 1, problems
    assert problems[0].startswith("SYS_STATUS from system 1")
    assert "SET_MESSAGE_INTERVAL 1000000 us: accepted" in problems[0]
    assert "REQUEST_DATA_STREAM MAV_DATA_STREAM_EXTENDED_STATUS" in problems[0]
    assert vehicle.received["REQUEST_DATA_STREAM"] == 1


def test_second_sender_with_the_vehicle_id_is_ignored_and_reported_once() -> None:
    port = _free_udp_port()

    async def main() -> tuple[list[Any], int]:
        link = PymavlinkLink(url=f"udpin:127.0.0.1:{port}", target_system=1)
        await link.open()
        ours = await _vehicle(port, custom_mode=4)
        stray = await _vehicle(port, custom_mode=17)
        try:
            ours.heartbeat()
            await asyncio.sleep(0.05)
            for _ in range(3):
                stray.heartbeat()
                ours.heartbeat()
                await asyncio.sleep(0.02)
            events = []
            while not link.events.empty():
                events.append(link.events.get_nowait())
            stray_port = stray.transport.get_extra_info("sockname")[1]  # type: ignore[union-attr]
            return events, stray_port
        finally:
            for v in (ours, stray):
                v.transport.close()  # type: ignore[union-attr]
            await link.close()

    events, stray_port = asyncio.run(main())
    beats = [e for e in events if isinstance(e, Heartbeat)]
    strays = [e for e in events if isinstance(e, StraySource)]
    assert [b.custom_mode for b in beats] == [4] * 4
    assert len(strays) == 1
    assert strays[0].address == f"127.0.0.1:{stray_port}"


def test_refusal_carries_the_vehicle_reason_and_no_parameter_loop() -> None:
    port = _free_udp_port()

    async def main() -> tuple[Any, Any, Any, _StockCopter]:
        link = PymavlinkLink(
            url=f"udpin:127.0.0.1:{port}", target_system=1, command_timeout=0.2, command_tries=3
        )
        await link.open()
        vehicle = await _vehicle(port)
        vehicle.heartbeat()
        await asyncio.sleep(0.05)
        try:
            refusal = await link.arm()
            first = await link.set_sensor(0)
            second = await link.set_sensor(1)
            return refusal, first, second, vehicle
        finally:
            vehicle.transport.close()  # type: ignore[union-attr]
            await link.close()

    refusal, first, second, vehicle = asyncio.run(main())
    assert refusal.outcome is Outcome.DENIED
    assert refusal.result == mavlink2.MAV_RESULT_FAILED
    assert refusal.reason == _ARM_REFUSAL
    assert _ARM_REFUSAL in refusal.describe()
    assert first.outcome is second.outcome is Outcome.DENIED
    assert "no MDM_SENSOR parameter" in str(first.reason)
    assert vehicle.received["PARAM_SET"] == 0
    assert vehicle.received["PARAM_REQUEST_READ"] == 3  # one probe, its transport retries


class _Sink:
    def emit(self, t: float, event: str, **fields: Any) -> None:
        return


def test_waiting_for_the_vehicle_names_url_awaited_id_and_ids_heard(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    port = _free_udp_port()
    url = f"udpin:127.0.0.1:{port}"
    config = MissionConfig(
        vehicle=1, profile=load_profile("paper-fixed"), log_dir=tmp_path, waiting_line_period=0.3
    )

    async def main() -> None:
        link = PymavlinkLink(url=url, target_system=2)
        mission = VehicleMission(config, link, _Sink())
        flying = asyncio.create_task(mission.run())
        await asyncio.sleep(0.5)  # one waiting period in silence
        vehicle = await _vehicle(port, system=1)
        try:
            for _ in range(10):
                vehicle.heartbeat()
                await asyncio.sleep(0.1)
            mission.request_end("test")
            await asyncio.wait_for(flying, 5.0)
        finally:
            vehicle.transport.close()  # type: ignore[union-attr]

    with caplog.at_level(logging.WARNING):
        asyncio.run(main())
    lines = [r.getMessage() for r in caplog.records]
    assert f"vehicle 1: waiting on {url} for system 2; heard nothing" in lines
    assert f"vehicle 1: waiting on {url} for system 2; heard systems [1]" in lines
