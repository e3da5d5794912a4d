"""One vehicle's mission: lifecycle, decision loop and link supervision as named tasks."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
import random
import time
from collections.abc import Callable, Coroutine
from typing import Any

import numpy as np

from companion import guidance
from companion.autopilots import FlightMode
from companion.geofence import Geofence
from companion.guidance import GuidanceConfig, Setpoint
from companion.link.base import LinkError, VehicleLink
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
from companion.link.streams import needs
from companion.mission.clock import VehicleClock
from companion.mission.config import MissionConfig
from companion.mission.control import (
    Action,
    Control,
    EndMission,
    LinkRestored,
    ModeReport,
    OperatorPause,
    OperatorResume,
    Refused,
    enter,
    step,
)
from companion.mission.core_for import core_for
from companion.mission.fence_watch import FenceWatch
from companion.mission.phase import Phase
from companion.mission.swarm_core import SwarmCore, SwarmExchange
from companion.mission.vehicle_fence import VehicleFence
from companion.sensors.base import SensorSource
from companion.sensors.mavlink_source import MavlinkSensorSource
from companion.telemetry import events
from companion.telemetry.mission_log import EventSink, Recovered

log = logging.getLogger(__name__)
_SETPOINT_GAP_S = 0.5
"""A gap in our setpoints this long (vehicle s) can explain a HOLD: PX4's COM_OF_LOSS_T is 1 s."""
_OPEN_BACKOFF_MAX_S = 8.0
_TEXT_LEVEL = {0: logging.ERROR, 1: logging.ERROR, 2: logging.ERROR, 3: logging.ERROR,
               4: logging.WARNING, 5: logging.INFO, 6: logging.INFO}  # fmt: skip
"""MAV_SEVERITY -> log level for the vehicle's STATUSTEXT (7, debug, is logged at DEBUG)."""


