"""What the mission does about bad positions: reports the ones the link's check dropped
(console and ``telemetry_dropped`` records, at most once per ``REPORT_PERIOD_S``), and flies the
profile's failsafe when no valid position came for ``failsafe.position_timeout`` wall s while
flying: hold setpoints at once (the setpoint stream goes on), HOLD (in the search: a pause,
as the operator's), then, when none came for
``position_hold`` more, the end action; positions back before that resume the search."""

from __future__ import annotations

import logging
from typing import Protocol

from companion.autopilots import FlightMode
from companion.link.base import VehicleLink
from companion.mission.config import MissionConfig
from companion.mission.control import OperatorPause, OperatorResume
from companion.mission.lifecycle import Event
from companion.mission.observed import Observed
from companion.mission.phase import Phase
from companion.mission.setpoint_out import SetpointOut
from companion.telemetry import events

log = logging.getLogger(__name__)

REPORT_PERIOD_S = 5.0
"""Wall seconds between two reports of dropped positions."""
_FLYING = frozenset({Phase.CLIMB, Phase.TRANSIT, Phase.SEARCH})
_ALIVE_S = 1.0
"""A HEARTBEAT this long after the last valid position: the link lives, the positions are bad
(when both stop, the link is lost: the supervision's case, not this one)."""
_STREAM_GAP_S = 0.5
"""Wall s without a valid position after which each check (4 a second) sends a hold setpoint:
PX4 leaves OFFBOARD after COM_OF_LOSS_T (1 s) without setpoints, before the failsafe's HOLD."""
BY = "position failsafe"
"""The ``by`` of the pause's ``phase`` record."""


class Guarded(Protocol):
    """What the failsafe reads of the mission and asks of it (VehicleMission)."""

    @property
    def config(self) -> MissionConfig: ...
    @property
    def link(self) -> VehicleLink: ...
    @property
    def seen(self) -> Observed: ...
    @property
    def out(self) -> SetpointOut: ...
    @property
    def phase(self) -> Phase: ...
    @property
    def end_reason(self) -> str | None: ...
    @property
    def end_action(self) -> FlightMode: ...
    def ask(self, event: Event, *, by: str | None = None) -> str | None: ...
    def request_end(self, reason: str) -> None: ...
    def record(self, event: events.DurableEvent) -> None: ...


class PositionFailsafe:
    """Called by the mission's supervision every quarter wall second (:meth:`check`)."""

    def __init__(self, mission: Guarded) -> None:
        self.m = mission
        self.spec = mission.config.profile.failsafe
        self._next_report = 0.0
        self.holding = False
        """The failsafe paused the search (HOLD) and waits for a valid position."""
        self.cause: str | None = None
        """Set when the failsafe ended the mission."""
        self._since: float | None = None
        """Wall time the vehicle began flying without a valid position (None: one came)."""

    def check(self, now: float) -> None:
        self._report(now)
        self._watch(now)

    def flush(self) -> None:
        """Report what was dropped since the last report (the mission's end)."""
        self._report(self._next_report)

    def _report(self, now: float) -> None:
        if now < self._next_report:
            return
        new = self.m.link.guard.take_report()
        if not new:
            return
        self._next_report = now + REPORT_PERIOD_S
        total = self.m.link.guard.dropped
        log.warning(
            "vehicle %d: dropped %s",
            self.m.config.vehicle,
            ", ".join(f"{n} position(s): {cause}" for cause, n in sorted(new.items())),
        )
        for cause, n in sorted(new.items()):
            self.m.record(events.TelemetryDropped(cause, n, total[cause]))

    def _watch(self, now: float) -> None:
        m, v = self.m, self.m.config.vehicle
        hb = m.seen.heartbeat
        flying = hb is not None and hb.armed and (m.phase in _FLYING or self.holding)
        last = m.link.guard.last_valid_wall
        if not flying or m.end_reason is not None:
            self._since = None
            return
        alive = now - m.seen.last_heartbeat_wall < m.config.link_timeout
        if m.phase in _FLYING and alive and last is not None and now - last >= _STREAM_GAP_S:
            m.out.hold_here()
        fresh = last is not None and now - last < self.spec.position_timeout
        if fresh:
            self._since = None
            if self.holding:
                self.holding = False
                log.warning("vehicle %d: valid positions again: resuming the search", v)
                m.ask(OperatorResume())
            return
        if self._since is None:
            self._since = now if last is None else last
        silent = now - self._since
        beat = m.seen.last_heartbeat_wall
        if silent < self.spec.position_timeout or beat - self._since < _ALIVE_S:
            return  # (no heartbeat since the positions stopped either: the link's loss)
        if silent < self.spec.position_timeout + self.spec.position_hold:
            if (
                not self.holding
                and m.phase is Phase.SEARCH
                and m.ask(OperatorPause(), by=BY) is None
            ):
                self.holding = True
                log.error(
                    "vehicle %d: no valid position for %.1f s: HOLD (failsafe); the end "
                    "action in %g s unless positions come back",
                    v,
                    silent,
                    self.spec.position_hold,
                )
            if self.holding:
                return
        if self.holding or m.phase in _FLYING:
            self.cause = f"no valid position for {silent:.1f} s"
            log.error(
                "vehicle %d: %s: ending with %s (failsafe)",
                v,
                self.cause,
                m.end_action.value.upper(),
            )
            m.request_end(f"failsafe: {self.cause}")
