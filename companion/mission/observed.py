"""What one mission has observed of its vehicle: the last messages of each kind, the vehicle's
clock and position period, and the times the decision loop steers by. Written by the event
intake (and the search's common answer); read by the lifecycle's steps, the failsafes and the
snapshot."""

from __future__ import annotations

import math

from companion.link.messages import GlobalPosition, Heartbeat, LocalPosition, SystemStatus
from companion.mission.battery_reserve import DrainMeter
from companion.mission.vehicle_clock import VehicleClock


class Observed:
    """The vehicle as the mission last saw it; times are vehicle seconds unless named wall."""

    def __init__(self, clock: VehicleClock, search_start: float | None) -> None:
        self.clock = clock
        """The vehicle's mission clock (vehicle_clock.py)."""
        self.heartbeat: Heartbeat | None = None
        self.last_heartbeat_wall = 0.0
        """``time.perf_counter()`` of the last HEARTBEAT (the link supervision's measure)."""
        self.position: LocalPosition | None = None
        self.status: SystemStatus | None = None
        self.gps: GlobalPosition | None = None
        self.home: tuple[float, float] | None = None
        """Where the vehicle was first seen on the ground (profile frame)."""
        self.period = 0.1
        """The positions' period (vehicle s), smoothed: the pursuit's look-ahead."""
        self.last_tick = -math.inf
        """Mission time of the last ``tick`` record."""
        self.received_time = -math.inf
        """Vehicle time of the newest position received (acted on or not)."""
        self.setpoint_time = -math.inf
        """Vehicle time of the position our last setpoint answered."""
        self.search_start = search_start
        """Mission time the search began (None: not yet)."""
        self.max_search_speed = 0.0
        """Fastest horizontal speed the vehicle reported while searching, m/s."""
        self.flew = False
        """The vehicle was seen more than 1 m up in this run."""
        self.drain = DrainMeter()
        self.return_speed: float | None = None
        """m/s the autopilot's own return flies (read before arming; None: not known)."""
        """The battery's drain in this flight (the reserve rule's measure)."""

    def note_received(self, vehicle_time: float) -> None:
        """A position of ``vehicle_time`` came in (whether or not it is acted on)."""
        self.received_time = max(self.received_time, vehicle_time)

    def note_position(self, pos: LocalPosition) -> float:
        """The vehicle's clock, period and position from ``pos``; its mission time."""
        self.note_received(pos.time)
        prev = self.position
        t = self.clock.update(pos.time)
        if self.home is None and -pos.down < 1.0:
            self.home = (pos.north, pos.east)
        self.flew |= -pos.down > 1.0
        if prev is not None and pos.time > prev.time:
            self.period += 0.2 * (min(pos.time - prev.time, 1.0) - self.period)
        self.position = pos
        return t

    def note_search_speed(self, pos: LocalPosition) -> None:
        """``pos`` was flown while searching: keep the fastest horizontal speed."""
        self.max_search_speed = max(self.max_search_speed, math.hypot(pos.vn, pos.ve))

    def begin_search(self, t: float) -> None:
        """The search begins at mission time ``t`` (kept when it began before a restart)."""
        if self.search_start is None:
            self.search_start = t

    def forget_gps(self) -> None:
        """Wait for a GPS position newer than now (one taken once the origin is known)."""
        self.gps = None