class VehicleMission:
    """Flies one vehicle's MDM search over ``link``; events go to ``sink``.

    Tasks (one TaskGroup): ``decide`` (events in, policy, setpoints and the companion
    HEARTBEAT out: if it dies, the heartbeat stops), ``lifecycle`` (connect, mode, arm,
    takeoff, search, end), ``supervise`` (link loss -> stop commanding, reconnect with
    backoff), ``sensor`` (the sensor source's own work: MDM_SENSOR switches for ``mavlink``,
    the silence watch for ``mqtt``).
    """

    def __init__(
        self,
        config: MissionConfig,
        link: VehicleLink,
        sink: EventSink,
        *,
        recovered: Recovered | None = None,
        fence: Geofence | None = None,
        peers: SwarmExchange | None = None,
        sensors: SensorSource | None = None,
        watch: FenceWatch | None = None,
        start: tuple[float, float] | None = None,
        own_fence: list[tuple[float, float]] | None = None,
    ) -> None:
        profile = config.profile
        self.config = config
        self.link = link
        self.sink = sink
        self.recovered = recovered or Recovered()
        self.clock = VehicleClock(floor=self.recovered.last_time)
        self.sensors = sensors or MavlinkSensorSource(link, len(profile.sensors))
        self.sensors.report = self.emit
        self.core = core_for(config, lambda: self.sensors.signal, peers)
        if isinstance(self.core, SwarmCore):
            self.core.emit = self.emit  # swarm_follow events in the mission log
        self.fence = fence or Geofence.rectangle(profile.area.north, profile.area.east)
        self.guide = GuidanceConfig(
            speed=profile.fleet.speed,
            altitude=config.altitude,
            acceptance_radius=profile.fleet.acceptance_radius,
        )
        self.control = Control()
        """Phase and who is in control: the pure state machine of mission/control.py."""
        self.heartbeat: Heartbeat | None = None
        self.position: LocalPosition | None = None
        self.status: SystemStatus | None = None
        self.end_reason: str | None = None
        self.search_start = self.recovered.search_start
        self.latencies: list[float] = []
        self.real_targets = sum(not t.false_target for t in profile.targets)
        self._last_heartbeat_wall = 0.0
        self._period = 0.1
        self._last_tick = -np.inf
        self._changed = asyncio.Event()
        self._setpoint_time = -np.inf
        """Vehicle time of the position our last setpoint answered."""
        self._received_time = -np.inf
        """Vehicle time of the newest position received (acted on or not)."""
        self._climbing_by_command = False
        self._main: asyncio.Task[object] | None = None
        self._end_action = config.end_action
        self._chores: set[asyncio.Task[None]] = set()
        self._signals = 0
        self._speed_report: str | None = None
        """What setting the profile's speed on the vehicle gave (once per process)."""
        self.max_search_speed = 0.0
        """Fastest horizontal speed the vehicle reported while searching, m/s."""
        self.watch = watch
        """The fence and search area against the GPS position (geo-referenced profiles)."""
        self.gps: GlobalPosition | None = None
        self._inside_fence = False
        """The GPS position was inside the fence since the transit began: from then on,
        outside is a breach (a vehicle may start outside and fly in)."""
        self.start = start
        """Where the search begins (profile frame); None: where the vehicle is."""
        self.refusal: str | None = None
        """Why the companion did not start the vehicle, when it refused."""
        self.vehicle_fence = (
            VehicleFence(link, own_fence, config.vehicle, self.emit) if own_fence else None
        )

    # -- public ----------------------------------------------------------------------------

    async def run(self) -> str:
        """Fly the mission; returns why it ended."""
        self._main = asyncio.current_task()
        if not await self._open_link():
            return self.end_reason or "stopped"
        self.record(events.Start(self.config.vehicle, self.config.profile.name, self.config.seed,
                                 len(self.recovered.confirmed), self.config.altitude))  # fmt: skip
        try:
            async with asyncio.TaskGroup() as tg:
                loops = [
                    tg.create_task(self._decide(), name=f"v{self.config.vehicle}-decide"),
                    tg.create_task(self._supervise(), name=f"v{self.config.vehicle}-supervise"),
                    tg.create_task(self.sensors.run(), name=f"v{self.config.vehicle}-sensor"),
                ]  # fmt: skip
                life = tg.create_task(self._lifecycle(), name=f"v{self.config.vehicle}-lifecycle")
                life.add_done_callback(lambda _: [t.cancel() for t in loops])
        finally:
            self._emit_latency()
            await self.link.close()
        return self.end_reason or "stopped"

    def request_end(self, reason: str) -> None:
        """End the search and fly the end action (operator signal, mission time, battery)."""
        if self.end_reason is None:
            self.end_reason = reason
            self._changed.set()

    def operator_stop(self) -> None:
        """SIGINT/SIGTERM: the first one ends the mission with its end action and waits for it
        (also when the mission was already ending); a second one stops commanding at once."""
        self._signals += 1
        v = self.config.vehicle
        if self._signals > 1:
            print(f"vehicle {v}: second signal: stop commanding and exit", flush=True)
            if self._main is not None:
                self._main.cancel()
            return
        self.request_end("operator")
        armed = self.heartbeat is not None and self.heartbeat.armed
        doing = (
            f"flying {self._end_action.value.upper()} and waiting until it lands and disarms"
            if armed and self.phase not in (Phase.PAUSED, Phase.LINK_LOST)
            else "not commanding the vehicle (not armed, or a pilot has it)"
        )
        print(f"vehicle {v}: ending ({self.end_reason}): {doing}; signal again to stop at once",
              flush=True)  # fmt: skip

    def emit(self, event: str, **fields: object) -> None:
        """A record that is not a decision (ticks, texts, measurements)."""
        self.sink.emit(self.clock.now, event, **fields)

    def record(self, event: events.DurableEvent) -> None:
        """A durable event (telemetry/events.py: the same classes read it back)."""
        self.sink.emit(self.clock.now, event.NAME, **events.to_fields(event))

    # -- operator (MQTT commands): each returns None when obeyed, else why not -------------

    def operator_pause(self) -> str | None:
        """Stop commanding and hold (autopilot HOLD) until ``operator_resume``."""
        return self._step(step(self.control, OperatorPause()), by="operator")

    def operator_resume(self) -> str | None:
        """Back to the guided mode and the search, as after a link loss."""
        return self._step(step(self.control, OperatorResume()))

    def operator_end(self, action: FlightMode, reason: str) -> str | None:
        """End the mission now with ``action`` (RTL or LAND) instead of the configured one."""
        if self.end_reason is not None:
            return f"{action.value}: the mission is already ending ({self.end_reason})"
        self._end_action = action
        self.request_end(reason)
        return None

    def snapshot(self) -> dict[str, object]:
        """What the vehicle is doing now (the MQTT state message)."""
        pos, hb, ap = self.position, self.heartbeat, self.link.autopilot
        t = self.clock.now
        ci = self.core.index_value(t) if self.core.started else math.nan
        sensor = self.core.sensor()
        return {"vehicle": self.config.vehicle, "t": round(t, 3), "phase": self.phase.value,
                "mode": ap.mode_name(hb.custom_mode) if hb is not None and ap is not None else None,
                "armed": hb.armed if hb is not None else None, "level": self.core.level,
                "sensor": sensor, "sensor_name": self.config.profile.sensors[sensor].name,
                "ci": None if math.isnan(ci) else round(ci, 4), "found": self.core.confirmed_count,
                **({} if pos is None else {"north": round(pos.north, 1), "east": round(pos.east, 1),
                                           "alt": round(-pos.down, 1)})}  # fmt: skip

    async def _hold(self) -> None:
        try:
            result = await self.link.set_mode(FlightMode.HOLD)
            if not result:
                log.error("vehicle %d refused hold: %s", self.config.vehicle, result.describe())
        except LinkError as exc:
            log.error("vehicle %d: hold not sent: %s", self.config.vehicle, exc)

    # -- decision loop ---------------------------------------------------------------------

    async def _decide(self) -> None:
        events = self.link.events
        loop = asyncio.get_running_loop()
        me = asyncio.current_task()
        failed: list[Exception] = []
        timer: asyncio.TimerHandle | None = None

        def beat() -> None:
            # The companion HEARTBEAT every period (wall s), scheduled by this loop and stopped
            # with it: if the decision loop dies, the vehicle stops hearing the companion. A
            # timer, not a timeout on every wait: one plain queue wait per wake-up is most of
            # the asyncio cost at 1000 positions per wall second.
            nonlocal timer
            try:
                self.link.send_heartbeat()
            except Exception as exc:  # ends the decision loop with this error
                failed.append(exc)
                if me is not None:
                    me.cancel()
                return
            timer = loop.call_later(self.config.heartbeat_period, beat)

        beat()
        try:
            while True:
                self._handle_queued(await events.get(), events)
        except asyncio.CancelledError:
            if failed:
                raise failed[0] from None
            raise
        finally:
            if timer is not None:
                timer.cancel()

    def _handle_queued(self, first: LinkEvent, events: asyncio.Queue[LinkEvent]) -> None:
        """``first`` and the events queued behind it, in order; of several positions only the
        newest is acted on: after a stall (a loaded machine, a sped-up vehicle) the older ones
        are stale, and a setpoint computed from each would steer seconds late."""
        if events.empty():
            self._handle(first)
            return
        batch = [first]
        while not events.empty():
            batch.append(events.get_nowait())
        # How far the vehicle's clock has run, for a HOLD queued before the newest position.
        self._received_time = max(
            [self._received_time] + [e.time for e in batch if isinstance(e, LocalPosition)]
        )
        newest = max(i for i, e in enumerate(batch) if isinstance(e, LocalPosition) or i == 0)
        for i, event in enumerate(batch):
            if i == newest or not isinstance(event, LocalPosition):
                self._handle(event)

    def _handle(self, event: LinkEvent) -> None:
        if isinstance(event, LocalPosition):
            self._on_position(event)
        elif isinstance(event, GlobalPosition):
            self._on_gps(event)
        elif isinstance(event, SensorContact | SensorSignal):
            self.sensors.accept(event)
        elif isinstance(event, Heartbeat):
            self._on_heartbeat(event)
        elif isinstance(event, StatusText):
            self._on_text(event)
        elif isinstance(event, StraySource):
            self.emit("stray", address=event.address, locked=event.locked)
        elif isinstance(event, SystemStatus):
            self.status = event
            if (
                0 <= event.battery_remaining < self.config.battery_min
                and self.phase is Phase.SEARCH
            ):
                self.request_end(f"battery {event.battery_remaining}%")
        self._changed.set()

    def _on_text(self, text: StatusText) -> None:
        """The autopilot's own words on the console and in the mission log."""
        log.log(_TEXT_LEVEL.get(text.severity, logging.DEBUG), "vehicle %d says: %s",
                self.config.vehicle, text.text)  # fmt: skip
        if text.severity <= 6:
            self.emit("statustext", severity=text.severity, text=text.text)

    def _on_heartbeat(self, hb: Heartbeat) -> None:
        self._last_heartbeat_wall = time.perf_counter()
        previous = self.heartbeat
        self.heartbeat = hb
        ap = self.link.autopilot
        if ap is None:
            return
        guided = ap.is_guided(hb.custom_mode)
        if previous is None or previous.custom_mode != hb.custom_mode:
            self.record(events.ModeChange(ap.mode_name(hb.custom_mode), guided))
        report = ModeReport(guided, self._hold_mode(hb), self._setpoints_stalled(),
                            self.core.started)  # fmt: skip
        self._step(step(self.control, report), mode=ap.mode_name(hb.custom_mode))

    def _step(self, result: tuple[Control, tuple[Action, ...]] | Refused, *, by: str | None = None,
              mode: str = "") -> str | None:  # fmt: skip
        """Apply a transition of the control state machine and perform its actions; returns
        why an operator request was refused (None when applied)."""
        if isinstance(result, Refused):
            return result.reason
        state, actions = result
        self._apply(state, by=by)
        v = self.config.vehicle
        for action in actions:
            if action is Action.HOLD:
                self._chore(self._hold())
            elif action is Action.SAY_RESUMING:
                log.info("vehicle %d back in the guided mode: resuming", v)
            elif action is Action.WARN_FALLBACK:
                log.warning(
                    "vehicle %d: autopilot fell back to HOLD; re-entering the guided mode", v
                )
            elif action is Action.WARN_TAKEN_OVER:
                log.warning(
                    "vehicle %d: mode changed to %s by someone else; not commanding", v, mode
                )
        return None

    def _chore(self, work: Coroutine[Any, Any, None]) -> None:
        """Run ``work`` beside the loops (kept referenced until done)."""
        task = asyncio.ensure_future(work)
        self._chores.add(task)
        task.add_done_callback(self._chores.discard)

    def _on_position(self, pos: LocalPosition) -> None:
        self._received_time = max(self._received_time, pos.time)
        prev = self.position
        t = self.clock.update(pos.time)
        if prev is not None and pos.time > prev.time:
            self._period += 0.2 * (min(pos.time - prev.time, 1.0) - self._period)
        self.position = pos
        self.sensors.observe(t, pos.north, pos.east)
        if t - self._last_tick >= 10.0:
            self._last_tick = t
            self.emit("tick", phase=self.phase.value, level=self.core.level, wall=round(time.time(), 3),
                      north=round(pos.north, 1), east=round(pos.east, 1),
                      alt=round(-pos.down, 1), found=self.core.confirmed_count)  # fmt: skip
        if self.phase is Phase.SEARCH:
            self._search_step(t, pos)
        elif self.phase is Phase.PAUSED:
            if (
                self.search_start is not None
                and t - self.search_start >= self.config.search_duration
            ):
                self.request_end("mission time (paused)")  # ends without commanding
            elif not self.control.operator_paused and self._guided_needs_stream():
                # A pilot hands back by switching to OFFBOARD, which PX4 refuses without a
                # setpoint stream: keep one flowing that holds here (ignored in other modes).
                self._send(Setpoint(pos.north, pos.east, pos.down, 0.0, 0.0, 0.0), pos)
        elif self.phase is Phase.PREPARE:
            # Neutral stream before arming: stay where it is (a climb here would start the
            # moment the mode switches, before the vehicle is armed).
            self._send(Setpoint(pos.north, pos.east, pos.down, 0.0, 0.0, 0.0), pos)
        elif self.phase is Phase.TRANSIT and self.start is not None:
            here = np.array([pos.north, pos.east])
            goal = np.array(self.start)
            self._send(guidance.pursuit(here, pos.down, goal, self.guide, self.fence,
                                        self._period), pos)  # fmt: skip
        elif self.phase is Phase.CLIMB and not self._climbing_by_command:
            here = np.array([pos.north, pos.east])
            self._send(guidance.pursuit(here, pos.down, here, self.guide, self.fence, 1.0), pos)

    def _on_gps(self, gps: GlobalPosition) -> None:
        """The fence watch: outside the fence after having been inside it (transit or
        search) ends the search; the end action (RTL) flies the vehicle home, inside."""
        self.gps = gps
        watch = self.watch
        if watch is None:
            return
        breach = watch.breach(gps.north, gps.east)
        own = self.vehicle_fence
        if (breach is None and own is not None and own.installed and not own.enabling
                and self.phase not in (Phase.RETURN, Phase.DONE)):  # fmt: skip
            self._chore(own.enable())
        if self.phase not in (Phase.TRANSIT, Phase.SEARCH):
            return
        if breach is None:
            self._inside_fence = True
            return
        if self._inside_fence and self.end_reason is None:
            log.error("vehicle %d is %s (GPS %.7f, %.7f): ending the search", self.config.vehicle,
                      breach, gps.lat, gps.lon)  # fmt: skip
            self.emit("fence", state="breach", where=breach, lat=gps.lat, lon=gps.lon)
            self.request_end(f"outside the fence: {breach}")

    def _search_step(self, t: float, pos: LocalPosition) -> None:
        self.max_search_speed = max(self.max_search_speed, math.hypot(pos.vn, pos.ve))
        here = np.array([pos.north, pos.east])
        contacts = self.sensors.take()
        # Reached means reached as far as the fence lets the vehicle go: a waypoint between the
        # area's edge and the fence is clamped, and the clamped point is where it stops.
        goal = self.fence.clamp(self.core.waypoint)
        reached = guidance.reached(here, goal, self.guide.acceptance_radius)
        if self.core.needs_step(t, reached, contacts):
            d = self.core.step(t, here, reached, contacts)
            if d.detected:
                self.record(events.Detection(round(pos.north, 1), round(pos.east, 1), d.level))
            for north, east in d.confirmed:
                self.record(events.Confirmation(north, east, d.previous_level,
                                                self.core.confirmed_count))  # fmt: skip
            if d.fell_back:
                self.record(events.Fallback(d.level))
            if d.level != d.previous_level:
                self.record(events.Level(d.level, self.core.sensor()))
                self.sensors.select(self.core.sensor(), t)
        if self.search_start is not None and t - self.search_start >= self.config.search_duration:
            self.request_end("mission time")
        elif self.config.stop_when_all_found and self.core.confirmed_count >= self.real_targets:
            self.request_end("all targets")
        if self.end_reason is not None:
            return
        if self.config.setpoints == "position":
            wp = self.fence.clamp(self.core.waypoint)
            sp = Setpoint(float(wp[0]), float(wp[1]), -self.guide.altitude, 0.0, 0.0, 0.0)
        else:
            sp = guidance.pursuit(here, pos.down, self.core.waypoint, self.guide, self.fence,
                                  self._period)  # fmt: skip
        self._send(sp, pos)

    def _send(self, sp: Setpoint, pos: LocalPosition) -> None:
        self.link.send_setpoint(sp, self.config.setpoints)
        self._setpoint_time = pos.time
        if len(self.latencies) < 200_000:
            self.latencies.append(time.perf_counter() - pos.received)

    # -- lifecycle -------------------------------------------------------------------------

    async def _lifecycle(self) -> None:
        if self.recovered.ended:
            # A restart after the end must not take the vehicle back from its RTL / landing.
            self.end_reason = "already ended (mission log)"
            self._set_phase(Phase.DONE)
            return
        await self._await_vehicle()
        if self.config.dedicated_link:
            await self.link.configure_streams()
        await self._ensure_streams()
        await self._learn_origin()
        await self._check_start()
        if self.vehicle_fence is not None and self.end_reason is None:
            self._chore(self.vehicle_fence.install())
        while self.end_reason is None:
            await self._until(lambda: self.heartbeat is not None and self.position is not None)
            if self.end_reason is not None:
                break
            if self.phase is Phase.PAUSED or self.phase is Phase.LINK_LOST:
                await self._until(lambda: self.phase not in (Phase.PAUSED, Phase.LINK_LOST))
                continue
            if not self._airborne_guided() and not await self._prepare():
                await self._sleep_vehicle(1.0)
                continue
            await self.link.begin_setpoints()
            if self._speed_report is None:
                self._speed_report = await self.link.set_speed(self.config.profile.fleet.speed)
                log.info("vehicle %d speed: %s", self.config.vehicle, self._speed_report)
                self.emit("speed", report=self._speed_report)
            if self.search_start is None and self.start is not None and not await self._transit():
                continue
            self._start_search()
            await self._until(lambda: self.phase is not Phase.SEARCH)
        await self._finish()

    async def _open_link(self) -> bool:
        """Open the link, retrying with backoff while the endpoint is not up (an autopilot
        still booting); False when the mission was ended meanwhile."""
        backoff, attempt = 0.5, 0
        while True:
            try:
                await self.link.open()
                return True
            except LinkError as exc:
                attempt += 1
                wait = min(backoff * 2 ** (attempt - 1), _OPEN_BACKOFF_MAX_S)
                log.warning("vehicle %d: %s; retry %d in %.1f s", self.config.vehicle, exc,
                            attempt, wait)  # fmt: skip
            deadline = time.monotonic() + wait
            while time.monotonic() < deadline:
                if self.end_reason is not None:
                    return False
                await asyncio.sleep(0.1)

    async def _learn_origin(self) -> None:
        """Geo-referenced profiles: where the vehicle's local frame starts (the link shifts
        positions into the profile's frame from then on); asked again until known."""
        if self.link.alignment is None:
            return
        while self.end_reason is None:
            missing = await self.link.learn_origin()
            origin = self.link.alignment.origin
            if missing is None and origin is not None:
                a = self.link.alignment
                self.emit("frame", source=origin.source, lat=round(origin.lat, 7),
                          lon=round(origin.lon, 7), north=round(a.north, 2),
                          east=round(a.east, 2))  # fmt: skip
                return
            log.warning("vehicle %d: origin of its local frame unknown: %s; asking again",
                        self.config.vehicle, missing)  # fmt: skip
            await asyncio.sleep(2.0)

    async def _check_start(self) -> None:
        """Refuse to start a vehicle (GPS position) too far outside the search area."""
        if self.watch is None:
            return
        self.gps = None  # one taken after the origin is known: the GPS has a fix by then
        await self._until(lambda: self.gps is not None)
        gps = self.gps
        if gps is None:
            return
        why = self.watch.start_refusal(gps.north, gps.east)
        if why is None:
            return
        self.refusal = (f"vehicle {self.config.vehicle} (system {self.config.system_id}) at "
                        f"{gps.lat:.6f}, {gps.lon:.6f} is {why} of profile "
                        f"{self.config.profile.name}: not starting")  # fmt: skip
        log.error("%s", self.refusal)
        self.emit("refused", command="start", reason=self.refusal)
        self.request_end(f"refused: {self.refusal}")

    async def _transit(self) -> bool:
        """Fly at the search altitude to the start point; the search clock starts there.
        False when the phase changed on the way (a pilot, a fall-back): the lifecycle retries."""
        pos, start = self.position, self.start
        assert pos is not None
        assert start is not None
        distance = math.hypot(start[0] - pos.north, start[1] - pos.east)
        t0 = self.clock.now
        self._set_phase(Phase.TRANSIT)
        self.emit("transit", state="begin", north=round(pos.north, 1), east=round(pos.east, 1),
                  to_north=round(start[0], 1), to_east=round(start[1], 1),
                  distance=round(distance, 1))  # fmt: skip
        log.info("vehicle %d: transit %.0f m to its start point (%.0f, %.0f)",
                 self.config.vehicle, distance, *start)  # fmt: skip
        limit = 60.0 + 3.0 * distance / self.config.profile.fleet.speed
        arrived = await self._until(
            lambda: not self._in(Phase.TRANSIT) or (
                self.position is not None and guidance.reached(
                    np.array([self.position.north, self.position.east]), np.array(start),
                    self.guide.acceptance_radius)),
            limit,
        )  # fmt: skip
        if not self._in(Phase.TRANSIT):
            return False
        if not arrived:
            if self.end_reason is None:
                self.request_end(f"transit not done in {limit:.0f} s")
            return False
        self.emit("transit", state="done", seconds=round(self.clock.now - t0, 1))
        return True

    async def _await_vehicle(self) -> None:
        """Wait for the vehicle's HEARTBEAT, saying every few seconds what is heard instead."""
        period = self.config.waiting_line_period
        next_line = time.monotonic() + period
        while self.heartbeat is None and self.end_reason is None:
            self._changed.clear()
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._changed.wait(), max(next_line - time.monotonic(), 0.0))
            if self.heartbeat is not None or time.monotonic() < next_line:
                continue  # other messages of the vehicle woke us: not yet time for a line
            next_line = time.monotonic() + period
            heard = sorted(self.link.heard)
            log.warning("vehicle %d: waiting on %s for system %d; heard %s%s",
                        self.config.vehicle, self.link.describe(), self.config.system_id,
                        f"systems {heard}" if heard else "nothing",
                        " (no autopilot HEARTBEAT from it yet)"
                        if self.config.system_id in heard else "")  # fmt: skip

    async def _ensure_streams(self) -> None:
        """Ask for every message the mission reads; while one is missing, say which and what
        was tried, and ask again (a vehicle still booting may not answer the first time)."""
        while self.end_reason is None:
            problems = await self.link.request_streams(
                needs(global_position=self.link.global_position)
            )
            if not problems:
                return
            for line in problems:
                log.warning("vehicle %d: missing %s", self.config.vehicle, line)
            self.emit("streams", missing=problems)
            await asyncio.sleep(5.0)

    def _airborne_guided(self) -> bool:
        hb, pos, ap = self.heartbeat, self.position, self.link.autopilot
        if hb is None or pos is None or ap is None:
            return False
        near = -pos.down > 0.8 * self.config.altitude
        return hb.armed and ap.is_guided(hb.custom_mode) and near

    async def _prepare(self) -> bool:
        """Stream setpoints, switch to the guided mode, arm, take off. False to retry."""
        self._set_phase(Phase.PREPARE)
        await self._until(lambda: self.status is None or self.status.healthy, 30.0)
        await self._sleep_vehicle(1.0)  # setpoints flowing before the mode switch (PX4)
        ap = self.link.autopilot
        if ap is None or not self._in(Phase.PREPARE):
            return False
        if not await self._ensure_guided():
            return False
        hb = self.heartbeat
        if hb is not None and not hb.armed:
            result = await self.link.arm()
            if not result:
                log.warning("vehicle %d refused to arm: %s", self.config.vehicle, result.describe())
                self.emit("refused", command="arm", outcome=result.outcome.value,
                          reason=result.reason)  # fmt: skip
                return False
        await self._until(lambda: self.heartbeat is not None and self.heartbeat.armed, 10.0)
        self._set_phase(Phase.CLIMB)
        pos = self.position
        on_ground = pos is not None and -pos.down < 0.5 * self.config.altitude
        if ap.takeoff_by_command and on_ground:
            self._climbing_by_command = True
            result = await self.link.takeoff(self.config.altitude)
            if not result:
                self._climbing_by_command = False
                log.warning("vehicle %d: takeoff %s", self.config.vehicle, result.describe())
                self.emit("refused", command="takeoff", outcome=result.outcome.value,
                          reason=result.reason)  # fmt: skip
                return False
            # If the autopilot's takeoff stops short (its own takeoff altitude), setpoints
            # finish the climb: wait for the altitude or for the climb to stall airborne.
            # A fall-back HOLD during the climb sends the phase back to PREPARE: retry from there.
            await self._until(
                lambda: self._climb_done_or_stalled() or not self._in(Phase.CLIMB),
                self.config.climb_timeout,
            )
            self._climbing_by_command = False
            if self._in(Phase.CLIMB):
                await self.link.begin_setpoints()  # setpoints finish a climb that stopped short
        try:
            ok = await self._until(
                lambda: (
                    not self._in(Phase.CLIMB)
                    or (
                        self.position is not None
                        and -self.position.down > 0.95 * self.config.altitude
                    )
                ),
                self.config.climb_timeout,
            )
        finally:
            self._climbing_by_command = False
        if not self._in(Phase.CLIMB):
            return False
        if not ok:
            self.request_end("climb timeout")
            return False
        return True

    def _climb_done_or_stalled(self) -> bool:
        pos = self.position
        if pos is None:
            return False
        alt = -pos.down
        return alt > 0.95 * self.config.altitude or (alt > 1.0 and abs(pos.vd) < 0.05)

    async def _ensure_guided(self) -> bool:
        ap = self.link.autopilot
        assert ap is not None
        for _ in range(3):
            hb = self.heartbeat
            if hb is not None and ap.is_guided(hb.custom_mode):
                return True
            result = await self.link.set_mode(FlightMode.GUIDED)
            if not result:
                log.warning("vehicle %d: guided mode %s", self.config.vehicle, result.describe())
                self.emit("refused", command="guided", outcome=result.outcome.value,
                          reason=result.reason)  # fmt: skip
                continue
            if await self._until(
                lambda: self.heartbeat is not None and ap.is_guided(self.heartbeat.custom_mode),
                5.0,
            ):
                return True
        return False

    def _start_search(self) -> None:
        pos = self.position
        assert pos is not None
        here = np.array([pos.north, pos.east])
        t = self.clock.now
        if self.search_start is None:
            self.search_start = t
        if not self.core.started:
            self.core.start(here, t, self.recovered.confirmed)
        self._set_phase(Phase.SEARCH, search_start=self.search_start)
        self.record(events.Level(self.core.level, self.core.sensor()))
        self.sensors.select(self.core.sensor(), t)

    async def _finish(self) -> None:
        armed = self.heartbeat is not None and self.heartbeat.armed
        ended = step(self.control, EndMission(armed))
        assert not isinstance(ended, Refused)
        state, actions = ended
        self._apply(state)
        self.record(events.End(str(self.end_reason), self.core.confirmed_count))
        self._report_speed()
        self.sensors.select(-1, self.clock.now)
        if Action.END_ACTION not in actions:
            self._set_phase(Phase.DONE)
            return
        result = await self.link.set_mode(self._end_action)
        if not result:
            log.error("vehicle %d refused %s: %s", self.config.vehicle, self._end_action.value,
                      result.describe())  # fmt: skip
        if self.config.land_wait > 0:
            log.info("vehicle %d: %s; waiting up to %g vehicle s until it lands and disarms",
                     self.config.vehicle, self._end_action.value.upper(), self.config.land_wait)  # fmt: skip
            if await self._until(
                lambda: self.heartbeat is not None and not self.heartbeat.armed,
                self.config.land_wait,
            ):
                log.info("vehicle %d: landed and disarmed", self.config.vehicle)
            else:
                log.error("vehicle %d: still armed %g vehicle s after %s", self.config.vehicle,
                          self.config.land_wait, self._end_action.value.upper())  # fmt: skip
        self._set_phase(Phase.DONE)

    # -- link supervision ------------------------------------------------------------------

    async def _supervise(self) -> None:
        backoff = 0.5
        while True:
            await asyncio.sleep(0.25)
            if self.heartbeat is None or self.phase is Phase.DONE:
                continue
            silent = time.perf_counter() - self._last_heartbeat_wall
            if silent <= self.config.link_timeout:
                backoff = 0.5
                continue
            resume = self.phase
            if resume is not Phase.LINK_LOST:
                log.warning("vehicle %d: no heartbeat for %.1f s; stop commanding",
                            self.config.vehicle, silent)  # fmt: skip
                self._set_phase(Phase.LINK_LOST)
                self.record(events.LinkState("lost", round(silent, 1)))
            await asyncio.sleep(backoff * (1 + random.random()))  # jittered backoff
            backoff = min(backoff * 2, 8.0)
            try:
                await self.link.reconnect()
            except (OSError, LinkError) as exc:
                log.warning("reconnect failed: %s", exc)
                continue
            deadline = time.perf_counter() + 2.0 * self.config.link_timeout
            while time.perf_counter() < deadline:
                await asyncio.sleep(0.1)
                if time.perf_counter() - self._last_heartbeat_wall < 1.0:
                    self.record(events.LinkState("restored"))
                    self._after_link_restored(resume)
                    break

    def _after_link_restored(self, before: Phase) -> None:
        hb, ap = self.heartbeat, self.link.autopilot
        if hb is None or ap is None:
            event = LinkRestored(before, known=False, guided=False, armed=False, hold=False)
        else:
            event = LinkRestored(before, True, ap.is_guided(hb.custom_mode), hb.armed,
                                 self._hold_mode(hb))  # fmt: skip
        self._step(step(self.control, event))

    def _setpoints_stalled(self) -> bool:
        """The vehicle's clock ran _SETPOINT_GAP_S or more past our last setpoint's position."""
        return bool(self._received_time - self._setpoint_time >= _SETPOINT_GAP_S)

    def _guided_needs_stream(self) -> bool:
        ap = self.link.autopilot
        return ap is not None and ap.guided_needs_stream

    def _hold_mode(self, hb: Heartbeat) -> bool:
        ap = self.link.autopilot
        return ap is not None and hb.custom_mode == ap.custom_mode(FlightMode.HOLD)

    # -- helpers ---------------------------------------------------------------------------

    def _in(self, phase: Phase) -> bool:
        return self.phase is phase

    @property
    def phase(self) -> Phase:
        return self.control.phase

    def _set_phase(self, phase: Phase, *, search_start: float | None = None) -> None:
        self._apply(enter(self.control, phase), search_start=search_start)

    def _apply(
        self, state: Control, *, search_start: float | None = None, by: str | None = None
    ) -> None:
        """Take the new control state; a phase change is a ``phase`` event."""
        changed = state.phase is not self.control.phase
        self.control = state
        if changed:
            self.record(events.PhaseChange(state.phase.value, search_start, by))
            self._changed.set()

    async def _until(self, predicate: Callable[[], bool], timeout: float | None = None) -> bool:
        """Wait until ``predicate`` holds or ``timeout`` vehicle seconds pass (or the mission ends)."""
        start = self.clock.now
        while not predicate():
            if self.end_reason is not None and self.phase is not Phase.RETURN:
                return False
            if timeout is not None and self.clock.now - start >= timeout:
                return False
            self._changed.clear()
            await self._changed.wait()
        return True

    async def _sleep_vehicle(self, seconds: float) -> None:
        start = self.clock.now
        await self._until(lambda: self.clock.now - start >= seconds)

    def _report_speed(self) -> None:
        """A vehicle that kept below the profile's speed says so: an autopilot limit the
        companion could not raise, or the airframe (ArduCopter SITL: about 11 m/s at its default
        30-degree lean limit, ANGLE_MAX, with WPNAV_SPEED at 20 m/s)."""
        if not self.core.started:
            return
        asked = self.config.profile.fleet.speed
        self.emit("speed", max_search=round(self.max_search_speed, 2), asked=asked)
        if self.max_search_speed < 0.9 * asked:
            log.warning("vehicle %d flew at most %.1f m/s while searching; the profile asks "
                        "%g m/s: the vehicle caps it (%s)", self.config.vehicle,
                        self.max_search_speed, asked, self._speed_report)  # fmt: skip

    def _emit_latency(self) -> None:
        if self.latencies:
            ms = np.array(self.latencies) * 1e3
            self.emit("latency", n=len(ms), p50_ms=round(float(np.percentile(ms, 50)), 4),
                      p99_ms=round(float(np.percentile(ms, 99)), 4))  # fmt: skip
