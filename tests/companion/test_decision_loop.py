"""The decision loop: heartbeats on a wall-clock period only while it runs; a companion that fell
behind acts on the newest position only (no setpoints from stale ones): the pymavlink link reads
every datagram already waiting in one go, and the loop, of several queued positions, steers from
the newest.
"""

from __future__ import annotations

import asyncio
import contextlib
import socket
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from companion.autopilots import FlightMode, autopilot_for
from companion.guidance import NedSetpoint
from companion.link.base import SetpointKind, VehicleLink
from companion.link.mavlink_transport import _Protocol
from companion.link.messages import Heartbeat, LinkEvent, LocalPosition, SystemStatus
from companion.link.outcome import CommandResult, accepted
from companion.link.pymavlink_link import PymavlinkLink
from companion.mission import MissionConfig, VehicleMission
from companion.mission.control import enter
from companion.mission.phase import Phase
from mdm_profiles import load_profile


class _Sink:
    def __init__(self) -> None:
        self.events: list[str] = []

    def emit(self, t: float, event: str, **fields: Any) -> None:
        self.events.append(event)


class _Link(VehicleLink):
    """A vehicle that accepts everything and records setpoints (no sockets)."""

    def __init__(self) -> None:
        super().__init__()
        self.target_system = 1
        self.setpoints: list[NedSetpoint] = []

    def describe(self) -> str:
        return "test"

    async def open(self) -> None:
        return

    async def close(self) -> None:
        return

    def send_heartbeat(self) -> None:
        return

    def send_setpoint(self, setpoint: NedSetpoint, kind: SetpointKind) -> None:
        self.setpoints.append(setpoint)

    async def set_mode(self, mode: FlightMode) -> CommandResult:
        return accepted(mode.value)

    async def arm(self) -> CommandResult:
        return accepted("arm")

    async def takeoff(self, altitude: float) -> CommandResult:
        return accepted("takeoff")

    async def command_long(self, command: int, *params: float) -> CommandResult:
        return accepted(str(command))

    def request_data_stream(self, stream_id: int, rate_hz: int) -> None:
        return

    async def read_param(self, name: str) -> float | None:
        return 0.0

    async def set_param(self, name: str, value: float, param_type: int) -> float | None:
        return value

    async def _set_sensor(self, index: int) -> CommandResult:
        return accepted("MDM_SENSOR")


def _position(t: float, north: float) -> LocalPosition:
    return LocalPosition(t, north, 100.0, -30.0, 0.0, 0.0, 0.0, 0.0)


@pytest.mark.asyncio
async def test_of_queued_positions_only_the_newest_is_steered_from(tmp_path: Path) -> None:
    link = _Link()
    config = MissionConfig(vehicle=0, profile=load_profile("paper-fixed"), log_dir=tmp_path)
    mission = VehicleMission(config, link, _Sink())
    # a neutral setpoint for every position acted on
    mission.state = replace(mission.state, control=enter(mission.control, Phase.PREPARE))
    for k in range(5):
        link.events.put_nowait(_position(0.1 * k, 1000.0 + k))
    link.events.put_nowait(Heartbeat(12, 0, False, 3))
    mission.intake.handle_queued(_position(0.0, 999.0), link.events)
    assert link.events.empty()
    assert [sp.north for sp in link.setpoints] == [1004.0]
    assert mission.seen.position is not None
    assert mission.seen.position.north == 1004.0
    assert mission.seen.heartbeat is not None  # other events are all handled


@pytest.mark.asyncio
async def test_a_lone_position_is_acted_on(tmp_path: Path) -> None:
    link = _Link()
    config = MissionConfig(vehicle=0, profile=load_profile("paper-fixed"), log_dir=tmp_path)
    mission = VehicleMission(config, link, _Sink())
    mission.state = replace(mission.state, control=enter(mission.control, Phase.PREPARE))
    mission.intake.handle_queued(_position(0.0, 5.0), link.events)
    link.events.put_nowait(_position(0.1, 6.0))
    mission.intake.handle_queued(Heartbeat(12, 0, False, 3), link.events)
    assert [sp.north for sp in link.setpoints] == [5.0, 6.0]


