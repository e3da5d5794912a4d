"""SET_POSITION_TARGET_LOCAL_NED / _GLOBAL_INT to a :class:`NeuSetpoint` in the local frame.

type_mask bits set mean "ignore": 1 x, 2 y, 4 z, 8 vx, 16 vy, 32 vz, 64/128/256 acceleration,
512 force, 1024 yaw, 2048 yaw rate. As ArduCopter (GCS_MAVLink_Copter.cpp,
handle_message_set_position_target_local_ned): an acceleration alone is followed (as a velocity
that integrates it), an acceleration next to a position or velocity is feed-forward the lag
model has no use for, force is refused. A message with no target at all is rejected.
"""

from __future__ import annotations

import math
from typing import Any

from sim_vehicle_stub.geo_frame import GeoFrame
from sim_vehicle_stub.vehicle import NeuSetpoint, Vehicle

LOCAL_NED, LOCAL_OFFSET_NED, BODY_NED, BODY_OFFSET_NED = 1, 7, 8, 9
_GLOBAL_AMSL = (0, 5)
_GLOBAL_RELATIVE = (3, 6, 10, 11)


def _fields(mask: int) -> tuple[bool, bool, bool, bool, bool]:
    """(xy position, z, xy velocity, vz, yaw) used by a type_mask."""
    return (mask & 3) == 0, not mask & 4, (mask & 24) == 0, not mask & 32, not mask & 1024


def _accel(msg: Any, mask: int) -> tuple[float, float, float] | None:
    """The acceleration (north, east, up) of an acceleration-only target, else None."""
    if mask & 448 or (mask & 63) != 63:
        return None
    return float(msg.afx), float(msg.afy), -float(msg.afz)


def _yaw_rate(msg: Any, mask: int) -> float | None:
    return float(msg.yaw_rate) if not mask & 2048 and _ok(msg.yaw_rate) else None


_LIMIT = 1e7
"""Metres or m/s beyond which a setpoint value is rejected as nonsense (no area is that big)."""


def _ok(*values: float) -> bool:
    """Every value finite and below the limit (``abs(x) < _LIMIT`` is false for NaN and inf).
    A loop, not ``all()`` over a generator: this runs for every setpoint received."""
    for x in values:  # noqa: SIM110
        if not abs(x) < _LIMIT:
            return False
    return True


def local_setpoint(msg: Any, v: Vehicle, t: float) -> NeuSetpoint | None:
    """The setpoint a LOCAL_NED-family message asks for, or None when it cannot be followed."""
    frame = int(msg.coordinate_frame)
    if frame not in (LOCAL_NED, LOCAL_OFFSET_NED, BODY_NED, BODY_OFFSET_NED):
        return None
    mask = int(msg.type_mask)
    use_pos, use_z, use_vel, use_vz, use_yaw = _fields(mask)
    accel = _accel(msg, mask)
    if accel is not None and (mask & 512 or not _ok(*accel)):
        return None
    if not (use_pos or use_z or use_vel or use_vz or accel):
        return None
    i, f = v.index, v.fleet
    body = frame in (BODY_NED, BODY_OFFSET_NED)
    yaw = float(f.yaw[i])
    c, s = math.cos(yaw), math.sin(yaw)

    def rotate(x: float, y: float) -> tuple[float, float]:
        return (x * c - y * s, x * s + y * c) if body else (x, y)

    position = velocity = None
    alt = climb = None
    if use_pos:
        if not _ok(msg.x, msg.y):
            return None
        dn, de = rotate(msg.x, msg.y)
        # LOCAL_NED is metres from the vehicle's local origin (where it booted), as on a real
        # autopilot; the offset frames from where it is now.
        base = v.origin if frame == LOCAL_NED else (float(f.pos[i, 0]), float(f.pos[i, 1]))
        position = (base[0] + dn, base[1] + de)
    if use_z:
        if not _ok(msg.z):
            return None
        alt = -msg.z if frame == LOCAL_NED else float(f.alt[i]) - msg.z
    if use_vel:
        if not _ok(msg.vx, msg.vy):
            return None
        velocity = rotate(msg.vx, msg.vy)
    if use_vz:
        if not _ok(msg.vz):
            return None
        climb = -msg.vz
    yaw_cmd = float(msg.yaw) if use_yaw and _ok(msg.yaw) else None
    if yaw_cmd is not None and body:
        yaw_cmd += yaw
    if accel is not None and body:
        accel = (*rotate(accel[0], accel[1]), accel[2])
    return NeuSetpoint(t, position, velocity, alt, climb, yaw_cmd, _yaw_rate(msg, mask), accel)


