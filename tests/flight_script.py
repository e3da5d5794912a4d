"""One scripted flight, flown the same way against any ArduPilot or PX4 vehicle (the emulator's
persona or the real SITL), recording what the differential test compares: command results, the
sequence of modes, climb rate, cruise and top speed, and time to reach a position setpoint.

ArduPilot: GUIDED, arm, takeoff 20 m, 5 m/s north for 10 s, a position 150 m east, LOITER, RTL,
land. PX4 the same with its modes: arm, takeoff (TAKEOFF, then HOLD), OFFBOARD, the same two
setpoints, HOLD, RTL, land. Times are the vehicle's clock (time_boot_ms), so SITL speed-ups and
the emulator's speed-up do not matter.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass, field
from typing import Any

from mavlink_conformance.checks import mode_name

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil

ml = mavutil.mavlink
ALT = 20.0
CRUISE = 5.0
CRUISE_S = 10.0
LEG_EAST = 150.0
TOP_SPEED = 10.0
"""m/s: the horizontal speed limit both sides are set to (WPNAV_SPEED / MPC_XY_VEL_MAX)."""
READY_S = 120.0
"""Wall seconds a SITL may take to accept the first mode change / arming (GPS, EKF)."""


@dataclass
class Record:
    results: list[tuple[str, int]] = field(default_factory=list)
    modes: list[str] = field(default_factory=list)
    climb_rate: float = math.nan
    cruise_speed: float = math.nan
    """Median ground speed over the last 2 s of the 10 s velocity leg."""
    cruise_rise: float = math.nan
    """Vehicle s from the first velocity setpoint to 90 % of the cruise speed (reported only)."""
    top_speed: float = math.nan
    time_to_setpoint: float = math.nan
    landed_disarmed: bool = False


class Flight:
    """A pymavlink client flying one vehicle through the script."""

    def __init__(self, url: str, sysid: int, wall_timeout: float) -> None:
        self.conn: Any = mavutil.mavlink_connection(url, source_system=246, source_component=190)
        self.sysid = sysid
        self.wall_timeout = wall_timeout
        self.rec = Record()
        self.hb: Any = None
        self.gpi: Any = None
        self.lpn: Any = None
        self.home: tuple[float, float] = (0.0, 0.0)
        self._beat = 0.0

    def close(self) -> None:
        self.conn.close()

    # ----- reading
    def pump(self, seconds: float, until: Any = None) -> Any:
        end = time.monotonic() + seconds
        while (left := end - time.monotonic()) > 0:
            if time.monotonic() - self._beat > 0.5:
                self._beat = time.monotonic()
                self.conn.mav.heartbeat_send(ml.MAV_TYPE_GCS, ml.MAV_AUTOPILOT_INVALID, 0, 0, 0)
            m = self.conn.recv_match(blocking=True, timeout=min(left, 0.05))
            if m is None or m.get_srcSystem() != self.sysid or m.get_srcComponent() != 1:
                continue
            kind = m.get_type()
            if kind == "HEARTBEAT":
                self.hb = m
                name = mode_name(m) or f"{m.custom_mode:#x}"
                if not self.rec.modes or self.rec.modes[-1] != name:
                    self.rec.modes.append(name)
            elif kind == "GLOBAL_POSITION_INT":
                self.gpi = m
            elif kind == "LOCAL_POSITION_NED":
                self.lpn = m
            if until is not None and until(m):
                return m
        return None

    def wait(self, cond: Any, vehicle_s: float, what: str, send: Any = None) -> float:
        """Wait (streaming ``send`` at 40 Hz wall: 8-10 Hz of vehicle time at the speed-ups used)
        until ``cond()``; the vehicle time it took."""
        t0 = self.now()
        end = time.monotonic() + self.wall_timeout
        while not cond():
            if time.monotonic() > end or self.now() - t0 > vehicle_s:
                raise AssertionError(
                    f"{what}: not within {vehicle_s} vehicle s; modes {self.rec.modes}"
                )
            if send is not None:
                send()
            self.pump(0.025)
        return self.now() - t0

    def now(self) -> float:
        return self.gpi.time_boot_ms / 1000.0 if self.gpi is not None else 0.0

    @property
    def alt(self) -> float:
        return self.gpi.relative_alt / 1000.0 if self.gpi is not None else 0.0

    @property
    def armed(self) -> bool:
        return bool(self.hb is not None and self.hb.base_mode & ml.MAV_MODE_FLAG_SAFETY_ARMED)

    def ground_speed(self) -> float:
        return math.hypot(self.lpn.vx, self.lpn.vy) if self.lpn is not None else 0.0

    # ----- sending
    def command(self, name: str, cmd: int, *p: float, retry_s: float = 0.0) -> int:
        """COMMAND_LONG until acked (and, with ``retry_s``, until ACCEPTED or the time is up);
        the final result is recorded under ``name``."""
        params = [*p, *([0.0] * (7 - len(p)))]
        end = time.monotonic() + retry_s
        result = None
        while True:
            for _ in range(3):
                self.conn.mav.command_long_send(self.sysid, 1, cmd, 0, *params)
                ack = self.pump(
                    2.0,
                    lambda m: (
                        m.get_type() == "COMMAND_ACK"
                        and m.command == cmd
                        and m.target_system in (0, 246)
                    ),
                )
                if ack is not None:
                    result = int(ack.result)
                    break
            if result == 0 or time.monotonic() > end:
                break
            self.pump(1.0)
        assert result is not None, f"{name}: no COMMAND_ACK"
        self.rec.results.append((name, result))
        return result

    def set_param(self, name: str, value: float) -> None:
        for _ in range(5):
            self.conn.mav.param_set_send(
                self.sysid, 1, name.encode(), value, ml.MAV_PARAM_TYPE_REAL32
            )
            echo = self.pump(2.0, lambda m: m.get_type() == "PARAM_VALUE" and m.param_id == name)
            if echo is not None and abs(echo.param_value - value) < 1e-3:
                return
        raise AssertionError(f"PARAM_SET {name} = {value} not echoed")

    def velocity(self, vn: float, ve: float) -> None:
        self.conn.mav.set_position_target_local_ned_send(
            0, self.sysid, 1, ml.MAV_FRAME_LOCAL_NED, 3527, 0, 0, 0, vn, ve, 0, 0, 0, 0, 0, 0
        )

    def position(self, n: float, e: float, alt: float) -> None:
        self.conn.mav.set_position_target_local_ned_send(
            0, self.sysid, 1, ml.MAV_FRAME_LOCAL_NED, 3576, n, e, -alt, 0, 0, 0, 0, 0, 0, 0, 0
        )

    def mode(self, name: str, number: int, sub: int = 0, retry_s: float = 0.0) -> int:
        return self.command(name, ml.MAV_CMD_DO_SET_MODE, 1, number, sub, retry_s=retry_s)


def _streams(f: Flight) -> None:
    """Position streams at 10 Hz, once the vehicle has a position (a SITL's EKF takes a while)."""
    end = time.monotonic() + READY_S
    while f.gpi is None or f.lpn is None:
        assert time.monotonic() < end, "no position streams"
        for msg_id in (ml.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, ml.MAVLINK_MSG_ID_LOCAL_POSITION_NED):
            f.conn.mav.command_long_send(f.sysid, 1, 511, 0, msg_id, 100_000, 0, 0, 0, 0, 0)
        f.pump(2.0)


def _climb(f: Flight) -> None:
    """Takeoff climb: the mean rate between 25 % and 75 % of the altitude."""
    f.wait(lambda: f.alt >= 0.25 * ALT, 60.0, "takeoff start")
    t0, a0 = f.now(), f.alt
    f.wait(lambda: f.alt >= 0.75 * ALT, 60.0, "takeoff climb")
    f.rec.climb_rate = (f.alt - a0) / max(f.now() - t0, 1e-3)
    f.wait(lambda: f.alt >= ALT - 0.5, 60.0, "takeoff altitude")


def _legs(f: Flight) -> None:
    """5 m/s north for 10 s, then a position 150 m east of where that ends."""
    speeds: list[float] = []
    t0 = f.now()

    def cruise() -> None:
        f.velocity(CRUISE, 0.0)
        speed = f.ground_speed()
        if speed >= 0.9 * CRUISE and math.isnan(f.rec.cruise_rise):
            f.rec.cruise_rise = f.now() - t0
        if f.now() - t0 > CRUISE_S - 2.0:
            speeds.append(speed)

    f.wait(lambda: f.now() - t0 >= CRUISE_S, CRUISE_S + 5.0, "velocity leg", cruise)
    f.rec.cruise_speed = sorted(speeds)[len(speeds) // 2] if speeds else math.nan
    target = (f.lpn.x, f.lpn.y + LEG_EAST)
    top = [0.0]

    def go() -> None:
        f.position(*target, ALT)
        top[0] = max(top[0], f.ground_speed())

    def there() -> bool:
        return math.hypot(f.lpn.x - target[0], f.lpn.y - target[1]) < 2.0

    f.rec.time_to_setpoint = f.wait(there, 90.0, "position setpoint", go)
    f.rec.top_speed = top[0]


def _home_then_land(f: Flight) -> None:
    f.command("rtl", ml.MAV_CMD_NAV_RETURN_TO_LAUNCH)
    f.wait(lambda: math.hypot(f.lpn.x - f.home[0], f.lpn.y - f.home[1]) < 3.0, 120.0, "RTL home")
    f.command("land", ml.MAV_CMD_NAV_LAND)
    f.wait(lambda: not f.armed, 120.0, "landed and disarmed")
    f.rec.landed_disarmed = True


def fly_ardupilot(f: Flight) -> Record:
    _streams(f)
    f.set_param("WPNAV_SPEED", TOP_SPEED * 100.0)
    f.mode("guided", 4, retry_s=READY_S)
    f.command("arm", ml.MAV_CMD_COMPONENT_ARM_DISARM, 1, retry_s=READY_S)
    f.home = (f.lpn.x, f.lpn.y)
    f.command("takeoff", ml.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, ALT)
    _climb(f)
    _legs(f)
    f.mode("loiter", 5)
    f.pump(2.0)
    _home_then_land(f)
    return f.rec


def fly_px4(f: Flight, home_amsl: float) -> Record:
    _streams(f)
    f.set_param("MPC_XY_VEL_MAX", TOP_SPEED)
    f.set_param("RTL_RETURN_ALT", ALT)
    f.command("arm", ml.MAV_CMD_COMPONENT_ARM_DISARM, 1, retry_s=READY_S)
    f.home = (f.lpn.x, f.lpn.y)
    f.command(
        "takeoff",
        ml.MAV_CMD_NAV_TAKEOFF,
        math.nan,
        0,
        0,
        math.nan,
        math.nan,
        math.nan,
        home_amsl + ALT,
    )
    _climb(f)
    f.pump(2.0)  # TAKEOFF ends in HOLD
    hold = (f.lpn.x, f.lpn.y)
    for _ in range(20):  # PX4 takes OFFBOARD only once setpoints stream
        f.position(*hold, ALT)
        f.pump(0.05)
    f.mode("offboard", 6)
    _legs(f)
    f.mode("hold", 4, 3)
    f.pump(2.0)
    _home_then_land(f)
    return f.rec
