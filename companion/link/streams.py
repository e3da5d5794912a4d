"""The messages the companion needs from its vehicle, how fast, and a watch on what arrives.

A stock ArduCopter sends only HEARTBEAT, SYS_STATUS and TIMESYNC until a client asks
(../shared/sitl/README.md); PX4 and the emulator stream positions by default. The link first
looks at what already arrives and asks only for what is missing or too slow, so a vehicle (or a
ground station sharing the link) keeps its own configuration where it already suffices.
"""

from __future__ import annotations

import time
from collections import deque
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink2


@dataclass(frozen=True)
class StreamNeed:
    """One message the mission reads."""

    name: str
    msg_id: int
    rate_hz: float
    """Vehicle-time rate the mission needs; slower counts as missing (0: any rate)."""
    data_stream: int
    """MAV_DATA_STREAM_* group that carries it, for autopilots that ignore SET_MESSAGE_INTERVAL."""

    def interval_us(self) -> float:
        return 1e6 / self.rate_hz if self.rate_hz > 0 else 1e6


POSITION_RATE_HZ = 10.0
"""The decision loop answers every position; 10 Hz is the emulator's default and the paper's
control period scale (tau = 0.33 s)."""


FENCE_WATCH_RATE_HZ = 2.0
"""GLOBAL_POSITION_INT for the fence watch: at 10 m/s a breach is seen within 5 m."""


def needs(*, global_position: bool) -> tuple[StreamNeed, ...]:
    """What the mission reads: LOCAL_POSITION_NED (the decision loop), SYS_STATUS (health,
    battery) and, for a geo-referenced profile, GLOBAL_POSITION_INT (the fence watch)."""
    position = StreamNeed(
        "LOCAL_POSITION_NED",
        mavlink2.MAVLINK_MSG_ID_LOCAL_POSITION_NED,
        POSITION_RATE_HZ,
        mavlink2.MAV_DATA_STREAM_POSITION,
    )
    status = StreamNeed(
        "SYS_STATUS",
        mavlink2.MAVLINK_MSG_ID_SYS_STATUS,
        0.0,
        mavlink2.MAV_DATA_STREAM_EXTENDED_STATUS,
    )
    if not global_position:
        return (position, status)
    gps = StreamNeed(
        "GLOBAL_POSITION_INT",
        mavlink2.MAVLINK_MSG_ID_GLOBAL_POSITION_INT,
        FENCE_WATCH_RATE_HZ,
        mavlink2.MAV_DATA_STREAM_POSITION,
    )
    return (position, status, gps)


class StreamWatch:
    """Recent arrivals per message name: vehicle time where the message carries one."""

    def __init__(self, keep: int = 12) -> None:
        self._times: dict[str, deque[float]] = {}
        self._wall: dict[str, float] = {}
        self._keep = keep

    def note(self, name: str, vehicle_time: float | None = None) -> None:
        now = time.monotonic()
        self._wall[name] = now
        if vehicle_time is not None:
            times = self._times.get(name)
            if times is None:  # (not setdefault: that builds a deque on every call)
                times = self._times[name] = deque(maxlen=self._keep)
            times.append(vehicle_time)

    def seen_since(self, name: str, since: float) -> bool:
        """Arrived after ``since`` (time.monotonic)."""
        return self._wall.get(name, -1.0) >= since

    def rate(self, name: str) -> float | None:
        """Vehicle-time rate over the recent arrivals, None with fewer than three."""
        times = self._times.get(name)
        if times is None or len(times) < 3 or times[-1] <= times[0]:
            return None
        return (len(times) - 1) / (times[-1] - times[0])

    def clear(self, name: str) -> None:
        self._times.pop(name, None)
        self._wall.pop(name, None)

    def satisfied(self, need: StreamNeed, since: float) -> bool:
        """Arriving (after ``since``) at 80 % of the needed rate or better."""
        if not self.seen_since(need.name, since):
            return False
        if need.rate_hz <= 0:
            return True
        rate = self.rate(need.name)
        return rate is not None and rate >= 0.8 * need.rate_hz
