"""The live vehicle's adapter to the lawnmower baselines (policy.kind lm1, lm2): its strip.

Same interface as SearchCore (what VehicleMission calls). The plan is the engine's
(mdm_core.search.lawnmower_profile.team_plan of the team's start points, drawn from the
mission's seed as the emulator draws them: Scenario.live_run), the vehicle's lanes cut to the
guidance fence (fenced_lanes). It flies the rules of mdm_montecarlo.kernels.lawnmower_kernel:

- the sweep: from where the search begins to the first lane's end, then the lanes in order,
  and at the last one back the other way (last lane first), back and forth until the mission
  ends;
- lm1: the confirmation sensor on all the time; a contact of a target not yet confirmed (none
  confirmed within ``policy.memory_radius``) is a confirmation; the course is kept;
- lm2: the detection sensor on the lanes (level 0); a detection of a target neither confirmed
  nor held starts the confirmation search (level 1, the confirmation sensor): the spiral's
  offsets (lawnmower.spiral), turned to the heading at detection, round the point of detection,
  until the detected target is confirmed or the spiral ends; then back to the point where the
  vehicle left its lane (detection sensor on: a detection on the way starts another search, and
  the vehicle still goes back to the same point). A target searched for in vain is held: its
  detections are ignored for ``policy.lawnmower.search_hold`` s, or (None) until the pass over
  the cell ends.

The engine knows which target a contact is; the vehicle knows where the contact is. A target
is "the same" as a remembered one within ``policy.memory_radius``; the sought target of a
search is confirmed by a confirmation within that radius of where it was detected, plus the
distance a moving target can have covered since (its top speed x the time).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from companion.geofence import Geofence
from companion.mission.fenced_lanes import fenced_lanes
from companion.mission.search_core import Decision, FloatArray
from mdm_core.search.lawnmower_profile import search_hold, search_spiral, team_plan
from mdm_core.world.scenario import Scenario
from mdm_profiles import MissionProfile

SWEEP, SEARCH, RETURN = range(3)


class LawnmowerCore:
    """One vehicle's strip: its fenced lanes, where it is in them and what it remembers."""

    def __init__(self, profile: MissionProfile, seed: int, vehicle: int, fence: Geofence) -> None:
        self.profile = profile
        self.two_sensor = profile.policy.kind == "lm2"
        starts, _ = Scenario.from_profile(profile).live_run(
            seed, profile.fleet.vehicles, profile.fleet.start
        )
        plan = team_plan(profile, starts)
        self.region = plan.regions[vehicle]
        """(2, 2) the vehicle's cell, low and high corners (north, east)."""
        self.lanes = fenced_lanes(plan.waypoints[vehicle], fence)
        """(2 lanes, 2) one sweep of the cell inside the fence, in flying order."""
        self.spiral = search_spiral(profile)
        self.hold = search_hold(profile)
        self.radius = profile.policy.memory_radius
        motion = profile.target_motion
        self.target_speed = (
            0.0
            if motion is None
            else math.sqrt(2.0) * max(abs(motion.low), abs(motion.high)) * motion.speed
        )
        """The fastest a target can move (both axes at the walk's largest step), m/s."""
        self.area = (profile.area.north, profile.area.east)
        self.mode = SWEEP
        self.k = 0
        self.direction = 1
        self.s = 0
        self.back = np.zeros(2)
        self.centre = np.zeros(2)
        self.heading = np.array([1.0, 0.0])
        self.sought = np.zeros(2)
        self.sought_since = 0.0
        self.confirmed: list[tuple[float, float]] = []
        self.held: list[tuple[float, float, float]] = []
        """(north, east, until) of targets searched for in vain; until inf: this pass."""
        self.passes = 0
        """Sweeps of the cell completed (one end of the lanes to the other)."""
        self._started = False
        self.emit: Callable[..., Any] | None = None
        """Where to log (event name, fields) what the strip is; set by the companion to the
        mission log's emit (VehicleMission.emit). Logged: ``lawnmower_lanes`` at the start
        (the cell and the fenced lanes), ``lawnmower_pass`` at each end of the lanes, and
        ``lawnmower_search`` at the end of each lm2 confirmation search."""

    def start(self, position: FloatArray, time: float, memory: list[tuple[float, float]]) -> None:
        """The sweep from its first lane's end; ``memory``: targets confirmed earlier."""
        self.confirmed = list(memory)
        self._started = True
        self._log(
            "lawnmower_lanes",
            cell=[[round(float(v), 1) for v in corner] for corner in self.region],
            lanes=[[round(float(v), 1) for v in point] for point in self.lanes],
        )

    @property
    def started(self) -> bool:
        return self._started

    @property
    def level(self) -> int:
        """0 on the lanes (and flying back to them), 1 in lm2's confirmation search."""
        return 1 if self.mode == SEARCH else 0

    @property
    def waypoint(self) -> FloatArray:
        if self.mode == SWEEP:
            return np.asarray(self.lanes[self.k])
        if self.mode == RETURN:
            return self.back
        north, east = self.spiral[self.s]
        hn, he = self.heading
        point = self.centre + np.array([north * hn - east * he, north * he + east * hn])
        return np.asarray(np.clip(point, 0.0, self.area), dtype=float)

    @property
    def confirmed_count(self) -> int:
        return len(self.confirmed)

    def sensor(self) -> int:
        """The confirmation sensor, but on lm2's lanes the first (detection) sensor."""
        return 0 if self.two_sensor and self.mode != SEARCH else len(self.profile.sensors) - 1

    def needs_step(
        self, time: float, position: FloatArray, reached: bool, contacts: FloatArray
    ) -> bool:
        """The waypoint reached, or a contact of a target that is news (not confirmed, not
        held)."""
        return reached or any(self._news(c, time) for c in contacts)

    def step(
        self, time: float, position: FloatArray, reached: bool, contacts: FloatArray
    ) -> Decision:
        """Contacts first (a confirmation, or lm2's detection), then the waypoint reached."""
        before = self.level
        confirmed: list[tuple[float, float]] = []
        detected = False
        moved = False
        if self.mode == SEARCH or not self.two_sensor:
            confirmed = self._confirm(contacts)
            if self.mode == SEARCH and any(self._is_sought(c, time) for c in confirmed):
                self.mode = RETURN
                moved = True
                self._log("lawnmower_search", confirmed=True, chords=self.s)
        else:
            fresh = [c for c in contacts if self._news(c, time)]
            if fresh:
                self._begin_search(time, position, fresh[0])
                detected = moved = True
        if reached and not moved:
            self._advance(time)
            moved = True
        return Decision(
            level=self.level,
            previous_level=before,
            detected=detected,
            confirmed=confirmed,
            fell_back=False,
            new_waypoint=moved,
        )

    def index_value(self, time: float) -> float:
        return math.nan

    # -- internals -------------------------------------------------------------------------

    def _known(self, point: FloatArray) -> bool:
        n, e = float(point[0]), float(point[1])
        return any(math.hypot(n - a, e - b) <= self.radius for a, b in self.confirmed)

    def _news(self, point: FloatArray, time: float) -> bool:
        if self._known(point):
            return False
        if self.mode == SEARCH or not self.two_sensor:
            return True
        n, e = float(point[0]), float(point[1])
        return not any(
            until > time and math.hypot(n - a, e - b) <= self.radius for a, b, until in self.held
        )

    def _confirm(self, contacts: FloatArray) -> list[tuple[float, float]]:
        new: list[tuple[float, float]] = []
        for c in contacts:
            if not self._known(c):
                new.append((float(c[0]), float(c[1])))
                self.confirmed.append(new[-1])
        return new

    def _is_sought(self, point: tuple[float, float], time: float) -> bool:
        reach = self.radius + self.target_speed * (time - self.sought_since)
        return math.hypot(point[0] - self.sought[0], point[1] - self.sought[1]) <= reach

    def _begin_search(self, time: float, position: FloatArray, target: FloatArray) -> None:
        ahead = self.waypoint - position
        length = float(np.hypot(*ahead))
        if self.mode == SWEEP:
            self.back = np.array(position, dtype=float)
        if length > 0.0:
            self.heading = ahead / length
        self.mode = SEARCH
        self.s = 0
        self.centre = np.array(position, dtype=float)
        self.sought = np.array(target, dtype=float)
        self.sought_since = time

    def _advance(self, time: float) -> None:
        if self.mode == RETURN:
            self.mode = SWEEP
        elif self.mode == SEARCH:
            self.s += 1
            if self.s == len(self.spiral):
                until = time + self.hold if self.hold >= 0.0 else math.inf
                self.held.append((float(self.sought[0]), float(self.sought[1]), until))
                self.mode = RETURN
                self._log("lawnmower_search", confirmed=False, chords=self.s)
        else:
            self.k += self.direction
            if self.k == len(self.lanes) or self.k < 0:
                self.direction = -self.direction
                self.k += 2 * self.direction
                self.passes += 1
                self.held = [h for h in self.held if h[2] != math.inf]  # held for one pass
                self._log("lawnmower_pass", passes=self.passes)

    def _log(self, event: str, **fields: object) -> None:
        if self.emit is not None:
            self.emit(event, **fields)
