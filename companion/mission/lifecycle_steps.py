"""The I/O of the lifecycle's steps: what ``VehicleMission`` does for each :class:`Do` the
lifecycle machine (lifecycle.py) asks for, and the outcome it feeds back. Every decision is the
machine's; here are only the waits, the commands and what they are told to say."""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Awaitable, Callable

import numpy as np

from companion import guidance
from companion.autopilots import FlightMode
from companion.link.outcome import CommandResult
from companion.mission.connect_steps import connect
from companion.mission.flown import Flown
from companion.mission.lifecycle_events import (
    Began,
    Climbed,
    ClimbStopped,
    Connected,
    ControlBack,
    Do,
    Ending,
    EndRecorded,
    Landed,
    Located,
    Outcome,
    Prepared,
    Retried,
    SearchBegun,
    SearchLeft,
    SetpointsBegun,
    TakeoffSent,
    TransitEnded,
)
from companion.mission.mission_exit import MissionExit
from companion.mission.phase import Phase
from companion.mission.return_speed import learn_return_speed
from companion.mission.safety_net import install_safety_net
from companion.telemetry import events

log = logging.getLogger(__name__)

_HEARTBEAT_FRESH_S = 2.0
"""A HEARTBEAT this recent (wall s) means the link is alive (they come at 1 Hz or faster)."""
_MODE_SEEN_S = 3.0
"""How long (wall s) a companion that does not wait for the landing waits for a HEARTBEAT to
report the end action's mode: three HEARTBEAT periods at real time."""


