"""A pilot's sticks from a ground station: MANUAL_CONTROL and RC_CHANNELS_OVERRIDE.

In the persona's pilot modes (ArduCopter STABILIZE, ALT_HOLD, LOITER, POSHOLD; PX4 MANUAL,
ALTCTL, POSCTL) the sticks fly the vehicle as a position-mode pilot does: pitch and roll ask
for a horizontal velocity in the heading's frame (full stick: the speed limit), throttle above
or below its centre for a climb or descent (full: the climb or descent limit), yaw for a turn
rate. Centred sticks, or none within the persona's RC time-out (RC_OVERRIDE_TIME /
COM_RC_LOSS_T), hold the position, as LOITER and POSCTL do. The attitude modes are flown the
same way (the lag model has no attitude loop): a simplification named in docs/protocol.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from sim_vehicle_stub.vehicle import Vehicle

YAW_RATE = math.radians(90.0)
"""Turn rate at full yaw stick, rad/s."""
_UNUSED = 32767
"""MANUAL_CONTROL: INT16_MAX marks an axis as not sent."""
_RELEASE = (0, 65535)
"""RC_CHANNELS_OVERRIDE: 0 releases a channel, UINT16_MAX leaves it alone."""
_DEADBAND = 0.05


@dataclass(frozen=True)
class Sticks:
    """Stick positions, each -1..1: forward (pitch), right (roll), up (throttle about its
    centre) and yaw (clockwise)."""

    forward: float
    right: float
    up: float
    yaw: float

    @property
    def centred(self) -> bool:
        return max(abs(self.forward), abs(self.right), abs(self.up), abs(self.yaw)) < _DEADBAND


def _axis(value: float, centre: float, span: float) -> float:
    if not math.isfinite(value):
        return 0.0
    x = (value - centre) / span
    x = max(-1.0, min(1.0, x))
    return 0.0 if abs(x) < _DEADBAND else x


def manual_sticks(msg: Any) -> Sticks | None:
    """MANUAL_CONTROL: x pitch (+ forward), y roll (+ right), r yaw, -1000..1000; z throttle
    0..1000 with 500 the hover centre (MAVSDK, QGroundControl). None: nothing usable."""
    x, y, z, r = (int(msg.x), int(msg.y), int(msg.z), int(msg.r))
    if all(a == _UNUSED for a in (x, y, z, r)):
        return None
    return Sticks(
        _axis(0 if x == _UNUSED else x, 0.0, 1000.0),
        _axis(0 if y == _UNUSED else y, 0.0, 1000.0),
        _axis(500 if z == _UNUSED else z, 500.0, 500.0),
        _axis(0 if r == _UNUSED else r, 0.0, 1000.0),
    )


def override_sticks(msg: Any) -> Sticks | None:
    """RC_CHANNELS_OVERRIDE channels 1-4 (ArduPilot's AETR order: roll, pitch, throttle, yaw;
    PWM 1000-2000, pitch low = forward). None: every one of them released."""
    chans = [int(msg.chan1_raw), int(msg.chan2_raw), int(msg.chan3_raw), int(msg.chan4_raw)]
    if all(c in _RELEASE for c in chans):
        return None
    roll, pitch, throttle, yaw = (1500 if c in _RELEASE else c for c in chans)
    return Sticks(
        -_axis(pitch, 1500.0, 500.0),
        _axis(roll, 1500.0, 500.0),
        _axis(throttle, 1500.0, 500.0),
        _axis(yaw, 1500.0, 500.0),
    )


class Pilot:
    """The latest sticks of one vehicle and when they came (sim s)."""

    def __init__(self) -> None:
        self.sticks: Sticks | None = None
        self.t = -math.inf
        self.flying = False
        """The sticks moved the vehicle at the last tick (released: it stops and holds)."""

    def take(self, sticks: Sticks, t: float) -> None:
        self.sticks, self.t = sticks, t

    def current(self, now: float, timeout: float) -> Sticks | None:
        """The sticks, or None when none came within ``timeout`` sim s."""
        if self.sticks is None or now - self.t > timeout:
            return None
        return self.sticks


def fly_sticks(v: Vehicle) -> None:
    """One tick of a pilot mode: the sticks' velocity, climb and turn, or a hold once they are
    centred or timed out. On the ground only a climb (throttle up) starts anything."""
    pilot = v.pilot
    i, f = v.index, v.fleet
    if not v.armed:
        pilot.flying = False  # motors off: the vehicle falls (Vehicle._fall), no hold
        return
    sticks = pilot.current(v.now, v.limits.sticks)
    if sticks is None or sticks.centred:
        if pilot.flying:
            pilot.flying = False
            f.hold(i)
            f.yaw_rate[i] = math.nan
        return
    if v.landed and sticks.up <= 0:
        return
    v.auto_armed = True
    pilot.flying = True
    c, s = math.cos(float(f.yaw[i])), math.sin(float(f.yaw[i]))
    speed = float(f.speed[i])
    fwd, right = sticks.forward * speed, sticks.right * speed
    f.fly_velocity(i, fwd * c - right * s, fwd * s + right * c)
    rate = sticks.up * (float(f.climb[i]) if sticks.up > 0 else float(f.descent[i]))
    f.climb_rate(i, rate)
    f.yaw_cmd[i] = math.nan
    f.yaw_rate[i] = sticks.yaw * YAW_RATE if sticks.yaw else math.nan
    v.takeoff_alt = None
