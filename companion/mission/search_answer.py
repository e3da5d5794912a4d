"""The search phase's common answer, without events: a position in, the pursuit setpoint out.

Between two decisions of the policy, nearly every position the vehicle sends changes nothing
but where the vehicle is: the waypoint not reached, C_I not run out, no tick to log, the mission
time not over, no contact or only contacts the policy rules out (a target the vehicle confirmed
itself, read again). For those positions the decision loop's path (the link's events, the
batch, the policy's check) costs about twice what answering them needs, and at a 100x speed-up
that is most of a companion's CPU. The link hands such a position here
(``VehicleLink.answerer``) when its datagram holds nothing but it, the sensor's signal and
contacts and the vehicle's HEARTBEAT or SYS_STATUS: :meth:`SearchAnswer.ready` says whether the
mission would only steer, and :meth:`SearchAnswer.answer` does what the decision loop does
then, step for step (the same state changes, records and setpoint;
tests/companion/test_search_answer.py flies a vehicle both ways). Anything else (a contact the
policy acts on, a waypoint reached, a tick, another phase, a second datagram waiting) takes the
decision loop's path as before.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from companion.link.messages import LinkEvent, LocalPosition
from companion.mission.config import MissionConfig
from companion.mission.core_for import MissionCore
from companion.mission.observed import Observed
from companion.mission.search_core import SearchCore
from companion.sensors.base import SensorSource
from companion.sensors.mavlink_source import MavlinkSensorSource

TICK_S = 10.0
"""Vehicle seconds between two ``tick`` records of the mission log."""


Steer = Callable[[LocalPosition, float, float], None]
"""The mission's steering: the pursuit setpoint from a position towards (north, east)."""


class SearchAnswer:
    """The decision loop's steering of one position, for the positions that change nothing else.

    It writes what the mission observed (``seen``: the position, clock and period) and steers
    through ``steer``; every other event of the datagram goes to the mission's ``handle``, and
    ``searching()`` says whether the mission is in the search and not ending. ``plan`` holds the waypoint the policy chose and its fenced goal; the decision loop sets it
    after each policy step (:meth:`steer_to`) and clears it on every phase change (:meth:`forget`),
    so that nothing here acts on a waypoint the policy has since replaced.
    """

    def __init__(
        self,
        seen: Observed,
        steer: Steer,
        *,
        handle: Callable[[LinkEvent], None],
        searching: Callable[[], bool],
        config: MissionConfig,
        core: MissionCore,
        sensors: SensorSource,
        acceptance_radius: float,
    ) -> None:
        self.seen = seen
        self.steer = steer
        self.handle = handle
        self.searching = searching
        self.search_duration = config.search_duration
        self.core = core
        self.sensors = sensors
        self.acceptance_radius = acceptance_radius
        self.plan: tuple[float, float, float, float] | None = None
        """(waypoint north, east, fenced goal north, east) of the current policy decision."""
        self._parts = (
            (core, sensors)
            if isinstance(core, SearchCore)
            and isinstance(sensors, MavlinkSensorSource)
            and config.setpoints == "velocity"
            else None
        )
        """Only with the MDM core (a swarm core decides on its peers' news too), readings over
        MAVLink (a virtual or MQTT source reads the position itself) and velocity setpoints."""
        self.answered = 0
        """Positions answered here (the rest went through the decision loop)."""
        self.failed: Callable[[Exception], None] = _reraise
        """What an error here does: the decision loop sets it to end itself with the error."""

    def steer_to(
        self, waypoint_north: float, waypoint_east: float, goal: tuple[float, float]
    ) -> None:
        """The policy's waypoint after a step of the decision loop, and its fenced goal."""
        self.plan = (waypoint_north, waypoint_east, goal[0], goal[1])

    def forget(self) -> None:
        """The phase changed: the next position goes through the decision loop."""
        self.plan = None

    def ready(self, vehicle_time: float, north: float, east: float) -> bool:
        """Whether the decision loop, given this position, would do nothing but steer (and
        drop the contacts waiting, ruled out by the policy)."""
        try:
            return self._ready(vehicle_time, north, east)
        except Exception as exc:  # as an error of the decision loop: it ends the loop
            self.failed(exc)
            return False

    def _ready(self, vehicle_time: float, north: float, east: float) -> bool:
        seen, plan, parts = self.seen, self.plan, self._parts
        if plan is None or parts is None or not self.searching():
            return False
        t = seen.clock.peek(vehicle_time)
        if t is None or t - seen.last_tick >= TICK_S:
            return False
        start = seen.search_start
        if start is not None and t - start >= self.search_duration:
            return False
        if math.hypot(north - plan[2], east - plan[3]) <= self.acceptance_radius:
            return False  # reached
        contacts = parts[1].waiting()
        if len(contacts) == 0:
            return t < parts[0].deadline
        # contacts that change nothing (a target the vehicle confirmed itself, read again)
        return not parts[0].needs_step(t, np.array([north, east]), False, contacts)

    def answer(
        self,
        pos: LocalPosition,
        signal: float | None,
        before: list[LinkEvent],
        after: list[LinkEvent],
    ) -> None:
        """What the decision loop does with the events of a datagram when :meth:`ready` holds
        for its position ``pos``: the events ``before`` it, then the steering (the vehicle's
        clock and period, its position, the pursuit setpoint), then the events ``after`` it.
        When an event before it changed the mission (a mode, a low battery, a contact), the
        position takes the decision loop's way. ``signal``, the sensor's reading, is only read by a policy step
        (never here), so where it came in the datagram does not matter."""
        try:
            self.seen.note_received(pos.time)  # as the batch does first
            if signal is not None:
                self.sensors.signal = signal
            for event in before:
                self.handle(event)
            if before and not self._ready(pos.time, pos.north, pos.east):
                self.handle(pos)
            else:
                self._steer(pos)
            for event in after:
                self.handle(event)
        except Exception as exc:
            self.failed(exc)

    def _steer(self, pos: LocalPosition) -> None:
        plan = self.plan
        assert plan is not None
        t = self.seen.note_position(pos)
        self.sensors.observe(t, pos.north, pos.east)
        self.sensors.take()  # ruled out by ready, as the policy would
        self.seen.note_search_speed(pos)
        self.steer(pos, plan[0], plan[1])
        self.answered += 1


def _reraise(exc: Exception) -> None:
    raise exc