def global_setpoint(msg: Any, geo: GeoFrame, t: float) -> NeuSetpoint | None:
    """The setpoint a SET_POSITION_TARGET_GLOBAL_INT asks for, or None."""
    frame = int(msg.coordinate_frame)
    if frame not in _GLOBAL_AMSL + _GLOBAL_RELATIVE:
        return None
    mask = int(msg.type_mask)
    use_pos, use_z, use_vel, use_vz, use_yaw = _fields(mask)
    accel = _accel(msg, mask)
    if accel is not None and (mask & 512 or not _ok(*accel)):
        return None
    if not (use_pos or use_z or use_vel or use_vz or accel):
        return None
    position = velocity = None
    alt = climb = None
    if use_pos:
        lat, lon = msg.lat_int * 1e-7, msg.lon_int * 1e-7
        if not (-90 <= lat <= 90 and -180 <= lon <= 180):
            return None
        north, east, _ = geo.to_local(lat, lon, geo.alt)
        position = (north, east)
    if use_z:
        if not _ok(msg.alt):
            return None
        alt = msg.alt - geo.alt if frame in _GLOBAL_AMSL else float(msg.alt)
    if use_vel:
        if not _ok(msg.vx, msg.vy):
            return None
        velocity = (float(msg.vx), float(msg.vy))
    if use_vz:
        if not _ok(msg.vz):
            return None
        climb = -float(msg.vz)
    yaw_cmd = float(msg.yaw) if use_yaw and _ok(msg.yaw) else None
    return NeuSetpoint(t, position, velocity, alt, climb, yaw_cmd, _yaw_rate(msg, mask), accel)


_G = 9.80665
_MAX_TILT = math.radians(30.0)
"""ArduCopter's ANGLE_MAX default (3000 cd): the steepest lean a guided attitude gets."""
_THROTTLE_IGNORE, _ATTITUDE_IGNORE = 64, 128


def attitude_setpoint(msg: Any, v: Vehicle, t: float) -> NeuSetpoint | None:
    """SET_ATTITUDE_TARGET as ArduCopter's guided mode reads it (GCS_MAVLink_Copter.cpp,
    handle_message_set_attitude_target): thrust 0.5 holds altitude, above climbs at up to the
    climb limit, below descends at up to the descent limit; a quaternion that is not unit length
    or an ignored thrust stops the vehicle (here: a hold where it is). Roll and pitch become the
    horizontal acceleration g tan(angle) that lean would give (capped at 30 degrees), yaw the
    commanded heading; the lag loop and speed limit do the rest. None: not a number."""
    i, f = v.index, v.fleet
    mask = int(msg.type_mask)
    q = [float(x) for x in msg.q]
    if not _ok(*q, msg.thrust):
        return None
    hold = NeuSetpoint(
        t, (float(f.pos[i, 0]), float(f.pos[i, 1])), None, float(f.alt[i]), None, None
    )
    if mask & _THROTTLE_IGNORE:
        return hold
    roll = pitch = 0.0
    yaw: float | None = None
    if not mask & _ATTITUDE_IGNORE:
        w, x, y, z = q
        if abs(math.sqrt(w * w + x * x + y * y + z * z) - 1.0) > 1e-3:
            return hold
        roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
        pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
        yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    heading = float(f.yaw[i]) if yaw is None else yaw
    forward = -_G * math.tan(max(-_MAX_TILT, min(_MAX_TILT, pitch)))
    right = _G * math.tan(max(-_MAX_TILT, min(_MAX_TILT, roll)))
    c, s = math.cos(heading), math.sin(heading)
    accel = (forward * c - right * s, forward * s + right * c, 0.0)
    thrust = max(0.0, min(1.0, float(msg.thrust)))
    if thrust >= 0.5:
        climb = (thrust - 0.5) * 2.0 * float(f.climb[i])
    else:
        climb = -(0.5 - thrust) * 2.0 * float(f.descent[i])
    return NeuSetpoint(t, None, None, None, climb, yaw, None, accel)
