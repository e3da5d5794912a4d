"""Flights flown through MAVSDK 4's own plugins, the same way against the emulator and against a
SITL autopilot: a QGroundControl plan (mission_raw's QGC import, with its fence and rally
point), offboard position setpoints ending in a landing, the pilot's sticks (manual_control).
Written here from the plugins' API; each returns what the tests compare."""

from __future__ import annotations

import asyncio
import contextlib
import json
import math
from dataclasses import dataclass, field
from typing import Any

import pymap3d
from mavsdk.asyncio import Configuration, Mavsdk
from mavsdk.asyncio.plugins.action import ActionAsync, ActionError
from mavsdk.asyncio.plugins.manual_control import ManualControlAsync
from mavsdk.asyncio.plugins.mission import MissionAsync, MissionError, MissionItem, MissionPlan
from mavsdk.asyncio.plugins.mission_raw import MissionRawAsync
from mavsdk.asyncio.plugins.offboard import OffboardAsync, PositionNedYaw
from mavsdk.asyncio.plugins.param import ParamAsync
from mavsdk.asyncio.plugins.telemetry import TelemetryAsync
from mavsdk.plugins.mavlink_direct import MavlinkDirect, MavlinkMessage


@dataclass
class PlanFlight:
    """What a flown plan left: the mission items in the order the vehicle reported them as
    current, the path (north, east, up from home, every sample), how it ended."""

    uploaded: tuple[int, int, int] = (0, 0, 0)
    """Mission, fence and rally items uploaded (ArduPilot's home item included)."""
    downloaded: int = 0
    progress: list[int] = field(default_factory=list)
    total: int = 0
    path: list[tuple[float, float, float]] = field(default_factory=list)
    landed_at: tuple[float, float] | None = None
    """Where it disarmed, north and east of home."""


async def autopilot(mavsdk: Mavsdk, url: str, seconds: float = 30.0) -> Any:
    await mavsdk.add_any_connection(url)
    system = await mavsdk.first_autopilot(seconds)
    if system is None:
        raise TimeoutError(f"no autopilot on {url} in {seconds:.0f} s")
    return system


async def _ready(tel: TelemetryAsync, seconds: float) -> tuple[float, float, float]:
    """Wait for home (streamed at 1 Hz on request: ArduCopter sends it only when asked, and
    has none before its GPS fix); (lat, lon, AMSL) of home."""

    async def wait() -> tuple[float, float, float]:
        async for home in tel.subscribe_home():
            if home.latitude_deg != 0.0 and math.isfinite(home.latitude_deg):
                return home.latitude_deg, home.longitude_deg, home.absolute_altitude_m
        raise RuntimeError("home stream ended")

    await tel.set_rate_position(10.0)
    await tel.set_rate_home(1.0)
    return await asyncio.wait_for(wait(), seconds)


def _local(home: tuple[float, float, float], lat: float, lon: float) -> tuple[float, float]:
    n, e, _ = pymap3d.geodetic2ned(lat, lon, home[2], *home)
    return float(n), float(e)


async def _sample(tel: TelemetryAsync, home: tuple[float, float, float], out: list[Any]) -> None:
    async for pos in tel.subscribe_position():
        n, e = _local(home, pos.latitude_deg, pos.longitude_deg)
        out.append((n, e, pos.relative_altitude_m))


async def _until_disarmed(tel: TelemetryAsync, seconds: float) -> None:
    async def wait() -> None:
        seen_armed = False
        async for armed in tel.subscribe_armed():
            seen_armed |= armed
            if seen_armed and not armed:
                return

    await asyncio.wait_for(wait(), seconds)


