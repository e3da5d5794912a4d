"""The mission, fence, home and yaw commands (COMMAND_LONG / COMMAND_INT), each answered as the
persona's autopilot answers it (measured on ArduCopter and PX4 SITL; docs/protocol.md,
*Commands*): MISSION_START, DO_SET_MISSION_CURRENT, DO_FENCE_ENABLE, DO_SET_HOME,
CONDITION_YAW, NAV_LOITER_UNLIM."""

from __future__ import annotations

import math

from sim_vehicle_stub.geo_frame import GeoFrame
from sim_vehicle_stub.mavlink import dialect as d
from sim_vehicle_stub.orbit import orbit_about
from sim_vehicle_stub.vehicle import ACCEPTED, DENIED, FAILED, UNSUPPORTED, Vehicle

MISSION_COMMANDS = frozenset(
    (
        d.MAV_CMD_MISSION_START,
        d.MAV_CMD_DO_SET_MISSION_CURRENT,
        d.MAV_CMD_DO_FENCE_ENABLE,
        d.MAV_CMD_DO_SET_HOME,
        d.MAV_CMD_CONDITION_YAW,
        d.MAV_CMD_NAV_LOITER_UNLIM,
        d.MAV_CMD_DO_ORBIT,
    )
)


def run_flight_command(
    v: Vehicle, cmd: int, p: tuple[float, ...], frame: int | None, geo: GeoFrame
) -> int:
    """The MAV_RESULT of one of :data:`MISSION_COMMANDS` (UNSUPPORTED where the persona's
    autopilot does not have it)."""
    if cmd not in v.persona.flight_commands:
        return UNSUPPORTED
    if cmd == d.MAV_CMD_MISSION_START:
        return _mission_start(v)
    if cmd == d.MAV_CMD_DO_SET_MISSION_CURRENT:
        if not v.mission_run.has_items:
            return v.persona.mission.set_current_without_mission
        if not math.isfinite(p[0]):
            return DENIED
        return ACCEPTED if v.mission_run.set_current(int(p[0])) else DENIED
    if cmd == d.MAV_CMD_DO_FENCE_ENABLE:
        if not math.isfinite(p[0]) or int(p[0]) not in (0, 1, 2):
            return DENIED
        # 2 disables the floor only (ArduPilot): the emulator's fence has no floor to drop.
        v.params.set(v.persona.fence_enable_param, 1.0 if int(p[0]) == 1 else 0.0)
        v.apply_params()
        return ACCEPTED
    if cmd == d.MAV_CMD_DO_SET_HOME:
        return _set_home(v, p, frame, geo)
    if cmd == d.MAV_CMD_CONDITION_YAW:
        return _condition_yaw(v, p)
    if cmd == d.MAV_CMD_DO_ORBIT:
        return _orbit(v, p, frame, geo)
    # NAV_LOITER_UNLIM as a command: ArduCopter switches to LOITER where it is.
    return v.set_mode(v.persona.mode(v.persona.loiter_mode))


def _mission_start(v: Vehicle) -> int:
    """ArduCopter: AUTO, auto_armed, the mission (re)started, disarmed too; PX4: armed only."""
    p = v.persona
    if p.mission.start_needs_armed and not v.armed:
        return DENIED
    if not v.mission_run.has_items:
        return FAILED if not p.mission.start_needs_armed else DENIED
    result = v.set_mode(p.mode(p.mission_mode), "mission start")
    if result != ACCEPTED:
        return FAILED if not p.mission.start_needs_armed else result
    if v.armed:
        v.auto_armed = True
        if not v.mission_run.running:
            v.mission_run.enter()
    return ACCEPTED


def _set_home(v: Vehicle, p: tuple[float, ...], frame: int | None, geo: GeoFrame) -> int:
    if p[0] >= 0.5:
        f = v.fleet
        v.home = (float(f.pos[v.index, 0]), float(f.pos[v.index, 1]))
        return ACCEPTED
    scale = 1e-7 if frame is not None else 1.0
    lat, lon = p[4] * scale, p[5] * scale
    if not (math.isfinite(lat) and math.isfinite(lon)) or abs(lat) > 90 or abs(lon) > 180:
        return DENIED
    north, east, _ = geo.to_local(lat, lon, geo.alt)
    v.home = (north, east)
    return ACCEPTED


_ORBIT_RADIUS, _ORBIT_SPEED = 10.0, 1.0
"""PX4's DO_ORBIT defaults for NaN radius and speed (m, m/s)."""


def _orbit(v: Vehicle, p: tuple[float, ...], frame: int | None, geo: GeoFrame) -> int:
    """PX4 DO_ORBIT: p1 radius (negative: counter-clockwise), p2 speed, p5/p6 centre (NaN:
    here), p7 altitude AMSL (NaN: kept). ACCEPTED on the ground too, as PX4 SITL; flown once
    airborne in ORBIT."""
    radius = p[0] if math.isfinite(p[0]) and p[0] != 0 else _ORBIT_RADIUS
    speed = p[1] if math.isfinite(p[1]) and p[1] > 0 else _ORBIT_SPEED
    if abs(radius) > 1e5 or speed > 100.0:
        return DENIED
    f, i = v.fleet, v.index
    here = (float(f.pos[i, 0]), float(f.pos[i, 1]))
    north, east = here
    if math.isfinite(p[4]) and math.isfinite(p[5]):
        scale = 1e-7 if frame is not None else 1.0
        lat, lon = p[4] * scale, p[5] * scale
        if abs(lat) > 90 or abs(lon) > 180:
            return DENIED
        north, east, _ = geo.to_local(lat, lon, geo.alt)
    v.orbit = orbit_about(north, east, here, radius, speed)
    if math.isfinite(p[6]) and abs(p[6] - geo.alt) < 1e5:
        f.climb_to(i, max(p[6] - geo.alt, 0.0))
    return v.set_mode(v.persona.mode("ORBIT"), "orbit")


def _condition_yaw(v: Vehicle, p: tuple[float, ...]) -> int:
    """p1 heading (deg), p2 rate, p3 direction (-1 ccw, 1 cw), p4 1 relative; taken disarmed
    too (ArduCopter), acted on in GUIDED and AUTO."""
    angle, direction, relative = p[0], p[2], p[3]
    if not (math.isfinite(angle) and math.isfinite(relative)):
        return DENIED
    f, i = v.fleet, v.index
    heading = math.radians(angle)
    if relative >= 0.5:
        sign = -1.0 if math.isfinite(direction) and direction < 0 else 1.0
        heading = float(f.yaw[i]) + sign * heading
    if v.armed:
        f.yaw_cmd[i] = heading % (2 * math.pi)
        f.yaw_rate[i] = math.nan
    return ACCEPTED
