"""AUTO (ArduCopter) / AUTO.MISSION (PX4): flying the stored mission with the paper's dynamics.

Each navigation item becomes a target of the shared tau-lag loop (``Fleet.go_to`` /
``climb_to``): the vehicle pursues it at the speed limit and slows within 4 tau v of it, as for
a position setpoint. An item is reached within its acceptance radius (param2, else the persona's
parameter: WPNAV_RADIUS / NAV_ACC_RAD) horizontally and 1 m vertically; MISSION_ITEM_REACHED
goes out then, and the vehicle holds there for the item's hold time before the next. Items:
NAV_TAKEOFF, NAV_WAYPOINT, NAV_LOITER_TIME, NAV_LOITER_UNLIM, NAV_RETURN_TO_LAUNCH, NAV_LAND,
DO_CHANGE_SPEED, DO_JUMP; other DO_/CONDITION_ items are stepped over. After the last item the
vehicle holds where it is (both autopilots loiter at the end of a mission).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from sim_vehicle_stub.mavlink import dialect as d
from sim_vehicle_stub.personas.mission_rules import GLOBAL_FRAMES

if TYPE_CHECKING:
    from sim_vehicle_stub.mission_store import MissionItem
    from sim_vehicle_stub.vehicle import Vehicle

NOT_STARTED, ACTIVE, COMPLETE, NO_MISSION = (
    d.MISSION_STATE_NOT_STARTED,
    d.MISSION_STATE_ACTIVE,
    d.MISSION_STATE_COMPLETE,
    d.MISSION_STATE_NO_MISSION,
)
_RELATIVE = (3, 6, 10, 11)
_VERTICAL_ACCEPT = 1.0
"""Metres of altitude error within which a waypoint counts as reached."""
_TAKEOFF_ACCEPT = 0.3
_REPEAT_FOREVER = -1


class MissionRun:
    """The mission state of one vehicle: current item, phase, hold timer, DO_JUMP counters."""

    def __init__(self, vehicle: Vehicle) -> None:
        self.v = vehicle
        self.current = 0
        self.state = NO_MISSION
        self.running = False
        """An item is being flown (the vehicle is in the mission mode and armed)."""
        self.phase = ""
        self.hold_until: float | None = None
        self.jumps: dict[int, int] = {}
        """DO_JUMP repeats left, by the jump item's sequence number."""
        self.reached_sent = -1
        self._goal: tuple[float, float] = (0.0, 0.0)
        """Horizontal target of the waypoint or landing being flown."""
        self._after_takeoff: tuple[float, float] | None = None
        """PX4's own takeoff before a first waypoint: where to go once up."""

    # ----- the plan
    @property
    def items(self) -> list[MissionItem]:
        return self.v.plans.mission.items

    @property
    def has_items(self) -> bool:
        """Something to fly (ArduPilot's home item alone is no mission)."""
        return len(self.items) > self.first

    @property
    def first(self) -> int:
        """The first item flown: 1 on ArduPilot (item 0 is home), else 0."""
        return 1 if self.v.persona.mission.home_is_item0 else 0

    def plan_changed(self) -> None:
        """A new mission (or none): back to its start, not started."""
        self.current = 0
        self.jumps = {}
        self.reached_sent = -1
        self.state = NOT_STARTED if self.has_items else NO_MISSION
        if self.running:
            self._begin(self._start_seq())

    def _start_seq(self) -> int:
        return max(self.current, self.first)

    def set_current(self, seq: int) -> bool:
        """DO_SET_MISSION_CURRENT / MISSION_SET_CURRENT: fly ``seq`` next."""
        if not 0 <= seq < len(self.items):
            return False
        self.current = seq
        self.jumps = {}
        self.state = ACTIVE
        self.v.outbox.append(self.current_message())
        if self.running:
            self._begin(max(seq, self.first))
        return True

    # ----- MISSION_CURRENT
    def current_message(self) -> Any:
        return d.MAVLink_mission_current_message(*self.current_args())

    def current_args(self) -> tuple[int, int, int, int]:
        """MISSION_CURRENT's seq, total, mission_state, mission_mode."""
        rules = self.v.persona.mission
        n = len(self.items)
        total = max(n - 1, 0) if rules.home_is_item0 else (n or 65535)
        state = mode = 0
        if rules.reports_mission_state:
            state = self.state
            mode = 1 if self.v.mode.behaviour.value == "mission" else 2
        return self.current, total, state, mode

    # ----- AUTO
    def enter(self) -> None:
        """The vehicle entered the mission mode (armed, or arming in it)."""
        if not self.has_items:
            self.v.fleet.hold(self.v.index)
            return
        self.running = True
        v = self.v
        v.fleet.speed[v.index] = v.persona.mission_speed(v.params)
        if self.state == COMPLETE:
            self.current = 0
        self.state = ACTIVE
        self._begin(self._start_seq())

    def leave(self) -> None:
        """Out of the mission mode: the ordinary speed limit again."""
        self.running = False
        self.hold_until = None
        v = self.v
        v.fleet.speed[v.index] = v.persona.speeds(v.params)[0]

    def _begin(self, seq: int) -> None:
        """Start flying item ``seq`` (past the end: the mission is complete)."""
        v, f, i = self.v, self.v.fleet, self.v.index
        self.hold_until = None
        self.phase = ""
        for _ in range(len(self.items) + 1):  # DO_ items step on at once; a jump loop ends here
            if seq >= len(self.items):
                self.current = max(len(self.items) - 1, 0)
                self.state = COMPLETE
                self.running = False
                f.hold(i)
                v.say(6, "Mission complete")
                v.outbox.append(self.current_message())
                return
            self.current = seq
            item = self.items[seq]
            nxt = self._start(seq, item)
            if nxt is None:
                v.outbox.append(self.current_message())  # one, for the item now flown
                return
            seq = nxt
        f.hold(i)

    def _target(self, item: MissionItem) -> tuple[float, float, float | None]:
        """(north, east, altitude above home or None) of a position item; lat/lon 0 = here."""
        v, f, i = self.v, self.v.fleet, self.v.index
        north, east = float(f.pos[i, 0]), float(f.pos[i, 1])
        if item.frame in GLOBAL_FRAMES and (item.x, item.y) != (0, 0):
            north, east, _ = v.geo.to_local(item.x * 1e-7, item.y * 1e-7, v.geo.alt)
        alt: float | None = None
        if item.frame in GLOBAL_FRAMES and math.isfinite(item.z):
            alt = item.z if item.frame in _RELATIVE else item.z - v.geo.alt
        return north, east, alt

    def _start(self, seq: int, item: MissionItem) -> int | None:
        """Begin ``item``; returns the next sequence number when the item is done at once."""
        v, f, i = self.v, self.v.fleet, self.v.index
        cmd = item.command
        if cmd == d.MAV_CMD_DO_CHANGE_SPEED:
            v.change_speed(item.params[0], item.params[1])
            return seq + 1
        if cmd == d.MAV_CMD_DO_JUMP:
            return self._jump(seq, item)
        if cmd == d.MAV_CMD_NAV_RETURN_TO_LAUNCH:
            if v.persona.mission.rtl_item_switches_mode:
                self.running = False
                v.set_mode(v.persona.mode(v.persona.rtl_mode), "mission")
                return None
            self.phase = "rtl-climb"
            f.hold(i)
            f.climb_to(i, max(float(f.alt[i]), v.persona.rtl_altitude(v.params)))
            return None
        if cmd == d.MAV_CMD_NAV_TAKEOFF:
            _, _, alt = self._target(item)
            height = alt if alt is not None and alt > 0 else 0.0
            if float(f.alt[i]) >= height - _TAKEOFF_ACCEPT:
                self._reached(seq)
                return seq + 1
            self.phase = "takeoff"
            f.hold(i)
            f.climb_to(i, height)
            v.takeoff_alt = height
            return None
        if cmd == d.MAV_CMD_NAV_LAND:
            north, east, _ = self._target(item)
            self.phase = "land-approach"
            f.go_to(i, north, east)
            self._goal = (north, east)
            return None
        if cmd in (
            d.MAV_CMD_NAV_WAYPOINT,
            d.MAV_CMD_NAV_LOITER_TIME,
            d.MAV_CMD_NAV_LOITER_UNLIM,
            d.MAV_CMD_NAV_LOITER_TURNS,
            d.MAV_CMD_NAV_SPLINE_WAYPOINT,
            d.MAV_CMD_NAV_LOITER_TO_ALT,
        ):
            north, east, alt = self._target(item)
            if v.landed and v.persona.mission.takeoff_when_landed:
                self.phase = "takeoff"
                height = (
                    alt if alt is not None and alt > 0 else v.persona.default_takeoff_alt(v.params)
                )
                f.hold(i)
                f.climb_to(i, height)
                v.takeoff_alt = height
                self._after_takeoff = (north, east)
                return None
            self.phase = "waypoint"
            f.go_to(i, north, east)
            f.climb_to(i, float(f.alt[i]) if alt is None or alt <= 0 else alt)
            self._goal = (north, east)
            return None
        return seq + 1  # camera, servo, ROI, condition items: nothing to fly

    def _jump(self, seq: int, item: MissionItem) -> int:
        target, repeat = item.params[0], item.params[1]
        if not (math.isfinite(target) and 0 <= target < len(self.items)):
            return seq + 1
        left = self.jumps.setdefault(seq, int(repeat) if math.isfinite(repeat) else 0)
        if left == 0:
            return seq + 1
        if left != _REPEAT_FOREVER:
            self.jumps[seq] = left - 1
        return int(target)

    def _reached(self, seq: int) -> None:
        if self.reached_sent != seq:
            self.reached_sent = seq
            self.v.outbox.append(d.MAVLink_mission_item_reached_message(seq))

    def _radius(self, item: MissionItem) -> float:
        p2 = item.params[1]
        if item.command == d.MAV_CMD_NAV_WAYPOINT and math.isfinite(p2) and p2 > 0:
            return float(p2)
        rules = self.v.persona.mission
        return self.v.params.get(rules.acceptance_param) / rules.acceptance_scale

    # ----- per tick
    def step(self) -> None:
        """Called every telemetry tick while the vehicle is in the mission mode."""
        v = self.v
        if not self.running:
            if v.armed and self.has_items and self.state != COMPLETE and self._may_start():
                self.enter()
            return
        if not v.armed:
            return
        if v.landed and self.phase not in ("takeoff", "land", "rtl-land") and not self._may_start():
            return
        seq = self.current
        if seq >= len(self.items):
            return
        item = self.items[seq]
        f, i = v.fleet, v.index
        pos, alt = f.pos[i], float(f.alt[i])
        phase = self.phase
        if phase == "takeoff":
            if alt >= float(f.v_target[i]) - _TAKEOFF_ACCEPT:
                v.takeoff_alt = None
                after = self._after_takeoff
                if item.command == d.MAV_CMD_NAV_TAKEOFF or after is None:
                    self._reached(seq)
                    self._begin(seq + 1)
                    return
                self._after_takeoff = None
                self.phase = "waypoint"
                f.go_to(i, *after)
                self._goal = after
            return
        if phase == "waypoint":
            north, east = self._goal
            near = math.hypot(pos[0] - north, pos[1] - east) <= self._radius(item)
            if not (near and abs(alt - float(f.v_target[i])) <= _VERTICAL_ACCEPT):
                return
            self._reached(seq)
            if item.command == d.MAV_CMD_NAV_LOITER_UNLIM:
                self.phase = "loiter"
                return
            hold = item.params[0] if item.command != d.MAV_CMD_NAV_LOITER_TURNS else 0.0
            self.phase = "hold"
            self.hold_until = v.now + (hold if math.isfinite(hold) and hold > 0 else 0.0)
        if self.phase == "hold":
            if self.hold_until is not None and v.now >= self.hold_until - 1e-9:
                self._begin(seq + 1)
            return
        if phase == "land-approach":
            north, east = self._goal
            if math.hypot(pos[0] - north, pos[1] - east) <= 1.0:
                self.phase = "land"
                f.climb_rate(i, -v.persona.speeds(v.params)[3])
            return
        if phase == "rtl-climb" and alt >= float(f.v_target[i]) - 0.5:
            self.phase = "rtl-home"
            self._goal = return_point(v)
            f.go_to(i, *self._goal)
        elif phase == "rtl-home" and np.hypot(*(pos - self._goal)) < 1.0:
            self.phase = "rtl-land"
            f.climb_rate(i, -v.persona.speeds(v.params)[3])

    @property
    def landing(self) -> bool:
        """Descending to touch down (the vehicle disarms on the ground)."""
        return self.running and self.phase in ("land", "rtl-land")

    def touched_down(self) -> None:
        """Landed at the end of a LAND or RTL item: the mission is over."""
        self._reached(self.current)
        self.state = COMPLETE
        self.running = False

    def _may_start(self) -> bool:
        """ArduCopter on the ground waits for auto_armed (a MISSION_START, a takeoff, throttle)
        before AUTO moves it; PX4 starts on arming."""
        v = self.v
        return not v.landed or v.auto_armed or v.persona.mission.auto_armable


def return_point(v: Vehicle) -> tuple[float, float]:
    """Where RTL goes: the nearest of home and the stored rally points (ArduCopter with
    RALLY_INCL_HOME 1, PX4 with RTL_TYPE 0, both stock), in the profile's frame."""
    f, i = v.fleet, v.index
    here = (float(f.pos[i, 0]), float(f.pos[i, 1]))
    best, dist = v.home, math.hypot(here[0] - v.home[0], here[1] - v.home[1])
    for it in v.plans.rally.items:
        if it.frame not in GLOBAL_FRAMES:
            continue
        n, e, _ = v.geo.to_local(it.x * 1e-7, it.y * 1e-7, v.geo.alt)
        d = math.hypot(here[0] - n, here[1] - e)
        if d < dist:
            best, dist = (n, e), d
    return best