async def fly_plan(
    url: str,
    plan: str,
    *,
    ardupilot: bool,
    speed: float,
    ready_s: float = 90.0,
    flight_s: float = 300.0,
) -> PlanFlight:
    """Import ``plan`` with mission_raw, upload mission, fence and rally points, read the
    mission back, fly it at ``speed`` m/s to its RTL and touch-down."""
    rec = PlanFlight()
    async with Mavsdk(Configuration.create_manual(245, 190, True)) as mavsdk:
        system = await autopilot(mavsdk, url)
        tel, act, mr = TelemetryAsync(system), ActionAsync(system), MissionRawAsync(system)
        param = ParamAsync(system)
        home = await _ready(tel, ready_s)
        if ardupilot:
            await param.set_param_float("WPNAV_SPEED", speed * 100.0)
        else:
            await param.set_param_float("MPC_XY_CRUISE", speed)
        data = await mr.import_qgroundcontrol_mission_from_string(plan)
        await mr.upload_mission(data.mission_items)
        await mr.upload_geofence(data.geofence_items)
        await mr.upload_rally_points(data.rally_items)
        rec.uploaded = (len(data.mission_items), len(data.geofence_items), len(data.rally_items))
        rec.downloaded = len(await mr.download_mission())
        sampler = asyncio.create_task(_sample(tel, home, rec.path))
        watcher = asyncio.create_task(_progress(mr, rec))
        try:
            if ardupilot:
                # ArduCopter's AUTO leaves the ground only once auto_armed: MISSION_START (AUTO
                # and auto_armed, as a ground station starts it; MAVSDK's own start_mission only
                # switches the mode), right after arming (DISARM_DELAY disarms it on the
                # ground), both again while the SITL still lacks a position ("requires
                # position").
                await _start_ardupilot_mission(act, MavlinkDirect(system._system), system, ready_s)
            else:
                await _arm_when_ready(act, ready_s)
                await mr.start_mission()
            await _until_disarmed(tel, flight_s)
        finally:
            for task in (sampler, watcher):
                task.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await task
        if rec.path:
            rec.landed_at = rec.path[-1][:2]
    return rec


def _mission_start(direct: MavlinkDirect, sysid: int) -> int:
    """COMMAND_LONG MISSION_START (first item 0, last 0) through MAVSDK's MavlinkDirect; its
    MAV_RESULT."""
    fields: dict[str, float] = {f"param{i}": 0.0 for i in range(1, 8)}
    fields.update({"target_system": sysid, "target_component": 1, "command": 300})
    fields["confirmation"] = 0
    msg = MavlinkMessage("COMMAND_LONG", 245, 190, sysid, 1, json.dumps(fields))
    return int(json.loads(direct.send_command(msg).fields_json).get("result", -1))


def _ask_mission_current(direct: MavlinkDirect, sysid: int) -> int:
    """SET_MESSAGE_INTERVAL MISSION_CURRENT at 1 Hz, as a ground station asks a stock
    ArduCopter (which sends none until asked; MAVSDK does not ask); its MAV_RESULT."""
    fields: dict[str, float] = {f"param{i}": 0.0 for i in range(1, 8)}
    fields.update({"target_system": sysid, "target_component": 1, "command": 511})
    fields.update({"param1": 42.0, "param2": 1e6, "confirmation": 0})
    msg = MavlinkMessage("COMMAND_LONG", 245, 190, sysid, 1, json.dumps(fields))
    return int(json.loads(direct.send_command(msg).fields_json).get("result", -1))


async def _start_ardupilot_mission(
    act: ActionAsync, direct: MavlinkDirect, system: Any, seconds: float
) -> None:
    """Arm and MISSION_START, both again until MISSION_START is ACCEPTED."""
    sysid = await system.get_system_id()
    loop = asyncio.get_running_loop()
    deadline = loop.time() + seconds
    while True:
        await _arm_when_ready(act, seconds)
        if await loop.run_in_executor(None, _mission_start, direct, sysid) == 0:
            return
        if loop.time() > deadline:
            raise RuntimeError(f"MISSION_START refused for {seconds:.0f} s")
        await asyncio.sleep(1.0)


async def _progress(mr: MissionRawAsync, rec: PlanFlight) -> None:
    async for p in mr.subscribe_mission_progress():
        rec.total = p.total
        if not rec.progress or rec.progress[-1] != p.current:
            rec.progress.append(p.current)


async def _arm_when_ready(act: ActionAsync, seconds: float) -> None:
    """Arm, retried while the autopilot still refuses (a SITL's EKF settling)."""
    deadline = asyncio.get_running_loop().time() + seconds
    while True:
        try:
            await act.arm()
            return
        except Exception:
            if asyncio.get_running_loop().time() > deadline:
                raise
            await asyncio.sleep(1.0)


