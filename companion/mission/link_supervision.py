"""The link's supervision: opening it with backoff while the autopilot boots, and, once the
vehicle was heard, its loss (no HEARTBEAT for ``link_timeout``: stop commanding), the reconnects
with jittered backoff, its return, and giving it up after the profile's ``failsafe.link_wait``."""

from __future__ import annotations

import asyncio
import logging
import random
import time
from collections.abc import Callable
from typing import Protocol

from companion.autopilots import FlightMode
from companion.link.base import LinkError, VehicleLink
from companion.link.messages import Heartbeat
from companion.mission.config import MissionConfig
from companion.mission.control import Control, LinkRestored
from companion.mission.lifecycle import Event
from companion.mission.lifecycle_events import Do, LinkLost
from companion.mission.mission_exit import MissionExit
from companion.mission.observed import Observed
from companion.mission.phase import Phase
from companion.mission.vehicle_waits import VehicleWaits
from companion.telemetry import events

log = logging.getLogger(__name__)

_OPEN_BACKOFF_MAX_S = 8.0
_LINK_LINE_S = 5.0
"""Wall seconds between two 'link lost, waiting' lines."""


class Supervised(Protocol):
    """What the supervision reads of the mission and asks of it (VehicleMission)."""

    @property
    def config(self) -> MissionConfig: ...
    @property
    def link(self) -> VehicleLink: ...
    @property
    def seen(self) -> Observed: ...
    @property
    def waits(self) -> VehicleWaits: ...
    @property
    def phase(self) -> Phase: ...
    @property
    def control(self) -> Control: ...
    @property
    def end_reason(self) -> str | None: ...
    @property
    def end_action(self) -> FlightMode: ...
    def feed(self, event: Event, *, mode: str = "") -> tuple[Do, ...]: ...
    def record(self, event: events.DurableEvent) -> None: ...
    def where(self) -> str: ...
    def end_with(self, exit: MissionExit) -> None: ...
    def request_end(self, reason: str) -> None: ...
    def hold_mode(self, hb: Heartbeat) -> bool: ...


class LinkSupervision:
    """Opens ``mission``'s link and watches it (:meth:`run`); ``check`` runs on every look
    (each quarter wall second) with the wall time (the position failsafe)."""

    def __init__(self, mission: Supervised, check: Callable[[float], None]) -> None:
        self.m = mission
        self.check = check

    async def open_link(self) -> bool:
        """Open the link, retrying with backoff while the endpoint is not up (an autopilot
        still booting); False when the mission was ended meanwhile."""
        m, backoff, attempt = self.m, 0.5, 0
        while True:
            try:
                await m.link.open()
                return True
            except LinkError as exc:
                attempt += 1
                wait = min(backoff * 2 ** (attempt - 1), _OPEN_BACKOFF_MAX_S)
                log.warning(
                    "vehicle %d: %s; retry %d in %.1f s", m.config.vehicle, exc, attempt, wait
                )
            deadline = time.monotonic() + wait
            while time.monotonic() < deadline:
                if m.end_reason is not None:
                    return False
                await asyncio.sleep(0.1)

    async def run(self) -> None:
        """Watch the link until it is given up (returns) or the mission's tasks end."""
        m, seen = self.m, self.m.seen
        backoff, next_line = 0.5, 0.0
        wait = m.config.profile.failsafe.link_wait
        while True:
            await asyncio.sleep(0.25)
            self.check(time.perf_counter())
            if seen.heartbeat is None or m.phase is Phase.DONE:
                continue
            silent = time.perf_counter() - seen.last_heartbeat_wall
            if silent <= m.config.link_timeout:
                backoff = 0.5
                continue
            resume = m.phase
            if resume is not Phase.LINK_LOST:
                log.warning(
                    "vehicle %d: no heartbeat for %.1f s; stop commanding", m.config.vehicle, silent
                )
                m.feed(LinkLost())
                m.record(events.LinkState("lost", round(silent, 1)))
            if silent >= wait:
                self._give_up(silent)
                return
            if time.perf_counter() >= next_line:
                next_line = time.perf_counter() + _LINK_LINE_S
                log.warning(
                    "vehicle %d: link lost for %.0f s; waiting up to %g s for it",
                    m.config.vehicle,
                    silent,
                    wait,
                )
            give_up = seen.last_heartbeat_wall + wait  # no wait below runs past it
            left = max(give_up - time.perf_counter(), 0.0)
            await asyncio.sleep(min(backoff * (1 + random.random()), left))  # jittered backoff
            backoff = min(backoff * 2, 8.0)
            try:
                await m.link.reconnect()
            except (OSError, LinkError) as exc:
                log.warning("reconnect failed: %s", exc)
                continue
            deadline = min(time.perf_counter() + 2.0 * m.config.link_timeout, give_up)
            while time.perf_counter() < deadline:
                await asyncio.sleep(0.1)
                if time.perf_counter() - seen.last_heartbeat_wall < 1.0:
                    m.record(events.LinkState("restored"))
                    self._restored(resume)
                    break

    def _give_up(self, silent: float) -> None:
        """The link stayed lost for the profile's ``failsafe.link_wait``: the mission ends
        (exit status 1), saying what the vehicle was last seen doing and where."""
        m = self.m
        hb, ap = m.seen.heartbeat, m.link.autopilot
        armed = hb is not None and hb.armed
        if m.control.ending:
            doing = f"{m.end_action.value.upper()} under way"
        elif hb is not None and ap is not None:
            doing = f"in {ap.mode_name(hb.custom_mode)}"
        else:
            doing = "mode unknown"
        cause = (
            f"link lost while {'armed' if armed else 'disarmed'} (no heartbeat for "
            f"{silent:.0f} s), {doing} {m.where()}"
        )
        log.error("vehicle %d: %s; not waiting longer", m.config.vehicle, cause)
        m.end_with(MissionExit(1, cause))
        m.request_end("link lost")
        m.waits.wake()

    def _restored(self, before: Phase) -> None:
        m = self.m
        hb, ap = m.seen.heartbeat, m.link.autopilot
        if hb is None or ap is None:
            event = LinkRestored(before, known=False, guided=False, armed=False, hold=False)
        else:
            event = LinkRestored(
                before, True, ap.is_guided(hb.custom_mode), hb.armed, m.hold_mode(hb)
            )
        m.feed(event)
