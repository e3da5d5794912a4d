"""The decision loop's intake: the link's events in (as the link reads them), each to what it
changes (the observed state, the lifecycle machine, the sensor source, the fence watch), and
the companion's HEARTBEAT out on a timer of this loop: if the loop dies, the heartbeat stops."""

from __future__ import annotations

import asyncio
import logging
import math
import time
from collections.abc import Callable, Coroutine
from typing import Any, Protocol

from companion.link.base import VehicleLink
from companion.link.messages import (
    GlobalPosition,
    Heartbeat,
    LinkEvent,
    LocalPosition,
    SensorContact,
    SensorSignal,
    StatusText,
    StraySource,
    SystemStatus,
)
from companion.mission.battery_reserve import percent_home
from companion.mission.config import MissionConfig
from companion.mission.control import ModeReport
from companion.mission.core_for import MissionCore
from companion.mission.fence_watch import FenceWatch
from companion.mission.lifecycle import Event
from companion.mission.lifecycle_events import Battery, Do, Gps
from companion.mission.observed import Observed
from companion.mission.phase import Phase
from companion.mission.search_answer import SearchAnswer
from companion.mission.vehicle_fence import VehicleFence
from companion.mission.vehicle_waits import VehicleWaits
from companion.sensors.base import SensorSource
from companion.telemetry import events

log = logging.getLogger(__name__)

_SETPOINT_GAP_S = 0.8
"""A gap in our setpoints this long (vehicle s) can explain a HOLD. PX4 falls back only after
COM_OF_LOSS_T (1 s stock) without setpoints; the newest position we hold may lag that HOLD by
one 10 Hz period, so 0.8 still sees every fall-back, while a shorter gap would turn a pilot's
HOLD on a loaded host (the companion descheduled for a fraction of a second) into one."""
_TEXT_LEVEL = {0: logging.ERROR, 1: logging.ERROR, 2: logging.ERROR, 3: logging.ERROR,
               4: logging.WARNING, 5: logging.INFO, 6: logging.INFO}  # fmt: skip
"""MAV_SEVERITY -> log level for the vehicle's STATUSTEXT (7, debug, is logged at DEBUG)."""


class Taken(Protocol):
    """What the intake reads of the mission and asks of it (VehicleMission)."""

    @property
    def config(self) -> MissionConfig: ...
    @property
    def link(self) -> VehicleLink: ...
    @property
    def seen(self) -> Observed: ...
    @property
    def waits(self) -> VehicleWaits: ...
    @property
    def core(self) -> MissionCore: ...
    @property
    def sensors(self) -> SensorSource: ...
    @property
    def answer(self) -> SearchAnswer: ...
    @property
    def watch(self) -> FenceWatch | None: ...
    @property
    def vehicle_fence(self) -> VehicleFence | None: ...
    @property
    def phase(self) -> Phase: ...
    def feed(self, event: Event, *, mode: str = "") -> tuple[Do, ...]: ...
    def chore(self, work: Coroutine[Any, Any, None]) -> None: ...
    def emit(self, event: str, **fields: object) -> None: ...
    def record(self, event: events.DurableEvent) -> None: ...
    def hold_mode(self, hb: Heartbeat) -> bool: ...


