"""Outgoing messages of a vehicle: what each stream carries and at which sim-time rate."""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from sim_vehicle_stub.fast_streams import ATT, GPI, LPN, WireLayout, att_rows, gpi_rows, lpn_rows
from sim_vehicle_stub.fleet_kinematics import Fleet
from sim_vehicle_stub.geo_frame import GeoFrame
from sim_vehicle_stub.mavlink import dialect as d
from sim_vehicle_stub.personas.base import Behaviour
from sim_vehicle_stub.sim_clock import SimClock
from sim_vehicle_stub.vehicle import Vehicle

# Sensors reported present, enabled and healthy: gyro, accel, mag, baro, GPS, motors, AHRS,
# battery and the pre-arm check bit that MAVSDK reads for health.
SENSOR_BITS = 0x1 | 0x2 | 0x4 | 0x8 | 0x20 | 0x8000 | 0x200000 | 0x2000000 | 0x10000000

GEOFENCE = d.MAV_SYS_STATUS_GEOFENCE

DEFAULT_RATES: dict[int, float] = {
    d.MAVLINK_MSG_ID_HEARTBEAT: 1.0,
    d.MAVLINK_MSG_ID_SYS_STATUS: 1.0,
    d.MAVLINK_MSG_ID_SYSTEM_TIME: 1.0,
    d.MAVLINK_MSG_ID_BATTERY_STATUS: 1.0,
    d.MAVLINK_MSG_ID_EXTENDED_SYS_STATE: 1.0,
    d.MAVLINK_MSG_ID_GPS_RAW_INT: 1.0,
    d.MAVLINK_MSG_ID_HOME_POSITION: 0.2,
    d.MAVLINK_MSG_ID_GLOBAL_POSITION_INT: 10.0,
    d.MAVLINK_MSG_ID_LOCAL_POSITION_NED: 10.0,
    d.MAVLINK_MSG_ID_ATTITUDE: 10.0,
    d.MAVLINK_MSG_ID_MISSION_CURRENT: 1.0,
    d.MAVLINK_MSG_ID_VFR_HUD: 1.0,
}
"""Hz of sim time; SET_MESSAGE_INTERVAL changes them per vehicle."""
ON_REQUEST_RATE = 1.0
"""Hz of a stream that is off by default when a client sets its interval to 0 (default)."""
DATA_STREAMS: dict[int, tuple[int, ...]] = {
    d.MAV_DATA_STREAM_EXTENDED_STATUS: (
        d.MAVLINK_MSG_ID_SYS_STATUS,
        d.MAVLINK_MSG_ID_GPS_RAW_INT,
        d.MAVLINK_MSG_ID_MISSION_CURRENT,
    ),
    d.MAV_DATA_STREAM_RC_CHANNELS: (
        d.MAVLINK_MSG_ID_SERVO_OUTPUT_RAW,
        d.MAVLINK_MSG_ID_RC_CHANNELS,
    ),
    d.MAV_DATA_STREAM_POSITION: (
        d.MAVLINK_MSG_ID_GLOBAL_POSITION_INT,
        d.MAVLINK_MSG_ID_LOCAL_POSITION_NED,
    ),
    d.MAV_DATA_STREAM_EXTRA1: (d.MAVLINK_MSG_ID_ATTITUDE,),
    d.MAV_DATA_STREAM_EXTRA2: (d.MAVLINK_MSG_ID_VFR_HUD,),
    d.MAV_DATA_STREAM_EXTRA3: (
        d.MAVLINK_MSG_ID_SYSTEM_TIME,
        d.MAVLINK_MSG_ID_BATTERY_STATUS,
    ),
}
"""ArduPilot's REQUEST_DATA_STREAM groups (GCS_MAVLink ap_message lists), the messages the
emulator has of each; MAV_DATA_STREAM_ALL (0) is all of them."""


def _message(cls: Any, args: Callable[[Vehicle], tuple[Any, ...]], v: Vehicle) -> Any:
    return cls(*args(v))


