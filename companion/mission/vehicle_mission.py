"""One vehicle's mission: the I/O around the lifecycle machine (lifecycle.py), the decision
loop and the link supervision, as named tasks."""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Coroutine
from typing import Any

from companion.autopilots import FlightMode
from companion.geofence import Geofence
from companion.guidance import GuidanceConfig
from companion.link.base import LinkError, VehicleLink
from companion.link.messages import (
    Heartbeat,
    LocalPosition,
)
from companion.link.telemetry_guard import TelemetryLimits
from companion.mission.config import MissionConfig
from companion.mission.control import (
    Action,
    Control,
    OperatorPause,
    OperatorResume,
    Refused,
)
from companion.mission.core_for import core_for
from companion.mission.event_intake import EventIntake
from companion.mission.fence_watch import FenceWatch
from companion.mission.lawnmower_core import LawnmowerCore
from companion.mission.lifecycle import Event, Mission, step
from companion.mission.lifecycle_events import (
    Do,
    EndRequested,
    OperatorEnd,
    SearchBegun,
    Signal,
)
from companion.mission.lifecycle_steps import LifecycleSteps
from companion.mission.link_supervision import LinkSupervision
from companion.mission.mission_exit import MissionExit, final_exit, where
from companion.mission.observed import Observed
from companion.mission.phase import Phase
from companion.mission.phase_steering import PhaseSteering
from companion.mission.position_failsafe import PositionFailsafe
from companion.mission.search_answer import SearchAnswer
from companion.mission.setpoint_guard import SetpointGuard
from companion.mission.setpoint_out import SetpointOut
from companion.mission.state_message import state_message
from companion.mission.swarm_core import SwarmCore, SwarmExchange
from companion.mission.vehicle_clock import VehicleClock
from companion.mission.vehicle_fence import VehicleFence
from companion.mission.vehicle_waits import VehicleWaits
from companion.sensors.base import SensorSource
from companion.sensors.mavlink_source import MavlinkSensorSource
from companion.telemetry import events
from companion.telemetry.mission_log import EventSink, Recovered

log = logging.getLogger(__name__)
_RATE_MARGIN = 1.5
"""The vehicle clock may run this much faster than the speed-up asked (a simulator catching up
after a stall of its host)."""


