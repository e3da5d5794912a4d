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
from typing import TYPE_CHECKING

import numpy as np

from companion.link.messages import LinkEvent, LocalPosition
from companion.mission.phase import Phase
from companion.mission.search_core import SearchCore
from companion.sensors.mavlink_source import MavlinkSensorSource

if TYPE_CHECKING:
    from companion.mission.vehicle_mission import VehicleMission

TICK_S = 10.0
"""Vehicle seconds between two ``tick`` records of the mission log."""


class SearchAnswer:
    """The decision loop's steering of one position, for the positions that change nothing else
    (a part of :class:`VehicleMission` in a file of its own: it changes the mission's state).

    ``plan`` holds the waypoint the policy chose and its fenced goal; the decision loop sets it
    after each policy step (:meth:`steer_to`) and clears it on every phase change (:meth:`forget`),
    so that nothing here acts on a waypoint the policy has since replaced.
    """

    def __init__(self, mission: VehicleMission) -> None:
        self.m = mission
        self.plan: tuple[float, float, float, float] | None = None
        """(waypoint north, east, fenced goal north, east) of the current policy decision."""
        core, source = mission.core, mission.sensors
        self._parts = (
            (core, source)
            if isinstance(core, SearchCore)
            and isinstance(source, MavlinkSensorSource)
            and mission.config.setpoints == "velocity"
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
        m, plan = self.m, self.plan
        parts = self._parts
        if plan is None or parts is None or m.phase is not Phase.SEARCH:
            return False
        t = m.clock.peek(vehicle_time)
        if t is None or t - m._last_tick >= TICK_S or m.end_reason is not None:
            return False
        start = m.search_start
        if start is not None and t - start >= m.config.search_duration:
            return False
        if math.hypot(north - plan[2], east - plan[3]) <= m.guide.acceptance_radius:
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
        m = self.m
        try:
            m._received_time = max(m._received_time, pos.time)  # as the batch does first
            if signal is not None:
                m.sensors.signal = signal
            for event in before:
                m._handle(event)
            if before and not self._ready(pos.time, pos.north, pos.east):
                m._handle(pos)
            else:
                self._steer(pos)
            for event in after:
                m._handle(event)
        except Exception as exc:
            self.failed(exc)

    def _steer(self, pos: LocalPosition) -> None:
        m, plan = self.m, self.plan
        assert plan is not None
        m._note_position(pos)
        m.sensors.take()  # ruled out by ready, as the policy would
        m.max_search_speed = max(m.max_search_speed, math.hypot(pos.vn, pos.ve))
        m.pursue(pos, plan[0], plan[1])
        m._wake()
        self.answered += 1


def _reraise(exc: Exception) -> None:
    raise exc