@dataclass
class GeoCache:
    """WGS84 positions of all vehicles at one sim time (converted once per tick, when asked)."""

    t: float = -1.0
    lat: Any = None
    lon: Any = None
    amsl: Any = None


@dataclass
class AttitudeCache:
    """Roll and pitch of all vehicles at one sim time."""

    t: float = -1.0
    roll: Any = None
    pitch: Any = None


class PositionRows(dict[int, list[bytes]]):
    """Payloads of the 10 Hz position/attitude messages of every vehicle at one sim time, each
    message packed for the whole fleet when first asked for: a fleet whose clients switched
    GLOBAL_POSITION_INT and ATTITUDE off never converts to WGS84 nor computes an attitude."""

    def __init__(self, telemetry: Telemetry) -> None:
        super().__init__()
        self.telemetry = telemetry

    def __missing__(self, msg_id: int) -> list[bytes]:
        tel, f = self.telemetry, self.telemetry.fleet
        boot_ms = tel.clock.boot_ms
        if msg_id == GPI:
            c = tel._geodetic()
            rows = gpi_rows(f, boot_ms, c.lat, c.lon, c.amsl)
        elif msg_id == LPN:
            rows = lpn_rows(f, boot_ms, tel.origins)
        elif msg_id == ATT:
            a = tel._attitude()
            rows = att_rows(f, boot_ms, a.roll, a.pitch)
        else:
            raise KeyError(msg_id)
        self[msg_id] = rows
        return rows


