"""The mission's setpoints out: each through the last check (setpoint_guard.py) onto the link,
with the latency from the position it answers."""

from __future__ import annotations

import logging
import time
from collections.abc import Callable

import numpy as np

from companion import guidance
from companion.geofence import Geofence
from companion.guidance import GuidanceConfig, NedSetpoint
from companion.link.base import SetpointKind, VehicleLink
from companion.link.messages import LocalPosition
from companion.mission.observed import Observed
from companion.mission.setpoint_guard import SetpointGuard
from companion.telemetry import events

log = logging.getLogger(__name__)

_LATENCIES_KEPT = 200_000
"""Latencies kept for the end's percentiles (a cap on the memory of a long sped-up run)."""


class SetpointOut:
    """Sends one vehicle's setpoints; ``record`` takes the refusals' durable events."""

    def __init__(
        self,
        vehicle: int,
        link: VehicleLink,
        seen: Observed,
        guard: SetpointGuard,
        kind: SetpointKind,
        record: Callable[[events.DurableEvent], None],
    ) -> None:
        self.vehicle = vehicle
        self.link = link
        self.seen = seen
        self.guard = guard
        self.kind = kind
        self.record = record
        self.latencies: list[float] = []
        """Wall s from a position's arrival to the setpoint that answered it."""

    @property
    def guide(self) -> GuidanceConfig:
        return self.guard.guide

    @property
    def fence(self) -> Geofence:
        return self.guard.fence

    def pursue(self, pos: LocalPosition, north: float, east: float) -> None:
        """The search's velocity setpoint from ``pos`` towards the waypoint (north, east)."""
        self.send(
            guidance.pursuit_xy(
                pos.north, pos.east, pos.down, north, east, self.guide, self.fence, self.seen.period
            ),
            pos,
        )

    def hold_here(self) -> None:
        """A setpoint that holds at the last valid position (while none valid comes)."""
        pos = self.seen.position
        if pos is not None:
            self.send(NedSetpoint(pos.north, pos.east, pos.down, 0.0, 0.0, 0.0), pos, answer=False)

    def send(self, sp: NedSetpoint, pos: LocalPosition, *, answer: bool = True) -> None:
        """``sp``, the answer to ``pos`` (its latency measured; not for a hold without a new
        position), through the last check."""
        safe, why = self.guard.safe(sp)
        if why is not None:
            self._refused(*why)
            if safe is None:
                return
            sp = safe
        self.link.send_setpoint(sp, self.kind)
        self.seen.setpoint_time = pos.time
        if answer and len(self.latencies) < _LATENCIES_KEPT:
            self.latencies.append(time.perf_counter() - pos.received)

    def latency_ms(self) -> dict[str, float] | None:
        """The latencies' median and 99th percentile in ms (None: no setpoint answered)."""
        if not self.latencies:
            return None
        ms = np.array(self.latencies) * 1e3
        return {
            "p50_ms": round(float(np.percentile(ms, 50)), 4),
            "p99_ms": round(float(np.percentile(ms, 99)), 4),
        }

    def _refused(self, kind: str, detail: str) -> None:
        """A setpoint the last check refused: a bug, logged with its cause (the 1st, 10th,
        100th ... of each kind) and replaced by a hold."""
        n = self.guard.refused[kind]
        if n == 10 ** (len(str(n)) - 1):
            log.error(
                "vehicle %d: setpoint not sent (%s; %d so far): a bug; sent a hold instead",
                self.vehicle,
                detail,
                n,
            )
            self.record(events.SetpointRefused(kind, detail, n))
