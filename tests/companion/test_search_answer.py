"""The search's common answer (mission/search_answer.py) does what the decision loop does.

A companion (PymavlinkLink + VehicleMission in the search phase, real UDP on 127.0.0.1) flies a
scripted vehicle twice: once as it runs, once with the answer switched off, so that every
position takes the decision loop's events. The vehicle integrates the velocity setpoints it
gets, so both flights are the same flight only if every answer is. The script holds what a
sped-up vehicle sends: a position and the sensor's signal every tick, a heartbeat before and a
status after the position every tenth, contacts of the targets the vehicle comes near (one it
confirmed before), and at the end a low battery before the position (it ends the search there).
"""

from __future__ import annotations

import asyncio
import math
import socket
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from companion.geofence import Geofence
from companion.link.pymavlink_link import PymavlinkLink
from companion.mission import MissionConfig, VehicleMission
from companion.mission.control import enter
from companion.mission.phase import Phase
from companion.mission.search_answer import SearchAnswer
from companion.telemetry.mission_log import MissionLog, read_records
from mdm_core.search.policy import SearchPolicy
from mdm_profiles import load_profile
from tests.setpoint_record import PROFILE

TICKS = 3000
TARGET = (1500.0, 1500.0)
KNOWN = (0.0, 300.0)
"""A target this vehicle confirmed before (a restarted companion's memory): read again, it
changes nothing, and the policy step is skipped."""
LOW_BATTERY_AT = TICKS - 1
FENCE = Geofence.rectangle(1200.0, 1700.0)
"""Smaller than the area: some waypoints lie outside it, and the vehicle steers to the fence."""


def _datagram(mav: Any, k: int, north: float, east: float, vn: float, ve: float) -> bytes:
    t = 100 * k
    frames = []
    if k % 10 == 0:  # ArduCopter GUIDED, armed, active
        frames.append(mav.heartbeat_encode(2, 3, 128 | 8 | 1, 4, 4, 3))
    if k == LOW_BATTERY_AT:
        frames.append(mav.sys_status_encode(1, 1, 1, 100, 1, 500, 10, 0, 0, 0, 0, 0, 0))
    frames.append(mav.local_position_ned_encode(t, north, east, -30.0, vn, ve, 0.0))
    if k % 10 == 5:
        frames.append(mav.sys_status_encode(1, 1, 1, 100, 1, 500, 90, 0, 0, 0, 0, 0, 0))
    distance = math.hypot(north - TARGET[0], east - TARGET[1])
    frames.append(mav.named_value_float_encode(t, b"SENS_SIG", math.exp(-distance / 1000.0)))
    for where in (TARGET, KNOWN):  # the detection sensor's readings, and the confirming one's
        distance = math.hypot(north - where[0], east - where[1])
        if distance < 1000.0 and k % 3 == 0:
            frames.append(mav.debug_vect_encode(b"DET", t * 1000, *where, 0.0))
        if distance < 50.0:
            frames.append(mav.debug_vect_encode(b"CNF", t * 1000, *where, 0.0))
    return b"".join(bytes(f.pack(mav)) for f in frames)


async def _fly(out: Path) -> tuple[list[tuple[Any, ...]], VehicleMission]:
    out.mkdir()
    profile_file = out / "profile.yaml"
    profile_file.write_text(PROFILE)
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    link = PymavlinkLink(url=f"udpin:127.0.0.1:{port}", target_system=1, tlog=out / "v.tlog")
    profile = load_profile(str(profile_file))  # (KNOWN would count as the one target found)
    config = MissionConfig(0, profile, log_dir=out, seed=7, stop_when_all_found=False)
    mission = VehicleMission(config, link, MissionLog(out / "mission.jsonl"), fence=FENCE)
    await link.open()
    loop = asyncio.get_running_loop()
    mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    vehicle = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    vehicle.setblocking(False)
    north, east, vn, ve = 300.0, 400.0, 0.0, 0.0
    answers: list[tuple[Any, ...]] = []
    decide: asyncio.Task[None] | None = None
    try:
        for k in range(TICKS):
            vehicle.sendto(_datagram(mav, k, north, east, vn, ve), ("127.0.0.1", port))
            if k == 0:  # the search starts where the first position is, as once climbed
                while mission.seen.position is None:
                    mission.intake.handle_queued(await link.events.get(), link.events)
                _begin_search(mission)
                mission.intake.handle(mission.seen.position)
                decide = asyncio.create_task(mission.intake.decide())
            if k == LOW_BATTERY_AT:  # no answer: the search ends
                await asyncio.sleep(0.1)
                break
            while True:  # the setpoint (the companion's own heartbeats pass by)
                data = await asyncio.wait_for(loop.sock_recv(vehicle, 2048), 5.0)
                msg = mav.parse_char(data)
                if msg.get_type() == "SET_POSITION_TARGET_LOCAL_NED":
                    break
            answers.append(
                (
                    msg.time_boot_ms,
                    msg.x,
                    msg.y,
                    msg.z,
                    msg.vx,
                    msg.vy,
                    msg.vz,
                    msg.type_mask,
                    msg.target_system,
                )
            )
            vn, ve = msg.vx, msg.vy
            north, east = north + 0.1 * vn, east + 0.1 * ve
    finally:
        if decide is not None:
            decide.cancel()
            await asyncio.gather(decide, return_exceptions=True)
        await link.close()
        vehicle.close()
    return answers, mission