@pytest.mark.asyncio
async def test_link_reads_every_waiting_datagram_at_once(monkeypatch: Any) -> None:
    calls = 0
    original = _Protocol.datagram_received

    def counting(self: _Protocol, data: bytes, addr: tuple[str | Any, int]) -> None:
        nonlocal calls
        calls += 1
        original(self, data, addr)

    monkeypatch.setattr(_Protocol, "datagram_received", counting)
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]

    link = PymavlinkLink(url=f"udpin:127.0.0.1:{port}", target_system=1)
    await link.open()
    mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    events: list[LinkEvent] = []
    try:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as vehicle:
            for k in range(6):  # all waiting before the loop looks at the socket
                msg = mav.local_position_ned_encode(100 * k, float(k), 0.0, -30.0, 0, 0, 0)
                vehicle.sendto(msg.pack(mav), ("127.0.0.1", port))
            await asyncio.sleep(0.05)
        while not link.events.empty():
            events.append(link.events.get_nowait())
    finally:
        await link.close()
    assert [e.north for e in events if isinstance(e, LocalPosition)] == [
        0.0,
        1.0,
        2.0,
        3.0,
        4.0,
        5.0,
    ]
    assert calls == 1


class _BeatingLink(_Link):
    def __init__(self, fail_after: int | None = None) -> None:
        super().__init__()
        self.beats = 0
        self.fail_after = fail_after

    def send_heartbeat(self) -> None:
        if self.fail_after is not None and self.beats >= self.fail_after:
            raise OSError("socket gone")
        self.beats += 1


def _mission(tmp_path: Path, link: _Link) -> VehicleMission:
    config = MissionConfig(vehicle=0, profile=load_profile("paper-fixed"), log_dir=tmp_path)
    return VehicleMission(replace(config, heartbeat_period=0.02), link, _Sink())


@pytest.mark.asyncio
async def test_heartbeats_flow_while_the_loop_runs_and_stop_with_it(tmp_path: Path) -> None:
    link = _BeatingLink()
    mission = _mission(tmp_path, link)
    mission.state = replace(mission.state, control=enter(mission.control, Phase.PREPARE))
    task = asyncio.create_task(mission.intake.decide())
    await asyncio.sleep(0)
    assert link.beats == 1  # one at once
    link.publish([_position(0.1, 7.0)])
    await asyncio.sleep(0.3)
    running = link.beats
    assert running >= 3
    task.cancel()
    with contextlib.suppress(asyncio.CancelledError):
        await task
    await asyncio.sleep(0.1)
    assert [sp.north for sp in link.setpoints] == [7.0]
    assert link.beats == running  # none after the loop stopped


@pytest.mark.asyncio
async def test_a_failing_heartbeat_ends_the_loop_with_its_error(tmp_path: Path) -> None:
    link = _BeatingLink(fail_after=2)
    with pytest.raises(OSError, match="socket gone"):
        await asyncio.wait_for(_mission(tmp_path, link).intake.decide(), 5.0)


@pytest.mark.asyncio
async def test_the_state_message_leaves_out_what_is_not_known_yet(tmp_path: Path) -> None:
    link = _Link()
    config = MissionConfig(vehicle=0, profile=load_profile("paper-fixed"), log_dir=tmp_path)
    mission = VehicleMission(config, link, _Sink())
    before = mission.snapshot()
    assert (before["mode"], before["armed"], before["battery"]) == (None, None, None)
    assert "north" not in before
    assert before["sensor_name"] == config.profile.sensors[mission.core.sensor()].name
    link.autopilot = autopilot_for(12)  # PX4, as the link learns it from the first HEARTBEAT
    mission.intake.handle_batch(
        [Heartbeat(12, 0, True, 3), SystemStatus(-1, True), _position(0.0, 12.34)]
    )
    after = mission.snapshot()
    assert after["mode"] == link.autopilot.mode_name(0)
    assert after["armed"] is True
    assert after["battery"] is None  # -1: the autopilot does not know
    assert (after["north"], after["east"], after["alt"]) == (12.3, 100.0, 30.0)
    assert after["phase"] == mission.phase.value