class EventIntake:
    """The decision loop (:meth:`decide`); positions acted on go to ``on_position``."""

    def __init__(self, mission: Taken, on_position: Callable[[LocalPosition], None]) -> None:
        self.m = mission
        self.on_position = on_position

    async def decide(self) -> None:
        """Until cancelled: the link's events handled as it reads them, the heartbeat sent;
        an error of either ends the loop with that error."""
        m, link = self.m, self.m.link
        queue = link.events
        loop = asyncio.get_running_loop()
        me = asyncio.current_task()
        failed: list[Exception] = []
        timer: asyncio.TimerHandle | None = None

        def beat() -> None:
            # The companion HEARTBEAT every period (wall s), scheduled by this loop and stopped
            # with it. A timer, not a timeout on a wait: asyncio's cost per wake-up is most of
            # a companion's CPU at 1000 positions per wall second.
            nonlocal timer
            try:
                link.send_heartbeat()
            except Exception as exc:  # ends the decision loop with this error
                failed.append(exc)
                if me is not None:
                    me.cancel()
                return
            timer = loop.call_later(m.config.heartbeat_period, beat)

        def stop(exc: Exception) -> None:
            failed.append(exc)
            link.listener = None
            link.answerer = None
            if me is not None:
                me.cancel()

        def listen(batch: list[LinkEvent]) -> None:
            # Called by the link as it reads (one batch per socket read): the setpoint leaves
            # in the same loop iteration as the position came in. An error ends this loop.
            try:
                self.handle_batch(batch)
            except Exception as exc:
                stop(exc)

        beat()
        try:
            if not queue.empty():  # what came before the listener
                self.handle_queued(queue.get_nowait(), queue)
            link.listener = listen
            m.answer.failed = stop
            link.answerer = m.answer
            await loop.create_future()  # until cancelled (the mission ends, an error)
        except asyncio.CancelledError:
            if failed:
                raise failed[0] from None
            raise
        finally:
            link.listener = None
            link.answerer = None
            if timer is not None:
                timer.cancel()

    def handle_queued(self, first: LinkEvent, queue: asyncio.Queue[LinkEvent]) -> None:
        """``first`` and the events queued behind it (those that came before the listener)."""
        batch = [first]
        while not queue.empty():
            batch.append(queue.get_nowait())
        self.handle_batch(batch)

    def handle_batch(self, batch: list[LinkEvent]) -> None:
        """Events read together, in order; of several positions only the newest is acted on:
        after a stall (a loaded machine, a sped-up vehicle) the older ones are stale, and a
        setpoint computed from each would steer seconds late."""
        newest = -1
        for i, event in enumerate(batch):
            if isinstance(event, LocalPosition):
                # How far the vehicle's clock has run, for a HOLD queued before the newest one.
                newest = i
                self.m.seen.note_received(event.time)
        for i, event in enumerate(batch):
            if i == newest or not isinstance(event, LocalPosition):
                self.handle(event)

    def handle(self, event: LinkEvent) -> None:
        """One event; the waits see the change."""
        m = self.m
        if isinstance(event, LocalPosition):
            self.on_position(event)
        elif isinstance(event, GlobalPosition):
            self._on_gps(event)
        elif isinstance(event, SensorContact | SensorSignal):
            m.sensors.accept(event)
        elif isinstance(event, Heartbeat):
            self._on_heartbeat(event)
        elif isinstance(event, StatusText):
            self._on_text(event)
        elif isinstance(event, StraySource):
            m.emit("stray", address=event.address, locked=event.locked)
        elif isinstance(event, SystemStatus):
            m.seen.status = event
            self._on_battery(event.battery_remaining)
        m.waits.wake()

    def _on_battery(self, remaining: int) -> None:
        """The fixed minimum, and the reserve rule once airborne: the percent the flight home
        needs at the drain measured so far (from where the vehicle was first seen on the
        ground; the descent alone where that is not known)."""
        m, seen, rule = self.m, self.m.seen, self.m.config.battery_reserve
        rule = rule.at_most(seen.return_speed) if rule is not None else None
        pos, home = seen.position, None
        if rule is not None and pos is not None and -pos.down > 1.0 and remaining >= 0:
            rate = seen.drain.note(seen.clock.now, remaining)
            start = seen.home or (pos.north, pos.east)
            away = math.hypot(pos.north - start[0], pos.east - start[1])
            home = percent_home(rate, rule, away, -pos.down)
        reserve = rule.reserve if rule is not None else 0.0
        m.feed(Battery(remaining, m.config.battery_min, home, reserve))

    def _on_text(self, text: StatusText) -> None:
        """The autopilot's own words on the console and in the mission log."""
        log.log(
            _TEXT_LEVEL.get(text.severity, logging.DEBUG),
            "vehicle %d says: %s",
            self.m.config.vehicle,
            text.text,
        )
        if text.severity <= 6:
            self.m.emit("statustext", severity=text.severity, text=text.text)

    def _on_heartbeat(self, hb: Heartbeat) -> None:
        m, seen = self.m, self.m.seen
        seen.last_heartbeat_wall = time.perf_counter()
        previous = seen.heartbeat
        seen.heartbeat = hb
        ap = m.link.autopilot
        if ap is None:
            return
        guided = ap.is_guided(hb.custom_mode)
        if previous is None or previous.custom_mode != hb.custom_mode:
            m.record(events.ModeChange(ap.mode_name(hb.custom_mode), guided))
        stalled = seen.received_time - seen.setpoint_time >= _SETPOINT_GAP_S
        report = ModeReport(guided, m.hold_mode(hb), bool(stalled), m.core.started)
        m.feed(report, mode=ap.mode_name(hb.custom_mode))

    def _on_gps(self, gps: GlobalPosition) -> None:
        """The fence watch: outside the fence after having been inside it (transit or
        search) ends the search; the end action (RTL) flies the vehicle home, inside."""
        m = self.m
        m.seen.gps = gps
        watch = m.watch
        if watch is None:
            return
        breach = watch.breach(gps.north, gps.east)
        own = m.vehicle_fence
        if (
            breach is None
            and own is not None
            and own.installed
            and not own.enabling
            and m.phase not in (Phase.RETURN, Phase.DONE)
        ):
            m.chore(own.enable())
        if Do.SAY_BREACH in m.feed(Gps(breach)):
            log.error(
                "vehicle %d is %s (GPS %.7f, %.7f): ending the search",
                m.config.vehicle,
                breach,
                gps.lat,
                gps.lon,
            )
            m.emit("fence", state="breach", where=breach, lat=gps.lat, lon=gps.lon)
