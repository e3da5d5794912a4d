"""Commands and parameters over pymavlink's codec: COMMAND_LONG retried until a final
COMMAND_ACK, PARAM_REQUEST_READ / PARAM_SET retried until the PARAM_VALUE; the transport
(pymavlink_link.py) sends the frames and hands the answers back here."""

from __future__ import annotations

import asyncio
import logging
import math
import struct
import time
from collections.abc import Awaitable, Callable
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from companion.link.outcome import CommandResult, Outcome, accepted, timed_out

log = logging.getLogger(__name__)

PARAM_INT32 = mavlink2.MAV_PARAM_TYPE_INT32
UNREAD_STREAMS = (
    mavlink2.MAVLINK_MSG_ID_ATTITUDE,
    mavlink2.MAVLINK_MSG_ID_SYSTEM_TIME,
    mavlink2.MAVLINK_MSG_ID_GPS_RAW_INT,
    mavlink2.MAVLINK_MSG_ID_BATTERY_STATUS,
    mavlink2.MAVLINK_MSG_ID_HOME_POSITION,
    mavlink2.MAVLINK_MSG_ID_EXTENDED_SYS_STATE,
)
"""Streams the mission never reads, switched off on a dedicated link (``configure_streams``)."""
GLOBAL_POSITION_INT = mavlink2.MAVLINK_MSG_ID_GLOBAL_POSITION_INT
"""Switched off too, unless the fence watch reads it."""


class MavlinkCommands:
    """One vehicle's commands and parameters: ``send`` puts a message on the link; each is
    sent up to ``tries`` times, ``timeout`` wall s apart; ``with_reason`` adds the vehicle's
    STATUSTEXT to a refusal; ``bytewise()`` says whether integer parameters travel bytewise
    in the float field (PX4) or cast (ArduPilot)."""

    def __init__(
        self,
        mav: Any,
        send: Callable[[Any], None],
        target_system: int,
        *,
        timeout: float,
        tries: int,
        with_reason: Callable[[CommandResult, float], Awaitable[CommandResult]],
        bytewise: Callable[[], bool],
    ) -> None:
        self._mav = mav
        self._send = send
        self.target_system = target_system
        self.timeout = timeout
        self.tries = tries
        self._with_reason = with_reason
        self._bytewise = bytewise
        self._acks: dict[int, asyncio.Future[int]] = {}
        self._params: dict[str, asyncio.Future[tuple[float, int]]] = {}

    def on_ack(self, command: int, result: int) -> None:
        """A COMMAND_ACK came (IN_PROGRESS is not final: the wait goes on)."""
        future = self._acks.get(command)
        if future is not None and not future.done() and result != mavlink2.MAV_RESULT_IN_PROGRESS:
            future.set_result(result)

    def on_param_value(self, name: str, value: float, param_type: int) -> None:
        """A PARAM_VALUE came."""
        pending = self._params.get(name)
        if pending is not None and not pending.done():
            pending.set_result((value, param_type))

    async def command_long(self, command: int, *params: float) -> CommandResult:
        """COMMAND_LONG with retries until a final COMMAND_ACK; a refusal carries the
        vehicle's STATUSTEXT reason."""
        name = _command_name(command)
        full = list(params) + [0.0] * (7 - len(params))
        future: asyncio.Future[int] = asyncio.get_running_loop().create_future()
        self._acks[command] = future
        since = time.monotonic()
        try:
            for attempt in range(self.tries):
                self._send(
                    self._mav.command_long_encode(self.target_system, 1, command, attempt, *full)
                )
                # asyncio.wait, not wait_for: on 3.11 wait_for can swallow a cancel
                await asyncio.wait({future}, timeout=self.timeout)
                if future.done():
                    break
        finally:
            self._acks.pop(command, None)
        if not future.done():
            result = timed_out(name, f"no COMMAND_ACK after {self.tries} tries")
        elif future.result() == mavlink2.MAV_RESULT_ACCEPTED:
            return accepted(name)
        else:
            code = future.result()
            label = (
                mavlink2.enums["MAV_RESULT"][code].name
                if code in mavlink2.enums["MAV_RESULT"]
                else str(code)
            )
            result = CommandResult(name, Outcome.DENIED, code, None)
            result = await self._with_reason(result, since)
            if result.reason is None:
                result = CommandResult(name, Outcome.DENIED, code, label)
        log.warning("%s", result.describe())
        return result

    async def configure_streams(self, *, keep_global_position: bool) -> None:
        """SET_MESSAGE_INTERVAL -1 for the streams the mission does not read: ATTITUDE,
        SYSTEM_TIME, GPS_RAW_INT, BATTERY_STATUS, HOME_POSITION, EXTENDED_SYS_STATE (and
        GLOBAL_POSITION_INT unless ``keep_global_position``): at high speed-ups every message
        not parsed is CPU for the rest of the fleet. Only on a dedicated link
        (``--dedicated-link``): a ground station sharing the link would lose them."""
        unused = UNREAD_STREAMS + (() if keep_global_position else (GLOBAL_POSITION_INT,))
        for msg_id in unused:
            if not await self.command_long(
                mavlink2.MAV_CMD_SET_MESSAGE_INTERVAL, float(msg_id), -1.0
            ):
                log.info("vehicle keeps streaming message %d", msg_id)

    async def read_param(self, name: str) -> float | None:
        return await self._param_exchange(
            name,
            lambda: self._mav.param_request_read_encode(self.target_system, 1, name.encode(), -1),
        )

    async def set_param(self, name: str, value: float, param_type: int) -> float | None:
        encoded = value
        if param_type == PARAM_INT32 and self._bytewise():
            encoded = struct.unpack("<f", struct.pack("<i", round(value)))[0]
        return await self._param_exchange(
            name,
            lambda: self._mav.param_set_encode(
                self.target_system, 1, name.encode(), encoded, param_type
            ),
        )

    async def _param_exchange(self, name: str, encode: Callable[[], Any]) -> float | None:
        """Send until a PARAM_VALUE of ``name`` comes back; its decoded value, or None."""
        for _ in range(self.tries):
            future: asyncio.Future[tuple[float, int]] = asyncio.get_running_loop().create_future()
            self._params[name] = future
            self._send(encode())
            try:
                await asyncio.wait({future}, timeout=self.timeout)
            finally:
                self._params.pop(name, None)
            if future.done():
                return self._param_value(*future.result())
        log.info(
            "parameter %s: no PARAM_VALUE from system %d after %d tries",
            name,
            self.target_system,
            self.tries,
        )
        return None

    def _param_value(self, value: float, param_type: int) -> float:
        if param_type == PARAM_INT32 and self._bytewise():
            return float(struct.unpack("<i", struct.pack("<f", value))[0])
        return value if math.isfinite(value) else math.nan


def _command_name(command: int) -> str:
    entry = mavlink2.enums["MAV_CMD"].get(command)
    return entry.name if entry is not None else f"command {command}"