class VehicleMission:
    """Flies one vehicle's MDM search over ``link``; events go to ``sink``.

    Tasks (one TaskGroup): ``decide`` (events in, policy, setpoints and the companion
    HEARTBEAT out: if it dies, the heartbeat stops), ``lifecycle`` (the steps the lifecycle
    machine asks for: lifecycle_steps.py), ``supervise`` (link loss -> stop commanding,
    reconnect with backoff), ``sensor`` (the sensor source's own work: MDM_SENSOR switches for
    ``mavlink``, the silence watch for ``mqtt``). Every decision of the lifecycle is the pure
    machine's (:meth:`feed`); here is the I/O.
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
        clock = VehicleClock(floor=self.recovered.last_time)
        self.seen = Observed(clock, self.recovered.search_start)
        self.waits = VehicleWaits(self.seen.clock, self._ended)
        self.sensors = sensors or MavlinkSensorSource(link, len(profile.sensors))
        self.sensors.report = self.emit
        self.fence = fence or Geofence.rectangle(profile.area.north, profile.area.east)
        self.core = core_for(config, lambda: self.sensors.signal, peers, self.fence)
        if isinstance(self.core, SwarmCore | LawnmowerCore):
            self.core.emit = self.emit  # swarm_follow, lawnmower_* events in the mission log
        self.guide = GuidanceConfig(
            speed=profile.fleet.speed,
            altitude=config.altitude,
            acceptance_radius=profile.fleet.acceptance_radius,
        )
        self.state = Mission(end_action=config.end_action)
        """The lifecycle machine's state (mission/lifecycle.py), who is in control included."""
        self.real_targets = sum(not t.false_target for t in profile.targets)
        self._main: asyncio.Task[object] | None = None
        self._chores: set[asyncio.Task[None]] = set()
        self.watch = watch
        """The fence and search area against the GPS position (geo-referenced profiles)."""
        self.start = start
        """Where the search begins (profile frame); None: where the vehicle is."""
        self.vehicle_fence = (
            VehicleFence(link, own_fence, config.vehicle, self.emit) if own_fence else None
        )
        failsafe = profile.failsafe
        rate = None if config.max_speedup is None else config.max_speedup * _RATE_MARGIN
        link.guard.limits = TelemetryLimits(
            max_speed=max(profile.fleet.speed * failsafe.speed_margin, 10.0), max_rate=rate
        )
        self.setpoint_guard = SetpointGuard(
            self.guide, self.fence, config.setpoints, max(profile.fleet.altitude_step / 2, 1.0)
        )
        self.out = SetpointOut(
            config.vehicle, link, self.seen, self.setpoint_guard, config.setpoints, self.record
        )
        self.steering = PhaseSteering(self)
        self.intake = EventIntake(self, self.steering.on_position)
        self.answer = SearchAnswer(
            self.seen,
            self._steer_answered,
            handle=self.intake.handle,
            searching=lambda: self.phase is Phase.SEARCH and self.end_reason is None,
            config=config,
            core=self.core,
            sensors=self.sensors,
            acceptance_radius=self.guide.acceptance_radius,
        )
        """The search's common answer without the decision loop's events (search_answer.py)."""
        self.lifecycle = LifecycleSteps(self)
        self.position_failsafe = PositionFailsafe(self)
        self.supervision = LinkSupervision(self, self.position_failsafe.check)
        self.exit: MissionExit | None = None
        """How the companion ends (set by the end action's wait, the link's loss, or at the
        end of :meth:`run`); recorded as the log's ``exit``."""

    # -- public ----------------------------------------------------------------------------

    async def run(self) -> str:
        """Fly the mission; returns why it ended."""
        self._main = asyncio.current_task()
        if not await self.supervision.open_link():
            return self.end_reason or "stopped"
        self.record(
            events.Start(
                self.config.vehicle,
                self.config.profile.name,
                self.config.seed,
                len(self.recovered.confirmed),
                self.config.altitude,
            )
        )
        try:
            async with asyncio.TaskGroup() as tg:
                loops = [
                    tg.create_task(self.intake.decide(), name=f"v{self.config.vehicle}-decide"),
                    tg.create_task(
                        self.supervision.run(), name=f"v{self.config.vehicle}-supervise"
                    ),
                    tg.create_task(self.sensors.run(), name=f"v{self.config.vehicle}-sensor"),
                ]
                life = tg.create_task(
                    self.lifecycle.run(), name=f"v{self.config.vehicle}-lifecycle"
                )
                life.add_done_callback(lambda _: [t.cancel() for t in loops])
            await self._keep_flight_log()
        finally:
            self._emit_latency()
            self.position_failsafe.flush()
            self._record_exit()
            await self.link.close()
        return self.end_reason or "stopped"

    async def _keep_flight_log(self) -> None:
        """Landed and disarmed after a flight: the autopilot's own log into the run directory,
        or why there is none; printed and recorded (``flight_log``)."""
        hb, limit = self.seen.heartbeat, self.config.flight_log_wait
        if limit <= 0 or hb is None or hb.armed or not self.seen.flew:
            return
        kept = await self.link.download_log(self.config.autopilot_log_stem(), limit)
        print(f"vehicle {self.config.vehicle}: {kept.describe()}", flush=True)
        self.emit("flight_log", path=str(kept.path) if kept.path else None, size=kept.size,
                  note=kept.note or None)  # fmt: skip

    def _record_exit(self) -> None:
        """The ``exit`` record (mission_exit.final_exit)."""
        self.exit = final_exit(
            self.exit,
            self.seen.heartbeat,
            self.link.autopilot,
            self.where(),
            self.position_failsafe.cause,
            self.end_reason,
        )
        self.record(events.Exit(self.exit.status, self.exit.cause))

    def where(self) -> str:
        """Where the vehicle was last seen, for the exit's line."""
        return where(self.seen.position, self.seen.home)

    def request_end(self, reason: str) -> None:
        """End the search and fly the end action (operator signal, mission time, battery)."""
        self.feed(EndRequested(reason))

    def operator_stop(self) -> None:
        """SIGINT/SIGTERM: the first one ends the mission with its end action and waits for it
        (also when the mission was already ending); a second one stops commanding at once."""
        v = self.config.vehicle
        if Do.EXIT in self.feed(Signal()):
            print(f"vehicle {v}: second signal: stop commanding and exit", flush=True)
            if self._main is not None:
                self._main.cancel()
            return
        hb = self.seen.heartbeat
        armed = hb is not None and hb.armed
        doing = (
            f"flying {self.state.end_action.value.upper()} and waiting until it lands and disarms"
            if armed and self.phase not in (Phase.PAUSED, Phase.LINK_LOST)
            else "not commanding the vehicle (not armed, or a pilot has it)"
        )
        print(
            f"vehicle {v}: ending ({self.end_reason}): {doing}; signal again to stop at once",
            flush=True,
        )

    def emit(self, event: str, **fields: object) -> None:
        """A record that is not a decision (ticks, texts, measurements)."""
        self.sink.emit(self.seen.clock.now, event, **fields)

    def record(self, event: events.DurableEvent) -> None:
        """A durable event (telemetry/events.py: the same classes read it back)."""
        self.sink.emit(self.seen.clock.now, event.NAME, **events.to_fields(event))

    # -- operator (MQTT commands): each returns None when obeyed, else why not -------------

    def operator_pause(self) -> str | None:
        """Stop commanding and hold (autopilot HOLD) until ``operator_resume``."""
        return self.ask(OperatorPause(), by="operator")

    def operator_resume(self) -> str | None:
        """Back to the guided mode and the search, as after a link loss."""
        return self.ask(OperatorResume())

    def operator_end(self, action: FlightMode, reason: str) -> str | None:
        """End the mission now with ``action`` (RTL or LAND) instead of the configured one."""
        return self.ask(OperatorEnd(action, reason))

    def snapshot(self) -> dict[str, object]:
        """What the vehicle is doing now (the MQTT state message)."""
        names = [sensor.name for sensor in self.config.profile.sensors]
        return state_message(
            self.config.vehicle, names, self.seen, self.core, self.phase, self.link.autopilot
        )

    async def hold(self) -> None:
        """Ask the autopilot's HOLD (a refusal or a lost link is logged)."""
        try:
            result = await self.link.set_mode(FlightMode.HOLD)
            if not result:
                log.error("vehicle %d refused hold: %s", self.config.vehicle, result.describe())
        except LinkError as exc:
            log.error("vehicle %d: hold not sent: %s", self.config.vehicle, exc)

    def feed(self, event: Event, *, mode: str = "") -> tuple[Do, ...]:
        """An event the lifecycle machine never refuses: its steps left for the caller."""
        result = self._step(event, mode=mode)
        assert not isinstance(result, Refused), result  # only operator requests are refused
        return result

    def ask(self, event: Event, *, by: str | None = None) -> str | None:
        """An operator's request: None when obeyed, else why not."""
        result = self._step(event, by=by)
        return result.reason if isinstance(result, Refused) else None

    def _step(
        self, event: Event, *, by: str | None = None, mode: str = ""
    ) -> Refused | tuple[Do, ...]:
        """Take the machine's transition for ``event`` and perform who-is-in-control's
        actions; the lifecycle's steps are returned (the caller's I/O)."""
        result = step(self.state, event)
        if isinstance(result, Refused):
            return result
        state, actions = result
        started = self.seen.search_start if isinstance(event, SearchBegun) else None
        self._apply(state, by=by, search_start=started)
        v = self.config.vehicle
        steps: list[Do] = []
        for action in actions:
            if isinstance(action, Do):
                steps.append(action)
            elif action is Action.HOLD:
                self.chore(self.hold())
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
        return tuple(steps)

    def chore(self, work: Coroutine[Any, Any, None]) -> None:
        """Run ``work`` beside the loops (kept referenced until done)."""
        task = asyncio.ensure_future(work)
        self._chores.add(task)
        task.add_done_callback(self._chores.discard)

    def hold_mode(self, hb: Heartbeat) -> bool:
        """``hb``'s mode is the autopilot's fall-back (HOLD, LOITER)."""
        ap = self.link.autopilot
        return ap is not None and ap.is_fallback(hb.custom_mode)

    # -- helpers ---------------------------------------------------------------------------

    @property
    def phase(self) -> Phase:
        return self.state.control.phase

    @property
    def control(self) -> Control:
        """Who is in control: the part of the state that is control.py's machine."""
        return self.state.control

    @property
    def end_reason(self) -> str | None:
        return self.state.end_reason

    @property
    def end_action(self) -> FlightMode:
        return self.state.end_action

    def end_with(self, exit: MissionExit) -> None:
        """How the companion ends (the end action's wait, the link given up)."""
        self.exit = exit

    def _ended(self) -> bool:
        """The waits end: the mission ends, and not with the end action still flying."""
        return self.end_reason is not None and self.phase is not Phase.RETURN

    def _apply(
        self, state: Mission, *, search_start: float | None = None, by: str | None = None
    ) -> None:
        """Take the machine's new state; a phase change is a ``phase`` event."""
        changed = state.phase is not self.phase
        woken = changed or state.end_reason != self.state.end_reason
        self.state = state
        if changed:
            self.answer.forget()
            self.record(events.PhaseChange(state.phase.value, search_start, by))
        if woken:
            self.waits.wake()

    def _steer_answered(self, pos: LocalPosition, north: float, east: float) -> None:
        """The search's common answer steers: the pursuit, then the waits see the change."""
        self.out.pursue(pos, north, east)
        self.waits.wake()

    def _emit_latency(self) -> None:
        ms = self.out.latency_ms()
        if ms is not None:
            self.emit("latency", n=len(self.out.latencies), direct=self.answer.answered, **ms)
