"""What each position asks of the mission in each phase: the search's policy step and pursuit,
a neutral stream before arming, the transit to the start point, the climb by setpoints, a
holding stream while a pilot has a PX4 vehicle; and the ``tick`` records."""

from __future__ import annotations

import logging
import time
from typing import Protocol

import numpy as np

from companion import guidance
from companion.guidance import NedSetpoint
from companion.link.base import VehicleLink
from companion.link.messages import LocalPosition
from companion.mission.config import MissionConfig
from companion.mission.core_for import MissionCore
from companion.mission.layer_watch import LayerWatch
from companion.mission.lifecycle import Mission
from companion.mission.observed import Observed
from companion.mission.phase import Phase
from companion.mission.search_answer import TICK_S, SearchAnswer
from companion.mission.setpoint_out import SetpointOut
from companion.sensors.base import SensorSource
from companion.telemetry import events

log = logging.getLogger(__name__)


class Steered(Protocol):
    """What the steering reads of the mission and asks of it (VehicleMission)."""

    @property
    def config(self) -> MissionConfig: ...
    @property
    def link(self) -> VehicleLink: ...
    @property
    def seen(self) -> Observed: ...
    @property
    def core(self) -> MissionCore: ...
    @property
    def sensors(self) -> SensorSource: ...
    @property
    def out(self) -> SetpointOut: ...
    @property
    def answer(self) -> SearchAnswer: ...
    @property
    def state(self) -> Mission: ...
    @property
    def start(self) -> tuple[float, float] | None: ...
    @property
    def real_targets(self) -> int: ...
    @property
    def phase(self) -> Phase: ...
    @property
    def end_reason(self) -> str | None: ...
    def emit(self, event: str, **fields: object) -> None: ...
    def record(self, event: events.DurableEvent) -> None: ...
    def request_end(self, reason: str) -> None: ...


class PhaseSteering:
    """Answers every position the decision loop acts on (:meth:`on_position`)."""

    def __init__(self, mission: Steered) -> None:
        self.m = mission
        self.layer = LayerWatch(mission)

    def on_position(self, pos: LocalPosition) -> None:
        m, seen, out = self.m, self.m.seen, self.m.out
        t = seen.note_position(pos)
        m.sensors.observe(t, pos.north, pos.east)
        if t - seen.last_tick >= TICK_S:
            seen.last_tick = t
            m.emit(
                "tick",
                phase=m.phase.value,
                level=m.core.level,
                wall=round(time.time(), 3),
                north=round(pos.north, 1),
                east=round(pos.east, 1),
                alt=round(-pos.down, 1),
                found=m.core.confirmed_count,
            )
        if m.phase is Phase.SEARCH:
            self.layer.check(t, -pos.down)
            self._search_step(t, pos)
        elif m.phase is Phase.PAUSED:
            start = seen.search_start
            if start is not None and t - start >= m.config.search_duration:
                m.request_end("mission time (paused)")  # ends without commanding
            elif not m.state.control.operator_paused and self._guided_needs_stream():
                # A pilot hands back by switching to OFFBOARD, which PX4 refuses without a
                # setpoint stream: keep one flowing that holds here (ignored in other modes).
                out.send(NedSetpoint(pos.north, pos.east, pos.down, 0.0, 0.0, 0.0), pos)
        elif m.phase is Phase.PREPARE:
            # Neutral stream before arming: stay where it is (a climb here would start the
            # moment the mode switches, before the vehicle is armed).
            out.send(NedSetpoint(pos.north, pos.east, pos.down, 0.0, 0.0, 0.0), pos)
        elif m.phase is Phase.TRANSIT and m.start is not None:
            here = np.array([pos.north, pos.east])
            goal = np.array(m.start)
            out.send(guidance.pursuit(here, pos.down, goal, out.guide, out.fence, seen.period), pos)
        elif m.phase is Phase.CLIMB and not m.state.climbing_by_command:
            here = np.array([pos.north, pos.east])
            out.send(guidance.pursuit(here, pos.down, here, out.guide, out.fence, 1.0), pos)

    def _search_step(self, t: float, pos: LocalPosition) -> None:
        m, out, core = self.m, self.m.out, self.m.core
        m.seen.note_search_speed(pos)
        here = np.array([pos.north, pos.east])
        contacts = m.sensors.take()
        # Reached means reached as far as the fence lets the vehicle go: a waypoint between the
        # area's edge and the fence is clamped, and the clamped point is where it stops.
        goal = out.fence.clamp(core.waypoint)
        reached = guidance.reached(here, goal, out.guide.acceptance_radius)
        if core.needs_step(t, here, reached, contacts):
            d = core.step(t, here, reached, contacts)
            goal = out.fence.clamp(core.waypoint)
            if d.detected:
                m.record(events.Detection(round(pos.north, 1), round(pos.east, 1), d.level))
            for north, east in d.confirmed:
                m.record(events.Confirmation(north, east, d.previous_level, core.confirmed_count))
            if d.fell_back:
                m.record(events.Fallback(d.level))
            if d.level != d.previous_level:
                m.record(events.Level(d.level, core.sensor()))
                m.sensors.select(core.sensor(), t)
        start = m.seen.search_start
        if start is not None and t - start >= m.config.search_duration:
            m.request_end("mission time")
        elif m.config.stop_when_all_found and core.confirmed_count >= m.real_targets:
            m.request_end("all targets")
        if m.end_reason is not None:
            return
        if m.config.setpoints == "position":  # (goal: the fenced waypoint of now)
            sp = NedSetpoint(float(goal[0]), float(goal[1]), -out.guide.altitude, 0.0, 0.0, 0.0)
            out.send(sp, pos)
            return
        wn, we = (float(c) for c in core.waypoint)
        m.answer.steer_to(wn, we, (float(goal[0]), float(goal[1])))
        out.pursue(pos, wn, we)

    def _guided_needs_stream(self) -> bool:
        ap = self.m.link.autopilot
        return ap is not None and ap.guided_needs_stream