class Telemetry:
    """Builds messages from the shared state; one instance serves every vehicle."""

    def __init__(self, fleet: Fleet, geo: GeoFrame, clock: SimClock, epoch_usec: int) -> None:
        self.fleet = fleet
        self.geo = geo
        self.clock = clock
        self.epoch_usec = epoch_usec
        self._geo = GeoCache()
        self._att = AttitudeCache()
        self._batch = PositionRows(self)
        self._batch_t = -1.0
        home = fleet.pos.copy()
        self.origins = home
        """Each vehicle's local origin (where it booted) in the profile's frame, (n, 2)."""
        lat, lon, _ = geo.to_geodetic(home[:, 0], home[:, 1], np.zeros(len(home)))
        self._home_geo = (np.atleast_1d(lat), np.atleast_1d(lon))
        self.args: dict[int, Callable[[Vehicle], tuple[Any, ...]]] = {
            d.MAVLINK_MSG_ID_HEARTBEAT: self.heartbeat_args,
            d.MAVLINK_MSG_ID_SYS_STATUS: self.sys_status_args,
            d.MAVLINK_MSG_ID_SYSTEM_TIME: self.system_time_args,
            d.MAVLINK_MSG_ID_BATTERY_STATUS: self.battery_status_args,
            d.MAVLINK_MSG_ID_EXTENDED_SYS_STATE: self.extended_sys_state_args,
            d.MAVLINK_MSG_ID_GPS_RAW_INT: self.gps_raw_int_args,
            d.MAVLINK_MSG_ID_HOME_POSITION: self.home_position_args,
            d.MAVLINK_MSG_ID_VFR_HUD: self.vfr_hud_args,
            d.MAVLINK_MSG_ID_MISSION_CURRENT: self.mission_current_args,
            d.MAVLINK_MSG_ID_RC_CHANNELS: self.rc_channels_args,
            d.MAVLINK_MSG_ID_SERVO_OUTPUT_RAW: self.servo_output_raw_args,
        }
        """Constructor arguments of the 1 Hz streams' messages: packed by :attr:`layouts` every
        tick, or made into message objects by :attr:`builders` when asked for."""
        self.layouts = {k: WireLayout(d.mavlink_map[k]) for k in self.args}
        self.builders: dict[int, Callable[[Vehicle], Any]] = {
            k: functools.partial(_message, d.mavlink_map[k], args) for k, args in self.args.items()
        }
        self.builders.update(
            {
                d.MAVLINK_MSG_ID_GLOBAL_POSITION_INT: self.global_position_int,
                d.MAVLINK_MSG_ID_LOCAL_POSITION_NED: self.local_position_ned,
                d.MAVLINK_MSG_ID_ATTITUDE: self.attitude,
                d.MAVLINK_MSG_ID_AUTOPILOT_VERSION: self.autopilot_version,
                d.MAVLINK_MSG_ID_GPS_GLOBAL_ORIGIN: self.gps_global_origin,
            }
        )

    def _geodetic(self) -> GeoCache:
        c = self._geo
        if c.t != self.clock.now:
            f = self.fleet
            c.lat, c.lon, _ = self.geo.to_geodetic(f.pos[:, 0], f.pos[:, 1], f.alt)
            c.lat, c.lon = np.atleast_1d(c.lat), np.atleast_1d(c.lon)
            # Altitude AMSL is home's plus the height above it, as a real autopilot reports it
            # over flat SITL terrain; the tangent plane's curvature drop (d^2 / 2R, 9 m at
            # 11 km) would make far vehicles' AMSL disagree with what they are commanded.
            c.amsl = self.geo.alt + f.alt
            c.t = self.clock.now
        return c

    def _attitude(self) -> AttitudeCache:
        a = self._att
        if a.t != self.clock.now:
            a.roll, a.pitch = self.fleet.attitude()
            a.t = self.clock.now
        return a

    def position_batch(self) -> PositionRows:
        """Payloads of the 10 Hz position/attitude messages for every vehicle, now (each
        message packed on first use)."""
        if self._batch_t != self.clock.now:
            self._batch = PositionRows(self)
            self._batch_t = self.clock.now
        return self._batch

    def heartbeat(self, v: Vehicle) -> Any:
        return d.MAVLink_heartbeat_message(*self.heartbeat_args(v))

    def heartbeat_args(self, v: Vehicle) -> tuple[Any, ...]:
        base = d.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
        if v.armed:
            base |= d.MAV_MODE_FLAG_SAFETY_ARMED
        if v.mode.behaviour is Behaviour.EXTERNAL:
            base |= d.MAV_MODE_FLAG_GUIDED_ENABLED
        status = d.MAV_STATE_ACTIVE if v.armed else d.MAV_STATE_STANDBY
        return (d.MAV_TYPE_QUADROTOR, v.persona.autopilot, base, v.mode.custom_mode, status, 3)

    def sys_status_args(self, v: Vehicle) -> tuple[Any, ...]:
        pct = round(v.battery * 100)
        present = enabled = health = SENSOR_BITS
        if v.persona.reports_geofence:
            # ArduPilot: present always, enabled with the fence, healthy unless breached.
            present |= GEOFENCE
            enabled |= GEOFENCE if v.limits.fence_rules is not None else 0
            health |= 0 if v.fence_breached else GEOFENCE
        return (
            present, enabled, health, 100, self._voltage_mv(v), 500, pct,
            0, 0, 0, 0, 0, 0, 0, 0, 0,
        )  # fmt: skip

    @staticmethod
    def _voltage_mv(v: Vehicle) -> int:
        return int(4 * (3500 + 700 * v.battery))

    def system_time_args(self, v: Vehicle) -> tuple[Any, ...]:
        return (self.epoch_usec + self.clock.usec, self.clock.boot_ms)

    def battery_status_args(self, v: Vehicle) -> tuple[Any, ...]:
        volts = [self._voltage_mv(v)] + [65535] * 9
        used = int((1.0 - v.battery) * 5200)
        return (0, 0, 1, 32767, volts, 500, used, -1, round(v.battery * 100))

    def extended_sys_state_args(self, v: Vehicle) -> tuple[Any, ...]:
        i = v.index
        if v.landed:
            state = d.MAV_LANDED_STATE_ON_GROUND
        elif self.fleet.vz[i] < -0.2 and v.mode.behaviour in (Behaviour.LAND, Behaviour.RTL):
            state = d.MAV_LANDED_STATE_LANDING
        elif v.takeoff_alt is not None:
            state = d.MAV_LANDED_STATE_TAKEOFF
        else:
            state = d.MAV_LANDED_STATE_IN_AIR
        return (d.MAV_VTOL_STATE_UNDEFINED, state)

    def gps_raw_int_args(self, v: Vehicle) -> tuple[Any, ...]:
        c, i, f = self._geodetic(), v.index, self.fleet
        speed = float(np.hypot(*f.vel[i]))
        cog = math.degrees(math.atan2(f.vel[i, 1], f.vel[i, 0])) % 360.0
        return (
            self.clock.usec, 3, int(c.lat[i] * 1e7), int(c.lon[i] * 1e7), int(c.amsl[i] * 1000),
            80, 120, int(speed * 100), int(cog * 100), 14,
        )  # fmt: skip

    def home_position_args(self, v: Vehicle) -> tuple[Any, ...]:
        lat, lon = self.home_geo(v)[:2]
        hn, he = v.home[0] - v.origin[0], v.home[1] - v.origin[1]
        return (
            int(lat * 1e7), int(lon * 1e7), round(self.geo.alt * 1000), hn, he, 0.0, [1.0, 0.0, 0.0, 0.0],
            0.0, 0.0, 0.0, self.clock.usec,
        )  # fmt: skip

    def home_geo(self, v: Vehicle) -> tuple[float, float, float]:
        """(lat, lon, alt AMSL) of the vehicle's home."""
        if v.home == v.origin:
            lat, lon = (float(a[v.index]) for a in self._home_geo)
        else:
            la, lo, _ = self.geo.to_geodetic(np.array(v.home[0]), np.array(v.home[1]), np.zeros(()))
            lat, lon = float(la), float(lo)
        return lat, lon, self.geo.alt

    def gps_global_origin(self, v: Vehicle) -> Any:
        """The local frame's origin: where the vehicle booted (its first home)."""
        lat, lon = (float(a[v.index]) for a in self._home_geo)
        return d.MAVLink_gps_global_origin_message(
            int(lat * 1e7), int(lon * 1e7), round(self.geo.alt * 1000), self.clock.usec
        )

    def mission_current_args(self, v: Vehicle) -> tuple[Any, ...]:
        return v.mission_run.current_args()

    def vfr_hud_args(self, v: Vehicle) -> tuple[Any, ...]:
        i, f = v.index, self.fleet
        speed = float(np.hypot(*f.vel[i]))
        hdg = int(math.degrees(float(f.yaw[i])) % 360.0)
        throttle = 0 if not v.armed else 50
        return (speed, speed, hdg, throttle, float(self.geo.alt + f.alt[i]), float(f.vz[i]))

    def rc_channels_args(self, v: Vehicle) -> tuple[Any, ...]:
        """The pilot's sticks as PWM (AETR), 1500 centred; throttle 1000 without a pilot."""
        s = v.pilot.sticks
        if s is None:
            pwm = [1500, 1500, 1000, 1500]
        else:
            pwm = [round(1500 + 500 * s.right), round(1500 - 500 * s.forward),
                   round(1500 + 500 * s.up), round(1500 + 500 * s.yaw)]  # fmt: skip
        return (self.clock.boot_ms, 16, *pwm, *([1500] * 14), 255)

    def servo_output_raw_args(self, v: Vehicle) -> tuple[Any, ...]:
        """Four motors at idle (1000) disarmed, near hover (1500) armed."""
        out = 1000 if not v.armed or v.landed else 1500
        return (self.clock.usec % 2**32, 0, out, out, out, out, 0, 0, 0, 0)

    def global_position_int(self, v: Vehicle) -> Any:
        c, i, f = self._geodetic(), v.index, self.fleet
        hdg = int(math.degrees(f.yaw[i]) % 360.0 * 100)
        return d.MAVLink_global_position_int_message(
            self.clock.boot_ms, int(c.lat[i] * 1e7), int(c.lon[i] * 1e7), int(c.amsl[i] * 1000),
            int(f.alt[i] * 1000), int(f.vel[i, 0] * 100), int(f.vel[i, 1] * 100),
            int(-f.vz[i] * 100), hdg,
        )  # fmt: skip

    def local_position_ned(self, v: Vehicle) -> Any:
        i, f = v.index, self.fleet
        return d.MAVLink_local_position_ned_message(
            self.clock.boot_ms, f.pos[i, 0] - v.origin[0], f.pos[i, 1] - v.origin[1], -f.alt[i],
            f.vel[i, 0], f.vel[i, 1], -f.vz[i],
        )  # fmt: skip

    def attitude(self, v: Vehicle) -> Any:
        a, i = self._attitude(), v.index
        roll, pitch = a.roll, a.pitch
        yaw = math.remainder(float(self.fleet.yaw[i]), 2 * math.pi)
        return d.MAVLink_attitude_message(
            self.clock.boot_ms, float(roll[i]), float(pitch[i]), yaw, 0.0, 0.0, 0.0
        )

    def autopilot_version(self, v: Vehicle) -> Any:
        """The persona's real capabilities (less what the emulator lacks: FTP, terrain, flight
        termination, compass calibration) and firmware version, measured on its SITL."""
        p = v.persona
        return d.MAVLink_autopilot_version_message(
            p.capabilities, p.firmware_version, 0, 0, 0, [0] * 8, [0] * 8, [0] * 8, 0, 0, v.sysid
        )