class LifecycleSteps:
    """Drives one mission's lifecycle: feeds outcomes to the machine, performs its steps."""

    def __init__(self, mission: Flown) -> None:
        self.m = mission
        self.config = mission.config
        self.link = mission.link
        self._speed_report: str | None = None
        """What setting the profile's speed on the vehicle gave (once per process)."""
        self._transit_t0 = 0.0
        self._safety_net_done = False
        """The safety net went into the vehicle (before the first arm of this process)."""
        self._return_speed_read = False
        """The autopilot's return speed was read (return_speed.py; once per process)."""
        self._steps: dict[Do, Callable[[], Awaitable[Outcome | None]]] = {
            Do.CONNECT: self._connect, Do.INSTALL_FENCE: self._install_fence,
            Do.LOCATE: self._locate, Do.AWAIT_CONTROL: self._await_control,
            Do.PREPARE: self._prepare, Do.TAKEOFF: self._takeoff,
            Do.AWAIT_CLIMB_STOP: self._await_climb_stop, Do.BEGIN_SETPOINTS: self._begin_setpoints,
            Do.CLIMB: self._climb, Do.RETRY: self._retry, Do.FLY: self._fly,
            Do.TRANSIT: self._transit, Do.SAY_TRANSIT_DONE: self._say_transit_done,
            Do.START_SEARCH: self._start_search, Do.ANNOUNCE_LEVEL: self._announce_level,
            Do.AWAIT_SEARCH_END: self._await_search_end, Do.FINISH: self._finish,
            Do.RECORD_END: self._record_end, Do.FLY_END_ACTION: self._fly_end_action,
        }  # fmt: skip
        """The I/O of each step the machine asks the lifecycle for; its outcome, if any."""

    async def run(self) -> None:
        """From the start to ``done`` (or to nothing: a restart after the end)."""
        event: Outcome | None = Began(self.m.recovered.ended)
        while event is not None:
            steps, event = self.m.feed(event), None
            for do in steps:  # at most one of a transition's steps has an outcome
                outcome = await self._steps[do]()
                if outcome is not None:
                    event = outcome

    # -- connect -----------------------------------------------------------------------------

    async def _connect(self) -> Connected:
        await connect(self.m)
        return Connected()

    async def _install_fence(self) -> None:
        if self.m.vehicle_fence is not None:
            self.m.chore(self.m.vehicle_fence.install())

    async def _locate(self) -> Located:
        m = self.m
        await m.waits.until(lambda: m.seen.heartbeat is not None and m.seen.position is not None)
        if not self._return_speed_read:  # on the ground, or a vehicle taken over in flight
            await learn_return_speed(m)
            self._return_speed_read = True
        return Located(self._airborne_guided())

    async def _await_control(self) -> ControlBack:
        await self.m.waits.until(lambda: self.m.phase not in (Phase.PAUSED, Phase.LINK_LOST))
        return ControlBack()

    async def _retry(self) -> Retried:
        await self.m.waits.sleep_vehicle(1.0)
        return Retried()

    # -- prepare and climb -------------------------------------------------------------------

    def _airborne_guided(self) -> bool:
        hb, pos, ap = self.m.seen.heartbeat, self.m.seen.position, self.link.autopilot
        if hb is None or pos is None or ap is None:
            return False
        near = -pos.down > 0.8 * self.config.altitude
        return hb.armed and ap.is_guided(hb.custom_mode) and near

    async def _prepare(self) -> Prepared:
        """Stream setpoints, switch to the guided mode, arm."""
        m = self.m
        await m.waits.until(lambda: m.seen.status is None or m.seen.status.healthy, 30.0)
        await m.waits.sleep_vehicle(1.0)  # setpoints flowing before the mode switch (PX4)
        ap = self.link.autopilot
        if ap is None or m.phase is not Phase.PREPARE or not await self._ensure_guided():
            return Prepared(ok=False, takeoff=False)
        hb = m.seen.heartbeat
        if hb is not None and not hb.armed:
            if not self._safety_net_done:
                if not await install_safety_net(m):
                    return Prepared(ok=False, takeoff=False)
                self._safety_net_done = True
            result = await self.link.arm()
            if not result:
                self._refused("arm", result, "vehicle %d refused to arm: %s")
                return Prepared(ok=False, takeoff=False)
        await m.waits.until(lambda: m.seen.heartbeat is not None and m.seen.heartbeat.armed, 10.0)
        pos = m.seen.position
        on_ground = pos is not None and -pos.down < 0.5 * self.config.altitude
        return Prepared(ok=True, takeoff=ap.takeoff_by_command and on_ground)

    async def _ensure_guided(self) -> bool:
        m, ap = self.m, self.link.autopilot
        assert ap is not None
        for _ in range(3):
            hb = m.seen.heartbeat
            if hb is not None and ap.is_guided(hb.custom_mode):
                return True
            result = await self.link.set_mode(FlightMode.GUIDED)
            if not result:
                self._refused("guided", result, "vehicle %d: guided mode %s")
                continue
            if await m.waits.until(
                lambda: m.seen.heartbeat is not None and ap.is_guided(m.seen.heartbeat.custom_mode),
                5.0,
            ):
                return True
        return False

    async def _takeoff(self) -> TakeoffSent:
        result = await self.link.takeoff(self.config.altitude)
        if not result:
            self._refused("takeoff", result, "vehicle %d: takeoff %s")
        return TakeoffSent(bool(result))

    def _refused(self, command: str, result: CommandResult, line: str) -> None:
        """A command the vehicle refused: ``line`` (vehicle, result) logged, a ``refused`` event."""
        log.warning(line, self.config.vehicle, result.describe())
        self.m.emit("refused", command=command, outcome=result.outcome.value, reason=result.reason)

    async def _await_climb_stop(self) -> ClimbStopped:
        # If the autopilot's takeoff stops short (its own takeoff altitude), setpoints
        # finish the climb: wait for the altitude or for the climb to stall airborne.
        m = self.m
        await m.waits.until(
            lambda: self._climb_done_or_stalled() or m.phase is not Phase.CLIMB,
            self.config.climb_timeout,
        )
        return ClimbStopped()

    async def _begin_setpoints(self) -> None:
        await self.link.begin_setpoints()

    async def _climb(self) -> Climbed:
        m = self.m
        return Climbed(
            await m.waits.until(
                lambda: (
                    m.phase is not Phase.CLIMB
                    or (
                        m.seen.position is not None
                        and -m.seen.position.down > 0.95 * self.config.altitude
                    )
                ),
                self.config.climb_timeout,
            )
        )

    def _climb_done_or_stalled(self) -> bool:
        pos = self.m.seen.position
        if pos is None:
            return False
        alt = -pos.down
        return alt > 0.95 * self.config.altitude or (alt > 1.0 and abs(pos.vd) < 0.05)

    # -- fly, transit, search ----------------------------------------------------------------

    async def _fly(self) -> SetpointsBegun:
        await self.link.begin_setpoints()
        if self._speed_report is None:
            self._speed_report = await self.link.set_speed(self.config.profile.fleet.speed)
            log.info("vehicle %d speed: %s", self.config.vehicle, self._speed_report)
            self.m.emit("speed", report=self._speed_report)
        return SetpointsBegun(self.m.seen.search_start is not None, self.m.start is not None)

    async def _transit(self) -> TransitEnded:
        """Fly at the search altitude to the start point; the search clock starts there."""
        m, pos, start = self.m, self.m.seen.position, self.m.start
        assert pos is not None
        assert start is not None
        distance = math.hypot(start[0] - pos.north, start[1] - pos.east)
        self._transit_t0 = m.seen.clock.now
        m.emit(
            "transit",
            state="begin",
            north=round(pos.north, 1),
            east=round(pos.east, 1),
            to_north=round(start[0], 1),
            to_east=round(start[1], 1),
            distance=round(distance, 1),
        )
        log.info(
            "vehicle %d: transit %.0f m to its start point (%.0f, %.0f)",
            self.config.vehicle,
            distance,
            *start,
        )
        limit = 60.0 + 3.0 * distance / self.config.profile.fleet.speed
        arrived = await m.waits.until(
            lambda: (
                m.phase is not Phase.TRANSIT
                or (
                    m.seen.position is not None
                    and guidance.reached(
                        np.array([m.seen.position.north, m.seen.position.east]),
                        np.array(start),
                        m.guide.acceptance_radius,
                    )
                )
            ),
            limit,
        )
        return TransitEnded(arrived, limit)

    async def _say_transit_done(self) -> None:
        self.m.emit(
            "transit", state="done", seconds=round(self.m.seen.clock.now - self._transit_t0, 1)
        )

    async def _start_search(self) -> SearchBegun:
        m, pos = self.m, self.m.seen.position
        assert pos is not None
        t = m.seen.clock.now
        m.seen.begin_search(t)
        if not m.core.started:
            m.core.start(np.array([pos.north, pos.east]), t, m.recovered.confirmed)
        return SearchBegun()

    async def _announce_level(self) -> None:
        m = self.m
        m.record(events.Level(m.core.level, m.core.sensor()))
        m.sensors.select(m.core.sensor(), m.seen.clock.now)

    async def _await_search_end(self) -> SearchLeft:
        await self.m.waits.until(lambda: self.m.phase is not Phase.SEARCH)
        return SearchLeft()

    # -- the end -----------------------------------------------------------------------------

    async def _finish(self) -> Ending:
        hb = self.m.seen.heartbeat
        return Ending(hb is not None and hb.armed)

    async def _record_end(self) -> EndRecorded:
        m = self.m
        m.record(events.End(str(m.end_reason), m.core.confirmed_count))
        self._report_speed()
        m.sensors.select(-1, m.seen.clock.now)
        return EndRecorded()

    async def _fly_end_action(self) -> Landed:
        m, action = self.m, self.m.end_action
        name = action.value.upper()
        result = await self.link.set_mode(action)
        if not result:
            log.error(
                "vehicle %d refused %s: %s", self.config.vehicle, action.value, result.describe()
            )
        if self.config.land_wait <= 0:
            if result:
                await self._await_mode(action)
            if m.exit is None:
                m.end_with(
                    MissionExit(0, f"{name} accepted; not waiting for the landing")
                    if result
                    else MissionExit(1, f"{name} refused: {result.describe()}")
                )
            return Landed()
        log.info(
            "vehicle %d: %s; waiting up to %g vehicle s until it lands and disarms",
            self.config.vehicle,
            name,
            self.config.land_wait,
        )
        how = await self._await_landing()
        if m.exit is not None:  # the link was given up meanwhile
            return Landed()
        if how == "landed":
            log.info("vehicle %d: landed and disarmed", self.config.vehicle)
            m.end_with(MissionExit(0, f"{name}: landed and disarmed"))
        else:
            end = MissionExit(1, f"{how} after {name}, still armed {m.where()}")
            m.end_with(end)
            log.error("vehicle %d: %s", self.config.vehicle, end.cause)
        return Landed()

    async def _await_mode(self, action: FlightMode) -> None:
        """Until a HEARTBEAT reports ``action``'s mode (so that the last state message says
        what the vehicle flies when the companion leaves without waiting for the landing), at
        most _MODE_SEEN_S wall s."""
        m, ap = self.m, self.link.autopilot
        if ap is None:
            return
        wanted = ap.mode_name(ap.custom_mode(action))
        deadline = time.monotonic() + _MODE_SEEN_S
        while m.exit is None and time.monotonic() < deadline:
            hb = m.seen.heartbeat
            if hb is not None and ap.mode_name(hb.custom_mode) == wanted:
                return
            await m.waits.wait_changed(0.2)

    async def _await_landing(self) -> str:
        """Until the vehicle disarms (``landed``), ``land_wait`` vehicle s pass, or its clock
        stands still (no valid position) for the failsafe's position_timeout + position_hold
        wall s while its HEARTBEATs still come (a vehicle gone silent altogether is the link
        supervision's: a lost link, not a bad estimator); while the link is lost, until the
        supervision gives it up (``m.exit``)."""
        m, wait = self.m, self.config.land_wait
        spec = self.config.profile.failsafe
        stall = spec.position_timeout + spec.position_hold
        start, last, moved = m.seen.clock.now, m.seen.clock.now, time.monotonic()
        while m.exit is None:
            if m.seen.heartbeat is not None and not m.seen.heartbeat.armed:
                return "landed"
            if m.seen.clock.now - start >= wait:
                return f"{wait:g} vehicle s"
            if m.seen.clock.now != last:
                last, moved = m.seen.clock.now, time.monotonic()
            elif (
                m.phase is not Phase.LINK_LOST
                and time.perf_counter() - m.seen.last_heartbeat_wall < _HEARTBEAT_FRESH_S
                and time.monotonic() - moved >= stall
            ):
                return f"no valid position for {time.monotonic() - moved:.0f} s ({m.seen.clock.now - start:.0f} vehicle s)"
            await m.waits.wait_changed(0.5)
        return "link given up"

    def _report_speed(self) -> None:
        """A vehicle that kept below the profile's speed says so: an autopilot limit the
        companion could not raise, or the airframe (ArduCopter SITL: about 11 m/s at its default
        30-degree lean limit, ANGLE_MAX, with WPNAV_SPEED at 20 m/s)."""
        m = self.m
        if not m.core.started:
            return
        asked = self.config.profile.fleet.speed
        m.emit("speed", max_search=round(m.seen.max_search_speed, 2), asked=asked)
        if m.seen.max_search_speed < 0.9 * asked:
            log.warning(
                "vehicle %d flew at most %.1f m/s while searching; the profile asks "
                "%g m/s: the vehicle caps it (%s)",
                self.config.vehicle,
                m.seen.max_search_speed,
                asked,
                self._speed_report,
            )