async def _take_off_when_ready(act: ActionAsync, seconds: float) -> None:
    """Arm and take off (MAVSDK's mission plugin has no take-off item for ArduPilot), both again
    while ArduCopter SITL refuses GUIDED's take-off (FAILED while its EKF has no position yet,
    though home is set)."""
    deadline = asyncio.get_running_loop().time() + seconds
    while True:
        await _arm_when_ready(act, seconds)
        try:
            await act.takeoff()
            return
        except ActionError:
            if asyncio.get_running_loop().time() > deadline:
                raise
            await asyncio.sleep(1.0)


@dataclass
class OffboardLanding:
    corners: list[tuple[float, float]] = field(default_factory=list)
    """Where the vehicle was after each position setpoint (north, east from home)."""
    landed_at: tuple[float, float] = (math.nan, math.nan)


async def fly_offboard_square(
    url: str, side: float, alt: float, *, ardupilot: bool, settle_s: float
) -> OffboardLanding:
    """Take off, fly a square of ``side`` m over the take-off point with offboard
    PositionNedYaw setpoints (LOCAL_POSITION_NED from the vehicle's origin), come back to its
    centre, land there: where it touched down."""
    rec = OffboardLanding()
    async with Mavsdk(Configuration.create_manual(245, 190, True)) as mavsdk:
        system = await autopilot(mavsdk, url)
        tel, act, off = TelemetryAsync(system), ActionAsync(system), OffboardAsync(system)
        home = await _ready(tel, 90.0)
        await _arm_when_ready(act, 60.0)
        await act.set_takeoff_altitude(alt)
        await act.takeoff()
        async for pos in tel.subscribe_position():
            if pos.relative_altitude_m > alt - 0.5:
                break
        await off.set_position_ned(PositionNedYaw(0.0, 0.0, -alt, 0.0))
        await off.start()
        for n, e in ((side, 0.0), (side, side), (0.0, side), (0.0, 0.0)):
            await off.set_position_ned(PositionNedYaw(n, e, -alt, 0.0))
            await asyncio.sleep(settle_s)
            pos = await tel.position()
            rec.corners.append(_local(home, pos.latitude_deg, pos.longitude_deg))
        await off.stop()
        await act.land()
        await _until_disarmed(tel, 120.0)
        pos = await tel.position()
        rec.landed_at = _local(home, pos.latitude_deg, pos.longitude_deg)
    return rec


@dataclass
class StickFlight:
    mode: str = ""
    moved: tuple[float, float] = (0.0, 0.0)
    """North, east flown while the pitch stick was forward."""
    drift_after_release: float = math.nan


async def fly_sticks(url: str, *, seconds: float) -> StickFlight:
    """Take off, then the pilot's sticks (manual_control position control): pitch forward for
    ``seconds``, then centred for as long: how far it flew, how far it drifted once centred."""
    rec = StickFlight()
    async with Mavsdk(Configuration.create_manual(245, 190, True)) as mavsdk:
        system = await autopilot(mavsdk, url)
        tel, act = TelemetryAsync(system), ActionAsync(system)
        manual = ManualControlAsync(system)
        home = await _ready(tel, 90.0)
        await _arm_when_ready(act, 60.0)
        await act.set_takeoff_altitude(10.0)
        await act.takeoff()
        async for pos in tel.subscribe_position():
            if pos.relative_altitude_m > 9.5:
                break
        for _ in range(10):
            await manual.set_manual_control_input(0.0, 0.0, 0.5, 0.0)
            await asyncio.sleep(0.05)
        await manual.start_position_control()
        rec.mode = str(await tel.flight_mode())
        start = await tel.position()
        before = _local(home, start.latitude_deg, start.longitude_deg)

        async def hold_sticks(x: float, duration: float) -> None:
            end = asyncio.get_running_loop().time() + duration
            while asyncio.get_running_loop().time() < end:
                await manual.set_manual_control_input(x, 0.0, 0.5, 0.0)
                await asyncio.sleep(0.05)

        await hold_sticks(1.0, seconds)
        pos = await tel.position()
        after = _local(home, pos.latitude_deg, pos.longitude_deg)
        rec.moved = (after[0] - before[0], after[1] - before[1])
        await hold_sticks(0.0, seconds / 2)
        pos = await tel.position()
        mid = _local(home, pos.latitude_deg, pos.longitude_deg)
        await hold_sticks(0.0, seconds / 2)
        pos = await tel.position()
        end = _local(home, pos.latitude_deg, pos.longitude_deg)
        rec.drift_after_release = math.hypot(end[0] - mid[0], end[1] - mid[1])
        await act.land()
    return rec


