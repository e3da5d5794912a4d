"""Making sure every stream the companion needs arrives at its rate: look first, then ask with
SET_MESSAGE_INTERVAL, then with REQUEST_DATA_STREAM (a part of every link)."""

from __future__ import annotations

import asyncio
import logging
import math
import time
from typing import Protocol

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from companion.link.outcome import CommandResult
from companion.link.streams import StreamNeed, StreamWatch

log = logging.getLogger(__name__)


class _Asker(Protocol):
    streams: StreamWatch
    target_system: int

    async def command_long(self, command: int, *params: float) -> CommandResult: ...

    def request_data_stream(self, stream_id: int, rate_hz: int) -> None: ...


async def _await_streams(
    streams: StreamWatch,
    needs: tuple[StreamNeed, ...] | list[StreamNeed],
    since: float,
    wait: float,
) -> tuple[StreamNeed, ...]:
    deadline = time.monotonic() + wait
    while True:
        missing = tuple(n for n in needs if not streams.satisfied(n, since))
        if not missing or time.monotonic() >= deadline:
            return missing
        await asyncio.sleep(0.1)


class StreamRequests:
    """The stream negotiation of a :class:`~companion.link.base.VehicleLink`."""

    async def request_streams(
        self: _Asker, needs: tuple[StreamNeed, ...], wait: float = 2.0
    ) -> list[str]:
        """Make sure every needed message arrives at its rate: look first, then ask with
        SET_MESSAGE_INTERVAL, then with REQUEST_DATA_STREAM. Returns one line per message still
        missing, naming what was tried (empty when all arrive)."""
        since = time.monotonic()
        missing = await _await_streams(self.streams, needs, since, wait)
        tried: dict[str, list[str]] = {n.name: [] for n in missing}
        for need in missing:
            self.streams.clear(need.name)
            result = await self.command_long(
                mavlink2.MAV_CMD_SET_MESSAGE_INTERVAL, float(need.msg_id), need.interval_us()
            )
            tried[need.name].append(
                f"SET_MESSAGE_INTERVAL {need.interval_us():.0f} us: {result.outcome.value}"
            )
            log.info(
                "asked system %d for %s every %.0f us: %s",
                self.target_system,
                need.name,
                need.interval_us(),
                result.describe(),
            )
        if missing:
            missing = await _await_streams(self.streams, missing, since, wait)
        for need in missing:
            rate = max(1, math.ceil(need.rate_hz))
            self.request_data_stream(need.data_stream, rate)
            stream = mavlink2.enums["MAV_DATA_STREAM"][need.data_stream].name
            tried[need.name].append(f"REQUEST_DATA_STREAM {stream} at {rate} Hz")
            log.info("asked system %d for %s at %d Hz", self.target_system, stream, rate)
        if missing:
            missing = await _await_streams(self.streams, missing, since, wait)
        problems = []
        for need in missing:
            measured = self.streams.rate(need.name)
            got = (
                "nothing"
                if not self.streams.seen_since(need.name, since)
                else (f"{measured:.1f} Hz" if measured is not None else "too few to time")
            )
            problems.append(
                f"{need.name} from system {self.target_system}: needed at "
                f"{need.rate_hz:g} Hz, got {got}; tried {'; '.join(tried[need.name])}"
            )
        return problems