def _begin_search(mission: VehicleMission) -> None:
    pos = mission.seen.position
    assert pos is not None
    t = mission.seen.clock.now
    mission.seen.begin_search(t)
    mission.core.start(np.array([pos.north, pos.east]), t, [KNOWN])
    mission._apply(replace(mission.state, control=enter(mission.control, Phase.SEARCH)))
    mission.sensors.select(mission.core.sensor(), t)


def _tlog(path: Path) -> list[tuple[str, Any]]:
    """Every message of the .tlog but the companion's own heartbeats (sent on a wall timer)."""
    log = mavutil.mavlink_connection(str(path), dialect="ardupilotmega")
    out = []
    while (msg := log.recv_match()) is not None:
        if msg.get_type() == "HEARTBEAT" and msg.get_srcSystem() != 1:
            continue
        fields = msg.to_dict()
        out.append((msg.get_type(), sorted(fields.items())))
    return out


def _state(m: VehicleMission) -> dict[str, Any]:
    seen = m.seen
    pos = seen.position
    where = None if pos is None else replace(pos, received=0.0)  # (wall time of arrival)
    return {
        "clock": seen.clock.now,
        "period": seen.period,
        "position": where,
        "speed": seen.max_search_speed,
        "level": m.core.level,
        "waypoint": m.core.waypoint.tolist(),
        "found": m.core.confirmed_count,
        "signal": m.sensors.signal,
        "end": m.end_reason,
        "phase": m.phase,
        "received": seen.received_time,
        "setpoint": seen.setpoint_time,
        "heartbeat": seen.heartbeat,
        "status": seen.status,
        "home": seen.home,
        "tick": seen.last_tick,
    }


def _records(path: Path) -> list[dict[str, Any]]:
    return [
        {k: v for k, v in r.items() if k != "wall"}
        for r in read_records(path)
        if r["event"] != "latency"
    ]


def test_the_answer_flies_as_the_decision_loop(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    skipped = 0
    step_changes = SearchPolicy.step_changes

    def counting(self: SearchPolicy, *args: Any) -> bool:
        nonlocal skipped
        said = step_changes(self, *args)
        skipped += not said and len(args[-1]) > 0
        return said

    stale: list[tuple[float, ...]] = []
    steer_to = SearchAnswer.steer_to

    def checked(self: SearchAnswer, north: float, east: float, goal: tuple[float, float]) -> None:
        # the plan is the policy's waypoint of now (also after a step that did not reach one)
        if (north, east) != tuple(self.core.waypoint) or goal != tuple(FENCE.clamp_xy(north, east)):
            stale.append((north, east, *goal))
        steer_to(self, north, east, goal)

    monkeypatch.setattr(SearchPolicy, "step_changes", counting)
    monkeypatch.setattr(SearchAnswer, "steer_to", checked)
    fast, fast_mission = asyncio.run(_fly(tmp_path / "fast"))
    assert skipped >= 20  # contacts of the known target, ruled out without a step
    assert stale == []
    with monkeypatch.context() as patched:
        patched.setattr(SearchAnswer, "ready", lambda *_: False)
        loop, loop_mission = asyncio.run(_fly(tmp_path / "loop"))
    assert loop_mission.answer.answered == 0
    # nearly every position was answered here (KNOWN's contacts too), the rest by the loop:
    # the ticks, the detection, the waypoints reached
    assert fast_mission.answer.answered >= 0.9 * len(fast)
    assert fast_mission.answer.answered <= len(fast) - 30
    assert fast == loop
    assert _state(fast_mission) == _state(loop_mission)
    assert _records(tmp_path / "fast" / "mission.jsonl") == _records(
        tmp_path / "loop" / "mission.jsonl"
    )
    assert _tlog(tmp_path / "fast" / "v.tlog") == _tlog(tmp_path / "loop" / "v.tlog")
    # the flight decided: it detected the target, and the low battery ended it
    events = [r["event"] for r in _records(tmp_path / "fast" / "mission.jsonl")]
    assert "detection" in events
    assert fast_mission.end_reason is not None
    assert "battery" in fast_mission.end_reason