def mission_plugin_plan(
    home: tuple[float, float, float], points: list[tuple[float, float]], alt: float
) -> MissionPlan:
    """MAVSDK mission items for waypoints (north, east from home) at ``alt``, 5 m/s, passed
    through within 2 m."""
    items = []
    for n, e in points:
        lat, lon, _ = pymap3d.ned2geodetic(n, e, 0.0, *home)
        items.append(MissionItem(float(lat), float(lon), alt, 5.0, True, acceptance_radius_m=2.0))
    return MissionPlan(items)


async def upload_with_return(url: str, points: list[tuple[float, float]], alt: float) -> str:
    """MAVSDK's mission plugin upload with its return to launch after the mission on: the
    MissionResult's name (MAVSDK sends the return as an item with NaN params)."""
    async with Mavsdk(Configuration.create_manual(245, 190, True)) as mavsdk:
        system = await autopilot(mavsdk, url)
        tel, mission = TelemetryAsync(system), MissionAsync(system)
        home = await _ready(tel, 90.0)
        await mission.set_return_to_launch_after_mission(True)
        try:
            await mission.upload_mission(mission_plugin_plan(home, points, alt))
        except MissionError as e:
            return str(e.result.name)
    return "SUCCESS"


async def fly_mission_plugin(
    url: str, points: list[tuple[float, float]], alt: float, *, ardupilot: bool
) -> tuple[list[int], int, tuple[float, float]]:
    """MAVSDK's mission plugin (not raw): waypoints (north, east from home) at ``alt``, then
    home: PX4 with the plugin's return to launch after the mission; ArduPilot, which refuses
    that item (NaN params, ``upload_with_return``), with Action's return to launch once the
    plugin reports the mission finished. (mission progress in order, items, landed at)."""
    progress: list[int] = []
    async with Mavsdk(Configuration.create_manual(245, 190, True)) as mavsdk:
        system = await autopilot(mavsdk, url)
        tel, act, mission = TelemetryAsync(system), ActionAsync(system), MissionAsync(system)
        home = await _ready(tel, 90.0)
        plan = mission_plugin_plan(home, points, alt)
        await mission.set_return_to_launch_after_mission(not ardupilot)
        await mission.upload_mission(plan)
        if ardupilot:  # the plugin's progress reads MISSION_CURRENT
            sysid = await system.get_system_id()
            direct = MavlinkDirect(system._system)
            asked = await asyncio.get_running_loop().run_in_executor(
                None, _ask_mission_current, direct, sysid
            )
            assert asked == 0, f"SET_MESSAGE_INTERVAL MISSION_CURRENT: result {asked}"

        async def watch() -> None:
            async for p in mission.subscribe_mission_progress():
                if not progress or progress[-1] != p.current:
                    progress.append(p.current)

        watcher = asyncio.create_task(watch())
        try:
            if ardupilot:
                await act.set_takeoff_altitude(alt)
                await _take_off_when_ready(act, 60.0)
                async for pos in tel.subscribe_position():
                    if pos.relative_altitude_m > 2.0:
                        break
            else:
                await _arm_when_ready(act, 60.0)
            await mission.start_mission()
            if ardupilot:
                while not await mission.is_mission_finished():
                    await asyncio.sleep(0.2)
                await act.return_to_launch()
            await _until_disarmed(tel, 180.0)
        finally:
            watcher.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await watcher
        pos = await tel.position()
        landed = _local(home, pos.latitude_deg, pos.longitude_deg)
    return progress, len(plan.mission_items), landed