STREAMABLE = frozenset(
    (
        *DEFAULT_RATES,
        d.MAVLINK_MSG_ID_AUTOPILOT_VERSION,
        d.MAVLINK_MSG_ID_RC_CHANNELS,
        d.MAVLINK_MSG_ID_SERVO_OUTPUT_RAW,
        d.MAVLINK_MSG_ID_GPS_GLOBAL_ORIGIN,
    )
)
"""Messages a client may give an interval (the default streams and those sent on request)."""


class StreamSchedule:
    """Per-vehicle message intervals (sim s) and next due times."""

    def __init__(self, unasked_off: frozenset[int] = frozenset()) -> None:
        """``unasked_off``: default streams this vehicle sends only once a client asks."""
        self.interval = {k: 1.0 / hz for k, hz in DEFAULT_RATES.items() if k not in unasked_off}
        self.next_due = dict.fromkeys(self.interval, 0.0)

    def streams(self, msg_id: int) -> bool:
        """Whether ``msg_id`` is streamed now (by default or because a client asked)."""
        return msg_id in self.interval

    def set_interval(self, msg_id: int, interval_us: float) -> bool:
        """SET_MESSAGE_INTERVAL semantics: -1 off, 0 default, else microseconds."""
        if msg_id not in STREAMABLE:
            return False
        if interval_us == 0:
            self.interval[msg_id] = 1.0 / DEFAULT_RATES.get(msg_id, ON_REQUEST_RATE)
        elif interval_us < 0:
            self.interval.pop(msg_id, None)
            self.next_due.pop(msg_id, None)
            return True
        else:
            self.interval[msg_id] = max(interval_us * 1e-6, 1e-3)
        self.next_due.setdefault(msg_id, 0.0)
        return True

    def request_data_stream(self, stream: int, rate_hz: int, start: bool) -> None:
        """REQUEST_DATA_STREAM as ArduPilot: the group's messages at ``rate_hz`` (its own
        rate); a stop, or a rate of 0, switches them off. HEARTBEAT is in no group."""
        groups = (
            DATA_STREAMS.values()
            if stream == d.MAV_DATA_STREAM_ALL
            else (DATA_STREAMS.get(stream, ()),)
        )
        for ids in groups:
            for msg_id in ids:
                if start and rate_hz > 0:
                    self.set_interval(msg_id, 1e6 / min(rate_hz, 50))
                else:
                    self.set_interval(msg_id, -1)

    def due(self, t: float) -> list[int]:
        out = []
        now = t + 1e-9
        interval, next_due = self.interval, self.next_due
        for k, nxt in next_due.items():
            if now >= nxt:
                out.append(k)
                later = nxt + interval[k]
                next_due[k] = later if later > t else t
        return out
